//! Terms the equation-error regression holds but whose physical range its σ carry (consider parameters),
//! and the kinematic α̇ the held C_mα̇ multiplies.

use super::{FlightRecord, RegressionResult};
use crate::signal::LeastSquares;

/// α̇ from the flight-path kinematics, without differentiating the vane: with u = V cos α cos β,
/// v = V sin β, w = V sin α cos β and the body accelerations from the measured specific forces,
/// u̇ = a_x − g sin θ + r v − q w, ẇ = a_z + g cos θ cos φ + q u − p v (Klein & Morelli §3.2),
/// α̇ = (u ẇ − w u̇)/(u² + w²). `None` without a_x, a_z or θ. Gusts move the vane's α but not this α̇, the
/// rate of the airframe's own incidence (JSBSim's α̇ coefficients read the same kinematic one).
pub(super) fn kinematic_alphadot(
    record: &FlightRecord<'_>,
    v: &[f64],
    alpha: &[f64],
    q: &[f64],
    g: f64,
) -> Option<Vec<f64>> {
    let n = v.len();
    fn full(x: Option<&[f64]>, n: usize) -> Option<&[f64]> {
        x.filter(|x| x.len() == n)
    }
    let (ax, az) = (full(record.ax_m_s2, n)?, full(record.az_m_s2, n)?);
    let theta = full(record.theta_rad, n)?;
    let or_zero = |x: Option<&[f64]>, i: usize| full(x, n).map_or(0.0, |x| x[i]);
    Some(
        (0..n)
            .map(|i| {
                let (beta, phi) = (or_zero(record.beta_rad, i), or_zero(record.phi_rad, i));
                let (p, r) = (or_zero(record.p_rad_s, i), or_zero(record.r_rad_s, i));
                let u = v[i] * alpha[i].cos() * beta.cos();
                let vs = v[i] * beta.sin();
                let w = v[i] * alpha[i].sin() * beta.cos();
                let udot = ax[i] - g * theta[i].sin() + r * vs - q[i] * w;
                let wdot = az[i] + g * theta[i].cos() * phi.cos() + q[i] * u - p * vs;
                (u * wdot - w * udot) / (u * u + w * w)
            })
            .collect(),
    )
}

/// σ of a held C_mα̇ as a fraction of |C_mq| (an estimate that carries C_mα̇ with it), carried into the
/// covariance as a consider parameter (Jategaonkar §4.17; [`crate::estimate::Parameter::considered`] in the
/// estimation core). In level flight, to first order, α̇ = q + Z_α α + Z_δe δe + Z_V V̂ (the gravity term
/// varies only with sin γ₀), so C_mα̇ α̇ c̄/2V is a combination of the other regressors and the records cannot
/// separate it (Klein & Morelli §3.5). Held at 0, it leaves C_mq + C_mα̇ in C_mq, C_mα + C_mα̇ Z_α c̄/2V in
/// C_mα and C_mδe + C_mα̇ Z_δe c̄/2V in C_mδe. On the JSBSim c310 (C_mα̇ −12.7, C_mq −80, Z_α −1.5 /s,
/// c̄/2V 0.0097 s) that is +0.19 on C_mα (19 %): it came out 12–16 % high in still air and 15–22 % high in
/// light turbulence, by equation error and output error alike, and no fit of these records can mend it.
/// Downwash lag at the tail makes C_mα̇ = C_mq,tail dε/dα, with dε/dα from 0 to about 0.6 on conventional
/// aircraft, i.e. C_mα̇ between 0 and 0.4 (C_mq + C_mα̇); 0.2 |C_mq| as one σ about the held 0 spans that
/// band at 2σ, and the σ reported for C_mα, C_mq and C_mδe then says how far they could be off if the
/// aircraft has the α̇ term it physically would.
pub const CM_ALPHADOT_CONSIDER: f64 = 0.2;

/// The note on a held C_mα̇ whose range the σ carry ([`CM_ALPHADOT_CONSIDER`], σ `sd`); `free_it` says how
/// to estimate it instead.
pub fn held_alphadot_note(sd: f64, free_it: &str) -> String {
    format!(
        "Cm_alphadot is held at 0 but the records cannot tell it from the other pitch derivatives; the σ \
         reported carries its physical range (0 ± {sd:.2}, from downwash lag), so read C_mα, C_mq and C_mδe \
         with that σ: held, C_mq stands for C_mq + C_mα̇ and C_mα for C_mα + C_mα̇ Z_α c̄/(2V), the \
         equivalent derivatives ({free_it} on records that separate it)"
    )
}

/// Carries the held terms of [`RegressionResult::considered`] into the standard errors (a consider
/// parameter in linear regression): a held term c with column x_c and σ_c shifts the estimates by
/// d c, d = (XᵀX)⁻¹ Xᵀ x_c (the regression of x_c on the regressors), so the covariance grows by
/// σ_c² d dᵀ. C_mα̇'s σ_c is [`CM_ALPHADOT_CONSIDER`] |C_mq|. Returns each term considered with its σ_c.
pub fn consider_held_terms(res: &mut RegressionResult) -> Vec<(String, f64)> {
    let mut done = Vec::new();
    for (name, column) in std::mem::take(&mut res.considered) {
        let sd = match name.as_str() {
            "Cm_alphadot" => match res.terms.iter().find(|t| t.name == "Cm_q") {
                Some(t) => CM_ALPHADOT_CONSIDER * t.value.abs(),
                None => continue,
            },
            _ => continue,
        };
        let Ok(shift) = LeastSquares::fit(&res.regressors, &column) else {
            continue;
        };
        for (t, d) in res.terms.iter_mut().zip(&shift.theta) {
            let add = (sd * d).powi(2);
            t.std_error = (t.std_error.powi(2) + add).sqrt();
            t.std_error_colored = (t.std_error_colored.powi(2) + add).sqrt();
        }
        done.push((name, sd));
    }
    done
}
