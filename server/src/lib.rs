//! knotsweep's sweep service.
//!
//! Layout (data flows one way: parameters -> case -> solver -> result ->
//! store -> API):
//! - [`spec`]: what a sweep is (base case + grid, or a preset), limits, and
//!   the expansion into validated `CaseParams`;
//! - [`core`]: the typed operations (submit, query, control, phase diagram,
//!   metrics) over the store (`knotsweep_worker::Store`);
//! - [`fit`]: fits of a parameter to measured inversions, over sweeps;
//! - [`api`]: axum handlers, thin adapters over the core (their inputs read by
//!   the extractors of `extract`), and the OpenAPI document; [`views`] and
//!   [`error`]: the JSON they return, built from the store's records;
//! - [`start`]: the server with its embedded worker pool (one case per core
//!   on a rayon pool, off the async runtime) and graceful shutdown.
pub mod api;
pub mod core;
pub mod error;
mod extract;
pub mod fit;
mod http;
pub mod measurements;
pub mod openapi;
pub mod spec;
mod strict_json;
pub mod views;

use anyhow::Context;
use knotsweep_worker::store::RetryPolicy;
use knotsweep_worker::store::{StoreOptions, open_store};
use knotsweep_worker::{PoolConfig, Store, WorkerPool};
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::watch;
use tokio::task::JoinHandle;

pub use crate::core::Core;
pub use crate::spec::{Limits, SweepSpec};

/// Default database: `knotsweep.sqlite` in the working directory.
pub const DEFAULT_DATABASE_URL: &str = "sqlite://knotsweep.sqlite";
/// Default listening address.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8080";

/// How to run the server.
#[derive(Clone, Debug)]
pub struct ServerConfig {
    pub database_url: String,
    /// Embedded worker slots: `None` one per core, `Some(0)` none.
    pub workers: Option<usize>,
    /// Lease length of the embedded workers (`PoolConfig::heartbeat`).
    pub lease: Duration,
    /// Idle poll interval of the embedded workers.
    pub poll: Duration,
    pub retry: RetryPolicy,
    pub limits: Limits,
    /// Bearer token for mutating requests (`KNOTSWEEP_TOKEN`).
    pub token: Option<String>,
    /// Poll interval of the server-sent event streams.
    pub events_interval: Duration,
    /// Time allowed for a request's headers (slow clients are cut off).
    pub header_read_timeout: Duration,
}

impl Default for ServerConfig {
    fn default() -> Self {
        Self {
            database_url: DEFAULT_DATABASE_URL.to_string(),
            workers: None,
            lease: knotsweep_worker::pool::DEFAULT_LEASE,
            poll: knotsweep_worker::pool::DEFAULT_POLL,
            retry: RetryPolicy::DEFAULT,
            limits: Limits::DEFAULT,
            token: None,
            events_interval: Duration::from_millis(500),
            header_read_timeout: http::HEADER_READ_TIMEOUT,
        }
    }
}

/// A server that is accepting connections.
pub struct RunningServer {
    pub addr: SocketAddr,
    store: Arc<dyn Store>,
    shutdown: watch::Sender<bool>,
    http: JoinHandle<()>,
    reaper: JoinHandle<()>,
    pool: Option<WorkerPool>,
}

/// Opens the store (running the migrations), starts the embedded workers and
/// serves the API on `listener`.
pub async fn start(config: ServerConfig, listener: tokio::net::TcpListener) -> anyhow::Result<RunningServer> {
    let addr = listener.local_addr()?;
    let store = open_store(
        &config.database_url,
        StoreOptions {
            retry: config.retry,
            ..StoreOptions::default()
        },
    )
    .await
    .with_context(|| format!("opening the database {}", config.database_url))?;
    let dyn_store = store.clone();
    let workers = config
        .workers
        .unwrap_or_else(knotsweep_worker::pool::default_workers);
    let pool = (workers > 0).then(|| {
        let mut pool_config = PoolConfig::new(workers).with_lease(config.lease);
        pool_config.poll = config.poll;
        WorkerPool::start(dyn_store.clone(), pool_config)
    });
    let core = Core::new(
        dyn_store.clone(),
        config.limits,
        pool.as_ref().map(|p| p.handle()),
    );
    let (shutdown, shutdown_rx) = watch::channel(false);
    let reaper = spawn_reaper(dyn_store.clone(), config.lease, shutdown_rx.clone());
    let app = api::App {
        core,
        token: config.token.clone().filter(|t| !t.is_empty()),
        shutdown: shutdown_rx.clone(),
        events_interval: config.events_interval,
    };
    let router = api::router(app);
    let rx = shutdown_rx;
    let http = tokio::spawn(http::serve(listener, router, rx, config.header_read_timeout));
    tracing::info!(%addr, workers, database = %config.database_url, "knotsweep server listening");
    Ok(RunningServer {
        addr,
        store,
        shutdown,
        http,
        reaper,
        pool,
    })
}

/// Puts expired leases back in the queue every half lease (at least every
/// 200 ms), even when no worker is polling, until `shutdown` changes.
fn spawn_reaper(
    store: Arc<dyn Store>,
    lease: Duration,
    mut shutdown: watch::Receiver<bool>,
) -> JoinHandle<()> {
    let every = (lease / 2).max(Duration::from_millis(200));
    tokio::spawn(async move {
        loop {
            tokio::select! {
                _ = tokio::time::sleep(every) => {}
                _ = shutdown.changed() => return,
            }
            if let Err(e) = store.requeue_expired().await {
                tracing::warn!(error = %e, "requeueing expired leases failed");
            }
        }
    })
}

impl RunningServer {
    /// `http://<addr>`.
    pub fn url(&self) -> String {
        format!("http://{}", self.addr)
    }

    /// The server's store.
    pub fn store(&self) -> Arc<dyn Store> {
        self.store.clone()
    }

    /// Graceful shutdown: stop accepting, finish in-flight requests, end the
    /// event streams, stop the embedded workers (releasing their leases so
    /// the cases are queued again at once) and close the database.
    pub async fn shutdown(self) -> anyhow::Result<()> {
        // Fails only when every receiver (the accept loop, the reaper, the
        // event streams) has already ended.
        let _ = self.shutdown.send(true);
        let served = self.http.await;
        if let Err(e) = self.reaper.await {
            tracing::error!(error = %e, "the lease reaper ended abnormally");
        }
        if let Some(pool) = self.pool {
            pool.shutdown().await;
        }
        self.store.close().await;
        tracing::info!("knotsweep server stopped");
        served.context("server task")?;
        Ok(())
    }
}
