//! Finite-difference checks of the analytic gradients and Hessians of eq. (6),
//! and the rigid-motion invariance of the energy.
use super::rng::SplitMix64;
use crate::energies::{self, BANDWIDTH, Terms};
use crate::linalg::banded::BandedSym;
use crate::material::Material;
use crate::rod::{Rod, node_dof, theta_dof};
use nalgebra::{DMatrix, Rotation3, Vector3};

/// Each energy alone and their sum, as checked by the derivative tests.
pub const TERM_SETS: [(&str, Terms); 4] = [
    (
        "stretching",
        Terms {
            stretching: true,
            bending: false,
            twisting: false,
        },
    ),
    (
        "bending",
        Terms {
            stretching: false,
            bending: true,
            twisting: false,
        },
    ),
    (
        "twisting",
        Terms {
            stretching: false,
            bending: false,
            twisting: true,
        },
    ),
    ("total", Terms::ALL),
];

/// A bent, stretched and twisted rod of 9 nodes with random perturbations: a
/// non-trivial configuration for the derivative checks (frames rebased on it).
pub fn sample_rod(seed: u64) -> Rod {
    let mut rng = SplitMix64::new(seed);
    let k = 9;
    let straight: Vec<Vector3<f64>> = (0..k).map(|i| Vector3::new(0.15 * i as f64, 0.0, 0.0)).collect();
    let material = Material {
        youngs_modulus: 1e5,
        poisson_ratio: 0.5,
        density: 1000.0,
    };
    let mut rod = Rod::new(&straight, 0.02, material).expect("valid sample rod");
    for i in 0..k {
        let s = i as f64 * 0.15;
        let x = Vector3::new(
            0.6 * s.sin() + rng.uniform(-0.02, 0.02),
            0.5 * (1.0 - (1.3 * s).cos()) + rng.uniform(-0.02, 0.02),
            0.2 * s * s + rng.uniform(-0.02, 0.02),
        );
        rod.set_node(i, x * 1.1);
    }
    rod.rebase_frames();
    for i in 0..rod.edges() {
        rod.set_theta(i, rng.uniform(-0.6, 0.6));
    }
    rod.update_geometry();
    rod
}

/// Relative 2-norm error |g - g_fd| / |g| of the analytic gradient of `terms`
/// against central differences of the energy (frames transported from the
/// configuration itself, where the DER gradient is exact).
pub fn gradient_error(rod: &mut Rod, terms: Terms) -> f64 {
    let n = rod.ndof();
    let mut g = vec![0.0; n];
    let mut scratch = vec![0.0; n];
    energies::evaluate(rod, terms, &mut g, None);
    let mut num = 0.0;
    let mut den = 0.0;
    for (j, gj) in g.iter().enumerate() {
        let h = 1e-6;
        let q0 = rod.q[j];
        rod.q[j] = q0 + h;
        rod.update_geometry();
        let ep = energies::evaluate(rod, terms, &mut scratch, None).total();
        rod.q[j] = q0 - h;
        rod.update_geometry();
        let em = energies::evaluate(rod, terms, &mut scratch, None).total();
        rod.q[j] = q0;
        let fd = (ep - em) / (2.0 * h);
        num += (gj - fd).powi(2);
        den += gj.powi(2);
    }
    rod.update_geometry();
    (num / den).sqrt()
}

/// Relative Frobenius error |H - J_sym| / |H| of the analytic Hessian against the
/// symmetrised central-difference Jacobian J_sym = (J + J^T)/2 of the gradient.
pub fn hessian_error(rod: &mut Rod, terms: Terms) -> f64 {
    let n = rod.ndof();
    let mut hess = BandedSym::new(n, BANDWIDTH);
    let mut g = vec![0.0; n];
    energies::evaluate(rod, terms, &mut g, Some(&mut hess));
    let h_an = hess.to_dense();
    let mut jac = DMatrix::<f64>::zeros(n, n);
    let mut gp = vec![0.0; n];
    let mut gm = vec![0.0; n];
    for j in 0..n {
        let h = 1e-6;
        let q0 = rod.q[j];
        rod.q[j] = q0 + h;
        rod.update_geometry();
        energies::evaluate(rod, terms, &mut gp, None);
        rod.q[j] = q0 - h;
        rod.update_geometry();
        energies::evaluate(rod, terms, &mut gm, None);
        rod.q[j] = q0;
        for i in 0..n {
            jac[(i, j)] = (gp[i] - gm[i]) / (2.0 * h);
        }
    }
    rod.update_geometry();
    let sym = (&jac + jac.transpose()) * 0.5;
    (&h_an - sym).norm() / h_an.norm()
}

/// Rigid-motion checks on a bent, twisted rod: returns (relative energy change
/// under a finite rotation + translation, relative net internal force, relative
/// net internal torque). The net force sum f_i and torque sum (x_i x f_i + m_e t_e)
/// of the internal forces must vanish: translations and rotations do no work.
pub fn rigid_motion_errors(seed: u64) -> (f64, f64, f64) {
    let mut rod = sample_rod(seed);
    let n = rod.ndof();
    let mut g = vec![0.0; n];
    let e0 = energies::evaluate(&rod, Terms::ALL, &mut g, None).total();
    let scale_f = (0..rod.nodes())
        .map(|i| Vector3::from_column_slice(&g[node_dof(i)..node_dof(i) + 3]).norm())
        .fold(0.0, f64::max);
    let mut force = Vector3::zeros();
    let mut torque = Vector3::zeros();
    let mut lever = 0.0f64;
    for i in 0..rod.nodes() {
        let f = Vector3::from_column_slice(&g[node_dof(i)..node_dof(i) + 3]);
        force += f;
        torque += rod.node(i).cross(&f);
        lever = lever.max(rod.node(i).norm());
    }
    for e in 0..rod.edges() {
        torque += rod.geo.tangent[e] * g[theta_dof(e)];
    }
    let r = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(Vector3::new(0.3, -0.5, 0.8)), 1.1);
    rod.transform_rigid(&r, &Vector3::new(0.4, -1.2, 2.5));
    let e1 = energies::evaluate(&rod, Terms::ALL, &mut g, None).total();
    (
        (e1 - e0).abs() / e0,
        force.norm() / scale_f,
        torque.norm() / (scale_f * lever),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gradients_match_finite_differences() {
        for seed in 0..4 {
            for (name, terms) in TERM_SETS {
                let mut rod = sample_rod(seed);
                let err = gradient_error(&mut rod, terms);
                assert!(err <= 1e-6, "{name} gradient, seed {seed}: {err:e}");
            }
        }
    }

    #[test]
    fn hessians_match_symmetrised_finite_differences() {
        for seed in 0..4 {
            for (name, terms) in TERM_SETS {
                let mut rod = sample_rod(seed);
                let err = hessian_error(&mut rod, terms);
                assert!(err <= 1e-6, "{name} Hessian, seed {seed}: {err:e}");
            }
        }
    }

    #[test]
    fn rigid_motions_do_no_work() {
        for seed in 0..4 {
            let (de, f, t) = rigid_motion_errors(seed);
            assert!(de < 1e-12, "energy change {de:e}");
            assert!(f < 1e-12, "net force {f:e}");
            assert!(t < 1e-12, "net torque {t:e}");
        }
    }
}
