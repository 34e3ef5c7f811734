//! The transfer-function coefficient vector of the derivative model and the parameter scaling shared by the
//! derivative fit ([`super::fit`]) and the identifiability analysis ([`super::identifiability`]).

use faer::Mat;

use super::model::{AeroModel, TfOutput};
use super::params::Derivative;
use super::AeroError;

/// Model coefficient vector [den₁…den₄, num(last len)] for each output.
pub(crate) fn model_coefficients(
    model: &AeroModel,
    outputs: &[TfOutput],
    num_lengths: &[usize],
) -> Result<Vec<f64>, AeroError> {
    let mut out = Vec::new();
    for (&o, &len) in outputs.iter().zip(num_lengths) {
        let tf = model.transfer_function(o)?;
        out.extend_from_slice(&tf.den[1..]);
        out.extend_from_slice(&tf.num[tf.num.len() - len..]);
    }
    Ok(out)
}

/// Relative weights 1/max(|c|, 1e-3 · max|c of the same polynomial|) as a diagonal whitening matrix.
pub(crate) fn relative_whitening(coefficients: &[f64], num_lengths: &[usize]) -> Mat<f64> {
    let n = coefficients.len();
    let mut w = Mat::<f64>::zeros(n, n);
    let mut start = 0;
    for &len in num_lengths {
        for (lo, hi) in [(start, start + 4), (start + 4, start + 4 + len)] {
            let max = coefficients[lo..hi]
                .iter()
                .fold(0.0f64, |m, c| m.max(c.abs()));
            let floor = if max > 0.0 { 1e-3 * max } else { 1.0 };
            for i in lo..hi {
                w[(i, i)] = 1.0 / coefficients[i].abs().max(floor);
            }
        }
        start += 4 + len;
    }
    w
}

/// Scale of each free derivative: |prior|, or 0.01 for a prior of 0 (a typical small derivative).
pub(crate) fn scales(model: &AeroModel, free: &[Derivative]) -> Vec<f64> {
    free.iter()
        .map(|&d| {
            let v = model.derivatives.get(d).abs();
            if v > 1e-6 {
                v
            } else {
                0.01
            }
        })
        .collect()
}

/// A copy of `model` with the `free` derivatives set to `values`.
pub(crate) fn with_values(model: &AeroModel, free: &[Derivative], values: &[f64]) -> AeroModel {
    let mut m = model.clone();
    for (&d, &v) in free.iter().zip(values) {
        m.derivatives.set(d, v);
    }
    m
}
