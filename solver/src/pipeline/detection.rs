//! Step 1 of [`World::step`]: the contacts at the start of the step (broad
//! phase, closest points, the narrow phase's choices), and the
//! penetrations the step's end leaves.
use super::{Body, World, WorldError};
use crate::contact::broad_phase::Segment;
use crate::contact::curve::{
    CurvePair, Piece, chord_deviation_bound, closest_points_from, closest_points_on_pieces,
};
use crate::contact::segment::{SegmentPair, closest_points};
use crate::contact::{Candidates, ContactPoint, FrictionLaw, Geometry, narrow_phase};
use crate::rod::Rod;
use nalgebra::Vector3;

/// The broad phase's skin as a fraction of the largest radius: candidate
/// pairs are searched within `margin + SKIN r` and reused until a node has
/// moved half that far (`BroadPhase::find_pairs_reusing`; the contacts are
/// the same as a fresh search's). Of the skins from 0.25 r to 2 r, 0.25 r
/// cut a mu = 0.5 case's detection time most.
pub(super) const SKIN: f64 = 0.25;

/// Smooth contacts whose contact points lie within this fraction of an edge
/// of a nearer one's, on both curves, are merged into it
/// ([`narrow_phase::Merge`]). Over n = 3's adaptive pull
/// (docs/FIDELITY.md) 0.25 took F bar's ripple from 3.8 % to 0.93 % in as
/// many steps; 0.35 and 0.42 dropped constraints a line contact needs (the
/// step shrank for penetration: 1.3 and 1.7 times the steps).
const MERGE_FRACTION: f64 = 0.25;

/// The first id of an obstacle contact's pair, `(OBSTACLE, segment)`: after
/// every pair of segments, so that the pairs stay sorted.
const OBSTACLE: usize = usize::MAX;

impl World {
    /// The contacts of the start-of-step state into `contacts` (and their
    /// segment pairs into `pair_ids`).
    pub(super) fn detect(&mut self, dt: f64) -> Result<(), WorldError> {
        self.segments.clear();
        self.implicit.dropped.clear();
        let mut fastest: f64 = 0.0;
        let mut largest_radius: f64 = 0.0;
        for (b, rod) in self.rods.iter().enumerate() {
            largest_radius = largest_radius.max(rod.section.radius);
            for i in 0..rod.nodes() {
                fastest = fastest.max(rod.node_velocity(i).norm());
            }
            for e in 0..rod.edges() {
                self.segments.push(Segment {
                    a: rod.node(e),
                    b: rod.node(e + 1),
                    radius: rod.section.radius,
                    body: b,
                    index: e,
                });
            }
        }
        let margin = self.contact.margin * largest_radius + 2.0 * fastest * dt;
        let smooth = self.contact.geometry == Geometry::Smooth;
        self.pieces.reset(self.segments.len());
        self.deviations.clear();
        if smooth {
            for seg in &self.segments {
                let rod = &self.rods[seg.body];
                self.deviations
                    .push(chord_deviation_bound(rod.nodes(), seg.index, |i| rod.node(i)));
            }
        }
        // A smooth centre line strays from its chords by at most its pieces'
        // bound on both rods: the chords' search reaches that much further.
        let reach = 2.0 * self.deviations.iter().fold(0.0, |m: f64, &d| m.max(d));
        let pairs = self
            .broad
            .find_pairs_reusing(&self.segments, &self.gaps, margin + reach, SKIN * largest_radius)
            .map_err(|e| WorldError::Detection(e.to_string()))?;
        self.curves.clear();
        if smooth {
            // A pair whose chords lie further apart than a contact reaches
            // plus both pieces' bounds cannot touch: no closest points (and
            // no pieces).
            let pieces = &mut self.pieces;
            self.curves.extend(pairs.iter().map(|p| {
                let (sa, sb) = (&self.segments[p.i], &self.segments[p.j]);
                let beyond = sa.radius + sb.radius + margin + self.deviations[p.i] + self.deviations[p.j];
                if p.closest.distance >= beyond {
                    apart(&p.closest)
                } else {
                    let a = pieces.get(&self.rods, &self.segments, p.i);
                    let b = pieces.get(&self.rods, &self.segments, p.j);
                    closest_points_from(&pieces.pieces[a], &pieces.pieces[b], (p.closest.s, p.closest.t))
                }
            }));
            self.merge
                .run(pairs, &self.curves, &self.segments, MERGE_FRACTION, margin);
        }
        self.contacts.clear();
        self.pair_ids.clear();
        self.starts.clear();
        for (k, p) in pairs.iter().enumerate() {
            // Smooth contacts keep every pair but near-duplicates: a pair's
            // closest points lie on a piece's end wherever the distance runs
            // along a line contact, and each pair's constraint holds its
            // stretch of that line.
            if self.contact.candidates == Candidates::Detected
                && !smooth
                && narrow_phase::redundant(pairs, k, &self.segments)
            {
                continue;
            }
            let (sa, sb) = (&self.segments[p.i], &self.segments[p.j]);
            let (oa, ob) = (self.bodies[sa.body].first_node, self.bodies[sb.body].first_node);
            let contact_distance = sa.radius + sb.radius;
            let mu = self.contact.friction;
            // The contact and each rod's unit tangent at it.
            let start = if smooth {
                (self.curves[k].s, self.curves[k].t)
            } else {
                (p.closest.s, p.closest.t)
            };
            let found = if smooth {
                if !self.merge.keep(k) {
                    continue;
                }
                let curve = &self.curves[k];
                if curve.distance >= contact_distance + margin {
                    continue;
                }
                let (a, b) = (self.pieces.built(p.i), self.pieces.built(p.j));
                let stencil =
                    |piece: &Piece, u: f64, first: usize| (piece.nodes.map(|i| first + i), piece.weights(u));
                ContactPoint::from_curves(
                    stencil(a, curve.s, oa),
                    stencil(b, curve.t, ob),
                    curve,
                    contact_distance,
                    mu,
                )
                .map(|c| (c, a.tangent(curve.s), b.tangent(curve.t)))
            } else {
                let nodes = [oa + sa.index, oa + sa.index + 1, ob + sb.index, ob + sb.index + 1];
                ContactPoint::from_pair(nodes, &p.closest, contact_distance, mu)
                    .map(|c| (c, (sa.b - sa.a).normalize(), (sb.b - sb.a).normalize()))
            };
            let Some((mut c, ta, tb)) = found else {
                continue;
            };
            if c.gap < 0.0 {
                c.gap *= self.contact.penetration_recovery;
            }
            if self.contact.rolling {
                let (ea, eb) = (
                    self.bodies[sa.body].first_edge + sa.index,
                    self.bodies[sb.body].first_edge + sb.index,
                );
                let lever = |radius: f64, t: &Vector3<f64>| -radius * t.cross(&c.normal);
                c.spin = [(ea, lever(sa.radius, &ta)), (eb, lever(sb.radius, &tb))];
            }
            if self.contact.friction_law == FrictionLaw::SlidingDirection {
                c.sliding_direction = narrow_phase::sliding_direction(
                    &relative_velocity(&self.rods, &self.bodies, &c),
                    &c.normal,
                );
            }
            self.contacts.push(c);
            self.pair_ids.push((p.i, p.j));
            self.starts.push(start);
        }
        self.detect_obstacle(margin);
        Ok(())
    }

    /// Each segment's contact with the obstacle, after the rods' own, with
    /// pair id `(OBSTACLE, segment)`.
    fn detect_obstacle(&mut self, margin: f64) {
        let Some(cylinder) = self.obstacle else {
            return;
        };
        let mu = self.contact.friction;
        let smooth = self.contact.geometry == Geometry::Smooth;
        let axis = cylinder.axis_piece();
        let mut pieces = std::mem::take(&mut self.pieces);
        for (k, s) in self.segments.iter().enumerate() {
            let body = &self.bodies[s.body];
            let (found, start, tangent) = if smooth {
                // The piece strays from its chord by at most its bound.
                let chord = cylinder.closest(&s.a, &s.b);
                if chord.distance >= cylinder.radius + s.radius + margin + self.deviations[k] {
                    continue;
                }
                let built = pieces.get(&self.rods, &self.segments, k);
                let piece = &pieces.pieces[built];
                let closest = closest_points_from(piece, &axis, (chord.s, chord.t));
                let found = cylinder.curve_contact(piece, body.first_node, &closest, s.radius, margin, mu);
                (found, (closest.s, closest.t), piece.tangent(closest.s))
            } else {
                let first = body.first_node + s.index;
                let found = cylinder.contact([first, first + 1], (&s.a, &s.b), s.radius, margin, mu);
                (found, (0.0, 0.0), (s.b - s.a).normalize())
            };
            let Some(mut c) = found else {
                continue;
            };
            if c.gap < 0.0 {
                c.gap *= self.contact.penetration_recovery;
            }
            if self.contact.rolling {
                let edge = body.first_edge + s.index;
                let lever = -s.radius * tangent.cross(&c.normal);
                c.spin = [(edge, lever), (edge, Vector3::zeros())];
            }
            if self.contact.friction_law == FrictionLaw::SlidingDirection {
                c.sliding_direction = narrow_phase::sliding_direction(
                    &relative_velocity(&self.rods, &self.bodies, &c),
                    &c.normal,
                );
            }
            self.contacts.push(c);
            self.pair_ids.push((OBSTACLE, k));
            self.starts.push(start);
        }
        self.pieces = pieces;
    }

    /// Largest penetration over the detected pairs at the current positions.
    pub(super) fn max_penetration(&mut self) -> f64 {
        let mut ends = std::mem::take(&mut self.end_pieces);
        ends.reset(self.segments.len());
        let detected = self
            .pair_ids
            .iter()
            .zip(&self.starts)
            .map(|(&id, &st)| (id, Some(st)));
        let dropped = self.implicit.dropped.iter().map(|&id| (id, None));
        let worst = detected.chain(dropped).fold(0.0, |worst: f64, ((i, j), start)| {
            worst.max(self.penetration(i, j, start, &mut ends))
        });
        self.end_pieces = ends;
        worst
    }

    /// How far segments `i` and `j` overlap at the current positions:
    /// `r_a + r_b` minus their distance (negative when apart).
    /// `i` is [`OBSTACLE`] for segment `j`'s contact with the obstacle.
    /// The smooth centre lines' closest points are sought from `start`
    /// (the pair's parameters at detection), or from the chords', on the
    /// pieces `ends` holds for the current positions (reset since the rods
    /// last moved).
    pub(super) fn penetration(
        &self,
        i: usize,
        j: usize,
        start: Option<(f64, f64)>,
        ends: &mut Pieces,
    ) -> f64 {
        if i == OBSTACLE {
            let Some(cylinder) = self.obstacle else {
                return f64::NEG_INFINITY;
            };
            let s = &self.segments[j];
            let rod = &self.rods[s.body];
            return match self.contact.geometry {
                Geometry::Smooth => {
                    let built = ends.get(&self.rods, &self.segments, j);
                    let piece = &ends.pieces[built];
                    let axis = cylinder.axis_piece();
                    let d = match start {
                        Some(start) => closest_points_from(piece, &axis, start).distance,
                        None => closest_points_on_pieces(piece, &axis).distance,
                    };
                    cylinder.radius + s.radius - d
                }
                Geometry::Segment => {
                    cylinder.penetration(&rod.node(s.index), &rod.node(s.index + 1), s.radius)
                }
            };
        }
        let (sa, sb) = (&self.segments[i], &self.segments[j]);
        let distance = match self.contact.geometry {
            Geometry::Smooth => {
                let a = ends.get(&self.rods, &self.segments, i);
                let b = ends.get(&self.rods, &self.segments, j);
                let (a, b) = (&ends.pieces[a], &ends.pieces[b]);
                match start {
                    Some(start) => closest_points_from(a, b, start).distance,
                    None => closest_points_on_pieces(a, b).distance,
                }
            }
            Geometry::Segment => {
                let (ra, rb) = (&self.rods[sa.body], &self.rods[sb.body]);
                closest_points(
                    &ra.node(sa.index),
                    &ra.node(sa.index + 1),
                    &rb.node(sb.index),
                    &rb.node(sb.index + 1),
                )
                .distance
            }
        };
        sa.radius + sb.radius - distance
    }
}

/// Pieces of the smooth centre lines at the rods' current positions, each
/// built the first time a segment asks for it. Buffers are reused.
#[derive(Clone, Default)]
pub(super) struct Pieces {
    /// For each segment, its piece's index in `pieces` (`usize::MAX`: not
    /// built yet).
    index: Vec<usize>,
    pieces: Vec<Piece>,
}

impl Pieces {
    /// Forgets every piece (the rods have moved), for `segments` segments.
    pub(super) fn reset(&mut self, segments: usize) {
        self.index.clear();
        self.index.resize(segments, usize::MAX);
        self.pieces.clear();
    }

    /// The index in `pieces` of segment `k`'s piece, built if needed.
    fn get(&mut self, rods: &[Rod], segments: &[Segment], k: usize) -> usize {
        if self.index[k] == usize::MAX {
            let seg = &segments[k];
            let rod = &rods[seg.body];
            self.index[k] = self.pieces.len();
            self.pieces
                .push(Piece::new(rod.nodes(), seg.index, |i| rod.node(i)));
        }
        self.index[k]
    }

    /// Segment `k`'s piece, built by [`Pieces::get`] since the last reset.
    fn built(&self, k: usize) -> &Piece {
        &self.pieces[self.index[k]]
    }
}

/// A candidate pair whose pieces cannot touch: its chords' closest points
/// at distance infinity, so that merging takes it last and no contact
/// comes of it ([`narrow_phase::Merge`] lets only nearer pairs
/// drop a pair).
fn apart(chords: &SegmentPair) -> CurvePair {
    CurvePair {
        s: chords.s,
        t: chords.t,
        point_a: chords.point_a,
        point_b: chords.point_b,
        distance: f64::INFINITY,
    }
}

/// The relative velocity of contact `c`'s points at the start of the step.
fn relative_velocity(rods: &[Rod], bodies: &[Body], c: &ContactPoint) -> Vector3<f64> {
    let velocity = |g: usize| {
        let body = bodies.partition_point(|b| b.first_node <= g) - 1;
        rods[body].node_velocity(g - bodies[body].first_node)
    };
    let (nodes, weights) = c.stencil();
    let mut u = weights[0] * velocity(nodes[0]);
    for (&g, &w) in nodes.iter().zip(weights).skip(1) {
        u += w * velocity(g);
    }
    u
}
