//! The API's response types (JSON), documented in the OpenAPI document.
//!
//! Status words of a case (`status`): `queued`, `running`, `failed` (out of
//! attempts after infrastructure failures), `cancelled`, or, once it has a
//! result, the solver's status: `completed`, `invalid`, `diverged`,
//! `penetrated`, `topology_changed`. Times are Unix milliseconds.
//!
//! The views are built here from the store's records (`From` impls and
//! constructors), so the core only gathers the records.
use knotsweep_worker::store::{
    CaseRecord, CaseState, CaseStatus, LogLine, ResultDetails, ResultSummary, StoreError, SweepCase,
    SweepRecord, SweepState,
};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use solver::measurements::Sample;
use solver::protocol::{Event, Hysteresis, Progress, QuasiStatic, Status};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::fmt::Write;
use utoipa::ToSchema;

/// Status words of a whole sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum SweepStatus {
    /// Nothing has started yet.
    Queued,
    /// Some cases are running or queued.
    Running,
    /// Paused with cases left (running ones go back to the queue).
    Paused,
    /// Every case has a result, failed or was cancelled.
    Done,
    Cancelled,
}

/// The inversion point of a case (paper Fig. 5): the last sample before the
/// loop's H bar drops.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct InversionPoint {
    /// l_k bar = (L - l_c) / h at the inversion.
    pub l_k_bar: f64,
    /// The knot's own length (s - l_c) / h at the inversion, s the rod's arc
    /// length between the clamps: l_k bar less the rod's elastic stretch (0
    /// for results computed before it was measured).
    #[serde(default)]
    pub l_k_arc_bar: f64,
    /// l_c / L at the inversion.
    #[serde(rename = "l_c_over_L")]
    pub l_c_over_l: f64,
    /// F bar = F h^2 / EI just before the drop and its minimum just after.
    #[serde(rename = "F_bar_before")]
    pub f_bar_before: f64,
    #[serde(rename = "F_bar_after")]
    pub f_bar_after: f64,
    /// H bar before and after the drop.
    #[serde(rename = "H_bar_before")]
    pub h_bar_before: f64,
    #[serde(rename = "H_bar_after")]
    pub h_bar_after: f64,
    /// Peak kinetic energy around the drop over its median before it. With
    /// `F_bar_after >= F_bar_before` it tells a snap (tens) from a loop that
    /// lies down while the pull keeps loading it (5-10; docs/FIDELITY.md).
    pub kinetic_energy_ratio: f64,
}

impl From<&solver::measurements::Inversion> for InversionPoint {
    fn from(i: &solver::measurements::Inversion) -> Self {
        Self {
            l_k_bar: i.l_k_bar,
            l_k_arc_bar: i.l_k_arc_bar,
            l_c_over_l: i.l_c_over_l,
            f_bar_before: i.f_bar_before,
            f_bar_after: i.f_bar_after,
            h_bar_before: i.h_bar_before,
            h_bar_after: i.h_bar_after,
            kinetic_energy_ratio: i.kinetic_energy_ratio,
        }
    }
}

/// Progress of a running case, stored by its last heartbeat.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct CaseProgress {
    /// Fraction of the pull done (0..1).
    pub fraction: f64,
    pub l_k_bar: f64,
    #[serde(rename = "H_bar")]
    pub h_bar: f64,
    pub steps: u64,
}

/// What a client needs to know of the service's limits and thresholds
/// (`GET /api/limits`), so that the web page and the Python client never
/// write them again.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ServiceLimits {
    /// Largest number of cases in a sweep, a certified sweep's refined twins
    /// included (422 beyond).
    pub max_cases: usize,
    /// Largest request body in bytes (413 beyond).
    pub max_body_bytes: usize,
    /// Longest sweep name (characters).
    pub max_name_chars: usize,
    /// Longest `Idempotency-Key` (characters).
    pub max_idempotency_key_chars: usize,
    /// Largest `limit` of a page of a list (`GET /api/sweeps`, `GET /api/sweeps/{id}/cases`).
    pub max_page: usize,
    /// A certified point is converged when its relative uncertainty is at
    /// most this (`solver::certify::CONVERGED_WITHIN`).
    pub converged_within: f64,
}

impl ServiceLimits {
    /// The limits of `limits`, lists paged by at most `max_page`.
    pub fn new(limits: &crate::spec::Limits, max_page: usize) -> Self {
        Self {
            max_cases: limits.max_cases,
            max_body_bytes: limits.max_body_bytes,
            max_name_chars: limits.max_name_len,
            max_idempotency_key_chars: limits.max_idempotency_key_len,
            max_page,
            converged_within: solver::certify::CONVERGED_WITHIN,
        }
    }
}

/// A sweep in a list.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SweepSummary {
    pub id: i64,
    pub name: Option<String>,
    pub preset: Option<String>,
    /// `active`, `paused` or `cancelled` (what was asked), or `done` once
    /// every case of an active or paused sweep has finished.
    pub state: String,
    /// Where the sweep is.
    pub status: SweepStatus,
    /// Number of cases.
    pub total: i64,
    /// Cases per status word.
    #[schema(value_type = BTreeMap<String, i64>)]
    pub counts: BTreeMap<CaseStatus, i64>,
    pub created_at: i64,
    /// Links: self, phase diagram, events.
    pub links: BTreeMap<String, String>,
}

/// A case as part of a sweep.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SweepCaseView {
    pub case_id: i64,
    /// Position in the grid (0-based).
    pub position: i64,
    /// The grid axes' values of this case.
    #[schema(value_type = BTreeMap<String, Object>)]
    pub params: BTreeMap<String, Value>,
    #[schema(value_type = String)]
    pub status: CaseStatus,
    /// The result existed when the sweep was submitted (reused, not rerun).
    pub cached: bool,
    pub attempts: u32,
    /// 0..1 (1 when done).
    pub progress: f64,
    pub progress_detail: Option<CaseProgress>,
    pub inversion: Option<InversionPoint>,
    /// Why the case ended as it did (solver reason, failure, cancellation).
    pub reason: Option<String>,
    /// Solver wall time (s) of the result.
    pub wall_time: Option<f64>,
    /// In a certified sweep, a refined twin's point (its case id); null for
    /// the points themselves.
    pub twin_of: Option<i64>,
}

/// A sweep with its cases.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SweepDetail {
    #[serde(flatten)]
    pub summary: SweepSummary,
    /// Grid axes in order.
    pub varied: Vec<String>,
    /// The accepted specification.
    #[schema(value_type = Object)]
    pub spec: Value,
    /// Fraction of the sweep done (cases with a result or failed, plus
    /// running fractions; a cancelled case without a result is not done).
    pub progress: f64,
    /// Estimated seconds to the end (null when unknown or done).
    pub eta_seconds: Option<f64>,
    /// Cases whose result was reused from an earlier computation.
    pub cached: i64,
    /// The cases in grid order; served a page at a time by
    /// `GET /api/sweeps/{id}/cases`, not with the sweep, so that polling a
    /// sweep of any size stays small.
    #[serde(skip)]
    pub cases: Vec<SweepCaseView>,
}

/// Answer to a submission: the sweep, and whether it was an idempotent replay.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SubmitResponse {
    /// The `Idempotency-Key` was seen before: this is the first sweep.
    pub replayed: bool,
    #[serde(flatten)]
    pub sweep: SweepDetail,
}

/// One point of a phase diagram.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct PhasePoint {
    pub case_id: i64,
    /// The knot the case ties: `"overhand n = 3"`, `"figure_eight"`,
    /// `"braid s1 s1 s1"`.
    pub knot: String,
    /// The varied parameters' values (e.g. `{"h": 0.0016}`).
    #[schema(value_type = BTreeMap<String, Object>)]
    pub params: BTreeMap<String, Value>,
    /// Status word of the case.
    #[schema(value_type = String)]
    pub status: CaseStatus,
    /// The inversion point, or null (see `reason`).
    pub inversion: Option<InversionPoint>,
    /// Null when there is an inversion; otherwise why not: no inversion before
    /// the stop condition, the solver's reason for failing, not computed yet, ...
    pub reason: Option<String>,
    /// The simplified model's snap-through l_k bar at this case's n and h
    /// (paper Sec. 5, Figs 14 and 15: epsilon = 0.7, phi = pi/3, no contact or
    /// friction); null where the model has no snap (n = 1).
    pub simplified_l_k_bar: Option<f64>,
    /// In a certified sweep, the inversion's numerical uncertainty from the
    /// refined twin; null otherwise.
    pub uncertainty: Option<UncertaintyView>,
    /// Where the program loosens after the inversion: the loop's flip back
    /// and the hysteresis width; null otherwise.
    #[schema(value_type = Option<Object>)]
    pub hysteresis: Option<Hysteresis>,
    /// Every event of the case's program (stage, direction, kind, l_k bar,
    /// F bar and H bar around it, clean).
    #[schema(value_type = Vec<Object>)]
    pub events: Vec<Event>,
    /// A bend's holding force: the largest F bar before its rods parted
    /// (its `slip_through` event's), or the largest it held when they held
    /// to the end; null for a knot in one rod or before the result.
    pub holding_force_bar: Option<f64>,
    /// A bend's rods still hold each other at the end; null for a knot in
    /// one rod or before the result.
    pub tied: Option<bool>,
    /// Whether the loading stayed quasi-static (kinetic over elastic energy
    /// against its limit); null before the result, or for results stored
    /// before it was measured.
    #[schema(value_type = Option<Object>)]
    pub quasi_static: Option<QuasiStatic>,
}

/// The phase diagram of a sweep: for each case its varied parameters, status
/// and inversion point, in grid order. Paper Figs 7, 9 and 11 plot
/// `inversion.l_k_bar` (and `inversion.l_c_over_l`) against the one varied
/// parameter (`h`, `n` or `mu`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct PhaseDiagram {
    pub sweep_id: i64,
    pub name: Option<String>,
    pub preset: Option<String>,
    pub status: SweepStatus,
    /// True when every case has finished (a result or a failure); false
    /// while cases run and when some were cancelled without a result.
    pub complete: bool,
    /// Grid axes in order.
    pub varied: Vec<String>,
    /// The parameters shared by every case (full CaseParams of the base).
    #[schema(schema_with = crate::openapi::case_params_ref)]
    pub base: Value,
    pub solver_version: String,
    /// The physics revision the points were computed under (part of every
    /// case's cache key; `solver::case::PHYSICS_REVISION`).
    pub physics_revision: u32,
    /// Every point carries its `uncertainty` (the sweep asked to `certify`).
    pub certified: bool,
    pub points: Vec<PhasePoint>,
}

/// A stored result (without the series and snapshots).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ResultView {
    /// The solver's status.
    #[schema(value_type = String)]
    pub outcome: Status,
    pub reason: String,
    pub inversion: Option<InversionPoint>,
    /// Determinants and solver statistics.
    #[schema(value_type = Object)]
    pub summary: ResultDetails,
    pub wall_time: f64,
    /// Lease owner that computed it.
    pub worker: String,
    pub created_at: i64,
}

/// A per-case log line.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct LogLineView {
    pub at: i64,
    pub level: String,
    pub message: String,
}

/// Everything about a case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct CaseDetail {
    pub id: i64,
    /// blake3 of the canonical parameters and the solver version.
    pub key: String,
    pub solver_version: String,
    #[schema(schema_with = crate::openapi::case_params_ref)]
    pub params: Value,
    /// The node count K the case runs with (`params.nodes`, or its default
    /// when that is null).
    pub nodes: usize,
    #[schema(value_type = String)]
    pub status: CaseStatus,
    /// Queue state: queued, running, done, failed, cancelled.
    #[schema(value_type = String)]
    pub state: CaseState,
    pub attempts: u32,
    pub max_attempts: u32,
    pub progress: f64,
    pub progress_detail: Option<CaseProgress>,
    pub lease_owner: Option<String>,
    pub lease_expires_at: Option<i64>,
    pub last_error: Option<String>,
    pub created_at: i64,
    pub started_at: Option<i64>,
    pub finished_at: Option<i64>,
    /// Sweeps that asked for this case.
    pub sweeps: Vec<i64>,
    pub result: Option<ResultView>,
    /// The tightening series (one object per sample, named as the columns of
    /// `series.csv`: time, l_k_bar, l_k_arc_bar, l_c_over_L, F, F_bar, W, H, H_bar,
    /// kinetic_energy (peak since the previous sample), contacts,
    /// active_contacts, max_penetration_over_h, epsilon, phi,
    /// newton_iterations, dt), null before the result.
    #[schema(value_type = Option<Vec<Object>>)]
    pub series: Option<Vec<Sample>>,
    pub logs: Vec<LogLineView>,
    pub links: BTreeMap<String, String>,
}

/// `/healthz`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct Health {
    /// `ok`, or `degraded` (database unreachable or a worker stopped polling).
    pub status: String,
    pub database: bool,
    /// Embedded worker slots (0: none).
    pub workers: usize,
    /// Embedded worker slots that stopped polling (should be empty).
    pub stalled_workers: Vec<usize>,
    pub solver_version: String,
    pub uptime_seconds: f64,
}

/// A running case in a progress event.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct RunningCase {
    pub case_id: i64,
    pub progress: f64,
    pub l_k_bar: Option<f64>,
}

/// Data of a server-sent `progress` event (and of the final `done` event).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SweepEvent {
    pub sweep_id: i64,
    pub status: SweepStatus,
    pub total: i64,
    #[schema(value_type = BTreeMap<String, i64>)]
    pub counts: BTreeMap<CaseStatus, i64>,
    pub progress: f64,
    pub eta_seconds: Option<f64>,
    pub running: Vec<RunningCase>,
}

impl From<&SweepDetail> for SweepEvent {
    fn from(d: &SweepDetail) -> Self {
        Self {
            sweep_id: d.summary.id,
            status: d.summary.status,
            total: d.summary.total,
            counts: d.summary.counts.clone(),
            progress: d.progress,
            eta_seconds: d.eta_seconds,
            running: d
                .cases
                .iter()
                .filter(|c| c.status == CaseStatus::RUNNING)
                .map(|c| RunningCase {
                    case_id: c.case_id,
                    progress: c.progress,
                    l_k_bar: c.progress_detail.map(|p| p.l_k_bar),
                })
                .collect(),
        }
    }
}

/// One event of a sweep's stream ([`crate::core::Core::events`]).
#[derive(Clone, Debug, PartialEq)]
pub enum SweepUpdate {
    /// The sweep changed.
    Progress(SweepEvent),
    /// The sweep is finished or cancelled: the stream's last event.
    Done(SweepEvent),
}

impl SweepUpdate {
    /// The server-sent event's name: `progress` or `done`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Progress(_) => "progress",
            Self::Done(_) => "done",
        }
    }

    pub fn event(&self) -> &SweepEvent {
        match self {
            Self::Progress(e) | Self::Done(e) => e,
        }
    }
}

impl From<&Progress> for CaseProgress {
    fn from(p: &Progress) -> Self {
        Self {
            fraction: p.fraction,
            l_k_bar: p.l_k_bar,
            h_bar: p.h_bar,
            steps: p.steps,
        }
    }
}

/// The solver's progress of a running case; none once it has stopped running
/// (a finished case's last heartbeat is not its progress).
fn progress_of(c: &CaseRecord) -> Option<CaseProgress> {
    if c.state != CaseState::Running {
        return None;
    }
    c.progress_detail.as_ref().map(CaseProgress::from)
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

fn status_of(state: SweepState, counts: &BTreeMap<CaseStatus, i64>) -> SweepStatus {
    let open = |status| counts.get(&status).copied().unwrap_or(0);
    let (queued, running) = (open(CaseStatus::QUEUED), open(CaseStatus::RUNNING));
    match state {
        SweepState::Cancelled => SweepStatus::Cancelled,
        _ if queued + running == 0 => SweepStatus::Done,
        SweepState::Paused => SweepStatus::Paused,
        SweepState::Active if running == 0 && counts.values().sum::<i64>() == queued => SweepStatus::Queued,
        SweepState::Active => SweepStatus::Running,
    }
}

/// A sweep and its cases per status word.
impl From<(&SweepRecord, BTreeMap<CaseStatus, i64>)> for SweepSummary {
    fn from((s, counts): (&SweepRecord, BTreeMap<CaseStatus, i64>)) -> Self {
        let status = status_of(s.state, &counts);
        Self {
            id: s.id,
            name: s.name.clone(),
            preset: s.preset.clone(),
            state: match status {
                SweepStatus::Done => "done",
                _ => s.state.as_str(),
            }
            .to_string(),
            status,
            total: counts.values().sum(),
            counts,
            created_at: s.created_at,
            links: links(s.id),
        }
    }
}

/// Why a case has no inversion point (None when it has one).
fn reason_of(c: &CaseRecord) -> Option<String> {
    match (&c.result, c.state) {
        (Some(r), _) if r.inversion.is_some() => None,
        (Some(r), _) if r.outcome == Status::Completed => Some(match c.params.max_force_bar {
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
        (None, CaseState::Failed) => Some(
            c.last_error
                .clone()
                .unwrap_or_else(|| CaseState::Failed.as_str().to_string()),
        ),
        (None, CaseState::Cancelled) => Some(CaseState::Cancelled.as_str().to_string()),
        (None, CaseState::Queued) => Some(match &c.last_error {
            Some(e) => format!("not computed yet (queued; last attempt: {e})"),
            None => "not computed yet (queued)".to_string(),
        }),
        (None, CaseState::Running) => Some("not computed yet (running)".to_string()),
        (None, CaseState::Done) => Some("result missing".to_string()),
    }
}

/// A sweep's case with the values of the sweep's varied parameters.
impl From<(&SweepCase, &[String])> for SweepCaseView {
    fn from((s, varied): (&SweepCase, &[String])) -> Self {
        let c = &s.case;
        let params = serde_json::to_value(&c.params).expect("params serialise");
        Self {
            case_id: c.id,
            position: s.position,
            params: varied
                .iter()
                .map(|name| (name.clone(), varied_value(name, &c.params, &params)))
                .collect(),
            status: c.status(),
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
            twin_of: None,
        }
    }
}

/// A case's value of the grid axis `name`: its parameter, for the material
/// axis the named material whose constants it has, for the knot axis the
/// knot's label (`"overhand n = 2"`).
fn varied_value(name: &str, params: &solver::case::CaseParams, json: &Value) -> Value {
    if name == crate::spec::KNOT_AXIS {
        return Value::from(params.knot_label());
    }
    if name == crate::spec::MATERIAL_AXIS {
        let found = solver::case::MATERIALS.iter().find(|m| {
            (m.youngs_modulus, m.density, m.poisson_ratio)
                == (params.youngs_modulus, params.density, params.poisson_ratio)
        });
        return found.map_or(Value::Null, |m| Value::from(m.name));
    }
    json.get(name).cloned().unwrap_or(Value::Null)
}

/// A sweep's point (one of its first [`crate::spec::points`] cases) and, in a
/// certified sweep, its refined twin ([`solver::certify::refined`]).
pub struct Point<'a> {
    pub case: &'a SweepCase,
    pub twin: Option<&'a SweepCase>,
}

/// The sweep's stored specification; `Corrupt` when it no longer parses.
pub fn stored_spec(record: &SweepRecord) -> Result<crate::spec::SweepSpec, StoreError> {
    serde_json::from_value(record.spec.clone()).map_err(|source| StoreError::Json {
        what: format!("sweep {}'s specification", record.id),
        source,
    })
}

/// The points of a sweep of `cases` (in position order) and whether it is
/// certified. A point's twin is the case at the position stored with the
/// point at submission; in a certified sweep stored before that relation
/// was, the case with the point's refined parameters (never its cache key,
/// which changes with the physics revision).
pub fn points<'a>(
    record: &SweepRecord,
    cases: &'a [SweepCase],
) -> Result<(Vec<Point<'a>>, bool), StoreError> {
    let spec = stored_spec(record)?;
    let count = crate::spec::points(&spec);
    let certified = spec.certify == Some(true);
    let at: HashMap<i64, &SweepCase> = cases.iter().map(|c| (c.position, c)).collect();
    let unrelated = certified && cases.iter().all(|c| c.twin_position.is_none());
    let by_params: HashMap<String, &SweepCase> = match unrelated {
        true => (cases.iter())
            .map(|c| (knotsweep_worker::key::canonical_json(&c.case.params), c))
            .collect(),
        false => HashMap::new(),
    };
    let twin = |case: &SweepCase| match case.twin_position {
        Some(position) => at.get(&position).copied(),
        None if unrelated => {
            let refined = solver::certify::refined(&case.case.params);
            by_params
                .get(&knotsweep_worker::key::canonical_json(&refined))
                .copied()
        }
        None => None,
    };
    let points = cases
        .iter()
        .filter(|c| (c.position as usize) < count)
        .map(|case| Point {
            case,
            twin: twin(case),
        })
        .collect();
    Ok((points, certified))
}

/// The numerical uncertainty of a certified point: its refined twin's
/// inversion against its own (`solver::certify::Uncertainty`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct UncertaintyView {
    /// The refined twin (time step halved).
    pub refined_case_id: i64,
    /// The twin's inversion l_k bar (null without one, or until both have a result).
    pub refined_l_k_bar: Option<f64>,
    /// |refined - default| in l_k bar (null unless both inverted).
    pub absolute: Option<f64>,
    /// `absolute` over the point's l_k bar.
    pub relative: Option<f64>,
    /// `relative` at most `converged_within` (`GET /api/limits`); false when
    /// only one of the two inverted; null until both have a result.
    pub converged: Option<bool>,
}

impl UncertaintyView {
    fn new(point: &CaseRecord, twin: &CaseRecord) -> Self {
        let inversion = |c: &CaseRecord| c.result.as_ref().and_then(|r| r.inversion);
        // Compared only once both have a result (the twin may finish first).
        let refined = (point.result.is_some() && twin.result.is_some()).then(|| inversion(twin));
        let u = solver::certify::Uncertainty::new(
            inversion(point).as_ref(),
            refined.as_ref().map(Option::as_ref),
        );
        Self {
            refined_case_id: twin.id,
            refined_l_k_bar: u.refined_l_k_bar,
            absolute: u.absolute,
            relative: u.relative,
            converged: u.converged,
        }
    }
}

/// Whether a case is done for its sweep: a result, or out of attempts (a
/// case cancelled without a result is not).
fn finished(c: &SweepCase) -> bool {
    c.case.state.is_terminal() && c.case.state != CaseState::Cancelled
}

/// Cases per status.
fn status_counts(cases: &[SweepCase]) -> BTreeMap<CaseStatus, i64> {
    let mut counts: BTreeMap<CaseStatus, i64> = BTreeMap::new();
    for c in cases {
        *counts.entry(c.case.status()).or_default() += 1;
    }
    counts
}

impl SweepDetail {
    /// The detail of a sweep from its record and its cases (in position order).
    pub fn new(record: &SweepRecord, cases: &[SweepCase]) -> Result<Self, StoreError> {
        let counts = status_counts(cases);
        let total = cases.len().max(1) as f64;
        let finished = cases.iter().filter(|c| finished(c)).count() as f64;
        let running_done: f64 = cases
            .iter()
            .filter(|c| c.case.state == CaseState::Running)
            .map(|c| c.case.progress)
            .sum();
        let summary = SweepSummary::from((record, counts));
        let eta_seconds = match summary.status {
            SweepStatus::Running | SweepStatus::Queued => eta(cases),
            _ => None,
        };
        // Twin case id -> its point's (a twin that is itself a point is listed as a point).
        let (points, _) = points(record, cases)?;
        let is_point: HashSet<i64> = points.iter().map(|p| p.case.case.id).collect();
        let twin_of: HashMap<i64, i64> = (points.iter())
            .filter_map(|p| Some((p.twin?.case.id, p.case.case.id)))
            .filter(|(twin, _)| !is_point.contains(twin))
            .collect();
        Ok(Self {
            varied: record.varied.clone(),
            spec: record.spec.clone(),
            progress: ((finished + running_done) / total).clamp(0.0, 1.0),
            eta_seconds,
            cached: cases.iter().filter(|c| c.cached).count() as i64,
            cases: cases
                .iter()
                .map(|c| SweepCaseView {
                    twin_of: twin_of.get(&c.case.id).copied(),
                    ..SweepCaseView::from((c, &record.varied[..]))
                })
                .collect(),
            summary,
        })
    }
}

/// Seconds left: the remaining work (queued cases and running remainders)
/// times the mean case duration (from the sweep's results, else from the
/// running cases' speed), over the cases running in parallel; none while
/// nothing runs.
fn eta(cases: &[SweepCase]) -> Option<f64> {
    let running: Vec<&CaseRecord> = cases
        .iter()
        .map(|c| &c.case)
        .filter(|c| c.state == CaseState::Running)
        .collect();
    if running.is_empty() {
        return None;
    }
    let durations: Vec<f64> = cases
        .iter()
        .filter(|c| !c.cached)
        .filter_map(|c| c.case.result.as_ref().map(|r| r.wall_time))
        .collect();
    let now = knotsweep_worker::store::now_ms();
    let mean = if durations.is_empty() {
        let speeds: Vec<f64> = running
            .iter()
            .filter(|c| c.progress > 0.02)
            .filter_map(|c| c.started_at.map(|t| (now - t) as f64 / 1000.0 / c.progress))
            .collect();
        (!speeds.is_empty()).then(|| speeds.iter().sum::<f64>() / speeds.len() as f64)
    } else {
        Some(durations.iter().sum::<f64>() / durations.len() as f64)
    }?;
    let queued = cases.iter().filter(|c| c.case.state == CaseState::Queued).count() as f64;
    let running_done: f64 = running.iter().map(|c| c.progress).sum();
    let remaining = queued + running.len() as f64 - running_done;
    Some(remaining * mean / running.len() as f64)
}

impl From<&ResultSummary> for ResultView {
    fn from(r: &ResultSummary) -> Self {
        Self {
            outcome: r.outcome,
            reason: r.reason.clone(),
            inversion: r.inversion.as_ref().map(InversionPoint::from),
            summary: r.summary.clone(),
            wall_time: r.wall_time,
            worker: r.worker.clone(),
            created_at: r.created_at,
        }
    }
}

impl From<LogLine> for LogLineView {
    fn from(l: LogLine) -> Self {
        Self {
            at: l.at,
            level: l.level,
            message: l.message,
        }
    }
}

impl CaseDetail {
    /// A case with the sweeps that asked for it, its stored series (if any)
    /// and its log lines.
    pub fn new(c: &CaseRecord, sweeps: Vec<i64>, series: Option<Vec<Sample>>, logs: Vec<LogLine>) -> Self {
        let id = c.id;
        let links = BTreeMap::from([
            ("self".to_string(), format!("/api/cases/{id}")),
            ("series_csv".to_string(), format!("/api/cases/{id}/series.csv")),
            ("snapshots".to_string(), format!("/api/cases/{id}/snapshots")),
        ]);
        Self {
            id,
            key: c.key.clone(),
            solver_version: c.solver_version.clone(),
            params: serde_json::to_value(&c.params).expect("params serialise"),
            nodes: c.params.node_count(),
            status: c.status(),
            state: c.state,
            attempts: c.attempts,
            max_attempts: c.max_attempts,
            progress: c.progress,
            progress_detail: progress_of(c),
            lease_owner: c.lease_owner.clone(),
            lease_expires_at: c.lease_expires_at,
            last_error: c.last_error.clone(),
            created_at: c.created_at,
            started_at: c.started_at,
            finished_at: c.finished_at,
            sweeps,
            result: c.result.as_ref().map(ResultView::from),
            series,
            logs: logs.into_iter().map(LogLineView::from).collect(),
            links,
        }
    }
}

impl PhaseDiagram {
    /// The phase diagram of a sweep: `base` its full base parameters,
    /// `simplified` the simplified model's snap for each point (grid order).
    pub fn new(
        record: &SweepRecord,
        cases: &[SweepCase],
        base: Value,
        simplified: Vec<Option<f64>>,
    ) -> Result<Self, StoreError> {
        let (points, certified) = points(record, cases)?;
        Ok(Self {
            sweep_id: record.id,
            name: record.name.clone(),
            preset: record.preset.clone(),
            status: SweepSummary::from((record, status_counts(cases))).status,
            complete: cases.iter().all(finished),
            varied: record.varied.clone(),
            base,
            solver_version: knotsweep_worker::SOLVER_VERSION.to_string(),
            physics_revision: solver::case::PHYSICS_REVISION,
            certified,
            points: (points.iter().zip(simplified))
                .map(|(point, simplified_l_k_bar)| {
                    let c = SweepCaseView::from((point.case, &record.varied[..]));
                    PhasePoint {
                        case_id: c.case_id,
                        knot: point.case.case.params.knot_label(),
                        params: c.params,
                        status: c.status,
                        inversion: c.inversion,
                        reason: c.reason,
                        simplified_l_k_bar,
                        uncertainty: point
                            .twin
                            .map(|t| UncertaintyView::new(&point.case.case, &t.case)),
                        hysteresis: details(point.case).and_then(|d| d.hysteresis),
                        holding_force_bar: details(point.case).and_then(|d| d.holding_force_bar),
                        tied: details(point.case).and_then(|d| d.tied),
                        events: details(point.case).map(|d| d.events.clone()).unwrap_or_default(),
                        quasi_static: details(point.case).and_then(|d| d.quasi_static),
                    }
                })
                .collect(),
        })
    }
}

/// A case's stored result details, none before its result.
fn details(case: &SweepCase) -> Option<&ResultDetails> {
    case.case.result.as_ref().map(|r| &r.summary)
}

/// What `/metrics` reports besides the embedded workers' own counters.
pub struct Metrics {
    /// Cases per status, across every process.
    pub cases: BTreeMap<CaseStatus, i64>,
    /// Queued cases of active sweeps.
    pub queue_depth: i64,
    /// Sweeps per status.
    pub sweeps: BTreeMap<SweepStatus, usize>,
    /// Embedded worker slots.
    pub workers: usize,
}

impl Metrics {
    /// Prometheus text exposition (`let _ =`: writing to a `String` cannot fail).
    pub fn render(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "# HELP knotsweep_cases Cases by status.\n# TYPE knotsweep_cases gauge"
        );
        for status in CaseStatus::all() {
            let _ = writeln!(
                out,
                "knotsweep_cases{{status=\"{status}\"}} {}",
                self.cases.get(&status).copied().unwrap_or(0)
            );
        }
        let _ = writeln!(
            out,
            "# HELP knotsweep_queue_depth Queued cases of active sweeps.\n# TYPE knotsweep_queue_depth gauge\nknotsweep_queue_depth {}",
            self.queue_depth
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
            let n = self.sweeps.get(&status).copied().unwrap_or(0);
            let word = serde_json::to_value(status).expect("status serialises");
            let _ = writeln!(
                out,
                "knotsweep_sweeps{{status=\"{}\"}} {n}",
                word.as_str().expect("a status is a word")
            );
        }
        let _ = writeln!(
            out,
            "# HELP knotsweep_workers Embedded worker slots.\n# TYPE knotsweep_workers gauge\nknotsweep_workers {}",
            self.workers
        );
        out
    }
}
