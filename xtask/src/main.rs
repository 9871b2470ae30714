//! `xtask`: the benchmarks of BENCHMARKS.md and the store's sizes of docs/API.md
//! (`cargo run --release -p xtask -- --help`).
use clap::{Parser, Subcommand};
use xtask::{bench_queue, bench_rods, bench_soak, fisherman, store_sizes};

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
    /// What results take in the store: a report's series and snapshots as JSON and packed, or a SQLite store's files per result.
    #[command(name = "store-sizes")]
    StoreSizes(store_sizes::Args),
    /// The fisherman's knot's sliding and stretching regimes from run reports (figure and markdown table).
    #[command(name = "fisherman")]
    Fisherman(fisherman::Args),
}

fn main() {
    let result = match Cli::parse().command {
        Command::Queue(args) => bench_queue::run(args),
        Command::Soak(args) => bench_soak::run(args, &mut std::io::stdout()),
        Command::Rods(args) => bench_rods::run(args).map(|doc| print!("{doc}")),
        Command::StoreSizes(args) => store_sizes::run(args).map(|doc| print!("{doc}")),
        Command::Fisherman(args) => fisherman::run(args).map(|doc| print!("{doc}")),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
