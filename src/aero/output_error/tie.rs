//! The tie of C_Lα̇ to C_Lq that filter error's α̇ check uses ([`lift_alphadot_tied`]).

use super::free_block;
use crate::aero::flight_models::LONGITUDINAL_PARAMETERS;
use crate::estimate::{self, Method};

/// θ indices of C_Lq, C_Lα̇, C_mq and C_mα̇.
pub(super) fn lift_alphadot_indices() -> [usize; 4] {
    ["CL_q", "CL_alphadot", "Cm_q", "Cm_alphadot"].map(|n| {
        LONGITUDINAL_PARAMETERS
            .iter()
            .position(|p| *p == n)
            .expect("a longitudinal parameter")
    })
}

/// Whether a filter-error fit ties C_Lα̇ to C_Lq: when C_Lq and C_mα̇ are free and C_Lα̇ is held (the α̇ check's
/// wider fit, [`super::checks::ALPHADOT`], and every fit after it adopts). With the accelerometer measuring the whole
/// lift, α̇ = q − q̄S C_L/(mV) + g cos γ/V makes the lift equation C_L (1 + ρSc̄ C_Lα̇/(4m)) = C_L0 + C_Lα α +
/// (C_Lq + C_Lα̇) q̂ + …: the records fix the sum C_Lq + C_Lα̇, and their split only rescales every lift derivative
/// by 1 + ρSc̄ C_Lα̇/(4m) (Klein & Morelli §3.5). Filter error's gust states add the rotary gust, which C_Lq sees
/// and C_Lα̇ does not, but that share of the lift is a few parts in a thousand, and the split it gives follows
/// whatever else the model misses: freed together, C_Lq and C_Lα̇ came out 0–11 and 11–19 on the c310 (JSBSim 9.5
/// and 5.1), C_Lα +2…+4.4 % off in step with ρSc̄ ΔC_Lα̇/(4m), and on two of five seeds the wider fit ran off.
/// Holding C_Lq at 0 put C_Lα +4…+6 % off on all five; holding C_Lα̇ at 0 put it −1.8 % off (−ρSc̄ C_Lα̇/(4m)) and
/// C_mq, C_mδe 7–12 % off on two. The tie pins the split as a horizontal tail does (Etkin & Reid §5.4): its lift
/// and moment per unit q are C_Lq,t = 2 a_t η V_H and C_mq,t = −(l_t/c̄) C_Lq,t, and downwash lag multiplies both
/// by dε/dα, so C_Lα̇/C_Lq = C_mα̇/C_mq = dε/dα, a ratio the pitch equation does determine; C_Lα̇ = C_Lq
/// C_mα̇/C_mq. On five c310 gust realisations it gave C_Lα̇ 3.1–6.5 (JSBSim 5.1) and C_Lα, C_mq, C_mδe within 2 %;
/// C_Lq itself, which carries the whole q̂ share of the lift, came out 18–26.
pub(super) fn lift_alphadot_tied(method: Method, free: impl Fn(&str) -> bool) -> bool {
    method == Method::Fem && free("CL_q") && free("Cm_alphadot") && !free("CL_alphadot")
}

/// C_Lα̇ = C_Lq C_mα̇/C_mq ([`lift_alphadot_tied`]; 0 when C_mq is 0).
pub(super) fn tied_lift_alphadot(theta: &[f64]) -> f64 {
    let [clq, _, cmq, cmad] = lift_alphadot_indices();
    if theta[cmq] == 0.0 {
        0.0
    } else {
        theta[clq] * theta[cmad] / theta[cmq]
    }
}

/// σ of the tied C_Lα̇ = C_Lq C_mα̇/C_mq ([`lift_alphadot_tied`]) by first-order propagation of the covariance of
/// C_Lq, C_mα̇ and C_mq (0 when C_mq is 0, as the tie's value is).
pub(super) fn tied_lift_alphadot_sigma(est: &estimate::Estimate) -> f64 {
    let (free, cov) = free_block(est);
    let [clq, _, cmq, cmad] = lift_alphadot_indices();
    let v = |i: usize| est.parameters[i].value;
    if v(cmq) == 0.0 {
        return 0.0;
    }
    let gradient = [
        (clq, v(cmad) / v(cmq)),
        (cmad, v(clq) / v(cmq)),
        (cmq, -v(clq) * v(cmad) / (v(cmq) * v(cmq))),
    ];
    let at = |i: usize| free.iter().position(|&f| f == i);
    let mut var = 0.0;
    for &(i, gi) in &gradient {
        for &(j, gj) in &gradient {
            if let (Some(a), Some(b)) = (at(i), at(j)) {
                var += gi * cov[a][b] * gj;
            }
        }
    }
    var.max(0.0).sqrt()
}
