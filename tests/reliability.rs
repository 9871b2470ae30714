//! The defects found when the service was tried as a new user would (issue
//! 15), one named test each: every one of these failed before its fix.
mod common;

use common::*;
use reqwest::StatusCode;
use serde_json::{Value, json};
use std::io::{Read, Write};
use std::process::Command;
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_knotsweep");

/// Cases the knot builder cannot build are refused at submit (422, the field
/// and the builder's reason), and nothing is stored.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn infeasible_knots_are_refused_at_submit() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let endpoint = format!("{url}/api/sweeps");
    for (base, field, says) in [
        (json!({"nodes": 101}), "base.nodes", "need 158"),
        (json!({"length": 100}), "base.h", "L/16000"),
        (json!({"h": 1e-300}), "base.h", "L/16000"),
        (
            json!({"h": 0.019}),
            "base.h",
            "the knot with n = 3 passes cannot be built",
        ),
    ] {
        let (status, body) = post(&c, &endpoint, &json!({"base": base, "grid": {"mu": [0.1]}})).await;
        assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY, "{base}: {body}");
        let fields = body["fields"].as_array().expect("fields");
        assert!(
            fields
                .iter()
                .any(|f| f["field"] == field && f["reason"].as_str().unwrap().contains(says)),
            "{base}: want {field} saying {says:?}, got {body}"
        );
    }
    let (_, listed) = get(&c, &endpoint).await;
    assert_eq!(listed.as_array().map(Vec::len), Some(0), "{listed}");
    server.shutdown().await.unwrap();
}

/// 405 and 404 answers carry the JSON error body (Swagger UI's too); 405
/// keeps `Allow`.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn error_answers_are_json() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let r = c
        .put(format!("{url}/api/sweeps"))
        .body("{}")
        .send()
        .await
        .unwrap();
    assert_eq!(r.status(), StatusCode::METHOD_NOT_ALLOWED);
    let allow = r.headers()["allow"].to_str().unwrap().to_string();
    assert!(allow.contains("GET") && allow.contains("POST"), "{allow}");
    let body: Value = r.json().await.expect("JSON body");
    assert_eq!(body["error"], "method_not_allowed");
    assert!(body["message"].as_str().unwrap().contains("PUT"), "{body}");
    for path in [
        "/api/no-such-thing",
        "/api/sweeps/999",
        "/api/docs/nothing.js",
        "/nowhere",
    ] {
        let (status, body) = get(&c, &format!("{url}{path}")).await;
        assert_eq!(status, StatusCode::NOT_FOUND, "{path}");
        assert_eq!(body["error"], "not_found", "{path}: {body}");
    }
    server.shutdown().await.unwrap();
}

/// Bodies that serde_json would read silently are refused: duplicate keys
/// (400), a non-JSON media type (415), two `Idempotency-Key` headers (400).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ambiguous_requests_are_refused() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let endpoint = format!("{url}/api/sweeps");
    let (status, body) = post_raw(&c, &endpoint, r#"{"preset": "fig9", "preset": "fig7"}"#, &[]).await;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{body}");
    assert!(
        body["message"].as_str().unwrap().contains("duplicate key"),
        "{body}"
    );
    let r = c
        .post(&endpoint)
        .header("content-type", "text/plain")
        .body(r#"{"preset": "fig9"}"#)
        .send()
        .await
        .unwrap();
    assert_eq!(r.status(), StatusCode::UNSUPPORTED_MEDIA_TYPE);
    let body: Value = r.json().await.unwrap();
    assert_eq!(body["fields"][0]["field"], "Content-Type", "{body}");
    let r = c
        .post(&endpoint)
        .header("content-type", "application/json")
        .header("idempotency-key", "a")
        .header("idempotency-key", "b")
        .body("{}")
        .send()
        .await
        .unwrap();
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    let body: Value = r.json().await.unwrap();
    assert_eq!(body["fields"][0]["field"], "Idempotency-Key", "{body}");
    let (_, listed) = get(&c, &endpoint).await;
    assert_eq!(listed.as_array().map(Vec::len), Some(0), "{listed}");
    server.shutdown().await.unwrap();
}

/// The authentication scheme is case-insensitive (RFC 9110, 11.1).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn lowercase_bearer_is_accepted() {
    let (_dir, db) = temp_db();
    let mut cfg = config(&db, 0);
    cfg.token = Some("s3cret".to_string());
    let server = start(cfg).await;
    let (url, c) = (server.url(), client());
    let endpoint = format!("{url}/api/sweeps");
    for scheme in ["bearer", "BEARER", "Bearer"] {
        let auth = format!("{scheme} s3cret");
        let body = json!({"base": tiny_base(), "grid": {"mu": [0.1]}, "name": scheme}).to_string();
        let (status, body) = post_raw(&c, &endpoint, body, &[("authorization", auth.as_str())]).await;
        assert!(status.is_success(), "{scheme}: {status} {body}");
    }
    let (status, _) = post_raw(&c, &endpoint, "{}", &[("authorization", "Basic s3cret")]).await;
    assert_eq!(status, StatusCode::UNAUTHORIZED);
    server.shutdown().await.unwrap();
}

/// A client whose headers never finish is disconnected after the header
/// timeout instead of holding a connection forever.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn slow_clients_are_cut_off() {
    let (_dir, db) = temp_db();
    let mut cfg = config(&db, 0);
    cfg.header_read_timeout = Duration::from_secs(1);
    let server = start(cfg).await;
    let addr = server.url().trim_start_matches("http://").to_string();
    let closed_after = tokio::task::spawn_blocking(move || {
        let mut s = std::net::TcpStream::connect(addr).unwrap();
        s.write_all(b"GET /healthz HTTP/1.1\r\nHost: x\r\n").unwrap();
        s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
        let started = Instant::now();
        let mut buf = [0u8; 1024];
        // Whatever the server sends (nothing, or a 408), it then closes.
        while let Ok(n) = s.read(&mut buf) {
            if n == 0 {
                return Some(started.elapsed());
            }
        }
        None
    })
    .await
    .unwrap();
    let after = closed_after.expect("connection still open after 20 s");
    assert!(after < Duration::from_secs(10), "closed after {after:?}");
    server.shutdown().await.unwrap();
}

/// An empty `KNOTSWEEP_TOKEN` would silently disable authentication: the
/// server refuses to start and says why.
#[test]
fn an_empty_token_is_refused_at_start() {
    let dir = tempfile::tempdir().unwrap();
    let out = serve_command(dir.path())
        .env("KNOTSWEEP_TOKEN", "")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("KNOTSWEEP_TOKEN is set but empty"), "{err}");
}

/// `--workers` beyond the documented maximum is refused with the bound.
#[test]
fn unbounded_worker_counts_are_refused() {
    let out = Command::new(BIN)
        .args(["worker", "--workers", "100000"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("at most 256"), "{err}");
}

/// Log lines written to a file carry no ANSI colour codes.
#[test]
fn logs_to_a_file_have_no_colour_codes() {
    let out = Command::new(BIN)
        .args(["run", "--relax-time", "0.01", "--min-l-k-bar", "430", "--out"])
        .arg(tempfile::NamedTempFile::new().unwrap().path())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("running case"), "{err}");
    assert!(!err.contains('\u{1b}'), "{err}");
}

/// `sweep` with neither `--preset` nor `--spec` names both.
#[test]
fn sweep_without_a_specification_names_the_flags() {
    let out = Command::new(BIN).arg("sweep").output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--preset") && err.contains("--spec"), "{err}");
}

/// A database URL of another backend is named as unsupported, once.
#[test]
fn unsupported_database_urls_say_so() {
    let out = Command::new(BIN)
        .args(["worker", "--database-url", "mysql://127.0.0.1/none"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("mysql:// databases are not supported"), "{err}");
    assert_eq!(err.matches("not supported").count(), 1, "{err}");
}

/// A PostgreSQL URL whose server does not answer says which server.
#[test]
fn unreachable_postgres_says_which_server() {
    // Port 1 on loopback: nothing listens there.
    let out = Command::new(BIN)
        .args(["worker", "--database-url", "postgres://postgres@127.0.0.1:1/none"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cannot reach PostgreSQL at 127.0.0.1:1"), "{err}");
}

/// Reasons users read carry values as users write them, not Rust's Debug
/// forms (`None`, `Some(5)`).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn reasons_have_no_debug_formatting() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 1)).await;
    let (url, c) = (server.url(), client());
    let id = submit_sweep(&c, &url, &json!({"base": tiny_base()})).await;
    wait_sweep(&c, &url, id, Duration::from_secs(60), finished).await;
    let (_, diagram) = get(&c, &format!("{url}/api/sweeps/{id}/phase-diagram")).await;
    let reason = diagram["points"][0]["reason"].as_str().unwrap().to_string();
    assert!(reason.contains("no inversion"), "{reason}");
    assert!(!reason.contains("None") && !reason.contains("Some("), "{reason}");
    server.shutdown().await.unwrap();
}

/// `GET /api/sweeps` is paginated: `limit` and `offset`, the total in
/// `X-Total-Count`, the next page in `Link`; a bad limit is a 400 naming it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sweeps_are_listed_a_page_at_a_time() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let mut ids = Vec::new();
    for mu in [0.1, 0.2, 0.3] {
        ids.push(submit_sweep(&c, &url, &json!({"base": tiny_base(), "grid": {"mu": [mu]}})).await);
    }
    let r = c.get(format!("{url}/api/sweeps?limit=2")).send().await.unwrap();
    assert_eq!(r.headers()["x-total-count"], "3");
    let link = r.headers()["link"].to_str().unwrap().to_string();
    assert_eq!(link, "</api/sweeps?limit=2&offset=2>; rel=\"next\"");
    let page: Value = r.json().await.unwrap();
    let got: Vec<i64> = page
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["id"].as_i64().unwrap())
        .collect();
    assert_eq!(got, ids[..2]);
    let r = c
        .get(format!("{url}/api/sweeps?limit=2&offset=2"))
        .send()
        .await
        .unwrap();
    assert!(r.headers().get("link").is_none());
    let page: Value = r.json().await.unwrap();
    assert_eq!(page[0]["id"], ids[2]);
    assert_eq!(
        page[0]["counts"],
        json!({"queued": 1}),
        "a later page carries its sweeps' counts"
    );
    for bad in ["limit=0", "limit=5000", "limit=x"] {
        let (status, body) = get(&c, &format!("{url}/api/sweeps?{bad}")).await;
        assert_eq!(status, StatusCode::BAD_REQUEST, "{bad}: {body}");
        assert_eq!(body["error"], "bad_request", "{bad}: {body}");
    }
    server.shutdown().await.unwrap();
}

/// Defect 9: a finished case shows no stale progress, and a finished sweep no ETA.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn finished_cases_carry_no_stale_progress_and_done_sweeps_no_eta() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 1)).await;
    let (url, c) = (server.url(), client());
    // Long enough for heartbeats (every 0.67 s) to store progress while it runs.
    let id = submit_sweep(&c, &url, &json!({"base": long_base()})).await;
    let running = wait_sweep(&c, &url, id, Duration::from_secs(60), |s| {
        s["cases"][0]["progress_detail"].is_object()
    })
    .await;
    assert!(running["cases"][0]["progress"].as_f64().unwrap() < 1.0);
    let done = wait_sweep(&c, &url, id, Duration::from_secs(120), finished).await;
    assert!(done["eta_seconds"].is_null(), "{done:#}");
    for case in done["cases"].as_array().unwrap() {
        assert_eq!(case["progress"], 1.0, "{case:#}");
        assert!(case["progress_detail"].is_null(), "stale progress: {case:#}");
        let (_, detail) = get(&c, &format!("{url}/api/cases/{}", case["case_id"])).await;
        assert!(detail["progress_detail"].is_null(), "{detail:#}");
    }
    server.shutdown().await.unwrap();
}

/// The soak benchmark (`xtask bench-soak`), shortened: 10 clients replaying
/// 6 minutes of submits, polls and cancels against stand-in workers lose and
/// duplicate no sweep or case (the full run, with its memory check, is in
/// BENCHMARKS.md).
#[test]
fn a_short_soak_loses_and_duplicates_nothing() {
    use clap::Parser;
    let args = xtask::bench_soak::Args::parse_from([
        "bench-soak",
        "--knotsweep",
        BIN,
        "--clients",
        "10",
        "--minutes",
        "6",
        "--no-memory-check",
    ]);
    let mut out = Vec::new();
    let result = xtask::bench_soak::run(args, &mut out);
    let stdout = String::from_utf8_lossy(&out);
    assert!(result.is_ok(), "{stdout}\n{result:?}");
    assert!(stdout.contains("20 sweeps (4 cancelled)"), "{stdout}");
    assert!(
        stdout.contains("no accepted sweep or case lost or duplicated"),
        "{stdout}"
    );
}
