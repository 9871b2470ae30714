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
    #[command(name = "bench-queue")]
    Queue(bench_queue::Args),
    /// Soak the service: many clients submitting, polling and cancelling for a while.
    #[command(name = "bench-soak")]
    Soak(bench_soak::Args),
    /// The solver's cost and inversion across materials and slenderness, against the paper's rod (markdown tables).
    #[command(name = "bench-rods")]
    Rods(bench_rods::Args),
}

fn main() {
    let result = match Cli::parse().command {
        Command::Queue(args) => bench_queue::run(args),
        Command::Soak(args) => bench_soak::run(args, &mut std::io::stdout()),
        Command::Rods(args) => bench_rods::run(args).map(|doc| print!("{doc}")),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
