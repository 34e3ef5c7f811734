//! Stage 1b, channel weights: each channel weighted by its actual misfit, not only by its sensor noise.
//!
//! The search weights every channel by its measurement noise, which is the maximum-likelihood weighting only
//! when the residual is that noise. In turbulence it is not: the gusts' response is tens to thousands of times
//! the noise in the attitude angles, the altitude and the airspeed, which integrate it. The cost is then that of
//! one or two channels, a candidate that bends φ or θ towards the gusts' drift looks like a cause, and the rate
//! gyros, where an effect's signature is sharp, count for little.
//!
//! Output error with the residual covariance unknown estimates it with the parameters, `R = (1/N) Σ ν νᵀ`, and
//! the relaxation algorithm holds it fixed while the parameters are fitted (Jategaonkar, *Flight Vehicle System
//! Identification*, 2nd ed., §4.3–4.4; Klein & Morelli, *Aircraft System Identification*, §6.1). Here `R` is
//! diagonal and estimated once, from the unextended model's residual with the segment initial states projected
//! off and, per channel, what an offset, a scale of the simulated output and a linear response to the inputs
//! explain (a sensor's bias and scale factor and any wrong derivative are candidates, not process noise;
//! [`relaxation`]): a channel whose remaining mean square exceeds [`RELAX_MIN`] times its noise variance is
//! weighted by that mean square instead. A record whose every channel sits near its noise (a clean record in still air) keeps the
//! noise weights. Held for the whole search, so that the costs of every round stay comparable; the floor at
//! which a residual earns no further credit stays at the measurement noise
//! ([`super::search::Weighted::noise_cost`]).

use std::collections::BTreeMap;

use super::prepare::Prepared;
use super::search::{self, Worker};
use super::{sim_err, DiagnoseError};

/// The nuisance columns in the relaxed weights, and each relaxed channel's factor on its noise variance.
pub type Relaxed = (Vec<Vec<f64>>, BTreeMap<String, f64>);

/// Mean square of a channel's noise-normalised residual above which its weight is relaxed to it: well above
/// what a clean record leaves (1–3 on the independent generator's still-air records).
pub const RELAX_MIN: f64 = 4.0;

/// Relaxes the training record's channel weights `p.sigma` to the unextended model's residual, with the
/// segment initial-state responses `columns` (noise-normalised, channel-major) as the nuisance terms. Returns
/// the columns in the new weights and, per relaxed channel, the factor its variance was multiplied by. With
/// `enabled` false the noise weights stay.
pub fn relax(
    worker: &mut Worker,
    p: &mut Prepared,
    columns: Vec<Vec<f64>>,
    enabled: bool,
) -> Result<Relaxed, DiagnoseError> {
    if !enabled {
        return Ok((columns, BTreeMap::new()));
    }
    p.nuisance = search::orthonormal_basis(&columns);
    let r = search::residuals(worker, &p.training(), &[]).map_err(sim_err("replay"))?;
    let (trace, _) = search::simulate(worker, &p.case, &[]).map_err(sim_err("replay"))?;
    let simulated: Vec<&[f64]> = p
        .case
        .outputs
        .iter()
        .map(|c| trace.column(c).unwrap_or(&[]))
        .collect();
    let len = p.case.len();
    let driven = input_responses(&p.case.inputs, p.case.dt_s());
    let factors = relaxation(&r, &simulated, &driven, len);
    if factors.iter().all(|&f| f == 1.0) {
        return Ok((columns, BTreeMap::new()));
    }
    for (s, f) in p.sigma.iter_mut().zip(&factors) {
        *s *= f.sqrt();
    }
    let columns = columns
        .into_iter()
        .map(|mut c| {
            for (chunk, f) in c.chunks_mut(len).zip(&factors) {
                let g = f.sqrt().recip();
                chunk.iter_mut().for_each(|v| *v *= g);
            }
            c
        })
        .collect();
    let relaxed: BTreeMap<String, f64> = p
        .case
        .outputs
        .iter()
        .zip(&factors)
        .filter(|(_, &f)| f > 1.0)
        .map(|(c, &f)| (c.clone(), f))
        .collect();
    p.warnings.push(format!(
        "the unextended model misses {} by far more than their sensor noise (turbulence, or a large effect): \
         the search weights each channel by its residual instead (variance × {})",
        relaxed.keys().cloned().collect::<Vec<_>>().join(", "),
        relaxed
            .values()
            .map(|f| format!("{f:.0}"))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    Ok((columns, relaxed))
}

/// Per channel of the channel-major residual `r` (channels of `len` samples): the mean square of what an
/// offset, a scale of the channel's `simulated` output and the input responses `driven` leave of it, where
/// above [`RELAX_MIN`], else 1.
///
/// What the regressors take out is misfit that a cause explains, not the record's process noise:
/// - a sensor's bias and scale factor are candidates of the search: a hidden q-gyro scale of 1.13 alone left
///   q's residual at 38 times its noise on a turbulent record, and weighted by that the scale's own channel no
///   longer counted. The simulated output, not the measured one, is the regressor: the measured one carries
///   the gusts' response, which is the misfit to keep;
/// - about a trim point both the model and the aircraft are close to linear, so the misfit that any wrong
///   derivative, control power, delay or lag leaves is the response of a linear system to the inputs, which
///   the Laguerre responses span; gusts are not driven by the inputs of an open-loop maneuver. In still air
///   a hidden `Cn_beta` ×0.41 left β, p, r and φ at 160–940 times their noise, and weighted by that the
///   search named a rudder delay instead.
fn relaxation(r: &[f64], simulated: &[&[f64]], driven: &[Vec<f64>], len: usize) -> Vec<f64> {
    // The offset and the input responses are every channel's: orthonormalised once.
    let mut shared = vec![vec![1.0; len]];
    shared.extend(driven.iter().filter(|d| d.len() == len).cloned());
    let shared = search::orthonormal_basis(&shared);
    r.chunks(len.max(1))
        .enumerate()
        .map(|(c, chunk)| {
            let mut e = chunk.to_vec();
            search::project_off(&mut e, &shared);
            // The channel's own scale: its simulated output, orthogonal to the shared directions.
            if let Some(s) = simulated.get(c).filter(|s| s.len() == chunk.len()) {
                let mut s = s.to_vec();
                search::project_off(&mut s, &shared);
                search::project_off(&mut e, &search::orthonormal_basis(&[s]));
            }
            let ms = crate::signal::sum_sq(&e) / e.len().max(1) as f64;
            if ms > RELAX_MIN {
                ms
            } else {
                1.0
            }
        })
        .collect()
}

/// Laguerre banks the input responses are expanded in: (time constant s, number of functions). The fast bank
/// spans the short-period, roll and Dutch-roll responses, the slow one the start of the phugoid and spiral
/// (their long tails are the segment initial states').
const LAGUERRE_BANKS: [(f64, usize); 2] = [(0.4, 6), (4.0, 4)];

/// The responses of every input that moves to the discrete Laguerre functions of [`LAGUERRE_BANKS`]
/// (Wahlberg, IEEE Trans. AC 36, 1991): `L₁(q) = √(1 − a²) / (1 − a q⁻¹)`, `L_{j+1} = L_j (q⁻¹ − a) /
/// (1 − a q⁻¹)`, `a = e^{−Δt/τ}`. An orthonormal basis of stable linear responses: a few functions per input
/// fit any linear response whose time scale is near τ.
fn input_responses(inputs: &[(String, Vec<f64>)], dt_s: f64) -> Vec<Vec<f64>> {
    let mut out = Vec::new();
    for (_, u) in inputs {
        if u.iter().all(|v| *v == u[0]) {
            continue;
        }
        for (tau_s, count) in LAGUERRE_BANKS {
            let a = (-dt_s / tau_s).exp();
            let g = (1.0 - a * a).sqrt();
            let mut x: Vec<f64> = Vec::with_capacity(u.len());
            let mut prev = 0.0;
            for v in u {
                prev = a * prev + g * v;
                x.push(prev);
            }
            for _ in 0..count {
                out.push(x.clone());
                // The all-pass section (q⁻¹ − a) / (1 − a q⁻¹): y_k = a y_{k−1} + x_{k−1} − a x_k.
                let mut y = vec![0.0; x.len()];
                for k in 0..x.len() {
                    let (y1, x1) = if k > 0 {
                        (y[k - 1], x[k - 1])
                    } else {
                        (0.0, 0.0)
                    };
                    y[k] = a * y1 + x1 - a * x[k];
                }
                x = y;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_channels_far_above_their_noise_are_relaxed() {
        // Two channels of four samples, the simulated outputs flat: one at its noise (mean square 1), one at
        // 100 times it.
        let flat = [0.0; 4];
        let r = [1.0, -1.0, 1.0, -1.0, 10.0, -10.0, 10.0, -10.0];
        assert_eq!(relaxation(&r, &[&flat, &flat], &[], 4), vec![1.0, 100.0]);
        // Just above the threshold is relaxed, just below is not.
        let r = [2.01, -2.01, 1.99, -1.99];
        let flat = [0.0; 2];
        let f = relaxation(&r, &[&flat, &flat], &[], 2);
        assert!((f[0] - 2.01 * 2.01).abs() < 1e-12 && f[1] == 1.0, "{f:?}");
    }

    #[test]
    fn a_sensor_offset_and_scale_do_not_relax_their_channel() {
        // The residual of a channel whose sensor reads 1.2 × the simulated output plus an offset, with a
        // little noise: the offset and the scale are the search's to find, so the channel keeps its weight.
        let s: Vec<f64> = (0..200).map(|k| 30.0 * (0.1 * k as f64).sin()).collect();
        let noise = |k: usize| if k.is_multiple_of(2) { 0.9 } else { -0.9 };
        let r: Vec<f64> = (0..200).map(|k| 0.2 * s[k] + 5.0 + noise(k)).collect();
        assert_eq!(relaxation(&r, &[&s], &[], 200), vec![1.0]);
        // The same misfit uncorrelated with the output (a gust's response) is relaxed.
        let c: Vec<f64> = (0..200).map(|k| 30.0 * (0.1 * k as f64).cos()).collect();
        let r: Vec<f64> = (0..200).map(|k| 0.2 * c[k] + noise(k)).collect();
        assert!(relaxation(&r, &[&s], &[], 200)[0] > 4.0);
    }

    #[test]
    fn a_misfit_driven_by_the_inputs_does_not_relax_its_channel() {
        // 20 s at 50 Hz: an elevator doublet, and the residual of a model whose pitch response to it is off, a
        // lightly damped second-order response (ω 3 rad/s, ζ 0.3), 30 times the noise at its peak.
        let (dt, n) = (0.02, 1000);
        let u: Vec<f64> = (0..n)
            .map(|k| match k as f64 * dt {
                t if (2.0..3.0).contains(&t) => 1.0,
                t if (3.0..4.0).contains(&t) => -1.0,
                _ => 0.0,
            })
            .collect();
        let (w, z) = (3.0f64, 0.3);
        let (mut x, mut v) = (0.0, 0.0);
        let noise = |k: usize| if k.is_multiple_of(2) { 1.0 } else { -1.0 };
        let r: Vec<f64> = (0..n)
            .map(|k| {
                let acc = w * w * (u[k] - x) - 2.0 * z * w * v;
                v += acc * dt;
                x += v * dt;
                30.0 * x + noise(k)
            })
            .collect();
        let driven = input_responses(&[("elevator".into(), u)], dt);
        assert_eq!(relaxation(&r, &[&[]], &driven, n), vec![1.0]);
        // Without the input responses the same channel is relaxed.
        assert!(relaxation(&r, &[&[]], &[], n)[0] > 4.0);
    }
}
