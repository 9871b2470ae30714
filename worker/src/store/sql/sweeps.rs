//! Sweeps: creation (idempotent, sharing cases by key) and pause, resume and
//! cancel.
use super::*;

impl<B: Backend> SqlStore<B> {
    /// [`Store::create_sweep`].
    pub(super) async fn create(&self, sweep: NewSweep) -> StoreResult<CreateOutcome> {
        let mut tx = self.begin().await?;
        B::serialise_creation(&mut tx).await?;
        if let Some(idem) = &sweep.idempotency {
            if let Some(sweep) = Self::replay(&mut tx, idem).await? {
                tx.commit().await?;
                return Ok(CreateOutcome::Replayed { sweep });
            }
        }
        let now = now_ms();
        let id = sqlx::query(
            "INSERT INTO sweeps (name, preset, spec, varied, state, idempotency_key, request_hash, created_at, \
             updated_at, snapshots) VALUES ($1, $2, $3, $4, 'active', $5, $6, $7, $7, $8) RETURNING id",
        )
        .bind(&sweep.name)
        .bind(&sweep.preset)
        .bind(sweep.spec.to_string())
        .bind(serde_json::to_string(&sweep.varied).expect("strings serialise"))
        .bind(sweep.idempotency.as_ref().map(|i| &i.key))
        .bind(sweep.idempotency.as_ref().map(|i| &i.request_hash))
        .bind(now)
        .bind(sweep.snapshots.as_str())
        .fetch_one(&mut *tx)
        .await?
        .int("id")?;
        let mut cached = 0;
        for (position, case) in sweep.queue_order() {
            let (case_id, done) = self.enqueue(&mut tx, case, now).await?;
            cached += usize::from(done);
            sqlx::query(
                "INSERT INTO sweep_cases (sweep_id, case_id, position, cached, twin_position) \
                 VALUES ($1, $2, $3, $4, $5)",
            )
            .bind(id)
            .bind(case_id)
            .bind(position as i64)
            .bind(i64::from(done))
            .bind(case.twin_position.map(|p| p as i64))
            .execute(&mut *tx)
            .await?;
        }
        B::announce(&mut tx).await?;
        let sweep = Self::sweep(&mut tx, id, "").await?.ok_or(StoreError::NotFound)?;
        tx.commit().await?;
        Ok(CreateOutcome::Created { sweep, cached })
    }

    /// The sweep first created with this idempotency key, if any; `Conflict`
    /// if it came with another request.
    async fn replay(conn: &mut AnyConnection, idem: &Idempotency) -> StoreResult<Option<SweepRecord>> {
        let found = sqlx::query("SELECT id, request_hash FROM sweeps WHERE idempotency_key = $1")
            .bind(&idem.key)
            .fetch_optional(&mut *conn)
            .await?;
        let Some(row) = found else { return Ok(None) }; // a new key: no sweep to replay
        if row.text_or_null("request_hash")?.as_deref() != Some(idem.request_hash.as_str()) {
            return Err(StoreError::Conflict(
                "Idempotency-Key was already used with a different request".to_string(),
            ));
        }
        Self::sweep(conn, row.int("id")?, "").await
    }

    /// Queues `case` unless its key is queued, running or done; returns its
    /// row's id and whether it is done.
    ///
    /// A failed or cancelled row with this key is retired: it keeps its
    /// history (and the sweeps that ended with it keep their outcome) under
    /// the key `key#id` (`rows::case_from_row` reads the key back), and a new
    /// row is queued. Done stays done (cached), and queued or running stay as
    /// they are (a running case's pending cancellation is withdrawn).
    async fn enqueue(&self, conn: &mut AnyConnection, case: &NewCase, now: i64) -> StoreResult<(i64, bool)> {
        sqlx::query(
            "UPDATE cases SET case_key = case_key || '#' || CAST(id AS TEXT) \
             WHERE case_key = $1 AND status IN ('failed', 'cancelled')",
        )
        .bind(&case.key)
        .execute(&mut *conn)
        .await?;
        let row = sqlx::query(
            "INSERT INTO cases (case_key, solver_version, params, status, max_attempts, created_at) \
             VALUES ($1, $2, $3, 'queued', $4, $5) \
             ON CONFLICT (case_key) DO UPDATE SET max_attempts = excluded.max_attempts, cancel_requested = 0 \
             RETURNING id, status",
        )
        .bind(&case.key)
        .bind(crate::key::SOLVER_VERSION)
        .bind(crate::key::canonical_json(&case.params))
        .bind(i64::from(self.retry.max_attempts))
        .bind(now)
        .fetch_one(&mut *conn)
        .await?;
        Ok((
            row.int("id")?,
            CaseState::parse(&row.text("status")?)? == CaseState::Done,
        ))
    }

    /// [`Store::control_sweep`].
    pub(super) async fn control(&self, id: i64, action: SweepAction) -> StoreResult<SweepRecord> {
        let mut tx = self.begin().await?;
        let sweep = Self::sweep(&mut tx, id, B::FOR_UPDATE)
            .await?
            .ok_or(StoreError::NotFound)?;
        let target = match (action, sweep.state) {
            (_, SweepState::Cancelled) if action != SweepAction::Cancel => {
                return Err(StoreError::Conflict(format!("sweep {id} is cancelled")));
            }
            (SweepAction::Pause, _) => SweepState::Paused,
            (SweepAction::Resume, _) => SweepState::Active,
            // A finished sweep (no case queued or running) stays as it is.
            (SweepAction::Cancel, state) if Self::open_cases(&mut tx, id).await? == 0 => state,
            (SweepAction::Cancel, _) => SweepState::Cancelled,
        };
        if target != sweep.state {
            sqlx::query("UPDATE sweeps SET state = $1, updated_at = $2 WHERE id = $3")
                .bind(target.as_str())
                .bind(now_ms())
                .bind(id)
                .execute(&mut *tx)
                .await?;
            match target {
                SweepState::Active => {
                    Self::resume_cases(&mut tx, id).await?;
                    B::announce(&mut tx).await?
                }
                SweepState::Cancelled => Self::cancel_cases(&mut tx, id).await?,
                SweepState::Paused => Self::pause_cases(&mut tx, id).await?,
            }
        }
        let record = Self::sweep(&mut tx, id, "").await?.ok_or(StoreError::NotFound)?;
        tx.commit().await?;
        Ok(record)
    }

    /// The cases of sweep `id` queued or running (by the status words the
    /// sweep's counts use).
    async fn open_cases(conn: &mut AnyConnection, id: i64) -> StoreResult<i64> {
        let row = sqlx::query(
            "SELECT COUNT(*) AS n FROM sweep_cases sc JOIN cases c ON c.id = sc.case_id \
             LEFT JOIN results r ON r.case_id = c.id \
             WHERE sc.sweep_id = $1 AND COALESCE(r.outcome, c.status) IN ('queued', 'running')",
        )
        .bind(id)
        .fetch_one(&mut *conn)
        .await?;
        row.int("n")
    }

    /// Hands the running cases of sweep `id` that no active sweep wants back to
    /// the queue at their next heartbeat (`cancel_requested = 2`; the worker
    /// stops and `end_cancelled` queues the case again, the attempt not
    /// counted), so that a paused sweep computes nothing.
    async fn pause_cases(conn: &mut AnyConnection, id: i64) -> StoreResult<()> {
        let running = sqlx::query(&format!(
            "UPDATE cases AS c SET cancel_requested = 2 \
             WHERE c.status = 'running' AND c.cancel_requested = 0 \
             AND c.id IN (SELECT case_id FROM sweep_cases WHERE sweep_id = $1) AND NOT {ACTIVELY_WANTED} RETURNING id"
        ))
        .bind(id)
        .fetch_all(&mut *conn)
        .await?;
        for row in running {
            let message = format!("sweep {id} paused; handed back to the queue at its next heartbeat");
            Self::log(conn, row.int("id")?, "info", &message).await?;
        }
        Ok(())
    }

    /// Withdraws the pause's requests on the running cases of sweep `id`.
    async fn resume_cases(conn: &mut AnyConnection, id: i64) -> StoreResult<()> {
        sqlx::query(
            "UPDATE cases SET cancel_requested = 0 WHERE status = 'running' AND cancel_requested = 2 \
             AND id IN (SELECT case_id FROM sweep_cases WHERE sweep_id = $1)",
        )
        .bind(id)
        .execute(&mut *conn)
        .await?;
        Ok(())
    }

    /// Cancels the cases of sweep `id` that no other sweep wants: queued ones
    /// at once, running ones at their next heartbeat.
    async fn cancel_cases(conn: &mut AnyConnection, id: i64) -> StoreResult<()> {
        let mine = "c.id IN (SELECT case_id FROM sweep_cases WHERE sweep_id = $1)";
        let queued = sqlx::query(&format!(
            "UPDATE cases AS c SET status = 'cancelled', finished_at = $2, last_error = $3 \
             WHERE c.status = 'queued' AND {mine} AND NOT {WANTED} RETURNING id"
        ))
        .bind(id)
        .bind(now_ms())
        .bind(format!("cancelled with sweep {id}"))
        .fetch_all(&mut *conn)
        .await?;
        for row in queued {
            let message = format!("cancelled with sweep {id} before it ran");
            Self::log(conn, row.int("id")?, "info", &message).await?;
        }
        let running = sqlx::query(&format!(
            "UPDATE cases AS c SET cancel_requested = 1 \
             WHERE c.status = 'running' AND {mine} AND NOT {WANTED} RETURNING id"
        ))
        .bind(id)
        .fetch_all(&mut *conn)
        .await?;
        for row in running {
            let message = format!("cancel requested with sweep {id}; stops at its next heartbeat");
            Self::log(conn, row.int("id")?, "info", &message).await?;
        }
        Ok(())
    }

    /// The sweep with this id; `lock` ends its `SELECT` ([`Backend::FOR_UPDATE`] or nothing).
    pub(super) async fn sweep(
        conn: &mut AnyConnection,
        id: i64,
        lock: &str,
    ) -> StoreResult<Option<SweepRecord>> {
        let sql = format!("SELECT {SWEEP_COLUMNS} FROM sweeps WHERE id = $1{lock}");
        let row = sqlx::query(&sql).bind(id).fetch_optional(conn).await?;
        row.map(|r| sweep_from_row(&r)).transpose()
    }
}
