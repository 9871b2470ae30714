//! Stretching energy, eq. (6a): E_s = 1/2 sum_i EA (eps_i)^2 |e^_i| with the
//! strain eps_i = |e_i| / |e^_i| - 1 of eq. (2).
use super::Local;
use crate::rod::Rod;
use nalgebra::Matrix3;

/// Energy, gradient and Hessian of edge `i` over its local DOFs
/// [x_i, th_i, x_{i+1}] (7 entries, the twist entry is zero); lower Hessian only.
pub fn edge(rod: &Rod, i: usize, with_hessian: bool, out: &mut Local<7>) {
    let ea = rod.section.ea;
    let rest = rod.rest_len[i];
    let len = rod.geo.edge_len[i];
    let t = rod.geo.tangent[i];
    let strain = len / rest - 1.0;
    out.energy = 0.5 * ea * strain * strain * rest;
    // dE/de = EA eps t.
    let f = t * (ea * strain);
    out.grad.fixed_rows_mut::<3>(0).copy_from(&-f);
    out.grad[3] = 0.0;
    out.grad.fixed_rows_mut::<3>(4).copy_from(&f);
    if with_hessian {
        // d2E/de2 = EA [(1/|e^| - 1/|e|) I + t t^T / |e|].
        let k = Matrix3::identity() * (ea * (1.0 / rest - 1.0 / len)) + t * t.transpose() * (ea / len);
        out.hess.fill(0.0);
        out.hess.fixed_view_mut::<3, 3>(0, 0).copy_from(&k);
        out.hess.fixed_view_mut::<3, 3>(4, 4).copy_from(&k);
        out.hess.fixed_view_mut::<3, 3>(4, 0).copy_from(&-k);
    }
}
