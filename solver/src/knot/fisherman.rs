//! The fisherman's knot: two rods laid side by side, antiparallel, each
//! tying an overhand knot round the other's standing part (Ashley #293;
//! Tong et al., J. Appl. Mech., "Mechanical response of fisherman's knots
//! during tightening").
//!
//! Rod 0 comes from its standing end far left along `y = -SIDE` and ties
//! its overhand at `x = CENTRE` round rod 1's standing part, which runs
//! along `y = +SIDE` from its standing end far right; rod 1 is rod 0 turned
//! half a turn about `z`, its overhand at `x = -CENTRE` round rod 0's
//! standing part. In radii h, about the overhand's own origin (the other's
//! standing part is its `x` axis, the own standing part its line
//! `y = -2 SIDE`), the overhand's centre line in the plane is a smooth curve
//! through [`OVERHAND`]: on along the standing line, up and round a loop
//! that encloses the other's standing part, down across the standing line,
//! and up through the loop (across the standing line, the other's standing
//! part and the loop's top) into a tail that leaves along `+x`, [`TAIL`]
//! radii long. The diagram has three crossings in each rod (the overhand's)
//! and three between each overhand and the other's standing part. About
//! each crossing the strand on top is lifted to `+LIFT` and the one below
//! to `-LIFT` (by arc length along each strand): the overhand's own
//! crossings alternate, over first (the standing line over the loop's
//! return, the tail over the standing line, the loop's top over the tail:
//! an alternating three-crossing diagram, the trefoil); the other's
//! standing part passes under the loop's far side, over the tail and over
//! the loop's near side, through the loop beside the tail.
//!
//! The builder checks each rod's Alexander polynomial (the trefoil's: each
//! rod ties an overhand knot) and the diagram's crossings (three in each
//! rod, six between them); whether the overhands hold each other is no
//! invariant of two open rods (pulled by their tails they slide apart) and
//! is the run's to report, as for the other bends.
use super::alexander::Alexander;
use super::polyline::{Dense, check_clearance_rods, equal_chords};
use super::{BendSpec, KnotError, StartShape, check_knot};
use nalgebra::{Vector2, Vector3};
use std::f64::consts::PI;
use std::ops::Range;

/// Half the distance between the two standing parts, in radii h.
const SIDE: f64 = 2.0;
/// The overhand's distance from the knot's middle along the pull, in radii h.
const CENTRE: f64 = 60.0;
/// Height of a crossing's strands above and below the plane, in radii h.
const LIFT: f64 = 1.8;
/// Arc length either side of a crossing over which a strand rises and falls, in radii h.
const SPREAD: f64 = 4.0;
/// Length of the free tail past the overhand, in radii h.
pub const TAIL: f64 = 60.0;
/// Longest edge, in radii h: the crossings' lifts need a few nodes.
const MAX_EDGE: f64 = 2.5;
/// Points of the overhand's planar centre line, about its origin, in radii
/// h (module documentation): a Catmull-Rom spline passes through them.
const OVERHAND: [(f64, f64); 22] = [
    (-14.0, -4.0),
    (-6.0, -4.0),
    (2.0, -4.0),
    (9.0, -3.5),
    (14.0, 0.0),
    (15.0, 5.0),
    (12.0, 10.0),
    (5.0, 13.0),
    (-3.0, 12.0),
    (-9.0, 8.0),
    (-11.0, 2.0),
    (-10.0, -4.0),
    (-7.0, -9.0),
    (-1.0, -11.0),
    (4.0, -8.0),
    (5.5, -2.0),
    (5.5, 4.0),
    (5.0, 10.0),
    (5.5, 16.0),
    (9.0, 19.0),
    (16.0, 20.0),
    (24.0, 20.0),
];

/// The fisherman's knot tied as `spec` asks (its `bend` is the fisherman's):
/// each rod starts at its standing end, the pulled clamp, and ends in its
/// free tail.
pub(super) fn tie(spec: &BendSpec) -> Result<StartShape, KnotError> {
    let (h, length) = (spec.radius, spec.length);
    for (name, value) in [("length", length), ("radius", h)] {
        if !(value.is_finite() && value > 0.0) {
            return Err(KnotError::InvalidParameter { name, value });
        }
    }
    let edge = length / (spec.nodes.max(2) - 1) as f64;
    if edge > MAX_EDGE * h {
        return Err(KnotError::TooFewNodes {
            nodes: spec.nodes,
            min: (length / (MAX_EDGE * h)).ceil() as usize + 1,
        });
    }
    let spacing = edge.min(h) / (4.0 * h);
    let overhand = spline(&OVERHAND, spacing);
    let overhand_length = Dense::new(overhand.iter().map(|p| Vector3::new(p.x, p.y, 0.0)).collect()).length();
    // The standing part reaches as far past the other's overhand as the tail
    // past its own.
    let start = OVERHAND[0].0 + CENTRE;
    let far = OVERHAND.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max) + CENTRE;
    let needed = (overhand_length + TAIL + start + far + TAIL) * h + 4.0 * edge;
    if length < needed {
        return Err(KnotError::RodTooShort { needed, length });
    }
    // Rod 0 in the plane: its standing line, the overhand moved to its
    // place, the tail's line running on past the tail to outlast the
    // resampling.
    let shift = Vector2::new(CENTRE, SIDE);
    let first = overhand[0] + shift;
    let standing = length / h - overhand_length - TAIL;
    let line = |from: Vector2<f64>, along: f64| {
        let steps = (along.abs() / spacing).ceil().max(1.0) as usize;
        (1..=steps).map(move |k| from + Vector2::new(along * k as f64 / steps as f64, 0.0))
    };
    let mut planar: Vec<Vector2<f64>> = line(first, -standing).collect();
    planar.reverse();
    planar.push(first);
    let knot_from = planar.len() - 1;
    planar.extend(overhand[1..].iter().map(|p| p + shift));
    let knot_to = planar.len() - 1;
    let past = TAIL + (4.0 * edge + 0.02 * length) / h;
    planar.extend(line(planar[knot_to], past));
    let arc = arc_lengths(&planar);
    let bumps = lifts(&planar, &arc, knot_from..knot_to);
    let rod0: Vec<Vector3<f64>> = (planar.iter().zip(&arc))
        .map(|(p, &s)| Vector3::new(p.x, p.y, height(&bumps, s)) * h)
        .collect();
    // Rod 1: half a turn about z.
    let rod1: Vec<Vector3<f64>> = rod0.iter().map(|p| Vector3::new(-p.x, -p.y, p.z)).collect();
    let rods: Vec<Vec<Vector3<f64>>> = [rod0, rod1]
        .into_iter()
        .map(|dense| {
            let dense = Dense::new(dense);
            equal_chords(&dense.points, &dense.arc, edge, spec.nodes)
                .expect("the tail's line outlasts the chords")
                .0
        })
        .collect();
    check_clearance_rods(&rods, h, edge)?;
    for rod in &rods {
        check_knot(rod, &Alexander::torus_2(3))?;
    }
    Ok(StartShape::two_rods(rods, true))
}

/// The uniform Catmull-Rom spline through `points`,
/// sampled at most `spacing` apart.
fn spline(points: &[(f64, f64)], spacing: f64) -> Vec<Vector2<f64>> {
    let p: Vec<Vector2<f64>> = points.iter().map(|&(x, y)| Vector2::new(x, y)).collect();
    let n = p.len();
    let at = |i: isize| -> Vector2<f64> {
        match i {
            -1 => 2.0 * p[0] - p[1],
            i if i as usize >= n => 2.0 * p[n - 1] - p[n - 2],
            i => p[i as usize],
        }
    };
    let mut out = Vec::new();
    for i in 0..n as isize - 1 {
        let (p0, p1, p2, p3) = (at(i - 1), at(i), at(i + 1), at(i + 2));
        // Samples dense enough for the curve's bulge past its chord.
        let steps = (2.0 * (p2 - p1).norm() / spacing).ceil() as usize;
        out.extend((0..steps).map(|k| {
            let t = k as f64 / steps as f64;
            0.5 * (2.0 * p1
                + (p2 - p0) * t
                + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * (t * t)
                + (3.0 * p1 - p0 - 3.0 * p2 + p3) * (t * t * t))
        }));
    }
    out.push(p[n - 1]);
    out
}

/// Cumulative arc length along a planar polyline.
fn arc_lengths(points: &[Vector2<f64>]) -> Vec<f64> {
    let mut arc = vec![0.0];
    for w in points.windows(2) {
        arc.push(arc[arc.len() - 1] + (w[1] - w[0]).norm());
    }
    arc
}

/// Rod 0's lifts: `(arc length, +1 on top or -1 below)` at each of its
/// crossings with itself and with rod 1 (its half-turned image) in the
/// plane. Its own crossings, all within the overhand (`knot` nodes),
/// alternate over first; at the crossings of its overhand with rod 1's
/// standing part, in their order along rod 1, rod 0 lies over, under,
/// under, and at the images of these (rod 1's overhand on rod 0's standing
/// part) its standing part the other way round, so that the half turn maps
/// the diagram onto itself.
fn lifts(planar: &[Vector2<f64>], arc: &[f64], knot: Range<usize>) -> Vec<(f64, f64)> {
    let along = |i: usize, t: f64| arc[i] + t * (arc[i + 1] - arc[i]);
    let mut own: Vec<f64> = Vec::new();
    for i in knot.clone() {
        for j in i + 2..knot.end {
            if let Some((s, t)) = planar_crossing(planar[i], planar[i + 1], planar[j], planar[j + 1]) {
                own.extend([along(i, s), along(j, t)]);
            }
        }
    }
    assert_eq!(own.len(), 6, "the overhand's three crossings");
    own.sort_by(f64::total_cmp);
    let mut bumps: Vec<(f64, f64)> = (own.iter().enumerate())
        .map(|(k, &s)| (s, if k % 2 == 0 { 1.0 } else { -1.0 }))
        .collect();
    // Rod 1's point j is rod 0's point j turned: its arc is rod 0's.
    let turned: Vec<Vector2<f64>> = planar.iter().map(|p| -p).collect();
    let mut between: Vec<(f64, f64)> = Vec::new();
    for i in knot {
        for j in 0..turned.len() - 1 {
            if let Some((s, t)) = planar_crossing(planar[i], planar[i + 1], turned[j], turned[j + 1]) {
                between.push((along(i, s), along(j, t)));
            }
        }
    }
    assert_eq!(
        between.len(),
        3,
        "the overhand's three crossings with the other's standing part"
    );
    between.sort_by(|a, b| a.1.total_cmp(&b.1));
    for ((mine, theirs), side) in between.into_iter().zip([1.0, -1.0, -1.0]) {
        bumps.extend([(mine, side), (theirs, -side)]);
    }
    bumps
}

/// Height (radii h) at arc length `s` of a strand lifted by `bumps`.
fn height(bumps: &[(f64, f64)], s: f64) -> f64 {
    bumps
        .iter()
        .filter(|(at, _)| (s - at).abs() < SPREAD)
        .map(|(at, side)| side * LIFT * (0.5 * PI * (s - at).abs() / SPREAD).cos().powi(2))
        .sum()
}

/// Where planar segments `p0 p1` and `q0 q1` cross, as fractions along
/// each, if they do.
fn planar_crossing(
    p0: Vector2<f64>,
    p1: Vector2<f64>,
    q0: Vector2<f64>,
    q1: Vector2<f64>,
) -> Option<(f64, f64)> {
    let (d, e, r) = (p1 - p0, q1 - q0, q0 - p0);
    let den = d.perp(&e);
    if den.abs() < 1e-14 {
        return None;
    }
    let s = r.perp(&e) / den;
    let t = r.perp(&d) / den;
    ((0.0..1.0).contains(&s) && (0.0..1.0).contains(&t)).then_some((s, t))
}
