//! A rigid, fixed cylinder the rods lie on (a hitch's pole): one contact
//! per rod segment within reach of its surface, under the same Signorini
//! and Coulomb law (eqs. 8-9) as the contacts between rods.
//!
//! The cylinder is body B of its contacts with weight zero on every node:
//! the relative velocity is the rod's, and the force acts on the rod alone.
//! Under the smooth geometry ([`super::Geometry::Smooth`]) a contact is
//! between a piece of the rod's smooth centre line and the axis
//! ([`Cylinder::axis_piece`], [`Cylinder::curve_contact`]).
use super::curve::{CurvePair, Piece, STENCIL};
use super::point::{CONTACT_NODES, ContactPoint, MIN_NORMAL_DISTANCE};
use super::segment::{SegmentPair, closest_points};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// A finite circular cylinder, fixed in space. Lengths in metres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Cylinder {
    /// The middle of its axis.
    pub center: Vector3<f64>,
    /// Unit direction of its axis.
    pub axis: Vector3<f64>,
    /// Its radius `R`.
    pub radius: f64,
    /// Its length along the axis.
    pub length: f64,
}

impl Cylinder {
    /// The two ends of its axis.
    pub fn ends(&self) -> [Vector3<f64>; 2] {
        let half = 0.5 * self.length * self.axis;
        [self.center - half, self.center + half]
    }

    /// The closest points of segment `[a, b]` (A) and the axis (B).
    pub fn closest(&self, a: &Vector3<f64>, b: &Vector3<f64>) -> SegmentPair {
        let [p, q] = self.ends();
        closest_points(a, b, &p, &q)
    }

    /// The axis as a piece of a straight centre line through its two ends
    /// (the segment between them), for [`super::curve::closest_points_from`].
    pub fn axis_piece(&self) -> Piece {
        let [p, q] = self.ends();
        Piece::new(2, 0, |i| if i == 0 { p } else { q })
    }

    /// How far a rod of radius `rod_radius` whose segment is `[a, b]` sinks
    /// into the surface: `R + r` less the segment's distance from the axis
    /// (negative when apart).
    pub fn penetration(&self, a: &Vector3<f64>, b: &Vector3<f64>, rod_radius: f64) -> f64 {
        self.radius + rod_radius - self.closest(a, b).distance
    }

    /// The contact of the segment between global nodes `nodes` (at `a` and
    /// `b`, of a rod of radius `rod_radius`) with the surface, when its
    /// centre line is within `margin` of touching; `None` otherwise or
    /// where the normal is undefined (the centre line on the axis).
    pub fn contact(
        &self,
        nodes: [usize; 2],
        (a, b): (&Vector3<f64>, &Vector3<f64>),
        rod_radius: f64,
        margin: f64,
        mu: f64,
    ) -> Option<ContactPoint> {
        let closest = self.closest(a, b);
        let reach = self.radius + rod_radius;
        let d = closest.distance;
        if d >= reach + margin || d <= MIN_NORMAL_DISTANCE * reach {
            return None;
        }
        let mut weights = [0.0; CONTACT_NODES];
        weights[..2].copy_from_slice(&[1.0 - closest.s, closest.s]);
        Some(ContactPoint {
            nodes: std::array::from_fn(|k| nodes[k % 2]),
            weights,
            width: 4,
            normal: (closest.point_a - closest.point_b) / d,
            gap: d - reach,
            mu,
            sliding_direction: Vector3::zeros(),
            spin: [(0, Vector3::zeros()); 2],
        })
    }

    /// The contact of a rod's smooth centre-line `piece` (its nodes' global
    /// ids are `first` plus the piece's) with the surface, given the closest
    /// points `closest` of the piece (A) and [`Cylinder::axis_piece`] (B),
    /// when within `margin` of touching: the force reaches the piece's six
    /// nodes by its weights at the contact point.
    pub fn curve_contact(
        &self,
        piece: &Piece,
        first: usize,
        closest: &CurvePair,
        rod_radius: f64,
        margin: f64,
        mu: f64,
    ) -> Option<ContactPoint> {
        let reach = self.radius + rod_radius;
        let d = closest.distance;
        if d >= reach + margin || d <= MIN_NORMAL_DISTANCE * reach {
            return None;
        }
        let w = piece.weights(closest.s);
        let mut nodes = [first; CONTACT_NODES];
        let mut weights = [0.0; CONTACT_NODES];
        for k in 0..STENCIL {
            nodes[k] = first + piece.nodes[k];
            weights[k] = w[k];
        }
        Some(ContactPoint {
            nodes,
            weights,
            width: STENCIL,
            normal: (closest.point_a - closest.point_b) / d,
            gap: d - reach,
            mu,
            sliding_direction: Vector3::zeros(),
            spin: [(0, Vector3::zeros()); 2],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pole() -> Cylinder {
        Cylinder {
            center: Vector3::zeros(),
            axis: Vector3::z(),
            radius: 0.01,
            length: 0.1,
        }
    }

    /// A segment parallel to the axis at distance 0.0115 with radius 1 mm:
    /// gap 0.5 mm, normal radial, the whole force on the segment's nodes.
    #[test]
    fn a_segment_beside_the_pole_touches_along_the_normal() {
        let (a, b) = (Vector3::new(0.0115, 0.0, -0.01), Vector3::new(0.0115, 0.0, 0.03));
        let c = pole().contact([7, 8], (&a, &b), 1e-3, 1e-3, 0.3).unwrap();
        assert!((c.gap - 5e-4).abs() < 1e-15, "{}", c.gap);
        assert!((c.normal - Vector3::x()).norm() < 1e-12, "{}", c.normal);
        let (nodes, weights) = c.stencil();
        assert_eq!(nodes, [7, 8, 7, 8]);
        assert!((weights[0] + weights[1] - 1.0).abs() < 1e-15);
        assert_eq!(&weights[2..], [0.0, 0.0]);
        // The relative velocity is the segment's own.
        let v = vec![Vector3::zeros(); 7]
            .into_iter()
            .chain([Vector3::new(1.0, 2.0, 3.0), Vector3::new(1.0, 2.0, 3.0)])
            .collect::<Vec<_>>();
        assert!((c.gather(&v) - Vector3::new(1.0, 2.0, 3.0)).norm() < 1e-15);
        assert!(pole().contact([7, 8], (&a, &b), 1e-3, 4e-4, 0.3).is_none());
        assert!((pole().penetration(&a, &b, 1e-3) + 5e-4).abs() < 1e-15);
    }

    /// A rope's nodes on a circle of radius `R + r` around the pole, edges
    /// turning by `a`: the chords sag inside the circle by `(R + r)(1 - cos(a
    /// / 2))`, and the smooth centre line by about half that (module doc of
    /// [`super::super::curve`]), so its contact's gap lies between the
    /// chord's and zero; its force reaches six nodes with weights summing to
    /// one, along the radial normal.
    #[test]
    fn a_smooth_rope_on_the_pole_touches_between_its_chords_and_its_nodes() {
        use crate::contact::curve::closest_points_from;
        let (r, turn) = (1e-3, 0.35f64);
        let reach = pole().radius + r;
        let nodes: Vec<Vector3<f64>> = (0..12)
            .map(|i| {
                let a = i as f64 * turn;
                Vector3::new(reach * a.cos(), reach * a.sin(), 0.002 * i as f64)
            })
            .collect();
        let e = 5;
        let piece = Piece::new(nodes.len(), e, |i| nodes[i]);
        let chord = pole().closest(&nodes[e], &nodes[e + 1]);
        let closest = closest_points_from(&piece, &pole().axis_piece(), (chord.s, chord.t));
        let c = pole().curve_contact(&piece, 100, &closest, r, r, 0.3).unwrap();
        let chord_gap = chord.distance - reach;
        assert!(
            chord_gap < c.gap && c.gap < 0.0,
            "chord {chord_gap}, curve {}",
            c.gap
        );
        assert!(
            (c.gap / chord_gap - 0.5).abs() < 0.15,
            "{} of the chord's sag",
            c.gap / chord_gap
        );
        // Radial, but for the flat valley's slack along the helix (the closest
        // points stop where moving along it gains under 1e-3 of a chord).
        let radial = Vector3::new(closest.point_a.x, closest.point_a.y, 0.0).normalize();
        assert!((c.normal - radial).norm() < 1e-3, "{} against {radial}", c.normal);
        let (ids, weights) = c.stencil();
        assert_eq!(ids, [105, 106, 104, 107, 103, 108]);
        assert!((weights.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        // The contact point is the weights' combination of the nodes.
        let x: Vector3<f64> = ids.iter().zip(weights).map(|(&i, &w)| w * nodes[i - 100]).sum();
        assert!((x - closest.point_a).norm() < 1e-12);
    }
}
