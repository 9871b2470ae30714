//! The queue survives a crash of its PostgreSQL server: a private server
//! (`initdb` and `pg_ctl` in a temporary directory, its own port on
//! 127.0.0.1) is killed with SIGKILL while stand-in workers hold leases, then
//! started again; the sweep completes with no case lost and none run twice.
//! The workers claim, heartbeat and store synthetic results through the
//! `Store` trait, as in `store_conformance.rs` (the solver is not the
//! subject). Where the server binaries are not installed it is skipped with
//! the reason, or fails when `CI` is set (`common::missing`).
mod common;

use common::missing;
use knotsweep_worker::store::{
    CaseState, Claim, CreateOutcome, Heartbeat, NewCase, NewSweep, SnapshotChoice, Store, StoreOptions,
    open_store,
};
use solver::case::CaseParams;
use solver::protocol::{CaseReport, Status};
use std::collections::HashSet;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

const CASES: usize = 12;
const WORKERS: usize = 4;
/// How long a stand-in computes a case.
const HOLD: Duration = Duration::from_millis(1500);
const BEAT: Duration = Duration::from_millis(100);
/// How long the server stays down.
const OUTAGE: Duration = Duration::from_millis(500);
/// Far longer than the outage: no lease expires.
const LEASE: Duration = Duration::from_secs(30);

/// A PostgreSQL server of this test's own, stopped when dropped.
struct Server {
    bin: PathBuf,
    dir: tempfile::TempDir,
    port: u16,
    /// The `postgres` user's uid and gid when we are root (the server
    /// refuses to run as root).
    user: Option<(u32, u32)>,
}

impl Server {
    /// `initdb` in a new temporary directory, or why it cannot be done.
    fn init() -> Result<Self, String> {
        let bin = bin_dir().ok_or("no PostgreSQL server binaries (initdb, pg_ctl) are installed")?;
        // SAFETY: geteuid has no preconditions.
        let user = if unsafe { libc::geteuid() } == 0 {
            Some(postgres_user().ok_or("running as root and there is no postgres user")?)
        } else {
            None
        };
        let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
        if let Some((uid, gid)) = user {
            std::os::unix::fs::chown(dir.path(), Some(uid), Some(gid)).map_err(|e| e.to_string())?;
        }
        let port = std::net::TcpListener::bind("127.0.0.1:0")
            .and_then(|l| l.local_addr())
            .map_err(|e| e.to_string())?
            .port();
        let server = Self { bin, dir, port, user };
        let data = server.data();
        server.run(
            "initdb",
            &[
                "-D",
                &data,
                "-U",
                "postgres",
                "-A",
                "trust",
                "--no-sync",
                "--no-locale",
            ],
        );
        Ok(server)
    }

    fn data(&self) -> String {
        self.dir.path().join("data").display().to_string()
    }

    /// Runs a server binary as the server's user, panicking with its output on failure.
    fn run(&self, tool: &str, args: &[&str]) {
        let mut command = Command::new(self.bin.join(tool));
        command.args(args).current_dir(self.dir.path());
        if let Some((uid, gid)) = self.user {
            command.uid(uid).gid(gid);
        }
        let out = command.output().unwrap_or_else(|e| panic!("{tool}: {e}"));
        assert!(
            out.status.success(),
            "{tool} {args:?}: {}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }

    /// Starts the server and waits until it accepts connections.
    fn start(&self) {
        let options = format!(
            "-p {} -k {} -c listen_addresses=127.0.0.1",
            self.port,
            self.dir.path().display()
        );
        let log = self.dir.path().join("server.log").display().to_string();
        self.run(
            "pg_ctl",
            &[
                "start",
                "-w",
                "-t",
                "30",
                "-D",
                &self.data(),
                "-l",
                &log,
                "-o",
                &options,
            ],
        );
    }

    /// The postmaster's pid.
    fn pid(&self) -> i32 {
        let file =
            std::fs::read_to_string(Path::new(&self.data()).join("postmaster.pid")).expect("postmaster.pid");
        file.lines()
            .next()
            .and_then(|l| l.trim().parse().ok())
            .expect("a pid")
    }

    /// SIGKILL to the postmaster and every backend (pg_ctl makes the
    /// postmaster the leader of its own process group), then reaps them.
    fn kill(&self) {
        let pid = self.pid();
        // SAFETY: getpgid and kill on a pid of the server this test started.
        let group = unsafe { libc::getpgid(pid) };
        assert_eq!(group, pid, "the postmaster leads its process group");
        assert_eq!(unsafe { libc::kill(-pid, libc::SIGKILL) }, 0, "kill failed");
        let start = Instant::now();
        while running_in_group(pid) {
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "the server survived SIGKILL"
            );
            std::thread::sleep(Duration::from_millis(10));
        }
        reap_zombie_children();
        assert!(
            !Path::new(&format!("/proc/{pid}")).exists(),
            "postmaster {pid} not reaped"
        );
    }

    fn url(&self) -> String {
        format!("postgres://postgres@127.0.0.1:{}/postgres", self.port)
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let mut command = Command::new(self.bin.join("pg_ctl"));
        command
            .args(["stop", "-m", "immediate", "-D", &self.data()])
            .current_dir(self.dir.path());
        if let Some((uid, gid)) = self.user {
            command.uid(uid).gid(gid);
        }
        let _ = command.output();
        reap_zombie_children();
    }
}

/// The newest `/usr/lib/postgresql/<version>/bin`, else a `PATH` entry, that
/// holds `initdb` and `pg_ctl`.
fn bin_dir() -> Option<PathBuf> {
    let mut versions: Vec<(u32, PathBuf)> = std::fs::read_dir("/usr/lib/postgresql")
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| Some((e.file_name().to_str()?.parse().ok()?, e.path().join("bin"))))
        .collect();
    versions.sort_by_key(|(version, _)| std::cmp::Reverse(*version));
    let path = std::env::var_os("PATH").unwrap_or_default();
    (versions.into_iter().map(|(_, dir)| dir))
        .chain(std::env::split_paths(&path))
        .find(|dir| dir.join("initdb").is_file() && dir.join("pg_ctl").is_file())
}

fn postgres_user() -> Option<(u32, u32)> {
    // SAFETY: getpwnam with a NUL-terminated name; the entry is read at once.
    let entry = unsafe { libc::getpwnam(c"postgres".as_ptr()) };
    // SAFETY: a non-null entry points to a valid passwd.
    (!entry.is_null()).then(|| unsafe { ((*entry).pw_uid, (*entry).pw_gid) })
}

/// `/proc/<pid>/stat` as (state, parent, process group).
fn stat(pid: &str) -> Option<(char, i32, i32)> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name, in parentheses, may hold spaces.
    let mut fields = stat.rsplit_once(')')?.1.split_whitespace();
    let state = fields.next()?.chars().next()?;
    Some((state, fields.next()?.parse().ok()?, fields.next()?.parse().ok()?))
}

fn processes() -> impl Iterator<Item = (i32, (char, i32, i32))> {
    std::fs::read_dir("/proc")
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_str()?.to_string();
            Some((name.parse().ok()?, stat(&name)?))
        })
}

/// Some process of this group is still running (not a zombie).
fn running_in_group(group: i32) -> bool {
    processes().any(|(_, (state, _, g))| g == group && state != 'Z')
}

/// Reaps the dead processes that were orphaned to this one (this test is
/// their subreaper: a machine whose init reaps nothing would otherwise keep
/// the dead postmaster's pid alive, and the restart would refuse its lock
/// file).
fn reap_zombie_children() {
    let me = std::process::id() as i32;
    for (pid, _) in processes().filter(|(_, (state, parent, _))| *state == 'Z' && *parent == me) {
        // SAFETY: waitpid on a dead child of this process.
        unsafe { libc::waitpid(pid, std::ptr::null_mut(), libc::WNOHANG) };
    }
}

/// What the stand-in workers saw.
#[derive(Default)]
struct Seen {
    /// Cases whose result a worker stored.
    stored: Mutex<Vec<i64>>,
    /// Cases a worker found taken from it (lease lost, result refused).
    lost: Mutex<Vec<i64>>,
    /// Claims that have had a heartbeat (each one durable from then on).
    beaten: AtomicUsize,
    /// Store calls that failed (the server was down).
    errors: AtomicUsize,
    /// The longest heartbeat in ms (one waits for the server to come back).
    slowest_beat_ms: AtomicU64,
}

/// Claims cases and computes each for [`HOLD`], heartbeating, until `done`.
async fn stand_in(store: Arc<dyn Store>, name: String, seen: Arc<Seen>, done: Arc<AtomicBool>) {
    while !done.load(Ordering::Relaxed) {
        match store.claim(&name, LEASE).await {
            Ok(Some(claim)) => compute(&*store, claim, &seen).await,
            Ok(None) => tokio::time::sleep(Duration::from_millis(50)).await,
            Err(_) => {
                seen.errors.fetch_add(1, Ordering::Relaxed);
                tokio::time::sleep(Duration::from_millis(50)).await;
            }
        }
    }
}

/// Holds the case for [`HOLD`] with heartbeats (the work goes on while the
/// server is down), then stores a synthetic result, retrying until the server
/// answers.
async fn compute(store: &dyn Store, claim: Claim, seen: &Seen) {
    let id = claim.lease.case_id;
    let (until, mut beats) = (Instant::now() + HOLD, 0);
    while Instant::now() < until {
        tokio::time::sleep(BEAT).await;
        let sent = Instant::now();
        let beat = store.heartbeat(&claim.lease, None, LEASE).await;
        let took = sent.elapsed().as_millis() as u64;
        seen.slowest_beat_ms.fetch_max(took, Ordering::Relaxed);
        match beat {
            Ok(Heartbeat::Held { .. }) => {
                beats += 1;
                if beats == 1 {
                    seen.beaten.fetch_add(1, Ordering::Relaxed);
                }
            }
            Ok(Heartbeat::Lost) => {
                seen.lost.lock().unwrap().push(id);
                return;
            }
            Err(_) => {
                seen.errors.fetch_add(1, Ordering::Relaxed);
            }
        }
    }
    let report = CaseReport::empty(claim.params.clone(), Status::Completed);
    loop {
        match store.complete(&claim.lease, &report).await {
            Ok(stored) => {
                let list = if stored { &seen.stored } else { &seen.lost };
                list.lock().unwrap().push(id);
                return;
            }
            Err(_) => {
                seen.errors.fetch_add(1, Ordering::Relaxed);
                tokio::time::sleep(Duration::from_millis(50)).await;
            }
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn a_sigkilled_postgres_loses_no_case_and_runs_none_twice() {
    let server = match Server::init() {
        Ok(s) => s,
        Err(why) => return missing(&why),
    };
    // Orphans of the server come to this process, which reaps them.
    // SAFETY: prctl with an integer argument.
    assert_eq!(unsafe { libc::prctl(libc::PR_SET_CHILD_SUBREAPER, 1) }, 0);
    server.start();
    let store = open_store(&server.url(), StoreOptions::default()).await.unwrap();
    let cases = (0..CASES)
        .map(|i| {
            NewCase::new(CaseParams {
                mu: 0.01 * i as f64,
                ..CaseParams::default()
            })
        })
        .collect();
    let sweep = NewSweep {
        name: None,
        preset: None,
        spec: serde_json::json!({}),
        varied: vec!["mu".to_string()],
        snapshots: SnapshotChoice::All,
        cases,
        idempotency: None,
    };
    let CreateOutcome::Created { sweep, .. } = store.create_sweep(sweep).await.unwrap() else {
        panic!("a new sweep")
    };
    let (seen, done) = (Arc::new(Seen::default()), Arc::new(AtomicBool::new(false)));
    let workers: Vec<_> = (0..WORKERS)
        .map(|w| {
            tokio::spawn(stand_in(
                store.clone(),
                format!("w{w}"),
                seen.clone(),
                done.clone(),
            ))
        })
        .collect();

    // Every worker holds a lease that a heartbeat has made durable: kill.
    let start = Instant::now();
    while seen.beaten.load(Ordering::Relaxed) < WORKERS {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "the workers did not claim"
        );
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    let before = server.pid();
    tokio::task::block_in_place(|| server.kill());
    tokio::time::sleep(OUTAGE).await;
    tokio::task::block_in_place(|| server.start());
    assert_ne!(server.pid(), before, "a new postmaster");

    let start = Instant::now();
    let finished = loop {
        if let Ok(cases) = store.sweep_cases(sweep.id).await {
            if cases.iter().all(|c| c.case.state.is_terminal()) {
                break cases;
            }
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the sweep did not finish"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    };
    done.store(true, Ordering::Relaxed);
    for w in workers {
        w.await.unwrap();
    }

    let mut stored = seen.stored.lock().unwrap().clone();
    assert!(seen.lost.lock().unwrap().is_empty(), "{:?}", seen.lost);
    stored.sort();
    let mut ids: Vec<i64> = finished.iter().map(|c| c.case.id).collect();
    ids.sort();
    assert_eq!(stored, ids, "each case's result stored once");
    for c in &finished {
        let case = &c.case;
        assert_eq!(case.state, CaseState::Done, "case {} lost: {case:?}", case.id);
        assert_eq!(case.attempts, 1, "case {} ran twice: {case:?}", case.id);
        let logs = store.case_logs(case.id).await.unwrap();
        let count = |prefix: &str| logs.iter().filter(|l| l.message.starts_with(prefix)).count();
        assert_eq!(
            (count("claimed by"), count("result ")),
            (1, 1),
            "case {}: {logs:?}",
            case.id
        );
    }
    let slowest = Duration::from_millis(seen.slowest_beat_ms.load(Ordering::Relaxed));
    assert!(
        slowest >= OUTAGE,
        "no heartbeat waited for the server ({slowest:?})"
    );
    let distinct: HashSet<&String> = finished
        .iter()
        .filter_map(|c| c.case.result.as_ref())
        .map(|r| &r.worker)
        .collect();
    println!(
        "{CASES} cases by {} workers across a SIGKILL of the server: the slowest heartbeat took {slowest:?}, \
         {} store calls failed",
        distinct.len(),
        seen.errors.load(Ordering::Relaxed)
    );
    store.close().await;
}
