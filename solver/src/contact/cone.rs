//! Coulomb friction cone and the one-contact problem of Sec. 3.2 (eqs. 8-10).
//!
//! Local quantities are written in the contact frame `(n, t1, t2)`: a vector
//! `x` has components `(x_n, x_t1, x_t2)` and tangential part
//! `x_t = (x_t1, x_t2)`. The friction cone is
//! `K_mu = { r : |r_t| <= mu r_n }` and `n` points from body B to body A, so a
//! non-negative `r_n` pushes A away from B and `u` is the velocity of `C_a`
//! relative to `C_b`.

use nalgebra::{Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// Orthonormal contact frame `(n, t1, t2)`, right-handed, built
/// deterministically from the unit normal `n`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContactFrame {
    /// Unit normal, from body B to body A.
    pub n: Vector3<f64>,
    /// First unit tangent.
    pub t1: Vector3<f64>,
    /// Second unit tangent, `n x t1`.
    pub t2: Vector3<f64>,
}

impl ContactFrame {
    /// Frame around the unit normal `n` (Duff et al. 2017, "Building an
    /// orthonormal basis, revisited": branchless, continuous except where
    /// `n_z` changes sign).
    pub fn from_normal(n: &Vector3<f64>) -> Self {
        let sign = 1f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let t1 = Vector3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t2 = Vector3::new(b, sign + n.y * n.y * a, -n.y);
        Self { n: *n, t1, t2 }
    }

    /// World vector expressed in the frame: `(x . n, x . t1, x . t2)`.
    #[inline]
    pub fn to_local(&self, x: &Vector3<f64>) -> Vector3<f64> {
        Vector3::new(x.dot(&self.n), x.dot(&self.t1), x.dot(&self.t2))
    }

    /// Local vector back in world coordinates.
    #[inline]
    pub fn to_world(&self, x: &Vector3<f64>) -> Vector3<f64> {
        x.x * self.n + x.y * self.t1 + x.z * self.t2
    }
}

/// Tangential part `(x_t1, x_t2)` of a local vector.
#[inline]
pub fn tangential(x: &Vector3<f64>) -> Vector2<f64> {
    Vector2::new(x.y, x.z)
}

/// Orthogonal (Euclidean) projection onto `K_mu`, `mu >= 0`, in closed form:
/// `x` if `x` is in the cone, `0` if `x` is in the polar cone
/// `{ mu |x_t| <= -x_n }`, otherwise the boundary point
/// `a (1, mu x_t / |x_t|)` with `a = (x_n + mu |x_t|) / (1 + mu^2)`.
pub fn project_cone(x: &Vector3<f64>, mu: f64) -> Vector3<f64> {
    debug_assert!(mu >= 0.0, "friction coefficient {mu} < 0");
    let xt = tangential(x);
    let nt = xt.norm();
    if nt <= mu * x.x {
        *x
    } else if mu * nt <= -x.x {
        Vector3::zeros()
    } else {
        let a = (x.x + mu * nt) / (1.0 + mu * mu);
        let k = mu * a / nt;
        Vector3::new(a, k * xt.x, k * xt.y)
    }
}

/// Projection `P_D(radius)` onto the disk of the given radius (eq. 10);
/// a non-positive radius gives the origin.
pub fn project_disk(x: &Vector2<f64>, radius: f64) -> Vector2<f64> {
    if radius <= 0.0 {
        return Vector2::zeros();
    }
    let norm = x.norm();
    if norm <= radius { *x } else { x * (radius / norm) }
}

/// Alart-Curnier function of eq. (10) for one contact, at the velocity level
/// of Bertails-Descoubes et al. (the paper's ref. [21]): with
/// `m = max(0, r_n - rho u_n)`,
///
/// `f_n = r_n - m`, `f_t = r_t - P_D(mu m)(r_t - rho u_t)`.
///
/// The normal velocity `u_n` replaces eq. (10)'s `d`: it includes the gap
/// term `gap / dt` when the gap is closed in one step. `f = 0` exactly when
/// `(r, u)` satisfies Signorini (eq. 8) and Coulomb (eq. 9), for any
/// `rho > 0`. The result is in the local frame, `(f_n, f_t1, f_t2)`.
pub fn alart_curnier(r: &Vector3<f64>, u: &Vector3<f64>, mu: f64, rho: f64) -> Vector3<f64> {
    let m = (r.x - rho * u.x).max(0.0);
    let rt = tangential(r);
    let ft = rt - project_disk(&(rt - rho * tangential(u)), mu * m);
    Vector3::new(r.x - m, ft.x, ft.y)
}

/// Exact solution of the one-contact Coulomb problem with an isotropic
/// Delassus block `W_cc = w I`, `w > 0`: returns `r` such that
/// `u = u0 + w r` satisfies Signorini (`r_n >= 0`, `u_n >= 0`, `r_n u_n = 0`,
/// eq. 8) and Coulomb (`|r_t| <= mu r_n`; stick `u_t = 0` or slide with
/// `r_t = -mu r_n u_t / |u_t|`, eq. 9).
///
/// Because `W_cc` is a multiple of the identity, `u_n = u0_n + w r_n` does not
/// depend on `r_t` and `u_t = u0_t + w r_t` does not depend on `r_n`, so the
/// normal problem is solved first, `r_n = max(0, -u0_n / w)`, and then only
/// the disk radius `mu r_n` couples the two: `r_t = P_D(mu r_n)(-u0_t / w)`.
/// Inside the disk this is the stick solution `u_t = 0`; on its boundary
/// `u_t = u0_t (1 - w mu r_n / |u0_t|)` is a positive multiple of `u0_t`, so
/// `r_t` opposes `u_t` with `|r_t| = mu r_n` (slide). This is not the
/// orthogonal cone projection of `-u0 / w`, which solves the associated
/// (dilatant) law instead of Coulomb's.
pub fn solve_isotropic(u0: &Vector3<f64>, w: f64, mu: f64) -> Vector3<f64> {
    debug_assert!(w > 0.0, "Delassus block {w} <= 0");
    let rn = (-u0.x / w).max(0.0);
    let rt = project_disk(&(-tangential(u0) / w), mu * rn);
    Vector3::new(rn, rt.x, rt.y)
}

/// Projection `P` of the local update `r <- P(r - rho u)` of Signorini and
/// Coulomb's laws (eqs. 8-10), applied to `y = r - rho u`: `r_n = max(0, y_n)`,
/// then `r_t` the point of the disk of radius `mu r_n` closest to `y_t`, or,
/// with a (local, unit, tangent) `sliding` direction `t`, the point of the
/// segment `{a t : |a| <= mu r_n}` closest to `y_t` (eq. 10's `D`; zero
/// `sliding`: the disk).
#[inline(always)]
pub fn project_coulomb(y: &Vector3<f64>, mu: f64, sliding: &Vector3<f64>) -> Vector3<f64> {
    if y.x <= 0.0 {
        return Vector3::zeros();
    }
    if sliding.y != 0.0 || sliding.z != 0.0 {
        let a = (y.y * sliding.y + y.z * sliding.z).clamp(-mu * y.x, mu * y.x);
        return Vector3::new(y.x, a * sliding.y, a * sliding.z);
    }
    let (norm2, radius) = (y.y * y.y + y.z * y.z, mu * y.x);
    if norm2 <= radius * radius {
        *y
    } else {
        let k = radius / norm2.sqrt();
        Vector3::new(y.x, k * y.y, k * y.z)
    }
}

/// Natural-map residual of the Coulomb problem through De Saxce's modified
/// velocity `u_hat = u + mu |u_t| n`:
/// `|| r - P_K(r - rho u_hat) ||`, `rho > 0` (units of `r / u`).
///
/// Since `r` solves eqs. (8)-(9) iff `r in K_mu`, `u_hat in K_mu^*` and
/// `r . u_hat = 0`, which by Moreau's decomposition is `r = P_K(r - rho u_hat)`,
/// the residual is zero exactly at a solution and positive elsewhere.
pub fn natural_map_residual(r: &Vector3<f64>, u: &Vector3<f64>, mu: f64, rho: f64) -> f64 {
    let mut u_hat = *u;
    u_hat.x += mu * tangential(u).norm();
    (r - project_cone(&(r - rho * u_hat), mu)).norm()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    /// A vector with components uniform in (-scale, scale).
    pub(crate) fn random_vector(rng: &mut StdRng, scale: f64) -> Vector3<f64> {
        Vector3::new(
            rng.gen_range(-scale..scale),
            rng.gen_range(-scale..scale),
            rng.gen_range(-scale..scale),
        )
    }

    fn in_cone(x: &Vector3<f64>, mu: f64, tol: f64) -> bool {
        tangential(x).norm() <= mu * x.x + tol
    }

    #[test]
    fn frame_is_orthonormal_and_right_handed() {
        let mut rng = StdRng::seed_from_u64(10);
        let mut normals: Vec<Vector3<f64>> = (0..1000)
            .map(|_| random_vector(&mut rng, 1.0).normalize())
            .collect();
        normals.extend([
            Vector3::x(),
            Vector3::y(),
            Vector3::z(),
            -Vector3::z(),
            Vector3::new(1.0, 0.0, -0.0),
        ]);
        for n in &normals {
            let f = ContactFrame::from_normal(n);
            assert!((f.t1.norm() - 1.0).abs() < 1e-14 && (f.t2.norm() - 1.0).abs() < 1e-14);
            assert!(
                f.n.dot(&f.t1).abs() < 1e-14 && f.n.dot(&f.t2).abs() < 1e-14 && f.t1.dot(&f.t2).abs() < 1e-14
            );
            assert!((f.n.cross(&f.t1) - f.t2).norm() < 1e-14);
            let x = random_vector(&mut rng, 1.0);
            assert!((f.to_world(&f.to_local(&x)) - x).norm() < 1e-14);
        }
    }

    #[test]
    fn cone_projection_is_nearest_cone_point() {
        let mut rng = StdRng::seed_from_u64(11);
        for &mu in &[0.0, 0.1, 0.5, 1.0, 3.0] {
            for _ in 0..200 {
                let x = random_vector(&mut rng, 2.0);
                let p = project_cone(&x, mu);
                assert!(in_cone(&p, mu, 1e-14));
                let dist = (x - p).norm();
                // Moreau: x - p lies in the polar cone and is orthogonal to p.
                assert!((x - p).dot(&p).abs() < 1e-12);
                for _ in 0..2000 {
                    let rn: f64 = rng.gen_range(0.0..4.0);
                    let rho = mu * rn * rng.gen_range(0.0..1.0f64).sqrt();
                    let phi: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
                    let y = Vector3::new(rn, rho * phi.cos(), rho * phi.sin());
                    assert!(
                        (x - y).norm() >= dist - 1e-12,
                        "cone point closer than the projection"
                    );
                }
                // Points on the projection's ray, and perturbations of it along the
                // boundary, are never closer either.
                for k in [0.0, 0.5, 0.99, 1.01, 2.0] {
                    assert!((x - k * p).norm() >= dist - 1e-12);
                }
            }
        }
    }

    #[test]
    fn cone_projection_idempotent_and_fixes_inside() {
        let mut rng = StdRng::seed_from_u64(12);
        for &mu in &[0.0, 0.2, 1.0, 5.0] {
            for _ in 0..2000 {
                let x = random_vector(&mut rng, 3.0);
                let p = project_cone(&x, mu);
                assert!((project_cone(&p, mu) - p).norm() <= 1e-14 * (1.0 + p.norm()));
                if in_cone(&x, mu, 0.0) {
                    assert_eq!(p, x);
                }
                if mu * tangential(&x).norm() <= -x.x {
                    assert_eq!(p, Vector3::zeros());
                }
            }
        }
    }

    #[test]
    fn disk_projection() {
        let x = Vector2::new(3.0, 4.0);
        assert_eq!(project_disk(&x, 10.0), x);
        assert!((project_disk(&x, 1.0) - Vector2::new(0.6, 0.8)).norm() < 1e-15);
        assert_eq!(project_disk(&x, 0.0), Vector2::zeros());
        assert_eq!(project_disk(&x, -1.0), Vector2::zeros());
    }

    /// Checks eqs. (8)-(9) for `u = u0 + w r`.
    fn assert_signorini_coulomb(r: &Vector3<f64>, u: &Vector3<f64>, mu: f64, tol: f64) {
        let (rt, ut) = (tangential(r), tangential(u));
        assert!(
            r.x >= 0.0 && u.x >= -tol && (r.x * u.x).abs() <= tol,
            "Signorini: r {r:?} u {u:?}"
        );
        assert!(rt.norm() <= mu * r.x + tol, "outside the cone: r {r:?}");
        if ut.norm() > tol {
            assert!(
                (rt.norm() - mu * r.x).abs() <= tol,
                "sliding below the cone boundary"
            );
            assert!(
                (rt + mu * r.x * ut / ut.norm()).norm() <= tol,
                "friction not opposing sliding"
            );
        }
    }

    #[test]
    fn local_solution_satisfies_signorini_coulomb() {
        let mut rng = StdRng::seed_from_u64(13);
        let (mut stick, mut slide, mut separate) = (0, 0, 0);
        for _ in 0..20_000 {
            let u0 = random_vector(&mut rng, 1.0);
            let w = rng.gen_range(0.01..10.0);
            let mu = [0.0, 0.1, 0.3, 1.0, 2.0][rng.gen_range(0..5)];
            let r = solve_isotropic(&u0, w, mu);
            let u = u0 + w * r;
            assert_signorini_coulomb(&r, &u, mu, 1e-12);
            for rho in [1e-3, 1.0 / w, 1.0, 1e3] {
                assert!(
                    alart_curnier(&r, &u, mu, rho).norm() <= 1e-12 * (1.0 + rho),
                    "eq. (10) does not vanish"
                );
                assert!(natural_map_residual(&r, &u, mu, rho) <= 1e-12 * (1.0 + rho));
            }
            match (r.x > 0.0, tangential(&u).norm() > 1e-12) {
                (false, _) => separate += 1,
                (true, false) => stick += 1,
                (true, true) => slide += 1,
            }
        }
        assert!(
            stick > 100 && slide > 100 && separate > 100,
            "{stick} {slide} {separate}"
        );
    }

    #[test]
    fn residuals_positive_off_solution() {
        let mut rng = StdRng::seed_from_u64(14);
        for _ in 0..5000 {
            let u0 = random_vector(&mut rng, 1.0);
            let w = rng.gen_range(0.1..10.0);
            let mu = rng.gen_range(0.0..1.5);
            let r = solve_isotropic(&u0, w, mu);
            let dr = random_vector(&mut rng, 1e-3);
            let r_off = r + dr;
            let u_off = u0 + w * r_off;
            assert!(natural_map_residual(&r_off, &u_off, mu, 1.0 / w) > 0.0);
            assert!(alart_curnier(&r_off, &u_off, mu, 1.0 / w).norm() > 0.0);
        }
        // Explicit violations: penetration without force, adhesion, friction
        // outside the cone, friction along the sliding direction.
        let mu = 0.5;
        let cases = [
            (Vector3::zeros(), Vector3::new(-1.0, 0.0, 0.0)),
            (Vector3::new(-1.0, 0.0, 0.0), Vector3::zeros()),
            (Vector3::new(1.0, 1.0, 0.0), Vector3::zeros()),
            (Vector3::new(1.0, 0.5, 0.0), Vector3::new(0.0, 1.0, 0.0)),
            (Vector3::new(1.0, 0.2, 0.0), Vector3::new(0.0, -1.0, 0.0)),
            (Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.5, 0.0, 0.0)),
        ];
        for (r, u) in cases {
            assert!(natural_map_residual(&r, &u, mu, 1.0) > 1e-3, "r {r:?} u {u:?}");
            assert!(alart_curnier(&r, &u, mu, 1.0).norm() > 1e-3, "r {r:?} u {u:?}");
        }
    }
}
