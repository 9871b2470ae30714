//! The braid of the simplified knot model (paper Sec. 5, eqs. 13-14): two
//! intertwined helical strands of unit nondimensional radius (strand centrelines
//! one rod radius h from the braid axis, so the strands touch) and axial length
//! l̄_b, wound over the parameter range t in [-(n pi - theta), n pi - theta].
//!
//! All lengths are in units of the rod radius h and energies in units of EI/h
//! (eq. 12). Strand A is the helix of eq. (13), (cos t, sin t, b̄ t); strand B is
//! strand A turned by pi about the braid axis z, (-cos t, -sin t, b̄ t).
use crate::energies::{self, Terms};
use crate::material::Material;
use crate::rod::{Rod, RodError};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// One of the two helical strands of the braid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Strand {
    /// The helix of eq. (13); the loop leaves it at t = n pi - theta.
    A,
    /// Strand A turned by pi about z; the loop enters it at t = -(n pi - theta).
    B,
}

/// The braid for unknotting number `n`, rotation angle `theta` of its ends and
/// nondimensional axial length `l_b_bar` (eq. 13).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Braid {
    pub n: u32,
    pub theta: f64,
    pub l_b_bar: f64,
}

impl Braid {
    /// Half the parameter range, T = n pi - theta (eq. 13); positive for a valid braid.
    pub fn half_span(&self) -> f64 {
        f64::from(self.n) * PI - self.theta
    }

    /// Nondimensional pitch b̄ = l̄_b / (2 n pi - 2 theta), eq. (13).
    pub fn pitch(&self) -> f64 {
        self.l_b_bar / (2.0 * self.half_span())
    }

    /// Nondimensional curvature of each strand, κ̄ = 1 / (1 + b̄²), eq. (14).
    pub fn curvature(&self) -> f64 {
        1.0 / (1.0 + self.pitch().powi(2))
    }

    /// Arc length of one strand, 2 T sqrt(1 + b̄²).
    pub fn strand_length(&self) -> f64 {
        2.0 * self.half_span() * (1.0 + self.pitch().powi(2)).sqrt()
    }

    /// Bending energy of both strands, Ē_b = 2 κ̄² (n pi - theta) sqrt(1 + b̄²), eq. (14).
    pub fn energy(&self) -> f64 {
        let k = self.curvature();
        2.0 * k * k * self.half_span() * (1.0 + self.pitch().powi(2)).sqrt()
    }

    /// dĒ_b/dθ at fixed n and l̄_b. With T = n pi - theta, Ē_b = 2 T (1 + b̄²)^(-3/2)
    /// and b̄ = l̄_b / (2T), so dĒ_b/dT = 2 (1 + 4 b̄²) (1 + b̄²)^(-5/2) and dT/dθ = -1.
    pub fn energy_derivative(&self) -> f64 {
        let b2 = self.pitch().powi(2);
        -2.0 * (1.0 + 4.0 * b2) * (1.0 + b2).powf(-2.5)
    }

    /// Point of `strand` at helix parameter `t` (nondimensional).
    pub fn point(&self, strand: Strand, t: f64) -> Vector3<f64> {
        let (s, c) = t.sin_cos();
        let z = self.pitch() * t;
        match strand {
            Strand::A => Vector3::new(c, s, z),
            Strand::B => Vector3::new(-c, -s, z),
        }
    }

    /// Unit tangent of `strand` at `t`, in the direction of increasing t.
    pub fn tangent(&self, strand: Strand, t: f64) -> Vector3<f64> {
        let (s, c) = t.sin_cos();
        let v = match strand {
            Strand::A => Vector3::new(-s, c, self.pitch()),
            Strand::B => Vector3::new(s, -c, self.pitch()),
        };
        v.normalize()
    }

    /// Ē_b of a DER discretisation of the two strands (bending energy of eq. 6b,
    /// times h/EI) with `nodes` nodes per strand. Nodes are equally spaced in t and
    /// extend half a spacing beyond each end, so that the Voronoi cells of the
    /// interior nodes (which carry the bending energy) tile t in [-T, T] exactly;
    /// the discrete energy then converges to eq. (14) at second order in 1/nodes.
    pub fn discrete_energy(&self, nodes: usize) -> Result<f64, RodError> {
        if nodes < 3 {
            return Err(RodError::TooFewNodes(nodes));
        }
        let radius = 1.0;
        let material = Material::default();
        let span = self.half_span();
        let dt = 2.0 * span / (nodes - 2) as f64;
        let bending = Terms {
            stretching: false,
            bending: true,
            twisting: false,
        };
        let mut total = 0.0;
        for strand in [Strand::A, Strand::B] {
            let points: Vec<Vector3<f64>> = (0..nodes)
                .map(|j| self.point(strand, -span + (j as f64 - 0.5) * dt) * radius)
                .collect();
            let rod = Rod::new(&points, radius, material)?;
            let mut grad = vec![0.0; rod.ndof()];
            total += energies::evaluate(&rod, bending, &mut grad, None).bending * radius / rod.section.ei;
        }
        Ok(total)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper_braid(theta: f64) -> Braid {
        // n = 3, l̄_k = 137.5, epsilon = 0.7: l̄_b = 0.7 * 137.5 / 1.7.
        Braid {
            n: 3,
            theta,
            l_b_bar: 0.7 * 137.5 / 1.7,
        }
    }

    #[test]
    fn geometry_matches_eq13() {
        let b = paper_braid(0.8);
        let t = b.half_span();
        // The axial length is l̄_b and each strand is a unit-radius helix of pitch b̄.
        let za = b.point(Strand::A, t).z - b.point(Strand::A, -t).z;
        assert!((za - b.l_b_bar).abs() < 1e-12);
        for s in [-t, -0.3, 1.1, t] {
            let p = b.point(Strand::A, s);
            assert!(((p.x * p.x + p.y * p.y).sqrt() - 1.0).abs() < 1e-14);
            // Strand B is strand A turned by pi about z.
            let q = b.point(Strand::B, s);
            assert!((q - Vector3::new(-p.x, -p.y, p.z)).norm() < 1e-14);
            // The tangent is the normalised derivative.
            let h = 1e-6;
            let fd = (b.point(Strand::A, s + h) - b.point(Strand::A, s - h)).normalize();
            assert!((fd - b.tangent(Strand::A, s)).norm() < 1e-9);
        }
        // Arc length by quadrature of |x'(t)| equals the closed form.
        let m = 2000;
        let mut len = 0.0;
        for j in 0..m {
            let a = -t + 2.0 * t * j as f64 / m as f64;
            let c = -t + 2.0 * t * (j + 1) as f64 / m as f64;
            len += (b.point(Strand::A, c) - b.point(Strand::A, a)).norm();
        }
        assert!((len - b.strand_length()).abs() < 1e-5 * len);
    }

    #[test]
    fn energy_is_half_integral_of_curvature_squared() {
        // Independent evaluation: 2 strands x (1/2) κ̄² x arc length.
        let b = paper_braid(1.3);
        let k = b.curvature();
        let expected = 2.0 * 0.5 * k * k * b.strand_length();
        assert!((b.energy() - expected).abs() < 1e-14 * expected);
        // κ̄ = r / (r² + c²) for a helix of radius r = 1 and c = b̄.
        let pitch = b.pitch();
        assert!((k - 1.0 / (1.0 + pitch * pitch)).abs() < 1e-15);
    }

    #[test]
    fn derivative_matches_finite_differences() {
        for theta in [0.0, 1.0, 2.5, 4.9] {
            let h = 1e-5;
            let fd = (paper_braid(theta + h).energy() - paper_braid(theta - h).energy()) / (2.0 * h);
            let d = paper_braid(theta).energy_derivative();
            assert!((fd - d).abs() < 1e-8 * d.abs(), "theta {theta}: fd {fd} vs {d}");
            // Unwinding the braid relaxes it.
            assert!(d < 0.0);
        }
    }
}
