//! The typed core of the service: every operation of the API (and of
//! `knotsweep sweep`) as a method over the store, returning the views of
//! [`crate::views`]. The HTTP handlers in [`crate::api`] only extract, call
//! one of these and serialise.
use crate::computing::Computing;
use crate::error::CoreError;
use crate::events::SweepStamp;
use crate::spec::{self, Expanded, FieldError, Limits, SweepSpec};
use crate::strict_json;
use crate::views::{self, *};
use knotsweep_worker::pool::PoolHandle;
use knotsweep_worker::store::{
    CaseRecord, CreateOutcome, Idempotency, NewCase, NewSweep, Store, SweepAction, SweepRecord,
};
use report::charts::{self, CaseCurve, Quantity};
use serde_json::Value;
use solver::measurements::Sample;
use std::collections::BTreeMap;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Instant;

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
    /// Slots for the requests' CPU-bound work, one per core.
    computing: Computing,
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
            computing: Computing::per_core(),
        }
    }

    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    pub(crate) fn store(&self) -> &Arc<dyn Store> {
        &self.store
    }

    /// Parses a request body into a spec: 400 for malformed JSON, 422 with the
    /// field for unknown fields and wrong types. Returns the spec and the
    /// parsed body (for the idempotency hash).
    pub fn parse_spec(body: &[u8]) -> Result<(SweepSpec, Value), CoreError> {
        if body.iter().all(u8::is_ascii_whitespace) {
            return Err(CoreError::bad_request(
                "body",
                "empty body: send a JSON object ({} is one case at the paper's defaults)",
            ));
        }
        let value = strict_json::parse(body)
            .map_err(|e| CoreError::bad_request("body", format!("malformed JSON: {e}")))?;
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
            self.check_idempotency_key(key)?;
        }
        // Every point's knot is built here (tens of milliseconds each): off the async runtime.
        let (given, limits) = (spec.clone(), self.limits);
        let expanded = self
            .computing
            .run(move || spec::expand(&given, &limits))
            .await?
            .map_err(CoreError::Invalid)?;
        let cases = expanded.cases.len();
        let new = new_sweep(&spec, raw, expanded, idempotency_key);
        let (record, replayed) = match self.store.create_sweep(new).await? {
            CreateOutcome::Created { sweep, cached } => {
                tracing::info!(
                    sweep_id = sweep.id,
                    preset = ?sweep.preset,
                    cases,
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
            sweep: SweepDetail::new(&record, &cases)?,
        })
    }

    /// An `Idempotency-Key` has 1 to `max_idempotency_key_len` printable
    /// ASCII characters, no spaces (400 otherwise).
    fn check_idempotency_key(&self, key: &str) -> Result<(), CoreError> {
        let bad = |reason: String| Err(CoreError::bad_request("Idempotency-Key", reason));
        let longest = self.limits.max_idempotency_key_len;
        if key.is_empty() || key.chars().count() > longest {
            return bad(format!("must have 1 to {longest} characters"));
        }
        if !key.chars().all(|c| c.is_ascii_graphic()) {
            return bad("must be printable ASCII without spaces".to_string());
        }
        Ok(())
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
        let mut counts: BTreeMap<i64, BTreeMap<knotsweep_worker::store::CaseStatus, i64>> = BTreeMap::new();
        for (id, status, n) in self.store.sweep_status_counts(first.id..=last.id).await? {
            counts.entry(id).or_default().insert(status, n);
        }
        let summaries = sweeps
            .iter()
            // A sweep absent from the counts has no case row: no counts.
            .map(|s| SweepSummary::from((s, counts.remove(&s.id).unwrap_or_default())))
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
        Ok(SweepDetail::new(&record, &cases)?)
    }

    /// What sweep `id`'s event feed polls ([`crate::events`]): its state and
    /// counts per status, one grouped query rather than its cases. 404 when
    /// there is no such sweep.
    pub(crate) async fn sweep_stamp(&self, id: i64) -> Result<SweepStamp, CoreError> {
        let record = self.record(id).await?;
        let counts = self.store.sweep_status_counts(id..=id).await?;
        Ok(SweepStamp {
            state: record.state,
            updated_at: record.updated_at,
            counts: counts.into_iter().map(|(_, status, n)| (status, n)).collect(),
        })
    }

    /// Pause (queued cases are not handed out; running ones go back to the
    /// queue at their next heartbeat unless an active sweep wants them), resume,
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
        // The embedded workers stop the cases a pause or cancellation reached now.
        if let Some(pool) = &self.pool
            && action != SweepAction::Resume
        {
            pool.nudge();
        }
        let cases = self.store.sweep_cases(id).await?;
        Ok(SweepDetail::new(&record, &cases)?)
    }

    pub async fn phase_diagram(&self, id: i64) -> Result<PhaseDiagram, CoreError> {
        let record = self.record(id).await?;
        let cases = self.store.sweep_cases(id).await?;
        let spec = views::stored_spec(&record)?;
        let base = spec::base_params(&spec).map_err(|e| {
            knotsweep_worker::StoreError::Corrupt(format!("sweep {id}'s stored base parameters: {e}"))
        })?;
        let base = serde_json::to_value(base).expect("params serialise");
        let (points, _) = views::points(&record, &cases)?;
        // The simplified model is the overhand knot's: other knots have no line.
        let simplified = futures_util::future::join_all(points.iter().map(|p| {
            let params = &p.case.case.params;
            let overhand = params.knot == solver::case::KnotKind::Overhand;
            async move {
                if overhand {
                    self.simplified_snap(params.n, params.h).await
                } else {
                    None
                }
            }
        }))
        .await;
        Ok(PhaseDiagram::new(&record, &cases, base, simplified)?)
    }

    /// The phase diagram as SVG: critical l̄_k against the first varied
    /// parameter (h in mm; a second axis splits the points into one series
    /// per value), the simplified model's line against n or h, and the
    /// points of the sweeps `with` overlaid; its caption holds what is fixed.
    pub async fn phase_figure(&self, id: i64, with: &[i64]) -> Result<String, CoreError> {
        let pd = self.phase_diagram(id).await?;
        let Some(axis) = pd.varied.first().cloned() else {
            return Err(CoreError::NotFound(format!(
                "a varied parameter in sweep {id} (a single case has no phase diagram)"
            )));
        };
        let mut diagrams = vec![pd];
        for other in with {
            let other_pd = self.phase_diagram(*other).await?;
            if other_pd.varied.first() != Some(&axis) {
                return Err(CoreError::Invalid(vec![FieldError::new(
                    "with",
                    format!("sweep {other} does not vary {axis} first, as sweep {id} does"),
                )]));
            }
            diagrams.push(other_pd);
        }
        let scale = if axis == "h" { 1e3 } else { 1.0 };
        let x = |p: &PhasePoint| p.params.get(&axis).and_then(Value::as_f64).map(|v| v * scale);
        let mark = |p: &PhasePoint| {
            Some(charts::PhaseMark {
                x: x(p)?,
                l_k_bar: p.inversion.as_ref()?.l_k_bar,
                uncertainty: p.uncertainty.as_ref().and_then(|u| u.absolute),
                converged: p.uncertainty.as_ref().is_none_or(|u| u.converged != Some(false)),
            })
        };
        // (label, marks) per sweep, and per value of a second axis.
        let mut groups: Vec<(String, Vec<charts::PhaseMark>)> = Vec::new();
        for pd in &diagrams {
            let sweep = if diagrams.len() > 1 {
                format!("sweep {}", pd.sweep_id)
            } else {
                String::new()
            };
            for p in &pd.points {
                let second = pd.varied.get(1).map(|b| report::symbols::value(b, &p.params[b]));
                let label = [sweep.clone(), second.unwrap_or_default()]
                    .into_iter()
                    .filter(|t| !t.is_empty())
                    .collect::<Vec<_>>()
                    .join(", ");
                let at = match groups.iter().position(|(l, _)| *l == label) {
                    Some(at) => at,
                    None => {
                        groups.push((label, Vec::new()));
                        groups.len() - 1
                    }
                };
                groups[at].1.extend(mark(p));
            }
        }
        let pd = &diagrams[0];
        let simplified: Vec<(f64, f64)> = if (axis == "n" || axis == "h") && pd.varied.len() == 1 {
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
            report::symbols::column(&axis)
        };
        let integer_x = solver::case::PARAMETERS
            .iter()
            .any(|p| p.name == axis && matches!(p.range, solver::case::Range::Integers(..)));
        let name = pd
            .name
            .as_deref()
            .or(pd.preset.as_deref())
            .map_or(String::new(), |n| format!(" ({n})"));
        let figure = charts::PhaseFigure {
            title: format!(
                "Critical {} against {}",
                report::symbols::L_K_BAR,
                report::symbols::symbol(&axis)
            ),
            caption: format!(
                "sweep {id}{name}; held fixed: {}",
                charts::sweep_caption(&pd.base, &pd.varied)
            ),
            x_label,
            integer_x,
            sets: groups
                .iter()
                .filter(|(_, marks)| !marks.is_empty())
                .map(|(label, marks)| charts::PhaseSet {
                    label: label.clone(),
                    marks,
                })
                .collect(),
            simplified,
            measured: (self.measurements(id).await?.iter())
                .filter_map(|m| {
                    Some(charts::Measured {
                        x: m.params.get(&axis)?.as_f64()? * scale,
                        l_k_bar: m.l_k_bar,
                        error: m.error,
                    })
                })
                .collect(),
        };
        charts::phase_chart(&figure).map_err(|e| CoreError::Figure(e.to_string()))
    }

    /// A sweep over two axes as a map (`report::map`): its first axis across
    /// (h in mm), its second up, each point's critical l̄_k; 404 for a sweep
    /// with fewer than two axes.
    pub async fn map_figure(&self, id: i64) -> Result<String, CoreError> {
        let pd = self.phase_diagram(id).await?;
        let [a, b] = match &pd.varied[..] {
            [a, b, ..] => [a.clone(), b.clone()],
            _ => {
                return Err(CoreError::NotFound(format!(
                    "a second varied parameter in sweep {id} (a map needs two axes)"
                )));
            }
        };
        let scale = |axis: &str| if axis == "h" { 1e3 } else { 1.0 };
        let label = |axis: &str| {
            if axis == "h" {
                "h (mm)".to_string()
            } else {
                report::symbols::column(axis)
            }
        };
        let points = (pd.points.iter())
            .filter_map(|p| {
                Some(report::map::MapPoint {
                    x: p.params.get(&a)?.as_f64()? * scale(&a),
                    y: p.params.get(&b)?.as_f64()? * scale(&b),
                    l_k_bar: p.inversion.map(|i| i.l_k_bar),
                })
            })
            .collect();
        let (refined, brackets) = self.map_refinement(id, [a.as_str(), b.as_str()], scale).await?;
        let figure = report::map::MapFigure {
            title: format!(
                "Critical {} over {} and {}",
                report::symbols::L_K_BAR,
                report::symbols::symbol(&a),
                report::symbols::symbol(&b)
            ),
            caption: format!(
                "sweep {id}; held fixed: {}",
                charts::sweep_caption(&pd.base, &pd.varied)
            ),
            x_label: label(&a),
            y_label: label(&b),
            points,
            refined,
            brackets,
        };
        report::map::map_chart(&figure).map_err(|e| CoreError::Figure(e.to_string()))
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
                // A failure leaves the point without its reference line (the
                // field is null), logged here with its reason.
                match self
                    .computing
                    .run(move || solver::simplified::reproduce::snap_l_k_bar(n, h))
                    .await
                {
                    Ok(Ok(snap)) => snap,
                    Ok(Err(e)) => {
                        tracing::warn!(n, h, error = %e, "simplified model failed");
                        None
                    }
                    Err(e) => {
                        tracing::error!(n, h, error = %e, "simplified model panicked");
                        None
                    }
                }
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
        // Samples (a series stored under older names is read under today's).
        let series = match c.result {
            Some(_) => Some(self.series(&c).await?),
            None => None,
        };
        let logs = self.store.case_logs(id).await?;
        Ok(CaseDetail::new(&c, sweeps, series, logs))
    }

    /// A case's stored series; 404 before the result.
    async fn series(&self, c: &CaseRecord) -> Result<Vec<Sample>, CoreError> {
        self.store
            .case_series(c.id)
            .await?
            .ok_or_else(|| CoreError::NotFound(format!("result of case {} (status {})", c.id, c.status())))
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
        charts::case_chart(&c.params, &series, &events_of(&c), quantity)
            .map_err(|e| CoreError::Figure(e.to_string()))
    }

    /// The curves of every finished case of a sweep overlaid (grid order),
    /// their events marked, its caption holding what is fixed.
    pub async fn sweep_figure(&self, id: i64, quantity: Quantity) -> Result<String, CoreError> {
        let record = self.record(id).await?;
        let mut loaded = Vec::new();
        // The sweep's case rows already hold their result summaries: only the series are read.
        let cases = self.store.sweep_cases(id).await?;
        for point in views::points(&record, &cases)?.0 {
            let s = point.case;
            if s.case.result.is_some() {
                let view = SweepCaseView::from((s, &record.varied[..]));
                let label = (view.params.iter())
                    .map(|(k, v)| report::symbols::value(k, v))
                    .collect::<Vec<_>>()
                    .join(", ");
                loaded.push((
                    label,
                    self.series(&s.case).await?,
                    s.case.params.clone(),
                    events_of(&s.case),
                ));
            }
        }
        let curves: Vec<CaseCurve> = loaded
            .iter()
            .map(|(label, series, params, events)| {
                let label = if label.is_empty() {
                    format!("sweep {id}")
                } else {
                    label.clone()
                };
                CaseCurve::new(label, params, series, events)
            })
            .collect();
        let spec = views::stored_spec(&record)?;
        let base = spec::base_params(&spec).map_err(|e| {
            knotsweep_worker::StoreError::Corrupt(format!("sweep {id}'s stored base parameters: {e}"))
        })?;
        let base = serde_json::to_value(base).expect("params serialise");
        let caption = format!(
            "sweep {id}; held fixed: {}",
            charts::sweep_caption(&base, &record.varied)
        );
        let title = format!("{} against {}", quantity.symbol(), report::symbols::L_K_BAR);
        let measured: Vec<(f64, f64)> = (self.measurements(id).await?.iter())
            .map(|m| (m.l_k_bar, m.error))
            .collect();
        charts::tightening_chart(&title, &caption, quantity, &curves, &measured)
            .map_err(|e| CoreError::Figure(e.to_string()))
    }

    /// The snapshots as JSON; 404 before the result. Writing them (over a
    /// megabyte for a default case: docs/API.md, "Stored results") runs on
    /// the blocking pool, not on the async workers.
    pub async fn snapshots(&self, id: i64) -> Result<String, CoreError> {
        let c = self.case_record(id).await?;
        let snapshots = self.snapshots_of(&c).await?;
        tokio::task::spawn_blocking(move || serde_json::to_string(&snapshots).expect("snapshots serialise"))
            .await
            .map_err(|e| CoreError::Internal(format!("writing the snapshots of case {id}: {e}")))
    }

    /// The stored snapshots of case `c`; 404 before its result.
    async fn snapshots_of(&self, c: &CaseRecord) -> Result<Vec<solver::snapshot::Snapshot>, CoreError> {
        let id = c.id;
        self.store
            .case_snapshots(id)
            .await?
            .ok_or_else(|| CoreError::NotFound(format!("result of case {id} (status {})", c.status())))
    }

    /// The snapshots as ParaView files (`report::vtk`: `case-{id}.pvd` over
    /// `case-{id}/*.vtp`) in a zip archive; 404 before the result. Writing
    /// the archive runs on the blocking pool, not on the async workers.
    pub async fn snapshots_zip(&self, id: i64) -> Result<Vec<u8>, CoreError> {
        let c = self.case_record(id).await?;
        let snapshots = self.snapshots_of(&c).await?;
        let h = c.params.h;
        tokio::task::spawn_blocking(move || {
            let files = report::vtk::case_files(&format!("case-{id}"), h, &snapshots);
            zip_archive(&files).map_err(|e| CoreError::Figure(e.to_string()))
        })
        .await
        .map_err(|e| CoreError::Figure(format!("building the archive: {e}")))?
    }

    pub async fn health(&self) -> Health {
        let database = self.store.queue_depth().await.is_ok();
        // Without embedded workers no slot can stall.
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
        let metrics = Metrics {
            cases: self.store.status_counts().await?.into_iter().collect(),
            queue_depth: self.store.queue_depth().await?,
            sweeps: self.sweeps_by_status().await?,
            workers: self.pool.as_ref().map_or(0, |p| p.workers()),
        };
        let mut out = metrics.render();
        if let Some(pool) = &self.pool {
            pool.metrics.render(&mut out);
        }
        Ok(out)
    }

    /// The number of sweeps per status, read a page at a time.
    async fn sweeps_by_status(&self) -> Result<BTreeMap<SweepStatus, usize>, CoreError> {
        let mut sweeps: BTreeMap<SweepStatus, usize> = BTreeMap::new();
        for offset in (0..).step_by(METRICS_PAGE) {
            let (page, _) = self.list_sweeps(METRICS_PAGE, offset).await?;
            for s in &page {
                *sweeps.entry(s.status).or_default() += 1;
            }
            if page.len() < METRICS_PAGE {
                break;
            }
        }
        Ok(sweeps)
    }
}

/// Sweeps read per page when the metrics count them.
const METRICS_PAGE: usize = 1000;

/// The events of a case's result, none before it.
fn events_of(c: &CaseRecord) -> Vec<solver::protocol::Event> {
    c.result
        .as_ref()
        .map(|r| r.summary.events.clone())
        .unwrap_or_default()
}

/// The sweep to store: its cases' parameters and the idempotency key with
/// the body's hash.
fn new_sweep(spec: &SweepSpec, raw: &Value, expanded: Expanded, idempotency_key: Option<&str>) -> NewSweep {
    let request_hash = blake3::hash(knotsweep_worker::canonical_value(raw).as_bytes())
        .to_hex()
        .to_string();
    NewSweep {
        name: expanded.name,
        preset: expanded.preset,
        spec: serde_json::to_value(spec).expect("spec serialises"),
        varied: expanded.varied,
        snapshots: spec.snapshots.unwrap_or_default(),
        cases: with_twins(expanded.cases, expanded.twins),
        idempotency: idempotency_key.map(|key| Idempotency {
            key: key.to_string(),
            request_hash,
        }),
    }
}

/// The sweep's cases: its points in grid order, then the refined twins not
/// already among them ([`spec::points`] tells the two apart), each point
/// holding its twin's position.
fn with_twins(points: Vec<spec::GridCase>, twins: Vec<solver::case::CaseParams>) -> Vec<NewCase> {
    let mut cases: Vec<NewCase> = points.into_iter().map(|c| NewCase::new(c.params)).collect();
    for (point, twin) in twins.into_iter().enumerate() {
        let twin = NewCase::new(twin);
        let position = match cases.iter().position(|c| c.key == twin.key) {
            Some(position) => position,
            None => {
                cases.push(twin);
                cases.len() - 1
            }
        };
        cases[point].twin_position = Some(position);
    }
    cases
}

/// `files` deflated into a zip archive.
fn zip_archive(files: &[report::vtk::VtkFile]) -> zip::result::ZipResult<Vec<u8>> {
    use std::io::Write;
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default();
    for file in files {
        zip.start_file(file.path.as_str(), options)?;
        zip.write_all(file.text.as_bytes())?;
    }
    Ok(zip.finish()?.into_inner())
}
