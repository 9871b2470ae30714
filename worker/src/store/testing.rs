//! Unit checks of the store, one function per concern (sweeps, claims,
//! results), written once and run by each backend's tests on a fresh
//! database: the shared code of `sql/` on both, and each backend's own claim,
//! locks and notifications.
use super::postgres::PgStore;
use super::sqlite::{SqliteOptions, SqliteStore};
use super::*;
use solver::case::{Direction, StageKind};
use solver::measurements::Inversion;
use solver::protocol::{Event, EventKind, Hysteresis, QuasiStatic, Scaling, Stats, Status};
use solver::snapshot::{EventWhen, SnapshotLabel};

const LEASE: Duration = Duration::from_secs(30);

/// A store on a new SQLite file (kept while the directory lives).
pub(crate) async fn sqlite() -> (SqliteStore, tempfile::TempDir) {
    let dir = tempfile::tempdir().expect("temporary directory");
    let url = format!("sqlite://{}", dir.path().join("q.sqlite").display());
    let options = SqliteOptions {
        retry: retry(),
        ..SqliteOptions::default()
    };
    (
        SqliteStore::connect(&url, options).await.expect("SQLite opens"),
        dir,
    )
}

/// A store on a new database of the test server (`KNOTSWEEP_TEST_POSTGRES`,
/// default the local one), dropped by [`PgDatabase::drop_database`]; `None`
/// (with the reason printed) when no server answers, a failure when `CI` is
/// set.
pub(crate) async fn postgres(tag: &str) -> Option<PgDatabase> {
    let empty = empty_postgres(tag).await?;
    let options = StoreOptions {
        retry: retry(),
        ..StoreOptions::default()
    };
    let store = PgStore::connect(&empty.url, options)
        .await
        .expect("PostgreSQL store opens");
    Some(PgDatabase {
        store,
        admin: empty.admin,
        db: empty.db,
    })
}

/// A new, empty database of the test server (as [`postgres`]'s, without a
/// store).
pub(crate) struct EmptyPg {
    pub url: String,
    admin: String,
    db: String,
}

impl EmptyPg {
    /// Its store, which migrates it.
    pub async fn open(self) -> PgDatabase {
        let store = PgStore::connect(&self.url, StoreOptions::default())
            .await
            .expect("PostgreSQL store opens");
        PgDatabase {
            store,
            admin: self.admin,
            db: self.db,
        }
    }
}

pub(crate) async fn empty_postgres(tag: &str) -> Option<EmptyPg> {
    use sqlx::Connection;
    let admin = std::env::var("KNOTSWEEP_TEST_POSTGRES")
        .unwrap_or_else(|_| "postgres://postgres@127.0.0.1:5432/test".to_string());
    let connect = tokio::time::timeout(Duration::from_secs(5), sqlx::PgConnection::connect(&admin));
    let mut c = match connect.await {
        Ok(Ok(c)) => c,
        Ok(Err(e)) => return skipped(&format!("cannot connect to {admin}: {e}")),
        Err(_) => return skipped(&format!("no answer from {admin} within 5 s")),
    };
    let db = format!("ks_unit_{tag}_{}_{}", std::process::id(), rand::random::<u32>());
    sqlx::query(&format!("CREATE DATABASE {db}"))
        .execute(&mut c)
        .await
        .expect("the test server lets us create a database");
    let (base, _) = admin.rsplit_once('/').expect("URL has a database");
    let url = format!("{base}/{db}");
    Some(EmptyPg { url, admin, db })
}

fn skipped<T>(why: &str) -> Option<T> {
    if std::env::var_os("CI").is_some_and(|v| !v.is_empty()) {
        panic!("PostgreSQL unit check: {why} (CI is set: a missing prerequisite fails the test)");
    }
    println!("PostgreSQL unit check skipped: {why}");
    None
}

/// A PostgreSQL store on its own database.
pub(crate) struct PgDatabase {
    pub store: PgStore,
    admin: String,
    db: String,
}

impl PgDatabase {
    pub async fn drop_database(self) {
        use sqlx::Connection;
        self.store.close().await;
        if let Ok(mut c) = sqlx::PgConnection::connect(&self.admin).await {
            let sql = format!("DROP DATABASE IF EXISTS {} WITH (FORCE)", self.db);
            if let Err(e) = sqlx::query(&sql).execute(&mut c).await {
                println!("the test database {} was left behind: {e}", self.db);
            }
        }
    }
}

/// Two attempts, 200 ms base backoff.
fn retry() -> RetryPolicy {
    RetryPolicy {
        max_attempts: 2,
        base: Duration::from_millis(200),
        cap: Duration::from_secs(1),
    }
}

/// Cases differing in mu (distinct keys).
fn cases(mus: &[f64]) -> Vec<NewCase> {
    mus.iter()
        .map(|&mu| {
            NewCase::new(CaseParams {
                mu,
                ..CaseParams::default()
            })
        })
        .collect()
}

fn sweep(mus: &[f64]) -> NewSweep {
    NewSweep {
        name: Some("unit".to_string()),
        preset: None,
        spec: serde_json::json!({ "mu": mus }),
        varied: vec!["mu".to_string()],
        snapshots: SnapshotChoice::All,
        cases: cases(mus),
        idempotency: None,
    }
}

async fn create(store: &dyn Store, s: NewSweep) -> SweepRecord {
    match store.create_sweep(s).await.expect("sweep is created") {
        CreateOutcome::Created { sweep, .. } => sweep,
        CreateOutcome::Replayed { sweep } => panic!("sweep {} replayed", sweep.id),
    }
}

async fn case(store: &dyn Store, id: i64) -> CaseRecord {
    store.get_case(id).await.unwrap().expect("case exists")
}

async fn last_log(store: &dyn Store, id: i64) -> String {
    let logs = store.case_logs(id).await.unwrap();
    logs.last().expect("the case has a log").message.clone()
}

fn report(params: CaseParams, status: Status) -> CaseReport {
    CaseReport {
        determinant_initial: Some(7),
        determinant_final: Some(7),
        ..CaseReport::empty(params, status)
    }
}

/// Sweeps: grid order, shared cases, per-sweep counts, idempotency, and the
/// pause/resume/cancel transitions with the log line each cancelled case gets.
pub(crate) async fn sweeps(store: &dyn Store) {
    let a = create(store, sweep(&[0.1, 0.2, 0.3])).await;
    let b = create(store, sweep(&[0.3, 0.4])).await;
    let ids = |limit, offset| async move {
        let page = store.list_sweeps(limit, offset).await.unwrap();
        page.iter().map(|s| s.id).collect::<Vec<i64>>()
    };
    assert_eq!(ids(10, 0).await, vec![a.id, b.id]);
    assert_eq!(ids(1, 1).await, vec![b.id], "the page after the first");
    assert!(ids(10, 2).await.is_empty(), "past the end");
    assert_eq!(store.count_sweeps().await.unwrap(), 2);
    let in_a = store.sweep_cases(a.id).await.unwrap();
    let in_b = store.sweep_cases(b.id).await.unwrap();
    assert_eq!(in_a.iter().map(|c| c.position).collect::<Vec<_>>(), vec![0, 1, 2]);
    assert_eq!(in_a[2].case.id, in_b[0].case.id, "mu = 0.3 is one case for both");
    let counts = store.sweep_status_counts(a.id..=b.id).await.unwrap();
    assert_eq!(
        counts,
        vec![(a.id, CaseStatus::QUEUED, 3), (b.id, CaseStatus::QUEUED, 2)]
    );
    let only_b = store.sweep_status_counts(b.id..=b.id).await.unwrap();
    assert_eq!(only_b, vec![(b.id, CaseStatus::QUEUED, 2)]);

    let idem = |hash: &str| {
        let mut s = sweep(&[0.5]);
        s.idempotency = Some(Idempotency {
            key: "k1".to_string(),
            request_hash: hash.to_string(),
        });
        s
    };
    let first = create(store, idem("h")).await;
    match store.create_sweep(idem("h")).await.unwrap() {
        CreateOutcome::Replayed { sweep } => assert_eq!(sweep.id, first.id),
        CreateOutcome::Created { sweep, .. } => panic!("sweep {} created twice", sweep.id),
    }
    assert!(matches!(
        store.create_sweep(idem("other")).await,
        Err(StoreError::Conflict(_))
    ));

    let paused = store.control_sweep(a.id, SweepAction::Pause).await.unwrap();
    assert_eq!(paused.state, SweepState::Paused);
    let resumed = store.control_sweep(a.id, SweepAction::Resume).await.unwrap();
    assert_eq!(resumed.state, SweepState::Active);
    let cancelled = store.control_sweep(a.id, SweepAction::Cancel).await.unwrap();
    assert_eq!(cancelled.state, SweepState::Cancelled);
    let in_a = store.sweep_cases(a.id).await.unwrap();
    let own = &in_a[0].case;
    assert_eq!(own.state, CaseState::Cancelled);
    assert_eq!(
        last_log(store, own.id).await,
        format!("cancelled with sweep {} before it ran", a.id)
    );
    assert_eq!(
        in_a[2].case.state,
        CaseState::Queued,
        "sweep b still wants mu = 0.3"
    );
    assert!(matches!(
        store.control_sweep(a.id, SweepAction::Resume).await,
        Err(StoreError::Conflict(_))
    ));
    assert!(matches!(
        store.control_sweep(a.id + 100, SweepAction::Pause).await,
        Err(StoreError::NotFound)
    ));

    // Measured points beside a sweep: none, then the last upload.
    assert_eq!(store.measurements(b.id).await.unwrap(), None);
    store.set_measurements(b.id, "[1]").await.unwrap();
    store.set_measurements(b.id, "[2]").await.unwrap();
    assert_eq!(store.measurements(b.id).await.unwrap().as_deref(), Some("[2]"));
    assert_eq!(store.measurements(a.id).await.unwrap(), None, "per sweep");
    assert!(matches!(
        store.set_measurements(b.id + 100, "[]").await,
        Err(StoreError::NotFound)
    ));

    // Fits: ids in order, a view replaced whole, unknown ids.
    let f1 = store.create_fit("running", "{\"a\":1}").await.unwrap();
    let f2 = store.create_fit("running", "{}").await.unwrap();
    assert!(f2 > f1);
    store.update_fit(f1, "done", "{\"a\":2}").await.unwrap();
    assert_eq!(store.get_fit(f1).await.unwrap().as_deref(), Some("{\"a\":2}"));
    assert_eq!(store.get_fit(f2 + 100).await.unwrap(), None);
    assert!(matches!(
        store.update_fit(f2 + 100, "done", "{}").await,
        Err(StoreError::NotFound)
    ));
    let listed: Vec<(i64, String)> = (store.list_fits().await.unwrap().into_iter())
        .map(|(id, status, _)| (id, status))
        .collect();
    assert_eq!(
        listed,
        vec![(f1, "done".to_string()), (f2, "running".to_string())]
    );

    // Refinements: one per sweep, the last put, found by status.
    assert_eq!(store.refinement(a.id).await.unwrap(), None);
    store.put_refinement(a.id, "running", "[1]").await.unwrap();
    store.put_refinement(b.id, "running", "[2]").await.unwrap();
    store.put_refinement(a.id, "done", "[3]").await.unwrap();
    assert_eq!(store.refinement(a.id).await.unwrap().as_deref(), Some("[3]"));
    assert_eq!(
        store.refinements_with_status("running").await.unwrap(),
        vec![(b.id, "[2]".to_string())]
    );
    assert!(matches!(
        store.put_refinement(b.id + 100, "running", "[]").await,
        Err(StoreError::NotFound)
    ));
}

/// Claims and leases: the claim's lease and log line, heartbeats that store
/// progress and report a cancel request, fencing of a stale holder, a
/// withdrawn cancellation, and lease expiry with backoff then failure.
pub(crate) async fn claims(store: &dyn Store) {
    let s = create(store, sweep(&[0.1, 0.2])).await;
    assert_eq!(store.queue_depth().await.unwrap(), 2);
    let before = now_ms();
    let claim = store.claim("w1", LEASE).await.unwrap().expect("a queued case");
    assert_eq!((claim.attempt, claim.lease.fence), (1, 1));
    assert_eq!(store.queue_depth().await.unwrap(), 1);
    let c = case(store, claim.lease.case_id).await;
    assert_eq!(
        (c.state, c.lease_owner.as_deref()),
        (CaseState::Running, Some("w1"))
    );
    let expires = c.lease_expires_at.expect("a lease expiry");
    assert!(expires >= before + 30_000 && expires <= now_ms() + 30_000);
    assert_eq!(last_log(store, c.id).await, "claimed by w1 (attempt 1, fence 1)");

    let progress = Progress {
        fraction: 0.4,
        l_k_bar: 50.0,
        h_bar: 30.0,
        steps: 1000,
    };
    let held = store
        .heartbeat(&claim.lease, Some(&progress), LEASE)
        .await
        .unwrap();
    assert_eq!(held, Heartbeat::Held { cancel: false });
    let c = case(store, claim.lease.case_id).await;
    assert_eq!(c.progress, 0.4);
    assert_eq!(c.progress_detail.map(|p| p.steps), Some(1000));
    let stale = Lease {
        fence: claim.lease.fence + 1,
        ..claim.lease.clone()
    };
    assert_eq!(
        store.heartbeat(&stale, None, LEASE).await.unwrap(),
        Heartbeat::Lost
    );
    assert!(!store.release(&stale).await.unwrap());

    // A cancel request reaches the holder at its heartbeat; a new sweep that
    // wants the case withdraws it, and the stopped run queues it again without
    // counting the attempt.
    store.control_sweep(s.id, SweepAction::Cancel).await.unwrap();
    let cancel = store.heartbeat(&claim.lease, None, LEASE).await.unwrap();
    assert_eq!(cancel, Heartbeat::Held { cancel: true });
    create(store, sweep(&[claim.params.mu])).await;
    assert!(store.finish_cancelled(&claim.lease).await.unwrap());
    let c = case(store, claim.lease.case_id).await;
    assert_eq!((c.state, c.attempts), (CaseState::Queued, 0));
    assert_eq!(
        last_log(store, c.id).await,
        "stopped for a pause, or a cancellation since withdrawn; queued again"
    );

    // Expiry: queued again after a backoff, then failed at the second attempt.
    let first = store
        .claim("w2", Duration::ZERO)
        .await
        .unwrap()
        .expect("the case again");
    assert_eq!(first.lease.case_id, c.id);
    tokio::time::sleep(Duration::from_millis(5)).await;
    assert_eq!(store.requeue_expired().await.unwrap(), 1);
    let c = case(store, c.id).await;
    assert_eq!(c.state, CaseState::Queued);
    assert!(c.not_before > now_ms(), "a backoff of 100..200 ms");
    assert!(store.claim("w3", LEASE).await.unwrap().is_none(), "backing off");
    tokio::time::sleep(Duration::from_millis(250)).await;
    let second = store
        .claim("w3", Duration::ZERO)
        .await
        .unwrap()
        .expect("after the backoff");
    assert_eq!((second.attempt, second.lease.fence), (2, 3));
    tokio::time::sleep(Duration::from_millis(5)).await;
    assert_eq!(store.requeue_expired().await.unwrap(), 1);
    let c = case(store, c.id).await;
    assert_eq!(c.state, CaseState::Failed);
    assert_eq!(
        c.last_error.as_deref(),
        Some("lease expired on attempt 2 of 2 (worker w3 lost)")
    );
    assert!(
        !store.release(&second.lease).await.unwrap(),
        "the failed case has no lease"
    );
}

/// An inversion whose every field holds a value of its own.
fn inversion(l_k_bar: f64) -> Inversion {
    Inversion {
        l_k_bar,
        l_k_arc_bar: l_k_bar - 0.5,
        l_c_over_l: 0.375,
        f_bar_before: 2.25,
        f_bar_after: 1.125,
        h_bar_before: 0.625,
        h_bar_after: 0.25,
        kinetic_energy_ratio: 40.5,
        sample: 17,
    }
}

/// A completed report with everything its summary holds: events, the
/// hysteresis, the quasi-staticity, the scaling and the statistics.
fn full_report(params: CaseParams) -> CaseReport {
    let event = |stage, direction, kind, at| Event {
        stage,
        direction,
        kind,
        at,
        clean: true,
        restarts: 1,
    };
    CaseReport {
        inversion: Some(inversion(120.5)),
        events: vec![
            event(0, Direction::Tighten, EventKind::Inversion, inversion(120.5)),
            event(1, Direction::Loosen, EventKind::FlipBack, inversion(160.25)),
        ],
        hysteresis: Some(Hysteresis {
            inversion_l_k_bar: 120.5,
            flip_back_l_k_bar: 160.25,
            width: 39.75,
        }),
        quasi_static: Some(QuasiStatic {
            kinetic_ratio: 1e-4,
            limit: 5e-3,
            holds: true,
        }),
        scaling: Some(Scaling {
            time_step: 1e-6,
            mass_scale: 1.0,
            time_unit: 1.0,
            pull_rate: 7.1e-5,
            simulated_pull_rate: 7.1e-5,
        }),
        stats: Stats {
            steps: 1234,
            newton_iterations: 4321,
            contact_sweeps: 99,
            relax_steps: 10,
            restarts: 1,
            rejected_steps: 2,
            smallest_dt: 5e-7,
            wall_time: 1.5,
            detection_time: 0.25,
            contact_time: 0.5,
            dynamics_time: 0.625,
        },
        reason: String::new(),
        ..report(params, Status::Completed)
    }
}

/// Results: stored once, only under the current lease; a cancelled run is not
/// a result; the stored outcome, summary, series, snapshots, log line and
/// counts read back typed as they were written.
pub(crate) async fn results(store: &dyn Store) {
    let s = create(store, sweep(&[0.1, 0.2])).await;
    let claim = store.claim("w1", LEASE).await.unwrap().expect("a queued case");
    let id = claim.lease.case_id;
    let cancelled = report(claim.params.clone(), Status::Cancelled);
    assert!(matches!(
        store.complete(&claim.lease, &cancelled).await,
        Err(StoreError::Conflict(_))
    ));
    assert_eq!(case(store, id).await.state, CaseState::Running);
    let done = full_report(claim.params.clone());
    let stale = Lease {
        owner: "w0".to_string(),
        ..claim.lease.clone()
    };
    assert!(!store.complete(&stale, &done).await.unwrap());
    assert!(store.complete(&claim.lease, &done).await.unwrap());
    assert!(!store.complete(&claim.lease, &done).await.unwrap(), "stored once");

    let c = case(store, id).await;
    assert_eq!((c.state, c.status()), (CaseState::Done, CaseStatus::COMPLETED));
    let result = c.result.expect("a result");
    assert_eq!(result.worker, "w1");
    assert_eq!(
        (result.outcome, result.inversion, result.wall_time),
        (Status::Completed, done.inversion, 1.5)
    );
    assert_eq!(
        result.summary,
        ResultDetails::from(&done),
        "the summary reads back typed"
    );
    assert_eq!(result.summary.events, done.events);
    assert_eq!(store.case_series(id).await.unwrap(), Some(Vec::new()));
    assert_eq!(store.case_snapshots(id).await.unwrap(), Some(Vec::new()));
    assert_eq!(store.case_series(id + 100).await.unwrap(), None);
    assert_eq!(store.case_snapshots(id + 100).await.unwrap(), None);
    assert_eq!(store.case_sweeps(id).await.unwrap(), vec![s.id]);
    assert!(
        last_log(store, id)
            .await
            .starts_with("result completed by w1 in ")
    );
    store.append_log(id, "warn", "a note").await.unwrap();
    assert_eq!(last_log(store, id).await, "a note");

    // A solver failure is a result with its status and reason.
    let other = store.claim("w2", LEASE).await.unwrap().expect("the second case");
    let diverged = CaseReport {
        reason: "the step failed at dt 1e-9".to_string(),
        ..report(other.params.clone(), Status::Diverged)
    };
    assert!(store.complete(&other.lease, &diverged).await.unwrap());
    let c = case(store, other.lease.case_id).await;
    assert_eq!(c.status(), CaseStatus::Result(Status::Diverged));
    let result = c.result.expect("a result");
    assert_eq!(
        (result.outcome, result.reason.as_str()),
        (Status::Diverged, "the step failed at dt 1e-9")
    );
    assert_eq!(result.summary, ResultDetails::from(&diverged));
    assert_eq!(
        store.status_counts().await.unwrap(),
        vec![
            (CaseStatus::COMPLETED, 1),
            (CaseStatus::Result(Status::Diverged), 1)
        ]
    );
    assert_eq!(
        store.sweep_status_counts(s.id..=s.id).await.unwrap(),
        vec![
            (s.id, CaseStatus::COMPLETED, 1),
            (s.id, CaseStatus::Result(Status::Diverged), 1)
        ]
    );
}

/// A snapshot labelled `label` of a two-node rod.
fn snapshot(label: SnapshotLabel, l_k_bar: f64) -> solver::snapshot::Snapshot {
    solver::snapshot::Snapshot {
        label,
        l_k_bar,
        time: l_k_bar / 100.0,
        points: vec![[0.0, 0.0, 0.0], [0.5, 0.25, -0.125]],
        twist_rate: vec![1.0, -2.0],
        curvature: vec![0.5, 0.25],
        velocity: vec![[0.0, 0.5, 1.0], [-1.0, 0.25, 0.0]],
        contacts: Vec::new(),
        rods: Vec::new(),
    }
}

/// Labels a report's snapshots take: the start, stage names and events.
const LABELS: [SnapshotLabel; 7] = [
    SnapshotLabel::Relaxed,
    SnapshotLabel::Stage(StageKind::Pull),
    SnapshotLabel::Event(EventWhen::Near, EventKind::Inversion),
    SnapshotLabel::Event(EventWhen::At, EventKind::Inversion),
    SnapshotLabel::Event(EventWhen::After, EventKind::Inversion),
    SnapshotLabel::Event(EventWhen::Before, EventKind::FlipBack),
    SnapshotLabel::Final,
];

/// Packed results: the series comes back bit for bit, the snapshots within
/// the codec's bounds (exact on these values), and each sweep's snapshot
/// choice is honoured: the most of the
/// choices of the sweeps that asked for a case.
pub(crate) async fn packed_results(store: &dyn Store) {
    let chosen = |mus: &[f64], snapshots| NewSweep {
        snapshots,
        ..sweep(mus)
    };
    create(store, chosen(&[0.1], SnapshotChoice::All)).await;
    create(store, chosen(&[0.2, 0.4], SnapshotChoice::Events)).await;
    create(store, chosen(&[0.3, 0.4], SnapshotChoice::None)).await;
    let series: Vec<solver::measurements::Sample> = (0..50)
        .map(|i| solver::measurements::Sample {
            time: i as f64 * 1e-3,
            l_k_bar: 200.0 - 0.37 * i as f64,
            f_bar: (i as f64).sqrt() / 3.0,
            contacts: i,
            stage: i / 20,
            ..Default::default()
        })
        .collect();
    let mut kept = Vec::new();
    while let Some(claim) = store.claim("w1", LEASE).await.unwrap() {
        let done = CaseReport {
            series: series.clone(),
            snapshots: (LABELS.iter().enumerate())
                .map(|(i, label)| snapshot(*label, i as f64))
                .collect(),
            ..report(claim.params.clone(), Status::Completed)
        };
        assert!(store.complete(&claim.lease, &done).await.unwrap());
        let id = claim.lease.case_id;
        let back = store.case_series(id).await.unwrap().expect("a series");
        let bits = |s: &[solver::measurements::Sample]| {
            s.iter()
                .map(|s| (s.time.to_bits(), s.l_k_bar.to_bits(), s.f_bar.to_bits()))
                .collect::<Vec<_>>()
        };
        assert_eq!((&back, bits(&back)), (&series, bits(&series)), "lossless series");
        let snapshots = store.case_snapshots(id).await.unwrap().expect("snapshots");
        let labels: Vec<SnapshotLabel> = snapshots.iter().map(|s| s.label).collect();
        for s in &snapshots {
            let i = LABELS.iter().position(|l| *l == s.label).unwrap();
            assert_eq!(*s, snapshot(s.label, i as f64), "exact on these values");
        }
        kept.push((claim.params.mu, labels));
    }
    kept.sort_by(|a, b| a.0.total_cmp(&b.0));
    let events = LABELS[2..6].to_vec();
    let expected: [(f64, Vec<SnapshotLabel>); 4] = [
        (0.1, LABELS.to_vec()),
        (0.2, events.clone()),
        (0.3, Vec::new()),
        (0.4, events),
    ];
    assert_eq!(kept.len(), 4);
    for ((mu, labels), (expected_mu, expected_labels)) in kept.iter().zip(expected) {
        assert_eq!((*mu, labels.clone()), (expected_mu, expected_labels));
    }
}

/// A bend's snapshots stored and read back: the reef knot's two rods as
/// built, one after the other, keep which nodes are whose (`rods`), and the
/// centre lines come back within the codec's bounds.
pub(crate) async fn bend_snapshots(store: &dyn Store) {
    let params = CaseParams {
        knot: solver::case::KnotKind::Reef,
        ..CaseParams::default()
    };
    let built = params.validated().expect("the reef knot builds");
    let rods = &built.start().rods;
    let points: Vec<[f64; 3]> = rods.iter().flatten().map(|p| [p.x, p.y, p.z]).collect();
    let counts: Vec<usize> = rods.iter().map(Vec::len).collect();
    create(
        store,
        NewSweep {
            cases: vec![NewCase::new(params)],
            ..sweep(&[])
        },
    )
    .await;
    let claim = store.claim("w1", LEASE).await.unwrap().expect("the reef case");
    let shot = solver::snapshot::Snapshot {
        points: points.clone(),
        twist_rate: Vec::new(),
        curvature: Vec::new(),
        velocity: Vec::new(),
        rods: counts.clone(),
        ..snapshot(SnapshotLabel::Relaxed, 150.0)
    };
    let done = CaseReport {
        snapshots: vec![shot.clone(), shot],
        ..report(claim.params.clone(), Status::Completed)
    };
    assert!(store.complete(&claim.lease, &done).await.unwrap());
    let back = store
        .case_snapshots(claim.lease.case_id)
        .await
        .unwrap()
        .expect("snapshots");
    assert_eq!(back.len(), 2);
    for s in &back {
        assert_eq!(s.rods, counts, "two rods of {} nodes", counts[0]);
        let mut nodes = s.points.iter();
        for rod in rods {
            for (p, q) in rod.iter().zip(nodes.by_ref()) {
                for k in 0..3 {
                    assert!(
                        (p[k] - q[k]).abs() <= 2f64.powi(-24) * p[k].abs() + 1e-15,
                        "{p:?} vs {q:?}"
                    );
                }
            }
        }
        assert!(nodes.next().is_none());
    }
}

/// The migrations a database stored before the packed results had run.
pub(crate) fn before_packing(mut migrator: sqlx::migrate::Migrator) -> sqlx::migrate::Migrator {
    const PACKED: i64 = 20261126000000;
    let earlier: Vec<_> = migrator.iter().filter(|m| m.version < PACKED).cloned().collect();
    assert!(
        earlier.len() < migrator.iter().count(),
        "the packing migration exists"
    );
    migrator.migrations = earlier.into();
    migrator
}

/// The series and snapshots of a result stored before the packed columns:
/// JSON text, here in the older names (`force`, `f_bar`) the report's
/// aliases read.
const OLD_SERIES: &str = r#"[{"time":0.0,"l_k_bar":190.5,"l_c_over_l":0.4,"force":0.01,"f_bar":2.5,"width":0.01,"height":0.005,"h_bar":0.5,"kinetic_energy":0.0,"contacts":3,"active_contacts":2,"max_penetration_over_h":0.001,"epsilon":0.7,"phi":1.0,"newton_iterations":4,"dt":0.0001}]"#;
const OLD_SNAPSHOTS: &str =
    r#"[{"label":"at_inversion","l_k_bar":120.0,"points":[[0.0,0.0,0.0],[0.1,0.0,0.0]]}]"#;

/// Writes, through the schema of [`before_packing`], a sweep and a done
/// case whose result holds the series and snapshots as JSON text; returns
/// the case's id.
pub(crate) async fn write_old_result(pool: &sqlx::AnyPool) -> i64 {
    use rows::Columns;
    let sweep = sqlx::query(
        "INSERT INTO sweeps (name, preset, spec, varied, state, created_at, updated_at) \
         VALUES ('old', NULL, '{}', '[\"mu\"]', 'active', 1, 1) RETURNING id",
    )
    .fetch_one(pool)
    .await
    .unwrap()
    .int("id")
    .unwrap();
    let params = serde_json::to_string(&CaseParams::default()).unwrap();
    let case = sqlx::query(
        "INSERT INTO cases (case_key, solver_version, params, status, max_attempts, created_at, finished_at) \
         VALUES ('old-key', 'old', $1, 'done', 3, 1, 2) RETURNING id",
    )
    .bind(params)
    .fetch_one(pool)
    .await
    .unwrap()
    .int("id")
    .unwrap();
    sqlx::query("INSERT INTO sweep_cases (sweep_id, case_id, position) VALUES ($1, $2, 0)")
        .bind(sweep)
        .bind(case)
        .execute(pool)
        .await
        .unwrap();
    sqlx::query(
        "INSERT INTO results (case_id, outcome, reason, inversion, summary, series, snapshots, wall_time, worker, \
         fence, created_at) VALUES ($1, 'completed', '', NULL, '{\"determinant_final\": 7}', $2, $3, 1.5, 'w-old', 1, 2)",
    )
    .bind(case)
    .bind(OLD_SERIES)
    .bind(OLD_SNAPSHOTS)
    .execute(pool)
    .await
    .unwrap();
    case
}

/// The result [`write_old_result`] wrote, read through the migrated store:
/// its JSON text read as the report's types (older names under today's).
pub(crate) async fn read_old_result(store: &dyn Store, id: i64) {
    let c = case(store, id).await;
    assert_eq!((c.state, c.status()), (CaseState::Done, CaseStatus::COMPLETED));
    let result = c.result.expect("a result");
    assert_eq!(result.worker, "w-old");
    assert_eq!(
        result.summary,
        ResultDetails {
            determinant_final: Some(7),
            ..ResultDetails::default()
        },
        "a summary stored before its later fields reads them empty"
    );
    let series = store.case_series(id).await.unwrap().expect("a series");
    assert_eq!(series.len(), 1);
    assert_eq!(
        (
            series[0].l_k_bar,
            series[0].f_bar,
            series[0].force,
            series[0].contacts,
            series[0].l_c_over_l
        ),
        (190.5, 2.5, 0.01, 3, 0.4),
        "the old names read"
    );
    let snapshots = store.case_snapshots(id).await.unwrap().expect("snapshots");
    assert_eq!(snapshots.len(), 1);
    assert_eq!(
        (
            snapshots[0].label,
            snapshots[0].l_k_bar,
            snapshots[0].points.clone()
        ),
        (
            SnapshotLabel::Event(EventWhen::At, EventKind::Inversion),
            120.0,
            vec![[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]]
        )
    );
}
