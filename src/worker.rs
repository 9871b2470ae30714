//! `knotsweep worker`: adds workers in this process to the queue of a
//! database that a server (or `knotsweep sweep`) uses. On SIGTERM or Ctrl-C
//! it stops claiming, releases its leases (the cases are queued again at
//! once) and exits.
use anyhow::{Context, Result};
use knotsweep_worker::store::{StoreOptions, open_store};
use knotsweep_worker::{PoolConfig, Store, WorkerPool};
use std::sync::Arc;
use std::time::Duration;

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    queue: crate::queue_args::QueueArgs,
    /// Idle poll interval (ms).
    #[arg(long, default_value_t = 250)]
    poll_ms: u64,
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
        let mut config = PoolConfig::new(args.queue.workers.unwrap_or(0))
            .with_lease(Duration::from_secs_f64(args.queue.lease_seconds.max(0.1)));
        config.poll = Duration::from_millis(args.poll_ms.max(1));
        let name = config.name.clone();
        let workers = config.workers;
        let pool = WorkerPool::start(store.clone(), config);
        println!(
            "knotsweep worker {name}: {workers} workers on {}",
            args.queue.database_url
        );
        shutdown_signal().await;
        tracing::info!("stopping: no new claims, releasing leases");
        pool.shutdown().await;
        store.close().await;
        Ok(())
    })
}
