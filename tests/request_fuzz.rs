//! Property test of the API's request parsing (issue 15): arbitrary JSON
//! shapes and values posted as sweeps never get a 5xx; every 4xx is a JSON
//! error that names a field or gives a reason; a rejected request stores nothing.
mod common;

use common::*;
use proptest::prelude::*;
use serde_json::{Map, Value, json};

/// Keys a sweep request has, a few near misses and any short string.
fn key() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("base".to_string()),
        Just("grid".to_string()),
        Just("preset".to_string()),
        Just("name".to_string()),
        Just("n".to_string()),
        Just("h".to_string()),
        Just("mu".to_string()),
        Just("nodes".to_string()),
        Just("gravity".to_string()),
        Just("initial_shape".to_string()),
        Just("fig9".to_string()),
        "[a-z_]{0,12}",
    ]
}

/// Any JSON value, biased to the numbers and shapes that stress validation.
fn value() -> impl Strategy<Value = Value> {
    let leaf = prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::Bool),
        any::<i64>().prop_map(|v| json!(v)),
        prop_oneof![
            Just(0.0),
            Just(-1.0),
            Just(1e-300),
            Just(1e300),
            Just(f64::MAX),
            -1e3..1e3f64,
            0.0..0.01f64
        ]
        .prop_map(|v| json!(v)),
        "[ -~]{0,16}".prop_map(Value::String),
        Just(json!("fig9")),
    ];
    leaf.prop_recursive(3, 24, 6, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..6).prop_map(Value::Array),
            prop::collection::vec((key(), inner), 0..6)
                .prop_map(|kv| Value::Object(kv.into_iter().collect::<Map<_, _>>())),
        ]
    })
}

/// A request body: a JSON object of sweep-like keys, any JSON value, or bytes.
fn body() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        4 => prop::collection::vec((key(), value()), 0..5)
            .prop_map(|kv| serde_json::to_vec(&Value::Object(kv.into_iter().collect::<Map<_, _>>())).unwrap()),
        1 => value().prop_map(|v| serde_json::to_vec(&v).unwrap()),
        1 => prop::collection::vec(any::<u8>(), 0..64),
    ]
}

#[test]
fn arbitrary_sweep_requests_get_no_5xx_and_rejections_store_nothing() {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    let (_dir, db) = temp_db();
    // No workers: accepted sweeps stay queued, nothing computes.
    let server = rt.block_on(start(config(&db, 0)));
    let url = server.url();
    let c = client();
    let sweeps = |c: &reqwest::Client| {
        let c = c.clone();
        let url = url.clone();
        async move {
            let r = c.get(format!("{url}/api/sweeps?limit=1")).send().await.unwrap();
            r.headers()["x-total-count"]
                .to_str()
                .unwrap()
                .parse::<u64>()
                .unwrap()
        }
    };
    let config = ProptestConfig {
        cases: 300,
        failure_persistence: None,
        ..ProptestConfig::default()
    };
    proptest!(config, |(body in body())| {
        rt.block_on(async {
            let before = sweeps(&c).await;
            let r = c
                .post(format!("{url}/api/sweeps"))
                .header("Content-Type", "application/json")
                .body(body.clone())
                .send()
                .await
                .unwrap();
            let status = r.status();
            let text = r.text().await.unwrap();
            let after = sweeps(&c).await;
            let shown = String::from_utf8_lossy(&body);
            prop_assert!(status.as_u16() < 500, "{status} for {shown}: {text}");
            if status.is_client_error() {
                let e: Value = serde_json::from_str(&text).map_err(|_| TestCaseError::fail(format!("non-JSON {status}: {text}")))?;
                let named = e["fields"].as_array().is_some_and(|f| {
                    !f.is_empty() && f.iter().all(|x| x["field"].is_string() && !x["reason"].as_str().unwrap_or("").is_empty())
                });
                prop_assert!(named || !e["message"].as_str().unwrap_or("").is_empty(), "{status} without a reason: {text}");
                prop_assert_eq!(before, after, "a rejected request stored a sweep: {}", shown);
            } else {
                prop_assert!(status.is_success(), "{status} for {shown}");
                prop_assert!(after >= before, "{shown}");
            }
            Ok(())
        })?;
    });
    rt.block_on(server.shutdown()).unwrap();
}
