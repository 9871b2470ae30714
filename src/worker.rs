//! `knotsweep worker`: adds workers in this process to the queue of a
//! database that a server (or `knotsweep sweep`) uses: a SQLite file on this
//! machine or a PostgreSQL server anywhere. On SIGTERM or Ctrl-C it stops
//! claiming, releases its leases (the cases are queued again at once) and
//! exits; `--exit-when-idle` and `--max-cases` end it on its own for batch
//! schedulers.
use anyhow::{Context, Result};
use knotsweep_worker::store::{StoreOptions, open_store};
use knotsweep_worker::{PoolConfig, Store, WorkerPool};
use std::sync::Arc;
use std::time::Duration;

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    queue: crate::queue_args::QueueArgs,
    /// Idle poll interval (ms; on PostgreSQL, idle workers wake on notifications
    /// and poll every 5 s).
    #[arg(long, default_value_t = knotsweep_worker::pool::DEFAULT_POLL.as_millis() as u64)]
    poll_ms: u64,
    /// Exit once no case has run for this many seconds (batch jobs: a Slurm
    /// array task ends when the queue is drained).
    #[arg(long, value_name = "SECONDS")]
    exit_when_idle: Option<f64>,
    /// Claim at most this many cases, finish them and exit.
    #[arg(long, value_name = "N")]
    max_cases: Option<u64>,
}

/// Why the worker stops.
#[derive(Debug, PartialEq)]
enum Stop {
    Signal,
    Idle,
    MaxCases,
}

/// Waits for a signal, `idle` without a running case, or the pool's end.
async fn wait_for_stop(pool: &WorkerPool, idle: Option<Duration>) -> Stop {
    let mut since = std::time::Instant::now();
    let mut tick = tokio::time::interval(Duration::from_millis(200));
    let signal = shutdown_signal();
    tokio::pin!(signal);
    loop {
        tokio::select! {
            _ = &mut signal => return Stop::Signal,
            _ = tick.tick() => {}
        }
        if pool.finished() {
            return Stop::MaxCases;
        }
        if pool
            .handle()
            .metrics
            .running
            .load(std::sync::atomic::Ordering::Relaxed)
            > 0
        {
            since = std::time::Instant::now();
        } else if idle.is_some_and(|d| since.elapsed() >= d) {
            return Stop::Idle;
        }
    }
}

/// Resolves on SIGTERM or Ctrl-C.
pub async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let terminate = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let terminate = std::future::pending::<()>();
    tokio::select! {
        _ = ctrl_c => {}
        _ = terminate => {}
    }
}

/// Opens the store at `url` (any backend [`open_store`] knows).
pub async fn open(url: &str) -> Result<Arc<dyn Store>> {
    open_store(url, StoreOptions::default())
        .await
        .with_context(|| format!("opening the database {url}"))
}

pub fn run(args: Args) -> Result<()> {
    let runtime = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    runtime.block_on(async {
        let store = open(&args.queue.database_url).await?;
        let cores = knotsweep_worker::pool::default_workers();
        let asked = args.queue.workers.unwrap_or(0);
        if asked > cores {
            tracing::warn!(
                asked,
                cores,
                "more workers than cores available to this process: using {cores}"
            );
        }
        let mut config = PoolConfig::new(asked.min(cores))
            .with_lease(Duration::from_secs_f64(args.queue.lease_seconds.max(0.1)));
        config.poll = Duration::from_millis(args.poll_ms.max(1));
        config.max_cases = args.max_cases;
        let name = config.name.clone();
        let workers = config.workers;
        let pool = WorkerPool::start(store.clone(), config);
        println!(
            "knotsweep worker {name}: {workers} workers on {}",
            args.queue.database_url
        );
        let idle = args.exit_when_idle.map(|s| Duration::from_secs_f64(s.max(0.0)));
        let stop = wait_for_stop(&pool, idle).await;
        tracing::info!(reason = ?stop, "stopping: no new claims, releasing leases");
        pool.shutdown().await;
        store.close().await;
        Ok(())
    })
}
