//! Twisting energy, eq. (6c): E_t = 1/2 sum_i GJ (tau_i - tau^_i)^2 / l_i with the
//! twist tau_i = th_i - th_{i-1} + reference twist (eq. 5) and the undeformed
//! Voronoi length l_i. The rod is untwisted at rest (tau^ = 0).
use super::{Local, add_outer_lower, scatter_stencil};
use crate::rod::Rod;
use nalgebra::{Matrix3, Vector3};

/// Adds the gradient and (lower) Hessian of interior node `i` over the stencil
/// [x_{i-1}, th_{i-1}, x_i, th_i, x_{i+1}] to `out` and returns its energy. The
/// Hessian is the symmetric DER Hessian (frames are transported, see `energies`).
pub fn node(rod: &Rod, i: usize, with_hessian: bool, out: &mut Local<11>) -> f64 {
    let g = &rod.geo;
    let gj_l = rod.section.gj / rod.voronoi[i];
    let tau = rod.twist(i);
    let kb = g.kb[i];
    let (ne, nf) = (g.edge_len[i - 1], g.edge_len[i]);
    let energy = 0.5 * gj_l * tau * tau;
    // d(tau)/de = kb / (2|e|), d(tau)/df = kb / (2|f|).
    let de = kb / (2.0 * ne);
    let df = kb / (2.0 * nf);
    let mut grad_tau = nalgebra::SVector::<f64, 11>::zeros();
    scatter_gradient(&mut grad_tau, &de, &df, -1.0, 1.0);
    out.grad.axpy(gj_l * tau, &grad_tau, 1.0);
    if with_hessian {
        let te = g.tangent[i - 1];
        let tf = g.tangent[i];
        let chi = 1.0 + te.dot(&tf);
        let tt = (te + tf) / chi;
        let sym = |a: Vector3<f64>, b: Vector3<f64>| a * b.transpose() + b * a.transpose();
        let a = sym(kb, te + tt) * (-0.25 / (ne * ne));
        let c = sym(kb, tf + tt) * (-0.25 / (nf * nf));
        let b: Matrix3<f64> = (te.cross_matrix() * (2.0 / chi) - kb * tt.transpose()) * (0.5 / (ne * nf));
        scatter_stencil(&mut out.hess, &a, &b, &c, (gj_l * tau, 0.0, 0.0));
        add_outer_lower(&mut out.hess, gj_l, &grad_tau);
    }
    energy
}

/// Writes d/dx of a stencil quantity from its derivatives along the edges
/// e = x_i - x_{i-1} and f = x_{i+1} - x_i, and its derivatives along th_{i-1}, th_i.
pub(super) fn scatter_gradient(
    grad: &mut nalgebra::SVector<f64, 11>,
    de: &Vector3<f64>,
    df: &Vector3<f64>,
    dthe: f64,
    dthf: f64,
) {
    grad.fixed_rows_mut::<3>(0).copy_from(&-de);
    grad[3] = dthe;
    grad.fixed_rows_mut::<3>(4).copy_from(&(de - df));
    grad[7] = dthf;
    grad.fixed_rows_mut::<3>(8).copy_from(df);
}
