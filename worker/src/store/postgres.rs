//! PostgreSQL: one database shared by a server and workers on any number of
//! hosts.
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
use super::rows::claim_from_row;
use super::sql::{Backend, SqlStore, claim_query, claim_statement};
use super::*;
use sqlx::any::AnyPoolOptions;
use sqlx::postgres::{PgConnectOptions, PgListener};
use sqlx::{AnyConnection, AnyPool};
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
pub type PgStore = SqlStore<Postgres>;

/// PostgreSQL's dialect, claim and notifications: a task that `LISTEN`s on
/// [`CHANNEL`] and wakes idle workers (stopped when dropped).
#[derive(Debug)]
pub struct Postgres {
    wake: Arc<Notify>,
    task: tokio::task::JoinHandle<()>,
}

impl Drop for Postgres {
    fn drop(&mut self) {
        self.task.abort();
    }
}

impl Backend for Postgres {
    const BEGIN: &'static str = "BEGIN";
    const FOR_UPDATE: &'static str = " FOR UPDATE";
    const SKIP_LOCKED: &'static str = " FOR UPDATE SKIP LOCKED";

    /// One statement claims and logs. Its commit need not wait for the WAL
    /// flush: a claim lost in a server crash leaves the case queued, and the
    /// worker's next heartbeat finds the lease gone.
    async fn claim(pool: &AnyPool, owner: &str, lease: Duration) -> StoreResult<Option<Claim>> {
        let mut tx = pool.begin().await?;
        sqlx::query("SET LOCAL synchronous_commit = off")
            .execute(&mut *tx)
            .await?;
        let sql = format!(
            "WITH claimed AS ({}), \
             logged AS ( \
               INSERT INTO case_logs (case_id, at, level, message) \
               SELECT id, $3, 'info', 'claimed by ' || $1 || ' (attempt ' || attempts || ', fence ' || fence || ')' \
               FROM claimed) \
             SELECT id, case_key, params, fence, attempts FROM claimed",
            claim_statement(Self::SKIP_LOCKED)
        );
        let row = claim_query(&sql, owner, lease).fetch_optional(&mut *tx).await?;
        tx.commit().await?;
        row.map(|r| claim_from_row(&r, owner)).transpose()
    }

    async fn serialise_creation(conn: &mut AnyConnection) -> StoreResult<()> {
        // In FROM: the `Any` driver decodes no `void` column.
        sqlx::query("SELECT 1 FROM pg_advisory_xact_lock($1)")
            .bind(CREATE_LOCK)
            .execute(conn)
            .await?;
        Ok(())
    }

    async fn announce(conn: &mut AnyConnection) -> StoreResult<()> {
        sqlx::query(&format!("NOTIFY {CHANNEL}")).execute(conn).await?;
        Ok(())
    }

    /// A notification or [`FALLBACK_POLL`], whichever comes first.
    async fn wait_for_work(&self, _poll: Duration) {
        tokio::select! {
            _ = self.wake.notified() => {}
            _ = tokio::time::sleep(FALLBACK_POLL) => {}
        }
    }

    fn stop_listening(&self) {
        self.task.abort();
    }
}

impl PgStore {
    /// Connects to `url` (`postgres://user@host:port/db`), runs the
    /// migrations (under sqlx's advisory lock, so several processes may start
    /// at once) and starts listening for work.
    pub async fn connect(url: &str, options: StoreOptions) -> StoreResult<Self> {
        let connect = PgConnectOptions::from_str(url)?;
        let server = format!("{}:{}", connect.get_host(), connect.get_port());
        sqlx::any::install_default_drivers();
        let pool = AnyPoolOptions::new()
            .max_connections(options.max_connections.max(2))
            .acquire_timeout(Duration::from_secs(30))
            .connect(url)
            .await
            .map_err(|e| match e {
                sqlx::Error::Io(_) | sqlx::Error::PoolTimedOut | sqlx::Error::Tls(_) => {
                    StoreError::Unreachable(format!("cannot reach PostgreSQL at {server}: {e}"))
                }
                other => StoreError::Database(other),
            })?;
        sqlx::migrate!("../migrations/postgres").run(&pool).await?;
        let wake = Arc::new(Notify::new());
        let task = tokio::spawn(listen(url.to_string(), wake.clone()));
        Ok(Self::new(pool, options.retry, Postgres { wake, task }))
    }
}

/// Wakes idle workers on every notification; reconnects after errors.
async fn listen(url: String, wake: Arc<Notify>) {
    loop {
        let mut listener = match PgListener::connect(&url).await {
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

#[cfg(test)]
mod tests {
    use crate::store::testing;

    #[tokio::test]
    async fn sweeps_on_postgres() {
        if let Some(db) = testing::postgres("sweeps").await {
            testing::sweeps(&db.store).await;
            db.drop_database().await;
        }
    }

    #[tokio::test]
    async fn claims_on_postgres() {
        if let Some(db) = testing::postgres("claims").await {
            testing::claims(&db.store).await;
            db.drop_database().await;
        }
    }

    #[tokio::test]
    async fn results_on_postgres() {
        if let Some(db) = testing::postgres("results").await {
            testing::results(&db.store).await;
            db.drop_database().await;
        }
    }

    #[tokio::test]
    async fn packed_results_on_postgres() {
        if let Some(db) = testing::postgres("packed").await {
            testing::packed_results(&db.store).await;
            db.drop_database().await;
        }
    }

    #[tokio::test]
    async fn bend_snapshots_on_postgres() {
        if let Some(db) = testing::postgres("bend").await {
            testing::bend_snapshots(&db.store).await;
            db.drop_database().await;
        }
    }

    /// A database written before the packed results, opened by the store
    /// (which migrates it): the old rows are served as stored.
    #[tokio::test]
    async fn old_results_on_postgres_stay_readable() {
        let Some(empty) = testing::empty_postgres("old").await else {
            return;
        };
        sqlx::any::install_default_drivers();
        let pool = sqlx::AnyPool::connect(&empty.url).await.unwrap();
        let before = testing::before_packing(sqlx::migrate!("../migrations/postgres"));
        before.run(&pool).await.unwrap();
        let id = testing::write_old_result(&pool).await;
        pool.close().await;
        let db = empty.open().await;
        testing::read_old_result(&db.store, id).await;
        db.drop_database().await;
    }
}
