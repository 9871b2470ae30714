//! The web page in a real browser: Debian's chromium driven through
//! chromedriver (WebDriver over HTTP). Submit a certified custom sweep through
//! the form, watch it finish, see its curves and phase diagram (with the
//! refined twins' error bars), open a case's 3D knot and
//! move the snapshot slider, cancel a sweep from the list, and get a field error
//! for a bad value, all without a violation of the page's Content-Security-Policy
//! (nor in Swagger UI). Screenshots land in `target/tmp/web-*.png`. Without
//! chromium or chromedriver it is skipped with the reason, or fails when `CI`
//! is set (`common::missing`).
mod common;

use common::*;
use serde_json::{Value, json};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A WebDriver session on a headless chromium.
struct Browser {
    driver: Child,
    base: String,
    session: String,
    http: reqwest::Client,
}

impl Browser {
    async fn start() -> Result<Self, String> {
        for tool in ["chromium", "chromedriver"] {
            let found = Command::new("sh")
                .args(["-c", &format!("command -v {tool}")])
                .stdout(Stdio::null())
                .status()
                .is_ok_and(|s| s.success());
            if !found {
                return Err(format!(
                    "{tool} is not installed (apt-get install chromium chromium-driver)"
                ));
            }
        }
        let port = std::net::TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        let driver = Command::new("chromedriver")
            .arg(format!("--port={port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .map_err(|e| format!("chromedriver: {e}"))?;
        let http = reqwest::Client::new();
        let base = format!("http://127.0.0.1:{port}");
        let t = Instant::now();
        while http.get(format!("{base}/status")).send().await.is_err() {
            if t.elapsed() > Duration::from_secs(20) {
                return Err("chromedriver did not start".into());
            }
            tokio::time::sleep(Duration::from_millis(200)).await;
        }
        let args = [
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--enable-unsafe-swiftshader",
            "--window-size=1280,1000",
        ];
        let caps = json!({"capabilities": {"alwaysMatch": {"goog:chromeOptions": {"args": args}}}});
        let r: Value = http
            .post(format!("{base}/session"))
            .json(&caps)
            .send()
            .await
            .map_err(|e| e.to_string())?
            .json()
            .await
            .map_err(|e| e.to_string())?;
        let session = r["value"]["sessionId"]
            .as_str()
            .ok_or_else(|| format!("no session: {r}"))?
            .to_string();
        Ok(Self {
            driver,
            base,
            session,
            http,
        })
    }

    async fn call(&self, method: reqwest::Method, path: &str, body: Value) -> Value {
        let url = format!("{}/session/{}{path}", self.base, self.session);
        let mut request = self.http.request(method.clone(), url);
        if method != reqwest::Method::GET {
            request = request.json(&body);
        }
        let r: Value = request.send().await.unwrap().json().await.unwrap();
        r["value"].clone()
    }

    async fn open(&self, url: &str) {
        self.call(reqwest::Method::POST, "/url", json!({"url": url}))
            .await;
    }

    /// Runs `script` (a function body; `arguments` are `args`) in the page.
    async fn js(&self, script: &str, args: Value) -> Value {
        self.call(
            reqwest::Method::POST,
            "/execute/sync",
            json!({"script": script, "args": args}),
        )
        .await
    }

    /// Waits until `script` returns a truthy value; returns it.
    async fn until(&self, what: &str, script: &str, timeout: Duration) -> Value {
        let t = Instant::now();
        loop {
            let v = self.js(script, json!([])).await;
            let truthy = !(v.is_null() || v == json!(false) || v == json!(0) || v == json!(""));
            if truthy {
                return v;
            }
            assert!(t.elapsed() < timeout, "timed out waiting for {what}");
            tokio::time::sleep(Duration::from_millis(250)).await;
        }
    }

    /// Fills the form's parameter fields from a case's parameters (a word,
    /// e.g. the protocol, goes in bare, a number as its JSON text) and the
    /// grid field `g-mu`.
    async fn fill_base(&self, base: &Value, mus: &str) {
        let mut fields = serde_json::Map::new();
        for (k, v) in base.as_object().unwrap() {
            let text = v.as_str().map_or_else(|| v.to_string(), str::to_string);
            fields.insert(format!("p-{k}"), json!(text));
        }
        fields.insert("g-mu".into(), json!(mus));
        self.js(FILL, json!([fields])).await;
    }

    /// Clicks the form's submit button.
    async fn submit(&self) {
        self.js(
            "document.querySelector('#custom button[type=submit]').click(); return true",
            json!([]),
        )
        .await;
    }

    /// Submits the form and waits for the new sweep's page: its id.
    async fn submit_and_open_sweep(&self) -> i64 {
        self.submit().await;
        let hash = self
            .until(
                "the sweep page",
                "return /^#\\/sweeps\\/\\d+/.test(location.hash) && location.hash",
                Duration::from_secs(20),
            )
            .await;
        hash.as_str()
            .unwrap()
            .rsplit('/')
            .next()
            .unwrap()
            .parse()
            .unwrap()
    }

    /// Records the page's Content-Security-Policy violations, those before
    /// this call included (a buffered `ReportingObserver`), for
    /// [`Browser::csp_violations`].
    async fn watch_csp(&self) {
        self.js(WATCH_CSP, json!([])).await;
    }

    /// The violations recorded since [`Browser::watch_csp`], each
    /// `directive URL`.
    async fn csp_violations(&self) -> Value {
        tokio::time::sleep(Duration::from_millis(300)).await;
        self.js("return window.cspViolations", json!([])).await
    }

    /// Sets the window's outer size.
    async fn size(&self, width: u32, height: u32) {
        self.call(
            reqwest::Method::POST,
            "/window/rect",
            json!({"width": width, "height": height}),
        )
        .await;
    }

    /// Opens `url` and waits until `ready` (a script) holds; then the page's
    /// width against the window's and the words of its text that speak code
    /// (`null`, `undefined`, `NaN`).
    async fn page(&self, url: &str, ready: &str) -> (u64, u64, Vec<String>) {
        self.open(url).await;
        self.until(url, ready, Duration::from_secs(60)).await;
        tokio::time::sleep(Duration::from_millis(500)).await;
        let v = self
            .js(
                "return [document.documentElement.scrollWidth, window.innerWidth, \
                 document.body.innerText.match(/\\b(null|undefined|NaN)\\b/g) || []]",
                json!([]),
            )
            .await;
        let words = v[2]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| w.as_str().unwrap().to_string())
            .collect();
        (v[0].as_u64().unwrap(), v[1].as_u64().unwrap(), words)
    }

    async fn screenshot(&self, name: &str) {
        let png = self.call(reqwest::Method::GET, "/screenshot", Value::Null).await;
        let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("web-{name}.png"));
        std::fs::write(&path, base64_decode(png.as_str().unwrap())).unwrap();
        println!("screenshot: {}", path.display());
    }
}

/// A browser beside a server with `workers` workers on its own database.
struct Page {
    browser: Browser,
    server: knotsweep_server::RunningServer,
    url: String,
    c: reqwest::Client,
    _dir: tempfile::TempDir,
}

/// A [`Page`]; `None` without chromium or chromedriver (reported by
/// `common::missing`: skipped, or a failure when `CI` is set).
async fn page(workers: usize) -> Option<Page> {
    let browser = match Browser::start().await {
        Ok(b) => b,
        Err(why) => {
            missing(&why);
            return None;
        }
    };
    let (_dir, db) = temp_db();
    let server = start(config(&db, workers)).await;
    let (url, c) = (server.url(), client());
    Some(Page {
        browser,
        server,
        url,
        c,
        _dir,
    })
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.driver.kill();
        let _ = self.driver.wait();
    }
}

/// Standard base64 (the WebDriver screenshot encoding).
fn base64_decode(text: &str) -> Vec<u8> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        _ => 63,
    };
    let bytes: Vec<u8> = text
        .bytes()
        .filter(|c| *c != b'=' && !c.is_ascii_whitespace())
        .collect();
    let mut out = Vec::with_capacity(bytes.len() * 3 / 4);
    for chunk in bytes.chunks(4) {
        let v: u32 = chunk
            .iter()
            .enumerate()
            .map(|(i, c)| u32::from(value(*c)) << (18 - 6 * i))
            .sum();
        out.extend_from_slice(&v.to_be_bytes()[1..chunk.len()]);
    }
    out
}

/// Sets form inputs by id and fires their input events.
const FILL: &str = "for (const [id, v] of Object.entries(arguments[0])) { const e = document.getElementById(id); \
    e.value = v; e.dispatchEvent(new Event('input', {bubbles: true})); } return true;";

/// Collects the page's CSP violations into `window.cspViolations`: the events
/// from now on and, through a buffered `ReportingObserver`, the reports of
/// those before.
const WATCH_CSP: &str = "window.cspViolations = []; \
    document.addEventListener('securitypolicyviolation', (e) => window.cspViolations.push(e.effectiveDirective + ' ' + e.blockedURI)); \
    new ReportingObserver((reports) => { for (const r of reports) window.cspViolations.push(r.body.effectiveDirective + ' ' + r.body.blockedURL); }, \
      {types: ['csp-violation'], buffered: true}).observe(); return true;";

/// Non-background pixels of the 3D canvas (read back from WebGL).
const KNOT_PIXELS: &str = "const c = document.querySelector('#knot canvas'); if (!c) return 0; \
    const gl = c.getContext('webgl2') || c.getContext('webgl'); const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight; \
    const px = new Uint8Array(4 * w * h); gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px); \
    let n = 0; for (let i = 0; i < px.length; i += 4) { if (Math.abs(px[i] - px[0]) + Math.abs(px[i + 1] - px[1]) + Math.abs(px[i + 2] - px[2]) > 30) n++; } \
    return n / (w * h);";

/// Pixels of the 3D canvas in each rod's colour: blue (the first rod's,
/// 0x2e7dd7) and orange (the second's, 0xd55e00), by their hue under the
/// lights.
const ROD_PIXELS: &str = "const c = document.querySelector('#knot canvas'); \
    const gl = c.getContext('webgl2') || c.getContext('webgl'); const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight; \
    const px = new Uint8Array(4 * w * h); gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px); \
    let blue = 0, orange = 0; for (let i = 0; i < px.length; i += 4) { const [r, g, b] = [px[i], px[i + 1], px[i + 2]]; \
      if (b > r + 60 && b > g) blue++; if (r > b + 60 && r > g + 30) orange++; } \
    return [blue / (w * h), orange / (w * h)];";

/// A bend's case page: the API's snapshots say which nodes are whose rod,
/// and the 3D view draws the two rods in their two colours, with a legend.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_bends_rods_are_drawn_each_in_its_colour() {
    let Some(Page {
        browser,
        server,
        url,
        c,
        _dir,
    }) = page(1).await
    else {
        return;
    };
    let base = json!({"knot": "reef", "length": 0.4, "nodes": 121, "relax_time": 0.1, "pull_speed": 0.01,
        "min_l_k_bar": 100.0});
    let id = submit_sweep(&c, &url, &json!({ "base": base })).await;
    let sweep = wait_sweep(&c, &url, id, Duration::from_secs(120), finished).await;
    let case = case_ids(&sweep)[0];
    let (_, snapshots) = get(&c, &format!("{url}/api/cases/{case}/snapshots")).await;
    assert_eq!(
        snapshots[0]["rods"],
        json!([121, 121]),
        "the stored snapshots keep the rods"
    );
    browser.open(&format!("{url}/#/cases/{case}")).await;
    browser
        .until(
            "the 3D canvas",
            "return document.querySelector('#knot canvas') !== null",
            Duration::from_secs(20),
        )
        .await;
    tokio::time::sleep(Duration::from_millis(500)).await;
    let fractions = browser.js(ROD_PIXELS, json!([])).await;
    let (blue, orange) = (fractions[0].as_f64().unwrap(), fractions[1].as_f64().unwrap());
    assert!(
        blue > 1e-3 && orange > 1e-3,
        "blue {blue}, orange {orange} of the canvas"
    );
    let hint = browser
        .js(
            "return document.querySelector('#knot').parentElement.textContent",
            json!([]),
        )
        .await;
    assert!(hint.as_str().unwrap().contains("rod 2 orange"), "{hint}");
    // The parameters line names the knot, not an overhand's n.
    let held = browser
        .js("return document.querySelector('#held').textContent", json!([]))
        .await;
    let held = held.as_str().unwrap();
    assert!(held.contains("reef") && !held.contains("n = "), "{held}");
    // The status line gives the bend's holding force, not "no inversion".
    let status = browser
        .js("return document.querySelector('#case p').textContent", json!([]))
        .await;
    let status = status.as_str().unwrap();
    assert!(
        status.contains("holding force") && !status.contains("no inversion"),
        "{status}"
    );
    browser.screenshot("bend").await;
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_submits_watches_plots_shows_the_knot_cancels_and_reports_field_errors() {
    let Some(Page {
        browser,
        server,
        url,
        c,
        _dir,
    }) = page(1).await
    else {
        return;
    };

    // Submit a custom sweep through the form generated from the schema.
    browser.open(&format!("{url}/#/")).await;
    browser
        .until(
            "the form",
            "return document.getElementById('p-h') !== null",
            Duration::from_secs(20),
        )
        .await;
    browser.watch_csp().await;
    // Pulled on to l_k bar 105: mu = 0.1 inverts near 116 in about a second,
    // and so does its refined twin; at mu = 0.05 only the point does.
    let base = with(tiny_base(), json!({"min_l_k_bar": 105.0}));
    browser.fill_base(&base, "0.05, 0.1").await;
    let count = browser
        .js("return document.getElementById('count').textContent", json!([]))
        .await;
    assert_eq!(count, "2 cases", "live case count");
    // Certified: each case also runs its refined twin.
    let count = browser
        .js(
            "document.getElementById('certify').click(); return document.getElementById('count').textContent",
            json!([]),
        )
        .await;
    assert_eq!(count, "4 cases: 2 points and their refined twins");
    let id = browser.submit_and_open_sweep().await;
    let (_, sweep) = get_sweep(&c, &url, id).await;
    assert_eq!(sweep["total"], 4, "2 points and 2 twins");
    assert_eq!(sweep["spec"]["base"]["h"], json!(5e-3), "{sweep:#}");
    assert_eq!(sweep["spec"]["base"]["protocol"], json!("reference"), "{sweep:#}");
    assert_eq!(sweep["spec"]["certify"], true, "{sweep:#}");

    // Progress moves to the end; the curves and the phase diagram appear.
    let first = browser
        .until(
            "a progress bar",
            "const p = document.querySelector('#summary progress'); return p && String(p.value)",
            Duration::from_secs(20),
        )
        .await;
    browser
        .until(
            "two curves per plot (the twins draw none)",
            "const f = document.getElementById('plot-f'); return f && f.dataset.series === '2' && document.getElementById('plot-h').dataset.series === '2'",
            Duration::from_secs(120),
        )
        .await;
    let last = browser
        .until("the full progress bar", "const p = document.querySelector('#summary progress'); return p && p.value >= 1 && String(p.value)", Duration::from_secs(60))
        .await;
    assert!(
        first.as_str().unwrap().parse::<f64>().unwrap() <= last.as_str().unwrap().parse::<f64>().unwrap()
    );
    let points = browser
        .until("the phase diagram", "const p = document.getElementById('phase'); return p && p.dataset.points !== undefined && p.dataset.points", Duration::from_secs(30))
        .await;
    let (inverted, loaded) = sweep_inversions(&c, &url, id).await;
    assert_eq!(points, json!(inverted.to_string()), "one point per inverted case");
    // Events through which F bar does not fall are drawn hollow and listed.
    let (hollow, note) = browser
        .js(
            "const p = document.getElementById('phase'); return [p.dataset.loaded, document.getElementById('phase-note').textContent]",
            json!([]),
        )
        .await
        .as_array()
        .map(|a| (a[0].clone(), a[1].as_str().unwrap_or_default().to_string()))
        .unwrap();
    assert_eq!(hollow, json!(loaded.to_string()), "hollow points: {note}");
    assert_eq!(note.contains("F̄ does not fall"), loaded > 0, "{note}");
    // Certified: an error bar on every point whose twin inverted too, a red
    // ring on the unconverged ones, and the twins marked in the case table.
    let (bars, unconverged) = sweep_uncertainties(&c, &url, id).await;
    assert!(bars > 0, "no point with an uncertainty");
    let shown = browser
        .until(
            "the error bars",
            &format!("const p = document.getElementById('phase'); return p.dataset.errorbars === '{bars}' && [p.dataset.errorbars, p.dataset.unconverged, document.getElementById('phase-note').textContent]"),
            Duration::from_secs(20),
        )
        .await;
    assert_eq!(shown[1], json!(unconverged.to_string()), "{shown}");
    assert_eq!(
        shown[2].as_str().unwrap().contains("Unconverged"),
        unconverged > 0,
        "{shown}"
    );
    let twins = browser
        .js(
            "return [...document.querySelectorAll('#cases tr.twin')].map((r) => r.textContent)",
            json!([]),
        )
        .await;
    let twins = twins.as_array().unwrap();
    assert_eq!(twins.len(), 2, "{twins:?}");
    assert!(
        twins
            .iter()
            .all(|t| t.as_str().unwrap().contains("refined twin of #")),
        "{twins:?}"
    );
    let canvases = browser
        .js(
            "return document.querySelectorAll('#main canvas').length",
            json!([]),
        )
        .await;
    assert!(
        canvases.as_u64().unwrap() >= 3,
        "F, H and phase plots: {canvases}"
    );
    browser.screenshot("sweep").await;
    browser
        .js(
            "document.getElementById('phase-h').scrollIntoView(); return true",
            json!([]),
        )
        .await;
    browser.screenshot("phase").await;

    // The case page: a 3D knot that is drawn, and a slider that changes the snapshot.
    browser
        .js(
            "document.querySelector('#cases a[href^=\"#/cases/\"]').click(); return true",
            json!([]),
        )
        .await;
    browser
        .until(
            "the 3D canvas",
            "return document.querySelector('#knot canvas') !== null",
            Duration::from_secs(20),
        )
        .await;
    tokio::time::sleep(Duration::from_millis(500)).await;
    let drawn = browser.js(KNOT_PIXELS, json!([])).await.as_f64().unwrap();
    assert!(drawn > 0.005, "the knot covers {drawn} of the canvas");
    let label = browser
        .js(
            "return document.getElementById('snapshot-label').textContent",
            json!([]),
        )
        .await;
    let snapshots = browser
        .js(
            "const s = document.getElementById('snapshot'); return Number(s.max) + 1",
            json!([]),
        )
        .await;
    assert!(snapshots.as_u64().unwrap() >= 2, "snapshots: {snapshots}");
    browser
        .js("const s = document.getElementById('snapshot'); s.value = s.value === '0' ? s.max : '0'; s.dispatchEvent(new Event('input')); return true", json!([]))
        .await;
    let moved = browser
        .js(
            "return document.getElementById('snapshot-label').textContent",
            json!([]),
        )
        .await;
    assert_ne!(label, moved, "the slider changes the snapshot");
    browser.screenshot("case").await;
    // The form, the plots and the 3D knot ran under the page's policy.
    assert_eq!(browser.csp_violations().await, json!([]));

    // Cancel from the sweeps list.
    let long = submit_sweep(
        &c,
        &url,
        &json!({"base": long_base(), "grid": {"mu": [0.2, 0.4, 0.6]}}),
    )
    .await;
    browser.open(&format!("{url}/#/")).await;
    let selector = format!("#sweeps button[data-id=\"{long}\"][data-action=\"cancel\"]");
    browser
        .until(
            "the cancel button",
            &format!("return document.querySelector('{selector}') !== null"),
            Duration::from_secs(20),
        )
        .await;
    browser
        .js(
            &format!("document.querySelector('{selector}').click(); return true"),
            json!([]),
        )
        .await;
    let t = Instant::now();
    loop {
        let (_, s) = get(&c, &format!("{url}/api/sweeps/{long}")).await;
        if s["state"] == "cancelled" {
            break;
        }
        assert!(t.elapsed() < Duration::from_secs(20), "not cancelled: {s:#}");
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    browser.screenshot("sweeps").await;

    // A bad value: the API's field error next to the field.
    browser.js(FILL, json!([{"p-h": "-1"}])).await;
    browser.submit().await;
    let error = browser
        .until(
            "the field error",
            "const e = document.querySelector('.field-error[data-for=\"h\"]'); return e && e.textContent",
            Duration::from_secs(20),
        )
        .await;
    assert!(error.as_str().unwrap().contains("base.h"), "{error}");
    server.shutdown().await.unwrap();
}

/// The form a researcher fills in: the parameters grouped as the table groups
/// them (the solver's folded away), a material picker that fills E, rho and
/// nu, and a loading-program editor whose program the submitted sweep
/// carries; the sweep's phase diagram draws the flip backs, and a case page
/// of a program that loosens draws tightening and loosening in their own
/// styles with its events marked.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_form_groups_parameters_picks_materials_and_edits_loading_programs() {
    let Some(Page {
        browser,
        server,
        url,
        c,
        _dir,
    }) = page(1).await
    else {
        return;
    };
    browser.open(&format!("{url}/#/")).await;
    browser
        .until(
            "the form",
            "return document.getElementById('p-h') !== null && document.getElementById('loading-json') !== null",
            Duration::from_secs(20),
        )
        .await;

    // One fieldset per group, in the table's order, with the groups' titles;
    // the solver's options folded under "advanced"; each doc folded.
    let layout = browser
        .js(
            "const sets = [...document.querySelectorAll('#params fieldset.group')]; \
             const adv = document.getElementById('advanced'); \
             return {groups: sets.map((f) => f.dataset.group), legends: sets.map((f) => f.querySelector('legend').textContent), \
               advanced: adv && adv.tagName === 'DETAILS' && !adv.open, dt: !!document.getElementById('p-dt').closest('details.advanced'), \
               n: !!document.getElementById('p-n').closest('details.advanced'), \
               first: [...sets[0].querySelectorAll('.field[data-param]')].map((f) => f.dataset.param).slice(0, 1), \
               docs: document.querySelectorAll('#params .field .doc').length, \
               fields: document.querySelectorAll('#params .field input[id^=\"p-\"], #params .field select[id^=\"p-\"]').length}",
            json!([]),
        )
        .await;
    assert_eq!(
        layout["groups"],
        json!(["knot", "rod", "friction", "loading", "solver"]),
        "{layout}"
    );
    assert_eq!(layout["legends"][1], "Rod and material", "{layout}");
    assert_eq!(layout["advanced"], true, "the solver's group is folded: {layout}");
    assert_eq!(layout["dt"], true, "{layout}");
    assert_eq!(layout["n"], false, "{layout}");
    assert_eq!(layout["first"], json!(["knot"]), "the table's order: {layout}");
    assert_eq!(layout["docs"], layout["fields"], "a doc per parameter: {layout}");

    // The material picker fills E, rho and nu from GET /api/materials.
    let (_, materials) = get(&c, &format!("{url}/api/materials")).await;
    let steel = materials
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == "steel")
        .unwrap()
        .clone();
    let pick = "const m = document.getElementById('material'); m.value = arguments[0]; m.dispatchEvent(new Event('change')); \
        return ['youngs_modulus', 'density', 'poisson_ratio'].map((k) => document.getElementById('p-' + k).value)";
    let filled = browser.js(pick, json!(["steel"])).await;
    let numbers: Vec<f64> = filled
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().parse().unwrap())
        .collect();
    assert_eq!(
        numbers,
        [
            steel["youngs_modulus"].as_f64().unwrap(),
            steel["density"].as_f64().unwrap(),
            steel["poisson_ratio"].as_f64().unwrap()
        ]
    );
    let source = browser
        .js(
            "return document.getElementById('material-source').textContent",
            json!([]),
        )
        .await;
    assert_eq!(source, steel["source"]);
    // Back to custom: the fields empty again (the rod's defaults).
    assert_eq!(browser.js(pick, json!([""])).await, json!(["", "", ""]));

    // The program editor: a preset, a stage added, edited and removed.
    let program =
        |script: &str| format!("{script}; return document.getElementById('loading-json').textContent");
    let shown = browser
        .js(
            &program("const p = document.getElementById('program-preset'); p.value = 'hysteresis'; p.dispatchEvent(new Event('change'))"),
            json!([]),
        )
        .await;
    assert_eq!(shown, r#"[{"pull":{}},{"release":{}}]"#);
    let shown = browser
        .js(
            &program("document.getElementById('stage-kind').value = 'hold'; document.getElementById('stage-add').click(); \
                const s = document.querySelector('[data-stage=\"2\"][data-key=\"seconds\"]'); s.value = '0.02'; \
                s.dispatchEvent(new Event('input', {bubbles: true}))"),
            json!([]),
        )
        .await;
    assert_eq!(shown, r#"[{"pull":{}},{"release":{}},{"hold":{"seconds":0.02}}]"#);
    let preset = browser
        .js(
            "return document.getElementById('program-preset').value",
            json!([]),
        )
        .await;
    assert_eq!(preset, "custom");
    let shown = browser
        .js(
            &program("document.querySelector('[data-remove=\"2\"]').click()"),
            json!([]),
        )
        .await;
    assert_eq!(shown, r#"[{"pull":{}},{"release":{}}]"#);

    // Submit: tightened past the snap (near l_k bar 116), then loosened back.
    let base = with(tiny_base(), json!({"min_l_k_bar": 105.0}));
    browser.fill_base(&base, "0.1, 0.15").await;
    let id = browser.submit_and_open_sweep().await;
    let (_, sweep) = get_sweep(&c, &url, id).await;
    assert_eq!(
        sweep["spec"]["base"]["loading"],
        json!([{"pull": {}}, {"release": {}}]),
        "{sweep:#}"
    );
    assert_eq!(sweep["total"], 2);

    // The phase diagram: a flip back and a band per point with hysteresis.
    let t = Instant::now();
    loop {
        let (_, s) = get(&c, &format!("{url}/api/sweeps/{id}")).await;
        if s["status"] == "done" {
            break;
        }
        assert!(t.elapsed() < Duration::from_secs(300), "not done: {s:#}");
        tokio::time::sleep(Duration::from_millis(500)).await;
    }
    let (_, pd) = get(&c, &format!("{url}/api/sweeps/{id}/phase-diagram")).await;
    let flipped = pd["points"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| !p["hysteresis"].is_null())
        .count();
    let unsteady = pd["points"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| !p["inversion"].is_null() && p["quasi_static"]["holds"] == false)
        .count();
    let drawn = browser
        .until(
            "the phase diagram",
            "const p = document.getElementById('phase'); return p && p.dataset.flips !== undefined && [p.dataset.flips, p.dataset.band, p.dataset.unsteady]",
            Duration::from_secs(30),
        )
        .await;
    assert_eq!(
        drawn,
        json!([flipped.to_string(), flipped.to_string(), unsteady.to_string()]),
        "{pd:#}"
    );
    println!("{flipped} of 2 points with hysteresis, {unsteady} not quasi-static");
    browser.screenshot("hysteresis-sweep").await;

    // A case of the program: its tightening and loosening drawn in both styles,
    // its events marked, and its quasi-staticity as the report has it.
    let case_id = pd["points"][0]["case_id"].as_i64().unwrap();
    browser.open(&format!("{url}/#/cases/{case_id}")).await;
    let styles = browser
        .until(
            "the curves",
            "const f = document.getElementById('plot-f'); return f && f.dataset.directions && [f.dataset.directions, f.dataset.events, \
             document.getElementById('plot-h').dataset.directions, document.querySelectorAll('#plot-e canvas').length, \
             document.getElementById('not-quasi-static') !== null]",
            Duration::from_secs(20),
        )
        .await;
    assert_eq!(styles[0], "loosen,tighten", "{styles}");
    assert_eq!(styles[2], "loosen,tighten", "{styles}");
    assert_eq!(styles[3], 1, "the energy plot: {styles}");
    let (_, case) = get(&c, &format!("{url}/api/cases/{case_id}")).await;
    let summary = &case["result"]["summary"];
    let kinds: Vec<&str> = summary["events"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["kind"].as_str().unwrap())
        .collect();
    assert_eq!(styles[1], kinds.join(","), "every event marked: {styles}");
    assert_eq!(
        styles[4],
        json!(summary["quasi_static"]["holds"] == false),
        "{summary:#}"
    );
    browser
        .js(
            "document.getElementById('curves-h').scrollIntoView(); return true",
            json!([]),
        )
        .await;
    browser.screenshot("hysteresis-case").await;
    server.shutdown().await.unwrap();
}

/// Cases of the sweep with an inversion, and those among them through which
/// F bar does not fall.
async fn sweep_inversions(c: &reqwest::Client, url: &str, id: i64) -> (usize, usize) {
    let (_, pd) = get(c, &format!("{url}/api/sweeps/{id}/phase-diagram")).await;
    let inverted: Vec<&Value> = pd["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| &p["inversion"])
        .filter(|i| !i.is_null())
        .collect();
    let loaded = inverted
        .iter()
        .filter(|i| i["F_bar_after"].as_f64() >= i["F_bar_before"].as_f64())
        .count();
    (inverted.len(), loaded)
}

/// Points of the sweep with an error bar (both the point and its refined twin
/// inverted), and the inverted points flagged as unconverged.
async fn sweep_uncertainties(c: &reqwest::Client, url: &str, id: i64) -> (usize, usize) {
    let (_, pd) = get(c, &format!("{url}/api/sweeps/{id}/phase-diagram")).await;
    assert_eq!(pd["certified"], true, "{pd:#}");
    let inverted: Vec<&Value> = pd["points"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| !p["inversion"].is_null())
        .map(|p| &p["uncertainty"])
        .collect();
    let bars = inverted.iter().filter(|u| !u["absolute"].is_null()).count();
    let unconverged = inverted.iter().filter(|u| u["converged"] == false).count();
    (bars, unconverged)
}

/// Swagger UI under `/api/docs/` renders the API's operations under the
/// Content-Security-Policy every answer carries, without a violation.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_api_docs_render_under_the_content_security_policy() {
    let Some(Page {
        browser,
        server,
        url,
        _dir,
        ..
    }) = page(0).await
    else {
        return;
    };
    browser.open(&format!("{url}/api/docs/")).await;
    let operations = browser
        .until(
            "Swagger UI's operations",
            "return document.querySelectorAll('.swagger-ui .opblock').length",
            Duration::from_secs(20),
        )
        .await;
    assert!(operations.as_u64().unwrap() >= 10, "{operations}");
    browser.watch_csp().await;
    browser
        .js(
            "document.querySelector('.swagger-ui .opblock-summary').click(); return true",
            json!([]),
        )
        .await;
    assert_eq!(browser.csp_violations().await, json!([]));
    browser.screenshot("api-docs").await;
    server.shutdown().await.unwrap();
}

/// Every page at 1280 x 900: no sideways scrolling, no `null`, `undefined`
/// or `NaN` in its text, units beside the numbers that have one, the
/// paper's symbols; the measured points uploaded drawn on the phase
/// diagram; a single case's sweep offers no phase diagram to download; the
/// fits' pages.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_page_fits_1280_pixels_shows_no_code_words_and_gives_units() {
    let Some(Page {
        browser,
        server,
        url,
        c,
        _dir,
    }) = page(2).await
    else {
        return;
    };
    browser.size(1280, 900).await;
    let base = with(tiny_base(), json!({"min_l_k_bar": 105.0}));
    let id = submit_sweep(&c, &url, &json!({"base": base, "grid": {"mu": [0.1, 0.15]}})).await;
    let single = submit_sweep(&c, &url, &json!({"base": base})).await;
    // Two axes: a map (its h = 5 mm points are the first sweep's, cached).
    let two = submit_sweep(
        &c,
        &url,
        &json!({"base": without(base.clone(), "h"), "grid": {"h": [5e-3, 5.5e-3], "mu": [0.1, 0.15]}}),
    )
    .await;
    wait_sweep(&c, &url, id, Duration::from_secs(120), finished).await;
    wait_sweep(&c, &url, single, Duration::from_secs(120), finished).await;
    wait_sweep(&c, &url, two, Duration::from_secs(120), finished).await;
    let (status, _) = post(
        &c,
        &format!("{url}/api/sweeps/{two}/refine"),
        &json!({"tolerance": {"mu": 0.01}}),
    )
    .await;
    assert_eq!(status, reqwest::StatusCode::ACCEPTED);
    let r = c
        .put(format!("{url}/api/sweeps/{id}/measurements"))
        .json(&json!({"csv": "mu,l_k_bar,error\n0.12,116.5,1.5\n0.14,117,2\n"}))
        .send()
        .await
        .unwrap();
    assert!(r.status().is_success());
    let (_, fit) = post(
        &c,
        &format!("{url}/api/fits"),
        &json!({"range": [0.05, 0.3], "base": base, "points": [{"params": {}, "l_k_bar": 116.0, "error": 1.0}]}),
    )
    .await;
    let (_, cases) = get(&c, &format!("{url}/api/sweeps/{id}/cases")).await;
    let case_id = cases[0]["case_id"].as_i64().unwrap();

    let pages = [
        (
            "home",
            format!("{url}/#/"),
            "return document.getElementById('p-youngs_modulus') !== null && document.querySelectorAll('#sweeps a').length >= 2",
        ),
        (
            "sweep",
            format!("{url}/#/sweeps/{id}"),
            "const p = document.getElementById('phase'); return p && p.dataset.measured !== undefined && document.getElementById('plot-f').dataset.series !== undefined",
        ),
        (
            "single",
            format!("{url}/#/sweeps/{single}"),
            "return document.getElementById('downloads') !== null && document.getElementById('summary').textContent.includes('done')",
        ),
        (
            "case",
            format!("{url}/#/cases/{case_id}"),
            "return document.getElementById('held') !== null && document.querySelector('#plot-f canvas') !== null",
        ),
        (
            "map",
            format!("{url}/#/sweeps/{two}/map"),
            "const m = document.getElementById('map'); return m && m.complete && m.naturalWidth > 0 && \
             document.getElementById('refinement').textContent.includes('done')",
        ),
        (
            "fits",
            format!("{url}/#/fits"),
            "return document.querySelectorAll('#fits a').length >= 1",
        ),
        (
            "fit",
            format!("{url}/#/fits/{}", fit["id"]),
            "return document.getElementById('evals-head') !== null && document.getElementById('fit').textContent.includes('searched')",
        ),
    ];
    for (name, page, ready) in &pages {
        let (width, window, words) = browser.page(page, ready).await;
        browser.screenshot(&format!("1280-{name}")).await;
        assert!(
            width <= window,
            "{name}: the page is {width} px wide in a {window} px window"
        );
        assert!(words.is_empty(), "{name}: the page says {words:?}");
    }

    // The home page: labels by symbol and name, units beside the fields.
    browser.page(&pages[0].1, pages[0].2).await;
    let form = browser
        .js(
            "const f = (n) => document.querySelector(`.field[data-param=\"${n}\"]`); \
             return [f('youngs_modulus').querySelector('label').textContent, f('h').querySelector('.unit').textContent, \
               f('youngs_modulus').querySelector('.unit').textContent, f('mu').querySelector('label').textContent, \
               document.getElementById('loading-json').textContent, \
               [...document.querySelectorAll('#stages li strong')].map((s) => s.textContent)]",
            json!([]),
        )
        .await;
    assert_eq!(form[0], "E · youngs modulus", "{form}");
    assert_eq!(
        (form[1].as_str(), form[2].as_str()),
        (Some("m"), Some("Pa")),
        "{form}"
    );
    assert_eq!(form[3], "μ · mu", "{form}");
    assert_eq!(form[5], json!(["pull"]), "no double numbering: {form}");
    // A bad value: its error beside the field and beside the button.
    browser.js(FILL, json!([{"p-h": "-1"}])).await;
    browser.submit().await;
    let error = browser
        .until(
            "the errors beside the button",
            "const e = document.querySelector('.field-error[data-for=\"form\"]'); return e && e.textContent",
            Duration::from_secs(20),
        )
        .await;
    assert!(error.as_str().unwrap().contains("base.h"), "{error}");

    // The sweep page: symbols, units, the measured points, the table's link.
    browser.page(&pages[1].1, pages[1].2).await;
    let sweep = browser
        .js(
            "return [document.getElementById('phase').dataset.measured, document.getElementById('cases').textContent, \
               [...document.querySelectorAll('#downloads a')].map((a) => a.getAttribute('href')), \
               document.querySelector('#phase .u-title').textContent]",
            json!([]),
        )
        .await;
    assert_eq!(sweep[0], "2", "the measured points drawn: {sweep}");
    assert!(sweep[1].as_str().unwrap().contains("μ = 0.1"), "{sweep}");
    let links = sweep[2].as_array().unwrap();
    assert!(
        links.contains(&json!(format!("/api/sweeps/{id}/phase-diagram.csv"))),
        "{sweep}"
    );
    assert!(
        links.contains(&json!(format!("/api/sweeps/{id}/figures/phase.svg"))),
        "{sweep}"
    );
    assert_eq!(sweep[3], "critical l̄_k against μ", "{sweep}");
    // A single case: no phase diagram to download.
    browser.page(&pages[2].1, pages[2].2).await;
    let links = browser
        .js(
            "return [...document.querySelectorAll('#downloads a')].map((a) => a.getAttribute('href'))",
            json!([]),
        )
        .await;
    assert!(
        !links
            .as_array()
            .unwrap()
            .iter()
            .any(|l| l.as_str().unwrap().ends_with("phase.svg")),
        "{links}"
    );
    for link in links.as_array().unwrap() {
        let (status, _) = get_text(&c, &format!("{url}{}", link.as_str().unwrap())).await;
        assert_eq!(status, reqwest::StatusCode::OK, "{link}");
    }

    // The map page: the sweep's two axes by symbol, the tolerance with its unit, the map drawn.
    browser.page(&pages[4].1, pages[4].2).await;
    let map = browser
        .js(
            "return [document.getElementById('map-summary').textContent, document.getElementById('refinement').textContent, \
               [...document.querySelectorAll('#refine-fields .unit')].map((u) => u.textContent), document.getElementById('map').naturalWidth, \
               document.getElementById('brackets').textContent]",
            json!([]),
        )
        .await;
    assert!(
        map[0].as_str().unwrap().contains("h (across) and μ (up)"),
        "{map}"
    );
    assert!(map[1].as_str().unwrap().contains("μ to 0.01"), "{map}");
    assert_eq!(map[2], json!(["m", ""]), "h in m, μ without a unit: {map}");
    assert!(map[3].as_u64().unwrap() > 500, "{map}");
    let (_, refined) = get(&c, &format!("{url}/api/sweeps/{two}/refinement")).await;
    let shown = map[4].as_str().unwrap();
    for b in refined["brackets"].as_array().unwrap() {
        assert!(
            shown.contains(&format!("case {}", b["low"]["case_id"])),
            "{shown} vs {refined:#}"
        );
    }
    // The sweep page of a two-axis sweep links its map's page.
    browser
        .page(
            &format!("{url}/#/sweeps/{two}"),
            "return document.getElementById('map-section') && !document.getElementById('map-section').hidden",
        )
        .await;
    let link = browser
        .js(
            "return document.getElementById('map-link').getAttribute('href')",
            json!([]),
        )
        .await;
    assert_eq!(link, json!(format!("#/sweeps/{two}/map")));

    // The case page: h in mm, E in Pa, the node count resolved.
    browser.page(&pages[3].1, pages[3].2).await;
    let held = browser
        .js("return document.getElementById('held').textContent", json!([]))
        .await;
    let held = held.as_str().unwrap();
    assert!(
        held.contains("h = 5 mm") && held.contains("E = 1800000 Pa") && held.contains("K = 121 nodes"),
        "{held}"
    );
    server.shutdown().await.unwrap();
}
