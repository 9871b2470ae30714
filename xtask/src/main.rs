//! `xtask`: the benchmarks of BENCHMARKS.md (`cargo run --release -p xtask -- --help`).
use clap::{Parser, Subcommand};
use xtask::{bench_queue, bench_rods, bench_soak};

#[derive(Parser)]
#[command(name = "xtask", about = "knotsweep's load generators and benchmarks")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Measure the queue's throughput (claims and completions of no-op cases).
    BenchQueue(bench_queue::Args),
    /// Soak the service: many clients submitting, polling and cancelling for a while.
    BenchSoak(bench_soak::Args),
    /// The solver's cost and inversion across materials and slenderness, against the paper's rod (markdown tables).
    BenchRods(bench_rods::Args),
}

fn main() {
    let result = match Cli::parse().command {
        Command::BenchQueue(args) => bench_queue::run(args),
        Command::BenchSoak(args) => bench_soak::run(args, &mut std::io::stdout()),
        Command::BenchRods(args) => bench_rods::run(args).map(|doc| print!("{doc}")),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
