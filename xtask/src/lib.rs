//! knotsweep's load generators and benchmarks, kept out of the product
//! binary: the queue's throughput ([`bench_queue`]), the service under a
//! sustained mixed load ([`bench_soak`]) and the solver's cost across rods
//! ([`bench_rods`]), what results take in the store ([`store_sizes`]), and
//! the fisherman's knot's regimes from run reports ([`fisherman`]).
//! `cargo run --release -p xtask -- bench-queue | bench-soak | bench-rods |
//! store-sizes | fisherman`; BENCHMARKS.md, docs/API.md and docs/FIDELITY.md
//! record their figures.
pub mod bench_queue;
pub mod bench_rods;
pub mod bench_soak;
pub mod fisherman;
pub mod store_sizes;
