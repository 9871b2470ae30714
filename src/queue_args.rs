//! Queue flags shared by `serve`, `worker` and `sweep`.
use knotsweep_server::DEFAULT_DATABASE_URL;

/// Where the queue lives and how this process works on it.
#[derive(clap::Args)]
pub struct QueueArgs {
    /// Database: `sqlite://PATH` (created if missing; processes on this
    /// machine) or `postgres://USER@HOST:PORT/DB` (workers on any host).
    /// `serve`, `worker` and `sweep` on one database share the queue and
    /// reuse each other's results.
    #[arg(long, env = "DATABASE_URL", default_value = DEFAULT_DATABASE_URL)]
    pub database_url: String,
    /// Cases run at once by this process, 0 to 256 [default: one per core].
    /// Cases are CPU-bound: more workers than cores only share the cores.
    #[arg(long, visible_alias = "threads", value_parser = parse_workers)]
    pub workers: Option<usize>,
    /// Lease length (s); workers heartbeat several times within it.
    #[arg(long, default_value_t = knotsweep_worker::pool::DEFAULT_LEASE.as_secs_f64())]
    pub lease_seconds: f64,
}

/// Largest `--workers`: each worker is a thread running a CPU-bound case.
pub const MAX_WORKERS: usize = 256;

fn parse_workers(text: &str) -> Result<usize, String> {
    let n: usize = text.parse().map_err(|e| format!("{e}"))?;
    if n > MAX_WORKERS {
        return Err(format!(
            "at most {MAX_WORKERS} (cases are CPU-bound: one worker per core, the default, keeps every core busy)"
        ));
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    #[test]
    fn worker_count_is_bounded() {
        assert_eq!(super::parse_workers("4"), Ok(4));
        assert_eq!(super::parse_workers("0"), Ok(0));
        let err = super::parse_workers("100000").unwrap_err();
        assert!(err.contains("at most 256"), "{err}");
        assert!(super::parse_workers("-1").is_err());
    }
}
