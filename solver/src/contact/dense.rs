//! Projected Gauss-Seidel on a dense Delassus operator (Sec. 3.2, eqs. 8-10),
//! for contacts coupled through the compliance of the implicit step
//! (`W = H^T A^-1 H / dt`, [`super::ContactSolve::Implicit`]) rather than
//! through the lumped mass alone ([`super::gauss_seidel`]).
//!
//! The problem is written in each contact's local frame `(n, t1, t2)`: the
//! relative velocities are `u = u_free + W r`, with `W` symmetric positive
//! semi-definite and stored by 3 x 3 blocks. Contact `c` is updated by
//! `r_c <- P(r_c - rho_c u_c)` ([`project_coulomb`]) with
//! `rho_c = (1 / W_cc,nn, 1 / lambda_max(W_cc,tt), ...)`; a fixed point
//! solves Signorini and Coulomb for any positive `rho`, and `u` is kept up to
//! date after each update (a column of blocks, `O(contacts)` per update).
//! Unlike the mass-only solver it does not over-relax (its
//! `GaussSeidelOptions::relaxation` is not used): along a stiff rope the
//! implicit operator couples every contact of a wrap, and over-relaxed
//! updates there oscillate instead of converging (the capstan at mu = 0.3
//! over a full turn read a tension ratio of 4.77 with omega = 1.5 and 6.53 with
//! plain Gauss-Seidel, against exp(mu phi) = 6.59).
use super::cone::{natural_map_residual, project_coulomb};
use super::error::ContactError;
use super::gauss_seidel::largest_eigenvalue;
use super::options::GaussSeidelOptions;
use super::problem::DenseProblem;
use super::report::SolveReport;
use nalgebra::{Matrix3, Vector3};

/// Solver state with reusable buffers.
#[derive(Debug, Clone, Default)]
pub struct DenseGaussSeidel {
    r: Vec<Vector3<f64>>,
    u: Vec<Vector3<f64>>,
    /// `(rho_n, rho_t)` per contact; zero: the contact cannot act.
    rho: Vec<(f64, f64)>,
}

impl DenseGaussSeidel {
    /// Local forces of the last solve.
    pub fn forces(&self) -> &[Vector3<f64>] {
        &self.r
    }

    /// Solves the problem from the local warm start `warm` (one force per
    /// contact, or zero forces); a [`ContactError`] for arrays of the wrong
    /// length, non-finite data or a negative friction coefficient.
    pub fn solve(
        &mut self,
        p: &DenseProblem,
        options: &GaussSeidelOptions,
        warm: Option<&[Vector3<f64>]>,
    ) -> Result<SolveReport, ContactError> {
        validate(p, warm)?;
        let m = p.free.len();
        self.rho.clear();
        self.rho.extend((0..m).map(|c| {
            let b = &p.w[c * m + c];
            let tangential = largest_eigenvalue([b[(1, 1)], b[(1, 2)], b[(2, 2)]]);
            if b[(0, 0)] > 0.0 && tangential > 0.0 {
                (1.0 / b[(0, 0)], 1.0 / tangential)
            } else {
                (0.0, 0.0)
            }
        }));
        self.r.clear();
        match warm {
            Some(w) => self.r.extend(
                w.iter()
                    .zip(&self.rho)
                    .map(|(f, rho)| if rho.0 > 0.0 { *f } else { Vector3::zeros() }),
            ),
            None => self.r.resize(m, Vector3::zeros()),
        }
        self.u.clear();
        self.u.extend_from_slice(p.free);
        for (c, rc) in self.r.iter().enumerate() {
            if *rc != Vector3::zeros() {
                add_column(p.w, m, c, rc, &mut self.u);
            }
        }
        let mut sweeps = 0;
        let mut converged = false;
        while sweeps < options.max_sweeps && !converged {
            sweeps += 1;
            let (mut max_change2, mut max_force2) = (0.0f64, 0.0f64);
            for c in 0..m {
                let (rho_n, rho_t) = self.rho[c];
                if rho_n == 0.0 {
                    continue;
                }
                let (r, u) = (self.r[c], self.u[c]);
                let y = Vector3::new(r.x - rho_n * u.x, r.y - rho_t * u.y, r.z - rho_t * u.z);
                let next = project_coulomb(&y, p.mu[c], &p.sliding[c]);
                let change = next - r;
                if change != Vector3::zeros() {
                    add_column(p.w, m, c, &change, &mut self.u);
                }
                self.r[c] = next;
                max_change2 = max_change2.max(change.norm_squared());
                max_force2 = max_force2.max(next.norm_squared());
            }
            converged = max_change2 <= options.tolerance.powi(2) * max_force2
                || (sweeps % RESIDUAL_EVERY == 0 && self.residual(p) <= options.tolerance);
        }
        Ok(SolveReport { sweeps, converged })
    }

    /// Natural-map residual of the current iterate over the largest force
    /// (as [`super::gauss_seidel`]'s), over the contacts that can act.
    fn residual(&self, p: &DenseProblem) -> f64 {
        let (mut max_force, mut max_residual) = (0.0f64, 0.0f64);
        for c in 0..self.r.len() {
            let (_, rho_t) = self.rho[c];
            if rho_t == 0.0 {
                continue;
            }
            let (r, u) = (&self.r[c], &self.u[c]);
            let residual = if p.sliding[c] == Vector3::zeros() {
                natural_map_residual(r, u, p.mu[c], rho_t)
            } else {
                let y = r - rho_t * u;
                (r - project_coulomb(&y, p.mu[c], &p.sliding[c])).norm()
            };
            max_residual = max_residual.max(residual);
            max_force = max_force.max(r.norm());
        }
        max_residual / max_force.max(f64::MIN_POSITIVE)
    }
}

/// Checks that `p` and `warm` have one entry per contact and finite data.
fn validate(p: &DenseProblem, warm: Option<&[Vector3<f64>]>) -> Result<(), ContactError> {
    let m = p.free.len();
    for (what, expected, got) in [
        ("w", m * m, p.w.len()),
        ("mu", m, p.mu.len()),
        ("sliding", m, p.sliding.len()),
    ] {
        if got != expected {
            return Err(ContactError::ProblemShape { what, expected, got });
        }
    }
    let finite = |x: &Vector3<f64>| x.iter().all(|v| v.is_finite());
    if let Some(c) = (0..m).find(|&c| {
        !(finite(&p.free[c])
            && finite(&p.sliding[c])
            && p.mu[c] >= 0.0
            && p.mu[c].is_finite()
            && p.w[c * m..(c + 1) * m]
                .iter()
                .all(|b| b.iter().all(|v| v.is_finite())))
    }) {
        return Err(ContactError::InvalidContact(c));
    }
    match warm {
        Some(forces) if forces.len() != m => Err(ContactError::WarmStartLength {
            expected: m,
            got: forces.len(),
        }),
        Some(forces) => forces
            .iter()
            .position(|f| !finite(f))
            .map_or(Ok(()), |c| Err(ContactError::InvalidWarmStart(c))),
        None => Ok(()),
    }
}

/// Sweeps between checks of the natural-map residual.
const RESIDUAL_EVERY: usize = 8;

/// `u_d += W_dc x` for every contact `d` (`W` symmetric: block `(c, d)` transposed).
#[inline]
fn add_column(w: &[Matrix3<f64>], m: usize, c: usize, x: &Vector3<f64>, u: &mut [Vector3<f64>]) {
    for (ud, block) in u.iter_mut().zip(&w[c * m..(c + 1) * m]) {
        *ud += block.tr_mul(x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::cone::tests::random_vector;
    use crate::contact::cone::{solve_isotropic, tangential};
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    /// A random SPD Delassus operator `G^T G + eps I` of `m` contacts, by blocks.
    fn random_delassus(rng: &mut StdRng, m: usize) -> Vec<Matrix3<f64>> {
        let n = 3 * m;
        let g = nalgebra::DMatrix::from_fn(n + 2, n, |_, _| rng.gen_range(-1.0..1.0));
        let dense = g.transpose() * g + nalgebra::DMatrix::identity(n, n) * 0.05;
        let mut w = vec![Matrix3::zeros(); m * m];
        for c in 0..m {
            for d in 0..m {
                w[c * m + d] = dense.fixed_view::<3, 3>(3 * c, 3 * d).into_owned();
            }
        }
        w
    }

    #[test]
    fn one_isotropic_contact_is_the_closed_form() {
        let mut rng = StdRng::seed_from_u64(1);
        let mut solver = DenseGaussSeidel::default();
        for _ in 0..200 {
            let w = rng.gen_range(0.1..3.0);
            let mu = rng.gen_range(0.0..1.0);
            let free = [random_vector(&mut rng, 1.0)];
            let problem = DenseProblem {
                w: &[Matrix3::identity() * w],
                free: &free,
                mu: &[mu],
                sliding: &[Vector3::zeros()],
            };
            solver
                .solve(&problem, &GaussSeidelOptions::default(), None)
                .unwrap();
            let expected = solve_isotropic(&free[0], w, mu);
            assert!((solver.forces()[0] - expected).norm() <= 1e-12 * (1.0 + expected.norm()));
        }
    }

    #[test]
    fn coupled_contacts_satisfy_signorini_and_coulomb() {
        let mut rng = StdRng::seed_from_u64(2);
        let mut solver = DenseGaussSeidel::default();
        for m in [2, 5, 12] {
            let w = random_delassus(&mut rng, m);
            let free: Vec<_> = (0..m).map(|_| random_vector(&mut rng, 1.0)).collect();
            let mu: Vec<_> = (0..m).map(|_| rng.gen_range(0.0..0.8)).collect();
            let sliding = vec![Vector3::zeros(); m];
            let problem = DenseProblem {
                w: &w,
                free: &free,
                mu: &mu,
                sliding: &sliding,
            };
            let options = GaussSeidelOptions {
                max_sweeps: 20_000,
                tolerance: 1e-12,
                ..Default::default()
            };
            let report = solver.solve(&problem, &options, None).unwrap();
            assert!(report.converged, "{m} contacts: {report:?}");
            let r = solver.forces();
            let f_max = r.iter().fold(0.0f64, |a, x| a.max(x.norm())).max(1e-300);
            for c in 0..m {
                // Recompute u = u_free + W r independently of the solver's bookkeeping.
                let u = (0..m).fold(free[c], |acc, d| acc + w[c * m + d] * r[d]);
                let (rc, tol) = (r[c], 1e-8);
                assert!(rc.x >= 0.0 && u.x >= -tol, "contact {c}: r {rc:?} u {u:?}");
                assert!(rc.x * u.x.max(0.0) <= tol * f_max, "complementarity {c}");
                assert!(tangential(&rc).norm() <= mu[c] * rc.x * (1.0 + 1e-12) + 1e-300);
                let ut = tangential(&u);
                if ut.norm() > tol {
                    let slide = tangential(&rc) + mu[c] * rc.x * ut / ut.norm();
                    assert!(
                        slide.norm() <= 1e-6 * f_max,
                        "contact {c} does not oppose sliding"
                    );
                } else {
                    assert!(ut.norm() <= tol);
                }
            }
        }
    }
}
