//! Turbulence in the search: the filter error method on the replay's residuals.
//!
//! The replay is deterministic. A record flown in gusts departs from it by the gusts' response, which output
//! error can only take for a cause or leave as coloured residual. To first order about the replayed trajectory
//! the error of the replayed state obeys linear dynamics driven by the gusts, and the noise-normalised
//! residual is its output plus measurement noise:
//!
//! `δx_{k+1} = A δx_k + w_k`,  `r_k = C δx_k + v_k`.
//!
//! `A` and `C` come from the responses that the segment initial states already need
//! ([`super::initial_state::initial_state_columns`]): the response to a unit perturbation `e_j` of state j at a
//! segment start is `Y(k) e_j` with `Y(k) = C A^{k−k₀}`, so `A` is the least-squares solution of
//! `Y(k+1) = Y(k) A` over the first [`MODEL_HORIZON_S`] of every segment, and `C = Y(k₀)`.
//!
//! The filter error method (Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., ch. 5; the
//! estimation core's steady-state gain, `estimate::fem::gain`) replaces the residual by the innovations
//! `ν_k = r_k − C x̃_k`, `x̂_k = x̃_k + K ν_k`, `x̃_{k+1} = A x̂_k`, a linear map of the residual that every
//! candidate fit, sensitivity and score test then works on, each channel divided by the root of its innovation
//! variance `R_c` so that a sum of squares is the method's cost `Σ νᵀR⁻¹ν` (eq. 5.6). With no process noise
//! `K = 0` and `ν = r`: the output-error search.
//!
//! The process-noise variances, one on the body velocities (the gusts) and one on the body rates, are chosen
//! by maximum likelihood on the unextended model's residual with the innovation variances relaxed,
//! `−2 ln L = N Σ_c ln R_c(q)`, `R_c = mean ν_c²` (Jategaonkar §5.2, the relaxation of eq. 5.11), on a grid.
//! They are kept only when the likelihood gain beats the Schwarz penalty counted in effective samples of the
//! output-error residual (modelling error colours residuals too, and must not pass for turbulence).

use faer::Mat;

use super::replay::ReplayCase;
pub use super::residual_filter::ResidualFilter;
use crate::estimate::fem;

/// How much of every segment the error dynamics are fitted on, s: long enough for the short-period and
/// Dutch-roll responses, short enough that the trajectory's own changes do not enter `A`.
pub const MODEL_HORIZON_S: f64 = 8.0;

/// Grid of the process-noise variances tried, per second in the perturbation units of
/// [`super::initial_state::initial_state_columns`] (0.5 m/s, 0.005 rad/s): 10^(−3 … 2) in half decades.
fn variance_grid() -> Vec<f64> {
    (0..=10)
        .map(|i| 10f64.powf(-3.0 + 0.5 * i as f64))
        .collect()
}

/// Perturbation indices of the body rates and the body velocities in `initial_state_columns`' order.
const RATES: [usize; 3] = [2, 3, 4];
const VELOCITIES: [usize; 3] = [5, 6, 7];

/// What the process-noise estimate found (reported with the diagnosis).
#[derive(Debug, Clone, serde::Serialize)]
pub struct ProcessNoise {
    /// Variance on the body velocities, (0.5 m/s)²/s.
    pub velocity_variance: f64,
    /// Variance on the body rates, (0.005 rad/s)²/s.
    pub rate_variance: f64,
    /// Likelihood gain over output error, −2 Δln L in effective samples.
    pub likelihood_gain: f64,
    /// The Schwarz penalty it had to beat.
    pub penalty: f64,
    /// Whether the filter is used in the search.
    pub used: bool,
}

/// The error dynamics `(A, C)` of `case` from the initial-state response `columns` (the same number per
/// segment, in segment order; channel-major, noise-normalised). `None` when there are none or the fit is
/// singular.
fn error_dynamics(case: &ReplayCase, columns: &[Vec<f64>]) -> Option<(Mat<f64>, Mat<f64>)> {
    let horizon = (MODEL_HORIZON_S / case.dt_s()).round() as usize;
    // the segments' own columns, without the nuisance columns appended after them
    let states = super::initial_state::columns_per_segment(case) * case.segments.len();
    fit_error_dynamics(
        columns.get(..states)?,
        &case.segments,
        case.len(),
        case.outputs.len(),
        horizon,
    )
}

/// [`error_dynamics`] for `columns` of `m` channels × `len` samples, the same number n per segment starting at
/// `segments` (n states), fitted over `horizon` samples of each segment.
fn fit_error_dynamics(
    columns: &[Vec<f64>],
    segments: &[usize],
    len: usize,
    m: usize,
    horizon: usize,
) -> Option<(Mat<f64>, Mat<f64>)> {
    let n = columns.len() / segments.len().max(1);
    if n == 0 || columns.len() != n * segments.len() || len < 3 {
        return None;
    }
    // Y(k) rows (one per channel) for every segment and step, and the next step's
    let (mut now, mut next) = (Vec::new(), Vec::new());
    let mut c_sum = Mat::<f64>::zeros(m, n);
    let mut c_count = 0;
    for (s, &b) in segments.iter().enumerate() {
        let end = segments.get(s + 1).copied().unwrap_or(len).min(b + horizon);
        let y = |k: usize, o: usize, j: usize| columns[s * n + j][o * len + k];
        let Some(k0) = (b..end).find(|&k| (0..m).any(|o| (0..n).any(|j| y(k, o, j) != 0.0))) else {
            continue;
        };
        for o in 0..m {
            for j in 0..n {
                c_sum[(o, j)] += y(k0, o, j);
            }
        }
        c_count += 1;
        for k in k0..end.saturating_sub(1) {
            for o in 0..m {
                now.push((0..n).map(|j| y(k, o, j)).collect::<Vec<f64>>());
                next.push((0..n).map(|j| y(k + 1, o, j)).collect::<Vec<f64>>());
            }
        }
    }
    if c_count == 0 || now.len() < n {
        return None;
    }
    let rows = now.len();
    let x = Mat::<f64>::from_fn(rows, n, |i, j| now[i][j]);
    // A column by column: Y(k+1) e_j = Y(k) A e_j
    let mut a = Mat::<f64>::zeros(n, n);
    for j in 0..n {
        let zj: Vec<f64> = next.iter().map(|row| row[j]).collect();
        let col = crate::ident::lstsq_qr(&x, &zj, "error dynamics").ok()?;
        for (i, v) in col.into_iter().enumerate() {
            a[(i, j)] = v;
        }
    }
    let c = Mat::<f64>::from_fn(m, n, |o, j| c_sum[(o, j)] / c_count as f64);
    Some((a, c))
}

/// Continuous-time equivalent of the sampled `A` for the core's Riccati solution: the matrix logarithm by
/// its series about the identity to first order, (A − I)/Δt (the filter itself propagates with `A`).
fn continuous(a: &Mat<f64>, dt_s: f64) -> Mat<f64> {
    let n = a.nrows();
    Mat::<f64>::from_fn(n, n, |i, j| {
        (a[(i, j)] - if i == j { 1.0 } else { 0.0 }) / dt_s
    })
}

/// The steady-state filter for variances `q` (per state, continuous time) and innovation variances `r`;
/// `None` when the gain breaks `diag(KC) ≤ 1` or the Riccati equation has no stabilising solution.
fn filter_for(
    a: &Mat<f64>,
    c: &Mat<f64>,
    q: &[f64],
    r: &[f64],
    dt_s: f64,
    len: usize,
) -> Option<ResidualFilter> {
    let gain = fem::gain(&continuous(a, dt_s), c, q, r, dt_s).ok()?;
    if gain.kc_max > 1.0 {
        return None;
    }
    let rows = |m: &Mat<f64>| -> Vec<Vec<f64>> {
        (0..m.nrows())
            .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
            .collect()
    };
    Some(ResidualFilter {
        a: rows(a),
        c: rows(c),
        k: gain.k,
        len,
        weight: vec![1.0; c.nrows()],
    })
}

/// Mean square per channel of the channel-major `r` (`len` samples each).
fn channel_variance(r: &[f64], len: usize) -> Vec<f64> {
    r.chunks(len.max(1))
        .map(|c| (c.iter().map(|v| v * v).sum::<f64>() / c.len() as f64).max(1e-12))
        .collect()
}

/// The innovations of `r` through `filter` with the nuisance `columns` (filtered the same way) projected off.
fn innovations(filter: Option<&ResidualFilter>, r: &[f64], columns: &[Vec<f64>]) -> Vec<f64> {
    let mut nu = r.to_vec();
    let mut cols = columns.to_vec();
    if let Some(f) = filter {
        cols.push(nu);
        f.apply_all(&mut cols);
        nu = cols.pop().unwrap_or_default();
    }
    super::search::project_off(&mut nu, &super::search::orthonormal_basis(&cols));
    nu
}

/// Estimates the process noise of `case` from the unextended model's noise-normalised residual `r0` (not
/// projected) and the initial-state response `columns`: the filter to use in the search (when the likelihood
/// gain beats the penalty) and the report. `None` when the error dynamics cannot be formed.
pub fn estimate(
    case: &ReplayCase,
    columns: &[Vec<f64>],
    r0: &[f64],
) -> Option<(Option<ResidualFilter>, ProcessNoise)> {
    let (a, c) = error_dynamics(case, columns)?;
    let (len, dt_s) = (case.len(), case.dt_s());
    let oe = innovations(None, r0, columns);
    let r_oe = channel_variance(&oe, len);
    // −2 ln L at q: the innovation variances relaxed twice from output error's; the filter carries the last
    // ones, those of its own innovations, as its channel weights
    let evaluate = |qv: f64, qr: f64| -> Option<(f64, ResidualFilter)> {
        // (no process noise on the heading, a state the rates drive)
        let mut q = vec![0.0; a.nrows()];
        VELOCITIES.iter().for_each(|&i| q[i] = qv);
        RATES.iter().for_each(|&i| q[i] = qr);
        let mut r = r_oe.clone();
        let mut best = None;
        for _ in 0..2 {
            let f = filter_for(&a, &c, &q, &r, dt_s, len)?;
            let nu = innovations(Some(&f), r0, columns);
            r = channel_variance(&nu, len);
            best = Some(f);
        }
        let cost: f64 = r.iter().map(|v| v.ln()).sum::<f64>() * len as f64;
        best.map(|f| {
            let weight = r.iter().map(|v| 1.0 / v.sqrt()).collect();
            (cost, ResidualFilter { weight, ..f })
        })
    };
    let cost_oe: f64 = r_oe.iter().map(|v| v.ln()).sum::<f64>() * len as f64;
    let grid = variance_grid();
    let (mut qv, mut qr) = (0.0, 0.0);
    let mut best: Option<(f64, ResidualFilter)> = None;
    // coordinate search: velocities, rates, velocities again
    // (the points of a round do not depend on each other: they are evaluated in parallel, then compared in
    // grid order)
    // A point evaluated in an earlier round is not evaluated again: its cost is no lower than the best so far, so
    // it could not be taken (when the rates' round keeps their variance, the third round is the first again).
    let mut threads = vec![(); std::thread::available_parallelism().map_or(1, |n| n.get())];
    let mut seen: Vec<(f64, f64)> = Vec::new();
    for round in 0..3 {
        let points: Vec<(f64, f64)> = std::iter::once(&0.0)
            .chain(&grid)
            .map(|&g| if round == 1 { (qv, g) } else { (g, qr) })
            .filter(|&(tv, tr)| (tv != 0.0 || tr != 0.0) && !seen.contains(&(tv, tr)))
            .collect();
        seen.extend(&points);
        let evaluated =
            super::search::par_map(&mut threads, &points, |_, &(tv, tr)| evaluate(tv, tr));
        for (&(tv, tr), e) in points.iter().zip(evaluated) {
            if let Some((cost, f)) = e {
                if best.as_ref().is_none_or(|(b, _)| cost < *b) {
                    best = Some((cost, f));
                    (qv, qr) = (tv, tr);
                }
            }
        }
    }
    // the gain in effective samples of the output-error residual (coloured by modelling error as well)
    let n_eff = super::residual::effective_n(&oe, len);
    let n_total = (len * case.outputs.len()) as f64;
    let (gain, filter) = match best {
        Some((cost, f)) => ((cost_oe - cost) * n_eff / n_total, Some(f)),
        None => (0.0, None),
    };
    let penalty = 2.0 * n_eff.ln();
    let used = gain > penalty;
    Some((
        filter.filter(|_| used),
        ProcessNoise {
            velocity_variance: qv,
            rate_variance: qr,
            likelihood_gain: gain,
            penalty,
            used,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::{filter_for, fit_error_dynamics};
    use faer::Mat;

    /// A, C, the responses, the segment starts and the number of samples.
    type System = (Mat<f64>, Mat<f64>, Vec<Vec<f64>>, Vec<usize>, usize);

    /// A lightly damped 9-state system (rotations of pairs of states, plus a decay), its output matrix
    /// (12 channels), and the responses to unit perturbations of each state at the starts of two segments.
    fn system() -> System {
        let n = 9;
        let mut a = Mat::<f64>::zeros(n, n);
        for i in 0..n {
            a[(i, i)] = 0.97;
        }
        for (i, j, w) in [(0, 1, 0.08), (2, 3, 0.15), (5, 6, 0.05)] {
            a[(i, j)] = w;
            a[(j, i)] = -w;
        }
        let m = 12;
        let c = Mat::<f64>::from_fn(m, n, |o, j| {
            ((o * 7 + j * 3) % 11) as f64 / 5.0 - 1.0 + if o == j { 2.0 } else { 0.0 }
        });
        let (len, segments) = (400, vec![0, 200]);
        let mut columns = Vec::new();
        for &b in &segments {
            for j in 0..n {
                let mut x = Mat::<f64>::zeros(n, 1);
                x[(j, 0)] = 1.0;
                let mut col = vec![0.0; m * len];
                for k in b..len {
                    for o in 0..m {
                        col[o * len + k] = (0..n).map(|i| c[(o, i)] * x[(i, 0)]).sum();
                    }
                    x = &a * &x;
                }
                columns.push(col);
            }
        }
        (a, c, columns, segments, len)
    }

    #[test]
    fn error_dynamics_are_recovered_from_the_perturbation_responses() {
        let (a, c, columns, segments, len) = system();
        let (a_fit, c_fit) = fit_error_dynamics(&columns, &segments, len, 12, 100).expect("a fit");
        for i in 0..9 {
            for j in 0..9 {
                assert!((a_fit[(i, j)] - a[(i, j)]).abs() < 1e-9, "A[{i}][{j}]");
            }
        }
        for o in 0..12 {
            for j in 0..9 {
                assert!((c_fit[(o, j)] - c[(o, j)]).abs() < 1e-12, "C[{o}][{j}]");
            }
        }
    }

    #[test]
    fn without_process_noise_the_innovations_are_the_residuals() {
        let (a, c, columns, _, len) = system();
        let f = filter_for(&a, &c, &[0.0; 9], &[1.0; 12], 0.02, len).expect("a filter");
        let mut r = columns[3].clone();
        f.apply(&mut r);
        assert_eq!(r, columns[3]);
        // with process noise the filter follows a free response: its innovations are far smaller
        let f = filter_for(&a, &c, &[1.0; 9], &[1.0; 12], 0.02, len).expect("a filter");
        let mut r = columns[3].clone();
        f.apply(&mut r);
        let ss = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>();
        assert!(
            ss(&r) < 0.5 * ss(&columns[3]),
            "{} vs {}",
            ss(&r),
            ss(&columns[3])
        );
    }
}
