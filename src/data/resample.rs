//! Resampling of irregularly sampled records onto a uniform time grid.

use super::error::DataError;
use super::record::FlightRecord;

/// The method [`resample_uniform`] uses, as stated in metadata and reports.
pub const RESAMPLE_METHOD: &str =
    "linear interpolation between the two neighbouring samples (no filtering, no extrapolation)";

/// Resamples every column onto the grid `t0 + k / rate_hz`, `k = 0, 1, …` up to the last sample time.
///
/// Method: piecewise-linear interpolation between the bracketing samples ([`RESAMPLE_METHOD`]).
/// No anti-alias filter is applied: downsampling by more than ~2× should be preceded by a low-pass
/// filter. The record is validated first (time strictly increasing, values finite).
pub fn resample_uniform(rec: &FlightRecord, rate_hz: f64) -> Result<FlightRecord, DataError> {
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(DataError::InvalidArgument(format!(
            "resampling rate must be a positive number of Hz, got {rate_hz}"
        )));
    }
    rec.validate()?;
    let t = &rec.time_s;
    let t0 = t[0];
    let t_end = t[t.len() - 1];
    crate::limits::check_samples(
        &format!("resampling {:.1} s at {rate_hz} Hz", t_end - t0),
        t_end - t0,
        rate_hz,
    )
    .map_err(|e| DataError::InvalidArgument(e.to_string()))?;
    let dt_s = 1.0 / rate_hz;
    // Tolerate round-off at the last grid point (1e-9 of a step).
    let n = ((t_end - t0) / dt_s + 1e-9).floor() as usize + 1;
    let grid: Vec<f64> = (0..n).map(|k| t0 + k as f64 * dt_s).collect();

    // Bracketing index and weight for each grid point, computed once and shared by every column.
    let mut brackets = Vec::with_capacity(n);
    let mut j = 0usize;
    for &tg in &grid {
        while j + 2 < t.len() && t[j + 1] < tg {
            j += 1;
        }
        let (lo, hi) = if t.len() == 1 { (0, 0) } else { (j, j + 1) };
        let w = if hi == lo {
            0.0
        } else {
            ((tg - t[lo]) / (t[hi] - t[lo])).clamp(0.0, 1.0)
        };
        brackets.push((lo, hi, w));
    }
    let mut out = FlightRecord::new(grid);
    out.metadata = rec.metadata.clone();
    out.metadata.push(format!(
        " resampled to {rate_hz} Hz by {RESAMPLE_METHOD}, from {} samples",
        rec.len()
    ));
    for (name, values) in &rec.columns {
        let col = brackets
            .iter()
            .map(|&(lo, hi, w)| values[lo] + w * (values[hi] - values[lo]))
            .collect();
        out.push_column(name, col);
    }
    Ok(out)
}
