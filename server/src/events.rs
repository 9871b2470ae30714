//! Server-sent progress of sweeps: one poller per watched sweep, fanned out
//! to that sweep's streams through a `watch` channel, so that watching a
//! sweep costs the same for one stream as for many.
//!
//! The poller reads the sweep in full only when a cheap probe (its state and
//! its counts per status: [`Core::sweep_stamp`]) changed or cases are
//! running, and passes on only changes. It ends when the sweep is finished or
//! cancelled (its streams end after the `done` event), when the sweep's last
//! stream closes, and at shutdown. Open streams are capped per sweep and per
//! client address ([`StreamLimits`], 429 beyond); idle streams carry a
//! comment every [`HEARTBEAT`], which is also how long a stream whose client
//! went away may keep its place.
use crate::core::Core;
use crate::error::CoreError;
use crate::views::{SweepEvent, SweepStatus, SweepUpdate};
use futures_util::Stream;
use knotsweep_worker::store::CaseStatus;
use std::collections::HashMap;
use std::net::IpAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::watch;

/// Interval of the comments that keep an idle stream open.
pub const HEARTBEAT: Duration = Duration::from_secs(15);

/// Caps on the event streams open at once.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamLimits {
    /// Streams of one sweep.
    pub per_sweep: usize,
    /// Streams from one client address (behind a proxy, the proxy's).
    pub per_client: usize,
}

impl StreamLimits {
    /// 64 per sweep, 16 per client address.
    pub const DEFAULT: Self = Self {
        per_sweep: 64,
        per_client: 16,
    };
}

impl Default for StreamLimits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The latest update of a sweep, as its poller last read it.
type Latest = watch::Receiver<Option<SweepUpdate>>;

/// What a sweep's poller probes before reading the sweep in full: its state
/// and its cases' counts per status word.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SweepStamp {
    pub state: knotsweep_worker::store::SweepState,
    pub updated_at: i64,
    pub counts: Vec<(CaseStatus, i64)>,
}

impl SweepStamp {
    /// Cases are running: their progress changes without the counts.
    fn running(&self) -> bool {
        self.counts
            .iter()
            .any(|(status, n)| *status == CaseStatus::RUNNING && *n > 0)
    }
}

/// The sweeps' event feeds.
#[derive(Clone)]
pub struct Feeds {
    core: Core,
    interval: Duration,
    shutdown: watch::Receiver<bool>,
    limits: StreamLimits,
    open: Arc<Mutex<Open>>,
}

/// The streams open now.
#[derive(Default)]
struct Open {
    sweeps: HashMap<i64, Feed>,
    clients: HashMap<IpAddr, usize>,
}

/// A watched sweep: its poller's channel and its open streams.
struct Feed {
    latest: Latest,
    streams: usize,
}

impl Feeds {
    /// Feeds polling every `interval`, ended by `shutdown`.
    pub fn new(
        core: Core,
        interval: Duration,
        shutdown: watch::Receiver<bool>,
        limits: StreamLimits,
    ) -> Self {
        Self {
            core,
            interval,
            shutdown,
            limits,
            open: Arc::default(),
        }
    }

    /// Sweep `id`'s updates for a client at `client`: its state now, then
    /// each change, the last one `done`. 404 without such a sweep, 429 over
    /// a cap.
    pub async fn subscribe(
        &self,
        id: i64,
        client: IpAddr,
    ) -> Result<impl Stream<Item = SweepUpdate> + use<>, CoreError> {
        self.core.sweep_stamp(id).await?;
        let (latest, ticket) = self.join(id, client)?;
        let listener = Listener {
            latest,
            shutdown: self.shutdown.clone(),
            _ticket: ticket,
            done: false,
        };
        Ok(futures_util::stream::unfold(listener, |mut l| async move {
            let update = l.next().await?;
            Some((update, l))
        }))
    }

    /// Counts a new stream of sweep `id` from `client`, starting the sweep's
    /// poller if none runs.
    fn join(&self, id: i64, client: IpAddr) -> Result<(Latest, Ticket), CoreError> {
        let mut open = self.open.lock().expect("feeds");
        let from_client = open.clients.get(&client).copied().unwrap_or(0);
        if from_client >= self.limits.per_client {
            return Err(CoreError::TooMany(format!(
                "{from_client} event streams are open from {client}, the most one client address may open; close one"
            )));
        }
        let streams = open.sweeps.get(&id).map_or(0, |f| f.streams);
        if streams >= self.limits.per_sweep {
            return Err(CoreError::TooMany(format!(
                "{streams} event streams of sweep {id} are open, the most a sweep may have; poll GET /api/sweeps/{id} \
                 instead"
            )));
        }
        let feed = open.sweeps.entry(id).or_insert_with(|| Feed {
            latest: self.start_poller(id),
            streams: 0,
        });
        // A poller that stopped before the end (the sweep could not be read) is started again.
        let ended = feed.latest.has_changed().is_err();
        let finished = matches!(*feed.latest.borrow(), Some(SweepUpdate::Done(_)));
        if ended && !finished {
            feed.latest = self.start_poller(id);
        }
        feed.streams += 1;
        let mut latest = feed.latest.clone();
        *open.clients.entry(client).or_default() += 1;
        latest.mark_changed();
        Ok((
            latest,
            Ticket {
                open: self.open.clone(),
                sweep: id,
                client,
            },
        ))
    }

    fn start_poller(&self, id: i64) -> Latest {
        let (tx, rx) = watch::channel(None);
        tokio::spawn(poll(
            self.core.clone(),
            id,
            self.interval,
            self.shutdown.clone(),
            tx,
        ));
        rx
    }
}

/// Reads sweep `id` every `interval` and sends what changed, until the sweep
/// ends, its streams close or `shutdown` turns true.
async fn poll(
    core: Core,
    id: i64,
    interval: Duration,
    mut shutdown: watch::Receiver<bool>,
    tx: watch::Sender<Option<SweepUpdate>>,
) {
    let mut seen = None;
    loop {
        let stamp = match core.sweep_stamp(id).await {
            Ok(stamp) => stamp,
            Err(e) => {
                tracing::warn!(sweep_id = id, error = %e, "event feed ended: the sweep cannot be read");
                return;
            }
        };
        if seen.as_ref() != Some(&stamp) || stamp.running() {
            let event = match core.sweep(id).await {
                Ok(detail) => SweepEvent::from(&detail),
                Err(e) => {
                    tracing::warn!(sweep_id = id, error = %e, "event feed ended: the sweep cannot be read");
                    return;
                }
            };
            let finished = matches!(event.status, SweepStatus::Done | SweepStatus::Cancelled);
            let update = if finished {
                SweepUpdate::Done(event)
            } else {
                SweepUpdate::Progress(event)
            };
            tx.send_if_modified(|latest| {
                let changed = latest.as_ref() != Some(&update);
                if changed {
                    *latest = Some(update);
                }
                changed
            });
            if finished {
                return;
            }
            seen = Some(stamp);
        }
        tokio::select! {
            _ = tokio::time::sleep(interval) => {}
            _ = tx.closed() => return,
            _ = shutdown.wait_for(|stop| *stop) => return,
        }
    }
}

/// One stream's place in the counts, given back when the stream is dropped.
struct Ticket {
    open: Arc<Mutex<Open>>,
    sweep: i64,
    client: IpAddr,
}

impl Drop for Ticket {
    fn drop(&mut self) {
        let mut open = self.open.lock().expect("feeds");
        if let Some(feed) = open.sweeps.get_mut(&self.sweep) {
            feed.streams -= 1;
            if feed.streams == 0 {
                // Its poller sees its channel closed and stops.
                open.sweeps.remove(&self.sweep);
            }
        }
        if let Some(n) = open.clients.get_mut(&self.client) {
            *n -= 1;
            if *n == 0 {
                open.clients.remove(&self.client);
            }
        }
    }
}

/// One stream: the updates not yet sent.
struct Listener {
    latest: Latest,
    shutdown: watch::Receiver<bool>,
    _ticket: Ticket,
    done: bool,
}

impl Listener {
    /// The next update; none after `done`, at shutdown or when the poller
    /// stopped.
    async fn next(&mut self) -> Option<SweepUpdate> {
        while !self.done {
            tokio::select! {
                changed = self.latest.changed() => changed.ok()?,
                _ = self.shutdown.wait_for(|stop| *stop) => return None,
            }
            let update = self.latest.borrow_and_update().clone();
            if let Some(update) = update {
                self.done = matches!(update, SweepUpdate::Done(_));
                return Some(update);
            }
        }
        None
    }
}
