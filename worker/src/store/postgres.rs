//! The PostgreSQL implementation of [`Store`]: one database shared by a server
//! and workers on any number of hosts.
//!
//! The claim is one `UPDATE ... WHERE id = (SELECT ... FOR UPDATE SKIP LOCKED)`
//! statement, so concurrent claimers skip each other's rows instead of
//! queueing on them. Read-then-write transactions lock what they read (`FOR
//! UPDATE`); sweep creation takes a transaction-level advisory lock so that
//! two submissions with one `Idempotency-Key` cannot both insert. Whatever
//! makes a case claimable (a new sweep, a resumed one, a released or requeued
//! case) sends `NOTIFY` on [`CHANNEL`] inside its transaction; idle workers
//! `LISTEN` and wake at once, and fall back to polling every
//! [`FALLBACK_POLL`] for what no notification announces (backoff expiries,
//! a lost listener connection).
use super::rows::*;
use super::*;
use sqlx::Row;
use sqlx::postgres::{PgConnectOptions, PgListener, PgPool, PgPoolOptions, PgRow};
use std::str::FromStr;
use std::sync::Arc;
use tokio::sync::Notify;

/// The notification channel of claimable work.
pub const CHANNEL: &str = "knotsweep_queue";
/// Longest idle wait without a notification.
pub const FALLBACK_POLL: Duration = Duration::from_secs(5);
/// Advisory lock key serialising sweep creation (any constant; "ksweep").
const CREATE_LOCK: i64 = 0x6b73_7765_6570;

/// The queue and results in a PostgreSQL database.
#[derive(Clone, Debug)]
pub struct PgStore {
    pool: PgPool,
    retry: RetryPolicy,
    wake: Arc<Notify>,
    listener: Arc<tokio::task::JoinHandle<()>>,
}

impl Drop for PgStore {
    fn drop(&mut self) {
        if Arc::strong_count(&self.listener) == 1 {
            self.listener.abort();
        }
    }
}

impl Columns for PgRow {
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
    E: sqlx::Executor<'e, Database = sqlx::Postgres>,
{
    sqlx::query("INSERT INTO case_logs (case_id, at, level, message) VALUES ($1, $2, $3, $4)")
        .bind(case_id)
        .bind(now_ms())
        .bind(level)
        .bind(message)
        .execute(exec)
        .await?;
    Ok(())
}

/// Announces claimable work (delivered when the transaction commits).
async fn notify<'e, E>(exec: E) -> StoreResult<()>
where
    E: sqlx::Executor<'e, Database = sqlx::Postgres>,
{
    sqlx::query(&format!("NOTIFY {CHANNEL}")).execute(exec).await?;
    Ok(())
}

fn ms(d: Duration) -> i64 {
    d.as_millis().min(i64::MAX as u128) as i64
}

impl PgStore {
    /// Connects to `url` (`postgres://user@host:port/db`), runs the
    /// migrations (under sqlx's advisory lock, so several processes may start
    /// at once) and starts listening for work.
    pub async fn connect(url: &str, options: StoreOptions) -> StoreResult<Self> {
        let connect = PgConnectOptions::from_str(url)?;
        let server = format!("{}:{}", connect.get_host(), connect.get_port());
        let pool = PgPoolOptions::new()
            .max_connections(options.max_connections.max(2))
            .acquire_timeout(Duration::from_secs(30))
            .connect_with(connect)
            .await
            .map_err(|e| match e {
                sqlx::Error::Io(_) | sqlx::Error::PoolTimedOut | sqlx::Error::Tls(_) => {
                    StoreError::Unreachable(format!("cannot reach PostgreSQL at {server}: {e}"))
                }
                other => StoreError::Database(other),
            })?;
        sqlx::migrate!("../migrations/postgres").run(&pool).await?;
        let wake = Arc::new(Notify::new());
        let listener = tokio::spawn(listen(pool.clone(), wake.clone()));
        Ok(Self {
            pool,
            retry: options.retry,
            wake,
            listener: Arc::new(listener),
        })
    }

    /// The connection pool (for tests and diagnostics).
    pub fn pool(&self) -> &PgPool {
        &self.pool
    }

    async fn sweep_by_id<'e, E>(exec: E, id: i64) -> StoreResult<Option<SweepRecord>>
    where
        E: sqlx::Executor<'e, Database = sqlx::Postgres>,
    {
        let row = sqlx::query(&format!("SELECT {SWEEP_COLUMNS} FROM sweeps WHERE id = $1"))
            .bind(id)
            .fetch_optional(exec)
            .await?;
        row.map(|r| sweep_from_row(&r)).transpose()
    }
}

/// Wakes idle workers on every notification; reconnects after errors.
async fn listen(pool: PgPool, wake: Arc<Notify>) {
    loop {
        let mut listener = match PgListener::connect_with(&pool).await {
            Ok(l) => l,
            Err(e) => {
                tracing::warn!(error = %e, "LISTEN connection failed; retrying");
                tokio::time::sleep(FALLBACK_POLL).await;
                continue;
            }
        };
        if let Err(e) = listener.listen(CHANNEL).await {
            tracing::warn!(error = %e, "LISTEN failed; retrying");
            tokio::time::sleep(FALLBACK_POLL).await;
            continue;
        }
        loop {
            match listener.recv().await {
                Ok(_) => wake.notify_waiters(),
                Err(e) => {
                    tracing::warn!(error = %e, "LISTEN connection lost; reconnecting");
                    // Work may have been announced while we were away.
                    wake.notify_waiters();
                    break;
                }
            }
        }
    }
}

#[async_trait]
impl Store for PgStore {
    async fn create_sweep(&self, sweep: NewSweep) -> StoreResult<CreateOutcome> {
        let now = now_ms();
        let mut tx = self.pool.begin().await?;
        sqlx::query("SELECT pg_advisory_xact_lock($1)")
            .bind(CREATE_LOCK)
            .execute(&mut *tx)
            .await?;
        if let Some(idem) = &sweep.idempotency {
            let found = sqlx::query("SELECT id, request_hash FROM sweeps WHERE idempotency_key = $1")
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
             VALUES ($1, $2, $3, $4, 'active', $5, $6, $7, $7) RETURNING id",
        )
        .bind(&sweep.name)
        .bind(&sweep.preset)
        .bind(sweep.spec.to_string())
        .bind(serde_json::to_string(&sweep.varied).expect("strings serialise"))
        .bind(sweep.idempotency.as_ref().map(|i| i.key.clone()))
        .bind(sweep.idempotency.as_ref().map(|i| i.request_hash.clone()))
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
                "UPDATE cases SET case_key = case_key || '#' || id::text \
                 WHERE case_key = $1 AND status IN ('failed', 'cancelled')",
            )
            .bind(&case.key)
            .execute(&mut *tx)
            .await?;
            let row = sqlx::query(
                "INSERT INTO cases AS c (case_key, solver_version, params, status, max_attempts, created_at) \
                 VALUES ($1, $2, $3, 'queued', $4, $5) \
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
            sqlx::query(
                "INSERT INTO sweep_cases (sweep_id, case_id, position, cached) VALUES ($1, $2, $3, $4)",
            )
            .bind(id)
            .bind(case_id)
            .bind(position as i64)
            .bind(i64::from(is_done))
            .execute(&mut *tx)
            .await?;
        }
        notify(&mut *tx).await?;
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
             WHERE sc.sweep_id = $1 ORDER BY sc.position"
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
        let mut tx = self.pool.begin().await?;
        let row = sqlx::query(&format!(
            "SELECT {SWEEP_COLUMNS} FROM sweeps WHERE id = $1 FOR UPDATE"
        ))
        .bind(id)
        .fetch_optional(&mut *tx)
        .await?;
        let sweep = row
            .map(|r| sweep_from_row(&r))
            .transpose()?
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
            sqlx::query("UPDATE sweeps SET state = $1, updated_at = $2 WHERE id = $3")
                .bind(target.as_str())
                .bind(now)
                .bind(id)
                .execute(&mut *tx)
                .await?;
            if target == SweepState::Active {
                notify(&mut *tx).await?;
            }
        }
        if target == SweepState::Cancelled && sweep.state != SweepState::Cancelled {
            let mine = "c.id IN (SELECT case_id FROM sweep_cases WHERE sweep_id = $1)";
            let queued: Vec<i64> = sqlx::query_scalar(&format!(
                "UPDATE cases AS c SET status = 'cancelled', finished_at = $2, last_error = $3 \
                 WHERE c.status = 'queued' AND {mine} AND NOT {WANTED} RETURNING id"
            ))
            .bind(id)
            .bind(now)
            .bind(format!("cancelled with sweep {id}"))
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
            "SELECT {CASE_COLUMNS} FROM cases c LEFT JOIN results r ON r.case_id = c.id WHERE c.id = $1"
        ))
        .bind(id)
        .fetch_optional(&self.pool)
        .await?;
        row.map(|r| case_from_row(&r)).transpose()
    }

    async fn case_sweeps(&self, id: i64) -> StoreResult<Vec<i64>> {
        Ok(
            sqlx::query_scalar("SELECT sweep_id FROM sweep_cases WHERE case_id = $1 ORDER BY sweep_id")
                .bind(id)
                .fetch_all(&self.pool)
                .await?,
        )
    }

    async fn case_series_json(&self, id: i64) -> StoreResult<Option<String>> {
        Ok(
            sqlx::query_scalar("SELECT series FROM results WHERE case_id = $1")
                .bind(id)
                .fetch_optional(&self.pool)
                .await?,
        )
    }

    async fn case_frames_json(&self, id: i64) -> StoreResult<Option<String>> {
        Ok(
            sqlx::query_scalar("SELECT frames FROM results WHERE case_id = $1")
                .bind(id)
                .fetch_optional(&self.pool)
                .await?,
        )
    }

    async fn case_logs(&self, id: i64) -> StoreResult<Vec<LogLine>> {
        let rows = sqlx::query("SELECT at, level, message FROM case_logs WHERE case_id = $1 ORDER BY id")
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
        let any: Option<i64> = sqlx::query_scalar(
            "SELECT id FROM cases WHERE status = 'running' AND lease_expires_at < $1 LIMIT 1",
        )
        .bind(now)
        .fetch_optional(&self.pool)
        .await?;
        if any.is_none() {
            return Ok(0);
        }
        let mut tx = self.pool.begin().await?;
        // Rows another process is requeueing right now are skipped, not waited for.
        let rows = sqlx::query(
            "SELECT id, attempts, max_attempts, lease_owner, fence, cancel_requested FROM cases \
             WHERE status = 'running' AND lease_expires_at < $1 FOR UPDATE SKIP LOCKED",
        )
        .bind(now)
        .fetch_all(&mut *tx)
        .await?;
        let mut requeued = false;
        for row in &rows {
            let id: i64 = row.try_get("id")?;
            let attempts = row.try_get::<i64, _>("attempts")? as u32;
            let max_attempts = row.try_get::<i64, _>("max_attempts")? as u32;
            let owner: Option<String> = row.try_get("lease_owner")?;
            let fence: i64 = row.try_get("fence")?;
            let owner = owner.unwrap_or_default();
            if row.try_get::<i64, _>("cancel_requested")? != 0 {
                sqlx::query(
                    "UPDATE cases SET status = 'cancelled', finished_at = $1, last_error = 'cancelled', \
                     lease_owner = NULL, lease_expires_at = NULL, cancel_requested = 0 WHERE id = $2 AND fence = $3",
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
                    "UPDATE cases SET status = 'failed', last_error = $1, finished_at = $2, lease_owner = NULL, \
                     lease_expires_at = NULL WHERE id = $3 AND fence = $4",
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
                    "UPDATE cases SET status = 'queued', last_error = $1, not_before = $2, lease_owner = NULL, \
                     lease_expires_at = NULL, progress = 0, progress_detail = NULL WHERE id = $3 AND fence = $4",
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
                requeued = true;
            }
        }
        if requeued {
            notify(&mut *tx).await?;
        }
        tx.commit().await?;
        Ok(rows.len())
    }

    async fn claim(&self, owner: &str, lease: Duration) -> StoreResult<Option<Claim>> {
        let now = now_ms();
        // One statement claims and logs. Its commit need not wait for the WAL
        // flush: a claim lost in a server crash leaves the case queued, and
        // the worker's next heartbeat finds the lease gone.
        let mut tx = self.pool.begin().await?;
        sqlx::query("SET LOCAL synchronous_commit = off")
            .execute(&mut *tx)
            .await?;
        let row = sqlx::query(
            "WITH claimed AS ( \
               UPDATE cases SET status = 'running', lease_owner = $1, lease_expires_at = $2, fence = fence + 1, \
                 attempts = attempts + 1, started_at = $3, progress = 0, progress_detail = NULL, cancel_requested = 0 \
               WHERE id = ( \
                 SELECT c.id FROM cases c WHERE c.status = 'queued' AND c.not_before <= $3 \
                   AND EXISTS (SELECT 1 FROM sweep_cases sc JOIN sweeps s ON s.id = sc.sweep_id \
                               WHERE sc.case_id = c.id AND s.state = 'active') \
                 ORDER BY c.id LIMIT 1 FOR UPDATE SKIP LOCKED) \
               RETURNING id, case_key, params, fence, attempts), \
             logged AS ( \
               INSERT INTO case_logs (case_id, at, level, message) \
               SELECT id, $3, 'info', 'claimed by ' || $1 || ' (attempt ' || attempts || ', fence ' || fence || ')' \
               FROM claimed) \
             SELECT id, case_key, params, fence, attempts FROM claimed",
        )
        .bind(owner)
        .bind(now + ms(lease))
        .bind(now)
        .fetch_optional(&mut *tx)
        .await?;
        tx.commit().await?;
        let Some(row) = row else { return Ok(None) };
        Ok(Some(Claim {
            lease: Lease {
                case_id: row.try_get("id")?,
                owner: owner.to_string(),
                fence: row.try_get("fence")?,
            },
            key: row.try_get("case_key")?,
            params: json(&row.try_get::<String, _>("params")?, "case params")?,
            attempt: row.try_get::<i64, _>("attempts")? as u32,
        }))
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
            "UPDATE cases SET lease_expires_at = $1, progress = COALESCE($2, progress), \
               progress_detail = COALESCE($3, progress_detail) \
             WHERE id = $4 AND lease_owner = $5 AND fence = $6 AND status = 'running' RETURNING cancel_requested",
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
        let mut tx = self.pool.begin().await?;
        let updated = sqlx::query(
            "UPDATE cases SET status = 'done', finished_at = $1, progress = 1, lease_owner = NULL, \
               lease_expires_at = NULL, cancel_requested = 0, last_error = NULL \
             WHERE id = $2 AND lease_owner = $3 AND fence = $4 AND status = 'running'",
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
             fence, created_at) VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11)",
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
        let mut tx = self.pool.begin().await?;
        let row = sqlx::query(
            "SELECT attempts, max_attempts FROM cases \
             WHERE id = $1 AND lease_owner = $2 AND fence = $3 AND status = 'running' FOR UPDATE",
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
                "UPDATE cases SET status = 'failed', last_error = $1, finished_at = $2, lease_owner = NULL, \
                 lease_expires_at = NULL WHERE id = $3",
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
                "UPDATE cases SET status = 'queued', last_error = $1, not_before = $2, lease_owner = NULL, \
                 lease_expires_at = NULL, progress = 0, progress_detail = NULL WHERE id = $3",
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
        let mut tx = self.pool.begin().await?;
        let n = sqlx::query(
            "UPDATE cases SET status = 'queued', attempts = GREATEST(attempts - 1, 0), not_before = 0, \
               lease_owner = NULL, lease_expires_at = NULL, progress = 0, progress_detail = NULL \
             WHERE id = $1 AND lease_owner = $2 AND fence = $3 AND status = 'running'",
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
            notify(&mut *tx).await?;
        }
        tx.commit().await?;
        Ok(n > 0)
    }

    async fn finish_cancelled(&self, lease: &Lease) -> StoreResult<bool> {
        let now = now_ms();
        let mut tx = self.pool.begin().await?;
        let status: Option<String> = sqlx::query_scalar(
            "UPDATE cases SET \
               status = CASE WHEN cancel_requested = 1 THEN 'cancelled' ELSE 'queued' END, \
               attempts = CASE WHEN cancel_requested = 1 THEN attempts ELSE GREATEST(attempts - 1, 0) END, \
               finished_at = CASE WHEN cancel_requested = 1 THEN $1 ELSE NULL END, \
               last_error = CASE WHEN cancel_requested = 1 THEN 'cancelled while running' ELSE last_error END, \
               lease_owner = NULL, lease_expires_at = NULL, cancel_requested = 0 \
             WHERE id = $2 AND lease_owner = $3 AND fence = $4 AND status = 'running' RETURNING status",
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
                notify(&mut *tx).await?;
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

    /// A notification or [`FALLBACK_POLL`], whichever comes first.
    async fn wait_for_work(&self, _poll: Duration) {
        tokio::select! {
            _ = self.wake.notified() => {}
            _ = tokio::time::sleep(FALLBACK_POLL) => {}
        }
    }

    async fn close(&self) {
        self.listener.abort();
        self.pool.close().await;
    }
}
