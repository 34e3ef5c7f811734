//! The columns of the flight-data schema (docs/data.md) as a type: a [`Channel`] names one column, and its
//! name carries its unit (`q_rad_s`), so code that means a schema column says which one, and a typo is a
//! compile error instead of a column that is silently never found.

use std::fmt;
use std::str::FromStr;

/// One column of the flight-data schema. SI units; angles in rad, body axes (x forward, y right, z down).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Channel {
    /// `time_s`: sample time, s.
    Time,
    /// `elevator_rad`: elevator deflection, rad (trailing edge down positive).
    Elevator,
    /// `aileron_rad`: aileron deflection, rad.
    Aileron,
    /// `rudder_rad`: rudder deflection, rad.
    Rudder,
    /// `throttle`: throttle setting, fraction 0..1.
    Throttle,
    /// `phi_rad`: roll angle φ, rad.
    Phi,
    /// `theta_rad`: pitch angle θ, rad.
    Theta,
    /// `psi_rad`: heading ψ, rad.
    Psi,
    /// `p_rad_s`: body roll rate, rad/s.
    P,
    /// `q_rad_s`: body pitch rate, rad/s.
    Q,
    /// `r_rad_s`: body yaw rate, rad/s.
    R,
    /// `alpha_rad`: angle of attack α, rad.
    Alpha,
    /// `beta_rad`: sideslip angle β, rad.
    Beta,
    /// `airspeed_m_s`: true airspeed, m/s.
    Airspeed,
    /// `altitude_m`: altitude, m.
    Altitude,
    /// `ax_m_s2`: body-x specific force, m/s².
    Ax,
    /// `ay_m_s2`: body-y specific force, m/s².
    Ay,
    /// `az_m_s2`: body-z specific force, m/s².
    Az,
    /// `thrust_n`: thrust, N.
    Thrust,
    /// `qbar_pa`: dynamic pressure, Pa.
    Qbar,
    /// `pdot_rad_s2`: body roll acceleration ṗ, rad/s² (a measured or differentiated angular acceleration).
    PDot,
    /// `qdot_rad_s2`: body pitch acceleration q̇, rad/s².
    QDot,
    /// `rdot_rad_s2`: body yaw acceleration ṙ, rad/s².
    RDot,
    /// `latitude_rad`: geodetic latitude, rad (from GPS; a replay trims at it, as gravity changes with it).
    Latitude,
    /// `density_kg_m3`: air density ρ, kg/m³ (from the data system's static pressure and temperature; the
    /// aerodynamic coefficients of a measured record use q̄ = ½ρV² with it when `qbar_pa` is not logged).
    Density,
}

impl Channel {
    /// Every column of the schema, in its canonical order.
    pub const ALL: [Channel; 25] = [
        Channel::Time,
        Channel::Elevator,
        Channel::Aileron,
        Channel::Rudder,
        Channel::Throttle,
        Channel::Phi,
        Channel::Theta,
        Channel::Psi,
        Channel::P,
        Channel::Q,
        Channel::R,
        Channel::Alpha,
        Channel::Beta,
        Channel::Airspeed,
        Channel::Altitude,
        Channel::Ax,
        Channel::Ay,
        Channel::Az,
        Channel::Thrust,
        Channel::Qbar,
        Channel::PDot,
        Channel::QDot,
        Channel::RDot,
        Channel::Latitude,
        Channel::Density,
    ];

    /// The control inputs: the three surfaces and the throttle (the four schema columns from `elevator_rad` on).
    pub const CONTROLS: [Channel; 4] = Channel::run_from(Channel::Elevator);

    /// The attitude angles and body rates of an attitude solution (φ, θ, ψ, p, q, r: the six schema columns from
    /// `phi_rad` on).
    pub const ATTITUDE_AND_RATES: [Channel; 6] = Channel::run_from(Channel::Phi);

    /// The body-axis specific forces (accelerometers).
    pub const SPECIFIC_FORCES: [Channel; 3] = [Channel::Ax, Channel::Ay, Channel::Az];

    /// The `N` schema columns from `first` on, in schema order (a const fn, so that a group of adjacent columns
    /// is a constant taken from [`Channel::ALL`] rather than a second copy of its order).
    pub(crate) const fn run_from<const N: usize>(first: Channel) -> [Channel; N] {
        let mut out = [first; N];
        let mut i = 0;
        while i < N {
            out[i] = Channel::ALL[first as usize + i];
            i += 1;
        }
        out
    }

    /// The column name of docs/data.md, e.g. `q_rad_s`.
    pub const fn name(self) -> &'static str {
        match self {
            Channel::Time => "time_s",
            Channel::Elevator => "elevator_rad",
            Channel::Aileron => "aileron_rad",
            Channel::Rudder => "rudder_rad",
            Channel::Throttle => "throttle",
            Channel::Phi => "phi_rad",
            Channel::Theta => "theta_rad",
            Channel::Psi => "psi_rad",
            Channel::P => "p_rad_s",
            Channel::Q => "q_rad_s",
            Channel::R => "r_rad_s",
            Channel::Alpha => "alpha_rad",
            Channel::Beta => "beta_rad",
            Channel::Airspeed => "airspeed_m_s",
            Channel::Altitude => "altitude_m",
            Channel::Ax => "ax_m_s2",
            Channel::Ay => "ay_m_s2",
            Channel::Az => "az_m_s2",
            Channel::Thrust => "thrust_n",
            Channel::Qbar => "qbar_pa",
            Channel::PDot => "pdot_rad_s2",
            Channel::QDot => "qdot_rad_s2",
            Channel::RDot => "rdot_rad_s2",
            Channel::Latitude => "latitude_rad",
            Channel::Density => "density_kg_m3",
        }
    }

    /// The channel of a column name, if it is a schema column.
    pub fn from_name(name: &str) -> Option<Channel> {
        Channel::ALL.into_iter().find(|c| c.name() == name)
    }

    /// The values the column can physically hold, `(min, max)` in its SI unit, or `None` (time: any finite
    /// value). The bounds lie far beyond any aircraft's flight, so a value outside is a corrupt sample or a
    /// unit gone wrong, never a manoeuvre; they are wide enough that a column logged in degrees, deg/s,
    /// knots, ft/s, ft, g or percent stays inside, for the unit-sanity warnings to name the unit. The
    /// reader refuses a value outside (docs/data.md, "Plausible values").
    pub const fn plausible_range(self) -> Option<(f64, f64)> {
        match self {
            Channel::Time => None,
            // 1000 rad is 159 turns; an angle logged in degrees (at most 360) stays inside.
            Channel::Elevator
            | Channel::Aileron
            | Channel::Rudder
            | Channel::Phi
            | Channel::Theta
            | Channel::Alpha
            | Channel::Beta
            | Channel::Latitude => Some((-1e3, 1e3)),
            // A heading may be unwrapped over a long flight of turns.
            Channel::Psi => Some((-1e6, 1e6)),
            // A fraction 0..1; percent (0..100) stays inside.
            Channel::Throttle => Some((-1e3, 1e3)),
            // 10 rad/s is a fast roll; 10⁴ leaves room for deg/s.
            Channel::P | Channel::Q | Channel::R => Some((-1e4, 1e4)),
            Channel::PDot | Channel::QDot | Channel::RDot => Some((-1e5, 1e5)),
            // A pitot never reads far below zero: a logger that takes the root of a noisy differential pressure
            // with its sign reads a few m/s below zero at rest, a negated column reads tens. 3000 m/s (Mach 9 at
            // sea level) leaves room for ft/s and knots.
            Channel::Airspeed => Some((-10.0, 3e3)),
            // The Dead Sea shore (−430 m, −1410 ft) to 100 km.
            Channel::Altitude => Some((-2e3, 1e5)),
            // 1000 g.
            Channel::Ax | Channel::Ay | Channel::Az => Some((-1e4, 1e4)),
            // Ten times the thrust of the heaviest aircraft (An-225, 1.4 MN).
            Channel::Thrust => Some((-1e7, 1e7)),
            // A differential pressure sensor's offset at rest may read slightly negative; Mach 3 at sea level
            // is 0.6 MPa.
            Channel::Qbar => Some((-1e3, 1e7)),
            // Sea level is 1.225 kg/m³.
            Channel::Density => Some((0.0, 100.0)),
        }
    }

    /// The surface a control input moves, as the simulation names it (`elevator`, ..., `throttle`); `None`
    /// for a channel that is not a control input.
    pub fn surface(self) -> Option<&'static str> {
        match self {
            Channel::Elevator => Some("elevator"),
            Channel::Aileron => Some("aileron"),
            Channel::Rudder => Some("rudder"),
            Channel::Throttle => Some("throttle"),
            _ => None,
        }
    }

    /// The control input that moves a surface the simulation names `surface`.
    pub fn of_surface(surface: &str) -> Option<Channel> {
        Channel::CONTROLS
            .into_iter()
            .find(|c| c.surface() == Some(surface))
    }
}

/// The column names of `channels`, in their order (a const fn, so that tables of names can be constants).
pub const fn names<const N: usize>(channels: [Channel; N]) -> [&'static str; N] {
    let mut out = [""; N];
    let mut i = 0;
    while i < N {
        out[i] = channels[i].name();
        i += 1;
    }
    out
}

impl fmt::Display for Channel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl AsRef<str> for Channel {
    fn as_ref(&self) -> &str {
        self.name()
    }
}

/// A column name that is not in the schema.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("'{0}' is not a column of the flight-data schema (docs/data.md)")]
pub struct UnknownChannel(pub String);

impl FromStr for Channel {
    type Err = UnknownChannel;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Channel::from_name(s).ok_or_else(|| UnknownChannel(s.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every channel's name parses back to it, and no two channels share a name.
    #[test]
    fn names_round_trip_and_are_unique() {
        for c in Channel::ALL {
            assert_eq!(c.name().parse::<Channel>(), Ok(c));
        }
        let mut seen: Vec<&str> = Channel::ALL.iter().map(|c| c.name()).collect();
        seen.sort();
        seen.dedup();
        assert_eq!(seen.len(), Channel::ALL.len());
        assert!("q_deg_s".parse::<Channel>().is_err());
    }

    /// [`Channel::ALL`] lists the channels in their declaration order, so `c as usize` is a channel's place
    /// in the schema.
    #[test]
    fn all_is_in_schema_order() {
        for (i, c) in Channel::ALL.into_iter().enumerate() {
            assert_eq!(c as usize, i, "{c}");
        }
    }

    /// A control input and its surface name map both ways; a sensor has no surface.
    #[test]
    fn control_inputs_map_to_surfaces() {
        for c in Channel::CONTROLS {
            assert_eq!(Channel::of_surface(c.surface().unwrap()), Some(c));
        }
        assert_eq!(Channel::Q.surface(), None);
        assert_eq!(Channel::of_surface("flap"), None);
    }

    /// The groups taken as runs of the schema hold the columns their docs name.
    #[test]
    fn groups_of_adjacent_columns_are_the_named_ones() {
        assert_eq!(
            names(Channel::CONTROLS),
            ["elevator_rad", "aileron_rad", "rudder_rad", "throttle"]
        );
        assert_eq!(
            names(Channel::ATTITUDE_AND_RATES),
            [
                "phi_rad",
                "theta_rad",
                "psi_rad",
                "p_rad_s",
                "q_rad_s",
                "r_rad_s"
            ]
        );
    }
}
