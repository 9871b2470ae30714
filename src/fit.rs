//! `knotsweep fit`: the value of a parameter (mu by default) that reproduces
//! measured inversions, found over cases queued on this machine (a local
//! SQLite file, as `knotsweep sweep`; cases already computed are reused).
use anyhow::{Context, Result, bail};
use knotsweep_server::fit::{FitSpec, FitStatus};
use knotsweep_server::{Core, Limits};
use knotsweep_worker::{PoolConfig, WorkerPool};
use serde_json::{Map, Value};
use std::path::PathBuf;
use std::time::Duration;

#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("fit").required(true).args(["spec", "points"])))]
pub struct Args {
    #[command(flatten)]
    queue: crate::queue_args::QueueArgs,
    /// A fit: JSON as for `POST /api/fits`.
    #[arg(long)]
    spec: Option<PathBuf>,
    /// Measured points as CSV: a header naming case parameters (`n`, `h`, ...),
    /// `l_k_bar` and `error`, then one row per measurement.
    #[arg(long)]
    points: Option<PathBuf>,
    /// With --points: the parameter to find.
    #[arg(long, default_value = "mu")]
    parameter: String,
    /// With --points: the values searched, `LOW,HIGH`.
    #[arg(long, default_value = "0.05,0.8")]
    range: String,
    /// With --points: sets a base parameter, e.g. `--set nodes=161` (value as JSON); repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Certify every case (its refined twin beside it) so that its numerical
    /// uncertainty widens the interval (about 3x the cost).
    #[arg(long)]
    certify: bool,
    /// The fit's JSON (value, interval, every evaluation) output.
    #[arg(long)]
    out: Option<PathBuf>,
}

fn build_spec(args: &Args) -> Result<FitSpec> {
    let mut spec = if let Some(path) = &args.spec {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        Core::parse_json(text.as_bytes()).map_err(|e| anyhow::anyhow!(crate::sweep::describe(e)))?
    } else {
        let path = args.points.as_ref().expect("clap requires --spec or --points");
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        let points = knotsweep_server::fit::measured_csv(&text)
            .map_err(|e| anyhow::anyhow!("--points {}: {e}", path.display()))?;
        let Some((lo, hi)) = args.range.split_once(',') else {
            bail!("--range {}: expected LOW,HIGH", args.range);
        };
        FitSpec {
            parameter: args.parameter.clone(),
            range: [lo.trim().parse()?, hi.trim().parse()?],
            base: None,
            points,
            certify: None,
            tolerance: None,
            name: None,
        }
    };
    for assignment in &args.set {
        let Some((name, value)) = assignment.split_once('=') else {
            bail!("--set {assignment}: expected NAME=VALUE");
        };
        let value = serde_json::from_str(value).unwrap_or_else(|_| Value::String(value.to_string()));
        spec.base
            .get_or_insert_with(Map::new)
            .insert(name.trim().to_string(), value);
    }
    if args.certify {
        spec.certify = Some(true);
    }
    Ok(spec)
}

pub fn run(args: Args) -> Result<()> {
    let spec = build_spec(&args)?;
    let runtime = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    runtime.block_on(async move {
        let store = crate::worker::open(&args.queue.database_url).await?;
        let core = Core::new(store.clone(), Limits::default(), None);
        let mut fit = core
            .submit_fit(spec)
            .await
            .map_err(|e| anyhow::anyhow!(crate::sweep::describe(e)))?;
        let config = PoolConfig::new(args.queue.workers.unwrap_or(0))
            .with_lease(Duration::from_secs_f64(args.queue.lease_seconds.max(0.1)));
        let pool = WorkerPool::start(store.clone(), config);
        let signal = crate::worker::shutdown_signal();
        tokio::pin!(signal);
        let mut shown = 0;
        while fit.status == FitStatus::Running {
            tokio::select! {
                _ = tokio::time::sleep(Duration::from_millis(500)) => {}
                _ = &mut signal => break,
            }
            fit = core
                .fit(fit.id)
                .await
                .map_err(|e| anyhow::anyhow!(crate::sweep::describe(e)))?;
            for e in &fit.evaluations[shown..] {
                let l_k: Vec<String> = (e.points.iter())
                    .map(|p| {
                        p.l_k_bar
                            .map_or("no inversion".to_string(), |l| format!("{l:.2}"))
                    })
                    .collect();
                eprintln!("{} = {}: l_k bar {}", fit.parameter, e.value, l_k.join(", "));
            }
            shown = fit.evaluations.len();
        }
        pool.shutdown().await;
        store.close().await;
        if let Some(out) = &args.out {
            std::fs::write(out, serde_json::to_string_pretty(&fit)?)
                .with_context(|| format!("writing {}", out.display()))?;
        }
        match (fit.status, fit.value, fit.interval) {
            (FitStatus::Done, Some(value), Some([lo, hi])) => {
                println!(
                    "{} = {value:.4}, interval [{lo:.4}, {hi:.4}] (chi^2 {:.3}, {} evaluations)",
                    fit.parameter,
                    fit.chi_squared.unwrap_or(f64::NAN),
                    fit.evaluations.len()
                );
                Ok(())
            }
            (FitStatus::Failed, ..) => bail!("the fit failed: {}", fit.reason.unwrap_or_default()),
            _ => bail!("interrupted: run the same command again (the cases computed are reused)"),
        }
    })
}
