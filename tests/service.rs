//! End-to-end tests of the sweep service: real HTTP on an ephemeral port, a
//! real SQLite file in a temporary directory, the real solver (cases made
//! short: see `common::tiny_base`), worker processes of the built binary.
mod common;

use common::*;
use knotsweep_worker::store::sqlite::{SqliteOptions, SqliteStore};
use knotsweep_worker::store::{Heartbeat, Store};
use knotsweep_worker::{PoolConfig, WorkerPool};
use reqwest::StatusCode;
use serde_json::{Value, json};
use std::process::{Command, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_knotsweep");

fn pool_config(workers: usize) -> PoolConfig {
    let mut c = PoolConfig::new(workers).with_lease(Duration::from_secs(2));
    c.poll = Duration::from_millis(20);
    c
}

async fn logs(store: &SqliteStore, case_id: i64) -> Vec<String> {
    store
        .case_logs(case_id)
        .await
        .unwrap()
        .into_iter()
        .map(|l| l.message)
        .collect()
}

fn claims(logs: &[String]) -> usize {
    logs.iter().filter(|m| m.starts_with("claimed by")).count()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn submit_run_and_phase_diagram_end_to_end() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 2)).await;
    let (url, c) = (server.url(), client());

    // Four real cases (a mesh the knot builder refuses is refused at submit:
    // tests/reliability.rs).
    let spec = json!({"name": "e2e", "base": without(tiny_base(), "nodes"), "grid": {"mu": [0.1, 0.3], "nodes": [121, 131]}});
    let r = c
        .post(format!("{url}/api/sweeps"))
        .json(&spec)
        .send()
        .await
        .unwrap();
    assert_eq!(r.status(), StatusCode::CREATED);
    let location = r.headers()["location"].to_str().unwrap().to_string();
    let sweep: Value = r.json().await.unwrap();
    let id = sweep["id"].as_i64().unwrap();
    assert_eq!(location, format!("/api/sweeps/{id}"));
    assert_eq!(sweep["replayed"], false);
    assert_eq!(sweep["total"], 4);
    assert_eq!(sweep["varied"], json!(["mu", "nodes"]));
    let (_, cases) = get(&c, &format!("{url}/api/sweeps/{id}/cases")).await;
    assert_eq!(cases[1]["params"], json!({"mu": 0.1, "nodes": 131}));

    // Follow the server-sent events to the end.
    let mut events = c
        .get(format!("{url}/api/sweeps/{id}/events"))
        .send()
        .await
        .unwrap();
    assert!(
        events.headers()["content-type"]
            .to_str()
            .unwrap()
            .starts_with("text/event-stream")
    );
    let mut text = String::new();
    tokio::time::timeout(Duration::from_secs(60), async {
        while let Some(chunk) = events.chunk().await.unwrap() {
            text.push_str(&String::from_utf8_lossy(&chunk));
            if text.contains("event: done") && text.ends_with("\n\n") {
                break;
            }
        }
    })
    .await
    .expect("the event stream ends with a done event");
    let done_data = text
        .split("event: done\ndata: ")
        .nth(1)
        .unwrap()
        .lines()
        .next()
        .unwrap();
    let done: Value = serde_json::from_str(done_data).unwrap();
    assert_eq!(done["status"], "done");
    assert_eq!(done["progress"], 1.0);

    let sweep = wait_sweep(&c, &url, id, Duration::from_secs(5), finished).await;
    assert_eq!(count(&sweep, "completed"), 4, "{sweep:#}");

    assert_eq!(sweep["state"], "done", "what was asked, once done: {sweep:#}");
    let (status, diagram) = get(&c, &format!("{url}/api/sweeps/{id}/phase-diagram")).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(diagram["complete"], true);
    assert_eq!(diagram["base"]["h"], 5e-3);
    assert_eq!(diagram["base"]["youngs_modulus"], 1.8e6, "defaults filled in");
    let points = diagram["points"].as_array().unwrap();
    assert_eq!(points.len(), 4);
    // The simplified model's reference: scale-free, so at h = 5 mm it is the
    // n = 3 snap computed at the paper's 1.6 mm.
    let at_paper_h = solver::simplified::reproduce::snap_l_k_bar(3, 1.6e-3)
        .unwrap()
        .unwrap();
    for p in points {
        let got = p["simplified_l_k_bar"].as_f64().unwrap();
        assert!(
            (got - at_paper_h).abs() < 1e-6 * at_paper_h,
            "{got} vs {at_paper_h}"
        );
    }
    for p in points {
        assert!(
            p.get("inversion").is_some() && p["inversion"].is_null(),
            "short cases do not invert: {p}"
        );
        let reason = p["reason"].as_str().unwrap();
        assert_eq!(p["status"], "completed");
        assert!(reason.contains("no inversion"), "{reason}");
    }

    // A completed case: parameters, result, series, CSV, snapshots, logs.
    let case_id = sweep["cases"][0]["case_id"].as_i64().unwrap();
    let (status, case) = get(&c, &format!("{url}/api/cases/{case_id}")).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(case["params"]["nodes"], 121);
    assert_eq!(case["params"]["mu"], 0.1);
    assert_eq!(case["status"], "completed");
    assert_eq!(case["attempts"], 1);
    assert_eq!(case["sweeps"], json!([id]));
    assert_eq!(case["key"].as_str().unwrap().len(), 64);
    let series = case["series"].as_array().unwrap();
    assert!(!series.is_empty());
    assert!(case["result"]["wall_time"].as_f64().unwrap() > 0.0);
    let messages: Vec<&str> = case["logs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["message"].as_str().unwrap())
        .collect();
    assert!(messages[0].starts_with("claimed by"), "{messages:?}");
    assert!(
        messages.iter().any(|m| m.starts_with("result completed")),
        "{messages:?}"
    );
    let (status, csv) = get_text(&c, &format!("{url}/api/cases/{case_id}/series.csv")).await;
    assert_eq!(status, StatusCode::OK);
    assert!(csv.starts_with("time,l_k_bar,l_k_arc_bar,l_c_over_L,F,F_bar,"));
    assert_eq!(csv.lines().count(), series.len() + 1);
    let (status, snapshots) = get(&c, &format!("{url}/api/cases/{case_id}/snapshots")).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(snapshots[0]["points"].as_array().unwrap().len(), 121);
    // Its figures: the charts `knotsweep run --plot` writes, drawn from the stored series.
    let (status, svg) = get_text(&c, &format!("{url}/api/cases/{case_id}/figures/F_bar.svg")).await;
    assert_eq!(status, StatusCode::OK);
    let samples: Vec<solver::measurements::Sample> = serde_json::from_value(case["series"].clone()).unwrap();
    let params: solver::case::CaseParams = serde_json::from_value(case["params"].clone()).unwrap();
    let events: Vec<solver::protocol::Event> =
        serde_json::from_value(case["result"]["summary"]["events"].clone()).unwrap();
    let expected =
        report::charts::case_chart(&params, &samples, &events, report::charts::Quantity::FBar).unwrap();
    assert_eq!(svg, expected);
    assert!(
        svg.contains("F̄ = F h² / EI") && svg.contains("μ = 0.1"),
        "the paper's symbols and units"
    );
    let (status, svg) = get_text(&c, &format!("{url}/api/sweeps/{id}/figures/H_bar.svg")).await;
    assert_eq!(status, StatusCode::OK);
    assert!(
        svg.starts_with("<svg") && svg.contains("μ = 0.1") && svg.contains("held fixed: n = "),
        "{}",
        &svg[..200.min(svg.len())]
    );
    let (status, svg) = get_text(&c, &format!("{url}/api/sweeps/{id}/figures/phase.svg")).await;
    assert_eq!(status, StatusCode::OK);
    assert!(
        svg.contains("critical l̄_k") && !svg.contains("simplified model"),
        "mu axis: no reference line"
    );
    // The table beside the JSON: one row per point, the JSON's numbers.
    let (status, csv) = get_text(&c, &format!("{url}/api/sweeps/{id}/phase-diagram.csv")).await;
    assert_eq!(status, StatusCode::OK);
    let rows: Vec<Vec<&str>> = csv.lines().map(|l| l.split(',').collect()).collect();
    let points = diagram["points"].as_array().unwrap();
    assert_eq!(rows.len(), points.len() + 1, "{csv}");
    assert_eq!(rows[0][..4], ["case", "μ", "K", "status"]);
    let l_k = rows[0].iter().position(|c| *c == "l̄_k").unwrap();
    for (row, point) in rows[1..].iter().zip(points) {
        assert_eq!(row[0].parse::<i64>().unwrap(), point["case_id"].as_i64().unwrap());
        assert_eq!(
            row[1].parse::<f64>().unwrap(),
            point["params"]["mu"].as_f64().unwrap()
        );
        assert_eq!(
            row[l_k].parse::<f64>().ok(),
            point["inversion"]["l_k_bar"].as_f64()
        );
    }
    let (status, _) = get(&c, &format!("{url}/api/cases/{case_id}/figures/k_bar.svg")).await;
    assert_eq!(status, StatusCode::NOT_FOUND);

    // Operations: list, metrics, health, OpenAPI, Swagger UI, the page.
    let (_, list) = get(&c, &format!("{url}/api/sweeps")).await;
    assert_eq!(list[0]["id"], id);
    assert_eq!(list[0]["status"], "done");
    let (_, metrics) = get_text(&c, &format!("{url}/metrics")).await;
    for line in [
        "knotsweep_cases{status=\"completed\"} 4",
        "knotsweep_cases{status=\"queued\"} 0",
        "knotsweep_queue_depth 0",
        "knotsweep_claims_total 4",
        "knotsweep_completions_total{outcome=\"completed\"} 4",
        "knotsweep_case_duration_seconds_count 4",
        "knotsweep_sweeps{status=\"done\"} 1",
        "knotsweep_sweeps{status=\"running\"} 0",
        "knotsweep_workers 2",
    ] {
        assert!(
            metrics.lines().any(|l| l == line),
            "missing {line:?} in\n{metrics}"
        );
    }
    let (status, health) = get(&c, &format!("{url}/healthz")).await;
    assert_eq!((status, health["status"].as_str()), (StatusCode::OK, Some("ok")));
    let (status, doc) = get(&c, &format!("{url}/api/openapi.json")).await;
    assert_eq!(status, StatusCode::OK);
    for path in [
        "/api/sweeps",
        "/api/sweeps/{id}/phase-diagram",
        "/api/cases/{id}/series.csv",
        "/metrics",
    ] {
        assert!(doc["paths"].get(path).is_some(), "{path} undocumented");
    }
    let params = &doc["components"]["schemas"]["CaseParams"]["properties"];
    assert_eq!(params["h"]["default"], 1.6e-3);
    assert!(doc["components"]["schemas"].get("PhaseDiagram").is_some());
    let snapshots = &doc["components"]["schemas"]["SweepSpec"]["properties"]["snapshots"];
    assert_eq!(
        (&snapshots["enum"], &snapshots["default"]),
        (&json!(["all", "events", "none"]), &json!("all"))
    );
    let (status, swagger) = get_text(&c, &format!("{url}/api/docs/")).await;
    assert_eq!(status, StatusCode::OK);
    assert!(swagger.contains("swagger-ui"), "{swagger}");
    let (status, page) = get_text(&c, &format!("{url}/")).await;
    assert!(status == StatusCode::OK && page.contains("knotsweep"));
    let (_, presets) = get(&c, &format!("{url}/api/presets")).await;
    let names: Vec<&str> = presets
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "fig7",
            "fig9",
            "fig11",
            "hysteresis",
            "twist",
            "knots",
            "bends",
            "hitches",
            "materials"
        ]
    );
    assert_eq!(presets[1]["grid"]["n"], json!([1, 2, 3, 4, 5]));
    assert_eq!(presets[2]["base_params"]["h"], 3.4e-3);

    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn idempotent_resubmission_returns_the_first_sweep() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let endpoint = format!("{url}/api/sweeps");
    let key = [("idempotency-key", "retry-7f3a")];

    let (status, first) = post_raw(
        &c,
        &endpoint,
        r#"{"grid": {"mu": [0.1, 0.2]}, "base": {"n": 2}}"#,
        &key,
    )
    .await;
    assert_eq!(status, StatusCode::CREATED, "{first}");
    // The same request again (keys in another order): the first sweep.
    let (status, again) = post_raw(
        &c,
        &endpoint,
        r#"{"base": {"n": 2}, "grid": {"mu": [0.1, 0.2]}}"#,
        &key,
    )
    .await;
    assert_eq!(status, StatusCode::OK, "{again}");
    assert_eq!(again["replayed"], true);
    assert_eq!(again["id"], first["id"]);
    let (_, list) = get(&c, &endpoint).await;
    assert_eq!(list.as_array().unwrap().len(), 1);
    // The same key with another request is a conflict.
    let (status, conflict) = post_raw(&c, &endpoint, r#"{"base": {"n": 4}}"#, &key).await;
    assert_eq!(status, StatusCode::CONFLICT, "{conflict}");
    // Without a key: a new sweep over the same (deduplicated) cases.
    let (status, other) = post_raw(
        &c,
        &endpoint,
        r#"{"base": {"n": 2}, "grid": {"mu": [0.1, 0.2]}}"#,
        &[],
    )
    .await;
    assert_eq!(status, StatusCode::CREATED);
    assert_ne!(other["id"], first["id"]);
    let (_, other) = get_sweep(&c, &url, other["id"].as_i64().unwrap()).await;
    let (_, first) = get_sweep(&c, &url, first["id"].as_i64().unwrap()).await;
    assert_eq!(case_ids(&other), case_ids(&first));
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn computed_cases_are_reused_across_sweeps() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 1)).await;
    let (url, c) = (server.url(), client());
    let store = SqliteStore::connect(&db, SqliteOptions::default()).await.unwrap();
    let endpoint = format!("{url}/api/sweeps");

    let (status, a) = post(
        &c,
        &endpoint,
        &json!({"base": tiny_base(), "grid": {"mu": [0.2]}}),
    )
    .await;
    assert_eq!(status, StatusCode::CREATED);
    let a_id = a["id"].as_i64().unwrap();
    let a_done = wait_sweep(&c, &url, a_id, Duration::from_secs(30), finished).await;
    let case_a = case_ids(&a_done)[0];
    let (_, before) = get(&c, &format!("{url}/api/cases/{case_a}")).await;

    // The same case spelled differently (0.2 as 2e-1), plus a new one.
    let base = with(tiny_base(), json!({"h": 0.005}));
    let (status, b) = post(&c, &endpoint, &json!({"base": base, "grid": {"mu": [2e-1, 0.4]}})).await;
    assert_eq!(status, StatusCode::CREATED);
    assert_eq!(b["cached"], 1, "{b:#}");
    let (_, b) = get_sweep(&c, &url, b["id"].as_i64().unwrap()).await;
    assert_eq!(b["cases"][0]["case_id"], case_a);
    assert_eq!(b["cases"][0]["cached"], true);
    assert_eq!(b["cases"][0]["status"], "completed", "reused at once");
    assert_eq!(b["cases"][1]["cached"], false);
    let b_id = b["id"].as_i64().unwrap();
    wait_sweep(&c, &url, b_id, Duration::from_secs(30), finished).await;

    let (_, after) = get(&c, &format!("{url}/api/cases/{case_a}")).await;
    assert_eq!(after["result"], before["result"], "the result was not recomputed");
    assert_eq!(after["sweeps"], json!([a_id, b_id]));
    assert_eq!(claims(&logs(&store, case_a).await), 1);
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn pause_holds_queued_cases_and_resume_releases_them() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let id = submit_sweep(
        &c,
        &url,
        &json!({"base": tiny_base(), "grid": {"mu": [0.11, 0.12, 0.13]}}),
    )
    .await;
    let (status, paused) = post(&c, &format!("{url}/api/sweeps/{id}/pause"), &json!({})).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(
        (paused["state"].as_str(), paused["status"].as_str()),
        (Some("paused"), Some("paused"))
    );

    // Workers come up: nothing of the paused sweep is handed out.
    let pool = WorkerPool::start(server.store(), pool_config(2));
    tokio::time::sleep(Duration::from_millis(800)).await;
    let (_, held) = get_sweep(&c, &url, id).await;
    assert_eq!(count(&held, "queued"), 3, "{held:#}");
    assert!(
        held["cases"]
            .as_array()
            .unwrap()
            .iter()
            .all(|c| c["attempts"] == 0)
    );

    let (status, resumed) = post(&c, &format!("{url}/api/sweeps/{id}/resume"), &json!({})).await;
    assert_eq!(
        (status, resumed["state"].as_str()),
        (StatusCode::OK, Some("active"))
    );
    let done = wait_sweep(&c, &url, id, Duration::from_secs(30), finished).await;
    assert_eq!(count(&done, "completed"), 3, "{done:#}");
    pool.shutdown().await;
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancel_stops_running_cases_at_their_next_heartbeat() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 1)).await;
    let (url, c) = (server.url(), client());
    let store = SqliteStore::connect(&db, SqliteOptions::default()).await.unwrap();
    let id = submit_sweep(
        &c,
        &url,
        &json!({"base": long_base(), "grid": {"mu": [0.1, 0.2]}}),
    )
    .await;
    // One worker: the first case runs (and reports progress), the second waits.
    let running = wait_sweep(&c, &url, id, Duration::from_secs(30), |s| {
        s["cases"][0]["status"] == "running" && s["cases"][0]["progress_detail"].is_object()
    })
    .await;
    assert!(running["cases"][0]["progress"].as_f64().unwrap() > 0.0);
    assert_eq!(running["cases"][1]["status"], "queued");
    let cancelled_at = Instant::now();
    let (status, cancelled) = post(&c, &format!("{url}/api/sweeps/{id}/cancel"), &json!({})).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(cancelled["status"], "cancelled");
    let done = wait_sweep(&c, &url, id, Duration::from_secs(15), |s| {
        count(s, "cancelled") == 2
    })
    .await;
    // Heartbeats come every lease / 3 (0.67 s here), the solver stops at its next sample.
    assert!(
        cancelled_at.elapsed() < Duration::from_secs(5),
        "took {:?}",
        cancelled_at.elapsed()
    );
    let ids = case_ids(&done);
    let first = logs(&store, ids[0]).await;
    assert!(
        first.iter().any(|m| m.starts_with("cancel requested")),
        "{first:?}"
    );
    assert!(
        first.iter().any(|m| m.starts_with("cancelled while running")),
        "{first:?}"
    );
    let second = logs(&store, ids[1]).await;
    assert_eq!(claims(&second), 0, "{second:?}");
    assert!(second.iter().any(|m| m.contains("before it ran")), "{second:?}");
    // Cancelled without a result: no progress, no complete phase diagram.
    assert_eq!(done["progress"], 0.0, "{done:#}");
    assert_eq!(
        (done["state"].as_str(), done["status"].as_str()),
        (Some("cancelled"), Some("cancelled"))
    );
    let (_, diagram) = get(&c, &format!("{url}/api/sweeps/{id}/phase-diagram")).await;
    assert_eq!(diagram["complete"], false, "{diagram:#}");
    // A cancelled sweep cannot be paused or resumed.
    let (status, _) = post(&c, &format!("{url}/api/sweeps/{id}/resume"), &json!({})).await;
    assert_eq!(status, StatusCode::CONFLICT);
    let (status, _) = post(&c, &format!("{url}/api/sweeps/{id}/pause"), &json!({})).await;
    assert_eq!(status, StatusCode::CONFLICT);
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancelling_spares_cases_another_sweep_wants_and_resubmitting_requeues() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let spec = json!({"base": tiny_base(), "grid": {"mu": [0.5]}});
    let (_, x) = post(&c, &format!("{url}/api/sweeps"), &spec).await;
    let (_, y) = post(&c, &format!("{url}/api/sweeps"), &spec).await;
    let (x, y) = (x["id"].as_i64().unwrap(), y["id"].as_i64().unwrap());
    post(&c, &format!("{url}/api/sweeps/{x}/cancel"), &json!({})).await;
    let (_, after_x) = get_sweep(&c, &url, x).await;
    assert_eq!(
        after_x["cases"][0]["status"], "queued",
        "sweep {y} still wants it"
    );
    post(&c, &format!("{url}/api/sweeps/{y}/cancel"), &json!({})).await;
    let (_, after_y) = get_sweep(&c, &url, y).await;
    assert_eq!(after_y["cases"][0]["status"], "cancelled");
    // A worker that dies while its case is being cancelled: when its lease
    // expires the case ends cancelled instead of going back to the queue.
    let (_, w) = post(
        &c,
        &format!("{url}/api/sweeps"),
        &json!({"base": tiny_base(), "grid": {"mu": [0.55]}}),
    )
    .await;
    let store = SqliteStore::connect(&db, SqliteOptions::default()).await.unwrap();
    let ghost = store
        .claim("ghost", Duration::from_millis(200))
        .await
        .unwrap()
        .expect("a case");
    post(&c, &format!("{url}/api/sweeps/{}/cancel", w["id"]), &json!({})).await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    store.requeue_expired().await.unwrap(); // (or the server's reaper did already)
    let (_, ghost_case) = get(&c, &format!("{url}/api/cases/{}", ghost.lease.case_id)).await;
    assert_eq!(ghost_case["status"], "cancelled", "{ghost_case:#}");
    // Asking again queues the cancelled case again, and it runs.
    let (status, z) = post(&c, &format!("{url}/api/sweeps"), &spec).await;
    assert_eq!(status, StatusCode::CREATED);
    let (_, z) = get_sweep(&c, &url, z["id"].as_i64().unwrap()).await;
    assert_eq!(z["cases"][0]["status"], "queued");
    assert_eq!(z["cached"], 0);
    let pool = WorkerPool::start(server.store(), pool_config(1));
    let z = wait_sweep(
        &c,
        &url,
        z["id"].as_i64().unwrap(),
        Duration::from_secs(30),
        finished,
    )
    .await;
    assert_eq!(count(&z, "completed"), 1);
    pool.shutdown().await;
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_dead_workers_case_is_finished_once_by_another_after_its_lease_expires() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let store = SqliteStore::connect(&db, SqliteOptions::default()).await.unwrap();
    let id = submit_sweep(&c, &url, &json!({"base": tiny_base(), "grid": {"mu": [0.6]}})).await;

    // A worker claims the case and dies: no heartbeat, no release.
    let ghost = store
        .claim("ghost-worker", Duration::from_secs(1))
        .await
        .unwrap()
        .expect("a case to claim");
    assert_eq!(ghost.attempt, 1);
    let (_, held) = get_sweep(&c, &url, id).await;
    assert_eq!(held["cases"][0]["status"], "running");

    // Another worker takes it over once the lease has expired.
    let pool = WorkerPool::start(server.store(), pool_config(1));
    let done = wait_sweep(&c, &url, id, Duration::from_secs(30), finished).await;
    pool.shutdown().await;
    assert_eq!(count(&done, "completed"), 1, "{done:#}");

    // The ghost wakes up, really computes the case and tries to finish it:
    // the fence refuses both its heartbeat and its result.
    let params = ghost.params.clone();
    let report = tokio::task::spawn_blocking(move || solver::protocol::run(&params, &mut |_| true))
        .await
        .unwrap();
    assert_eq!(
        store
            .heartbeat(&ghost.lease, None, Duration::from_secs(1))
            .await
            .unwrap(),
        Heartbeat::Lost
    );
    assert!(!store.complete(&ghost.lease, &report).await.unwrap());

    let case_id = ghost.lease.case_id;
    let (_, case) = get(&c, &format!("{url}/api/cases/{case_id}")).await;
    assert_eq!(case["attempts"], 2);
    assert_ne!(case["result"]["worker"], "ghost-worker");
    let messages = logs(&store, case_id).await;
    assert_eq!(claims(&messages), 2, "{messages:?}");
    assert_eq!(
        messages
            .iter()
            .filter(|m| m.contains("ghost-worker expired"))
            .count(),
        1,
        "{messages:?}"
    );
    assert_eq!(
        messages.iter().filter(|m| m.starts_with("result")).count(),
        1,
        "{messages:?}"
    );
    let results: i64 = sqlx_count(&store, "SELECT COUNT(*) FROM results").await;
    assert_eq!(results, 1);
    server.shutdown().await.unwrap();
}

/// Raw SQL for checks the API does not expose.
async fn sqlx_count(store: &SqliteStore, sql: &str) -> i64 {
    sqlx::query_scalar(sql).fetch_one(store.pool()).await.expect(sql)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_server_restart_loses_no_accepted_sweep_or_finished_result() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 1)).await;
    let (url, c) = (server.url(), client());
    // Two short cases and a longer one (about a second), in that order.
    let spec = json!({"name": "restart", "base": without(tiny_base(), "min_l_k_bar"), "grid": {"min_l_k_bar": [139.0, 138.5, 100.0]}});
    let (status, s) = post_raw(
        &c,
        &format!("{url}/api/sweeps"),
        spec.to_string(),
        &[("idempotency-key", "restart-1")],
    )
    .await;
    assert_eq!(status, StatusCode::CREATED);
    let id = s["id"].as_i64().unwrap();
    let midway = wait_sweep(&c, &url, id, Duration::from_secs(30), |s| {
        count(s, "queued") + count(s, "running") < 3 && s["cases"][2]["status"] == "running"
    })
    .await;
    server.shutdown().await.unwrap();
    let ids = case_ids(&midway);

    let server = start(config(&db, 1)).await;
    let (url, c) = (server.url(), client());
    let store = SqliteStore::connect(&db, SqliteOptions::default()).await.unwrap();
    let (_, list) = get(&c, &format!("{url}/api/sweeps")).await;
    assert_eq!(list[0]["id"], id);
    assert_eq!(list[0]["name"], "restart");
    // The idempotency key survives the restart too.
    let (status, again) = post_raw(
        &c,
        &format!("{url}/api/sweeps"),
        spec.to_string(),
        &[("idempotency-key", "restart-1")],
    )
    .await;
    assert_eq!((status, again["id"].as_i64()), (StatusCode::OK, Some(id)));
    // Results finished before the restart are there, unchanged.
    let mut before = Vec::new();
    for case_id in &ids[..2] {
        let (_, case) = get(&c, &format!("{url}/api/cases/{case_id}")).await;
        before.push(case["result"].clone());
    }
    let done = wait_sweep(&c, &url, id, Duration::from_secs(60), finished).await;
    for (case_id, result) in ids[..2].iter().zip(&before) {
        let (_, case) = get(&c, &format!("{url}/api/cases/{case_id}")).await;
        if !result.is_null() {
            assert_eq!(&case["result"], result);
        }
    }
    assert!(
        done["cases"]
            .as_array()
            .unwrap()
            .iter()
            .all(|c| c["progress"] == 1.0),
        "{done:#}"
    );
    // The case running at shutdown was released (its attempt not counted).
    let messages = logs(&store, ids[2]).await;
    assert!(
        messages.iter().any(|m| m.starts_with("released by")),
        "{messages:?}"
    );
    let (_, long_case) = get(&c, &format!("{url}/api/cases/{}", ids[2])).await;
    assert_eq!(long_case["attempts"], 1, "{long_case:#}");
    assert_eq!(sqlx_count(&store, "SELECT COUNT(*) FROM results").await, 3);
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn concurrent_worker_processes_never_run_a_case_twice() {
    const CASES: usize = 200;
    let (dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let store = SqliteStore::connect(&db, SqliteOptions::default()).await.unwrap();
    let mus: Vec<Value> = (0..CASES)
        .map(|i| serde_json::from_str(&format!("{:.2}", i as f64 / 100.0)).unwrap())
        .collect();
    let id = submit_sweep(&c, &url, &json!({"base": tiny_base(), "grid": {"mu": mus}})).await;

    // Four processes of two workers each: eight concurrent claimers.
    let started = Instant::now();
    let mut workers = Children(Vec::new());
    for i in 0..4 {
        let log = std::fs::File::create(dir.path().join(format!("worker-{i}.log"))).unwrap();
        let child = Command::new(BIN)
            .args([
                "worker",
                "--database-url",
                &db,
                "--workers",
                "2",
                "--lease-seconds",
                "3",
                "--poll-ms",
                "20",
            ])
            .env("RUST_LOG", "warn")
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .expect("spawn worker");
        workers.0.push(child);
    }
    // One of them dies mid-sweep (SIGKILL: no release).
    wait_sweep(&c, &url, id, Duration::from_secs(120), |s| {
        s["cases"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|c| c["progress"] == 1.0)
            .count()
            >= CASES / 4
    })
    .await;
    workers.0[0].kill().unwrap();
    workers.0[0].wait().unwrap();
    let done = wait_sweep(&c, &url, id, Duration::from_secs(180), finished).await;
    let elapsed = started.elapsed();
    for child in &workers.0[1..] {
        signal(child, libc::SIGTERM);
    }
    for child in &mut workers.0[1..] {
        let status = wait_exit(child, Duration::from_secs(20));
        assert!(status.success(), "worker exited with {status}");
    }

    assert_eq!(
        count(&done, "queued") + count(&done, "running") + count(&done, "failed"),
        0,
        "{:#}",
        done["counts"]
    );
    assert_eq!(
        sqlx_count(&store, "SELECT COUNT(*) FROM results").await,
        CASES as i64
    );
    let mut total_claims = 0;
    let mut takeovers = 0;
    for case_id in case_ids(&done) {
        let messages = logs(&store, case_id).await;
        let claimed = claims(&messages);
        let expired = messages.iter().filter(|m| m.contains("expired")).count();
        let results = messages.iter().filter(|m| m.starts_with("result")).count();
        assert_eq!(results, 1, "case {case_id}: {messages:?}");
        // A second claim only ever follows the expiry of the first lease.
        assert_eq!(claimed, 1 + expired, "case {case_id}: {messages:?}");
        let mut holding = false;
        for m in &messages {
            if m.starts_with("claimed by") {
                assert!(!holding, "case {case_id} handed out while held: {messages:?}");
                holding = true;
            } else if m.contains("expired") || m.starts_with("result") {
                holding = false;
            }
        }
        total_claims += claimed;
        takeovers += expired;
    }
    let wall: f64 = sqlx_count(
        &store,
        "SELECT CAST(SUM(wall_time) * 1000 AS INTEGER) FROM results",
    )
    .await as f64
        / 1000.0;
    println!(
        "{CASES} cases, 8 workers in 4 processes (one killed): {:.1} s, {total_claims} claims ({takeovers} after a lease expired), \
         {:.1} cases/s, solver time {wall:.1} s",
        elapsed.as_secs_f64(),
        CASES as f64 / elapsed.as_secs_f64()
    );
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_worker_process_releases_its_lease_on_sigterm() {
    let (dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let store = SqliteStore::connect(&db, SqliteOptions::default()).await.unwrap();
    let id = submit_sweep(&c, &url, &json!({"base": long_base(), "grid": {"mu": [0.3]}})).await;
    let log = std::fs::File::create(dir.path().join("worker.log")).unwrap();
    let mut workers = Children(vec![
        Command::new(BIN)
            .args([
                "worker",
                "--database-url",
                &db,
                "--workers",
                "1",
                "--lease-seconds",
                "60",
            ])
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .expect("spawn worker"),
    ]);
    let running = wait_sweep(&c, &url, id, Duration::from_secs(30), |s| {
        count(s, "running") == 1
    })
    .await;
    let case_id = case_ids(&running)[0];
    let asked = Instant::now();
    signal(&workers.0[0], libc::SIGTERM);
    let status = wait_exit(&mut workers.0[0], Duration::from_secs(20));
    assert!(status.success(), "{status}");
    assert!(
        asked.elapsed() < Duration::from_secs(10),
        "took {:?}",
        asked.elapsed()
    );
    // Queued again at once (not after the 60 s lease), the attempt not counted.
    let (_, case) = get(&c, &format!("{url}/api/cases/{case_id}")).await;
    assert_eq!(case["status"], "queued", "{case:#}");
    assert_eq!(case["attempts"], 0);
    assert!(case["lease_owner"].is_null());
    let messages = logs(&store, case_id).await;
    assert!(
        messages.iter().any(|m| m.starts_with("released by")),
        "{messages:?}"
    );
    post(&c, &format!("{url}/api/sweeps/{id}/cancel"), &json!({})).await;
    server.shutdown().await.unwrap();
}

/// `GET /api/materials`: the solver's named materials under the case
/// parameters' names, documented in the OpenAPI document with the
/// parameter table's order and groups (the web form's layout).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn materials_route_serves_the_named_materials() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let (status, materials) = get(&c, &format!("{url}/api/materials")).await;
    assert_eq!(status, StatusCode::OK);
    let names: Vec<&str> = materials
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["rubber", "silicone", "nylon", "nitinol", "steel"]);
    let steel = &materials[4];
    assert_eq!(steel["youngs_modulus"], 2.0e11);
    assert_eq!(steel["density"], 7850.0);
    assert_eq!(steel["poisson_ratio"], 0.3);
    assert!(steel["source"].as_str().unwrap().contains("ASTM A228"), "{steel}");
    let (_, doc) = get(&c, &format!("{url}/api/openapi.json")).await;
    assert!(doc["paths"].get("/api/materials").is_some());
    assert!(doc["components"]["schemas"].get("MaterialView").is_some());
    // The form's layout of the parameter table: its order and the groups' titles.
    let params = &doc["components"]["schemas"]["CaseParams"];
    assert_eq!(params["x-order"][0], "knot", "{params}");
    assert_eq!(
        params["x-groups"][1],
        json!({"name": "rod", "title": "Rod and material"})
    );
    assert_eq!(params["x-groups"][4]["name"], "solver");
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_input_gets_a_4xx_with_the_field_and_the_reason() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let endpoint = format!("{url}/api/sweeps");
    let many = |n: usize| (0..n).map(|i| json!(1e-3 + 1e-5 * i as f64)).collect::<Vec<_>>();
    let cases: Vec<(String, StatusCode, &str)> = vec![
        ("{not json".into(), StatusCode::BAD_REQUEST, "body"),
        ("[1, 2]".into(), StatusCode::UNPROCESSABLE_ENTITY, "body"),
        (
            r#"{"colour": "red"}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "colour",
        ),
        (
            r#"{"base": {"radius": 0.001}}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "base.radius",
        ),
        (
            r#"{"base": {"n": 2.5}}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "base.n",
        ),
        (
            r#"{"base": {"n": 0}}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "base.n",
        ),
        (
            r#"{"base": {"n": 9}}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "base.n",
        ),
        (
            r#"{"base": {"h": 0.02}}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "base.h",
        ),
        (
            r#"{"base": {"mu": -0.1}}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "base.mu",
        ),
        (
            r#"{"base": {"mu": "high"}}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "base.mu",
        ),
        (r#"{"base": 3}"#.into(), StatusCode::UNPROCESSABLE_ENTITY, "base"),
        (
            r#"{"snapshots": "some"}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "snapshots",
        ),
        (
            r#"{"grid": {"h": [0.001, 0.05]}}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "grid.h[1]",
        ),
        (
            r#"{"grid": {"n": [1, 2, 9]}}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "grid.n[2]",
        ),
        (
            r#"{"grid": {"foo": [1]}}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "grid.foo",
        ),
        (
            r#"{"grid": {"mu": 0.1}}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "grid.mu",
        ),
        (
            r#"{"grid": {"mu": []}}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "grid.mu",
        ),
        (
            json!({"grid": {"h": many(40), "mu": many(30)}}).to_string(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "grid",
        ),
        (
            r#"{"preset": "fig8"}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "preset",
        ),
        (
            r#"{"preset": "fig7", "grid": {"n": [1]}}"#.into(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "grid",
        ),
        (
            json!({"name": "x".repeat(300)}).to_string(),
            StatusCode::UNPROCESSABLE_ENTITY,
            "name",
        ),
        (
            format!(r#"{{"name": "{}"}}"#, "x".repeat(70 * 1024)),
            StatusCode::PAYLOAD_TOO_LARGE,
            "body",
        ),
        ("[".repeat(10_000), StatusCode::BAD_REQUEST, "body"),
    ];
    for (body, expected, field) in cases {
        let (status, error) = post_raw(&c, &endpoint, body.clone(), &[]).await;
        let shown = &body[..body.len().min(80)];
        assert_eq!(status, expected, "{shown}: {error}");
        let fields: Vec<&str> = error["fields"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["field"].as_str().unwrap())
            .collect();
        assert!(
            fields.contains(&field),
            "{shown}: expected field {field}, got {error}"
        );
        assert!(!error["message"].as_str().unwrap().is_empty());
    }
    let (status, error) = post_raw(&c, &endpoint, "{}", &[("idempotency-key", &"k".repeat(300))]).await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    assert_eq!(error["fields"][0]["field"], "Idempotency-Key");
    // Byte soup never gets a 5xx.
    for seed in 0..50u64 {
        let bytes: Vec<u8> = (0..(seed * 37 % 300))
            .map(|i| ((i * 7919 + seed * 104_729) % 256) as u8)
            .collect();
        let (status, _) = post_raw(&c, &endpoint, bytes, &[]).await;
        assert!(status.is_client_error(), "seed {seed}: {status}");
    }
    for (path, expected) in [
        ("/api/sweeps/abc", StatusCode::BAD_REQUEST),
        ("/api/sweeps/999", StatusCode::NOT_FOUND),
        ("/api/sweeps/999/phase-diagram", StatusCode::NOT_FOUND),
        ("/api/sweeps/999/events", StatusCode::NOT_FOUND),
        ("/api/cases/999", StatusCode::NOT_FOUND),
        ("/api/cases/999/series.csv", StatusCode::NOT_FOUND),
        ("/api/cases/999/snapshots", StatusCode::NOT_FOUND),
        ("/api/nothing", StatusCode::NOT_FOUND),
    ] {
        let (status, error) = get(&c, &format!("{url}{path}")).await;
        assert_eq!(status, expected, "{path}: {error}");
        assert!(error["error"].is_string(), "{path}: {error}");
    }
    let (status, _) = post(&c, &format!("{url}/api/sweeps/999/cancel"), &json!({})).await;
    assert_eq!(status, StatusCode::NOT_FOUND);
    let (_, list) = get(&c, &endpoint).await;
    assert_eq!(list, json!([]), "bad input created nothing");
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_token_guards_every_mutating_request() {
    let (_dir, db) = temp_db();
    let mut cfg = config(&db, 0);
    cfg.token = Some("s3cret".to_string());
    let server = start(cfg).await;
    let (url, c) = (server.url(), client());
    let endpoint = format!("{url}/api/sweeps");
    let r = c.post(&endpoint).json(&json!({})).send().await.unwrap();
    assert_eq!(r.status(), StatusCode::UNAUTHORIZED);
    assert_eq!(r.headers()["www-authenticate"], "Bearer");
    let body: Value = r.json().await.unwrap();
    assert_eq!(body["error"], "unauthorized");
    let (status, _) = post_raw(&c, &endpoint, "{}", &[("authorization", "Bearer wrong")]).await;
    assert_eq!(status, StatusCode::UNAUTHORIZED);
    let (status, _) = post_raw(&c, &endpoint, "{}", &[("authorization", "s3cret")]).await;
    assert_eq!(status, StatusCode::UNAUTHORIZED);
    let (status, s) = post_raw(&c, &endpoint, "{}", &[("authorization", "Bearer s3cret")]).await;
    assert_eq!(status, StatusCode::CREATED);
    let id = s["id"].as_i64().unwrap();
    let (status, _) = get(&c, &endpoint).await;
    assert_eq!(status, StatusCode::OK, "reads need no token");
    let (status, _) = post_raw(&c, &format!("{endpoint}/{id}/cancel"), "", &[]).await;
    assert_eq!(status, StatusCode::UNAUTHORIZED);
    let (status, body) = post_raw(
        &c,
        &format!("{endpoint}/{id}/cancel"),
        "",
        &[("authorization", "Bearer s3cret")],
    )
    .await;
    assert_eq!(status, StatusCode::OK, "{body}");
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cli_sweep_writes_the_phase_diagram_and_resumes_after_an_interruption() {
    let (dir, db) = temp_db();
    let spec_path = dir.path().join("spec.json");
    let out = dir.path().join("out.json");
    // Six cases, the later ones longer (about 0.1 s to 1 s each).
    let grid: Vec<f64> = vec![139.0, 138.0, 136.0, 133.0, 129.0, 124.0];
    std::fs::write(
        &spec_path,
        json!({"base": without(tiny_base(), "min_l_k_bar"), "grid": {"min_l_k_bar": grid}}).to_string(),
    )
    .unwrap();
    let sweep = |stderr: std::fs::File| {
        Command::new(BIN)
            .args(["sweep", "--spec"])
            .arg(&spec_path)
            .arg("--out")
            .arg(&out)
            .args(["--database-url", &db, "--workers", "1", "--lease-seconds", "5"])
            .stdout(Stdio::null())
            .stderr(stderr)
            .spawn()
            .expect("spawn sweep")
    };
    // First run: interrupted (SIGINT) after its first result.
    let mut first = Children(vec![sweep(
        std::fs::File::create(dir.path().join("run1.log")).unwrap(),
    )]);
    let store = loop {
        // The CLI creates the database; wait for it.
        match SqliteStore::connect(&db, SqliteOptions::default()).await {
            Ok(s) => break Arc::new(s),
            Err(_) => tokio::time::sleep(Duration::from_millis(50)).await,
        }
    };
    let start = Instant::now();
    while sqlx::query_scalar::<_, i64>("SELECT COUNT(*) FROM results")
        .fetch_one(store.pool())
        .await
        .unwrap_or(0)
        < 1
    {
        assert!(start.elapsed() < Duration::from_secs(60), "no result");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    signal(&first.0[0], libc::SIGINT);
    let status = wait_exit(&mut first.0[0], Duration::from_secs(20));
    let after_first = sqlx_count(&store, "SELECT COUNT(*) FROM results").await;
    let first_results = sqlx_count(&store, "SELECT COALESCE(SUM(created_at), 0) FROM results").await;
    let log = std::fs::read_to_string(dir.path().join("run1.log")).unwrap();
    assert!(
        !status.success() && log.contains("interrupted"),
        "{status}: {log}"
    );
    assert!(after_first < grid.len() as i64);
    assert!(!out.exists(), "no phase diagram for an unfinished sweep");
    // Its lease was released: nothing is left running.
    assert_eq!(
        sqlx_count(&store, "SELECT COUNT(*) FROM cases WHERE status = 'running'").await,
        0
    );

    // Second run: resumes the same sweep and finishes it.
    let mut second = Children(vec![sweep(
        std::fs::File::create(dir.path().join("run2.log")).unwrap(),
    )]);
    let status = wait_exit(&mut second.0[0], Duration::from_secs(120));
    let log = std::fs::read_to_string(dir.path().join("run2.log")).unwrap();
    assert!(status.success(), "{log}");
    assert!(log.contains("resuming sweep 1"), "{log}");
    let diagram: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(diagram["sweep_id"], 1);
    assert_eq!(diagram["complete"], true);
    assert_eq!(diagram["varied"], json!(["min_l_k_bar"]));
    assert_eq!(diagram["points"].as_array().unwrap().len(), grid.len());
    assert_eq!(sqlx_count(&store, "SELECT COUNT(*) FROM sweeps").await, 1);
    assert_eq!(
        sqlx_count(&store, "SELECT COUNT(*) FROM results").await,
        grid.len() as i64
    );
    // The results of the first run were kept, not recomputed.
    let kept = sqlx_count(
        &store,
        &format!("SELECT COALESCE(SUM(created_at), 0) FROM (SELECT created_at FROM results ORDER BY case_id LIMIT {after_first})"),
    )
    .await;
    assert_eq!(kept, first_results);
    store.close().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_certified_sweep_runs_a_refined_twin_per_point_and_reports_its_uncertainty() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 2)).await;
    let (url, c) = (server.url(), client());
    let spec = json!({"base": tiny_base(), "grid": {"mu": [0.1, 0.3]}, "certify": true});
    let id = submit_sweep(&c, &url, &spec).await;
    let sweep = wait_sweep(&c, &url, id, Duration::from_secs(60), finished).await;
    assert_eq!(sweep["total"], 4, "two points and their twins: {sweep:#}");
    let (_, cases) = get(&c, &format!("{url}/api/sweeps/{id}/cases")).await;
    let cases = cases.as_array().unwrap();
    let (points, twins): (Vec<&Value>, Vec<&Value>) = cases.iter().partition(|c| c["twin_of"].is_null());
    assert_eq!((points.len(), twins.len()), (2, 2), "{cases:#?}");

    let (_, diagram) = get(&c, &format!("{url}/api/sweeps/{id}/phase-diagram")).await;
    assert_eq!(diagram["certified"], true);
    let diagram_points = diagram["points"].as_array().unwrap();
    assert_eq!(diagram_points.len(), 2, "the twins are not points");
    for p in diagram_points {
        let twin_id = p["uncertainty"]["refined_case_id"].as_i64().unwrap();
        let twin = twins
            .iter()
            .find(|t| t["case_id"] == twin_id)
            .expect("the twin is a case of the sweep");
        assert_eq!(twin["twin_of"], p["case_id"]);
        let (_, point_case) = get(&c, &format!("{url}/api/cases/{}", p["case_id"])).await;
        let (_, twin_case) = get(&c, &format!("{url}/api/cases/{twin_id}")).await;
        let dt = |case: &Value| case["params"]["dt"].as_f64();
        let point_dt = solver::case::CaseParams {
            h: 5e-3,
            nodes: Some(121),
            ..Default::default()
        }
        .time_step();
        assert_eq!(dt(&point_case), None, "the point keeps the default step");
        assert_eq!(dt(&twin_case), Some(point_dt / 2.0), "the twin halves it");
        assert_eq!(twin_case["params"]["mu"], point_case["params"]["mu"]);
        // Neither short case inverts: they agree, with no distance to give.
        assert!(
            p["inversion"].is_null() && p["uncertainty"]["absolute"].is_null(),
            "{p}"
        );
        assert_eq!(p["uncertainty"]["converged"], true, "{p}");
    }

    // An uncertified sweep of the same points reuses them and has no uncertainty.
    let plain = json!({"base": tiny_base(), "grid": {"mu": [0.1, 0.3]}});
    let (status, body) = post(&c, &format!("{url}/api/sweeps"), &plain).await;
    assert_eq!(status, StatusCode::CREATED);
    assert_eq!(body["cached"], 2, "{body:#}");
    let (_, diagram) = get(&c, &format!("{url}/api/sweeps/{}/phase-diagram", body["id"])).await;
    assert_eq!(diagram["certified"], false);
    assert!(
        diagram["points"]
            .as_array()
            .unwrap()
            .iter()
            .all(|p| p["uncertainty"].is_null())
    );
    server.shutdown().await.unwrap();
}

/// The twin relation is stored at submission: after a physics revision bump
/// (every stored key rewritten to the next revision's) each point still
/// finds its twin; a sweep stored before the relation was finds them by
/// their parameters.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_certified_sweep_keeps_its_twins_across_a_physics_revision() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let spec = json!({"base": tiny_base(), "grid": {"mu": [0.1, 0.2, 0.3]}, "certify": true});
    let id = submit_sweep(&c, &url, &spec).await;
    let (_, cases) = get(&c, &format!("{url}/api/sweeps/{id}/cases")).await;
    let twin_of = |cases: &Value| -> Vec<(i64, i64)> {
        let mut pairs: Vec<(i64, i64)> = (cases.as_array().unwrap().iter())
            .filter_map(|c| Some((c["twin_of"].as_i64()?, c["case_id"].as_i64()?)))
            .collect();
        pairs.sort();
        pairs
    };
    let submitted = twin_of(&cases);
    assert_eq!(submitted.len(), 3, "{cases:#}");

    let store = SqliteStore::connect(&db, SqliteOptions::default()).await.unwrap();
    let next = solver::case::PHYSICS_REVISION + 1;
    for case in cases.as_array().unwrap() {
        let id = case["case_id"].as_i64().unwrap();
        let params = store.get_case(id).await.unwrap().unwrap().params;
        sqlx::query("UPDATE cases SET case_key = $1 WHERE id = $2")
            .bind(knotsweep_worker::key::case_key_under(&params, next))
            .bind(id)
            .execute(store.pool())
            .await
            .unwrap();
    }
    let found = |diagram: &Value| -> Vec<(i64, i64)> {
        let mut pairs: Vec<(i64, i64)> = (diagram["points"].as_array().unwrap().iter())
            .filter_map(|p| {
                Some((
                    p["case_id"].as_i64()?,
                    p["uncertainty"]["refined_case_id"].as_i64()?,
                ))
            })
            .collect();
        pairs.sort();
        pairs
    };
    let (_, diagram) = get(&c, &format!("{url}/api/sweeps/{id}/phase-diagram")).await;
    assert_eq!(found(&diagram), submitted, "{diagram:#}");
    let (_, cases) = get(&c, &format!("{url}/api/sweeps/{id}/cases")).await;
    assert_eq!(twin_of(&cases), submitted);

    sqlx::query("UPDATE sweep_cases SET twin_position = NULL")
        .execute(store.pool())
        .await
        .unwrap();
    let (_, diagram) = get(&c, &format!("{url}/api/sweeps/{id}/phase-diagram")).await;
    assert_eq!(found(&diagram), submitted, "found by parameters: {diagram:#}");
    store.close().await;
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_pooled_sqlite_connection_has_wal_busy_timeout_and_foreign_keys() {
    let (_dir, db) = temp_db();
    let store = SqliteStore::connect(&db, SqliteOptions::default()).await.unwrap();
    let mut held = Vec::new();
    for _ in 0..4 {
        held.push(store.pool().acquire().await.unwrap());
    }
    for conn in &mut held {
        let mode: String = sqlx::query_scalar("PRAGMA journal_mode")
            .fetch_one(&mut **conn)
            .await
            .unwrap();
        let sync: i64 = sqlx::query_scalar("PRAGMA synchronous")
            .fetch_one(&mut **conn)
            .await
            .unwrap();
        let busy: i64 = sqlx::query_scalar("PRAGMA busy_timeout")
            .fetch_one(&mut **conn)
            .await
            .unwrap();
        let fk: i64 = sqlx::query_scalar("PRAGMA foreign_keys")
            .fetch_one(&mut **conn)
            .await
            .unwrap();
        assert_eq!((mode.as_str(), sync, busy, fk), ("wal", 1, 10_000, 1));
    }
    let orphan = sqlx::query("INSERT INTO sweep_cases (sweep_id, case_id, position) VALUES (42, 42, 0)")
        .execute(&mut *held[0])
        .await;
    assert!(orphan.is_err(), "foreign keys are enforced");
    drop(held);
    store.close().await;
}

/// Measures the queue (not run by default: `cargo test --release --test
/// service -- --ignored --nocapture queue_figures`): claims per second with
/// eight concurrent claimers, and the queue's overhead per real case (claim
/// to stored result, minus the solver's own time).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore]
async fn queue_figures() {
    use knotsweep_worker::store::{CreateOutcome, NewCase, NewSweep};
    let (_dir, db) = temp_db();
    let store = Arc::new(SqliteStore::connect(&db, SqliteOptions::default()).await.unwrap());
    // 2000 distinct queued cases (never run: claims only).
    let cases: Vec<NewCase> = (0..2000)
        .map(|i| {
            NewCase::new(solver::case::CaseParams {
                mu: i as f64 / 1000.0,
                ..Default::default()
            })
        })
        .collect();
    let new = |cases: Vec<NewCase>| NewSweep {
        name: None,
        preset: None,
        spec: json!({}),
        varied: vec!["mu".to_string()],
        snapshots: knotsweep_worker::store::SnapshotChoice::All,
        cases,
        idempotency: None,
    };
    let t = Instant::now();
    let created = store.create_sweep(new(cases)).await.unwrap();
    assert!(matches!(created, CreateOutcome::Created { .. }));
    println!(
        "enqueue 2000 cases in one sweep: {:.3} s",
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    let mut tasks = Vec::new();
    for w in 0..8 {
        let store = store.clone();
        tasks.push(tokio::spawn(async move {
            let mut n = 0;
            while store
                .claim(&format!("bench-{w}"), Duration::from_secs(600))
                .await
                .unwrap()
                .is_some()
            {
                n += 1;
            }
            n
        }));
    }
    let mut total = 0;
    for task in tasks {
        total += task.await.unwrap();
    }
    let secs = t.elapsed().as_secs_f64();
    assert_eq!(total, 2000);
    println!(
        "8 concurrent claimers: {total} claims in {secs:.2} s = {:.0} claims/s",
        total as f64 / secs
    );

    // Overhead per real case: one worker, 40 tiny cases back to back.
    let (_dir2, db2) = temp_db();
    let server = start(config(&db2, 0)).await;
    let (url, c) = (server.url(), client());
    let mus: Vec<Value> = (0..40).map(|i| json!(0.3 + i as f64 / 100.0)).collect();
    let (_, s) = post(
        &c,
        &format!("{url}/api/sweeps"),
        &json!({"base": tiny_base(), "grid": {"mu": mus}}),
    )
    .await;
    let t = Instant::now();
    let pool = WorkerPool::start(server.store(), pool_config(1));
    wait_sweep(
        &c,
        &url,
        s["id"].as_i64().unwrap(),
        Duration::from_secs(120),
        finished,
    )
    .await;
    let elapsed = t.elapsed().as_secs_f64();
    pool.shutdown().await;
    let store2 = SqliteStore::connect(&db2, SqliteOptions::default())
        .await
        .unwrap();
    let solver_ms = sqlx_count(
        &store2,
        "SELECT CAST(SUM(wall_time) * 1000 AS INTEGER) FROM results",
    )
    .await as f64;
    let claim_to_done_ms = sqlx_count(
        &store2,
        "SELECT SUM(finished_at - started_at) FROM cases WHERE status = 'done'",
    )
    .await as f64;
    println!(
        "40 tiny cases on one worker: {elapsed:.2} s; solver {:.1} ms/case; claim-to-result {:.1} ms/case; \
         queue overhead {:.1} ms/case (claim to stored result), {:.1} ms/case end to end",
        solver_ms / 40.0,
        claim_to_done_ms / 40.0,
        (claim_to_done_ms - solver_ms) / 40.0,
        (elapsed * 1000.0 - solver_ms) / 40.0
    );
    server.shutdown().await.unwrap();
}

/// A base may name a material, as the grid's axis does: its E, rho and nu;
/// beside one of those constants it is refused naming the constant.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_base_names_a_material() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 0)).await;
    let (url, c) = (server.url(), client());
    let (status, sweep) = post(
        &c,
        &format!("{url}/api/sweeps"),
        &json!({"base": with(tiny_base(), json!({"material": "steel"}))}),
    )
    .await;
    assert_eq!(status, StatusCode::CREATED, "{sweep:#}");
    let (_, cases) = get(&c, &format!("{url}/api/sweeps/{}/cases", sweep["id"])).await;
    let (_, case) = get(&c, &format!("{url}/api/cases/{}", cases[0]["case_id"])).await;
    let (_, materials) = get(&c, &format!("{url}/api/materials")).await;
    let steel = materials
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == "steel")
        .unwrap();
    for k in ["youngs_modulus", "density", "poisson_ratio"] {
        assert_eq!(case["params"][k], steel[k], "{k}");
    }
    assert_eq!(case["nodes"], 121, "the node count the case runs with");
    let (status, refused) = post(
        &c,
        &format!("{url}/api/sweeps"),
        &json!({"base": {"material": "steel", "density": 1000.0}}),
    )
    .await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY);
    assert_eq!(refused["fields"][0]["field"], "base.density", "{refused:#}");
    let (status, refused) = post(
        &c,
        &format!("{url}/api/sweeps"),
        &json!({"base": {"material": "cheese"}}),
    )
    .await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY);
    assert!(
        refused["fields"][0]["reason"].as_str().unwrap().contains("steel"),
        "{refused:#}"
    );
    // A case left at the default node count gives the count it runs with.
    let (_, sweep) = post(&c, &format!("{url}/api/sweeps"), &json!({})).await;
    let (_, cases) = get(&c, &format!("{url}/api/sweeps/{}/cases", sweep["id"])).await;
    let (_, case) = get(&c, &format!("{url}/api/cases/{}", cases[0]["case_id"])).await;
    assert!(case["params"]["nodes"].is_null());
    let default: solver::case::CaseParams = serde_json::from_value(case["params"].clone()).unwrap();
    assert_eq!(case["nodes"], default.node_count());
    server.shutdown().await.unwrap();
}

/// Measured points beside a sweep: as CSV, refused without the varied
/// parameter, read back, and drawn on the phase diagram and the curves.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn measured_points_are_stored_beside_a_sweep_and_drawn() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 2)).await;
    let (url, c) = (server.url(), client());
    let base = with(tiny_base(), json!({"min_l_k_bar": 105.0}));
    let id = submit_sweep(&c, &url, &json!({"base": base, "grid": {"mu": [0.1, 0.15]}})).await;
    let measurements = format!("{url}/api/sweeps/{id}/measurements");
    let (status, none) = get(&c, &measurements).await;
    assert_eq!((status, none), (StatusCode::OK, json!([])));
    let put = |body: Value| {
        let c = c.clone();
        let measurements = measurements.clone();
        async move {
            let r = c.put(&measurements).json(&body).send().await.unwrap();
            (r.status(), r.json::<Value>().await.unwrap())
        }
    };
    let (status, refused) = put(json!({"csv": "h,l_k_bar,error\n0.005,116,1\n"})).await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY);
    assert_eq!(
        refused["fields"][0]["field"], "points[0].params.mu",
        "{refused:#}"
    );
    let (status, refused) = put(json!({"csv": "mu,l_k_bar,error\n0.12,116,0\n"})).await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY);
    assert_eq!(refused["fields"][0]["field"], "points[0].error", "{refused:#}");
    let (status, stored) = put(json!({"csv": "# bench, 2026\nmu,l_k_bar,error\n0.12,116.5,1.5\n"})).await;
    assert_eq!(status, StatusCode::OK, "{stored:#}");
    let (_, back) = get(&c, &measurements).await;
    assert_eq!(
        back,
        json!([{"params": {"mu": 0.12}, "l_k_bar": 116.5, "error": 1.5}])
    );
    wait_sweep(&c, &url, id, Duration::from_secs(120), finished).await;
    let (_, svg) = get_text(&c, &format!("{url}/api/sweeps/{id}/figures/phase.svg")).await;
    assert!(
        svg.contains("measured (± error)"),
        "the measured point in the legend"
    );
    let (_, svg) = get_text(&c, &format!("{url}/api/sweeps/{id}/figures/F_bar.svg")).await;
    assert!(
        svg.contains("measured 116.5 ± 1.5"),
        "the measured inversion on the curves"
    );
    // Another sweep's points overlaid on the phase diagram.
    let other = submit_sweep(&c, &url, &json!({"base": with(tiny_base(), json!({"min_l_k_bar": 105.0, "h": 5.5e-3})), "grid": {"mu": [0.1]}})).await;
    wait_sweep(&c, &url, other, Duration::from_secs(120), finished).await;
    let (status, svg) = get_text(
        &c,
        &format!("{url}/api/sweeps/{id}/figures/phase.svg?with={other}"),
    )
    .await;
    assert_eq!(status, StatusCode::OK);
    assert!(
        svg.contains(&format!("sweep {id}")) && svg.contains(&format!("sweep {other}")),
        "both sweeps in the legend"
    );
    let (status, _) = get_text(&c, &format!("{url}/api/sweeps/{id}/figures/phase.svg?with=x")).await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    server.shutdown().await.unwrap();
}

/// A fit recovers the mu that made its measurements: the tool's own
/// inversions of two rods (h = 3.4 and 2.4 mm) at a known mu, each given an error of 1 in l_k bar,
/// give back that mu inside the fit's interval, and the interval is no wider
/// than those errors allow (at most 0.08).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_fit_recovers_the_mu_that_made_its_points() {
    let (_dir, db) = temp_db();
    let server = start(config(&db, 2)).await;
    let (url, c) = (server.url(), client());
    // The paper's rod (the short rods of the other tests invert too erratically with mu to fit).
    let base = json!({});
    let truth = 0.3;
    let radii = [3.4e-3, 2.4e-3];
    let made = submit_sweep(
        &c,
        &url,
        &json!({"base": with(base.clone(), json!({"mu": truth})), "grid": {"h": radii}}),
    )
    .await;
    wait_sweep(&c, &url, made, Duration::from_secs(600), finished).await;
    let (_, pd) = get(&c, &format!("{url}/api/sweeps/{made}/phase-diagram")).await;
    let points: Vec<Value> = (pd["points"].as_array().unwrap().iter())
        .map(|p| {
            let l_k_bar = p["inversion"]["l_k_bar"]
                .as_f64()
                .unwrap_or_else(|| panic!("no inversion: {p:#}"));
            json!({"params": {"h": p["params"]["h"]}, "l_k_bar": l_k_bar, "error": 1.0})
        })
        .collect();

    // Bad fits are refused at submit time, naming the field.
    let fits = format!("{url}/api/fits");
    let (status, refused) = post(
        &c,
        &fits,
        &json!({"parameter": "n", "range": [1, 4], "points": points}),
    )
    .await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY);
    assert_eq!(refused["fields"][0]["field"], "parameter", "{refused:#}");
    let (status, refused) = post(&c, &fits, &json!({"range": [0.4, 0.05], "points": []})).await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY);
    let fields: Vec<&str> = refused["fields"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["field"].as_str().unwrap())
        .collect();
    assert_eq!(fields, ["range", "points"], "{refused:#}");

    let (status, fit) = post(
        &c,
        &fits,
        &json!({"parameter": "mu", "range": [0.05, 0.8], "base": base, "points": points}),
    )
    .await;
    assert_eq!(status, StatusCode::ACCEPTED, "{fit:#}");
    assert_eq!(fit["status"], "running");
    let id = fit["id"].as_i64().unwrap();
    let t = Instant::now();
    let fit = loop {
        let (_, fit) = get(&c, &format!("{url}/api/fits/{id}")).await;
        if fit["status"] != "running" {
            break fit;
        }
        assert!(t.elapsed() < Duration::from_secs(1200), "fit not done: {fit:#}");
        tokio::time::sleep(Duration::from_millis(500)).await;
    };
    assert_eq!(fit["status"], "done", "{fit:#}");
    let (value, lo, hi) = (
        fit["value"].as_f64().unwrap(),
        fit["interval"][0].as_f64().unwrap(),
        fit["interval"][1].as_f64().unwrap(),
    );
    println!(
        "fit: mu = {value:.4} in [{lo:.4}, {hi:.4}], {} evaluations",
        fit["evaluations"].as_array().unwrap().len()
    );
    assert!(
        lo <= truth && truth <= hi,
        "{truth} outside [{lo}, {hi}]: {fit:#}"
    );
    assert!(hi - lo <= 0.08, "interval {} wide: {fit:#}", hi - lo);
    // Its cases ran as sweeps of the queue, one per point and evaluation.
    let sweeps = fit["sweeps"].as_array().unwrap();
    assert!(sweeps.len() >= 4 && sweeps.len() % 2 == 0, "{fit:#}");
    let (status, _) = get(&c, &format!("{url}/api/sweeps/{}", sweeps[0])).await;
    assert_eq!(status, StatusCode::OK);
    server.shutdown().await.unwrap();
}
