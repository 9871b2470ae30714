//! The typed core of the service: every operation of the API (and of
//! `knotsweep sweep`) as a method over the store. The HTTP handlers in
//! [`crate::api`] only extract, call one of these and serialise.
use crate::error::CoreError;
use crate::figures::{self, CaseCurve, Quantity};
use crate::spec::{self, FieldError, Limits, SweepSpec};
use crate::strict_json;
use crate::views::*;
use knotsweep_worker::pool::PoolHandle;
use knotsweep_worker::store::{
    CaseRecord, CaseState, CreateOutcome, Idempotency, NewCase, NewSweep, Store, SweepAction, SweepCase,
    SweepRecord, SweepState,
};
use serde_json::Value;
use solver::measurements::Sample;
use solver::protocol::Status;
use std::collections::BTreeMap;
use std::collections::HashMap;
use std::fmt::Write;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Status words of cases, in the order metrics list them: the queue states
/// before a result, the solver's outcomes, then the queue's failures.
pub fn status_words() -> Vec<String> {
    let queue = |s: CaseState| s.as_str().to_string();
    let outcomes = Status::ALL
        .into_iter()
        .filter(|s| *s != Status::Cancelled)
        .map(|s| s.to_string());
    [queue(CaseState::Queued), queue(CaseState::Running)]
        .into_iter()
        .chain(outcomes)
        .chain([queue(CaseState::Failed), queue(CaseState::Cancelled)])
        .collect()
}

/// The service's operations.
#[derive(Clone)]
pub struct Core {
    store: Arc<dyn Store>,
    limits: Limits,
    pool: Option<PoolHandle>,
    started: Instant,
    /// The simplified model's snap by (n, h bits): computed once (about 0.4 s
    /// each), concurrent first requests waiting on the same computation.
    simplified: Arc<Mutex<SimplifiedSnaps>>,
}

/// The simplified model's snaps, computed or under way, by (n, bits of h).
type SimplifiedSnaps = HashMap<(u32, u64), Arc<tokio::sync::OnceCell<Option<f64>>>>;

impl Core {
    pub fn new(store: Arc<dyn Store>, limits: Limits, pool: Option<PoolHandle>) -> Self {
        Self {
            store,
            limits,
            pool,
            started: Instant::now(),
            simplified: Arc::default(),
        }
    }

    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// Parses a request body into a spec: 400 for malformed JSON, 422 with the
    /// field for unknown fields and wrong types. Returns the spec and the
    /// parsed body (for the idempotency hash).
    pub fn parse_spec(body: &[u8]) -> Result<(SweepSpec, Value), CoreError> {
        if body.iter().all(u8::is_ascii_whitespace) {
            return Err(CoreError::BadRequest(
                "body".to_string(),
                "empty body: send a JSON object ({} is one case at the paper's defaults)".to_string(),
            ));
        }
        let value = strict_json::parse(body)
            .map_err(|e| CoreError::BadRequest("body".to_string(), format!("malformed JSON: {e}")))?;
        if !value.is_object() {
            return Err(CoreError::Invalid(vec![FieldError::new(
                "body",
                "must be a JSON object",
            )]));
        }
        let spec: SweepSpec = serde_path_to_error::deserialize(value.clone()).map_err(|e| {
            let path = e.path().to_string();
            let text = e.inner().to_string();
            let field = match text
                .strip_prefix("unknown field `")
                .and_then(|r| r.split_once('`'))
            {
                Some((name, _)) if path == "." || path == name || path.ends_with(&format!(".{name}")) => {
                    if path == "." {
                        name.to_string()
                    } else {
                        path
                    }
                }
                Some((name, _)) => format!("{path}.{name}"),
                None => path,
            };
            CoreError::Invalid(vec![FieldError::new(field, text)])
        })?;
        Ok((spec, value))
    }

    /// Validates, expands and enqueues a sweep. With an idempotency key seen
    /// before (same body), the first sweep is returned with `replayed: true`.
    pub async fn submit(
        &self,
        spec: SweepSpec,
        raw: &Value,
        idempotency_key: Option<&str>,
    ) -> Result<SubmitResponse, CoreError> {
        if let Some(key) = idempotency_key {
            if key.is_empty() || key.chars().count() > self.limits.max_idempotency_key_len {
                return Err(CoreError::BadRequest(
                    "Idempotency-Key".to_string(),
                    format!(
                        "must have 1 to {} characters",
                        self.limits.max_idempotency_key_len
                    ),
                ));
            }
            if !key.chars().all(|c| c.is_ascii_graphic()) {
                return Err(CoreError::BadRequest(
                    "Idempotency-Key".to_string(),
                    "must be printable ASCII without spaces".to_string(),
                ));
            }
        }
        let expanded = spec::expand(&spec, &self.limits).map_err(CoreError::Invalid)?;
        let request_hash = blake3::hash(knotsweep_worker::canonical_value(raw).as_bytes())
            .to_hex()
            .to_string();
        let new = NewSweep {
            name: expanded.name.clone(),
            preset: expanded.preset.clone(),
            spec: serde_json::to_value(&spec).expect("spec serialises"),
            varied: expanded.varied.clone(),
            cases: expanded
                .cases
                .iter()
                .map(|c| NewCase::new(c.params.clone()))
                .collect(),
            idempotency: idempotency_key.map(|key| Idempotency {
                key: key.to_string(),
                request_hash,
            }),
        };
        let (record, replayed) = match self.store.create_sweep(new).await? {
            CreateOutcome::Created { sweep, cached } => {
                tracing::info!(
                    sweep_id = sweep.id,
                    preset = ?sweep.preset,
                    cases = expanded.cases.len(),
                    cached,
                    "sweep accepted"
                );
                (sweep, false)
            }
            CreateOutcome::Replayed { sweep } => {
                tracing::info!(
                    sweep_id = sweep.id,
                    "idempotent resubmission: returning the first sweep"
                );
                (sweep, true)
            }
        };
        let cases = self.store.sweep_cases(record.id).await?;
        Ok(SubmitResponse {
            replayed,
            sweep: detail(&record, &cases),
        })
    }

    /// At most `limit` sweeps from the `offset`-th, oldest first, with their
    /// counts per status, and the number of sweeps: one page read from the
    /// store, so a request's memory is bounded by the page, not the history.
    pub async fn list_sweeps(
        &self,
        limit: usize,
        offset: usize,
    ) -> Result<(Vec<SweepSummary>, usize), CoreError> {
        let total = self.store.count_sweeps().await?;
        let sweeps = self.store.list_sweeps(limit as i64, offset as i64).await?;
        let (Some(first), Some(last)) = (sweeps.first(), sweeps.last()) else {
            return Ok((Vec::new(), total as usize));
        };
        let mut counts: BTreeMap<i64, BTreeMap<String, i64>> = BTreeMap::new();
        for (id, status, n) in self.store.sweep_status_counts(first.id..=last.id).await? {
            counts.entry(id).or_default().insert(status, n);
        }
        let summaries = sweeps
            .iter()
            .map(|s| summary(s, counts.remove(&s.id).unwrap_or_default()))
            .collect();
        Ok((summaries, total as usize))
    }

    async fn record(&self, id: i64) -> Result<SweepRecord, CoreError> {
        self.store
            .get_sweep(id)
            .await?
            .ok_or_else(|| CoreError::NotFound(format!("sweep {id}")))
    }

    pub async fn sweep(&self, id: i64) -> Result<SweepDetail, CoreError> {
        let record = self.record(id).await?;
        let cases = self.store.sweep_cases(id).await?;
        Ok(detail(&record, &cases))
    }

    /// Pause (queued cases are not handed out; running ones finish), resume,
    /// or cancel (queued cases are cancelled, running ones stop at their next
    /// heartbeat; cases another live sweep wants go on).
    pub async fn control(&self, id: i64, action: SweepAction) -> Result<SweepDetail, CoreError> {
        let record = match self.store.control_sweep(id, action).await {
            Err(knotsweep_worker::StoreError::NotFound) => {
                return Err(CoreError::NotFound(format!("sweep {id}")));
            }
            other => other?,
        };
        tracing::info!(
            sweep_id = id,
            ?action,
            state = record.state.as_str(),
            "sweep control"
        );
        let cases = self.store.sweep_cases(id).await?;
        Ok(detail(&record, &cases))
    }

    pub async fn phase_diagram(&self, id: i64) -> Result<PhaseDiagram, CoreError> {
        let record = self.record(id).await?;
        let cases = self.store.sweep_cases(id).await?;
        let d = detail(&record, &cases);
        let spec: SweepSpec = serde_json::from_value(record.spec.clone()).unwrap_or_default();
        let base = spec::base_params(&spec)
            .map(|p| serde_json::to_value(p).expect("params serialise"))
            .unwrap_or(Value::Null);
        Ok(PhaseDiagram {
            sweep_id: record.id,
            name: record.name.clone(),
            preset: record.preset.clone(),
            status: d.summary.status,
            complete: cases.iter().all(|c| c.case.state.is_terminal()),
            varied: record.varied.clone(),
            base,
            solver_version: knotsweep_worker::SOLVER_VERSION.to_string(),
            physics_revision: solver::case::PHYSICS_REVISION,
            points: futures_util::future::join_all(d.cases.into_iter().zip(&cases).map(
                |(c, full)| async move {
                    PhasePoint {
                        case_id: c.case_id,
                        params: c.params,
                        status: c.status,
                        inversion: c.inversion,
                        reason: c.reason,
                        simplified_l_k_bar: self
                            .simplified_snap(full.case.params.n, full.case.params.h)
                            .await,
                    }
                },
            ))
            .await,
        })
    }

    /// The phase diagram as SVG: critical l_k bar against the first varied
    /// parameter (h in mm), the simplified model's line against n or h.
    pub async fn phase_figure(&self, id: i64) -> Result<String, CoreError> {
        let pd = self.phase_diagram(id).await?;
        let Some(axis) = pd.varied.first() else {
            return Err(CoreError::NotFound(format!(
                "a varied parameter in sweep {id} (a single case has no phase diagram)"
            )));
        };
        let scale = if axis == "h" { 1e3 } else { 1.0 };
        let x = |p: &PhasePoint| p.params.get(axis).and_then(Value::as_f64).map(|v| v * scale);
        let points: Vec<(f64, f64)> = pd
            .points
            .iter()
            .filter_map(|p| Some((x(p)?, p.inversion.as_ref()?.l_k_bar)))
            .collect();
        let simplified: Vec<(f64, f64)> = if axis == "n" || axis == "h" {
            pd.points
                .iter()
                .filter_map(|p| Some((x(p)?, p.simplified_l_k_bar?)))
                .collect()
        } else {
            Vec::new()
        };
        let x_label = if axis == "h" {
            "h (mm)".to_string()
        } else {
            axis.clone()
        };
        figures::phase_chart(
            &format!("sweep {id}: critical l_k bar against {x_label}"),
            &x_label,
            &points,
            &simplified,
        )
        .map_err(|e| CoreError::Figure(e.to_string()))
    }

    /// The simplified model's snap-through l_k bar (paper Sec. 5, Figs 14 and
    /// 15: epsilon = 0.7, phi = pi/3, no contact or friction) for `n` passes and
    /// radius `h`; `None` where it has no snap (n = 1) or fails.
    async fn simplified_snap(&self, n: u32, h: f64) -> Option<f64> {
        let cell = self
            .simplified
            .lock()
            .expect("simplified cache")
            .entry((n, h.to_bits()))
            .or_default()
            .clone();
        *cell
            .get_or_init(|| async move {
                tokio::task::spawn_blocking(move || solver::simplified::reproduce::snap_l_k_bar(n, h))
                    .await
                    .ok()
                    .and_then(|r| {
                        r.map_err(|e| tracing::warn!(n, h, error = %e, "simplified model failed"))
                            .ok()
                    })
                    .flatten()
            })
            .await
    }

    async fn case_record(&self, id: i64) -> Result<CaseRecord, CoreError> {
        self.store
            .get_case(id)
            .await?
            .ok_or_else(|| CoreError::NotFound(format!("case {id}")))
    }

    pub async fn case(&self, id: i64) -> Result<CaseDetail, CoreError> {
        let c = self.case_record(id).await?;
        let sweeps = self.store.case_sweeps(id).await?;
        let series = match self.store.case_series_json(id).await? {
            Some(text) => Some(
                serde_json::from_str(&text)
                    .map_err(|e| CoreError::Store(knotsweep_worker::StoreError::Corrupt(e.to_string())))?,
            ),
            None => None,
        };
        let logs = self
            .store
            .case_logs(id)
            .await?
            .into_iter()
            .map(|l| LogLineView {
                at: l.at,
                level: l.level,
                message: l.message,
            })
            .collect();
        let links = BTreeMap::from([
            ("self".to_string(), format!("/api/cases/{id}")),
            ("series_csv".to_string(), format!("/api/cases/{id}/series.csv")),
            ("frames".to_string(), format!("/api/cases/{id}/frames")),
        ]);
        Ok(CaseDetail {
            id: c.id,
            key: c.key.clone(),
            solver_version: c.solver_version.clone(),
            params: serde_json::to_value(&c.params).expect("params serialise"),
            status: c.status().to_string(),
            state: c.state.as_str().to_string(),
            attempts: c.attempts,
            max_attempts: c.max_attempts,
            progress: c.progress,
            progress_detail: progress_of(&c),
            lease_owner: c.lease_owner.clone(),
            lease_expires_at: c.lease_expires_at,
            last_error: c.last_error.clone(),
            created_at: c.created_at,
            started_at: c.started_at,
            finished_at: c.finished_at,
            sweeps,
            result: c.result.as_ref().map(|r| ResultView {
                outcome: r.outcome.clone(),
                reason: r.reason.clone(),
                inversion: r.inversion.as_ref().map(InversionPoint::from),
                summary: r.summary.clone(),
                wall_time: r.wall_time,
                worker: r.worker.clone(),
                created_at: r.created_at,
            }),
            series,
            logs,
            links,
        })
    }

    /// A case's stored series; 404 before the result.
    async fn series(&self, c: &CaseRecord) -> Result<Vec<Sample>, CoreError> {
        let text =
            self.store.case_series_json(c.id).await?.ok_or_else(|| {
                CoreError::NotFound(format!("result of case {} (status {})", c.id, c.status()))
            })?;
        serde_json::from_str(&text)
            .map_err(|e| CoreError::Store(knotsweep_worker::StoreError::Corrupt(e.to_string())))
    }

    /// The series as CSV (one row per sample); 404 before the result.
    pub async fn series_csv(&self, id: i64) -> Result<String, CoreError> {
        let c = self.case_record(id).await?;
        Ok(solver::measurements::series_csv(&self.series(&c).await?))
    }

    /// F bar or H bar against l_k bar of a case as SVG: the figure of
    /// `knotsweep run --plot`; 404 before the result.
    pub async fn case_figure(&self, id: i64, quantity: Quantity) -> Result<String, CoreError> {
        let c = self.case_record(id).await?;
        let series = self.series(&c).await?;
        let p = &c.params;
        let label = format!("n = {}, h = {} mm, mu = {}", p.n, p.h * 1e3, p.mu);
        let curve = CaseCurve {
            label: label.clone(),
            series: &series,
            inversion: inversion_of(&c),
        };
        figures::tightening_chart(&label, quantity, &[curve]).map_err(|e| CoreError::Figure(e.to_string()))
    }

    /// The curves of every finished case of a sweep overlaid (grid order),
    /// their inversions marked.
    pub async fn sweep_figure(&self, id: i64, quantity: Quantity) -> Result<String, CoreError> {
        let record = self.record(id).await?;
        let mut loaded = Vec::new();
        // The sweep's case rows already hold their result summaries: only the series are read.
        for s in self.store.sweep_cases(id).await? {
            if s.case.result.is_some() {
                let label = case_view(&s, &record.varied)
                    .params
                    .iter()
                    .map(|(k, v)| format!("{k} = {v}"))
                    .collect::<Vec<_>>()
                    .join(", ");
                loaded.push((label, self.series(&s.case).await?, inversion_of(&s.case)));
            }
        }
        let curves: Vec<CaseCurve> = loaded
            .iter()
            .map(|(label, series, inversion)| CaseCurve {
                label: if label.is_empty() {
                    format!("sweep {id}")
                } else {
                    label.clone()
                },
                series,
                inversion: *inversion,
            })
            .collect();
        figures::tightening_chart(&format!("sweep {id}"), quantity, &curves)
            .map_err(|e| CoreError::Figure(e.to_string()))
    }

    /// The frames (centreline snapshots) as stored JSON; 404 before the result.
    pub async fn frames(&self, id: i64) -> Result<String, CoreError> {
        let c = self.case_record(id).await?;
        self.store
            .case_frames_json(id)
            .await?
            .ok_or_else(|| CoreError::NotFound(format!("result of case {id} (status {})", c.status())))
    }

    pub async fn health(&self) -> Health {
        let database = self.store.queue_depth().await.is_ok();
        let stalled = self.pool.as_ref().map(|p| p.stalled_slots()).unwrap_or_default();
        Health {
            status: if database && stalled.is_empty() {
                "ok"
            } else {
                "degraded"
            }
            .to_string(),
            database,
            workers: self.pool.as_ref().map_or(0, |p| p.workers()),
            stalled_workers: stalled,
            solver_version: knotsweep_worker::SOLVER_VERSION.to_string(),
            uptime_seconds: self.started.elapsed().as_secs_f64(),
        }
    }

    /// Prometheus text: cases by status and queue depth (from the store, so
    /// across every process), this process's workers' counters.
    pub async fn metrics(&self) -> Result<String, CoreError> {
        let counts: BTreeMap<String, i64> = self.store.status_counts().await?.into_iter().collect();
        let depth = self.store.queue_depth().await?;
        let mut by_status: BTreeMap<SweepStatus, usize> = BTreeMap::new();
        for offset in (0..).step_by(METRICS_PAGE) {
            let (page, _) = self.list_sweeps(METRICS_PAGE, offset).await?;
            for s in &page {
                *by_status.entry(s.status).or_default() += 1;
            }
            if page.len() < METRICS_PAGE {
                break;
            }
        }
        let mut out = String::new();
        let _ = writeln!(
            out,
            "# HELP knotsweep_cases Cases by status.\n# TYPE knotsweep_cases gauge"
        );
        for word in status_words() {
            let _ = writeln!(
                out,
                "knotsweep_cases{{status=\"{word}\"}} {}",
                counts.get(&word).copied().unwrap_or(0)
            );
        }
        let _ = writeln!(
            out,
            "# HELP knotsweep_queue_depth Queued cases of active sweeps.\n# TYPE knotsweep_queue_depth gauge\nknotsweep_queue_depth {depth}"
        );
        let _ = writeln!(
            out,
            "# HELP knotsweep_sweeps Sweeps by status (as GET /api/sweeps reports it: a sweep whose cases all finished is done).\n# TYPE knotsweep_sweeps gauge"
        );
        for status in [
            SweepStatus::Queued,
            SweepStatus::Running,
            SweepStatus::Paused,
            SweepStatus::Done,
            SweepStatus::Cancelled,
        ] {
            let n = by_status.get(&status).copied().unwrap_or(0);
            let word = serde_json::to_value(status).expect("status serialises");
            let _ = writeln!(
                out,
                "knotsweep_sweeps{{status=\"{}\"}} {n}",
                word.as_str().unwrap_or_default()
            );
        }
        let _ = writeln!(
            out,
            "# HELP knotsweep_workers Embedded worker slots.\n# TYPE knotsweep_workers gauge\nknotsweep_workers {}",
            self.pool.as_ref().map_or(0, |p| p.workers())
        );
        if let Some(pool) = &self.pool {
            pool.metrics.render(&mut out);
        }
        Ok(out)
    }
}

/// Sweeps read per page when the metrics count them.
const METRICS_PAGE: usize = 1000;

/// The solver's progress of a running case; none once it has stopped running
/// (a finished case's last heartbeat is not its progress).
fn progress_of(c: &CaseRecord) -> Option<CaseProgress> {
    if c.state != CaseState::Running {
        return None;
    }
    c.progress_detail.map(|p| CaseProgress {
        fraction: p.fraction,
        l_k_bar: p.l_k_bar,
        h_bar: p.h_bar,
        steps: p.steps,
    })
}

fn links(id: i64) -> BTreeMap<String, String> {
    BTreeMap::from([
        ("self".to_string(), format!("/api/sweeps/{id}")),
        (
            "phase_diagram".to_string(),
            format!("/api/sweeps/{id}/phase-diagram"),
        ),
        ("events".to_string(), format!("/api/sweeps/{id}/events")),
        ("cases".to_string(), format!("/api/sweeps/{id}/cases")),
    ])
}

fn status_of(state: SweepState, counts: &BTreeMap<String, i64>) -> SweepStatus {
    let open = |w: &str| counts.get(w).copied().unwrap_or(0);
    let (queued, running) = (
        open(CaseState::Queued.as_str()),
        open(CaseState::Running.as_str()),
    );
    match state {
        SweepState::Cancelled => SweepStatus::Cancelled,
        _ if queued + running == 0 => SweepStatus::Done,
        SweepState::Paused => SweepStatus::Paused,
        SweepState::Active if running == 0 && counts.values().sum::<i64>() == queued => SweepStatus::Queued,
        SweepState::Active => SweepStatus::Running,
    }
}

fn summary(s: &SweepRecord, counts: BTreeMap<String, i64>) -> SweepSummary {
    SweepSummary {
        id: s.id,
        name: s.name.clone(),
        preset: s.preset.clone(),
        state: s.state.as_str().to_string(),
        status: status_of(s.state, &counts),
        total: counts.values().sum(),
        counts,
        created_at: s.created_at,
        links: links(s.id),
    }
}

/// Why a case has no inversion point (None when it has one).
fn reason_of(c: &CaseRecord) -> Option<String> {
    match (&c.result, c.state) {
        (Some(r), _) if r.inversion.is_some() => None,
        (Some(r), _) if r.outcome == "completed" => Some(match c.params.max_force_bar {
            Some(f) => format!(
                "no inversion detected before the case stopped (at l_k bar {} or F bar {f})",
                c.params.min_l_k_bar
            ),
            None => format!(
                "no inversion detected before the case stopped (at l_k bar {})",
                c.params.min_l_k_bar
            ),
        }),
        (Some(r), _) => Some(format!("{}: {}", r.outcome, r.reason)),
        (None, CaseState::Failed) => Some(c.last_error.clone().unwrap_or_else(|| "failed".to_string())),
        (None, CaseState::Cancelled) => Some(CaseState::Cancelled.as_str().to_string()),
        (None, CaseState::Queued) => Some(match &c.last_error {
            Some(e) => format!("not computed yet (queued; last attempt: {e})"),
            None => "not computed yet (queued)".to_string(),
        }),
        (None, CaseState::Running) => Some("not computed yet (running)".to_string()),
        (None, CaseState::Done) => Some("result missing".to_string()),
    }
}

fn case_view(s: &SweepCase, varied: &[String]) -> SweepCaseView {
    let c = &s.case;
    let params = serde_json::to_value(&c.params).expect("params serialise");
    SweepCaseView {
        case_id: c.id,
        position: s.position,
        params: varied
            .iter()
            .map(|name| (name.clone(), params.get(name).cloned().unwrap_or(Value::Null)))
            .collect(),
        status: c.status().to_string(),
        cached: s.cached,
        attempts: c.attempts,
        progress: if c.state == CaseState::Done {
            1.0
        } else {
            c.progress
        },
        progress_detail: progress_of(c),
        inversion: c
            .result
            .as_ref()
            .and_then(|r| r.inversion.as_ref())
            .map(InversionPoint::from),
        reason: reason_of(c),
        wall_time: c.result.as_ref().map(|r| r.wall_time),
    }
}

/// The sweep's view: counts, progress, ETA and cases.
pub fn detail(record: &SweepRecord, cases: &[SweepCase]) -> SweepDetail {
    let mut counts: BTreeMap<String, i64> = BTreeMap::new();
    for c in cases {
        *counts.entry(c.case.status().to_string()).or_default() += 1;
    }
    let views: Vec<SweepCaseView> = cases.iter().map(|c| case_view(c, &record.varied)).collect();
    let total = cases.len().max(1) as f64;
    let finished = cases.iter().filter(|c| c.case.state.is_terminal()).count() as f64;
    let running: Vec<&SweepCase> = cases
        .iter()
        .filter(|c| c.case.state == CaseState::Running)
        .collect();
    let running_done: f64 = running.iter().map(|c| c.case.progress).sum();
    let queued = cases.iter().filter(|c| c.case.state == CaseState::Queued).count() as f64;
    let summary = summary(record, counts);
    // ETA: remaining work (queued cases + running remainders) times the mean
    // case duration (from this sweep's results, else from the running cases'
    // speed), over the number of cases running in parallel.
    let durations: Vec<f64> = cases
        .iter()
        .filter(|c| !c.cached)
        .filter_map(|c| c.case.result.as_ref().map(|r| r.wall_time))
        .collect();
    let now = knotsweep_worker::store::now_ms();
    let mean = if durations.is_empty() {
        let speeds: Vec<f64> = running
            .iter()
            .filter(|c| c.case.progress > 0.02)
            .filter_map(|c| {
                c.case
                    .started_at
                    .map(|t| (now - t) as f64 / 1000.0 / c.case.progress)
            })
            .collect();
        (!speeds.is_empty()).then(|| speeds.iter().sum::<f64>() / speeds.len() as f64)
    } else {
        Some(durations.iter().sum::<f64>() / durations.len() as f64)
    };
    let remaining = queued + running.len() as f64 - running_done;
    let eta_seconds = match (summary.status, mean) {
        (SweepStatus::Running | SweepStatus::Queued, Some(mean)) if !running.is_empty() => {
            Some(remaining * mean / running.len() as f64)
        }
        _ => None,
    };
    SweepDetail {
        varied: record.varied.clone(),
        spec: record.spec.clone(),
        progress: ((finished + running_done) / total).clamp(0.0, 1.0),
        eta_seconds,
        cached: cases.iter().filter(|c| c.cached).count() as i64,
        cases: views,
        summary,
    }
}

/// The action named in a control route.
pub fn action(name: &str) -> Option<SweepAction> {
    match name {
        "pause" => Some(SweepAction::Pause),
        "resume" => Some(SweepAction::Resume),
        "cancel" => Some(SweepAction::Cancel),
        _ => None,
    }
}

/// l_k bar of a case's inversion, if it has a result with one.
fn inversion_of(c: &CaseRecord) -> Option<f64> {
    c.result.as_ref().and_then(|r| r.inversion).map(|i| i.l_k_bar)
}
