//! The API's response types (JSON), documented in the OpenAPI document.
//!
//! Status words of a case (`status`): `queued`, `running`, `failed` (out of
//! attempts after infrastructure failures), `cancelled`, or, once it has a
//! result, the solver's status: `completed`, `invalid`, `diverged`,
//! `penetrated`, `topology_changed`. Times are Unix milliseconds.
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;
use utoipa::ToSchema;

/// Status words of a whole sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum SweepStatus {
    /// Nothing has started yet.
    Queued,
    /// Some cases are running or queued.
    Running,
    /// Paused with cases left (running ones finish).
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
    /// l_c / L at the inversion.
    pub l_c_over_l: f64,
    /// F bar = F h^2 / EI just before the drop and its minimum just after.
    #[serde(rename = "F_bar_before")]
    pub f_bar_before: f64,
    #[serde(rename = "F_bar_after")]
    pub f_bar_after: f64,
    /// H bar before and after the drop.
    pub h_bar_before: f64,
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
    pub h_bar: f64,
    pub steps: u64,
}

/// A sweep in a list.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SweepSummary {
    pub id: i64,
    pub name: Option<String>,
    pub preset: Option<String>,
    /// `active`, `paused` or `cancelled` (what was asked).
    pub state: String,
    /// Where the sweep is.
    pub status: SweepStatus,
    /// Number of cases.
    pub total: i64,
    /// Cases per status word.
    pub counts: BTreeMap<String, i64>,
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
    pub status: String,
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
    /// Fraction of the sweep done (finished cases plus running fractions).
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
    /// The varied parameters' values (e.g. `{"h": 0.0016}`).
    #[schema(value_type = BTreeMap<String, Object>)]
    pub params: BTreeMap<String, Value>,
    /// Status word of the case.
    pub status: String,
    /// The inversion point, or null (see `reason`).
    pub inversion: Option<InversionPoint>,
    /// Null when there is an inversion; otherwise why not: no inversion before
    /// the stop condition, the solver's reason for failing, not computed yet, ...
    pub reason: Option<String>,
    /// The simplified model's snap-through l_k bar at this case's n and h
    /// (paper Sec. 5, Figs 14 and 15: epsilon = 0.7, phi = pi/3, no contact or
    /// friction); null where the model has no snap (n = 1).
    pub simplified_l_k_bar: Option<f64>,
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
    /// True when every case has finished (result, failure or cancellation).
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
    pub points: Vec<PhasePoint>,
}

/// A stored result (without the series and frames).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ResultView {
    /// The solver's status.
    pub outcome: String,
    pub reason: String,
    pub inversion: Option<InversionPoint>,
    /// Determinants and solver statistics.
    #[schema(value_type = Object)]
    pub summary: Value,
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
    pub status: String,
    /// Queue state: queued, running, done, failed, cancelled.
    pub state: String,
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
    /// The tightening series (one object per sample: time, l_k_bar,
    /// l_c_over_l, force, f_bar, width, height, h_bar, kinetic_energy (peak since the previous sample),
    /// contacts, active_contacts, max_penetration_over_h, epsilon, phi, newton_iterations, dt), null
    /// before the result.
    #[schema(value_type = Option<Vec<Object>>)]
    pub series: Option<Value>,
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
    pub counts: BTreeMap<String, i64>,
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
                .filter(|c| c.status == knotsweep_worker::store::CaseState::Running.as_str())
                .map(|c| RunningCase {
                    case_id: c.case_id,
                    progress: c.progress,
                    l_k_bar: c.progress_detail.map(|p| p.l_k_bar),
                })
                .collect(),
        }
    }
}
