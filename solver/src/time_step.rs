//! Adaptive time step for the contact-rich knot runs.
//!
//! The contact forces of Sec. 3.2 are computed with the mass-only Delassus
//! operator (eq. 10), so within one step a penetration is pushed out with an
//! effective stiffness of about `m / dt^2` per contact, while the rod's own
//! stiffness is much larger in a tight knot. Penetration is therefore what
//! limits the step: a step whose end state penetrates more than
//! `reject_penetration` is redone from a checkpoint with half the step, one
//! that penetrates more than `shrink_penetration` halves the next step, and
//! after `grow_after` calm steps (little penetration, Newton converging in
//! `calm_iterations` or fewer) the step doubles again, up to `dt_max`. A step
//! that fails (Newton diverging after its own substeps) is also redone with
//! half the step. Penetrations are fractions of the largest rod radius.
use crate::pipeline::{World, WorldError, WorldStepReport};
use serde::{Deserialize, Serialize};

/// Limits and thresholds of the controller.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveOptions {
    /// Largest (and first) step (s).
    pub dt_max: f64,
    /// Smallest step (s).
    pub dt_min: f64,
    /// End-of-step penetration (fraction of the radius) that halves the next step.
    pub shrink_penetration: f64,
    /// End-of-step penetration that rejects the step: it is redone with half the step.
    pub reject_penetration: f64,
    /// A calm step penetrates at most this much...
    pub calm_penetration: f64,
    /// ...and needs at most this many Newton iterations per rod.
    pub calm_iterations: u32,
    /// Consecutive calm steps before the step doubles.
    pub grow_after: u32,
}

impl AdaptiveOptions {
    /// Steps between `dt_max / 64` and `dt_max`; halve above 5 % of the radius,
    /// redo above 20 %, double after 50 steps below 1 % converging in two iterations.
    pub fn up_to(dt_max: f64) -> Self {
        Self {
            dt_max,
            dt_min: dt_max / 64.0,
            shrink_penetration: 0.05,
            reject_penetration: 0.2,
            calm_penetration: 0.01,
            calm_iterations: 2,
            grow_after: 50,
        }
    }

    /// A constant step `dt` (the paper's scheme).
    pub fn fixed(dt: f64) -> Self {
        Self {
            dt_min: dt,
            ..Self::up_to(dt)
        }
    }
}

/// One accepted step: what the world reported and the step it took.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Advance {
    pub report: WorldStepReport,
    pub dt: f64,
}

/// The controller: the current step and its counts.
#[derive(Clone, Debug)]
pub struct TimeStep {
    pub options: AdaptiveOptions,
    dt: f64,
    calm: u32,
    /// Steps redone with a smaller step.
    pub rejected: u64,
    /// The smallest step taken so far (s).
    pub smallest: f64,
    /// Simulated time of the accepted steps so far (s).
    pub elapsed: f64,
}

impl TimeStep {
    /// A controller starting at `options.dt_max`.
    pub fn new(options: AdaptiveOptions) -> Self {
        Self {
            options,
            dt: options.dt_max,
            calm: 0,
            rejected: 0,
            smallest: options.dt_max,
            elapsed: 0.0,
        }
    }

    /// Rescales the limits so that the largest step is `dt_max` (a fixed step
    /// stays fixed); the current step is kept within them.
    pub fn rescale(&mut self, dt_max: f64) {
        self.options.dt_min *= dt_max / self.options.dt_max;
        self.options.dt_max = dt_max;
        self.dt = self.dt.clamp(self.options.dt_min, dt_max);
    }

    /// The step the next [`TimeStep::advance`] tries first (s).
    pub fn next_dt(&self) -> f64 {
        self.dt
    }

    /// Advances `world` by one accepted step.
    pub fn advance(&mut self, world: &mut World) -> Result<Advance, WorldError> {
        let o = self.options;
        let radius = world.largest_radius();
        loop {
            let dt = self.dt;
            let can_shrink = dt > o.dt_min * (1.0 + 1e-12);
            if can_shrink {
                world.checkpoint();
            }
            let (report, penetration) = match world.step(dt) {
                Ok(r) => (r, r.max_penetration / radius),
                Err(e) if !can_shrink => return Err(e),
                // Not dropped: the step is redone with half the step, and the
                // error is returned once the step is at its smallest.
                Err(_) => (WorldStepReport::default(), f64::INFINITY),
            };
            if can_shrink && penetration > o.reject_penetration {
                world.rollback();
                self.halve();
                self.rejected += 1;
                continue;
            }
            self.smallest = self.smallest.min(dt);
            self.elapsed += dt;
            let rods = world.rods.len() as u32;
            if penetration > o.shrink_penetration {
                self.halve();
            } else if penetration <= o.calm_penetration
                && report.newton_iterations <= o.calm_iterations * rods
            {
                self.calm += 1;
                if self.calm >= o.grow_after {
                    self.dt = (2.0 * dt).min(o.dt_max);
                    self.calm = 0;
                }
            } else {
                self.calm = 0;
            }
            return Ok(Advance { report, dt });
        }
    }

    fn halve(&mut self) {
        self.dt = (0.5 * self.dt).max(self.options.dt_min);
        self.calm = 0;
    }
}
