//! Bends: two rods of length `L` tied together by two interlocked bights,
//! the reef, granny, thief and grief knots (Patil et al., Science 2020), or
//! by two overhand knots, the fisherman's ([`super::fisherman`]).
//!
//! The shape, in radii h, in the plane `z = 0` up to the crossings: rod 0
//! is a bight open to the left, its two legs `S` apart at its bend (a half
//! circle of radius `S` about `(C, 0)`) and `s` apart far left; rod 1 its
//! half-turned twin, open to the right. The legs narrow from `+-S` to `+-s`
//! across `|x| < T` (a smoothstep), so that each bend encloses the other
//! rod's legs: the diagram has six crossings,
//!
//! | crossing | where             | strands                         |
//! |----------|-------------------|---------------------------------|
//! | c1, c2   | `(x_b, +-s)`      | rod 0's bend, rod 1's legs      |
//! | c3, c4   | `(0, +-(S + s)/2)` | the rods' upper, lower legs     |
//! | c5, c6   | `(-x_b, +-s)`     | rod 1's bend, rod 0's legs      |
//!
//! with `x_b = C + sqrt(S^2 - s^2)`; the strand on top is lifted to `+LIFT`
//! and the one below to `-LIFT` about each crossing. Which rod lies on top
//! at each crossing ([`Bend::over`]) makes the bend. In the reef knot rod 0
//! lies on top wherever a bend crosses legs and rod 1 where the legs cross:
//! each rod's two legs, standing part and tail, pass through the other's
//! bight the same way (E. F. Knight, "Sailing", 1889: "not one under and
//! one above, as in the granny"), the rods' crossing signs sum to zero and
//! a half turn about the y axis swaps the rods. In the granny knot every
//! strand alternates over and under: the legs pass through the other
//! bight one over and one under, and all six crossings have one sign (the
//! signs of the crossings of Patil et al.'s reef and granny coordinates,
//! projected, sum likewise to zero and all agree). The thief and grief
//! knots are the reef and granny pulled by the other end of rod 1: the
//! reef's and granny's tails leave on the same side of the knot (both at
//! `y > 0`), the thief's and grief's on opposite sides.
//!
//! Each rod starts at its standing end, the pulled clamp, far out along its
//! lower (reef, granny) or upper (rod 1 of the thief and grief) leg, and
//! ends in a free tail [`TAIL`] radii past the other rod's bend.
use super::polyline::{Dense, check_clearance_rods, equal_chords};
use super::{KnotError, StartShape};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Half the legs' spacing far from their bend, in radii h.
const INNER: f64 = 3.0;
/// Half the legs' spacing at their bend (the bend's radius), in radii h.
const OUTER: f64 = 9.0;
/// Half the length over which the legs narrow, in radii h.
const NARROW: f64 = 6.0;
/// The bend's centre's distance from the knot's middle, in radii h.
const CENTRE: f64 = 10.0;
/// Height of a crossing's strands above and below the plane, in radii h.
const LIFT: f64 = 1.8;
/// Planar radius about a crossing over which a strand rises and falls, in radii h.
const SPREAD: f64 = 4.0;
/// Length of the free tail past the other rod's bend, in radii h.
pub const TAIL: f64 = 30.0;
/// Longest edge, in radii h: the crossings' lifts need a few nodes.
const MAX_EDGE: f64 = 2.5;

/// A bend of the catalog.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Bend {
    Reef,
    Granny,
    Thief,
    Grief,
    /// Two overhand knots, each round the other rod's standing part.
    Fisherman,
}

impl Bend {
    /// Which rod lies on top at crossings c1 ... c6 of two interlocked
    /// bights (module documentation); `None` for the fisherman's knot.
    pub fn over(self) -> Option<[usize; 6]> {
        match self {
            Bend::Reef | Bend::Thief => Some([0, 0, 1, 1, 0, 0]),
            Bend::Granny | Bend::Grief => Some([0, 1, 1, 0, 0, 1]),
            Bend::Fisherman => None,
        }
    }

    /// Whether rod 1 is pulled by the end of its upper leg (its tail then
    /// leaves on the other side from rod 0's).
    fn crossed_tails(self) -> bool {
        matches!(self, Bend::Thief | Bend::Grief)
    }

    /// The bend in words.
    pub fn name(self) -> &'static str {
        match self {
            Bend::Reef => "the reef knot",
            Bend::Granny => "the granny knot",
            Bend::Thief => "the thief knot",
            Bend::Grief => "the grief knot",
            Bend::Fisherman => "the fisherman's knot",
        }
    }
}

/// A bend to tie: two rods of `length` with `nodes` each. Lengths in metres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BendSpec {
    pub bend: Bend,
    /// Length `L` of each rod.
    pub length: f64,
    /// Node count `K` of each rod.
    pub nodes: usize,
    /// Cross-section radius `h`.
    pub radius: f64,
}

impl BendSpec {
    /// The two rods' loose, contact-free start, each starting at its
    /// standing end (the pulled clamps: rod 0's start and rod 1's start).
    pub fn tie(&self) -> Result<StartShape, KnotError> {
        let Some(over) = self.bend.over() else {
            return super::fisherman::tie(self);
        };
        let (h, length) = (self.radius, self.length);
        for (name, value) in [("length", length), ("radius", h)] {
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
        let spacing = edge.min(h) / 4.0;
        let core = bight(spacing / h);
        let core_length = Dense::new(core.clone()).length() * h;
        // Each standing part reaches out at least as far as the tail.
        let needed = core_length + TAIL * h + 4.0 * edge;
        if length < needed {
            return Err(KnotError::RodTooShort { needed, length });
        }
        let standing = length - core_length;
        let extension = 4.0 * edge + 0.02 * length;
        let rods: Vec<Vec<Vector3<f64>>> =
            [0, 1]
                .into_iter()
                .map(|rod| {
                    let mut planar = Vec::new();
                    let start = core[0];
                    let steps = (standing / h / (spacing / h)).ceil().max(1.0) as usize;
                    planar.extend((0..steps).map(|k| {
                        start - Vector3::new(standing / h * (1.0 - k as f64 / steps as f64), 0.0, 0.0)
                    }));
                    planar.extend(core.iter().copied());
                    let end = core[core.len() - 1];
                    let steps = (extension / spacing).ceil() as usize;
                    planar.extend(
                        (1..=steps)
                            .map(|k| end - Vector3::new(extension / h * k as f64 / steps as f64, 0.0, 0.0)),
                    );
                    // Rod 1 is rod 0 turned about the y axis (from its lower
                    // leg), or half-turned about z (from its upper leg): the
                    // same planar bight, open to the right.
                    let turn = match (rod, self.bend.crossed_tails()) {
                        (0, _) => Vector3::new(1.0, 1.0, 0.0),
                        (_, false) => Vector3::new(-1.0, 1.0, 0.0),
                        (_, true) => Vector3::new(-1.0, -1.0, 0.0),
                    };
                    planar
                        .iter()
                        .map(|p| {
                            let q = p.component_mul(&turn);
                            Vector3::new(q.x, q.y, lift(&q, rod, &over)) * h
                        })
                        .collect()
                })
                .collect();
        let rods = rods
            .into_iter()
            .map(|dense| {
                let dense = Dense::new(dense);
                equal_chords(&dense.points, &dense.arc, edge, self.nodes)
                    .expect("the extension outlasts the chords")
                    .0
            })
            .collect::<Vec<_>>();
        check_clearance_rods(&rods, h, edge)?;
        Ok(StartShape::two_rods(rods, false))
    }
}

/// The crossings' planar positions, c1 ... c6, in radii h.
fn crossings() -> [Vector3<f64>; 6] {
    let x_b = CENTRE + (OUTER * OUTER - INNER * INNER).sqrt();
    let m = 0.5 * (OUTER + INNER);
    [
        (x_b, INNER),
        (x_b, -INNER),
        (0.0, m),
        (0.0, -m),
        (-x_b, INNER),
        (-x_b, -INNER),
    ]
    .map(|(x, y)| Vector3::new(x, y, 0.0))
}

/// Height (radii h) of rod `rod`'s point `p` (planar, radii h): up about
/// the crossings where it lies on top, down where below.
fn lift(p: &Vector3<f64>, rod: usize, over: &[usize; 6]) -> f64 {
    crossings()
        .iter()
        .zip(over)
        .map(|(c, &top)| {
            let r = ((p.x - c.x).powi(2) + (p.y - c.y).powi(2)).sqrt();
            let side = if top == rod { 1.0 } else { -1.0 };
            if r < SPREAD {
                side * LIFT * (0.5 * PI * r / SPREAD).cos().powi(2)
            } else {
                0.0
            }
        })
        .sum()
}

/// Rod 0's knotted part in the plane (radii h), points at most `spacing`
/// apart: from its lower leg `TAIL` past rod 1's bend, rightwards to its
/// own bend, round it and back along its upper leg to as far out.
fn bight(spacing: f64) -> Vec<Vector3<f64>> {
    let far = CENTRE + OUTER + TAIL;
    // The upper leg's height at x (the lower leg's is its negative).
    let leg = |x: f64| {
        let u = ((x + NARROW) / (2.0 * NARROW)).clamp(0.0, 1.0);
        INNER + (OUTER - INNER) * u * u * (3.0 - 2.0 * u)
    };
    let along = |from: f64, to: f64, sign: f64| {
        let steps = (((to - from) / spacing).abs() * 1.5).ceil() as usize;
        (0..steps).map(move |k| {
            let x = from + (to - from) * k as f64 / steps as f64;
            Vector3::new(x, sign * leg(x), 0.0)
        })
    };
    let mut points: Vec<Vector3<f64>> = along(-far, CENTRE, -1.0).collect();
    let steps = (PI * OUTER / spacing).ceil() as usize;
    points.extend((0..steps).map(|k| {
        let phi = -0.5 * PI + PI * k as f64 / steps as f64;
        Vector3::new(CENTRE + OUTER * phi.cos(), OUTER * phi.sin(), 0.0)
    }));
    points.extend(along(CENTRE, -far, 1.0));
    points.push(Vector3::new(-far, leg(-far), 0.0));
    points
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The designed crossings are where the two rods' planar paths cross:
    /// each rod's bend crosses the other's legs at c1, c2 and c5, c6, the
    /// legs cross each other at c3, c4, and nowhere else.
    #[test]
    fn the_rods_cross_at_the_designed_crossings_only() {
        let spec = BendSpec {
            bend: Bend::Reef,
            length: 1.0,
            nodes: 301,
            radius: 1.6e-3,
        };
        let shape = spec.tie().unwrap();
        let h = spec.radius;
        let flat = |rod: &[Vector3<f64>]| -> Vec<Vector3<f64>> {
            rod.iter().map(|p| Vector3::new(p.x, p.y, 0.0) / h).collect()
        };
        let (a, b) = (flat(&shape.rods[0]), flat(&shape.rods[1]));
        let mut found = Vec::new();
        for i in 0..a.len() - 1 {
            for j in 0..b.len() - 1 {
                if let Some(p) = planar_crossing(&a[i], &a[i + 1], &b[j], &b[j + 1]) {
                    found.push(p);
                }
            }
        }
        assert_eq!(found.len(), 6, "{found:?}");
        for c in crossings() {
            let nearest = found.iter().map(|p| (p - c).norm()).fold(f64::INFINITY, f64::min);
            assert!(nearest < 0.5, "crossing {c:?}: nearest found {nearest}");
        }
    }

    /// Where segments `p0 p1` and `q0 q1` cross in the plane, if they do.
    fn planar_crossing(
        p0: &Vector3<f64>,
        p1: &Vector3<f64>,
        q0: &Vector3<f64>,
        q1: &Vector3<f64>,
    ) -> Option<Vector3<f64>> {
        let (d, e, r) = (p1 - p0, q1 - q0, q0 - p0);
        let den = d.x * e.y - d.y * e.x;
        if den.abs() < 1e-14 {
            return None;
        }
        let s = (r.x * e.y - r.y * e.x) / den;
        let t = (r.x * d.y - r.y * d.x) / den;
        ((0.0..1.0).contains(&s) && (0.0..1.0).contains(&t)).then(|| p0 + s * d)
    }
}
