//! Gravity F^G of eq. (7c): constant nodal forces m_i g from the lumped mass.
use crate::rod::{Rod, node_dof};
use nalgebra::Vector3;

/// Adds m_i g to the position entries of `force`.
pub fn add(rod: &Rod, g: &Vector3<f64>, force: &mut [f64]) {
    for i in 0..rod.nodes() {
        let d = node_dof(i);
        for c in 0..3 {
            force[d + c] += rod.mass[d + c] * g[c];
        }
    }
}
