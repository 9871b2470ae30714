//! The queue is the `cases` table; this trait is everything the server and the
//! workers do with it. [`SqlStore`] implements it once, over sqlx, for both
//! backends: [`sqlite::SqliteStore`] on one SQLite file (the embedded
//! default), [`postgres::PgStore`] on a PostgreSQL server that workers on many
//! hosts share (`FOR UPDATE SKIP LOCKED` claims, wake-ups by `LISTEN/NOTIFY`).
//! Both run the same schema (`migrations/sqlite`, `migrations/postgres`) and
//! the same statements (`sql/`), decode rows with the same code (`rows`), and
//! differ only where [`Backend`] says; [`open_store`] picks one from a URL.
//!
//! Queue invariants, whatever the backend:
//! - a case is claimed by one statement that sets the lease (owner, expiry)
//!   and increments the fencing counter; no transaction is open while the
//!   solver computes;
//! - heartbeats, completion, release and failure only touch the row when the
//!   caller's (owner, fence) is the current lease: a worker that lost its lease
//!   cannot complete the case;
//! - an expired lease returns the case to the queue (with backoff) or, after
//!   `max_attempts` claims, marks it `failed` with the reason;
//! - a solver failure (diverged, topology changed, ...) is a result, not a retry.
pub mod codec;
pub mod postgres;
mod result;
mod rows;
mod sql;
pub mod sqlite;
mod status;
#[cfg(test)]
mod testing;

use async_trait::async_trait;
use serde::{Deserialize, Serialize};
use solver::case::CaseParams;
use solver::measurements::Sample;
use solver::protocol::{CaseReport, Progress};
use solver::snapshot::{Snapshot, SnapshotLabel};
use std::ops::RangeInclusive;
use std::time::Duration;

pub use result::{ResultDetails, ResultSummary};
pub use sql::{Backend, SqlStore};
pub use status::{CaseState, CaseStatus, SweepState};

/// Errors of the store.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    #[error("database error: {0}")]
    Database(#[from] sqlx::Error),
    #[error("migration failed: {0}")]
    Migrate(#[from] sqlx::migrate::MigrateError),
    #[error("stored data is corrupt: {0}")]
    Corrupt(String),
    /// A stored JSON value that does not read as its type.
    #[error("stored {what} does not read: {source}")]
    Json {
        what: String,
        #[source]
        source: serde_json::Error,
    },
    /// A packed column that does not decode.
    #[error("stored {column} does not decode: {source}")]
    Codec {
        column: &'static str,
        #[source]
        source: codec::CodecError,
    },
    /// A stored word that names none of its kind's values.
    #[error("stored {what} {word:?} is none of its words")]
    UnknownWord { what: &'static str, word: String },
    #[error("not found")]
    NotFound,
    #[error("{0}")]
    Conflict(String),
    /// A database URL this build cannot open.
    #[error("{0}")]
    Unsupported(String),
    /// The database server did not answer.
    #[error("{0}")]
    Unreachable(String),
}

pub type StoreResult<T> = Result<T, StoreError>;

impl StoreError {
    /// `word`, stored as a `what`, names none.
    pub(crate) fn word(what: &'static str, word: &str) -> Self {
        Self::UnknownWord {
            what,
            word: word.to_string(),
        }
    }
}

/// Retry policy for infrastructure failures (lost workers, panics, storage
/// errors while completing): exponential backoff with jitter, at most
/// `max_attempts` claims, then `failed`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RetryPolicy {
    pub max_attempts: u32,
    /// Backoff before attempt k+1 is `min(cap, base * 2^(k-1))`, of which a
    /// random half is jitter.
    pub base: Duration,
    pub cap: Duration,
}

impl Default for RetryPolicy {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl RetryPolicy {
    /// Three claims, backoff from 1 s up to 60 s.
    pub const DEFAULT: Self = Self {
        max_attempts: 3,
        base: Duration::from_secs(1),
        cap: Duration::from_secs(60),
    };

    /// The delay before the next attempt after `attempts` failed ones.
    pub fn backoff(&self, attempts: u32) -> Duration {
        let exp = attempts.saturating_sub(1).min(30);
        let full = self.base.saturating_mul(1u32 << exp).min(self.cap);
        let half = full / 2;
        half + half.mul_f64(rand::random::<f64>())
    }
}

/// Which of a result's snapshots the store keeps, chosen per sweep. A case
/// that several sweeps asked for keeps the most of their choices (`all` over
/// `events` over `none`); a case already done when a sweep asks for it keeps
/// what was stored. The choice is no part of a case's key: the physics is
/// the same whatever is kept.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SnapshotChoice {
    /// No snapshots.
    None,
    /// The snapshots around each event (inversion, flip back): those whose
    /// label names one, as `before_inversion` or `after_flip_back`.
    Events,
    /// Every snapshot the solver took.
    #[default]
    All,
}

impl SnapshotChoice {
    /// Every choice, as the API lists them.
    pub const ALL: [Self; 3] = [Self::All, Self::Events, Self::None];

    pub fn as_str(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Events => "events",
            Self::All => "all",
        }
    }

    pub fn parse(s: &str) -> StoreResult<Self> {
        (Self::ALL.into_iter())
            .find(|choice| choice.as_str() == s)
            .ok_or_else(|| StoreError::word("snapshot choice", s))
    }

    /// Whether a snapshot labelled `label` is kept.
    pub fn keeps(self, label: SnapshotLabel) -> bool {
        match self {
            Self::None => false,
            Self::Events => label.event().is_some(),
            Self::All => true,
        }
    }
}

/// A case to enqueue: its parameters and key.
#[derive(Clone, Debug)]
pub struct NewCase {
    pub key: String,
    pub params: CaseParams,
    /// In a certified sweep, a point's refined twin: the twin's position
    /// among the sweep's cases (stored with the sweep, so that the twin is
    /// found whatever its key becomes).
    pub twin_position: Option<usize>,
}

impl NewCase {
    /// The case of `params` under its current key, with no twin.
    pub fn new(params: CaseParams) -> Self {
        Self {
            key: crate::key::case_key(&params),
            params,
            twin_position: None,
        }
    }
}

/// A sweep to create.
#[derive(Clone, Debug)]
pub struct NewSweep {
    pub name: Option<String>,
    pub preset: Option<String>,
    /// The accepted specification, stored as given.
    pub spec: serde_json::Value,
    /// Grid axes in order.
    pub varied: Vec<String>,
    /// Which snapshots its cases' results keep.
    pub snapshots: SnapshotChoice,
    /// The cases in grid order (distinct keys).
    pub cases: Vec<NewCase>,
    /// `Idempotency-Key` and a hash of the request it came with.
    pub idempotency: Option<Idempotency>,
}

impl NewSweep {
    /// The cases with their grid positions in the order they join the queue:
    /// costliest first ([`solver::protocol::work_estimate`]; ties in grid
    /// order), so that the sweep's longest case does not start last.
    pub fn queue_order(&self) -> Vec<(usize, &NewCase)> {
        let mut order: Vec<(f64, usize, &NewCase)> = (self.cases.iter().enumerate())
            .map(|(position, case)| (solver::protocol::work_estimate(&case.params), position, case))
            .collect();
        order.sort_by(|a, b| b.0.total_cmp(&a.0));
        order
            .into_iter()
            .map(|(_, position, case)| (position, case))
            .collect()
    }
}

#[derive(Clone, Debug)]
pub struct Idempotency {
    pub key: String,
    pub request_hash: String,
}

/// A stored sweep.
#[derive(Clone, Debug, Serialize)]
pub struct SweepRecord {
    pub id: i64,
    pub name: Option<String>,
    pub preset: Option<String>,
    pub spec: serde_json::Value,
    pub varied: Vec<String>,
    pub state: SweepState,
    pub created_at: i64,
    pub updated_at: i64,
}

/// What `create_sweep` did.
#[derive(Clone, Debug)]
pub enum CreateOutcome {
    /// A new sweep; `cached` of its cases already had a result.
    Created { sweep: SweepRecord, cached: usize },
    /// The idempotency key was seen with the same request: the first sweep.
    Replayed { sweep: SweepRecord },
}

/// A case row with its result summary (no series or snapshots).
#[derive(Clone, Debug)]
pub struct CaseRecord {
    pub id: i64,
    pub key: String,
    pub solver_version: String,
    pub params: CaseParams,
    pub state: CaseState,
    pub attempts: u32,
    pub max_attempts: u32,
    pub not_before: i64,
    pub lease_owner: Option<String>,
    pub lease_expires_at: Option<i64>,
    pub fence: i64,
    pub progress: f64,
    pub progress_detail: Option<Progress>,
    pub cancel_requested: bool,
    pub last_error: Option<String>,
    pub created_at: i64,
    pub started_at: Option<i64>,
    pub finished_at: Option<i64>,
    pub result: Option<ResultSummary>,
}

impl CaseRecord {
    /// The one status of the API: the solver's status when the case has a
    /// result, otherwise the queue state.
    pub fn status(&self) -> CaseStatus {
        match &self.result {
            Some(r) => CaseStatus::Result(r.outcome),
            None => CaseStatus::Queue(self.state),
        }
    }
}

/// A case as a member of a sweep.
#[derive(Clone, Debug)]
pub struct SweepCase {
    pub position: i64,
    /// The result existed when the sweep was submitted.
    pub cached: bool,
    /// A certified point's refined twin: its position in the sweep (none on
    /// other cases and in sweeps stored before the relation was).
    pub twin_position: Option<i64>,
    pub case: CaseRecord,
}

/// A per-case log line.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct LogLine {
    /// Unix milliseconds.
    pub at: i64,
    pub level: String,
    pub message: String,
}

/// A held lease: only its holder (owner and fence) may heartbeat, complete,
/// fail or release the case.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Lease {
    pub case_id: i64,
    pub owner: String,
    pub fence: i64,
}

/// A claimed case.
#[derive(Clone, Debug)]
pub struct Claim {
    pub lease: Lease,
    pub key: String,
    pub params: CaseParams,
    /// 1 for the first claim.
    pub attempt: u32,
}

/// What a heartbeat found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Heartbeat {
    /// Still ours (lease extended); `cancel`: every sweep that wants the case
    /// was cancelled or paused, stop computing (`finish_cancelled`).
    Held { cancel: bool },
    /// Someone else holds the case now (or it is no longer running).
    Lost,
}

/// What `fail_attempt` did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FailOutcome {
    /// Back in the queue, not before the backoff.
    Retry { after: Duration },
    /// Out of attempts: `failed`.
    Failed,
    /// The lease was no longer ours.
    Lost,
}

/// Pause, resume or cancel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SweepAction {
    Pause,
    Resume,
    Cancel,
}

/// Count of cases per status (see [`CaseRecord::status`]), in word order.
pub type StatusCounts = Vec<(CaseStatus, i64)>;

/// Everything done with the queue. Every method is short: no transaction stays
/// open across calls, and none across a computation.
#[async_trait]
pub trait Store: Send + Sync + 'static {
    // --- sweeps (the API) ---

    /// Creates a sweep and enqueues its cases (dedup by key: a case already
    /// done is linked as cached; one that failed or was cancelled is queued
    /// again). With an idempotency key seen before: the first sweep when the
    /// request hash matches, `Conflict` otherwise. One IMMEDIATE transaction.
    async fn create_sweep(&self, sweep: NewSweep) -> StoreResult<CreateOutcome>;
    /// At most `limit` sweeps from the `offset`-th, oldest first.
    async fn list_sweeps(&self, limit: i64, offset: i64) -> StoreResult<Vec<SweepRecord>>;
    async fn count_sweeps(&self) -> StoreResult<i64>;
    async fn get_sweep(&self, id: i64) -> StoreResult<Option<SweepRecord>>;
    /// Per-sweep counts by status, for the sweeps whose id is in `ids`
    /// (by sweep, then status word).
    async fn sweep_status_counts(&self, ids: RangeInclusive<i64>)
    -> StoreResult<Vec<(i64, CaseStatus, i64)>>;
    /// The sweep's cases in grid order, with result summaries.
    async fn sweep_cases(&self, id: i64) -> StoreResult<Vec<SweepCase>>;
    /// Pause (its running cases no active sweep wants are handed back to the
    /// queue at their next heartbeat), resume or cancel. `NotFound` for an
    /// unknown sweep, `Conflict` for pausing or resuming a cancelled one;
    /// cancelling a finished sweep (no case queued or running) changes nothing.
    async fn control_sweep(&self, id: i64, action: SweepAction) -> StoreResult<SweepRecord>;
    /// Puts measured points (JSON text) beside sweep `id`, replacing any
    /// before; `NotFound` for an unknown sweep.
    async fn set_measurements(&self, id: i64, points: &str) -> StoreResult<()>;
    /// The measured points put beside sweep `id`, if any.
    async fn measurements(&self, id: i64) -> StoreResult<Option<String>>;

    // --- fits and maps' refinements (searches over sweeps, kept as their JSON views) ---

    /// Stores a new fit's view (JSON) and status word; returns its id.
    async fn create_fit(&self, status: &str, view: &str) -> StoreResult<i64>;
    /// Replaces fit `id`'s status and view; `NotFound` for an unknown fit.
    async fn update_fit(&self, id: i64, status: &str, view: &str) -> StoreResult<()>;
    /// Fit `id`'s view, if any.
    async fn get_fit(&self, id: i64) -> StoreResult<Option<String>>;
    /// Every fit as (id, status, view), oldest first.
    async fn list_fits(&self) -> StoreResult<Vec<(i64, String, String)>>;
    /// Puts sweep `id`'s refinement (view and status), replacing any before;
    /// `NotFound` for an unknown sweep.
    async fn put_refinement(&self, id: i64, status: &str, view: &str) -> StoreResult<()>;
    /// Sweep `id`'s refinement view, if any.
    async fn refinement(&self, id: i64) -> StoreResult<Option<String>>;
    /// Every refinement whose status is `status`, as (sweep id, view).
    async fn refinements_with_status(&self, status: &str) -> StoreResult<Vec<(i64, String)>>;

    // --- cases (the API) ---

    async fn get_case(&self, id: i64) -> StoreResult<Option<CaseRecord>>;
    /// Ids of the sweeps that asked for a case.
    async fn case_sweeps(&self, id: i64) -> StoreResult<Vec<i64>>;
    /// The series of a case's result, `None` before it: decoded from its
    /// packed form, or read from the JSON text of a result stored before it.
    async fn case_series(&self, id: i64) -> StoreResult<Option<Vec<Sample>>>;
    /// The snapshots of a case's result, likewise.
    async fn case_snapshots(&self, id: i64) -> StoreResult<Option<Vec<Snapshot>>>;
    async fn case_logs(&self, id: i64) -> StoreResult<Vec<LogLine>>;
    async fn append_log(&self, case_id: i64, level: &str, message: &str) -> StoreResult<()>;

    // --- the queue (the workers) ---

    /// Returns cases whose lease expired to the queue (with backoff) or marks
    /// them failed when out of attempts. Returns how many it touched.
    async fn requeue_expired(&self) -> StoreResult<usize>;
    /// Claims the oldest queued case of an active sweep whose backoff has
    /// passed, in one UPDATE ... RETURNING statement.
    async fn claim(&self, owner: &str, lease: Duration) -> StoreResult<Option<Claim>>;
    /// Extends the lease, stores progress and reads the cancel flag.
    async fn heartbeat(
        &self,
        lease: &Lease,
        progress: Option<&Progress>,
        extend: Duration,
    ) -> StoreResult<Heartbeat>;
    /// Stores the result and marks the case done, if `lease` is current;
    /// `Ok(false)` otherwise (nothing written). `report.status` must not be
    /// `cancelled`. The series and snapshots are stored packed (`codec`), the
    /// snapshots those that the [`SnapshotChoice`] of the sweeps asking for
    /// the case keeps.
    async fn complete(&self, lease: &Lease, report: &CaseReport) -> StoreResult<bool>;
    /// A retryable failure of this attempt (not a solver failure).
    async fn fail_attempt(&self, lease: &Lease, reason: &str) -> StoreResult<FailOutcome>;
    /// Gives the case back (shutdown): queued at once, the attempt not counted.
    async fn release(&self, lease: &Lease) -> StoreResult<bool>;
    /// The solver stopped on a cancel request: `cancelled`, or queued again,
    /// the attempt not counted, if the request was a pause's or a sweep asked
    /// for the case in the meantime.
    async fn finish_cancelled(&self, lease: &Lease) -> StoreResult<bool>;

    // --- metrics ---

    /// Count of all cases by status word.
    async fn status_counts(&self) -> StoreResult<StatusCounts>;
    /// Queued cases of active sweeps whose backoff has passed.
    async fn queue_depth(&self) -> StoreResult<i64>;

    // --- connection ---

    /// Waits until work may be available: `poll` on a backend without
    /// notifications; until a notification (or a fallback interval) on one with.
    async fn wait_for_work(&self, poll: Duration) {
        tokio::time::sleep(poll).await;
    }
    /// Closes every connection.
    async fn close(&self);
}

/// Connection settings common to the backends.
#[derive(Clone, Debug)]
pub struct StoreOptions {
    /// Connections in the pool.
    pub max_connections: u32,
    pub retry: RetryPolicy,
}

impl Default for StoreOptions {
    fn default() -> Self {
        Self {
            max_connections: 8,
            retry: RetryPolicy::default(),
        }
    }
}

/// Opens the store at `url` and runs its migrations: `sqlite://PATH` (or a
/// plain path; created if missing) or `postgres://...` / `postgresql://...`.
/// Any other scheme is `Unsupported`, naming it; an unreachable server is a
/// `Database` error naming the URL's host.
pub async fn open_store(url: &str, options: StoreOptions) -> StoreResult<std::sync::Arc<dyn Store>> {
    let scheme = url.split_once("://").map(|(s, _)| s);
    Ok(match scheme {
        Some("postgres" | "postgresql") => {
            std::sync::Arc::new(postgres::PgStore::connect(url, options).await?)
        }
        Some("sqlite") | None => std::sync::Arc::new(
            sqlite::SqliteStore::connect(
                url,
                sqlite::SqliteOptions {
                    max_connections: options.max_connections,
                    retry: options.retry,
                    ..Default::default()
                },
            )
            .await?,
        ),
        Some(other) => {
            return Err(StoreError::Unsupported(format!(
                "{other}:// databases are not supported: give sqlite://PATH (the embedded default) or postgres://USER@HOST/DB"
            )));
        }
    })
}

/// Milliseconds since the Unix epoch.
pub fn now_ms() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_millis() as i64)
        .unwrap_or(0)
}

/// A duration in whole milliseconds (saturating), as the tables store them.
fn ms(d: Duration) -> i64 {
    d.as_millis().min(i64::MAX as u128) as i64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A friction sweep under the adaptive protocol: the cases above
    /// `ADAPTIVE_MAX_MU` run the whole pull slowly and join the queue first,
    /// the rest keep their grid order, and every case keeps its grid position.
    #[test]
    fn queue_order_puts_slow_cases_first() {
        const { assert!(0.8 > solver::protocol::ADAPTIVE_MAX_MU) };
        let cases = [0.1, 0.8, 0.2, 0.9]
            .map(|mu| {
                NewCase::new(CaseParams {
                    mu,
                    protocol: solver::case::Protocol::Adaptive,
                    ..CaseParams::default()
                })
            })
            .to_vec();
        let sweep = NewSweep {
            name: None,
            preset: None,
            spec: serde_json::Value::Null,
            varied: vec!["mu".to_string()],
            snapshots: SnapshotChoice::All,
            cases,
            idempotency: None,
        };
        let order: Vec<(usize, f64)> = sweep
            .queue_order()
            .iter()
            .map(|(p, c)| (*p, c.params.mu))
            .collect();
        assert_eq!(order, [(1, 0.8), (3, 0.9), (0, 0.1), (2, 0.2)]);
    }

    #[test]
    fn backoff_grows_exponentially_with_jitter_and_is_capped() {
        let p = RetryPolicy {
            max_attempts: 10,
            base: Duration::from_millis(100),
            cap: Duration::from_secs(1),
        };
        for attempts in 1..8 {
            let full = Duration::from_millis(100 * (1 << (attempts - 1))).min(Duration::from_secs(1));
            for _ in 0..20 {
                let d = p.backoff(attempts);
                assert!(d >= full / 2 && d <= full, "{attempts}: {d:?}");
            }
        }
    }
}
