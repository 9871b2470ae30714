//! `knotsweep`: one command for everything — validation suite, single cases,
//! sweeps and the service (subcommands are added as the features land).
#[cfg(test)]
mod doc_commands;
mod fit;
mod queue_args;
mod reproduce;
mod run;
mod serve;
mod simplified;
mod snapshots;
mod sweep;
mod validate;
mod worker;

use anyhow::Result;
use clap::{Parser, Subcommand};
use tracing_subscriber::EnvFilter;

#[derive(Parser)]
#[command(
    name = "knotsweep",
    version,
    about = "Snap-buckling of overhand knots: DER solver and tools"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the solver's validation suite and print a table of expected vs got.
    Validate(validate::Args),
    /// Run one overhand-knot tightening case (paper Sec. 4).
    Run(Box<run::Args>),
    /// Rerun the paper's Sec. 4 checks and write docs/VALIDATION.md.
    Reproduce(reproduce::Args),
    /// The simplified knot model of paper Sec. 5.
    Simplified(simplified::Args),
    /// Side views of the knot at given l_c / L (SVG, framed as the paper's Fig. 1).
    Snapshots(Box<snapshots::Args>),
    /// Serve the sweep API (and run cases on this machine's cores).
    Serve(serve::Args),
    /// Add workers to the queue of a server's database.
    Worker(worker::Args),
    /// Run a sweep locally (resumable) and write its phase diagram.
    Sweep(sweep::Args),
    /// Fit a parameter (mu by default) to measured inversions over local cases.
    Fit(fit::Args),
}

fn main() {
    tracing_subscriber::fmt()
        .with_env_filter(EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new("info")))
        .with_writer(std::io::stderr)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .init();
    let cli = Cli::parse();
    let result: Result<()> = match cli.command {
        Command::Validate(args) => validate::run(args),
        Command::Run(args) => run::run(*args),
        Command::Reproduce(args) => reproduce::run(args),
        Command::Simplified(args) => simplified::run(args),
        Command::Snapshots(args) => snapshots::run(*args),
        Command::Serve(args) => serve::run(args),
        Command::Worker(args) => worker::run(args),
        Command::Sweep(args) => sweep::run(args),
        Command::Fit(args) => fit::run(args),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
