//! Joint identification from several records (maneuvers, segments or files): one shared
//! continuous transfer function `B(s)/A(s) · e^{−τs}`, and per record only what differs between
//! experiments — the trim, a constant output offset and the initial condition.
//!
//! Multiple experiments (Ljung 1999, *System Identification*, 2nd ed., §14.3 and the prediction
//! error criterion of §7.3/§10.1 summed over data sets): the criterion is the sum of each record's
//! own criterion, and no regression row, filter state or simulation runs across a record boundary.
//!
//! Per record r (samples k = 0…N_r−1, trim removed as in [`super::identify`]):
//! `y_r(k) = [B/A · e^{−τs} u_r](k) + Σ_i x_{r,i} f_i(k) + c_r + e_r(k)`,
//! where `f_0 … f_{n−1}` span the free responses of `A` (solutions of `A(d/dt) f = 0`, here the
//! state trajectories of the state-variable filter `1/A` leaving a unit pulse) and `c_r` is the
//! output offset. Given `A`, the model is linear in `B`, every `x_r` and every `c_r`.
//!
//! | method | joint estimate of A (and B) | per-record nuisances |
//! |---|---|---|
//! | `ls`  | ARX rows of every record stacked (Şahin & Kalyon 2021 eq. 59–64) + one offset column per record, then ZOH d2c | offsets in the regression; ICs implicit (past outputs are regressors), then fitted |
//! | `iv`  | the same rows with auxiliary-model instruments (Söderström & Stoica 1989 §8.2), iterated; B refitted jointly with A fixed | as `ls` |
//! | `srivc` | Young's SRIV (Young 1976, "Some observations on instrumental variable methods of time-series analysis", IJC 23(5); continuous form Young & Jakeman 1980) with the IV normal equations summed over records; per-record columns for the filtered offset (step response of 1/Â) and the filtered initial conditions (free responses of 1/Â), instrumented by themselves | in the IV equations |
//! | `oe`  | output error by variable projection (Golub & Pereyra 1973, SIAM J. Numer. Anal. 10(2); 2003 review in Inverse Problems 19(2)): the linear parameters (B, every x_r, c_r) are eliminated by least squares, Levenberg–Marquardt runs on A alone | eliminated |
//!
//! Delay: `estimate_delay` searches **whole samples** only (0 … min(1 s, shortest record/10)),
//! with the joint simulation error as criterion; the fractional delay of the single-record
//! `srivc`/`oe` is not implemented here.
//!
//! Standard errors (`oe` only): the Cramér–Rao bound of the full parameter vector corrected for
//! coloured residuals by the estimation core's rule (`estimate::covariance`), marginalised to
//! `[B, A]`: the same rule as the single-record `oe`.

use faer::Mat;
use serde::{Deserialize, Serialize};

use super::filter::{simulate, Columns, Hold, Svf};
use super::linalg::{lstsq_qr, poly_from_roots, solve_square, stabilize_continuous};
use super::ls::{arx_regressor, arx_to_continuous, continuous_poles};
use super::srivc::lambdas;
use super::{metrics, nrmse_fit, ContinuousModel, IdentError, IdentOptions, IdentResult, Method};

mod oe;
use oe::{covariance, oe_joint};

/// One record of a joint fit: input and output sampled every `dt_s` seconds.
#[derive(Clone, Debug)]
pub struct JointRecord {
    /// Where the record comes from (file, segment), for reports and errors.
    pub label: String,
    /// Input samples (e.g. a surface deflection, rad).
    pub u: Vec<f64>,
    /// Output samples (e.g. a rate or angle).
    pub y: Vec<f64>,
    /// Sample time, seconds (the same for every record of a joint fit).
    pub dt_s: f64,
}

/// What the joint fit says about one record.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RecordFit {
    /// The record's label.
    pub label: String,
    /// Samples in the record.
    pub n_samples: usize,
    /// Input trim removed (input units).
    pub u_offset: f64,
    /// Output trim removed plus the estimated constant offset `c_r` (output units).
    pub y_offset: f64,
    /// Initial-condition coefficients `x_r` on the free-response basis (see module docs).
    pub initial_state: Vec<f64>,
    /// Simulation fit of this record with its own offset and initial condition, NRMSE %.
    pub fit_sim_percent: f64,
}

/// The joint estimate: one transfer function and the per-record nuisances.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct JointResult {
    /// The shared model. `fit_sim_percent` and `n_samples` are over all records; the residual
    /// tests, `fit_one_step_percent` and the offsets are those of the longest record.
    pub result: IdentResult,
    /// One entry per record, in the order given.
    pub records: Vec<RecordFit>,
}

/// A record with its trim removed.
struct Centered {
    u: Vec<f64>,
    y: Vec<f64>,
    u_offset: f64,
    y_offset: f64,
}

/// Per-record nuisance estimate for a fixed transfer function.
struct Nuisance {
    /// `[x_0 … x_{n−1}, c]`.
    coef: Vec<f64>,
    /// Model output including free response and offset.
    y_model: Vec<f64>,
}

/// Identifies one transfer function jointly from several records (see module docs).
pub fn identify_joint(
    records: &[JointRecord],
    opts: &IdentOptions,
) -> Result<JointResult, IdentError> {
    let Some(first) = records.first() else {
        return Err(IdentError::InvalidOptions(
            "a joint identification needs at least one record".into(),
        ));
    };
    let dt_s = first.dt_s;
    for r in records {
        super::validate(&r.u, &r.y, r.dt_s, opts)
            .map_err(|e| IdentError::InvalidOptions(format!("record {}: {e}", r.label)))?;
        if (r.dt_s - dt_s).abs() > 1e-6 * dt_s {
            return Err(IdentError::InvalidOptions(format!(
                "record {} is sampled every {} s but {} every {} s; resample them to one rate",
                r.label, r.dt_s, first.label, dt_s
            )));
        }
    }
    let recs: Vec<Centered> = records
        .iter()
        .map(|r| {
            let (u_offset, y_offset) = super::trim_offsets(&r.u, &r.y);
            Centered {
                u: r.u.iter().map(|v| v - u_offset).collect(),
                y: r.y.iter().map(|v| v - y_offset).collect(),
                u_offset,
                y_offset,
            }
        })
        .collect();
    let (n, m) = (opts.poles, opts.zeros);
    let mut model = if opts.estimate_delay {
        delay_search(&recs, dt_s, opts.method, n, m)?
    } else {
        estimate_joint(&recs, dt_s, opts.method, n, m, 0)?.0
    };
    let nuis = nuisances(&recs, dt_s, &model)?;
    if opts.method == Method::Oe {
        model.cov = covariance(&recs, dt_s, &model, &nuis);
    }
    Ok(assemble(records, &recs, dt_s, opts, model, &nuis))
}

/// Builds the public result from the shared model and the per-record nuisances.
fn assemble(
    records: &[JointRecord],
    recs: &[Centered],
    dt_s: f64,
    opts: &IdentOptions,
    model: ContinuousModel,
    nuis: &[Nuisance],
) -> JointResult {
    let n = model.den.len() - 1;
    let longest = (0..recs.len())
        .max_by_key(|&i| recs[i].y.len())
        .expect("at least one record");
    // The longest record with its free response removed and its offset as the model's bias.
    let free_removed: Vec<f64> = {
        let (y_model, c) = (&nuis[longest].y_model, nuis[longest].coef[n]);
        let forced = simulate(
            &model.num,
            &model.den,
            &recs[longest].u,
            dt_s,
            model.delay_s,
        );
        recs[longest]
            .y
            .iter()
            .zip(y_model)
            .zip(&forced)
            .map(|((y, ym), f)| y - (ym - f - c))
            .collect()
    };
    let mut with_bias = model.clone();
    with_bias.y_bias = nuis[longest].coef[n];
    let mut result = metrics::build_result(
        opts.method,
        with_bias,
        &recs[longest].u,
        &free_removed,
        dt_s,
        opts.estimate_delay,
        recs[longest].u_offset,
        recs[longest].y_offset,
    );
    let y_all: Vec<f64> = recs.iter().flat_map(|r| r.y.iter().copied()).collect();
    let model_all: Vec<f64> = nuis
        .iter()
        .flat_map(|q| q.y_model.iter().copied())
        .collect();
    result.fit_sim_percent = nrmse_fit(&y_all, &model_all);
    result.n_samples = y_all.len();
    let per_record = records
        .iter()
        .zip(recs)
        .zip(nuis)
        .map(|((r, c), q)| RecordFit {
            label: r.label.clone(),
            n_samples: c.y.len(),
            u_offset: c.u_offset,
            y_offset: c.y_offset + q.coef[n],
            initial_state: q.coef[..n].to_vec(),
            fit_sim_percent: nrmse_fit(&c.y, &q.y_model),
        })
        .collect();
    JointResult {
        result,
        records: per_record,
    }
}

/// Keeps `model` in `best` when its joint simulation error ([`joint_cost`]) is the lowest so far: the joint
/// IV and SRIVC estimators pick their start and the iterate they return by it, not by the last step.
fn keep_if_lower(
    recs: &[Centered],
    dt_s: f64,
    model: &ContinuousModel,
    best: &mut Option<(f64, ContinuousModel)>,
) {
    let cost = joint_cost(recs, dt_s, model);
    if best.as_ref().is_none_or(|b| cost < b.0) {
        *best = Some((cost, model.clone()));
    }
}

/// Joint simulation error `Σ_r Σ_k (y_r − ŷ_r)²` with each record's nuisances fitted.
fn joint_cost(recs: &[Centered], dt_s: f64, model: &ContinuousModel) -> f64 {
    match nuisances(recs, dt_s, model) {
        Ok(nuis) => {
            let c: f64 = recs
                .iter()
                .zip(&nuis)
                .map(|(r, q)| sse(&r.y, &q.y_model))
                .sum();
            if c.is_finite() {
                c
            } else {
                f64::INFINITY
            }
        }
        Err(_) => f64::INFINITY,
    }
}

/// Largest relative change between two coefficient vectors (1e-6 guards zero coefficients).
fn relative_change(new: &[f64], old: &[f64]) -> f64 {
    new.iter()
        .zip(old)
        .map(|(a, b)| (a - b).abs() / (1e-6 + b.abs()))
        .fold(0.0_f64, f64::max)
}

fn sse(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

/// Whole-sample delay search: a grid of at most 21 delays over 0 … min(1 s, shortest/10), then
/// every sample around the best grid point; the joint simulation error decides.
fn delay_search(
    recs: &[Centered],
    dt_s: f64,
    method: Method,
    n: usize,
    m: usize,
) -> Result<ContinuousModel, IdentError> {
    let shortest = recs.iter().map(|r| r.y.len()).min().unwrap_or(0);
    let max_samples = ((shortest as f64 * dt_s / 10.0).min(1.0) / dt_s).floor() as usize;
    let step = (max_samples / 20).max(1);
    let mut best: Option<(f64, usize, ContinuousModel)> = None;
    let mut last_err = None;
    let mut try_d =
        |d: usize, best: &mut Option<(f64, usize, ContinuousModel)>| match estimate_joint(
            recs, dt_s, method, n, m, d,
        ) {
            Ok((model, cost)) => {
                if best.as_ref().is_none_or(|b| cost < b.0) {
                    *best = Some((cost, d, model));
                }
            }
            Err(e) => last_err = Some(e),
        };
    for d in (0..=max_samples).step_by(step) {
        try_d(d, &mut best);
    }
    if let Some(centre) = best.as_ref().map(|b| b.1) {
        let lo = centre.saturating_sub(step - 1);
        let hi = (centre + step - 1).min(max_samples);
        for d in (lo..=hi).filter(|d| (d % step) != 0) {
            try_d(d, &mut best);
        }
    }
    match (best, last_err) {
        (Some((_, _, model)), _) => Ok(model),
        (None, Some(e)) => Err(e),
        (None, None) => Err(IdentError::Failed {
            method: method.name().into(),
            reason: "no delay candidate could be fitted".into(),
        }),
    }
}

/// The joint estimate at a fixed whole-sample delay `d`, with its joint simulation error.
fn estimate_joint(
    recs: &[Centered],
    dt_s: f64,
    method: Method,
    n: usize,
    m: usize,
    d: usize,
) -> Result<(ContinuousModel, f64), IdentError> {
    let delay_s = d as f64 * dt_s;
    let model = match method {
        Method::Ls => {
            let (a, b) = arx_joint(recs, n, d, None)?;
            arx_to_continuous(&super::ls::Arx { a, b }, dt_s, m, d)?
        }
        Method::Iv => iv_joint(recs, dt_s, n, m, d)?,
        Method::Srivc => srivc_joint(recs, dt_s, n, m, delay_s)?,
        Method::Oe => {
            let start = srivc_joint(recs, dt_s, n, m, delay_s)?;
            oe_joint(recs, dt_s, m, start)?
        }
    };
    let cost = joint_cost(recs, dt_s, &model);
    Ok((model, cost))
}

/// Stacked ARX (eq. 59–62 of the paper, rows of every record, `nb = n`) with one constant column
/// per record; with `instruments` (one auxiliary output per record) the output lags of the
/// instrument vector are replaced by the auxiliary outputs' lags (basic IV). Returns the
/// discrete `a = [1, a₁…a_n]` and `b`.
fn arx_joint(
    recs: &[Centered],
    n: usize,
    d: usize,
    instruments: Option<&[Vec<f64>]>,
) -> Result<(Vec<f64>, Vec<f64>), IdentError> {
    let nr = recs.len();
    let p = 2 * n + nr;
    let blocks: Vec<(Mat<f64>, Vec<f64>)> = recs
        .iter()
        .map(|r| arx_regressor(&r.u, &r.y, n, n, d))
        .collect();
    let rows: usize = blocks.iter().map(|b| b.1.len()).sum();
    let row_of: Vec<(usize, usize)> = blocks
        .iter()
        .enumerate()
        .flat_map(|(r, b)| (0..b.1.len()).map(move |k| (r, k)))
        .collect();
    let phi = Mat::<f64>::from_fn(rows, p, |i, c| {
        let (r, k) = row_of[i];
        if c < 2 * n {
            blocks[r].0[(k, c)]
        } else {
            f64::from(u8::from(c - 2 * n == r))
        }
    });
    let target: Vec<f64> = blocks.iter().flat_map(|b| b.1.iter().copied()).collect();
    let theta = match instruments {
        None => lstsq_qr(&phi, &target, "ls (joint)")?,
        Some(aux) => {
            let first = n.max(n + d);
            let zeta = |i: usize, c: usize| -> f64 {
                let (r, k) = row_of[i];
                if c < n {
                    -aux[r][k + first - 1 - c]
                } else {
                    phi[(i, c)]
                }
            };
            let mut zphi = vec![0.0; p * p];
            let mut zy = vec![0.0; p];
            for i in 0..rows {
                for a in 0..p {
                    let z = zeta(i, a);
                    zy[a] += z * target[i];
                    for c in 0..p {
                        zphi[a * p + c] += z * phi[(i, c)];
                    }
                }
            }
            solve_square(&zphi, &zy).ok_or_else(|| IdentError::SingularRegression {
                method: "iv (joint)".into(),
                rank: 0,
                n_params: p,
            })?
        }
    };
    let mut a = vec![1.0];
    a.extend_from_slice(&theta[..n]);
    Ok((a, theta[n..2 * n].to_vec()))
}

/// Joint basic IV: instruments from the auxiliary model (the previous estimate, continuous,
/// stabilised, simulated per record), iterated from the stacked ARX estimate; then A from the
/// discrete poles and B refitted jointly with A fixed.
fn iv_joint(
    recs: &[Centered],
    dt_s: f64,
    n: usize,
    m: usize,
    d: usize,
) -> Result<ContinuousModel, IdentError> {
    const MAX_ITER: usize = 20;
    let delay_s = d as f64 * dt_s;
    let (a, b) = arx_joint(recs, n, d, None)?;
    let mut model = arx_to_continuous(&super::ls::Arx { a, b }, dt_s, n - 1, d)?;
    let mut best: Option<(f64, ContinuousModel)> = None;
    for _ in 0..MAX_ITER {
        let den_aux = stabilize_continuous(&model.den);
        let aux: Vec<Vec<f64>> = recs
            .iter()
            .map(|r| simulate(&model.num, &den_aux, &r.u, dt_s, delay_s))
            .collect();
        let (a, b) = arx_joint(recs, n, d, Some(&aux))?;
        let den = poly_from_roots(&continuous_poles(&a, dt_s)?);
        let next = arx_to_continuous(&super::ls::Arx { a, b }, dt_s, n - 1, d)?;
        let change = relative_change(&den, &model.den);
        model = next;
        let candidate = refit_linear(recs, dt_s, &model.den, m, delay_s)?;
        keep_if_lower(recs, dt_s, &candidate, &mut best);
        if change < 1e-9 {
            break;
        }
    }
    best.map(|b| b.1).ok_or_else(|| IdentError::Failed {
        method: "iv (joint)".into(),
        reason: "no iteration produced a model".into(),
    })
}

/// Free-response basis of `1/A` for `len` samples: `n` state trajectories leaving a unit pulse,
/// shifted so that sample 0 is the first state after the pulse.
fn free_basis(svf: &Svf, len: usize) -> Columns {
    let mut pulse = vec![0.0; len + 1];
    pulse[0] = 1.0;
    svf.run(&pulse).skip(1)
}

/// Columns of the joint linear problem for a fixed `A`: `m+1` shared numerator columns
/// (`s^j/A · e^{−τs}u_r`, highest power first), then per record `n` free-response columns and
/// one offset column. Returns the matrix and the stacked outputs.
fn linear_system(
    recs: &[Centered],
    dt_s: f64,
    den: &[f64],
    m: usize,
    delay_s: f64,
) -> (Mat<f64>, Vec<f64>) {
    let n = den.len() - 1;
    let svf_u = Svf::new(den, dt_s, Hold::Zoh { delay_s });
    let svf_free = Svf::new(den, dt_s, Hold::Zoh { delay_s: 0.0 });
    let states: Vec<Columns> = recs.iter().map(|r| svf_u.run(&r.u)).collect();
    let longest = recs.iter().map(|r| r.y.len()).max().unwrap_or(0);
    let free = free_basis(&svf_free, longest);
    let rows: usize = recs.iter().map(|r| r.y.len()).sum();
    let row_of: Vec<(usize, usize)> = recs
        .iter()
        .enumerate()
        .flat_map(|(r, rec)| (0..rec.y.len()).map(move |k| (r, k)))
        .collect();
    let cols = m + 1 + recs.len() * (n + 1);
    let mat = Mat::<f64>::from_fn(rows, cols, |i, c| {
        let (r, k) = row_of[i];
        if c <= m {
            return states[r].col(m - c)[k];
        }
        let own = c - (m + 1);
        if own / (n + 1) != r {
            return 0.0;
        }
        match own % (n + 1) {
            j if j < n => free.col(j)[k],
            _ => 1.0,
        }
    });
    let y = recs.iter().flat_map(|r| r.y.iter().copied()).collect();
    (mat, y)
}

/// `B` (and the nuisances, discarded here) by joint least squares for a fixed `A`.
fn refit_linear(
    recs: &[Centered],
    dt_s: f64,
    den: &[f64],
    m: usize,
    delay_s: f64,
) -> Result<ContinuousModel, IdentError> {
    let (mat, y) = linear_system(recs, dt_s, den, m, delay_s);
    let theta = lstsq_qr(&mat, &y, "joint numerator")?;
    Ok(ContinuousModel::new(
        theta[..=m].to_vec(),
        den.to_vec(),
        delay_s,
    ))
}

/// Each record's free-response coefficients and offset for a fixed `B/A`, by least squares on
/// the record's simulation residual.
fn nuisances(
    recs: &[Centered],
    dt_s: f64,
    model: &ContinuousModel,
) -> Result<Vec<Nuisance>, IdentError> {
    let n = model.den.len() - 1;
    let svf_free = Svf::new(&model.den, dt_s, Hold::Zoh { delay_s: 0.0 });
    recs.iter()
        .map(|r| {
            let len = r.y.len();
            let forced = simulate(&model.num, &model.den, &r.u, dt_s, model.delay_s);
            let free = free_basis(&svf_free, len);
            let mat =
                Mat::<f64>::from_fn(len, n + 1, |k, c| if c < n { free.col(c)[k] } else { 1.0 });
            let resid: Vec<f64> = r.y.iter().zip(&forced).map(|(y, f)| y - f).collect();
            let coef = lstsq_qr(&mat, &resid, "initial condition")?;
            let y_model = (0..len)
                .map(|k| forced[k] + (0..=n).map(|c| mat[(k, c)] * coef[c]).sum::<f64>())
                .collect();
            Ok(Nuisance { coef, y_model })
        })
        .collect()
}

/// Joint SRIVC (see module docs): IV normal equations summed over records, prefilter `1/Â`,
/// per-record offset and initial-condition columns; started from the stacked SVF least-squares
/// estimate with prefilter `(s+λ)^n` (best λ by joint simulation error); the iterate with the
/// lowest joint simulation error is returned.
fn srivc_joint(
    recs: &[Centered],
    dt_s: f64,
    n: usize,
    m: usize,
    delay_s: f64,
) -> Result<ContinuousModel, IdentError> {
    const MAX_ITER: usize = 30;
    let mut best: Option<(f64, ContinuousModel)> = None;
    let mut start: Option<(f64, ContinuousModel)> = None;
    for lambda in lambdas(dt_s) {
        let den_f = poly_from_roots(&vec![num_complex::Complex64::new(-lambda, 0.0); n]);
        if let Some(model) = srivc_step(recs, dt_s, m, delay_s, &den_f, None) {
            keep_if_lower(recs, dt_s, &model, &mut start);
        }
    }
    let Some((_, mut model)) = start else {
        return Err(IdentError::SingularRegression {
            method: "srivc (joint)".into(),
            rank: 0,
            n_params: n + m + 1,
        });
    };
    keep_if_lower(recs, dt_s, &model, &mut best);
    for _ in 0..MAX_ITER {
        let den_f = stabilize_continuous(&model.den);
        let Some(next) = srivc_step(recs, dt_s, m, delay_s, &den_f, Some(&model.num)) else {
            break;
        };
        let change =
            relative_change(&next.den, &model.den).max(relative_change(&next.num, &model.num));
        model = next;
        keep_if_lower(recs, dt_s, &model, &mut best);
        if change < 1e-9 {
            break;
        }
    }
    Ok(best.expect("the start was considered").1)
}

/// One joint SRIVC step with prefilter `1/den_f`; `aux_num` = None: least squares (instruments
/// = regressors), else the auxiliary model `aux_num/den_f` gives the instruments.
/// Parameters: `[a_1…a_n, b_m…b_0]` shared, then per record `[offset, ic_0…ic_{n−1}]`.
fn srivc_step(
    recs: &[Centered],
    dt_s: f64,
    m: usize,
    delay_s: f64,
    den_f: &[f64],
    aux_num: Option<&[f64]>,
) -> Option<ContinuousModel> {
    let n = den_f.len() - 1;
    let nr = recs.len();
    let shared = n + m + 1;
    let p = shared + nr * (n + 1);
    let svf_u = Svf::new(den_f, dt_s, Hold::Zoh { delay_s });
    let svf_y = Svf::new(den_f, dt_s, Hold::Foh);
    let svf_0 = Svf::new(den_f, dt_s, Hold::Zoh { delay_s: 0.0 });
    let mut zphi = vec![0.0; p * p];
    let mut zy = vec![0.0; p];
    let mut phi = vec![0.0; p];
    let mut zeta = vec![0.0; p];
    for (r, rec) in recs.iter().enumerate() {
        let len = rec.y.len();
        let xu = svf_u.run(&rec.u);
        let xy = svf_y.run(&rec.y);
        let step = svf_0.run(&vec![1.0; len]);
        let free = free_basis(&svf_0, len);
        let sx = aux_num.map(|b| svf_y.run(&xu.combine(b)));
        let target = svf_y.top_derivative(&xy, &rec.y);
        let own = shared + r * (n + 1);
        for k in 0..len {
            phi.iter_mut().for_each(|v| *v = 0.0);
            for (i, v) in phi.iter_mut().take(n).enumerate() {
                *v = -xy.col(n - 1 - i)[k];
            }
            for j in 0..=m {
                phi[n + j] = xu.col(m - j)[k];
            }
            phi[own] = step.col(0)[k];
            for j in 0..n {
                phi[own + 1 + j] = free.col(j)[k];
            }
            zeta.copy_from_slice(&phi);
            if let Some(sx) = &sx {
                for (i, z) in zeta.iter_mut().take(n).enumerate() {
                    *z = -sx.col(n - 1 - i)[k];
                }
            }
            let target = target[k];
            for a in 0..p {
                let z = zeta[a];
                if z == 0.0 {
                    continue;
                }
                zy[a] += z * target;
                for c in 0..p {
                    zphi[a * p + c] += z * phi[c];
                }
            }
        }
    }
    let theta = solve_square(&zphi, &zy)?;
    if theta.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let mut den = vec![1.0];
    den.extend_from_slice(&theta[..n]);
    Some(ContinuousModel::new(
        theta[n..shared].to_vec(),
        den,
        delay_s,
    ))
}

#[cfg(test)]
mod tests;
