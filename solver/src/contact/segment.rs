//! Closest points between two 3D segments (the contact points `C_a`, `C_b` of
//! Sec. 3.2, Fig. 3(c)), after Lumelsky 1985 (the paper's ref. [56]).
//!
//! Segment A is `p0 + s (p1 - p0)`, segment B is `q0 + t (q1 - q0)`, with
//! `s, t` in `[0, 1]`. The squared distance is a convex quadratic in `(s, t)`;
//! its minimiser over the unit square is found as in Lumelsky: the closest
//! points of the supporting lines, `s` clamped, `t` the clamped projection of
//! `A(s)` on B, and `s` re-projected when `t` was clamped. Three details make it
//! robust:
//! - the line-line parameter is `((q0 - p0) x d2) . (d1 x d2) / |d1 x d2|^2`
//!   (Lagrange's identity applied to Lumelsky's `S1 D2 - S2 R` over
//!   `D1 D2 - R^2`), which avoids the cancellation in `D1 D2 - R^2` for nearly
//!   parallel segments; its remaining error lies along the flat valley of the
//!   distance, so the distance error is second order (and the clamping
//!   sequence returns the right distance from any start when the segments are
//!   parallel);
//! - parallel segments, `|d1 x d2| <= PARALLEL_SIN |d1| |d2|`, take the
//!   midpoint of the overlap of their projections when they overlap (the
//!   minimiser is not unique; the midpoint is symmetric in A and B) and the
//!   nearest endpoints otherwise;
//! - a segment shorter than `DEGENERATE_RATIO` times the other one is a point.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// Segments whose directions satisfy `sin(angle) <= PARALLEL_SIN` (parallel up
/// to rounding) are treated as parallel; the distance error this causes is at
/// most `PARALLEL_SIN * max(|d1|, |d2|)`.
pub const PARALLEL_SIN: f64 = 1e-14;

/// A segment with `|d|^2 <= DEGENERATE_RATIO * (|d1|^2 + |d2|^2)` is a point.
pub const DEGENERATE_RATIO: f64 = 1e-28;

/// Closest points of two segments: `point_a = p0 + s (p1 - p0)`,
/// `point_b = q0 + t (q1 - q0)`, `distance = |point_a - point_b|`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SegmentPair {
    /// Parameter of the closest point on segment A, in `[0, 1]`.
    pub s: f64,
    /// Parameter of the closest point on segment B, in `[0, 1]`.
    pub t: f64,
    /// Distance between the segments (centre lines).
    pub distance: f64,
    /// Closest point on segment A (`C_a` of Sec. 3.2).
    pub point_a: Vector3<f64>,
    /// Closest point on segment B (`C_b` of Sec. 3.2).
    pub point_b: Vector3<f64>,
}

/// Closest points between segments `[p0, p1]` and `[q0, q1]`.
///
/// Two segments crossing at right angles, one unit apart:
/// ```
/// use nalgebra::Vector3;
/// use solver::contact::segment::closest_points;
///
/// let pair = closest_points(
///     &Vector3::new(-1.0, 0.0, 0.0),
///     &Vector3::new(1.0, 0.0, 0.0),
///     &Vector3::new(0.0, -1.0, 1.0),
///     &Vector3::new(0.0, 3.0, 1.0),
/// );
/// assert_eq!((pair.s, pair.t, pair.distance), (0.5, 0.25, 1.0));
/// assert_eq!(pair.point_a, Vector3::zeros());
/// assert_eq!(pair.point_b, Vector3::new(0.0, 0.0, 1.0));
/// ```
pub fn closest_points(
    p0: &Vector3<f64>,
    p1: &Vector3<f64>,
    q0: &Vector3<f64>,
    q1: &Vector3<f64>,
) -> SegmentPair {
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = q0 - p0;
    let a = d1.norm_squared();
    let e = d2.norm_squared();
    let tiny = DEGENERATE_RATIO * (a + e);
    let (s, t) = if a <= tiny && e <= tiny {
        (0.0, 0.0)
    } else if a <= tiny {
        (0.0, clamp01(-d2.dot(&r) / e))
    } else if e <= tiny {
        (clamp01(d1.dot(&r) / a), 0.0)
    } else {
        let n = d1.cross(&d2);
        let n2 = n.norm_squared();
        if n2 <= PARALLEL_SIN * PARALLEL_SIN * a * e {
            parallel(&d1, &d2, &r, a, e)
        } else {
            general(&d1, &d2, &r, &n, n2, a, e)
        }
    };
    let point_a = p0 + s * d1;
    let point_b = q0 + t * d2;
    SegmentPair {
        s,
        t,
        distance: (point_a - point_b).norm(),
        point_a,
        point_b,
    }
}

fn clamp01(x: f64) -> f64 {
    x.clamp(0.0, 1.0)
}

/// Lumelsky's clamping sequence from the line-line solution.
fn general(
    d1: &Vector3<f64>,
    d2: &Vector3<f64>,
    r: &Vector3<f64>,
    n: &Vector3<f64>,
    n2: f64,
    a: f64,
    e: f64,
) -> (f64, f64) {
    let s = clamp01(r.cross(d2).dot(n) / n2);
    let b = d1.dot(d2);
    let t = (b * s - d2.dot(r)) / e;
    if t < 0.0 {
        (clamp01(d1.dot(r) / a), 0.0)
    } else if t > 1.0 {
        (clamp01((b + d1.dot(r)) / a), 1.0)
    } else {
        (s, t)
    }
}

/// Parallel segments: midpoint of the overlap of B's projection on A, else
/// the nearest endpoints.
fn parallel(d1: &Vector3<f64>, d2: &Vector3<f64>, r: &Vector3<f64>, a: f64, e: f64) -> (f64, f64) {
    let sq0 = d1.dot(r) / a;
    let sq1 = sq0 + d1.dot(d2) / a;
    let lo = sq0.min(sq1).max(0.0);
    let hi = sq0.max(sq1).min(1.0);
    let s = if lo <= hi {
        0.5 * (lo + hi)
    } else if hi < 0.0 {
        0.0
    } else {
        1.0
    };
    let b = d1.dot(d2);
    let t = clamp01((b * s - d2.dot(r)) / e);
    let s = if lo <= hi {
        s
    } else {
        clamp01((b * t + d1.dot(r)) / a)
    };
    (s, t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// Distance from `p` to segment `[q0, q1]` (well conditioned).
    fn point_segment(p: &Vector3<f64>, q0: &Vector3<f64>, q1: &Vector3<f64>) -> f64 {
        let d = q1 - q0;
        let e = d.norm_squared();
        let t = if e > 0.0 {
            clamp01((p - q0).dot(&d) / e)
        } else {
            0.0
        };
        (p - (q0 + t * d)).norm()
    }

    /// Reference minimum: `g(s) = dist(A(s), B)` is convex in `s`; dense
    /// sampling brackets its minimum and golden-section search refines it.
    fn brute_force(p0: &Vector3<f64>, p1: &Vector3<f64>, q0: &Vector3<f64>, q1: &Vector3<f64>) -> f64 {
        let g = |s: f64| point_segment(&(p0 + s * (p1 - p0)), q0, q1);
        let m = 2000;
        let best = (0..=m)
            .min_by(|&i, &j| g(i as f64 / m as f64).total_cmp(&g(j as f64 / m as f64)))
            .unwrap();
        let (mut lo, mut hi) = (
            (best as f64 - 1.0).max(0.0) / m as f64,
            (best as f64 + 1.0).min(m as f64) / m as f64,
        );
        let phi = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..200 {
            let x1 = hi - phi * (hi - lo);
            let x2 = lo + phi * (hi - lo);
            if g(x1) <= g(x2) {
                hi = x2;
            } else {
                lo = x1;
            }
        }
        g(0.5 * (lo + hi)).min(g(0.0)).min(g(1.0))
    }

    fn check_consistent(pair: &SegmentPair, p: [&Vector3<f64>; 4]) {
        assert!((0.0..=1.0).contains(&pair.s) && (0.0..=1.0).contains(&pair.t));
        let pa = p[0] + pair.s * (p[1] - p[0]);
        let pb = p[2] + pair.t * (p[3] - p[2]);
        assert!((pa - pair.point_a).norm() <= 1e-14 * (1.0 + pa.norm()));
        assert!((pb - pair.point_b).norm() <= 1e-14 * (1.0 + pb.norm()));
        assert!((pair.distance - (pa - pb).norm()).abs() <= 1e-14);
    }

    fn check_against_brute_force(
        p0: Vector3<f64>,
        p1: Vector3<f64>,
        q0: Vector3<f64>,
        q1: Vector3<f64>,
        tol: f64,
    ) {
        let pair = closest_points(&p0, &p1, &q0, &q1);
        check_consistent(&pair, [&p0, &p1, &q0, &q1]);
        let reference = brute_force(&p0, &p1, &q0, &q1);
        assert!(
            (pair.distance - reference).abs() <= tol,
            "distance {} vs brute force {reference}",
            pair.distance
        );
    }

    fn random_point(rng: &mut StdRng) -> Vector3<f64> {
        v(
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
        )
    }

    #[test]
    fn random_pairs_match_brute_force() {
        let mut rng = StdRng::seed_from_u64(1);
        for _ in 0..2000 {
            let p = [0; 4].map(|_| random_point(&mut rng));
            check_against_brute_force(p[0], p[1], p[2], p[3], 1e-12);
        }
    }

    #[test]
    fn exactly_parallel() {
        // Overlapping: distance is the offset, contact at the overlap midpoint.
        let pair = closest_points(
            &v(0.0, 0.0, 0.0),
            &v(2.0, 0.0, 0.0),
            &v(1.0, 0.5, 0.0),
            &v(3.0, 0.5, 0.0),
        );
        assert!((pair.distance - 0.5).abs() < 1e-15);
        assert!((pair.s - 0.75).abs() < 1e-15 && (pair.t - 0.25).abs() < 1e-15);
        // Opposite directions, overlapping.
        let pair = closest_points(
            &v(0.0, 0.0, 0.0),
            &v(2.0, 0.0, 0.0),
            &v(3.0, 0.0, 0.5),
            &v(1.0, 0.0, 0.5),
        );
        assert!((pair.distance - 0.5).abs() < 1e-15);
        assert!((pair.s - 0.75).abs() < 1e-15 && (pair.t - 0.75).abs() < 1e-15);
        // Disjoint along the axis: nearest endpoints.
        let pair = closest_points(
            &v(0.0, 0.0, 0.0),
            &v(1.0, 0.0, 0.0),
            &v(4.0, 1.0, 0.0),
            &v(2.0, 1.0, 0.0),
        );
        assert!((pair.distance - 2f64.sqrt()).abs() < 1e-15);
        assert_eq!((pair.s, pair.t), (1.0, 1.0));
        let pair = closest_points(
            &v(0.0, 0.0, 0.0),
            &v(1.0, 0.0, 0.0),
            &v(-3.0, 1.0, 0.0),
            &v(-1.0, 1.0, 0.0),
        );
        assert!((pair.distance - 2f64.sqrt()).abs() < 1e-15);
        assert_eq!((pair.s, pair.t), (0.0, 1.0));
        // Random parallel pairs (scaled copies of one direction).
        let mut rng = StdRng::seed_from_u64(2);
        for _ in 0..500 {
            let p0 = random_point(&mut rng);
            let d = random_point(&mut rng);
            let q0 = random_point(&mut rng);
            let k: f64 = rng.gen_range(-2.0..2.0);
            check_against_brute_force(p0, p0 + d, q0, q0 + k * d, 1e-12);
        }
    }

    #[test]
    fn nearly_parallel() {
        for (angle, seed) in [(1e-6, 3), (1e-9, 4), (1e-12, 5), (1e-15, 8)] {
            let mut rng = StdRng::seed_from_u64(seed);
            for _ in 0..500 {
                let p0 = random_point(&mut rng);
                let p1 = random_point(&mut rng);
                let d = p1 - p0;
                let axis = d.cross(&random_point(&mut rng)).normalize();
                let rot = nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_unchecked(axis), angle);
                let q0 = p0 + rng.gen_range(-1.0..1.0) * d + 1e-3 * random_point(&mut rng);
                let q1 = q0 + rng.gen_range(-2.0..2.0) * (rot * d);
                check_against_brute_force(p0, p1, q0, q1, 1e-12);
            }
        }
        // An X of two unit segments crossing at their midpoints at 1e-9 rad.
        let c = 1e-9f64.cos();
        let s = 1e-9f64.sin();
        let pair = closest_points(
            &v(-0.5, 0.0, 0.0),
            &v(0.5, 0.0, 0.0),
            &v(-0.5 * c, -0.5 * s, 0.0),
            &v(0.5 * c, 0.5 * s, 0.0),
        );
        assert!(pair.distance < 1e-15, "distance {}", pair.distance);
        assert!((pair.s - 0.5).abs() < 1e-6 && (pair.t - 0.5).abs() < 1e-6);
    }

    #[test]
    fn collinear_overlapping() {
        let pair = closest_points(
            &v(0.0, 0.0, 0.0),
            &v(2.0, 2.0, 2.0),
            &v(1.0, 1.0, 1.0),
            &v(5.0, 5.0, 5.0),
        );
        assert_eq!(pair.distance, 0.0);
        assert!((pair.s - 0.75).abs() < 1e-15 && (pair.t - 0.125).abs() < 1e-15);
        // B inside A.
        let pair = closest_points(
            &v(0.0, 0.0, 0.0),
            &v(4.0, 0.0, 0.0),
            &v(3.0, 0.0, 0.0),
            &v(1.0, 0.0, 0.0),
        );
        assert_eq!(pair.distance, 0.0);
        assert!((pair.s - 0.5).abs() < 1e-15 && (pair.t - 0.5).abs() < 1e-15);
        // Collinear, touching at one endpoint.
        let pair = closest_points(
            &v(0.0, 0.0, 0.0),
            &v(1.0, 0.0, 0.0),
            &v(1.0, 0.0, 0.0),
            &v(2.0, 0.0, 0.0),
        );
        assert_eq!(pair.distance, 0.0);
        assert_eq!((pair.s, pair.t), (1.0, 0.0));
    }

    #[test]
    fn crossing() {
        let pair = closest_points(
            &v(-1.0, 0.0, 0.0),
            &v(1.0, 0.0, 0.0),
            &v(0.0, -1.0, 0.3),
            &v(0.0, 3.0, 0.3),
        );
        assert!((pair.distance - 0.3).abs() < 1e-15);
        assert!((pair.s - 0.5).abs() < 1e-15 && (pair.t - 0.25).abs() < 1e-15);
        assert!((pair.point_a - v(0.0, 0.0, 0.0)).norm() < 1e-15);
        assert!((pair.point_b - v(0.0, 0.0, 0.3)).norm() < 1e-15);
        // Intersecting segments.
        let pair = closest_points(
            &v(0.0, 0.0, 0.0),
            &v(2.0, 2.0, 0.0),
            &v(2.0, 0.0, 0.0),
            &v(0.0, 2.0, 0.0),
        );
        assert!(pair.distance < 1e-15);
        // T configuration: endpoint of B closest to the interior of A.
        let pair = closest_points(
            &v(-1.0, 0.0, 0.0),
            &v(1.0, 0.0, 0.0),
            &v(0.5, 0.2, 0.0),
            &v(0.5, 2.0, 0.0),
        );
        assert!((pair.distance - 0.2).abs() < 1e-15);
        assert!((pair.s - 0.75).abs() < 1e-15 && pair.t == 0.0);
    }

    #[test]
    fn degenerate() {
        let o = v(0.0, 0.0, 0.0);
        // Both points.
        let pair = closest_points(&o, &o, &v(3.0, 4.0, 0.0), &v(3.0, 4.0, 0.0));
        assert_eq!(pair.distance, 5.0);
        assert_eq!((pair.s, pair.t), (0.0, 0.0));
        // A is a point.
        let pair = closest_points(
            &v(0.5, 1.0, 0.0),
            &v(0.5, 1.0, 0.0),
            &v(0.0, 0.0, 0.0),
            &v(2.0, 0.0, 0.0),
        );
        assert!((pair.distance - 1.0).abs() < 1e-15 && (pair.t - 0.25).abs() < 1e-15);
        // B is a point beyond A's end.
        let pair = closest_points(
            &v(0.0, 0.0, 0.0),
            &v(1.0, 0.0, 0.0),
            &v(2.0, 1.0, 0.0),
            &v(2.0, 1.0, 0.0),
        );
        assert!((pair.distance - 2f64.sqrt()).abs() < 1e-15 && pair.s == 1.0);
        // Nearly degenerate (1e-15 long) segment against a unit one.
        let mut rng = StdRng::seed_from_u64(6);
        for _ in 0..500 {
            let p0 = random_point(&mut rng);
            let p1 = p0 + 1e-15 * random_point(&mut rng);
            let (q0, q1) = (random_point(&mut rng), random_point(&mut rng));
            check_against_brute_force(p0, p1, q0, q1, 1e-12);
            check_against_brute_force(q0, q1, p0, p1, 1e-12);
        }
    }

    #[test]
    fn symmetric_under_swap() {
        let mut rng = StdRng::seed_from_u64(7);
        for _ in 0..2000 {
            let p = [0; 4].map(|_| random_point(&mut rng));
            let ab = closest_points(&p[0], &p[1], &p[2], &p[3]);
            let ba = closest_points(&p[2], &p[3], &p[0], &p[1]);
            assert!((ab.s - ba.t).abs() < 1e-9 && (ab.t - ba.s).abs() < 1e-9);
            assert!((ab.distance - ba.distance).abs() < 1e-14);
        }
        // Parallel overlapping pairs have a non-unique minimiser; the overlap
        // midpoint makes the choice symmetric.
        let (p0, p1, q0, q1) = (
            v(0.0, 0.0, 0.0),
            v(2.0, 0.0, 0.0),
            v(3.0, 0.5, 0.0),
            v(1.0, 0.5, 0.0),
        );
        let ab = closest_points(&p0, &p1, &q0, &q1);
        let ba = closest_points(&q0, &q1, &p0, &p1);
        assert!((ab.s - ba.t).abs() < 1e-15 && (ab.t - ba.s).abs() < 1e-15);
    }
}
