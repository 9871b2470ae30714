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

mod claims;
mod results;
mod sweeps;

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

store_impl!(SqliteStore, {
    /// Closes every connection (checkpointing the WAL).
    async fn close(&self) {
        self.pool.close().await;
    }
});
