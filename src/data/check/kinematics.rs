//! The flight-path reconstruction of the compatibility check: the rigid-body kinematics driven by the
//! measured rates and specific forces (Klein & Morelli eq. 10.1–10.3), the altitude among them, integrated
//! by Runge–Kutta 4 with the inputs linear over each sample interval, and the output model
//! `y_m(t) = (1 + s) · y(t − τ) + b`. The altitude pins the flight-path angle: without it a rotation of the
//! velocity vector about the y axis, with an α bias to match, fits V, α and the specific forces nearly as
//! well (on pa28 records in light turbulence the α bias came out at 34°).

use crate::data::record::G0_M_S2;

/// One estimated quantity of the check, with the index of the signal it applies to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Param {
    GyroBias(usize),
    AccelBias(usize),
    OutBias(usize),
    OutScale(usize),
    OutSkew(usize),
    /// A state at the start of the record.
    Init(usize),
    /// A state at the start of piece `.0` (1, 2, …) of a record with dropouts.
    PieceInit(usize, usize),
}

/// Number of outputs (and of states).
pub(super) const N_OUT: usize = 7;

/// Output indices: V, α, β, φ, θ, ψ, h.
pub(super) const OUT_NAMES: [&str; N_OUT] = [
    "airspeed_m_s",
    "alpha_rad",
    "beta_rad",
    "phi_rad",
    "theta_rad",
    "psi_rad",
    "altitude_m",
];

/// Indices of the roll and pitch attitude among the outputs and the states.
pub(super) const PHI: usize = 3;
pub(super) const THETA: usize = 4;

/// Index of the altitude among the outputs and the states.
pub(super) const ALTITUDE: usize = 6;
const GYRO: [&str; 3] = ["p_rad_s", "q_rad_s", "r_rad_s"];
const ACCEL: [&str; 3] = ["ax_m_s2", "ay_m_s2", "az_m_s2"];
const STATE_NAMES: [&str; N_OUT] = [
    "u_m_s",
    "v_m_s",
    "w_m_s",
    "phi_rad",
    "theta_rad",
    "psi_rad",
    "altitude_m",
];

impl Param {
    /// (parameter name, column it applies to).
    pub(super) fn name(self) -> (String, String) {
        match self {
            Param::GyroBias(i) => (format!("bias_{}", GYRO[i]), GYRO[i].into()),
            Param::AccelBias(i) => (format!("bias_{}", ACCEL[i]), ACCEL[i].into()),
            Param::OutBias(j) => (format!("bias_{}", OUT_NAMES[j]), OUT_NAMES[j].into()),
            Param::OutScale(j) => (
                format!("scale_{}", OUT_NAMES[j].split('_').next().unwrap_or("")),
                OUT_NAMES[j].into(),
            ),
            Param::OutSkew(j) => (
                format!("skew_{}_s", OUT_NAMES[j].split('_').next().unwrap_or("")),
                OUT_NAMES[j].into(),
            ),
            Param::Init(k) => (format!("initial_{}", STATE_NAMES[k]), STATE_NAMES[k].into()),
            Param::PieceInit(p, k) => (
                format!("initial_{}_piece{}", STATE_NAMES[k], p + 1),
                STATE_NAMES[k].into(),
            ),
        }
    }

    /// Finite-difference step and practical significance floor.
    pub(super) fn step_and_floor(self) -> (f64, f64) {
        match self {
            // 0.05 °/s: below the resolution a flight-test engineer acts on.
            Param::GyroBias(_) => (1e-6, 0.05_f64.to_radians()),
            Param::AccelBias(_) => (1e-5, 0.02),
            Param::OutBias(0) => (1e-5, 0.1),
            Param::OutBias(_) => (1e-7, 0.1_f64.to_radians()),
            Param::OutScale(_) => (1e-6, 0.01),
            Param::OutSkew(_) => (1e-4, 0.01),
            Param::Init(k) | Param::PieceInit(_, k) if k < 3 => (1e-5, 0.0),
            Param::Init(ALTITUDE) | Param::PieceInit(_, ALTITUDE) => (1e-3, 0.0),
            Param::Init(_) | Param::PieceInit(..) => (1e-7, 0.0),
        }
    }

    /// The state this parameter starts, for an initial state (of any piece).
    pub(super) fn initial_state(self) -> Option<usize> {
        match self {
            Param::Init(k) | Param::PieceInit(_, k) => Some(k),
            _ => None,
        }
    }
}

/// Measured data laid out for the reconstruction.
pub(super) struct Data {
    pub(super) t: Vec<f64>,
    pub(super) gyro: [Vec<f64>; 3],
    pub(super) accel: Option<[Vec<f64>; 3]>,
    /// Measured outputs; `None` when the column is absent.
    pub(super) out: [Option<Vec<f64>>; N_OUT],
    /// The samples after a dropout ([`crate::data::dropout_starts`]): each begins a piece that starts
    /// from its own initial state, as integrating over the missing samples would invent the motion in them.
    pub(super) piece_starts: Vec<usize>,
}

/// Rigid-body kinematics: state derivative for rates ω and specific force f.
fn derivative(x: &[f64; N_OUT], w: [f64; 3], f: [f64; 3], translational: bool) -> [f64; N_OUT] {
    let [u, v, wv, phi, theta, _, _] = *x;
    let [p, q, r] = w;
    let (sphi, cphi) = phi.sin_cos();
    let (sth, cth) = theta.sin_cos();
    let g = G0_M_S2;
    let (du, dv, dw) = if translational {
        (
            r * v - q * wv - g * sth + f[0],
            p * wv - r * u + g * cth * sphi + f[1],
            q * u - p * v + g * cth * cphi + f[2],
        )
    } else {
        (0.0, 0.0, 0.0)
    };
    let cth_safe = if cth.abs() < 1e-6 {
        1e-6_f64.copysign(cth)
    } else {
        cth
    };
    [
        du,
        dv,
        dw,
        p + sth / cth_safe * (q * sphi + r * cphi),
        q * cphi - r * sphi,
        (q * sphi + r * cphi) / cth_safe,
        u * sth - v * sphi * cth - wv * cphi * cth,
    ]
}

/// Integrates the kinematics and returns the residuals `y_m − model` for each output used.
pub(super) fn residuals(
    data: &Data,
    params: &[Param],
    th: &[f64],
    outputs: &[usize],
) -> Vec<Vec<f64>> {
    let n = data.t.len();
    let mut gyro_bias = [0.0; 3];
    let mut accel_bias = [0.0; 3];
    let mut bias = [0.0; N_OUT];
    let mut scale = [0.0; N_OUT];
    let mut skew = [0.0; N_OUT];
    let mut x0 = vec![[0.0; N_OUT]; data.piece_starts.len() + 1];
    for (p, &v) in params.iter().zip(th) {
        match *p {
            Param::GyroBias(i) => gyro_bias[i] = v,
            Param::AccelBias(i) => accel_bias[i] = v,
            Param::OutBias(j) => bias[j] = v,
            Param::OutScale(j) => scale[j] = v,
            Param::OutSkew(j) => skew[j] = v,
            Param::Init(k) => x0[0][k] = v,
            Param::PieceInit(piece, k) => x0[piece][k] = v,
        }
    }
    let translational = data.accel.is_some();
    let inputs = |k: usize| -> ([f64; 3], [f64; 3]) {
        let w = [0, 1, 2].map(|i| data.gyro[i][k] - gyro_bias[i]);
        let f = match &data.accel {
            Some(a) => [0, 1, 2].map(|i| a[i][k] - accel_bias[i]),
            None => [0.0; 3],
        };
        (w, f)
    };
    // Model outputs at every sample.
    let mut y: Vec<[f64; N_OUT]> = Vec::with_capacity(n);
    let mut x = x0[0];
    let mut next_piece = 0;
    for k in 0..n {
        if data.piece_starts.get(next_piece) == Some(&k) {
            next_piece += 1;
            x = x0[next_piece];
        }
        y.push(outputs_of(&x));
        if k + 1 == n {
            break;
        }
        let h = data.t[k + 1] - data.t[k];
        let (w0, f0) = inputs(k);
        let (w1, f1) = inputs(k + 1);
        let mid = |a: [f64; 3], b: [f64; 3]| [0, 1, 2].map(|i| 0.5 * (a[i] + b[i]));
        let (wm, fm) = (mid(w0, w1), mid(f0, f1));
        let k1 = derivative(&x, w0, f0, translational);
        let k2 = derivative(&add(&x, &k1, 0.5 * h), wm, fm, translational);
        let k3 = derivative(&add(&x, &k2, 0.5 * h), wm, fm, translational);
        let k4 = derivative(&add(&x, &k3, h), w1, f1, translational);
        for i in 0..N_OUT {
            x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        if x.iter().any(|v| !v.is_finite()) {
            // Diverged: make the cost infinite so the step is rejected.
            return outputs.iter().map(|_| vec![f64::INFINITY; n]).collect();
        }
    }
    outputs
        .iter()
        .map(|&j| {
            let meas = data.out[j].as_ref().map_or(&[][..], Vec::as_slice);
            (0..n)
                .map(|k| {
                    let model =
                        (1.0 + scale[j]) * sample_at(&data.t, &y, j, data.t[k] - skew[j]) + bias[j];
                    meas[k] - model
                })
                .collect()
        })
        .collect()
}

fn add(x: &[f64; N_OUT], d: &[f64; N_OUT], h: f64) -> [f64; N_OUT] {
    std::array::from_fn(|i| x[i] + h * d[i])
}

/// V, α, β, φ, θ, ψ, h from the state.
fn outputs_of(x: &[f64; N_OUT]) -> [f64; N_OUT] {
    let [u, v, w, phi, theta, psi, altitude] = *x;
    let vt = (u * u + v * v + w * w).sqrt();
    let beta = if vt > 0.0 {
        (v / vt).clamp(-1.0, 1.0).asin()
    } else {
        0.0
    };
    [vt, w.atan2(u), beta, phi, theta, psi, altitude]
}

/// Output `j` of the model at time `t` (linear interpolation, held at the ends).
fn sample_at(time: &[f64], y: &[[f64; N_OUT]], j: usize, t: f64) -> f64 {
    let n = time.len();
    if t <= time[0] {
        return y[0][j];
    }
    if t >= time[n - 1] {
        return y[n - 1][j];
    }
    let k = time
        .partition_point(|&s| s <= t)
        .saturating_sub(1)
        .min(n - 2);
    let w = (t - time[k]) / (time[k + 1] - time[k]);
    y[k][j] + w * (y[k + 1][j] - y[k][j])
}
