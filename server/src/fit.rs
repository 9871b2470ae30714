//! Fits: the value of one parameter (mu by default) that reproduces measured
//! inversion points, found over queued cases.
//!
//! A fit is built on sweeps: each evaluation at a value p of the parameter is
//! one sweep per measured point (the point's parameters over the fit's base,
//! the parameter on the grid), so its cases are queued, cached, certified and
//! shown like any other. The fit's view (its evaluations and result) is
//! stored at every step; a fit left running when its server stopped starts
//! again when one starts, reusing every case already computed.
//!
//! The search solves r(p) = 0 for the weighted residual
//! r(p) = Σ_i (l_i(p) - m_i) / s_i², s_i² = σ_i² + u_i², where l_i(p) is the
//! simulated inversion l̄_k of point i, m_i its measurement with error σ_i and
//! u_i the case's certified uncertainty (its refined twin's difference, with
//! `certify`). It brackets the root between the range's ends and narrows the
//! bracket by regula falsi (Illinois) to the tolerance. The interval is
//! value ± (σ_p + half the last bracket, none when the value itself was
//! evaluated), σ_p = (Σ_i l_i'(p)² / s_i²)^(-1/2),
//! the slopes l_i' from the evaluations around the value (two more at
//! value ± a twentieth of the range when there are none).
use crate::core::Core;
use crate::error::CoreError;
use crate::spec::{self, FieldError, SweepSpec};
use crate::views::SweepStatus;
use knotsweep_worker::store::SnapshotChoice;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};
use solver::case::Range;
use std::collections::BTreeMap;
use std::time::Duration;
use utoipa::ToSchema;

/// A fit to run (`POST /api/fits`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(example = json!({"parameter": "mu", "range": [0.05, 0.8], "base": {},
    "points": [{"params": {"n": 3, "h": 3.4e-3}, "l_k_bar": 129.3, "error": 1.0}]}))]
pub struct FitSpec {
    /// The case parameter to find (a number of the parameter table); `mu` by default.
    #[serde(default = "default_parameter")]
    pub parameter: String,
    /// The values it is searched between, [low, high].
    pub range: [f64; 2],
    /// Case parameters shared by every point (a partial `CaseParams`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<Object>, schema_with = crate::openapi::partial_case_params)]
    pub base: Option<Map<String, Value>>,
    /// The measured inversion points.
    pub points: Vec<MeasuredPoint>,
    /// Certify every case (its refined twin beside it), so that its
    /// numerical uncertainty widens the interval; about 3 times the cost.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub certify: Option<bool>,
    /// The bracket's width at which the search stops, in the parameter's
    /// unit; a 400th of the range by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// Display name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
}

fn default_parameter() -> String {
    "mu".to_string()
}

/// A measured inversion: the case it was measured on, l̄_k and its error.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct MeasuredPoint {
    /// Its case parameters over the fit's base (e.g. `{"n": 3, "h": 3.4e-3}`).
    #[serde(default)]
    #[schema(value_type = Object)]
    pub params: Map<String, Value>,
    /// The measured l̄_k at inversion.
    pub l_k_bar: f64,
    /// Its error (one standard deviation, in l̄_k), positive.
    pub error: f64,
}

/// Where a fit is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum FitStatus {
    Running,
    Done,
    Failed,
}

/// A simulated point at one value of the parameter: its inversion l̄_k and
/// certified uncertainty, or why it has none.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct Simulated {
    pub case_id: i64,
    pub l_k_bar: Option<f64>,
    /// The certified uncertainty (l̄_k), null unless certified.
    pub uncertainty: Option<f64>,
    /// Why there is no inversion.
    pub reason: Option<String>,
}

/// One evaluation: the parameter's value and each point's simulation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct Evaluation {
    pub value: f64,
    /// The weighted residual r(value) (null when a point has no inversion).
    pub residual: Option<f64>,
    /// One per measured point, in their order.
    pub points: Vec<Simulated>,
}

/// A fit and where it is (`GET /api/fits/{id}`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct FitView {
    pub id: i64,
    pub name: Option<String>,
    pub status: FitStatus,
    pub parameter: String,
    pub range: [f64; 2],
    /// The fitted value (null until done).
    pub value: Option<f64>,
    /// [low, high]: value ± (σ from the measurement errors and the certified
    /// uncertainties, plus half the last bracket); null until done.
    pub interval: Option<[f64; 2]>,
    /// χ² of the points at the fitted value (linear between the evaluations around it).
    pub chi_squared: Option<f64>,
    /// Why the fit failed.
    pub reason: Option<String>,
    /// The sweeps its evaluations ran in.
    pub sweeps: Vec<i64>,
    /// Every evaluation, in the order they ran.
    pub evaluations: Vec<Evaluation>,
    /// The accepted specification.
    #[schema(value_type = Object)]
    pub spec: Value,
}

/// What the search asks for next.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// Simulate every point at these values.
    Evaluate(Vec<f64>),
    /// The value and its interval.
    Done {
        value: f64,
        interval: [f64; 2],
        chi_squared: f64,
    },
    Failed(String),
}

/// The search's state: the measurements, the evaluations so far and the
/// bracket. Pure numbers, driven by [`crate::core::Core`] (tested on closed forms).
#[derive(Clone, Debug)]
pub struct Search {
    range: [f64; 2],
    tolerance: f64,
    measured: Vec<(f64, f64)>,
    /// (value, each point's (l̄_k, uncertainty)), in the order they ran.
    evaluations: Vec<(f64, Vec<(f64, f64)>)>,
    /// The bracket's ends (value, residual) and which end was kept twice
    /// (Illinois: its residual is halved).
    bracket: Option<[(f64, f64); 2]>,
    kept: Option<usize>,
    /// The root estimate when the bracket is narrow enough, and how far it
    /// may be from the root (half the last bracket; 0 when it was evaluated).
    root: Option<f64>,
    located: f64,
    iterations: usize,
}

/// Each point's (l̄_k, certified uncertainty) at one value, or why one has no inversion.
pub type Simulations = Result<Vec<(f64, f64)>, String>;

/// Most evaluations a search makes before it gives up.
const MAX_ITERATIONS: usize = 40;

impl Search {
    /// A search over `range` for `measured` (l̄_k, error) points, stopping at
    /// a bracket of `tolerance`.
    pub fn new(range: [f64; 2], tolerance: f64, measured: Vec<(f64, f64)>) -> Self {
        Self {
            range,
            tolerance,
            measured,
            evaluations: Vec::new(),
            bracket: None,
            kept: None,
            root: None,
            located: 0.0,
            iterations: 0,
        }
    }

    /// The first step: both ends of the range.
    pub fn start(&self) -> Step {
        Step::Evaluate(self.range.to_vec())
    }

    /// r(p) for each point's (l̄_k, uncertainty) at p.
    fn residual(&self, simulated: &[(f64, f64)]) -> f64 {
        (self.measured.iter().zip(simulated))
            .map(|(&(m, e), &(l, u))| (l - m) / (e * e + u * u))
            .sum()
    }

    /// Records the simulations at `values` (each point's (l̄_k, uncertainty),
    /// `Err` with the reason where one has no inversion) and says what next.
    pub fn record(&mut self, results: Vec<(f64, Simulations)>) -> Step {
        let mut fresh = Vec::new();
        for (value, simulated) in results {
            match simulated {
                Ok(s) => {
                    fresh.push((value, self.residual(&s)));
                    self.evaluations.push((value, s));
                }
                Err(reason) => return Step::Failed(format!("at {value}: {reason}")),
            }
        }
        self.iterations += 1;
        if self.iterations > MAX_ITERATIONS {
            return Step::Failed(format!("no convergence after {MAX_ITERATIONS} evaluations"));
        }
        if self.root.is_some() {
            return self.finish();
        }
        let [a, b] = match self.bracket {
            None => {
                let [lo, hi] = [fresh[0], fresh[fresh.len() - 1]];
                if lo.1 * hi.1 > 0.0 {
                    return Step::Failed(format!(
                        "the measurements lie outside what the range gives: the weighted residual is {:.3} at {} \
                         and {:.3} at {} (same sign)",
                        lo.1, lo.0, hi.1, hi.0
                    ));
                }
                [lo, hi]
            }
            Some(mut bracket) => {
                let (p, r) = fresh[0];
                // The end whose residual has the sign of r(p) moves to p.
                let moved = if r * bracket[0].1 > 0.0 { 0 } else { 1 };
                bracket[moved] = (p, r);
                if self.kept == Some(1 - moved) {
                    bracket[1 - moved].1 /= 2.0;
                }
                self.kept = Some(1 - moved);
                bracket
            }
        };
        self.bracket = Some([a, b]);
        let secant = |a: (f64, f64), b: (f64, f64)| {
            if a.1 == b.1 {
                0.5 * (a.0 + b.0)
            } else {
                a.0 - a.1 * (b.0 - a.0) / (b.1 - a.1)
            }
        };
        if a.1 == 0.0 || b.1 == 0.0 || (b.0 - a.0).abs() <= self.tolerance {
            let root = if a.1 == 0.0 {
                a.0
            } else if b.1 == 0.0 {
                b.0
            } else {
                secant(a, b)
            };
            // An evaluation at the root itself leaves no doubt where it is.
            let exact = a.1 == 0.0 || b.1 == 0.0;
            self.located = if exact { 0.0 } else { 0.5 * (b.0 - a.0).abs() };
            self.root = Some(root);
            return match self.slope_values(root) {
                Some(values) => Step::Evaluate(values),
                None => self.finish(),
            };
        }
        // Kept inside the bracket's middle 90 % so that it shrinks from both sides.
        let (lo, hi) = (a.0.min(b.0), a.0.max(b.0));
        let margin = 0.05 * (hi - lo);
        Step::Evaluate(vec![secant(a, b).clamp(lo + margin, hi - margin)])
    }

    /// Half the distance over which the slopes are taken.
    fn spread(&self) -> f64 {
        (self.range[1] - self.range[0]) / 20.0
    }

    /// The evaluations within 3 spreads of `root`, when they span at least one spread.
    fn around(&self, root: f64) -> Vec<&(f64, Vec<(f64, f64)>)> {
        let near: Vec<_> = (self.evaluations.iter())
            .filter(|(p, _)| (p - root).abs() <= 3.0 * self.spread())
            .collect();
        let (lo, hi) = near
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (p, _)| {
                (lo.min(*p), hi.max(*p))
            });
        if hi - lo >= self.spread() {
            near
        } else {
            Vec::new()
        }
    }

    /// Values to evaluate for the slopes at `root`; none when the evaluations
    /// around it already give them.
    fn slope_values(&self, root: f64) -> Option<Vec<f64>> {
        if !self.around(root).is_empty() {
            return None;
        }
        let d = self.spread();
        let values = [(root - d).max(self.range[0]), (root + d).min(self.range[1])];
        Some(values.to_vec())
    }

    /// The value, its interval and χ²: slopes by least squares over the
    /// evaluations around the root.
    fn finish(&self) -> Step {
        let root = self.root.expect("finish after the root");
        let near = self.around(root);
        if near.is_empty() {
            return Step::Failed("too few evaluations around the value for its slopes".to_string());
        }
        let mean_p = near.iter().map(|(p, _)| p).sum::<f64>() / near.len() as f64;
        let spread_p: f64 = near.iter().map(|(p, _)| (p - mean_p).powi(2)).sum();
        let mut information = 0.0;
        let mut chi_squared = 0.0;
        for (i, &(m, e)) in self.measured.iter().enumerate() {
            let mean_l = near.iter().map(|(_, s)| s[i].0).sum::<f64>() / near.len() as f64;
            let slope = near
                .iter()
                .map(|(p, s)| (p - mean_p) * (s[i].0 - mean_l))
                .sum::<f64>()
                / spread_p;
            let at_root = mean_l + slope * (root - mean_p);
            // The certified uncertainty of the evaluation nearest the root.
            let nearest = near
                .iter()
                .min_by(|a, b| (a.0 - root).abs().total_cmp(&(b.0 - root).abs()))
                .expect("evaluations around the root");
            let u = nearest.1[i].1;
            let variance = e * e + u * u;
            information += slope * slope / variance;
            chi_squared += (at_root - m).powi(2) / variance;
        }
        if information <= 0.0 || !information.is_finite() {
            return Step::Failed("the points do not depend on the parameter around the value".to_string());
        }
        let sigma = information.sqrt().recip() + self.located;
        Step::Done {
            value: root,
            interval: [root - sigma, root + sigma],
            chi_squared,
        }
    }

    /// The weighted residual of the evaluation at `value`, if recorded.
    pub fn residual_at(&self, value: f64) -> Option<f64> {
        (self.evaluations.iter())
            .find(|(p, _)| *p == value)
            .map(|(_, s)| self.residual(s))
    }
}

/// Measured points from CSV: a header naming case parameters (`n`, `h`, ...;
/// SI units), `l_k_bar` and `error`, then one row per measurement; blank
/// lines and `#` comments are skipped. Parameter cells are JSON values where
/// they parse (numbers), words otherwise.
pub fn measured_csv(text: &str) -> Result<Vec<MeasuredPoint>, String> {
    let mut lines =
        (text.lines().enumerate()).filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let header: Vec<&str> = lines
        .next()
        .ok_or("no header line")?
        .1
        .split(',')
        .map(str::trim)
        .collect();
    let column = |name: &str| header.iter().position(|c| *c == name);
    let (Some(l_k), Some(error)) = (column("l_k_bar"), column("error")) else {
        return Err(format!(
            "the header needs the columns l_k_bar and error, got {}",
            header.join(", ")
        ));
    };
    lines
        .map(|(k, line)| {
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            if cells.len() != header.len() {
                return Err(format!(
                    "line {}: {} cells under {} columns",
                    k + 1,
                    cells.len(),
                    header.len()
                ));
            }
            let number = |i: usize| {
                (cells[i].parse::<f64>())
                    .map_err(|_| format!("line {}: {} = {:?} is not a number", k + 1, header[i], cells[i]))
            };
            let params = (header.iter().zip(&cells).enumerate())
                .filter(|(i, _)| *i != l_k && *i != error)
                .map(|(_, (name, cell))| {
                    let value = serde_json::from_str(cell).unwrap_or_else(|_| Value::from(*cell));
                    (name.to_string(), value)
                })
                .collect();
            Ok(MeasuredPoint {
                params,
                l_k_bar: number(l_k)?,
                error: number(error)?,
            })
        })
        .collect()
}

/// Problems of measured points: a positive l̄_k and error each (fields
/// under `prefix`, e.g. `points`).
pub fn check_measured(points: &[MeasuredPoint], prefix: &str) -> Vec<FieldError> {
    let mut errors = Vec::new();
    for (k, p) in points.iter().enumerate() {
        if !(p.l_k_bar.is_finite() && p.l_k_bar > 0.0) {
            errors.push(FieldError::new(
                format!("{prefix}[{k}].l_k_bar"),
                "must be a positive number",
            ));
        }
        if !(p.error.is_finite() && p.error > 0.0) {
            errors.push(FieldError::new(
                format!("{prefix}[{k}].error"),
                "must be a positive number (one standard deviation in l̄_k)",
            ));
        }
    }
    errors
}

/// The field a problem of a fit's evaluation sweep belongs to: `range` for
/// the parameter's grid, `points[k].params.x` for a parameter the point sets.
pub fn fit_field(field: &str, parameter: &str, point: usize, params: &Map<String, Value>) -> String {
    if field.starts_with(&format!("grid.{parameter}")) {
        return "range".to_string();
    }
    match field.strip_prefix("base.") {
        Some(name) if params.contains_key(name.split(['.', '[']).next().unwrap_or(name)) => {
            format!("points[{point}].params.{name}")
        }
        _ => field.to_string(),
    }
}

/// How often a fit looks at its evaluation sweeps.
const POLL: Duration = Duration::from_millis(500);

/// A fit's status as stored beside its view.
fn status_word(status: FitStatus) -> &'static str {
    match status {
        FitStatus::Running => "running",
        FitStatus::Done => "done",
        FitStatus::Failed => "failed",
    }
}

/// A stored view, parsed.
pub(crate) fn parse_view<T: serde::de::DeserializeOwned>(what: &str, json: &str) -> Result<T, CoreError> {
    serde_json::from_str(json)
        .map_err(|e| CoreError::Store(knotsweep_worker::StoreError::Corrupt(format!("{what}: {e}"))))
}

impl Core {
    /// Parses a JSON body (a fit's, measured points'): 400 for malformed
    /// JSON, 422 with the field for unknown fields and wrong types.
    pub fn parse_json<T: serde::de::DeserializeOwned>(body: &[u8]) -> Result<T, CoreError> {
        let value: Value = serde_json::from_slice(body)
            .map_err(|e| CoreError::bad_request("body", format!("malformed JSON: {e}")))?;
        serde_path_to_error::deserialize(value).map_err(|e| {
            let path = e.path().to_string();
            let field = if path == "." { "body".to_string() } else { path };
            CoreError::Invalid(vec![FieldError::new(field, e.inner().to_string())])
        })
    }

    /// Checks a fit (every point's cases at both ends of the range must be
    /// valid), stores it and starts its search; answers at once.
    pub async fn submit_fit(&self, spec: FitSpec) -> Result<FitView, CoreError> {
        check_fit(&spec).map_err(CoreError::Invalid)?;
        let mut errors = Vec::new();
        for (k, sweep) in fit_sweeps(&spec, "check", &spec.range).iter().enumerate() {
            if let Err(problems) = spec::expand(sweep, self.limits()) {
                errors.extend(problems.into_iter().map(|e| {
                    let field = fit_field(&e.field, &spec.parameter, k, &spec.points[k].params);
                    FieldError::new(field, e.reason)
                }));
            }
        }
        if !errors.is_empty() {
            errors.dedup();
            return Err(CoreError::Invalid(errors));
        }
        let mut view = FitView {
            id: 0,
            name: spec.name.clone(),
            status: FitStatus::Running,
            parameter: spec.parameter.clone(),
            range: spec.range,
            value: None,
            interval: None,
            chi_squared: None,
            reason: None,
            sweeps: Vec::new(),
            evaluations: Vec::new(),
            spec: serde_json::to_value(&spec).expect("spec serialises"),
        };
        let json = serde_json::to_string(&view).expect("view serialises");
        view.id = self.store().create_fit("running", &json).await?;
        self.save_fit(&view).await?;
        tracing::info!(fit_id = view.id, parameter = %spec.parameter, points = spec.points.len(), "fit accepted");
        self.spawn_fit(view.clone(), spec);
        Ok(view)
    }

    /// Runs fit `view`'s search in the background, storing each step.
    fn spawn_fit(&self, mut view: FitView, spec: FitSpec) {
        let core = self.clone();
        tokio::spawn(async move {
            let end = core.run_fit(&mut view, &spec).await;
            if let Err(reason) = &end {
                tracing::warn!(fit_id = view.id, %reason, "fit failed");
            }
            match end {
                Ok((value, interval, chi_squared)) => {
                    view.status = FitStatus::Done;
                    view.value = Some(value);
                    view.interval = Some(interval);
                    view.chi_squared = Some(chi_squared);
                }
                Err(reason) => {
                    view.status = FitStatus::Failed;
                    view.reason = Some(reason);
                }
            }
            if let Err(e) = core.save_fit(&view).await {
                tracing::error!(fit_id = view.id, error = %e, "storing the fit's end failed");
            }
        });
    }

    /// Takes up the fits left running by a server that stopped: each search
    /// starts again from its specification (its cases are cached).
    pub async fn resume_fits(&self) -> Result<usize, CoreError> {
        let mut resumed = 0;
        for (id, status, json) in self.store().list_fits().await? {
            if status != status_word(FitStatus::Running) {
                continue;
            }
            let mut view: FitView = parse_view(&format!("fit {id}"), &json)?;
            let spec: FitSpec = serde_json::from_value(view.spec.clone()).map_err(|e| {
                CoreError::Store(knotsweep_worker::StoreError::Corrupt(format!(
                    "fit {id}'s spec: {e}"
                )))
            })?;
            view.id = id;
            view.evaluations.clear();
            view.sweeps.clear();
            tracing::info!(fit_id = id, "fit taken up again");
            self.spawn_fit(view, spec);
            resumed += 1;
        }
        Ok(resumed)
    }

    /// A fit; 404 for an unknown id.
    pub async fn fit(&self, id: i64) -> Result<FitView, CoreError> {
        match self.store().get_fit(id).await? {
            Some(json) => parse_view(&format!("fit {id}"), &json),
            None => Err(CoreError::NotFound(format!("fit {id}"))),
        }
    }

    /// Every fit, oldest first.
    pub async fn list_fits(&self) -> Result<Vec<FitView>, CoreError> {
        (self.store().list_fits().await?.iter())
            .map(|(id, _, json)| parse_view(&format!("fit {id}"), json))
            .collect()
    }

    async fn save_fit(&self, view: &FitView) -> Result<(), CoreError> {
        let json = serde_json::to_string(view).expect("view serialises");
        Ok(self
            .store()
            .update_fit(view.id, status_word(view.status), &json)
            .await?)
    }

    /// The search of fit `view` to its end (each evaluation stored as it
    /// lands): the value, interval and χ², or why not.
    async fn run_fit(&self, view: &mut FitView, spec: &FitSpec) -> Result<(f64, [f64; 2], f64), String> {
        let measured = spec.points.iter().map(|p| (p.l_k_bar, p.error)).collect();
        let tolerance = spec.tolerance.unwrap_or((spec.range[1] - spec.range[0]) / 400.0);
        let mut search = Search::new(spec.range, tolerance, measured);
        let mut step = search.start();
        loop {
            match step {
                Step::Evaluate(values) => {
                    let (sweeps, results) = self.evaluate(view.id, spec, &values).await?;
                    view.sweeps.extend(sweeps);
                    let recorded: Vec<(f64, Simulations)> = (values.iter().zip(&results))
                        .map(|(&value, simulated)| (value, pair(simulated)))
                        .collect();
                    step = search.record(recorded);
                    for (&value, points) in values.iter().zip(results) {
                        let residual = search.residual_at(value);
                        view.evaluations.push(Evaluation {
                            value,
                            residual,
                            points,
                        });
                    }
                    self.save_fit(view).await.map_err(|e| e.to_string())?;
                }
                Step::Done {
                    value,
                    interval,
                    chi_squared,
                } => return Ok((value, interval, chi_squared)),
                Step::Failed(reason) => return Err(reason),
            }
        }
    }

    /// Every point simulated at each of `values`: one sweep per point, its
    /// results once the sweep is done. Returns the sweeps and, per value, the points.
    async fn evaluate(
        &self,
        id: i64,
        spec: &FitSpec,
        values: &[f64],
    ) -> Result<(Vec<i64>, Vec<Vec<Simulated>>), String> {
        let mut sweep_ids = Vec::new();
        for sweep in fit_sweeps(spec, &format!("fit {id}"), values) {
            let raw = serde_json::to_value(&sweep).expect("spec serialises");
            let submitted = self.submit(sweep, &raw, None).await.map_err(|e| e.to_string())?;
            sweep_ids.push(submitted.sweep.summary.id);
        }
        let mut results = vec![Vec::new(); values.len()];
        for &sweep_id in &sweep_ids {
            let pd = self.finished_phase_diagram(sweep_id).await?;
            for (k, point) in pd.points.iter().enumerate().take(values.len()) {
                results[k].push(Simulated {
                    case_id: point.case_id,
                    l_k_bar: point.inversion.map(|i| i.l_k_bar),
                    uncertainty: point.uncertainty.as_ref().and_then(|u| u.absolute),
                    reason: point.reason.clone(),
                });
            }
        }
        Ok((sweep_ids, results))
    }

    /// Sweep `id`'s phase diagram once the sweep is done; why not when it
    /// was cancelled.
    pub(crate) async fn finished_phase_diagram(&self, id: i64) -> Result<crate::views::PhaseDiagram, String> {
        loop {
            let detail = self.sweep(id).await.map_err(|e| e.to_string())?;
            match detail.summary.status {
                SweepStatus::Done => break,
                SweepStatus::Cancelled => return Err(format!("its sweep {id} was cancelled")),
                _ => tokio::time::sleep(POLL).await,
            }
        }
        self.phase_diagram(id).await.map_err(|e| e.to_string())
    }
}

/// Each point's (l̄_k, certified uncertainty), or why one has no inversion.
fn pair(simulated: &[Simulated]) -> Simulations {
    (simulated.iter().enumerate())
        .map(|(k, s)| match s.l_k_bar {
            Some(l) => Ok((l, s.uncertainty.unwrap_or(0.0))),
            None => Err(format!(
                "point {} (case {}) has no inversion: {}",
                k + 1,
                s.case_id,
                s.reason.as_deref().unwrap_or("no result")
            )),
        })
        .collect()
}

/// The sweeps of one evaluation: per point, its parameters over the base and
/// the fitted parameter on the grid at `values`.
fn fit_sweeps(spec: &FitSpec, name: &str, values: &[f64]) -> Vec<SweepSpec> {
    (spec.points.iter().enumerate())
        .map(|(k, point)| {
            let mut base = spec.base.clone().unwrap_or_default();
            base.extend(point.params.clone());
            let axis = values.iter().map(|&v| Value::from(v)).collect();
            SweepSpec {
                name: Some(format!("{name}: point {k}")),
                base: Some(base),
                grid: Some(BTreeMap::from([(spec.parameter.clone(), axis)])),
                certify: spec.certify,
                snapshots: Some(SnapshotChoice::Events),
                ..SweepSpec::default()
            }
        })
        .collect()
}

/// The fit's own fields: a numeric parameter of the table that neither the
/// base nor a point sets, a range low < high, measurements with positive
/// errors, a positive tolerance.
fn check_fit(spec: &FitSpec) -> Result<(), Vec<FieldError>> {
    let mut errors = Vec::new();
    let numeric = solver::case::PARAMETERS
        .iter()
        .any(|p| p.name == spec.parameter && matches!(p.range, Range::Interval(..) | Range::LengthOver(..)));
    if !numeric {
        let names: Vec<&str> = (solver::case::PARAMETERS.iter())
            .filter(|p| matches!(p.range, Range::Interval(..) | Range::LengthOver(..)))
            .map(|p| p.name)
            .collect();
        errors.push(FieldError::new(
            "parameter",
            format!("must be a number of the parameter table: {}", names.join(", ")),
        ));
    }
    let [lo, hi] = spec.range;
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        errors.push(FieldError::new(
            "range",
            format!("must be [low, high] with low < high, got [{lo}, {hi}]"),
        ));
    }
    if spec
        .base
        .as_ref()
        .is_some_and(|b| b.contains_key(&spec.parameter))
    {
        errors.push(FieldError::new(
            format!("base.{}", spec.parameter),
            "the fit finds it: leave it out",
        ));
    }
    if spec.points.is_empty() {
        errors.push(FieldError::new("points", "needs at least one measured point"));
    }
    for (k, p) in spec.points.iter().enumerate() {
        if p.params.contains_key(&spec.parameter) {
            errors.push(FieldError::new(
                format!("points[{k}].params.{}", spec.parameter),
                "the fit finds it: leave it out",
            ));
        }
    }
    errors.extend(check_measured(&spec.points, "points"));
    if spec.tolerance.is_some_and(|t| !(t.is_finite() && t > 0.0)) {
        errors.push(FieldError::new("tolerance", "must be a positive number"));
    }
    if errors.is_empty() { Ok(()) } else { Err(errors) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Drives a search on simulated points l_i(p) = a_i + b_i p.
    fn solve(lines: &[(f64, f64)], truth: f64, error: f64, range: [f64; 2]) -> (Step, usize) {
        let measured: Vec<(f64, f64)> = lines.iter().map(|(a, b)| (a + b * truth, error)).collect();
        let mut search = Search::new(range, (range[1] - range[0]) / 400.0, measured);
        let mut step = search.start();
        let mut runs = 0;
        while let Step::Evaluate(values) = step {
            runs += values.len();
            let results = values
                .iter()
                .map(|&p| (p, Ok(lines.iter().map(|(a, b)| (a + b * p, 0.0)).collect())))
                .collect();
            step = search.record(results);
        }
        (step, runs)
    }

    #[test]
    fn recovers_the_value_of_linear_points_with_the_closed_form_sigma() {
        let lines = [(100.0, 100.0), (150.0, 200.0)];
        let (step, runs) = solve(&lines, 0.3, 1.0, [0.05, 0.8]);
        let Step::Done {
            value,
            interval,
            chi_squared,
        } = step
        else {
            panic!("{step:?}")
        };
        assert!((value - 0.3).abs() < 1e-9, "{value}");
        // σ = (Σ b_i² / σ_i²)^(-1/2) for straight lines.
        let sigma = (100.0f64.powi(2) + 200.0f64.powi(2)).sqrt().recip();
        let half = 0.5 * (interval[1] - interval[0]);
        assert!(
            (half - sigma).abs() < 1e-12 * sigma,
            "{half} vs {sigma}: the value was evaluated"
        );
        assert!(chi_squared < 1e-12);
        assert!(runs <= 8, "{runs} evaluations");
    }

    #[test]
    fn recovers_a_curved_response_within_its_interval() {
        let measured_at = 0.42;
        let model = |p: f64| [90.0 + 300.0 * p * p, 140.0 + 80.0 * p.sqrt()];
        let measured: Vec<(f64, f64)> = model(measured_at).iter().map(|&m| (m, 1.0)).collect();
        let mut search = Search::new([0.05, 0.8], 0.75 / 400.0, measured);
        let mut step = search.start();
        while let Step::Evaluate(values) = step {
            step = search.record(
                values
                    .iter()
                    .map(|&p| (p, Ok(model(p).iter().map(|&l| (l, 0.5)).collect())))
                    .collect(),
            );
        }
        let Step::Done { value, interval, .. } = step else {
            panic!("{step:?}")
        };
        assert!(
            interval[0] <= measured_at && measured_at <= interval[1],
            "{value} {interval:?}"
        );
        assert!(interval[1] - interval[0] < 0.02, "{interval:?}");
    }

    #[test]
    fn measurements_outside_the_range_fail_with_the_residuals() {
        let (step, _) = solve(&[(100.0, 100.0)], 2.0, 1.0, [0.05, 0.8]);
        let Step::Failed(reason) = step else {
            panic!("{step:?}")
        };
        assert!(reason.contains("same sign"), "{reason}");
    }

    #[test]
    fn a_missing_inversion_fails_naming_the_value() {
        let mut search = Search::new([0.05, 0.8], 0.01, vec![(120.0, 1.0)]);
        let step = search.record(vec![
            (0.05, Err("no inversion".to_string())),
            (0.8, Ok(vec![(130.0, 0.0)])),
        ]);
        assert_eq!(step, Step::Failed("at 0.05: no inversion".to_string()));
    }

    #[test]
    fn measured_points_read_from_csv() {
        let points =
            measured_csv("# lab, 2026\nn,h,l_k_bar,error\n3,3.4e-3,129.3,1.0\n4, 1.6e-3, 210,2\n").unwrap();
        assert_eq!(points.len(), 2);
        assert_eq!(points[0].params["n"], 3);
        assert_eq!(points[1].params["h"], 1.6e-3);
        assert_eq!((points[1].l_k_bar, points[1].error), (210.0, 2.0));
        assert!(measured_csv("n,l_k_bar\n3,1\n").unwrap_err().contains("error"));
        assert!(
            measured_csv("n,l_k_bar,error\n3,x,1\n")
                .unwrap_err()
                .contains("line 2")
        );
    }

    #[test]
    fn fields_name_the_fit() {
        let params = Map::from_iter([("n".to_string(), Value::from(3))]);
        assert_eq!(fit_field("grid.mu[1]", "mu", 0, &params), "range");
        assert_eq!(fit_field("base.n", "mu", 2, &params), "points[2].params.n");
        assert_eq!(fit_field("base.h", "mu", 2, &params), "base.h");
    }
}
