//! Static cases: twisting of a clamped straight rod, Euler buckling of a
//! clamped-clamped column, and a cantilever under gravity (small deflection
//! against Euler-Bernoulli, large deflection against an elastica solved by
//! shooting in `elastica`).
//!
//! Clamps hold a whole end edge (two nodes and the edge twist, paper Sec. 4), so
//! the continuum rod they represent starts at the middle of that edge: the free
//! length between two clamps is L - l_e and a cantilever's is L - l_e/2, with l_e
//! the edge length. Expectations below use these lengths.
use super::elastica;
use crate::external::Environment;
use crate::material::Material;
use crate::rod::{End, Rod, theta_dof};
use crate::stepper::{NewtonOptions, StepError, Stepper};
use nalgebra::Vector3;
use std::f64::consts::PI;

/// A quasi-static step: long enough that inertia is negligible.
const STATIC_DT: f64 = 1e4;

fn straight_rod(k: usize, length: f64, radius: f64, material: Material) -> Rod {
    let nodes: Vec<Vector3<f64>> = (0..k)
        .map(|i| Vector3::new(length * i as f64 / (k - 1) as f64, 0.0, 0.0))
        .collect();
    Rod::new(&nodes, radius, material).expect("valid straight rod")
}

/// Twist of a straight rod clamped at both ends, one end turned by `phi`:
/// returns (twist energy, expected GJ phi^2 / (2 L_f), end torque, expected GJ phi / L_f).
pub fn twisted_rod(phi: f64) -> Result<(f64, f64, f64, f64), StepError> {
    let mut rod = straight_rod(51, 0.5, 2e-3, Material::default());
    rod.clamp(End::Start);
    rod.clamp(End::Finish);
    let last = rod.edges() - 1;
    rod.set_theta(last, phi);
    rod.rebase_frames();
    let env = Environment::default();
    let mut stepper = Stepper::new(&rod, NewtonOptions::default());
    let report = stepper.step(&mut rod, &env, None, STATIC_DT)?;
    let free = rod.length() - rod.rest_len[0];
    let gj = rod.section.gj;
    let (_, torque) = stepper.clamp_reaction(&rod, End::Finish);
    debug_assert_eq!(rod.clamp_dofs(End::Finish)[6], theta_dof(last));
    Ok((
        report.energies.twisting,
        gj * phi * phi / (2.0 * free),
        torque,
        gj * phi / free,
    ))
}

/// Clamped-clamped column under slow end shortening: returns (measured critical
/// load, Euler load 4 pi^2 EI / L_f^2, peak lateral deflection / L).
pub fn euler_buckling(k: usize) -> Result<(f64, f64, f64), StepError> {
    let length = 1.0;
    let mut rod = straight_rod(k, length, 5e-3, Material::default());
    // Imperfection: a small lateral bump in the first buckling mode.
    for i in 0..rod.nodes() {
        let x = rod.node(i);
        let w = 1e-4 * length * (1.0 - (2.0 * PI * x.x / length).cos());
        rod.set_node(i, x + Vector3::new(0.0, w, 0.0));
    }
    rod.rebase_frames();
    rod.clamp(End::Start);
    rod.clamp(End::Finish);
    let free = length - rod.rest_len[0];
    let euler = 4.0 * PI * PI * rod.section.ei / (free * free);
    let critical_shortening = euler * free / rod.section.ea;
    let steps = 60;
    let total = 3.0 * critical_shortening;
    let speed = total / (steps as f64 * STATIC_DT);
    rod.move_clamp(End::Finish, Vector3::new(-speed, 0.0, 0.0));
    let env = Environment::default();
    let mut stepper = Stepper::new(&rod, NewtonOptions::default());
    let mut load = 0.0;
    for _ in 0..steps {
        stepper.step(&mut rod, &env, None, STATIC_DT)?;
        load = -stepper.clamp_reaction(&rod, End::Finish).0.x;
    }
    let deflection = (0..rod.nodes()).map(|i| rod.node(i).y.abs()).fold(0.0, f64::max);
    Ok((load, euler, deflection / length))
}

/// Horizontal cantilever (clamped at the start) under gravity with
/// nondimensional load alpha = q L_f^3 / EI, loaded in `increments` quasi-static
/// steps: returns (tip deflection, free length L_f).
pub fn cantilever(alpha: f64, k: usize, increments: usize) -> Result<(f64, f64), StepError> {
    let length = 0.5;
    let mut rod = straight_rod(k, length, 2e-3, Material::default());
    rod.clamp(End::Start);
    let free = length - rod.rest_len[0] / 2.0;
    let q_needed = alpha * rod.section.ei / free.powi(3);
    let g = q_needed / rod.section.linear_density;
    let mut stepper = Stepper::new(&rod, NewtonOptions::default());
    for n in 1..=increments {
        let env = Environment {
            gravity: Vector3::new(0.0, 0.0, -g * n as f64 / increments as f64),
            damping: 0.0,
        };
        stepper.step(&mut rod, &env, None, STATIC_DT)?;
    }
    let tip = rod.node(rod.nodes() - 1);
    Ok((-tip.z, free))
}

/// Tip deflection of the elastica cantilever with load alpha, in units of its length.
pub fn elastica_tip(alpha: f64) -> f64 {
    elastica::cantilever_tip_deflection(alpha)
}
