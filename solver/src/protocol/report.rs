//! What a case reports: how it ended, its series (eq. 11 and the energies),
//! its events, the snapshots kept for viewers, how it was computed and
//! whether it stayed quasi-static.
use super::adaptive::{Outcome, Phase};
use crate::case::{CaseParams, Direction};
use crate::knot::Alexander;
use crate::measurements::{Inversion, Sample};
use crate::snapshot::Snapshot;
use crate::words::display_as_word;
use serde::{Deserialize, Serialize};

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

display_as_word!(Status, EventKind);

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

/// Counts and timings of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    pub steps: u64,
    pub newton_iterations: u64,
    /// Contact-solve sweeps summed over the loading steps.
    pub contact_sweeps: u64,
    pub relax_steps: u64,
    /// Times a stage of the adaptive pull went back to a checkpoint (at most
    /// `MAX_RESTARTS` per stage).
    #[serde(default)]
    pub restarts: u64,
    /// Steps redone with half the step (adaptive time step).
    pub rejected_steps: u64,
    /// Smallest time step taken (s).
    pub smallest_dt: f64,
    /// Wall time (s) of the whole case and per step phase.
    pub wall_time: f64,
    pub detection_time: f64,
    pub contact_time: f64,
    pub dynamics_time: f64,
}

/// What an event is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EventKind {
    /// The overhand knot's loop snaps through the braid while the knot
    /// tightens (paper Fig. 5).
    Inversion,
    /// The loop flips back while the knot loosens (the simplified model's
    /// second fold, Sec. 5).
    FlipBack,
    /// A snap of any knot but the overhand (whose loop's snap is an
    /// inversion): F bar drops suddenly with a burst of kinetic energy.
    Snap,
    /// A bend slips through: its rods part. `F_bar_before` is the holding
    /// force, the largest F bar of the stage before they parted, at `l_k_bar`.
    SlipThrough,
}

impl EventKind {
    /// Every kind of event.
    pub const ALL: [Self; 4] = [Self::Inversion, Self::FlipBack, Self::Snap, Self::SlipThrough];
}

/// A snap of the loop, in the stage that saw it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Event {
    /// Index of the loading program's stage.
    pub stage: usize,
    pub direction: Direction,
    pub kind: EventKind,
    /// l_k bar, F bar and H bar around the event ([`Inversion`]'s).
    #[serde(flatten)]
    pub at: Inversion,
    /// A clean snap: an inversion through which F bar falls, a flip back
    /// whose kinetic energy spikes (at least `InversionCriteria::kinetic_energy_spike`
    /// times its median before).
    pub clean: bool,
    /// Restarts from a checkpoint the stage took until the event was found
    /// (the adaptive pull; at most `MAX_RESTARTS`).
    #[serde(default)]
    pub restarts: u32,
}

/// The loop's hysteresis: it snapped at `inversion_l_k_bar` while tightened
/// and flipped back at `flip_back_l_k_bar` while loosened.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Hysteresis {
    pub inversion_l_k_bar: f64,
    pub flip_back_l_k_bar: f64,
    /// flip back - inversion, in l_k bar.
    pub width: f64,
}

/// The result of one case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CaseReport {
    pub status: Status,
    /// Why the case ended that way (empty when completed).
    pub reason: String,
    /// The parameters, with the node count and pull speed used.
    pub params: CaseParams,
    /// Alexander polynomial of the initial shape and at the end
    /// (coefficients, lowest power first; the knot's, `params.knot`), `None`
    /// where not reached or undetermined.
    #[serde(default)]
    pub alexander_initial: Option<Alexander>,
    #[serde(default)]
    pub alexander_final: Option<Alexander>,
    /// Knot determinant |Delta(-1)| of the initial shape and at the end
    /// (2n + 1 for the overhand knot).
    pub determinant_initial: Option<u64>,
    pub determinant_final: Option<u64>,
    /// Writhe of the start shape (closed by tails along the pull axis) and
    /// the twist (turns) it started with (`start_twist`, or the paper's code's).
    #[serde(default)]
    pub writhe: f64,
    #[serde(default)]
    pub start_twist: f64,
    /// The first inversion of a tightening stage, `None` when H bar never
    /// snapped.
    pub inversion: Option<Inversion>,
    /// Every event of every stage, in order (absent before physics revision 8).
    #[serde(default)]
    pub events: Vec<Event>,
    /// Where the program loosens after an inversion and the loop flips back.
    #[serde(default)]
    pub hysteresis: Option<Hysteresis>,
    pub series: Vec<Sample>,
    /// The knot's states kept for viewers (stored as `frames` before they
    /// were called snapshots).
    #[serde(alias = "frames")]
    pub snapshots: Vec<Snapshot>,
    pub stats: Stats,
    /// The run's step phases in order, with their steps (absent before
    /// physics revision 8).
    #[serde(default)]
    pub phases: Vec<PhaseSpan>,
    /// How the case was computed: time step, inertia and rates (absent before
    /// physics revision 8).
    #[serde(default)]
    pub scaling: Option<Scaling>,
    /// Whether the loading was quasi-static, measured (absent before physics
    /// revision 8, and where no sample was taken at `pull_speed`).
    #[serde(default)]
    pub quasi_static: Option<QuasiStatic>,
    /// A bend: whether its rods still hold each other at the end; a hitch:
    /// whether it still holds its cylinder (a slip is an outcome, not a
    /// failure); absent for a knot in one rod.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tied: Option<bool>,
    /// A bend or a hitch: the holding force, the largest F bar with the
    /// tails free before the rods parted or the hitch slipped (its
    /// slip-through event's), or, where it held to the end, the largest F
    /// bar it held (a lower bound); absent for a knot in one rod.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub holding_force_bar: Option<f64>,
    /// A hitch's cylinder (centre, axis, radius, length; m), for viewers;
    /// absent for a knot without one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cylinder: Option<crate::contact::Cylinder>,
    /// A bend's or a hitch's own measurements at each sample of `series`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bend_series: Vec<BendSample>,
}

/// A bend's own measurements at a sample.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BendSample {
    /// F bar at each pulled clamp (rod 0's standing end, rod 1's), each
    /// along its own side of the pull, averaged over the sample's interval.
    #[serde(rename = "F_bar")]
    pub f_bar: [f64; 2],
    /// Each rod's elastic energy over EI / h (eq. 6 by node, `energies::within`;
    /// a hitch's one rod, and 0).
    #[serde(rename = "E_bar")]
    pub energy_bar: [f64; 2],
    /// The rods have come apart: they neither touch (no two segments within
    /// half a radius of each other's surface) nor bend (each rod's elastic
    /// energy below 0.02 EI / h; rods with knots of their own, the
    /// fisherman's, need only not touch), or no two segments come within a
    /// diameter of each other's surface however they bend (rods flung apart,
    /// vibrating); a hitch's rod wraps its cylinder by less than one and a
    /// half turns.
    pub apart: bool,
    /// The tails are free (the bend has set).
    pub tails_free: bool,
    /// The fisherman's knot's two overhand knots, each the span of its rod
    /// that touches itself (`knot::self_contact_span`): the distance between
    /// their nodes' centroids along the pull, over h (positive while rod
    /// 0's, on rod 1's side, has not passed rod 1's); absent for other knots
    /// and while an overhand is loose (no two of its strands touch).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub knots_apart_bar: Option<f64>,
    /// The fisherman's two overhand knots (those spans) touch each other
    /// (two of their segments within half a radius of each other's
    /// surface); absent as the separation is.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub knots_touch: Option<bool>,
}

impl CaseReport {
    /// A report of `params` with `status` and nothing measured yet.
    pub fn empty(params: CaseParams, status: Status) -> Self {
        Self {
            status,
            reason: String::new(),
            params,
            alexander_initial: None,
            alexander_final: None,
            determinant_initial: None,
            determinant_final: None,
            writhe: 0.0,
            start_twist: 0.0,
            inversion: None,
            events: Vec::new(),
            hysteresis: None,
            series: Vec::new(),
            snapshots: Vec::new(),
            stats: Stats::default(),
            phases: Vec::new(),
            scaling: None,
            quasi_static: None,
            tied: None,
            holding_force_bar: None,
            cylinder: None,
            bend_series: Vec::new(),
        }
    }

    /// A bend's outcome: still tied unless it slipped through, and its
    /// holding force (the slip's, or where it held most in its series:
    /// [`holding_point`]).
    pub(super) fn close_bend(&mut self) {
        let slip = self.events.iter().find(|e| e.kind == EventKind::SlipThrough);
        self.tied = Some(slip.is_none() && self.bend_series.last().is_none_or(|b| !b.apart));
        self.holding_force_bar = match slip {
            Some(e) => Some(e.at.f_bar_before),
            None => holding_point(&self.series, &self.bend_series, 0).map(|(_, s)| s.f_bar),
        };
    }

    /// The first inversion of a tightening stage, and the first flip back
    /// after it: the hysteresis.
    pub(super) fn close_events(&mut self) {
        let first = self.events.iter().find(|e| e.kind == EventKind::Inversion);
        self.inversion = first.map(|e| e.at);
        self.hysteresis = first.and_then(|inv| {
            let back = self
                .events
                .iter()
                .find(|e| e.kind == EventKind::FlipBack && e.stage > inv.stage)?;
            Some(Hysteresis {
                inversion_l_k_bar: inv.at.l_k_bar,
                flip_back_l_k_bar: back.at.l_k_bar,
                width: back.at.l_k_bar - inv.at.l_k_bar,
            })
        });
    }
}

/// A stretch of a run in one step phase.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhaseSpan {
    pub phase: Phase,
    /// Index of the loading program's stage (`None`: the relaxation).
    pub stage: Option<usize>,
    /// l_k bar where the stretch began and ended.
    pub from_l_k_bar: f64,
    pub to_l_k_bar: f64,
    /// Time steps taken in it, their Newton iterations and contact sweeps.
    pub steps: u64,
    pub newton_iterations: u64,
    pub contact_sweeps: u64,
    /// How the adaptive schedule ended it (`None`: it ran its course).
    #[serde(default)]
    pub outcome: Option<Outcome>,
}

impl PhaseSpan {
    /// A new span of `phase` in program stage `stage` (`None`: relaxing),
    /// starting at `l_k_bar`.
    pub(super) fn new(phase: Phase, stage: Option<usize>, l_k_bar: f64) -> Self {
        Self {
            phase,
            stage,
            from_l_k_bar: l_k_bar,
            to_l_k_bar: l_k_bar,
            steps: 0,
            newton_iterations: 0,
            contact_sweeps: 0,
            outcome: None,
        }
    }
}

/// Progress handed to the caller after every sample and during the
/// relaxation (`steps` 0: no pull steps yet).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Progress {
    /// Fraction of the program done (0..1): stages done, and within a stage
    /// the part of the way to its end.
    pub fraction: f64,
    pub l_k_bar: f64,
    #[serde(rename = "H_bar", alias = "h_bar")]
    pub h_bar: f64,
    pub steps: u64,
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
    pub(super) fn of(params: &CaseParams) -> Self {
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

/// The measured quasi-staticity of a loading: the kinetic energy (each
/// sample's largest since the one before) over the elastic energy, median
/// over the samples taken at `pull_speed` (phases `reference`, `snap` and `fallback`) up
/// to each stage's first event. A snap and the stick-slip of friction are
/// dynamic events of a quasi-static pull: the median sees past them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct QuasiStatic {
    pub kinetic_ratio: f64,
    /// [`QUASI_STATIC_LIMIT`].
    pub limit: f64,
    /// `kinetic_ratio` is at most `limit`.
    pub holds: bool,
}

impl QuasiStatic {
    /// Of a report's series, each sample with the phase it was taken in, or
    /// `None` without samples taken at `pull_speed`.
    pub(super) fn of(report: &CaseReport, phases: &[Phase]) -> Option<Self> {
        let energy_unit = report.params.bending_stiffness() / report.params.h;
        let first_event = |stage: usize| {
            report
                .events
                .iter()
                .find(|e| e.stage == stage)
                .map(|e| e.at.sample)
        };
        let mut ratios: Vec<f64> = (report.series.iter().enumerate().zip(phases))
            .filter(|((i, s), phase)| {
                matches!(phase, Phase::Reference | Phase::Snap | Phase::Fallback)
                    && s.elastic_bar() > 0.0
                    && first_event(s.stage).is_none_or(|e| *i < e)
            })
            .map(|((_, s), _)| s.kinetic_energy / (s.elastic_bar() * energy_unit))
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

/// Where a bend or a hitch held most among the samples of `series` from
/// `first` (`bend` its own samples): the index and sample of the largest F
/// bar with the tails free. After the adaptive pull's restart for the
/// holding point these are the slow phase's through it and, once the rods
/// came apart, the fast pull's to where they part (a knot that grips again
/// there, as the fisherman's jamming overhands, holds most there).
pub(super) fn holding_point<'a>(
    series: &'a [Sample],
    bend: &[BendSample],
    first: usize,
) -> Option<(usize, &'a Sample)> {
    (series.iter().zip(bend).enumerate().skip(first))
        .filter(|(_, (_, b))| b.tails_free)
        .map(|(i, (s, _))| (i, s))
        .max_by(|a, b| a.1.f_bar.total_cmp(&b.1.f_bar))
}
