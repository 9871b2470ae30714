//! Snapshots: the states of the knot a report keeps for viewers (the web
//! page's 3D view, ParaView): the centre line with its per-node state and the
//! loaded contacts with their forces. Taken only at samples, never per step.
//! ("Frame" is kept for the rods' material and reference frames.)
use crate::contact::ContactPoint;
use crate::pipeline::World;
use crate::rod::Rod;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

pub use crate::snapshot_label::{EventWhen, SnapshotLabel, UnknownLabel};

/// A centreline snapshot. The per-node fields are single precision (they
/// are for viewing, and keep the stored report small); they and `time` are
/// empty or zero in snapshots stored before they were recorded.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    pub label: SnapshotLabel,
    pub l_k_bar: f64,
    /// Simulated time since the case started, relaxation included (s).
    #[serde(default)]
    pub time: f64,
    pub points: Vec<[f64; 3]>,
    /// Twist rate per node (1/m): the integrated twist of eq. (5) over the
    /// node's Voronoi length; the end nodes repeat their neighbour's.
    #[serde(default)]
    pub twist_rate: Vec<f32>,
    /// Curvature per node (1/m): |kappa b| of eq. (3) over the Voronoi
    /// length; the end nodes repeat their neighbour's.
    #[serde(default)]
    pub curvature: Vec<f32>,
    /// Node velocities at the last step (m/s).
    #[serde(default)]
    pub velocity: Vec<[f32; 3]>,
    /// The contacts carrying load at this snapshot (empty in snapshots stored
    /// before they were recorded).
    #[serde(default)]
    pub contacts: Vec<SnapshotContact>,
    /// Node counts of the rods whose nodes `points` lists one rod after the
    /// other (a bend's two); empty for one rod.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub rods: Vec<usize>,
}

/// A loaded contact of a snapshot: the closest points on the two segments (m),
/// the magnitude of the contact force (N) and its parts on the first
/// segment's rod (`a`): normal (along the normal from `b` to `a`) and
/// friction (tangential), and whether friction sticks (strictly inside the
/// Coulomb cone) or slips (on its boundary).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SnapshotContact {
    pub a: [f64; 3],
    pub b: [f64; 3],
    pub force: f64,
    #[serde(default)]
    pub normal_force: [f64; 3],
    #[serde(default)]
    pub friction_force: [f64; 3],
    #[serde(default)]
    pub stick: bool,
}

/// Relative margin under mu f_n below which friction counts as sticking
/// (the contact solvers put a slipping force on the cone to round-off).
const STICK_MARGIN: f64 = 1e-6;

impl Snapshot {
    /// A snapshot of the world's rods at simulated time `time` (a bend's
    /// rods one after the other, `rods` giving their node counts).
    pub fn capture(world: &World, label: SnapshotLabel, l_k_bar: f64, time: f64) -> Self {
        let rods = &world.rods;
        let points: Vec<Vector3<f64>> = rods.iter().flat_map(Rod::positions).collect();
        let contacts = world
            .contacts()
            .iter()
            .zip(world.contact_forces())
            .filter(|(_, f)| f.norm() > 0.0)
            .map(|(c, f)| SnapshotContact::new(c, f, &points))
            .collect();
        let per_node = |f: &dyn Fn(&Rod, usize) -> f64| -> Vec<f32> {
            rods.iter()
                .flat_map(|rod| ends_repeated(rod, &|i| f(rod, i)))
                .collect()
        };
        Self {
            label,
            l_k_bar,
            time,
            points: points.iter().map(|p| [p.x, p.y, p.z]).collect(),
            twist_rate: per_node(&|rod, i| rod.twist(i) / rod.voronoi[i]),
            curvature: per_node(&|rod, i| rod.geo.kb[i].norm() / rod.voronoi[i]),
            velocity: (rods.iter())
                .flat_map(|rod| (0..rod.nodes()).map(|i| rod.node_velocity(i).map(|v| v as f32).into()))
                .collect(),
            contacts,
            rods: match rods.len() {
                1 => Vec::new(),
                _ => rods.iter().map(Rod::nodes).collect(),
            },
        }
    }
}

/// `f` at each interior node of `rod`, the end nodes taking their neighbour's value.
fn ends_repeated(rod: &Rod, f: &dyn Fn(usize) -> f64) -> Vec<f32> {
    let last = rod.nodes() - 1;
    (0..=last).map(|i| f(i.clamp(1, last - 1)) as f32).collect()
}

impl SnapshotContact {
    /// Contact `c` with force `f` (on A), at node positions `points`.
    fn new(c: &ContactPoint, f: &Vector3<f64>, points: &[Vector3<f64>]) -> Self {
        let (a, b) = c.points(points);
        let normal = c.normal * f.dot(&c.normal);
        let friction = f - normal;
        let bound = c.mu * normal.norm();
        Self {
            a: a.into(),
            b: b.into(),
            force: f.norm(),
            normal_force: normal.into(),
            friction_force: friction.into(),
            stick: friction.norm() < (1.0 - STICK_MARGIN) * bound,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::SnapshotContact;
    use crate::contact::ContactPoint;
    use crate::contact::segment::closest_points;
    use nalgebra::Vector3;

    /// Two crossing segments, A above B by 1 along z; friction 0.5.
    fn crossing() -> (ContactPoint, Vec<Vector3<f64>>) {
        let points = vec![
            Vector3::new(-1.0, 0.0, 1.0),
            Vector3::new(1.0, 0.0, 1.0),
            Vector3::new(0.0, -1.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let pair = closest_points(&points[0], &points[1], &points[2], &points[3]);
        let c = ContactPoint::from_pair([0, 1, 2, 3], &pair, 1.0, 0.5).unwrap();
        (c, points)
    }

    #[test]
    fn splits_the_force_and_tells_stick_from_slip() {
        let (c, points) = crossing();
        let stuck = SnapshotContact::new(&c, &Vector3::new(0.2, 0.0, 1.0), &points);
        assert_eq!(stuck.a, [0.0, 0.0, 1.0]);
        assert_eq!(stuck.b, [0.0, 0.0, 0.0]);
        assert_eq!(stuck.normal_force, [0.0, 0.0, 1.0]);
        assert_eq!(stuck.friction_force, [0.2, 0.0, 0.0]);
        assert!(stuck.stick);
        let slipping = SnapshotContact::new(&c, &Vector3::new(0.0, 0.5, 1.0), &points);
        assert!(!slipping.stick);
        assert!((slipping.force - 1.25f64.sqrt()).abs() < 1e-15);
    }
}
