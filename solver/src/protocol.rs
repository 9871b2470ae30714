//! The tightening protocol of paper Sec. 4: build the knot, clamp both ends
//! (equal material frames, no relative rotation), relax with the ends held,
//! then pull the clamps apart along the line joining them at a steady speed,
//! sampling the measurements of eq. (11) at a fixed interval of l_k bar.
use crate::case::CaseParams;
use crate::contact::gauss_seidel::GaussSeidelOptions;
use crate::external::Environment;
use crate::knot;
use crate::material::Material;
use crate::measurements::{self, Inversion, InversionCriteria, Sample};
use crate::pipeline::{ContactOptions, World};
use crate::rod::{End, Rod};
use crate::stepper::NewtonOptions;
use crate::time_step::{AdaptiveOptions, TimeStep};
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

impl std::fmt::Display for Status {
    /// The status word of the reports and the API (the serde names).
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(match self {
            Status::Completed => "completed",
            Status::Invalid => "invalid",
            Status::Diverged => "diverged",
            Status::Penetrated => "penetrated",
            Status::TopologyChanged => "topology_changed",
            Status::Cancelled => "cancelled",
        })
    }
}

/// A centreline snapshot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    pub label: String,
    pub l_k_bar: f64,
    pub points: Vec<[f64; 3]>,
    /// The contacts carrying load at this frame (empty in frames stored before
    /// they were recorded).
    #[serde(default)]
    pub contacts: Vec<FrameContact>,
}

/// A loaded contact of a frame: the closest points on the two segments (m)
/// and the magnitude of the contact force (N).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameContact {
    pub a: [f64; 3],
    pub b: [f64; 3],
    pub force: f64,
}

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
    /// The inversion point, `None` when H bar never snapped.
    pub inversion: Option<Inversion>,
    pub series: Vec<Sample>,
    pub frames: Vec<Frame>,
    pub stats: Stats,
}

/// Progress handed to the caller after every sample.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Progress {
    /// Fraction of the pull done, from the start to the stop condition (0..1).
    pub fraction: f64,
    pub l_k_bar: f64,
    pub h_bar: f64,
    pub steps: u64,
}

/// Penetration (fraction of h) that ends a case as `Penetrated`.
const MAX_PENETRATION: f64 = 0.5;
/// Frames kept around the newest sample for the inversion snapshots.
const FRAME_HISTORY: usize = 40;
/// Stored frames (the report's size budget, about 20 kB each at K = 301): one
/// every `FRAME_SPACING` in l_k bar along the pull, and every
/// `SNAP_FRAME_SPACING` within `SNAP_WINDOW` either side of the inversion, so
/// that a viewer steps through the snap (about 40 frames in all).
const FRAME_SPACING: f64 = 20.0;
const SNAP_FRAME_SPACING: f64 = 2.0;
const SNAP_WINDOW: f64 = 10.0;
/// Damping rate (1/s) while relaxing.
const RELAX_DAMPING: f64 = 20.0;

/// Runs one case. `observer` sees progress after every sample and returns
/// `false` to cancel.
pub fn run(params: &CaseParams, observer: &mut dyn FnMut(&Progress) -> bool) -> CaseReport {
    run_observed(params, &mut |progress, _| observer(progress))
}

/// [`run`] with the rod's centre line (node positions) handed to the
/// observer with every sample's progress.
pub fn run_observed(
    params: &CaseParams,
    observer: &mut dyn FnMut(&Progress, &[Vector3<f64>]) -> bool,
) -> CaseReport {
    let started = std::time::Instant::now();
    let mut report = CaseReport {
        status: Status::Completed,
        reason: String::new(),
        params: params.clone(),
        determinant_initial: None,
        determinant_final: None,
        inversion: None,
        series: Vec::new(),
        frames: Vec::new(),
        stats: Stats::default(),
    };
    let shape = match params.validated_start() {
        Ok(s) => s,
        Err(errors) => {
            report.status = Status::Invalid;
            report.reason = errors
                .iter()
                .map(|e| e.to_string())
                .collect::<Vec<_>>()
                .join("; ");
            return report;
        }
    };
    let expected = knot::expected_determinant(params.n);
    report.determinant_initial = knot::knot_determinant(&shape.points).ok();
    if report.determinant_initial != Some(expected) {
        report.status = Status::Invalid;
        report.reason = format!(
            "the start shape has knot determinant {}, expected {expected}",
            determinant_text(report.determinant_initial)
        );
        return report;
    }
    let material = Material {
        youngs_modulus: params.youngs_modulus,
        poisson_ratio: params.poisson_ratio,
        density: params.density,
    };
    let mut rod = match Rod::new(&shape.points, params.h, material) {
        Ok(r) => r,
        Err(e) => {
            report.status = Status::Invalid;
            report.reason = format!("rod: {e}");
            return report;
        }
    };
    rod.clamp(End::Start);
    rod.clamp(End::Finish);
    let ei = params.bending_stiffness();
    let force_unit = ei / (params.h * params.h);
    let newton = NewtonOptions {
        force_scale: Some(force_unit),
        ..NewtonOptions::default()
    };
    let defaults = ContactOptions::default();
    let contact = ContactOptions {
        friction: params.mu,
        friction_law: params.friction_law,
        rolling: params.rolling,
        solver: GaussSeidelOptions {
            tolerance: params.contact_tolerance,
            ..defaults.solver
        },
        ..defaults
    };
    let env = Environment {
        gravity: Vector3::from(params.gravity),
        damping: RELAX_DAMPING,
    };
    let mut world = World::new(vec![rod], env, contact, newton);
    let dt = params.time_step();
    let mut clock = TimeStep::new(if params.adaptive_dt {
        AdaptiveOptions::up_to(dt)
    } else {
        AdaptiveOptions::fixed(dt)
    });
    let l_k_bar_of = |w: &World| l_k_bar(w, params);

    // Relaxation with the ends held.
    let mut grad = vec![0.0; world.rods[0].ndof()];
    let mut relaxed_for = 0.0;
    while relaxed_for < params.relax_time {
        let step = match clock.advance(&mut world) {
            Ok(s) => s,
            Err(e) => {
                let reason = format!("while relaxing: {e}");
                return finish(report, world, &clock, Status::Diverged, reason, started);
            }
        };
        relaxed_for += step.dt;
        report.stats.relax_steps += 1;
        if step.report.max_penetration > MAX_PENETRATION * params.h {
            let reason = format!(
                "penetration {:.3} h exceeds {MAX_PENETRATION} h while relaxing",
                step.report.max_penetration / params.h
            );
            return finish(report, world, &clock, Status::Penetrated, reason, started);
        }
        let ke = world.rods[0].kinetic_energy();
        let elastic =
            crate::energies::evaluate(&world.rods[0], crate::energies::Terms::ALL, &mut grad, None).total();
        if ke <= params.relax_tolerance * elastic {
            break;
        }
    }
    let det = knot::knot_determinant(&world.rods[0].positions()).ok();
    if det != Some(expected) {
        report.determinant_final = det;
        let reason = format!(
            "knot determinant {} after relaxing, expected {expected}",
            determinant_text(det)
        );
        return finish(report, world, &clock, Status::TopologyChanged, reason, started);
    }
    report.frames.push(frame(&world, "relaxed", l_k_bar_of(&world)));

    // Pull both clamps apart along the line joining them.
    let axis = {
        let r = &world.rods[0];
        (r.node(r.nodes() - 1) - r.node(0)).normalize()
    };
    world.env.damping = params.damping;
    world.rods[0].move_clamp(End::Start, -axis * params.pull_speed);
    world.rods[0].move_clamp(End::Finish, axis * params.pull_speed);
    let start_l_k_bar = l_k_bar_of(&world);
    let mut next_sample = start_l_k_bar;
    let mut next_frame = start_l_k_bar - FRAME_SPACING;
    // After the inversion: the next dense frame and where the dense frames stop.
    let mut after_snap: Option<(f64, f64)> = None;
    let mut history: VecDeque<Frame> = VecDeque::with_capacity(FRAME_HISTORY);
    let criteria = InversionCriteria::default();
    // The loop's middle node, from the builder and then tracked from each sample's braid ends.
    let mut mid = shape.loop_middle;
    let mut time = 0.0;
    let mut peak_kinetic_energy: f64 = 0.0;
    loop {
        let (step, dt) = match clock.advance(&mut world) {
            Ok(s) => (s.report, s.dt),
            Err(e) => return finish(report, world, &clock, Status::Diverged, e.to_string(), started),
        };
        time += dt;
        peak_kinetic_energy = peak_kinetic_energy.max(world.rods[0].kinetic_energy());
        report.stats.steps += 1;
        report.stats.newton_iterations += u64::from(step.newton_iterations);
        report.stats.contact_sweeps += step.contact_sweeps as u64;
        if step.max_penetration > MAX_PENETRATION * params.h {
            let reason = format!(
                "penetration {:.3} h exceeds {MAX_PENETRATION} h at l_k bar {:.2}",
                step.max_penetration / params.h,
                l_k_bar_of(&world)
            );
            return finish(report, world, &clock, Status::Penetrated, reason, started);
        }
        let l_k_bar = l_k_bar_of(&world);
        if l_k_bar > next_sample {
            continue;
        }
        next_sample = l_k_bar - params.sample_interval;
        let rod = &world.rods[0];
        let stepper = world.stepper(0);
        let f_start = -stepper.clamp_reaction(rod, End::Start).0.dot(&axis);
        let f_finish = stepper.clamp_reaction(rod, End::Finish).0.dot(&axis);
        let force = 0.5 * (f_start + f_finish);
        let points = rod.positions();
        let pairs = world.contacts().iter().map(|c| (c.nodes[0], c.nodes[2]));
        let braid = measurements::braid(pairs, mid);
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
            mid = (g.start + g.end) / 2;
        }
        report.series.push(Sample {
            time,
            l_k_bar,
            l_c_over_l: 1.0 - l_k_bar * params.h / params.length,
            force,
            f_bar: force / force_unit,
            width,
            height,
            h_bar: if width > 0.0 { height / width } else { 0.0 },
            kinetic_energy: std::mem::take(&mut peak_kinetic_energy),
            contacts: step.contacts,
            active_contacts: step.active_contacts,
            max_penetration_over_h: step.max_penetration / params.h,
            epsilon,
            phi,
            newton_iterations: step.newton_iterations,
            dt,
        });
        if history.len() == FRAME_HISTORY {
            history.pop_front();
        }
        history.push_back(frame(&world, "sample", l_k_bar));
        if report.inversion.is_none() {
            report.inversion = measurements::detect_inversion(&report.series, &criteria);
            if let Some(inv) = &report.inversion {
                let snap = inv.l_k_bar;
                // The detection lags the snap: the frames on both sides are in the history.
                let mut stored: Vec<f64> = Vec::new();
                let mut offset = SNAP_WINDOW;
                while offset >= -SNAP_WINDOW {
                    let label = if offset == 0.0 {
                        "at_inversion"
                    } else if offset == SNAP_FRAME_SPACING {
                        "before_inversion"
                    } else if offset > 0.0 {
                        "near_inversion"
                    } else {
                        "after_inversion"
                    };
                    let nearest = history
                        .iter()
                        .filter(|f| offset > 0.0 || f.l_k_bar <= snap)
                        .min_by(|a, b| {
                            (a.l_k_bar - snap - offset)
                                .abs()
                                .total_cmp(&(b.l_k_bar - snap - offset).abs())
                        });
                    if let Some(f) =
                        nearest.filter(|f| (f.l_k_bar - snap - offset).abs() < SNAP_FRAME_SPACING / 2.0)
                    {
                        if !stored.contains(&f.l_k_bar) {
                            stored.push(f.l_k_bar);
                            report.frames.push(Frame {
                                label: label.to_string(),
                                ..f.clone()
                            });
                        }
                    }
                    offset -= SNAP_FRAME_SPACING;
                }
                let lowest = stored.iter().copied().fold(snap, f64::min);
                after_snap = Some((lowest - SNAP_FRAME_SPACING, snap - SNAP_WINDOW));
            }
        } else if let Some((next, end)) = after_snap {
            if l_k_bar <= next && l_k_bar >= end {
                report.frames.push(frame(&world, "after_inversion", l_k_bar));
                after_snap = Some((l_k_bar - SNAP_FRAME_SPACING, end));
            }
        }
        if l_k_bar <= next_frame {
            report.frames.push(frame(&world, "pull", l_k_bar));
            next_frame = l_k_bar - FRAME_SPACING;
        }
        let det = knot::knot_determinant(&points).ok();
        if det != Some(expected) {
            report.determinant_final = det;
            let reason = format!(
                "knot determinant {} at l_k bar {l_k_bar:.2}, expected {expected}",
                determinant_text(det)
            );
            return finish(report, world, &clock, Status::TopologyChanged, reason, started);
        }
        let stop_l = match (report.inversion, params.stop_after_inversion) {
            (Some(inv), Some(margin)) => (inv.l_k_bar - margin).max(params.min_l_k_bar),
            _ => params.min_l_k_bar,
        };
        let sample = report.series.last().copied().unwrap_or_default();
        let fraction = ((start_l_k_bar - l_k_bar) / (start_l_k_bar - stop_l)).clamp(0.0, 1.0);
        let progress = Progress {
            fraction,
            l_k_bar,
            h_bar: sample.h_bar,
            steps: report.stats.steps,
        };
        let keep_going = observer(&progress, &points);
        if !keep_going {
            return finish(
                report,
                world,
                &clock,
                Status::Cancelled,
                "cancelled".to_string(),
                started,
            );
        }
        let tight = params.max_force_bar.is_some_and(|m| sample.f_bar > m);
        if l_k_bar <= stop_l || tight {
            break;
        }
    }
    let det = knot::knot_determinant(&world.rods[0].positions()).ok();
    report.determinant_final = det;
    if det != Some(expected) {
        let reason = format!(
            "knot determinant {} at the end, expected {expected}",
            determinant_text(det)
        );
        return finish(report, world, &clock, Status::TopologyChanged, reason, started);
    }
    let l_end = l_k_bar_of(&world);
    report.frames.push(frame(&world, "final", l_end));
    finish(report, world, &clock, Status::Completed, String::new(), started)
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

/// A snapshot of the world's rod.
fn frame(world: &World, label: &str, l_k_bar: f64) -> Frame {
    let points = world.rods[0].positions();
    let contacts = world
        .contacts()
        .iter()
        .zip(world.contact_forces())
        .filter(|(_, f)| f.norm() > 0.0)
        .map(|(c, f)| {
            let [a0, a1, b0, b1] = c.nodes;
            let [w0, w1, w2, w3] = c.weights;
            let a = points[a0] * w0 + points[a1] * w1;
            let b = -(points[b0] * w2 + points[b1] * w3);
            FrameContact {
                a: [a.x, a.y, a.z],
                b: [b.x, b.y, b.z],
                force: f.norm(),
            }
        })
        .collect();
    Frame {
        label: label.to_string(),
        l_k_bar,
        points: points.iter().map(|p| [p.x, p.y, p.z]).collect(),
        contacts,
    }
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
    if status != Status::Completed {
        report.inversion = None;
        let at = l_k_bar(&world, &report.params);
        report.frames.push(frame(&world, "failure", at));
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
    use super::Status;

    #[test]
    fn status_words_are_the_serde_names() {
        for s in [
            Status::Completed,
            Status::Invalid,
            Status::Diverged,
            Status::Penetrated,
            Status::TopologyChanged,
            Status::Cancelled,
        ] {
            assert_eq!(serde_json::to_value(s).unwrap(), s.to_string());
        }
    }
}
