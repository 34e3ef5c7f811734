//! Residual analysis per output channel: fit %, ISE, RMS, whiteness, cross-correlation with the inputs.

use serde::Serialize;

use crate::estimate::covariance;
use crate::ident::nrmse_fit;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Statistics of one channel's residual (measured − simulated).
#[derive(Debug, Clone, Serialize)]
pub struct ChannelResidual {
    /// Root mean square of the residual, column units.
    pub rms: f64,
    /// Mean of the residual (a constant offset suggests a bias or trim mismatch), column units.
    pub mean: f64,
    /// Integral of the squared residual, column units² · s.
    pub ise: f64,
    /// Fit, % (100 · (1 − ‖e‖ / ‖y − ȳ‖)).
    pub fit_percent: f64,
    /// Ljung–Box portmanteau p-value of residual whiteness (20 lags); small = coloured residual.
    pub whiteness_p: f64,
    /// Per input: peak |cross-correlation| of residual and input deviation and its lag (s, positive = residual lags).
    pub input_correlation: Vec<InputCorrelation>,
}

/// Peak normalised cross-correlation between a residual and an input.
#[derive(Debug, Clone, Serialize)]
pub struct InputCorrelation {
    /// Input (surface) name.
    pub input: String,
    /// Peak |ρ| over lags within ±2 s.
    pub peak: f64,
    /// Lag of the peak, s.
    pub lag_s: f64,
}

/// Ljung–Box Q statistic p-value for `lags` autocorrelation lags (Ljung & Box 1978, Biometrika 65, eq. 2.1).
pub fn whiteness_p(e: &[f64], lags: usize) -> f64 {
    let n = e.len();
    if n <= lags + 1 {
        return f64::NAN;
    }
    let mean = e.iter().sum::<f64>() / n as f64;
    let c0: f64 = e.iter().map(|v| (v - mean).powi(2)).sum();
    if c0 <= 0.0 {
        return 1.0;
    }
    let mut q = 0.0;
    for k in 1..=lags {
        let ck: f64 = (k..n).map(|i| (e[i] - mean) * (e[i - k] - mean)).sum();
        let rho = ck / c0;
        q += rho * rho / (n - k) as f64;
    }
    q *= n as f64 * (n as f64 + 2.0);
    match ChiSquared::new(lags as f64) {
        Ok(chi) => 1.0 - chi.cdf(q),
        Err(_) => f64::NAN,
    }
}

/// Peak of the normalised cross-correlation ρ(τ) = Σ e[k] u[k−τ] / (‖e‖‖u‖) over |τ| ≤ `max_lag` samples.
pub fn peak_cross_correlation(e: &[f64], u: &[f64], max_lag: usize) -> (f64, isize) {
    let n = e.len().min(u.len());
    let me = e[..n].iter().sum::<f64>() / n.max(1) as f64;
    let mu = u[..n].iter().sum::<f64>() / n.max(1) as f64;
    let ne: f64 = e[..n].iter().map(|v| (v - me).powi(2)).sum::<f64>().sqrt();
    let nu: f64 = u[..n].iter().map(|v| (v - mu).powi(2)).sum::<f64>().sqrt();
    if ne <= 0.0 || nu <= 0.0 {
        return (0.0, 0);
    }
    let mut best = (0.0, 0isize);
    let l = max_lag as isize;
    for lag in -l..=l {
        let mut s = 0.0;
        for k in 0..n as isize {
            let j = k - lag;
            if j >= 0 && j < n as isize {
                s += (e[k as usize] - me) * (u[j as usize] - mu);
            }
        }
        let rho = s / (ne * nu);
        if rho.abs() > best.0 {
            best = (rho.abs(), lag);
        }
    }
    best
}

/// All statistics of one channel.
pub fn analyse(
    measured: &[f64],
    simulated: &[f64],
    dt_s: f64,
    inputs: &[(String, Vec<f64>)],
) -> ChannelResidual {
    let n = measured.len().min(simulated.len());
    let e: Vec<f64> = (0..n).map(|k| measured[k] - simulated[k]).collect();
    let ss: f64 = e.iter().map(|v| v * v).sum();
    let max_lag = ((2.0 / dt_s).round() as usize).min(n / 4);
    let input_correlation = inputs
        .iter()
        .map(|(name, u)| {
            let (peak, lag) = peak_cross_correlation(&e, u, max_lag);
            InputCorrelation {
                input: name.clone(),
                peak,
                lag_s: lag as f64 * dt_s,
            }
        })
        .collect();
    ChannelResidual {
        rms: (ss / n.max(1) as f64).sqrt(),
        mean: e.iter().sum::<f64>() / n.max(1) as f64,
        ise: ss * dt_s,
        fit_percent: nrmse_fit(&measured[..n], &simulated[..n]),
        whiteness_p: whiteness_p(&e, 20),
        input_correlation,
    }
}

pub use crate::signal::noise_std;

/// Sample correlation of two sensitivity vectors (|ρ| near 1: the data cannot tell the parameters apart).
pub fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let ab: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    let aa: f64 = a.iter().map(|x| x * x).sum();
    let bb: f64 = b.iter().map(|x| x * x).sum();
    if aa <= 0.0 || bb <= 0.0 {
        0.0
    } else {
        ab / (aa * bb).sqrt()
    }
}

/// `Σ_c Σ_d Σ_i Σ_j s_c[i] R_cd(i−j) s_d[j]ᵀ` (row-major p × p) over the output channels c, d, with R_cd the
/// Bartlett-tapered cross-correlation of the channels' residuals over the lags where they are correlated
/// ([`covariance::cross_lag_weighted_products`], the estimation core's window; channel-major vectors of `m`
/// samples each). A window fitted to the residual matters in gusts: their response stays correlated over the
/// phugoid and Dutch-roll periods, and a fixed one-second window made the standard errors of the effects that
/// absorb it several times too small. So do the cross-correlations: a gust moves the vanes, the rates and the
/// accelerometers together, and channels taken as independent count it once per channel.
pub fn coloured_products(cols: &[Vec<f64>], r: &[f64], m: usize) -> Vec<f64> {
    let m = m.max(1);
    let channels: Vec<&[f64]> = r.chunks(m).collect();
    let col_refs: Vec<Vec<&[f64]>> = channels
        .iter()
        .enumerate()
        .map(|(c, rc)| cols.iter().map(|s| &s[c * m..c * m + rc.len()]).collect())
        .collect();
    covariance::cross_lag_weighted_products(&col_refs, &channels)
}

/// Effective number of independent residuals: the sum over channels of
/// [`covariance::effective_samples`] of the mean-removed residual with the window of [`coloured_products`].
pub fn effective_n(r: &[f64], m: usize) -> f64 {
    if m == 0 {
        return 0.0;
    }
    r.chunks(m)
        .map(|e| {
            let mean = e.iter().sum::<f64>() / e.len() as f64;
            let centred: Vec<f64> = e.iter().map(|v| v - mean).collect();
            covariance::effective_samples(&covariance::lag_weights(&centred), e.len())
        })
        .sum()
}

/// Least share of the change's weight Σ dᵀd that the other segments (folds) must carry for a segment to be held
/// out in [`held_out_share`] ([`cross_validated`]): a segment the others barely inform is not tested.
const HELD_OUT_MIN_REST: f64 = 0.25;

/// Least share of the change's weight that a held-out segment must carry to count.
const HELD_OUT_MIN_OWN: f64 = 0.05;

/// Leave-one-segment-out cross-validation of a fitted change (Stone 1974; Allen's PRESS): the residual moves
/// from `r_base` (the model before) to `r_fit` (after), channel-major, `len` samples per channel, the record
/// split at `segments` (sample indices of the segment starts, `ReplayCase::segments`; the one at 0 may be left
/// out). Along that change,
/// r(t) = r_base + t d with d = r_fit − r_base, each segment g is held out in turn: t is estimated from the
/// others, t₋g = −Σ_{h≠g} d_hᵀ r_h / Σ_{h≠g} d_hᵀ d_h, and the cost it removes on g, ‖r_g‖² − ‖r_g + t₋g d_g‖²,
/// is summed. Returned: that held-out reduction over the in-sample one (t = 1) on the same segments, 1 for a
/// change the segments agree on, ≤ 0 for one that fits a single segment's departure (a drift, a gust) and
/// makes the others worse. `None` when no segment can be held out (an effect one maneuver alone excites).
pub fn held_out_share(
    r_base: &[f64],
    r_fit: &[f64],
    segments: &[usize],
    len: usize,
) -> Option<f64> {
    let folds: Vec<Vec<(usize, usize)>> = segment_bounds(segments, len)
        .map(|bounds| vec![bounds])
        .collect();
    cross_validated(r_base, r_fit, &folds, len).and_then(HeldOut::share)
}

/// [start, end) of every segment of a record of `len` samples whose segments start at `segments` (a start
/// listed at 0 gives an empty first pair, dropped).
fn segment_bounds(segments: &[usize], len: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
    std::iter::once(0)
        .chain(segments.iter().copied())
        .zip(segments.iter().copied().chain(std::iter::once(len)))
        .filter(|(b, e)| b < e)
}

/// The record split in time into two folds for [`cross_validated`]: the first half of every segment, and the
/// second half of every segment (`segments`: the segment starts, `len` samples). Every maneuver lies in both
/// folds, so a change that any maneuver excites is informed in both; the two folds are different stretches
/// of the flight, seconds apart within each maneuver, so they meet different gusts.
pub fn segment_halves(segments: &[usize], len: usize) -> [Vec<(usize, usize)>; 2] {
    let mut folds = [Vec::new(), Vec::new()];
    for (b, e) in segment_bounds(segments, len) {
        let mid = b + (e - b) / 2;
        folds[0].push((b, mid));
        folds[1].push((mid, e));
    }
    folds
}

/// What a fitted change does on the parts of the record held out from its sizing ([`cross_validated`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeldOut {
    /// Σ over the held-out folds g of ‖r_g‖² − ‖r_g + t₋g d_g‖²: the cost the change, sized from the other
    /// folds, removes where it was not sized.
    pub reduction: f64,
    /// The cost the fit itself (t = 1) removes on the same folds.
    pub in_sample: f64,
}

impl HeldOut {
    /// The held-out reduction over the in-sample one (None when the fit removes nothing there).
    pub fn share(self) -> Option<f64> {
        (self.in_sample > 0.0).then(|| self.reduction / self.in_sample)
    }
}

/// Leave-one-fold-out cross-validation of a fitted change along its direction d = r_fit − r_base (see
/// [`held_out_share`]); each fold is a set of [start, end) sample ranges of every channel (`len` samples per
/// channel, channel-major). A fold is held out only when the other folds carry at least
/// [`HELD_OUT_MIN_REST`] of Σ dᵀd and it carries [`HELD_OUT_MIN_OWN`]. `None` when no fold can be held out.
pub fn cross_validated(
    r_base: &[f64],
    r_fit: &[f64],
    folds: &[Vec<(usize, usize)>],
    len: usize,
) -> Option<HeldOut> {
    if len == 0 || r_base.len() != r_fit.len() || !r_base.len().is_multiple_of(len) {
        return None;
    }
    // per fold: dᵀd, dᵀr
    let sums: Vec<(f64, f64)> = folds
        .iter()
        .map(|ranges| {
            let (mut dd, mut dr) = (0.0, 0.0);
            for &(b, e) in ranges {
                for c in 0..r_base.len() / len {
                    for k in c * len + b..c * len + e.min(len) {
                        let d = r_fit[k] - r_base[k];
                        dd += d * d;
                        dr += d * r_base[k];
                    }
                }
            }
            (dd, dr)
        })
        .collect();
    let (total_dd, total_dr) = sums
        .iter()
        .fold((0.0, 0.0), |(a, b), &(dd, dr)| (a + dd, b + dr));
    if total_dd <= 0.0 {
        return None;
    }
    let mut out = HeldOut {
        reduction: 0.0,
        in_sample: 0.0,
    };
    let mut tested = false;
    for &(dd, dr) in &sums {
        let rest = total_dd - dd;
        if rest < HELD_OUT_MIN_REST * total_dd || dd < HELD_OUT_MIN_OWN * total_dd {
            continue;
        }
        let t = -(total_dr - dr) / rest;
        out.reduction += -(2.0 * t * dr + t * t * dd);
        out.in_sample += -(2.0 * dr + dd);
        tested = true;
    }
    tested.then_some(out)
}

#[cfg(test)]
mod tests {
    use super::held_out_share;

    /// Two channels of 300 samples, segments starting at 100 and 200; `f(channel, k)`.
    fn series(f: impl Fn(usize, usize) -> f64) -> Vec<f64> {
        (0..2)
            .flat_map(|c| (0..300).map(move |k| (c, k)))
            .map(|(c, k)| f(c, k))
            .collect()
    }

    fn wiggle(c: usize, k: usize) -> f64 {
        ((k as f64) * 0.37 + c as f64).sin()
    }

    #[test]
    fn a_change_every_segment_agrees_on_keeps_its_whole_gain() {
        // the base misses the same signature everywhere; the fit removes it
        let base = series(|c, k| 2.0 * wiggle(c, k));
        let fit = series(|_, _| 0.0);
        let share = held_out_share(&base, &fit, &[100, 200], 300).expect("testable");
        assert!((share - 1.0).abs() < 1e-12, "{share}");
    }

    #[test]
    fn a_change_that_fits_one_segment_and_spoils_the_others_gains_nothing_held_out() {
        // segment 1 departs by +2 w, the others not; the fit moves all three by −0.7 w (the compromise)
        let base = series(|c, k| if k < 100 { 2.0 * wiggle(c, k) } else { 0.0 });
        let fit = series(base_minus);
        fn base_minus(c: usize, k: usize) -> f64 {
            let b = if k < 100 { 2.0 * wiggle(c, k) } else { 0.0 };
            b - 0.7 * wiggle(c, k)
        }
        let share = held_out_share(&base, &fit, &[100, 200], 300).expect("testable");
        assert!(share < 0.0, "{share}");
    }

    #[test]
    fn a_change_one_segment_alone_carries_cannot_be_held_out() {
        let base = series(|c, k| {
            if (100..200).contains(&k) {
                wiggle(c, k)
            } else {
                0.0
            }
        });
        let fit = series(|_, _| 0.0);
        assert_eq!(held_out_share(&base, &fit, &[100, 200], 300), None);
    }

    #[test]
    fn every_segment_is_split_at_its_middle_into_the_two_halves() {
        use super::segment_halves;
        // segments listed as `ReplayCase::segments` lists them (the first at 0), one of odd length
        let [first, second] = segment_halves(&[0, 100, 251], 300);
        assert_eq!(first, vec![(0, 50), (100, 175), (251, 275)]);
        assert_eq!(second, vec![(50, 100), (175, 251), (275, 300)]);
    }

    #[test]
    fn the_held_out_share_matches_a_direct_leave_one_out() {
        // pseudo-random residuals and change; three segments of unequal length
        let mut state = 12345u64;
        let mut rnd = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let (len, segments) = (250, [80usize, 170]);
        let base: Vec<f64> = (0..2 * len).map(|_| rnd()).collect();
        let fit: Vec<f64> = base.iter().map(|b| 0.6 * b + 0.3 * rnd()).collect();
        // direct: per held-out segment, t by the parabola through three evaluations of the others' cost
        let seg = |k: usize| segments.iter().filter(|&&b| k % len >= b).count();
        let cost = |t: f64, keep: &dyn Fn(usize) -> bool| -> f64 {
            (0..2 * len)
                .filter(|&k| keep(seg(k)))
                .map(|k| (base[k] + t * (fit[k] - base[k])).powi(2))
                .sum()
        };
        let (mut held, mut fitted) = (0.0, 0.0);
        for g in 0..3 {
            let others = |s: usize| s != g;
            let (c0, c1, c2) = (cost(-1.0, &others), cost(0.0, &others), cost(1.0, &others));
            let t = 0.5 * (c0 - c2) / (c0 - 2.0 * c1 + c2);
            let own = |s: usize| s == g;
            held += cost(0.0, &own) - cost(t, &own);
            fitted += cost(0.0, &own) - cost(1.0, &own);
        }
        let share = held_out_share(&base, &fit, &segments, len).expect("testable");
        // the same with the first segment's start listed, as `ReplayCase::segments` lists it
        assert_eq!(held_out_share(&base, &fit, &[0, 80, 170], len), Some(share));
        assert!(
            (share - held / fitted).abs() < 1e-9,
            "{share} vs {}",
            held / fitted
        );
    }
}
