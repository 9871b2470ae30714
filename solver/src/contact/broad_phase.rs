//! Broad phase of Sec. 3.2: the segment pairs closer than the contact distance
//! `r_a + r_b` (eq. 8's `2h` for equal radii) plus a margin.
//!
//! Each segment's bounding box is inflated by `radius + margin / 2`, so two
//! segments within `r_a + r_b + margin` have overlapping boxes. Boxes are
//! binned on a uniform grid whose cell size is the largest inflated box
//! extent: a segment is stored once, in the cell of its box's lower corner,
//! and overlapping boxes then lie in the same or adjacent cells. Occupied
//! cells come from sorting `(cell, segment)` entries (no hashing,
//! deterministic); a half stencil of 13 neighbours, located by cursors that
//! only move forward through the sorted cells, visits every cell pair once.
//! The cost is `O(n log n + k)` for `n` segments of comparable length and `k`
//! box overlaps; one very long segment makes the cells coarse and the search
//! quadratic.

use super::segment::{SegmentPair, closest_points};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// One rod segment (a cylinder of the given radius around `[a, b]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// First node.
    pub a: Vector3<f64>,
    /// Second node.
    pub b: Vector3<f64>,
    /// Cross-section radius (`h` in the paper).
    pub radius: f64,
    /// Rod the segment belongs to.
    pub body: usize,
    /// Segment index along its rod; segments `i` and `i + 1` share a node.
    pub index: usize,
}

impl Segment {
    #[inline]
    fn key(&self) -> (usize, usize) {
        (self.body, self.index)
    }
}

/// A segment pair within contact range: `i < j` index the input slice and
/// `closest` is `closest_points(segments[i], segments[j])`, so `s` lies on
/// segment `i` (body A) and `t` on segment `j` (body B).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CandidatePair {
    /// Lower segment index (segment A).
    pub i: usize,
    /// Higher segment index (segment B).
    pub j: usize,
    /// Closest points between the centre lines.
    pub closest: SegmentPair,
}

/// Invalid broad-phase input.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum BroadPhaseError {
    /// A segment refers to a body without a neighbour gap.
    #[error("segment {segment} belongs to body {body} but only {bodies} neighbour gaps were given")]
    UnknownBody {
        /// Offending segment.
        segment: usize,
        /// Its body.
        body: usize,
        /// Number of neighbour gaps given.
        bodies: usize,
    },
    /// A segment has a non-finite node or a negative or non-finite radius.
    #[error("segment {0} has a non-finite node or an invalid radius")]
    InvalidSegment(usize),
    /// The margin is negative or not finite.
    #[error("contact margin {0} is negative or not finite")]
    InvalidMargin(f64),
}

/// The segments of one rod's polyline `nodes` (body `body`, indices in order).
pub fn polyline_segments(nodes: &[Vector3<f64>], radius: f64, body: usize) -> Vec<Segment> {
    nodes
        .windows(2)
        .enumerate()
        .map(|(index, w)| Segment {
            a: w[0],
            b: w[1],
            radius,
            body,
            index,
        })
        .collect()
}

/// Index gap below which two segments of one rod are never in contact:
/// `ceil(contact_distance / edge_length) + 1`, i.e. segments closer in arc
/// length than the contact distance plus one edge.
pub fn neighbour_gap(contact_distance: f64, edge_length: f64) -> usize {
    ((contact_distance / edge_length).ceil() as usize).saturating_add(1)
}

/// Whether a pair is skipped: same body and `|index_a - index_b| <=
/// neighbour_gap[body]`.
#[inline]
fn excluded(a: (usize, usize), b: (usize, usize), neighbour_gap: &[usize]) -> bool {
    a.0 == b.0 && a.1.abs_diff(b.1) <= neighbour_gap[a.0]
}

/// The exact test: centre-line distance `< r_a + r_b + margin`.
#[inline]
fn narrow_phase(segments: &[Segment], i: usize, j: usize, margin: f64) -> Option<CandidatePair> {
    let (sa, sb) = (&segments[i], &segments[j]);
    let closest = closest_points(&sa.a, &sa.b, &sb.a, &sb.b);
    (closest.distance < sa.radius + sb.radius + margin).then_some(CandidatePair { i, j, closest })
}

fn validate(segments: &[Segment], neighbour_gap: &[usize], margin: f64) -> Result<(), BroadPhaseError> {
    if !(margin >= 0.0 && margin.is_finite()) {
        return Err(BroadPhaseError::InvalidMargin(margin));
    }
    for (k, seg) in segments.iter().enumerate() {
        if seg.body >= neighbour_gap.len() {
            return Err(BroadPhaseError::UnknownBody {
                segment: k,
                body: seg.body,
                bodies: neighbour_gap.len(),
            });
        }
        let finite = seg.a.iter().chain(seg.b.iter()).all(|x| x.is_finite());
        if !(finite && seg.radius >= 0.0 && seg.radius.is_finite()) {
            return Err(BroadPhaseError::InvalidSegment(k));
        }
    }
    Ok(())
}

/// All pairs by exhaustive `O(n^2)` search; same output as
/// [`BroadPhase::find_pairs`] (reference for tests).
pub fn brute_force(
    segments: &[Segment],
    neighbour_gap: &[usize],
    margin: f64,
) -> Result<Vec<CandidatePair>, BroadPhaseError> {
    validate(segments, neighbour_gap, margin)?;
    let mut pairs = Vec::new();
    for i in 0..segments.len() {
        for j in i + 1..segments.len() {
            if !excluded(segments[i].key(), segments[j].key(), neighbour_gap) {
                pairs.extend(narrow_phase(segments, i, j, margin));
            }
        }
    }
    Ok(pairs)
}

/// Integer grid cell, ordered lexicographically `(x, y, z)`.
type Cell = [i64; 3];

/// A segment's inflated box and exclusion data, stored in cell order.
#[derive(Debug, Clone, Copy)]
struct Slot {
    lo: Vector3<f64>,
    hi: Vector3<f64>,
    segment: usize,
    /// `(body, index)`.
    key: (usize, usize),
}

impl Slot {
    #[inline]
    fn overlaps(&self, other: &Slot) -> bool {
        (0..3).all(|k| self.lo[k] <= other.hi[k] && other.lo[k] <= self.hi[k])
    }
}

/// Grid broad phase with buffers reused across calls (no allocation once the
/// buffers have grown to the problem size).
#[derive(Debug, Clone, Default)]
pub struct BroadPhase {
    /// `(cell, segment)`, sorted.
    entries: Vec<(Cell, usize)>,
    /// Boxes in the order of `entries`.
    slots: Vec<Slot>,
    /// Occupied cells with their `slots` range.
    runs: Vec<(Cell, usize, usize)>,
    pairs: Vec<CandidatePair>,
    /// [`BroadPhase::find_pairs_reusing`]'s candidates: the pairs found
    /// within `reach`, and every segment's endpoints when they were found.
    candidates: Vec<(usize, usize)>,
    anchors: Vec<(Vector3<f64>, Vector3<f64>)>,
    reach: f64,
}

/// Cell coordinates are clamped to `+-CELL_LIMIT` (monotone and 1-Lipschitz,
/// so overlapping boxes still land in adjacent cells) to keep `+-1` in range.
const CELL_LIMIT: f64 = (1u64 << 60) as f64;

/// Forward half of the 26 neighbour cells: the cell above (`dz = +1`) and four
/// `(dx, dy)` columns spanning `dz = -1..=1`.
const FORWARD_COLUMNS: [(i64, i64); 4] = [(0, 1), (1, -1), (1, 0), (1, 1)];

impl BroadPhase {
    /// Empty broad phase.
    pub fn new() -> Self {
        Self::default()
    }

    /// Pairs found by the last successful [`BroadPhase::find_pairs`].
    pub fn pairs(&self) -> &[CandidatePair] {
        &self.pairs
    }

    /// Segment pairs with centre-line distance `< r_a + r_b + margin`,
    /// skipping same-body pairs with `|index_a - index_b| <=
    /// neighbour_gap[body]`, sorted by `(i, j)`.
    pub fn find_pairs(
        &mut self,
        segments: &[Segment],
        neighbour_gap: &[usize],
        margin: f64,
    ) -> Result<&[CandidatePair], BroadPhaseError> {
        validate(segments, neighbour_gap, margin)?;
        self.pairs.clear();
        self.build_grid(segments, margin);
        let Self {
            slots, runs, pairs, ..
        } = self;
        let mut test = |p: usize, q: usize| {
            let (a, b) = (&slots[p], &slots[q]);
            if a.overlaps(b) && !excluded(a.key, b.key, neighbour_gap) {
                let (i, j) = (a.segment.min(b.segment), a.segment.max(b.segment));
                pairs.extend(narrow_phase(segments, i, j, margin));
            }
        };
        // Neighbour cells grow with the current cell (a constant offset keeps
        // the lexicographic order), so each column's cursor only moves forward.
        let mut cursors = [0usize; 5];
        for &(cell, start, end) in runs.iter() {
            for p in start..end {
                for q in p + 1..end {
                    test(p, q);
                }
            }
            let above = [cell[0], cell[1], cell[2] + 1];
            let columns = std::iter::once((above, above)).chain(FORWARD_COLUMNS.map(|(dx, dy)| {
                let (x, y) = (cell[0] + dx, cell[1] + dy);
                ([x, y, cell[2] - 1], [x, y, cell[2] + 1])
            }));
            for ((first, last), cursor) in columns.zip(&mut cursors) {
                while *cursor < runs.len() && runs[*cursor].0 < first {
                    *cursor += 1;
                }
                for &(_, lo, hi) in runs[*cursor..].iter().take_while(|r| r.0 <= last) {
                    for p in start..end {
                        for q in lo..hi {
                            test(p, q);
                        }
                    }
                }
            }
        }
        self.pairs.sort_unstable_by_key(|p| (p.i, p.j));
        Ok(&self.pairs)
    }

    /// [`BroadPhase::find_pairs`] with a candidate list kept between calls
    /// (a Verlet list): the grid search runs with `margin + skin`, and later
    /// calls only test its candidates while no segment endpoint has moved by
    /// more than `(margin + skin - margin_now) / 2` since, so that no other
    /// pair can have come within `margin_now` (a point of a segment moves at
    /// most as far as its farther endpoint). The result is the same as
    /// [`BroadPhase::find_pairs`]' (the same exact test on the same pairs).
    pub fn find_pairs_reusing(
        &mut self,
        segments: &[Segment],
        neighbour_gap: &[usize],
        margin: f64,
        skin: f64,
    ) -> Result<&[CandidatePair], BroadPhaseError> {
        validate(segments, neighbour_gap, margin)?;
        if !(skin >= 0.0 && skin.is_finite()) {
            return Err(BroadPhaseError::InvalidMargin(skin));
        }
        let moved = if self.anchors.len() == segments.len() {
            segments
                .iter()
                .zip(&self.anchors)
                .map(|(s, (a, b))| (s.a - a).norm().max((s.b - b).norm()))
                .fold(0.0f64, f64::max)
        } else {
            f64::INFINITY
        };
        // Covers rounding in the closest points of either call.
        let largest = segments.iter().fold(0.0f64, |m, s| m.max(s.radius));
        let slack = 1e-9 * (2.0 * largest + self.reach);
        if margin + 2.0 * moved + slack > self.reach {
            let reach = margin + skin;
            self.find_pairs(segments, neighbour_gap, reach)?;
            self.candidates.clear();
            self.candidates.extend(self.pairs.iter().map(|p| (p.i, p.j)));
            self.anchors.clear();
            self.anchors.extend(segments.iter().map(|s| (s.a, s.b)));
            self.reach = reach;
        }
        self.pairs.clear();
        let Self {
            candidates, pairs, ..
        } = self;
        pairs.extend(
            candidates
                .iter()
                .filter_map(|&(i, j)| narrow_phase(segments, i, j, margin)),
        );
        Ok(&self.pairs)
    }

    /// Sorted `(cell, segment)` entries, the boxes in that order and the runs
    /// of occupied cells.
    fn build_grid(&mut self, segments: &[Segment], margin: f64) {
        let max_coord = segments
            .iter()
            .flat_map(|s| s.a.iter().chain(s.b.iter()))
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let max_radius = segments.iter().fold(0.0f64, |m, s| m.max(s.radius));
        // Covers rounding in the closest points, so the box test never rejects
        // a pair the exact test accepts.
        let slack = 1e-12 * (max_coord + max_radius + margin);
        let inflated = |s: &Segment| {
            let pad = Vector3::repeat(s.radius + 0.5 * margin + slack);
            (s.a.inf(&s.b) - pad, s.a.sup(&s.b) + pad)
        };
        let extent = segments.iter().fold(0.0f64, |m, s| {
            let (lo, hi) = inflated(s);
            m.max((hi - lo).max())
        });
        // Cells slightly larger than any box, so rounding in `lo * inv_cell`
        // cannot separate overlapping boxes by two cells.
        let inv_cell = if extent > 0.0 {
            1.0 / (extent * (1.0 + 1e-9))
        } else {
            1.0
        };
        self.entries.clear();
        self.entries.extend(segments.iter().enumerate().map(|(k, s)| {
            let c = (inflated(s).0 * inv_cell).map(|x| x.floor().clamp(-CELL_LIMIT, CELL_LIMIT) as i64);
            ([c.x, c.y, c.z], k)
        }));
        self.entries.sort_unstable();
        self.slots.clear();
        self.slots.extend(self.entries.iter().map(|&(_, k)| {
            let s = &segments[k];
            let (lo, hi) = inflated(s);
            Slot {
                lo,
                hi,
                segment: k,
                key: s.key(),
            }
        }));
        self.runs.clear();
        let mut start = 0;
        while start < self.entries.len() {
            let cell = self.entries[start].0;
            let end = start + self.entries[start..].partition_point(|e| e.0 == cell);
            self.runs.push((cell, start, end));
            start = end;
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::f64::consts::TAU;

    /// `nodes` points on a `(p, q)` torus knot (tube radius `minor` around a
    /// circle of radius `major`) covering the fraction `arc` of the closed
    /// curve: `arc = 1` closes it (the last node is the first), `arc < 1`
    /// leaves an open knotted rod.
    pub(crate) fn torus_knot(
        p: f64,
        q: f64,
        major: f64,
        minor: f64,
        nodes: usize,
        arc: f64,
    ) -> Vec<Vector3<f64>> {
        (0..nodes)
            .map(|k| {
                let phi = arc * TAU * k as f64 / (nodes - 1) as f64;
                let rho = major + minor * (q * phi).cos();
                Vector3::new(
                    rho * (p * phi).cos(),
                    rho * (p * phi).sin(),
                    -minor * (q * phi).sin(),
                )
            })
            .collect()
    }

    /// Segments of one polyline as body `body`, global order preserved.
    fn check_same_as_brute_force(segments: &[Segment], gaps: &[usize], margin: f64) -> usize {
        let mut bp = BroadPhase::new();
        let fast = bp.find_pairs(segments, gaps, margin).unwrap().to_vec();
        let slow = brute_force(segments, gaps, margin).unwrap();
        assert_eq!(fast, slow);
        fast.len()
    }

    #[test]
    fn trefoil_and_torus_knots_match_brute_force() {
        let cases = [
            (2.0, 3.0, 0.2, 0.0, 1.0),
            (2.0, 3.0, 0.2, 0.0, 0.9),
            (2.0, 7.0, 0.2, 0.05, 1.0),
            (2.0, 7.0, 0.2, 0.0, 0.9),
            (3.0, 5.0, 0.3, 0.02, 0.9),
        ];
        for (p, q, radius, margin, arc) in cases {
            let nodes = torus_knot(p, q, 1.5, 0.5, 301, arc);
            let edge = (nodes[1] - nodes[0]).norm();
            let segments = polyline_segments(&nodes, radius, 0);
            let gap = neighbour_gap(2.0 * radius, edge);
            let count = check_same_as_brute_force(&segments, &[gap], margin);
            assert!(count > 90, "({p}, {q}) knot: only {count} contacts");
        }
    }

    #[test]
    fn tight_double_helix_matches_brute_force() {
        let (helix_radius, pitch, radius, n) = (0.5, 0.25, 0.5, 300);
        let strand = |phase: f64| -> Vec<Vector3<f64>> {
            (0..=n)
                .map(|k| {
                    let theta = 0.1 * k as f64 + phase;
                    Vector3::new(
                        helix_radius * theta.cos(),
                        helix_radius * theta.sin(),
                        pitch * theta / TAU,
                    )
                })
                .collect()
        };
        let mut segments = polyline_segments(&strand(0.0), radius, 0);
        segments.extend(polyline_segments(&strand(0.5 * TAU), radius, 1));
        let edge = (segments[0].b - segments[0].a).norm();
        let gap = neighbour_gap(2.0 * radius, edge);
        let count = check_same_as_brute_force(&segments, &[gap, gap], 1e-3);
        let inter = brute_force(&segments, &[gap, gap], 1e-3)
            .unwrap()
            .iter()
            .filter(|p| segments[p.i].body != segments[p.j].body)
            .count();
        assert!(
            count > 1000 && inter > 300,
            "{count} pairs, {inter} between strands"
        );
    }

    #[test]
    fn exclusion_rule() {
        let nodes: Vec<_> = (0..=10).map(|k| Vector3::new(k as f64, 0.0, 0.0)).collect();
        let segments = polyline_segments(&nodes, 0.6, 0);
        // Straight chain: only index gap >= 2 can be within 1.2 (gap 2 is 1.0 apart).
        let pairs = brute_force(&segments, &[1], 0.0).unwrap();
        assert!(pairs.iter().all(|p| p.j - p.i == 2) && pairs.len() == 8);
        assert!(brute_force(&segments, &[2], 0.0).unwrap().is_empty());
        check_same_as_brute_force(&segments, &[1], 0.0);
        // Different bodies are never excluded.
        let mut two = segments.clone();
        two.extend(polyline_segments(&nodes, 0.6, 1));
        let pairs = BroadPhase::new()
            .find_pairs(&two, &[100, 100], 0.0)
            .unwrap()
            .to_vec();
        assert!(pairs.iter().all(|p| two[p.i].body != two[p.j].body));
        assert_eq!(pairs.len(), 10 + 2 * 9 + 2 * 8);
        assert_eq!(neighbour_gap(2.0, 1.0), 3);
        assert_eq!(neighbour_gap(2.5, 1.0), 4);
    }

    #[test]
    fn buffers_reused_and_errors() {
        let nodes = torus_knot(2.0, 7.0, 1.5, 0.5, 301, 1.0);
        let segments = polyline_segments(&nodes, 0.2, 0);
        let mut bp = BroadPhase::new();
        let first = bp.find_pairs(&segments, &[3], 0.01).unwrap().to_vec();
        let ptrs = |bp: &BroadPhase| {
            [
                bp.entries.as_ptr() as usize,
                bp.slots.as_ptr() as usize,
                bp.runs.as_ptr() as usize,
                bp.pairs.as_ptr() as usize,
            ]
        };
        let before = ptrs(&bp);
        let again = bp.find_pairs(&segments, &[3], 0.01).unwrap().to_vec();
        assert_eq!(first, again);
        assert_eq!(before, ptrs(&bp));
        assert_eq!(bp.pairs(), &first[..]);

        assert_eq!(
            bp.find_pairs(&segments, &[], 0.0),
            Err(BroadPhaseError::UnknownBody {
                segment: 0,
                body: 0,
                bodies: 0
            })
        );
        assert_eq!(
            bp.find_pairs(&segments, &[3], -1.0),
            Err(BroadPhaseError::InvalidMargin(-1.0))
        );
        let mut bad = segments.clone();
        bad[5].b.y = f64::NAN;
        assert_eq!(
            bp.find_pairs(&bad, &[3], 0.0),
            Err(BroadPhaseError::InvalidSegment(5))
        );
        assert!(bp.find_pairs(&segments[..1], &[3], 0.0).unwrap().is_empty());
    }

    fn soup() -> impl Strategy<Value = (Vec<Segment>, Vec<usize>, f64)> {
        let segment = (
            prop::array::uniform3(-2.0..2.0f64),
            prop::array::uniform3(-0.5..0.5f64),
            0.0..0.3f64,
            0..3usize,
        );
        (
            prop::collection::vec(segment, 0..80),
            prop::collection::vec(0..4usize, 3),
            0.0..0.2f64,
        )
            .prop_map(|(raw, gaps, margin)| {
                let mut counts = [0usize; 3];
                let segments = raw
                    .into_iter()
                    .map(|(a, d, radius, body)| {
                        let a = Vector3::from(a);
                        counts[body] += 1;
                        Segment {
                            a,
                            b: a + Vector3::from(d),
                            radius,
                            body,
                            index: counts[body] - 1,
                        }
                    })
                    .collect();
                (segments, gaps, margin)
            })
    }

    /// The Verlet list finds what the exhaustive search finds, step after
    /// step, while a knotted rod drifts, is shaken and then jumps.
    #[test]
    fn reused_candidates_give_the_exhaustive_pairs() {
        use rand::{Rng, SeedableRng, rngs::StdRng};
        let mut nodes = torus_knot(2.0, 3.0, 0.05, 0.02, 301, 0.95);
        let radius = 0.004;
        let gaps = [neighbour_gap(2.0 * radius, 0.002)];
        let mut rng = StdRng::seed_from_u64(7);
        let mut broad = BroadPhase::new();
        let (mut reused, mut found) = (0, 0);
        for step in 0..200 {
            let size = match step {
                150 => 0.01,
                _ if step % 40 == 39 => 0.002,
                _ => 1e-4,
            };
            for x in nodes.iter_mut() {
                *x += Vector3::from_fn(|_, _| rng.gen_range(-size..size));
            }
            let segments = polyline_segments(&nodes, radius, 0);
            let margin = 0.001 * (1.0 + (step % 3) as f64);
            let pairs = broad
                .find_pairs_reusing(&segments, &gaps, margin, 0.004)
                .unwrap()
                .to_vec();
            reused += usize::from(broad.anchors[0].0 != segments[0].a);
            found += pairs.len();
            assert_eq!(
                pairs,
                brute_force(&segments, &gaps, margin).unwrap(),
                "step {step}"
            );
        }
        assert!(found > 1000, "{found} pairs in all");
        assert!(
            reused > 100 && reused < 200,
            "{reused} steps reused the candidates"
        );
    }

    proptest! {
        #[test]
        fn random_soups_match_brute_force((segments, gaps, margin) in soup()) {
            let mut bp = BroadPhase::new();
            let fast = bp.find_pairs(&segments, &gaps, margin).unwrap().to_vec();
            prop_assert_eq!(fast, brute_force(&segments, &gaps, margin).unwrap());
        }
    }
}
