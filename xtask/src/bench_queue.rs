//! `xtask bench-queue`: throughput of the queue itself. Enqueues no-op
//! cases and lets W concurrent claimers claim and complete them (no solver),
//! for each W given; prints claim+complete per second and the queue's
//! overhead per case against a real case's time. BENCHMARKS.md records it.
use anyhow::{Context, Result};
use knotsweep_worker::store::{CreateOutcome, NewCase, NewSweep, Store, StoreOptions, open_store};
use solver::case::CaseParams;
use solver::protocol::{CaseReport, Status};
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(clap::Args)]
pub struct Args {
    /// Database to measure: a scratch `sqlite://PATH` or `postgres://...`
    /// (the benchmark adds sweeps, cases and results to it) [default: a
    /// temporary SQLite file].
    #[arg(long)]
    database_url: Option<String>,
    /// Concurrent claimers, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "8,32,128")]
    workers: Vec<usize>,
    /// Cases per measurement.
    #[arg(long, default_value_t = 2000)]
    cases: usize,
    /// A real case's time (s) for the overhead figure (the n = 3 default case, BENCHMARKS.md).
    #[arg(long, default_value_t = 55.0)]
    case_seconds: f64,
}

pub fn run(args: Args) -> Result<()> {
    let runtime = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    runtime.block_on(async move {
        let dir = tempfile::tempdir()?;
        let url = args
            .database_url
            .clone()
            .unwrap_or_else(|| format!("sqlite://{}", dir.path().join("bench.sqlite").display()));
        let largest = args.workers.iter().copied().max().unwrap_or(1);
        let store = open_store(
            &url,
            StoreOptions {
                max_connections: (largest as u32).clamp(8, 64),
                ..StoreOptions::default()
            },
        )
        .await
        .with_context(|| format!("opening {url}"))?;
        println!(
            "queue benchmark on {}: {} no-op cases per row",
            url.split('@').next_back().unwrap_or(&url),
            args.cases
        );
        println!(
            "| claimers | claim+complete per s | queue time per case (ms) | overhead of a {} s case |",
            args.case_seconds
        );
        println!("|---|---|---|---|");
        // Distinct keys across rows and runs: a random offset in mu.
        let offset = rand::random::<f64>();
        for (row, &w) in args.workers.iter().enumerate() {
            let cases = (0..args.cases)
                .map(|i| {
                    NewCase::new(CaseParams {
                        mu: offset + (row * args.cases + i) as f64 * 1e-9,
                        ..CaseParams::default()
                    })
                })
                .collect();
            let sweep = NewSweep {
                name: Some(format!("bench-queue {w}")),
                preset: None,
                spec: serde_json::json!({}),
                varied: vec!["mu".into()],
                snapshots: knotsweep_worker::store::SnapshotChoice::All,
                cases,
                idempotency: None,
            };
            let CreateOutcome::Created { .. } = store.create_sweep(sweep).await? else {
                anyhow::bail!("the benchmark sweep was replayed");
            };
            let started = Instant::now();
            let tasks: Vec<_> = (0..w).map(|i| tokio::spawn(claimer(store.clone(), i))).collect();
            let mut done = 0;
            for t in tasks {
                done += t.await??;
            }
            let secs = started.elapsed().as_secs_f64();
            let rate = done as f64 / secs;
            // Each claimer spends w / rate seconds of queue time per case.
            let per_case = w as f64 / rate;
            println!(
                "| {w} | {rate:.0} | {:.2} | {:.4} % |",
                per_case * 1e3,
                100.0 * per_case / args.case_seconds
            );
        }
        store.close().await;
        Ok(())
    })
}

/// Claims and completes until the queue is empty; returns how many.
async fn claimer(store: Arc<dyn Store>, i: usize) -> Result<usize> {
    let owner = format!("bench-{i}");
    let mut n = 0;
    while let Some(c) = store.claim(&owner, Duration::from_secs(60)).await? {
        let report = CaseReport::empty(c.params, Status::Completed);
        anyhow::ensure!(store.complete(&c.lease, &report).await?, "lost a lease");
        n += 1;
    }
    Ok(n)
}
