//! The tightening protocol of paper Sec. 4: build the knot, clamp both ends
//! (equal material frames, no relative rotation), relax with the ends held,
//! then pull the clamps apart along the line joining them at a steady speed,
//! sampling the measurements of eq. (11) at a fixed interval of l_k bar.
use crate::case::{CaseParams, ParamError, Protocol, Scales, ValidCase};
use crate::contact::gauss_seidel::GaussSeidelOptions;
use crate::external::{Environment, sliding};
use crate::knot;
use crate::material::Material;
use crate::measurements::{self, Inversion, InversionCriteria, Sample};
use crate::pipeline::{ContactOptions, World, WorldStepReport};
use crate::rod::{End, Rod};
use crate::stepper::NewtonOptions;
use crate::time_step::{AdaptiveOptions, TimeStep};
use crate::words::display_as_word;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// How a case ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Ran to its stop condition; the result is valid.
    Completed,
    /// Parameters out of range or no knot can be built with them.
    Invalid,
    /// A time step failed even after time-step reductions.
    Diverged,
    /// Penetration beyond half the radius: contact was lost.
    Penetrated,
    /// The knot type changed (strands passed through each other).
    TopologyChanged,
    /// Stopped by the caller.
    Cancelled,
}

display_as_word!(Status, Stage);

impl Status {
    /// Every solver status, in the order reports list them.
    pub const ALL: [Status; 6] = [
        Status::Completed,
        Status::Invalid,
        Status::Diverged,
        Status::Penetrated,
        Status::TopologyChanged,
        Status::Cancelled,
    ];
}

/// [`Protocol::Adaptive`]: the largest friction coefficient it runs fast
/// at; above it the whole pull is the reference's. Under physics revision 5
/// (friction at the centre lines, the paper's start twist) every Fig. 11 case
/// (h = 3.4 mm, mu = 0.1 ... 0.7) snaps cleanly and the adaptive pull lands
/// within 0.3 % of the reference's at each (BENCHMARKS.md, "Physics revision
/// 6"); larger frictions were not measured. (Under revision 4's rolling
/// strands the fast approaches landed 1.8-17 % off at mu = 0.3-0.7.)
pub const ADAPTIVE_MAX_MU: f64 = 0.7;
/// [`Protocol::Adaptive`]: the largest simulated pull rate, over the paper's
/// rod's, it runs fast at; above it the whole pull is the reference's. Its
/// fast approach is quasi-static enough at the paper's rate (the inversion
/// within 0.2 % of the reference's); at 3.3 times that rate (the paper's rod
/// at 1 cm/s with its physical inertia) it lands 0.5 % from the reference
/// pull at that rate (BENCHMARKS.md, "Any rod", the rates table). The
/// default pull and mass scaling bring every rod to the paper's rate.
pub const ADAPTIVE_MAX_RATE: f64 = 3.5;
/// Whether `params` pull fast far from the snap: [`Protocol::Adaptive`] up
/// to [`ADAPTIVE_MAX_MU`] and [`ADAPTIVE_MAX_RATE`].
pub fn pulls_fast(params: &CaseParams) -> bool {
    params.protocol == Protocol::Adaptive
        && params.mu <= ADAPTIVE_MAX_MU
        && params.scales().pull_rate_ratio <= ADAPTIVE_MAX_RATE
}

/// A case's cost in node-steps, to the order of magnitude: a pull over the
/// rod's length at `pull_speed` and the largest step, each step linear in
/// the node count, `FAST_FACTOR` times fewer steps when the approach runs
/// fast. Queues hand out the costliest cases first, so that a long case does
/// not start last and leave the other workers idle.
pub fn work_estimate(params: &CaseParams) -> f64 {
    let steps = params.length / (params.clamp_speed() * params.time_step());
    let fast = if pulls_fast(params) { FAST_FACTOR } else { 1.0 };
    steps * params.node_count() as f64 / fast
}

/// [`Protocol::Adaptive`]: speed-up far from the snap.
const FAST_FACTOR: f64 = 16.0;
/// [`Protocol::Adaptive`]: the largest time step while fast, over the case's.
const FAST_DT_FACTOR: f64 = 4.0;
/// [`Protocol::Adaptive`]: checkpoint spacing in l_k bar while fast.
const CHECKPOINT_SPACING: f64 = 2.0;
/// [`Protocol::Adaptive`]: how far (l_k bar) before the fast pull's snap the
/// slow pull restarts (the fast pull snaps late: n = 3 by 3, n = 5 by 5), and
/// how much further back each retry goes. The slow pull needs a few l_k bar to
/// take over from the settled state: restarting 6 before moved n = 3's
/// inversion by -0.65 % and n = 5's by -0.91 %, 8 before n = 3's by -0.17 %
/// (BENCHMARKS.md, "Physics revision 7").
const RESTART_BEFORE: f64 = 8.0;
/// [`Protocol::Adaptive`]: a slow pull that snaps within this much l_k bar of
/// its restart started past the fold, and is retried from further back.
const MIN_LEAD: f64 = 2.0;
/// [`Protocol::Adaptive`]: how far (l_k bar) past the snap the pull stays slow.
const SLOW_AFTER: f64 = 1.0;
/// [`Protocol::Adaptive`]: clamp speed over `pull_speed` through the snap:
/// the reference's. At twice it the reference moves the n = 3 inversion by
/// only 0.07 %, but the K = 158, mu = 0.2 one by 1.7 % (BENCHMARKS.md).
const SNAP_FACTOR: f64 = 1.0;
/// [`Protocol::Adaptive`]: the contact solve's tolerance while fast, when the
/// case's is tighter.
const FAST_CONTACT_TOLERANCE: f64 = 1e-4;
/// [`Protocol::Adaptive`]: the approach ramps its speed up over this much
/// l_k bar (a sudden start shakes the knot), the stage after the snap over
/// `RAMP_AFTER`.
const RAMP: f64 = 4.0;
const RAMP_AFTER: f64 = 2.0;
/// [`Protocol::Adaptive`]: longest settling (s, in the case's time unit) after going back to a checkpoint.
const SETTLE_TIME: f64 = 0.5;
/// [`Protocol::Adaptive`]: how far (l_k bar) past the fast pull's snap the
/// snap stage goes on without one before it takes that snap for the fast
/// pull's own swinging and approaches fast again.
const FALSE_ALARM: f64 = 10.0;
/// [`Protocol::Adaptive`]: how much of the pull's end (l_k bar) is redone at
/// the snap speed when the fast approach reaches it without a snap (its lag
/// and swinging may hide one there).
const END_REVIEW: f64 = 20.0;
/// [`Protocol::Adaptive`]: a fall of H bar to `SMEARED_FALL` of its largest
/// value within `SMEARED_WINDOW` (l_k bar), from `SMEARED_START` of it over
/// more than `SMEARED_SPAN`, is a snap the fast approach smeared out
/// ([`smeared_snap`]). Steady tightening lowers H bar by about 10 % over the
/// window (n = 3: 0.59 at l_k bar 431 to 0.24 at 141).
const SMEARED_FALL: f64 = 0.4;
const SMEARED_START: f64 = 0.9;
const SMEARED_WINDOW: f64 = 20.0;
const SMEARED_SPAN: f64 = 5.0;
/// [`Protocol::Adaptive`]: checkpoints kept (they span several retries of
/// `RESTART_BEFORE`).
const CHECKPOINTS: usize = 24;

pub use crate::snapshot::{Snapshot, SnapshotContact};

/// Counts and timings of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    pub steps: u64,
    pub newton_iterations: u64,
    /// Contact-solve sweeps summed over the pulling steps.
    pub contact_sweeps: u64,
    pub relax_steps: u64,
    /// Steps redone with half the step (adaptive time step).
    pub rejected_steps: u64,
    /// Smallest time step taken (s).
    pub smallest_dt: f64,
    /// Wall time (s) of the whole case and per stage.
    pub wall_time: f64,
    pub detection_time: f64,
    pub contact_time: f64,
    pub dynamics_time: f64,
}

/// The result of one case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CaseReport {
    pub status: Status,
    /// Why the case ended that way (empty when completed).
    pub reason: String,
    pub params: CaseParams,
    /// Knot determinant of the initial shape and at the end (2n + 1 expected).
    pub determinant_initial: Option<u64>,
    pub determinant_final: Option<u64>,
    /// Writhe of the start shape (closed by tails along the pull axis) and
    /// the twist (turns) it started with (`start_twist`, or the paper's code's).
    #[serde(default)]
    pub writhe: f64,
    #[serde(default)]
    pub start_twist: f64,
    /// The inversion point, `None` when H bar never snapped.
    pub inversion: Option<Inversion>,
    pub series: Vec<Sample>,
    /// The knot's states kept for viewers (stored as `frames` before they
    /// were called snapshots).
    #[serde(alias = "frames")]
    pub snapshots: Vec<Snapshot>,
    pub stats: Stats,
    /// The run's stages in order, with their steps (empty in reports stored
    /// before they were recorded).
    #[serde(default)]
    pub stages: Vec<StageSpan>,
    /// How the case was computed: time step, inertia and rates (absent from
    /// reports stored before physics revision 8).
    #[serde(default)]
    pub scaling: Option<Scaling>,
    /// Whether the pull was quasi-static, measured (absent before physics
    /// revision 8, and where no sample was pulled at `pull_speed`).
    #[serde(default)]
    pub quasi_static: Option<QuasiStatic>,
}

/// How a case was computed ([`CaseParams::scales`], [`CaseParams::time_step`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scaling {
    /// The largest time step (s).
    pub time_step: f64,
    /// The factor on the density in the inertia (1: the physical inertia).
    pub mass_scale: f64,
    /// The case's time over the paper's rod's.
    pub time_unit: f64,
    /// The pull rate pull_speed / sqrt(E / rho), physical and simulated (the
    /// paper's rod: 7.1e-5).
    pub pull_rate: f64,
    pub simulated_pull_rate: f64,
}

impl Scaling {
    fn of(params: &CaseParams) -> Self {
        let scales = params.scales();
        Self {
            time_step: params.time_step(),
            mass_scale: scales.mass_scale,
            time_unit: scales.time_unit,
            pull_rate: params.pull_rate(),
            simulated_pull_rate: scales.pull_rate_ratio * crate::case::reference_pull_rate(),
        }
    }
}

/// The largest median kinetic-to-elastic energy ratio of a quasi-static
/// pull. The paper's rod under the reference pull with its physical inertia:
/// at 3 mm/s 6.7e-4 (inversion at 136.38), at 1 cm/s 3.4e-3 (136.06,
/// -0.2 %), at 3 cm/s 8.3e-3 (134.57, -1.3 %), at 6 cm/s 3.0e-2 (130.95,
/// -4 %) (BENCHMARKS.md, "Any rod", the rates table).
pub const QUASI_STATIC_LIMIT: f64 = 5e-3;

/// The measured quasi-staticity of a pull: the kinetic energy (each
/// sample's largest since the one before) over the elastic energy, median
/// over the samples pulled at `pull_speed` (stages `reference` and `snap`)
/// before the inversion. A snap and the stick-slip of friction are dynamic
/// events of a quasi-static pull: the median sees past them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct QuasiStatic {
    pub kinetic_ratio: f64,
    /// [`QUASI_STATIC_LIMIT`].
    pub limit: f64,
    /// `kinetic_ratio` is at most `limit`.
    pub holds: bool,
}

impl QuasiStatic {
    /// Of a report's series, or `None` without samples pulled at `pull_speed`.
    fn of(report: &CaseReport) -> Option<Self> {
        let energy_unit = report.params.bending_stiffness() / report.params.h;
        let before = report.inversion.map_or(f64::NEG_INFINITY, |i| i.l_k_bar);
        // A sample belongs to the last stage that reached its l_k bar (a
        // stage going back drops the samples after its checkpoint).
        let slow = |l: f64| {
            let span = report
                .stages
                .iter()
                .rev()
                .find(|s| s.stage != Stage::Settle && s.to_l_k_bar <= l && l <= s.from_l_k_bar);
            span.is_some_and(|s| matches!(s.stage, Stage::Reference | Stage::Snap))
        };
        let mut ratios: Vec<f64> = (report.series.iter())
            .filter(|s| s.l_k_bar > before && slow(s.l_k_bar) && s.elastic_bar() > 0.0)
            .map(|s| s.kinetic_energy / (s.elastic_bar() * energy_unit))
            .collect();
        if ratios.is_empty() {
            return None;
        }
        ratios.sort_by(f64::total_cmp);
        let kinetic_ratio = ratios[ratios.len() / 2];
        Some(Self {
            kinetic_ratio,
            limit: QUASI_STATIC_LIMIT,
            holds: kinetic_ratio <= QUASI_STATIC_LIMIT,
        })
    }
}

impl CaseReport {
    /// A report of `params` with `status` and nothing measured yet.
    pub fn empty(params: CaseParams, status: Status) -> Self {
        Self {
            status,
            reason: String::new(),
            params,
            determinant_initial: None,
            determinant_final: None,
            writhe: 0.0,
            start_twist: 0.0,
            inversion: None,
            series: Vec::new(),
            snapshots: Vec::new(),
            stats: Stats::default(),
            stages: Vec::new(),
            scaling: None,
            quasi_static: None,
        }
    }
}

/// A stretch of a run in one stage.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageSpan {
    pub stage: Stage,
    /// l_k bar where the stretch began and ended.
    pub from_l_k_bar: f64,
    pub to_l_k_bar: f64,
    /// Time steps taken in it.
    pub steps: u64,
    /// Newton iterations and contact solve sweeps of those steps (absent
    /// from reports stored before physics revision 4).
    #[serde(default)]
    pub newton_iterations: u64,
    #[serde(default)]
    pub contact_sweeps: u64,
}

/// Progress handed to the caller after every sample.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Progress {
    /// Fraction of the pull done, from the start to the stop condition (0..1).
    pub fraction: f64,
    pub l_k_bar: f64,
    #[serde(rename = "H_bar", alias = "h_bar")]
    pub h_bar: f64,
    pub steps: u64,
}

/// Penetration (fraction of h) that ends a case as `Penetrated`.
const MAX_PENETRATION: f64 = 0.5;
/// Snapshots kept around the newest sample for those around the inversion.
const SNAPSHOT_HISTORY: usize = 40;
/// Stored snapshots (the report's size budget, about 50 kB each at K = 301):
/// one every `SNAPSHOT_SPACING` in l_k bar along the pull, and every
/// `SNAP_SNAPSHOT_SPACING` within `SNAP_WINDOW` either side of the inversion,
/// so that a viewer steps through the snap (about 40 snapshots in all).
const SNAPSHOT_SPACING: f64 = 20.0;
const SNAP_SNAPSHOT_SPACING: f64 = 2.0;
const SNAP_WINDOW: f64 = 10.0;
/// Damping rate (1/s, over the case's time unit) while relaxing.
const RELAX_DAMPING: f64 = 20.0;

/// Runs one case: validates `params`, building the start shape once, and
/// runs it ([`run_valid`]); invalid parameters give a report with
/// [`Status::Invalid`] and the reasons. `observer` sees progress after every
/// sample and returns `false` to cancel.
///
/// A short rod with one pass, pulled quickly at a constant speed (the
/// reference protocol: no stage goes back) until l_k bar falls below 130:
/// ```
/// use solver::case::{CaseParams, Protocol};
/// use solver::protocol::{self, Status};
///
/// let params = CaseParams {
///     n: 1,
///     length: 0.3,
///     nodes: Some(102),
///     relax_time: Some(0.1),
///     pull_speed: 0.01,
///     min_l_k_bar: 130.0,
///     protocol: Protocol::Reference,
///     ..CaseParams::default()
/// };
/// let mut samples = 0;
/// let report = protocol::run(&params, &mut |_| {
///     samples += 1;
///     true
/// });
/// assert_eq!(report.status, Status::Completed, "{}", report.reason);
/// assert_eq!(report.determinant_initial, Some(3), "a trefoil: 2n + 1");
/// assert_eq!(report.series.len(), samples);
/// let l_k_bar: Vec<f64> = report.series.iter().map(|s| s.l_k_bar).collect();
/// assert!(l_k_bar.windows(2).all(|w| w[1] < w[0]), "the pull shortens the knot");
/// assert!(l_k_bar[0] > 135.0 && l_k_bar[l_k_bar.len() - 1] < 130.0);
/// ```
pub fn run(params: &CaseParams, observer: &mut dyn FnMut(&Progress) -> bool) -> CaseReport {
    let started = std::time::Instant::now();
    match params.validated() {
        Ok(case) => run_from(&case, started, &mut |progress, _| observer(progress)),
        Err(errors) => {
            let mut report = CaseReport::empty(params.clone(), Status::Invalid);
            report.reason = reasons(&errors);
            report
        }
    }
}

/// [`run`] for a case already validated, from the start shape its validation built.
pub fn run_valid(case: &ValidCase, observer: &mut dyn FnMut(&Progress) -> bool) -> CaseReport {
    run_from(case, std::time::Instant::now(), &mut |progress, _| {
        observer(progress)
    })
}

/// [`run_valid`] with the rod's centre line (node positions) handed to the
/// observer with every sample's progress.
pub fn run_observed(
    case: &ValidCase,
    observer: &mut dyn FnMut(&Progress, &[Vector3<f64>]) -> bool,
) -> CaseReport {
    run_from(case, std::time::Instant::now(), observer)
}

/// The stages of paper Sec. 4 from `started`: clamp the start shape, relax
/// it with the ends held, pull the clamps apart sampling eq. (11) until the
/// stop condition, and report.
fn run_from(
    case: &ValidCase,
    started: std::time::Instant,
    observer: &mut dyn FnMut(&Progress, &[Vector3<f64>]) -> bool,
) -> CaseReport {
    let params = case.params();
    let mut report = CaseReport::empty(params.clone(), Status::Completed);
    let world = match build(case, &mut report) {
        Ok(world) => world,
        Err(reason) => {
            report.status = Status::Invalid;
            report.reason = reason;
            return report;
        }
    };
    let mut run = Case::new(params, report, world, started);
    let ending = run
        .relax()
        .and_then(|()| run.pull(case.start().loop_middle, observer));
    run.finish(ending.err().unwrap_or(Ending {
        status: Status::Completed,
        reason: String::new(),
    }))
}

/// Parameter errors as one line.
fn reasons(errors: &[ParamError]) -> String {
    errors
        .iter()
        .map(|e| e.to_string())
        .collect::<Vec<_>>()
        .join("; ")
}

/// Why a case stopped before the end of its pull.
struct Ending {
    status: Status,
    reason: String,
}

impl Ending {
    fn new(status: Status, reason: impl Into<String>) -> Self {
        Self {
            status,
            reason: reason.into(),
        }
    }
}

/// Stage 1, the knot: the case's start shape (built or the user's) with its
/// knot type checked, and the world holding it as a clamped DER rod with the
/// case's contact, friction and time-stepping options.
fn build(case: &ValidCase, report: &mut CaseReport) -> Result<World, String> {
    let (params, shape) = (case.params(), case.start());
    let expected = knot::expected_determinant(params.n);
    report.determinant_initial = knot::knot_determinant(&shape.points).ok();
    if report.determinant_initial != Some(expected) {
        return Err(format!(
            "the start shape has knot determinant {}, expected {expected}",
            determinant_text(report.determinant_initial)
        ));
    }
    let scales = params.scales();
    let material = Material {
        youngs_modulus: params.youngs_modulus,
        poisson_ratio: params.poisson_ratio,
        density: params.density * scales.mass_scale,
    };
    let mut rod = Rod::new(&shape.points, params.h, material).map_err(|e| format!("rod: {e}"))?;
    report.writhe = knot::writhe(&shape.points);
    report.start_twist = params
        .start_twist
        .unwrap_or_else(|| knot::paper_twist(params.n, report.writhe));
    rod.add_twist(report.start_twist);
    rod.clamp(End::Start);
    rod.clamp(End::Finish);
    let newton = NewtonOptions {
        force_scale: Some(force_unit(params)),
        ..NewtonOptions::default()
    };
    let defaults = ContactOptions::default();
    let contact = ContactOptions {
        friction: params.mu,
        friction_law: params.friction_law,
        rolling: params.rolling,
        solve: params.contact_solve,
        candidates: params.contact_candidates,
        solver: GaussSeidelOptions {
            tolerance: params.contact_tolerance,
            ..defaults.solver
        },
        ..defaults
    };
    let env = Environment {
        gravity: Vector3::from(params.gravity) / scales.mass_scale,
        damping: RELAX_DAMPING / scales.time_unit,
    };
    Ok(World::new(vec![rod], env, contact, newton))
}

/// The pulling force (N) the clamps exert along `axis` after the last step:
/// the mean of the two clamps' reactions along the pull.
fn clamp_force(world: &World, axis: &Vector3<f64>) -> f64 {
    let (rod, stepper) = (&world.rods[0], world.stepper(0));
    let start = -stepper.clamp_reaction(rod, End::Start).0.dot(axis);
    let finish = stepper.clamp_reaction(rod, End::Finish).0.dot(axis);
    0.5 * (start + finish)
}

/// The force unit of F bar: EI / h^2 (eq. 11).
fn force_unit(params: &CaseParams) -> f64 {
    params.bending_stiffness() / (params.h * params.h)
}

/// A case being run: its world, clock and the report being filled.
struct Case<'a> {
    params: &'a CaseParams,
    report: CaseReport,
    world: World,
    clock: TimeStep,
    /// Knot determinant of an n-pass overhand knot (2n + 1).
    expected: u64,
    /// The case's inertia and time unit.
    scales: Scales,
    /// Scratch for the energies' gradient.
    gradient: Vec<f64>,
    started: std::time::Instant,
}

/// What the pull keeps between samples.
#[derive(Clone)]
struct Pull {
    /// Unit vector from the start clamp to the finish clamp.
    axis: Vector3<f64>,
    start_l_k_bar: f64,
    next_sample: f64,
    next_snapshot: f64,
    /// After the inversion: the next dense snapshot and where the dense snapshots stop.
    after_snap: Option<(f64, f64)>,
    history: VecDeque<Snapshot>,
    criteria: InversionCriteria,
    /// The loop's middle node, from the builder and then tracked from each sample's braid ends.
    mid: usize,
    time: f64,
    peak_kinetic_energy: f64,
    /// The clamp force (N) integrated over time since the last sample, and that time (s).
    impulse: f64,
    impulse_time: f64,
    stage: Stage,
    /// l_k bar where `stage` began.
    stage_start: f64,
    /// Where the fast approach saw the snap that the snap stage is resolving.
    fast_snap: Option<f64>,
}

/// Where a run is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    /// Damped, with the clamps held, after the knot is built (stage 2) or
    /// after going back to a checkpoint.
    Settle,
    /// [`Protocol::Reference`]: the whole pull at `pull_speed`.
    Reference,
    /// [`Protocol::Adaptive`]: fast, checkpointing, until a snap is detected.
    Approach,
    /// [`Protocol::Adaptive`]: from a checkpoint through the snap.
    Snap,
    /// [`Protocol::Adaptive`]: fast again, `SLOW_AFTER` past the snap.
    After,
}

impl Stage {
    /// Clamp speed over `pull_speed`, `pulled` (in l_k bar) into the stage:
    /// the fast stages ramp up from the snap speed over `RAMP` (the approach)
    /// or `RAMP_AFTER` (after the snap).
    fn speed(self, pulled: f64) -> f64 {
        match self {
            Stage::Settle => 0.0,
            Stage::Reference => 1.0,
            Stage::Snap => SNAP_FACTOR,
            Stage::Approach => ramp(pulled / RAMP),
            Stage::After => ramp(pulled / RAMP_AFTER),
        }
    }

    /// The damping rate (1/s) given the case's and the relaxation's: the fast stages damp like
    /// the relaxation, so that the knot follows the clamps without swinging
    /// (sparing the sliding along the rod, [`Stage::spares_sliding`]).
    fn damping(self, case: f64, relax: f64) -> f64 {
        match self {
            Stage::Reference | Stage::Snap => case,
            Stage::Settle | Stage::Approach | Stage::After => case.max(relax),
        }
    }

    /// Whether the damping spares sliding along the centre line
    /// ([`sliding::exempt_sliding`]): in the fast pulls, where a drag on the
    /// material drawn through the knot would read as clamp force. The
    /// settling damps every motion, and the slow stages keep the case's
    /// mass-proportional damping.
    fn spares_sliding(self) -> bool {
        matches!(self, Stage::Approach | Stage::After)
    }

    /// The largest time step given the case's.
    fn dt_max(self, case: f64) -> f64 {
        match self {
            Stage::Reference | Stage::Snap => case,
            Stage::Settle | Stage::Approach | Stage::After => case * FAST_DT_FACTOR,
        }
    }

    /// The contact solve's tolerance given the case's.
    fn contact_tolerance(self, case: f64) -> f64 {
        match self {
            Stage::Settle | Stage::Reference | Stage::Snap => case,
            Stage::Approach | Stage::After => case.max(FAST_CONTACT_TOLERANCE),
        }
    }
}

/// A snap the damped fast approach smeared out: H bar has fallen below
/// `SMEARED_FALL` of its largest value within the last `SMEARED_WINDOW` of
/// l_k bar, over more than `SMEARED_SPAN` (a sudden drop is
/// [`measurements::detect_inversion`]'s). Returns where the fall began (the
/// last sample within `SMEARED_START` of that largest value: the fold lies
/// after it) and where H bar is now. The damping slows the snap down while the
/// clamps go on moving, so that it spans many samples without the sudden drop
/// that detection looks for (n = 5: H bar 0.18 -> 0.07 over about 20 l_k bar, where
/// the reference pull snaps at once).
fn smeared_snap(series: &[Sample]) -> Option<(f64, f64)> {
    let last = series.last().filter(|s| s.h_bar > 0.0)?;
    let window = || (series.iter().rev()).take_while(|s| s.l_k_bar <= last.l_k_bar + SMEARED_WINDOW);
    let peak = window().map(|s| s.h_bar).fold(0.0, f64::max);
    if last.h_bar >= SMEARED_FALL * peak {
        return None;
    }
    let began = window().find(|s| s.h_bar >= SMEARED_START * peak)?.l_k_bar;
    (began - last.l_k_bar > SMEARED_SPAN).then_some((began, last.l_k_bar))
}

/// From the snap speed (0) to the fast one (1).
fn ramp(fraction: f64) -> f64 {
    SNAP_FACTOR + (FAST_FACTOR - SNAP_FACTOR) * fraction.clamp(0.0, 1.0)
}

/// A fast approach's checkpoints and where the next is due.
struct Checkpoints {
    list: VecDeque<Checkpoint>,
    next: f64,
}

impl Checkpoints {
    /// The latest checkpoint at or before `l_k_bar` along the pull (at l_k
    /// bar >= it), else the earliest kept; it and the later ones leave the
    /// list, the earlier ones stay for a retry from further back.
    fn before(&mut self, l_k_bar: f64) -> Option<Checkpoint> {
        let at = self.list.iter().rposition(|c| c.l_k_bar >= l_k_bar).unwrap_or(0);
        self.list.drain(at..).next()
    }
}

/// The state a fast pull can return to.
struct Checkpoint {
    l_k_bar: f64,
    world: World,
    clock: TimeStep,
    pull: Pull,
    series: usize,
    snapshots: usize,
}

impl<'a> Case<'a> {
    fn new(params: &'a CaseParams, report: CaseReport, world: World, started: std::time::Instant) -> Self {
        let dt = params.time_step();
        let gradient = vec![0.0; world.rods[0].ndof()];
        let clock = TimeStep::new(if params.adaptive_dt {
            AdaptiveOptions::up_to(dt)
        } else {
            AdaptiveOptions::fixed(dt)
        });
        Self {
            params,
            report,
            world,
            clock,
            expected: knot::expected_determinant(params.n),
            scales: params.scales(),
            gradient,
            started,
        }
    }

    fn l_k_bar(&self) -> f64 {
        l_k_bar(&self.world, self.params)
    }

    /// Whether the pull goes fast far from the snap ([`pulls_fast`]).
    fn fast(&self) -> bool {
        pulls_fast(self.params)
    }

    /// An `Ending` when the last step penetrated beyond `MAX_PENETRATION` h
    /// (`during` says when; called only then).
    fn penetration(&self, max_penetration: f64, during: impl FnOnce() -> String) -> Result<(), Ending> {
        if max_penetration > MAX_PENETRATION * self.params.h {
            return Err(Ending::new(
                Status::Penetrated,
                format!(
                    "penetration {:.3} h exceeds {MAX_PENETRATION} h {}",
                    max_penetration / self.params.h,
                    during()
                ),
            ));
        }
        Ok(())
    }

    /// An `Ending` when the knot type of `points` is not the case's (`when`
    /// says where; called only then).
    fn topology(&mut self, points: &[Vector3<f64>], when: impl FnOnce() -> String) -> Result<(), Ending> {
        let det = knot::knot_determinant(points).ok();
        self.determinant(det, when)
    }

    fn determinant(&mut self, det: Option<u64>, when: impl FnOnce() -> String) -> Result<(), Ending> {
        if det != Some(self.expected) {
            self.report.determinant_final = det;
            return Err(Ending::new(
                Status::TopologyChanged,
                format!(
                    "knot determinant {} {}, expected {}",
                    determinant_text(det),
                    when(),
                    self.expected
                ),
            ));
        }
        Ok(())
    }

    /// Stage 2: relaxation with the ends held (damped, with the settling's
    /// longer steps), until the kinetic
    /// energy is a `relax_tolerance` fraction of the elastic energy or
    /// `relax_time` has passed.
    fn relax(&mut self) -> Result<(), Ending> {
        self.begin(Stage::Settle);
        if self.params.adaptive_dt {
            self.clock.rescale(Stage::Settle.dt_max(self.params.time_step()));
        }
        self.settle(self.params.relax_limit())?;
        let points = self.world.rods[0].positions();
        self.topology(&points, || "after relaxing".to_string())?;
        let at = self.l_k_bar();
        self.report
            .snapshots
            .push(Snapshot::capture(&self.world, "relaxed", at, self.clock.elapsed));
        Ok(())
    }

    /// Damped steps with the clamps held until the kinetic energy is a
    /// `relax_tolerance` fraction of the elastic energy, or for `max_time`.
    fn settle(&mut self, max_time: f64) -> Result<(), Ending> {
        let mut settled_for = 0.0;
        while settled_for < max_time {
            let step = self
                .clock
                .advance(&mut self.world)
                .map_err(|e| Ending::new(Status::Diverged, format!("while relaxing: {e}")))?;
            settled_for += step.dt;
            self.report.stats.relax_steps += 1;
            self.count_step(&step.report);
            self.penetration(step.report.max_penetration, || "while relaxing".to_string())?;
            let rod = &self.world.rods[0];
            let ke = rod.kinetic_energy();
            let elastic =
                crate::energies::evaluate(rod, crate::energies::Terms::ALL, &mut self.gradient, None).total();
            if ke <= self.params.relax_tolerance * elastic {
                break;
            }
        }
        Ok(())
    }

    /// Stage 3: both clamps pulled apart along the line joining them; a
    /// sample every `sample_interval` in l_k bar, until `min_l_k_bar`, the
    /// margin after the inversion, or `max_force_bar`.
    fn pull(
        &mut self,
        loop_middle: usize,
        observer: &mut dyn FnMut(&Progress, &[Vector3<f64>]) -> bool,
    ) -> Result<(), Ending> {
        let axis = {
            let r = &self.world.rods[0];
            (r.node(r.nodes() - 1) - r.node(0)).normalize()
        };
        let stage = if self.fast() {
            Stage::Approach
        } else {
            Stage::Reference
        };
        let start_l_k_bar = self.l_k_bar();
        let mut pull = Pull {
            axis,
            start_l_k_bar,
            next_sample: start_l_k_bar,
            next_snapshot: start_l_k_bar - SNAPSHOT_SPACING,
            after_snap: None,
            history: VecDeque::with_capacity(SNAPSHOT_HISTORY),
            criteria: InversionCriteria::default(),
            mid: loop_middle,
            time: 0.0,
            peak_kinetic_energy: 0.0,
            impulse: 0.0,
            impulse_time: 0.0,
            stage,
            stage_start: start_l_k_bar,
            fast_snap: None,
        };
        self.enter(&mut pull, stage, start_l_k_bar);
        let mut saved = Checkpoints {
            list: VecDeque::with_capacity(CHECKPOINTS),
            next: start_l_k_bar,
        };
        loop {
            let (step, dt) = self.step(&mut pull)?;
            let l_k_bar = self.l_k_bar();
            if l_k_bar > pull.next_sample {
                continue;
            }
            pull.next_sample = l_k_bar - self.params.sample_interval;
            let points = self.sample(&mut pull, &step, dt, l_k_bar);
            self.keep_snapshots(&mut pull, l_k_bar);
            self.topology(&points, || format!("at l_k bar {l_k_bar:.2}"))?;
            let stop_l = match (self.report.inversion, self.params.stop_after_inversion) {
                (Some(inv), Some(margin)) => (inv.l_k_bar - margin).max(self.params.min_l_k_bar),
                _ => self.params.min_l_k_bar,
            };
            let sample = self.report.series.last().copied().unwrap_or_default();
            let progress = Progress {
                fraction: ((pull.start_l_k_bar - l_k_bar) / (pull.start_l_k_bar - stop_l)).clamp(0.0, 1.0),
                l_k_bar,
                h_bar: sample.h_bar,
                steps: self.report.stats.steps,
            };
            if !observer(&progress, &points) {
                return Err(Ending::new(Status::Cancelled, Status::Cancelled.to_string()));
            }
            if self.schedule(&mut pull, &mut saved, l_k_bar)? {
                continue;
            }
            let tight = self.params.max_force_bar.is_some_and(|m| sample.f_bar > m);
            if (l_k_bar <= stop_l || tight) && !self.review_end(&mut pull, &mut saved, l_k_bar)? {
                break;
            }
        }
        let det = knot::knot_determinant(&self.world.rods[0].positions()).ok();
        self.report.determinant_final = det;
        self.determinant(det, || "at the end".to_string())?;
        let at = self.l_k_bar();
        self.report
            .snapshots
            .push(Snapshot::capture(&self.world, "final", at, self.clock.elapsed));
        Ok(())
    }

    /// One world step of the pull, counted; an `Ending` when it diverges or
    /// penetrates. Returns the step's report and size.
    fn step(&mut self, pull: &mut Pull) -> Result<(WorldStepReport, f64), Ending> {
        if pull.stage.spares_sliding() {
            let gamma = self.world.env.damping;
            self.world
                .set_load(0, |rod, load| sliding::exempt_sliding(rod, gamma, load));
        }
        let (step, dt) = match self.clock.advance(&mut self.world) {
            Ok(s) => (s.report, s.dt),
            Err(e) => return Err(Ending::new(Status::Diverged, e.to_string())),
        };
        pull.time += dt;
        pull.peak_kinetic_energy = pull.peak_kinetic_energy.max(self.world.rods[0].kinetic_energy());
        pull.impulse += dt * clamp_force(&self.world, &pull.axis);
        pull.impulse_time += dt;
        let stats = &mut self.report.stats;
        stats.steps += 1;
        stats.newton_iterations += u64::from(step.newton_iterations);
        stats.contact_sweeps += step.contact_sweeps as u64;
        self.count_step(&step);
        self.penetration(step.max_penetration, || {
            format!("at l_k bar {:.2}", self.l_k_bar())
        })?;
        Ok((step, dt))
    }

    /// The adaptive protocol's moves after a sample at `l_k_bar`
    /// ([`Protocol::Adaptive`]): back to a checkpoint when the fast approach
    /// sees a snap (returns `true`), checkpoints while fast, fast again past
    /// the snap or after a false alarm; otherwise the clamps' speed.
    fn schedule(&mut self, pull: &mut Pull, saved: &mut Checkpoints, l_k_bar: f64) -> Result<bool, Ending> {
        if pull.stage == Stage::Approach && self.report.inversion.is_none() {
            if let Some((began, fell)) = smeared_snap(&self.report.series) {
                if let Some(c) = saved.before(began + RESTART_BEFORE) {
                    self.restore(c, pull)?;
                    pull.fast_snap = Some(fell);
                    return Ok(true);
                }
            }
        }
        match (pull.stage, self.report.inversion) {
            (Stage::Approach, Some(inv)) => {
                if let Some(c) = saved.before(inv.l_k_bar + RESTART_BEFORE) {
                    self.restore(c, pull)?;
                    pull.fast_snap = Some(inv.l_k_bar);
                    return Ok(true);
                }
            }
            (Stage::Approach, None) if l_k_bar <= saved.next => {
                if saved.list.len() == CHECKPOINTS {
                    saved.list.pop_front();
                }
                saved.list.push_back(self.checkpoint(pull, l_k_bar));
                saved.next = l_k_bar - CHECKPOINT_SPACING;
            }
            (Stage::Snap, Some(inv))
                if inv.l_k_bar > pull.stage_start - MIN_LEAD && !saved.list.is_empty() =>
            {
                // The slow pull snapped right after its restart: the restart
                // was already past the fold. Go back further.
                if let Some(c) = saved.before(pull.stage_start + RESTART_BEFORE) {
                    let fast = pull.fast_snap;
                    self.restore(c, pull)?;
                    pull.fast_snap = fast;
                    return Ok(true);
                }
            }
            (Stage::Snap, Some(inv)) if l_k_bar <= inv.l_k_bar - SLOW_AFTER => {
                self.enter(pull, Stage::After, l_k_bar);
            }
            (Stage::Snap, None) if pull.fast_snap.is_some_and(|f| l_k_bar < f - FALSE_ALARM) => {
                // The fast pull's snap was its own swinging: approach again.
                self.enter(pull, Stage::Approach, l_k_bar);
                saved.next = l_k_bar;
            }
            _ => self.drive(pull, l_k_bar),
        }
        Ok(false)
    }

    /// At the stop condition: a fast approach without a snap redoes the
    /// last `END_REVIEW` of the pull from a checkpoint (returns `true`).
    fn review_end(&mut self, pull: &mut Pull, saved: &mut Checkpoints, l_k_bar: f64) -> Result<bool, Ending> {
        if pull.stage != Stage::Approach {
            return Ok(false);
        }
        match saved.before(l_k_bar + END_REVIEW) {
            Some(c) => self.restore(c, pull).map(|()| true),
            None => Ok(false),
        }
    }

    /// The state to come back to from `l_k_bar`.
    fn checkpoint(&self, pull: &Pull, l_k_bar: f64) -> Checkpoint {
        Checkpoint {
            l_k_bar,
            world: self.world.clone(),
            clock: self.clock.clone(),
            pull: pull.clone(),
            series: self.report.series.len(),
            snapshots: self.report.snapshots.len(),
        }
    }

    /// Enters `stage` at `l_k_bar`: the clamps at its speed, the contact
    /// solve at its tolerance, the largest step its own (a constant step,
    /// `adaptive_dt` false, stays the case's).
    fn enter(&mut self, pull: &mut Pull, stage: Stage, l_k_bar: f64) {
        self.begin(stage);
        pull.stage = stage;
        pull.stage_start = l_k_bar;
        self.world.contact.solver.tolerance = stage.contact_tolerance(self.params.contact_tolerance);
        self.world.env.damping = stage.damping(self.params.damping, RELAX_DAMPING / self.scales.time_unit);
        if !stage.spares_sliding() {
            self.world.set_load(0, |_, load| load.fill(0.0));
        }
        if self.params.adaptive_dt {
            self.clock.rescale(stage.dt_max(self.params.time_step()));
        }
        self.drive(pull, l_k_bar);
    }

    /// A new entry in the report's stages, from here.
    fn begin(&mut self, stage: Stage) {
        let at = self.l_k_bar();
        self.report.stages.push(StageSpan {
            stage,
            from_l_k_bar: at,
            to_l_k_bar: at,
            steps: 0,
            newton_iterations: 0,
            contact_sweeps: 0,
        });
    }

    /// Counts `step` in the current stage, which now ends here.
    fn count_step(&mut self, step: &WorldStepReport) {
        let at = self.l_k_bar();
        if let Some(span) = self.report.stages.last_mut() {
            span.steps += 1;
            span.newton_iterations += u64::from(step.newton_iterations);
            span.contact_sweeps += step.contact_sweeps as u64;
            span.to_l_k_bar = at;
        }
    }

    /// Both clamps moving apart at the stage's speed at `l_k_bar`.
    fn drive(&mut self, pull: &Pull, l_k_bar: f64) {
        let v = pull.axis * (pull.stage.speed(pull.stage_start - l_k_bar) * self.params.clamp_speed());
        self.world.rods[0].move_clamp(End::Start, -v);
        self.world.rods[0].move_clamp(End::Finish, v);
    }

    /// Back to checkpoint `c` of a fast approach, to pull through the snap:
    /// the series and snapshots after it are dropped, and the knot settles
    /// with the clamps held (the fast pull leaves it swinging) before the
    /// snap stage starts.
    fn restore(&mut self, c: Checkpoint, pull: &mut Pull) -> Result<(), Ending> {
        let at = c.l_k_bar;
        self.rewind(c, pull);
        self.enter(pull, Stage::Settle, at);
        self.settle(SETTLE_TIME * self.scales.time_unit)?;
        self.enter(pull, Stage::Snap, at);
        Ok(())
    }

    /// The world, pull, series and snapshots back as they were at `c`.
    fn rewind(&mut self, c: Checkpoint, pull: &mut Pull) {
        self.world = c.world;
        self.clock = c.clock;
        *pull = c.pull;
        self.report.series.truncate(c.series);
        self.report.snapshots.truncate(c.snapshots);
        self.report.inversion = None;
    }

    /// One sample of eq. (11) and the braid's shape; detects the inversion.
    /// Returns the rod's node positions.
    fn sample(
        &mut self,
        pull: &mut Pull,
        step: &WorldStepReport,
        dt: f64,
        l_k_bar: f64,
    ) -> Vec<Vector3<f64>> {
        let params = self.params;
        let rod = &self.world.rods[0];
        let force = if pull.impulse_time > 0.0 {
            pull.impulse / pull.impulse_time
        } else {
            clamp_force(&self.world, &pull.axis)
        };
        (pull.impulse, pull.impulse_time) = (0.0, 0.0);
        let points = rod.positions();
        let energy_unit = params.bending_stiffness() / params.h;
        let energies = crate::energies::evaluate(rod, crate::energies::Terms::ALL, &mut self.gradient, None);
        let pairs = self.world.contacts().iter().map(|c| (c.nodes[0], c.nodes[2]));
        let braid = measurements::braid(pairs, pull.mid);
        let geometry = braid.map(|b| {
            let (p, q) = b.loop_ends();
            (
                measurements::loop_geometry(&points, p, q),
                measurements::braid_shape(&points, &b),
            )
        });
        let (width, height) = geometry.map_or((0.0, 0.0), |(g, _)| (g.width, g.height));
        let (epsilon, phi) = geometry.map_or((0.0, 0.0), |(_, b)| (b.epsilon, b.phi));
        if let Some((g, _)) = geometry {
            pull.mid = (g.start + g.end) / 2;
        }
        self.report.series.push(Sample {
            time: pull.time,
            l_k_bar,
            l_c_over_l: 1.0 - l_k_bar * params.h / params.length,
            force,
            f_bar: force / force_unit(params),
            width,
            height,
            h_bar: if width > 0.0 { height / width } else { 0.0 },
            kinetic_energy: std::mem::take(&mut pull.peak_kinetic_energy),
            contacts: step.contacts,
            active_contacts: step.active_contacts,
            max_penetration_over_h: step.max_penetration / params.h,
            epsilon,
            phi,
            newton_iterations: step.newton_iterations,
            dt,
            e_stretch_bar: energies.stretching / energy_unit,
            e_bend_bar: energies.bending / energy_unit,
            e_twist_bar: energies.twisting / energy_unit,
        });
        points
    }

    /// The snapshots a viewer steps through (`SNAPSHOT_SPACING` along the pull,
    /// `SNAP_SNAPSHOT_SPACING` around the inversion); detects the inversion.
    fn keep_snapshots(&mut self, pull: &mut Pull, l_k_bar: f64) {
        if pull.history.len() == SNAPSHOT_HISTORY {
            pull.history.pop_front();
        }
        pull.history.push_back(Snapshot::capture(
            &self.world,
            "sample",
            l_k_bar,
            self.clock.elapsed,
        ));
        if self.report.inversion.is_none() {
            self.report.inversion = measurements::detect_inversion(&self.report.series, &pull.criteria);
            if let Some(inv) = self.report.inversion {
                self.snap_snapshots(pull, inv.l_k_bar);
            }
        } else if let Some((next, end)) = pull.after_snap {
            if l_k_bar <= next && l_k_bar >= end {
                self.report.snapshots.push(Snapshot::capture(
                    &self.world,
                    "after_inversion",
                    l_k_bar,
                    self.clock.elapsed,
                ));
                pull.after_snap = Some((l_k_bar - SNAP_SNAPSHOT_SPACING, end));
            }
        }
        if l_k_bar <= pull.next_snapshot {
            self.report.snapshots.push(Snapshot::capture(
                &self.world,
                "pull",
                l_k_bar,
                self.clock.elapsed,
            ));
            pull.next_snapshot = l_k_bar - SNAPSHOT_SPACING;
        }
    }

    /// The snapshots either side of the inversion at `snap`, taken from the
    /// history (the detection lags the snap).
    fn snap_snapshots(&mut self, pull: &mut Pull, snap: f64) {
        let mut stored: Vec<f64> = Vec::new();
        let mut offset = SNAP_WINDOW;
        while offset >= -SNAP_WINDOW {
            let label = if offset == 0.0 {
                "at_inversion"
            } else if offset == SNAP_SNAPSHOT_SPACING {
                "before_inversion"
            } else if offset > 0.0 {
                "near_inversion"
            } else {
                "after_inversion"
            };
            let distance = |f: &Snapshot| (f.l_k_bar - snap - offset).abs();
            let nearest = pull
                .history
                .iter()
                .filter(|f| offset > 0.0 || f.l_k_bar <= snap)
                .min_by(|a, b| distance(a).total_cmp(&distance(b)));
            if let Some(f) = nearest.filter(|f| distance(f) < SNAP_SNAPSHOT_SPACING / 2.0) {
                if !stored.contains(&f.l_k_bar) {
                    stored.push(f.l_k_bar);
                    self.report.snapshots.push(Snapshot {
                        label: label.to_string(),
                        ..f.clone()
                    });
                }
            }
            offset -= SNAP_SNAPSHOT_SPACING;
        }
        let lowest = stored.iter().copied().fold(snap, f64::min);
        pull.after_snap = Some((lowest - SNAP_SNAPSHOT_SPACING, snap - SNAP_WINDOW));
    }

    /// Stage 4: the report, with the ending's status and the run's statistics.
    fn finish(self, ending: Ending) -> CaseReport {
        finish(
            self.report,
            self.world,
            &self.clock,
            ending.status,
            ending.reason,
            self.started,
        )
    }
}

/// A knot determinant as users read it.
fn determinant_text(det: Option<u64>) -> String {
    det.map_or_else(|| "undetermined".to_string(), |d| d.to_string())
}

/// l_k bar = (L - l_c) / h (eq. 11) of the world's rod.
fn l_k_bar(world: &World, params: &CaseParams) -> f64 {
    let r = &world.rods[0];
    (params.length - (r.node(r.nodes() - 1) - r.node(0)).norm()) / params.h
}

fn finish(
    mut report: CaseReport,
    world: World,
    clock: &TimeStep,
    status: Status,
    reason: String,
    started: std::time::Instant,
) -> CaseReport {
    report.status = status;
    report.reason = reason;
    report.scaling = Some(Scaling::of(&report.params));
    report.quasi_static = QuasiStatic::of(&report);
    if status != Status::Completed {
        report.inversion = None;
        let at = l_k_bar(&world, &report.params);
        report
            .snapshots
            .push(Snapshot::capture(&world, "failure", at, clock.elapsed));
    }
    report.stats.rejected_steps = clock.rejected;
    report.stats.smallest_dt = clock.smallest;
    report.stats.wall_time = started.elapsed().as_secs_f64();
    report.stats.detection_time = world.counters.detection.as_secs_f64();
    report.stats.contact_time = world.counters.contact_solve.as_secs_f64();
    report.stats.dynamics_time = world.counters.dynamics.as_secs_f64();
    report
}

#[cfg(test)]
mod tests {
    use super::{Case, CaseReport, Protocol, Stage, Status, build, smeared_snap};
    use crate::case::CaseParams;
    use crate::measurements::Sample;

    /// A contact solve that refuses its problem (here an over-relaxation
    /// factor outside (0, 2)) ends the case as diverged with the solver's
    /// reason, after the time step has been halved to its smallest.
    #[test]
    fn a_failed_contact_solve_ends_the_case_with_its_reason() {
        let params = CaseParams {
            n: 1,
            length: 0.3,
            nodes: 102,
            relax_time: 0.1,
            protocol: Protocol::Reference,
            ..CaseParams::default()
        };
        let case = params.validated().expect("a valid case");
        let mut report = CaseReport::empty(params.clone(), Status::Completed);
        let mut world = build(&case, &mut report).expect("the knot builds");
        world.contact.solver.relaxation = 2.5;
        let mut run = Case::new(&params, report, world, std::time::Instant::now());
        let ending = run
            .relax()
            .and_then(|()| run.pull(case.start().loop_middle, &mut |_, _| true))
            .expect_err("the case cannot go on without its contact forces");
        let report = run.finish(ending);
        assert_eq!(report.status, Status::Diverged);
        assert_eq!(
            report.reason,
            "while relaxing: contact solve failed: over-relaxation factor 2.5 is outside (0, 2)"
        );
        assert!(
            report.stats.rejected_steps >= 6,
            "the step is halved to dt/64 before the case ends"
        );
    }

    /// Samples every 0.5 in l_k bar from 300 down, H bar from `h`.
    fn series(h: impl Fn(f64) -> f64) -> Vec<Sample> {
        (0..60)
            .map(|i| 300.0 - 0.5 * f64::from(i))
            .map(|l_k_bar| Sample {
                l_k_bar,
                h_bar: h(l_k_bar),
                ..Sample::default()
            })
            .collect()
    }

    #[test]
    fn a_fall_of_h_bar_spread_over_many_samples_is_a_smeared_snap() {
        // Steady at 0.2 down to 290, then falling linearly to 0.02 at 272.
        let smeared = series(|l| if l > 290.0 { 0.2 } else { 0.2 - 0.01 * (290.0 - l) });
        let (began, now) = smeared_snap(&smeared).expect("a smeared snap");
        assert_eq!(now, 270.5);
        assert!(
            (began - 288.0).abs() < 0.01,
            "the last sample within 0.9 of the peak: {began}"
        );
        // A sudden drop is left to the inversion detection.
        assert_eq!(
            smeared_snap(&series(|l| if l > 275.0 { 0.2 } else { 0.05 })),
            None
        );
        // Steady tightening: 10 % over the window.
        assert_eq!(smeared_snap(&series(|l| 0.2 - 0.001 * (300.0 - l))), None);
    }

    #[test]
    fn enum_words_are_the_serde_names() {
        for s in Status::ALL {
            assert_eq!(serde_json::to_value(s).unwrap(), s.to_string());
        }
        for p in [Protocol::Reference, Protocol::Adaptive] {
            assert_eq!(serde_json::to_value(p).unwrap(), p.to_string());
        }
        assert_eq!(Stage::Settle.to_string(), "settle");
    }
}
