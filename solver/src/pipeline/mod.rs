//! One time step of several rods with frictional contact (paper Sec. 3.2):
//!
//! 1. detection on the start-of-step state: broad phase, then segment-segment
//!    closest points, pairs closer than r_a + r_b + margin, and each
//!    segment's contact with the obstacle, if there is one;
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
mod detection;
mod explicit;
mod implicit;
mod warm_start;

pub use crate::contact::ContactOptions;
use crate::contact::broad_phase::{BroadPhase, Segment, neighbour_gap};
use crate::contact::curve::CurvePair;
use crate::contact::gauss_seidel::GaussSeidel;
use crate::contact::narrow_phase::Merge;
use crate::contact::{Candidates, ContactError, ContactPoint, ContactSolve, Cylinder};
use crate::counters::Counters;
use crate::energies::Energies;
use crate::external::Environment;
use crate::rod::{Rod, RodState};
use crate::stepper::{NewtonOptions, StepError, StepReport, Stepper};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use thiserror::Error;
use warm_start::ForceHistory;

/// What one world step did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WorldStepReport {
    /// Contact candidates within the margin.
    pub contacts: usize,
    /// Contacts carrying a normal force.
    pub active_contacts: usize,
    /// Largest penetration r_a + r_b - d over the contacts at the end of the step (m, 0 if none).
    pub max_penetration: f64,
    /// Sweeps (or operator products) of the contact solve.
    pub contact_sweeps: usize,
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
    /// A rigid, fixed cylinder the rods touch (a hitch's pole), if any.
    pub obstacle: Option<Cylinder>,
    pub counters: Counters,
    spin_inv_inertia: Vec<f64>,
    spin_free: Vec<f64>,
    broad: BroadPhase,
    gauss_seidel: GaussSeidel,
    segments: Vec<Segment>,
    /// The smooth centre line's pieces at the step's start, built as the
    /// pairs' closest points ask for them, and each segment's
    /// [`crate::contact::curve::chord_deviation_bound`].
    pieces: detection::Pieces,
    deviations: Vec<f64>,
    /// The pieces at the current positions, built as the step-end
    /// penetration asks for them.
    end_pieces: detection::Pieces,
    /// The smooth centre lines' closest points of each candidate pair.
    curves: Vec<CurvePair>,
    /// Which of `curves` stay after merging near-duplicates.
    merge: Merge,
    gaps: Vec<usize>,
    contacts: Vec<ContactPoint>,
    pair_ids: Vec<(usize, usize)>,
    /// Each contact's closest-point parameters at detection (on its pieces
    /// or segments), where the step-end penetration's search starts.
    starts: Vec<(f64, f64)>,
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
            obstacle: None,
            counters: Counters::default(),
            spin_inv_inertia: vec![0.0; total_edges],
            spin_free: vec![0.0; total_edges],
            broad: BroadPhase::new(),
            gauss_seidel: GaussSeidel::new(),
            segments: Vec::new(),
            pieces: detection::Pieces::default(),
            deviations: Vec::new(),
            end_pieces: detection::Pieces::default(),
            curves: Vec::new(),
            merge: Merge::default(),
            gaps,
            contacts: Vec::new(),
            pair_ids: Vec::new(),
            starts: Vec::new(),
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
            let solved = if self.contacts.is_empty() {
                Ok(())
            } else {
                Counters::time(&mut solve, || self.solve(dt, &mut report))
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

    /// Steps 2-3: the contact forces into each rod's `force`, by the
    /// implicit solve where it is chosen and its Newton matrices are at hand,
    /// else by the explicit one.
    fn solve(&mut self, dt: f64, report: &mut WorldStepReport) -> Result<(), WorldError> {
        if self.contact.solve == ContactSolve::Implicit && self.solve_contacts_implicit(dt, report)? {
            return Ok(());
        }
        self.solve_contacts(dt, report)
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
}
