//! knotsweep's job queue and its workers.
//!
//! - [`key`]: a case's identity, the blake3 hash of its canonical parameters and
//!   the solver version (dedup and result cache).
//! - [`store`]: the queue is the `cases` table, behind the [`store::Store`] trait,
//!   implemented once ([`store::SqlStore`]) for SQLite and PostgreSQL
//!   (one-statement claims, leases with fencing).
//! - [`pool`]: a worker pool that claims cases, runs the real solver on a rayon
//!   pool off the async runtime, heartbeats its leases and stores the results.
//! - [`metrics`]: in-process counters of a pool, rendered as Prometheus text.
//!
//! Data flows one way: parameters -> case -> solver -> result -> store.
pub mod key;
pub mod metrics;
pub mod pool;
pub mod store;

pub use key::{SOLVER_VERSION, canonical_json, canonical_value, case_key};
pub use pool::{PoolConfig, PoolHandle, WorkerPool};
pub use store::{Store, StoreError, sqlite::SqliteStore};
