//! A rigid, fixed cylinder the rods lie on (a hitch's pole): one contact
//! per rod segment within reach of its surface, under the same Signorini
//! and Coulomb law (eqs. 8-9) as the contacts between rods.
//!
//! The cylinder is body B of its contacts with weight zero on every node:
//! the relative velocity is the rod's, and the force acts on the rod alone.
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
}
