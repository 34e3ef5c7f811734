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
//! 4. Classification by the signed pulses inside an event (runs of one sign, slivers under a quarter
//!    of the median width merged): 2 alternating pulses of similar width (ratio 0.6–1.6) → doublet;
//!    4 with widths ≈ 3:2:1:1 (±40 %) → 3-2-1-1; 6 or more → sweep; any other train of 2–5
//!    alternating pulses (unequal doublets, 2-1-1s, 3-2-1-1s with loose timing) → multistep.
//! 5. Pulse trains across quiet holds: single pulses (back at trim within 8 s) on one surface,
//!    alternating in sign and at most 8 s apart, are one maneuver — bank-to-bank on the aileron, a
//!    multistep on the other surfaces.
//! 6. What is not a maneuver is listed with the reason (`SegmentScan::rejected`): a spike shorter
//!    than 0.2 s, a deflection held longer than 8 s (a trim change, a turn, a step), a lone pulse.
//!    An event with a held deflection in it is first cut at the hold (`split_at_holds`), so that a
//!    maneuver the hold follows (a doublet, then the pilot's recovery held for seconds) is found.
//! 7. Near-steady check: over the 2 s before the start the body rates (when present) stay within
//!    0.05 rad/s of their mean.

use serde::Serialize;

use super::channel::Channel;
use super::error::DataError;
use super::record::FlightRecord;
use crate::signal::{difference_noise_std, median_in_place};

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
    /// Two to five alternating pulses that are not a doublet or a 3-2-1-1.
    Multistep,
    /// Aileron pulses of alternating sign separated by holds (rolls from one bank to the other).
    BankToBank,
}

impl ManeuverKind {
    /// Name as used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            ManeuverKind::Doublet => "doublet",
            ManeuverKind::ThreeTwoOneOne => "3-2-1-1",
            ManeuverKind::Sweep => "sweep",
            ManeuverKind::Multistep => "multistep",
            ManeuverKind::BankToBank => "bank-to-bank",
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

/// Surface activity that is not a maneuver, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Rejected {
    /// Surface column.
    pub surface: String,
    /// Start of the activity, s.
    pub start_s: f64,
    /// End of the activity, s.
    pub end_s: f64,
    /// Largest deviation from trim, rad.
    pub amplitude_rad: f64,
    /// Why it is not a maneuver.
    pub reason: String,
}

/// Everything [`scan_segments`] saw.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SegmentScan {
    /// The maneuvers, in time order.
    pub segments: Vec<Segment>,
    /// Surface activity that is not a maneuver, in time order.
    pub rejected: Vec<Rejected>,
}

/// Longest a single deflection may last and still be a pulse, s (also the longest hold between
/// the pulses of a pulse train).
const MAX_PULSE_S: f64 = 8.0;

/// Longest transition at a pulse's edge (a surface moving from one deflection to the next), s.
const RISE_S: f64 = 0.3;

/// Shortest activity that is an input rather than a spike, s.
const MIN_ACTIVITY_S: f64 = 0.2;

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
            surfaces: [Channel::Elevator, Channel::Aileron, Channel::Rudder]
                .map(|c| c.to_string())
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
    Ok(scan_segments(rec, opts)?.segments)
}

/// Finds the maneuvers on every surface column present and lists the activity that is not one.
pub fn scan_segments(rec: &FlightRecord, opts: &SegmentOptions) -> Result<SegmentScan, DataError> {
    rec.validate()?;
    let dt_s = rec.dt_s().unwrap_or(1.0);
    let mut out = Vec::new();
    let mut rejected = Vec::new();
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
    let last = rec.len() - 1;
    for surface in present {
        let u = rec.column(surface).unwrap_or(&[]);
        let baseline = moving_median_baseline(&rec.time_s, u, opts.baseline_window_s);
        let dev: Vec<f64> = u.iter().zip(&baseline).map(|(a, b)| a - b).collect();
        let thr = opts.min_amplitude_rad.max(6.0 * difference_noise_std(u));
        let active: Vec<bool> = dev.iter().map(|d| d.abs() > thr).collect();
        let gap = (opts.max_gap_s / dt_s).ceil() as usize;
        let amplitude = |s: usize, e: usize| dev[s..e].iter().fold(0.0_f64, |m, d| m.max(d.abs()));
        // (start, end, class, sign of a single pulse)
        let mut found: Vec<(usize, usize, Class, f64)> = Vec::new();
        let pieces = events(&active, gap).into_iter().flat_map(|(s, e)| {
            let pieces = split_at_holds(&dev[s..e], &active[s..e], dt_s, thr);
            let split = pieces.len() > 1;
            pieces
                .into_iter()
                .map(move |(ps, pe)| (s + ps, s + pe, split))
        });
        for (s, e, split) in pieces {
            let span_s = rec.time_s[e.min(last)] - rec.time_s[s];
            // a piece cut off a hold ends where the hold begins: it cannot settle back there
            let settled = if split {
                Ok(())
            } else {
                settles_back(&rec.time_s, u, s, e, (2.0 * thr).max(0.1 * amplitude(s, e)))
            };
            match settled.and_then(|()| classify(&dev[s..e], &active[s..e], span_s)) {
                Ok(class) => {
                    let sign = dev[s..e]
                        .iter()
                        .copied()
                        .fold(0.0_f64, |m, d| if d.abs() > m.abs() { d } else { m })
                        .signum();
                    found.push((s, e, class, sign));
                }
                Err(reason) => rejected.push(Rejected {
                    surface: surface.clone(),
                    start_s: rec.time_s[s],
                    end_s: rec.time_s[e.min(last)],
                    amplitude_rad: amplitude(s, e),
                    reason,
                }),
            }
        }
        let train_kind = if surface.starts_with("aileron") {
            ManeuverKind::BankToBank
        } else {
            ManeuverKind::Multistep
        };
        for (s, e, class) in pulse_trains(&found, &rec.time_s, train_kind) {
            let Class::Maneuver(kind) = class else {
                rejected.push(Rejected {
                    surface: surface.clone(),
                    start_s: rec.time_s[s],
                    end_s: rec.time_s[e.min(last)],
                    amplitude_rad: amplitude(s, e),
                    reason: format!(
                        "a lone pulse (no opposite pulse within {MAX_PULSE_S} s to make a doublet or a pulse train)"
                    ),
                });
                continue;
            };
            out.push(Segment {
                number: 0,
                surface: surface.clone(),
                kind,
                start_s: rec.time_s[s],
                end_s: rec.time_s[e.min(last)],
                amplitude_rad: amplitude(s, e),
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
    rejected.sort_by(|a, b| a.start_s.total_cmp(&b.start_s));
    Ok(SegmentScan {
        segments: out,
        rejected,
    })
}

/// `Err` when the surface settles away from where it started: the medians over 1 s before `s`
/// and 1 s after `e` differ by more than `tol` (a turn's roll-in, a trim change). Passes at the
/// record's edges.
fn settles_back(t: &[f64], u: &[f64], s: usize, e: usize, tol: f64) -> Result<(), String> {
    let before_lo = t.partition_point(|&x| x < t[s] - 1.0);
    let end = e.min(t.len() - 1);
    let after_hi = t.partition_point(|&x| x <= t[end] + 1.0);
    if before_lo + 2 > s || end + 2 > after_hi {
        return Ok(());
    }
    let mut before = u[before_lo..s].to_vec();
    let mut after = u[end..after_hi].to_vec();
    let shift = median_in_place(&mut after) - median_in_place(&mut before);
    if shift.abs() > tol {
        return Err(format!(
            "the surface settles {:.2} deg away from where it started (a turn entry or exit, a trim \
             change), not back at trim",
            shift.to_degrees()
        ));
    }
    Ok(())
}

/// Joins consecutive single pulses of alternating sign at most [`MAX_PULSE_S`] apart into one
/// maneuver of `train_kind`; everything else passes unchanged: `(start, end, class)`.
fn pulse_trains(
    found: &[(usize, usize, Class, f64)],
    t: &[f64],
    train_kind: ManeuverKind,
) -> Vec<(usize, usize, Class)> {
    let mut out: Vec<(usize, usize, Class)> = Vec::new();
    // the last entry is a single pulse or a train of them, ending with a pulse of this sign
    let mut open_train: Option<f64> = None;
    for &(s, e, class, sign) in found {
        let is_pulse = class == Class::Pulse;
        if let (Some(prev), Some(last_sign)) = (out.last_mut(), open_train) {
            let close = t[s] - t[prev.1.min(t.len() - 1)] <= MAX_PULSE_S;
            if is_pulse && sign == -last_sign && close {
                prev.1 = e;
                prev.2 = Class::Maneuver(train_kind);
                open_train = Some(sign);
                continue;
            }
        }
        out.push((s, e, class));
        open_train = is_pulse.then_some(sign);
    }
    out
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

/// The most samples a pulse of [`MAX_PULSE_S`] has at a sample interval `dt_s`.
fn max_pulse_samples(dt_s: f64) -> usize {
    (MAX_PULSE_S / dt_s.max(1e-9)).floor() as usize
}

/// One pulse of an event: a run of one sign among its active samples, `[start, end)` relative to the
/// event, with its number of active samples and its largest deviation.
#[derive(Clone, Copy, Debug)]
struct PulseSpan {
    sign: f64,
    start: usize,
    end: usize,
    width: usize,
    peak: f64,
}

/// The signed pulses of an event (samples of the other sign split pulses, quiet samples do not), with the
/// slivers (under a quarter of the median pulse) that noise leaves at the edges of a step dropped and the
/// pulses they separated joined. The median is over the pulses of at most `max_width` samples (all when
/// none is): a long hold must not make a maneuver's pulses beside it slivers.
fn pulse_spans(dev: &[f64], active: &[bool], max_width: usize) -> Vec<PulseSpan> {
    let mut pulses: Vec<PulseSpan> = Vec::new();
    for (i, (d, a)) in dev.iter().zip(active).enumerate() {
        if !a {
            continue;
        }
        let sign = d.signum();
        match pulses.last_mut() {
            Some(p) if p.sign == sign => {
                p.end = i + 1;
                p.width += 1;
                p.peak = p.peak.max(d.abs());
            }
            _ => pulses.push(PulseSpan {
                sign,
                start: i,
                end: i + 1,
                width: 1,
                peak: d.abs(),
            }),
        }
    }
    let mut widths: Vec<f64> = pulses
        .iter()
        .filter(|p| p.width <= max_width)
        .map(|p| p.width as f64)
        .collect();
    if widths.is_empty() {
        widths = pulses.iter().map(|p| p.width as f64).collect();
    }
    if widths.is_empty() {
        return pulses;
    }
    let med = median_in_place(&mut widths);
    let mut merged: Vec<PulseSpan> = Vec::new();
    for p in pulses.into_iter().filter(|p| p.width as f64 >= 0.25 * med) {
        match merged.last_mut() {
            Some(q) if q.sign == p.sign => {
                q.end = p.end;
                q.width += p.width;
                q.peak = q.peak.max(p.peak);
            }
            _ => merged.push(p),
        }
    }
    merged
}

/// An event cut at the deflections held longer than [`MAX_PULSE_S`]: `[start, end)` pieces relative to the
/// event, in order; the whole event when nothing in it is held. A pilot's recovery (a roll back to wings
/// level held for seconds) or a trim change right after a maneuver joins it into one event, which as a
/// whole is a held deflection; cut, the maneuver is a piece of its own and the hold another (which
/// [`classify`] then rejects). Where a held pulse begins (or ends) deeper than its own plateau, the deeper
/// part is a pulse of the maneuver beside it (a doublet's second half that the hold continues in the same
/// direction): the plateau is the pulse's median deviation, and the part beyond it by more than
/// max(`thr`, 30 % of the plateau) is cut off. Pulses at a piece's edge smaller than a quarter of its
/// largest are the trim settling, not the maneuver, and are left out of it.
fn split_at_holds(dev: &[f64], active: &[bool], dt_s: f64, thr: f64) -> Vec<(usize, usize)> {
    let spans = pulse_spans(dev, active, max_pulse_samples(dt_s));
    let held = |p: &PulseSpan| p.width as f64 * dt_s > MAX_PULSE_S;
    if !spans.iter().any(held) {
        return vec![(0, dev.len())];
    }
    // (span, held)
    let mut parts: Vec<(PulseSpan, bool)> = Vec::new();
    for p in spans {
        if !held(&p) {
            parts.push((p, false));
            continue;
        }
        let mut inside: Vec<f64> = dev[p.start..p.end].iter().map(|d| d * p.sign).collect();
        let plateau = median_in_place(&mut inside);
        let deeper = |i: &usize| dev[*i] * p.sign > plateau + thr.max(0.3 * plateau);
        // the deeper run that starts (ends) within the edge's transition, RISE_S, of the pulse's edge
        let edge = (RISE_S / dt_s.max(1e-9)).ceil() as usize;
        let run = |mut samples: Box<dyn Iterator<Item = usize>>| -> usize {
            let Some(skip) = samples.by_ref().position(|i| deeper(&i)) else {
                return 0;
            };
            if skip > edge {
                return 0;
            }
            skip + 1 + samples.take_while(deeper).count()
        };
        let lead = run(Box::new(p.start..p.end));
        let trail = run(Box::new((p.start..p.end).rev())).min(p.end - p.start - lead);
        let piece = |start: usize, end: usize| PulseSpan {
            start,
            end,
            width: active[start..end].iter().filter(|a| **a).count(),
            peak: dev[start..end].iter().fold(0.0_f64, |m, d| m.max(d.abs())),
            ..p
        };
        let (hold_start, hold_end) = (p.start + lead, p.end - trail);
        if lead > 0 {
            parts.push((piece(p.start, hold_start), false));
        }
        if hold_end > hold_start {
            parts.push((piece(hold_start, hold_end), true));
        }
        if trail > 0 && hold_end > hold_start {
            parts.push((piece(hold_end, p.end), false));
        }
    }
    let mut pieces = Vec::new();
    let mut group: Vec<PulseSpan> = Vec::new();
    let flush = |group: &mut Vec<PulseSpan>, pieces: &mut Vec<(usize, usize)>| {
        let largest = group.iter().fold(0.0_f64, |m, p| m.max(p.peak));
        let kept: Vec<&PulseSpan> = {
            let lo = group.iter().position(|p| p.peak >= 0.25 * largest);
            let hi = group.iter().rposition(|p| p.peak >= 0.25 * largest);
            match (lo, hi) {
                (Some(lo), Some(hi)) => group[lo..=hi].iter().collect(),
                _ => Vec::new(),
            }
        };
        if let (Some(first), Some(last)) = (kept.first(), kept.last()) {
            pieces.push((first.start, last.end));
        }
        group.clear();
    };
    for (p, is_held) in parts {
        if is_held {
            flush(&mut group, &mut pieces);
            pieces.push((p.start, p.end));
        } else {
            group.push(p);
        }
    }
    flush(&mut group, &mut pieces);
    pieces
}

/// Classifies one event from its signed pulses (runs of one sign among active samples), or says
/// why it is not a maneuver.
fn classify(dev: &[f64], active: &[bool], span_s: f64) -> Result<Class, String> {
    if span_s < MIN_ACTIVITY_S {
        return Err(format!(
            "a spike of {span_s:.2} s (an input lasts at least {MIN_ACTIVITY_S} s)"
        ));
    }
    let dt_s = span_s / dev.len().max(1) as f64;
    let merged = pulse_spans(dev, active, max_pulse_samples(dt_s));
    if merged.is_empty() {
        return Err("no deflection above the threshold".into());
    }
    let w: Vec<f64> = merged.iter().map(|p| p.width as f64).collect();
    let longest_s = w.iter().fold(0.0_f64, |m, v| m.max(*v)) * dt_s;
    if longest_s > MAX_PULSE_S {
        return Err(format!(
            "a deflection held for {longest_s:.1} s (a turn, a trim change or a step, not a pulse back \
             to trim within {MAX_PULSE_S} s)"
        ));
    }
    Ok(Class::Maneuver(match w.len() {
        1 => return Ok(Class::Pulse),
        2 => {
            let r = w[0] / w[1];
            if (0.6..=1.6).contains(&r) {
                ManeuverKind::Doublet
            } else {
                ManeuverKind::Multistep
            }
        }
        4 => {
            let unit = w.iter().sum::<f64>() / 7.0;
            let expected = [3.0, 2.0, 1.0, 1.0];
            let ok = w
                .iter()
                .zip(expected)
                .all(|(wi, e)| (wi / (e * unit) - 1.0).abs() < 0.4);
            if ok {
                ManeuverKind::ThreeTwoOneOne
            } else {
                ManeuverKind::Multistep
            }
        }
        n if n >= 6 => ManeuverKind::Sweep,
        _ => ManeuverKind::Multistep,
    }))
}

/// What one burst of surface activity is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Class {
    /// A maneuver by itself.
    Maneuver(ManeuverKind),
    /// One pulse back at trim: a maneuver only as part of a pulse train.
    Pulse,
}

/// True if the body rates present stay within `tol` of their mean over `window_s` before `start`.
fn steady_before(rec: &FlightRecord, start: usize, window_s: f64, tol: f64) -> bool {
    let t0 = rec.time_s[start] - window_s;
    let lo = rec.time_s.partition_point(|&t| t < t0);
    if start <= lo + 1 {
        return true;
    }
    [Channel::P, Channel::Q, Channel::R].into_iter().all(|c| {
        let Some(x) = rec.column(c) else {
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
