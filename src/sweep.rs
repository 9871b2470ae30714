//! `knotsweep sweep`: runs a sweep on this machine through the same queue as
//! the service (a local SQLite file), with a progress bar, and writes the
//! phase-diagram JSON. The submission carries an idempotency key derived from
//! the specification, so running the same command again after an
//! interruption resumes the sweep (finished cases are kept) instead of
//! starting over.
use anyhow::{Context, Result, bail};
use clap::builder::PossibleValuesParser;
use indicatif::{ProgressBar, ProgressStyle};
use knotsweep_server::views::SweepStatus;
use knotsweep_server::{Core, Limits};
use knotsweep_worker::store::{CaseState, CaseStatus, SnapshotChoice, SweepAction, SweepState};
use knotsweep_worker::{PoolConfig, WorkerPool};
use serde_json::Value;
use std::path::PathBuf;
use std::time::Duration;

#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("sweep").required(true).args(["preset", "spec"])))]
pub struct Args {
    #[command(flatten)]
    queue: crate::queue_args::QueueArgs,
    /// A preset: fig7, fig9, fig11, hysteresis, twist, knots, bends, hitches or materials (see `GET /api/presets`).
    #[arg(long)]
    preset: Option<String>,
    /// A sweep specification: JSON as for `POST /api/sweeps`.
    #[arg(long)]
    spec: Option<PathBuf>,
    /// Sets a base parameter, e.g. `--set nodes=161` (value as JSON); repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Phase-diagram JSON output [default: PRESET.json for --preset, SPEC-phase-diagram.json for --spec SPEC.json].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Also write the phase diagram as CSV, one row per point (the table of
    /// `GET /api/sweeps/{id}/phase-diagram.csv`).
    #[arg(long, value_name = "PATH")]
    csv: Option<PathBuf>,
    /// Write the figures into this directory, as SVG and PDF: the phase
    /// diagram (`phase`, with a varied parameter) and the curves of every
    /// case overlaid (`F_bar`, `H_bar`), as `GET /api/sweeps/{id}/figures/` serves them.
    #[arg(long, value_name = "DIR")]
    figures: Option<PathBuf>,
    /// Certify every point: also run each case's refined twin (time step
    /// halved) and give each inversion its numerical uncertainty (about 3x the cost).
    #[arg(long)]
    certify: bool,
    /// Which snapshots the results keep: all, events (those around each
    /// inversion or flip back) or none [default: the specification's, else all].
    #[arg(long, value_parser = PossibleValuesParser::new(SnapshotChoice::ALL.map(SnapshotChoice::as_str)))]
    snapshots: Option<String>,
    /// Once the sweep is done, bisect every grid line where the outcome
    /// changes (an inversion or none, a clean snap or not) until the two cases
    /// bracketing it are within the tolerance: `AXIS=TOL,...` in SI units,
    /// e.g. `--refine h=2e-4,mu=0.02` (`POST /api/sweeps/{id}/refine`).
    #[arg(long, value_name = "AXIS=TOL,...")]
    refine: Option<String>,
}

/// `--refine h=2e-4,mu=0.02` as a refinement.
fn refine_spec(text: &str) -> Result<knotsweep_server::refine::RefineSpec> {
    let mut tolerance = std::collections::BTreeMap::new();
    for item in text.split(',').filter(|i| !i.trim().is_empty()) {
        let Some((axis, tol)) = item.split_once('=') else {
            bail!("--refine {item}: expected AXIS=TOLERANCE");
        };
        let tol: f64 = (tol.trim().parse())
            .with_context(|| format!("--refine {item}: the tolerance is not a number"))?;
        tolerance.insert(axis.trim().to_string(), tol);
    }
    Ok(knotsweep_server::refine::RefineSpec { tolerance })
}

fn build_spec(args: &Args) -> Result<Value> {
    let mut spec = match (&args.preset, &args.spec) {
        (Some(preset), _) => serde_json::json!({ "preset": preset }),
        (None, Some(path)) => {
            let text =
                std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
            serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?
        }
        (None, None) => bail!("give --preset or --spec"),
    };
    let Some(object) = spec.as_object_mut() else {
        bail!("the specification must be a JSON object")
    };
    if args.certify {
        object.insert("certify".to_string(), Value::Bool(true));
    }
    if let Some(choice) = &args.snapshots {
        object.insert("snapshots".to_string(), Value::String(choice.clone()));
    }
    for assignment in &args.set {
        let Some((name, value)) = assignment.split_once('=') else {
            bail!("--set {assignment}: expected NAME=VALUE");
        };
        let value: Value = serde_json::from_str(value).unwrap_or_else(|_| Value::String(value.to_string()));
        let base = object
            .entry("base")
            .or_insert_with(|| Value::Object(Default::default()));
        let Some(base) = base.as_object_mut() else {
            bail!("base must be a JSON object")
        };
        base.insert(name.trim().to_string(), value);
    }
    Ok(spec)
}

fn default_out(args: &Args) -> PathBuf {
    match (&args.preset, &args.spec) {
        (Some(p), _) => PathBuf::from(format!("{p}.json")),
        (None, Some(path)) => {
            let stem = path
                .file_stem()
                .map_or("sweep".into(), |s| s.to_string_lossy().into_owned());
            PathBuf::from(format!("{stem}-phase-diagram.json"))
        }
        (None, None) => PathBuf::from("sweep.json"),
    }
}

pub fn run(args: Args) -> Result<()> {
    let spec_value = build_spec(&args)?;
    let body = serde_json::to_vec(&spec_value)?;
    let (spec, raw) = Core::parse_spec(&body).map_err(|e| anyhow::anyhow!(describe(e)))?;
    let out = args.out.clone().unwrap_or_else(|| default_out(&args));
    let refinement = args.refine.as_deref().map(refine_spec).transpose()?;
    let runtime = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    runtime.block_on(async move {
        let store = crate::worker::open(&args.queue.database_url).await?;
        let core = Core::new(store.clone(), Limits::default(), None);
        // Same specification, same key: a rerun finds the first sweep.
        let key = format!(
            "cli-{}",
            &blake3::hash(knotsweep_worker::canonical_value(&raw).as_bytes()).to_hex()[..32]
        );
        let mut submitted = core
            .submit(spec.clone(), &raw, Some(&key))
            .await
            .map_err(|e| anyhow::anyhow!(describe(e)))?;
        let mut id = submitted.sweep.summary.id;
        // A refinement's tolerances are checked now, not after the sweep has run.
        if let Some(r) = &refinement {
            r.check(id, &submitted.sweep.varied)
                .map_err(|e| anyhow::anyhow!(describe(e)))?;
        }
        if submitted.replayed {
            let state = submitted.sweep.summary.state.clone();
            if state == SweepState::Cancelled.as_str() {
                eprintln!(
                    "sweep {id} of this specification was cancelled: starting a new one (results are reused)"
                );
                submitted = core
                    .submit(spec, &raw, None)
                    .await
                    .map_err(|e| anyhow::anyhow!(describe(e)))?;
                id = submitted.sweep.summary.id;
            } else if state == SweepState::Paused.as_str() {
                core.control(id, SweepAction::Resume)
                    .await
                    .map_err(|e| anyhow::anyhow!(describe(e)))?;
            }
            let done = submitted.sweep.cases.iter().filter(|c| c.progress >= 1.0).count();
            eprintln!(
                "resuming sweep {id}: {done} of {} cases finished",
                submitted.sweep.cases.len()
            );
        } else {
            eprintln!(
                "sweep {id}: {} cases ({} reused from earlier results), database {}",
                submitted.sweep.cases.len(),
                submitted.sweep.cached,
                args.queue.database_url
            );
        }
        let total = submitted.sweep.cases.len() as u64;
        let mut config = PoolConfig::new(args.queue.workers.unwrap_or(0))
            .with_lease(Duration::from_secs_f64(args.queue.lease_seconds.max(0.1)));
        config.poll = Duration::from_millis(100);
        let pool = WorkerPool::start(store.clone(), config);
        let bar = ProgressBar::new(total * 100).with_style(
            ProgressStyle::with_template("{bar:40} {percent:>3}% {elapsed_precise} {msg}")
                .expect("valid template"),
        );
        let signal = crate::worker::shutdown_signal();
        tokio::pin!(signal);
        let finished = loop {
            let detail = core.sweep(id).await.map_err(|e| anyhow::anyhow!(describe(e)))?;
            bar.set_position((detail.progress * total as f64 * 100.0) as u64);
            let finished = detail
                .cases
                .iter()
                .filter(|c| c.progress >= 1.0 || c.status == CaseStatus::Queue(CaseState::Failed))
                .count();
            let running = detail
                .summary
                .counts
                .get(&CaseStatus::RUNNING)
                .copied()
                .unwrap_or(0);
            let eta = detail
                .eta_seconds
                .map_or("?".to_string(), |s| format!("{s:.0} s"));
            bar.set_message(format!("{finished}/{total} cases, {running} running, eta {eta}"));
            if matches!(detail.summary.status, SweepStatus::Done | SweepStatus::Cancelled) {
                break true;
            }
            tokio::select! {
                _ = tokio::time::sleep(Duration::from_millis(300)) => {}
                _ = &mut signal => break false,
            }
        };
        bar.finish_and_clear();
        let refined = match (refinement, finished) {
            (Some(spec), true) => refine(&core, id, spec, &mut signal).await?,
            _ => true,
        };
        pool.shutdown().await;
        if !finished || !refined {
            store.close().await;
            bail!("interrupted: run the same command again to resume sweep {id}");
        }
        let diagram = core
            .phase_diagram(id)
            .await
            .map_err(|e| anyhow::anyhow!(describe(e)))?;
        std::fs::write(&out, serde_json::to_string_pretty(&diagram)?)
            .with_context(|| format!("writing {}", out.display()))?;
        if let Some(csv) = &args.csv {
            let table = report::tables::phase_diagram_csv(&serde_json::to_value(&diagram)?);
            std::fs::write(csv, table).with_context(|| format!("writing {}", csv.display()))?;
            println!("phase diagram table written to {}", csv.display());
        }
        if let Some(dir) = &args.figures {
            for quantity in report::charts::Quantity::ALL {
                let svg = core
                    .sweep_figure(id, quantity)
                    .await
                    .map_err(|e| anyhow::anyhow!(describe(e)))?;
                write_figure(dir, quantity.stem(), &svg)?;
            }
            if !diagram.varied.is_empty() {
                let svg = core
                    .phase_figure(id, &[])
                    .await
                    .map_err(|e| anyhow::anyhow!(describe(e)))?;
                write_figure(dir, "phase", &svg)?;
            }
            if diagram.varied.len() >= 2 {
                let svg = core
                    .map_figure(id)
                    .await
                    .map_err(|e| anyhow::anyhow!(describe(e)))?;
                write_figure(dir, "map", &svg)?;
            }
            println!("figures written to {}", dir.display());
        }
        for p in &diagram.points {
            let values: Vec<String> = p.params.iter().map(|(k, v)| format!("{k} = {v}")).collect();
            let certified =
                p.uncertainty
                    .as_ref()
                    .map_or(String::new(), |u| match (u.absolute, u.converged) {
                        (Some(a), Some(ok)) => format!(
                            " +- {a:.2} ({:.2} %{})",
                            100.0 * u.relative.unwrap_or(0.0),
                            if ok { "" } else { ", UNCONVERGED" }
                        ),
                        (None, Some(false)) => ", UNCONVERGED: the refined twin disagrees".to_string(),
                        _ => String::new(),
                    });
            match &p.inversion {
                Some(inv) => println!(
                    "{:<24} {:<18} inversion at l_k bar {:.2}{certified} (l_c/L {:.4})",
                    values.join(", "),
                    p.status,
                    inv.l_k_bar,
                    inv.l_c_over_l
                ),
                None => println!(
                    "{:<24} {:<18} no inversion: {}",
                    values.join(", "),
                    p.status,
                    p.reason.as_deref().unwrap_or("")
                ),
            }
        }
        println!("phase diagram of sweep {id} written to {}", out.display());
        store.close().await;
        Ok(())
    })
}

/// Runs sweep `id`'s refinement to its end and prints its brackets; false
/// when interrupted.
async fn refine(
    core: &Core,
    id: i64,
    spec: knotsweep_server::refine::RefineSpec,
    signal: &mut std::pin::Pin<&mut impl std::future::Future<Output = ()>>,
) -> Result<bool> {
    use knotsweep_server::refine::RefineStatus;
    let mut view = match core.submit_refinement(id, spec.clone()).await {
        Err(knotsweep_server::error::CoreError::Conflict(_)) => {
            eprintln!("sweep {id}'s refinement is running: following it");
            core.refinement(id)
                .await
                .map_err(|e| anyhow::anyhow!(describe(e)))?
        }
        other => other.map_err(|e| anyhow::anyhow!(describe(e)))?,
    };
    let mut shown = 0;
    while view.status == RefineStatus::Running {
        tokio::select! {
            _ = tokio::time::sleep(Duration::from_millis(300)) => {}
            _ = signal.as_mut() => return Ok(false),
        }
        view = core
            .refinement(id)
            .await
            .map_err(|e| anyhow::anyhow!(describe(e)))?;
        for p in &view.points[shown.min(view.points.len())..] {
            let at: Vec<String> = p.params.iter().map(|(k, v)| format!("{k} = {v}")).collect();
            let found = p.outcome.map_or("no outcome".to_string(), |o| format!("{o:?}"));
            eprintln!("refinement round {}: {}: {found}", view.rounds, at.join(", "));
        }
        shown = view.points.len();
    }
    if view.status == RefineStatus::Failed {
        bail!("the refinement failed: {}", view.reason.unwrap_or_default());
    }
    for b in &view.brackets {
        let at: Vec<String> = b.at.iter().map(|(k, v)| format!("{k} = {v}")).collect();
        println!(
            "{} at {}: {:?} at {} (case {}), {:?} at {} (case {}): {} apart{}",
            b.axis,
            at.join(", "),
            b.low.outcome,
            b.low.value,
            b.low.case_id,
            b.high.outcome,
            b.high.value,
            b.high.case_id,
            b.width,
            b.reason
                .as_ref()
                .map_or(String::new(), |r| format!(" (stopped: {r})"))
        );
    }
    println!(
        "refinement of sweep {id}: {} brackets, {} cases added in {} rounds",
        view.brackets.len(),
        view.points.len(),
        view.rounds
    );
    Ok(true)
}

pub(crate) fn describe(e: knotsweep_server::error::CoreError) -> String {
    use knotsweep_server::error::CoreError;
    match e {
        CoreError::Invalid(fields) => {
            let list: Vec<String> = fields
                .iter()
                .map(|f| format!("{}: {}", f.field, f.reason))
                .collect();
            format!("invalid sweep: {}", list.join("; "))
        }
        other => other.to_string(),
    }
}

/// A chart as `dir/STEM.svg` and `dir/STEM.pdf` (`report::pdf`).
pub(crate) fn write_figure(dir: &std::path::Path, stem: &str, svg: &str) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let path = dir.join(format!("{stem}.svg"));
    std::fs::write(&path, svg).with_context(|| format!("writing {}", path.display()))?;
    let path = dir.join(format!("{stem}.pdf"));
    std::fs::write(&path, report::pdf::svg_to_pdf(svg)?)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::refine_spec;
    use knotsweep_server::error::CoreError;

    /// `--refine` reads `AXIS=TOL` pairs and refuses what is not one; the
    /// tolerances are checked against the sweep's axes before it runs.
    #[test]
    fn refine_flag_is_read_and_checked_before_the_sweep_runs() {
        let spec = refine_spec(" h=2e-4, mu=0.02,").unwrap();
        assert_eq!(spec.tolerance.len(), 2);
        assert_eq!((spec.tolerance["h"], spec.tolerance["mu"]), (2e-4, 0.02));
        assert!(
            refine_spec("h")
                .unwrap_err()
                .to_string()
                .contains("AXIS=TOLERANCE")
        );
        assert!(
            refine_spec("h=wide")
                .unwrap_err()
                .to_string()
                .contains("not a number")
        );

        let varied = ["h".to_string(), "mu".to_string()];
        assert!(spec.check(7, &varied).is_ok());
        let Err(CoreError::Invalid(fields)) = refine_spec("n=1,mu=0").unwrap().check(7, &varied) else {
            panic!("an axis the sweep does not vary and a zero tolerance are refused");
        };
        let names: Vec<&str> = fields.iter().map(|f| f.field.as_str()).collect();
        assert_eq!(names, ["tolerance.mu", "tolerance.n"]);
        assert!(
            fields[1].reason.contains("not a varied axis of sweep 7"),
            "{fields:?}"
        );
    }
}
