//! Leases: a case handed to one worker, heartbeats, and every way a lease
//! ends (a result, a failure, a release, a cancellation, expiry).
use super::*;
use sqlx::any::{AnyArguments, AnyRow};
use sqlx::query::Query;

/// The caller's lease is the case's current one: `$1` case, `$2` owner, `$3`
/// fence (bound by [`SqlStore::on_lease`]).
const HELD: &str = "id = $1 AND lease_owner = $2 AND fence = $3 AND status = 'running'";
/// One fewer attempt (a run given back is not counted).
const UNCOUNTED: &str = "CASE WHEN attempts > 0 THEN attempts - 1 ELSE 0 END";
/// Ends a lease with the case failed: `$1` reason, `$2` time, `$3` case, `$4` fence.
const FAIL: &str = "UPDATE cases SET status = 'failed', last_error = $1, finished_at = $2, lease_owner = NULL, \
    lease_expires_at = NULL WHERE id = $3 AND fence = $4";
/// Ends a lease with the case queued again: `$1` reason, `$2` not before, `$3` case, `$4` fence.
const RETRY: &str = "UPDATE cases SET status = 'queued', last_error = $1, not_before = $2, lease_owner = NULL, \
    lease_expires_at = NULL, progress = 0, progress_detail = NULL WHERE id = $3 AND fence = $4";

/// Claims the oldest queued case of an active sweep whose backoff has passed
/// (`$1` owner, `$2` lease expiry, `$3` now), returning `id, case_key,
/// params, fence, attempts`; `lock` ends the candidate's `SELECT`.
pub(in crate::store) fn claim_statement(lock: &str) -> String {
    format!(
        "UPDATE cases SET status = 'running', lease_owner = $1, lease_expires_at = $2, fence = fence + 1, \
           attempts = attempts + 1, started_at = $3, progress = 0, progress_detail = NULL, cancel_requested = 0 \
         WHERE status = 'queued' AND id = ( \
           SELECT c.id FROM cases c WHERE c.status = 'queued' AND c.not_before <= $3 AND {CLAIMABLE} \
           ORDER BY c.id LIMIT 1{lock}) \
         RETURNING id, case_key, params, fence, attempts"
    )
}

/// `sql` (made around [`claim_statement`]) with the claim's `$1..$3` bound.
pub(in crate::store) fn claim_query<'q>(
    sql: &'q str,
    owner: &'q str,
    lease: Duration,
) -> Query<'q, Any, AnyArguments<'q>> {
    let now = now_ms();
    sqlx::query(sql).bind(owner).bind(now + ms(lease)).bind(now)
}

/// A running case whose lease expired.
struct Expired {
    id: i64,
    attempts: u32,
    max_attempts: u32,
    owner: String,
    fence: i64,
    cancel_requested: bool,
}

impl Expired {
    fn from_row(r: &AnyRow) -> StoreResult<Self> {
        Ok(Self {
            id: r.int("id")?,
            attempts: r.int("attempts")? as u32,
            max_attempts: r.int("max_attempts")? as u32,
            // An expired lease always has an owner; an empty name only shortens the log line.
            owner: r.text_or_null("lease_owner")?.unwrap_or_default(),
            fence: r.int("fence")?,
            // 2 (its sweeps paused) is no cancellation: the lease ends as any other.
            cancel_requested: r.int("cancel_requested")? == 1,
        })
    }
}

impl<B: Backend> SqlStore<B> {
    /// Begins a transaction that reads, then writes ([`Backend::BEGIN`]).
    pub(super) async fn begin(&self) -> StoreResult<Tx> {
        Ok(self.pool.begin_with(B::BEGIN).await?)
    }

    /// Appends a line to a case's log.
    pub(in crate::store) async fn log(
        conn: &mut AnyConnection,
        case_id: i64,
        level: &str,
        message: &str,
    ) -> StoreResult<()> {
        sqlx::query("INSERT INTO case_logs (case_id, at, level, message) VALUES ($1, $2, $3, $4)")
            .bind(case_id)
            .bind(now_ms())
            .bind(level)
            .bind(message)
            .execute(conn)
            .await?;
        Ok(())
    }

    /// `sql` (conditions on [`HELD`]) with the lease bound to `$1..$3`.
    fn on_lease<'q>(sql: &'q str, lease: &'q Lease) -> Query<'q, Any, AnyArguments<'q>> {
        sqlx::query(sql)
            .bind(lease.case_id)
            .bind(&lease.owner)
            .bind(lease.fence)
    }

    /// [`Store::requeue_expired`].
    pub(super) async fn expire_leases(&self) -> StoreResult<usize> {
        let now = now_ms();
        // Cheap read first: the write lock only when there is work.
        let any =
            sqlx::query("SELECT id FROM cases WHERE status = 'running' AND lease_expires_at < $1 LIMIT 1")
                .bind(now)
                .fetch_optional(&self.pool)
                .await?;
        if any.is_none() {
            return Ok(0);
        }
        let mut tx = self.begin().await?;
        let sql = format!(
            "SELECT id, attempts, max_attempts, lease_owner, fence, cancel_requested FROM cases \
             WHERE status = 'running' AND lease_expires_at < $1{}",
            B::SKIP_LOCKED
        );
        let rows = sqlx::query(&sql).bind(now).fetch_all(&mut *tx).await?;
        let mut requeued = false;
        for row in &rows {
            requeued |= self.expire(&mut tx, &Expired::from_row(row)?, now).await?;
        }
        if requeued {
            B::announce(&mut tx).await?;
        }
        tx.commit().await?;
        Ok(rows.len())
    }

    /// Ends an expired lease: cancelled if cancellation was requested, failed
    /// after the last attempt, queued again (true) otherwise.
    async fn expire(&self, conn: &mut AnyConnection, case: &Expired, now: i64) -> StoreResult<bool> {
        let Expired {
            id,
            attempts,
            max_attempts,
            fence,
            ..
        } = *case;
        let owner = &case.owner;
        if case.cancel_requested {
            sqlx::query(
                "UPDATE cases SET status = 'cancelled', finished_at = $1, last_error = 'cancelled', \
                 lease_owner = NULL, lease_expires_at = NULL, cancel_requested = 0 WHERE id = $2 AND fence = $3",
            )
            .bind(now)
            .bind(id)
            .bind(fence)
            .execute(&mut *conn)
            .await?;
            let message = format!("lease of worker {owner} expired after a cancel request: cancelled");
            Self::log(conn, id, "info", &message).await?;
            return Ok(false);
        }
        if attempts >= max_attempts {
            let reason =
                format!("lease expired on attempt {attempts} of {max_attempts} (worker {owner} lost)");
            Self::end_lease(conn, FAIL, &reason, now, id, fence).await?;
            Self::log(conn, id, "error", &format!("failed: {reason}")).await?;
            tracing::warn!(case_id = id, %owner, "lease expired, out of attempts: failed");
            return Ok(false);
        }
        let after = self.retry.backoff(attempts);
        let reason = format!("lease of worker {owner} expired on attempt {attempts}");
        Self::end_lease(conn, RETRY, &reason, now + ms(after), id, fence).await?;
        let message = format!("{reason}; queued again in {:.1} s", after.as_secs_f64());
        Self::log(conn, id, "warn", &message).await?;
        tracing::warn!(case_id = id, %owner, "lease expired: case queued again");
        Ok(true)
    }

    /// Runs [`FAIL`] or [`RETRY`].
    async fn end_lease(
        conn: &mut AnyConnection,
        sql: &str,
        reason: &str,
        at: i64,
        id: i64,
        fence: i64,
    ) -> StoreResult<()> {
        sqlx::query(sql)
            .bind(reason)
            .bind(at)
            .bind(id)
            .bind(fence)
            .execute(conn)
            .await?;
        Ok(())
    }

    /// [`Store::heartbeat`].
    pub(super) async fn extend_lease(
        &self,
        lease: &Lease,
        progress: Option<&Progress>,
        extend: Duration,
    ) -> StoreResult<Heartbeat> {
        let sql = format!(
            "UPDATE cases SET lease_expires_at = $4, progress = COALESCE($5, progress), \
             progress_detail = COALESCE($6, progress_detail) WHERE {HELD} RETURNING cancel_requested"
        );
        let row = Self::on_lease(&sql, lease)
            .bind(now_ms() + ms(extend))
            .bind(progress.map(|p| p.fraction.clamp(0.0, 1.0)))
            .bind(progress.map(|p| serde_json::to_string(p).expect("progress serialises")))
            .fetch_optional(&self.pool)
            .await?;
        Ok(match row {
            Some(r) => Heartbeat::Held {
                cancel: r.int("cancel_requested")? != 0,
            },
            None => Heartbeat::Lost,
        })
    }

    /// [`Store::complete`].
    pub(super) async fn store_result(&self, lease: &Lease, report: &CaseReport) -> StoreResult<bool> {
        let stored = StoredResult::new(report, &lease.owner)?;
        let now = now_ms();
        let mut tx = self.begin().await?;
        let sql = format!(
            "UPDATE cases SET status = 'done', finished_at = $4, progress = 1, lease_owner = NULL, \
             lease_expires_at = NULL, cancel_requested = 0, last_error = NULL WHERE {HELD}"
        );
        let updated = Self::on_lease(&sql, lease).bind(now).execute(&mut *tx).await?;
        if updated.rows_affected() == 0 {
            tx.rollback().await?;
            return Ok(false);
        }
        let choices = sqlx::query(
            "SELECT s.snapshots FROM sweep_cases sc JOIN sweeps s ON s.id = sc.sweep_id WHERE sc.case_id = $1",
        )
        .bind(lease.case_id)
        .fetch_all(&mut *tx)
        .await?;
        let choice = (choices.iter())
            .map(|r| SnapshotChoice::parse(&r.text("snapshots")?))
            .collect::<StoreResult<Vec<_>>>()?
            .into_iter()
            .max()
            .unwrap_or_default();
        sqlx::query(
            "INSERT INTO results (case_id, outcome, reason, inversion, summary, series_packed, snapshots_packed, \
             wall_time, worker, fence, created_at) VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11)",
        )
        .bind(lease.case_id)
        .bind(&stored.outcome)
        .bind(&report.reason)
        .bind(&stored.inversion)
        .bind(&stored.summary)
        .bind(&stored.series)
        .bind(packed_snapshots(&report.snapshots, choice))
        .bind(report.stats.wall_time)
        .bind(&lease.owner)
        .bind(lease.fence)
        .bind(now)
        .execute(&mut *tx)
        .await?;
        Self::log(&mut tx, lease.case_id, "info", &stored.message).await?;
        tx.commit().await?;
        Ok(true)
    }

    /// [`Store::fail_attempt`].
    pub(super) async fn retry_or_fail(&self, lease: &Lease, reason: &str) -> StoreResult<FailOutcome> {
        let now = now_ms();
        let mut tx = self.begin().await?;
        let sql = format!(
            "SELECT attempts, max_attempts FROM cases WHERE {HELD}{}",
            B::FOR_UPDATE
        );
        let Some(row) = Self::on_lease(&sql, lease).fetch_optional(&mut *tx).await? else {
            tx.rollback().await?;
            return Ok(FailOutcome::Lost);
        };
        let (attempts, max_attempts) = (row.int("attempts")? as u32, row.int("max_attempts")? as u32);
        let (id, fence) = (lease.case_id, lease.fence);
        let outcome = if attempts >= max_attempts {
            let last_error = format!("{reason} (attempt {attempts} of {max_attempts})");
            Self::end_lease(&mut tx, FAIL, &last_error, now, id, fence).await?;
            let message = format!("failed after {attempts} attempts: {reason}");
            Self::log(&mut tx, id, "error", &message).await?;
            FailOutcome::Failed
        } else {
            let after = self.retry.backoff(attempts);
            Self::end_lease(&mut tx, RETRY, reason, now + ms(after), id, fence).await?;
            let secs = after.as_secs_f64();
            let message = format!("attempt {attempts} failed: {reason}; retry in {secs:.1} s");
            Self::log(&mut tx, id, "warn", &message).await?;
            FailOutcome::Retry { after }
        };
        tx.commit().await?;
        Ok(outcome)
    }

    /// [`Store::release`].
    pub(super) async fn release_lease(&self, lease: &Lease) -> StoreResult<bool> {
        let mut tx = self.begin().await?;
        let sql = format!(
            "UPDATE cases SET status = 'queued', attempts = {UNCOUNTED}, not_before = 0, lease_owner = NULL, \
             lease_expires_at = NULL, progress = 0, progress_detail = NULL WHERE {HELD}"
        );
        let released = Self::on_lease(&sql, lease)
            .execute(&mut *tx)
            .await?
            .rows_affected()
            > 0;
        if released {
            let message = format!("released by {} (shutting down)", lease.owner);
            Self::log(&mut tx, lease.case_id, "info", &message).await?;
            B::announce(&mut tx).await?;
        }
        tx.commit().await?;
        Ok(released)
    }

    /// [`Store::finish_cancelled`].
    pub(super) async fn end_cancelled(&self, lease: &Lease) -> StoreResult<bool> {
        let mut tx = self.begin().await?;
        let sql = format!(
            "UPDATE cases SET \
               status = CASE WHEN cancel_requested = 1 THEN 'cancelled' ELSE 'queued' END, \
               attempts = CASE WHEN cancel_requested = 1 THEN attempts ELSE {UNCOUNTED} END, \
               finished_at = CASE WHEN cancel_requested = 1 THEN $4 ELSE NULL END, \
               last_error = CASE WHEN cancel_requested = 1 THEN 'cancelled while running' ELSE last_error END, \
               lease_owner = NULL, lease_expires_at = NULL, cancel_requested = 0 \
             WHERE {HELD} RETURNING status"
        );
        let row = Self::on_lease(&sql, lease)
            .bind(now_ms())
            .fetch_optional(&mut *tx)
            .await?;
        let Some(row) = row else {
            tx.rollback().await?;
            return Ok(false);
        };
        let message = if CaseState::parse(&row.text("status")?)? == CaseState::Cancelled {
            format!("cancelled while running on {}", lease.owner)
        } else {
            B::announce(&mut tx).await?;
            "stopped for a pause, or a cancellation since withdrawn; queued again".to_string()
        };
        Self::log(&mut tx, lease.case_id, "info", &message).await?;
        tx.commit().await?;
        Ok(true)
    }
}
