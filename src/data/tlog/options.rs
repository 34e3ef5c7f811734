//! What `read_tlog` is asked to read: which system, grid and stretch, and what VFR_HUD's airspeed is.

/// Which stretch of a log with breaks in its time base to read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StretchChoice {
    /// The K-th stretch in log order, from 1.
    Index(usize),
    /// The stretch with the most ATTITUDE samples.
    Longest,
}

impl std::str::FromStr for StretchChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "longest" => Ok(Self::Longest),
            _ => match s.parse::<usize>() {
                Ok(k) if k >= 1 => Ok(Self::Index(k)),
                _ => Err(format!(
                    "expected a stretch number from 1 or `longest`, got '{s}'"
                )),
            },
        }
    }
}

/// Options of [`super::read_tlog`].
#[derive(Debug, Clone, Default)]
pub struct TlogOptions {
    /// System id to extract; default: the one with the most ATTITUDE messages.
    pub sysid: Option<u8>,
    /// Output grid rate, Hz; default: the ATTITUDE rate (1 / median ATTITUDE interval).
    pub rate_hz: Option<f64>,
    /// The stretch to read when the time base breaks (a gap or a jump back); without it such a log is
    /// refused with the list of its stretches.
    pub stretch: Option<StretchChoice>,
    /// What VFR_HUD's airspeed is.
    pub airspeed: AirspeedKind,
}

/// What an autopilot sends as VFR_HUD's airspeed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum AirspeedKind {
    /// Equivalent (or indicated) airspeed, as ArduPilot and PX4 send it: converted to true airspeed with the
    /// standard atmosphere at the logged altitude, V_true = V_eq √(ρ₀/ρ(h)).
    #[default]
    Equivalent,
    /// True airspeed: taken as it is.
    True,
}

/// True airspeed from equivalent airspeed `eas` at altitude `altitude_m`, in the standard atmosphere (clamped
/// to the troposphere).
pub fn true_from_equivalent(eas: f64, altitude_m: f64) -> f64 {
    use crate::sim::atmosphere::density_kg_m3;
    let rho = |h: f64| density_kg_m3(h.clamp(-500.0, 10_900.0), 0.0).unwrap_or(f64::NAN);
    eas * (rho(0.0) / rho(altitude_m)).sqrt()
}
