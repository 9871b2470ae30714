//! knotsweep's sweep service.
//!
//! Layout (data flows one way: parameters -> case -> solver -> result ->
//! store -> API):
//! - [`spec`]: what a sweep is (base case + grid, or a preset), limits, and
//!   the expansion into validated `CaseParams`;
//! - [`core`]: the typed operations (submit, query, control, phase diagram,
//!   metrics) over the store (`knotsweep_worker::Store`);
//! - [`fit`]: fits of a parameter to measured inversions, over sweeps;
//!   [`refine`]: a map's grid lines bisected where the outcome changes;
//! - [`api`]: axum handlers, thin adapters over the core (their inputs read by
//!   the extractors of `extract`), and the OpenAPI document; [`views`] and
//!   [`error`]: the JSON they return, built from the store's records;
//!   [`guard`]: the cross-site guards and security headers; [`events`]: the
//!   sweeps' event feeds;
//! - [`start`]: the server with its embedded worker pool (one case per core
//!   on a rayon pool, off the async runtime) and graceful shutdown.
pub mod api;
mod computing;
pub mod core;
pub mod error;
pub mod events;
mod extract;
pub mod fit;
pub mod guard;
mod http;
pub mod measurements;
pub mod openapi;
pub mod refine;
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
pub use crate::events::StreamLimits;
pub use crate::guard::AllowedHosts;
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
    /// Bearer token for mutating requests (`KNOTSWEEP_TOKEN`; [`check_token`]).
    pub token: Option<String>,
    /// Host names a `POST` may name besides IP addresses and localhost
    /// (`serve --allowed-host`; [`guard`]).
    pub allowed_hosts: AllowedHosts,
    /// Poll interval of the server-sent event streams.
    pub events_interval: Duration,
    /// Event streams open at once, per sweep and per client address.
    pub stream_limits: StreamLimits,
    /// Time allowed for a request's headers (slow clients are cut off).
    pub header_read_timeout: Duration,
    /// Time allowed for a request's body (408 beyond).
    pub body_read_timeout: Duration,
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
            allowed_hosts: AllowedHosts::default(),
            events_interval: Duration::from_millis(500),
            stream_limits: StreamLimits::DEFAULT,
            header_read_timeout: http::HEADER_READ_TIMEOUT,
            body_read_timeout: http::BODY_READ_TIMEOUT,
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

/// Why `token` cannot be a bearer token, if it cannot: it must be 1 to 4096
/// printable ASCII characters without spaces (a client sends it in a header,
/// where anything else is lost or refused).
pub fn check_token(token: &str) -> Result<(), String> {
    if token.is_empty() || token.len() > 4096 {
        return Err("the token must have 1 to 4096 characters".to_string());
    }
    match token.chars().find(|c| !c.is_ascii_graphic()) {
        Some(c) => Err(format!(
            "the token must be printable ASCII without spaces; it holds {c:?}"
        )),
        None => Ok(()),
    }
}

/// Opens the store (running the migrations), starts the embedded workers and
/// serves the API on `listener`. A token [`check_token`] refuses stops it (an
/// empty one is none).
pub async fn start(config: ServerConfig, listener: tokio::net::TcpListener) -> anyhow::Result<RunningServer> {
    let token = config.token.clone().filter(|t| !t.is_empty());
    if let Some(token) = &token {
        check_token(token).map_err(|e| anyhow::anyhow!("KNOTSWEEP_TOKEN: {e}"))?;
    }
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
    let resumed = core.resume_searches().await?;
    if resumed > 0 {
        tracing::info!(resumed, "fits and refinements taken up again");
    }
    let (shutdown, shutdown_rx) = watch::channel(false);
    let reaper = spawn_reaper(dyn_store.clone(), config.lease, shutdown_rx.clone());
    let feeds = events::Feeds::new(
        core.clone(),
        config.events_interval,
        shutdown_rx.clone(),
        config.stream_limits,
    );
    let app = api::App {
        core,
        token,
        allowed_hosts: config.allowed_hosts.clone(),
        feeds,
        body_read_timeout: config.body_read_timeout,
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
