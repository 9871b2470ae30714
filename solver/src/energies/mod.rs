//! Elastic energies of a rod, eq. (6), with analytic gradients and Hessians,
//! assembled into a global gradient and a banded Hessian.
//!
//! Reference frames are carried by time-parallel transport from the last accepted
//! step, so the exact Jacobian of the DER gradient is slightly unsymmetric away
//! from that step; the Hessians here are the symmetric DER Hessians (Bergou et al.
//! 2010), which equal the symmetric part of that Jacobian. The tests check them
//! against the symmetrised finite-difference Jacobian of the gradient.
pub mod bending;
pub mod stretching;
pub mod twisting;

use crate::linalg::banded::BandedSym;
use crate::rod::{Rod, node_dof};
use nalgebra::{Matrix3, SMatrix, SVector};
use serde::{Deserialize, Serialize};

/// Half-bandwidth of the DER Hessian in the DOF order of eq. (1): a bending or
/// twisting stencil spans 11 consecutive DOFs.
pub const BANDWIDTH: usize = 10;

/// Energy, gradient and Hessian of one stencil over `N` consecutive DOFs.
/// Only the lower triangle of `hess` is kept (the Hessian is symmetric).
#[derive(Clone, Debug)]
pub struct Local<const N: usize> {
    pub energy: f64,
    pub grad: SVector<f64, N>,
    pub hess: SMatrix<f64, N, N>,
}

impl<const N: usize> Default for Local<N> {
    fn default() -> Self {
        Self {
            energy: 0.0,
            grad: SVector::zeros(),
            hess: SMatrix::zeros(),
        }
    }
}

/// The elastic energies of eq. (6) (J).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Energies {
    pub stretching: f64,
    pub bending: f64,
    pub twisting: f64,
}

impl Energies {
    /// E_s + E_b + E_t.
    pub fn total(&self) -> f64 {
        self.stretching + self.bending + self.twisting
    }
}

/// Which energies to include (all by default; the checks test each alone).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Terms {
    pub stretching: bool,
    pub bending: bool,
    pub twisting: bool,
}

impl Terms {
    pub const ALL: Terms = Terms {
        stretching: true,
        bending: true,
        twisting: true,
    };
}

/// Evaluates the energies at the rod's current geometry (call
/// `Rod::update_geometry` after changing q), overwriting `grad` with dE/dq and,
/// when given, `hess` with the Hessian.
pub fn evaluate(rod: &Rod, terms: Terms, grad: &mut [f64], mut hess: Option<&mut BandedSym>) -> Energies {
    grad.fill(0.0);
    if let Some(h) = hess.as_deref_mut() {
        h.clear();
    }
    let with_h = hess.is_some();
    let mut out = Energies::default();
    if terms.stretching {
        let mut local = Local::<7>::default();
        for i in 0..rod.edges() {
            stretching::edge(rod, i, with_h, &mut local);
            out.stretching += local.energy;
            add_local(node_dof(i), &local, grad, hess.as_deref_mut());
        }
    }
    if terms.bending || terms.twisting {
        let mut local = Local::<11>::default();
        for i in 1..rod.nodes() - 1 {
            local.energy = 0.0;
            local.grad.fill(0.0);
            if with_h {
                local.hess.fill(0.0);
            }
            if terms.bending {
                out.bending += bending::node(rod, i, with_h, &mut local);
            }
            if terms.twisting {
                out.twisting += twisting::node(rod, i, with_h, &mut local);
            }
            add_local(node_dof(i - 1), &local, grad, hess.as_deref_mut());
        }
    }
    out
}

/// The elastic energy attributed to the nodes `nodes` (J), by node: the
/// bending and twisting energies of eq. (6) at each interior node in the
/// range, and half the stretching energy of each edge per end node in it.
/// Over `0..K` it is `evaluate`'s total; disjoint ranges add up.
pub fn within(rod: &Rod, nodes: std::ops::Range<usize>) -> f64 {
    let mut edge = Local::<7>::default();
    let mut node = Local::<11>::default();
    let mut total = 0.0;
    for i in nodes.clone() {
        for e in [i.wrapping_sub(1), i] {
            if e < rod.edges() {
                stretching::edge(rod, e, false, &mut edge);
                total += 0.5 * edge.energy;
            }
        }
        if i >= 1 && i + 1 < rod.nodes() {
            node.energy = 0.0;
            total += bending::node(rod, i, false, &mut node) + twisting::node(rod, i, false, &mut node);
        }
    }
    total
}

fn add_local<const N: usize>(
    offset: usize,
    local: &Local<N>,
    grad: &mut [f64],
    hess: Option<&mut BandedSym>,
) {
    for (g, l) in grad[offset..offset + N].iter_mut().zip(local.grad.iter()) {
        *g += l;
    }
    if let Some(h) = hess {
        h.add_block(offset, &local.hess);
    }
}

/// Adds `scale` times the lower position blocks of a stencil Hessian, from the
/// second derivatives along the edges e = x_i - x_{i-1}, f = x_{i+1} - x_i
/// (`a` = d2/de2, `b` = d2/de df, `c` = d2/df2), and `dthe2`, `dthf2` to the
/// (th_{i-1}, th_{i-1}) and (th_i, th_i) entries. Lower triangle only.
pub(crate) fn scatter_stencil(
    hess: &mut SMatrix<f64, 11, 11>,
    a: &Matrix3<f64>,
    b: &Matrix3<f64>,
    c: &Matrix3<f64>,
    (scale, dthe2, dthf2): (f64, f64, f64),
) {
    let bt = b.transpose();
    let blocks = [
        (0, 0, *a),
        (4, 0, bt - a),
        (4, 4, a - b - bt + c),
        (8, 0, -bt),
        (8, 4, bt - c),
        (8, 8, *c),
    ];
    for (r, col, m) in blocks {
        let mut v = hess.fixed_view_mut::<3, 3>(r, col);
        v += m * scale;
    }
    hess[(3, 3)] += dthe2;
    hess[(7, 7)] += dthf2;
}

/// Adds `w v v^T` to the lower triangle of `hess`.
#[inline]
pub(crate) fn add_outer_lower<const N: usize>(hess: &mut SMatrix<f64, N, N>, w: f64, v: &SVector<f64, N>) {
    for c in 0..N {
        let wc = w * v[c];
        for r in c..N {
            hess[(r, c)] += wc * v[r];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use nalgebra::Vector3;

    /// A bent, stretched and twisted rod: the energy by node over all nodes
    /// is the total of eq. (6), and disjoint ranges add up.
    #[test]
    fn energies_by_node_add_up_to_the_total() {
        let points: Vec<Vector3<f64>> = (0..40)
            .map(|i| {
                let s = i as f64 * 0.03;
                Vector3::new(s, 0.1 * (3.0 * s).sin(), 0.05 * s * s)
            })
            .collect();
        let mut rod = Rod::new(&points, 1e-3, Material::default()).unwrap();
        rod.add_twist(0.7);
        for (k, q) in rod.q.iter_mut().enumerate() {
            *q *= 1.0 + 1e-3 * (k % 3) as f64;
        }
        rod.update_geometry();
        let mut grad = vec![0.0; rod.ndof()];
        let total = evaluate(&rod, Terms::ALL, &mut grad, None).total();
        let k = rod.nodes();
        let all = within(&rod, 0..k);
        assert!(
            total > 0.0 && (all - total).abs() <= 1e-12 * total,
            "{all} against {total}"
        );
        let parts = within(&rod, 0..7) + within(&rod, 7..25) + within(&rod, 25..k);
        assert!((parts - total).abs() <= 1e-12 * total);
    }
}
