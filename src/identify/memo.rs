//! The weighted residuals of the campaign's last replays, kept by what they were replayed
//! from, so that a replay asked for again is a copy instead of a simulation.
//!
//! A search asks for the same replay many times: every candidate's start grid begins at
//! the current model (its own size at "off"), each screening fit starts by replaying its
//! start, and a fit's end point is replayed again for the criterion. On the ten-record
//! timing campaigns at 1 and 10 kHz, about one record replay in eleven was one already made
//! with the same parameters, records and step. A replay depends on nothing else, so the copy
//! is the replay, bit for bit: nothing the calibration finds changes.
//!
//! The key is the parameters (their `Debug` text, which prints every `f64` so that it reads
//! back to the same bits), the step rule and each record's identity within the calibration:
//! its name, length, sample step, Cd factor, residual window and decimations, the weights of
//! its channels and its command's buffer. What is kept is bounded by its count of values
//! ([`KEPT_VALUES`]); the oldest goes first.

use super::replay::{PreparedRecord, StepRule};
use crate::params::Params;
use std::collections::{HashMap, VecDeque};
use std::fmt::Write as _;
use std::sync::{Arc, Mutex};

/// Most residual values kept (8 bytes each: 64 MB); a ten-record campaign of 60 s has about
/// 23 000 per replay, so about 350 replays are kept.
pub const KEPT_VALUES: usize = 8 << 20;

#[derive(Default)]
struct Kept {
    by_key: HashMap<String, Arc<Vec<f64>>>,
    order: VecDeque<String>,
    values: usize,
}

/// The kept residuals of one calibration (see the [module docs](self)).
#[derive(Default)]
pub struct ResidualMemo {
    kept: Mutex<Kept>,
}

impl ResidualMemo {
    /// The key of a replay of `records` with `params` at `step`.
    pub fn key(params: &Params, records: &[PreparedRecord], step: StepRule) -> String {
        let mut key = format!("{params:?}|{step:?}");
        for r in records {
            let _ = write!(
                key,
                "|{}:{}:{:x}:{:x}:{}..{}:{}:{}:{:x}:{:x}:{:x}:{:x}:{:x}:{:p}",
                r.name,
                r.len,
                r.dt.to_bits(),
                r.cd_factor.to_bits(),
                r.window.start,
                r.window.end,
                r.decimate,
                r.drift_decimate,
                r.scale_du.to_bits(),
                r.scale_ydd.to_bits(),
                r.scale_p[0].to_bits(),
                r.scale_p[1].to_bits(),
                r.lowpass_hz.to_bits(),
                Arc::as_ptr(&r.v_in),
            );
        }
        key
    }

    /// The residuals kept under `key`, if any.
    pub fn get(&self, key: &str) -> Option<Vec<f64>> {
        // The copy is made after the lock is released: the other threads' replays wait for
        // the lock only while the map is read.
        let kept = self.kept.lock().ok()?.by_key.get(key).cloned()?;
        Some(kept.as_ref().clone())
    }

    /// Keeps `residuals` under `key`, dropping the oldest while more than [`KEPT_VALUES`]
    /// values are kept. A set larger than that alone is not kept.
    pub fn put(&self, key: String, residuals: &[f64]) {
        if residuals.len() > KEPT_VALUES {
            return;
        }
        let Ok(mut kept) = self.kept.lock() else {
            return;
        };
        if kept.by_key.contains_key(&key) {
            return;
        }
        while kept.values + residuals.len() > KEPT_VALUES {
            let Some(old) = kept.order.pop_front() else {
                break;
            };
            if let Some(r) = kept.by_key.remove(&old) {
                kept.values -= r.len();
            }
        }
        kept.values += residuals.len();
        kept.order.push_back(key.clone());
        kept.by_key.insert(key, Arc::new(residuals.to_vec()));
    }

    /// How many replays are kept.
    pub fn len(&self) -> usize {
        self.kept.lock().map_or(0, |k| k.order.len())
    }

    /// Whether none is.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The key tells apart parameters one unit in the last place apart, and the step rules.
    #[test]
    fn the_key_holds_every_bit_of_the_parameters() {
        let p = Params::paper();
        let mut q = p;
        q.plant.valve.cd = q.plant.valve.cd.next_up();
        let key = |p: &Params, s| ResidualMemo::key(p, &[], s);
        assert_eq!(
            key(&p, StepRule::Resolving),
            key(&Params::paper(), StepRule::Resolving)
        );
        assert_ne!(key(&p, StepRule::Resolving), key(&q, StepRule::Resolving));
        assert_ne!(key(&p, StepRule::Resolving), key(&p, StepRule::Screening));
    }

    #[test]
    fn the_oldest_go_first_and_a_key_gives_back_its_own() {
        let memo = ResidualMemo::default();
        let n = KEPT_VALUES / 3;
        memo.put("a".into(), &vec![1.0; n]);
        memo.put("b".into(), &vec![2.0; n]);
        memo.put("c".into(), &vec![3.0; n]);
        assert_eq!(memo.len(), 3);
        assert_eq!(memo.get("b").map(|r| r[0]), Some(2.0));
        // A fourth of the same size pushes out the first only.
        memo.put("d".into(), &vec![4.0; n]);
        assert_eq!(memo.len(), 3);
        assert!(memo.get("a").is_none());
        assert_eq!(memo.get("d").map(|r| r.len()), Some(n));
        // Too large alone: not kept, nothing pushed out.
        memo.put("e".into(), &vec![5.0; KEPT_VALUES + 1]);
        assert!(memo.get("e").is_none());
        assert_eq!(memo.len(), 3);
    }
}
