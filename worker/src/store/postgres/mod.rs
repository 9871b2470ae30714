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

mod claims;
mod results;
mod sweeps;

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

store_impl!(PgStore, {
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
});
