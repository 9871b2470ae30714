//! Block Gauss-Seidel for many coupled frictional contacts (Sec. 3.2, eqs.
//! 8-10), solved one contact at a time as in Daviet et al. (the paper's refs.
//! [22, 25]) without forming the Delassus matrix `W = dt H^T M^-1 H`.
//!
//! Contact `c` joins the closest points `C_a = (1 - s) x_a0 + s x_a1` and
//! `C_b = (1 - t) x_b0 + t x_b1`; its relative velocity is
//! `u_c = sum_k w_ck v_k` with weights `(1 - s, s, -(1 - t), -t)` on nodes
//! `(a0, a1, b0, b1)`, expressed in the frame `(n, t1, t2)` with `n` from B to
//! A. A force `F_c` (on A; B receives `-F_c`), constant over the step, changes
//! node `k`'s velocity by `dt inv_mass_k w_ck F_c`. With a lumped isotropic
//! mass every diagonal block of `W` is `w_c I`, so each local problem is
//! solved exactly by [`super::cone::solve_isotropic`]; the step towards that
//! local solution is over-relaxed (`GaussSeidelOptions::relaxation`).

use super::cone::{ContactFrame, natural_map_residual, project_coulomb};
use super::error::ContactError;
use super::options::GaussSeidelOptions;
use super::point::{CONTACT_NODES, ContactPoint, SpinDofs};
use super::problem::MassProblem;
use super::report::SolveReport;
use nalgebra::Vector3;

/// One contact's row of the solve, packed so that a sweep reads each
/// contact's data from one place.
#[derive(Debug, Clone, Copy)]
pub(super) struct Row {
    nodes: [usize; CONTACT_NODES],
    weights: [f64; CONTACT_NODES],
    /// Velocity change of each node per unit force, `dt inv_mass_k w_ck`.
    push: [f64; CONTACT_NODES],
    /// Nodes used ([`ContactPoint::width`]).
    width: usize,
    /// Twist DOFs, levers and twist-rate change per unit torque (`dt / I`).
    spin_edges: [usize; 2],
    spin_levers: [Vector3<f64>; 2],
    spin_push: [f64; 2],
    pub(super) frame: ContactFrame,
    /// Inverse of the normal entry `w_c` of the diagonal block of `W` (the
    /// isotropic part: levers are tangent); 0 when `w_c = 0` (both bodies
    /// fixed: the contact cannot act).
    pub(super) inv_w_n: f64,
    /// Inverse of the largest eigenvalue of the block's tangential part
    /// (`w_c` plus the rank-two spin terms); `inv_w_n` without levers.
    pub(super) inv_w_t: f64,
    pub(super) mu: f64,
    /// `sliding_direction` in the local frame (zero normal component).
    pub(super) sliding: Vector3<f64>,
    /// Local relative velocity of the free step, gap term included.
    pub(super) free: Vector3<f64>,
    /// Local contact force `r_c = (r_n, r_t1, r_t2)`.
    pub(super) r: Vector3<f64>,
}

impl Row {
    /// The row of `contact` with the free velocities `v_free` (and the spin
    /// DOFs' `spin`, rolling) over a step `dt`, its force `warm` or zero
    /// (zero too when the contact cannot act); `close_gap` as in
    /// [`GaussSeidelOptions::close_gap`].
    pub(super) fn new(
        contact: &ContactPoint,
        inv_mass: &[f64],
        v_free: &[Vector3<f64>],
        spin: Option<SpinDofs>,
        dt: f64,
        close_gap: bool,
        warm: Option<&Vector3<f64>>,
    ) -> Self {
        let frame = ContactFrame::from_normal(&contact.normal);
        let (spin_free, spin_push, spin_block) = spin_terms(contact, &frame, spin, dt);
        let w_n = dt * self_block(contact, inv_mass);
        let w_t = w_n + largest_eigenvalue(spin_block);
        let mut free = frame.to_local(&(contact.gather(v_free) + spin_free));
        free.x += if close_gap {
            contact.gap
        } else {
            contact.gap.max(0.0)
        } / dt;
        Self {
            nodes: contact.nodes,
            weights: contact.weights,
            push: std::array::from_fn(|k| {
                if k < contact.width {
                    dt * inv_mass[contact.nodes[k]] * contact.weights[k]
                } else {
                    0.0
                }
            }),
            width: contact.width,
            spin_edges: [contact.spin[0].0, contact.spin[1].0],
            spin_levers: [contact.spin[0].1, contact.spin[1].1],
            spin_push,
            frame,
            inv_w_n: if w_n > 0.0 { 1.0 / w_n } else { 0.0 },
            inv_w_t: if w_n > 0.0 { 1.0 / w_t } else { 0.0 },
            mu: contact.mu,
            sliding: frame.to_local(&contact.sliding_direction),
            free,
            r: match warm {
                Some(force) if w_n > 0.0 => frame.to_local(force),
                _ => Vector3::zeros(),
            },
        }
    }

    /// Current local relative velocity `u_c` given the velocity corrections.
    #[inline(always)]
    pub(super) fn velocity(&self, dv: &[Vector3<f64>], dspin: &[f64]) -> Vector3<f64> {
        let mut g = self.weights[0] * dv[self.nodes[0]];
        for k in 1..self.width {
            g += self.weights[k] * dv[self.nodes[k]];
        }
        if self.spin_push != [0.0; 2] {
            g += self.spin_levers[0] * dspin[self.spin_edges[0]]
                + self.spin_levers[1] * dspin[self.spin_edges[1]];
        }
        self.free + self.frame.to_local(&g)
    }

    /// Adds the velocity changes caused by the local force change `dr`.
    #[inline(always)]
    pub(super) fn push(&self, dr: &Vector3<f64>, dv: &mut [Vector3<f64>], dspin: &mut [f64]) {
        let f = self.frame.to_world(dr);
        for k in 0..self.width {
            dv[self.nodes[k]] += self.push[k] * f;
        }
        for k in 0..2 {
            if self.spin_push[k] != 0.0 {
                dspin[self.spin_edges[k]] += self.spin_push[k] * self.spin_levers[k].dot(&f);
            }
        }
    }

    /// The local update `r <- P(r - rho u)` for the current local velocity
    /// `u` (`rho = (rho_n, rho_t, rho_t)`), with `P` the projection of
    /// Signorini and Coulomb's laws, [`project_coulomb`].
    /// A fixed point satisfies Signorini (eq. 8) and Coulomb (eq. 9) for any
    /// `rho_n, rho_t > 0`: `u_n = 0` where `r_n > 0` whatever `rho_n`, and a
    /// tangential force on the disk's rim points against `u_t` because
    /// `rho_t` is one scalar. With `rho_n = rho_t = 1 / w_c` this is the exact
    /// solution of the one-contact problem, [`super::cone::solve_isotropic`]
    /// (as `u` is affine in `r` with slope `w_c I` without levers); `omega`
    /// times the inverse block entries over-relaxes it.
    #[inline(always)]
    pub(super) fn update(&self, u: &Vector3<f64>, rho_n: f64, rho_t: f64) -> Vector3<f64> {
        let y = Vector3::new(
            self.r.x - rho_n * u.x,
            self.r.y - rho_t * u.y,
            self.r.z - rho_t * u.z,
        );
        project_coulomb(&y, self.mu, &self.sliding)
    }

    /// Natural-map residual of the force `r` at the local velocity `u`,
    /// `|| r - P_K(r - u_hat / w_c) ||` (with a sliding direction,
    /// `|| r - P(r - u / w_c) ||`, zero exactly at the fixed point of eq.
    /// 10's local update).
    #[inline]
    pub(super) fn residual(&self, r: &Vector3<f64>, u: &Vector3<f64>) -> f64 {
        if self.sliding == Vector3::zeros() {
            natural_map_residual(r, u, self.mu, self.inv_w_t)
        } else {
            let y = r - self.inv_w_t * u;
            (r - project_coulomb(&y, self.mu, &self.sliding)).norm()
        }
    }
}

/// Contact solver state; buffers are reused, so a solve allocates nothing once
/// they have grown to the problem size.
#[derive(Debug, Clone, Default)]
pub struct GaussSeidel {
    rows: Vec<Row>,
    /// Sweep order: even contacts, then odd ones (see [`sweep_order`]).
    order: Vec<usize>,
    /// Per-node velocity corrections `sum_c dt inv_mass_k w_ck F_c`.
    dv: Vec<Vector3<f64>>,
    /// Per-edge twist-rate corrections (rolling, [`SpinDofs`]).
    dspin: Vec<f64>,
    forces: Vec<Vector3<f64>>,
    node_forces: Vec<Vector3<f64>>,
    /// Per-edge contact torques `sum_c L_ce . F_c` of the last solve.
    spin_torques: Vec<f64>,
}

/// Sweeps between checks of the natural-map residual (a pass costing about
/// half a sweep).
const RESIDUAL_EVERY: usize = 8;

/// Tolerance on `|normal| - 1`.
const NORMAL_TOL: f64 = 1e-9;

impl GaussSeidel {
    /// Empty solver.
    pub fn new() -> Self {
        Self::default()
    }

    /// Contact forces `F_c` (on body A, world coordinates) of the last solve.
    pub fn contact_forces(&self) -> &[Vector3<f64>] {
        &self.forces
    }

    /// Per-node contact forces `sum_c w_ck F_c` (the `F^fr` of eq. 7c) of the
    /// last solve.
    pub fn node_forces(&self) -> &[Vector3<f64>] {
        &self.node_forces
    }

    /// Per-edge torques on the twist DOFs of the last [`GaussSeidel::solve_problem`].
    pub fn spin_torques(&self) -> &[f64] {
        &self.spin_torques
    }

    /// Per-node velocity corrections of the last solve: the end-of-step
    /// velocity is `v_free + correction`.
    pub fn velocity_corrections(&self) -> &[Vector3<f64>] {
        &self.dv
    }

    /// Solves eqs. (8)-(9) for `contacts` given the contact-free velocities
    /// `v_free` (friction at the centre lines), optionally warm-started from
    /// world forces (one per contact).
    pub fn solve(
        &mut self,
        contacts: &[ContactPoint],
        inv_mass: &[f64],
        v_free: &[Vector3<f64>],
        dt: f64,
        options: &GaussSeidelOptions,
        warm_start: Option<&[Vector3<f64>]>,
    ) -> Result<SolveReport, ContactError> {
        let problem = MassProblem {
            contacts,
            inv_mass,
            v_free,
            spin: None,
            dt,
        };
        self.solve_problem(&problem, options, warm_start)
    }

    /// Solves eqs. (8)-(9) for `problem`, optionally warm-started from world
    /// forces (one per contact); contacts whose levers are non-zero also move
    /// the twist DOFs of `problem.spin` ([`ContactPoint::spin`]).
    pub fn solve_problem(
        &mut self,
        problem: &MassProblem,
        options: &GaussSeidelOptions,
        warm_start: Option<&[Vector3<f64>]>,
    ) -> Result<SolveReport, ContactError> {
        let MassProblem {
            contacts,
            inv_mass,
            v_free,
            spin,
            dt,
        } = *problem;
        validate(contacts, inv_mass, v_free, dt, warm_start)?;
        if !(options.relaxation > 0.0 && options.relaxation < 2.0) {
            return Err(ContactError::InvalidRelaxation(options.relaxation));
        }
        let nodes = inv_mass.len();
        self.dv.clear();
        self.dv.resize(nodes, Vector3::zeros());
        let edges = spin.map_or(0, |s| s.inv_inertia.len());
        self.dspin.clear();
        self.dspin.resize(edges, 0.0);
        self.rows.clear();
        for (c, contact) in contacts.iter().enumerate() {
            let warm = warm_start.map(|forces| &forces[c]);
            let row = Row::new(contact, inv_mass, v_free, spin, dt, options.close_gap, warm);
            row.push(&row.r, &mut self.dv, &mut self.dspin);
            self.rows.push(row);
        }
        sweep_order(&self.rows, &mut self.order);
        let (sweeps, converged) = self.sweep(options);
        self.collect_forces(nodes, edges);
        Ok(SolveReport { sweeps, converged })
    }

    /// Sweeps the rows in order until a stopping rule holds or the sweep cap
    /// is reached; returns the sweeps taken and whether a rule held.
    fn sweep(&mut self, options: &GaussSeidelOptions) -> (usize, bool) {
        let mut sweeps = 0;
        let mut converged = false;
        while sweeps < options.max_sweeps && !converged {
            sweeps += 1;
            let (mut max_change2, mut max_force2) = (0.0f64, 0.0f64);
            for &c in &self.order {
                let row = &mut self.rows[c];
                let r = row.update(
                    &row.velocity(&self.dv, &self.dspin),
                    options.relaxation * row.inv_w_n,
                    options.relaxation * row.inv_w_t,
                );
                let change = r - row.r;
                // A contact that stays apart (zero force) moves nothing.
                if change != Vector3::zeros() {
                    row.push(&change, &mut self.dv, &mut self.dspin);
                }
                row.r = r;
                max_change2 = max_change2.max(change.norm_squared());
                max_force2 = max_force2.max(r.norm_squared());
            }
            converged = max_change2 <= options.tolerance.powi(2) * max_force2
                || (sweeps % RESIDUAL_EVERY == 0 && self.residual() <= options.tolerance);
        }
        (sweeps, converged)
    }

    /// The rows' forces in world coordinates, per contact, summed per node
    /// and as torques per edge (of `nodes` nodes and `edges` spinning edges).
    fn collect_forces(&mut self, nodes: usize, edges: usize) {
        collect_forces(
            &self.rows,
            (nodes, edges),
            &mut self.forces,
            &mut self.node_forces,
            &mut self.spin_torques,
        );
    }

    /// Natural-map residual of the last solve's forces ([`residual`]):
    /// `max_c || r_c - P_K(r_c - u_hat_c / w_c) ||` over the largest `|r_c|`
    /// (zero at an exact solution of eqs. 8-9).
    pub fn residual(&self) -> f64 {
        residual(&self.rows, &self.dv, &self.dspin)
    }
}

/// The rows' forces in world coordinates, per contact (`forces`), summed
/// per node (`node_forces`) and as torques per edge (`spin_torques`), for a
/// world of `(nodes, edges)` nodes and spinning edges.
pub(super) fn collect_forces(
    rows: &[Row],
    (nodes, edges): (usize, usize),
    forces: &mut Vec<Vector3<f64>>,
    node_forces: &mut Vec<Vector3<f64>>,
    spin_torques: &mut Vec<f64>,
) {
    forces.clear();
    node_forces.clear();
    node_forces.resize(nodes, Vector3::zeros());
    spin_torques.clear();
    spin_torques.resize(edges, 0.0);
    for row in rows {
        let force = row.frame.to_world(&row.r);
        for (&k, &wk) in row.nodes.iter().zip(&row.weights).take(row.width) {
            node_forces[k] += wk * force;
        }
        for k in 0..2 {
            if row.spin_push[k] != 0.0 {
                spin_torques[row.spin_edges[k]] += row.spin_levers[k].dot(&force);
            }
        }
        forces.push(force);
    }
}

/// Natural-map residual of the rows' forces `r` with the velocity
/// corrections `dv` and `dspin`: `max_c || r_c - P_K(r_c - u_hat_c / w_c) ||`
/// (with a sliding direction, `|| r_c - P(r_c - u_c / w_c) ||` for eq. 10's
/// projection) over `max_c |r_c|`, skipping contacts with `w_c = 0` (they
/// cannot act).
pub(super) fn residual(rows: &[Row], dv: &[Vector3<f64>], dspin: &[f64]) -> f64 {
    let (mut max_force, mut max_residual) = (0.0f64, 0.0f64);
    for row in rows.iter().filter(|row| row.inv_w_n > 0.0) {
        let residual = row.residual(&row.r, &row.velocity(dv, dspin));
        max_residual = max_residual.max(residual);
        max_force = max_force.max(row.r.norm());
    }
    max_residual / max_force.max(f64::MIN_POSITIVE)
}

/// The contacts that can act (`w_c > 0`, stored as `inv_w_n > 0`), evens first, then odds. Contacts
/// come from detection sorted by segment pair, so neighbours in that list
/// usually share nodes and each update would wait for the previous one's
/// velocity correction; two apart they rarely do, and the processor overlaps
/// their updates. The order changes the iterates, not the solution.
fn sweep_order(rows: &[Row], order: &mut Vec<usize>) {
    order.clear();
    for parity in [0, 1] {
        order.extend((parity..rows.len()).step_by(2).filter(|&c| rows[c].inv_w_n > 0.0));
    }
}

/// Rolling's terms of a contact's row: the free velocity the spin DOFs add
/// (world), each lever's twist-rate change per unit torque (`dt / I`), and
/// the spin part of the tangential block, `sum_k (dt / I_k) L_k L_k^T` in the
/// local tangent axes: entries (t1 t1, t1 t2, t2 t2). Zero without `spin`.
fn spin_terms(
    contact: &ContactPoint,
    frame: &ContactFrame,
    spin: Option<SpinDofs>,
    dt: f64,
) -> (Vector3<f64>, [f64; 2], [f64; 3]) {
    let mut spin_free = Vector3::zeros();
    let mut spin_push = [0.0; 2];
    let mut spin_block = [0.0; 3];
    if let Some(sp) = spin {
        let edges = sp.inv_inertia.len();
        for (k, (e, lever)) in contact.spin.iter().enumerate() {
            if *lever != Vector3::zeros() && *e < edges {
                spin_free += lever * sp.free[*e];
                spin_push[k] = dt * sp.inv_inertia[*e];
                let l = frame.to_local(lever);
                spin_block[0] += spin_push[k] * l.y * l.y;
                spin_block[1] += spin_push[k] * l.y * l.z;
                spin_block[2] += spin_push[k] * l.z * l.z;
            }
        }
    }
    (spin_free, spin_push, spin_block)
}

/// Largest eigenvalue of the symmetric 2x2 matrix with entries `(a, b, c)`
/// = `[[a, b], [b, c]]`.
pub(super) fn largest_eigenvalue([a, b, c]: [f64; 3]) -> f64 {
    0.5 * (a + c) + (0.25 * (a - c) * (a - c) + b * b).sqrt()
}

/// `W_cc / dt = sum_{k, k'} [node_k = node_k'] w_ck w_ck' inv_mass_k`, exact
/// even when a node appears twice in the contact.
fn self_block(contact: &ContactPoint, inv_mass: &[f64]) -> f64 {
    let (nodes, weights) = contact.stencil();
    let mut sum = 0.0;
    for (a, (&ka, &wa)) in nodes.iter().zip(weights).enumerate() {
        let mut same = wa;
        for (&kb, &wb) in nodes[a + 1..].iter().zip(&weights[a + 1..]) {
            same += if kb == ka { wb } else { 0.0 };
        }
        sum += inv_mass[ka] * wa * (2.0 * same - wa);
    }
    sum
}

pub(super) fn validate(
    contacts: &[ContactPoint],
    inv_mass: &[f64],
    v_free: &[Vector3<f64>],
    dt: f64,
    warm_start: Option<&[Vector3<f64>]>,
) -> Result<(), ContactError> {
    if inv_mass.len() != v_free.len() {
        return Err(ContactError::LengthMismatch {
            inv_mass: inv_mass.len(),
            v_free: v_free.len(),
        });
    }
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(ContactError::InvalidTimeStep(dt));
    }
    if let Some(k) = (0..inv_mass.len()).find(|&k| {
        !(inv_mass[k] >= 0.0 && inv_mass[k].is_finite() && v_free[k].iter().all(|x| x.is_finite()))
    }) {
        return Err(ContactError::InvalidNode(k));
    }
    for (c, contact) in contacts.iter().enumerate() {
        if !(1..=CONTACT_NODES).contains(&contact.width) {
            return Err(ContactError::InvalidContact(c));
        }
        let (nodes, weights) = contact.stencil();
        if let Some(&node) = nodes.iter().find(|&&k| k >= inv_mass.len()) {
            return Err(ContactError::NodeOutOfRange {
                contact: c,
                node,
                nodes: inv_mass.len(),
            });
        }
        // `x * 0` is zero for every finite `x` and NaN otherwise: the sum is
        // zero exactly when every entry is finite.
        let mut zero = contact.gap * 0.0;
        for x in weights
            .iter()
            .chain(&contact.normal)
            .chain(&contact.sliding_direction)
        {
            zero += x * 0.0;
        }
        let unit = (contact.normal.norm() - 1.0).abs() <= NORMAL_TOL;
        let t = &contact.sliding_direction;
        let tangent = *t == Vector3::zeros()
            || ((t.norm() - 1.0).abs() <= NORMAL_TOL && t.dot(&contact.normal).abs() <= NORMAL_TOL);
        if !(zero == 0.0 && unit && tangent && contact.mu >= 0.0 && contact.mu.is_finite()) {
            return Err(ContactError::InvalidContact(c));
        }
    }
    match warm_start {
        Some(forces) if forces.len() != contacts.len() => Err(ContactError::WarmStartLength {
            expected: contacts.len(),
            got: forces.len(),
        }),
        Some(forces) => match forces.iter().position(|f| !f.iter().all(|x| x.is_finite())) {
            Some(c) => Err(ContactError::InvalidWarmStart(c)),
            None => Ok(()),
        },
        None => Ok(()),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::contact::broad_phase::polyline_segments;
    use crate::contact::broad_phase::tests::torus_knot;
    use crate::contact::broad_phase::{BroadPhase, neighbour_gap};
    use crate::contact::cone::tests::random_vector;
    use crate::contact::cone::{solve_isotropic, tangential};
    use crate::contact::segment::closest_points;
    use rand::rngs::StdRng;
    use rand::seq::SliceRandom;
    use rand::{Rng, SeedableRng};

    /// Contact between segments `(nodes[0], nodes[1])` (A) and
    /// `(nodes[2], nodes[3])` (B) of the node array `x`.
    pub(crate) fn contact(
        x: &[Vector3<f64>],
        nodes: [usize; 4],
        contact_distance: f64,
        mu: f64,
    ) -> ContactPoint {
        let pair = closest_points(&x[nodes[0]], &x[nodes[1]], &x[nodes[2]], &x[nodes[3]]);
        ContactPoint::from_pair(nodes, &pair, contact_distance, mu).unwrap()
    }

    /// Checks Signorini and Coulomb (eqs. 8-9) at every contact of the last
    /// solve, with tolerances relative to the largest force and velocity.
    fn assert_solution(gs: &GaussSeidel, contacts: &[ContactPoint], tol: f64) {
        let f_max = gs
            .rows
            .iter()
            .fold(0.0f64, |m, row| m.max(row.r.norm()))
            .max(1e-300);
        let u_max = gs
            .rows
            .iter()
            .fold(0.0f64, |m, row| m.max(row.free.norm()))
            .max(1e-300);
        for (c, contact) in contacts.iter().enumerate() {
            let r = gs.rows[c].r;
            let u = gs.rows[c].free + gs.rows[c].frame.to_local(&contact.gather(&gs.dv));
            let (rt, ut) = (tangential(&r), tangential(&u));
            let mu = contact.mu;
            assert!(r.x >= 0.0 && u.x >= -tol * u_max, "contact {c}: r {r:?} u {u:?}");
            assert!(
                r.x.min(u.x / u_max * f_max) <= tol * f_max,
                "contact {c}: complementarity r {r:?} u {u:?}"
            );
            assert!(
                rt.norm() <= mu * r.x * (1.0 + 1e-12) + 1e-300,
                "contact {c}: outside the cone"
            );
            if ut.norm() > tol * u_max {
                let slide = rt + mu * r.x * ut / ut.norm();
                assert!(
                    slide.norm() <= tol * f_max,
                    "contact {c}: r {r:?} does not oppose sliding u {u:?}"
                );
            }
        }
    }

    fn total_momentum(inv_mass: &[f64], v: &[Vector3<f64>]) -> Vector3<f64> {
        inv_mass.iter().zip(v).map(|(&im, v)| v / im).sum()
    }

    fn end_velocities(gs: &GaussSeidel, v_free: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        v_free
            .iter()
            .zip(gs.velocity_corrections())
            .map(|(v, dv)| v + dv)
            .collect()
    }

    #[test]
    fn from_pair_weights_and_normal() {
        let x = [
            Vector3::new(-1.0, 0.0, 0.5),
            Vector3::new(3.0, 0.0, 0.5),
            Vector3::new(0.0, -1.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let c = contact(&x, [0, 1, 2, 3], 0.4, 0.2);
        assert_eq!(c.stencil().1, [0.75, 0.25, -0.5, -0.5]);
        assert!((c.normal - Vector3::z()).norm() < 1e-15 && (c.gap - 0.1).abs() < 1e-15);
        assert!(c.weights.iter().sum::<f64>().abs() < 1e-15);
        let touching = closest_points(&x[0], &x[1], &x[0], &x[3]);
        assert!(ContactPoint::from_pair([0, 1, 0, 3], &touching, 0.4, 0.2).is_none());
    }

    #[test]
    fn single_contact_on_fixed_body_matches_analytic() {
        let mut rng = StdRng::seed_from_u64(20);
        let mut gs = GaussSeidel::new();
        for _ in 0..500 {
            let x: Vec<_> = [
                (0.0, 0.0, 0.3),
                (1.0, 0.2, 0.3),
                (0.4, -1.0, 0.0),
                (0.5, 1.0, 0.0),
            ]
            .iter()
            .map(|&(a, b, c)| Vector3::new(a, b, c) + random_vector(&mut rng, 0.05))
            .collect();
            let mu = rng.gen_range(0.0..1.0);
            let c = contact(&x, [0, 1, 2, 3], 0.3, mu);
            let inv_mass = [rng.gen_range(0.5..2.0), rng.gen_range(0.5..2.0), 0.0, 0.0];
            let v_free: Vec<_> = (0..4).map(|_| random_vector(&mut rng, 1.0)).collect();
            let dt = 1e-2;
            let close_gap = rng.gen_bool(0.5);
            // Plain Gauss-Seidel solves a lone contact exactly in one sweep.
            let options = GaussSeidelOptions {
                close_gap,
                relaxation: 1.0,
                ..Default::default()
            };
            let report = gs.solve(&[c], &inv_mass, &v_free, dt, &options, None).unwrap();

            let frame = ContactFrame::from_normal(&c.normal);
            let w = dt * (c.weights[0].powi(2) * inv_mass[0] + c.weights[1].powi(2) * inv_mass[1]);
            let mut u0 = frame.to_local(&(0..4).map(|k| c.weights[k] * v_free[k]).sum::<Vector3<f64>>());
            u0.x += if close_gap { c.gap } else { c.gap.max(0.0) } / dt;
            let expected = frame.to_world(&solve_isotropic(&u0, w, mu));
            let force = gs.contact_forces()[0];
            assert!((force - expected).norm() <= 1e-12 * (1.0 + expected.norm()));
            assert!(
                report.converged && report.sweeps <= 2 && gs.residual() <= 1e-12,
                "{report:?}"
            );
            for k in 0..4 {
                assert!((gs.node_forces()[k] - c.weights[k] * force).norm() <= 1e-15 * (1.0 + force.norm()));
            }
            assert_eq!(&gs.velocity_corrections()[2..], &[Vector3::zeros(); 2]);
            assert_solution(&gs, &[c], 1e-12);
        }
    }

    #[test]
    fn head_on_frictionless_conserves_momentum() {
        let mut rng = StdRng::seed_from_u64(21);
        let mut gs = GaussSeidel::new();
        for _ in 0..200 {
            let r = 0.1;
            let x = [
                Vector3::new(-1.0, 0.3, r),
                Vector3::new(1.0, 0.3, r),
                Vector3::new(0.2, -1.0, -r),
                Vector3::new(0.2, 1.0, -r),
            ];
            let c = contact(&x, [0, 1, 2, 3], 2.0 * r, 0.0);
            let inv_mass: Vec<f64> = (0..4).map(|_| 1.0 / rng.gen_range(0.5..3.0)).collect();
            let mut v_free: Vec<_> = (0..4).map(|_| random_vector(&mut rng, 0.5)).collect();
            v_free[0].z -= 2.0;
            v_free[1].z -= 2.0;
            v_free[2].z += 1.0;
            v_free[3].z += 1.0;
            let exact = GaussSeidelOptions {
                relaxation: 1.0,
                ..Default::default()
            };
            let report = gs.solve(&[c], &inv_mass, &v_free, 1e-3, &exact, None).unwrap();
            assert!(report.converged);
            let v = end_velocities(&gs, &v_free);
            let u_free: Vector3<f64> = (0..4).map(|k| c.weights[k] * v_free[k]).sum();
            let u: Vector3<f64> = (0..4).map(|k| c.weights[k] * v[k]).sum();
            assert!(u_free.dot(&c.normal) < 0.0);
            assert!(
                u.dot(&c.normal).abs() <= 1e-12,
                "normal relative velocity {}",
                u.dot(&c.normal)
            );
            let tangential_change = (u - u_free) - (u - u_free).dot(&c.normal) * c.normal;
            assert!(tangential_change.norm() <= 1e-12);
            let p0 = total_momentum(&inv_mass, &v_free);
            assert!((total_momentum(&inv_mass, &v) - p0).norm() <= 1e-12 * (1.0 + p0.norm()));
            assert!(gs.node_forces().iter().sum::<Vector3<f64>>().norm() <= 1e-12);
        }
    }

    /// Ground segment (fixed, nodes 0-1) with three free segments stacked on
    /// it, alternately along x and y, under gravity with random sliding.
    pub(crate) fn stack(rng: &mut StdRng, mu: f64) -> (Vec<ContactPoint>, Vec<f64>, Vec<Vector3<f64>>) {
        let r = 0.05;
        let mut x = Vec::new();
        for level in 0..4 {
            let z = 2.0 * r * level as f64;
            let (c, o) = (0.1 * level as f64, 0.2 - 0.15 * level as f64);
            if level % 2 == 0 {
                x.extend([Vector3::new(-1.0 + c, o, z), Vector3::new(1.0 + c, o, z)]);
            } else {
                x.extend([Vector3::new(o, -1.0 + c, z), Vector3::new(o, 1.0 + c, z)]);
            }
        }
        let contacts = (1..4)
            .map(|l| contact(&x, [2 * l, 2 * l + 1, 2 * l - 2, 2 * l - 1], 2.0 * r, mu))
            .collect();
        let mut inv_mass = vec![0.0, 0.0];
        inv_mass.extend((2..8).map(|_| 1.0 / rng.gen_range(0.5..2.0)));
        let dt = 1e-2;
        let v_free = (0..8)
            .map(|k| {
                if k < 2 {
                    Vector3::zeros()
                } else {
                    let mut v = random_vector(rng, 0.1);
                    v.z = -9.81 * dt - rng.gen_range(0.0..0.05);
                    v
                }
            })
            .collect();
        (contacts, inv_mass, v_free)
    }

    #[test]
    fn stack_converges_and_satisfies_signorini_coulomb() {
        let mut rng = StdRng::seed_from_u64(22);
        let mut gs = GaussSeidel::new();
        for (&mu, relaxation) in [0.0, 0.05, 0.3, 1.0, 5.0].iter().zip([1.0, 1.5].iter().cycle()) {
            let options = GaussSeidelOptions {
                max_sweeps: 10_000,
                relaxation: *relaxation,
                tolerance: 1e-12,
                close_gap: true,
            };
            for _ in 0..50 {
                let (contacts, inv_mass, v_free) = stack(&mut rng, mu);
                let report = gs
                    .solve(&contacts, &inv_mass, &v_free, 1e-2, &options, None)
                    .unwrap();
                assert!(report.converged && gs.residual() <= 1e-10, "mu {mu}: {report:?}");
                assert!(
                    gs.rows.iter().all(|row| row.r.x > 0.0),
                    "every contact of the stack carries load"
                );
                assert_solution(&gs, &contacts, 1e-9);
            }
        }
    }

    #[test]
    fn result_independent_of_contact_order() {
        let mut rng = StdRng::seed_from_u64(23);
        let options = GaussSeidelOptions {
            max_sweeps: 10_000,
            tolerance: 1e-13,
            ..Default::default()
        };
        let (mut gs, mut gs_shuffled) = (GaussSeidel::new(), GaussSeidel::new());
        for &mu in &[0.0, 0.3] {
            for _ in 0..20 {
                let (contacts, inv_mass, v_free) = stack(&mut rng, mu);
                let mut order: Vec<usize> = (0..contacts.len()).collect();
                order.shuffle(&mut rng);
                let shuffled: Vec<_> = order.iter().map(|&c| contacts[c]).collect();
                gs.solve(&contacts, &inv_mass, &v_free, 1e-2, &options, None)
                    .unwrap();
                gs_shuffled
                    .solve(&shuffled, &inv_mass, &v_free, 1e-2, &options, None)
                    .unwrap();
                let scale = gs.contact_forces().iter().fold(0.0f64, |m, f| m.max(f.norm()));
                for (k, &c) in order.iter().enumerate() {
                    let diff = (gs_shuffled.contact_forces()[k] - gs.contact_forces()[c]).norm();
                    assert!(diff <= 1e-9 * scale, "mu {mu}: force differs by {diff}");
                }
            }
        }
        // Knot contacts, frictionless: end velocities are unique.
        let (contacts, inv_mass, v_free) = knot_problem(0.0);
        let mut order: Vec<usize> = (0..contacts.len()).collect();
        order.shuffle(&mut rng);
        let shuffled: Vec<_> = order.iter().map(|&c| contacts[c]).collect();
        gs.solve(&contacts, &inv_mass, &v_free, 1e-3, &options, None)
            .unwrap();
        gs_shuffled
            .solve(&shuffled, &inv_mass, &v_free, 1e-3, &options, None)
            .unwrap();
        let scale = v_free.iter().fold(0.0f64, |m, v| m.max(v.norm()));
        let (va, vb) = (
            end_velocities(&gs, &v_free),
            end_velocities(&gs_shuffled, &v_free),
        );
        for (a, b) in va.iter().zip(&vb) {
            assert!((a - b).norm() <= 1e-8 * scale);
        }
    }

    /// Contacts of an open tight (2, 7) torus knot (301 nodes, unit inverse masses)
    /// whose nodes move towards the knot's axis.
    pub(crate) fn knot_problem(mu: f64) -> (Vec<ContactPoint>, Vec<f64>, Vec<Vector3<f64>>) {
        let (radius, margin) = (0.25, 0.02);
        let x = torus_knot(2.0, 7.0, 1.5, 0.5, 301, 0.9);
        let segments = polyline_segments(&x, radius, 0);
        let gap = neighbour_gap(2.0 * radius, (x[1] - x[0]).norm());
        let mut bp = BroadPhase::new();
        let contacts: Vec<_> = bp
            .find_pairs(&segments, &[gap], margin)
            .unwrap()
            .iter()
            .filter_map(|p| {
                ContactPoint::from_pair([p.i, p.i + 1, p.j, p.j + 1], &p.closest, 2.0 * radius, mu)
            })
            .collect();
        assert!(contacts.len() > 100);
        let v_free = x
            .iter()
            .map(|p| Vector3::new(-p.x, -p.y, 0.5 * p.z.signum()))
            .collect();
        (contacts, vec![1.0; x.len()], v_free)
    }

    #[test]
    fn knot_contacts_converge() {
        let mut gs = GaussSeidel::new();
        for (mu, relaxation) in [(0.0, 1.0), (0.0, 1.5), (0.1, 1.0), (0.1, 1.5), (0.5, 1.5)] {
            let (contacts, inv_mass, v_free) = knot_problem(mu);
            let options = GaussSeidelOptions {
                max_sweeps: 20_000,
                relaxation,
                tolerance: 1e-10,
                close_gap: true,
            };
            let report = gs
                .solve(&contacts, &inv_mass, &v_free, 1e-3, &options, None)
                .unwrap();
            assert!(
                report.converged && gs.residual() <= 1e-8,
                "mu {mu}, omega {relaxation}: {report:?}"
            );
            assert_solution(&gs, &contacts, 1e-7);
        }
    }

    #[test]
    fn warm_start_reuses_solution_without_allocating() {
        let mut rng = StdRng::seed_from_u64(24);
        let (contacts, inv_mass, v_free) = stack(&mut rng, 0.3);
        let options = GaussSeidelOptions {
            tolerance: 1e-12,
            max_sweeps: 10_000,
            ..Default::default()
        };
        let mut gs = GaussSeidel::new();
        let cold = gs
            .solve(&contacts, &inv_mass, &v_free, 1e-2, &options, None)
            .unwrap();
        let forces = gs.contact_forces().to_vec();
        let buffers = |gs: &GaussSeidel| {
            [
                gs.rows.as_ptr() as usize,
                gs.order.as_ptr() as usize,
                gs.dv.as_ptr() as usize,
                gs.forces.as_ptr() as usize,
                gs.node_forces.as_ptr() as usize,
            ]
        };
        let before = buffers(&gs);
        let warm = gs
            .solve(&contacts, &inv_mass, &v_free, 1e-2, &options, Some(&forces))
            .unwrap();
        assert_eq!(before, buffers(&gs));
        assert!(
            cold.sweeps > 2 && warm.sweeps == 1 && warm.converged,
            "{cold:?} {warm:?}"
        );
        for (a, b) in forces.iter().zip(gs.contact_forces()) {
            assert!((a - b).norm() <= 1e-10 * a.norm());
        }
    }

    #[test]
    fn separating_and_gap_handling() {
        let x = [
            Vector3::new(-1.0, 0.0, 0.25),
            Vector3::new(1.0, 0.0, 0.25),
            Vector3::new(0.0, -1.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let mut gs = GaussSeidel::new();
        let inv_mass = [1.0, 1.0, 0.0, 0.0];
        let dt = 0.1;
        let open = |close_gap| GaussSeidelOptions {
            close_gap,
            relaxation: 1.0,
            ..Default::default()
        };
        // Gap 0.05 closes at 0.5 m/s: approaching at 0.4 m/s needs no force.
        let c = contact(&x, [0, 1, 2, 3], 0.2, 0.5);
        let v_free = [
            Vector3::new(0.0, 0.0, -0.4),
            Vector3::new(0.0, 0.0, -0.4),
            Vector3::zeros(),
            Vector3::zeros(),
        ];
        gs.solve(&[c], &inv_mass, &v_free, dt, &open(true), None).unwrap();
        assert_eq!(gs.contact_forces()[0], Vector3::zeros());
        // Penetration of 0.05: pushed out at 0.5 m/s only when closing the gap.
        let c = contact(&x, [0, 1, 2, 3], 0.3, 0.5);
        let v_free = [Vector3::zeros(); 4];
        gs.solve(&[c], &inv_mass, &v_free, dt, &open(true), None).unwrap();
        let v = end_velocities(&gs, &v_free);
        assert!((0.5 * (v[0].z + v[1].z) - 0.5).abs() < 1e-12);
        gs.solve(&[c], &inv_mass, &v_free, dt, &open(false), None)
            .unwrap();
        assert_eq!(gs.contact_forces()[0], Vector3::zeros());
        // Both bodies fixed: the contact cannot act.
        let report = gs.solve(&[c], &[0.0; 4], &v_free, dt, &open(true), None).unwrap();
        assert!(report.converged && gs.residual() == 0.0);
        assert_eq!(gs.contact_forces()[0], Vector3::zeros());
        // No contacts.
        let report = gs.solve(&[], &inv_mass, &v_free, dt, &open(true), None).unwrap();
        assert!(report.converged && gs.node_forces().iter().all(|f| *f == Vector3::zeros()));
    }

    #[test]
    fn invalid_input() {
        let x = [
            Vector3::new(-1.0, 0.0, 0.25),
            Vector3::new(1.0, 0.0, 0.25),
            Vector3::new(0.0, -1.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let c = contact(&x, [0, 1, 2, 3], 0.2, 0.5);
        let inv_mass = [1.0; 4];
        let v = [Vector3::zeros(); 4];
        let o = GaussSeidelOptions::default();
        let mut gs = GaussSeidel::new();
        let err = |r: Result<SolveReport, ContactError>| r.unwrap_err();
        assert_eq!(
            err(gs.solve(&[c], &inv_mass, &v[..3], 0.1, &o, None)),
            ContactError::LengthMismatch {
                inv_mass: 4,
                v_free: 3
            }
        );
        assert_eq!(
            err(gs.solve(&[c], &inv_mass, &v, 0.0, &o, None)),
            ContactError::InvalidTimeStep(0.0)
        );
        for omega in [0.0, 2.0, f64::NAN] {
            let o = GaussSeidelOptions {
                relaxation: omega,
                ..o
            };
            assert!(matches!(
                err(gs.solve(&[c], &inv_mass, &v, 0.1, &o, None)),
                ContactError::InvalidRelaxation(_)
            ));
        }
        assert_eq!(
            err(gs.solve(&[c], &[1.0, -1.0, 1.0, 1.0], &v, 0.1, &o, None)),
            ContactError::InvalidNode(1)
        );
        let far = ContactPoint {
            nodes: [0, 1, 2, 9, 0, 1, 2, 9, 0, 1, 2, 9],
            ..c
        };
        assert_eq!(
            err(gs.solve(&[c, far], &inv_mass, &v, 0.1, &o, None)),
            ContactError::NodeOutOfRange {
                contact: 1,
                node: 9,
                nodes: 4
            }
        );
        let skew = ContactPoint {
            normal: 2.0 * c.normal,
            ..c
        };
        assert_eq!(
            err(gs.solve(&[skew], &inv_mass, &v, 0.1, &o, None)),
            ContactError::InvalidContact(0)
        );
        let sticky = ContactPoint { mu: -0.1, ..c };
        assert_eq!(
            err(gs.solve(&[sticky], &inv_mass, &v, 0.1, &o, None)),
            ContactError::InvalidContact(0)
        );
        assert_eq!(
            err(gs.solve(&[c], &inv_mass, &v, 0.1, &o, Some(&[]))),
            ContactError::WarmStartLength { expected: 1, got: 0 }
        );
        assert_eq!(
            err(gs.solve(&[c], &inv_mass, &v, 0.1, &o, Some(&[Vector3::repeat(f64::NAN)]))),
            ContactError::InvalidWarmStart(0)
        );
    }

    /// Eq. (10) along a sliding direction `t` (one contact between two free
    /// unit-mass nodes pressed together): a tangential load across `t` meets
    /// no friction, one along `t` is resisted up to mu F_n and no further.
    #[test]
    fn friction_along_the_sliding_direction() {
        let (dt, mu) = (0.1, 0.3);
        let t = Vector3::x();
        let c = ContactPoint {
            nodes: [0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1],
            weights: [1.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            width: 4,
            normal: Vector3::z(),
            gap: 0.0,
            mu,
            sliding_direction: t,
            spin: [(0, Vector3::zeros()); 2],
        };
        let inv_mass = [1.0, 1.0];
        let solve = |v0: Vector3<f64>| {
            let mut gs = GaussSeidel::new();
            let v_free = [v0, Vector3::zeros()];
            let options = GaussSeidelOptions {
                tolerance: 1e-13,
                max_sweeps: 1000,
                ..GaussSeidelOptions::default()
            };
            let report = gs.solve(&[c], &inv_mass, &v_free, dt, &options, None).unwrap();
            assert!(report.converged);
            (
                gs.contact_forces()[0],
                v0 + gs.velocity_corrections()[0] - gs.velocity_corrections()[1],
            )
        };
        // Approaching at 1 m/s and sliding across t at 0.1 m/s: W = 2 dt, so the
        // normal force is 1 / (2 dt) = 5 N and nothing resists the sideways slide.
        let (f, u) = solve(Vector3::new(0.0, 0.1, -1.0));
        assert!(
            (f.z - 5.0).abs() < 1e-9 && f.x.abs() < 1e-12 && f.y.abs() < 1e-12,
            "{f:?}"
        );
        assert!((u.y - 0.1).abs() < 1e-9 && u.z.abs() < 1e-9, "{u:?}");
        // Sliding along t slowly enough to stop within the step: it sticks.
        let (f, u) = solve(Vector3::new(0.1, 0.0, -1.0));
        assert!((f.x + 0.5).abs() < 1e-9 && u.x.abs() < 1e-9, "{f:?} {u:?}");
        // Too fast to stop: friction is mu F_n = 1.5 N against t.
        let (f, u) = solve(Vector3::new(1.0, 0.0, -1.0));
        assert!(
            (f.x + mu * f.z).abs() < 1e-9 && (u.x - (1.0 - 2.0 * dt * 1.5)).abs() < 1e-9,
            "{f:?} {u:?}"
        );
    }

    #[test]
    fn repeated_node_self_block() {
        // Contact sharing node 1 between A and B (degenerate, but W_cc stays exact).
        let c = ContactPoint {
            nodes: [0, 1, 1, 2, 0, 1, 1, 2, 0, 1, 1, 2],
            weights: [0.5, 0.5, -0.3, -0.7, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            width: 4,
            normal: Vector3::z(),
            gap: 0.0,
            mu: 0.0,
            sliding_direction: Vector3::zeros(),
            spin: [(0, Vector3::zeros()); 2],
        };
        let inv_mass = [1.0, 2.0, 3.0];
        let expected = 0.25 * 1.0 + 0.2f64.powi(2) * 2.0 + 0.49 * 3.0;
        assert!((self_block(&c, &inv_mass) - expected).abs() < 1e-15);
    }
}
