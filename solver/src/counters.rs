//! Wall-clock time spent in each stage of a step (like rapier's `counters`):
//! measurement only, it never changes results.
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// Accumulated time per stage and the number of steps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Counters {
    pub steps: u64,
    /// Broad and narrow phase.
    pub detection: Duration,
    /// Free velocities and the frictional contact solve.
    pub contact_solve: Duration,
    /// Implicit rod steps (Newton).
    pub dynamics: Duration,
    /// Steps whose implicit contact solve fell back to the explicit one
    /// (a rod's contact-free step needed substeps).
    pub explicit_fallbacks: u64,
}

impl Counters {
    /// Runs `f` and adds its duration to `slot`.
    pub fn time<T>(slot: &mut Duration, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        *slot += start.elapsed();
        out
    }
}
