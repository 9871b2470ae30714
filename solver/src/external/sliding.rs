//! Damping that spares sliding along the centre line: the fast stages of the
//! adaptive pull (the protocol module) damp the swinging of the loop and the
//! tails, not the flow of material through the knot.
//!
//! The stepper's damping is mass-proportional, F = -gamma M v. Pulling a knot
//! moves most of the rod along its own centre line (the tails translate, the
//! loop's material slides out through the braid), so that force is a drag
//! that the clamps must overcome, amplified by friction in the braid: at 16
//! times the pull speed and gamma = 20/s it raised n = 3's F bar by about 11 %.
//! The load gamma m_i t_i (t_i . v_i) at each free node cancels the drag's
//! part along the node's tangent t_i, so the damping acts on
//! (I - t_i t_i^T) v_i alone. It is explicit (from the last accepted step's
//! velocity); within a step it differs from the tangential velocity by
//! gamma dt times the step's change.
use crate::rod::{Rod, node_dof};
use nalgebra::Vector3;

/// Writes into `load` (one entry per DOF) the forces that exempt sliding
/// along the centre line from the damping rate `gamma` (1/s); zero at the
/// twist angles and at fixed nodes.
pub fn exempt_sliding(rod: &Rod, gamma: f64, load: &mut [f64]) {
    load.fill(0.0);
    let n = rod.nodes();
    for i in 0..n {
        let d = node_dof(i);
        if rod.fixed[d] {
            continue;
        }
        let t = tangent(rod, i, n);
        let f = t * (gamma * rod.mass[d] * t.dot(&rod.node_velocity(i)));
        load[d..d + 3].copy_from_slice(f.as_slice());
    }
}

/// The centre line's unit tangent at node `i` of `n`: along its two edges'
/// chord (the end edge at an end node).
fn tangent(rod: &Rod, i: usize, n: usize) -> Vector3<f64> {
    (rod.node((i + 1).min(n - 1)) - rod.node(i.saturating_sub(1))).normalize()
}

#[cfg(test)]
mod tests {
    use super::exempt_sliding;
    use crate::external::Environment;
    use crate::material::Material;
    use crate::rod::{Rod, node_dof};
    use crate::stepper::{NewtonOptions, Stepper};
    use nalgebra::Vector3;

    /// A free straight rod translating along and across its axis under
    /// damping gamma: backward Euler leaves each damped velocity component
    /// divided by 1 + gamma dt per step. With the exemption the component
    /// along the rod keeps its value exactly and the one across it decays
    /// as before.
    #[test]
    fn damping_spares_the_motion_along_the_rod_only() {
        let (gamma, dt, steps): (f64, f64, i32) = (20.0, 1e-3, 100);
        let decay = (1.0 + gamma * dt).powi(steps);
        for exempt in [false, true] {
            let points: Vec<_> = (0..31).map(|i| Vector3::new(0.01 * i as f64, 0.0, 0.0)).collect();
            let mut rod = Rod::new(&points, 1e-3, Material::default()).expect("valid rod");
            for i in 0..rod.nodes() {
                rod.velocity[node_dof(i)] = 0.1;
                rod.velocity[node_dof(i) + 1] = 0.05;
            }
            let env = Environment {
                gravity: Vector3::zeros(),
                damping: gamma,
            };
            let mut stepper = Stepper::new(&rod, NewtonOptions::default());
            let mut load = vec![0.0; rod.ndof()];
            for _ in 0..steps {
                exempt_sliding(&rod, if exempt { gamma } else { 0.0 }, &mut load);
                stepper.step(&mut rod, &env, Some(&load), dt).expect("step");
            }
            for i in 0..rod.nodes() {
                let v = rod.node_velocity(i);
                let along = if exempt { 0.1 } else { 0.1 / decay };
                assert!(
                    (v.x - along).abs() < 1e-9 * along,
                    "exempt {exempt}: v_x {} vs {along}",
                    v.x
                );
                assert!(
                    (v.y - 0.05 / decay).abs() < 1e-9 * 0.05,
                    "exempt {exempt}: v_y {}",
                    v.y
                );
            }
        }
    }
}
