//! A case's run: the knot built and clamped, relaxed, then its loading
//! program walked stage by stage; the steps, samples and checks every stage
//! shares; the report at the end.
use super::adaptive::{Outcome, Phase, RELAX_DAMPING};
use super::report::{CaseReport, Event, PhaseSpan, Progress, QuasiStatic, Scaling, Status};
use super::twist::{self, Tracker};
use crate::case::{CaseParams, LoadStage, Scales, ValidCase};
use crate::contact::GaussSeidelOptions;
use crate::energies;
use crate::external::{Environment, sliding};
use crate::knot::StartShape;
use crate::knot::{self, Alexander, Family};
use crate::material::Material;
use crate::measurements::{self, InversionCriteria, Sample};
use crate::pipeline::{ContactOptions, World, WorldStepReport};
use crate::rod::{End, Rod};
use crate::snapshot::{Snapshot, SnapshotLabel};
use crate::stepper::NewtonOptions;
use crate::time_step::{AdaptiveOptions, TimeStep};
use nalgebra::Vector3;
use std::collections::VecDeque;
use std::time::Instant;

/// Penetration (fraction of h) that ends a case as `Penetrated`.
const MAX_PENETRATION: f64 = 0.5;
/// What to change when a case fails in a step: the numerical options that
/// hold contacts and knots together.
const STEP_HINT: &str = "a smaller dt, adaptive_dt, more nodes or contact_solve \"implicit\" may hold it";
/// Snapshots kept around the newest sample for those around an event.
pub(super) const SNAPSHOT_HISTORY: usize = 40;

/// The observer of a run: progress and the centre line after every sample;
/// `false` cancels.
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
    let ending = run.relax().and_then(|()| run.program(observer));
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
/// type checked, and the world holding it as a clamped DER rod with the
/// case's contact, friction and time-stepping options, its inertia scaled and
/// its weight physical ([`CaseParams::scales`]).
fn build(case: &ValidCase, report: &mut CaseReport) -> Result<World, String> {
    let (params, shape) = (case.params(), case.start());
    let points = shape.points();
    report.determinant_initial = knot::knot_determinant(points).ok();
    report.alexander_initial = knot::alexander(points).ok();
    if report.alexander_initial.as_ref() != Some(&shape.alexander) {
        return Err(format!(
            "the start shape has Alexander polynomial {}, expected {}",
            alexander_text(report.alexander_initial.as_ref()),
            shape.alexander
        ));
    }
    let scales = params.scales();
    let material = Material {
        youngs_modulus: params.youngs_modulus,
        poisson_ratio: params.poisson_ratio,
        density: params.density * scales.mass_scale,
    };
    let mut rod = Rod::new(points, params.h, material).map_err(|e| format!("rod: {e}"))?;
    report.writhe = knot::writhe(points);
    let family = params.knot().map_err(|e| e.to_string())?;
    report.start_twist = params.start_twist.unwrap_or_else(|| family.twist(report.writhe));
    rod.add_twist(report.start_twist);
    for (_, end) in shape.clamps() {
        rod.clamp(end);
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
        geometry: params.contact_geometry,
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

/// The force unit of F bar: EI / h^2 (eq. 11).
pub(super) fn force_unit(params: &CaseParams) -> f64 {
    params.bending_stiffness() / (params.h * params.h)
}

/// The pulling force (N) on the knot along `axis` after the last step: the
/// mean of the two clamps' reactions along the pull, or of the springs'
/// tensions when the clamps sit on springs (a soft stage).
fn pulling_force(world: &World, axis: &Vector3<f64>) -> f64 {
    let (rod, stepper) = (&world.rods[0], world.stepper(0));
    if let [start, finish] = rod.springs[..] {
        return 0.5 * (finish.force(&rod.q, finish.anchor) - start.force(&rod.q, start.anchor));
    }
    let start = -stepper.clamp_reaction(rod, End::Start).0.dot(axis);
    let finish = stepper.clamp_reaction(rod, End::Finish).0.dot(axis);
    0.5 * (start + finish)
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
    /// The loop's middle node, from the builder and then tracked from each
    /// sample's braid ends.
    pub(super) mid: usize,
    pub(super) twist: Tracker,
    /// The latest samples' snapshots, for those around an event.
    pub(super) history: VecDeque<Snapshot>,
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
    /// The knot's Alexander polynomial, and its determinant |Delta(-1)|
    /// checked at every sample.
    alexander: Alexander,
    expected: u64,
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
        let axis = (rod.node(rod.nodes() - 1) - rod.node(0)).normalize();
        let carried = Carried {
            time: 0.0,
            peak_kinetic_energy: 0.0,
            impulse: 0.0,
            impulse_time: 0.0,
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
            expected: start.alexander.determinant(),
            scales: params.scales(),
            axis,
            program: params.program(),
            program_start: 0.0,
            stage: 0,
            started,
        }
    }

    pub(super) fn l_k_bar(&self) -> f64 {
        let r = &self.world.rods[0];
        (self.params.length - (r.node(r.nodes() - 1) - r.node(0)).norm()) / self.params.h
    }

    /// The knot's own length, which the stopping rules and the adaptive
    /// schedule's windows act on (`measurements::l_k_arc_bar`).
    pub(super) fn l_k_arc_bar(&self) -> f64 {
        measurements::l_k_arc_bar(&self.world.rods[0].positions(), self.params.h)
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
    fn relax(&mut self) -> Result<(), Ending> {
        self.begin(Phase::Settle, None);
        let spec = self.params.knot_spec();
        if self.params.adaptive_dt && spec.knot_length() < spec.length {
            self.clock.rescale(Phase::Settle.dt_max(self.params.time_step()));
        }
        self.settle(self.params.relax_limit())?;
        let points = self.world.rods[0].positions();
        self.topology(&points, || "after relaxing".to_string())?;
        let at = self.l_k_bar();
        self.report.snapshots.push(Snapshot::capture(
            &self.world,
            SnapshotLabel::Relaxed,
            at,
            self.clock.elapsed,
        ));
        Ok(())
    }

    /// Damped steps with the clamps held until the kinetic energy is a
    /// `relax_tolerance` fraction of the elastic energy, or for `max_time`.
    pub(super) fn settle(&mut self, max_time: f64) -> Result<(), Ending> {
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
            let ke = self.world.rods[0].kinetic_energy();
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
        let points = self.world.rods[0].positions();
        let det = knot::knot_determinant(&points).ok();
        self.report.determinant_final = det;
        self.determinant(det, || "at the end".to_string())?;
        let alexander = knot::alexander(&points).ok();
        self.report.alexander_final = alexander.clone();
        if alexander.as_ref() != Some(&self.alexander) {
            return Err(Ending::new(
                Status::TopologyChanged,
                format!(
                    "Alexander polynomial {} at the end, expected {}: strands passed through each other; \
                     {STEP_HINT}",
                    alexander_text(alexander.as_ref()),
                    self.alexander
                ),
            ));
        }
        let at = self.l_k_bar();
        self.report.snapshots.push(Snapshot::capture(
            &self.world,
            SnapshotLabel::Final,
            at,
            self.clock.elapsed,
        ));
        Ok(())
    }

    /// One world step, counted, with the loads of the current phase; an
    /// `Ending` when it diverges or penetrates. Returns the step's report and
    /// size.
    pub(super) fn step(&mut self, phase: Phase) -> Result<(WorldStepReport, f64), Ending> {
        if phase.spares_sliding() {
            let gamma = self.world.env.damping;
            self.world
                .set_load(0, |rod, load| sliding::exempt_sliding(rod, gamma, load));
        }
        let (step, dt) = match self.clock.advance(&mut self.world) {
            Ok(s) => (s.report, s.dt),
            Err(e) => return Err(Ending::new(Status::Diverged, format!("{e}; {STEP_HINT}"))),
        };
        let c = &mut self.carried;
        c.time += dt;
        c.twist.step(&self.world.rods[0]);
        c.peak_kinetic_energy = c.peak_kinetic_energy.max(self.world.rods[0].kinetic_energy());
        c.impulse += dt * pulling_force(&self.world, &self.axis);
        c.impulse_time += dt;
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
            self.world.set_load(0, |_, load| load.fill(0.0));
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
        let rod = &self.world.rods[0];
        let c = &mut self.carried;
        let force = if c.impulse_time > 0.0 {
            c.impulse / c.impulse_time
        } else {
            pulling_force(&self.world, &self.axis)
        };
        (c.impulse, c.impulse_time) = (0.0, 0.0);
        let points = rod.positions();
        let energy_unit = params.bending_stiffness() / params.h;
        let energies = step.energies;
        let pairs = self.world.contacts().iter().map(|c| (c.nodes[0], c.nodes[2]));
        let braid = measurements::braid(pairs, c.mid);
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
        let torque = twist::clamp_torque(rod, self.world.stepper(0));
        self.report.series.push(Sample {
            time: c.time,
            l_k_bar,
            l_k_arc_bar: measurements::l_k_arc_bar(&points, params.h),
            l_c_over_l: 1.0 - l_k_bar * params.h / params.length,
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
            lk: c.twist.linking_number(rod),
            end_turns: c.twist.end_turns(rod),
            m_bar: torque * params.h / params.bending_stiffness(),
            stage: self.stage,
        });
        self.sample_phases.push(phase);
        points
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
        report.scaling = Some(Scaling::of(&report.params));
        report.quasi_static = QuasiStatic::of(&report, &sample_phases);
        if report.status != Status::Completed {
            report.inversion = None;
            report.hysteresis = None;
            let r = &world.rods[0];
            let at = (report.params.length - (r.node(r.nodes() - 1) - r.node(0)).norm()) / report.params.h;
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
