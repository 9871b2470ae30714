//! External forces of eq. (7c) that do not come from contact: gravity F^G and an
//! optional viscous damping (applied by the stepper), and the load that spares
//! sliding along the centre line from it (`sliding`).
pub mod gravity;
pub mod sliding;

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
}
