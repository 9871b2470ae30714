//! Claims and leases: handing a queued case to one worker, heartbeats, and
//! every way a lease ends other than a result (failure, release, cancellation,
//! expiry).
use super::*;

pub(super) async fn requeue_expired(pool: &SqlitePool, retry: &RetryPolicy) -> StoreResult<usize> {
    let now = now_ms();
    // Cheap read first: the write lock only when there is work.
    let any: Option<i64> =
        sqlx::query_scalar("SELECT id FROM cases WHERE status = 'running' AND lease_expires_at < ? LIMIT 1")
            .bind(now)
            .fetch_optional(pool)
            .await?;
    if any.is_none() {
        return Ok(0);
    }
    let mut tx = pool.begin_with("BEGIN IMMEDIATE").await?;
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
            let after = retry.backoff(attempts);
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

pub(super) async fn claim(pool: &SqlitePool, owner: &str, lease: Duration) -> StoreResult<Option<Claim>> {
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
    .fetch_optional(pool)
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
        pool,
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

pub(super) async fn heartbeat(
    pool: &SqlitePool,
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
    .fetch_optional(pool)
    .await?;
    Ok(match cancel {
        Some(c) => Heartbeat::Held { cancel: c != 0 },
        None => Heartbeat::Lost,
    })
}

pub(super) async fn fail_attempt(
    pool: &SqlitePool,
    retry: &RetryPolicy,
    lease: &Lease,
    reason: &str,
) -> StoreResult<FailOutcome> {
    let now = now_ms();
    let mut tx = pool.begin_with("BEGIN IMMEDIATE").await?;
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
        let after = retry.backoff(attempts);
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

pub(super) async fn release(pool: &SqlitePool, lease: &Lease) -> StoreResult<bool> {
    let mut tx = pool.begin_with("BEGIN IMMEDIATE").await?;
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

pub(super) async fn finish_cancelled(pool: &SqlitePool, lease: &Lease) -> StoreResult<bool> {
    let now = now_ms();
    let mut tx = pool.begin_with("BEGIN IMMEDIATE").await?;
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

pub(super) async fn queue_depth(pool: &SqlitePool) -> StoreResult<i64> {
    Ok(sqlx::query_scalar(
        "SELECT COUNT(*) FROM cases c WHERE c.status = 'queued' AND EXISTS (SELECT 1 FROM sweep_cases sc \
         JOIN sweeps s ON s.id = sc.sweep_id WHERE sc.case_id = c.id AND s.state = 'active')",
    )
    .fetch_one(pool)
    .await?)
}

#[cfg(test)]
mod tests {
    use crate::store::testing;

    #[tokio::test]
    async fn claims_on_sqlite() {
        let (store, _dir) = testing::sqlite().await;
        testing::claims(&store).await;
    }
}
