//! `store-sizes`: what results take in the store (docs/API.md, "Stored
//! results").
//!
//! - `--report n3.json` (a report of `knotsweep run`): the bytes of its series
//!   and snapshots as JSON text (how results were stored before the packed
//!   columns) and packed (`knotsweep_worker::store::codec`), for each
//!   snapshot choice;
//! - `--database h.db` (a SQLite store, e.g. after `knotsweep sweep`): its
//!   files (`h.db`, `h.db-wal`, `h.db-shm`) and, per packed result, the
//!   files' bytes, the packed series and snapshots' and what they would take
//!   as JSON text.
use anyhow::{Context, Result, bail};
use knotsweep_worker::store::SnapshotChoice;
use knotsweep_worker::store::codec::{pack_series, pack_snapshots, unpack_series, unpack_snapshots};
use solver::measurements::Sample;
use solver::snapshot::Snapshot;
use std::fmt::Write;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("input").required(true).args(["report", "database"])))]
pub struct Args {
    /// A case report (`knotsweep run --out`).
    #[arg(long)]
    report: Option<PathBuf>,
    /// A SQLite store's file.
    #[arg(long)]
    database: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<String> {
    match (&args.report, &args.database) {
        (Some(path), _) => report_sizes(path),
        (None, Some(path)) => database_sizes(path),
        (None, None) => bail!("give --report or --database"),
    }
}

fn report_sizes(path: &Path) -> Result<String> {
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut report: serde_json::Value = serde_json::from_str(&text)?;
    let series: Vec<Sample> =
        serde_json::from_value(report["series"].take()).context("the report's series")?;
    let snapshots: Vec<Snapshot> =
        serde_json::from_value(report["snapshots"].take()).context("the report's snapshots")?;
    let series_json = serde_json::to_string(&series)?.len();
    let snapshots_json = serde_json::to_string(&snapshots)?.len();
    let series_packed = pack_series(&series).len();
    let mut out = format!(
        "{}: {} samples, {} snapshots\n\n| stored as | series | snapshots | together |\n| --- | --- | --- | --- |\n",
        path.display(),
        series.len(),
        snapshots.len()
    );
    let row = |out: &mut String, what: &str, a: usize, b: usize| {
        writeln!(out, "| {what} | {a} B | {b} B | {} B |", a + b).expect("writing to a string")
    };
    row(&mut out, "JSON text", series_json, snapshots_json);
    for choice in SnapshotChoice::ALL {
        let kept: Vec<Snapshot> = (snapshots.iter())
            .filter(|s| choice.keeps(s.label))
            .cloned()
            .collect();
        let what = format!("packed, snapshots `{}` ({})", choice.as_str(), kept.len());
        row(&mut out, &what, series_packed, pack_snapshots(&kept).len());
    }
    Ok(out)
}

fn database_sizes(path: &Path) -> Result<String> {
    let mut out = String::new();
    let mut total = 0;
    for suffix in ["", "-wal", "-shm"] {
        let file = PathBuf::from(format!("{}{suffix}", path.display()));
        let bytes = std::fs::metadata(&file).map_or(0, |m| m.len());
        writeln!(out, "{}: {bytes} B", file.display())?;
        total += bytes;
    }
    let url = format!("sqlite://{}", path.display());
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    let rows: Vec<(Vec<u8>, Vec<u8>)> = runtime.block_on(async {
        sqlx::any::install_default_drivers();
        let pool = sqlx::AnyPool::connect(&format!("{url}?mode=ro")).await?;
        let rows = sqlx::query_as(
            "SELECT series_packed, snapshots_packed FROM results WHERE series_packed IS NOT NULL ORDER BY case_id",
        )
        .fetch_all(&pool)
        .await?;
        pool.close().await;
        anyhow::Ok(rows)
    })?;
    let (mut packed, mut json) = (0, 0);
    for (series, snapshots) in &rows {
        packed += series.len() + snapshots.len();
        json += serde_json::to_string(&unpack_series(series)?)?.len();
        json += serde_json::to_string(&unpack_snapshots(snapshots)?)?.len();
    }
    writeln!(out, "together: {total} B over {} packed results", rows.len())?;
    if !rows.is_empty() {
        let kb = |bytes: f64| bytes / rows.len() as f64 / 1000.0;
        writeln!(
            out,
            "per result: {:.1} kB of files; {:.1} kB of packed series and snapshots, {:.1} kB as JSON text",
            kb(total as f64),
            kb(packed as f64),
            kb(json as f64)
        )?;
    }
    Ok(out)
}
