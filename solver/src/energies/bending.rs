//! Bending energy, eq. (6b): E_b = 1/2 sum_i EI [(k1_i - k1^_i)^2 + (k2_i - k2^_i)^2] / l_i
//! with the material curvatures of eq. (4) and the undeformed Voronoi length l_i.
//! The rod is naturally straight (k^ = 0); EI1 = EI2 = EI for a circular section.
use super::twisting::scatter_gradient;
use super::{Local, add_outer_lower, scatter_stencil};
use crate::rod::Rod;
use nalgebra::{Matrix3, SVector, Vector3};

/// Adds the gradient and (lower) Hessian of interior node `i` over the stencil
/// [x_{i-1}, th_{i-1}, x_i, th_i, x_{i+1}] to `out` and returns its energy.
pub fn node(rod: &Rod, i: usize, with_hessian: bool, out: &mut Local<11>) -> f64 {
    let g = &rod.geo;
    let ei_l = rod.section.ei / rod.voronoi[i];
    let [k1, k2] = g.kappa[i];
    let kb = g.kb[i];
    let (te, tf) = (g.tangent[i - 1], g.tangent[i]);
    let (ne, nf) = (g.edge_len[i - 1], g.edge_len[i]);
    let (m1e, m2e, m1f, m2f) = (g.m1[i - 1], g.m2[i - 1], g.m1[i], g.m2[i]);
    let chi = 1.0 + te.dot(&tf);
    let tt = (te + tf) / chi;
    let mt1 = (m1e + m1f) / chi;
    let mt2 = (m2e + m2f) / chi;
    let energy = 0.5 * ei_l * (k1 * k1 + k2 * k2);

    let tf_x_m2 = tf.cross(&mt2);
    let te_x_m2 = te.cross(&mt2);
    let tf_x_m1 = tf.cross(&mt1);
    let te_x_m1 = te.cross(&mt1);
    let mut gk1 = SVector::<f64, 11>::zeros();
    let mut gk2 = SVector::<f64, 11>::zeros();
    scatter_gradient(
        &mut gk1,
        &((tf_x_m2 - tt * k1) / ne),
        &((-te_x_m2 - tt * k1) / nf),
        -0.5 * kb.dot(&m1e),
        -0.5 * kb.dot(&m1f),
    );
    scatter_gradient(
        &mut gk2,
        &((-tf_x_m1 - tt * k2) / ne),
        &((te_x_m1 - tt * k2) / nf),
        -0.5 * kb.dot(&m2e),
        -0.5 * kb.dot(&m2f),
    );
    out.grad.axpy(ei_l * k1, &gk1, 1.0);
    out.grad.axpy(ei_l * k2, &gk2, 1.0);
    if !with_hessian {
        return energy;
    }
    let id = Matrix3::identity();
    let outer = |a: &Vector3<f64>, b: &Vector3<f64>| a * b.transpose();
    let sym = |a: &Vector3<f64>, b: &Vector3<f64>| a * b.transpose() + b * a.transpose();
    let ttt = outer(&tt, &tt);
    let pe = id - outer(&te, &te);
    let pf = id - outer(&tf, &tf);
    let (ne2, nf2, nef) = (ne * ne, nf * nf, ne * nf);
    // Second derivatives of k1 and of k2 along (e, e), (e, f), (f, f).
    let a1 = (ttt * (2.0 * k1) - sym(&tf_x_m2, &tt)) / ne2 - pe * (k1 / (chi * ne2))
        + sym(&kb, &m2e) / (4.0 * ne2);
    let c1 = (ttt * (2.0 * k1) + sym(&te_x_m2, &tt)) / nf2 - pf * (k1 / (chi * nf2))
        + sym(&kb, &m2f) / (4.0 * nf2);
    let b1 = (id + outer(&te, &tf)) * (-k1 / (chi * nef))
        + (ttt * (2.0 * k1) - outer(&tf_x_m2, &tt) + outer(&tt, &te_x_m2) - mt2.cross_matrix()) / nef;
    let a2 = (ttt * (2.0 * k2) + sym(&tf_x_m1, &tt)) / ne2
        - pe * (k2 / (chi * ne2))
        - sym(&kb, &m1e) / (4.0 * ne2);
    let c2 = (ttt * (2.0 * k2) - sym(&te_x_m1, &tt)) / nf2
        - pf * (k2 / (chi * nf2))
        - sym(&kb, &m1f) / (4.0 * nf2);
    let b2 = (id + outer(&te, &tf)) * (-k2 / (chi * nef))
        + (ttt * (2.0 * k2) + outer(&tf_x_m1, &tt) - outer(&tt, &te_x_m1) + mt1.cross_matrix()) / nef;
    let a: Matrix3<f64> = a1 * k1 + a2 * k2;
    let b: Matrix3<f64> = b1 * k1 + b2 * k2;
    let c: Matrix3<f64> = c1 * k1 + c2 * k2;
    // Second derivatives along th: d2/dth_e^2, d2/dth_f^2 (no th_e th_f coupling).
    let dthe2 = k1 * (-0.5 * kb.dot(&m2e)) + k2 * (0.5 * kb.dot(&m1e));
    let dthf2 = k1 * (-0.5 * kb.dot(&m2f)) + k2 * (0.5 * kb.dot(&m1f));
    scatter_stencil(&mut out.hess, &a, &b, &c, (ei_l, ei_l * dthe2, ei_l * dthf2));
    // Mixed (position, th) derivatives, combined over k1 and k2.
    let mixed = |m1: &Vector3<f64>, m2: &Vector3<f64>| {
        let de =
            (tt * (0.5 * (k1 * kb.dot(m1) + k2 * kb.dot(m2))) - tf.cross(&(m1 * k1 + m2 * k2)) / chi) / ne;
        let df =
            (tt * (0.5 * (k1 * kb.dot(m1) + k2 * kb.dot(m2))) + te.cross(&(m1 * k1 + m2 * k2)) / chi) / nf;
        (de, df)
    };
    for (col, (m1, m2)) in [(3usize, (m1e, m2e)), (7usize, (m1f, m2f))] {
        let (de, df) = mixed(&m1, &m2);
        let mut v = SVector::<f64, 11>::zeros();
        scatter_gradient(&mut v, &de, &df, 0.0, 0.0);
        // Lower triangle: entries below the th column, right of the th row.
        for r in col + 1..11 {
            out.hess[(r, col)] += ei_l * v[r];
        }
        for k in 0..col {
            out.hess[(col, k)] += ei_l * v[k];
        }
    }
    add_outer_lower(&mut out.hess, ei_l, &gk1);
    add_outer_lower(&mut out.hess, ei_l, &gk2);
    energy
}
