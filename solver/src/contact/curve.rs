//! Smooth contact geometry: each rod's centre line as the C1 curve through
//! its nodes, and the closest points of two of its pieces.
//!
//! Piece `e` of a rod runs from the smoothed node `Q_e` (`u = 0`) to `Q_(e+1)`
//! (`u = 1`), `Q_i = P_i + c ((P_(i-1) + P_(i+1)) / 2 - P_i)` with
//! `c =` [`SMOOTHING`]: the cubic Hermite interpolant whose tangent at node
//! `i` is the fourth-order central difference
//! `(P_(i-2) - 8 P_(i-1) + 8 P_(i+1) - P_(i+2)) / 12`, so each point is a
//! fixed combination of the six nodes `e - 2 ... e + 3`, and neighbouring
//! pieces join with one point and one tangent (C1). Past an end a missing
//! node is the reflection `P_(-k) = 2 P_0 - P_k` (its weight folds into the
//! nodes it is made of), so an end piece leaves straight from the end node
//! (`Q_0 = P_0`). On a polygon inscribed in a circle of radius `R` whose
//! edges turn by `a`, the chords fall short of the circle by their sag
//! `s = R (1 - cos(a / 2))`, about `a^2 R / 8`; the curve through the nodes
//! themselves (`c = 0`) would stray from the circle by at most about
//! `0.006 a^4 R` (`a <= 1`; 56 times less than the sag at `a = 0.7`, an
//! edge of 2.08 h on a bend of radius 3 h), and the smoothed nodes lie
//! `c R (1 - cos a)`, about `4 c s`, inside it: with `c = 1 / 8` the curve
//! runs half the sag inside the circle, midway between it and the chords
//! (docs/FIDELITY.md, "A curve between the chords and the circle").
//!
//! The closest points of two pieces minimise `f(s, t) = |A(s) - B(t)|^2 / 2`
//! over `[0, 1]^2`; Newton's method with the exact Hessian, safeguarded to a
//! descent step and projected on the square, starts from the chords' closest
//! points ([`super::segment::closest_points`]). Gap, normal, contact points
//! and the weights that carry a contact force to the nodes then all vary
//! smoothly as one rod slides along another, where the chords' have kinks at
//! every node.
use super::segment::closest_points;
use nalgebra::Vector3;

/// Nodes a piece's point depends on: `(e, e + 1, e - 1, e + 2, e - 2,
/// e + 3)`, the piece's own two first (as a segment's).
pub const STENCIL: usize = 6;

/// How far each node moves towards its neighbours' midpoint before the
/// curve interpolates it: half the chords' sag inside the circle through
/// the nodes (module doc). n = 3's inversion then moves by 1.0 in l_k bar
/// from the paper's K = 301 to 601, where the curve through the nodes
/// moves by 4.2 (docs/FIDELITY.md).
pub const SMOOTHING: f64 = 1.0 / 8.0;

/// Node offsets from `e` in stencil order.
const OFFSETS: [isize; STENCIL] = [0, 1, -1, 2, -2, 3];

/// A piece of a rod's C1 centre line: its control points and the rod's
/// nodes (local ids) that carry them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Piece {
    /// Control points `P_(e + OFFSETS_k)`, reflected through the end node
    /// past an end (`P_(-k) = 2 P_0 - P_k`).
    control: [Vector3<f64>; STENCIL],
    /// Local node ids in stencil order; past an end, the end node (weight
    /// zero: a reflected point's weight folds into the nodes it is made of).
    pub nodes: [usize; STENCIL],
    /// The rod's node count.
    rod_nodes: usize,
    /// The piece in powers of `u`: `x(u) = sum_j power_j u^j`.
    power: [Vector3<f64>; 4],
}

/// A point of a piece: position, first and second derivatives in `u`.
#[derive(Debug, Clone, Copy)]
struct Jet {
    x: Vector3<f64>,
    dx: Vector3<f64>,
    ddx: Vector3<f64>,
}

/// The weights of the control points (stencil order) at `u` for the
/// cubic Hermite interpolant between the smoothed nodes `Q_e` and
/// `Q_(e+1)` ([`SMOOTHING`]) whose tangents are the nodes' fourth-order
/// central differences `m_i = (P_(i-2) - 8 P_(i-1) + 8 P_(i+1) - P_(i+2)) / 12`,
/// given the Hermite basis `(h00, h10, h01, h11)` at `u` (or its derivatives).
#[inline]
const fn combine([h00, h10, h01, h11]: [f64; 4]) -> [f64; STENCIL] {
    let c = SMOOTHING;
    let (a, b) = (h10 / 12.0, h11 / 12.0);
    let (p, q) = (0.5 * c * h00, 0.5 * c * h01);
    [
        (1.0 - c) * h00 + q - 8.0 * b,
        p + (1.0 - c) * h01 + 8.0 * a,
        p - 8.0 * a + b,
        q - a + 8.0 * b,
        a,
        -b,
    ]
}

/// The control points' weights in powers of `u`: row `j` holds the
/// coefficients of `u^j` in [`combine`] of the Hermite basis
/// `h00 = 1 - 3u^2 + 2u^3`, `h10 = u - 2u^2 + u^3`, `h01 = 3u^2 - 2u^3`,
/// `h11 = u^3 - u^2`.
const POWERS: [[f64; STENCIL]; 4] = [
    combine([1.0, 0.0, 0.0, 0.0]),
    combine([0.0, 1.0, 0.0, 0.0]),
    combine([-3.0, -2.0, 3.0, -1.0]),
    combine([2.0, 1.0, -2.0, 1.0]),
];

/// Control-point weights at `u` (the Hermite basis in [`combine`]).
#[inline]
fn basis(u: f64) -> [f64; STENCIL] {
    let (u2, u3) = (u * u, u * u * u);
    combine([
        2.0 * u3 - 3.0 * u2 + 1.0,
        u3 - 2.0 * u2 + u,
        -2.0 * u3 + 3.0 * u2,
        u3 - u2,
    ])
}

/// Whether piece `e` of a rod of `n` nodes has its whole stencil inside
/// the rod (no reflected node).
#[inline]
fn interior(n: usize, e: usize) -> bool {
    e >= 2 && e + 3 < n
}

/// Node `e + o` of a rod of `n` nodes, clamped to the rod.
#[inline]
fn clamp_node(n: usize, e: usize, o: isize) -> usize {
    (e as isize + o).clamp(0, n as isize - 1) as usize
}

/// For each control point of an end piece `e` (stencil `nodes`), the
/// nodes it is made of: `(slot, factor)` pairs, the second `factor` zero
/// where the point is a node itself; past an end `P_(-k) = 2 P_0 - P_k`.
fn folds(n: usize, e: usize, nodes: &[usize; STENCIL]) -> [[(usize, f64); 2]; STENCIL] {
    let last = n as isize - 1;
    let slot = |i: usize| nodes.iter().position(|&k| k == i).unwrap_or(0);
    OFFSETS.map(|o| {
        let i = e as isize + o;
        if i < 0 {
            [(slot(0), 2.0), (slot(clamp_node(n, 0, -i)), -1.0)]
        } else if i > last {
            [
                (slot(last as usize), 2.0),
                (slot(clamp_node(n, 0, 2 * last - i)), -1.0),
            ]
        } else {
            [(slot(i as usize), 1.0), (0, 0.0)]
        }
    })
}

/// Piece `e`'s local node ids in stencil order and control points, of the
/// centre line through the `n` nodes `node(0..n)` (`e + 1 < n`).
#[inline]
fn control_points(
    n: usize,
    e: usize,
    node: impl Fn(usize) -> Vector3<f64>,
) -> ([usize; STENCIL], [Vector3<f64>; STENCIL]) {
    debug_assert!(e + 1 < n);
    if interior(n, e) {
        let nodes = OFFSETS.map(|o| e.wrapping_add_signed(o));
        let mut control = [Vector3::zeros(); STENCIL];
        for (c, &i) in control.iter_mut().zip(&nodes) {
            *c = node(i);
        }
        (nodes, control)
    } else {
        let nodes = OFFSETS.map(|o| clamp_node(n, e, o));
        let folds = folds(n, e, &nodes);
        let control = std::array::from_fn(|k| {
            let [(a, fa), (b, fb)] = folds[k];
            let p = fa * node(nodes[a]);
            if fb == 0.0 { p } else { p + fb * node(nodes[b]) }
        });
        (nodes, control)
    }
}

/// [`Piece::chord_deviation_bound`] of the piece with control points `c`.
#[inline]
fn deviation_bound(c: &[Vector3<f64>; STENCIL]) -> f64 {
    // Stencil order: e, e+1, e-1, e+2, e-2, e+3.
    let d = c[1] - c[0];
    let m0 = (c[4] - 8.0 * c[2] + 8.0 * c[1] - c[3]) / 12.0;
    let m1 = (c[2] - 8.0 * c[0] + 8.0 * c[3] - c[5]) / 12.0;
    let d0 = SMOOTHING * (0.5 * (c[2] + c[1]) - c[0]);
    let d1 = SMOOTHING * (0.5 * (c[0] + c[3]) - c[1]);
    d0.norm().max(d1.norm()) + 4.0 / 27.0 * ((m0 - d).norm() + (m1 - d).norm())
}

/// [`Piece::chord_deviation_bound`] of piece `e` of the centre line through
/// the `n` nodes `node(0..n)`, without building the piece.
#[inline]
pub fn chord_deviation_bound(n: usize, e: usize, node: impl Fn(usize) -> Vector3<f64>) -> f64 {
    deviation_bound(&control_points(n, e, node).1)
}

impl Piece {
    /// Piece `e` of the centre line through the `n` nodes `node(0..n)`
    /// (`e + 1 < n`).
    #[inline]
    pub fn new(n: usize, e: usize, node: impl Fn(usize) -> Vector3<f64>) -> Self {
        let (nodes, control) = control_points(n, e, node);
        let mut power = [Vector3::zeros(); 4];
        for (x, w) in power.iter_mut().zip(&POWERS) {
            *x = w[0] * control[0];
            for k in 1..STENCIL {
                *x += w[k] * control[k];
            }
        }
        Self {
            control,
            nodes,
            rod_nodes: n,
            power,
        }
    }

    #[inline]
    fn jet(&self, u: f64) -> Jet {
        let [a0, a1, a2, a3] = &self.power;
        Jet {
            x: ((a3 * u + a2) * u + a1) * u + a0,
            dx: (a3 * (3.0 * u) + a2 * 2.0) * u + a1,
            ddx: a3 * (6.0 * u) + a2 * 2.0,
        }
    }

    /// The point at `u`.
    pub fn point(&self, u: f64) -> Vector3<f64> {
        self.jet(u).x
    }

    /// The unit tangent at `u`.
    pub fn tangent(&self, u: f64) -> Vector3<f64> {
        self.jet(u).dx.normalize()
    }

    /// The weights of [`Piece::nodes`] at `u`: the point is
    /// `sum_k weights_k x_(nodes_k)`, and a force `F` there puts
    /// `weights_k F` on node `nodes_k`.
    pub fn weights(&self, u: f64) -> [f64; STENCIL] {
        let b = basis(u);
        let (n, e) = (self.rod_nodes, self.nodes[0]);
        if interior(n, e) {
            return b;
        }
        let mut w = [0.0; STENCIL];
        for (k, fold) in folds(n, e, &self.nodes).iter().enumerate() {
            for &(slot, factor) in fold {
                w[slot] += factor * b[k];
            }
        }
        w
    }

    /// The largest distance between the piece and its chord is at most
    /// this: the curve less the chord is `h00(u) (Q_e - P_e) + h01(u)
    /// (Q_(e+1) - P_(e+1)) + h10(u) (m_0 - d) + h11(u) (m_1 - d)` with
    /// `d = P_(e+1) - P_e`, `h00, h01 >= 0` summing to 1 and
    /// `|h10|, |h11| <= 4 / 27`.
    pub fn chord_deviation_bound(&self) -> f64 {
        deviation_bound(&self.control)
    }
}

/// Closest points of two pieces: parameters, points and distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvePair {
    /// Parameter on piece A, in `[0, 1]`.
    pub s: f64,
    /// Parameter on piece B, in `[0, 1]`.
    pub t: f64,
    /// `A(s)`.
    pub point_a: Vector3<f64>,
    /// `B(t)`.
    pub point_b: Vector3<f64>,
    /// `|A(s) - B(t)|`.
    pub distance: f64,
}

/// Newton iterations at most; each costs two piece evaluations.
const MAX_ITERATIONS: usize = 12;

/// Newton stops when its step is below this (in the pieces' parameters).
const STEP_TOL: f64 = 1e-12;

/// Newton stops when a step changes the squared distance by less than this
/// fraction of it (round-off's scale).
const GAIN_TOL: f64 = 1e-14;

/// Newton steps are at most this long in each parameter (a quarter piece),
/// so that a step never leaps past a nearby minimum.
const MAX_STEP: f64 = 0.25;

/// In a flat valley of the distance (its curvature in the free parameters,
/// scaled to unit Gauss-Newton diagonal, below [`FLAT_CURVATURE`]: a rope
/// wrapped on a rod, a curve nearly concentric with its partner), a Newton
/// step is taken only if it shortens the distance by at least this fraction
/// of the shorter piece's chord. There the distance varies by less than that
/// over a whole piece, and chasing its variations moved the contact point
/// across its piece from one step to the next and shook the rope off the
/// capstan's law (docs/FIDELITY.md, "The smooth geometry on the capstan").
const FLAT_DISTANCE: f64 = 1e-3;

/// The scaled curvature below which the distance's valley is flat
/// ([`FLAT_DISTANCE`]); a crossing's is about 1.
const FLAT_CURVATURE: f64 = 0.05;

/// Closest points of pieces `a` and `b`, from the closest points of their
/// chords.
pub fn closest_points_on_pieces(a: &Piece, b: &Piece) -> CurvePair {
    let chord = closest_points(&a.control[0], &a.control[1], &b.control[0], &b.control[1]);
    closest_points_from(a, b, (chord.s, chord.t))
}

/// Closest points of pieces `a` and `b` from the parameters `start` (the
/// closest points of their chords, where the caller has them).
pub fn closest_points_from(a: &Piece, b: &Piece, start: (f64, f64)) -> CurvePair {
    let (mut s, mut t) = start;
    let (mut ja, mut jb) = (a.jet(s), b.jet(t));
    for _ in 0..MAX_ITERATIONS {
        let d = ja.x - jb.x;
        // Gradient and Hessian of f(s, t) = |A(s) - B(t)|^2 / 2.
        let (gs, gt) = (d.dot(&ja.dx), -d.dot(&jb.dx));
        let (aa, bb) = (ja.dx.norm_squared(), jb.dx.norm_squared());
        let hss = aa + d.dot(&ja.ddx);
        let htt = bb - d.dot(&jb.ddx);
        let hst = -ja.dx.dot(&jb.dx);
        // Variables held at a bound that the gradient pushes against stay there.
        let hold_s = (s <= 0.0 && gs > 0.0) || (s >= 1.0 && gs < 0.0);
        let hold_t = (t <= 0.0 && gt > 0.0) || (t >= 1.0 && gt < 0.0);
        // A step, clamped, with its jets and squared distance.
        let trial = |(ds, dt): (f64, f64)| {
            let s1 = (s + ds.clamp(-MAX_STEP, MAX_STEP)).clamp(0.0, 1.0);
            let t1 = (t + dt.clamp(-MAX_STEP, MAX_STEP)).clamp(0.0, 1.0);
            let (ja1, jb1) = (a.jet(s1), b.jet(t1));
            (s1, t1, ja1, jb1, (ja1.x - jb1.x).norm_squared())
        };
        // In a flat valley a step along its floor must shorten the distance
        // by FLAT_DISTANCE chords (in squares; per unit of the scaled
        // parameters, whose unit is a chord, and in the pieces' own).
        let f0 = d.norm_squared();
        let per_chord = 2.0 * f0.sqrt() * FLAT_DISTANCE;
        let gain = per_chord * aa.min(bb).sqrt();
        let (s1, t1, ja1, jb1, f1) = match (hold_s, hold_t) {
            (true, true) => break,
            (true, false) | (false, true) => {
                let (step, curvature) = if hold_s {
                    ((0.0, -gt / safe_curvature(htt, bb)), htt / bb)
                } else {
                    ((-gs / safe_curvature(hss, aa), 0.0), hss / aa)
                };
                let next = trial(step);
                if curvature.abs() < FLAT_CURVATURE && f0 - next.4 < gain {
                    break;
                }
                next
            }
            (false, false) => {
                let full = || trial(newton_2x2(gs, gt, hss, hst, htt, aa, bb));
                let flat = smallest_scaled_curvature(hss, hst, htt, aa, bb).abs() < FLAT_CURVATURE;
                match flat.then(|| stiff_step(gs, gt, hss, hst, htt, aa, bb)) {
                    None => full(),
                    // The floor's slope could not gain FLAT_DISTANCE chords
                    // within a step of MAX_STEP: the stiff step alone.
                    Some(Some((stiff, slope))) if slope * MAX_STEP < per_chord => trial(stiff),
                    Some(Some((stiff, _))) => {
                        let (stiff, full) = (trial(stiff), full());
                        if stiff.4 - full.4 >= gain { full } else { stiff }
                    }
                    Some(None) => {
                        let full = full();
                        if f0 - full.4 < gain {
                            break;
                        }
                        full
                    }
                }
            }
        };
        let moved = (s1 - s).abs().max((t1 - t).abs());
        (s, t) = (s1, t1);
        (ja, jb) = (ja1, jb1);
        // Converged: the step no longer moves, or no longer changes the
        // distance measurably (a flat valley's stiff steps keep turning
        // with its floor).
        if moved <= STEP_TOL || (f0 - f1).abs() <= GAIN_TOL * f0 {
            break;
        }
    }
    let d = ja.x - jb.x;
    CurvePair {
        s,
        t,
        point_a: ja.x,
        point_b: jb.x,
        distance: d.norm(),
    }
}

/// A one-variable Newton denominator kept positive: the curvature `h`, at
/// least a small fraction of the Gauss-Newton term `g` (`|x'|^2`).
#[inline]
fn safe_curvature(h: f64, g: f64) -> f64 {
    h.max(1e-3 * g).max(f64::MIN_POSITIVE)
}

/// The smallest eigenvalue of the Hessian `[[hss, hst], [hst, htt]]` scaled
/// to unit Gauss-Newton diagonal (`aa`, `bb`).
#[inline]
fn smallest_scaled_curvature(hss: f64, hst: f64, htt: f64, aa: f64, bb: f64) -> f64 {
    let (p, q, r) = (hss / aa, hst / (aa * bb).sqrt(), htt / bb);
    0.5 * (p + r) - (0.25 * (p - r) * (p - r) + q * q).sqrt()
}

/// The Newton step of the 2 x 2 system restricted to its stiff eigenvector
/// (scaled to unit Gauss-Newton diagonal, eigenvalue at least
/// [`FLAT_CURVATURE`]): the step that does not move along a flat valley's
/// floor, and the gradient's component along the floor (in the scaled
/// parameters, whose unit is a chord); `None` when no direction is stiff.
#[inline]
fn stiff_step(gs: f64, gt: f64, hss: f64, hst: f64, htt: f64, aa: f64, bb: f64) -> Option<((f64, f64), f64)> {
    let (da, db) = (1.0 / aa.sqrt(), 1.0 / bb.sqrt());
    let (p, q, r) = (hss * da * da, hst * da * db, htt * db * db);
    let hi = 0.5 * (p + r) + (0.25 * (p - r) * (p - r) + q * q).sqrt();
    if hi < FLAT_CURVATURE {
        return None;
    }
    // The eigenvector of hi: (q, hi - p) or (hi - r, q), the better conditioned.
    let (x, y) = if (hi - p).abs() >= (hi - r).abs() {
        (q, hi - p)
    } else {
        (hi - r, q)
    };
    let norm = x.hypot(y);
    let (x, y) = (x / norm, y / norm);
    let (g1, g2) = (gs * da, gt * db);
    let along = -(x * g1 + y * g2) / hi;
    Some(((along * x * da, along * y * db), (y * g1 - x * g2).abs()))
}

/// The Newton step of the 2 x 2 system `[[hss, hst], [hst, htt]] d = -g`,
/// with the diagonal raised (Levenberg) until the matrix is safely positive
/// definite, so the step descends; `aa`, `bb` are the Gauss-Newton diagonal,
/// the scale of each variable.
#[inline]
fn newton_2x2(gs: f64, gt: f64, hss: f64, hst: f64, htt: f64, aa: f64, bb: f64) -> (f64, f64) {
    // Scale to unit Gauss-Newton diagonal: H' = D H D, D = diag(1/sqrt(aa), 1/sqrt(bb)).
    let (da, db) = (1.0 / aa.sqrt(), 1.0 / bb.sqrt());
    let (p, q, r) = (hss * da * da, hst * da * db, htt * db * db);
    // Smallest eigenvalue of [[p, q], [q, r]]; shift it to at least EPS.
    const EPS: f64 = 1e-3;
    let lo = smallest_scaled_curvature(hss, hst, htt, aa, bb);
    let shift = (EPS - lo).max(0.0);
    let (p, r) = (p + shift, r + shift);
    let det = p * r - q * q;
    let (g1, g2) = (gs * da, gt * db);
    let x = -(r * g1 - q * g2) / det;
    let y = -(p * g2 - q * g1) / det;
    (x * da, y * db)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};
    use std::f64::consts::PI;

    fn random_points(rng: &mut StdRng, n: usize) -> Vec<Vector3<f64>> {
        (0..n)
            .map(|_| {
                Vector3::new(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                )
            })
            .collect()
    }

    /// Node `i` moved `SMOOTHING` of the way to its neighbours' midpoint;
    /// an end node stays.
    fn smoothed(x: &[Vector3<f64>], i: usize) -> Vector3<f64> {
        if i == 0 || i + 1 == x.len() {
            x[i]
        } else {
            x[i] + SMOOTHING * (0.5 * (x[i - 1] + x[i + 1]) - x[i])
        }
    }

    #[test]
    fn interpolates_the_smoothed_nodes_with_c1_joins() {
        let mut rng = StdRng::seed_from_u64(1);
        let x = random_points(&mut rng, 7);
        for e in 0..6 {
            let p = Piece::new(x.len(), e, |i| x[i]);
            assert!((p.point(0.0) - smoothed(&x, e)).norm() < 1e-15);
            assert!((p.point(1.0) - smoothed(&x, e + 1)).norm() < 1e-15);
            if e + 1 < 6 {
                let (a, b) = (p.jet(1.0), Piece::new(x.len(), e + 1, |i| x[i]).jet(0.0));
                assert!((a.dx - b.dx).norm() < 1e-14, "tangents join at node {}", e + 1);
            }
            for u in [0.0, 0.3, 0.5, 0.9, 1.0] {
                let w = p.weights(u);
                let from_weights: Vector3<f64> = (0..STENCIL).map(|k| w[k] * x[p.nodes[k]]).sum();
                assert!((from_weights - p.point(u)).norm() < 1e-14, "piece {e} at {u}");
                assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
            }
        }
    }

    /// The jet's derivatives against central differences of its points.
    #[test]
    fn jet_derivatives() {
        let mut rng = StdRng::seed_from_u64(2);
        let x = random_points(&mut rng, 8);
        let h = 1e-6;
        for e in [0, 3, 6] {
            let p = Piece::new(x.len(), e, |i| x[i]);
            for u in [0.0, 0.2, 0.5, 0.77, 1.0] {
                let (j, jp, jm) = (p.jet(u), p.jet(u + h), p.jet(u - h));
                assert!((j.dx - (jp.x - jm.x) / (2.0 * h)).norm() < 1e-8);
                assert!((j.ddx - (jp.dx - jm.dx) / (2.0 * h)).norm() < 1e-7);
            }
        }
    }

    /// Nodes on a circle of radius 1 with 30 degree edges, whose chords sag
    /// by 3.4e-2: the curve runs inside the circle by the smoothed nodes'
    /// offset `c (1 - cos a)` (half the sag) to within 1 % of the sag, and
    /// the bound on its distance from the chord holds.
    #[test]
    fn runs_inside_a_circle_by_half_the_sag() {
        let x: Vec<_> = (0..13)
            .map(|i| {
                let a = i as f64 * PI / 6.0;
                Vector3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        let a = PI / 6.0;
        let sag = 1.0 - (0.5 * a).cos();
        let offset = SMOOTHING * (1.0 - a.cos());
        assert!(
            (offset / sag - 0.5).abs() < 0.01,
            "half the sag: {}",
            offset / sag
        );
        for e in 2..10 {
            let p = Piece::new(x.len(), e, |i| x[i]);
            for k in 0..=20 {
                let u = k as f64 / 20.0;
                let inside = 1.0 - p.point(u).norm();
                assert!((inside - offset).abs() < 1e-2 * sag, "{u}: {inside} inside");
                let chord = x[e] + u * (x[e + 1] - x[e]);
                assert!((p.point(u) - chord).norm() <= p.chord_deviation_bound() * (1.0 + 1e-12));
            }
        }
        assert!(sag > 3.4e-2);
    }

    /// Whether the distance of pieces `a` and `b` at `(s, t)` lies in a flat
    /// valley ([`FLAT_CURVATURE`]).
    fn in_flat_valley(a: &Piece, b: &Piece, s: f64, t: f64) -> bool {
        let (ja, jb) = (a.jet(s), b.jet(t));
        let d = ja.x - jb.x;
        let (aa, bb) = (ja.dx.norm_squared(), jb.dx.norm_squared());
        let (hss, htt, hst) = (aa + d.dot(&ja.ddx), bb - d.dot(&jb.ddx), -ja.dx.dot(&jb.dx));
        let held = [hss / aa, htt / bb];
        let lo = smallest_scaled_curvature(hss, hst, htt, aa, bb);
        lo.abs() < FLAT_CURVATURE || held.iter().any(|c| c.abs() < FLAT_CURVATURE)
    }

    /// A rope wrapped on a rod: pieces of a circle (edges of 6 degrees)
    /// about a straight rod on its axis. The distance barely varies along
    /// the rope's piece (a flat valley), so its contact point stays where
    /// the search starts, on every start, within FLAT_DISTANCE of a chord
    /// of the brute-force minimum, and the rod's point is the foot of the
    /// rope's.
    #[test]
    fn a_flat_valley_keeps_its_start() {
        let a = PI / 30.0;
        let rope: Vec<_> = (0..13)
            .map(|i| Vector3::new((i as f64 * a).cos(), (i as f64 * a).sin(), 0.0))
            .collect();
        let rod: Vec<_> = (0..9)
            .map(|i| Vector3::new(0.0, 0.0, -0.4 + 0.1 * i as f64))
            .collect();
        let (p, q) = (
            Piece::new(rope.len(), 5, |i| rope[i]),
            Piece::new(rod.len(), 4, |i| rod[i]),
        );
        let chord = (rope[6] - rope[5]).norm();
        let best = brute_force(&p, &q);
        for s0 in [0.1, 0.35, 0.5, 0.8] {
            let c = closest_points_from(&p, &q, (s0, 0.3));
            assert_eq!(c.s, s0, "the rope's point stays");
            assert!(
                c.distance - best <= FLAT_DISTANCE * chord,
                "start {s0}: {} vs {best}",
                c.distance
            );
            assert!(
                q.point(c.t).z.abs() < 1e-9,
                "the rod's point is the foot of the rope's"
            );
        }
    }

    /// A brute-force minimum of |A(s) - B(t)| on a grid refined around its best point.
    fn brute_force(a: &Piece, b: &Piece) -> f64 {
        let mut best = (f64::INFINITY, 0.5, 0.5);
        let mut width = 0.5;
        for _ in 0..30 {
            let (_, s0, t0) = best;
            for i in 0..=20 {
                for j in 0..=20 {
                    let s = (s0 + width * (i as f64 / 10.0 - 1.0)).clamp(0.0, 1.0);
                    let t = (t0 + width * (j as f64 / 10.0 - 1.0)).clamp(0.0, 1.0);
                    let d = (a.point(s) - b.point(t)).norm();
                    if d < best.0 {
                        best = (d, s, t);
                    }
                }
            }
            width *= 0.5;
        }
        best.0
    }

    /// Random pieces turning by up to about 35 degrees per edge: Newton ends
    /// at a local minimum of the distance on the square (no feasible move
    /// of 1e-4 gets closer), and for pieces turning by up to about 10
    /// degrees, whose distance has one minimum, at the grid search's.
    #[test]
    fn closest_points_are_minima() {
        let mut rng = StdRng::seed_from_u64(2);
        let random_unit = |rng: &mut StdRng| -> Vector3<f64> {
            Vector3::new(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            )
            .normalize()
        };
        for (turn, global) in [(0.6, false), (0.15, true)] {
            for _ in 0..300 {
                let curve = |rng: &mut StdRng| {
                    let mut dir = random_unit(rng);
                    let mut x =
                        vec![2.0 * Vector3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), 0.0)];
                    for _ in 0..3 {
                        dir = (dir + turn * rng.gen_range(0.0..1.0) * random_unit(rng)).normalize();
                        x.push(x.last().unwrap() + dir);
                    }
                    x
                };
                let (xa, xb) = (curve(&mut rng), curve(&mut rng));
                let (a, b) = (
                    Piece::new(xa.len(), 1, |i| xa[i]),
                    Piece::new(xb.len(), 1, |i| xb[i]),
                );
                let pair = closest_points_on_pieces(&a, &b);
                assert!((pair.distance - (pair.point_a - pair.point_b).norm()).abs() < 1e-15);
                // In a flat valley Newton stops where its step would gain
                // less than FLAT_DISTANCE chords (of length 1 here).
                let slack = if in_flat_valley(&a, &b, pair.s, pair.t) {
                    FLAT_DISTANCE
                } else {
                    1e-12
                };
                let h = 1e-4;
                for (ds, dt) in [
                    (h, 0.0),
                    (-h, 0.0),
                    (0.0, h),
                    (0.0, -h),
                    (h, h),
                    (h, -h),
                    (-h, h),
                    (-h, -h),
                ] {
                    let (s, t) = ((pair.s + ds).clamp(0.0, 1.0), (pair.t + dt).clamp(0.0, 1.0));
                    let d = (a.point(s) - b.point(t)).norm();
                    assert!(d >= pair.distance - slack, "{pair:?}: ({s}, {t}) is closer, {d}");
                }
                if global {
                    let reference = brute_force(&a, &b);
                    assert!(
                        (pair.distance - reference).abs() <= slack.max(1e-9),
                        "Newton {} against the grid's {reference}",
                        pair.distance
                    );
                }
            }
        }
    }

    /// A straight rod crossing a bent one: as the bent rod's nodes slide past
    /// the crossing, the distance between the curves stays that of the
    /// circle the smoothed nodes lie on (half the sag inside the nodes') to
    /// 1 % of the chords' swing, their sag.
    #[test]
    fn no_washboard_under_a_crossing() {
        let (radius, edge_angle) = (3.0, 0.5);
        let straight = [
            Vector3::new(0.0, -1.0, 0.0),
            Vector3::new(0.0, -0.1, 0.0),
            Vector3::new(0.0, 0.1, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let b = Piece::new(straight.len(), 1, |i| straight[i]);
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        let (mut chord_lo, mut chord_hi) = (f64::INFINITY, 0.0f64);
        for k in 0..50 {
            let phase = edge_angle * k as f64 / 50.0;
            // Nodes on the circle of radius 3 about (0, 0, 3 + 1) in the xz plane.
            let x: Vec<_> = (-3..=3)
                .map(|i| {
                    let a = phase + edge_angle * i as f64;
                    Vector3::new(radius * a.sin(), 0.0, 4.0 - radius * a.cos())
                })
                .collect();
            let mut best = f64::INFINITY;
            let mut best_chord = f64::INFINITY;
            for e in 1..5 {
                let pair = closest_points_on_pieces(&Piece::new(x.len(), e, |i| x[i]), &b);
                best = best.min(pair.distance);
                best_chord =
                    best_chord.min(closest_points(&x[e], &x[e + 1], &straight[1], &straight[2]).distance);
            }
            (lo, hi) = (lo.min(best), hi.max(best));
            (chord_lo, chord_hi) = (chord_lo.min(best_chord), chord_hi.max(best_chord));
        }
        let sag = radius * (1.0 - (0.5 * edge_angle).cos());
        assert!(
            (chord_hi - chord_lo - sag).abs() < 1e-3 * sag,
            "chords swing by their sag"
        );
        assert!(hi - lo < 1e-2 * sag, "the curve swings by {}", hi - lo);
        let inside = SMOOTHING * radius * (1.0 - edge_angle.cos());
        assert!(
            (lo - 1.0 - inside).abs() < 1e-2 * sag,
            "{lo} against {}",
            1.0 + inside
        );
    }
}
