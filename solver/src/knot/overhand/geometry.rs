//! The continuous centreline of the knot in ring coordinates (Sec. 2, Fig. 2).
//!
//! A convex planar ring (plane `z = 0`) is made of the braid arc, a circular
//! arc of centreline length `b` and turning angle `2 theta` centred on the
//! origin with tangent `+x`, and the loop, which turns the remaining
//! `2 pi - 2 theta` with the heading profile `theta + Phi g(t)`,
//! `g(t) = t - alpha sin(2 pi t) / (2 pi)` (`alpha < 0` flattens its top).
//! Along the braid the two strands are `C(s) +- a (cos psi n + sin psi z)`
//! (`n` the outward normal) with `psi` advancing by `(2n+1) pi`, so strand A
//! enters on the `-z` side and leaves on the `+z` side, where the loop (the
//! ring offset to `z = +a`) takes it to the entry of strand B; strand B leaves
//! on the `-z` side. Each tail (in `z = -a`) bends away from the ring by
//! `theta` along a circular arc and ends with a straight clamp section along
//! `x`. Closing the tails underneath everything gives the closure of the
//! 2-braid `sigma^(2n+1)`, the `(2, 2n+1)` torus knot.
use crate::knot::polyline;
use nalgebra::Vector3;
use std::f64::consts::PI;

/// Fraction of the braid, at each end, over which the twist rate ramps up.
const RAMP: f64 = 0.15;

/// `sin(x) / x`.
pub fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        1.0 - x * x / 6.0
    } else {
        x.sin() / x
    }
}

/// Normalised twist `w(u)` and `w'(u)` on `u in [0, 1]`: `w' = S(u / RAMP) /
/// (1 - RAMP)` on the ramps (`S` the smoothstep) and `1 / (1 - RAMP)` between.
fn twist(u: f64) -> (f64, f64) {
    let m = 1.0 / (1.0 - RAMP);
    let ramp = |t: f64| {
        (
            m * RAMP * (t * t * t - 0.5 * t * t * t * t),
            m * t * t * (3.0 - 2.0 * t),
        )
    };
    if u < RAMP {
        ramp(u / RAMP)
    } else if u > 1.0 - RAMP {
        let (w, dw) = ramp((1.0 - u) / RAMP);
        (1.0 - w, dw)
    } else {
        (m * (0.5 * RAMP + u - RAMP), m)
    }
}

/// The two strands of the braid: `passes = n`, helix radius `a`.
#[derive(Clone, Copy, Debug)]
pub struct Braid {
    pub passes: u32,
    pub radius: f64,
}

impl Braid {
    /// Number of half twists (crossings of the braid), `2n + 1`.
    pub fn half_twists(&self) -> f64 {
        f64::from(2 * self.passes + 1)
    }

    /// Phase `psi(u)` of strand A and `d psi / du`.
    pub fn phase(&self, u: f64) -> (f64, f64) {
        let (w, dw) = twist(u);
        let k = self.half_twists() * PI;
        (-0.5 * PI + k * w, k * dw)
    }

    /// Shortest centreline for which the helix pitch per radian is at least
    /// `min_pitch` times its radius.
    pub fn min_centreline(&self, min_pitch: f64) -> f64 {
        min_pitch * self.radius * self.half_twists() * PI / (1.0 - RAMP)
    }

    /// Point of strand A (`sign = 1`) or B (`sign = -1`) at `u in [0, 1]` on a
    /// braid arc of length `b` and curvature `kappa`.
    fn point(&self, u: f64, b: f64, kappa: f64, sign: f64) -> Vector3<f64> {
        let s = b * (u - 0.5);
        let phi = kappa * s;
        let chord = s * sinc(0.5 * phi);
        let centre = Vector3::new(chord * (0.5 * phi).cos(), chord * (0.5 * phi).sin(), 0.0);
        let normal = Vector3::new(phi.sin(), -phi.cos(), 0.0);
        let (psi, _) = self.phase(u);
        centre + sign * self.radius * (psi.cos() * normal + psi.sin() * Vector3::z())
    }
}

/// Loop heading profile `theta + (2 pi - 2 theta) g(t)`.
fn loop_heading(theta: f64, alpha: f64, t: f64) -> f64 {
    theta + (2.0 * PI - 2.0 * theta) * (t - alpha * (2.0 * PI * t).sin() / (2.0 * PI))
}

/// Mean of `cos(heading)` over `steps` midpoint steps of the loop: the loop's
/// x-displacement divided by its length (increasing in `alpha`).
pub fn loop_drift(theta: f64, alpha: f64, steps: usize) -> f64 {
    (0..steps)
        .map(|i| loop_heading(theta, alpha, (i as f64 + 0.5) / steps as f64).cos())
        .sum::<f64>()
        / steps as f64
}

/// Solved geometry of one knot, in ring coordinates.
#[derive(Clone, Copy, Debug)]
pub struct Plan {
    pub braid: Braid,
    /// Half turning angle of the braid arc.
    pub theta: f64,
    /// Braid centreline length.
    pub centreline: f64,
    /// Loop length and shape parameter; the loop is integrated in `loop_steps`
    /// equal steps (its closure is solved for that discretisation).
    pub loop_length: f64,
    pub alpha: f64,
    pub loop_steps: usize,
    /// Length of each tail and of its straight clamp section.
    pub tail_length: f64,
    pub clamp_section: f64,
}

/// Dense polyline of the knot: points, cumulative arc length, and the indices
/// where strand A, the loop, strand B and tail B start and where tail B
/// reaches its clamp point (it continues straight beyond it so that
/// resampling never runs out of curve).
pub struct Dense {
    pub points: Vec<Vector3<f64>>,
    pub arc: Vec<f64>,
    pub marks: [usize; 5],
}

impl Plan {
    /// Half chord of the braid arc: the braid ends are at `x = +-half_width()`.
    pub fn half_width(&self) -> f64 {
        0.5 * self.centreline * sinc(self.theta)
    }

    /// Curved part of each tail.
    fn tail_arc(&self) -> f64 {
        self.tail_length - self.clamp_section
    }

    /// Bend radius of the tails (infinite for a straight braid).
    pub fn tail_radius(&self) -> f64 {
        self.tail_arc() / self.theta
    }

    /// Smallest x of tail B (tail A mirrors it): the tails stay apart if positive.
    pub fn tail_min_x(&self) -> f64 {
        let dip = if self.theta > 0.5 * PI {
            self.tail_radius() * (1.0 - self.theta.sin())
        } else {
            0.0
        };
        self.half_width() - dip
    }

    /// Dense polyline with spacing at most `spacing`, translated so that the
    /// clamp sections lie on the x axis, plus `extension` of straight curve
    /// beyond clamp B.
    pub fn dense(&self, spacing: f64, extension: f64) -> Dense {
        let (theta, b, a) = (self.theta, self.centreline, self.braid.radius);
        let kappa = 2.0 * theta / b;
        let half_width = self.half_width();
        let braid_rise = 0.25 * b * theta * sinc(0.5 * theta).powi(2);
        let arc = self.tail_arc();
        let rise = arc * sinc(0.5 * theta) * (0.5 * theta).sin();
        // Clamp height in ring coordinates; subtracting it puts the clamps on y = 0.
        let axis_y = braid_rise + rise;
        let count = |len: f64| ((len / spacing).ceil() as usize).max(1);

        // Tail B from the braid end, in z = -a, then its clamp section.
        let start = Vector3::new(half_width, braid_rise, -a);
        let mut tail_b = Vec::new();
        let m = count(arc);
        for i in 0..=m {
            let s = arc * i as f64 / m as f64;
            let turned = theta * i as f64 / m as f64;
            let chord = s * sinc(0.5 * turned);
            let heading = theta - 0.5 * turned;
            tail_b.push(start + chord * Vector3::new(heading.cos(), heading.sin(), 0.0));
        }
        let bend_end = start.x + arc * sinc(theta);
        let straight = |x: f64| Vector3::new(x, axis_y, -a);
        let m = count(self.clamp_section);
        tail_b.extend((1..=m).map(|i| straight(bend_end + self.clamp_section * i as f64 / m as f64)));
        let clamp = tail_b.len() - 1;
        let clamp_x = tail_b[clamp].x;
        let m = count(extension);
        tail_b.extend((1..=m).map(|i| straight(clamp_x + extension * i as f64 / m as f64)));

        let strand = |sign: f64| {
            let m = count(b * 1.5);
            (1..=m).map(move |i| self.braid.point(i as f64 / m as f64, b, kappa, sign))
        };
        let steps = self.loop_steps;
        let ds = self.loop_length / steps as f64;
        let mut loop_arc = Vec::with_capacity(steps);
        let mut last = Vector3::new(half_width, braid_rise, a);
        for i in 1..steps {
            let h = loop_heading(theta, self.alpha, (i as f64 - 0.5) / steps as f64);
            last += ds * Vector3::new(h.cos(), h.sin(), 0.0);
            loop_arc.push(last);
        }
        loop_arc.push(Vector3::new(-half_width, braid_rise, a));

        // Tail A mirrors tail B up to its clamp, traversed towards the braid;
        // each later piece starts where the previous one ends.
        let mut points: Vec<Vector3<f64>> = tail_b[..=clamp]
            .iter()
            .rev()
            .map(|p| Vector3::new(-p.x, p.y, p.z))
            .collect();
        let mut marks = [points.len() - 1; 5];
        points.extend(strand(1.0));
        marks[1] = points.len() - 1;
        points.extend(loop_arc);
        marks[2] = points.len() - 1;
        points.extend(strand(-1.0));
        marks[3] = points.len() - 1;
        marks[4] = marks[3] + clamp;
        points.extend(tail_b.into_iter().skip(1));
        let shift = Vector3::new(0.0, -axis_y, a);
        for p in &mut points {
            *p += shift;
        }
        let curve = polyline::Dense::new(points);
        Dense {
            points: curve.points,
            arc: curve.arc,
            marks,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn twist_is_continuous_and_reaches_one() {
        assert_eq!(twist(0.0), (0.0, 0.0));
        assert!((twist(1.0).0 - 1.0).abs() < 1e-15 && twist(1.0).1 == 0.0);
        for u in [RAMP, 1.0 - RAMP] {
            let (below, above) = (twist(u - 1e-12), twist(u + 1e-12));
            assert!((below.0 - above.0).abs() < 1e-11 && (below.1 - above.1).abs() < 1e-9);
        }
        // w' integrates to w.
        let steps = 100_000;
        let integral: f64 = (0..steps)
            .map(|i| twist((i as f64 + 0.5) / steps as f64).1)
            .sum::<f64>()
            / steps as f64;
        assert!((integral - 1.0).abs() < 1e-9);
    }

    #[test]
    fn braid_strands_end_on_opposite_sides() {
        let braid = Braid {
            passes: 3,
            radius: 0.01,
        };
        let (b, kappa) = (0.3, 2.0);
        for sign in [1.0, -1.0] {
            let (start, end) = (braid.point(0.0, b, kappa, sign), braid.point(1.0, b, kappa, sign));
            assert!(
                (start.z + sign * 0.01).abs() < 1e-15,
                "strand enters on the -sign z side"
            );
            assert!((end.z - sign * 0.01).abs() < 1e-15, "and leaves on the other");
        }
    }
}
