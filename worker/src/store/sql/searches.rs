//! Fits and maps' refinements: searches over sweeps, each kept whole as its
//! JSON view beside a status word (`migrations/*/…_fits_and_refinements.sql`).
use super::*;
use sqlx::Row;

/// A text column of `row` (views and status words are never null).
fn text(row: &sqlx::any::AnyRow, column: &str) -> StoreResult<String> {
    row.try_get(column)
        .map_err(|e| StoreError::Corrupt(format!("{column}: {e}")))
}

/// An integer column of `row`.
fn int(row: &sqlx::any::AnyRow, column: &str) -> StoreResult<i64> {
    row.try_get(column)
        .map_err(|e| StoreError::Corrupt(format!("{column}: {e}")))
}

impl<B: Backend> SqlStore<B> {
    /// [`Store::create_fit`].
    pub(super) async fn insert_fit(&self, status: &str, view: &str) -> StoreResult<i64> {
        let now = now_ms();
        let row = sqlx::query(
            "INSERT INTO fits (status, view, created_at, updated_at) VALUES ($1, $2, $3, $3) RETURNING id",
        )
        .bind(status)
        .bind(view)
        .bind(now)
        .fetch_one(self.pool())
        .await?;
        int(&row, "id")
    }

    /// [`Store::update_fit`].
    pub(super) async fn replace_fit(&self, id: i64, status: &str, view: &str) -> StoreResult<()> {
        let done = sqlx::query("UPDATE fits SET status = $1, view = $2, updated_at = $3 WHERE id = $4")
            .bind(status)
            .bind(view)
            .bind(now_ms())
            .bind(id)
            .execute(self.pool())
            .await?;
        if done.rows_affected() == 0 {
            return Err(StoreError::NotFound);
        }
        Ok(())
    }

    /// [`Store::get_fit`].
    pub(super) async fn fit_view(&self, id: i64) -> StoreResult<Option<String>> {
        let row = sqlx::query("SELECT view FROM fits WHERE id = $1")
            .bind(id)
            .fetch_optional(self.pool())
            .await?;
        row.map(|r| text(&r, "view")).transpose()
    }

    /// [`Store::list_fits`].
    pub(super) async fn fit_views(&self) -> StoreResult<Vec<(i64, String, String)>> {
        let rows = sqlx::query("SELECT id, status, view FROM fits ORDER BY id")
            .fetch_all(self.pool())
            .await?;
        (rows.iter())
            .map(|r| Ok((int(r, "id")?, text(r, "status")?, text(r, "view")?)))
            .collect()
    }

    /// [`Store::put_refinement`].
    pub(super) async fn upsert_refinement(&self, id: i64, status: &str, view: &str) -> StoreResult<()> {
        if self.get_sweep(id).await?.is_none() {
            return Err(StoreError::NotFound);
        }
        sqlx::query(
            "INSERT INTO refinements (sweep_id, status, view, created_at, updated_at) VALUES ($1, $2, $3, $4, $4) \
             ON CONFLICT (sweep_id) DO UPDATE SET status = excluded.status, view = excluded.view, \
             updated_at = excluded.updated_at",
        )
        .bind(id)
        .bind(status)
        .bind(view)
        .bind(now_ms())
        .execute(self.pool())
        .await?;
        Ok(())
    }

    /// [`Store::refinement`].
    pub(super) async fn refinement_view(&self, id: i64) -> StoreResult<Option<String>> {
        let row = sqlx::query("SELECT view FROM refinements WHERE sweep_id = $1")
            .bind(id)
            .fetch_optional(self.pool())
            .await?;
        row.map(|r| text(&r, "view")).transpose()
    }

    /// [`Store::refinements_with_status`].
    pub(super) async fn refinement_views(&self, status: &str) -> StoreResult<Vec<(i64, String)>> {
        let rows = sqlx::query("SELECT sweep_id, view FROM refinements WHERE status = $1 ORDER BY sweep_id")
            .bind(status)
            .fetch_all(self.pool())
            .await?;
        (rows.iter())
            .map(|r| Ok((int(r, "sweep_id")?, text(r, "view")?)))
            .collect()
    }
}
