//! In-process counters of a worker pool (claims, completions by outcome,
//! retries, lost leases, case durations), rendered as Prometheus text.
use std::collections::BTreeMap;
use std::fmt::Write;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

/// Upper bounds (s) of the case duration histogram.
pub const DURATION_BUCKETS: [f64; 10] = [0.1, 0.5, 1.0, 5.0, 10.0, 30.0, 60.0, 120.0, 300.0, 600.0];

#[derive(Debug, Default)]
pub struct WorkerMetrics {
    pub claims: AtomicU64,
    pub releases: AtomicU64,
    pub lost_leases: AtomicU64,
    pub retries: AtomicU64,
    pub failures: AtomicU64,
    pub cancellations: AtomicU64,
    pub store_errors: AtomicU64,
    pub running: AtomicU64,
    inner: Mutex<Inner>,
}

#[derive(Debug, Default)]
struct Inner {
    completions: BTreeMap<String, u64>,
    buckets: [u64; DURATION_BUCKETS.len()],
    count: u64,
    sum: f64,
    overhead_sum: f64,
}

impl WorkerMetrics {
    pub fn inc(counter: &AtomicU64) {
        counter.fetch_add(1, Ordering::Relaxed);
    }

    /// A stored result: its solver status, the solver's wall time and the
    /// time from claim to stored result (the difference is queue overhead).
    pub fn record_completion(&self, outcome: &str, solver_seconds: f64, total_seconds: f64) {
        let mut inner = self.inner.lock().expect("metrics lock");
        *inner.completions.entry(outcome.to_string()).or_default() += 1;
        for (i, bound) in DURATION_BUCKETS.iter().enumerate() {
            if total_seconds <= *bound {
                inner.buckets[i] += 1;
            }
        }
        inner.count += 1;
        inner.sum += total_seconds;
        inner.overhead_sum += (total_seconds - solver_seconds).max(0.0);
    }

    /// Completions so far.
    pub fn completions(&self) -> u64 {
        self.inner.lock().expect("metrics lock").count
    }

    /// The counters: name, help text, value.
    fn counters(&self) -> [(&'static str, &'static str, u64); 7] {
        let get = |c: &AtomicU64| c.load(Ordering::Relaxed);
        [
            (
                "knotsweep_claims_total",
                "Cases claimed by this process's workers.",
                get(&self.claims),
            ),
            (
                "knotsweep_releases_total",
                "Leases released at shutdown.",
                get(&self.releases),
            ),
            (
                "knotsweep_lost_leases_total",
                "Cases whose lease was taken over while running.",
                get(&self.lost_leases),
            ),
            (
                "knotsweep_retries_total",
                "Attempts that failed and were queued again.",
                get(&self.retries),
            ),
            (
                "knotsweep_failures_total",
                "Cases failed after their last attempt.",
                get(&self.failures),
            ),
            (
                "knotsweep_cancellations_total",
                "Running cases stopped by a cancel request.",
                get(&self.cancellations),
            ),
            (
                "knotsweep_store_errors_total",
                "Store errors seen by the workers (retried).",
                get(&self.store_errors),
            ),
        ]
    }

    /// Prometheus text exposition of these counters (`let _ =`: writing to a
    /// `String` cannot fail).
    pub fn render(&self, out: &mut String) {
        for (name, help, value) in self.counters() {
            let _ = writeln!(out, "# HELP {name} {help}\n# TYPE {name} counter\n{name} {value}");
        }
        let _ = writeln!(
            out,
            "# HELP knotsweep_running_cases Cases computing in this process.\n# TYPE knotsweep_running_cases gauge\nknotsweep_running_cases {}",
            self.running.load(Ordering::Relaxed)
        );
        let inner = self.inner.lock().expect("metrics lock");
        let _ = writeln!(
            out,
            "# HELP knotsweep_completions_total Results stored by this process's workers, by solver status.\n# TYPE knotsweep_completions_total counter"
        );
        for (outcome, n) in &inner.completions {
            let _ = writeln!(out, "knotsweep_completions_total{{outcome=\"{outcome}\"}} {n}");
        }
        let name = "knotsweep_case_duration_seconds";
        let _ = writeln!(
            out,
            "# HELP {name} Time from claim to stored result.\n# TYPE {name} histogram"
        );
        for (bound, n) in DURATION_BUCKETS.iter().zip(inner.buckets) {
            let _ = writeln!(out, "{name}_bucket{{le=\"{bound}\"}} {n}");
        }
        let _ = writeln!(out, "{name}_bucket{{le=\"+Inf\"}} {}", inner.count);
        let _ = writeln!(out, "{name}_sum {}\n{name}_count {}", inner.sum, inner.count);
        let _ = writeln!(
            out,
            "# HELP knotsweep_queue_overhead_seconds_total Claim-to-result time not spent in the solver.\n# TYPE knotsweep_queue_overhead_seconds_total counter\nknotsweep_queue_overhead_seconds_total {}",
            inner.overhead_sum
        );
    }
}
