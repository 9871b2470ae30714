//! The clove hitch: one rod tied round a rigid, fixed cylinder (a pole) of
//! radius `R` (Maddocks and Keller 1987; Sabater et al. 2026).
//!
//! The pole's axis is `z` through the origin. A point of the rod's surface
//! path at angle `theta` about the axis (0 at `+y`, growing towards `+x`)
//! and height `z` lies at `rho (sin theta, cos theta, z)`, with
//! `rho = R + h + GAP h` (the rod loose on the pole) plus the lift where
//! it rides over another strand. In radii h, with the front window
//! `|theta mod 2 pi| < BETA`:
//!
//! | part         | theta                        | z                 |
//! |--------------|------------------------------|-------------------|
//! | standing end | a line `y = rho`, from `x = -inf` | `ENDS`       |
//! | first turn   | `0 .. 2 pi - BETA`           | `ENDS` to `-RISE` |
//! | diagonal     | `2 pi - BETA .. 2 pi + BETA` | `-RISE` to `RISE` |
//! | second turn  | `2 pi + BETA .. 4 pi - BETA` | `RISE` to `-ENDS` |
//! | tail         | `4 pi - BETA .. 4 pi`, then a line `y = rho + LIFT` to `x = TAIL` | `-ENDS` |
//!
//! each height changing along a smoothstep (the first turn's after `BETA`).
//! Both turns wind the same way, and in the front window each turn's end
//! crosses over its start: the diagonal over the standing end, lifted by
//! `LIFT`, and the tail over the diagonal, lifted as it starts its last
//! part. These are two identical loops slipped over the pole, the clove
//! hitch: off the pole it falls apart (the rod alone is unknotted, which
//! the builder checks), while loops of opposite crossings tie an overhand
//! knot round the pole (the trefoil off it). The turns stay `RISE - ENDS`
//! apart, and the ends leave in opposite directions along `x`.
//!
//! The rod starts at its standing end, the first clamp, and ends at its
//! tail, the second; both are pulled apart along `x`, away from the pole,
//! until the hitch has set, and then the tail is let go with a weight on
//! it and the standing end pulled on (`protocol::runner`).
use super::alexander::Alexander;
use super::polyline::{Dense, check_clearance, equal_chords};
use super::{Clamp, Family, KnotError, StartShape, check_knot};
use crate::contact::Cylinder;
use crate::rod::End;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// The rod's loose gap from the pole, in radii h.
const GAP: f64 = 0.5;
/// Height of the two ends (standing `+`, tail `-`), in radii h.
const ENDS: f64 = 2.5;
/// Height of the diagonal's ends, in radii h: the turns lie `RISE - ENDS`
/// apart.
const RISE: f64 = 5.2;
/// Half the front window's angle (rad).
const BETA: f64 = 1.2;
/// How far the diagonal rides above the pole's other strands, in radii h.
const LIFT: f64 = 2.6;
/// Fraction of the diagonal over which it rises to its lift, and falls.
const RAMP: f64 = 0.15;
/// Where along the diagonal (fraction) it starts to rise: past its
/// crossing with the tail, below its crossing with the standing end.
const DIAGONAL_RISE: f64 = 0.4;
/// Fraction of the window's half angle over which the tail rises as it
/// starts its last part, before the diagonal crosses it.
const TAIL_RAMP: f64 = 0.4;
/// Length of the tail past the pole, in radii h.
pub const TAIL: f64 = 12.0;
/// The pole's length, in radii h (far longer than the hitch is tall).
const POLE: f64 = 80.0;
/// Longest edge, in radii h: the lift needs a few nodes.
const MAX_EDGE: f64 = 2.5;
/// The pole's default radius, in radii h.
pub const DEFAULT_RADIUS: f64 = 10.0;

/// A clove hitch to tie: a rod of `length` with `nodes`, on a pole of
/// `cylinder_radius`. Lengths in metres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CloveHitchSpec {
    /// Rod length `L`.
    pub length: f64,
    /// Node count `K`.
    pub nodes: usize,
    /// Cross-section radius `h`.
    pub radius: f64,
    /// The pole's radius `R`.
    pub cylinder_radius: f64,
}

impl CloveHitchSpec {
    /// The pole.
    pub fn cylinder(&self) -> Cylinder {
        Cylinder {
            center: Vector3::zeros(),
            axis: Vector3::z(),
            radius: self.cylinder_radius,
            length: POLE * self.radius,
        }
    }
}

impl Family for CloveHitchSpec {
    /// The unknot's: the rod alone is not knotted.
    fn alexander(&self) -> Alexander {
        Alexander::one()
    }

    fn tie(&self) -> Result<StartShape, KnotError> {
        let (h, length) = (self.radius, self.length);
        for (name, value) in [
            ("length", length),
            ("radius", h),
            ("cylinder_radius", self.cylinder_radius),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(KnotError::InvalidParameter { name, value });
            }
        }
        let edge = length / (self.nodes.max(2) - 1) as f64;
        if edge > MAX_EDGE * h {
            return Err(KnotError::TooFewNodes {
                nodes: self.nodes,
                min: (length / (MAX_EDGE * h)).ceil() as usize + 1,
            });
        }
        let rho = self.cylinder_radius / h + 1.0 + GAP;
        let spacing = edge.min(h) / (4.0 * h);
        let wrap = wrapped(rho, spacing);
        let wrap_length = Dense::new(wrap.clone()).length() * h;
        let tail = TAIL * h;
        let needed = wrap_length + tail + 4.0 * edge + TAIL * h;
        if length < needed {
            return Err(KnotError::RodTooShort { needed, length });
        }
        // The tail's line runs past the tail to outlast the resampling.
        let standing = (length - wrap_length - tail) / h;
        let past = (tail + 4.0 * edge + 0.02 * length) / h;
        let line = |from: Vector3<f64>, along: f64| {
            let steps = (along.abs() / spacing).ceil().max(1.0) as usize;
            (1..=steps).map(move |k| from + Vector3::new(along * k as f64 / steps as f64, 0.0, 0.0))
        };
        let first = wrap[0];
        let mut planar: Vec<Vector3<f64>> = line(first, -standing).collect();
        planar.reverse();
        planar.extend(wrap.iter().copied());
        planar.extend(line(wrap[wrap.len() - 1], past));
        let dense = Dense::new(planar.into_iter().map(|p| p * h).collect());
        let points = equal_chords(&dense.points, &dense.arc, edge, self.nodes)
            .expect("the tail's line outlasts the chords")
            .0;
        check_clearance(&points, h, edge)?;
        let cylinder = self.cylinder();
        let touching = points
            .windows(2)
            .map(|w| cylinder.closest(&w[0], &w[1]).distance - cylinder.radius - h)
            .fold(f64::INFINITY, f64::min);
        if touching <= 0.0 {
            return Err(KnotError::Clearance {
                distance: touching + 2.0 * h,
                required: 2.0 * h,
            });
        }
        check_knot(&points, &self.alexander())?;
        Ok(StartShape {
            rods: vec![points],
            loop_middle: 0,
            alexander: None,
            clamps: [
                Clamp {
                    rod: 0,
                    end: End::Start,
                },
                Clamp {
                    rod: 0,
                    end: End::Finish,
                },
            ],
            cylinder: Some(cylinder),
            own_knots: false,
        })
    }

    /// None: the tail is let go once the hitch has set.
    fn twist(&self, _writhe: f64) -> f64 {
        0.0
    }
}

/// The turns a rod's centre line `points` makes about `cylinder`'s axis:
/// the angle its projection onto the plane normal to the axis sweeps about
/// the axis, over 2 pi (positive right-handed about the axis).
pub fn wrap_turns(points: &[Vector3<f64>], cylinder: &Cylinder) -> f64 {
    let a = cylinder.axis;
    let flat = |p: &Vector3<f64>| {
        let r = p - cylinder.center;
        r - a * a.dot(&r)
    };
    let swept: f64 = points
        .windows(2)
        .map(|w| {
            let (u, v) = (flat(&w[0]), flat(&w[1]));
            u.cross(&v).dot(&a).atan2(u.dot(&v))
        })
        .sum();
    swept / TAU
}

/// The smoothstep `3u^2 - 2u^3` of `u` clamped to `[0, 1]`.
fn smoothstep(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

/// The rod's path on the pole (radii h), from the standing end's touch
/// (`theta = 0`) to the tail's (`theta = 4 pi`), points at most `spacing`
/// apart.
fn wrapped(rho: f64, spacing: f64) -> Vec<Vector3<f64>> {
    // Heights at the parts' ends (module documentation).
    let keys = [
        (0.0, ENDS),
        (BETA, ENDS),
        (TAU - BETA, -RISE),
        (TAU + BETA, RISE),
        (2.0 * TAU - BETA, -ENDS),
        (2.0 * TAU, -ENDS),
    ];
    let height = |theta: f64| {
        let k = keys
            .windows(2)
            .position(|w| theta <= w[1].0)
            .unwrap_or(keys.len() - 2);
        let ((t0, z0), (t1, z1)) = (keys[k], keys[k + 1]);
        z0 + (z1 - z0) * smoothstep((theta - t0) / (t1 - t0))
    };
    let lift = |theta: f64| {
        // The diagonal rises over the standing end's crossing...
        let u = (theta - (TAU - BETA)) / (2.0 * BETA);
        let over = if (0.0..=1.0).contains(&u) {
            smoothstep((u - DIAGONAL_RISE) / RAMP).min(smoothstep((1.0 - u) / RAMP))
        } else {
            0.0
        };
        // ...and the tail over the diagonal, staying up as it leaves.
        let tail = smoothstep((theta - (2.0 * TAU - BETA)) / (TAIL_RAMP * BETA));
        LIFT * (over + tail)
    };
    let steps = (2.0 * TAU * (rho + LIFT) / spacing * 1.5).ceil() as usize;
    (0..=steps)
        .map(|k| {
            let theta = 2.0 * TAU * k as f64 / steps as f64;
            let r = rho + lift(theta);
            Vector3::new(r * theta.sin(), r * theta.cos(), height(theta))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(cylinder_radius: f64) -> CloveHitchSpec {
        CloveHitchSpec {
            length: 1.0,
            nodes: 301,
            radius: 1.6e-3,
            cylinder_radius,
        }
    }

    /// The hitch is tied loose: off the pole, its strands 2h apart, its
    /// ends on the line `y = rho` either side of the pole, the rod's length
    /// `L`, two full turns about the pole between the ends' touches.
    #[test]
    fn the_hitch_is_tied_loose_round_the_pole() {
        let s = spec(16e-3);
        let shape = s.tie().unwrap();
        let points = shape.points();
        assert_eq!(points.len(), 301);
        let arc: f64 = points.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
        assert!((arc - 1.0).abs() < 1e-9, "{arc}");
        let [a, b] = shape.clamp_points();
        let rho = 16e-3 + 1.5 * 1.6e-3;
        assert!(a.x < -0.5 && b.x > 0.0, "{a:?} {b:?}");
        assert!((a.y - rho).abs() < 1e-9 && (b.y - rho - LIFT * 1.6e-3).abs() < 1e-9);
        let turns = wrap_turns(points, &shape.cylinder.unwrap()).abs();
        // Two turns, and the ends' lines sweep a little more as seen from
        // the axis (towards a half turn each for infinite lines).
        assert!((2.0..2.5).contains(&turns), "{turns}");
    }

    /// Too small a node count, a pole radius that is not positive and a
    /// rod too short for the turns are refused.
    #[test]
    fn impossible_hitches_are_refused() {
        let coarse = CloveHitchSpec {
            nodes: 101,
            ..spec(16e-3)
        };
        assert!(matches!(coarse.tie(), Err(KnotError::TooFewNodes { .. })));
        assert!(matches!(
            spec(0.0).tie(),
            Err(KnotError::InvalidParameter {
                name: "cylinder_radius",
                ..
            })
        ));
        let short = CloveHitchSpec {
            length: 0.2,
            nodes: 101,
            ..spec(16e-3)
        };
        assert!(matches!(short.tie(), Err(KnotError::RodTooShort { .. })));
    }

    /// A circle about the axis makes one turn, however far off centre the
    /// axis's point is along it; a segment beside the pole nearly none.
    #[test]
    fn wrap_turns_counts_turns_about_the_axis() {
        let pole = spec(0.01).cylinder();
        let circle: Vec<_> = (0..=64)
            .map(|k| {
                let t = TAU * f64::from(k) / 64.0;
                Vector3::new(0.02 * t.cos(), 0.02 * t.sin(), 0.3 * t)
            })
            .collect();
        assert!((wrap_turns(&circle, &pole) - 1.0).abs() < 1e-12);
        let line = [Vector3::new(0.05, -0.01, 0.0), Vector3::new(0.05, 0.01, 0.0)];
        assert!(wrap_turns(&line, &pole).abs() < 0.1);
    }
}
