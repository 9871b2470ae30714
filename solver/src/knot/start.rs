//! A user's start shape, checked like a built knot.
use super::StartShape;
use super::alexander::{Alexander, alexander};
use super::polyline::closest_approach;
use crate::contact::broad_phase::neighbour_gap;
use crate::contact::segment::closest_points;
use nalgebra::Vector3;

/// A user's start shape for a rod of `length`, `nodes` and `radius` h
/// tied in the knot `name` of Alexander polynomial `expected`: a
/// [`checked_rod`], every node between the two ends along the line joining
/// them (the clamps hold the ends), no two non-neighbouring segments closer
/// than 2h, and the knot's Alexander polynomial. The error is the reason, in
/// words.
pub fn checked_start(
    points: &[[f64; 3]],
    (length, nodes, radius): (f64, usize, f64),
    name: &str,
    expected: &Alexander,
) -> Result<StartShape, String> {
    let points = checked_rod(points, (length, nodes))?;
    let edges: Vec<f64> = points.windows(2).map(|w| (w[1] - w[0]).norm()).collect();
    check_between_ends(&points)?;
    check_clearance(&points, &edges, radius)?;
    match alexander(&points) {
        Ok(got) if got == *expected => {
            let middle = points.len() / 2;
            Ok(StartShape::one_rod(points, middle, got))
        }
        Ok(got) => Err(format!("Alexander polynomial {got}, but {name} has {expected}")),
        Err(e) => Err(format!("knot type undetermined: {e}")),
    }
}

/// One rod of a user's start shape for rods of `length` and `nodes`:
/// `nodes` finite points, no two consecutive ones equal, a polyline of
/// length `length` (within 1 %).
pub fn checked_rod(points: &[[f64; 3]], (length, nodes): (f64, usize)) -> Result<Vec<Vector3<f64>>, String> {
    if points.len() != nodes {
        return Err(format!(
            "{} points, but nodes = {nodes}: give one point per node",
            points.len()
        ));
    }
    if let Some(i) = points.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
        return Err(format!("point {i} is not finite"));
    }
    let points: Vec<Vector3<f64>> = points.iter().map(|p| Vector3::from(*p)).collect();
    let edges: Vec<f64> = points.windows(2).map(|w| (w[1] - w[0]).norm()).collect();
    if let Some(i) = edges.iter().position(|&e| e <= 0.0) {
        return Err(format!("points {i} and {} coincide", i + 1));
    }
    let total: f64 = edges.iter().sum();
    if (total - length).abs() > 0.01 * length {
        return Err(format!(
            "the polyline is {total:.4} m long, but length = {length} m (within 1 %)"
        ));
    }
    Ok(points)
}

/// No two segments of different rods, nor two non-neighbouring segments of
/// one rod, closer than 2h (`radius` h), less [`START_OVERLAP`]: the
/// clearance of a start of several rods ([`checked_rod`] each).
pub fn check_rods_clearance(rods: &[Vec<Vector3<f64>>], radius: f64) -> Result<(), String> {
    let shortest = (rods.iter())
        .flat_map(|rod| rod.windows(2).map(|w| (w[1] - w[0]).norm()))
        .fold(f64::INFINITY, f64::min);
    match closest_approach(rods, radius, shortest, 0.0, false) {
        Some(d) if d < 2.0 * radius * (1.0 - START_OVERLAP) => Err(format!(
            "two segments are {d:.4e} m apart, closer than 2h = {:.4e} m by more than {} %",
            2.0 * radius,
            100.0 * START_OVERLAP
        )),
        _ => Ok(()),
    }
}

/// Every node lies between the two ends along the line joining them.
fn check_between_ends(points: &[Vector3<f64>]) -> Result<(), String> {
    let (first, last) = (points[0], points[points.len() - 1]);
    let span = (last - first).norm();
    let axis = (last - first) / span;
    match points.iter().position(|p| {
        let s = (p - first).dot(&axis);
        s < -1e-9 * span || s > span * (1.0 + 1e-9)
    }) {
        Some(i) => Err(format!(
            "point {i} lies beyond an end along the line joining the ends: the clamps hold the \
             first and last points and pull them apart along that line"
        )),
        None => Ok(()),
    }
}

/// How far two strands of a start shape may overlap, as a fraction of 2h: a
/// knot at rest presses its strands together and the contact solve leaves
/// them overlapping by a small fraction of h, so that a state a case wrote
/// (its relaxed snapshot) starts a case again as it is.
pub const START_OVERLAP: f64 = 0.01;

/// No two non-neighbouring segments closer than 2h (`radius` h), less
/// [`START_OVERLAP`].
fn check_clearance(points: &[Vector3<f64>], edges: &[f64], radius: f64) -> Result<(), String> {
    let shortest = edges.iter().cloned().fold(f64::INFINITY, f64::min);
    let gap = neighbour_gap(2.0 * radius, shortest);
    for i in 0..edges.len() {
        for j in i + gap + 1..edges.len() {
            let d = closest_points(&points[i], &points[i + 1], &points[j], &points[j + 1]).distance;
            if d < 2.0 * radius * (1.0 - START_OVERLAP) {
                return Err(format!(
                    "segments {i} and {j} are {d:.4e} m apart, closer than 2h = {:.4e} m by more than {} %",
                    2.0 * radius,
                    100.0 * START_OVERLAP
                ));
            }
        }
    }
    Ok(())
}
