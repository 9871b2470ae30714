//! Accelerated projected gradient (APGD: Mazhar, Heyn, Negrut and Tasora,
//! ACM Trans. Graph. 2015) for the frictional contact problem on the lumped
//! mass (Sec. 3.2, eqs. 8-10), the problem [`super::gauss_seidel`] solves.
//!
//! With the Delassus operator `W = dt H^T M^-1 H` (never formed: `W r` is one
//! pass pushing the forces onto the nodes and one gathering the contacts'
//! velocities) and the free velocities `b`, the contacts' velocities are
//! `u = b + W r`, the gradient of `f(r) = r . (W r / 2 + b)`. Each iteration
//! takes a projected step from an extrapolated point `y`,
//! `r_c <- P_c(y_c - t s_c u_c(y))`, with `s_c = 1 / w_c` the inverse diagonal
//! block (a Jacobi preconditioner) and `t = 1 / L` found by backtracking on
//! `f`'s quadratic bound in the metric `1 / s`. `P_c` is Signorini's
//! half-line times a disk of fixed radius `g_c` (Tresca's law,
//! `project_tresca`), a convex set, so between updates of the bounds this
//! is FISTA on a convex quadratic, whose iterations grow with the square root
//! of `W`'s condition number where Gauss-Seidel's grow with it. Every
//! `BOUNDS_EVERY` (100) iterations the bounds become `g_c = mu r_n` of the
//! current iterate and the momentum restarts (the outer loop of a Tresca
//! fixed point); Coulomb's law itself (eq. 9) is not a projection on a convex
//! set, and Nesterov steps with its projection
//! ([`super::cone::project_coulomb`]) stalled on n = 3's smooth contacts. The
//! extrapolation is Nesterov's, restarted whenever the step goes uphill
//! (O'Donoghue and Candes 2015), and `L` shrinks by a tenth after each
//! accepted step. The solve stops at Gauss-Seidel's natural-map residual
//! (Coulomb's, not Tresca's), so a converged solve solves eqs. 8-9; the
//! iterate of smallest residual is returned.
//!
//! Rows whose twelve-node stencils overlap along a line contact
//! ([`super::curve`]) make `W` ill-conditioned: forces alternating along the
//! strands move almost no node, and Gauss-Seidel damps those modes slowly.

use super::error::ContactError;
use super::gauss_seidel::{Row, collect_forces, validate};
use super::options::GaussSeidelOptions;
use super::problem::MassProblem;
use super::report::SolveReport;
use nalgebra::Vector3;

/// Factor by which the step's Lipschitz estimate `L` shrinks after each
/// accepted step (Mazhar et al.'s 0.9).
const SHRINK: f64 = 0.9;

/// Factor by which `L` grows while the quadratic bound fails.
const GROW: f64 = 2.0;

/// Iterations between updates of the friction bounds `mu r_n` (the outer
/// loop of a Tresca fixed point, under which each inner problem is convex).
/// On contact problems saved from n = 3's smooth pull (docs/FIDELITY.md, "The
/// contact solve on overlapping rows"), 10 and 40 left many short of 1e-6
/// after 5 000 products, 100 one in twenty and 250 none; 100 renews the bounds
/// once within the cases' cap of 200.
const BOUNDS_EVERY: usize = 100;

/// Solver state; buffers are reused, so a solve allocates nothing once they
/// have grown to the problem size.
#[derive(Debug, Clone, Default)]
pub struct Apgd {
    rows: Vec<Row>,
    /// The iterate `r_k`, the previous one and the extrapolated point `y`.
    r: Vec<Vector3<f64>>,
    r_prev: Vec<Vector3<f64>>,
    y: Vec<Vector3<f64>>,
    /// The iterate of smallest residual so far.
    best: Vec<Vector3<f64>>,
    /// Each contact's friction bound `mu r_n`, held for [`BOUNDS_EVERY`]
    /// iterations.
    bound: Vec<f64>,
    /// `W` applied to `r`, `r_prev` and `y` (local frames).
    w_r: Vec<Vector3<f64>>,
    w_r_prev: Vec<Vector3<f64>>,
    w_y: Vec<Vector3<f64>>,
    /// Per-node velocity and per-edge twist-rate corrections of a force set.
    dv: Vec<Vector3<f64>>,
    dspin: Vec<f64>,
    forces: Vec<Vector3<f64>>,
    node_forces: Vec<Vector3<f64>>,
    spin_torques: Vec<f64>,
    /// The last solve's Lipschitz estimate, the next one's start.
    lipschitz: f64,
}

impl Apgd {
    /// Empty solver.
    pub fn new() -> Self {
        Self::default()
    }

    /// Contact forces `F_c` (on body A, world coordinates) of the last solve.
    pub fn contact_forces(&self) -> &[Vector3<f64>] {
        &self.forces
    }

    /// Per-node contact forces `sum_c w_ck F_c` of the last solve.
    pub fn node_forces(&self) -> &[Vector3<f64>] {
        &self.node_forces
    }

    /// Per-edge torques on the twist DOFs of the last solve.
    pub fn spin_torques(&self) -> &[f64] {
        &self.spin_torques
    }

    /// Per-node velocity corrections of the last solve: the end-of-step
    /// velocity is `v_free + correction`.
    pub fn velocity_corrections(&self) -> &[Vector3<f64>] {
        &self.dv
    }

    /// Solves eqs. (8)-(9) for `problem` as
    /// [`super::gauss_seidel::GaussSeidel::solve_problem`] does, from the
    /// warm start (world forces, one per contact) or zero forces.
    /// `options.max_sweeps` caps the products `W r` (one per iteration, one
    /// more per backtracking), the report's `sweeps`; the solve stops when
    /// the natural-map residual is at most `options.tolerance`;
    /// `options.relaxation` is not used.
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
        let (nodes, edges) = (inv_mass.len(), spin.map_or(0, |s| s.inv_inertia.len()));
        self.dv.clear();
        self.dv.resize(nodes, Vector3::zeros());
        self.dspin.clear();
        self.dspin.resize(edges, 0.0);
        self.rows.clear();
        for (c, contact) in contacts.iter().enumerate() {
            let warm = warm_start.map(|forces| &forces[c]);
            self.rows.push(Row::new(
                contact,
                inv_mass,
                v_free,
                spin,
                dt,
                options.close_gap,
                warm,
            ));
        }
        let m = self.rows.len();
        for buffer in [
            &mut self.r,
            &mut self.r_prev,
            &mut self.y,
            &mut self.best,
            &mut self.w_r,
            &mut self.w_r_prev,
            &mut self.w_y,
        ] {
            buffer.clear();
            buffer.resize(m, Vector3::zeros());
        }
        self.bound.clear();
        self.bound.resize(m, 0.0);
        for (r, row) in self.r.iter_mut().zip(&self.rows) {
            // A warm force outside the admissible set starts at its projection.
            *r = super::cone::project_coulomb(&row.r, row.mu, &row.sliding);
        }
        let report = self.iterate(options);
        for (row, best) in self.rows.iter_mut().zip(&self.best) {
            row.r = *best;
        }
        apply(
            &self.rows,
            &self.best,
            &mut self.dv,
            &mut self.dspin,
            &mut self.w_r,
        );
        collect_forces(
            &self.rows,
            (nodes, edges),
            &mut self.forces,
            &mut self.node_forces,
            &mut self.spin_torques,
        );
        Ok(report)
    }

    /// The accelerated iteration from `self.r`; leaves the iterate of
    /// smallest residual in `self.best`.
    fn iterate(&mut self, options: &GaussSeidelOptions) -> SolveReport {
        let mut products = 1;
        apply(&self.rows, &self.r, &mut self.dv, &mut self.dspin, &mut self.w_r);
        let mut best_residual = residual(&self.rows, &self.r, &self.w_r);
        self.best.copy_from_slice(&self.r);
        self.y.copy_from_slice(&self.r);
        self.w_y.copy_from_slice(&self.w_r);
        let mut theta: f64 = 1.0;
        let mut lipschitz = if self.lipschitz > 0.0 { self.lipschitz } else { 1.0 };
        let mut since_bounds = 0;
        while products < options.max_sweeps && best_residual > options.tolerance {
            if since_bounds % BOUNDS_EVERY == 0 {
                // New friction bounds: a new convex problem, momentum restarts.
                for (bound, (r, row)) in self.bound.iter_mut().zip(self.r.iter().zip(&self.rows)) {
                    *bound = row.mu * r.x;
                }
                theta = 1.0;
                self.y.copy_from_slice(&self.r);
                self.w_y.copy_from_slice(&self.w_r);
            }
            since_bounds += 1;
            std::mem::swap(&mut self.r, &mut self.r_prev);
            std::mem::swap(&mut self.w_r, &mut self.w_r_prev);
            // Backtrack until f's quadratic bound at y holds at the new
            // iterate: f(r) - f(y) - grad f(y) . (r - y) = (r - y) . W (r - y) / 2
            // is at most L / 2 |r - y|^2 in the metric 1 / s (computed from
            // differences, free of the cancellation in f(r) - f(y)).
            loop {
                let t = 1.0 / lipschitz;
                for (((r, y), w_y), (row, bound)) in self
                    .r
                    .iter_mut()
                    .zip(&self.y)
                    .zip(&self.w_y)
                    .zip(self.rows.iter().zip(&self.bound))
                {
                    let z = y - t * row.inv_w_t * (row.free + w_y);
                    *r = project_tresca(&z, *bound, &row.sliding);
                }
                apply(&self.rows, &self.r, &mut self.dv, &mut self.dspin, &mut self.w_r);
                products += 1;
                let (curvature, distance) = curvature(&self.rows, (&self.r, &self.w_r), (&self.y, &self.w_y));
                if curvature <= lipschitz * distance || products >= options.max_sweeps {
                    break;
                }
                lipschitz *= GROW;
            }
            let current = residual(&self.rows, &self.r, &self.w_r);
            if current < best_residual {
                best_residual = current;
                self.best.copy_from_slice(&self.r);
            }
            // Nesterov's extrapolation, restarted when the step went uphill:
            // the gradient at y against the step taken.
            let uphill = self
                .rows
                .iter()
                .zip(&self.w_y)
                .zip(self.r.iter().zip(&self.r_prev))
                .map(|((row, w_y), (r, r_prev))| (row.free + w_y).dot(&(r - r_prev)))
                .sum::<f64>()
                > 0.0;
            let next = 0.5 * theta * ((theta * theta + 4.0).sqrt() - theta);
            let beta = if uphill {
                0.0
            } else {
                theta * (1.0 - theta) / (theta * theta + next)
            };
            theta = if uphill { 1.0 } else { next };
            for c in 0..self.rows.len() {
                self.y[c] = self.r[c] + beta * (self.r[c] - self.r_prev[c]);
                self.w_y[c] = self.w_r[c] + beta * (self.w_r[c] - self.w_r_prev[c]);
            }
            lipschitz *= SHRINK;
        }
        self.lipschitz = lipschitz;
        SolveReport {
            sweeps: products,
            converged: best_residual <= options.tolerance,
        }
    }
}

/// Projection on Signorini's half-line and a fixed friction bound (Tresca's
/// law): `r_n = max(0, y_n)` and `r_t` the point of the disk of radius
/// `bound` (with a local unit tangent `sliding`, of the segment
/// `{a t : |a| <= bound}`) closest to `y_t`. With `bound = mu r_n` it is
/// [`super::cone::project_coulomb`]'s fixed point.
#[inline]
fn project_tresca(y: &Vector3<f64>, bound: f64, sliding: &Vector3<f64>) -> Vector3<f64> {
    let n = y.x.max(0.0);
    if sliding.y != 0.0 || sliding.z != 0.0 {
        let a = (y.y * sliding.y + y.z * sliding.z).clamp(-bound, bound);
        return Vector3::new(n, a * sliding.y, a * sliding.z);
    }
    let norm2 = y.y * y.y + y.z * y.z;
    if norm2 <= bound * bound {
        Vector3::new(n, y.y, y.z)
    } else {
        let k = bound / norm2.sqrt();
        Vector3::new(n, k * y.y, k * y.z)
    }
}

/// `W r` in the contacts' local frames into `w_r`, through the velocity
/// corrections `dv` and `dspin` the forces `r` cause (left in them); contacts
/// that cannot act (`w_c = 0`) get zero.
fn apply(
    rows: &[Row],
    r: &[Vector3<f64>],
    dv: &mut [Vector3<f64>],
    dspin: &mut [f64],
    w_r: &mut [Vector3<f64>],
) {
    dv.fill(Vector3::zeros());
    dspin.fill(0.0);
    for (row, rc) in rows.iter().zip(r) {
        if row.inv_w_n > 0.0 {
            row.push(rc, dv, dspin);
        }
    }
    for (row, out) in rows.iter().zip(w_r) {
        *out = if row.inv_w_n > 0.0 {
            row.velocity(dv, dspin) - row.free
        } else {
            Vector3::zeros()
        };
    }
}

/// `(r - y) . W (r - y)` and `|r - y|^2` in the metric `1 / s`,
/// `sum_c w_c |r_c - y_c|^2`, from `r`, `y` and their products with `W`.
fn curvature(
    rows: &[Row],
    (r, w_r): (&[Vector3<f64>], &[Vector3<f64>]),
    (y, w_y): (&[Vector3<f64>], &[Vector3<f64>]),
) -> (f64, f64) {
    let (mut curvature, mut distance) = (0.0, 0.0);
    for (c, row) in rows.iter().enumerate() {
        if row.inv_w_t > 0.0 {
            let d = r[c] - y[c];
            curvature += d.dot(&(w_r[c] - w_y[c]));
            distance += d.norm_squared() / row.inv_w_t;
        }
    }
    (curvature, distance)
}

/// Natural-map residual of forces `r` with `W r = w_r`, over the largest
/// force (as [`super::gauss_seidel::residual`]).
fn residual(rows: &[Row], r: &[Vector3<f64>], w_r: &[Vector3<f64>]) -> f64 {
    let (mut max_force, mut max_residual) = (0.0f64, 0.0f64);
    for (row, (r, w_r)) in rows.iter().zip(r.iter().zip(w_r)) {
        if row.inv_w_n > 0.0 {
            max_residual = max_residual.max(row.residual(r, &(row.free + w_r)));
            max_force = max_force.max(r.norm());
        }
    }
    max_residual / max_force.max(f64::MIN_POSITIVE)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::ContactPoint;
    use crate::contact::broad_phase::tests::torus_knot;
    use crate::contact::broad_phase::{BroadPhase, neighbour_gap, polyline_segments};
    use crate::contact::cone::tests::random_vector;
    use crate::contact::cone::{ContactFrame, solve_isotropic, tangential};
    use crate::contact::curve::{Piece, closest_points_on_pieces};
    use crate::contact::gauss_seidel::GaussSeidel;
    use crate::contact::gauss_seidel::tests::{contact, knot_problem, stack};
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    fn tight(tolerance: f64) -> GaussSeidelOptions {
        GaussSeidelOptions {
            max_sweeps: 200_000,
            tolerance,
            ..Default::default()
        }
    }

    fn solve(
        contacts: &[ContactPoint],
        inv_mass: &[f64],
        v_free: &[Vector3<f64>],
        dt: f64,
        options: &GaussSeidelOptions,
    ) -> (Apgd, SolveReport) {
        let mut apgd = Apgd::new();
        let problem = MassProblem {
            contacts,
            inv_mass,
            v_free,
            spin: None,
            dt,
        };
        let report = apgd.solve_problem(&problem, options, None).unwrap();
        (apgd, report)
    }

    /// Signorini and Coulomb (eqs. 8-9) at every contact, recomputed from
    /// the forces alone: end velocities `v_free + dt M^-1 sum_c w_ck F_c`.
    fn assert_solution(
        contacts: &[ContactPoint],
        inv_mass: &[f64],
        v_free: &[Vector3<f64>],
        dt: f64,
        forces: &[Vector3<f64>],
        tol: f64,
    ) {
        let mut v = v_free.to_vec();
        for (c, f) in contacts.iter().zip(forces) {
            let (nodes, weights) = c.stencil();
            for (&k, &w) in nodes.iter().zip(weights) {
                v[k] += dt * inv_mass[k] * w * f;
            }
        }
        let f_max = forces.iter().fold(0.0f64, |m, f| m.max(f.norm())).max(1e-300);
        let u_max = v_free.iter().fold(0.0f64, |m, f| m.max(f.norm())).max(1e-300);
        for (c, (contact, f)) in contacts.iter().zip(forces).enumerate() {
            let frame = ContactFrame::from_normal(&contact.normal);
            let (r, mut u) = (frame.to_local(f), frame.to_local(&contact.gather(&v)));
            u.x += contact.gap / dt;
            assert!(r.x >= 0.0 && u.x >= -tol * u_max, "contact {c}: r {r:?} u {u:?}");
            assert!(
                r.x.min(u.x / u_max * f_max) <= tol * f_max,
                "contact {c}: complementarity"
            );
            let (rt, ut) = (tangential(&r), tangential(&u));
            // The frame's round trip rounds at 1e-16 of the largest force.
            assert!(rt.norm() <= contact.mu * r.x + 1e-12 * f_max);
            if ut.norm() > tol * u_max {
                let slide = rt + contact.mu * r.x * ut / ut.norm();
                assert!(
                    slide.norm() <= tol * f_max,
                    "contact {c}: friction does not oppose sliding"
                );
            }
        }
    }

    #[test]
    fn one_contact_is_the_closed_form() {
        let mut rng = StdRng::seed_from_u64(30);
        for _ in 0..200 {
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
            let (apgd, report) = solve(&[c], &inv_mass, &v_free, dt, &tight(1e-12));
            let frame = ContactFrame::from_normal(&c.normal);
            let w = dt * (c.weights[0].powi(2) * inv_mass[0] + c.weights[1].powi(2) * inv_mass[1]);
            let mut u0 = frame.to_local(&c.gather(&v_free));
            u0.x += c.gap / dt;
            let expected = frame.to_world(&solve_isotropic(&u0, w, mu));
            assert!(report.converged, "{report:?}");
            assert!((apgd.contact_forces()[0] - expected).norm() <= 1e-10 * (1.0 + expected.norm()));
        }
    }

    #[test]
    fn stack_matches_gauss_seidel() {
        let mut rng = StdRng::seed_from_u64(31);
        let mut gs = GaussSeidel::new();
        for mu in [0.0, 0.05, 0.3, 1.0] {
            for _ in 0..20 {
                let (contacts, inv_mass, v_free) = stack(&mut rng, mu);
                let (apgd, report) = solve(&contacts, &inv_mass, &v_free, 1e-2, &tight(1e-11));
                assert!(report.converged, "mu {mu}: {report:?}");
                assert_solution(&contacts, &inv_mass, &v_free, 1e-2, apgd.contact_forces(), 1e-8);
                gs.solve(&contacts, &inv_mass, &v_free, 1e-2, &tight(1e-13), None)
                    .unwrap();
                let scale = gs.contact_forces().iter().fold(0.0f64, |m, f| m.max(f.norm()));
                for (a, b) in apgd.contact_forces().iter().zip(gs.contact_forces()) {
                    assert!((a - b).norm() <= 1e-8 * scale, "mu {mu}: {a:?} against {b:?}");
                }
            }
        }
    }

    /// End velocities `v_free + correction` of a solve.
    fn end_velocities(v_free: &[Vector3<f64>], correction: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        v_free.iter().zip(correction).map(|(v, dv)| v + dv).collect()
    }

    #[test]
    fn knot_contacts_match_gauss_seidel() {
        let mut gs = GaussSeidel::new();
        for mu in [0.0, 0.1, 0.5] {
            let (contacts, inv_mass, v_free) = knot_problem(mu);
            let (apgd, report) = solve(&contacts, &inv_mass, &v_free, 1e-3, &tight(1e-10));
            assert!(report.converged, "mu {mu}: {report:?}");
            assert_solution(&contacts, &inv_mass, &v_free, 1e-3, apgd.contact_forces(), 1e-7);
            if mu == 0.0 {
                // Frictionless end velocities are unique.
                gs.solve(&contacts, &inv_mass, &v_free, 1e-3, &tight(1e-12), None)
                    .unwrap();
                let scale = v_free.iter().fold(0.0f64, |m, v| m.max(v.norm()));
                let va = end_velocities(&v_free, apgd.velocity_corrections());
                let vb = end_velocities(&v_free, gs.velocity_corrections());
                for (a, b) in va.iter().zip(&vb) {
                    assert!((a - b).norm() <= 1e-7 * scale, "{a:?} against {b:?}");
                }
            }
        }
    }

    /// The frictionless contacts of [`knot_problem`]'s knot between the
    /// smooth centre line's pieces: twelve-node rows, those of neighbouring
    /// pairs overlapping.
    fn smooth_knot_problem() -> (Vec<ContactPoint>, Vec<f64>, Vec<Vector3<f64>>) {
        let (radius, margin) = (0.25, 0.02);
        let x = torus_knot(2.0, 7.0, 1.5, 0.5, 301, 0.9);
        let segments = polyline_segments(&x, radius, 0);
        let gap = neighbour_gap(2.0 * radius, (x[1] - x[0]).norm());
        let piece = |e: usize| Piece::new(x.len(), e, |i| x[i]);
        let mut bp = BroadPhase::new();
        let contacts: Vec<_> = bp
            .find_pairs(&segments, &[gap], margin)
            .unwrap()
            .iter()
            .filter_map(|p| {
                let (a, b) = (piece(p.i), piece(p.j));
                let pair = closest_points_on_pieces(&a, &b);
                ContactPoint::from_curves(
                    (a.nodes, a.weights(pair.s)),
                    (b.nodes, b.weights(pair.t)),
                    &pair,
                    2.0 * radius,
                    0.0,
                )
            })
            .collect();
        assert!(contacts.len() > 100 && contacts.iter().all(|c| c.width == 12));
        let v_free = x
            .iter()
            .map(|p| Vector3::new(-p.x, -p.y, 0.5 * p.z.signum()))
            .collect();
        (contacts, vec![1.0; x.len()], v_free)
    }

    /// On overlapping twelve-node rows APGD reaches Gauss-Seidel's end
    /// velocities (unique without friction).
    #[test]
    fn smooth_knot_matches_gauss_seidel() {
        let (contacts, inv_mass, v_free) = smooth_knot_problem();
        let (apgd, report) = solve(&contacts, &inv_mass, &v_free, 1e-3, &tight(1e-10));
        assert!(report.converged, "{report:?}");
        assert_solution(&contacts, &inv_mass, &v_free, 1e-3, apgd.contact_forces(), 1e-7);
        let mut gs = GaussSeidel::new();
        let gs_report = gs
            .solve(&contacts, &inv_mass, &v_free, 1e-3, &tight(1e-10), None)
            .unwrap();
        eprintln!(
            "smooth knot, {} contacts: APGD {report:?}, Gauss-Seidel {gs_report:?}",
            contacts.len()
        );
        let scale = v_free.iter().fold(0.0f64, |m, v| m.max(v.norm()));
        let va = end_velocities(&v_free, apgd.velocity_corrections());
        let vb = end_velocities(&v_free, gs.velocity_corrections());
        for (a, b) in va.iter().zip(&vb) {
            assert!((a - b).norm() <= 1e-7 * scale, "{a:?} against {b:?}");
        }
    }

    #[test]
    fn warm_start_from_the_solution_and_no_allocation() {
        let mut rng = StdRng::seed_from_u64(32);
        let (contacts, inv_mass, v_free) = stack(&mut rng, 0.3);
        let problem = MassProblem {
            contacts: &contacts,
            inv_mass: &inv_mass,
            v_free: &v_free,
            spin: None,
            dt: 1e-2,
        };
        let mut apgd = Apgd::new();
        let cold = apgd.solve_problem(&problem, &tight(1e-12), None).unwrap();
        let forces = apgd.contact_forces().to_vec();
        let buffers = |a: &Apgd| {
            [
                a.rows.as_ptr() as usize,
                a.y.as_ptr() as usize,
                a.w_y.as_ptr() as usize,
                a.dv.as_ptr() as usize,
                a.forces.as_ptr() as usize,
            ]
        };
        let before = buffers(&apgd);
        let warm = apgd.solve_problem(&problem, &tight(1e-9), Some(&forces)).unwrap();
        assert_eq!(before, buffers(&apgd));
        assert!(
            cold.sweeps > 2 && warm.sweeps == 1 && warm.converged,
            "{cold:?} {warm:?}"
        );
        let err = apgd.solve_problem(&problem, &tight(1e-9), Some(&forces[1..]));
        assert!(matches!(err, Err(ContactError::WarmStartLength { .. })));
    }
}
