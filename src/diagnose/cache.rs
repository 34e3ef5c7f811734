//! Replays already simulated in one diagnosis, shared by its workers: the search asks for the same simulation
//! many times (the unextended model for the baseline, the nuisance terms, the identifiability screening and the
//! first round; an accepted model again for the next round and the validation), and a 200 Hz replay of a
//! minute of flight costs a fifth of a second of JSBSim.
//!
//! A replay is fully determined by the record (its trim point, rate and input deviations) and the extensions
//! that act before the outputs ([`super::replay::replay`] resets every coefficient knob and added term first),
//! so that pair is the key; sensor extensions are applied to a copy of the cached record.

use std::collections::hash_map::DefaultHasher;
use std::collections::VecDeque;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex};

use super::replay::ReplayCase;
use crate::data::FlightRecord;
use crate::sim::TrimState;

/// Memory the cache may hold, bytes (a 60 s record at 50 Hz with 17 channels is 0.4 MB).
pub const BUDGET_BYTES: usize = 64 << 20;

/// What a replay depends on: the fingerprint of the record and the simulation's rate ([`fingerprint`]) and each extension acting before the
/// outputs with a non-null value, as `effect/target` and the bits of its parameters.
pub type ReplayKey = (u64, Vec<(String, Vec<u64>)>);

/// A simulated record with the model trim it started from.
pub type Replayed = Arc<(FlightRecord, TrimState)>;

/// Least-recently-used store of replays, cloned handles share one store (one per diagnosis).
#[derive(Clone, Default)]
pub struct ReplayCache {
    entries: Arc<Mutex<VecDeque<(ReplayKey, Replayed)>>>,
}

impl ReplayCache {
    /// An empty store.
    pub fn new() -> Self {
        Self::default()
    }

    /// The replay stored under `key`, now the most recently used.
    pub fn get(&self, key: &ReplayKey) -> Option<Replayed> {
        let mut e = self.entries.lock().unwrap_or_else(|p| p.into_inner());
        let i = e.iter().position(|(k, _)| k == key)?;
        let hit = e.remove(i)?;
        let out = Arc::clone(&hit.1);
        e.push_front(hit);
        Some(out)
    }

    /// Stores a replay; the least recently used ones go once the store exceeds [`BUDGET_BYTES`] (one at least
    /// is kept).
    pub fn insert(&self, key: ReplayKey, value: Replayed) {
        let bytes = record_bytes(&value.0).max(1);
        let capacity = (BUDGET_BYTES / bytes).max(1);
        let mut e = self.entries.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(i) = e.iter().position(|(k, _)| *k == key) {
            e.remove(i);
        }
        e.push_front((key, value));
        e.truncate(capacity);
    }

    /// Number of stored replays.
    pub fn len(&self) -> usize {
        self.entries.lock().map(|e| e.len()).unwrap_or(0)
    }

    /// True when nothing is stored.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

fn record_bytes(r: &FlightRecord) -> usize {
    8 * (r.time_s.len() + r.columns.iter().map(|(_, c)| c.len()).sum::<usize>())
}

/// Hash of what a replay of `case` depends on: the rate the simulation integrates at (None: a simulation without
/// a rate of its own), the record's rate and length, the trim point and the input deviations (bits).
pub fn fingerprint(case: &ReplayCase, sim_rate_hz: Option<f64>) -> u64 {
    let mut h = DefaultHasher::new();
    sim_rate_hz.map(f64::to_bits).hash(&mut h);
    case.rate_hz.to_bits().hash(&mut h);
    case.len().hash(&mut h);
    let p = &case.point;
    for v in [
        p.altitude_ft,
        p.speed_kts,
        p.heading_deg,
        p.gamma_deg,
        p.latitude_deg,
        p.temperature_offset_k,
    ] {
        v.to_bits().hash(&mut h);
    }
    for (surface, dev) in &case.inputs {
        surface.hash(&mut h);
        for v in dev {
            v.to_bits().hash(&mut h);
        }
    }
    h.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(n: usize) -> Replayed {
        let mut r = FlightRecord::new(vec![0.0; n]);
        r.push_column("q_rad_s", vec![0.0; n]);
        let trim = TrimState {
            aircraft: "c172x".into(),
            point: crate::sim::TrimPoint::level(4000.0, 100.0),
            alpha_rad: 0.0,
            theta_rad: 0.0,
            phi_rad: 0.0,
            beta_rad: 0.0,
            airspeed_m_s: 51.4,
            altitude_m: 1219.2,
            throttle: 0.6,
            surfaces_rad: Default::default(),
            commands_norm: Default::default(),
            method: Default::default(),
        };
        Arc::new((r, trim))
    }

    #[test]
    fn the_least_recently_used_replay_goes_first_when_the_budget_is_full() {
        // Records of a quarter of the budget: four fit (two columns of 8 bytes per sample).
        let n = BUDGET_BYTES / 4 / 16;
        let c = ReplayCache::new();
        for i in 0..4 {
            c.insert((i, vec![]), entry(n));
        }
        assert!(c.get(&(0, vec![])).is_some()); // 0 is now the most recently used
        c.insert((4, vec![]), entry(n));
        assert_eq!(c.len(), 4);
        assert!(
            c.get(&(1, vec![])).is_none(),
            "1 was the least recently used"
        );
        for k in [0, 2, 3, 4] {
            assert!(c.get(&(k, vec![])).is_some(), "{k}");
        }
    }

    #[test]
    fn the_key_tells_extension_values_apart_and_clones_share_the_store() {
        let c = ReplayCache::new();
        let other = c.clone();
        let key = |v: f64| {
            (
                7,
                vec![("input_delay/elevator".to_string(), vec![v.to_bits()])],
            )
        };
        c.insert(key(0.08), entry(10));
        assert!(other.get(&key(0.08)).is_some());
        assert!(other.get(&key(0.0800001)).is_none());
    }
}
