//! Results and what is read about a case: completion under a held lease,
//! the case record, its series, frames and logs, and status counts.
use super::*;

pub(super) async fn complete(pool: &PgPool, lease: &Lease, report: &CaseReport) -> StoreResult<bool> {
    let stored = StoredResult::new(report, &lease.owner)?;
    let now = now_ms();
    let mut tx = pool.begin().await?;
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

pub(super) async fn get_case(pool: &PgPool, id: i64) -> StoreResult<Option<CaseRecord>> {
    let row = sqlx::query(&format!(
        "SELECT {CASE_COLUMNS} FROM cases c LEFT JOIN results r ON r.case_id = c.id WHERE c.id = $1"
    ))
    .bind(id)
    .fetch_optional(pool)
    .await?;
    row.map(|r| case_from_row(&r)).transpose()
}

pub(super) async fn case_sweeps(pool: &PgPool, id: i64) -> StoreResult<Vec<i64>> {
    Ok(
        sqlx::query_scalar("SELECT sweep_id FROM sweep_cases WHERE case_id = $1 ORDER BY sweep_id")
            .bind(id)
            .fetch_all(pool)
            .await?,
    )
}

pub(super) async fn series_json(pool: &PgPool, id: i64) -> StoreResult<Option<String>> {
    Ok(
        sqlx::query_scalar("SELECT series FROM results WHERE case_id = $1")
            .bind(id)
            .fetch_optional(pool)
            .await?,
    )
}

pub(super) async fn frames_json(pool: &PgPool, id: i64) -> StoreResult<Option<String>> {
    Ok(
        sqlx::query_scalar("SELECT frames FROM results WHERE case_id = $1")
            .bind(id)
            .fetch_optional(pool)
            .await?,
    )
}

pub(super) async fn logs(pool: &PgPool, id: i64) -> StoreResult<Vec<LogLine>> {
    let rows = sqlx::query("SELECT at, level, message FROM case_logs WHERE case_id = $1 ORDER BY id")
        .bind(id)
        .fetch_all(pool)
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

pub(super) async fn status_counts(pool: &PgPool) -> StoreResult<StatusCounts> {
    let rows = sqlx::query(
        "SELECT COALESCE(r.outcome, c.status) AS st, COUNT(*) AS n FROM cases c \
         LEFT JOIN results r ON r.case_id = c.id GROUP BY st ORDER BY st",
    )
    .fetch_all(pool)
    .await?;
    rows.iter()
        .map(|r| Ok((r.try_get("st")?, r.try_get("n")?)))
        .collect()
}

#[cfg(test)]
mod tests {
    use crate::store::testing;

    #[tokio::test]
    async fn results_on_postgres() {
        if let Some(db) = testing::postgres("results").await {
            testing::results(&db.store).await;
            db.drop_database().await;
        }
    }
}
