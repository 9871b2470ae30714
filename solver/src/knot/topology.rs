//! Topology check: the knot determinant `|Delta(-1)|` of a polygonal curve.
//!
//! The closed polygon is projected along a generic direction; the crossings of
//! the diagram (found by a sweep over the projected segments, `O(N log N + k)`
//! for `N` segments and `k` overlapping pairs) cut it into `c` arcs, one per
//! crossing. Each crossing gives the row `2 x_over - x_in - x_out` of the Fox
//! colouring matrix, which is the Alexander matrix at `t = -1`; the knot
//! determinant is `|det|` of any `(c-1) x (c-1)` minor (1 for `c <= 1`). The
//! minor is evaluated exactly modulo two 62-bit primes and recombined (exact
//! for `|det| < 2^121`). A projection is rejected as degenerate when a crossing
//! lies on a vertex, two crossings or two segments coincide in the diagram, or
//! the two strands of a crossing touch in space; the direction is then tilted
//! deterministically and the diagram rebuilt.
//!
//! Open curves (the clamped rod) are closed first, see [`close_open_curve`].
//! The overhand knot with `n` passes closes to the `(2, 2n+1)` torus knot, whose
//! determinant is [`expected_determinant`]`(n) = 2n + 1`.
use nalgebra::{Matrix3, SymmetricEigen, Vector2, Vector3};
use thiserror::Error;

/// Projection directions tried before giving up.
pub const MAX_ATTEMPTS: usize = 16;

/// Relative tolerance of the diagram: segment parameters within it of a vertex,
/// and depths within it (times the curve's size) of each other, are degenerate.
const TOLERANCE: f64 = 1e-9;

/// Two primes below `2^62`; the determinant is computed modulo each.
pub(super) const PRIMES: [u64; 2] = [(1 << 61) - 1, (1 << 62) - 57];

/// Why the determinant could not be computed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum TopologyError {
    #[error("a curve needs at least {min} points, got {got}")]
    TooFewPoints { got: usize, min: usize },
    #[error("point {0} is not finite")]
    NonFinite(usize),
    #[error("the end points of the open curve coincide: no pulling axis")]
    DegenerateAxis,
    #[error("projection direction must be finite and non-zero")]
    InvalidDirection,
    #[error("the projection is degenerate (crossing at a vertex, overlapping segments, or touching strands)")]
    DegenerateProjection,
    #[error("no generic projection in {0} directions: the curve probably touches itself")]
    NoGenericProjection(usize),
    #[error("the knot determinant does not fit in 64 bits")]
    Overflow,
}

/// Determinant of the `(2, 2n+1)` torus knot, the closure of the overhand knot
/// with `n` passes: `2n + 1`.
pub fn expected_determinant(n: u32) -> u64 {
    2 * u64::from(n) + 1
}

/// Knot determinant of an open polyline whose end nodes lie on the pulling
/// axis, closed as in [`close_open_curve`]; the projection starts from the
/// normal of the best-fit plane of `points` (made perpendicular to the axis).
pub fn knot_determinant(points: &[Vector3<f64>]) -> Result<u64, TopologyError> {
    open_diagram(points, colouring_determinant)
}

/// Knot determinant of a closed polygon (the last point joins the first); the
/// projection starts from the normal of the best-fit plane of `points`.
pub fn closed_knot_determinant(points: &[Vector3<f64>]) -> Result<u64, TopologyError> {
    closed_diagram(points, colouring_determinant)
}

/// `invariant` of the first generic diagram of the open polyline `points`,
/// closed as in [`close_open_curve`] (the projections of [`knot_determinant`]).
pub(super) fn open_diagram<T>(
    points: &[Vector3<f64>],
    invariant: impl Fn(&[Crossing]) -> Result<T, TopologyError>,
) -> Result<T, TopologyError> {
    let (closed, direction) = closure(points)?;
    search(&closed, &direction, invariant)
}

/// `invariant` of the first generic diagram of the closed polygon `points`
/// (the projections of [`closed_knot_determinant`]).
pub(super) fn closed_diagram<T>(
    points: &[Vector3<f64>],
    invariant: impl Fn(&[Crossing]) -> Result<T, TopologyError>,
) -> Result<T, TopologyError> {
    validate(points, 3)?;
    search(points, &best_fit_normal(points), invariant)
}

/// `invariant` of the closed polygon's diagram along `direction` only;
/// [`TopologyError::DegenerateProjection`] if that diagram is not generic.
pub(super) fn diagram_along<T>(
    points: &[Vector3<f64>],
    direction: &Vector3<f64>,
    invariant: impl Fn(&[Crossing]) -> Result<T, TopologyError>,
) -> Result<T, TopologyError> {
    validate(points, 3)?;
    let norm = direction.norm();
    if !(norm.is_finite() && norm > 0.0) {
        return Err(TopologyError::InvalidDirection);
    }
    let crossings = crossings(points, &(direction / norm)).ok_or(TopologyError::DegenerateProjection)?;
    invariant(&crossings)
}

/// Knot determinant of a closed polygon from its projection along `direction`
/// only; [`TopologyError::DegenerateProjection`] if that diagram is not generic.
pub fn determinant_along(points: &[Vector3<f64>], direction: &Vector3<f64>) -> Result<u64, TopologyError> {
    diagram_along(points, direction, colouring_determinant)
}

/// Closes an open polyline: with `m` the midpoint of the end nodes, `u` the unit
/// pulling axis from the first to the last node and `R` the largest distance of
/// a node from `m`, appends `m + D u`, `m + D u + D w`, `m - D u + D w`,
/// `m - D u` (`D = 2R`, `w` a unit vector perpendicular to `u`, in the best-fit
/// plane of the curve when it is not perpendicular to `u`). The ends are thus
/// extended along the axis beyond the curve's bounding sphere and joined by a
/// path outside it, which crosses nothing; the knot type does not depend on
/// `w` as long as the two extensions miss the curve.
pub fn close_open_curve(points: &[Vector3<f64>]) -> Result<Vec<Vector3<f64>>, TopologyError> {
    closure(points).map(|(closed, _)| closed)
}

fn validate(points: &[Vector3<f64>], min: usize) -> Result<(), TopologyError> {
    if points.len() < min {
        return Err(TopologyError::TooFewPoints {
            got: points.len(),
            min,
        });
    }
    match points.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
        Some(i) => Err(TopologyError::NonFinite(i)),
        None => Ok(()),
    }
}

/// The closed polygon of [`close_open_curve`] and the preferred projection
/// direction (perpendicular to the axis and to the closing rectangle).
fn closure(points: &[Vector3<f64>]) -> Result<(Vec<Vector3<f64>>, Vector3<f64>), TopologyError> {
    validate(points, 2)?;
    let (first, last) = (points[0], points[points.len() - 1]);
    let mid = 0.5 * (first + last);
    let radius = points.iter().map(|p| (p - mid).norm()).fold(0.0, f64::max);
    let axis = last - first;
    if axis.norm() <= TOLERANCE * radius {
        return Err(TopologyError::DegenerateAxis);
    }
    let u = axis.normalize();
    let normal = best_fit_normal(points);
    let d = normal - normal.dot(&u) * u;
    let direction = if d.norm() > 1e-6 {
        d.normalize()
    } else {
        perpendicular(&u)
    };
    let w = direction.cross(&u);
    let far = 2.0 * radius;
    let mut closed = points.to_vec();
    closed.extend([
        mid + far * u,
        mid + far * (u + w),
        mid + far * (w - u),
        mid - far * u,
    ]);
    Ok((closed, direction))
}

/// Unit normal of the least-squares plane through `points` (eigenvector of the
/// smallest eigenvalue of their covariance).
fn best_fit_normal(points: &[Vector3<f64>]) -> Vector3<f64> {
    let centroid = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let covariance = points.iter().fold(Matrix3::zeros(), |acc, p| {
        let d = p - centroid;
        acc + d * d.transpose()
    });
    let eigen = SymmetricEigen::new(covariance);
    eigen.eigenvectors.column(eigen.eigenvalues.imin()).into_owned()
}

/// A unit vector perpendicular to the unit vector `v`.
fn perpendicular(v: &Vector3<f64>) -> Vector3<f64> {
    let axis = Vector3::ith(v.iamin(), 1.0);
    v.cross(&axis).normalize()
}

/// Tries `start` tilted by a fixed sequence of small angles until a diagram is
/// generic, and gives `invariant` of its crossings.
fn search<T>(
    points: &[Vector3<f64>],
    start: &Vector3<f64>,
    invariant: impl Fn(&[Crossing]) -> Result<T, TopologyError>,
) -> Result<T, TopologyError> {
    let e1 = perpendicular(start);
    let e2 = start.cross(&e1);
    for k in 0..MAX_ATTEMPTS {
        let tilt = 0.0137 + 0.05 * k as f64;
        let azimuth = 0.5 + 2.399_963 * k as f64;
        let side = azimuth.cos() * e1 + azimuth.sin() * e2;
        let direction = tilt.cos() * start + tilt.sin() * side;
        if let Some(crossings) = crossings(points, &direction) {
            return invariant(&crossings);
        }
    }
    Err(TopologyError::NoGenericProjection(MAX_ATTEMPTS))
}

/// One crossing: curve positions (segment index + parameter) of the over and
/// under strands, and its sign (right-handed: the under strand passes from
/// the over strand's right to its left, seen from the viewer).
#[derive(Clone, Copy, Debug)]
pub(super) struct Crossing {
    pub(super) over: f64,
    pub(super) under: f64,
    pub(super) positive: bool,
}

/// The arc (0..c) through curve position `x` of a diagram whose under-passes
/// are the sorted `unders`: arc k runs from the (k-1)-th to the k-th
/// under-pass in curve order, so it is the number of under-passes before `x`,
/// mod c.
pub(super) fn arc_of(unders: &[f64], x: f64) -> usize {
    unders.partition_point(|&u| u < x) % unders.len()
}

/// The crossings of the closed polygon projected along `direction`, or `None`
/// if the diagram is not generic.
fn crossings(points: &[Vector3<f64>], direction: &Vector3<f64>) -> Option<Vec<Crossing>> {
    let n = points.len();
    let e1 = perpendicular(direction);
    let e2 = direction.cross(&e1);
    let plane: Vec<Vector2<f64>> = points
        .iter()
        .map(|p| Vector2::new(p.dot(&e1), p.dot(&e2)))
        .collect();
    let depth: Vec<f64> = points.iter().map(|p| p.dot(direction)).collect();
    let centroid = points.iter().sum::<Vector3<f64>>() / n as f64;
    let size = points.iter().map(|p| (p - centroid).norm()).fold(0.0, f64::max);
    let depth_tol = TOLERANCE * size;
    // Sweep: segments sorted by their lowest projected x, each compared with
    // the following ones whose x-interval starts before its own ends.
    let lo_x = |i: usize| plane[i].x.min(plane[(i + 1) % n].x);
    let hi_x = |i: usize| plane[i].x.max(plane[(i + 1) % n].x);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| lo_x(a).total_cmp(&lo_x(b)));
    let mut found = Vec::new();
    for (k, &i) in order.iter().enumerate() {
        let end = hi_x(i);
        for &j in order[k + 1..].iter().take_while(|&&j| lo_x(j) <= end) {
            let adjacent = j == (i + 1) % n || i == (j + 1) % n;
            if adjacent {
                continue;
            }
            match segment_crossing(&plane, i, j) {
                Intersection::None => {}
                Intersection::Degenerate => return None,
                Intersection::At(t, s) => {
                    let di = depth[i] + t * (depth[(i + 1) % n] - depth[i]);
                    let dj = depth[j] + s * (depth[(j + 1) % n] - depth[j]);
                    if (di - dj).abs() <= depth_tol {
                        return None;
                    }
                    let (pi, pj) = (i as f64 + t, j as f64 + s);
                    let turn = (plane[(i + 1) % n] - plane[i]).perp(&(plane[(j + 1) % n] - plane[j]));
                    // Viewed from +direction (the over strand nearer): the
                    // under strand crosses from the over strand's right to
                    // its left when turn(over, under) > 0.
                    found.push(if di > dj {
                        Crossing {
                            over: pi,
                            under: pj,
                            positive: turn > 0.0,
                        }
                    } else {
                        Crossing {
                            over: pj,
                            under: pi,
                            positive: turn < 0.0,
                        }
                    });
                }
            }
        }
    }
    // Two crossings at one point of the curve (a triple point) are degenerate.
    let mut positions: Vec<f64> = found.iter().flat_map(|c| [c.over, c.under]).collect();
    positions.sort_by(f64::total_cmp);
    let distinct = positions.windows(2).all(|w| w[1] - w[0] > TOLERANCE);
    distinct.then_some(found)
}

enum Intersection {
    None,
    /// Parameters along segments `i` and `j`, strictly inside both.
    At(f64, f64),
    Degenerate,
}

/// Intersection of projected segments `i` and `j` (closed polygon).
fn segment_crossing(plane: &[Vector2<f64>], i: usize, j: usize) -> Intersection {
    let n = plane.len();
    let (p, q) = (plane[i], plane[j]);
    let r = plane[(i + 1) % n] - p;
    let v = plane[(j + 1) % n] - q;
    let w = q - p;
    let denom = r.perp(&v);
    let scale = r.norm() * v.norm();
    if denom.abs() <= TOLERANCE * scale {
        // Parallel: degenerate only if collinear and overlapping.
        let collinear = w.perp(&r).abs() <= TOLERANCE * r.norm() * (w.norm() + r.norm());
        let rr = r.norm_squared();
        let (a, b) = (w.dot(&r) / rr, (w + v).dot(&r) / rr);
        let overlap = a.min(b) <= 1.0 + TOLERANCE && a.max(b) >= -TOLERANCE;
        return if collinear && overlap {
            Intersection::Degenerate
        } else {
            Intersection::None
        };
    }
    let t = w.perp(&v) / denom;
    let s = w.perp(&r) / denom;
    let outside = |x: f64| !(-TOLERANCE..=1.0 + TOLERANCE).contains(&x);
    let near_vertex = |x: f64| !(TOLERANCE..=1.0 - TOLERANCE).contains(&x);
    if outside(t) || outside(s) {
        Intersection::None
    } else if near_vertex(t) || near_vertex(s) {
        Intersection::Degenerate
    } else {
        Intersection::At(t, s)
    }
}

/// `|det|` of the colouring matrix with its last row and column removed.
pub(super) fn colouring_determinant(crossings: &[Crossing]) -> Result<u64, TopologyError> {
    let c = crossings.len();
    if c <= 1 {
        return Ok(1);
    }
    let mut unders: Vec<f64> = crossings.iter().map(|x| x.under).collect();
    unders.sort_by(f64::total_cmp);
    let arc = |x: f64| arc_of(&unders, x);
    let m = c - 1;
    let mut matrix = vec![0i64; m * m];
    for (row, crossing) in crossings.iter().take(m).enumerate() {
        let incoming = arc(crossing.under);
        let entries = [(arc(crossing.over), 2), (incoming, -1), ((incoming + 1) % c, -1)];
        for (col, value) in entries {
            if col < m {
                matrix[row * m + col] += value;
            }
        }
    }
    let residues = PRIMES.map(|p| det_mod(&matrix, m, p));
    u64::try_from(recombine(residues).unsigned_abs()).map_err(|_| TopologyError::Overflow)
}

/// The integer `x`, `|x| < p0 p1 / 2`, with the given residues modulo
/// [`PRIMES`] (Chinese remainder).
pub(super) fn recombine(residues: [u64; 2]) -> i128 {
    let (p0, p1) = (u128::from(PRIMES[0]), u128::from(PRIMES[1]));
    // x = r0 + p0 * ((r1 - r0) / p0 mod p1), 0 <= x < p0 p1.
    let r0 = u128::from(residues[0]);
    let diff = (u128::from(residues[1]) + p1 - r0 % p1) % p1;
    let k = mul_mod(
        diff as u64,
        pow_mod((p0 % p1) as u64, PRIMES[1] - 2, PRIMES[1]),
        PRIMES[1],
    );
    let x = r0 + p0 * u128::from(k);
    let modulus = p0 * p1;
    if x > modulus / 2 {
        -((modulus - x) as i128)
    } else {
        x as i128
    }
}

pub(super) fn mul_mod(a: u64, b: u64, p: u64) -> u64 {
    (u128::from(a) * u128::from(b) % u128::from(p)) as u64
}

pub(super) fn pow_mod(mut base: u64, mut exp: u64, p: u64) -> u64 {
    let mut acc = 1;
    while exp > 0 {
        if exp & 1 == 1 {
            acc = mul_mod(acc, base, p);
        }
        base = mul_mod(base, base, p);
        exp >>= 1;
    }
    acc
}

/// Determinant of the `m x m` row-major integer matrix modulo the prime `p`
/// (Gaussian elimination).
pub(super) fn det_mod(matrix: &[i64], m: usize, p: u64) -> u64 {
    let mut a: Vec<u64> = matrix.iter().map(|&x| x.rem_euclid(p as i64) as u64).collect();
    let mut det = 1;
    for col in 0..m {
        let Some(pivot) = (col..m).find(|&r| a[r * m + col] != 0) else {
            // A zero column: the matrix is singular modulo p, its determinant 0.
            return 0;
        };
        if pivot != col {
            for k in col..m {
                a.swap(pivot * m + k, col * m + k);
            }
            det = p - det;
        }
        let lead = a[col * m + col];
        det = mul_mod(det, lead, p);
        let inv = pow_mod(lead, p - 2, p);
        for r in col + 1..m {
            let factor = mul_mod(a[r * m + col], inv, p);
            if factor == 0 {
                continue;
            }
            for k in col..m {
                let sub = mul_mod(factor, a[col * m + k], p);
                a[r * m + k] = (a[r * m + k] + p - sub) % p;
            }
        }
    }
    det % p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modular_determinant_matches_integer_determinant() {
        // det = 2 (32 - 35) + (24 + 30) = 48; swapping two rows negates it.
        let m = [2, -1, 0, 3, 4, 5, -6, 7, 8];
        let swapped = [3, 4, 5, 2, -1, 0, -6, 7, 8];
        for p in PRIMES {
            assert_eq!(det_mod(&m, 3, p), 48);
            assert_eq!(det_mod(&swapped, 3, p), p - 48);
        }
        assert_eq!(det_mod(&[1, 2, 2, 4], 2, PRIMES[0]), 0);
    }

    #[test]
    fn colouring_matrix_of_standard_trefoil_diagram() {
        // Standard trefoil diagram: positions 0..6 along the curve alternate
        // over (even) and under (odd).
        let crossings = [
            Crossing {
                over: 0.5,
                under: 3.5,
                positive: true,
            },
            Crossing {
                over: 2.5,
                under: 5.5,
                positive: true,
            },
            Crossing {
                over: 4.5,
                under: 1.5,
                positive: true,
            },
        ];
        assert_eq!(colouring_determinant(&crossings), Ok(3));
        assert_eq!(colouring_determinant(&crossings[..1]), Ok(1));
    }
}
