//! `xtask bench-soak`: the service under a sustained mixed load, on
//! loopback only. A `knotsweep serve` child process (no embedded workers) on a
//! scratch SQLite file; `--clients` researchers, each replaying
//! `--minutes` of use without think time (a sweep submitted every 3 minutes,
//! one in five cancelled, its sweep polled every 10 s, its cases every
//! minute, the sweep list every minute, the phase diagram every 3 minutes);
//! `--workers` stand-in workers that claim, hold a case `--case-ms`,
//! heartbeat (stopping when cancelled) and store a synthetic result (the
//! solver is not the subject). Afterwards it checks that no accepted sweep or
//! case was lost or duplicated and that the server's memory levelled off, and
//! prints requests/s, latency percentiles and the server's RSS.
//! BENCHMARKS.md records it.
use anyhow::{Context, Result, bail, ensure};
use knotsweep_worker::store::{CaseState, CaseStatus, Heartbeat, Store, StoreOptions, open_store};
use rand::{Rng, SeedableRng};
use serde_json::{Value, json};
use solver::protocol::{CaseReport, Status};
use std::collections::{BTreeMap, HashSet};
use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

#[derive(clap::Parser)]
pub struct Args {
    /// The `knotsweep` binary to serve [default: the one next to this
    /// program, e.g. `target/release/knotsweep` after `cargo build --release`].
    #[arg(long)]
    knotsweep: Option<PathBuf>,
    /// Concurrent clients.
    #[arg(long, default_value_t = 50)]
    clients: usize,
    /// Minutes of use each client replays.
    #[arg(long, default_value_t = 30)]
    minutes: usize,
    /// Stand-in workers.
    #[arg(long, default_value_t = 8)]
    workers: usize,
    /// How long a stand-in worker holds a case (ms).
    #[arg(long, default_value_t = 20)]
    case_ms: u64,
    /// Distinct friction values the clients draw from (sweeps share cases).
    #[arg(long, default_value_t = 200)]
    distinct: usize,
    /// Report the server's memory without asserting that it levelled off (for
    /// runs too short to reach a steady state).
    #[arg(long)]
    no_memory_check: bool,
}

/// Per request kind: latencies in microseconds.
type Latencies = BTreeMap<&'static str, Vec<u64>>;

/// What one client submitted.
struct Submitted {
    id: i64,
    mus: Vec<f64>,
    cancelled: bool,
}

/// Runs the soak and writes its report to `out`.
pub fn run(args: Args, out: &mut dyn Write) -> Result<()> {
    ensure!(
        args.clients > 0 && args.minutes > 0,
        "--clients and --minutes must be positive"
    );
    let runtime = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    runtime.block_on(soak(args, out))
}

/// The `knotsweep` binary: `--knotsweep`, else the one next to this program.
fn server_binary(args: &Args) -> Result<PathBuf> {
    let path = match &args.knotsweep {
        Some(path) => path.clone(),
        None => std::env::current_exe()?.with_file_name(format!("knotsweep{}", std::env::consts::EXE_SUFFIX)),
    };
    ensure!(
        path.is_file(),
        "no knotsweep binary at {}: build it with the same profile (`cargo build --release`) or give --knotsweep",
        path.display()
    );
    Ok(path)
}

async fn soak(args: Args, out: &mut dyn Write) -> Result<()> {
    let binary = server_binary(&args)?;
    let dir = tempfile::tempdir()?;
    let url = format!("sqlite://{}", dir.path().join("soak.sqlite").display());
    let addr = {
        let probe = std::net::TcpListener::bind("127.0.0.1:0")?;
        probe.local_addr()?
    };
    let mut server = std::process::Command::new(&binary)
        .args([
            "serve",
            "--workers",
            "0",
            "--addr",
            &addr.to_string(),
            "--database-url",
            &url,
        ])
        .env("RUST_LOG", "warn")
        .stdout(std::process::Stdio::null())
        .stderr(std::fs::File::create(dir.path().join("server.log"))?)
        .spawn()
        .context("starting the server")?;
    let base = format!("http://{addr}");
    let http = reqwest::Client::new();
    let result = drive(&args, &url, &base, &http, server.id(), out).await;
    let _ = server.kill();
    let _ = server.wait();
    if result.is_err() {
        let log = std::fs::read_to_string(dir.path().join("server.log")).unwrap_or_default();
        eprintln!("server log (last lines):\n{}", tail(&log, 20));
    }
    result
}

async fn drive(
    args: &Args,
    url: &str,
    base: &str,
    http: &reqwest::Client,
    pid: u32,
    out: &mut dyn Write,
) -> Result<()> {
    wait_until_up(http, base).await?;
    let store = open_store(url, StoreOptions::default()).await?;
    let rss = Arc::new(std::sync::Mutex::new(Vec::<(f64, u64)>::new()));
    let stop = Arc::new(AtomicBool::new(false));
    let completed = Arc::new(AtomicUsize::new(0));
    let started = Instant::now();
    let sampler = tokio::spawn(sample_rss(pid, rss.clone(), stop.clone(), started));
    let workers: Vec<_> = (0..args.workers)
        .map(|i| {
            let (store, stop, completed) = (store.clone(), stop.clone(), completed.clone());
            tokio::spawn(stand_in_worker(
                store,
                i,
                Duration::from_millis(args.case_ms),
                stop,
                completed,
            ))
        })
        .collect();
    let clients: Vec<_> = (0..args.clients)
        .map(|c| {
            tokio::spawn(client(
                http.clone(),
                base.to_string(),
                c,
                args.minutes,
                args.distinct,
            ))
        })
        .collect();
    let mut latencies = Latencies::new();
    let mut submitted = Vec::new();
    for c in clients {
        let (lat, subs) = c.await??;
        for (kind, v) in lat {
            latencies.entry(kind).or_default().extend(v);
        }
        submitted.extend(subs);
    }
    let load_secs = started.elapsed().as_secs_f64();
    drain(&*store).await?;
    stop.store(true, Ordering::Relaxed);
    for w in workers {
        w.await??;
    }
    sampler.await?;
    check(http, base, &*store, &submitted, completed.load(Ordering::Relaxed)).await?;
    let rss = rss.lock().expect("sampler finished").clone();
    report(args, &latencies, load_secs, &rss, &submitted, out)?;
    store.close().await;
    Ok(())
}

async fn wait_until_up(http: &reqwest::Client, base: &str) -> Result<()> {
    for _ in 0..200 {
        if let Ok(r) = http.get(format!("{base}/healthz")).send().await {
            if r.status().is_success() {
                return Ok(());
            }
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    bail!("the server did not answer /healthz within 10 s")
}

/// One researcher's session, compressed: per simulated minute six polls of the
/// newest sweep, one of its cases, one of the sweep list; every third minute a
/// new sweep of four cases and its phase diagram; one sweep in five cancelled
/// (staggered across clients, so short runs cancel some too).
async fn client(
    http: reqwest::Client,
    base: String,
    c: usize,
    minutes: usize,
    distinct: usize,
) -> Result<(Latencies, Vec<Submitted>)> {
    let mut lat = Latencies::new();
    let mut subs: Vec<Submitted> = Vec::new();
    let mut rng = rand::rngs::StdRng::seed_from_u64(c as u64);
    for minute in 0..minutes {
        if minute % 3 == 0 {
            let ks: std::collections::BTreeSet<usize> = (0..4).map(|_| rng.gen_range(0..distinct)).collect();
            let mus: Vec<f64> = ks.into_iter().map(|k| (50 + k) as f64 / 1000.0).collect();
            let body = json!({"name": format!("soak {c}.{minute}"), "base": {"n": 3}, "grid": {"mu": mus}});
            let sweep = request(
                &mut lat,
                "submit",
                http.post(format!("{base}/api/sweeps")).json(&body),
            )
            .await?;
            let id = sweep["id"].as_i64().context("a sweep id")?;
            subs.push(Submitted {
                id,
                mus,
                cancelled: false,
            });
            if (c + subs.len()) % 5 == 0 {
                let url = format!("{base}/api/sweeps/{id}/cancel");
                request(&mut lat, "cancel", http.post(url).json(&serde_json::json!({}))).await?;
                subs.last_mut().expect("just pushed").cancelled = true;
            }
            let url = format!("{base}/api/sweeps/{id}/phase-diagram");
            request(&mut lat, "phase_diagram", http.get(url)).await?;
        }
        let id = subs.last().context("a sweep")?.id;
        for _ in 0..6 {
            request(
                &mut lat,
                "poll_sweep",
                http.get(format!("{base}/api/sweeps/{id}")),
            )
            .await?;
        }
        request(
            &mut lat,
            "poll_cases",
            http.get(format!("{base}/api/sweeps/{id}/cases")),
        )
        .await?;
        request(&mut lat, "list", http.get(format!("{base}/api/sweeps"))).await?;
    }
    Ok((lat, subs))
}

/// Sends a request; a non-2xx answer ends the soak with its body.
async fn request(lat: &mut Latencies, kind: &'static str, req: reqwest::RequestBuilder) -> Result<Value> {
    let t = Instant::now();
    let resp = req.send().await.with_context(|| format!("{kind}: no answer"))?;
    let status = resp.status();
    let body = resp.text().await?;
    lat.entry(kind).or_default().push(t.elapsed().as_micros() as u64);
    ensure!(status.is_success(), "{kind}: {status}: {body}");
    Ok(serde_json::from_str(&body).unwrap_or(Value::Null))
}

/// Claims, holds the case with a heartbeat, then stores a synthetic result
/// (or stops it when cancelled), until `stop`.
async fn stand_in_worker(
    store: Arc<dyn Store>,
    i: usize,
    hold: Duration,
    stop: Arc<AtomicBool>,
    completed: Arc<AtomicUsize>,
) -> Result<()> {
    let owner = format!("soak-{i}");
    let lease = Duration::from_secs(30);
    while !stop.load(Ordering::Relaxed) {
        let Some(claim) = store.claim(&owner, lease).await? else {
            tokio::time::sleep(Duration::from_millis(20)).await;
            continue;
        };
        tokio::time::sleep(hold).await;
        match store.heartbeat(&claim.lease, None, lease).await? {
            Heartbeat::Held { cancel: true } => {
                store.finish_cancelled(&claim.lease).await?;
            }
            Heartbeat::Held { cancel: false } => {
                let report = CaseReport {
                    determinant_initial: Some(7),
                    determinant_final: Some(7),
                    ..CaseReport::empty(claim.params, Status::Completed)
                };
                ensure!(
                    store.complete(&claim.lease, &report).await?,
                    "lease lost while held"
                );
                completed.fetch_add(1, Ordering::Relaxed);
            }
            Heartbeat::Lost => bail!("lease of case {} lost within its 30 s", claim.lease.case_id),
        }
    }
    Ok(())
}

/// Waits until nothing is queued or running.
async fn drain(store: &dyn Store) -> Result<()> {
    let deadline = Instant::now() + Duration::from_secs(600);
    loop {
        let counts = store.status_counts().await?;
        let open: i64 = counts.iter().filter(|(s, _)| s.is_open()).map(|(_, n)| n).sum();
        if open == 0 {
            return Ok(());
        }
        ensure!(
            Instant::now() < deadline,
            "{open} cases still open after 10 minutes"
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

/// No accepted sweep or case lost or duplicated: every submitted sweep is
/// listed once, holds its grid's cases once each in order, ends with a result
/// for each case (or a cancellation, if it was cancelled); every stored result
/// is one completion.
async fn check(
    http: &reqwest::Client,
    base: &str,
    store: &dyn Store,
    submitted: &[Submitted],
    completions: usize,
) -> Result<()> {
    let mut listed: Vec<i64> = Vec::new();
    loop {
        let url = format!("{base}/api/sweeps?limit=1000&offset={}", listed.len());
        let page: Value = http.get(url).send().await?.json().await?;
        let page = page.as_array().context("a list of sweeps")?;
        if page.is_empty() {
            break;
        }
        listed.extend(page.iter().filter_map(|s| s["id"].as_i64()));
    }
    let unique: HashSet<i64> = listed.iter().copied().collect();
    ensure!(unique.len() == listed.len(), "a sweep is listed twice");
    for s in submitted {
        ensure!(unique.contains(&s.id), "accepted sweep {} is not listed", s.id);
        let cases: Value = http
            .get(format!("{base}/api/sweeps/{}/cases", s.id))
            .send()
            .await?
            .json()
            .await?;
        let cases = cases.as_array().context("a list of cases")?;
        let mus: Vec<f64> = cases.iter().filter_map(|c| c["params"]["mu"].as_f64()).collect();
        ensure!(
            mus == s.mus,
            "sweep {}: cases {mus:?}, submitted {:?}",
            s.id,
            s.mus
        );
        for c in cases {
            let status: CaseStatus =
                serde_json::from_value(c["status"].clone()).context("a case's status")?;
            let fine = status == CaseStatus::COMPLETED
                || (s.cancelled && status == CaseStatus::Queue(CaseState::Cancelled));
            ensure!(
                fine,
                "sweep {} (cancelled: {}): case {} ended {status}",
                s.id,
                s.cancelled,
                c["case_id"]
            );
        }
    }
    let counts: BTreeMap<CaseStatus, i64> = store.status_counts().await?.into_iter().collect();
    let stored = counts.get(&CaseStatus::COMPLETED).copied().unwrap_or(0) as usize;
    ensure!(
        stored == completions,
        "{stored} stored results for {completions} completions"
    );
    Ok(())
}

/// Samples the server's resident set every 200 ms.
async fn sample_rss(
    pid: u32,
    into: Arc<std::sync::Mutex<Vec<(f64, u64)>>>,
    stop: Arc<AtomicBool>,
    t0: Instant,
) {
    while !stop.load(Ordering::Relaxed) {
        if let Some(kb) = rss_kib(pid) {
            into.lock()
                .expect("one writer")
                .push((t0.elapsed().as_secs_f64(), kb));
        }
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
}

fn rss_kib(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn report(
    args: &Args,
    lat: &Latencies,
    secs: f64,
    rss: &[(f64, u64)],
    subs: &[Submitted],
    out: &mut dyn Write,
) -> Result<()> {
    let total: usize = lat.values().map(Vec::len).sum();
    let all: Vec<u64> = lat.values().flatten().copied().collect();
    writeln!(
        out,
        "soak: {} clients x {} minutes, {} stand-in workers ({} ms per case), {} sweeps ({} cancelled)",
        args.clients,
        args.minutes,
        args.workers,
        args.case_ms,
        subs.len(),
        subs.iter().filter(|s| s.cancelled).count()
    )?;
    writeln!(
        out,
        "{total} requests in {secs:.1} s: {:.0} requests/s",
        total as f64 / secs
    )?;
    writeln!(out, "| request | count | p50 (ms) | p99 (ms) | max (ms) |")?;
    writeln!(out, "|---|---|---|---|---|")?;
    for (kind, v) in lat.iter().chain(std::iter::once((&"all", &all))) {
        let (p50, p99, max) = percentiles(v);
        writeln!(out, "| {kind} | {} | {p50:.1} | {p99:.1} | {max:.1} |", v.len())?;
    }
    ensure!(rss.len() >= 2, "too few RSS samples ({})", rss.len());
    let half = rss.len() / 2;
    let peak = |s: &[(f64, u64)]| s.iter().map(|&(_, kb)| kb).max().unwrap_or(0);
    let (first, second) = (peak(&rss[..half]), peak(&rss[half..]));
    writeln!(
        out,
        "server RSS: {:.1} MiB at start, peak {:.1} MiB over the first half of the run, {:.1} MiB over the second, {:.1} MiB at the end",
        rss[0].1 as f64 / 1024.0,
        first as f64 / 1024.0,
        second as f64 / 1024.0,
        rss[rss.len() - 1].1 as f64 / 1024.0
    )?;
    if args.no_memory_check {
        writeln!(out, "no accepted sweep or case lost or duplicated")?;
        return Ok(());
    }
    ensure!(
        second as f64 <= 1.1 * first as f64,
        "server memory kept growing: peak {second} KiB in the second half against {first} KiB in the first"
    );
    writeln!(
        out,
        "no accepted sweep or case lost or duplicated; memory levelled off (second-half peak within 10 % of the first)"
    )?;
    Ok(())
}

/// p50, p99 and max in milliseconds.
fn percentiles(v: &[u64]) -> (f64, f64, f64) {
    let mut v = v.to_vec();
    v.sort_unstable();
    let at = |q: f64| {
        v.get(((v.len() as f64 - 1.0) * q).round() as usize)
            .copied()
            .unwrap_or(0) as f64
            / 1e3
    };
    (at(0.5), at(0.99), at(1.0))
}

fn tail(s: &str, n: usize) -> String {
    let lines: Vec<&str> = s.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n")
}
