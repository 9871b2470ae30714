//! `knotsweep serve`: the sweep service (HTTP API, embedded workers) on a
//! local SQLite database.
use anyhow::{Context, Result};
use knotsweep_server::{AllowedHosts, DEFAULT_ADDR, Limits, ServerConfig};
use knotsweep_worker::store::RetryPolicy;
use std::time::Duration;

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    queue: crate::queue_args::QueueArgs,
    /// Address to listen on (port 0: any free port).
    #[arg(long, default_value = DEFAULT_ADDR)]
    addr: String,
    /// Claims of a case before it is marked failed (lost workers, panics).
    #[arg(long, default_value_t = RetryPolicy::DEFAULT.max_attempts)]
    max_attempts: u32,
    /// Largest number of cases per sweep.
    #[arg(long, default_value_t = Limits::DEFAULT.max_cases)]
    max_cases: usize,
    /// Largest request body (bytes).
    #[arg(long, default_value_t = Limits::DEFAULT.max_body_bytes)]
    max_body_bytes: usize,
    /// A host name clients reach the server by, besides IP addresses and
    /// localhost (behind a proxy: its public name); repeat it or separate
    /// names by commas; `*` allows any. A POST naming another host in `Host`
    /// or `Origin` is refused (403).
    #[arg(long = "allowed-host", env = "KNOTSWEEP_ALLOWED_HOSTS", value_delimiter = ',')]
    allowed_hosts: Vec<String>,
}

pub fn run(args: Args) -> Result<()> {
    let runtime = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    runtime.block_on(async {
        let token = match std::env::var("KNOTSWEEP_TOKEN") {
            Ok(t) if t.trim().is_empty() => anyhow::bail!(
                "KNOTSWEEP_TOKEN is set but empty: give a token, or unset it to serve without authentication"
            ),
            Ok(t) => {
                knotsweep_server::check_token(&t).map_err(|e| anyhow::anyhow!("KNOTSWEEP_TOKEN: {e}"))?;
                Some(t)
            }
            Err(_) => None,
        };
        let allowed_hosts =
            AllowedHosts::new(&args.allowed_hosts).map_err(|e| anyhow::anyhow!("--allowed-host: {e}"))?;
        let listener = tokio::net::TcpListener::bind(&args.addr)
            .await
            .with_context(|| format!("listening on {}", args.addr))?;
        let config = ServerConfig {
            database_url: args.queue.database_url.clone(),
            workers: args.queue.workers,
            lease: Duration::from_secs_f64(args.queue.lease_seconds.max(0.1)),
            retry: RetryPolicy {
                max_attempts: args.max_attempts.max(1),
                ..RetryPolicy::DEFAULT
            },
            limits: Limits {
                max_cases: args.max_cases,
                max_body_bytes: args.max_body_bytes,
                ..Limits::DEFAULT
            },
            token: token.clone(),
            allowed_hosts,
            ..ServerConfig::default()
        };
        let workers = args
            .queue
            .workers
            .unwrap_or_else(knotsweep_worker::pool::default_workers);
        let server = knotsweep_server::start(config, listener).await?;
        let url = server.url();
        println!(
            "knotsweep serving on {url} (API docs {url}/api/docs; database {}; {workers} embedded workers{})",
            args.queue.database_url,
            if token.is_some() {
                "; POST requests need the bearer token"
            } else {
                ""
            }
        );
        crate::worker::shutdown_signal().await;
        tracing::info!("shutting down");
        server.shutdown().await
    })
}
