//! Beyond one machine (docs/scale-out.md): the compose file, the Slurm recipe
//! on a real single-node cluster, and workers in separate network namespaces
//! sharing PostgreSQL over a link that is cut mid-case. Where its engine
//! (docker-compose, sbatch, PostgreSQL, `ip netns`) is missing, each test is
//! skipped with the reason, or fails when `CI` is set (`common::missing`).
mod common;

use common::*;
use serde_json::{Value, json};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_knotsweep");

fn installed(tool: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Kills a child process when dropped.
struct Killed(Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn the_compose_file_is_valid_and_runs_postgres_a_server_and_scalable_workers() {
    if !installed("docker-compose") {
        return missing("docker-compose is not installed (apt-get install docker-compose)");
    }
    let root = env!("CARGO_MANIFEST_DIR");
    let out = Command::new("docker-compose")
        .args(["-f", &format!("{root}/docker-compose.yml"), "config"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for needle in [
        "postgres:",
        "server:",
        "worker:",
        "replicas: 2",
        "healthcheck:",
        "pgdata:",
    ] {
        assert!(text.contains(needle), "no {needle} in\n{text}");
    }
}

/// `sbatch --array` of deploy/slurm/worker.sbatch drains a sweep queued on
/// PostgreSQL: every case runs once, and the array tasks exit when idle.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_slurm_job_array_of_workers_drains_a_postgres_sweep() {
    if !installed("sbatch") {
        return missing(
            "sbatch is not installed (slurm-wlm; deploy/slurm/local-cluster.sh starts a local cluster)",
        );
    }
    let idle = Command::new("sinfo").args(["-h", "-o", "%T"]).output();
    if !idle.is_ok_and(|o| String::from_utf8_lossy(&o.stdout).contains("idle")) {
        return missing("no idle Slurm node (run deploy/slurm/local-cluster.sh as root)");
    }
    let (db_url, admin, db) = match fresh_postgres("slurm").await {
        Ok(v) => v,
        Err(why) => return missing(&why),
    };
    let server = start(config(&db_url, 0)).await;
    let (url, c) = (server.url(), client());
    let id = submit_sweep(
        &c,
        &url,
        &json!({"base": tiny_base(), "grid": {"mu": [0.1, 0.3, 0.5]}}),
    )
    .await;
    let logs = tempfile::tempdir().unwrap();
    let script = format!("{}/deploy/slurm/worker.sbatch", env!("CARGO_MANIFEST_DIR"));
    let out = Command::new("sbatch")
        .args([
            "--parsable",
            "--array=1-2",
            "--cpus-per-task=1",
            &format!("--output={}/w-%A_%a.log", logs.path().display()),
            &script,
        ])
        .env("DATABASE_URL", &db_url)
        .env("KNOTSWEEP", BIN)
        .env("KNOTSWEEP_IDLE_SECONDS", "3")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let job = String::from_utf8_lossy(&out.stdout).trim().to_string();
    let sweep = wait_sweep(&c, &url, id, Duration::from_secs(300), finished).await;
    let cases: Vec<&Value> = sweep["cases"].as_array().unwrap().iter().collect();
    assert_eq!(cases.len(), 3);
    for case in &cases {
        assert_eq!(case["status"], "completed", "{case:#}");
        assert_eq!(case["attempts"], 1, "each case ran once: {case:#}");
    }
    // The array tasks exit on their own once the queue is idle.
    let t = Instant::now();
    loop {
        let q = Command::new("squeue").args(["-h", "-j", &job]).output().unwrap();
        if String::from_utf8_lossy(&q.stdout).trim().is_empty() {
            break;
        }
        assert!(t.elapsed() < Duration::from_secs(60), "array {job} still running");
        tokio::time::sleep(Duration::from_millis(500)).await;
    }
    let written: String = std::fs::read_dir(logs.path())
        .unwrap()
        .map(|e| std::fs::read_to_string(e.unwrap().path()).unwrap())
        .collect();
    assert!(
        written.contains("reason=Idle"),
        "each task exits when idle:\n{written}"
    );
    server.shutdown().await.unwrap();
    drop_database(&admin, &db).await;
}

/// Runs `ip` with `args`, panicking with its stderr on failure.
fn ip(args: &[&str]) {
    let out = Command::new("ip").args(args).output().unwrap();
    assert!(
        out.status.success(),
        "ip {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A network namespace joined to this one by a veth pair (/30 network).
struct Namespace {
    name: String,
    host_if: String,
    host_ip: String,
    ns_ip: String,
}

impl Namespace {
    fn create() -> Result<Self, String> {
        let tag = std::process::id() % 100_000;
        let name = format!("ks{tag}");
        let host_if = format!("ksh{tag}");
        let ns_if = format!("ksn{tag}");
        let subnet = 16 + tag % 200;
        let (host_ip, ns_ip) = (format!("10.213.{subnet}.1"), format!("10.213.{subnet}.2"));
        let out = Command::new("ip").args(["netns", "add", &name]).output();
        match out {
            Ok(o) if o.status.success() => {}
            Ok(o) => {
                return Err(format!(
                    "ip netns add: {}",
                    String::from_utf8_lossy(&o.stderr).trim()
                ));
            }
            Err(e) => return Err(format!("no ip command: {e}")),
        }
        let ns = Self {
            name,
            host_if,
            host_ip,
            ns_ip,
        };
        ip(&["link", "add", &ns.host_if, "type", "veth", "peer", "name", &ns_if]);
        ip(&["link", "set", &ns_if, "netns", &ns.name]);
        ip(&["addr", "add", &format!("{}/30", ns.host_ip), "dev", &ns.host_if]);
        ip(&["link", "set", &ns.host_if, "up"]);
        let inside = |args: &[&str]| {
            let mut all = vec!["netns", "exec", &ns.name, "ip"];
            all.extend_from_slice(args);
            ip(&all);
        };
        inside(&["addr", "add", &format!("{}/30", ns.ns_ip), "dev", &ns_if]);
        inside(&["link", "set", &ns_if, "up"]);
        inside(&["link", "set", "lo", "up"]);
        Ok(ns)
    }

    fn cut(&self) {
        ip(&["link", "set", &self.host_if, "down"]);
    }
}

impl Drop for Namespace {
    fn drop(&mut self) {
        let _ = Command::new("ip").args(["link", "del", &self.host_if]).output();
        let _ = Command::new("ip").args(["netns", "del", &self.name]).output();
    }
}

/// Forwards TCP connections from `listen` to `target` (PostgreSQL listens on
/// loopback only; the namespace reaches it through this relay on the veth address).
async fn relay(listen: &str, target: String) -> String {
    let listener = tokio::net::TcpListener::bind(format!("{listen}:0"))
        .await
        .unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    tokio::spawn(async move {
        while let Ok((mut inbound, _)) = listener.accept().await {
            let target = target.clone();
            tokio::spawn(async move {
                if let Ok(mut outbound) = tokio::net::TcpStream::connect(&target).await {
                    let _ = tokio::io::copy_bidirectional(&mut inbound, &mut outbound).await;
                }
            });
        }
    });
    addr
}

/// A worker in its own network namespace claims a case over a real link; the
/// link goes down mid-case; its lease expires and a worker on the other side
/// completes the case, which is stored exactly once.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_worker_cut_off_mid_case_loses_the_case_to_another_which_completes_it_once() {
    let ns = match Namespace::create() {
        Ok(ns) => ns,
        Err(why) => return missing(&format!("cannot create a network namespace ({why})")),
    };
    let (db_url, admin, db) = match fresh_postgres("netns").await {
        Ok(v) => v,
        Err(why) => return missing(&why),
    };
    let pg = test_postgres();
    let hostport = pg
        .split('@')
        .nth(1)
        .and_then(|r| r.split('/').next())
        .unwrap()
        .to_string();
    let relayed = relay(&ns.host_ip, hostport).await;
    let remote_url = db_url.replacen(
        db_url.split('@').nth(1).unwrap().split('/').next().unwrap(),
        &relayed,
        1,
    );
    let server = start(config(&db_url, 0)).await;
    let (url, c) = (server.url(), client());
    let id = submit_sweep(&c, &url, &json!({"base": long_base()})).await;
    let worker = |mut cmd: Command, url: &str| {
        cmd.args([
            "worker",
            "--database-url",
            url,
            "--workers",
            "1",
            "--lease-seconds",
            "2",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null());
        Killed(cmd.spawn().unwrap())
    };
    let mut in_namespace = Command::new("ip");
    in_namespace.args(["netns", "exec", &ns.name, BIN]);
    let _remote = worker(in_namespace, &remote_url);
    // The remote worker claims the case over the link.
    let running = wait_sweep(&c, &url, id, Duration::from_secs(60), |s| {
        s["cases"][0]["status"] == "running"
    })
    .await;
    let case_id = running["cases"][0]["case_id"].as_i64().unwrap();
    let (_, case) = get(&c, &format!("{url}/api/cases/{case_id}")).await;
    let remote_owner = case["lease_owner"].as_str().unwrap().to_string();
    assert_eq!(case["attempts"], 1);
    ns.cut();
    let _local = worker(Command::new(BIN), &db_url);
    wait_sweep(&c, &url, id, Duration::from_secs(180), finished).await;
    let (_, case) = get(&c, &format!("{url}/api/cases/{case_id}")).await;
    assert_eq!(case["status"], "completed", "{case:#}");
    assert_eq!(
        case["attempts"], 2,
        "claimed again after the lease expired: {case:#}"
    );
    let stored_by = case["result"]["worker"].as_str().unwrap();
    assert_ne!(
        stored_by, remote_owner,
        "the cut-off worker cannot store a result"
    );
    let messages: Vec<&str> = case["logs"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|l| l["message"].as_str())
        .collect();
    assert!(
        messages
            .iter()
            .any(|m| m.contains(&format!("lease of worker {remote_owner} expired"))),
        "{messages:#?}"
    );
    assert_eq!(
        messages.iter().filter(|m| m.starts_with("result ")).count(),
        1,
        "{messages:#?}"
    );
    server.shutdown().await.unwrap();
    drop_database(&admin, &db).await;
}
