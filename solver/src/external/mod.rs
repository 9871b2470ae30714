//! External forces of eq. (7c) that do not come from contact: gravity F^G and an
//! optional viscous damping (applied by the stepper).
pub mod gravity;

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
