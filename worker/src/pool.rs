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
use crate::store::{Claim, FailOutcome, Heartbeat, Lease, Store, StoreError, now_ms};
use solver::case::CaseParams;
use solver::protocol::{self, CaseReport, Progress, Status};
use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicBool, AtomicI64, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::{oneshot, watch};
use tokio::task::JoinHandle;
use tracing::Instrument;

/// The default lease length ([`PoolConfig::lease`]).
pub const DEFAULT_LEASE: Duration = Duration::from_secs(30);
/// The default idle poll interval ([`PoolConfig::poll`]).
pub const DEFAULT_POLL: Duration = Duration::from_millis(250);
/// Heartbeats per lease ([`PoolConfig::heartbeat`]): a lease survives two
/// missed heartbeats.
pub const HEARTBEATS_PER_LEASE: u32 = 3;

/// Settings of a pool.
#[derive(Clone, Debug)]
pub struct PoolConfig {
    /// Concurrent cases (one per core by default).
    pub workers: usize,
    /// Lease length; a case whose holder stops heartbeating returns to the
    /// queue this long after its last heartbeat.
    pub lease: Duration,
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
    /// `workers` slots (0: one per core), [`DEFAULT_LEASE`], [`DEFAULT_POLL`].
    pub fn new(workers: usize) -> Self {
        let workers = if workers == 0 { default_workers() } else { workers };
        Self {
            workers,
            lease: DEFAULT_LEASE,
            poll: DEFAULT_POLL,
            name: default_owner_name(),
            shutdown_grace: Duration::from_secs(5),
            max_cases: None,
        }
    }

    /// Sets the lease.
    pub fn with_lease(mut self, lease: Duration) -> Self {
        self.lease = lease;
        self
    }

    /// The heartbeat interval: the lease over [`HEARTBEATS_PER_LEASE`].
    pub fn heartbeat(&self) -> Duration {
        self.lease / HEARTBEATS_PER_LEASE
    }
}

/// One per core.
pub fn default_workers() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// `<hostname>-<pid>-<random>`: unique per pool.
pub fn default_owner_name() -> String {
    // The host only makes the lease owners' names readable: without one the
    // pid and the random suffix still make them unique.
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
    nudge: Arc<watch::Sender<u64>>,
}

impl PoolHandle {
    pub fn workers(&self) -> usize {
        self.config.workers
    }

    /// Makes every running slot heartbeat now: a pause or a cancellation
    /// reaches this pool's cases at once (other processes' workers see it at
    /// their next heartbeat).
    pub fn nudge(&self) {
        self.nudge.send_modify(|n| *n += 1);
    }

    /// Slots that have neither polled the queue nor heartbeated for longer
    /// than `max(4 * heartbeat, 4 * poll, 10 s)`: a pool that silently stopped.
    pub fn stalled_slots(&self) -> Vec<usize> {
        let limit = (4 * self.config.heartbeat())
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
    /// Bumped by [`PoolHandle::nudge`]: heartbeat now.
    nudge: Arc<watch::Sender<u64>>,
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
        let nudge = Arc::new(watch::channel(0).0);
        let ctx = Arc::new(Ctx {
            reserved: AtomicU64::new(0),
            store,
            config: config.clone(),
            metrics: metrics.clone(),
            last_poll: last_poll.clone(),
            rayon: Arc::new(rayon),
            nudge: nudge.clone(),
        });
        let (shutdown, rx) = watch::channel(false);
        let tasks = (0..config.workers)
            .map(|slot| tokio::spawn(run_slot(ctx.clone(), slot, rx.clone())))
            .collect();
        tracing::info!(workers = config.workers, name = %config.name, lease_s = config.lease.as_secs_f64(), "worker pool started");
        Self {
            shutdown,
            tasks,
            handle: PoolHandle {
                metrics,
                last_poll,
                config,
                nudge,
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
        // Fails only when every slot has already ended (no receiver left).
        let _ = self.shutdown.send(true);
        for task in self.tasks {
            if let Err(e) = task.await {
                tracing::error!(error = %e, "a worker slot's supervisor ended abnormally");
            }
        }
        tracing::info!(name = %self.handle.config.name, "worker pool stopped");
    }
}

/// Runs a slot, restarting it if it panics (outside the solver, which is caught).
async fn run_slot(ctx: Arc<Ctx>, slot: usize, shutdown: watch::Receiver<bool>) {
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

/// Runs a claimed case to its end and records how it ended.
async fn run_claim(ctx: &Ctx, slot: usize, claim: Claim, shutdown: &mut watch::Receiver<bool>) {
    let claimed_at = Instant::now();
    let params = &claim.params;
    tracing::info!(n = params.n, h = params.h, mu = params.mu, "case claimed");
    let mut run = SolverRun::spawn(&ctx.rayon, claim.params);
    ctx.metrics.running.fetch_add(1, Ordering::Relaxed);
    let outcome = supervise(ctx, slot, &claim.lease, &mut run, shutdown).await;
    ctx.metrics.running.fetch_sub(1, Ordering::Relaxed);
    record(ctx, &claim.lease, outcome, claimed_at).await;
}

/// A case computing on a rayon thread.
struct SolverRun {
    /// Asks the solver to stop at its next progress report.
    stop: Arc<AtomicBool>,
    /// Its latest progress report.
    latest: Arc<Mutex<Option<Progress>>>,
    /// Its report, or why it has none (a panic).
    report: oneshot::Receiver<Result<CaseReport, String>>,
}

impl SolverRun {
    fn spawn(rayon: &rayon::ThreadPool, params: CaseParams) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let latest = Arc::new(Mutex::new(None));
        let (tx, report) = oneshot::channel();
        let (stopped, progress) = (stop.clone(), latest.clone());
        rayon.spawn(move || {
            let run = std::panic::catch_unwind(AssertUnwindSafe(|| {
                protocol::run(&params, &mut |p| {
                    if let Ok(mut l) = progress.lock() {
                        *l = Some(*p);
                    }
                    !stopped.load(Ordering::Relaxed)
                })
            }));
            // The receiver is gone only when the slot stopped waiting for this
            // run (shutdown after its grace period): nobody is left to tell.
            let _ = tx.send(run.map_err(|payload| panic_message(payload.as_ref())));
        });
        Self { stop, latest, report }
    }

    fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
    }

    /// The latest progress; none yet, or none after the solver panicked while
    /// holding the lock (the panic itself is reported as the run's outcome).
    fn progress(&self) -> Option<Progress> {
        self.latest.lock().ok().and_then(|l| *l)
    }

    /// The solver's report (cancel-safe: polls the same channel every time).
    async fn finished(&mut self) -> Result<CaseReport, String> {
        (&mut self.report)
            .await
            .unwrap_or_else(|_| Err("the solver thread ended without a result".to_string()))
    }
}

/// What the heartbeats of a run have found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum LeaseState {
    Held,
    /// Every sweep that wants the case was cancelled; the solver is stopping.
    Cancelling,
    /// Another worker holds the case now; the solver is stopping.
    Lost,
}

/// How a run ended.
enum Outcome {
    /// The solver returned (a result, a solver failure or a cancelled run).
    Report(Box<CaseReport>),
    /// The solver panicked.
    Crashed(String),
    /// The lease was lost: the run is discarded.
    LeaseLost,
    /// The pool is shutting down: the lease was given back.
    ShutDown,
}

/// Follows a run to its end: heartbeats every [`PoolConfig::heartbeat`] and
/// when nudged (storing progress, stopping the solver when cancelled or
/// paused, or when the lease is lost) and shutdown.
async fn supervise(
    ctx: &Ctx,
    slot: usize,
    lease: &Lease,
    run: &mut SolverRun,
    shutdown: &mut watch::Receiver<bool>,
) -> Outcome {
    let period = ctx.config.heartbeat().max(Duration::from_millis(10));
    let mut ticker = tokio::time::interval_at(tokio::time::Instant::now() + period, period);
    ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let mut state = LeaseState::Held;
    // The sender lives in `ctx`: `changed` never fails while this runs.
    let mut nudges = ctx.nudge.subscribe();
    loop {
        tokio::select! {
            report = run.finished() => {
                return match (state, report) {
                    (LeaseState::Lost, _) => Outcome::LeaseLost,
                    (_, Ok(report)) => Outcome::Report(Box::new(report)),
                    (_, Err(panic)) => Outcome::Crashed(panic),
                };
            }
            _ = ticker.tick() => {
                ctx.last_poll[slot].store(now_ms(), Ordering::Relaxed);
                state = heartbeat(ctx, lease, run, state).await;
            }
            Ok(()) = nudges.changed() => {
                state = heartbeat(ctx, lease, run, state).await;
            }
            _ = shutdown.changed(), if state != LeaseState::Lost => {
                return shut_down(ctx, lease, run).await;
            }
        }
    }
}

/// Extends the lease and stores progress; stops the solver at the first
/// cancel request or when the lease is lost.
async fn heartbeat(ctx: &Ctx, lease: &Lease, run: &SolverRun, state: LeaseState) -> LeaseState {
    let progress = run.progress();
    match ctx
        .store
        .heartbeat(lease, progress.as_ref(), ctx.config.lease)
        .await
    {
        Ok(Heartbeat::Held { cancel: true }) if state == LeaseState::Held => {
            tracing::info!("cancel or pause requested: stopping the solver");
            run.stop();
            LeaseState::Cancelling
        }
        Ok(Heartbeat::Held { .. }) => state,
        Ok(Heartbeat::Lost) => {
            if state != LeaseState::Lost {
                tracing::warn!("lease lost to another worker: stopping the solver");
            }
            run.stop();
            LeaseState::Lost
        }
        Err(e) => {
            WorkerMetrics::inc(&ctx.metrics.store_errors);
            tracing::warn!(error = %e, "heartbeat failed; will retry");
            state
        }
    }
}

/// Stops the solver, gives the lease back at once and leaves once the solver
/// has noticed (or after `shutdown_grace`).
async fn shut_down(ctx: &Ctx, lease: &Lease, run: &mut SolverRun) -> Outcome {
    run.stop();
    match ctx.store.release(lease).await {
        Ok(true) => {
            WorkerMetrics::inc(&ctx.metrics.releases);
            tracing::info!("shutting down: lease released");
        }
        Ok(false) => tracing::info!("shutting down: the lease was no longer ours"),
        Err(e) => tracing::warn!(error = %e, "shutting down: releasing the lease failed; it will expire"),
    }
    if tokio::time::timeout(ctx.config.shutdown_grace, run.finished())
        .await
        .is_err()
    {
        tracing::warn!(
            grace_s = ctx.config.shutdown_grace.as_secs_f64(),
            "shutting down: the solver did not stop within the grace period; left to end on its own"
        );
    }
    Outcome::ShutDown
}

/// Stores what a run ended with, with its metrics.
async fn record(ctx: &Ctx, lease: &Lease, outcome: Outcome, claimed_at: Instant) {
    match outcome {
        Outcome::ShutDown => {}
        Outcome::LeaseLost => {
            WorkerMetrics::inc(&ctx.metrics.lost_leases);
            let message = format!("{} lost its lease; its run was discarded", lease.owner);
            if let Err(e) = ctx.store.append_log(lease.case_id, "warn", &message).await {
                tracing::warn!(error = %e, "{message}; the log line could not be stored");
            }
        }
        Outcome::Crashed(panic) => record_crash(ctx, lease, &panic).await,
        Outcome::Report(report) if report.status == Status::Cancelled => {
            WorkerMetrics::inc(&ctx.metrics.cancellations);
            match with_retries(|| ctx.store.finish_cancelled(lease)).await {
                Ok(_) => tracing::info!("case cancelled"),
                Err(e) => {
                    tracing::error!(error = %e, "recording the cancellation failed; the lease will expire")
                }
            }
        }
        Outcome::Report(report) => record_result(ctx, lease, &report, claimed_at).await,
    }
}

/// A solver panic is a failed attempt: retried with backoff, then `failed`.
async fn record_crash(ctx: &Ctx, lease: &Lease, panic: &str) {
    tracing::error!(reason = %panic, "solver panicked");
    let reason = format!("solver panicked: {panic}");
    match with_retries(|| ctx.store.fail_attempt(lease, &reason)).await {
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

/// Stores the solver's report as the case's result, if the lease is still ours.
async fn record_result(ctx: &Ctx, lease: &Lease, report: &CaseReport, claimed_at: Instant) {
    match with_retries(|| ctx.store.complete(lease, report)).await {
        Ok(true) => {
            let outcome = report.status.to_string();
            let outcome = outcome.as_str();
            let total = claimed_at.elapsed().as_secs_f64();
            ctx.metrics
                .record_completion(outcome, report.stats.wall_time, total);
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
