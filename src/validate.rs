//! `knotsweep validate`: runs the validation suite, prints the table and writes
//! it as JSON; exits non-zero when a row fails.
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use solver::validation::{self, CaseResult};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Write the table as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Run only the cases whose name contains this text.
    #[arg(long)]
    only: Option<String>,
}

pub fn run(args: Args) -> Result<()> {
    let cases: Vec<_> = validation::all_cases()
        .into_iter()
        .filter(|c| args.only.as_deref().is_none_or(|o| c.name.contains(o)))
        .collect();
    if cases.is_empty() {
        bail!("no validation case matches {:?}", args.only);
    }
    let bar = ProgressBar::new(cases.len() as u64)
        .with_style(ProgressStyle::with_template("{bar:30} {pos}/{len} {msg}").expect("valid template"));
    let mut rows: Vec<CaseResult> = Vec::new();
    for case in &cases {
        bar.set_message(case.name);
        let started = std::time::Instant::now();
        let case_rows = (case.run)();
        tracing::info!(
            case = case.name,
            seconds = started.elapsed().as_secs_f64(),
            "validation case done"
        );
        rows.extend(case_rows);
        bar.inc(1);
    }
    bar.finish_and_clear();
    print_table(&rows);
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&rows)?;
        std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    let failed = rows.iter().filter(|r| !r.pass).count();
    println!("{} passed, {} failed", rows.len() - failed, failed);
    if failed > 0 {
        bail!("{failed} validation row(s) failed");
    }
    Ok(())
}

fn print_table(rows: &[CaseResult]) {
    println!(
        "{:<26} {:>13} {:>13} {:>10} {:>9}  {:<4}  quantity",
        "case", "expected", "got", "error", "tol", "pass"
    );
    for r in rows {
        println!(
            "{:<26} {:>13.6e} {:>13.6e} {:>10.2e} {:>9.1e}  {:<4}  {}",
            r.case,
            r.expected,
            r.got,
            r.error,
            r.tolerance,
            if r.pass { "yes" } else { "NO" },
            r.quantity
        );
    }
}
