//! Stages that keep the clamps' distance: a hold, and a rotation of the
//! clamps about the pull axis. They sample every `sample_interval` of the
//! time a pull takes to move that far in l_k bar.
use super::adaptive::Phase;
use super::runner::{Case, Ending, Observer};
use crate::case::{Ends, Rotate};
use crate::rod::{End, Rod};
use crate::snapshot::Snapshot;
use std::f64::consts::TAU;

/// The time a rotation takes per turn (s, in the case's time unit): slow
/// against the loop's bending dynamics (the paper's rod relaxes in about
/// 0.5 s), so that the knot follows quasi-statically; the report's
/// kinetic-to-elastic ratio checks it.
pub(super) const TURN_TIME: f64 = 4.0;

impl Case<'_> {
    /// Holds the clamps still for `seconds`.
    pub(super) fn hold(&mut self, seconds: f64, observer: &mut Observer) -> Result<(), Ending> {
        self.still(Phase::Hold, seconds, observer, &|_| true, |_, _| ())
    }

    /// Turns the finish clamp, or both clamps in opposite senses, by
    /// `rotate.turns` in all about the pull axis, at one turn per
    /// [`TURN_TIME`] case time units; the clamps' edges end at their angles
    /// exactly.
    pub(super) fn rotate(&mut self, rotate: Rotate, observer: &mut Observer) -> Result<(), Ending> {
        let rod = &self.world.rods[0];
        let [start_dof, finish_dof] = [End::Start, End::Finish].map(|e| rod.clamp_dofs(e)[6]);
        let shares = match rotate.ends {
            Ends::One => [0.0, 1.0],
            Ends::Both => [-0.5, 0.5],
        };
        let dofs = [start_dof, finish_dof];
        let targets = [0, 1].map(|i| rod.q[dofs[i]] + shares[i] * TAU * rotate.turns);
        let duration = rotate.turns.abs() * TURN_TIME * self.scales.time_unit;
        let rate = TAU * rotate.turns.abs() / duration;
        let reached = |rod: &Rod| {
            (0..2).all(|i| (targets[i] - rod.q[dofs[i]]).abs() <= 1e-12 * TAU * rotate.turns.abs())
        };
        let result = self.still(Phase::Rotate, duration, observer, &reached, |rod, dt| {
            for (dof, target) in dofs.into_iter().zip(targets) {
                let left = target - rod.q[dof];
                rod.prescribed_velocity[dof] = rate.min(left.abs() / dt).copysign(left);
            }
        });
        let rod = &mut self.world.rods[0];
        rod.prescribed_velocity[start_dof] = 0.0;
        rod.prescribed_velocity[finish_dof] = 0.0;
        result
    }

    /// Steps the current stage in `phase` for `duration` and until
    /// `reached`, `drive` setting the clamps' motion before each step (given
    /// the rod and the step to try), sampling by time.
    fn still(
        &mut self,
        phase: Phase,
        duration: f64,
        observer: &mut Observer,
        reached: &dyn Fn(&Rod) -> bool,
        mut drive: impl FnMut(&mut Rod, f64),
    ) -> Result<(), Ending> {
        self.enter_phase(phase);
        for clamp in self.clamps {
            self.move_held_clamp(clamp, nalgebra::Vector3::zeros());
        }
        let interval = self.params.sample_interval * self.params.h / (2.0 * self.params.clamp_speed());
        let (mut elapsed, mut next_sample) = (0.0, 0.0);
        loop {
            let dt = self.clock.next_dt();
            drive(&mut self.world.rods[0], dt);
            let (step, dt) = self.step(phase)?;
            elapsed += dt;
            let done = elapsed >= duration * (1.0 - 1e-12) && reached(&self.world.rods[0]);
            if elapsed < next_sample && !done {
                continue;
            }
            next_sample = elapsed + interval;
            let l_k_bar = self.l_k_bar();
            let points = self.sample(phase, &step, dt, l_k_bar);
            let stage = self.stage + 1;
            self.topology(&points, || format!("at {elapsed:.3} s into stage {stage}"))?;
            self.observe(observer, &points, l_k_bar, elapsed / duration)?;
            if done {
                break;
            }
        }
        let at = self.l_k_bar();
        let label = crate::snapshot::SnapshotLabel::Stage(self.program[self.stage].kind());
        self.report
            .snapshots
            .push(Snapshot::capture(&self.world, label, at, self.clock.elapsed));
        Ok(())
    }
}
