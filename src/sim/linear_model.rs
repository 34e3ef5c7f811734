//! A linear model standing in for the simulator: ẋ = A x + B u around a stored trim state, so numerics and
//! whole pipelines can be tested fast and deterministically, and aircraft without a JSBSim model can be flown.

use super::{FlightPlan, Linearization, SimError, Simulator, TrimPoint, TrimState, FT_TO_M};
use crate::data::{Channel, FlightRecord};
use crate::lti::{self, StateSpace};

/// State name (JSBSim linearization naming), schema column, factor from the state's unit to SI.
const STATE_COLUMNS: &[(&str, Channel, f64)] = &[
    ("Phi", Channel::Phi, 1.0),
    ("Theta", Channel::Theta, 1.0),
    ("Psi", Channel::Psi, 1.0),
    ("P", Channel::P, 1.0),
    ("Q", Channel::Q, 1.0),
    ("R", Channel::R, 1.0),
    ("Alpha", Channel::Alpha, 1.0),
    ("Beta", Channel::Beta, 1.0),
    ("Vt", Channel::Airspeed, FT_TO_M),
    ("Alt", Channel::Altitude, FT_TO_M),
];

/// A linearization plus the trim it was taken at.
pub struct LinearSim {
    lin: Linearization,
    trim: TrimState,
    trimmed: bool,
}

impl LinearSim {
    /// A linear simulator from a linearization (inputs named `elevator`, `aileron`, `rudder` in rad) and its trim.
    pub fn new(lin: Linearization, trim: TrimState) -> Self {
        LinearSim {
            lin,
            trim,
            trimmed: false,
        }
    }
}

impl Simulator for LinearSim {
    /// The linear model has one trim point: the one it was built at. Any other point is refused.
    fn trim(&mut self, point: &TrimPoint) -> Result<TrimState, SimError> {
        let same = (point.altitude_ft - self.trim.point.altitude_ft).abs() < 1e-6
            && (point.speed_kts - self.trim.point.speed_kts).abs() < 1e-6;
        if !same {
            return Err(SimError::TrimFailed(format!(
                "the linear model is valid only at its own trim point ({} ft, {} kts), not {} ft, {} kts",
                self.trim.point.altitude_ft, self.trim.point.speed_kts, point.altitude_ft, point.speed_kts
            )));
        }
        self.trimmed = true;
        Ok(self.trim.clone())
    }

    fn linearize(&mut self) -> Result<Linearization, SimError> {
        Ok(self.lin.clone())
    }

    fn fly(&mut self, plan: &FlightPlan) -> Result<FlightRecord, SimError> {
        if !std::mem::take(&mut self.trimmed) {
            return Err(SimError::Usage("fly needs a successful trim first".into()));
        }
        let n = plan.n_steps;
        let n_states = self.lin.states.len();
        let mut u = vec![vec![0.0; n + 1]; self.lin.inputs.len()];
        for input in &plan.inputs {
            let j = self
                .lin
                .inputs
                .iter()
                .position(|i| i == &input.surface)
                .ok_or_else(|| {
                    SimError::Usage(format!(
                        "the linear model has no input '{}' (has: {})",
                        input.surface,
                        self.lin.inputs.join(", ")
                    ))
                })?;
            u[j][..n].copy_from_slice(&input.deflection_rad);
            u[j][n] = input.deflection_rad.last().copied().unwrap_or(0.0);
        }
        let identity: Vec<Vec<f64>> = (0..n_states)
            .map(|r| (0..n_states).map(|c| f64::from(u8::from(r == c))).collect())
            .collect();
        let zeros = vec![vec![0.0; self.lin.inputs.len()]; n_states];
        let ss = StateSpace::from_rows(&self.lin.a, &self.lin.b, &identity, &zeros)
            .map_err(|e| SimError::Usage(e.to_string()))?;
        let x = lti::lsim_ss(&ss, &u, 1.0 / plan.rate_hz, None);
        let mut rec = FlightRecord::new((0..=n).map(|k| k as f64 / plan.rate_hz).collect());
        for surface in ["elevator", "aileron", "rudder"] {
            let base = self.trim.surfaces_rad.get(surface).copied().unwrap_or(0.0);
            let j = self.lin.inputs.iter().position(|i| i == surface);
            rec.push_column(
                format!("{surface}_rad"),
                (0..=n).map(|k| base + j.map_or(0.0, |j| u[j][k])).collect(),
            );
        }
        let base = |col: Channel| -> f64 {
            match col {
                Channel::Phi => self.trim.phi_rad,
                Channel::Theta => self.trim.theta_rad,
                Channel::Alpha => self.trim.alpha_rad,
                Channel::Beta => self.trim.beta_rad,
                Channel::Airspeed => self.trim.airspeed_m_s,
                Channel::Altitude => self.trim.altitude_m,
                _ => 0.0,
            }
        };
        for &(state, col, factor) in STATE_COLUMNS {
            if let Some(i) = self.lin.states.iter().position(|s| s == state) {
                rec.push_column(col, x[i].iter().map(|v| base(col) + factor * v).collect());
            }
        }
        rec.metadata.push(format!(
            "linear model of {} at {} ft, {} kts",
            self.trim.aircraft, self.trim.point.altitude_ft, self.trim.point.speed_kts
        ));
        Ok(rec)
    }
}
