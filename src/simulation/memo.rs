//! The exponential method's coefficients and the exact hold's transitions built last in this
//! process ([`Etd4::new`](super::integrate::Etd4::new),
//! [`ExactHold::new`](super::lti::ExactHold::new)), by the bits of what they were built from:
//! a run of the same plant at the same step takes a copy, bit for bit what building gives.

use std::any::Any;
use std::sync::{Arc, Mutex};

/// How many are kept (a sweep or a search uses one; the app a few).
const KEPT: usize = 8;

type Kept = Vec<(Vec<u64>, Arc<dyn Any + Send + Sync>)>;

static KEPT_COEFFICIENTS: Mutex<Kept> = Mutex::new(Vec::new());

/// A copy of the coefficients built from `key`, if kept.
pub(in crate::simulation) fn get<T: Any + Clone>(key: &[u64]) -> Option<T> {
    let kept = KEPT_COEFFICIENTS.lock().unwrap_or_else(|e| e.into_inner());
    let (_, value) = kept.iter().find(|(k, _)| k.as_slice() == key)?;
    value.downcast_ref::<T>().cloned()
}

/// Keeps `value`, built from `key`, in place of the oldest when full.
pub(in crate::simulation) fn put<T: Any + Send + Sync>(key: Vec<u64>, value: T) {
    let mut kept = KEPT_COEFFICIENTS.lock().unwrap_or_else(|e| e.into_inner());
    if kept.len() >= KEPT {
        kept.remove(0);
    }
    kept.push((key, Arc::new(value)));
}
