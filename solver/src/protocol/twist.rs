//! The linking number of the centre line closed along the pull axis, Lk =
//! Tw + Wr (Călugăreanu, White), the clamps' relative turns and the torque
//! about the pull axis. Tw is the rod's total twist; Wr is the start shape's
//! writhe ([`knot::writhe`], O(K^2) once) carried along every accepted step
//! by Fuller's theorem ([`knot::writhe_change`], O(K)). With both ends clamped
//! Lk changes only where a clamp turns, by the turns given: the series checks
//! it.
use crate::knot;
use crate::rod::{End, Rod};
use crate::stepper::Stepper;
use nalgebra::Vector3;
use std::f64::consts::TAU;

/// The writhe carried from step to step and what it was carried from.
#[derive(Clone, Debug)]
pub(super) struct Tracker {
    writhe: f64,
    tangents: Vec<Vector3<f64>>,
    /// The clamped edges' angle difference when tracking began (rad).
    clamped: f64,
}

impl Tracker {
    /// Tracking from `rod`'s shape, of writhe `writhe`.
    pub(super) fn new(rod: &Rod, writhe: f64) -> Self {
        Self {
            writhe,
            tangents: rod.geo.tangent.clone(),
            clamped: clamped_angle(rod),
        }
    }

    /// Carries the writhe to `rod`'s accepted step.
    pub(super) fn step(&mut self, rod: &Rod) {
        self.writhe += knot::writhe_change(&self.tangents, &rod.geo.tangent);
        self.tangents.copy_from_slice(&rod.geo.tangent);
    }

    /// Lk = Tw + Wr (turns).
    pub(super) fn linking_number(&self, rod: &Rod) -> f64 {
        total_twist(rod) + self.writhe
    }

    /// How far the clamps have turned against each other since tracking
    /// began (turns).
    pub(super) fn end_turns(&self, rod: &Rod) -> f64 {
        (clamped_angle(rod) - self.clamped) / TAU
    }
}

/// The finish clamp's edge angle minus the start clamp's (rad).
fn clamped_angle(rod: &Rod) -> f64 {
    rod.theta(rod.edges() - 1) - rod.theta(0)
}

/// The rod's total twist (turns): the sum of eq. (5)'s twists over the
/// interior nodes.
pub(super) fn total_twist(rod: &Rod) -> f64 {
    (1..rod.nodes() - 1).map(|i| rod.twist(i)).sum::<f64>() / TAU
}

/// The torque (N m) the clamps apply about the pull axis after the last step,
/// positive where it twists the rod right-handed from the start clamp to the
/// finish clamp: the mean of the two clamps' reactions on their edges' angles.
pub(super) fn clamp_torque(rod: &Rod, stepper: &Stepper) -> f64 {
    0.5 * (stepper.clamp_reaction(rod, End::Finish).1 - stepper.clamp_reaction(rod, End::Start).1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::external::Environment;
    use crate::material::Material;
    use crate::stepper::NewtonOptions;

    /// A straight clamped rod whose finish clamp turns by N turns carries the
    /// torque M = 2 pi N GJ / l, l the length between the clamped edges'
    /// middles (where the discrete twist lives), its Lk grows by N and its
    /// writhe stays zero.
    #[test]
    fn a_twisted_straight_rod_carries_the_closed_form_torque() {
        let k = 21;
        let points: Vec<Vector3<f64>> = (0..k).map(|i| Vector3::new(i as f64 / 20.0, 0.0, 0.0)).collect();
        let mut rod = Rod::new(&points, 1e-2, Material::default()).unwrap();
        rod.clamp(End::Start);
        rod.clamp(End::Finish);
        let mut stepper = Stepper::new(&rod, NewtonOptions::default());
        let mut tracker = Tracker::new(&rod, 0.0);
        let lk0 = tracker.linking_number(&rod);
        let (turns, dt, steps) = (1.0, 1e-3, 1000);
        let dof = rod.clamp_dofs(End::Finish)[6];
        rod.prescribed_velocity[dof] = TAU * turns / (dt * steps as f64);
        let env = Environment {
            damping: 50.0,
            ..Environment::default()
        };
        for step in 0..steps + 2000 {
            if step == steps {
                rod.prescribed_velocity[dof] = 0.0;
            }
            stepper.step(&mut rod, &env, None, dt).unwrap();
            tracker.step(&rod);
        }
        let length = 1.0 - 1.0 / 20.0;
        let expected = TAU * turns * rod.section.gj / length;
        let torque = clamp_torque(&rod, &stepper);
        assert!(
            (torque / expected - 1.0).abs() < 1e-6,
            "{torque} against {expected}"
        );
        assert!((tracker.end_turns(&rod) - turns).abs() < 1e-9);
        assert!((tracker.linking_number(&rod) - lk0 - turns).abs() < 1e-9);
        assert!(knot::writhe(&rod.positions()).abs() < 1e-9);
    }
}
