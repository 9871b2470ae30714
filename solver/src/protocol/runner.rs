//! A case's run: the knot built and clamped, relaxed, then its loading
//! program walked stage by stage; the steps, samples and checks every stage
//! shares; the report at the end.
use super::adaptive::{Outcome, Phase, RELAX_DAMPING};
use super::report::{BendSample, CaseReport, Event, PhaseSpan, Progress, QuasiStatic, Scaling, Status};
use super::twist::{self, Tracker};
use crate::case::{BEND_SET_FORCE_BAR, CaseParams, LoadStage, Scales, ValidCase};
use crate::contact::{Cylinder, GaussSeidelOptions};
use crate::energies;
use crate::external::{Environment, sliding};
use crate::knot::{self, Alexander, Clamp, StartShape};
use crate::material::Material;
use crate::measurements::{self, InversionCriteria, Sample};
use crate::pipeline::{ContactOptions, World, WorldStepReport};
use crate::rod::{End, Rod, node_dof};
use crate::snapshot::{Snapshot, SnapshotLabel};
use crate::stepper::NewtonOptions;
use crate::time_step::{AdaptiveOptions, TimeStep};
use nalgebra::Vector3;
use std::collections::VecDeque;
use std::time::Instant;

/// A bend's rods have come apart when no two of their segments are closer
/// than 2h plus this many radii...
pub(super) const PARTED: f64 = 0.5;
/// ...and neither rod's elastic energy is above this many EI / h: that of a
/// bend of radius 80 h through a half turn (pi h / 2R), an eighth of the
/// loose start's bights'. A slipped bend's rods lie straight side by side
/// along the pull, within reach of each other; a tied one's bights hold
/// their bends.
pub(super) const PARTED_ENERGY_BAR: f64 = 0.02;
/// ...or, whatever they bend, no two of their segments are closer than 2h
/// plus this many radii: a tied bend's rods touch, while a bend that springs
/// open flings its rods apart, vibrating (the reef at mu = 0.2 with K =
/// 1201: hundreds of radii apart, each rod's elastic energy 0.017 to 0.071
/// EI / h; docs/FIDELITY.md, Left open).
pub(super) const PARTED_FAR: f64 = 2.0;
/// The farthest (radii h) an end moves back while it is eased: a tail
/// trapped in the knot by friction may pull harder than the eased load
/// however far it goes.
pub(super) const EASE_TRAVEL: f64 = 10.0;
/// F bar of the constant load that holds a hitch's tail once it is let go,
/// and to which the set hitch is eased before (a fifth of the setting
/// load): a free tail is flung off the cylinder by the turns' own bending
/// as soon as it is let go (at mu 0.1 ... 0.5, R = 10 h), so the tail hangs
/// a weight, as in a hitch's holding test.
pub const HITCH_TAIL_FORCE_BAR: f64 = 0.2 * BEND_SET_FORCE_BAR;
/// A hitch has slipped when its rod wraps the cylinder by less than this
/// many turns: its tail has left the pinch under the diagonal and half a
/// turn more has unwound (it starts with two turns and its ends' lines).
pub(super) const HITCH_SLIPPED_TURNS: f64 = 1.5;
/// Penetration (fraction of h) that ends a case as `Penetrated`.
const MAX_PENETRATION: f64 = 0.5;
/// What to change when a case fails in a step: the numerical options that
/// hold contacts and knots together.
const STEP_HINT: &str = "a smaller dt, adaptive_dt, more nodes or contact_solve \"implicit\" may hold it";
/// Snapshots kept around the newest sample for those around an event.
pub(super) const SNAPSHOT_HISTORY: usize = 40;
/// Relaxation steps between the observer's calls: the relaxation takes no
/// samples, and a pause or cancel must not wait for its end (thousands of
/// steps on a long rod).
pub(super) const RELAX_OBSERVED: u64 = 50;

/// The observer of a run: progress and the centre line after every sample
/// and every `RELAX_OBSERVED` steps of the relaxation; `false` cancels.
pub(super) type Observer<'o> = dyn FnMut(&Progress, &[Vector3<f64>]) -> bool + 'o;

/// Runs a validated case from `started`: build, relax, walk the program,
/// report.
pub(super) fn run(case: &ValidCase, started: Instant, observer: &mut Observer) -> CaseReport {
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
    let mut run = Case::new(params, report, world, case.start(), started);
    let ending = run.relax(observer).and_then(|()| run.program(observer));
    run.finish(ending.err().unwrap_or(Ending {
        status: Status::Completed,
        reason: String::new(),
    }))
}

/// Why a case stopped before the end of its program.
pub(super) struct Ending {
    pub(super) status: Status,
    pub(super) reason: String,
}

impl Ending {
    pub(super) fn new(status: Status, reason: impl Into<String>) -> Self {
        Self {
            status,
            reason: reason.into(),
        }
    }
}

/// The knot: the case's start shape (built or the user's) with its knot
/// type checked (a knot in one rod), and the world holding its rods as DER
/// rods clamped at the pulled ends with the case's contact, friction and
/// time-stepping options, their inertia scaled and their weight physical
/// ([`CaseParams::scales`]).
fn build(case: &ValidCase, report: &mut CaseReport) -> Result<World, String> {
    let (params, shape) = (case.params(), case.start());
    let points = shape.points();
    if let Some(expected) = &shape.alexander {
        report.determinant_initial = knot::knot_determinant(points).ok();
        report.alexander_initial = knot::alexander(points).ok();
        if report.alexander_initial.as_ref() != Some(expected) {
            return Err(format!(
                "the start shape has Alexander polynomial {}, expected {}",
                alexander_text(report.alexander_initial.as_ref()),
                expected
            ));
        }
    }
    let scales = params.scales();
    let material = Material {
        youngs_modulus: params.youngs_modulus,
        poisson_ratio: params.poisson_ratio,
        density: params.density * scales.mass_scale,
    };
    let mut rods = shape
        .rods
        .iter()
        .map(|points| Rod::new(points, params.h, material).map_err(|e| format!("rod: {e}")))
        .collect::<Result<Vec<_>, _>>()?;
    let family = params.knot().map_err(|e| e.to_string())?;
    if !shape.is_bend() {
        report.writhe = knot::writhe(points);
        report.start_twist = params.start_twist.unwrap_or_else(|| family.twist(report.writhe));
        rods[0].add_twist(report.start_twist);
    }
    for clamp in shape.clamps {
        rods[clamp.rod].clamp(clamp.end);
    }
    if shape.is_bend() {
        // The tails are held while the bend relaxes and sets ([`Tails`]).
        for clamp in tails(&shape.clamps) {
            rods[clamp.rod].clamp(clamp.end);
        }
    }
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
    }
    .with_geometry(params.contact_geometry);
    let env = Environment {
        gravity: Vector3::from(params.gravity) / scales.mass_scale,
        damping: RELAX_DAMPING / scales.time_unit,
    };
    let mut world = World::new(rods, env, contact, newton);
    world.obstacle = shape.cylinder;
    report.cylinder = shape.cylinder;
    Ok(world)
}

/// The force unit of F bar: EI / h^2 (eq. 11).
pub(super) fn force_unit(params: &CaseParams) -> f64 {
    params.bending_stiffness() / (params.h * params.h)
}

/// The pulling force (N) on the knot along `axis` after the last step: the
/// mean of the two pulled clamps' reactions along the pull, or of the
/// springs' tensions when the clamps sit on springs (a soft stage), or,
/// once a hitch's tail is let go (`lone`), the first clamp's.
fn pulling_force(world: &World, clamps: &[Clamp; 2], axis: &Vector3<f64>, lone: bool) -> f64 {
    let rod = &world.rods[clamps[0].rod];
    if let [start, finish] = rod.springs[..] {
        return 0.5 * (finish.force(&rod.q, finish.anchor) - start.force(&rod.q, start.anchor));
    }
    let [start, finish] = clamp_forces(world, clamps, axis);
    if lone { start } else { 0.5 * (start + finish) }
}

/// Each pulled clamp's pull (N) along its own side of `axis` after the last
/// step: the first clamp's towards `-axis`, the second's towards `axis`.
pub(super) fn clamp_forces(world: &World, clamps: &[Clamp; 2], axis: &Vector3<f64>) -> [f64; 2] {
    let reaction = |c: &Clamp| {
        world
            .stepper(c.rod)
            .clamp_reaction(&world.rods[c.rod], c.end)
            .0
            .dot(axis)
    };
    [-reaction(&clamps[0]), reaction(&clamps[1])]
}

/// A bend's tails: the ends of its rods other than the pulled ones.
fn tails(clamps: &[Clamp; 2]) -> [Clamp; 2] {
    clamps.map(|c| Clamp {
        rod: c.rod,
        end: match c.end {
            End::Start => End::Finish,
            End::Finish => End::Start,
        },
    })
}

/// The position of clamp `c`'s end node.
pub(super) fn clamp_point(world: &World, c: &Clamp) -> Vector3<f64> {
    let rod = &world.rods[c.rod];
    match c.end {
        End::Start => rod.node(0),
        End::Finish => rod.node(rod.nodes() - 1),
    }
}

/// eq. 11's l_k bar for the pulled clamps at `[a, b]` (a bend's: the rods'
/// rest lengths less the pulled clamps' distance, over h).
fn l_k_bar_of([a, b]: [Vector3<f64>; 2], params: &CaseParams) -> f64 {
    (params.rest_length() - (b - a).norm()) / params.h
}

/// A knot determinant as users read it.
fn determinant_text(det: Option<u64>) -> String {
    det.map_or_else(|| "undetermined".to_string(), |d| d.to_string())
}

/// An Alexander polynomial as users read it.
fn alexander_text(alexander: Option<&Alexander>) -> String {
    alexander.map_or_else(|| "undetermined".to_string(), Alexander::to_string)
}

/// What the run carries from step to step, kept in checkpoints.
#[derive(Clone)]
pub(super) struct Carried {
    /// Simulated time since the program started (s).
    pub(super) time: f64,
    /// The largest kinetic energy since the last sample (J).
    pub(super) peak_kinetic_energy: f64,
    /// The pulling force integrated over time since the last sample, and that time.
    pub(super) impulse: f64,
    pub(super) impulse_time: f64,
    /// Each pulled clamp's force integrated over the same time (a bend's).
    pub(super) clamp_impulses: [f64; 2],
    /// Where a bend's tails, or a hitch's, stand in its setting.
    pub(super) tails: Tails,
    /// Where a hitch's tail was held when it was let go: the far end of
    /// its l_k bar from then on.
    pub(super) tail_anchor: Option<Vector3<f64>>,
    /// The load (N) on a hitch's tail end once it is let go
    /// ([`HITCH_TAIL_FORCE_BAR`]).
    pub(super) tail_load: Option<Vector3<f64>>,
    /// The loop's middle node, from the builder and then tracked from each
    /// sample's braid ends.
    pub(super) mid: usize,
    pub(super) twist: Tracker,
    /// The latest samples' snapshots, for those around an event.
    pub(super) history: VecDeque<Snapshot>,
}

/// A bend's or a hitch's tails through its setting: held while it relaxes
/// and its first pull tightens it to [`BEND_SET_FORCE_BAR`], held while the
/// clamps ease it back to `eased_force_bar` (a hitch to
/// [`HITCH_TAIL_FORCE_BAR`]), then let go (a knot tied by
/// hand is set by pulling its four ends before its standing ends are
/// loaded; a loose bend of elastic rods springs open when its tails are
/// free). A knot in one rod has none held.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Tails {
    Held,
    /// Easing: the held ends move back at `speed` (over `pull_speed`),
    /// from the program's time `since` (s).
    Easing {
        speed: f64,
        since: f64,
    },
    Free,
}

/// A case being run: its world, clock and the report being filled.
pub(super) struct Case<'a> {
    pub(super) params: &'a CaseParams,
    pub(super) report: CaseReport,
    pub(super) world: World,
    pub(super) clock: TimeStep,
    pub(super) carried: Carried,
    /// The phase each sample was taken in.
    pub(super) sample_phases: Vec<Phase>,
    /// The Alexander polynomial of a knot in one rod, and its determinant
    /// |Delta(-1)| checked at every sample (`None`: a bend).
    alexander: Option<Alexander>,
    expected: u64,
    /// The two pulled clamps.
    pub(super) clamps: [Clamp; 2],
    /// A hitch's cylinder.
    cylinder: Option<Cylinder>,
    /// Each rod of a bend ties a knot of its own (the fisherman's).
    own_knots: bool,
    /// The case's inertia and time unit.
    pub(super) scales: Scales,
    /// Unit vector from the start clamp to the finish clamp.
    pub(super) axis: Vector3<f64>,
    /// The program, where it started (the knot's own length) and the stage
    /// being run.
    pub(super) program: Vec<LoadStage>,
    pub(super) program_start: f64,
    pub(super) stage: usize,
    started: Instant,
}

impl<'a> Case<'a> {
    fn new(
        params: &'a CaseParams,
        report: CaseReport,
        world: World,
        start: &StartShape,
        started: Instant,
    ) -> Self {
        let dt = params.time_step();
        let clock = TimeStep::new(if params.adaptive_dt {
            AdaptiveOptions::up_to(dt)
        } else {
            AdaptiveOptions::fixed(dt)
        });
        let rod = &world.rods[0];
        let [a, b] = start.clamps.map(|c| clamp_point(&world, &c));
        let axis = (b - a).normalize();
        let carried = Carried {
            time: 0.0,
            peak_kinetic_energy: 0.0,
            impulse: 0.0,
            impulse_time: 0.0,
            clamp_impulses: [0.0; 2],
            tails: if start.is_bend() || start.is_hitch() {
                Tails::Held
            } else {
                Tails::Free
            },
            tail_anchor: None,
            tail_load: None,
            mid: start.loop_middle,
            twist: Tracker::new(rod, report.writhe),
            history: VecDeque::with_capacity(SNAPSHOT_HISTORY),
        };
        Self {
            params,
            report,
            world,
            clock,
            carried,
            sample_phases: Vec::new(),
            alexander: start.alexander.clone(),
            expected: start.alexander.as_ref().map_or(0, Alexander::determinant),
            clamps: start.clamps,
            cylinder: start.cylinder,
            own_knots: start.own_knots,
            scales: params.scales(),
            axis,
            program: params.program(),
            program_start: 0.0,
            stage: 0,
            started,
        }
    }

    pub(super) fn l_k_bar(&self) -> f64 {
        l_k_bar_of(self.clamp_points(), self.params)
    }

    /// Where the pulled clamps are: a hitch's second, once its tail is let
    /// go, where the tail was held.
    fn clamp_points(&self) -> [Vector3<f64>; 2] {
        let [a, b] = self.clamps.map(|c| clamp_point(&self.world, &c));
        [a, self.carried.tail_anchor.unwrap_or(b)]
    }

    /// The pulling force after the last step ([`pulling_force`]).
    fn pulling_force(&self) -> f64 {
        let lone = self.carried.tail_anchor.is_some();
        pulling_force(&self.world, &self.clamps, &self.axis, lone)
    }

    /// The knot's own length, which the stopping rules and the adaptive
    /// schedule's windows act on (`measurements::l_k_arc_bar`; a bend's:
    /// the rods' arc lengths less the pulled clamps' distance, over h).
    pub(super) fn l_k_arc_bar(&self) -> f64 {
        if !self.is_bend() {
            return measurements::l_k_arc_bar(&self.world.rods[0].positions(), self.params.h);
        }
        let arc: f64 = (self.world.rods.iter())
            .flat_map(|r| (1..r.nodes()).map(|i| (r.node(i) - r.node(i - 1)).norm()))
            .sum();
        let [a, b] = self.clamp_points();
        (arc - (b - a).norm()) / self.params.h
    }

    /// Starts easing a bend or a hitch once its first pull has set it (the
    /// pulling force after the last step at least [`BEND_SET_FORCE_BAR`]
    /// with the tails held: met at a step, so that the sampling does not
    /// move it), its held ends moving back at `speed` (over `pull_speed`);
    /// the set knot is kept as a snapshot. Returns whether it started now.
    pub(super) fn ease(&mut self, speed: f64) -> bool {
        let set = BEND_SET_FORCE_BAR * force_unit(self.params);
        if self.carried.tails != Tails::Held || self.pulling_force() < set {
            return false;
        }
        self.carried.tails = Tails::Easing {
            speed,
            since: self.carried.time,
        };
        self.snapshot_now(SnapshotLabel::Set);
        self.ease_ends();
        true
    }

    /// One step of the easing: each held end (a bend's standing ends and
    /// tails, a hitch's two ends) moves back towards the knot while it pulls
    /// harder than `eased_force_bar` ([`CaseParams::eased_force_bar`]; a hitch's:
    /// [`HITCH_TAIL_FORCE_BAR`]) and stays where it is once it pulls less (a
    /// tail held while the standing ends were pulled carries a load of its
    /// own, which easing the standing ends does not take off), for
    /// [`EASE_TRAVEL`] at most. Returns whether the knot is eased: no end
    /// pulls harder, or the ends have gone as far back as they may.
    pub(super) fn ease_ends(&mut self) -> bool {
        let Tails::Easing { speed, since } = self.carried.tails else {
            return false;
        };
        let speed = speed * self.params.clamp_speed();
        if (self.carried.time - since) * speed >= EASE_TRAVEL * self.params.h {
            for (end, _) in self.held_ends().into_iter().flatten() {
                self.world.rods[end.rod].move_clamp(end.end, Vector3::zeros());
            }
            return true;
        }
        let eased = match self.cylinder {
            Some(_) => HITCH_TAIL_FORCE_BAR,
            None => self.params.eased_force_bar(),
        } * force_unit(self.params);
        let mut held = false;
        for (end, outward) in self.held_ends().into_iter().flatten() {
            let pull = self
                .world
                .stepper(end.rod)
                .clamp_reaction(&self.world.rods[end.rod], end.end)
                .0;
            let back = pull.dot(&outward) > eased;
            held |= back;
            let v = if back { -outward * speed } else { Vector3::zeros() };
            self.world.rods[end.rod].move_clamp(end.end, v);
        }
        !held
    }

    /// Lets an eased knot's tails go. A hitch's tail is its second clamp:
    /// from then on it hangs a weight ([`HITCH_TAIL_FORCE_BAR`]) and its
    /// standing end alone is pulled, against the cylinder.
    pub(super) fn free_tails(&mut self) {
        self.carried.tails = Tails::Free;
        let freed = match self.cylinder {
            Some(_) => {
                self.carried.tail_anchor = Some(clamp_point(&self.world, &self.clamps[1]));
                let weight = HITCH_TAIL_FORCE_BAR * force_unit(self.params);
                self.carried.tail_load = Some(self.axis * weight);
                vec![self.clamps[1]]
            }
            None => tails(&self.clamps).to_vec(),
        };
        for tail in freed {
            let rod = &mut self.world.rods[tail.rod];
            for d in rod.clamp_dofs(tail.end) {
                rod.fixed[d] = false;
                rod.prescribed_velocity[d] = 0.0;
            }
        }
        self.world.forget_factorizations();
    }

    /// Keeps the rods as they are now as a snapshot labelled `label`.
    fn snapshot_now(&mut self, label: SnapshotLabel) {
        let at = self.l_k_bar();
        let shot = Snapshot::capture(&self.world, label, at, self.clock.elapsed);
        self.report.snapshots.push(shot);
    }

    /// The ends held through a bend's or a hitch's setting, each with the
    /// unit vector along the pull pointing away from the knot: the pulled
    /// clamps and, for a bend, its tails (on the side of the knot's middle,
    /// the pulled clamps' midpoint, where each lies); a hitch has no more.
    fn held_ends(&self) -> [Option<(Clamp, Vector3<f64>)>; 4] {
        let [a, b] = self.clamps.map(|c| clamp_point(&self.world, &c));
        let middle = 0.5 * (a + b);
        let [t0, t1] = tails(&self.clamps).map(|tail| {
            let side = (clamp_point(&self.world, &tail) - middle)
                .dot(&self.axis)
                .signum();
            self.cylinder.is_none().then_some((tail, self.axis * side))
        });
        [
            Some((self.clamps[0], -self.axis)),
            Some((self.clamps[1], self.axis)),
            t0,
            t1,
        ]
    }

    /// Puts a hitch's tail load on its tail end, added to the sliding
    /// exemption just written (`exempted`) or in place of the zero load.
    fn hang_tail_load(&mut self, exempted: bool) {
        let (Some(weight), tail) = (self.carried.tail_load, self.clamps[1]) else {
            return;
        };
        self.world.set_load(tail.rod, |rod, load| {
            let d = match tail.end {
                End::Start => node_dof(0),
                End::Finish => node_dof(rod.nodes() - 1),
            };
            for (i, f) in weight.iter().enumerate() {
                load[d + i] = if exempted { load[d + i] + f } else { *f };
            }
        });
    }

    /// Moves clamp `c` at `v`, unless it has been let go (a hitch's tail).
    pub(super) fn move_held_clamp(&mut self, c: Clamp, v: Vector3<f64>) {
        let rod = &mut self.world.rods[c.rod];
        if rod.fixed[rod.clamp_dofs(c.end)[0]] {
            rod.move_clamp(c.end, v);
        }
    }

    /// Whether the case pulls a bend (two rods) or a hitch: no knot type
    /// to keep, tails let go once set, and it may slip.
    pub(super) fn is_bend(&self) -> bool {
        self.alexander.is_none()
    }

    /// The rods' kinetic energies summed (J).
    fn kinetic_energy(&self) -> f64 {
        self.world.rods.iter().map(Rod::kinetic_energy).sum()
    }

    /// An `Ending` when the last step penetrated beyond `MAX_PENETRATION` h
    /// (`during` says when; called only then).
    pub(super) fn penetration(
        &self,
        max_penetration: f64,
        during: impl FnOnce() -> String,
    ) -> Result<(), Ending> {
        if max_penetration > MAX_PENETRATION * self.params.h {
            return Err(Ending::new(
                Status::Penetrated,
                format!(
                    "penetration {:.3} h exceeds {MAX_PENETRATION} h {}; {STEP_HINT}",
                    max_penetration / self.params.h,
                    during()
                ),
            ));
        }
        Ok(())
    }

    /// An `Ending` when the knot type of `points` is not the case's (`when`
    /// says where; called only then).
    pub(super) fn topology(
        &mut self,
        points: &[Vector3<f64>],
        when: impl FnOnce() -> String,
    ) -> Result<(), Ending> {
        if self.is_bend() {
            return Ok(());
        }
        let det = knot::knot_determinant(points).ok();
        self.determinant(det, when)
    }

    fn determinant(&mut self, det: Option<u64>, when: impl FnOnce() -> String) -> Result<(), Ending> {
        if det != Some(self.expected) {
            self.report.determinant_final = det;
            return Err(Ending::new(
                Status::TopologyChanged,
                format!(
                    "knot determinant {} {}, expected {}: strands passed through each other; {STEP_HINT}",
                    determinant_text(det),
                    when(),
                    self.expected
                ),
            ));
        }
        Ok(())
    }

    /// Relaxation with the ends held (damped), until the kinetic energy is a
    /// `relax_tolerance` fraction of the elastic energy or the longest
    /// relaxation has passed. A rod longer than its knot
    /// (`KnotSpec::knot_length`) relaxes with the settling's longer steps: its
    /// long straight tails let the knot drift sideways in a soft, slowly damped
    /// mode (L/h = 2500: 3 070 relaxing steps at the case's step, 1 150 at the
    /// settling's).
    fn relax(&mut self, observer: &mut Observer) -> Result<(), Ending> {
        self.begin(Phase::Settle, None);
        let spec = self.params.knot_spec();
        if self.params.adaptive_dt && spec.knot_length() < spec.length {
            self.clock.rescale(Phase::Settle.dt_max(self.params.time_step()));
        }
        self.settle(self.params.relax_limit(), Some(observer))?;
        let points = self.world.rods[0].positions();
        self.topology(&points, || "after relaxing".to_string())?;
        self.snapshot_now(SnapshotLabel::Relaxed);
        Ok(())
    }

    /// Damped steps with the clamps held until the kinetic energy is a
    /// `relax_tolerance` fraction of the elastic energy, or for `max_time`;
    /// `observer` is called every `RELAX_OBSERVED` steps.
    pub(super) fn settle(
        &mut self,
        max_time: f64,
        mut observer: Option<&mut Observer>,
    ) -> Result<(), Ending> {
        let mut settled_for = 0.0;
        while settled_for < max_time {
            let step = self
                .clock
                .advance(&mut self.world)
                .map_err(|e| Ending::new(Status::Diverged, format!("while relaxing: {e}; {STEP_HINT}")))?;
            settled_for += step.dt;
            self.report.stats.relax_steps += 1;
            self.carried.twist.step(&self.world.rods[0]);
            self.count_step(&step.report);
            self.penetration(step.report.max_penetration, || "while relaxing".to_string())?;
            if let Some(observer) = observer.as_deref_mut() {
                if self.report.stats.relax_steps % RELAX_OBSERVED == 0 {
                    let points = self.world.rods[0].positions();
                    self.observe(observer, &points, self.l_k_bar(), 0.0)?;
                }
            }
            let ke = self.kinetic_energy();
            if ke <= self.params.relax_tolerance * step.report.energies.total() {
                break;
            }
        }
        Ok(())
    }

    /// The loading program, stage by stage; the knot's type is checked at
    /// the end.
    fn program(&mut self, observer: &mut Observer) -> Result<(), Ending> {
        self.program_start = self.l_k_arc_bar();
        for index in 0..self.program.len() {
            self.stage = index;
            match self.program[index] {
                LoadStage::Hold(h) => self.hold(h.seconds, observer)?,
                LoadStage::Rotate(r) => self.rotate(r, observer)?,
                stage => self.travel(stage, observer)?,
            }
        }
        if let Some(expected) = self.alexander.clone() {
            let points = self.world.rods[0].positions();
            let det = knot::knot_determinant(&points).ok();
            self.report.determinant_final = det;
            self.determinant(det, || "at the end".to_string())?;
            let alexander = knot::alexander(&points).ok();
            self.report.alexander_final = alexander.clone();
            if alexander.as_ref() != Some(&expected) {
                return Err(Ending::new(
                    Status::TopologyChanged,
                    format!(
                        "Alexander polynomial {} at the end, expected {}: strands passed through each other; \
                         {STEP_HINT}",
                        alexander_text(alexander.as_ref()),
                        expected
                    ),
                ));
            }
        }
        self.snapshot_now(SnapshotLabel::Final);
        Ok(())
    }

    /// One world step, counted, with the loads of the current phase; an
    /// `Ending` when it diverges or penetrates. Returns the step's report and
    /// size.
    pub(super) fn step(&mut self, phase: Phase) -> Result<(WorldStepReport, f64), Ending> {
        if phase.spares_sliding() {
            let gamma = self.world.env.damping;
            for rod in 0..self.world.rods.len() {
                self.world
                    .set_load(rod, |rod, load| sliding::exempt_sliding(rod, gamma, load));
            }
        }
        self.hang_tail_load(phase.spares_sliding());
        let (step, dt) = match self.clock.advance(&mut self.world) {
            Ok(s) => (s.report, s.dt),
            Err(e) => return Err(Ending::new(Status::Diverged, format!("{e}; {STEP_HINT}"))),
        };
        let kinetic_energy = self.kinetic_energy();
        let force = self.pulling_force();
        let c = &mut self.carried;
        c.time += dt;
        c.twist.step(&self.world.rods[0]);
        c.peak_kinetic_energy = c.peak_kinetic_energy.max(kinetic_energy);
        c.impulse += dt * force;
        c.impulse_time += dt;
        if self.alexander.is_none() {
            let forces = clamp_forces(&self.world, &self.clamps, &self.axis);
            for (i, f) in c.clamp_impulses.iter_mut().zip(forces) {
                *i += dt * f;
            }
        }
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

    /// Enters `phase` of the current stage: the contact solve at its
    /// tolerance, its damping, loads and largest step (a constant step,
    /// `adaptive_dt` false, stays the case's).
    pub(super) fn enter_phase(&mut self, phase: Phase) {
        self.begin(phase, Some(self.stage));
        self.world.contact.solver.tolerance = phase.contact_tolerance(self.params.contact_tolerance);
        self.world.env.damping = phase.damping(self.params.damping, RELAX_DAMPING / self.scales.time_unit);
        if !phase.spares_sliding() {
            for rod in 0..self.world.rods.len() {
                self.world.set_load(rod, |_, load| load.fill(0.0));
            }
            self.hang_tail_load(false);
        }
        if self.params.adaptive_dt {
            self.clock.rescale(phase.dt_max(self.params.time_step()));
        }
    }

    /// A new entry in the report's phases, from here.
    fn begin(&mut self, phase: Phase, stage: Option<usize>) {
        let at = self.l_k_bar();
        self.report.phases.push(PhaseSpan::new(phase, stage, at));
    }

    /// Ends the current phase's span with `outcome`.
    pub(super) fn end_phase(&mut self, outcome: Outcome) {
        if let Some(span) = self.report.phases.last_mut() {
            span.outcome = Some(outcome);
        }
    }

    /// Counts `step` in the current phase, which now ends here.
    fn count_step(&mut self, step: &WorldStepReport) {
        let at = self.l_k_bar();
        if let Some(span) = self.report.phases.last_mut() {
            span.steps += 1;
            span.newton_iterations += u64::from(step.newton_iterations);
            span.contact_sweeps += step.contact_sweeps as u64;
            span.to_l_k_bar = at;
        }
    }

    /// One sample of eq. (11), the braid's shape, the energies and the
    /// linking number, taken in `phase`. Returns the rod's node positions.
    pub(super) fn sample(
        &mut self,
        phase: Phase,
        step: &WorldStepReport,
        dt: f64,
        l_k_bar: f64,
    ) -> Vec<Vector3<f64>> {
        let params = self.params;
        let bend = self.is_bend();
        if bend {
            self.sample_bend();
        }
        let l_k_arc_bar = self.l_k_arc_bar();
        let now = self.pulling_force();
        let rod = &self.world.rods[0];
        let c = &mut self.carried;
        let force = if c.impulse_time > 0.0 {
            c.impulse / c.impulse_time
        } else {
            now
        };
        (c.impulse, c.impulse_time) = (0.0, 0.0);
        let points = rod.positions();
        let energy_unit = params.bending_stiffness() / params.h;
        let energies = step.energies;
        let pairs = self.world.contacts().iter().map(|c| (c.nodes[0], c.nodes[2]));
        let braid = if bend {
            None
        } else {
            measurements::braid(pairs, c.mid)
        };
        let geometry = braid.map(|b| {
            let (p, q) = b.loop_ends();
            (
                measurements::loop_geometry(&points, p, q),
                measurements::braid_shape(&points, &b),
                energies::within(rod, b.first.0..p + 1) + energies::within(rod, q..b.second.1 + 2),
                energies::within(rod, p + 1..q),
            )
        });
        let (width, height) = geometry.map_or((0.0, 0.0), |(g, ..)| (g.width, g.height));
        let (epsilon, phi) = geometry.map_or((0.0, 0.0), |(_, b, ..)| (b.epsilon, b.phi));
        let (e_braid, e_loop) = geometry.map_or((0.0, 0.0), |(.., braid, lp)| (braid, lp));
        if let Some((g, ..)) = geometry {
            c.mid = (g.start + g.end) / 2;
        }
        let (torque, lk, end_turns) = if bend {
            (0.0, 0.0, 0.0)
        } else {
            let torque = twist::clamp_torque(rod, self.world.stepper(0));
            (torque, c.twist.linking_number(rod), c.twist.end_turns(rod))
        };
        self.report.series.push(Sample {
            time: c.time,
            l_k_bar,
            l_k_arc_bar,
            l_c_over_l: 1.0 - l_k_bar * params.h / params.rest_length(),
            force,
            f_bar: force / force_unit(params),
            width,
            height,
            h_bar: if width > 0.0 { height / width } else { 0.0 },
            kinetic_energy: std::mem::take(&mut c.peak_kinetic_energy),
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
            e_braid_bar: e_braid / energy_unit,
            e_loop_bar: e_loop / energy_unit,
            lk,
            end_turns,
            m_bar: torque * params.h / params.bending_stiffness(),
            stage: self.stage,
        });
        self.sample_phases.push(phase);
        if bend {
            return self.world.rods.iter().flat_map(Rod::positions).collect();
        }
        points
    }

    /// A bend's own sample: each pulled clamp's F bar (averaged over the
    /// interval, as F bar is), each rod's elastic energy and whether the
    /// rods have come apart ([`PARTED`]); a hitch's: its two clamps' F bar,
    /// its rod's energy (the second 0) and whether it has slipped round the
    /// cylinder ([`HITCH_SLIPPED_TURNS`]).
    fn sample_bend(&mut self) {
        let params = self.params;
        let c = &mut self.carried;
        let forces = if c.impulse_time > 0.0 {
            c.clamp_impulses.map(|i| i / c.impulse_time)
        } else {
            clamp_forces(&self.world, &self.clamps, &self.axis)
        };
        c.clamp_impulses = [0.0; 2];
        let energy_unit = params.bending_stiffness() / params.h;
        let rods = &self.world.rods;
        let positions: Vec<Vec<Vector3<f64>>> = rods.iter().map(Rod::positions).collect();
        let energy_bar = [0, 1].map(|i| {
            rods.get(i)
                .map_or(0.0, |rod| energies::within(rod, 0..rod.nodes()) / energy_unit)
        });
        let edge = rods[0].rest_len[0];
        let apart = match &self.cylinder {
            Some(cylinder) => knot::wrap_turns(&positions[0], cylinder).abs() < HITCH_SLIPPED_TURNS,
            None => {
                let within =
                    |radii: f64| knot::closest_approach(&positions, params.h, edge, radii * params.h, true);
                // Rods with knots of their own bend however they lie.
                let straight = self.own_knots || energy_bar.iter().all(|&e| e < PARTED_ENERGY_BAR);
                within(PARTED).is_none() && (straight || within(PARTED_FAR).is_none())
            }
        };
        let spans = (self.own_knots).then(|| {
            [0, 1].map(|r| knot::self_contact_span(&positions[r], params.h, edge, PARTED * params.h))
        });
        let (knots_apart_bar, knots_touch) = match spans {
            Some([Some(a), Some(b)]) => {
                let own = [positions[0][a].to_vec(), positions[1][b].to_vec()];
                let centroid = |p: &[Vector3<f64>]| p.iter().sum::<Vector3<f64>>() / p.len() as f64;
                let apart = (centroid(&own[0]) - centroid(&own[1])).dot(&self.axis) / params.h;
                let touch = knot::closest_approach(&own, params.h, edge, PARTED * params.h, true).is_some();
                (Some(apart), Some(touch))
            }
            _ => (None, None),
        };
        self.report.bend_series.push(BendSample {
            f_bar: forces.map(|f| f / force_unit(params)),
            energy_bar,
            apart,
            tails_free: c.tails == Tails::Free,
            knots_apart_bar,
            knots_touch,
        });
    }

    /// Hands the observer the progress after a sample at `l_k_bar`, `within`
    /// (0..1) of the way through the current stage; an `Ending` when it
    /// cancels.
    pub(super) fn observe(
        &mut self,
        observer: &mut Observer,
        points: &[Vector3<f64>],
        l_k_bar: f64,
        within: f64,
    ) -> Result<(), Ending> {
        let stages = self.program.len() as f64;
        let progress = Progress {
            fraction: ((self.stage as f64 + within.clamp(0.0, 1.0)) / stages).clamp(0.0, 1.0),
            l_k_bar,
            h_bar: self.report.series.last().map_or(0.0, |s| s.h_bar),
            steps: self.report.stats.steps,
        };
        if observer(&progress, points) {
            Ok(())
        } else {
            Err(Ending::new(Status::Cancelled, Status::Cancelled.to_string()))
        }
    }

    /// The detection thresholds of events.
    pub(super) fn criteria(&self) -> InversionCriteria {
        InversionCriteria::default()
    }

    /// Records `event` of the current stage.
    pub(super) fn record(&mut self, event: Event) {
        self.report.events.push(event);
    }

    /// The report, with the ending's status and the run's statistics.
    fn finish(self, ending: Ending) -> CaseReport {
        let bend = self.is_bend();
        let clamp_points = self.clamp_points();
        let Case {
            mut report,
            world,
            clock,
            sample_phases,
            started,
            ..
        } = self;
        report.status = ending.status;
        report.reason = ending.reason;
        report.close_events();
        if bend {
            report.close_bend();
        }
        report.scaling = Some(Scaling::of(&report.params));
        report.quasi_static = QuasiStatic::of(&report, &sample_phases);
        if report.status != Status::Completed {
            report.inversion = None;
            report.hysteresis = None;
            let at = l_k_bar_of(clamp_points, &report.params);
            report.snapshots.push(Snapshot::capture(
                &world,
                SnapshotLabel::Failure,
                at,
                clock.elapsed,
            ));
        }
        report.stats.rejected_steps = clock.rejected;
        report.stats.smallest_dt = clock.smallest;
        report.stats.wall_time = started.elapsed().as_secs_f64();
        report.stats.detection_time = world.counters.detection.as_secs_f64();
        report.stats.contact_time = world.counters.contact_solve.as_secs_f64();
        report.stats.dynamics_time = world.counters.dynamics.as_secs_f64();
        report
    }
}
