//! The narrow phase's choices (paper Sec. 3.2): which candidate pairs from
//! the broad phase become contacts, and eq. (9)'s sliding direction.
use super::broad_phase::{CandidatePair, Segment};
use super::curve::CurvePair;
use nalgebra::Vector3;

/// Whether candidate `k` duplicates a neighbour: its closest point lies on a
/// node shared with the adjacent segment of the same rod, and that segment also
/// pairs with the same partner. Such an endpoint pair has a normal tilted
/// towards the node, and closing its linearised gap would push back on a rod
/// sliding smoothly from one segment onto the next. When both pairs meet at the
/// shared node, the one with the lower segment index is kept.
pub(crate) fn redundant(pairs: &[CandidatePair], k: usize, segments: &[Segment]) -> bool {
    const END: f64 = 1e-9;
    let p = &pairs[k];
    let find = |i: usize, j: usize| {
        let key = if i < j { (i, j) } else { (j, i) };
        pairs
            .binary_search_by(|q| (q.i, q.j).cmp(&key))
            .ok() // Err: no such pair (not a failure)
            .map(|m| (m, key.0 == i))
    };
    // (this segment, partner, parameter on this segment)
    for (me, other, param) in [(p.i, p.j, p.closest.s), (p.j, p.i, p.closest.t)] {
        let seg = &segments[me];
        let neighbour = if param <= END {
            me.checked_sub(1)
        } else if param >= 1.0 - END {
            Some(me + 1)
        } else {
            None
        };
        let Some(n) = neighbour.filter(|&n| {
            n < segments.len() && segments[n].body == seg.body && segments[n].index.abs_diff(seg.index) == 1
        }) else {
            continue;
        };
        if n == other {
            continue;
        }
        if let Some((m, n_is_first)) = find(n, other) {
            let q = &pairs[m];
            let n_param = if n_is_first { q.closest.s } else { q.closest.t };
            let n_at_shared = if n < me {
                n_param >= 1.0 - END
            } else {
                n_param <= END
            };
            if !n_at_shared || n < me {
                return true;
            }
        }
    }
    false
}

/// Eq. (9)'s `t = u_t / |u_t|`: the tangential part of `u`, the relative
/// velocity of the contact points (A relative to B) at the start of the
/// step, against the contact's unit `normal`; zero when there is none.
pub(crate) fn sliding_direction(u: &Vector3<f64>, normal: &Vector3<f64>) -> Vector3<f64> {
    let ut = u - normal * u.dot(normal);
    let norm = ut.norm();
    if norm > 0.0 { ut / norm } else { Vector3::zeros() }
}

/// Smooth contacts ([`super::curve`]) whose closest points nearly coincide:
/// [`Merge::keep`] says whether a candidate stays. Pairs are taken nearest
/// first; one is dropped when a kept pair of an adjacent piece pair (the
/// eight around it, on the same rods) has its contact points within
/// `fraction` of this pair's segments' lengths on both curves. Nearly
/// parallel strands put the closest points of neighbouring piece pairs on
/// the pieces' shared ends, so a line contact is found by several pairs at
/// almost the same place; such near-duplicates make the Delassus operator
/// nearly singular and slow the solve. Points further apart than `fraction`
/// of an edge all stay, so a line contact keeps a point every `fraction`
/// edges or closer. Only pairs closer than their radii plus `margin` can
/// become contacts and take part (a farther pair, taken after every nearer
/// one, can drop none of them). Buffers are reused.
///
/// "Nearest first" needs no sort: a pair's fate depends only on its nearer
/// neighbours', so each pair is decided once, after the nearer neighbours
/// within reach of its points ([`Merge::decide`]).
#[derive(Debug, Clone, Default)]
pub(crate) struct Merge {
    /// `first[i]`: the first pair whose lower segment is `i` or more
    /// (pairs are sorted by `(i, j)`).
    first: Vec<usize>,
    /// Each pair's rank: nearer pairs first, ties in pair order; `None` for
    /// a pair that takes no part.
    rank: Vec<Option<(u64, usize)>>,
    fate: Vec<Fate>,
}

/// What [`Merge`] has decided for a pair.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Fate {
    Open,
    Kept,
    Dropped,
}

/// One [`Merge::run`]'s inputs.
struct MergeInput<'a> {
    pairs: &'a [CandidatePair],
    curves: &'a [CurvePair],
    segments: &'a [Segment],
    fraction: f64,
}

impl MergeInput<'_> {
    /// Segment `i`'s neighbour `d` along its rod, if any.
    #[inline]
    fn step(&self, i: usize, d: isize) -> Option<usize> {
        let n = i.checked_add_signed(d)?;
        let s = self.segments;
        (n < s.len() && s[n].body == s[i].body && s[n].index.abs_diff(s[i].index) == d.unsigned_abs())
            .then_some(n)
    }
}

impl Merge {
    /// Decides which of `pairs` (sorted by `(i, j)`, with `curves` their
    /// closest points) stay.
    pub(crate) fn run(
        &mut self,
        pairs: &[CandidatePair],
        curves: &[CurvePair],
        segments: &[Segment],
        fraction: f64,
        margin: f64,
    ) {
        // Ranked by the distance's bits (non-negative floats order as their
        // bits) and the index.
        self.rank.clear();
        self.rank
            .extend(pairs.iter().zip(curves).enumerate().map(|(k, (p, c))| {
                let d = c.distance;
                (d < segments[p.i].radius + segments[p.j].radius + margin)
                    .then_some((d.max(0.0).to_bits(), k))
            }));
        self.first.clear();
        let mut k = 0;
        for i in 0..=segments.len() {
            while k < pairs.len() && pairs[k].i < i {
                k += 1;
            }
            self.first.push(k);
        }
        self.fate.clear();
        self.fate.resize(pairs.len(), Fate::Open);
        let input = MergeInput {
            pairs,
            curves,
            segments,
            fraction,
        };
        for k in 0..pairs.len() {
            if self.rank[k].is_some() {
                self.decide(&input, k);
            }
        }
    }

    /// Whether pair `k` (taking part) stays: unless a nearer neighbour pair
    /// that stays has its points within reach of `k`'s. Each pair is decided
    /// once; the recursion descends to nearer pairs only.
    fn decide(&mut self, c: &MergeInput, k: usize) -> bool {
        match self.fate[k] {
            Fate::Kept => return true,
            Fate::Dropped => return false,
            Fate::Open => {}
        }
        let (pairs, curves, segments) = (c.pairs, c.curves, c.segments);
        let p = &pairs[k];
        let rank = self.rank[k];
        let (ca, cb) = (&curves[k].point_a, &curves[k].point_b);
        let tol_a = c.fraction * (segments[p.i].b - segments[p.i].a).norm();
        let tol_b = c.fraction * (segments[p.j].b - segments[p.j].a).norm();
        let mut kept = true;
        'around: for di in -1..=1 {
            let Some(i) = c.step(p.i, di) else {
                continue;
            };
            // Row `i` of the pairs, sorted by `j`: its pairs with `j` below
            // the neighbour sought are passed once, as `dj` grows.
            let row = self.first[i]..self.first[i + 1];
            let mut m = row.start;
            for dj in -1..=1 {
                if (di, dj) == (0, 0) {
                    continue;
                }
                let Some(j) = c.step(p.j, dj) else {
                    continue;
                };
                // Pairs are stored with i < j; a swapped key swaps the points.
                let (found, swapped) = if i < j {
                    while m < row.end && pairs[m].j < j {
                        m += 1;
                    }
                    ((m < row.end && pairs[m].j == j).then_some(m), false)
                } else {
                    let range = self.first[j]..self.first[j + 1];
                    let found = pairs[range.clone()].binary_search_by_key(&i, |q| q.j).ok();
                    (found.map(|n| range.start + n), true)
                };
                // No such candidate (not a failure), or not nearer.
                let Some(n) = found.filter(|&n| self.rank[n].is_some() && self.rank[n] < rank) else {
                    continue;
                };
                let (ma, mb) = if swapped {
                    (&curves[n].point_b, &curves[n].point_a)
                } else {
                    (&curves[n].point_a, &curves[n].point_b)
                };
                if (ma - ca).norm() <= tol_a && (mb - cb).norm() <= tol_b && self.decide(c, n) {
                    kept = false;
                    break 'around;
                }
            }
        }
        self.fate[k] = if kept { Fate::Kept } else { Fate::Dropped };
        kept
    }

    /// Whether pair `k` of the last [`Merge::run`] stays.
    pub(crate) fn keep(&self, k: usize) -> bool {
        self.fate[k] == Fate::Kept
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::broad_phase::{brute_force, polyline_segments};
    use crate::contact::curve::{Piece, closest_points_on_pieces};
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    /// Candidate pairs of rods `a` and `b` (radius `r`) within `margin` and
    /// their curves' closest points.
    fn candidates(
        rods: [&[Vector3<f64>]; 2],
        r: f64,
        margin: f64,
    ) -> (Vec<Segment>, Vec<CandidatePair>, Vec<CurvePair>) {
        let mut segments = polyline_segments(rods[0], r, 0);
        segments.extend(polyline_segments(rods[1], r, 1));
        let pairs = brute_force(&segments, &[2, 2], margin).unwrap();
        let piece = |s: &Segment| Piece::new(rods[s.body].len(), s.index, |i| rods[s.body][i]);
        let curves = pairs
            .iter()
            .map(|p| closest_points_on_pieces(&piece(&segments[p.i]), &piece(&segments[p.j])))
            .collect();
        (segments, pairs, curves)
    }

    fn line(start: Vector3<f64>, dir: Vector3<f64>, n: usize) -> Vec<Vector3<f64>> {
        (0..n).map(|i| start + i as f64 * dir).collect()
    }

    /// Two straight strands lying side by side, their nodes staggered: the
    /// pairs' closest points come in near-duplicates at the pieces' ends;
    /// merged, no two kept points of adjacent pairs are within the fraction
    /// on both curves, every dropped point has a kept one that close, and
    /// the kept points still hold the line contact at least once per edge.
    #[test]
    fn merging_keeps_a_line_contact() {
        let (r, edge, fraction) = (0.5, 1.0, 0.25);
        let a = line(Vector3::zeros(), Vector3::x() * edge, 21);
        let b = line(Vector3::new(0.37 * edge, 2.0 * r, 0.0), Vector3::x() * edge, 21);
        let (segments, pairs, curves) = candidates([&a, &b], r, 0.25 * r);
        let mut merge = Merge::default();
        merge.run(&pairs, &curves, &segments, fraction, 0.25 * r);
        let keep: Vec<bool> = (0..pairs.len()).map(|k| merge.keep(k)).collect();
        let close = |k: usize, m: usize| {
            (curves[k].point_a - curves[m].point_a).norm() <= fraction * edge
                && (curves[k].point_b - curves[m].point_b).norm() <= fraction * edge
        };
        let adjacent = |k: usize, m: usize| {
            k != m && pairs[k].i.abs_diff(pairs[m].i) <= 1 && pairs[k].j.abs_diff(pairs[m].j) <= 1
        };
        let all = 0..pairs.len();
        let near_duplicates = all.clone().flat_map(|k| all.clone().map(move |m| (k, m)));
        assert!(
            near_duplicates
                .filter(|&(k, m)| adjacent(k, m) && close(k, m))
                .count()
                > 10
        );
        for k in all.clone() {
            let kept_close = all
                .clone()
                .filter(|&m| keep[m] && adjacent(k, m) && close(k, m))
                .count();
            if keep[k] {
                assert_eq!(kept_close, 0, "kept pair {k} has a kept near-duplicate");
            } else {
                assert!(kept_close > 0, "pair {k} dropped without a kept near-duplicate");
            }
        }
        let mut xs: Vec<f64> = all.filter(|&k| keep[k]).map(|k| curves[k].point_a.x).collect();
        xs.sort_by(f64::total_cmp);
        assert!(xs.len() < pairs.len());
        assert!(xs[0] <= 0.37 * edge + 1.0 && *xs.last().unwrap() >= 19.0);
        assert!(xs.windows(2).all(|w| w[1] - w[0] <= edge), "kept points {xs:?}");
    }

    /// Merging as defined: pairs taken nearest first, each kept unless an
    /// adjacent pair already kept has its points within `fraction` of this
    /// pair's segments on both curves; a sort and a quadratic scan.
    fn merged_in_order(
        pairs: &[CandidatePair],
        curves: &[CurvePair],
        segments: &[Segment],
        margin: f64,
    ) -> Vec<bool> {
        let fraction = 0.25;
        let takes_part = |k: usize| {
            curves[k].distance < segments[pairs[k].i].radius + segments[pairs[k].j].radius + margin
        };
        let mut order: Vec<usize> = (0..pairs.len()).filter(|&k| takes_part(k)).collect();
        order.sort_by(|&k, &m| curves[k].distance.total_cmp(&curves[m].distance).then(k.cmp(&m)));
        let length = |i: usize| (segments[i].b - segments[i].a).norm();
        let neighbours = |i: usize, n: usize| {
            segments[i].body == segments[n].body && segments[i].index.abs_diff(segments[n].index) <= 1
        };
        let mut keep = vec![false; pairs.len()];
        for &k in &order {
            let p = &pairs[k];
            let duplicate = (0..pairs.len()).any(|m| {
                let q = &pairs[m];
                let (qa, qb, swapped) = if neighbours(p.i, q.i) && neighbours(p.j, q.j) {
                    (q.i, q.j, false)
                } else if neighbours(p.i, q.j) && neighbours(p.j, q.i) {
                    (q.j, q.i, true)
                } else {
                    return false;
                };
                let (ma, mb) = if swapped {
                    (curves[m].point_b, curves[m].point_a)
                } else {
                    (curves[m].point_a, curves[m].point_b)
                };
                m != k
                    && (qa, qb) != (p.i, p.j)
                    && keep[m]
                    && (ma - curves[k].point_a).norm() <= fraction * length(p.i)
                    && (mb - curves[k].point_b).norm() <= fraction * length(p.j)
            });
            keep[k] = !duplicate;
        }
        keep
    }

    /// Wavy strands lying along each other and crossing: [`Merge`], which
    /// decides each pair after its nearer neighbours without sorting, keeps
    /// exactly the pairs that merging in order of distance keeps.
    #[test]
    fn merging_without_a_sort_keeps_what_merging_in_order_keeps() {
        let mut rng = StdRng::seed_from_u64(7);
        let r = 0.5;
        let mut dropped = 0;
        for case in 0..40 {
            let wavy = |y: f64, z: f64, rng: &mut StdRng| -> Vec<Vector3<f64>> {
                let (amplitude, phase) = (rng.gen_range(0.0..0.3), rng.gen_range(0.0..6.0));
                (0..25)
                    .map(|i| {
                        let x = i as f64 * rng.gen_range(0.9..1.1);
                        Vector3::new(x, y + amplitude * (0.7 * x + phase).sin(), z)
                    })
                    .collect()
            };
            let a = wavy(0.0, 0.0, &mut rng);
            let b = if case % 4 == 3 {
                line(Vector3::new(10.0, -6.0, 2.0 * r), Vector3::new(0.1, 1.0, 0.0), 13)
            } else {
                wavy(2.0 * r + rng.gen_range(-0.05..0.05), 0.0, &mut rng)
            };
            let margin = 0.25 * r;
            let (segments, pairs, curves) = candidates([&a, &b], r, margin);
            let mut merge = Merge::default();
            merge.run(&pairs, &curves, &segments, 0.25, margin);
            let expected = merged_in_order(&pairs, &curves, &segments, margin);
            for (k, &e) in expected.iter().enumerate() {
                assert_eq!(merge.keep(k), e, "case {case}, pair {k}");
            }
            dropped += expected.iter().zip(&pairs).filter(|(e, _)| !**e).count();
        }
        assert!(
            dropped > 100,
            "the cases exercise merging ({dropped} pairs dropped)"
        );
    }

    /// Two strands crossing at right angles meet at one point: of the
    /// pairs around it (the crossing on a node, where four pairs find it),
    /// one stays, the nearest.
    #[test]
    fn merging_a_crossing_keeps_one_contact() {
        let r = 0.5;
        let a = line(Vector3::new(-4.0, 0.0, 0.0), Vector3::x(), 9);
        let b = line(Vector3::new(0.0, -4.0, 2.0 * r), Vector3::y(), 9);
        let (segments, pairs, curves) = candidates([&a, &b], r, 0.25 * r);
        assert_eq!(pairs.len(), 4);
        let mut merge = Merge::default();
        merge.run(&pairs, &curves, &segments, 0.25, 0.25 * r);
        let keep: Vec<bool> = (0..pairs.len()).map(|k| merge.keep(k)).collect();
        assert_eq!(keep.iter().filter(|&&k| k).count(), 1);
        let kept = keep.iter().position(|&k| k).unwrap();
        let nearest = curves.iter().map(|c| c.distance).fold(f64::INFINITY, f64::min);
        assert_eq!(curves[kept].distance, nearest);
        assert!((curves[kept].distance - 2.0 * r).abs() < 1e-12);
    }
}
