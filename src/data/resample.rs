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

/// A dropout: a time step longer than this many median steps (two samples or more missing in a row) splits
/// the record in [`uniform_pieces`] instead of being interpolated over.
pub const DROPOUT_STEPS: f64 = 2.5;

/// The shortest piece [`uniform_pieces`] keeps, s: shorter than a short-period or Dutch-roll cycle, a piece
/// carries its initial state and little else.
pub const MIN_PIECE_S: f64 = 2.0;

/// A record as an estimator can take it: uniformly sampled pieces, with what was done to get them.
#[derive(Debug, Clone)]
pub struct UniformPieces {
    /// The pieces, each uniformly sampled, in time order.
    pub pieces: Vec<FlightRecord>,
    /// What was done, one sentence each: where the record was split, what was left out, what was resampled.
    pub notes: Vec<String>,
}

/// The indices of the samples that follow a dropout: a time step over [`DROPOUT_STEPS`] median steps.
pub fn dropout_starts(t: &[f64]) -> Vec<usize> {
    let steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    if steps.is_empty() {
        return Vec::new();
    }
    let median = super::record::median_in_place(&mut steps.clone());
    steps
        .iter()
        .enumerate()
        .filter(|(_, s)| **s > DROPOUT_STEPS * median)
        .map(|(k, _)| k + 1)
        .collect()
}

/// A measured record in uniformly sampled pieces, the way a flight log needs it before a time-domain
/// estimator: split at every dropout (a step over [`DROPOUT_STEPS`] median steps: interpolating over missing
/// samples would invent the motion in them), pieces shorter than [`MIN_PIECE_S`] left out, and a piece whose
/// steps jitter by more than 10 % of the median step resampled onto its nominal step by [`resample_uniform`]
/// (logger timestamps taken from a clock that is not the sampling clock). A record that
/// is already uniform comes back as one piece, unchanged, with no note. The pieces are separate records to the
/// estimators: each with its own initial state, fitted jointly.
pub fn uniform_pieces(rec: &FlightRecord) -> Result<UniformPieces, DataError> {
    rec.validate()?;
    let t = &rec.time_s;
    let steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let too_short = |dropouts: usize| DataError::TooShort {
        samples: t.len(),
        span_s: t.last().zip(t.first()).map_or(0.0, |(b, a)| b - a),
        dropouts,
        min_s: MIN_PIECE_S,
    };
    if steps.is_empty() {
        return Err(too_short(0));
    }
    let mut sorted = steps.clone();
    let median = super::record::median_in_place(&mut sorted);
    let mut notes = Vec::new();
    let mut bounds = vec![0];
    for k in dropout_starts(t) {
        let s = t[k] - t[k - 1];
        bounds.push(k);
        notes.push(format!(
            "a dropout of {s:.3} s ({:.0} samples missing) after t = {} s: the record is split there",
            s / median - 1.0,
            t[k - 1]
        ));
    }
    bounds.push(t.len());
    let mut pieces = Vec::new();
    for w in bounds.windows(2) {
        let piece = rec.slice(w[0], w[1]);
        let span = piece.time_s[piece.len() - 1] - piece.time_s[0];
        if span < MIN_PIECE_S {
            notes.push(format!(
                "the piece from t = {:.3} s to {:.3} s is shorter than {MIN_PIECE_S} s and is left out",
                piece.time_s[0],
                piece.time_s[piece.len() - 1]
            ));
            continue;
        }
        if let Some(message) = super::record::irregular_sampling(&piece.time_s) {
            let rate_hz = 1.0 / nominal_step_s(&piece.time_s, median);
            notes.push(format!(
                "t = {:.3} s to {:.3} s: {message}; resampled onto a uniform {rate_hz:.4} Hz grid by {RESAMPLE_METHOD}",
                piece.time_s[0],
                piece.time_s[piece.len() - 1]
            ));
            pieces.push(resample_uniform(&piece, rate_hz)?);
        } else {
            pieces.push(piece);
        }
    }
    if pieces.is_empty() {
        return Err(too_short(bounds.len() - 2));
    }
    Ok(UniformPieces { pieces, notes })
}

/// The sampling step of a piece whose timestamps jitter about it or skip a sample: its span over the number of
/// nominal steps in it, each logged step counting as `round(step / median)` of them (at least one). The median
/// step alone is biased by a jitter pattern that is not symmetric (20 ms steps logged as 26, 9 and 25 ms have a
/// median of 25 ms); the mean step alone by the samples missing.
fn nominal_step_s(time_s: &[f64], median_s: f64) -> f64 {
    let steps: f64 = time_s
        .windows(2)
        .map(|w| ((w[1] - w[0]) / median_s).round().max(1.0))
        .sum();
    (time_s[time_s.len() - 1] - time_s[0]) / steps
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record of `time_s` with one column equal to 2 t.
    fn ramp(time_s: Vec<f64>) -> FlightRecord {
        let v = time_s.iter().map(|t| 2.0 * t).collect();
        let mut rec = FlightRecord::new(time_s);
        rec.push_column("q_rad_s", v);
        rec
    }

    #[test]
    fn a_uniform_record_is_one_piece_unchanged() {
        let rec = ramp((0..500).map(|k| k as f64 * 0.02).collect());
        let out = uniform_pieces(&rec).unwrap();
        assert_eq!(out.pieces.len(), 1);
        assert_eq!(out.pieces[0].time_s, rec.time_s);
        assert!(out.notes.is_empty());
    }

    #[test]
    fn a_dropout_splits_the_record_and_a_short_piece_is_left_out() {
        // 50 Hz: 0–5 s, a 1 s dropout, 6–10 s, a 0.5 s dropout, then 1 s (too short).
        let t: Vec<f64> = (0..=250)
            .chain(300..=500)
            .chain(525..=575)
            .map(|k| k as f64 * 0.02)
            .collect();
        let out = uniform_pieces(&ramp(t)).unwrap();
        assert_eq!(out.pieces.len(), 2);
        assert_eq!(out.pieces[0].time_s.len(), 251);
        assert!((out.pieces[1].time_s[0] - 6.0).abs() < 1e-12);
        assert_eq!(out.notes.len(), 3, "{:?}", out.notes);
        assert!(out.notes[0].contains("after t = 5 s"), "{}", out.notes[0]);
        assert!(out.notes[2].contains("left out"), "{}", out.notes[2]);
    }

    #[test]
    fn an_asymmetric_jitter_keeps_the_sampling_rate() {
        // 20 ms sampling logged with +6 ms and −5 ms on alternate samples: steps of 26, 9 and 25 ms.
        let t: Vec<f64> = (0..600)
            .map(|k| k as f64 * 0.02 + [0.0, 0.006, -0.005][k % 3])
            .collect();
        let out = uniform_pieces(&ramp(t)).unwrap();
        let p = &out.pieces[0];
        assert!(
            (p.time_s[1] - p.time_s[0] - 0.02).abs() < 1e-4,
            "{}",
            p.time_s[1]
        );
        assert!(out.notes[0].contains("uniform 50.0"), "{}", out.notes[0]);
    }

    #[test]
    fn one_missing_sample_and_jitter_are_resampled_not_split() {
        // 50 Hz with ±6 ms of timestamp jitter and one sample missing at t = 2 s: one piece on the 20 ms grid,
        // its column interpolated exactly (the column is linear in time).
        let mut t: Vec<f64> = (0..300)
            .filter(|&k| k != 100)
            .map(|k| k as f64 * 0.02 + if k % 3 == 1 { 0.006 } else { 0.0 })
            .collect();
        t[0] = 0.0;
        let out = uniform_pieces(&ramp(t)).unwrap();
        assert_eq!(out.pieces.len(), 1);
        let p = &out.pieces[0];
        assert!((p.time_s[1] - p.time_s[0] - 0.02).abs() < 1e-9);
        let q = p.column("q_rad_s").unwrap();
        for (t, v) in p.time_s.iter().zip(q) {
            assert!((v - 2.0 * t).abs() < 1e-9);
        }
        assert_eq!(out.notes.len(), 1);
        assert!(out.notes[0].contains("resampled"), "{}", out.notes[0]);
    }
}
