//! Start values from the records, so that a model the user writes needs no guessed numbers.
//!
//! Two steps, both non-iterative:
//! 1. **Subspace**: a linear model of the measured states driven by the model's inputs, of the
//!    model's order, in the states' own basis ([`super::subspace`]). It gives a smoothed state
//!    trajectory `x̂` per record and the derivative `ẋ̂ = A(x̂ − x̄) + B(u − ū) + (x̂_end − x̂_0)/T`
//!    (the model's derivative about the record's means; its mean over the record is the mean
//!    slope), without differentiating noisy data.
//! 2. **Equation error** (Klein & Morelli, *Aircraft System Identification*, 2nd ed., ch. 5;
//!    Jategaonkar, *Flight Vehicle System Identification*, 2nd ed., ch. 6): the model's state
//!    equations `f(x̂, u, θ) = ẋ̂` and observation equations `h(x̂, u, θ) = z` are affine in the
//!    parameters asked for, so one linear least-squares problem over all records gives them. The
//!    regressors are read from the model itself (`f(θ₀ + e_j) − f(θ₀)`), so this works for any
//!    model whose equations are affine in those parameters, linear or not in the states. Each
//!    equation's rows are scaled by its target's spread; an equation gets a constant per record
//!    (trim offsets, biases) unless one of the parameters is itself its constant term.

use super::model::{Parameter, StateModel};
use super::record::{InputHold, Record};
use super::subspace::{subspace, SubspaceModel, SubspaceOptions};
use super::EstimateError;
use crate::ident::lstsq_qr;
use faer::Mat;

/// Start values and how they were found.
#[derive(Clone, Debug)]
pub struct StartValues {
    /// The parameters with the `auto` ones set (clamped into their bounds).
    pub parameters: Vec<Parameter>,
    /// The subspace model of the measured states.
    pub subspace: SubspaceModel,
    /// The equations that constrained the parameters (`d/dt STATE`, or an output name).
    pub equations: Vec<String>,
}

/// One regression row: the target less the model at θ₀, and the regressors of the auto parameters.
type Row = (f64, Vec<f64>);

/// At most this many samples per record enter the regression (evenly spaced).
const MAX_ROWS_PER_RECORD: usize = 2000;

/// Start values for the parameters listed in `auto` (indices into `params`; their current values
/// are ignored). `state_records[r]` holds record `r` with the model's states as outputs;
/// `records[r]` the same record with the model's outputs.
pub fn start_values(
    model: &dyn StateModel,
    params: &[Parameter],
    auto: &[usize],
    state_records: &[Record],
    records: &[Record],
    hold: InputHold,
) -> Result<StartValues, EstimateError> {
    let sig = model.signature();
    let (n, p, m) = (sig.states.len(), sig.outputs.len(), sig.inputs.len());
    let basis: Vec<usize> = (0..n).collect();
    let options = SubspaceOptions {
        order: Some(n),
        hold,
        ..SubspaceOptions::default()
    };
    let sub = subspace(
        state_records,
        &sig.inputs,
        &sig.states,
        Some(&basis),
        &options,
    )?;
    if sub.state_names.is_none() {
        return Err(EstimateError::Invalid(
            "start values: the subspace model of the measured states cannot be written in the \
             states' own basis (the states are not independent in these records); give numbers"
                .into(),
        ));
    }
    let (a, b) = (&sub.continuous.a, &sub.continuous.b);
    let mut theta0: Vec<f64> = params.iter().map(|p| p.value).collect();
    for &j in auto {
        theta0[j] = 0.0;
    }
    // per equation (n state equations, then p outputs): rows per record of (target − base, regressors)
    let neq = n + p;
    let mut blocks: Vec<Vec<Vec<Row>>> = vec![vec![Vec::new(); records.len()]; neq];
    let eval = |theta: &[f64], x: &[f64], u: &[f64]| {
        let mut out = vec![0.0; neq];
        let (dx, y) = out.split_at_mut(n);
        model.derivatives(theta, x, u, dx);
        model.outputs(theta, x, u, y);
        out
    };
    let mut nonaffine: Option<String> = None;
    for (r, (srec, rec)) in state_records.iter().zip(records).enumerate() {
        let xh = &sub.records[r].predicted;
        let len = rec.len();
        let mean = |c: &Vec<f64>| c.iter().sum::<f64>() / c.len() as f64;
        let x_mean: Vec<f64> = xh.iter().map(mean).collect();
        let u_mean: Vec<f64> = rec.inputs.iter().map(mean).collect();
        let slope: Vec<f64> = xh
            .iter()
            .map(|c| (c[len - 1] - c[0]) / srec.duration_s().max(f64::MIN_POSITIVE))
            .collect();
        let stride = len.div_ceil(MAX_ROWS_PER_RECORD).max(1);
        for k in (0..len).step_by(stride) {
            let x: Vec<f64> = xh.iter().map(|c| c[k]).collect();
            let u: Vec<f64> = rec.inputs.iter().map(|c| c[k]).collect();
            let base = eval(&theta0, &x, &u);
            let regressors: Vec<Vec<f64>> = auto
                .iter()
                .map(|&j| {
                    let mut th = theta0.clone();
                    th[j] += 1.0;
                    let one = eval(&th, &x, &u);
                    if k % (10 * stride) == 0 && nonaffine.is_none() {
                        th[j] += 1.0;
                        let two = eval(&th, &x, &u);
                        if let Some(e) = (0..neq).find(|&e| {
                            let curvature = two[e] - 2.0 * one[e] + base[e];
                            curvature.abs() > 1e-6 * (two[e].abs() + base[e].abs() + 1e-9)
                        }) {
                            nonaffine = Some(format!(
                                "'{}' enters {} nonlinearly",
                                sig.parameters[j],
                                equation_name(sig.states.as_slice(), &sig.outputs, e)
                            ));
                        }
                    }
                    one.iter().zip(&base).map(|(o, b0)| o - b0).collect()
                })
                .collect();
            for e in 0..neq {
                let target = if e < n {
                    (0..n).map(|j| a[(e, j)] * (x[j] - x_mean[j])).sum::<f64>()
                        + (0..m).map(|l| b[(e, l)] * (u[l] - u_mean[l])).sum::<f64>()
                        + slope[e]
                } else {
                    rec.outputs[e - n][k]
                };
                let row: Vec<f64> = regressors.iter().map(|g| g[e]).collect();
                blocks[e][r].push((target - base[e], row));
            }
        }
    }
    if let Some(what) = nonaffine {
        return Err(EstimateError::Invalid(format!(
            "start values \"auto\" need equations affine in those parameters: {what}; give it a number"
        )));
    }
    // the equations some auto parameter enters, and whether one is their constant term
    let mut used = Vec::new();
    for (e, block) in blocks.iter().enumerate() {
        let rows = block.iter().flatten();
        let enters = (0..auto.len()).filter(|&c| rows.clone().any(|(_, g)| g[c] != 0.0));
        let mut is_used = false;
        let mut has_constant = false;
        for c in enters {
            is_used = true;
            let values: Vec<f64> = rows.clone().map(|(_, g)| g[c]).collect();
            let first = values[0];
            if values
                .iter()
                .all(|v| (v - first).abs() <= 1e-12 * first.abs())
            {
                has_constant = true;
            }
        }
        if is_used {
            used.push((e, !has_constant));
        }
    }
    let na = auto.len();
    let intercepts: usize = used.iter().filter(|(_, i)| *i).count() * records.len();
    let rows: usize = used
        .iter()
        .map(|(e, _)| blocks[*e].iter().map(Vec::len).sum::<usize>())
        .sum();
    let mut phi = Mat::<f64>::zeros(rows, na + intercepts);
    let mut y = Vec::with_capacity(rows);
    let mut row = 0;
    let mut next_intercept = na;
    for &(e, intercept) in &used {
        let all: Vec<f64> = blocks[e].iter().flatten().map(|(t, _)| *t).collect();
        let spread = crate::signal::std_dev(&all);
        let w = if spread > 0.0 { 1.0 / spread } else { 1.0 };
        for block in &blocks[e] {
            for (t, g) in block {
                for (c, v) in g.iter().enumerate() {
                    phi[(row, c)] = v * w;
                }
                if intercept {
                    phi[(row, next_intercept)] = w;
                }
                y.push(t * w);
                row += 1;
            }
            if intercept {
                next_intercept += 1;
            }
        }
    }
    let unconstrained: Vec<&str> = (0..na)
        .filter(|&c| (0..rows).all(|r| phi[(r, c)] == 0.0))
        .map(|c| sig.parameters[auto[c]].as_str())
        .collect();
    if !unconstrained.is_empty() {
        return Err(EstimateError::Invalid(format!(
            "start values \"auto\": {} enter no equation the records constrain; give numbers",
            unconstrained.join(", ")
        )));
    }
    let theta = lstsq_qr(&phi, &y, "start values by equation error").map_err(|e| {
        EstimateError::Invalid(format!(
            "start values \"auto\": {e}; the records cannot separate these parameters, give numbers"
        ))
    })?;
    let mut parameters = params.to_vec();
    for (c, &j) in auto.iter().enumerate() {
        let p = &mut parameters[j];
        p.value = theta[c].clamp(p.lower, p.upper);
    }
    Ok(StartValues {
        parameters,
        subspace: sub,
        equations: used
            .iter()
            .map(|(e, _)| equation_name(&sig.states, &sig.outputs, *e))
            .collect(),
    })
}

fn equation_name(states: &[String], outputs: &[String], e: usize) -> String {
    if e < states.len() {
        format!("d/dt {}", states[e])
    } else {
        outputs[e - states.len()].clone()
    }
}
