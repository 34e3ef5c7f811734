//! Maneuver detection in long logs: doublets, 3-2-1-1s and frequency sweeps on the control
//! surfaces, started from near-steady flight.
//!
//! Method, per surface column:
//! 1. Trim baseline: a centred moving median of the surface over 30 s, computed on a 0.25 s
//!    decimated copy and interpolated back (robust to the maneuvers themselves, which are short and
//!    symmetric about trim).
//! 2. Activity: samples whose deviation from the baseline exceeds a threshold
//!    `max(0.25°, 6 × robust noise)`, the noise being 1.4826 × MAD of the sample-to-sample
//!    difference / √2.
//! 3. Events: active samples grouped, bridging quiet gaps shorter than 1.5 s.
//! 4. Classification by the signed pulses inside an event (runs of one sign): 2 alternating pulses
//!    of similar width → doublet; 4 alternating pulses with widths ≈ 3:2:1:1 → 3-2-1-1; 6 or more
//!    alternating pulses → sweep. Anything else (a single pulse such as a turn entry, a step) is not
//!    a maneuver and is not listed.
//! 5. Near-steady check: over the 2 s before the start the body rates (when present) stay within
//!    0.05 rad/s of their mean.

use serde::Serialize;

use super::error::DataError;
use super::record::{median_in_place, FlightRecord};

/// The kind of maneuver found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ManeuverKind {
    /// Two opposite pulses of equal width.
    Doublet,
    /// Four alternating pulses, widths 3:2:1:1.
    ThreeTwoOneOne,
    /// Six or more alternating half-cycles (chirp / frequency sweep).
    Sweep,
}

impl ManeuverKind {
    /// Name as used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            ManeuverKind::Doublet => "doublet",
            ManeuverKind::ThreeTwoOneOne => "3-2-1-1",
            ManeuverKind::Sweep => "sweep",
        }
    }
}

/// One detected maneuver.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Segment {
    /// 1-based number in time order (what `identify --segment N` takes).
    pub number: usize,
    /// Surface column, e.g. `elevator_rad`.
    pub surface: String,
    /// Maneuver kind.
    pub kind: ManeuverKind,
    /// Time the input leaves trim, s.
    pub start_s: f64,
    /// Time the input is back at trim, s.
    pub end_s: f64,
    /// Largest deviation from trim, rad.
    pub amplitude_rad: f64,
    /// Trim value of the surface before the maneuver, rad.
    pub trim_rad: f64,
    /// Body rates were steady over the 2 s before the start (true when rates are not recorded).
    pub steady_before: bool,
    /// Index range `[start, end)` of the samples, for slicing the record.
    pub start_index: usize,
    /// End index (exclusive).
    pub end_index: usize,
}

/// Tuning of [`find_segments`].
#[derive(Debug, Clone)]
pub struct SegmentOptions {
    /// Surface columns searched.
    pub surfaces: Vec<String>,
    /// Smallest deviation from trim that counts as input, rad.
    pub min_amplitude_rad: f64,
    /// Quiet gaps shorter than this inside a maneuver are bridged, s.
    pub max_gap_s: f64,
    /// Window of the moving-median trim baseline, s.
    pub baseline_window_s: f64,
    /// Body-rate tolerance of the near-steady check, rad/s.
    pub steady_rate_tol_rad_s: f64,
}

impl Default for SegmentOptions {
    fn default() -> Self {
        Self {
            surfaces: ["elevator_rad", "aileron_rad", "rudder_rad"]
                .map(String::from)
                .to_vec(),
            min_amplitude_rad: 0.25_f64.to_radians(),
            max_gap_s: 1.5,
            baseline_window_s: 30.0,
            steady_rate_tol_rad_s: 0.05,
        }
    }
}

/// Finds the maneuvers on every surface column present, in time order.
pub fn find_segments(rec: &FlightRecord, opts: &SegmentOptions) -> Result<Vec<Segment>, DataError> {
    rec.validate()?;
    let dt_s = rec.dt_s().unwrap_or(1.0);
    let mut out = Vec::new();
    let present: Vec<&String> = opts
        .surfaces
        .iter()
        .filter(|s| rec.column(s).is_some())
        .collect();
    if present.is_empty() {
        return Err(DataError::MissingColumn {
            column: opts.surfaces.join(" or "),
            why: "to find maneuvers (segments look at the control-surface inputs)".into(),
            present: rec.column_names().join(", "),
        });
    }
    for surface in present {
        let u = rec.column(surface).unwrap_or(&[]);
        let baseline = moving_median_baseline(&rec.time_s, u, opts.baseline_window_s);
        let dev: Vec<f64> = u.iter().zip(&baseline).map(|(a, b)| a - b).collect();
        let thr = opts.min_amplitude_rad.max(6.0 * difference_noise(u));
        let active: Vec<bool> = dev.iter().map(|d| d.abs() > thr).collect();
        let gap = (opts.max_gap_s / dt_s).ceil() as usize;
        for (s, e) in events(&active, gap) {
            let Some(kind) = classify(&dev[s..e], &active[s..e]) else {
                continue;
            };
            let amplitude_rad = dev[s..e].iter().fold(0.0_f64, |m, d| m.max(d.abs()));
            out.push(Segment {
                number: 0,
                surface: surface.clone(),
                kind,
                start_s: rec.time_s[s],
                end_s: rec.time_s[(e).min(rec.len() - 1)],
                amplitude_rad,
                trim_rad: baseline[s],
                steady_before: steady_before(rec, s, 2.0, opts.steady_rate_tol_rad_s),
                start_index: s,
                end_index: e,
            });
        }
    }
    out.sort_by(|a, b| a.start_s.total_cmp(&b.start_s));
    for (i, seg) in out.iter_mut().enumerate() {
        seg.number = i + 1;
    }
    Ok(out)
}

/// Trim baseline: centred moving median over `window_s`, on a 0.25 s decimated grid.
fn moving_median_baseline(t: &[f64], u: &[f64], window_s: f64) -> Vec<f64> {
    let n = t.len();
    let dt = if n > 1 {
        (t[n - 1] - t[0]) / (n - 1) as f64
    } else {
        1.0
    };
    let step = ((0.25 / dt).round() as usize).max(1);
    let dec: Vec<f64> = u.iter().step_by(step).copied().collect();
    let half = ((window_s / 2.0) / (dt * step as f64)).round() as usize;
    let mut scratch = Vec::with_capacity(2 * half + 1);
    let med: Vec<f64> = (0..dec.len())
        .map(|i| {
            let lo = i.saturating_sub(half);
            let hi = (i + half + 1).min(dec.len());
            scratch.clear();
            scratch.extend_from_slice(&dec[lo..hi]);
            median_in_place(&mut scratch)
        })
        .collect();
    (0..n)
        .map(|i| {
            let x = i as f64 / step as f64;
            let k = (x.floor() as usize).min(med.len() - 1);
            let k1 = (k + 1).min(med.len() - 1);
            let w = x - k as f64;
            med[k] + w * (med[k1] - med[k])
        })
        .collect()
}

/// Robust noise standard deviation from first differences: 1.4826 · MAD(Δu) / √2.
fn difference_noise(u: &[f64]) -> f64 {
    if u.len() < 3 {
        return 0.0;
    }
    let mut d: Vec<f64> = u.windows(2).map(|w| w[1] - w[0]).collect();
    let m = median_in_place(&mut d);
    let mut ad: Vec<f64> = d.iter().map(|x| (x - m).abs()).collect();
    1.4826 * median_in_place(&mut ad) / std::f64::consts::SQRT_2
}

/// Runs of active samples, bridging inactive gaps of at most `gap` samples: `[start, end)`.
fn events(active: &[bool], gap: usize) -> Vec<(usize, usize)> {
    let mut out: Vec<(usize, usize)> = Vec::new();
    let mut i = 0;
    while i < active.len() {
        if !active[i] {
            i += 1;
            continue;
        }
        let s = i;
        while i < active.len() && active[i] {
            i += 1;
        }
        match out.last_mut() {
            Some(last) if s - last.1 <= gap => last.1 = i,
            _ => out.push((s, i)),
        }
    }
    out
}

/// Classifies one event from its signed pulses (runs of one sign among active samples).
fn classify(dev: &[f64], active: &[bool]) -> Option<ManeuverKind> {
    // Pulses: (sign, number of active samples); samples of the other sign split pulses, quiet
    // samples do not.
    let mut pulses: Vec<(f64, usize)> = Vec::new();
    for (d, a) in dev.iter().zip(active) {
        if !a {
            continue;
        }
        let s = d.signum();
        match pulses.last_mut() {
            Some(p) if p.0 == s => p.1 += 1,
            _ => pulses.push((s, 1)),
        }
    }
    // Ignore slivers (< 1/4 of the median pulse) left by noise at the edges of a step.
    let mut widths: Vec<f64> = pulses.iter().map(|p| p.1 as f64).collect();
    if widths.is_empty() {
        return None;
    }
    let med = median_in_place(&mut widths);
    let mut merged: Vec<(f64, usize)> = Vec::new();
    for p in pulses.into_iter().filter(|p| p.1 as f64 >= 0.25 * med) {
        match merged.last_mut() {
            Some(q) if q.0 == p.0 => q.1 += p.1,
            _ => merged.push(p),
        }
    }
    let w: Vec<f64> = merged.iter().map(|p| p.1 as f64).collect();
    match w.len() {
        2 => {
            let r = w[0] / w[1];
            (0.6..=1.6).contains(&r).then_some(ManeuverKind::Doublet)
        }
        4 => {
            let unit = w.iter().sum::<f64>() / 7.0;
            let expected = [3.0, 2.0, 1.0, 1.0];
            let ok = w
                .iter()
                .zip(expected)
                .all(|(wi, e)| (wi / (e * unit) - 1.0).abs() < 0.4);
            ok.then_some(ManeuverKind::ThreeTwoOneOne)
        }
        n if n >= 6 => Some(ManeuverKind::Sweep),
        _ => None,
    }
}

/// True if the body rates present stay within `tol` of their mean over `window_s` before `start`.
fn steady_before(rec: &FlightRecord, start: usize, window_s: f64, tol: f64) -> bool {
    let t0 = rec.time_s[start] - window_s;
    let lo = rec.time_s.partition_point(|&t| t < t0);
    if start <= lo + 1 {
        return true;
    }
    ["p_rad_s", "q_rad_s", "r_rad_s"].iter().all(|name| {
        let Some(x) = rec.column(name) else {
            return true;
        };
        let w = &x[lo..start];
        let mean = w.iter().sum::<f64>() / w.len() as f64;
        w.iter().all(|v| (v - mean).abs() <= tol)
    })
}

/// Seconds of record kept before a maneuver's start when a segment is cut out for identification
/// (the trim estimate needs samples before the input moves).
pub const SEGMENT_LEAD_IN_S: f64 = 1.0;

/// Seconds of record kept after a maneuver's end by default (its free response).
pub const SEGMENT_TAIL_S: f64 = 5.0;

/// A reference to a segment on the command line: `N` (segment N) or `K:N` (segment N of the
/// K-th file), both 1-based.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SegmentRef {
    /// 1-based file index, when given.
    pub file: Option<usize>,
    /// 1-based segment number as listed by [`find_segments`].
    pub segment: usize,
}

impl std::str::FromStr for SegmentRef {
    type Err = DataError;
    fn from_str(s: &str) -> Result<SegmentRef, DataError> {
        let bad = || {
            DataError::InvalidArgument(format!(
                "segment `{s}`: expected N or K:N (segment N of the K-th --data file, both from 1)"
            ))
        };
        let number = |t: &str| t.trim().parse::<usize>().ok().filter(|v| *v >= 1);
        match s.split_once(':') {
            Some((k, n)) => Ok(SegmentRef {
                file: Some(number(k).ok_or_else(bad)?),
                segment: number(n).ok_or_else(bad)?,
            }),
            None => Ok(SegmentRef {
                file: None,
                segment: number(s).ok_or_else(bad)?,
            }),
        }
    }
}

/// The part of `rec` around segment `number` (1-based, as listed by [`find_segments`] with
/// `opts`): from [`SEGMENT_LEAD_IN_S`] before its start to `window_s` after that (default: to
/// [`SEGMENT_TAIL_S`] after its end), clipped to the record. `file` names the record in errors.
pub fn segment_window(
    rec: &FlightRecord,
    file: &str,
    number: usize,
    window_s: Option<f64>,
    opts: &SegmentOptions,
) -> Result<(Segment, FlightRecord), DataError> {
    if let Some(w) = window_s {
        if !(w.is_finite() && w > 0.0) {
            return Err(DataError::InvalidArgument(format!(
                "--window-s must be a positive number of seconds, got {w}"
            )));
        }
    }
    let segments = find_segments(rec, opts)?;
    let Some(seg) = number.checked_sub(1).and_then(|i| segments.get(i)) else {
        return Err(DataError::NoSuchSegment {
            file: file.to_string(),
            segment: number,
            found: segments.len(),
            listing: if segments.is_empty() {
                String::new()
            } else {
                format!(" (1 … {})", segments.len())
            },
        });
    };
    let from_s = seg.start_s - SEGMENT_LEAD_IN_S;
    let to_s = match window_s {
        Some(w) => from_s + w,
        None => seg.end_s + SEGMENT_TAIL_S,
    };
    let start = rec.time_s.partition_point(|&t| t < from_s);
    let end = rec.time_s.partition_point(|&t| t <= to_s);
    Ok((seg.clone(), rec.slice(start, end)))
}
