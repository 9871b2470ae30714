//! One conformance suite for the `Store` trait, run against every backend:
//! SQLite (a temporary file) and PostgreSQL (a fresh database on the server
//! at `KNOTSWEEP_TEST_POSTGRES`, default `postgres://postgres@127.0.0.1:5432/test`;
//! when that server does not answer, skipped with the reason, or failing when
//! `CI` is set: `common::missing`).
mod common;

use common::{drop_database, fresh_postgres, missing};
use knotsweep_worker::store::{
    CaseState, CaseStatus, CreateOutcome, FailOutcome, Heartbeat, Idempotency, NewCase, NewSweep,
    RetryPolicy, SnapshotChoice, Store, StoreError, StoreOptions, SweepAction, SweepState, open_store,
};
use solver::case::CaseParams;
use solver::protocol::{CaseReport, Status};
use std::collections::HashSet;
use std::sync::Arc;
use std::time::Duration;

/// Retries without waiting, two attempts.
fn options() -> StoreOptions {
    StoreOptions {
        max_connections: 16,
        retry: RetryPolicy {
            max_attempts: 2,
            base: Duration::from_millis(1),
            cap: Duration::from_millis(1),
        },
    }
}

/// A backend under test; dropping it removes its database.
struct Backend {
    name: &'static str,
    store: Arc<dyn Store>,
    cleanup: Option<(String, String)>,
    _dir: Option<tempfile::TempDir>,
}

impl Backend {
    async fn close(self) {
        self.store.close().await;
        if let Some((admin, db)) = &self.cleanup {
            drop_database(admin, db).await;
        }
    }
}

/// Every backend that can run here (SQLite always).
async fn backends(tag: &str) -> Vec<Backend> {
    let dir = tempfile::tempdir().unwrap();
    let url = format!("sqlite://{}", dir.path().join("q.sqlite").display());
    let mut v = vec![Backend {
        name: "sqlite",
        store: open_store(&url, options()).await.unwrap(),
        cleanup: None,
        _dir: Some(dir),
    }];
    match fresh_postgres(tag).await {
        Ok((url, admin, db)) => v.push(Backend {
            name: "postgres",
            store: open_store(&url, options()).await.unwrap(),
            cleanup: Some((admin, db)),
            _dir: None,
        }),
        Err(why) => missing(&format!("the PostgreSQL backend: {why}")),
    }
    v
}

/// Cases that differ in mu only (distinct keys).
fn cases(count: usize) -> Vec<NewCase> {
    (0..count)
        .map(|i| {
            NewCase::new(CaseParams {
                mu: 0.01 * i as f64,
                ..CaseParams::default()
            })
        })
        .collect()
}

fn sweep(cases: Vec<NewCase>) -> NewSweep {
    NewSweep {
        name: None,
        preset: None,
        spec: serde_json::json!({}),
        varied: vec!["mu".to_string()],
        snapshots: SnapshotChoice::All,
        cases,
        idempotency: None,
    }
}

async fn create(store: &dyn Store, s: NewSweep) -> (i64, usize) {
    match store.create_sweep(s).await.unwrap() {
        CreateOutcome::Created { sweep, cached } => (sweep.id, cached),
        CreateOutcome::Replayed { sweep } => panic!("replayed sweep {}", sweep.id),
    }
}

fn report(params: CaseParams) -> CaseReport {
    CaseReport {
        determinant_initial: Some(7),
        determinant_final: Some(7),
        ..CaseReport::empty(params, Status::Completed)
    }
}

const LEASE: Duration = Duration::from_secs(30);

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn each_case_is_claimed_by_exactly_one_of_32_concurrent_claimers() {
    for b in backends("claim").await {
        let (_, _) = create(&*b.store, sweep(cases(96))).await;
        let tasks: Vec<_> = (0..32)
            .map(|w| {
                let store = b.store.clone();
                tokio::spawn(async move {
                    let mut mine = Vec::new();
                    while let Some(c) = store.claim(&format!("w{w}"), LEASE).await.unwrap() {
                        mine.push(c.lease.case_id);
                    }
                    mine
                })
            })
            .collect();
        let mut all = Vec::new();
        for t in tasks {
            all.extend(t.await.unwrap());
        }
        let distinct: HashSet<i64> = all.iter().copied().collect();
        assert_eq!(all.len(), 96, "{}: {} claims", b.name, all.len());
        assert_eq!(distinct.len(), 96, "{}: a case was claimed twice", b.name);
        b.close().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_expired_lease_requeues_the_case_and_fences_out_its_old_holder() {
    for b in backends("lease").await {
        let s = &*b.store;
        create(s, sweep(cases(1))).await;
        let old = s.claim("lost", Duration::from_millis(50)).await.unwrap().unwrap();
        tokio::time::sleep(Duration::from_millis(120)).await;
        assert_eq!(s.requeue_expired().await.unwrap(), 1, "{}", b.name);
        assert_eq!(
            s.get_case(old.lease.case_id).await.unwrap().unwrap().state,
            CaseState::Queued
        );
        tokio::time::sleep(Duration::from_millis(10)).await;
        let new = s.claim("alive", LEASE).await.unwrap().expect("claimable again");
        assert_eq!(new.lease.case_id, old.lease.case_id);
        assert_eq!(new.attempt, 2);
        assert_eq!(
            s.heartbeat(&old.lease, None, LEASE).await.unwrap(),
            Heartbeat::Lost
        );
        assert!(!s.complete(&old.lease, &report(old.params.clone())).await.unwrap());
        assert!(s.complete(&new.lease, &report(new.params.clone())).await.unwrap());
        let done = s.get_case(new.lease.case_id).await.unwrap().unwrap();
        assert_eq!(done.state, CaseState::Done, "{}", b.name);
        assert_eq!(done.result.unwrap().worker, "alive");
        b.close().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn failed_attempts_retry_then_fail_at_the_limit() {
    for b in backends("retry").await {
        let s = &*b.store;
        create(s, sweep(cases(1))).await;
        let first = s.claim("w", LEASE).await.unwrap().unwrap();
        assert!(matches!(
            s.fail_attempt(&first.lease, "disk full").await.unwrap(),
            FailOutcome::Retry { .. }
        ));
        tokio::time::sleep(Duration::from_millis(10)).await;
        let second = s.claim("w", LEASE).await.unwrap().expect("retried");
        assert_eq!(
            s.fail_attempt(&second.lease, "disk full").await.unwrap(),
            FailOutcome::Failed,
            "{}",
            b.name
        );
        let case = s.get_case(second.lease.case_id).await.unwrap().unwrap();
        assert_eq!(case.state, CaseState::Failed);
        assert!(case.last_error.unwrap().contains("disk full"));
        assert!(s.claim("w", LEASE).await.unwrap().is_none());
        b.close().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancel_stops_queued_and_running_cases() {
    for b in backends("cancel").await {
        let s = &*b.store;
        let (id, _) = create(s, sweep(cases(2))).await;
        let running = s.claim("w", LEASE).await.unwrap().unwrap();
        let sweep = s.control_sweep(id, SweepAction::Cancel).await.unwrap();
        assert_eq!(sweep.state, SweepState::Cancelled);
        assert!(s.claim("w", LEASE).await.unwrap().is_none(), "{}", b.name);
        assert_eq!(
            s.heartbeat(&running.lease, None, LEASE).await.unwrap(),
            Heartbeat::Held { cancel: true }
        );
        assert!(s.finish_cancelled(&running.lease).await.unwrap());
        let states: Vec<CaseState> = s
            .sweep_cases(id)
            .await
            .unwrap()
            .iter()
            .map(|c| c.case.state)
            .collect();
        assert_eq!(states, [CaseState::Cancelled, CaseState::Cancelled], "{}", b.name);
        assert!(matches!(
            s.control_sweep(id, SweepAction::Resume).await,
            Err(StoreError::Conflict(_))
        ));
        b.close().await;
    }
}

/// Cancelling a sweep whose cases all finished changes nothing: it stays
/// active (and so reads `done`), and its cases keep their outcomes.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancelling_a_finished_sweep_changes_nothing() {
    for b in backends("cancel_done").await {
        let s = &*b.store;
        let (id, _) = create(s, sweep(cases(1))).await;
        let c = s.claim("w", LEASE).await.unwrap().unwrap();
        assert!(s.complete(&c.lease, &report(c.params.clone())).await.unwrap());
        let before = s.get_sweep(id).await.unwrap().unwrap();
        let after = s.control_sweep(id, SweepAction::Cancel).await.unwrap();
        assert_eq!(after.state, SweepState::Active, "{}", b.name);
        assert_eq!(after.updated_at, before.updated_at, "{}", b.name);
        let counts = s.sweep_status_counts(id..=id).await.unwrap();
        assert_eq!(counts, [(id, CaseStatus::COMPLETED, 1)], "{}", b.name);
        b.close().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_paused_sweep_hands_out_nothing_until_resumed() {
    for b in backends("pause").await {
        let s = &*b.store;
        let (id, _) = create(s, sweep(cases(1))).await;
        s.control_sweep(id, SweepAction::Pause).await.unwrap();
        assert!(s.claim("w", LEASE).await.unwrap().is_none(), "{}", b.name);
        assert_eq!(s.queue_depth().await.unwrap(), 0);
        s.control_sweep(id, SweepAction::Resume).await.unwrap();
        assert_eq!(s.queue_depth().await.unwrap(), 1);
        assert!(s.claim("w", LEASE).await.unwrap().is_some(), "{}", b.name);
        b.close().await;
    }
}

/// Pausing hands a running case back at its next heartbeat (queued, the
/// attempt not counted) unless an active sweep also wants it; resuming
/// before that heartbeat withdraws the request.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn pausing_hands_running_cases_back_unless_an_active_sweep_wants_them() {
    for b in backends("pause_running").await {
        let s = &*b.store;
        let (id, _) = create(s, sweep(cases(1))).await;
        let running = s.claim("w", LEASE).await.unwrap().unwrap();
        s.control_sweep(id, SweepAction::Pause).await.unwrap();
        s.control_sweep(id, SweepAction::Resume).await.unwrap();
        assert_eq!(
            s.heartbeat(&running.lease, None, LEASE).await.unwrap(),
            Heartbeat::Held { cancel: false },
            "{}: resumed before the heartbeat",
            b.name
        );
        s.control_sweep(id, SweepAction::Pause).await.unwrap();
        assert_eq!(
            s.heartbeat(&running.lease, None, LEASE).await.unwrap(),
            Heartbeat::Held { cancel: true },
            "{}",
            b.name
        );
        assert!(s.finish_cancelled(&running.lease).await.unwrap());
        let case = s.get_case(running.lease.case_id).await.unwrap().unwrap();
        assert_eq!((case.state, case.attempts), (CaseState::Queued, 0), "{}", b.name);
        assert!(s.claim("w", LEASE).await.unwrap().is_none(), "{}: paused", b.name);
        s.control_sweep(id, SweepAction::Resume).await.unwrap();
        let again = s.claim("w", LEASE).await.unwrap().expect("queued again");
        assert_eq!(again.lease.case_id, running.lease.case_id);
        // Another active sweep wants it: it goes on.
        let (other, _) = create(s, sweep(cases(1))).await;
        s.control_sweep(id, SweepAction::Pause).await.unwrap();
        assert_eq!(
            s.heartbeat(&again.lease, None, LEASE).await.unwrap(),
            Heartbeat::Held { cancel: false },
            "{}: sweep {other} still wants it",
            b.name
        );
        b.close().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sweeps_share_cases_by_key_and_reuse_results() {
    for b in backends("dedup").await {
        let s = &*b.store;
        let (a, cached) = create(s, sweep(cases(2))).await;
        assert_eq!(cached, 0);
        let c = s.claim("w", LEASE).await.unwrap().unwrap();
        assert!(s.complete(&c.lease, &report(c.params.clone())).await.unwrap());
        let (bb, cached) = create(s, sweep(cases(3))).await;
        assert_eq!(cached, 1, "{}: the finished case is reused", b.name);
        let ids =
            |v: Vec<knotsweep_worker::store::SweepCase>| v.iter().map(|c| c.case.id).collect::<Vec<_>>();
        let (ia, ib) = (
            ids(s.sweep_cases(a).await.unwrap()),
            ids(s.sweep_cases(bb).await.unwrap()),
        );
        assert_eq!(ia[..], ib[..2], "{}: same keys, same rows", b.name);
        assert_eq!(s.case_sweeps(ia[0]).await.unwrap(), [a, bb]);
        b.close().await;
    }
}

/// Asking again for a case that failed queues a new attempt without touching
/// the sweep that ended with the failure, and cancelling the new sweep stops
/// only the new attempt.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_new_attempt_of_a_failed_shared_case_leaves_the_finished_sweep_as_it_ended() {
    for b in backends("retire").await {
        let s = &*b.store;
        let (first, _) = create(s, sweep(cases(1))).await;
        for _ in 0..2 {
            tokio::time::sleep(Duration::from_millis(5)).await;
            let c = s.claim("w", LEASE).await.unwrap().expect("queued");
            s.fail_attempt(&c.lease, "diverged").await.unwrap();
        }
        let failed = s.sweep_cases(first).await.unwrap()[0].case.clone();
        assert_eq!(failed.state, CaseState::Failed, "{}", b.name);
        let (second, cached) = create(s, sweep(cases(1))).await;
        assert_eq!(cached, 0);
        let retry = s.sweep_cases(second).await.unwrap()[0].case.clone();
        assert_ne!(retry.id, failed.id, "{}: a new row for the new attempt", b.name);
        assert_eq!(retry.key, failed.key, "{}: the same cache key", b.name);
        assert_eq!(retry.state, CaseState::Queued);
        let old = s.get_case(failed.id).await.unwrap().unwrap();
        assert_eq!(
            old.state,
            CaseState::Failed,
            "{}: the first sweep's case keeps its outcome",
            b.name
        );
        assert!(old.last_error.unwrap().contains("diverged"));
        assert_eq!(s.case_sweeps(failed.id).await.unwrap(), [first]);
        assert_eq!(s.case_sweeps(retry.id).await.unwrap(), [second]);
        let counts = |sweep: i64| async move {
            s.sweep_status_counts(sweep..=sweep)
                .await
                .unwrap()
                .into_iter()
                .filter(|(id, _, _)| *id == sweep)
                .map(|(_, st, n)| (st, n))
                .collect::<Vec<_>>()
        };
        assert_eq!(
            counts(first).await,
            [(CaseStatus::Queue(CaseState::Failed), 1)],
            "{}",
            b.name
        );
        let cancelled = s.control_sweep(second, SweepAction::Cancel).await.unwrap();
        assert_eq!(cancelled.state, SweepState::Cancelled);
        assert_eq!(
            s.get_case(retry.id).await.unwrap().unwrap().state,
            CaseState::Cancelled
        );
        let failed_once = [(CaseStatus::Queue(CaseState::Failed), 1)];
        assert_eq!(counts(first).await, failed_once, "{}", b.name);
        // A third request makes a third attempt; the two earlier rows stay.
        let (third, _) = create(s, sweep(cases(1))).await;
        let again = s.sweep_cases(third).await.unwrap()[0].case.clone();
        assert!(
            again.id != retry.id && again.state == CaseState::Queued,
            "{}",
            b.name
        );
        assert_eq!(
            s.get_case(retry.id).await.unwrap().unwrap().state,
            CaseState::Cancelled
        );
        b.close().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_repeated_idempotency_key_replays_or_conflicts() {
    for b in backends("idem").await {
        let s = &*b.store;
        let with = |hash: &str| NewSweep {
            idempotency: Some(Idempotency {
                key: "k1".to_string(),
                request_hash: hash.to_string(),
            }),
            ..sweep(cases(1))
        };
        let (first, _) = create(s, with("h")).await;
        match s.create_sweep(with("h")).await.unwrap() {
            CreateOutcome::Replayed { sweep } => assert_eq!(sweep.id, first, "{}", b.name),
            CreateOutcome::Created { .. } => panic!("{}: created twice", b.name),
        }
        assert!(matches!(
            s.create_sweep(with("other")).await,
            Err(StoreError::Conflict(_))
        ));
        assert_eq!(s.count_sweeps().await.unwrap(), 1);
        b.close().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_released_case_is_queued_at_once_without_counting_the_attempt() {
    for b in backends("release").await {
        let s = &*b.store;
        create(s, sweep(cases(1))).await;
        let c = s.claim("w", LEASE).await.unwrap().unwrap();
        assert!(s.release(&c.lease).await.unwrap());
        let again = s.claim("v", LEASE).await.unwrap().expect("queued at once");
        assert_eq!(again.attempt, 1, "{}", b.name);
        b.close().await;
    }
}
