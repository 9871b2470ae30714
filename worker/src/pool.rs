//! A pool of workers: each slot claims a case, runs the real solver on a rayon
//! thread (off the async runtime), heartbeats the lease at a fraction of its
//! length (storing progress and reading the cancel flag) and stores the
//! result only while it holds the lease.
//!
//! Failure handling:
//! - solver failures (diverged, topology changed, ...) are results;
//! - a panic in the solver is a failed attempt (retried with backoff, then
//!   `failed`); a store error is retried by the slot, never ends it;
//! - a slot that panics is restarted by its supervisor, and every slot records
//!   when it last polled ([`PoolHandle::stalled_slots`]) so a pool that stops
//!   claiming shows up in `/healthz`;
//! - on shutdown the slots stop claiming, release their leases at once (the
//!   cases are queued again, the attempt not counted) and stop their solvers.
use crate::metrics::WorkerMetrics;
use crate::store::{Claim, FailOutcome, Heartbeat, Store, StoreError, now_ms};
use solver::protocol::{self, CaseReport, Progress, Status};
use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicBool, AtomicI64, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::{oneshot, watch};
use tokio::task::JoinHandle;
use tracing::Instrument;

/// Settings of a pool.
#[derive(Clone, Debug)]
pub struct PoolConfig {
    /// Concurrent cases (one per core by default).
    pub workers: usize,
    /// Lease length; a case whose holder stops heartbeating returns to the
    /// queue this long after its last heartbeat.
    pub lease: Duration,
    /// Heartbeat interval: a fraction of the lease (default a third).
    pub heartbeat: Duration,
    /// Idle poll interval (with jitter) when the queue is empty.
    pub poll: Duration,
    /// Prefix of the lease owner names (`<name>-<slot>`).
    pub name: String,
    /// How long shutdown waits for a solver to notice its stop flag.
    pub shutdown_grace: Duration,
    /// Claim at most this many cases in all, then let the slots end (batch jobs).
    pub max_cases: Option<u64>,
}

impl PoolConfig {
    /// `workers` slots (0: one per core), 30 s leases, heartbeats every 10 s.
    pub fn new(workers: usize) -> Self {
        let workers = if workers == 0 { default_workers() } else { workers };
        Self {
            workers,
            lease: Duration::from_secs(30),
            heartbeat: Duration::from_secs(10),
            poll: Duration::from_millis(250),
            name: default_owner_name(),
            shutdown_grace: Duration::from_secs(5),
            max_cases: None,
        }
    }

    /// Sets the lease and a heartbeat at a third of it.
    pub fn with_lease(mut self, lease: Duration) -> Self {
        self.lease = lease;
        self.heartbeat = lease / 3;
        self
    }
}

/// One per core.
pub fn default_workers() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// `<hostname>-<pid>-<random>`: unique per pool.
pub fn default_owner_name() -> String {
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "local".to_string());
    format!("{host}-{}-{:04x}", std::process::id(), rand::random::<u16>())
}

/// What the server needs from a running pool: its counters and liveness.
#[derive(Clone, Debug)]
pub struct PoolHandle {
    pub metrics: Arc<WorkerMetrics>,
    last_poll: Arc<Vec<AtomicI64>>,
    config: Arc<PoolConfig>,
}

impl PoolHandle {
    pub fn workers(&self) -> usize {
        self.config.workers
    }

    /// Slots that have neither polled the queue nor heartbeated for longer
    /// than `max(4 * heartbeat, 4 * poll, 10 s)`: a pool that silently stopped.
    pub fn stalled_slots(&self) -> Vec<usize> {
        let limit = (4 * self.config.heartbeat)
            .max(4 * self.config.poll)
            .max(Duration::from_secs(10));
        let now = now_ms();
        self.last_poll
            .iter()
            .enumerate()
            .filter(|(_, t)| now - t.load(Ordering::Relaxed) > limit.as_millis() as i64)
            .map(|(i, _)| i)
            .collect()
    }
}

/// A running pool; [`WorkerPool::shutdown`] stops it.
pub struct WorkerPool {
    shutdown: watch::Sender<bool>,
    tasks: Vec<JoinHandle<()>>,
    handle: PoolHandle,
}

struct Ctx {
    /// Claims made or being attempted, against `config.max_cases`.
    reserved: AtomicU64,
    store: Arc<dyn Store>,
    config: Arc<PoolConfig>,
    metrics: Arc<WorkerMetrics>,
    last_poll: Arc<Vec<AtomicI64>>,
    rayon: Arc<rayon::ThreadPool>,
}

impl WorkerPool {
    /// Starts `config.workers` slots on the current tokio runtime and a rayon
    /// pool of as many threads for the solver.
    pub fn start(store: Arc<dyn Store>, config: PoolConfig) -> Self {
        let config = Arc::new(config);
        let metrics = Arc::new(WorkerMetrics::default());
        let last_poll: Arc<Vec<AtomicI64>> =
            Arc::new((0..config.workers).map(|_| AtomicI64::new(now_ms())).collect());
        let rayon = rayon::ThreadPoolBuilder::new()
            .num_threads(config.workers.max(1))
            .thread_name(|i| format!("knotsweep-solver-{i}"))
            .build()
            .expect("rayon pool starts");
        let ctx = Arc::new(Ctx {
            reserved: AtomicU64::new(0),
            store,
            config: config.clone(),
            metrics: metrics.clone(),
            last_poll: last_poll.clone(),
            rayon: Arc::new(rayon),
        });
        let (shutdown, rx) = watch::channel(false);
        let tasks = (0..config.workers)
            .map(|slot| tokio::spawn(supervise(ctx.clone(), slot, rx.clone())))
            .collect();
        tracing::info!(workers = config.workers, name = %config.name, lease_s = config.lease.as_secs_f64(), "worker pool started");
        Self {
            shutdown,
            tasks,
            handle: PoolHandle {
                metrics,
                last_poll,
                config,
            },
        }
    }

    pub fn handle(&self) -> PoolHandle {
        self.handle.clone()
    }

    /// Every slot has ended (only after `max_cases` or a shutdown).
    pub fn finished(&self) -> bool {
        self.tasks.iter().all(|t| t.is_finished())
    }

    /// Stops claiming, releases the held leases and waits for the slots.
    pub async fn shutdown(self) {
        let _ = self.shutdown.send(true);
        for task in self.tasks {
            let _ = task.await;
        }
        tracing::info!(name = %self.handle.config.name, "worker pool stopped");
    }
}

/// Restarts a slot that panicked (outside the solver, which is caught).
async fn supervise(ctx: Arc<Ctx>, slot: usize, shutdown: watch::Receiver<bool>) {
    loop {
        let task = tokio::spawn(slot_loop(ctx.clone(), slot, shutdown.clone()));
        match task.await {
            Ok(()) => return,
            Err(e) => {
                tracing::error!(slot, error = %e, "worker slot died; restarting it");
                tokio::time::sleep(Duration::from_secs(1)).await;
            }
        }
    }
}

fn jittered(d: Duration) -> Duration {
    d.mul_f64(0.5 + rand::random::<f64>())
}

async fn slot_loop(ctx: Arc<Ctx>, slot: usize, mut shutdown: watch::Receiver<bool>) {
    let owner = format!("{}-{slot}", ctx.config.name);
    let mut error_backoff = Duration::from_millis(100);
    loop {
        // Stop when asked, or when the pool was dropped without a shutdown.
        if *shutdown.borrow() || shutdown.has_changed().is_err() {
            return;
        }
        ctx.last_poll[slot].store(now_ms(), Ordering::Relaxed);
        if let Some(max) = ctx.config.max_cases {
            if ctx.reserved.fetch_add(1, Ordering::SeqCst) >= max {
                ctx.reserved.fetch_sub(1, Ordering::SeqCst);
                tracing::info!(slot, max, "claimed the maximum number of cases; slot ends");
                return;
            }
        }
        let claimed = match ctx.store.requeue_expired().await {
            Ok(_) => ctx.store.claim(&owner, ctx.config.lease).await,
            Err(e) => Err(e),
        };
        if ctx.config.max_cases.is_some() && !matches!(claimed, Ok(Some(_))) {
            ctx.reserved.fetch_sub(1, Ordering::SeqCst);
        }
        match claimed {
            Ok(Some(claim)) => {
                error_backoff = Duration::from_millis(100);
                WorkerMetrics::inc(&ctx.metrics.claims);
                let span = tracing::info_span!(
                    "case",
                    case_id = claim.lease.case_id,
                    sweeps = tracing::field::Empty,
                    attempt = claim.attempt,
                    worker = %owner
                );
                if let Ok(sweeps) = ctx.store.case_sweeps(claim.lease.case_id).await {
                    span.record("sweeps", tracing::field::debug(&sweeps));
                }
                run_claim(&ctx, slot, claim, &mut shutdown).instrument(span).await;
            }
            Ok(None) => {
                error_backoff = Duration::from_millis(100);
                tokio::select! {
                    _ = ctx.store.wait_for_work(jittered(ctx.config.poll)) => {}
                    _ = shutdown.changed() => {}
                }
            }
            Err(e) => {
                WorkerMetrics::inc(&ctx.metrics.store_errors);
                tracing::warn!(slot, error = %e, "claiming failed; retrying");
                tokio::select! {
                    _ = tokio::time::sleep(jittered(error_backoff)) => {}
                    _ = shutdown.changed() => {}
                }
                error_backoff = (error_backoff * 2).min(Duration::from_secs(5));
            }
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stop {
    Cancel,
    Lost,
    Shutdown,
}

type SolverOutcome = Result<CaseReport, String>;

async fn run_claim(ctx: &Ctx, slot: usize, claim: Claim, shutdown: &mut watch::Receiver<bool>) {
    let lease = claim.lease.clone();
    let claimed_at = Instant::now();
    tracing::info!(
        n = claim.params.n,
        h = claim.params.h,
        mu = claim.params.mu,
        "case claimed"
    );
    let stop = Arc::new(AtomicBool::new(false));
    let latest: Arc<Mutex<Option<Progress>>> = Arc::new(Mutex::new(None));
    let (tx, mut rx) = oneshot::channel::<SolverOutcome>();
    {
        let (stop, latest, params) = (stop.clone(), latest.clone(), claim.params.clone());
        ctx.rayon.spawn(move || {
            let run = std::panic::catch_unwind(AssertUnwindSafe(|| {
                protocol::run(&params, &mut |p| {
                    if let Ok(mut l) = latest.lock() {
                        *l = Some(*p);
                    }
                    !stop.load(Ordering::Relaxed)
                })
            }));
            let _ = tx.send(run.map_err(|payload| panic_message(payload.as_ref())));
        });
    }
    ctx.metrics.running.fetch_add(1, Ordering::Relaxed);
    let heartbeat = ctx.config.heartbeat.max(Duration::from_millis(10));
    let mut ticker = tokio::time::interval_at(tokio::time::Instant::now() + heartbeat, heartbeat);
    ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let mut why: Option<Stop> = None;
    let outcome: SolverOutcome = loop {
        tokio::select! {
            r = &mut rx => break r.unwrap_or_else(|_| Err("the solver thread ended without a result".to_string())),
            _ = ticker.tick() => {
                ctx.last_poll[slot].store(now_ms(), Ordering::Relaxed);
                let progress = latest.lock().ok().and_then(|l| *l);
                match ctx.store.heartbeat(&lease, progress.as_ref(), ctx.config.lease).await {
                    Ok(Heartbeat::Held { cancel: true }) if why.is_none() => {
                        tracing::info!("cancel requested: stopping the solver");
                        stop.store(true, Ordering::Relaxed);
                        why = Some(Stop::Cancel);
                    }
                    Ok(Heartbeat::Held { .. }) => {}
                    Ok(Heartbeat::Lost) => {
                        if why != Some(Stop::Lost) {
                            tracing::warn!("lease lost to another worker: stopping the solver");
                        }
                        stop.store(true, Ordering::Relaxed);
                        why = Some(Stop::Lost);
                    }
                    Err(e) => {
                        WorkerMetrics::inc(&ctx.metrics.store_errors);
                        tracing::warn!(error = %e, "heartbeat failed; will retry");
                    }
                }
            }
            _ = shutdown.changed(), if why != Some(Stop::Shutdown) && why != Some(Stop::Lost) => {
                stop.store(true, Ordering::Relaxed);
                why = Some(Stop::Shutdown);
                match ctx.store.release(&lease).await {
                    Ok(true) => {
                        WorkerMetrics::inc(&ctx.metrics.releases);
                        tracing::info!("shutting down: lease released");
                    }
                    Ok(false) => tracing::info!("shutting down: the lease was no longer ours"),
                    Err(e) => tracing::warn!(error = %e, "shutting down: releasing the lease failed; it will expire"),
                }
                // Give the solver a moment to notice the stop flag, then leave.
                match tokio::time::timeout(ctx.config.shutdown_grace, &mut rx).await {
                    Ok(r) => break r.unwrap_or_else(|_| Err("the solver thread ended without a result".to_string())),
                    Err(_) => break Err("shutdown".to_string()),
                }
            }
        }
    };
    ctx.metrics.running.fetch_sub(1, Ordering::Relaxed);
    match (why, outcome) {
        (Some(Stop::Shutdown), _) => {}
        (Some(Stop::Lost), _) => {
            WorkerMetrics::inc(&ctx.metrics.lost_leases);
            let _ = ctx
                .store
                .append_log(
                    lease.case_id,
                    "warn",
                    &format!("{} lost its lease; its run was discarded", lease.owner),
                )
                .await;
        }
        (_, Err(panic)) => {
            tracing::error!(reason = %panic, "solver panicked");
            let reason = format!("solver panicked: {panic}");
            match with_retries(|| ctx.store.fail_attempt(&lease, &reason)).await {
                Ok(FailOutcome::Retry { after }) => {
                    WorkerMetrics::inc(&ctx.metrics.retries);
                    tracing::warn!(retry_in_s = after.as_secs_f64(), "attempt failed; queued again");
                }
                Ok(FailOutcome::Failed) => {
                    WorkerMetrics::inc(&ctx.metrics.failures);
                    tracing::error!("out of attempts: case failed");
                }
                Ok(FailOutcome::Lost) => WorkerMetrics::inc(&ctx.metrics.lost_leases),
                Err(e) => tracing::error!(error = %e, "recording the failure failed; the lease will expire"),
            }
        }
        (_, Ok(report)) if report.status == Status::Cancelled => {
            WorkerMetrics::inc(&ctx.metrics.cancellations);
            match with_retries(|| ctx.store.finish_cancelled(&lease)).await {
                Ok(_) => tracing::info!("case cancelled"),
                Err(e) => {
                    tracing::error!(error = %e, "recording the cancellation failed; the lease will expire")
                }
            }
        }
        (_, Ok(report)) => match with_retries(|| ctx.store.complete(&lease, &report)).await {
            Ok(true) => {
                let outcome = serde_json::to_value(report.status).ok();
                let outcome = outcome.as_ref().and_then(|v| v.as_str()).unwrap_or("unknown");
                ctx.metrics.record_completion(
                    outcome,
                    report.stats.wall_time,
                    claimed_at.elapsed().as_secs_f64(),
                );
                tracing::info!(
                    outcome,
                    wall_s = report.stats.wall_time,
                    inversion = report.inversion.map(|i| i.l_k_bar),
                    "result stored"
                );
            }
            Ok(false) => {
                WorkerMetrics::inc(&ctx.metrics.lost_leases);
                tracing::warn!("lease lost before the result was stored; result discarded");
            }
            Err(e) => {
                tracing::error!(error = %e, "storing the result failed; the lease will expire and the case rerun")
            }
        },
    }
}

/// Retries a store call on transient errors (a few times, with backoff).
async fn with_retries<T, F, Fut>(mut f: F) -> Result<T, StoreError>
where
    F: FnMut() -> Fut,
    Fut: std::future::Future<Output = Result<T, StoreError>>,
{
    let mut delay = Duration::from_millis(200);
    let mut tries = 0;
    loop {
        match f().await {
            Err(StoreError::Database(e)) if tries < 5 => {
                tries += 1;
                tracing::warn!(error = %e, tries, "store call failed; retrying");
                tokio::time::sleep(jittered(delay)).await;
                delay *= 2;
            }
            other => return other,
        }
    }
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".to_string()
    }
}
