//! External forces of eq. (7c) that do not come from contact: gravity F^G and an
//! optional viscous damping (applied by the stepper), and the load that spares
//! sliding along the centre line from it (`sliding`). [`assemble`] adds them
//! up for the stepper and the contact solve alike.
pub mod gravity;
pub mod sliding;

use crate::rod::Rod;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// The rod's surroundings: gravity and viscous damping (both off by default, as
/// in the paper's knot simulations, Sec. 4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Environment {
    /// Gravitational acceleration (m/s^2), e.g. (0, 0, -9.81).
    pub gravity: Vector3<f64>,
    /// Mass-proportional viscous damping rate gamma (1/s): F = -gamma M v.
    pub damping: f64,
}

impl Environment {
    /// The factor 1 + gamma dt by which backward Euler's damping (F = -gamma
    /// M v) scales the inertia of a step of length `dt`: the one damping rule
    /// of the stepper and the contact solve's free velocities.
    pub fn damping_factor(&self, dt: f64) -> f64 {
        1.0 + self.damping * dt
    }

    /// The free-velocity rule: a DOF of mass `m` and velocity `v` under the
    /// net force `f` (external minus elastic, at the start of the step) moves
    /// after a step `dt` at `(v + dt f / m) / (1 + gamma dt)` without contact;
    /// returns that velocity and the effective inverse mass
    /// `1 / ((1 + gamma dt) m)` a contact force meets.
    pub fn free_velocity(&self, v: f64, f: f64, m: f64, dt: f64) -> (f64, f64) {
        let damp = 1.0 / self.damping_factor(dt);
        (damp * (v + dt * f / m), damp / m)
    }
}

/// F^ext of eq. (7c) without contact, one entry per DOF, into `out`: gravity
/// plus `load` (the loads a world puts on a rod: the sliding exemption, a
/// validation case's tension, the contact forces of the step).
pub fn assemble(rod: &Rod, env: &Environment, load: Option<&[f64]>, out: &mut [f64]) {
    out.fill(0.0);
    gravity::add(rod, &env.gravity, out);
    if let Some(f) = load {
        for (e, x) in out.iter_mut().zip(f) {
            *e += x;
        }
    }
}
