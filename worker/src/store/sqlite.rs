//! SQLite, the embedded default: the queue and results in one file.
//!
//! Every pooled connection runs in WAL mode with `synchronous = NORMAL`, a busy
//! timeout and foreign keys on (sqlx applies the connect options to each new
//! connection). Transactions that read and then write begin `IMMEDIATE`, so
//! they take the write lock up front and wait on the busy timeout instead of
//! failing with "database is locked" when upgrading a stale read snapshot;
//! single write statements (claim, heartbeat) take the write lock when they
//! start. Nothing stays open while a case computes, and nothing announces
//! work: idle workers poll.
use super::rows::claim_from_row;
use super::sql::{Backend, SqlStore, claim_query, claim_statement};
use super::*;
use sqlx::AnyPool;
use sqlx::any::AnyPoolOptions;
use sqlx::sqlite::SqliteConnectOptions;
use sqlx::{ConnectOptions, Executor};
use std::str::FromStr;

/// The queue and results in one SQLite file.
pub type SqliteStore = SqlStore<Sqlite>;

/// SQLite's dialect and claim.
#[derive(Debug)]
pub struct Sqlite;

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

impl Backend for Sqlite {
    const BEGIN: &'static str = "BEGIN IMMEDIATE";
    // The IMMEDIATE transaction holds the write lock: no row needs one.
    const FOR_UPDATE: &'static str = "";
    const SKIP_LOCKED: &'static str = "";

    /// The claim, then its log line, in one transaction (SQLite has no
    /// writes inside `WITH`): a worker killed between them leaves neither.
    async fn claim(pool: &AnyPool, owner: &str, lease: Duration) -> StoreResult<Option<Claim>> {
        let sql = claim_statement(Self::SKIP_LOCKED);
        let mut tx = pool.begin_with(Self::BEGIN).await?;
        let row = claim_query(&sql, owner, lease).fetch_optional(&mut *tx).await?;
        let Some(claim) = row.map(|r| claim_from_row(&r, owner)).transpose()? else {
            tx.rollback().await?;
            return Ok(None);
        };
        let (attempt, fence) = (claim.attempt, claim.lease.fence);
        let message = format!("claimed by {owner} (attempt {attempt}, fence {fence})");
        SqliteStore::log(&mut tx, claim.lease.case_id, "info", &message).await?;
        tx.commit().await?;
        Ok(Some(claim))
    }
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
        // The file as a URL the `Any` driver opens (its path made absolute, so
        // that URL parsing cannot fold a relative `..`); the pragmas apply to
        // each new connection.
        let file = SqliteConnectOptions::from_str(&url)?;
        let path = std::path::absolute(file.get_filename()).map_err(sqlx::Error::Io)?;
        let file = file.filename(path).create_if_missing(true).to_url_lossy();
        let pragmas = format!(
            "PRAGMA busy_timeout = {}; PRAGMA journal_mode = WAL; PRAGMA synchronous = NORMAL; \
             PRAGMA foreign_keys = ON",
            options.busy_timeout.as_millis()
        );
        sqlx::any::install_default_drivers();
        let pool = AnyPoolOptions::new()
            .max_connections(options.max_connections.max(1))
            .min_connections(1)
            .acquire_timeout(Duration::from_secs(60))
            .after_connect(move |conn, _| {
                let pragmas = pragmas.clone();
                Box::pin(async move { conn.execute(pragmas.as_str()).await.map(drop) })
            })
            .connect(file.as_str())
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
        Ok(Self::new(pool, options.retry, Sqlite))
    }
}

#[cfg(test)]
mod tests {
    use super::{SqliteOptions, SqliteStore};
    use crate::store::testing;

    #[tokio::test]
    async fn sweeps_on_sqlite() {
        let (store, _dir) = testing::sqlite().await;
        testing::sweeps(&store).await;
    }

    #[tokio::test]
    async fn claims_on_sqlite() {
        let (store, _dir) = testing::sqlite().await;
        testing::claims(&store).await;
    }

    #[tokio::test]
    async fn results_on_sqlite() {
        let (store, _dir) = testing::sqlite().await;
        testing::results(&store).await;
    }

    #[tokio::test]
    async fn packed_results_on_sqlite() {
        let (store, _dir) = testing::sqlite().await;
        testing::packed_results(&store).await;
    }

    #[tokio::test]
    async fn bend_snapshots_on_sqlite() {
        let (store, _dir) = testing::sqlite().await;
        testing::bend_snapshots(&store).await;
    }

    /// A file written before the packed results, opened by the store (which
    /// rebuilds its results table): the old rows are served as stored.
    #[tokio::test]
    async fn old_results_on_sqlite_stay_readable() {
        let dir = tempfile::tempdir().unwrap();
        let url = format!("sqlite://{}", dir.path().join("old.sqlite").display());
        sqlx::any::install_default_drivers();
        let pool = sqlx::AnyPool::connect(&format!("{url}?mode=rwc")).await.unwrap();
        let before = testing::before_packing(sqlx::migrate!("../migrations/sqlite"));
        before.run(&pool).await.unwrap();
        let id = testing::write_old_result(&pool).await;
        pool.close().await;
        let store = SqliteStore::connect(&url, SqliteOptions::default())
            .await
            .unwrap();
        testing::read_old_result(&store, id).await;
    }
}
