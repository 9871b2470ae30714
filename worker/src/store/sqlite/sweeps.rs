//! Sweeps: creation (idempotent, sharing cases by key), listing, per-sweep counts
//! and pause/resume/cancel.
use super::*;

pub(super) async fn create(
    pool: &SqlitePool,
    retry: &RetryPolicy,
    sweep: NewSweep,
) -> StoreResult<CreateOutcome> {
    let now = now_ms();
    let mut tx = pool.begin_with("BEGIN IMMEDIATE").await?;
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
            let sweep = by_id(&mut *tx, id).await?.ok_or(StoreError::NotFound)?;
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
    for (position, case) in sweep.queue_order() {
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
        .bind(i64::from(retry.max_attempts))
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
    let record = by_id(&mut *tx, id).await?.ok_or(StoreError::NotFound)?;
    tx.commit().await?;
    Ok(CreateOutcome::Created {
        sweep: record,
        cached,
    })
}

pub(super) async fn list(pool: &SqlitePool, limit: i64, offset: i64) -> StoreResult<Vec<SweepRecord>> {
    let rows = sqlx::query(&format!(
        "SELECT {SWEEP_COLUMNS} FROM sweeps ORDER BY id LIMIT ?1 OFFSET ?2"
    ))
    .bind(limit)
    .bind(offset)
    .fetch_all(pool)
    .await?;
    rows.iter().map(sweep_from_row).collect()
}

pub(super) async fn count(pool: &SqlitePool) -> StoreResult<i64> {
    Ok(sqlx::query("SELECT COUNT(*) AS n FROM sweeps")
        .fetch_one(pool)
        .await?
        .try_get("n")?)
}

pub(super) async fn get(pool: &SqlitePool, id: i64) -> StoreResult<Option<SweepRecord>> {
    by_id(pool, id).await
}

pub(super) async fn status_counts(
    pool: &SqlitePool,
    ids: RangeInclusive<i64>,
) -> StoreResult<Vec<(i64, String, i64)>> {
    let rows = sqlx::query(
        "SELECT sc.sweep_id, COALESCE(r.outcome, c.status) AS st, COUNT(*) AS n \
         FROM sweep_cases sc JOIN cases c ON c.id = sc.case_id LEFT JOIN results r ON r.case_id = c.id \
         WHERE sc.sweep_id BETWEEN ?1 AND ?2 GROUP BY sc.sweep_id, st ORDER BY sc.sweep_id, st",
    )
    .bind(*ids.start())
    .bind(*ids.end())
    .fetch_all(pool)
    .await?;
    rows.iter()
        .map(|r| Ok((r.try_get("sweep_id")?, r.try_get("st")?, r.try_get("n")?)))
        .collect()
}

pub(super) async fn cases(pool: &SqlitePool, id: i64) -> StoreResult<Vec<SweepCase>> {
    let rows = sqlx::query(&format!(
        "SELECT sc.position, sc.cached, {CASE_COLUMNS} FROM sweep_cases sc \
         JOIN cases c ON c.id = sc.case_id LEFT JOIN results r ON r.case_id = c.id \
         WHERE sc.sweep_id = ? ORDER BY sc.position"
    ))
    .bind(id)
    .fetch_all(pool)
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

pub(super) async fn control(pool: &SqlitePool, id: i64, action: SweepAction) -> StoreResult<SweepRecord> {
    let now = now_ms();
    let mut tx = pool.begin_with("BEGIN IMMEDIATE").await?;
    let sweep = by_id(&mut *tx, id).await?.ok_or(StoreError::NotFound)?;
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
    let record = by_id(&mut *tx, id).await?.ok_or(StoreError::NotFound)?;
    tx.commit().await?;
    Ok(record)
}

/// The sweep with this id, read through any executor (pool or transaction).
pub(super) async fn by_id<'e, E>(exec: E, id: i64) -> StoreResult<Option<SweepRecord>>
where
    E: sqlx::Executor<'e, Database = sqlx::Sqlite>,
{
    let row = sqlx::query(&format!("SELECT {SWEEP_COLUMNS} FROM sweeps WHERE id = ?"))
        .bind(id)
        .fetch_optional(exec)
        .await?;
    row.map(|r| sweep_from_row(&r)).transpose()
}

#[cfg(test)]
mod tests {
    use crate::store::testing;

    #[tokio::test]
    async fn sweeps_on_sqlite() {
        let (store, _dir) = testing::sqlite().await;
        testing::sweeps(&store).await;
    }
}
