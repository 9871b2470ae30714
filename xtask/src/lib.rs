//! knotsweep's load generators, kept out of the product binary: the queue's
//! throughput ([`bench_queue`]) and the service under a sustained mixed load
//! ([`bench_soak`]). `cargo run --release -p xtask -- bench-queue | bench-soak`;
//! BENCHMARKS.md records their figures.
pub mod bench_queue;
pub mod bench_soak;
