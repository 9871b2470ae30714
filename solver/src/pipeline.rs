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
use crate::contact::broad_phase::{BroadPhase, Segment, neighbour_gap};
use crate::contact::gauss_seidel::{ContactPoint, GaussSeidel, GaussSeidelOptions, SpinDofs};
use crate::contact::segment::closest_points;
use crate::contact::{FrictionLaw, narrow_phase};
use crate::counters::Counters;
use crate::energies::{self, Terms};
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
}

/// Why a world step failed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum WorldError {
    #[error("rod {rod}: {source}")]
    Step { rod: usize, source: StepError },
    #[error("contact detection: {0}")]
    Detection(String),
}

/// Several rods, their steppers and the contact machinery with reusable buffers.
#[derive(Clone)]
pub struct World {
    pub rods: Vec<Rod>,
    steppers: Vec<Stepper>,
    pub env: Environment,
    pub contact: ContactOptions,
    pub counters: Counters,
    /// Constant external loads per rod (one entry per DOF), added to F^ext.
    pub loads: Vec<Vec<f64>>,
    node_offset: Vec<usize>,
    /// First global edge id of each rod (twist DOFs for rolling).
    edge_offset: Vec<usize>,
    spin_inv_inertia: Vec<f64>,
    spin_free: Vec<f64>,
    broad: BroadPhase,
    gauss_seidel: GaussSeidel,
    segments: Vec<Segment>,
    gaps: Vec<usize>,
    contacts: Vec<ContactPoint>,
    pair_ids: Vec<(usize, usize)>,
    warm_ids: Vec<(usize, usize)>,
    warm_forces: Vec<Vector3<f64>>,
    warm: Vec<Vector3<f64>>,
    inv_mass: Vec<f64>,
    v_free: Vec<Vector3<f64>>,
    forces: Vec<Vec<f64>>,
    grad: Vec<Vec<f64>>,
    saved: Saved,
}

/// A checkpoint of the world: every rod's state and the contact warm start.
#[derive(Clone, Default)]
struct Saved {
    rods: Vec<RodState>,
    warm_ids: Vec<(usize, usize)>,
    warm_forces: Vec<Vector3<f64>>,
}

impl World {
    /// A world of `rods` under `env`, each stepped with `newton`.
    pub fn new(rods: Vec<Rod>, env: Environment, contact: ContactOptions, newton: NewtonOptions) -> Self {
        let steppers = rods.iter().map(|r| Stepper::new(r, newton)).collect();
        let mut node_offset = Vec::with_capacity(rods.len());
        let mut edge_offset = Vec::with_capacity(rods.len());
        let (mut total, mut total_edges) = (0, 0);
        for r in &rods {
            node_offset.push(total);
            edge_offset.push(total_edges);
            total += r.nodes();
            total_edges += r.edges();
        }
        let gaps = rods
            .iter()
            .map(|r| {
                let shortest = r.rest_len.iter().cloned().fold(f64::INFINITY, f64::min);
                neighbour_gap(2.0 * r.section.radius, shortest)
            })
            .collect();
        let forces = rods.iter().map(|r| vec![0.0; r.ndof()]).collect();
        let loads = rods.iter().map(|r| vec![0.0; r.ndof()]).collect();
        let grad = rods.iter().map(|r| vec![0.0; r.ndof()]).collect();
        Self {
            rods,
            steppers,
            env,
            contact,
            counters: Counters::default(),
            loads,
            node_offset,
            edge_offset,
            spin_inv_inertia: vec![0.0; total_edges],
            spin_free: vec![0.0; total_edges],
            broad: BroadPhase::new(),
            gauss_seidel: GaussSeidel::new(),
            segments: Vec::new(),
            gaps,
            contacts: Vec::new(),
            pair_ids: Vec::new(),
            warm_ids: Vec::new(),
            warm_forces: Vec::new(),
            warm: Vec::new(),
            inv_mass: vec![0.0; total],
            v_free: vec![Vector3::zeros(); total],
            forces,
            grad,
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
        self.saved.warm_ids.clone_from(&self.warm_ids);
        self.saved.warm_forces.clone_from(&self.warm_forces);
        self.steppers.iter_mut().for_each(Stepper::checkpoint);
    }

    /// Returns to the last [`World::checkpoint`] (to redo a step differently).
    pub fn rollback(&mut self) {
        for (rod, state) in self.rods.iter_mut().zip(&self.saved.rods) {
            rod.load_state(state);
        }
        self.warm_ids.clone_from(&self.saved.warm_ids);
        self.warm_forces.clone_from(&self.saved.warm_forces);
        self.steppers.iter_mut().for_each(Stepper::rollback);
    }

    /// The largest rod radius (the scale of contact tolerances).
    pub fn largest_radius(&self) -> f64 {
        self.rods.iter().map(|r| r.section.radius).fold(0.0, f64::max)
    }

    /// The stepper of rod `i` (for its clamp reactions).
    pub fn stepper(&self, i: usize) -> &Stepper {
        &self.steppers[i]
    }

    /// The contacts found at the start of the last step.
    pub fn contacts(&self) -> &[ContactPoint] {
        &self.contacts
    }

    /// Contact forces (on the first rod of each pair) of the last step.
    pub fn contact_forces(&self) -> &[Vector3<f64>] {
        self.gauss_seidel.contact_forces()
    }

    /// Advances every rod by `dt`.
    pub fn step(&mut self, dt: f64) -> Result<WorldStepReport, WorldError> {
        self.counters.steps += 1;
        let mut report = WorldStepReport::default();
        for (f, l) in self.forces.iter_mut().zip(&self.loads) {
            f.copy_from_slice(l);
        }
        if self.contact.enabled {
            let mut detection = self.counters.detection;
            Counters::time(&mut detection, || self.detect(dt))?;
            self.counters.detection = detection;
            report.contacts = self.contacts.len();
            if !self.contacts.is_empty() {
                let mut solve = self.counters.contact_solve;
                Counters::time(&mut solve, || self.solve_contacts(dt, &mut report));
                self.counters.contact_solve = solve;
            }
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
            .find_pairs(&self.segments, &self.gaps, margin)
            .map_err(|e| WorldError::Detection(e.to_string()))?;
        self.contacts.clear();
        self.pair_ids.clear();
        for (k, p) in pairs.iter().enumerate() {
            if narrow_phase::redundant(pairs, k, &self.segments) {
                continue;
            }
            let (sa, sb) = (&self.segments[p.i], &self.segments[p.j]);
            let (oa, ob) = (self.node_offset[sa.body], self.node_offset[sb.body]);
            let nodes = [oa + sa.index, oa + sa.index + 1, ob + sb.index, ob + sb.index + 1];
            if let Some(mut c) =
                ContactPoint::from_pair(nodes, &p.closest, sa.radius + sb.radius, self.contact.friction)
            {
                if c.gap < 0.0 {
                    c.gap *= self.contact.penetration_recovery;
                }
                if self.contact.rolling {
                    let (ea, eb) = (
                        self.edge_offset[sa.body] + sa.index,
                        self.edge_offset[sb.body] + sb.index,
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

    fn solve_contacts(&mut self, dt: f64, report: &mut WorldStepReport) {
        for (b, rod) in self.rods.iter().enumerate() {
            let grad: &[f64] = match self.steppers[b].elastic_gradient(rod) {
                Some(g) => g,
                None => {
                    energies::evaluate(rod, Terms::ALL, &mut self.grad[b], None);
                    &self.grad[b]
                }
            };
            let force = &mut self.forces[b];
            force.copy_from_slice(&self.loads[b]);
            gravity::add(rod, &self.env.gravity, force);
            // A free DOF's contact-free velocity, v + dt M^-1 (F - grad E),
            // damped, and its effective inverse mass (the same rule as the stepper's).
            let damp = 1.0 / self.env.damping_factor(dt);
            let free = |d: usize| {
                let m = rod.mass[d];
                (damp * (rod.velocity[d] + dt * (force[d] - grad[d]) / m), damp / m)
            };
            let off = self.node_offset[b];
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
                    let k = self.edge_offset[b] + e;
                    (self.spin_free[k], self.spin_inv_inertia[k]) = if rod.fixed[d] {
                        (rod.prescribed_velocity[d], 0.0)
                    } else {
                        free(d)
                    };
                }
            }
            force.copy_from_slice(&self.loads[b]);
        }
        // Warm start from the previous step's forces on the same segment pairs.
        self.warm.clear();
        let mut k = 0;
        for id in &self.pair_ids {
            while k < self.warm_ids.len() && self.warm_ids[k] < *id {
                k += 1;
            }
            let f = if k < self.warm_ids.len() && self.warm_ids[k] == *id {
                self.warm_forces[k]
            } else {
                Vector3::zeros()
            };
            self.warm.push(f);
        }
        let spin = self.contact.rolling.then_some(SpinDofs {
            inv_inertia: &self.spin_inv_inertia,
            free: &self.spin_free,
        });
        let solved = self.gauss_seidel.solve_with_spin(
            &self.contacts,
            &self.inv_mass,
            &self.v_free,
            spin,
            dt,
            &self.contact.solver,
            Some(&self.warm),
        );
        let Ok(sol) = solved else {
            return;
        };
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
        for (b, rod) in self.rods.iter().enumerate() {
            let off = self.node_offset[b];
            for i in 0..rod.nodes() {
                let d = node_dof(i);
                for (f, n) in self.forces[b][d..d + 3]
                    .iter_mut()
                    .zip(node_forces[off + i].iter())
                {
                    *f += n;
                }
            }
            if self.contact.rolling {
                let torques = self.gauss_seidel.spin_torques();
                for e in 0..rod.edges() {
                    self.forces[b][theta_dof(e)] += torques[self.edge_offset[b] + e];
                }
            }
        }
        self.warm_ids.clear();
        self.warm_ids.extend_from_slice(&self.pair_ids);
        self.warm_forces.clear();
        self.warm_forces
            .extend_from_slice(self.gauss_seidel.contact_forces());
    }

    fn step_rods(&mut self, dt: f64, report: &mut WorldStepReport) -> Result<(), WorldError> {
        for (b, (rod, stepper)) in self.rods.iter_mut().zip(&mut self.steppers).enumerate() {
            if rod.fixed.iter().all(|f| *f) && rod.prescribed_velocity.iter().all(|v| *v == 0.0) {
                continue;
            }
            let r: StepReport = stepper
                .step(rod, &self.env, Some(&self.forces[b]), dt)
                .map_err(|source| WorldError::Step { rod: b, source })?;
            report.newton_iterations += r.newton_iterations;
            report.substeps += r.substeps;
        }
        Ok(())
    }

    /// Largest penetration over the detected pairs at the current positions.
    fn max_penetration(&self) -> f64 {
        let mut worst: f64 = 0.0;
        for &(i, j) in &self.pair_ids {
            let (sa, sb) = (&self.segments[i], &self.segments[j]);
            let (ra, rb) = (&self.rods[sa.body], &self.rods[sb.body]);
            let cp = closest_points(
                &ra.node(sa.index),
                &ra.node(sa.index + 1),
                &rb.node(sb.index),
                &rb.node(sb.index + 1),
            );
            worst = worst.max(sa.radius + sb.radius - cp.distance);
        }
        worst
    }
}
