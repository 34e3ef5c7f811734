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
//! off: a channel whose mean square exceeds [`RELAX_MIN`] times its noise variance is weighted by that mean
//! square instead. A record whose every channel sits near its noise (a clean record in still air) keeps the
//! noise weights. Held for the whole search, so that the costs of every round stay comparable; the floor at
//! which a residual earns no further credit stays at the measurement noise
//! ([`super::search::Weighted::noise_cost`]).

use std::collections::BTreeMap;

use super::prepare::Prepared;
use super::search::{self, Worker};
use super::{sim_err, DiagnoseError};

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
) -> Result<(Vec<Vec<f64>>, BTreeMap<String, f64>), DiagnoseError> {
    if !enabled {
        return Ok((columns, BTreeMap::new()));
    }
    p.nuisance = search::orthonormal_basis(&columns);
    let r = search::residuals(worker, &p.training(), &[]).map_err(sim_err("replay"))?;
    let factors = relaxation(&r, p.case.len());
    if factors.iter().all(|&f| f == 1.0) {
        return Ok((columns, BTreeMap::new()));
    }
    let len = p.case.len();
    for (s, f) in p.sigma.iter_mut().zip(&factors) {
        *s *= f.sqrt();
    }
    p.noise_cost = factors.iter().map(|f| len as f64 / f).sum();
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

/// Per channel of the channel-major residual `r` (channels of `len` samples): its mean square where above
/// [`RELAX_MIN`], else 1.
fn relaxation(r: &[f64], len: usize) -> Vec<f64> {
    r.chunks(len.max(1))
        .map(|c| {
            let ms = crate::signal::sum_sq(c) / c.len() as f64;
            if ms > RELAX_MIN {
                ms
            } else {
                1.0
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_channels_far_above_their_noise_are_relaxed() {
        // Two channels of four samples: one at its noise (mean square 1), one at 100 times it.
        let r = [1.0, -1.0, 1.0, -1.0, 10.0, -10.0, 10.0, 10.0];
        assert_eq!(relaxation(&r, 4), vec![1.0, 100.0]);
        // Just above the threshold is relaxed, just below is not.
        let r = [2.01, 2.01, 1.99, 1.99];
        assert_eq!(relaxation(&r, 2), vec![2.01 * 2.01, 1.0]);
    }
}
