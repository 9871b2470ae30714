//! Queue flags shared by `serve`, `worker` and `sweep`.
use knotsweep_server::DEFAULT_DATABASE_URL;

/// Where the queue lives and how this process works on it.
#[derive(clap::Args)]
pub struct QueueArgs {
    /// Database: `sqlite://PATH`, created if missing; `serve`, `worker` and
    /// `sweep` on the same file share the queue and reuse each other's results.
    #[arg(long, default_value = DEFAULT_DATABASE_URL)]
    pub database_url: String,
    /// Cases run at once [default: one per core]; `serve --workers 0` runs none
    /// (add `knotsweep worker` processes instead).
    #[arg(long)]
    pub workers: Option<usize>,
    /// Lease length (s); workers heartbeat every third of it.
    #[arg(long, default_value_t = 30.0)]
    pub lease_seconds: f64,
}
