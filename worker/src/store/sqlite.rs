//! The SQLite implementation of [`Store`].
//!
//! Every pooled connection runs in WAL mode with `synchronous = NORMAL`, a busy
//! timeout and foreign keys on (sqlx applies the connect options to each new
//! connection). Transactions that read and then write begin `IMMEDIATE`, so
//! they take the write lock up front and wait on the busy timeout instead of
//! failing with "database is locked" when upgrading a stale read snapshot;
//! single write statements (claim, heartbeat) take the write lock when they
//! start. Nothing stays open while a case computes.
use super::rows::*;
use super::*;
use sqlx::Row;
use sqlx::sqlite::{
    SqliteConnectOptions, SqliteJournalMode, SqlitePool, SqlitePoolOptions, SqliteRow, SqliteSynchronous,
};
use std::str::FromStr;

/// Connection settings.
#[derive(Clone, Debug)]
pub struct SqliteOptions {
    /// Pool size.
    pub max_connections: u32,
    /// How long a statement waits for another connection's write lock.
    pub busy_timeout: Duration,
    pub retry: RetryPolicy,
}

impl Default for SqliteOptions {
    fn default() -> Self {
        Self {
            max_connections: 8,
            busy_timeout: Duration::from_secs(10),
            retry: RetryPolicy::default(),
        }
    }
}

/// The queue and results in one SQLite file.
#[derive(Clone, Debug)]
pub struct SqliteStore {
    pool: SqlitePool,
    retry: RetryPolicy,
}

impl SqliteStore {
    /// Opens (creating if missing) the database at `url` (`sqlite://path`,
    /// `sqlite:path` or a plain path) and runs the migrations.
    pub async fn connect(url: &str, options: SqliteOptions) -> StoreResult<Self> {
        let url = if url.starts_with("sqlite:") {
            url.to_string()
        } else if let Some((scheme, _)) = url.split_once("://") {
            return Err(StoreError::Unsupported(format!(
                "{scheme}:// is not a SQLite database: give sqlite://PATH (or a file path)"
            )));
        } else {
            format!("sqlite://{url}")
        };
        let connect = SqliteConnectOptions::from_str(&url)?
            .create_if_missing(true)
            .journal_mode(SqliteJournalMode::Wal)
            .synchronous(SqliteSynchronous::Normal)
            .busy_timeout(options.busy_timeout)
            .foreign_keys(true);
        let pool = SqlitePoolOptions::new()
            .max_connections(options.max_connections.max(1))
            .min_connections(1)
            .acquire_timeout(Duration::from_secs(60))
            .connect_with(connect)
            .await?;
        // Several processes may open a fresh file at once: a losing migration
        // run finds the schema in place on its next try.
        let mut tries = 0;
        loop {
            match sqlx::migrate!("../migrations/sqlite").run(&pool).await {
                Ok(()) => break,
                Err(e) if tries < 10 => {
                    tries += 1;
                    tracing::debug!(error = %e, "migration raced with another process; retrying");
                    tokio::time::sleep(Duration::from_millis(100 * tries)).await;
                }
                Err(e) => return Err(e.into()),
            }
        }
        Ok(Self {
            pool,
            retry: options.retry,
        })
    }

    /// The connection pool (for tests and diagnostics).
    pub fn pool(&self) -> &SqlitePool {
        &self.pool
    }

    async fn sweep_by_id<'e, E>(exec: E, id: i64) -> StoreResult<Option<SweepRecord>>
    where
        E: sqlx::Executor<'e, Database = sqlx::Sqlite>,
    {
        let row = sqlx::query(&format!("SELECT {SWEEP_COLUMNS} FROM sweeps WHERE id = ?"))
            .bind(id)
            .fetch_optional(exec)
            .await?;
        row.map(|r| sweep_from_row(&r)).transpose()
    }
}

impl Columns for SqliteRow {
    fn text(&self, column: &str) -> StoreResult<String> {
        Ok(self.try_get(column)?)
    }
    fn text_or_null(&self, column: &str) -> StoreResult<Option<String>> {
        Ok(self.try_get(column)?)
    }
    fn int(&self, column: &str) -> StoreResult<i64> {
        Ok(self.try_get(column)?)
    }
    fn int_or_null(&self, column: &str) -> StoreResult<Option<i64>> {
        Ok(self.try_get(column)?)
    }
    fn real(&self, column: &str) -> StoreResult<f64> {
        Ok(self.try_get(column)?)
    }
}

async fn log<'e, E>(exec: E, case_id: i64, level: &str, message: &str) -> StoreResult<()>
where
    E: sqlx::Executor<'e, Database = sqlx::Sqlite>,
{
    sqlx::query("INSERT INTO case_logs (case_id, at, level, message) VALUES (?, ?, ?, ?)")
        .bind(case_id)
        .bind(now_ms())
        .bind(level)
        .bind(message)
        .execute(exec)
        .await?;
    Ok(())
}

fn ms(d: Duration) -> i64 {
    d.as_millis().min(i64::MAX as u128) as i64
}

#[async_trait]
impl Store for SqliteStore {
    async fn create_sweep(&self, sweep: NewSweep) -> StoreResult<CreateOutcome> {
        let now = now_ms();
        let mut tx = self.pool.begin_with("BEGIN IMMEDIATE").await?;
        if let Some(idem) = &sweep.idempotency {
            let found = sqlx::query("SELECT id, request_hash FROM sweeps WHERE idempotency_key = ?")
                .bind(&idem.key)
                .fetch_optional(&mut *tx)
                .await?;
            if let Some(row) = found {
                let id: i64 = row.try_get("id")?;
                let hash: Option<String> = row.try_get("request_hash")?;
                if hash.as_deref() != Some(idem.request_hash.as_str()) {
                    return Err(StoreError::Conflict(
                        "Idempotency-Key was already used with a different request".to_string(),
                    ));
                }
                let sweep = Self::sweep_by_id(&mut *tx, id)
                    .await?
                    .ok_or(StoreError::NotFound)?;
                tx.commit().await?;
                return Ok(CreateOutcome::Replayed { sweep });
            }
        }
        let id: i64 = sqlx::query(
            "INSERT INTO sweeps (name, preset, spec, varied, state, idempotency_key, request_hash, created_at, updated_at) \
             VALUES (?, ?, ?, ?, 'active', ?, ?, ?, ?) RETURNING id",
        )
        .bind(&sweep.name)
        .bind(&sweep.preset)
        .bind(sweep.spec.to_string())
        .bind(serde_json::to_string(&sweep.varied).expect("strings serialise"))
        .bind(sweep.idempotency.as_ref().map(|i| i.key.clone()))
        .bind(sweep.idempotency.as_ref().map(|i| i.request_hash.clone()))
        .bind(now)
        .bind(now)
        .fetch_one(&mut *tx)
        .await?
        .try_get("id")?;
        let mut cached = 0;
        for (position, case) in sweep.cases.iter().enumerate() {
            // A failed or cancelled row with this key is retired: it keeps its
            // history (and the sweeps that ended with it keep their outcome)
            // under the key `key#id` (`rows::case_from_row` reads the key
            // back), and a new row is queued. Otherwise a new key is queued,
            // done stays done (cached), and queued/running stay as they are
            // (a running case's pending cancellation is withdrawn).
            sqlx::query(
                "UPDATE cases SET case_key = case_key || '#' || id \
                 WHERE case_key = ? AND status IN ('failed', 'cancelled')",
            )
            .bind(&case.key)
            .execute(&mut *tx)
            .await?;
            let row = sqlx::query(
                "INSERT INTO cases (case_key, solver_version, params, status, max_attempts, created_at) \
                 VALUES (?, ?, ?, 'queued', ?, ?) \
                 ON CONFLICT (case_key) DO UPDATE SET \
                   max_attempts = excluded.max_attempts, \
                   cancel_requested = 0 \
                 RETURNING id, status",
            )
            .bind(&case.key)
            .bind(crate::key::SOLVER_VERSION)
            .bind(crate::key::canonical_json(&case.params))
            .bind(i64::from(self.retry.max_attempts))
            .bind(now)
            .fetch_one(&mut *tx)
            .await?;
            let case_id: i64 = row.try_get("id")?;
            let is_done = row.try_get::<String, _>("status")? == "done";
            cached += usize::from(is_done);
            sqlx::query("INSERT INTO sweep_cases (sweep_id, case_id, position, cached) VALUES (?, ?, ?, ?)")
                .bind(id)
                .bind(case_id)
                .bind(position as i64)
                .bind(is_done)
                .execute(&mut *tx)
                .await?;
        }
        let record = Self::sweep_by_id(&mut *tx, id)
            .await?
            .ok_or(StoreError::NotFound)?;
        tx.commit().await?;
        Ok(CreateOutcome::Created {
            sweep: record,
            cached,
        })
    }

    async fn list_sweeps(&self) -> StoreResult<Vec<SweepRecord>> {
        let rows = sqlx::query(&format!("SELECT {SWEEP_COLUMNS} FROM sweeps ORDER BY id"))
            .fetch_all(&self.pool)
            .await?;
        rows.iter().map(sweep_from_row).collect()
    }

    async fn get_sweep(&self, id: i64) -> StoreResult<Option<SweepRecord>> {
        Self::sweep_by_id(&self.pool, id).await
    }

    async fn sweep_status_counts(&self) -> StoreResult<Vec<(i64, String, i64)>> {
        let rows = sqlx::query(
            "SELECT sc.sweep_id, COALESCE(r.outcome, c.status) AS st, COUNT(*) AS n \
             FROM sweep_cases sc JOIN cases c ON c.id = sc.case_id LEFT JOIN results r ON r.case_id = c.id \
             GROUP BY sc.sweep_id, st ORDER BY sc.sweep_id, st",
        )
        .fetch_all(&self.pool)
        .await?;
        rows.iter()
            .map(|r| Ok((r.try_get("sweep_id")?, r.try_get("st")?, r.try_get("n")?)))
            .collect()
    }

    async fn sweep_cases(&self, id: i64) -> StoreResult<Vec<SweepCase>> {
        let rows = sqlx::query(&format!(
            "SELECT sc.position, sc.cached, {CASE_COLUMNS} FROM sweep_cases sc \
             JOIN cases c ON c.id = sc.case_id LEFT JOIN results r ON r.case_id = c.id \
             WHERE sc.sweep_id = ? ORDER BY sc.position"
        ))
        .bind(id)
        .fetch_all(&self.pool)
        .await?;
        rows.iter()
            .map(|r| {
                Ok(SweepCase {
                    position: r.try_get("position")?,
                    cached: r.try_get::<i64, _>("cached")? != 0,
                    case: case_from_row(r)?,
                })
            })
            .collect()
    }

    async fn control_sweep(&self, id: i64, action: SweepAction) -> StoreResult<SweepRecord> {
        let now = now_ms();
        let mut tx = self.pool.begin_with("BEGIN IMMEDIATE").await?;
        let sweep = Self::sweep_by_id(&mut *tx, id)
            .await?
            .ok_or(StoreError::NotFound)?;
        let target = match (action, sweep.state) {
            (_, SweepState::Cancelled) if action != SweepAction::Cancel => {
                return Err(StoreError::Conflict(format!("sweep {id} is cancelled")));
            }
            (SweepAction::Pause, _) => SweepState::Paused,
            (SweepAction::Resume, _) => SweepState::Active,
            (SweepAction::Cancel, _) => SweepState::Cancelled,
        };
        if target != sweep.state {
            sqlx::query("UPDATE sweeps SET state = ?, updated_at = ? WHERE id = ?")
                .bind(target.as_str())
                .bind(now)
                .bind(id)
                .execute(&mut *tx)
                .await?;
        }
        if target == SweepState::Cancelled && sweep.state != SweepState::Cancelled {
            let mine = "c.id IN (SELECT case_id FROM sweep_cases WHERE sweep_id = ?)";
            let queued: Vec<i64> = sqlx::query_scalar(&format!(
                "UPDATE cases AS c SET status = 'cancelled', finished_at = ?, last_error = ? \
                 WHERE c.status = 'queued' AND {mine} AND NOT {WANTED} RETURNING id"
            ))
            .bind(now)
            .bind(format!("cancelled with sweep {id}"))
            .bind(id)
            .fetch_all(&mut *tx)
            .await?;
            for case_id in queued {
                log(
                    &mut *tx,
                    case_id,
                    "info",
                    &format!("cancelled with sweep {id} before it ran"),
                )
                .await?;
            }
            let running: Vec<i64> = sqlx::query_scalar(&format!(
                "UPDATE cases AS c SET cancel_requested = 1 \
                 WHERE c.status = 'running' AND {mine} AND NOT {WANTED} RETURNING id"
            ))
            .bind(id)
            .fetch_all(&mut *tx)
            .await?;
            for case_id in running {
                log(
                    &mut *tx,
                    case_id,
                    "info",
                    &format!("cancel requested with sweep {id}; stops at its next heartbeat"),
                )
                .await?;
            }
        }
        let record = Self::sweep_by_id(&mut *tx, id)
            .await?
            .ok_or(StoreError::NotFound)?;
        tx.commit().await?;
        Ok(record)
    }

    async fn get_case(&self, id: i64) -> StoreResult<Option<CaseRecord>> {
        let row = sqlx::query(&format!(
            "SELECT {CASE_COLUMNS} FROM cases c LEFT JOIN results r ON r.case_id = c.id WHERE c.id = ?"
        ))
        .bind(id)
        .fetch_optional(&self.pool)
        .await?;
        row.map(|r| case_from_row(&r)).transpose()
    }

    async fn case_sweeps(&self, id: i64) -> StoreResult<Vec<i64>> {
        Ok(
            sqlx::query_scalar("SELECT sweep_id FROM sweep_cases WHERE case_id = ? ORDER BY sweep_id")
                .bind(id)
                .fetch_all(&self.pool)
                .await?,
        )
    }

    async fn case_series_json(&self, id: i64) -> StoreResult<Option<String>> {
        Ok(sqlx::query_scalar("SELECT series FROM results WHERE case_id = ?")
            .bind(id)
            .fetch_optional(&self.pool)
            .await?)
    }

    async fn case_frames_json(&self, id: i64) -> StoreResult<Option<String>> {
        Ok(sqlx::query_scalar("SELECT frames FROM results WHERE case_id = ?")
            .bind(id)
            .fetch_optional(&self.pool)
            .await?)
    }

    async fn case_logs(&self, id: i64) -> StoreResult<Vec<LogLine>> {
        let rows = sqlx::query("SELECT at, level, message FROM case_logs WHERE case_id = ? ORDER BY id")
            .bind(id)
            .fetch_all(&self.pool)
            .await?;
        rows.iter()
            .map(|r| {
                Ok(LogLine {
                    at: r.try_get("at")?,
                    level: r.try_get("level")?,
                    message: r.try_get("message")?,
                })
            })
            .collect()
    }

    async fn append_log(&self, case_id: i64, level: &str, message: &str) -> StoreResult<()> {
        log(&self.pool, case_id, level, message).await
    }

    async fn requeue_expired(&self) -> StoreResult<usize> {
        let now = now_ms();
        // Cheap read first: the write lock only when there is work.
        let any: Option<i64> = sqlx::query_scalar(
            "SELECT id FROM cases WHERE status = 'running' AND lease_expires_at < ? LIMIT 1",
        )
        .bind(now)
        .fetch_optional(&self.pool)
        .await?;
        if any.is_none() {
            return Ok(0);
        }
        let mut tx = self.pool.begin_with("BEGIN IMMEDIATE").await?;
        let rows = sqlx::query(
            "SELECT id, attempts, max_attempts, lease_owner, fence, cancel_requested FROM cases \
             WHERE status = 'running' AND lease_expires_at < ?",
        )
        .bind(now)
        .fetch_all(&mut *tx)
        .await?;
        for row in &rows {
            let id: i64 = row.try_get("id")?;
            let attempts = row.try_get::<i64, _>("attempts")? as u32;
            let max_attempts = row.try_get::<i64, _>("max_attempts")? as u32;
            let owner: Option<String> = row.try_get("lease_owner")?;
            let fence: i64 = row.try_get("fence")?;
            let owner = owner.unwrap_or_default();
            if row.try_get::<i64, _>("cancel_requested")? != 0 {
                // Nobody wants it any more: no retry.
                sqlx::query(
                    "UPDATE cases SET status = 'cancelled', finished_at = ?, last_error = 'cancelled', \
                     lease_owner = NULL, lease_expires_at = NULL, cancel_requested = 0 WHERE id = ? AND fence = ?",
                )
                .bind(now)
                .bind(id)
                .bind(fence)
                .execute(&mut *tx)
                .await?;
                log(
                    &mut *tx,
                    id,
                    "info",
                    &format!("lease of worker {owner} expired after a cancel request: cancelled"),
                )
                .await?;
            } else if attempts >= max_attempts {
                let reason =
                    format!("lease expired on attempt {attempts} of {max_attempts} (worker {owner} lost)");
                sqlx::query(
                    "UPDATE cases SET status = 'failed', last_error = ?, finished_at = ?, lease_owner = NULL, \
                     lease_expires_at = NULL WHERE id = ? AND fence = ?",
                )
                .bind(&reason)
                .bind(now)
                .bind(id)
                .bind(fence)
                .execute(&mut *tx)
                .await?;
                log(&mut *tx, id, "error", &format!("failed: {reason}")).await?;
                tracing::warn!(case_id = id, %owner, "lease expired, out of attempts: failed");
            } else {
                let after = self.retry.backoff(attempts);
                let reason = format!("lease of worker {owner} expired on attempt {attempts}");
                sqlx::query(
                    "UPDATE cases SET status = 'queued', last_error = ?, not_before = ?, lease_owner = NULL, \
                     lease_expires_at = NULL, progress = 0, progress_detail = NULL WHERE id = ? AND fence = ?",
                )
                .bind(&reason)
                .bind(now + ms(after))
                .bind(id)
                .bind(fence)
                .execute(&mut *tx)
                .await?;
                log(
                    &mut *tx,
                    id,
                    "warn",
                    &format!("{reason}; queued again in {:.1} s", after.as_secs_f64()),
                )
                .await?;
                tracing::warn!(case_id = id, %owner, "lease expired: case queued again");
            }
        }
        tx.commit().await?;
        Ok(rows.len())
    }

    async fn claim(&self, owner: &str, lease: Duration) -> StoreResult<Option<Claim>> {
        let now = now_ms();
        let row = sqlx::query(
            "UPDATE cases SET status = 'running', lease_owner = ?1, lease_expires_at = ?2, fence = fence + 1, \
               attempts = attempts + 1, started_at = ?3, progress = 0, progress_detail = NULL, cancel_requested = 0 \
             WHERE status = 'queued' AND id = ( \
               SELECT c.id FROM cases c WHERE c.status = 'queued' AND c.not_before <= ?3 \
                 AND EXISTS (SELECT 1 FROM sweep_cases sc JOIN sweeps s ON s.id = sc.sweep_id \
                             WHERE sc.case_id = c.id AND s.state = 'active') \
               ORDER BY c.id LIMIT 1) \
             RETURNING id, case_key, params, fence, attempts",
        )
        .bind(owner)
        .bind(now + ms(lease))
        .bind(now)
        .fetch_optional(&self.pool)
        .await?;
        let Some(row) = row else { return Ok(None) };
        let claim = Claim {
            lease: Lease {
                case_id: row.try_get("id")?,
                owner: owner.to_string(),
                fence: row.try_get("fence")?,
            },
            key: row.try_get("case_key")?,
            params: json(&row.try_get::<String, _>("params")?, "case params")?,
            attempt: row.try_get::<i64, _>("attempts")? as u32,
        };
        log(
            &self.pool,
            claim.lease.case_id,
            "info",
            &format!(
                "claimed by {owner} (attempt {}, fence {})",
                claim.attempt, claim.lease.fence
            ),
        )
        .await?;
        Ok(Some(claim))
    }

    async fn heartbeat(
        &self,
        lease: &Lease,
        progress: Option<&Progress>,
        extend: Duration,
    ) -> StoreResult<Heartbeat> {
        let now = now_ms();
        let detail = progress.map(|p| serde_json::to_string(p).expect("progress serialises"));
        let cancel: Option<i64> = sqlx::query_scalar(
            "UPDATE cases SET lease_expires_at = ?, progress = COALESCE(?, progress), \
               progress_detail = COALESCE(?, progress_detail) \
             WHERE id = ? AND lease_owner = ? AND fence = ? AND status = 'running' RETURNING cancel_requested",
        )
        .bind(now + ms(extend))
        .bind(progress.map(|p| p.fraction.clamp(0.0, 1.0)))
        .bind(detail)
        .bind(lease.case_id)
        .bind(&lease.owner)
        .bind(lease.fence)
        .fetch_optional(&self.pool)
        .await?;
        Ok(match cancel {
            Some(c) => Heartbeat::Held { cancel: c != 0 },
            None => Heartbeat::Lost,
        })
    }

    async fn complete(&self, lease: &Lease, report: &CaseReport) -> StoreResult<bool> {
        let stored = StoredResult::new(report, &lease.owner)?;
        let now = now_ms();
        let mut tx = self.pool.begin_with("BEGIN IMMEDIATE").await?;
        let updated = sqlx::query(
            "UPDATE cases SET status = 'done', finished_at = ?, progress = 1, lease_owner = NULL, \
               lease_expires_at = NULL, cancel_requested = 0, last_error = NULL \
             WHERE id = ? AND lease_owner = ? AND fence = ? AND status = 'running'",
        )
        .bind(now)
        .bind(lease.case_id)
        .bind(&lease.owner)
        .bind(lease.fence)
        .execute(&mut *tx)
        .await?
        .rows_affected();
        if updated == 0 {
            tx.rollback().await?;
            return Ok(false);
        }
        sqlx::query(
            "INSERT INTO results (case_id, outcome, reason, inversion, summary, series, frames, wall_time, worker, \
             fence, created_at) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
        )
        .bind(lease.case_id)
        .bind(&stored.outcome)
        .bind(&report.reason)
        .bind(&stored.inversion)
        .bind(&stored.summary)
        .bind(&stored.series)
        .bind(&stored.frames)
        .bind(report.stats.wall_time)
        .bind(&lease.owner)
        .bind(lease.fence)
        .bind(now)
        .execute(&mut *tx)
        .await?;
        log(&mut *tx, lease.case_id, "info", &stored.message).await?;
        tx.commit().await?;
        Ok(true)
    }

    async fn fail_attempt(&self, lease: &Lease, reason: &str) -> StoreResult<FailOutcome> {
        let now = now_ms();
        let mut tx = self.pool.begin_with("BEGIN IMMEDIATE").await?;
        let row = sqlx::query(
            "SELECT attempts, max_attempts FROM cases \
             WHERE id = ? AND lease_owner = ? AND fence = ? AND status = 'running'",
        )
        .bind(lease.case_id)
        .bind(&lease.owner)
        .bind(lease.fence)
        .fetch_optional(&mut *tx)
        .await?;
        let Some(row) = row else {
            tx.rollback().await?;
            return Ok(FailOutcome::Lost);
        };
        let attempts = row.try_get::<i64, _>("attempts")? as u32;
        let max_attempts = row.try_get::<i64, _>("max_attempts")? as u32;
        let outcome = if attempts >= max_attempts {
            sqlx::query(
                "UPDATE cases SET status = 'failed', last_error = ?, finished_at = ?, lease_owner = NULL, \
                 lease_expires_at = NULL WHERE id = ?",
            )
            .bind(format!("{reason} (attempt {attempts} of {max_attempts})"))
            .bind(now)
            .bind(lease.case_id)
            .execute(&mut *tx)
            .await?;
            log(
                &mut *tx,
                lease.case_id,
                "error",
                &format!("failed after {attempts} attempts: {reason}"),
            )
            .await?;
            FailOutcome::Failed
        } else {
            let after = self.retry.backoff(attempts);
            sqlx::query(
                "UPDATE cases SET status = 'queued', last_error = ?, not_before = ?, lease_owner = NULL, \
                 lease_expires_at = NULL, progress = 0, progress_detail = NULL WHERE id = ?",
            )
            .bind(reason)
            .bind(now + ms(after))
            .bind(lease.case_id)
            .execute(&mut *tx)
            .await?;
            log(
                &mut *tx,
                lease.case_id,
                "warn",
                &format!(
                    "attempt {attempts} failed: {reason}; retry in {:.1} s",
                    after.as_secs_f64()
                ),
            )
            .await?;
            FailOutcome::Retry { after }
        };
        tx.commit().await?;
        Ok(outcome)
    }

    async fn release(&self, lease: &Lease) -> StoreResult<bool> {
        let mut tx = self.pool.begin_with("BEGIN IMMEDIATE").await?;
        let n = sqlx::query(
            "UPDATE cases SET status = 'queued', attempts = MAX(attempts - 1, 0), not_before = 0, \
               lease_owner = NULL, lease_expires_at = NULL, progress = 0, progress_detail = NULL \
             WHERE id = ? AND lease_owner = ? AND fence = ? AND status = 'running'",
        )
        .bind(lease.case_id)
        .bind(&lease.owner)
        .bind(lease.fence)
        .execute(&mut *tx)
        .await?
        .rows_affected();
        if n > 0 {
            log(
                &mut *tx,
                lease.case_id,
                "info",
                &format!("released by {} (shutting down)", lease.owner),
            )
            .await?;
        }
        tx.commit().await?;
        Ok(n > 0)
    }

    async fn finish_cancelled(&self, lease: &Lease) -> StoreResult<bool> {
        let now = now_ms();
        let mut tx = self.pool.begin_with("BEGIN IMMEDIATE").await?;
        let status: Option<String> = sqlx::query_scalar(
            "UPDATE cases SET \
               status = CASE WHEN cancel_requested = 1 THEN 'cancelled' ELSE 'queued' END, \
               attempts = CASE WHEN cancel_requested = 1 THEN attempts ELSE MAX(attempts - 1, 0) END, \
               finished_at = CASE WHEN cancel_requested = 1 THEN ? ELSE NULL END, \
               last_error = CASE WHEN cancel_requested = 1 THEN 'cancelled while running' ELSE last_error END, \
               lease_owner = NULL, lease_expires_at = NULL, cancel_requested = 0 \
             WHERE id = ? AND lease_owner = ? AND fence = ? AND status = 'running' RETURNING status",
        )
        .bind(now)
        .bind(lease.case_id)
        .bind(&lease.owner)
        .bind(lease.fence)
        .fetch_optional(&mut *tx)
        .await?;
        if let Some(status) = &status {
            let message = if status == CaseState::Cancelled.as_str() {
                format!("cancelled while running on {}", lease.owner)
            } else {
                "stopped for a cancellation that was withdrawn; queued again".to_string()
            };
            log(&mut *tx, lease.case_id, "info", &message).await?;
        }
        tx.commit().await?;
        Ok(status.is_some())
    }

    async fn status_counts(&self) -> StoreResult<StatusCounts> {
        let rows = sqlx::query(
            "SELECT COALESCE(r.outcome, c.status) AS st, COUNT(*) AS n FROM cases c \
             LEFT JOIN results r ON r.case_id = c.id GROUP BY st ORDER BY st",
        )
        .fetch_all(&self.pool)
        .await?;
        rows.iter()
            .map(|r| Ok((r.try_get("st")?, r.try_get("n")?)))
            .collect()
    }

    async fn queue_depth(&self) -> StoreResult<i64> {
        Ok(sqlx::query_scalar(
            "SELECT COUNT(*) FROM cases c WHERE c.status = 'queued' AND EXISTS (SELECT 1 FROM sweep_cases sc \
             JOIN sweeps s ON s.id = sc.sweep_id WHERE sc.case_id = c.id AND s.state = 'active')",
        )
        .fetch_one(&self.pool)
        .await?)
    }

    /// Closes every connection (checkpointing the WAL).
    async fn close(&self) {
        self.pool.close().await;
    }
}
