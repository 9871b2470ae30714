//! Steps 2-3 of [`World::step`] with [`crate::contact::ContactSolve::Explicit`]
//! (the paper's method): free velocities from the start-of-step state and the
//! contact problem on the lumped mass, solved by block Gauss-Seidel.
use super::{World, WorldError, WorldStepReport};
use crate::contact::{Geometry, MassProblem, SpinDofs};
use crate::energies::{self, Terms};
use crate::external;
use crate::rod::{node_dof, theta_dof};
use nalgebra::Vector3;

impl World {
    /// The explicit contact solve (steps 2-3): contact forces into each
    /// rod's `force`; a [`ContactError`] ends the step before the rods move.
    pub(super) fn solve_contacts(&mut self, dt: f64, report: &mut WorldStepReport) -> Result<(), WorldError> {
        for (rod, body) in self.rods.iter().zip(&mut self.bodies) {
            let grad: &[f64] = match body.stepper.elastic_gradient(rod) {
                Some(g) => g,
                None => {
                    energies::evaluate(rod, Terms::ALL, &mut body.grad, None);
                    &body.grad
                }
            };
            let force = &mut body.force;
            external::assemble(rod, &self.env, Some(&body.load), force);
            let free = |d: usize| {
                self.env
                    .free_velocity(rod.velocity[d], force[d] - grad[d], rod.mass[d], dt)
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
        // Warm start from the last steps' forces on the same segment pairs
        // (or, for smooth contacts, their neighbours).
        let follow = self.contact.geometry == Geometry::Smooth;
        self.history
            .warm_start(&self.pair_ids, dt, follow, &mut self.warm);
        let problem = MassProblem {
            contacts: &self.contacts,
            inv_mass: &self.inv_mass,
            v_free: &self.v_free,
            spin: self.contact.rolling.then_some(SpinDofs {
                inv_inertia: &self.spin_inv_inertia,
                free: &self.spin_free,
            }),
            dt,
        };
        let sol = self
            .gauss_seidel
            .solve_problem(&problem, &self.contact.solver, Some(&self.warm))?;
        report.contact_sweeps = sol.sweeps;
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
}
