//! A user's start shape, checked like a built knot.
use super::StartShape;
use super::alexander::{Alexander, alexander};
use crate::contact::Geometry;
use crate::contact::broad_phase::{BroadPhase, neighbour_gap, polyline_segments};
use crate::contact::curve::{Piece, closest_points_from};
use nalgebra::Vector3;

/// A user's start shape for a rod of `length`, `nodes` and `radius` h
/// tied in the knot `name` of Alexander polynomial `expected`: a
/// [`checked_rod`], every node between the two ends along the line joining
/// them (the clamps hold the ends), its surface clear of itself as the
/// contact `geometry` sees it ([`check_rods_clearance`]), and the knot's
/// Alexander polynomial. The error is the reason, in words.
pub fn checked_start(
    points: &[[f64; 3]],
    (length, nodes, radius): (f64, usize, f64),
    geometry: Geometry,
    name: &str,
    expected: &Alexander,
) -> Result<StartShape, String> {
    let points = checked_rod(points, (length, nodes))?;
    check_between_ends(&points)?;
    check_rods_clearance(std::slice::from_ref(&points), radius, geometry)?;
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

/// No two pieces of different rods, nor two non-neighbouring pieces of one
/// rod, closer than 2h (`radius` h), less [`START_OVERLAP`], measured
/// between the centre lines the contact `geometry` computes contacts on
/// (the chords, or the smooth curves through the nodes, which a state the
/// smooth contact relaxed holds apart where its chords come closer): the
/// clearance of a start of one rod or several ([`checked_rod`] each).
pub fn check_rods_clearance(
    rods: &[Vec<Vector3<f64>>],
    radius: f64,
    geometry: Geometry,
) -> Result<(), String> {
    let shortest = (rods.iter())
        .flat_map(|rod| rod.windows(2).map(|w| (w[1] - w[0]).norm()))
        .fold(f64::INFINITY, f64::min);
    match closest_surfaces(rods, radius, shortest, geometry) {
        Some(Approach {
            distance: d,
            a: (a, i),
            b: (b, j),
        }) if d < 2.0 * radius * (1.0 - START_OVERLAP) => {
            let pieces = match rods.len() {
                1 => format!("segments {i} and {j}"),
                _ => format!("rod {a}'s segment {i} and rod {b}'s segment {j}"),
            };
            Err(format!(
                "{pieces} are {d:.4e} m apart, closer than 2h = {:.4e} m by more than {} %",
                2.0 * radius,
                100.0 * START_OVERLAP
            ))
        }
        _ => Ok(()),
    }
}

/// Two pieces' closest approach: their centre lines' distance and each
/// piece as (rod, segment index).
struct Approach {
    distance: f64,
    a: (usize, usize),
    b: (usize, usize),
}

/// The closest approach of the rods' centre lines (radius `h`, shortest
/// edge `edge`) between non-neighbouring pieces as `geometry` computes it;
/// `None` if none come within 2h of each other's chords plus the curves'
/// largest deviation from them.
fn closest_surfaces(rods: &[Vec<Vector3<f64>>], h: f64, edge: f64, geometry: Geometry) -> Option<Approach> {
    let segments: Vec<_> = (rods.iter().enumerate())
        .flat_map(|(body, points)| polyline_segments(points, h, body))
        .collect();
    let piece = |rod: usize, e: usize| Piece::new(rods[rod].len(), e, |i| rods[rod][i]);
    let deviation = match geometry {
        Geometry::Segment => 0.0,
        Geometry::Smooth => (segments.iter())
            .map(|s| piece(s.body, s.index).chord_deviation_bound())
            .fold(0.0, f64::max),
    };
    let gaps = vec![neighbour_gap(2.0 * h, edge); rods.len()];
    let mut broad = BroadPhase::new();
    let pairs = broad
        .find_pairs(&segments, &gaps, 2.0 * deviation)
        .expect("valid segments");
    (pairs.iter())
        .map(|p| {
            let (a, b) = (&segments[p.i], &segments[p.j]);
            let d = match geometry {
                Geometry::Segment => p.closest.distance,
                Geometry::Smooth => {
                    let (pa, pb) = (piece(a.body, a.index), piece(b.body, b.index));
                    closest_points_from(&pa, &pb, (p.closest.s, p.closest.t)).distance
                }
            };
            Approach {
                distance: d,
                a: (a.body, a.index),
                b: (b.body, b.index),
            }
        })
        .min_by(|x, y| x.distance.total_cmp(&y.distance))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A short straight rod inside the bend of another, whose nodes lie on a
    /// circle of radius R with the edges turning by a, facing the chord at
    /// the bend's foot: that chord sags s = R (1 - cos(a / 2)) inside the
    /// circle and the smooth curve about half as far (`contact::curve`). The
    /// straight rod 2h (1 - 2 %) from the chord overlaps it by more than
    /// `START_OVERLAP` and lies about s / 2 further from the curve, clear of
    /// it; a sag closer it overlaps both.
    #[test]
    fn clearance_is_measured_on_the_contact_geometry() {
        let (h, radius, turn) = (1e-3, 0.02, 0.3_f64);
        let bend: Vec<Vector3<f64>> = (-4..=3)
            .map(|k| {
                let angle = -std::f64::consts::FRAC_PI_2 + (f64::from(k) + 0.5) * turn;
                Vector3::new(radius * angle.cos(), radius * angle.sin(), 0.0)
            })
            .collect();
        let sag = radius * (1.0 - (turn / 2.0).cos());
        let chord = -radius * (turn / 2.0).cos();
        let line = |from_chord: f64| -> Vec<Vector3<f64>> {
            let half = radius * (turn / 2.0).sin() / 2.0;
            (-1..=1)
                .map(|k| Vector3::new(half * f64::from(k), chord + from_chord, 0.0))
                .collect()
        };
        let near = vec![bend.clone(), line(2.0 * h * 0.98)];
        assert!(2.0 * h * 0.98 + sag / 2.0 > 2.0 * h * (1.0 - START_OVERLAP));
        let refused = check_rods_clearance(&near, h, Geometry::Segment).unwrap_err();
        assert!(
            refused.contains("rod 0's segment 3 and rod 1's segment"),
            "{refused}"
        );
        assert_eq!(check_rods_clearance(&near, h, Geometry::Smooth), Ok(()));
        let closer = vec![bend, line(2.0 * h * 0.98 - sag)];
        assert!(check_rods_clearance(&closer, h, Geometry::Smooth).is_err());
    }
}
