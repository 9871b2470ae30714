//! knotsweep's load generators and benchmarks, kept out of the product
//! binary: the queue's throughput ([`bench_queue`]), the service under a
//! sustained mixed load ([`bench_soak`]) and the solver's cost across rods
//! ([`bench_rods`]), and what results take in the store ([`store_sizes`]).
//! `cargo run --release -p xtask -- bench-queue | bench-soak | bench-rods |
//! store-sizes`; BENCHMARKS.md and docs/API.md record their figures.
pub mod bench_queue;
pub mod bench_rods;
pub mod bench_soak;
pub mod store_sizes;
