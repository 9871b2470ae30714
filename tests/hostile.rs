//! Hostile and careless clients against a real server (issue 44): equal
//! values written apart, grids whose checks take seconds, many event
//! streams, requests from other sites, and the small faults (offsets out of
//! range, cancelling a finished sweep, slow bodies, bad tokens, 404s under
//! `/api/docs/`, the OpenAPI document's security).
mod common;

use common::*;
use reqwest::StatusCode;
use serde_json::{Value, json};
use std::io::{Read, Write};
use std::net::IpAddr;
use std::time::{Duration, Instant};

/// The answer to a POST of `body` with `headers` (none added).
async fn send(c: &reqwest::Client, url: &str, body: &str, headers: &[(&str, &str)]) -> (StatusCode, Value) {
    let mut request = c.post(url).body(body.to_string());
    for (k, v) in headers {
        request = request.header(*k, *v);
    }
    let r = request.send().await.expect("request");
    let status = r.status();
    (status, r.json().await.unwrap_or(Value::Null))
}

fn fields(error: &Value) -> Vec<(String, String)> {
    error["fields"]
        .as_array()
        .map(|f| {
            f.iter()
                .map(|f| {
                    (
                        f["field"].as_str().unwrap().to_string(),
                        f["reason"].as_str().unwrap().to_string(),
                    )
                })
                .collect()
        })
        .unwrap_or_default()
}

/// Values the case key makes one case, written apart, are refused at submit
/// naming the second one with the first; nothing is stored and no answer
/// speaks of the database.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn equal_values_written_apart_are_refused_naming_both() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let endpoint = format!("{url}/api/sweeps");
    let base = json!({"n": 1, "nodes": 158, "h": 0.004});
    for (grid, field, reason) in [
        (
            json!({"mu": [1, 1.0]}),
            "grid.mu[1]",
            "the same case as grid.mu[0]",
        ),
        (
            json!({"mu": [0.1, 0, -0.0]}),
            "grid.mu[2]",
            "the same case as grid.mu[1]",
        ),
        (
            json!({"youngs_modulus": [1.8e6, 2e6, 1800000]}),
            "grid.youngs_modulus[2]",
            "the same case as grid.youngs_modulus[0]",
        ),
        (
            json!({"loading": [[{"pull": {}}], [{"pull": {"to_l_k_bar": null}}]]}),
            "grid.loading[1]",
            "the same case as grid.loading[0]",
        ),
        (
            json!({"mu": [0.2, 0.3], "relax_time": [0.01, 0.010]}),
            "grid.relax_time[1]",
            "the same case as grid.relax_time[0]",
        ),
        (
            json!({"material": ["steel", "steel"]}),
            "grid.material[1]",
            "the same case as grid.material[0]",
        ),
    ] {
        let (status, error) = post(&c, &endpoint, &json!({"base": base, "grid": grid})).await;
        assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY, "{grid}: {error}");
        assert_eq!(
            fields(&error)[0],
            (field.to_string(), reason.to_string()),
            "{grid}: {error}"
        );
        let text = error.to_string().to_lowercase();
        for word in ["unique", "constraint", "storage", "sql"] {
            assert!(!text.contains(word), "{grid}: {error}");
        }
    }
    // A parameter in both base and grid: the grid would win silently.
    let (status, error) = post(
        &c,
        &endpoint,
        &json!({"base": {"mu": 0.3}, "grid": {"mu": [0.1, 0.2]}}),
    )
    .await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY, "{error}");
    assert_eq!(fields(&error)[0].0, "base.mu", "{error}");
    let (status, error) = post(&c, &endpoint, &json!({"preset": "fig7", "base": {"h": 0.002}})).await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY, "{error}");
    assert_eq!(fields(&error)[0].0, "base.h", "{error}");
    assert!(fields(&error)[0].1.contains("fig7"), "{error}");
    // Types in the table's words.
    let (status, error) = post(&c, &endpoint, &json!({"base": {"n": "three", "h": "thin"}})).await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY, "{error}");
    assert_eq!(
        fields(&error),
        [
            (
                "base.h".to_string(),
                "must be a number in [L/16000, L/50) m, got \"thin\"".to_string()
            ),
            (
                "base.n".to_string(),
                "must be a whole number in 1..=8, got \"three\"".to_string()
            ),
        ],
        "{error}"
    );
    let (_, listed) = get(&c, &endpoint).await;
    assert_eq!(listed, json!([]), "nothing stored");
    server.shutdown().await.unwrap();
}

/// A store that fails is logged with its detail and answered without it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_failing_store_is_answered_without_its_detail() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    server.store().close().await;
    let (status, error) = get(&c, &format!("{url}/api/sweeps")).await;
    assert_eq!(status, StatusCode::SERVICE_UNAVAILABLE, "{error}");
    assert_eq!(error["error"], "unavailable");
    let text = error["message"].as_str().unwrap();
    assert!(text.starts_with("the database is unavailable"), "{error}");
    for word in ["pool", "closed", "sqlx", "sqlite"] {
        assert!(!text.contains(word), "{error}");
    }
    server.shutdown().await.unwrap();
}

/// While a grid of 1 000 distinct knots is checked (each built once, off the
/// async runtime), `/healthz` answers within 100 ms.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn health_answers_while_a_large_grid_is_checked() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let hs: Vec<Value> = (0..1000).map(|i| json!(4e-3 + 1e-6 * f64::from(i))).collect();
    let spec = json!({"base": {"n": 1, "nodes": 158}, "grid": {"h": hs}});
    let submit = {
        let (c, url) = (c.clone(), url.clone());
        tokio::spawn(async move {
            let t = Instant::now();
            let r = c
                .post(format!("{url}/api/sweeps"))
                .timeout(Duration::from_secs(300))
                .json(&spec)
                .send()
                .await
                .unwrap();
            (r.status(), t.elapsed())
        })
    };
    let mut worst = Duration::ZERO;
    let mut probes = 0;
    while !submit.is_finished() {
        let t = Instant::now();
        let (status, _) = get(&c, &format!("{url}/healthz")).await;
        assert_eq!(status, StatusCode::OK);
        worst = worst.max(t.elapsed());
        probes += 1;
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    let (status, took) = submit.await.unwrap();
    assert_eq!(status, StatusCode::CREATED);
    println!("1000-point grid checked in {took:?}; /healthz worst {worst:?} over {probes} probes");
    assert!(probes >= 5, "the check took {took:?}: too short to probe");
    assert!(worst < Duration::from_millis(100), "worst /healthz {worst:?}");
    server.shutdown().await.unwrap();
}

/// A process's CPU time (user and system) so far, from `/proc/{pid}/stat`.
fn cpu_time(pid: u32) -> Duration {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).expect("/proc/{pid}/stat");
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .expect("a stat line")
        .1
        .split_whitespace()
        .collect();
    let ticks: u64 = fields[11].parse::<u64>().unwrap() + fields[12].parse::<u64>().unwrap();
    // SAFETY: sysconf reads a constant of the system.
    let per_second = unsafe { libc::sysconf(libc::_SC_CLK_TCK) } as u64;
    Duration::from_secs_f64(ticks as f64 / per_second as f64)
}

/// An event stream's lines, read as they come.
struct Events(reqwest::Response);

impl Events {
    async fn open(url: &str, from: IpAddr) -> Result<Self, (StatusCode, Value)> {
        let c = reqwest::Client::builder().local_address(from).build().unwrap();
        let r = c.get(url).send().await.expect("request");
        if r.status() != StatusCode::OK {
            let status = r.status();
            return Err((status, r.json().await.unwrap_or(Value::Null)));
        }
        Ok(Self(r))
    }

    /// The events (name, data) that arrive within `wait`, until the stream ends.
    async fn within(&mut self, wait: Duration) -> (Vec<(String, Value)>, bool) {
        let (mut text, deadline) = (String::new(), tokio::time::Instant::now() + wait);
        let ended = loop {
            match tokio::time::timeout_at(deadline, self.0.chunk()).await {
                Ok(Ok(Some(bytes))) => text.push_str(&String::from_utf8_lossy(&bytes)),
                Ok(_) => break true,
                Err(_) => break false,
            }
        };
        let events = text
            .split("\n\n")
            .filter_map(|block| {
                let name = block.lines().find_map(|l| l.strip_prefix("event: "))?;
                let data = block.lines().find_map(|l| l.strip_prefix("data: "))?;
                Some((name.to_string(), serde_json::from_str(data).unwrap()))
            })
            .collect();
        (events, ended)
    }
}

/// A paused sweep watched by 20 streams: each gets the sweep's state at once
/// and then nothing while nothing changes. Streams beyond the caps per client
/// address and per sweep get 429; cancelling ends the streams with `done`,
/// and a stream of a finished sweep gets its `done` at once.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn streams_get_changes_only_within_caps_and_end_with_the_sweep() {
    let (_dir, db) = temp_db();
    let mut cfg = config(&db, 0);
    cfg.stream_limits = knotsweep_server::StreamLimits {
        per_sweep: 21,
        per_client: 20,
    };
    let server = start(cfg).await;
    let (url, c) = (server.url(), client());
    let id = submit_sweep(
        &c,
        &url,
        &json!({"base": tiny_base(), "grid": {"mu": [0.1, 0.2, 0.3]}}),
    )
    .await;
    let (status, _) = post(&c, &format!("{url}/api/sweeps/{id}/pause"), &json!({})).await;
    assert_eq!(status, StatusCode::OK);
    let stream_url = format!("{url}/api/sweeps/{id}/events");
    let local: IpAddr = "127.0.0.1".parse().unwrap();
    let mut streams = Vec::new();
    for _ in 0..20 {
        streams.push(Events::open(&stream_url, local).await.expect("a stream"));
    }
    let (status, error) = Events::open(&stream_url, local)
        .await
        .err()
        .expect("over the cap per client");
    assert_eq!(
        (status, error["error"].as_str()),
        (StatusCode::TOO_MANY_REQUESTS, Some("too_many_requests")),
        "{error}"
    );
    let mut last = Events::open(&stream_url, "127.0.0.2".parse().unwrap())
        .await
        .expect("another client");
    let (status, error) = Events::open(&stream_url, "127.0.0.3".parse().unwrap())
        .await
        .err()
        .expect("over the cap per sweep");
    assert_eq!(status, StatusCode::TOO_MANY_REQUESTS, "{error}");
    // Polled every 100 ms, paused: one event each, then quiet.
    for s in streams.iter_mut() {
        let (events, ended) = s.within(Duration::from_millis(150)).await;
        assert!(!ended);
        assert_eq!(events.len(), 1, "{events:?}");
        assert_eq!(
            (events[0].0.as_str(), &events[0].1["status"]),
            ("progress", &json!("paused"))
        );
    }
    let (quiet, _) = streams[0].within(Duration::from_millis(500)).await;
    assert!(quiet.is_empty(), "nothing changed, nothing sent: {quiet:?}");
    let (status, _) = post(&c, &format!("{url}/api/sweeps/{id}/cancel"), &json!({})).await;
    assert_eq!(status, StatusCode::OK);
    let (events, ended) = last.within(Duration::from_secs(10)).await;
    assert!(ended, "the stream of a cancelled sweep ends: {events:?}");
    let (name, data) = events.last().expect("a last event");
    assert_eq!((name.as_str(), &data["status"]), ("done", &json!("cancelled")));
    drop(streams);
    let t = Instant::now();
    let mut again = loop {
        match Events::open(&stream_url, local).await {
            Ok(stream) => break stream,
            Err(refused) => assert!(
                t.elapsed() < Duration::from_secs(5),
                "places not given back: {refused:?}"
            ),
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    };
    let (events, ended) = again.within(Duration::from_secs(5)).await;
    assert!(ended && events.len() == 1 && events[0].0 == "done", "{events:?}");
    server.shutdown().await.unwrap();
}

/// `knotsweep serve` with a paused 1 000-case sweep watched by 20 streams
/// (two client addresses) for 5 s: one poller reads it, so the server spends
/// under half a second of CPU (each stream reading the sweep itself every
/// 500 ms took 17 s of CPU in 10 s).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn watching_a_paused_sweep_costs_little_cpu() {
    let dir = tempfile::tempdir().unwrap();
    let mut server = serve_command(dir.path())
        .env("RUST_LOG", "warn")
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    std::io::BufRead::read_line(
        &mut std::io::BufReader::new(server.stdout.take().unwrap()),
        &mut line,
    )
    .unwrap();
    let _server = Children(vec![server]);
    let pid = _server.0[0].id();
    let url = line
        .split_whitespace()
        .find(|w| w.starts_with("http://"))
        .expect("the URL")
        .to_string();
    let c = client();
    let mus: Vec<Value> = (0..1000).map(|i| json!(0.05 + 0.0005 * f64::from(i))).collect();
    let id = submit_sweep(&c, &url, &json!({"base": {"n": 3}, "grid": {"mu": mus}})).await;
    let (status, _) = post(&c, &format!("{url}/api/sweeps/{id}/pause"), &json!({})).await;
    assert_eq!(status, StatusCode::OK);
    tokio::time::sleep(Duration::from_secs(1)).await;
    let stream_url = format!("{url}/api/sweeps/{id}/events");
    let before = cpu_time(pid);
    let mut streams = Vec::new();
    for i in 0..20 {
        let from = if i % 2 == 0 { "127.0.0.1" } else { "127.0.0.2" };
        streams.push(
            Events::open(&stream_url, from.parse().unwrap())
                .await
                .expect("a stream"),
        );
    }
    tokio::time::sleep(Duration::from_secs(5)).await;
    let spent = cpu_time(pid) - before;
    println!("20 streams on a paused 1000-case sweep for 5 s: the server spent {spent:?} of CPU");
    assert!(spent < Duration::from_millis(500), "{spent:?}");
    for s in streams.iter_mut() {
        let (events, _) = s.within(Duration::from_millis(100)).await;
        assert_eq!(events.len(), 1, "{events:?}");
    }
}

/// Pausing a sweep stops its running case at once in the server's own
/// workers (heartbeats 20 s apart could not): the case is queued again, its
/// attempt not counted, and runs when the sweep resumes.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn pausing_stops_the_running_case_at_once() {
    let (_dir, db) = temp_db();
    let mut cfg = config(&db, 1);
    cfg.lease = Duration::from_secs(60);
    let server = start(cfg).await;
    let (url, c) = (server.url(), client());
    let id = submit_sweep(&c, &url, &json!({"base": long_base()})).await;
    wait_sweep(&c, &url, id, Duration::from_secs(20), |s| {
        count(s, "running") == 1
    })
    .await;
    let t = Instant::now();
    let (status, _) = post(&c, &format!("{url}/api/sweeps/{id}/pause"), &json!({})).await;
    assert_eq!(status, StatusCode::OK);
    let held = wait_sweep(&c, &url, id, Duration::from_secs(5), |s| count(s, "queued") == 1).await;
    println!(
        "paused: the running case was queued again after {:?}",
        t.elapsed()
    );
    assert_eq!(held["cases"][0]["attempts"], 0, "{held:#}");
    assert_eq!(held["status"], "paused");
    let (status, _) = post(&c, &format!("{url}/api/sweeps/{id}/resume"), &json!({})).await;
    assert_eq!(status, StatusCode::OK);
    wait_sweep(&c, &url, id, Duration::from_secs(20), |s| {
        count(s, "running") == 1
    })
    .await;
    let (status, _) = post(&c, &format!("{url}/api/sweeps/{id}/cancel"), &json!({})).await;
    assert_eq!(status, StatusCode::OK);
    wait_sweep(&c, &url, id, Duration::from_secs(5), |s| {
        count(s, "cancelled") == 1
    })
    .await;
    server.shutdown().await.unwrap();
}

/// A POST from another site is refused, token or not: not JSON (415), a
/// foreign `Origin` or `Host` (403). The server's own pages, the Python
/// client and curl-like clients (no `Origin`) pass; `allowed_hosts` adds names.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cross_site_writes_are_refused() {
    let (_dir, db) = temp_db();
    let mut cfg = config(&db, 0);
    cfg.allowed_hosts = knotsweep_server::AllowedHosts::new(&["knots.example.org"]).unwrap();
    let server = start(cfg).await;
    let (url, c) = (server.url(), client());
    let endpoint = format!("{url}/api/sweeps");
    let body = json!({"base": tiny_base()}).to_string();
    let own = format!("http://{}", server.addr);
    let json_type = ("content-type", "application/json");
    for (headers, expected, field) in [
        (
            vec![("content-type", "text/plain")],
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            "Content-Type",
        ),
        (
            vec![("content-type", "application/x-www-form-urlencoded")],
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            "Content-Type",
        ),
        (vec![], StatusCode::UNSUPPORTED_MEDIA_TYPE, "Content-Type"),
        (
            vec![json_type, ("origin", "http://evil.example")],
            StatusCode::FORBIDDEN,
            "Origin",
        ),
        (
            vec![json_type, ("origin", "null")],
            StatusCode::FORBIDDEN,
            "Origin",
        ),
        (
            vec![json_type, ("host", "evil.example")],
            StatusCode::FORBIDDEN,
            "Host",
        ),
    ] {
        let (status, error) = send(&c, &endpoint, &body, &headers).await;
        assert_eq!(status, expected, "{headers:?}: {error}");
        assert_eq!(fields(&error)[0].0, field, "{headers:?}: {error}");
    }
    let (status, error) = send(
        &c,
        &format!("{endpoint}/1/cancel"),
        "x=1",
        &[("content-type", "application/x-www-form-urlencoded")],
    )
    .await;
    assert_eq!(status, StatusCode::UNSUPPORTED_MEDIA_TYPE, "{error}");
    let (_, listed) = get(&c, &endpoint).await;
    assert_eq!(listed, json!([]), "nothing stored");
    for headers in [
        vec![json_type],
        vec![json_type, ("origin", own.as_str())],
        vec![
            json_type,
            ("host", "knots.example.org"),
            ("origin", "https://knots.example.org"),
        ],
        vec![json_type, ("host", "localhost")],
    ] {
        let (status, answer) = send(&c, &endpoint, &body, &headers).await;
        assert!(status.is_success(), "{headers:?}: {status} {answer}");
    }
    // A bodiless control POST, as the page and the Python client send it.
    let (status, answer) = send(
        &c,
        &format!("{endpoint}/1/pause"),
        "{}",
        &[json_type, ("origin", own.as_str())],
    )
    .await;
    assert_eq!(status, StatusCode::OK, "{answer}");
    server.shutdown().await.unwrap();

    // With a token too: the guards come first.
    let (_dir, db) = temp_db();
    let mut cfg = config(&db, 0);
    cfg.token = Some("s3cret".to_string());
    let server = start(cfg).await;
    let endpoint = format!("{}/api/sweeps", server.url());
    let auth = ("authorization", "Bearer s3cret");
    let (status, _) = send(&c, &endpoint, &body, &[auth, ("content-type", "text/plain")]).await;
    assert_eq!(status, StatusCode::UNSUPPORTED_MEDIA_TYPE);
    let (status, _) = send(
        &c,
        &endpoint,
        &body,
        &[auth, json_type, ("origin", "http://evil.example")],
    )
    .await;
    assert_eq!(status, StatusCode::FORBIDDEN);
    let (status, _) = send(&c, &endpoint, &body, &[auth, json_type]).await;
    assert_eq!(status, StatusCode::CREATED);
    server.shutdown().await.unwrap();
}

/// Every page, asset and API answer carries the security headers; the
/// policy forbids framing.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_answer_carries_the_security_headers() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    for path in [
        "/",
        "/assets/app.js",
        "/assets/app.css",
        "/api/docs/",
        "/api/docs/swagger-initializer.js",
        "/api/openapi.json",
        "/api/sweeps",
        "/api/sweeps/7",
        "/healthz",
        "/metrics",
        "/nowhere",
    ] {
        let r = c.get(format!("{url}{path}")).send().await.unwrap();
        let h = r.headers();
        let csp = h["content-security-policy"].to_str().unwrap();
        assert!(csp.contains("frame-ancestors 'none'"), "{path}: {csp}");
        assert!(csp.contains("script-src 'self'"), "{path}: {csp}");
        assert_eq!(h["x-content-type-options"], "nosniff", "{path}");
        assert_eq!(h["referrer-policy"], "no-referrer", "{path}");
        assert_eq!(h["x-frame-options"], "DENY", "{path}");
    }
    server.shutdown().await.unwrap();
}

/// The small ones: an offset beyond the stores' range is a 400 (one within
/// it past the end an empty page); cancelling a finished sweep changes
/// nothing; the OpenAPI document requires the token on POST routes exactly
/// when one is set (JSON 404s under `/api/docs/`: tests/reliability.rs).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn offsets_finished_sweeps_and_openapi_security() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 1)).await;
    let (url, c) = (server.url(), client());
    let (status, error) = get(
        &c,
        &format!("{url}/api/sweeps?limit=2&offset=18446744073709551615"),
    )
    .await;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{error}");
    assert_eq!(fields(&error)[0].0, "offset", "{error}");
    let (status, page) = get(&c, &format!("{url}/api/sweeps?offset=9223372036854775807")).await;
    assert_eq!((status, page), (StatusCode::OK, json!([])));

    let id = submit_sweep(&c, &url, &json!({"base": tiny_base()})).await;
    let done = wait_sweep(&c, &url, id, Duration::from_secs(60), finished).await;
    let (status, after) = post(&c, &format!("{url}/api/sweeps/{id}/cancel"), &json!({})).await;
    assert_eq!(status, StatusCode::OK, "{after}");
    assert_eq!(
        (&after["status"], &after["state"]),
        (&json!("done"), &done["state"]),
        "{after}"
    );
    let (_, sweep) = get_sweep(&c, &url, id).await;
    assert_eq!(sweep["status"], "done");
    assert_eq!(count(&sweep, "cancelled"), 0, "{sweep}");

    let security = |doc: &Value, path: &str| doc["paths"][path]["post"]["security"].clone();
    let (_, doc) = get(&c, &format!("{url}/api/openapi.json")).await;
    assert_eq!(
        security(&doc, "/api/sweeps"),
        Value::Null,
        "no token, no security"
    );
    server.shutdown().await.unwrap();

    let (_dir, db) = temp_db();
    let mut cfg = config(&db, 0);
    cfg.token = Some("s3cret".to_string());
    let server = start(cfg).await;
    let (_, doc) = get(&c, &format!("{}/api/openapi.json", server.url())).await;
    for path in [
        "/api/sweeps",
        "/api/sweeps/{id}/pause",
        "/api/sweeps/{id}/resume",
        "/api/sweeps/{id}/cancel",
    ] {
        assert_eq!(security(&doc, path), json!([{"bearer": []}]), "{path}");
    }
    assert_eq!(doc["paths"]["/api/sweeps"]["get"]["security"], Value::Null);
    server.shutdown().await.unwrap();
}

/// A body that does not arrive in time is a 408, as docs/API.md says.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_slow_body_gets_408() {
    let (_dir, db) = temp_db();
    let mut cfg = config(&db, 0);
    cfg.body_read_timeout = Duration::from_millis(300);
    let server = start(cfg).await;
    let addr = server.addr;
    let answer = tokio::task::spawn_blocking(move || {
        let mut s = std::net::TcpStream::connect(addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
        write!(
            s,
            "POST /api/sweeps HTTP/1.1\r\nHost: {addr}\r\nContent-Type: application/json\r\nContent-Length: 100\r\n\r\n{{\"name\""
        )
        .unwrap();
        let mut answer = vec![0; 4096];
        let n = s.read(&mut answer).unwrap();
        String::from_utf8_lossy(&answer[..n]).to_string()
    })
    .await
    .unwrap();
    assert!(answer.starts_with("HTTP/1.1 408"), "{answer}");
    assert!(answer.contains("request_timeout"), "{answer}");
    server.shutdown().await.unwrap();
}

/// A token a client cannot send (spaces, letters beyond ASCII) stops the
/// server at startup with the reason.
#[test]
fn unusable_tokens_are_refused_at_startup() {
    for token in [" tok ", "t\u{f6}k", "a\tb"] {
        let dir = tempfile::tempdir().unwrap();
        let out = serve_command(dir.path())
            .env("KNOTSWEEP_TOKEN", token)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{token:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("printable ASCII without spaces"), "{token:?}: {err}");
    }
    assert!(knotsweep_server::check_token("Zm9v.YmFy-_~").is_ok());
}
