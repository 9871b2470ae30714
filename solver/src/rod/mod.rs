//! The discrete elastic rod (paper Sec. 3.1): K nodes, K-1 edges, the DOF vector
//! q = [x_0, th_0, x_1, th_1, ..., x_{K-1}] of eq. (1) with 4K-1 entries, reference
//! frames carried in time by parallel transport, material frames rotated by th_i,
//! curvature binormals (eq. 3), material curvatures (eq. 4) and twists (eq. 5).
pub mod frames;

use crate::material::{Material, Section};
use frames::{parallel_transport, perpendicular, signed_angle, transport_by, unwrap_near};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Why a rod could not be built.
#[derive(Debug, Error, PartialEq)]
pub enum RodError {
    #[error("a rod needs at least 3 nodes, got {0}")]
    TooFewNodes(usize),
    #[error("edge {0} has zero or non-finite length")]
    DegenerateEdge(usize),
    #[error("radius must be positive and finite, got {0}")]
    BadRadius(f64),
}

/// Which end of a rod: the first two nodes and edge 0, or the last two nodes and edge K-2.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum End {
    Start,
    Finish,
}

/// Index of the first DOF of node `i` in q (eq. 1).
#[inline]
pub const fn node_dof(i: usize) -> usize {
    4 * i
}

/// Index of the twist angle of edge `i` in q (eq. 1).
#[inline]
pub const fn theta_dof(i: usize) -> usize {
    4 * i + 3
}

/// Frames and strains of the current configuration, recomputed from q at every
/// Newton iterate (reference frames transported from the last accepted step).
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// Edge lengths |e_i|.
    pub edge_len: Vec<f64>,
    /// Unit tangents t_i.
    pub tangent: Vec<Vector3<f64>>,
    /// Reference directors d1_i, d2_i.
    pub d1: Vec<Vector3<f64>>,
    pub d2: Vec<Vector3<f64>>,
    /// Material directors m1_i, m2_i (reference frame rotated by th_i).
    pub m1: Vec<Vector3<f64>>,
    pub m2: Vec<Vector3<f64>>,
    /// Curvature binormal (kappa b)_i at interior nodes, eq. (3); index 0 and K-1 unused.
    pub kb: Vec<Vector3<f64>>,
    /// Material curvatures (kappa1, kappa2) at interior nodes, eq. (4).
    pub kappa: Vec<[f64; 2]>,
    /// Discrete integrated reference twist at interior nodes, eq. (5).
    pub ref_twist: Vec<f64>,
}

/// The state of a rod at an accepted step (DOFs, velocities and the frames the
/// next step transports from): enough to redo a step from there.
#[derive(Clone, Debug, Default)]
pub struct RodState {
    q: Vec<f64>,
    velocity: Vec<f64>,
    tangent: Vec<Vector3<f64>>,
    d1: Vec<Vector3<f64>>,
    ref_twist: Vec<f64>,
    /// The springs' anchors.
    anchors: Vec<f64>,
}

impl RodState {
    /// The DOFs q of the saved step.
    pub fn q(&self) -> &[f64] {
        &self.q
    }
}

/// One naturally straight elastic rod with circular cross-section.
#[derive(Clone, Debug)]
pub struct Rod {
    /// Material of the rod.
    pub material: Material,
    /// Stiffnesses and inertias derived from the material and radius.
    pub section: Section,
    /// DOFs q (eq. 1) at the current iterate.
    pub q: Vec<f64>,
    /// DOFs at the last accepted step.
    pub q_old: Vec<f64>,
    /// Velocities dq/dt at the last accepted step.
    pub velocity: Vec<f64>,
    /// Lumped diagonal mass of each DOF.
    pub mass: Vec<f64>,
    /// Undeformed edge lengths |e^_i|.
    pub rest_len: Vec<f64>,
    /// Undeformed Voronoi lengths l_i = (|e^_{i-1}| + |e^_i|) / 2 (interior nodes).
    pub voronoi: Vec<f64>,
    /// Per-DOF flag: position or twist prescribed (clamped).
    pub fixed: Vec<bool>,
    /// Prescribed velocity of each fixed DOF (zero for a still clamp).
    pub prescribed_velocity: Vec<f64>,
    /// Linear springs tying free DOFs to moving anchors (a clamp on a load
    /// cell); none by default.
    pub springs: Vec<Spring>,
    /// Frames and strains at the current iterate.
    pub geo: Geometry,
    tangent_old: Vec<Vector3<f64>>,
    d1_old: Vec<Vector3<f64>>,
    ref_twist_old: Vec<f64>,
}

/// A linear spring of stiffness `stiffness` (N/m) between a free position
/// DOF and an anchor moving at `velocity`: the energy
/// `k (q_dof - anchor)^2 / 2`, its force and stiffness taken implicitly by
/// the stepper.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spring {
    pub dof: usize,
    pub stiffness: f64,
    /// The anchor's position at the last accepted step (m) and its velocity (m/s).
    pub anchor: f64,
    pub velocity: f64,
}

impl Spring {
    /// The anchor a step of length `h` ends at.
    pub fn anchor_after(&self, h: f64) -> f64 {
        self.anchor + h * self.velocity
    }

    /// The force on the DOF (N) with the anchor at `anchor`.
    pub fn force(&self, q: &[f64], anchor: f64) -> f64 {
        self.stiffness * (anchor - q[self.dof])
    }
}

impl Rod {
    /// A rod through `nodes` whose undeformed shape is straight with the given
    /// edge lengths as rest lengths; twist angles start at zero and the reference
    /// frame is space-parallel transported from an arbitrary director on edge 0.
    pub fn new(nodes: &[Vector3<f64>], radius: f64, material: Material) -> Result<Self, RodError> {
        let k = nodes.len();
        if k < 3 {
            return Err(RodError::TooFewNodes(k));
        }
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(RodError::BadRadius(radius));
        }
        let ne = k - 1;
        let mut rest_len = Vec::with_capacity(ne);
        for i in 0..ne {
            let l = (nodes[i + 1] - nodes[i]).norm();
            if !(l > 0.0 && l.is_finite()) {
                return Err(RodError::DegenerateEdge(i));
            }
            rest_len.push(l);
        }
        let section = Section::circular(&material, radius);
        let ndof = 4 * k - 1;
        let mut q = vec![0.0; ndof];
        for (i, x) in nodes.iter().enumerate() {
            q[node_dof(i)..node_dof(i) + 3].copy_from_slice(x.as_slice());
        }
        let mut voronoi = vec![0.0; k];
        voronoi[0] = rest_len[0] / 2.0;
        voronoi[k - 1] = rest_len[ne - 1] / 2.0;
        for i in 1..k - 1 {
            voronoi[i] = (rest_len[i - 1] + rest_len[i]) / 2.0;
        }
        let mut mass = vec![0.0; ndof];
        for i in 0..k {
            let m = section.linear_density * voronoi[i];
            mass[node_dof(i)..node_dof(i) + 3].fill(m);
        }
        for (i, l) in rest_len.iter().enumerate() {
            mass[theta_dof(i)] = section.polar_inertia * l;
        }
        let tangent: Vec<Vector3<f64>> = (0..ne).map(|i| (nodes[i + 1] - nodes[i]) / rest_len[i]).collect();
        let mut d1_old = Vec::with_capacity(ne);
        d1_old.push(perpendicular(&tangent[0]));
        for i in 1..ne {
            let d = parallel_transport(&d1_old[i - 1], &tangent[i - 1], &tangent[i]);
            d1_old.push((d - tangent[i] * tangent[i].dot(&d)).normalize());
        }
        let geo = Geometry {
            edge_len: vec![0.0; ne],
            tangent: vec![Vector3::zeros(); ne],
            d1: vec![Vector3::zeros(); ne],
            d2: vec![Vector3::zeros(); ne],
            m1: vec![Vector3::zeros(); ne],
            m2: vec![Vector3::zeros(); ne],
            kb: vec![Vector3::zeros(); k],
            kappa: vec![[0.0; 2]; k],
            ref_twist: vec![0.0; k],
        };
        let mut rod = Self {
            material,
            section,
            q_old: q.clone(),
            q,
            velocity: vec![0.0; ndof],
            mass,
            rest_len,
            voronoi,
            fixed: vec![false; ndof],
            prescribed_velocity: vec![0.0; ndof],
            springs: Vec::new(),
            geo,
            tangent_old: tangent,
            d1_old,
            ref_twist_old: vec![0.0; k],
        };
        rod.update_geometry();
        rod.ref_twist_old.copy_from_slice(&rod.geo.ref_twist);
        rod.update_geometry();
        Ok(rod)
    }

    /// Number of nodes K.
    pub fn nodes(&self) -> usize {
        self.voronoi.len()
    }

    /// Number of edges K-1.
    pub fn edges(&self) -> usize {
        self.rest_len.len()
    }

    /// Number of DOFs 4K-1.
    pub fn ndof(&self) -> usize {
        self.q.len()
    }

    /// Undeformed length L.
    pub fn length(&self) -> f64 {
        self.rest_len.iter().sum()
    }

    /// Position of node `i` at the current iterate.
    #[inline]
    pub fn node(&self, i: usize) -> Vector3<f64> {
        Vector3::from_column_slice(&self.q[node_dof(i)..node_dof(i) + 3])
    }

    /// Twist angle th_i of edge `i`.
    #[inline]
    pub fn theta(&self, i: usize) -> f64 {
        self.q[theta_dof(i)]
    }

    /// Node positions at the current iterate.
    pub fn positions(&self) -> Vec<Vector3<f64>> {
        (0..self.nodes()).map(|i| self.node(i)).collect()
    }

    /// Velocity of node `i` at the last accepted step.
    #[inline]
    pub fn node_velocity(&self, i: usize) -> Vector3<f64> {
        Vector3::from_column_slice(&self.velocity[node_dof(i)..node_dof(i) + 3])
    }

    /// Moves node `i` (current and last accepted state) without touching frames' history.
    pub fn set_node(&mut self, i: usize, x: Vector3<f64>) {
        self.q[node_dof(i)..node_dof(i) + 3].copy_from_slice(x.as_slice());
        self.q_old[node_dof(i)..node_dof(i) + 3].copy_from_slice(x.as_slice());
    }

    /// Sets the twist angle of edge `i` in the current and last accepted state.
    pub fn set_theta(&mut self, i: usize, theta: f64) {
        self.q[theta_dof(i)] = theta;
        self.q_old[theta_dof(i)] = theta;
    }

    /// Adds `turns` of twist spread evenly along the rod: edge `i`'s angle
    /// grows by `2 pi turns i / (K - 2)`, so the last edge turns by `turns`
    /// against the first.
    pub fn add_twist(&mut self, turns: f64) {
        let last = (self.edges() - 1) as f64;
        for i in 0..self.edges() {
            let theta = self.theta(i) + std::f64::consts::TAU * turns * i as f64 / last;
            self.set_theta(i, theta);
        }
        self.update_geometry();
    }

    /// DOFs held by a clamp at `end`: positions of the two end nodes and the end
    /// edge's twist (7 DOFs; two clamps give the 14 of paper Sec. 4).
    pub fn clamp_dofs(&self, end: End) -> [usize; 7] {
        let k = self.nodes();
        let (n0, n1, e) = match end {
            End::Start => (0, 1, 0),
            End::Finish => (k - 2, k - 1, k - 2),
        };
        let a = node_dof(n0);
        let b = node_dof(n1);
        [a, a + 1, a + 2, b, b + 1, b + 2, theta_dof(e)]
    }

    /// Clamps `end` in place (prescribed velocity zero).
    pub fn clamp(&mut self, end: End) {
        for d in self.clamp_dofs(end) {
            self.fixed[d] = true;
            self.prescribed_velocity[d] = 0.0;
        }
    }

    /// Gives the clamp at `end` a constant translational velocity `v` (the
    /// clamp must be fixed first). The end twist stays prescribed.
    pub fn move_clamp(&mut self, end: End, v: Vector3<f64>) {
        let dofs = self.clamp_dofs(end);
        for (j, d) in dofs[..6].iter().enumerate() {
            debug_assert!(self.fixed[*d]);
            self.prescribed_velocity[*d] = v[j % 3];
        }
    }

    /// Total kinetic energy 1/2 v^T M v at the last accepted step (J).
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self
            .velocity
            .iter()
            .zip(&self.mass)
            .map(|(v, m)| m * v * v)
            .sum::<f64>()
    }

    /// Recomputes frames and strains from q: reference directors are transported
    /// in time from the last accepted step, then rotated by th_i into material
    /// directors; kb (eq. 3), kappa (eq. 4) and the reference twist (eq. 5).
    pub fn update_geometry(&mut self) {
        let ne = self.edges();
        let g = &mut self.geo;
        for i in 0..ne {
            let a = node_dof(i);
            let e = Vector3::new(
                self.q[a + 4] - self.q[a],
                self.q[a + 5] - self.q[a + 1],
                self.q[a + 6] - self.q[a + 2],
            );
            let len = e.norm();
            let t = e / len;
            let d1 = parallel_transport(&self.d1_old[i], &self.tangent_old[i], &t);
            let d1 = (d1 - t * t.dot(&d1)).normalize();
            let d2 = t.cross(&d1);
            let (s, c) = self.q[a + 3].sin_cos();
            g.edge_len[i] = len;
            g.tangent[i] = t;
            g.d1[i] = d1;
            g.d2[i] = d2;
            g.m1[i] = d1 * c + d2 * s;
            g.m2[i] = d2 * c - d1 * s;
        }
        for i in 1..ne {
            let te = g.tangent[i - 1];
            let tf = g.tangent[i];
            let (c, d) = (te.cross(&tf), te.dot(&tf));
            let kb = c * (2.0 / (1.0 + d));
            g.kb[i] = kb;
            g.kappa[i] = [
                0.5 * (g.m2[i - 1] + g.m2[i]).dot(&kb),
                -0.5 * (g.m1[i - 1] + g.m1[i]).dot(&kb),
            ];
            let u = transport_by(&g.d1[i - 1], &te, &c, d);
            let raw = signed_angle(&u, &g.d1[i], &tf);
            g.ref_twist[i] = unwrap_near(raw, self.ref_twist_old[i]);
        }
    }

    /// Twist tau_i = th_i - th_{i-1} + reference twist at interior node `i`, eq. (5).
    #[inline]
    pub fn twist(&self, i: usize) -> f64 {
        self.theta(i) - self.theta(i - 1) + self.geo.ref_twist[i]
    }

    /// Accepts the current iterate as the new time step of length `dt`:
    /// velocities, and the frames that the next step transports from.
    pub fn accept_step(&mut self, dt: f64) {
        for ((v, q), q0) in self.velocity.iter_mut().zip(&self.q).zip(&self.q_old) {
            *v = (q - q0) / dt;
        }
        for spring in &mut self.springs {
            spring.anchor = spring.anchor_after(dt);
        }
        self.q_old.copy_from_slice(&self.q);
        self.tangent_old.copy_from_slice(&self.geo.tangent);
        self.d1_old.copy_from_slice(&self.geo.d1);
        self.ref_twist_old.copy_from_slice(&self.geo.ref_twist);
    }

    /// Makes the current configuration the reference for frame transport without
    /// changing velocities (used after moving nodes by hand, and by FD checks).
    pub fn rebase_frames(&mut self) {
        self.update_geometry();
        self.tangent_old.copy_from_slice(&self.geo.tangent);
        self.d1_old.copy_from_slice(&self.geo.d1);
        self.ref_twist_old.copy_from_slice(&self.geo.ref_twist);
    }

    /// Applies the rigid motion x -> R x + c to the nodes and to every frame, in
    /// the current and last accepted state (twist angles are unchanged).
    pub fn transform_rigid(&mut self, r: &nalgebra::Rotation3<f64>, c: &Vector3<f64>) {
        for i in 0..self.nodes() {
            let x = r * self.node(i) + c;
            self.set_node(i, x);
        }
        for (t, d) in self.tangent_old.iter_mut().zip(self.d1_old.iter_mut()) {
            *t = r * *t;
            *d = r * *d;
        }
        self.update_geometry();
    }

    /// Copies the last accepted step into `state` (reusing its buffers).
    pub fn save_state(&self, state: &mut RodState) {
        state.q.clone_from(&self.q_old);
        state.velocity.clone_from(&self.velocity);
        state.tangent.clone_from(&self.tangent_old);
        state.d1.clone_from(&self.d1_old);
        state.ref_twist.clone_from(&self.ref_twist_old);
        state.anchors.clear();
        state.anchors.extend(self.springs.iter().map(|s| s.anchor));
    }

    /// Returns to a state saved by [`Rod::save_state`] on this rod.
    pub fn load_state(&mut self, state: &RodState) {
        self.q_old.copy_from_slice(&state.q);
        self.q.copy_from_slice(&state.q);
        self.velocity.copy_from_slice(&state.velocity);
        self.tangent_old.copy_from_slice(&state.tangent);
        self.d1_old.copy_from_slice(&state.d1);
        self.ref_twist_old.copy_from_slice(&state.ref_twist);
        for (spring, anchor) in self.springs.iter_mut().zip(&state.anchors) {
            spring.anchor = *anchor;
        }
        self.update_geometry();
    }

    /// Discards the current iterate and returns to the last accepted step.
    pub fn restore(&mut self) {
        self.q.copy_from_slice(&self.q_old);
        self.update_geometry();
    }
}
