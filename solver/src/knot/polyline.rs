//! What every builder does to its designed curve: resampling to equal
//! chords and the clearance check of the nodes.
use super::KnotError;
use crate::contact::broad_phase::{BroadPhase, neighbour_gap, polyline_segments};
use nalgebra::Vector3;
use std::ops::Range;

/// `count` nodes along the dense polyline from its start, consecutive nodes
/// exactly `edge` apart (each next node is the first point of the polyline,
/// past the current one, at distance `edge`), and their arc positions on the
/// polyline; `None` if the polyline is too short.
pub(super) fn equal_chords(
    dense: &[Vector3<f64>],
    arc: &[f64],
    edge: f64,
    count: usize,
) -> Option<(Vec<Vector3<f64>>, Vec<f64>)> {
    let mut nodes = vec![dense[0]];
    let mut positions = vec![0.0];
    let mut next = 1;
    while nodes.len() < count {
        let p = nodes[nodes.len() - 1];
        while (dense.get(next)? - p).norm() < edge {
            next += 1;
        }
        // The node lies on dense segment (next - 1, next), whose start is
        // closer than `edge` to p: take the root of |q + t d| = edge in [0, 1].
        let (q, d) = (dense[next - 1] - p, dense[next] - dense[next - 1]);
        let (dd, qd) = (d.norm_squared(), q.dot(&d));
        let t = (-qd + (qd * qd - dd * (q.norm_squared() - edge * edge)).sqrt()) / dd;
        nodes.push(dense[next - 1] + t * d);
        positions.push(arc[next - 1] + t * (arc[next] - arc[next - 1]));
    }
    Some((nodes, positions))
}

/// Fails if two non-neighbouring segments are closer than `2h`.
pub(super) fn check_clearance(points: &[Vector3<f64>], h: f64, edge: f64) -> Result<(), KnotError> {
    check_clearance_rods(std::slice::from_ref(&points.to_vec()), h, edge)
}

/// Fails if two segments of different rods, or two non-neighbouring
/// segments of one rod, are closer than `2h`.
pub(super) fn check_clearance_rods(rods: &[Vec<Vector3<f64>>], h: f64, edge: f64) -> Result<(), KnotError> {
    match closest_approach(rods, h, edge, 0.0, false) {
        Some(distance) => Err(KnotError::Clearance {
            distance,
            required: 2.0 * h,
        }),
        None => Ok(()),
    }
}

/// The smallest centre-line distance below `2h + margin` between segments
/// of different rods, and (unless `between_rods`) non-neighbouring segments
/// of one rod, of rods of radius `h` and edges `edge`; `None` if every such
/// pair is farther apart.
pub fn closest_approach(
    rods: &[Vec<Vector3<f64>>],
    h: f64,
    edge: f64,
    margin: f64,
    between_rods: bool,
) -> Option<f64> {
    let segments: Vec<_> = rods
        .iter()
        .enumerate()
        .flat_map(|(body, points)| polyline_segments(points, h, body))
        .collect();
    let mut broad = BroadPhase::new();
    let gaps = vec![neighbour_gap(2.0 * h, edge); rods.len()];
    let pairs = broad
        .find_pairs(&segments, &gaps, margin)
        .expect("valid segments");
    pairs
        .iter()
        .filter(|p| !between_rods || segments[p.i].body != segments[p.j].body)
        .map(|p| p.closest.distance)
        .min_by(f64::total_cmp)
}

/// The nodes of the rod `points` (radius `h`, edges `edge`) from the first
/// to the last segment that comes within `margin` of a non-neighbouring
/// segment of its own surface: where the rod is knotted on itself; `None`
/// if no two do.
pub fn self_contact_span(points: &[Vector3<f64>], h: f64, edge: f64, margin: f64) -> Option<Range<usize>> {
    let segments = polyline_segments(points, h, 0);
    let mut broad = BroadPhase::new();
    let pairs = broad
        .find_pairs(&segments, &[neighbour_gap(2.0 * h, edge)], margin)
        .expect("valid segments");
    let (first, last) = (pairs.iter())
        .filter(|p| p.closest.distance < 2.0 * h + margin)
        .fold((usize::MAX, 0), |(lo, hi), p| (lo.min(p.i), hi.max(p.j)));
    (first <= last).then_some(first..last + 2)
}

/// A dense polyline and its cumulative arc length.
pub(super) struct Dense {
    pub(super) points: Vec<Vector3<f64>>,
    pub(super) arc: Vec<f64>,
}

impl Dense {
    /// The polyline through `points`.
    pub(super) fn new(points: Vec<Vector3<f64>>) -> Self {
        let mut arc = Vec::with_capacity(points.len());
        let mut total = 0.0;
        arc.push(0.0);
        for w in points.windows(2) {
            total += (w[1] - w[0]).norm();
            arc.push(total);
        }
        Self { points, arc }
    }

    /// Its length.
    pub(super) fn length(&self) -> f64 {
        self.arc[self.arc.len() - 1]
    }
}
