//! The contact solve consistent with the implicit step ([`ContactSolve::Implicit`]).
//!
//! Eq. (7) with the contact forces `H r` is, linearised about the contact-free
//! implicit step `q_f` (Newton matrix `A = c_in M + H_E` there),
//! `q = q_f + A^-1 H r`, so the contacts' relative velocities at the end of
//! the step are
//!
//! `u = H^T (q_f - q_0) / dt + (H^T A^-1 H / dt) r = u_free + W r`.
//!
//! Each step therefore (1) takes the contact-free implicit step and goes back
//! to the start, (2) applies `A^-1` to the contact Jacobian's columns with the
//! factorisation that step left (one banded solve per column), (3) solves
//! Signorini and Coulomb (eqs. 8-9) with this `W` by projected Gauss-Seidel
//! ([`crate::contact::dense`]), and (4) hands the forces to the implicit step
//! as the explicit method does. Without stiffness `A = M / dt^2` and this is
//! the explicit method's `W = dt H^T M^-1 H`; with it, a sticking contact
//! holds for the motion the step actually takes.
use super::{World, WorldError, WorldStepReport};
use crate::contact::cone::ContactFrame;
use crate::contact::dense::DenseGaussSeidel;
use crate::contact::{Candidates, ContactPoint, ContactSolve, DenseProblem, Geometry};
use crate::rod::{Rod, RodState, node_dof, theta_dof};
use crate::stepper::StepError;
use nalgebra::{Matrix3, Vector3};

/// Where each global node and edge of the world lives in the concatenated
/// DOF vector of all rods.
#[derive(Clone, Default)]
struct Numbering {
    /// World DOF of each global node's first coordinate and of each global edge's twist.
    node_dofs: Vec<usize>,
    edge_dofs: Vec<usize>,
}

/// Reusable buffers of the implicit contact solve.
#[derive(Clone, Default)]
pub(super) struct Buffers {
    numbering: Numbering,
    /// Each rod's state at the start of the step.
    start: Vec<RodState>,
    /// Generalised velocities of the contact-free step, all rods' DOFs in a row.
    velocity: Vec<f64>,
    /// Each contact's local frame `(n, t1, t2)` this step.
    frames: Vec<ContactFrame>,
    /// `A^-1 H`, one column (all DOFs) per contact axis.
    columns: Vec<f64>,
    w: Vec<Matrix3<f64>>,
    free: Vec<Vector3<f64>>,
    mu: Vec<f64>,
    sliding: Vec<Vector3<f64>>,
    warm: Vec<Vector3<f64>>,
    solver: DenseGaussSeidel,
    /// Segment pairs that [`Candidates::Predicted`] dropped this step.
    pub(super) dropped: Vec<(usize, usize)>,
}

impl Buffers {
    /// Buffers for `rods`, numbered as the world numbers them.
    pub(super) fn new(rods: &[Rod]) -> Self {
        let mut b = Self::default();
        let mut first_dof = 0;
        for rod in rods {
            let numbering = &mut b.numbering;
            numbering
                .node_dofs
                .extend((0..rod.nodes()).map(|i| first_dof + node_dof(i)));
            numbering
                .edge_dofs
                .extend((0..rod.edges()).map(|e| first_dof + theta_dof(e)));
            first_dof += rod.ndof();
        }
        b.start = vec![RodState::default(); rods.len()];
        b.velocity = vec![0.0; first_dof];
        b
    }
}

impl Numbering {
    /// `H_c^T x` in world coordinates: the contact's relative velocity (or
    /// displacement) for the generalised vector `x` (all DOFs), spin included.
    #[inline]
    fn gather(&self, c: &ContactPoint, x: &[f64]) -> Vector3<f64> {
        let mut g = Vector3::zeros();
        let (nodes, weights) = c.stencil();
        for (&k, &wk) in nodes.iter().zip(weights) {
            let d = self.node_dofs[k];
            g += wk * Vector3::new(x[d], x[d + 1], x[d + 2]);
        }
        for (e, lever) in &c.spin {
            if *lever != Vector3::zeros() {
                g += lever * x[self.edge_dofs[*e]];
            }
        }
        g
    }

    /// Adds `H_c f` (the world force `f` on A, `-f` on B, and its torques) to
    /// the generalised vector `x`.
    #[inline]
    fn scatter(&self, c: &ContactPoint, f: &Vector3<f64>, x: &mut [f64]) {
        let (nodes, weights) = c.stencil();
        for (&k, &wk) in nodes.iter().zip(weights) {
            let d = self.node_dofs[k];
            for a in 0..3 {
                x[d + a] += wk * f[a];
            }
        }
        for (e, lever) in &c.spin {
            if *lever != Vector3::zeros() {
                x[self.edge_dofs[*e]] += lever.dot(f);
            }
        }
    }
}

impl World {
    /// The contact-free step of every rod from the start of the step, for the
    /// implicit solve and the predicted candidates: its generalised
    /// velocities into `implicit.velocity` and its Newton matrix left
    /// factored in each stepper; the rods go back to the start. With
    /// [`Candidates::Predicted`] it is the whole implicit step (Newton to
    /// convergence, as the paper's code's predictor), and the contacts it
    /// does not bring closer than `r_a + r_b` are dropped; otherwise the
    /// linearly implicit step ([`crate::stepper::Stepper::linear_step`]), so
    /// that the contact problem is linearised about the start of the step,
    /// where the contacts hold the rods, not about a contact-free state.
    pub(super) fn predict(&mut self, dt: f64) -> Result<(), WorldError> {
        let b = &mut self.implicit;
        let nonlinear = self.contact.candidates == Candidates::Predicted;
        let (mut failed, mut stepped) = (None, 0);
        for (i, (rod, body)) in self.rods.iter_mut().zip(&mut self.bodies).enumerate() {
            stepped = i + 1;
            let n = rod.ndof();
            let velocity = &mut b.velocity[body.first_dof..body.first_dof + n];
            if rod.fixed.iter().all(|f| *f) {
                velocity.copy_from_slice(&rod.prescribed_velocity);
                continue;
            }
            if !nonlinear {
                if let Err(reason) = body
                    .stepper
                    .linear_step(rod, &self.env, Some(&body.load), dt, velocity)
                {
                    failed = Some(WorldError::Step {
                        rod: i,
                        source: StepError::NotConverged {
                            halvings: 0,
                            dt,
                            reason,
                        },
                    });
                    break;
                }
                continue;
            }
            rod.save_state(&mut b.start[i]);
            if let Err(source) = body.stepper.step(rod, &self.env, Some(&body.load), dt) {
                failed = Some(WorldError::Step { rod: i, source });
                break;
            }
            for (v, (q, q0)) in velocity.iter_mut().zip(rod.q.iter().zip(b.start[i].q())) {
                *v = (q - q0) / dt;
            }
        }
        if failed.is_none() && self.contact.candidates == Candidates::Predicted {
            self.keep_predicted();
        }
        let b = &mut self.implicit;
        for (rod, start) in self.rods.iter_mut().zip(&b.start).take(stepped) {
            if nonlinear && !rod.fixed.iter().all(|f| *f) {
                rod.load_state(start);
            }
        }
        failed.map_or(Ok(()), Err)
    }

    /// Keeps the contacts whose segments the rods' current (predicted)
    /// positions bring closer than `r_a + r_b`; the others' pairs go to
    /// `implicit.dropped` (their penetration is still watched).
    fn keep_predicted(&mut self) {
        let mut ends = std::mem::take(&mut self.end_pieces);
        ends.reset(self.segments.len());
        let mut kept = 0;
        for k in 0..self.contacts.len() {
            let (i, j) = self.pair_ids[k];
            if self.penetration(i, j, Some(self.starts[k]), &mut ends) > 0.0 {
                self.contacts[kept] = self.contacts[k];
                self.pair_ids[kept] = self.pair_ids[k];
                self.starts[kept] = self.starts[k];
                kept += 1;
            } else {
                self.implicit.dropped.push((i, j));
            }
        }
        self.end_pieces = ends;
        self.contacts.truncate(kept);
        self.pair_ids.truncate(kept);
        self.starts.truncate(kept);
    }

    /// Step 3 of [`World::step`] for [`ContactSolve::Implicit`], after
    /// [`World::predict`]: adds the contact forces to each body's `force`.
    /// `Ok(false)` when a rod's Newton matrix for this step is not at hand
    /// (its contact-free step needed substeps); the explicit solve then
    /// stands in.
    pub(super) fn solve_contacts_implicit(
        &mut self,
        dt: f64,
        report: &mut WorldStepReport,
    ) -> Result<bool, WorldError> {
        debug_assert_eq!(self.contact.solve, ContactSolve::Implicit);
        if !self.compliance_columns(dt) {
            self.counters.explicit_fallbacks += 1;
            return Ok(false);
        }
        self.delassus(dt);
        let b = &mut self.implicit;
        let follow = self.contact.geometry == Geometry::Smooth;
        self.history
            .warm_start(&self.pair_ids, dt, follow, &mut self.warm);
        b.warm.clear();
        b.warm.extend(
            b.frames
                .iter()
                .zip(&self.warm)
                .map(|(frame, f)| frame.to_local(f)),
        );
        let problem = DenseProblem {
            w: &b.w,
            free: &b.free,
            mu: &b.mu,
            sliding: &b.sliding,
        };
        let sol = b.solver.solve(&problem, &self.contact.solver, Some(&b.warm))?;
        report.contact_sweeps = sol.sweeps;
        report.active_contacts = b.solver.forces().iter().filter(|r| r.x > 0.0).count();
        self.forces.clear();
        self.forces.extend(
            b.frames
                .iter()
                .zip(b.solver.forces())
                .map(|(frame, r)| frame.to_world(r)),
        );
        // The generalised contact forces, into the first column's room.
        let generalised = &mut b.columns[..b.velocity.len()];
        generalised.fill(0.0);
        for (c, f) in self.contacts.iter().zip(&self.forces) {
            b.numbering.scatter(c, f, generalised);
        }
        for body in &mut self.bodies {
            let n = body.force.len();
            for (f, x) in body
                .force
                .iter_mut()
                .zip(&generalised[body.first_dof..body.first_dof + n])
            {
                *f += x;
            }
        }
        self.history.push(&self.pair_ids, &self.forces, dt);
        Ok(true)
    }

    /// The contacts' frames into `implicit.frames` and `A^-1 H` into
    /// `implicit.columns`, one column per contact axis (`n`, `t1`, `t2`):
    /// `false` if some rod's factorisation is not this step's.
    fn compliance_columns(&mut self, dt: f64) -> bool {
        let b = &mut self.implicit;
        let ndof = b.velocity.len();
        b.frames.clear();
        b.frames
            .extend(self.contacts.iter().map(|c| ContactFrame::from_normal(&c.normal)));
        b.columns.clear();
        b.columns.resize(3 * self.contacts.len() * ndof, 0.0);
        for (c, (contact, frame)) in self.contacts.iter().zip(&b.frames).enumerate() {
            for (k, axis) in [frame.n, frame.t1, frame.t2].iter().enumerate() {
                let column = &mut b.columns[(3 * c + k) * ndof..(3 * c + k + 1) * ndof];
                b.numbering.scatter(contact, axis, column);
                for (rod, body) in self.rods.iter().zip(&self.bodies) {
                    let range = body.first_dof..body.first_dof + rod.ndof();
                    let part = &mut column[range];
                    if rod.fixed.iter().all(|f| *f) || part.iter().all(|x| *x == 0.0) {
                        part.fill(0.0);
                        continue;
                    }
                    if !body.stepper.solve_newton(rod, &self.env, dt, part) {
                        return false;
                    }
                }
            }
        }
        true
    }

    /// The Delassus blocks `W = H^T A^-1 H / dt` and the free velocities
    /// `H^T v_f` (gap term included), in each contact's local frame.
    fn delassus(&mut self, dt: f64) {
        let b = &mut self.implicit;
        let m = self.contacts.len();
        let ndof = b.velocity.len();
        b.w.clear();
        b.w.resize(m * m, Matrix3::zeros());
        b.free.clear();
        b.mu.clear();
        b.sliding.clear();
        for (d, contact) in self.contacts.iter().enumerate() {
            for j in 0..3 {
                let column = &b.columns[(3 * d + j) * ndof..(3 * d + j + 1) * ndof];
                for (c, (other, frame)) in self.contacts.iter().zip(&b.frames).enumerate() {
                    let local = frame.to_local(&b.numbering.gather(other, column)) / dt;
                    b.w[c * m + d].set_column(j, &local);
                }
            }
            let frame = &b.frames[d];
            let mut free = frame.to_local(&b.numbering.gather(contact, &b.velocity));
            free.x += if self.contact.solver.close_gap {
                contact.gap
            } else {
                contact.gap.max(0.0)
            } / dt;
            b.free.push(free);
            b.mu.push(contact.mu);
            b.sliding.push(frame.to_local(&contact.sliding_direction));
        }
    }
}
