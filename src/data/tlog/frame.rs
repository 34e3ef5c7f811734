//! MAVLink framing of a `.tlog`: `[8-byte big-endian µs timestamp][v1 or v2 frame]` records, the X.25 /
//! MCRF4XX checksum with each message's CRC_EXTRA (MAVLink serialization spec), and resynchronisation after
//! corrupt bytes. Payloads are left to the `mavlink` crate.

use mavlink::dialects::ardupilotmega::MavMessage;
use std::collections::HashMap;

use mavlink::Message;

/// Start-of-frame marker of MAVLink v1.
const STX_V1: u8 = 0xFE;
/// Start-of-frame marker of MAVLink v2.
const STX_V2: u8 = 0xFD;
/// MAVLink v2 incompatibility flag: the frame carries a 13-byte signature.
const IFLAG_SIGNED: u8 = 0x01;
/// Length of the v2 signature trailer.
const SIGNATURE_LEN: usize = 13;
/// A timestamp further than this from its predecessor (µs) is a suspected corruption: accepted
/// only if the next frame confirms the new time base (a genuine gap in logging), else dropped.
const MAX_TIME_JUMP_US: u64 = 10_000_000;

/// One frame found in a log.
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    /// Log timestamp, µs since the Unix epoch (as written by the ground station).
    pub time_us: u64,
    /// 1 or 2.
    pub version: u8,
    /// Sender system id.
    pub sysid: u8,
    /// Sender component id.
    pub compid: u8,
    /// Message id.
    pub msgid: u32,
    /// Payload bytes (v2: trailing zeros may be truncated).
    pub payload: &'a [u8],
}

/// Counts from scanning a log.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ScanStats {
    /// Frames with a valid CRC and a known message id.
    pub frames: usize,
    /// Of which MAVLink v1.
    pub frames_v1: usize,
    /// Of which MAVLink v2.
    pub frames_v2: usize,
    /// Bytes skipped while resynchronising (corrupt or unknown data).
    pub skipped_bytes: usize,
    /// Separate runs of skipped bytes.
    pub corrupt_regions: usize,
    /// Bytes of an incomplete frame at the end of the file (dropped).
    pub truncated_tail_bytes: usize,
    /// Frames whose CRC was valid but whose log timestamp jumped implausibly (dropped).
    pub bad_timestamps: usize,
}

/// Per-message-id CRC_EXTRA lookup with caching (`None`: id not in the dialect).
struct CrcExtra {
    v1: [Option<u8>; 256],
    other: HashMap<u32, Option<u8>>,
}

impl CrcExtra {
    fn new() -> Self {
        static V1: std::sync::OnceLock<[Option<u8>; 256]> = std::sync::OnceLock::new();
        let v1 = *V1.get_or_init(|| {
            let mut v1 = [None; 256];
            for (id, slot) in v1.iter_mut().enumerate() {
                *slot = Self::lookup(id as u32);
            }
            v1
        });
        Self {
            v1,
            other: HashMap::new(),
        }
    }

    fn lookup(id: u32) -> Option<u8> {
        MavMessage::default_message_from_id(id).map(|_| MavMessage::extra_crc(id))
    }

    fn get(&mut self, id: u32) -> Option<u8> {
        if id < 256 {
            self.v1[id as usize]
        } else {
            *self.other.entry(id).or_insert_with(|| Self::lookup(id))
        }
    }
}

/// MAVLink checksum: CRC-16/MCRF4XX (X.25), init 0xFFFF (MAVLink `crc_accumulate`).
#[inline]
fn crc_accumulate(crc: u16, byte: u8) -> u16 {
    let mut tmp = byte ^ (crc & 0xFF) as u8;
    tmp ^= tmp << 4;
    let tmp = u16::from(tmp);
    (crc >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4)
}

fn crc_of(bytes: &[u8], extra: u8) -> u16 {
    let crc = bytes.iter().fold(0xFFFF, |c, &b| crc_accumulate(c, b));
    crc_accumulate(crc, extra)
}

/// Result of trying to read a frame at one position.
enum Attempt<'a> {
    /// A valid frame and the total bytes it occupies (timestamp included).
    Frame(Frame<'a>, usize),
    /// The header is plausible but the frame runs past the end of the input.
    Truncated,
    /// Not a frame.
    Invalid,
}

fn try_frame<'a>(bytes: &'a [u8], pos: usize, crc_extra: &mut CrcExtra) -> Attempt<'a> {
    let n = bytes.len();
    let f = pos + 8;
    if f >= n {
        return Attempt::Truncated;
    }
    let (version, header_len) = match bytes[f] {
        STX_V1 => (1u8, 6usize),
        STX_V2 => (2u8, 10usize),
        _ => return Attempt::Invalid,
    };
    if f + 2 > n {
        return Attempt::Truncated;
    }
    let payload_len = usize::from(bytes[f + 1]);
    let mut total = header_len + payload_len + 2;
    if version == 2 {
        if f + 3 > n {
            return Attempt::Truncated;
        }
        let incompat = bytes[f + 2];
        if incompat & !IFLAG_SIGNED != 0 {
            return Attempt::Invalid;
        }
        if incompat & IFLAG_SIGNED != 0 {
            total += SIGNATURE_LEN;
        }
    }
    if f + total > n {
        return Attempt::Truncated;
    }
    let (sysid, compid, msgid) = if version == 1 {
        (bytes[f + 3], bytes[f + 4], u32::from(bytes[f + 5]))
    } else {
        let id = u32::from_le_bytes([bytes[f + 7], bytes[f + 8], bytes[f + 9], 0]);
        (bytes[f + 5], bytes[f + 6], id)
    };
    let Some(extra) = crc_extra.get(msgid) else {
        return Attempt::Invalid;
    };
    let crc_at = f + header_len + payload_len;
    let crc = u16::from_le_bytes([bytes[crc_at], bytes[crc_at + 1]]);
    if crc_of(&bytes[f + 1..crc_at], extra) != crc {
        return Attempt::Invalid;
    }
    let time_us = u64::from_be_bytes(bytes[pos..f].try_into().unwrap_or([0; 8]));
    Attempt::Frame(
        Frame {
            time_us,
            version,
            sysid,
            compid,
            msgid,
            payload: &bytes[f + header_len..crc_at],
        },
        8 + total,
    )
}

/// Walks every valid frame of a `.tlog` byte stream in order and returns the counts.
///
/// A position that does not hold a valid frame (bad start marker, unknown message id, CRC
/// mismatch, unsupported incompatibility flags) is skipped one byte at a time until the next valid
/// frame; an incomplete frame at the very end is dropped. A frame whose log timestamp jumps by
/// more than 10 s from the previous frame's (and the very first frame) is kept only if the frame
/// after it confirms the new time (a logging gap); otherwise it is dropped and counted as a bad
/// timestamp.
pub fn scan_frames<'a>(bytes: &'a [u8], mut visit: impl FnMut(&Frame<'a>)) -> ScanStats {
    let mut stats = ScanStats::default();
    let mut crc_extra = CrcExtra::new();
    let mut pos = 0usize;
    let mut run_start: Option<usize> = None; // start of the current run of skipped bytes
    let mut tail_start: Option<usize> = None; // first truncated-looking position of that run
    let mut last_time_us: Option<u64> = None;
    let mut pending: Option<Frame<'a>> = None; // a frame whose time jumped, awaiting confirmation
    while pos < bytes.len() {
        match try_frame(bytes, pos, &mut crc_extra) {
            Attempt::Frame(frame, len) => {
                run_start = None;
                tail_start = None;
                pos += len;
                let near = |a: u64, b: u64| a.abs_diff(b) <= MAX_TIME_JUMP_US;
                match (last_time_us, pending.take()) {
                    // The first frame waits for the second to confirm its time.
                    (None, None) => pending = Some(frame),
                    (None, Some(p)) if near(frame.time_us, p.time_us) => {
                        accept(&mut stats, &mut last_time_us, &p, &mut visit);
                        accept(&mut stats, &mut last_time_us, &frame, &mut visit);
                    }
                    (None, Some(_)) => {
                        stats.bad_timestamps += 1;
                        pending = Some(frame);
                    }
                    (Some(last), None) if near(frame.time_us, last) => {
                        accept(&mut stats, &mut last_time_us, &frame, &mut visit)
                    }
                    (Some(_), None) => pending = Some(frame),
                    (Some(_), Some(p)) if near(frame.time_us, p.time_us) => {
                        // Two frames agree on the new time: a real gap in the log.
                        accept(&mut stats, &mut last_time_us, &p, &mut visit);
                        accept(&mut stats, &mut last_time_us, &frame, &mut visit);
                    }
                    (Some(last), Some(_)) => {
                        stats.bad_timestamps += 1;
                        if near(frame.time_us, last) {
                            accept(&mut stats, &mut last_time_us, &frame, &mut visit);
                        } else {
                            pending = Some(frame);
                        }
                    }
                }
            }
            attempt => {
                if run_start.is_none() {
                    run_start = Some(pos);
                    stats.corrupt_regions += 1;
                }
                if matches!(attempt, Attempt::Truncated) && tail_start.is_none() {
                    tail_start = Some(pos);
                }
                stats.skipped_bytes += 1;
                pos += 1;
            }
        }
    }
    if let Some(p) = pending {
        if stats.frames == 0 {
            // A lone frame: nothing contradicts its time.
            accept(&mut stats, &mut last_time_us, &p, &mut visit);
        } else {
            // A jump at the very end cannot be confirmed.
            stats.bad_timestamps += 1;
        }
    }
    // Bytes from an incomplete frame to the end are a truncated tail, not corruption.
    if let (Some(run), Some(tail)) = (run_start, tail_start) {
        let tail_len = bytes.len() - tail;
        stats.truncated_tail_bytes = tail_len;
        stats.skipped_bytes -= tail_len;
        if run == tail {
            stats.corrupt_regions -= 1;
        }
    }
    stats
}

/// Counts a frame and hands it to the visitor.
fn accept<'a>(
    stats: &mut ScanStats,
    last_time_us: &mut Option<u64>,
    frame: &Frame<'a>,
    visit: &mut impl FnMut(&Frame<'a>),
) {
    *last_time_us = Some(frame.time_us);
    stats.frames += 1;
    if frame.version == 1 {
        stats.frames_v1 += 1;
    } else {
        stats.frames_v2 += 1;
    }
    visit(frame);
}
