//! One time step of several rods with frictional contact (paper Sec. 3.2):
//!
//! 1. detection on the start-of-step state: broad phase, then segment-segment
//!    closest points, pairs closer than r_a + r_b + margin;
//! 2. free velocities evaluated explicitly from the start-of-step state,
//!    v_free = v + dt M^-1 (F_int + F_ext), as in the paper's code, so that the
//!    mass-only Delassus operator W = dt H^T M^-1 H is the consistent one;
//! 3. the frictional contact problem (Signorini + Coulomb, eqs. 8-9) with the
//!    gap closed within the step, solved by block Gauss-Seidel;
//! 4. the implicit rod step (eq. 7) of every rod with the contact forces fixed
//!    (F^fr of eq. 7c).
//!
//! Contact forces couple rods only through step 3, so each rod's Newton system
//! stays banded and a step costs O(K) plus O(contacts * sweeps).
//!
//! With [`ContactSolve::Implicit`] steps 2-3 see the implicit step instead
//! ([`implicit`]): the free velocities come from a contact-free implicit step
//! and the Delassus operator from its Newton matrix.
mod implicit;
use crate::contact::broad_phase::{BroadPhase, Segment, neighbour_gap};
use crate::contact::gauss_seidel::{ContactError, ContactPoint, GaussSeidel, GaussSeidelOptions, SpinDofs};
use crate::contact::segment::closest_points;
use crate::contact::{Candidates, ContactSolve, FrictionLaw, narrow_phase};
use crate::counters::Counters;
use crate::energies::{self, Energies, Terms};
use crate::external::{Environment, gravity};
use crate::rod::{Rod, RodState, node_dof, theta_dof};
use crate::stepper::{NewtonOptions, StepError, StepReport, Stepper};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Contact model parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactOptions {
    /// Whether contact is detected and resolved at all.
    pub enabled: bool,
    /// Coulomb friction coefficient mu, eq. (9).
    pub friction: f64,
    /// Which tangential forces the friction bound admits (eqs. 9-10).
    pub friction_law: FrictionLaw,
    /// Friction acts at the rods' surfaces: a contact's relative velocity
    /// includes the touching surfaces' spin about each rod's axis (twist
    /// rates times the radius), and friction puts a torque on each twist, so
    /// a rod can roll on another. `false`: friction at the centre lines.
    pub rolling: bool,
    /// Detection margin added to r_a + r_b, as a fraction of the largest radius;
    /// the margin also grows with the fastest node's travel over the step.
    pub margin: f64,
    /// Fraction of a penetration removed within one step (1 = the paper's
    /// "gap closed in one step"; smaller values separate interpenetrating rods
    /// more gently).
    pub penetration_recovery: f64,
    /// The Gauss-Seidel stopping rule.
    pub solver: GaussSeidelOptions,
    /// Which free velocities and Delassus operator the contact solve uses.
    pub solve: ContactSolve,
    /// Which segment pairs get a contact force.
    pub candidates: Candidates,
}

impl Default for ContactOptions {
    fn default() -> Self {
        Self {
            enabled: true,
            friction: 0.1,
            friction_law: FrictionLaw::default(),
            rolling: true,
            margin: 0.25,
            penetration_recovery: 1.0,
            solver: GaussSeidelOptions::default(),
            solve: ContactSolve::default(),
            candidates: Candidates::default(),
        }
    }
}

/// What one world step did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WorldStepReport {
    /// Contact candidates within the margin.
    pub contacts: usize,
    /// Contacts carrying a normal force.
    pub active_contacts: usize,
    /// Largest penetration r_a + r_b - d over the contacts at the end of the step (m, 0 if none).
    pub max_penetration: f64,
    /// Gauss-Seidel sweeps and final natural-map residual (relative).
    pub contact_sweeps: usize,
    pub contact_residual: f64,
    /// Newton iterations and substeps summed over the rods.
    pub newton_iterations: u32,
    pub substeps: u32,
    /// The rods' elastic energies (eq. 6) at the step's end, summed: the
    /// steppers' final Newton iterates'.
    pub energies: Energies,
}

/// Why a world step failed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum WorldError {
    #[error("rod {rod}: {source}")]
    Step { rod: usize, source: StepError },
    #[error("contact detection: {0}")]
    Detection(String),
    /// The frictional contact solve refused its problem (non-finite or
    /// inconsistent data): the step is not taken without its contact forces.
    #[error("contact solve failed: {0}")]
    Contact(#[from] ContactError),
}

/// Several rods, their steppers and the contact machinery with reusable buffers.
#[derive(Clone)]
pub struct World {
    pub rods: Vec<Rod>,
    /// Per rod (same order as `rods`): stepper, numbering and force buffers.
    bodies: Vec<Body>,
    pub env: Environment,
    pub contact: ContactOptions,
    pub counters: Counters,
    spin_inv_inertia: Vec<f64>,
    spin_free: Vec<f64>,
    broad: BroadPhase,
    gauss_seidel: GaussSeidel,
    segments: Vec<Segment>,
    gaps: Vec<usize>,
    contacts: Vec<ContactPoint>,
    pair_ids: Vec<(usize, usize)>,
    history: ForceHistory,
    warm: Vec<Vector3<f64>>,
    inv_mass: Vec<f64>,
    v_free: Vec<Vector3<f64>>,
    /// Contact forces (on the first rod of each pair) of the last solve.
    forces: Vec<Vector3<f64>>,
    implicit: implicit::Buffers,
    saved: Saved,
}

/// A rod's stepper, its place in the world's numbering and its force buffers.
#[derive(Clone)]
struct Body {
    stepper: Stepper,
    /// Global ids of its first node and first edge (twist DOF, for rolling).
    first_node: usize,
    first_edge: usize,
    /// Offset of its DOFs in the world's concatenated DOF vector.
    first_dof: usize,
    /// Constant external load (one entry per DOF), added to F^ext.
    load: Vec<f64>,
    /// F^ext of the current step: load, gravity and contact forces.
    force: Vec<f64>,
    /// Elastic gradient, when the stepper has none cached.
    grad: Vec<f64>,
}

/// A checkpoint of the world: every rod's state and the contact warm start.
#[derive(Clone, Default)]
struct Saved {
    rods: Vec<RodState>,
    history: ForceHistory,
}

/// The contact forces of the last two solves, by segment pair, for the
/// next solve's warm start.
#[derive(Default)]
struct ForceHistory {
    /// Pair ids (sorted) and forces of the last solve, and its step.
    ids: Vec<(usize, usize)>,
    forces: Vec<Vector3<f64>>,
    dt: f64,
    /// The same for the solve before it.
    prev_ids: Vec<(usize, usize)>,
    prev_forces: Vec<Vector3<f64>>,
    prev_dt: f64,
}

impl Clone for ForceHistory {
    fn clone(&self) -> Self {
        let mut copy = Self::default();
        copy.clone_from(self);
        copy
    }

    /// Reuses this history's buffers (a checkpoint every step allocates nothing).
    fn clone_from(&mut self, source: &Self) {
        self.ids.clone_from(&source.ids);
        self.forces.clone_from(&source.forces);
        self.dt = source.dt;
        self.prev_ids.clone_from(&source.prev_ids);
        self.prev_forces.clone_from(&source.prev_forces);
        self.prev_dt = source.prev_dt;
    }
}

impl ForceHistory {
    /// The warm start of each of `pair_ids` (sorted) for a step of `dt`:
    /// where the pair was in contact at the last two solves of this step
    /// size, the force extrapolated linearly from them (the pull changes
    /// the forces smoothly, so this is closer to the solution than the last
    /// force); where only at the last, that force; else zero.
    fn warm_start(&self, pair_ids: &[(usize, usize)], dt: f64, out: &mut Vec<Vector3<f64>>) {
        out.clear();
        let extrapolate = self.dt == dt && self.prev_dt == dt;
        let (mut k, mut m) = (0, 0);
        for id in pair_ids {
            while k < self.ids.len() && self.ids[k] < *id {
                k += 1;
            }
            while m < self.prev_ids.len() && self.prev_ids[m] < *id {
                m += 1;
            }
            let last = (k < self.ids.len() && self.ids[k] == *id).then(|| self.forces[k]);
            let before = (m < self.prev_ids.len() && self.prev_ids[m] == *id).then(|| self.prev_forces[m]);
            out.push(match (last, before) {
                (Some(f1), Some(f0)) if extrapolate => 2.0 * f1 - f0,
                (Some(f1), _) => f1,
                _ => Vector3::zeros(),
            });
        }
    }

    /// Records a solve's forces: the last solve becomes the one before.
    fn push(&mut self, pair_ids: &[(usize, usize)], forces: &[Vector3<f64>], dt: f64) {
        std::mem::swap(&mut self.ids, &mut self.prev_ids);
        std::mem::swap(&mut self.forces, &mut self.prev_forces);
        self.prev_dt = self.dt;
        self.ids.clear();
        self.ids.extend_from_slice(pair_ids);
        self.forces.clear();
        self.forces.extend_from_slice(forces);
        self.dt = dt;
    }
}

/// The broad phase's skin as a fraction of the largest radius: candidate
/// pairs are searched within `margin + SKIN r` and reused until a node has
/// moved half that far (`BroadPhase::find_pairs_reusing`; the contacts are
/// the same as a fresh search's). Of the skins from 0.25 r to 2 r, 0.25 r
/// cut a mu = 0.5 case's detection time most.
const SKIN: f64 = 0.25;

impl World {
    /// A world of `rods` under `env`, each stepped with `newton`.
    pub fn new(rods: Vec<Rod>, env: Environment, contact: ContactOptions, newton: NewtonOptions) -> Self {
        let (mut total, mut total_edges, mut total_dofs) = (0, 0, 0);
        let bodies = rods
            .iter()
            .map(|r| {
                let body = Body {
                    stepper: Stepper::new(r, newton),
                    first_node: total,
                    first_edge: total_edges,
                    first_dof: total_dofs,
                    load: vec![0.0; r.ndof()],
                    force: vec![0.0; r.ndof()],
                    grad: vec![0.0; r.ndof()],
                };
                total += r.nodes();
                total_edges += r.edges();
                total_dofs += r.ndof();
                body
            })
            .collect();
        let gaps = rods
            .iter()
            .map(|r| {
                let shortest = r.rest_len.iter().cloned().fold(f64::INFINITY, f64::min);
                neighbour_gap(2.0 * r.section.radius, shortest)
            })
            .collect();
        let implicit = implicit::Buffers::new(&rods);
        Self {
            rods,
            bodies,
            env,
            contact,
            counters: Counters::default(),
            spin_inv_inertia: vec![0.0; total_edges],
            spin_free: vec![0.0; total_edges],
            broad: BroadPhase::new(),
            gauss_seidel: GaussSeidel::new(),
            segments: Vec::new(),
            gaps,
            contacts: Vec::new(),
            pair_ids: Vec::new(),
            history: ForceHistory::default(),
            warm: Vec::new(),
            inv_mass: vec![0.0; total],
            v_free: vec![Vector3::zeros(); total],
            forces: Vec::new(),
            implicit,
            saved: Saved::default(),
        }
    }

    /// Remembers the current state (rods, contact warm start, the steppers'
    /// reusable Newton matrices) so that [`World::rollback`] can return to it.
    pub fn checkpoint(&mut self) {
        self.saved.rods.resize_with(self.rods.len(), RodState::default);
        for (rod, state) in self.rods.iter().zip(&mut self.saved.rods) {
            rod.save_state(state);
        }
        self.saved.history.clone_from(&self.history);
        self.bodies.iter_mut().for_each(|b| b.stepper.checkpoint());
    }

    /// Returns to the last [`World::checkpoint`] (to redo a step differently).
    pub fn rollback(&mut self) {
        for (rod, state) in self.rods.iter_mut().zip(&self.saved.rods) {
            rod.load_state(state);
        }
        self.history.clone_from(&self.saved.history);
        self.bodies.iter_mut().for_each(|b| b.stepper.rollback());
    }

    /// Makes every stepper assemble a new Newton matrix at its next step:
    /// after a rod's constraints or springs change.
    pub fn forget_factorizations(&mut self) {
        self.bodies
            .iter_mut()
            .for_each(|b| b.stepper.forget_factorization());
    }

    /// The largest rod radius (the scale of contact tolerances).
    pub fn largest_radius(&self) -> f64 {
        self.rods.iter().map(|r| r.section.radius).fold(0.0, f64::max)
    }

    /// The stepper of rod `i` (for its clamp reactions).
    pub fn stepper(&self, i: usize) -> &Stepper {
        &self.bodies[i].stepper
    }

    /// Rod `i`'s constant external load (one entry per DOF), added to F^ext.
    pub fn load_mut(&mut self, i: usize) -> &mut [f64] {
        &mut self.bodies[i].load
    }

    /// Sets rod `i`'s external load from the rod's state: `f` gets the rod
    /// and the load (one entry per DOF) to overwrite.
    pub fn set_load(&mut self, i: usize, f: impl FnOnce(&Rod, &mut [f64])) {
        f(&self.rods[i], &mut self.bodies[i].load);
    }

    /// The contacts found at the start of the last step.
    pub fn contacts(&self) -> &[ContactPoint] {
        &self.contacts
    }

    /// Contact forces (on the first rod of each pair) of the last step.
    pub fn contact_forces(&self) -> &[Vector3<f64>] {
        &self.forces
    }

    /// Advances every rod by `dt`.
    pub fn step(&mut self, dt: f64) -> Result<WorldStepReport, WorldError> {
        self.counters.steps += 1;
        let mut report = WorldStepReport::default();
        for body in &mut self.bodies {
            body.force.copy_from_slice(&body.load);
        }
        if self.contact.enabled {
            let mut detection = self.counters.detection;
            Counters::time(&mut detection, || self.detect(dt))?;
            self.counters.detection = detection;
            self.forces.clear();
            let mut solve = self.counters.contact_solve;
            let predict = self.contact.candidates == Candidates::Predicted
                || self.contact.solve == ContactSolve::Implicit;
            if predict && !self.contacts.is_empty() {
                Counters::time(&mut solve, || self.predict(dt))?;
            }
            report.contacts = self.contacts.len();
            let implicit = self.contact.solve == ContactSolve::Implicit;
            let solved = if self.contacts.is_empty()
                || implicit && Counters::time(&mut solve, || self.solve_contacts_implicit(dt, &mut report))
            {
                Ok(())
            } else {
                Counters::time(&mut solve, || self.solve_contacts(dt, &mut report))
            };
            self.counters.contact_solve = solve;
            solved?;
        }
        let mut dynamics = self.counters.dynamics;
        let result = Counters::time(&mut dynamics, || self.step_rods(dt, &mut report));
        self.counters.dynamics = dynamics;
        result?;
        report.max_penetration = self.max_penetration();
        Ok(report)
    }

    fn detect(&mut self, dt: f64) -> Result<(), WorldError> {
        self.segments.clear();
        self.implicit.dropped.clear();
        let mut fastest: f64 = 0.0;
        let mut largest_radius: f64 = 0.0;
        for (b, rod) in self.rods.iter().enumerate() {
            largest_radius = largest_radius.max(rod.section.radius);
            for i in 0..rod.nodes() {
                fastest = fastest.max(rod.node_velocity(i).norm());
            }
            for e in 0..rod.edges() {
                self.segments.push(Segment {
                    a: rod.node(e),
                    b: rod.node(e + 1),
                    radius: rod.section.radius,
                    body: b,
                    index: e,
                });
            }
        }
        let margin = self.contact.margin * largest_radius + 2.0 * fastest * dt;
        let pairs = self
            .broad
            .find_pairs_reusing(&self.segments, &self.gaps, margin, SKIN * largest_radius)
            .map_err(|e| WorldError::Detection(e.to_string()))?;
        self.contacts.clear();
        self.pair_ids.clear();
        for (k, p) in pairs.iter().enumerate() {
            if self.contact.candidates == Candidates::Detected
                && narrow_phase::redundant(pairs, k, &self.segments)
            {
                continue;
            }
            let (sa, sb) = (&self.segments[p.i], &self.segments[p.j]);
            let (oa, ob) = (self.bodies[sa.body].first_node, self.bodies[sb.body].first_node);
            let nodes = [oa + sa.index, oa + sa.index + 1, ob + sb.index, ob + sb.index + 1];
            if let Some(mut c) =
                ContactPoint::from_pair(nodes, &p.closest, sa.radius + sb.radius, self.contact.friction)
            {
                if c.gap < 0.0 {
                    c.gap *= self.contact.penetration_recovery;
                }
                if self.contact.rolling {
                    let (ea, eb) = (
                        self.bodies[sa.body].first_edge + sa.index,
                        self.bodies[sb.body].first_edge + sb.index,
                    );
                    let lever = |seg: &Segment| {
                        let t = (seg.b - seg.a).normalize();
                        -seg.radius * t.cross(&c.normal)
                    };
                    c.spin = [(ea, lever(sa)), (eb, lever(sb))];
                }
                if self.contact.friction_law == FrictionLaw::SlidingDirection {
                    c.sliding_direction =
                        narrow_phase::sliding_direction(&self.rods, sa, sb, &p.closest, &c.normal);
                }
                self.contacts.push(c);
                self.pair_ids.push((p.i, p.j));
            }
        }
        Ok(())
    }

    /// The explicit contact solve (steps 2-3): contact forces into each
    /// rod's `force`; a [`ContactError`] ends the step before the rods move.
    fn solve_contacts(&mut self, dt: f64, report: &mut WorldStepReport) -> Result<(), WorldError> {
        for (rod, body) in self.rods.iter().zip(&mut self.bodies) {
            let grad: &[f64] = match body.stepper.elastic_gradient(rod) {
                Some(g) => g,
                None => {
                    energies::evaluate(rod, Terms::ALL, &mut body.grad, None);
                    &body.grad
                }
            };
            let force = &mut body.force;
            force.copy_from_slice(&body.load);
            gravity::add(rod, &self.env.gravity, force);
            // A free DOF's contact-free velocity, v + dt M^-1 (F - grad E),
            // damped, and its effective inverse mass (the same rule as the stepper's).
            let damp = 1.0 / self.env.damping_factor(dt);
            let free = |d: usize| {
                let m = rod.mass[d];
                (damp * (rod.velocity[d] + dt * (force[d] - grad[d]) / m), damp / m)
            };
            let off = body.first_node;
            for i in 0..rod.nodes() {
                let d = node_dof(i);
                let (v, inv_mass) = if rod.fixed[d] || rod.fixed[d + 1] || rod.fixed[d + 2] {
                    let p = &rod.prescribed_velocity;
                    (Vector3::new(p[d], p[d + 1], p[d + 2]), 0.0)
                } else {
                    let (x, y, z) = (free(d), free(d + 1), free(d + 2));
                    (Vector3::new(x.0, y.0, z.0), x.1)
                };
                self.v_free[off + i] = v;
                self.inv_mass[off + i] = inv_mass;
            }
            if self.contact.rolling {
                for e in 0..rod.edges() {
                    let d = theta_dof(e);
                    let k = body.first_edge + e;
                    (self.spin_free[k], self.spin_inv_inertia[k]) = if rod.fixed[d] {
                        (rod.prescribed_velocity[d], 0.0)
                    } else {
                        free(d)
                    };
                }
            }
            force.copy_from_slice(&body.load);
        }
        // Warm start from the last steps' forces on the same segment pairs.
        self.history.warm_start(&self.pair_ids, dt, &mut self.warm);
        let spin = self.contact.rolling.then_some(SpinDofs {
            inv_inertia: &self.spin_inv_inertia,
            free: &self.spin_free,
        });
        let sol = self.gauss_seidel.solve_with_spin(
            &self.contacts,
            &self.inv_mass,
            &self.v_free,
            spin,
            dt,
            &self.contact.solver,
            Some(&self.warm),
        )?;
        report.contact_sweeps = sol.sweeps;
        report.contact_residual = sol.residual;
        report.active_contacts = self
            .gauss_seidel
            .contact_forces()
            .iter()
            .zip(&self.contacts)
            .filter(|(f, c)| f.dot(&c.normal) > 0.0)
            .count();
        let node_forces = self.gauss_seidel.node_forces();
        for (rod, body) in self.rods.iter().zip(&mut self.bodies) {
            let off = body.first_node;
            for i in 0..rod.nodes() {
                let d = node_dof(i);
                for (f, n) in body.force[d..d + 3].iter_mut().zip(node_forces[off + i].iter()) {
                    *f += n;
                }
            }
            if self.contact.rolling {
                let torques = self.gauss_seidel.spin_torques();
                for e in 0..rod.edges() {
                    body.force[theta_dof(e)] += torques[body.first_edge + e];
                }
            }
        }
        self.forces.extend_from_slice(self.gauss_seidel.contact_forces());
        self.history.push(&self.pair_ids, &self.forces, dt);
        Ok(())
    }

    fn step_rods(&mut self, dt: f64, report: &mut WorldStepReport) -> Result<(), WorldError> {
        for (b, (rod, body)) in self.rods.iter_mut().zip(&mut self.bodies).enumerate() {
            if rod.fixed.iter().all(|f| *f) && rod.prescribed_velocity.iter().all(|v| *v == 0.0) {
                continue;
            }
            let r: StepReport = body
                .stepper
                .step(rod, &self.env, Some(&body.force), dt)
                .map_err(|source| WorldError::Step { rod: b, source })?;
            report.newton_iterations += r.newton_iterations;
            report.substeps += r.substeps;
            report.energies.stretching += r.energies.stretching;
            report.energies.bending += r.energies.bending;
            report.energies.twisting += r.energies.twisting;
        }
        Ok(())
    }

    /// Largest penetration over the detected pairs at the current positions.
    fn max_penetration(&self) -> f64 {
        let pairs = self.pair_ids.iter().chain(&self.implicit.dropped);
        pairs.fold(0.0, |worst: f64, &(i, j)| worst.max(self.penetration(i, j)))
    }

    /// How far segments `i` and `j` overlap at the current positions:
    /// `r_a + r_b` minus their distance (negative when apart).
    fn penetration(&self, i: usize, j: usize) -> f64 {
        let (sa, sb) = (&self.segments[i], &self.segments[j]);
        let (ra, rb) = (&self.rods[sa.body], &self.rods[sb.body]);
        let cp = closest_points(
            &ra.node(sa.index),
            &ra.node(sa.index + 1),
            &rb.node(sb.index),
            &rb.node(sb.index + 1),
        );
        sa.radius + sb.radius - cp.distance
    }
}
