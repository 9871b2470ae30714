//! A contact between two rods: where it acts, how its force reaches the
//! nodes, and the twist DOFs that rolling lets it spin (Sec. 3.2, Fig. 3c).
use super::curve::{CurvePair, STENCIL};
use super::segment::SegmentPair;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// Most nodes a contact point depends on: a smooth contact's two pieces'
/// stencils ([`super::curve::STENCIL`] each).
pub const CONTACT_NODES: usize = 2 * STENCIL;

/// One contact between two rods: the closest points `C_a` (on A) and `C_b`
/// (on B) of a segment pair, or of a pair of the smooth centre lines'
/// pieces ([`super::curve`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContactPoint {
    /// Global node ids, the first `width` used: a segment contact's
    /// `(a0, a1, b0, b1)`, a smooth contact's two pieces' stencils two
    /// nodes at a time, `(a0, a1, b0, b1, a_-1, a_2, b_-1, b_2, a_-2, a_3,
    /// b_-2, b_3)`, so that `nodes[0]` and `nodes[2]` are the first nodes of
    /// the two segments either way.
    pub nodes: [usize; CONTACT_NODES],
    /// Signed weights: `C_a - C_b = sum_k weights_k x_(nodes_k)` (positive
    /// on A, negative on B), and the force `F` on A puts `weights_k F` on
    /// node `nodes_k`. A segment contact's are `(1 - s, s, -(1 - t), -t)`.
    pub weights: [f64; CONTACT_NODES],
    /// How many of `nodes` and `weights` the contact uses (4 or 12).
    pub width: usize,
    /// Unit normal `(C_a - C_b) / d`, from B to A.
    pub normal: Vector3<f64>,
    /// Gap `d - (r_a + r_b)` of eq. (8), negative when penetrating.
    pub gap: f64,
    /// Friction coefficient `mu >= 0`.
    pub mu: f64,
    /// Unit tangent `t` of eq. (9) that friction acts along
    /// ([`super::FrictionLaw::SlidingDirection`]); zero: friction anywhere
    /// in the tangent disk of radius `mu r_n` ([`super::FrictionLaw::Isotropic`]).
    pub sliding_direction: Vector3<f64>,
    /// Rolling: the twist DOFs (global edge ids) of the two segments and
    /// their levers `L`, so that a twist rate `theta_dot` adds `L theta_dot`
    /// to the relative velocity of the touching surface points and the
    /// force `F` puts the torque `L . F` on that twist. `L_a = -r_a t_a x n`,
    /// `L_b = -r_b t_b x n`; zero levers: friction at the centre lines.
    pub spin: [(usize, Vector3<f64>); 2],
}

/// The twist DOFs that contacts may spin ([`ContactPoint::spin`]): inverse
/// rotational inertia (0: held) and contact-free twist rate of each edge.
#[derive(Debug, Clone, Copy)]
pub struct SpinDofs<'a> {
    pub inv_inertia: &'a [f64],
    pub free: &'a [f64],
}

impl ContactPoint {
    /// Contact from the closest points of segments `[a0, a1]` (A) and
    /// `[b0, b1]` (B) (see [`super::segment::closest_points`]), with
    /// `contact_distance = r_a + r_b`; `None` when the centre lines (nearly)
    /// touch, `d <= MIN_NORMAL_DISTANCE * contact_distance` (or `d = 0`), where
    /// the normal is undefined.
    pub fn from_pair(
        nodes: [usize; 4],
        closest: &SegmentPair,
        contact_distance: f64,
        mu: f64,
    ) -> Option<Self> {
        let d = closest.distance;
        let mut weights = [0.0; CONTACT_NODES];
        weights[..4].copy_from_slice(&[1.0 - closest.s, closest.s, closest.t - 1.0, -closest.t]);
        (d > 0.0 && d > MIN_NORMAL_DISTANCE * contact_distance).then(|| Self {
            nodes: std::array::from_fn(|k| nodes[k % 4]),
            weights,
            width: 4,
            normal: (closest.point_a - closest.point_b) / d,
            gap: d - contact_distance,
            mu,
            sliding_direction: Vector3::zeros(),
            spin: [(0, Vector3::zeros()); 2],
        })
    }

    /// Contact from the closest points of two pieces of the smooth centre
    /// lines, `closest` ([`super::curve::closest_points_on_pieces`]), whose
    /// stencils are `nodes_a` and `nodes_b` (global ids, stencil order) with
    /// weights `weights_a` and `weights_b` at the closest points; `None` as
    /// for [`ContactPoint::from_pair`].
    pub fn from_curves(
        (nodes_a, weights_a): ([usize; STENCIL], [f64; STENCIL]),
        (nodes_b, weights_b): ([usize; STENCIL], [f64; STENCIL]),
        closest: &CurvePair,
        contact_distance: f64,
        mu: f64,
    ) -> Option<Self> {
        let d = closest.distance;
        // Two slots of A, two of B, and so on (`on_a`).
        let nodes = std::array::from_fn(|k| {
            let i = 2 * (k / 4) + k % 2;
            if on_a(k) { nodes_a[i] } else { nodes_b[i] }
        });
        let weights = std::array::from_fn(|k| {
            let i = 2 * (k / 4) + k % 2;
            if on_a(k) { weights_a[i] } else { -weights_b[i] }
        });
        (d > 0.0 && d > MIN_NORMAL_DISTANCE * contact_distance).then(|| Self {
            nodes,
            weights,
            width: CONTACT_NODES,
            normal: (closest.point_a - closest.point_b) / d,
            gap: d - contact_distance,
            mu,
            sliding_direction: Vector3::zeros(),
            spin: [(0, Vector3::zeros()); 2],
        })
    }

    /// The nodes and weights the contact uses.
    #[inline]
    pub fn stencil(&self) -> (&[usize], &[f64]) {
        (&self.nodes[..self.width], &self.weights[..self.width])
    }

    /// `sum_k weights_k x_(nodes_k)`: for positions, `C_a - C_b`; for
    /// velocities, the relative velocity of the contact points.
    #[inline]
    pub fn gather(&self, x: &[Vector3<f64>]) -> Vector3<f64> {
        let (nodes, weights) = self.stencil();
        let mut sum = weights[0] * x[nodes[0]];
        for (&k, &w) in nodes.iter().zip(weights).skip(1) {
            sum += w * x[k];
        }
        sum
    }

    /// The contact points `(C_a, C_b)` for node positions `x`.
    pub fn points(&self, x: &[Vector3<f64>]) -> (Vector3<f64>, Vector3<f64>) {
        let (mut a, mut b) = (Vector3::zeros(), Vector3::zeros());
        for (k, (&node, &w)) in self.nodes.iter().zip(&self.weights).take(self.width).enumerate() {
            if on_a(k) {
                a += w * x[node];
            } else {
                b -= w * x[node];
            }
        }
        (a, b)
    }
}

/// Whether slot `k` of [`ContactPoint::nodes`] is on rod A: slots 0, 1, 4, 5, 8, 9.
#[inline]
fn on_a(k: usize) -> bool {
    k % 4 < 2
}

/// Relative centre-line distance below which [`ContactPoint::from_pair`] gives
/// no contact (normal direction lost in rounding).
pub const MIN_NORMAL_DISTANCE: f64 = 1e-9;
