//! Slots for the requests' CPU-bound work (a submission's knots, the
//! simplified model's curves), run on tokio's blocking pool: at most one
//! piece per slot at once, so that requests never stall the async runtime
//! (health checks, event streams, other requests) and never pile up threads.
use crate::error::CoreError;
use std::sync::Arc;
use tokio::sync::Semaphore;

/// The slots.
#[derive(Clone)]
pub struct Computing(Arc<Semaphore>);

impl Computing {
    /// `slots` pieces of work at once (at least one).
    pub fn new(slots: usize) -> Self {
        Self(Arc::new(Semaphore::new(slots.max(1))))
    }

    /// One slot per core.
    pub fn per_core() -> Self {
        Self::new(std::thread::available_parallelism().map_or(1, |n| n.get()))
    }

    /// `work` on the blocking pool once a slot is free; a panic in it is an
    /// internal error.
    pub async fn run<T: Send + 'static>(
        &self,
        work: impl FnOnce() -> T + Send + 'static,
    ) -> Result<T, CoreError> {
        let slot = self.0.clone().acquire_owned().await.expect("never closed");
        tokio::task::spawn_blocking(move || {
            let _slot = slot;
            work()
        })
        .await
        .map_err(|e| CoreError::Internal(format!("a computation failed: {e}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::time::{Duration, Instant};

    /// Eight pieces of 50 ms on two slots: never more than two at once, and
    /// the runtime's own tasks go on meanwhile.
    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn no_more_than_the_slots_run_at_once_and_the_runtime_stays_free() {
        let computing = Computing::new(2);
        let (running, most) = (Arc::new(AtomicUsize::new(0)), Arc::new(AtomicUsize::new(0)));
        let work: Vec<_> = (0..8)
            .map(|_| {
                let (computing, running, most) = (computing.clone(), running.clone(), most.clone());
                tokio::spawn(async move {
                    computing
                        .run(move || {
                            let now = running.fetch_add(1, Ordering::SeqCst) + 1;
                            most.fetch_max(now, Ordering::SeqCst);
                            std::thread::sleep(Duration::from_millis(50));
                            running.fetch_sub(1, Ordering::SeqCst);
                        })
                        .await
                })
            })
            .collect();
        let t = Instant::now();
        let mut ticks = 0;
        while ticks < 5 {
            tokio::time::sleep(Duration::from_millis(10)).await;
            ticks += 1;
        }
        assert!(
            t.elapsed() < Duration::from_millis(150),
            "the runtime was stalled: {:?}",
            t.elapsed()
        );
        for w in work {
            w.await.unwrap().unwrap();
        }
        assert_eq!(most.load(Ordering::SeqCst), 2);
        let panicked = computing.run(|| panic!("in the work")).await;
        assert!(matches!(panicked, Err(CoreError::Internal(_))), "{panicked:?}");
    }
}
