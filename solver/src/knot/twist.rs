//! The twist a knot starts with: its writhe and the paper's code's linking
//! number.
//!
//! A rod clamped at both ends keeps its linking number Lk = Tw + Wr (Călugăreanu,
//! White), with the writhe Wr of the centre line closed by straight tails along
//! the pull axis. The paper's code starts its knots with a rest twist computed
//! from the start shape (each edge's frame carried back to the pull axis by the
//! minimal rotation); on all four of its start shapes (n = 1..4) that makes
//! Lk = -2n to within 0.001 (Wr = -3.01, -5.04, -7.09, -9.14, twist +1.01 to
//! +1.14 turns). [`paper_twist`] gives a start shape that twist.
use nalgebra::Vector3;

/// Segments of each straight tail added along the axis when measuring the writhe.
const TAIL_SEGMENTS: usize = 64;
/// The tails reach this many end-to-end spans beyond the clamps.
const TAIL_SPANS: f64 = 100.0;

/// Writhe of the open polyline `points`, closed by straight tails along the
/// line joining its ends (out to [`TAIL_SPANS`] spans), by the exact
/// segment-pair solid angles of Klenin and Langowski (2000):
/// `Wr = (1/2pi) sum_{i<j} Omega_ij`. Zero for a planar curve; it changes sign
/// with the mirror image.
pub fn writhe(points: &[Vector3<f64>]) -> f64 {
    let (first, last) = (points[0], points[points.len() - 1]);
    let span = (last - first).norm();
    let axis = (last - first) / span;
    // Tail nodes spaced geometrically from a thousandth of the span out to the reach.
    let reach = |k: usize| span * 1e-3 * (1e3 * TAIL_SPANS).powf(k as f64 / TAIL_SEGMENTS as f64);
    let mut curve: Vec<Vector3<f64>> = (0..=TAIL_SEGMENTS)
        .rev()
        .map(|k| first - axis * reach(k))
        .collect();
    curve.extend_from_slice(points);
    curve.extend((0..=TAIL_SEGMENTS).map(|k| last + axis * reach(k)));
    let mut sum = 0.0;
    for i in 0..curve.len() - 1 {
        for j in i + 2..curve.len() - 1 {
            sum += solid_angle(&curve[i], &curve[i + 1], &curve[j], &curve[j + 1]);
        }
    }
    sum / (2.0 * std::f64::consts::PI)
}

/// Signed solid angle `Omega` under which segment `[p1, p2]` sees `[p3, p4]`
/// (Klenin and Langowski's quadrilateral formula).
fn solid_angle(p1: &Vector3<f64>, p2: &Vector3<f64>, p3: &Vector3<f64>, p4: &Vector3<f64>) -> f64 {
    let (r13, r14, r23, r24) = (p3 - p1, p4 - p1, p3 - p2, p4 - p2);
    let unit = |v: Vector3<f64>| {
        let n = v.norm();
        if n > 0.0 { v / n } else { v }
    };
    let n = [
        unit(r13.cross(&r14)),
        unit(r14.cross(&r24)),
        unit(r24.cross(&r23)),
        unit(r23.cross(&r13)),
    ];
    let omega: f64 = (0..4)
        .map(|k| n[k].dot(&n[(k + 1) % 4]).clamp(-1.0, 1.0).asin())
        .sum();
    let sign = (p4 - p3).cross(&(p2 - p1)).dot(&r13);
    if sign > 0.0 {
        omega
    } else if sign < 0.0 {
        -omega
    } else {
        0.0
    }
}

/// The change of writhe from the polyline with edge tangents `before` to the
/// one with tangents `after` (same edge count, the first and last tangents
/// along the closing axis in both), by Fuller's theorem: `(1/2pi)` times the
/// signed area the tangent indicatrix sweeps, each spherical quadrilateral
/// (`before[e]`, `before[e+1]`, `after[e+1]`, `after[e]`) as two triangles
/// (Van Oosterom and Strackee's solid angle). Exact for polygons while no
/// tangent turns to its antipode, so that a time step's small change costs
/// O(K) where [`writhe`] costs O(K^2).
pub fn writhe_change(before: &[Vector3<f64>], after: &[Vector3<f64>]) -> f64 {
    // tan(Omega / 2) = x: a step's triangles are small, where the series of
    // atan to x^5 is exact to rounding (|x| < 1e-3) and costs no atan.
    let triangle = |a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>| {
        let (num, den) = (a.dot(&b.cross(c)), 1.0 + a.dot(b) + b.dot(c) + c.dot(a));
        let x = num / den;
        if den > 0.0 && x.abs() < 1e-3 {
            let x2 = x * x;
            2.0 * x * (1.0 - x2 * (1.0 / 3.0 - x2 / 5.0))
        } else {
            2.0 * num.atan2(den)
        }
    };
    let mut area = 0.0;
    for e in 0..before.len().saturating_sub(1) {
        let (p, q, r, s) = (&before[e], &before[e + 1], &after[e + 1], &after[e]);
        area += triangle(p, q, r) + triangle(p, r, s);
    }
    -area / std::f64::consts::TAU
}

/// The twist (turns) that gives an `n`-pass knot of writhe `writhe` the
/// linking number `2n` with the writhe's sign, as the paper's code starts:
/// `Tw = ±2n - Wr`.
pub fn paper_twist(n: u32, writhe: f64) -> f64 {
    2.0 * f64::from(n) * writhe.signum() - writhe
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rod::frames::{parallel_transport, signed_angle, unwrap_near};
    use std::f64::consts::TAU;

    /// A smooth open curve with one loop (its tangent turns back along -x but,
    /// lifted, never exactly): its ends lie along x.
    fn looped(lift: f64, samples: usize) -> Vec<Vector3<f64>> {
        (0..samples)
            .map(|k| {
                let s = k as f64 / (samples - 1) as f64;
                let phi = TAU * s;
                // Straight ends along x, a tilted loop in between.
                Vector3::new(
                    4.0 * s - 2.0 + phi.sin(),
                    0.6 * (1.0 - phi.cos()),
                    lift * (2.0 * phi).sin(),
                )
            })
            .collect()
    }

    /// Twist (turns) of the frame carried to every edge from the axis by the
    /// minimal rotation, measured against the space-parallel frame.
    fn axis_frame_twist(points: &[Vector3<f64>]) -> f64 {
        let axis = (points[points.len() - 1] - points[0]).normalize();
        let t: Vec<_> = points.windows(2).map(|w| (w[1] - w[0]).normalize()).collect();
        let mut d = crate::rod::frames::perpendicular(&t[0]);
        let straight = parallel_transport(&d, &t[0], &axis);
        let mut theta = 0.0;
        for i in 0..t.len() {
            if i > 0 {
                d = parallel_transport(&d, &t[i - 1], &t[i]);
            }
            let carried = parallel_transport(&straight, &axis, &t[i]);
            theta = unwrap_near(signed_angle(&d, &carried, &t[i]), theta);
        }
        theta / TAU
    }

    #[test]
    fn planar_curve_has_no_writhe_and_mirror_flips_it() {
        let flat = looped(0.0, 400);
        assert!(writhe(&flat).abs() < 1e-9);
        let lifted = looped(0.3, 400);
        let mirrored: Vec<_> = lifted.iter().map(|p| Vector3::new(p.x, p.y, -p.z)).collect();
        let (w, m) = (writhe(&lifted), writhe(&mirrored));
        assert!(w.abs() > 0.05 && (w + m).abs() < 1e-9, "{w} {m}");
    }

    /// Călugăreanu-White-Fuller: the frame carried from the axis by minimal
    /// rotations closes up with the tails' frame, so its twist plus the
    /// writhe (its linking number) is an integer, for curves whose tangent
    /// never points along -axis.
    #[test]
    fn axis_frame_twist_plus_writhe_is_an_integer() {
        for lift in [0.1, 0.3, 0.6] {
            let curve = looped(lift, 3000);
            let wr = writhe(&curve);
            let lk = axis_frame_twist(&curve) + wr;
            assert!(
                wr.abs() > 0.5 && (lk - lk.round()).abs() < 1e-5,
                "lift {lift}: Wr {wr}, Tw + Wr = {lk}"
            );
        }
    }

    /// Fuller's increments, summed over a deformation in small steps, give
    /// the writhe's change that the double sum of [`writhe`] gives.
    #[test]
    fn writhe_changes_add_up_to_the_writhes_change() {
        // The edges' tangents between the closing tails' (the axis, x).
        let tangents = |p: &[Vector3<f64>]| -> Vec<Vector3<f64>> {
            let mut t = vec![Vector3::x()];
            t.extend(p.windows(2).map(|w| (w[1] - w[0]).normalize()));
            t.push(Vector3::x());
            t
        };
        // From a slightly lifted loop (the planar one crosses itself, where
        // the writhe jumps) to a high one.
        let steps = 200;
        let mut tracked = writhe(&looped(0.05, 300));
        let mut before = tangents(&looped(0.05, 300));
        for k in 1..=steps {
            let after = tangents(&looped(0.05 + 0.55 * k as f64 / steps as f64, 300));
            tracked += writhe_change(&before, &after);
            before = after;
        }
        let exact = writhe(&looped(0.6, 300));
        // The same to 9e-9 with 200 or 800 steps: the double sum's own error,
        // its closing tails stopping at TAIL_SPANS.
        assert!(
            exact.abs() > 0.5 && (tracked - exact).abs() < 1e-7,
            "{tracked} against {exact}"
        );
    }

    #[test]
    fn paper_twist_makes_the_linking_number_2n() {
        assert!((paper_twist(3, -7.09) - 1.09).abs() < 1e-12);
        assert!((paper_twist(4, 9.14) + 1.14).abs() < 1e-12);
    }
}
