//! Savitzky–Golay smoothing and differentiation of uniformly sampled signals, and the central difference that
//! differentiates the smoothed rates.

use faer::prelude::Solve;
use faer::Mat;

use super::AeroError;

/// First derivative of a uniformly sampled signal by a local polynomial least-squares fit of `order` over
/// 2 `half_window` + 1 samples (Savitzky & Golay 1964); near the ends the window is shifted inside the record.
pub fn savitzky_golay_derivative(
    y: &[f64],
    dt_s: f64,
    half_window: usize,
    order: usize,
) -> Result<Vec<f64>, AeroError> {
    savitzky_golay(y, dt_s, half_window, order, 1)
}

/// The same local polynomial fit, evaluated (not differentiated): the matching smoother, so that regressors
/// can be filtered exactly like the differentiated outputs (Morelli & Klein §11.1 smooth every channel).
pub fn savitzky_golay_smooth(
    y: &[f64],
    half_window: usize,
    order: usize,
) -> Result<Vec<f64>, AeroError> {
    savitzky_golay(y, 1.0, half_window, order, 0)
}

fn savitzky_golay(
    y: &[f64],
    dt_s: f64,
    half_window: usize,
    order: usize,
    deriv: usize,
) -> Result<Vec<f64>, AeroError> {
    let width = 2 * half_window + 1;
    if !(dt_s.is_finite() && dt_s > 0.0) {
        return Err(AeroError::BadRecord(format!(
            "sample interval must be positive, got {dt_s}"
        )));
    }
    if order == 0 || order >= width {
        return Err(AeroError::BadRecord(format!(
            "Savitzky–Golay order {order} needs 1 ≤ order < window {width}"
        )));
    }
    if y.len() < width {
        return Err(AeroError::BadRecord(format!(
            "{} samples are fewer than the differentiation window of {width}",
            y.len()
        )));
    }
    let n = y.len();
    let mut cache: Vec<Option<Vec<f64>>> = vec![None; width];
    let mut out = vec![0.0; n];
    for (i, o) in out.iter_mut().enumerate() {
        let start = i.saturating_sub(half_window).min(n - width);
        let pos = i - start; // position of sample i inside its window
        if cache[pos].is_none() {
            cache[pos] = Some(sg_weights(
                pos,
                width,
                order,
                half_window.max(1) as f64,
                deriv,
            )?);
        }
        let w = cache[pos].as_deref().unwrap_or(&[]);
        *o = w
            .iter()
            .zip(&y[start..start + width])
            .map(|(a, b)| a * b)
            .sum::<f64>()
            / dt_s.powi(deriv as i32);
    }
    Ok(out)
}

/// Derivative by the 5-point central difference (4th order) inside, 2nd-order differences at the ends.
pub(super) fn central_difference(y: &[f64], dt_s: f64) -> Vec<f64> {
    let n = y.len();
    (0..n)
        .map(|i| {
            if i >= 2 && i + 2 < n {
                (y[i - 2] - 8.0 * y[i - 1] + 8.0 * y[i + 1] - y[i + 2]) / (12.0 * dt_s)
            } else if i == 0 {
                (-3.0 * y[0] + 4.0 * y[1] - y[2]) / (2.0 * dt_s)
            } else if i + 1 == n {
                (3.0 * y[n - 1] - 4.0 * y[n - 2] + y[n - 3]) / (2.0 * dt_s)
            } else {
                (y[i + 1] - y[i - 1]) / (2.0 * dt_s)
            }
        })
        .collect()
}

/// Weights giving the value (`deriv` 0) or the slope (`deriv` 1) at window position `pos` of a polynomial LS fit (offsets scaled by `h`).
fn sg_weights(
    pos: usize,
    width: usize,
    order: usize,
    h: f64,
    deriv: usize,
) -> Result<Vec<f64>, AeroError> {
    let m = order + 1;
    let x: Vec<f64> = (0..width).map(|j| (j as f64 - pos as f64) / h).collect();
    let vtv = Mat::from_fn(m, m, |a, b| {
        x.iter().map(|t| t.powi((a + b) as i32)).sum::<f64>()
    });
    let vt = Mat::from_fn(m, width, |a, j| x[j].powi(a as i32));
    let sol = vtv.partial_piv_lu().solve(&vt);
    let w: Vec<f64> = (0..width)
        .map(|j| sol[(deriv, j)] / h.powi(deriv as i32))
        .collect();
    if w.iter().any(|v| !v.is_finite()) {
        return Err(AeroError::Numerical("Savitzky–Golay weights"));
    }
    Ok(w)
}
