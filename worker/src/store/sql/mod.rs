//! The queue's statements and logic, written once for both backends.
//!
//! [`SqlStore`] runs on sqlx's `Any` driver: one pool type, rows decoded the
//! same way (the schema has integers, reals, text and bytes only). A
//! [`Backend`] holds what differs. Its dialect is three SQL fragments (how a
//! read-then-write transaction begins and locks the rows it reads) and two
//! hooks that do nothing by default (serialising sweep creation, announcing
//! new work); its own code is the claim and the wait for work. Everything
//! else is portable SQL: `$n` placeholders on both (sqlx's SQLite driver
//! binds `$n` by number), `CASE` rather than `MAX` or `GREATEST`,
//! `CAST(... AS TEXT)`.
use super::rows::*;
use super::*;
use sqlx::Transaction;
use sqlx::any::Any;
use sqlx::{AnyConnection, AnyPool};
use std::fmt::Debug;
use std::future::Future;

mod leases;
mod searches;
mod sweeps;

pub(super) use leases::{claim_query, claim_statement};

/// A transaction on the store's pool.
type Tx = Transaction<'static, Any>;

/// A database the queue runs on: where its SQL differs and what only it
/// does. The defaults are those of a backend without notifications.
pub trait Backend: Debug + Send + Sync + 'static {
    /// Begins a transaction that reads, then writes.
    const BEGIN: &'static str;
    /// Ends a `SELECT` whose rows its transaction then updates.
    const FOR_UPDATE: &'static str;
    /// Ends such a `SELECT` where rows that other transactions hold are
    /// skipped, not waited for.
    const SKIP_LOCKED: &'static str;

    /// [`Store::claim`]: [`claim_statement`] (bound by [`claim_query`]) and
    /// the claim's log line.
    fn claim(
        pool: &AnyPool,
        owner: &str,
        lease: Duration,
    ) -> impl Future<Output = StoreResult<Option<Claim>>> + Send;

    /// Runs first when a sweep is created, so that two creations with one
    /// idempotency key cannot both insert (beyond what [`Self::BEGIN`] locks).
    fn serialise_creation(_: &mut AnyConnection) -> impl Future<Output = StoreResult<()>> + Send {
        async { Ok(()) }
    }

    /// Announces claimable work when the transaction commits.
    fn announce(_: &mut AnyConnection) -> impl Future<Output = StoreResult<()>> + Send {
        async { Ok(()) }
    }

    /// [`Store::wait_for_work`].
    fn wait_for_work(&self, poll: Duration) -> impl Future<Output = ()> + Send {
        tokio::time::sleep(poll)
    }

    /// Stops listening for work (before the pool closes).
    fn stop_listening(&self) {}
}

/// The queue on a SQL database: [`SqliteStore`](super::sqlite::SqliteStore)
/// or [`PgStore`](super::postgres::PgStore).
#[derive(Debug)]
pub struct SqlStore<B: Backend> {
    pool: AnyPool,
    retry: RetryPolicy,
    backend: B,
}

impl<B: Backend> SqlStore<B> {
    pub(super) fn new(pool: AnyPool, retry: RetryPolicy, backend: B) -> Self {
        Self { pool, retry, backend }
    }

    /// The connection pool (for tests and diagnostics).
    pub fn pool(&self) -> &AnyPool {
        &self.pool
    }

    /// The series or snapshots of case `id`'s result ([`stored_values`],
    /// decoded on the blocking pool); `None` before the result.
    async fn stored<T: serde::de::DeserializeOwned + Send + 'static>(
        &self,
        id: i64,
        what: Packed,
        unpack: fn(&[u8]) -> Result<T, super::codec::CodecError>,
    ) -> StoreResult<Option<T>> {
        let (text, packed) = what.columns();
        let sql = format!("SELECT {text}, {packed} FROM results WHERE case_id = $1");
        let Some(row) = sqlx::query(&sql).bind(id).fetch_optional(&self.pool).await? else {
            return Ok(None);
        };
        tokio::task::spawn_blocking(move || stored_values(&row, what, unpack))
            .await
            .map_err(|e| StoreError::Corrupt(format!("decoding the result of case {id}: {e}")))?
            .map(Some)
    }
}

#[async_trait]
impl<B: Backend> Store for SqlStore<B> {
    async fn create_sweep(&self, sweep: NewSweep) -> StoreResult<CreateOutcome> {
        self.create(sweep).await
    }

    async fn list_sweeps(&self, limit: i64, offset: i64) -> StoreResult<Vec<SweepRecord>> {
        let sql = format!("SELECT {SWEEP_COLUMNS} FROM sweeps ORDER BY id LIMIT $1 OFFSET $2");
        let rows = sqlx::query(&sql)
            .bind(limit)
            .bind(offset)
            .fetch_all(&self.pool)
            .await?;
        rows.iter().map(sweep_from_row).collect()
    }

    async fn count_sweeps(&self) -> StoreResult<i64> {
        let row = sqlx::query("SELECT COUNT(*) AS n FROM sweeps")
            .fetch_one(&self.pool)
            .await?;
        row.int("n")
    }

    async fn get_sweep(&self, id: i64) -> StoreResult<Option<SweepRecord>> {
        Self::sweep(&mut *self.pool.acquire().await?, id, "").await
    }

    async fn sweep_status_counts(
        &self,
        ids: RangeInclusive<i64>,
    ) -> StoreResult<Vec<(i64, CaseStatus, i64)>> {
        let rows = sqlx::query(
            "SELECT sc.sweep_id, COALESCE(r.outcome, c.status) AS st, COUNT(*) AS n \
             FROM sweep_cases sc JOIN cases c ON c.id = sc.case_id LEFT JOIN results r ON r.case_id = c.id \
             WHERE sc.sweep_id BETWEEN $1 AND $2 GROUP BY sc.sweep_id, st ORDER BY sc.sweep_id, st",
        )
        .bind(*ids.start())
        .bind(*ids.end())
        .fetch_all(&self.pool)
        .await?;
        rows.iter()
            .map(|r| Ok((r.int("sweep_id")?, status_from_row(r, "st")?, r.int("n")?)))
            .collect()
    }

    async fn sweep_cases(&self, id: i64) -> StoreResult<Vec<SweepCase>> {
        let sql = format!(
            "SELECT sc.position, sc.cached, sc.twin_position, {CASE_COLUMNS} FROM sweep_cases sc \
             JOIN cases c ON c.id = sc.case_id LEFT JOIN results r ON r.case_id = c.id \
             WHERE sc.sweep_id = $1 ORDER BY sc.position"
        );
        let rows = sqlx::query(&sql).bind(id).fetch_all(&self.pool).await?;
        rows.iter()
            .map(|r| {
                Ok(SweepCase {
                    position: r.int("position")?,
                    cached: r.int("cached")? != 0,
                    twin_position: r.int_or_null("twin_position")?,
                    case: case_from_row(r)?,
                })
            })
            .collect()
    }

    async fn control_sweep(&self, id: i64, action: SweepAction) -> StoreResult<SweepRecord> {
        self.control(id, action).await
    }

    async fn get_case(&self, id: i64) -> StoreResult<Option<CaseRecord>> {
        let sql = format!(
            "SELECT {CASE_COLUMNS} FROM cases c LEFT JOIN results r ON r.case_id = c.id WHERE c.id = $1"
        );
        let row = sqlx::query(&sql).bind(id).fetch_optional(&self.pool).await?;
        row.map(|r| case_from_row(&r)).transpose()
    }

    async fn case_sweeps(&self, id: i64) -> StoreResult<Vec<i64>> {
        let rows = sqlx::query("SELECT sweep_id FROM sweep_cases WHERE case_id = $1 ORDER BY sweep_id")
            .bind(id)
            .fetch_all(&self.pool)
            .await?;
        rows.iter().map(|r| r.int("sweep_id")).collect()
    }

    async fn case_series(&self, id: i64) -> StoreResult<Option<Vec<Sample>>> {
        self.stored(id, Packed::Series, super::codec::unpack_series).await
    }

    async fn case_snapshots(&self, id: i64) -> StoreResult<Option<Vec<Snapshot>>> {
        self.stored(id, Packed::Snapshots, super::codec::unpack_snapshots)
            .await
    }

    async fn set_measurements(&self, id: i64, points: &str) -> StoreResult<()> {
        if self.get_sweep(id).await?.is_none() {
            return Err(StoreError::NotFound);
        }
        sqlx::query(
            "INSERT INTO measurements (sweep_id, points, created_at) VALUES ($1, $2, $3) \
             ON CONFLICT (sweep_id) DO UPDATE SET points = excluded.points, created_at = excluded.created_at",
        )
        .bind(id)
        .bind(points)
        .bind(now_ms())
        .execute(&self.pool)
        .await?;
        Ok(())
    }

    async fn measurements(&self, id: i64) -> StoreResult<Option<String>> {
        let row = sqlx::query("SELECT points FROM measurements WHERE sweep_id = $1")
            .bind(id)
            .fetch_optional(&self.pool)
            .await?;
        row.map(|r| r.text("points")).transpose()
    }

    async fn create_fit(&self, status: &str, view: &str) -> StoreResult<i64> {
        self.insert_fit(status, view).await
    }

    async fn update_fit(&self, id: i64, status: &str, view: &str) -> StoreResult<()> {
        self.replace_fit(id, status, view).await
    }

    async fn get_fit(&self, id: i64) -> StoreResult<Option<String>> {
        self.fit_view(id).await
    }

    async fn list_fits(&self) -> StoreResult<Vec<(i64, String, String)>> {
        self.fit_views().await
    }

    async fn put_refinement(&self, id: i64, status: &str, view: &str) -> StoreResult<()> {
        self.upsert_refinement(id, status, view).await
    }

    async fn refinement(&self, id: i64) -> StoreResult<Option<String>> {
        self.refinement_view(id).await
    }

    async fn refinements_with_status(&self, status: &str) -> StoreResult<Vec<(i64, String)>> {
        self.refinement_views(status).await
    }

    async fn case_logs(&self, id: i64) -> StoreResult<Vec<LogLine>> {
        let rows = sqlx::query("SELECT at, level, message FROM case_logs WHERE case_id = $1 ORDER BY id")
            .bind(id)
            .fetch_all(&self.pool)
            .await?;
        rows.iter()
            .map(|r| {
                Ok(LogLine {
                    at: r.int("at")?,
                    level: r.text("level")?,
                    message: r.text("message")?,
                })
            })
            .collect()
    }

    async fn append_log(&self, case_id: i64, level: &str, message: &str) -> StoreResult<()> {
        Self::log(&mut *self.pool.acquire().await?, case_id, level, message).await
    }

    async fn requeue_expired(&self) -> StoreResult<usize> {
        self.expire_leases().await
    }

    async fn claim(&self, owner: &str, lease: Duration) -> StoreResult<Option<Claim>> {
        B::claim(&self.pool, owner, lease).await
    }

    async fn heartbeat(
        &self,
        lease: &Lease,
        progress: Option<&Progress>,
        extend: Duration,
    ) -> StoreResult<Heartbeat> {
        self.extend_lease(lease, progress, extend).await
    }

    async fn complete(&self, lease: &Lease, report: &CaseReport) -> StoreResult<bool> {
        self.store_result(lease, report).await
    }

    async fn fail_attempt(&self, lease: &Lease, reason: &str) -> StoreResult<FailOutcome> {
        self.retry_or_fail(lease, reason).await
    }

    async fn release(&self, lease: &Lease) -> StoreResult<bool> {
        self.release_lease(lease).await
    }

    async fn finish_cancelled(&self, lease: &Lease) -> StoreResult<bool> {
        self.end_cancelled(lease).await
    }

    async fn status_counts(&self) -> StoreResult<StatusCounts> {
        let rows = sqlx::query(
            "SELECT COALESCE(r.outcome, c.status) AS st, COUNT(*) AS n FROM cases c \
             LEFT JOIN results r ON r.case_id = c.id GROUP BY st ORDER BY st",
        )
        .fetch_all(&self.pool)
        .await?;
        rows.iter()
            .map(|r| Ok((status_from_row(r, "st")?, r.int("n")?)))
            .collect()
    }

    async fn queue_depth(&self) -> StoreResult<i64> {
        let sql = format!("SELECT COUNT(*) AS n FROM cases c WHERE c.status = 'queued' AND {CLAIMABLE}");
        sqlx::query(&sql).fetch_one(&self.pool).await?.int("n")
    }

    async fn wait_for_work(&self, poll: Duration) {
        self.backend.wait_for_work(poll).await;
    }

    async fn close(&self) {
        self.backend.stop_listening();
        self.pool.close().await;
    }
}
