//! The loop of the simplified knot model (paper Sec. 5, eq. 15): a contact-free
//! DER rod of nondimensional length l̄_l = l̄_k / (1 + epsilon) clamped at the two
//! braid ends, whose static equilibrium energy is Ē_l = f(phi, theta, l̄_k, epsilon).
//!
//! Reconstruction of the boundary conditions (Fig. 12 is not in the text); z is
//! the braid axis of eq. (13) and T = n pi - theta:
//! - The loop leaves strand A at its end t = T, at p_s = (cos T, sin T, l̄_b/2),
//!   and enters strand B at its end t = -T, at p_f = (-cos T, sin T, -l̄_b/2), so
//!   that braid and loop form one closed curve.
//! - End tangents: t_s = cos(phi) z + sin(phi) e(T), with e(T) = (-sin T, cos T, 0)
//!   the azimuthal direction of the braid cylinder at p_s. This is the braid axis
//!   rotated by phi about the x axis (at theta = 0 and n odd, e = -y), then turned
//!   with the braid end by theta about z: the helix tangent of strand A at t = T
//!   with its pitch angle replaced by phi. The loop arrives at p_f along
//!   t_f = -R t_s, where R is the half turn about y.
//! - Antisymmetry: R maps the braid onto itself (strand A onto strand B) and p_s,
//!   t_s onto p_f, -t_f, so the whole knot keeps the two-fold symmetry about the
//!   y axis, which reverses x and z; this is the paper's antisymmetry about the YZ
//!   plane. At theta = 0 the loop lies in the YZ plane but for the clamps' offsets
//!   of ±h in x.
//! - Twist: at theta = 0 each clamp's material director is
//!   m1_s = cos(phi) e(T) - sin(phi) z, the normal of t_s in the tangent plane of
//!   the braid cylinder (the loop's plane), and m1_f = R m1_s, so the loop at
//!   theta = 0 is untwisted but for the clamps' offsets. As theta grows, the start
//!   clamp turns by -theta and the finish clamp by +theta about z, and `EndTwist`
//!   says what the clamp's frame does: `Transported` (the default) carries it by
//!   parallel transport along the path of its tangent (no spin about the tangent;
//!   what a DER clamp does when its two nodes are turned with the edge twist
//!   held, as in Sec. 4), `Clamped` turns it rigidly with the braid end (a spin
//!   of cos(phi) per radian about the tangent more), `Free` leaves the end twist
//!   free. Only `Transported` shows the paper's sequence of Fig. 13 (c); see
//!   `docs/SIMPLIFIED_MODEL.md`.
//! - Each clamp holds the loop's end edge (two nodes and the edge twist, as in
//!   paper Sec. 4) centred on the braid end, so the rod between the two clamp
//!   points (edge midpoints) has length exactly l̄_l: K - 2 edges of length
//!   l̄_l / (K - 2).
//!
//! Equilibria come from static Newton solves (`Stepper` with a time step so long
//! that inertia is negligible), continued in theta and l̄_k from the neighbouring
//! solution with a secant predictor, so that one branch is followed.
use super::{Params, SimplifiedError};
use crate::energies::{self, BANDWIDTH, Terms};
use crate::external::Environment;
use crate::linalg::banded::{BandedLdlt, BandedSym};
use crate::rod::frames::{parallel_transport, signed_angle, unwrap_near};
use crate::rod::{End, Rod, node_dof, theta_dof};
use crate::stepper::{NewtonOptions, Stepper};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A static step: inertia (M/dt²) is negligible against the elastic stiffness.
const STATIC_DT: f64 = 1e4;
/// Largest change of theta in one continuation substep (rad).
const MAX_DTHETA: f64 = 0.1;
/// Largest relative change of l̄_k in one continuation substep.
const MAX_DLOG_LK: f64 = 0.02;
/// Substeps are halved at most this many times before continuation gives up.
const MAX_SPLITS: u32 = 10;
/// Scale of l̄_k against theta when comparing continuation steps.
const LK_PER_RADIAN: f64 = 20.0;
/// A substep whose solution lies farther from its prediction than this many loop
/// lengths per radian (or per unit change of ln l̄_k) left the branch.
const JUMP_RATE: f64 = 1.0;

/// Twist boundary condition at the loop's clamped ends as theta turns them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum EndTwist {
    /// Each clamp's frame is parallel transported along the path of its tangent (the
    /// tangent turns about z; the frame does not spin about the tangent).
    #[default]
    Transported,
    /// Each clamp's frame turns rigidly with its braid end about z.
    Clamped,
    /// The end twist is free (zero twisting moment; the start's twist is held only
    /// to fix the uniform rotation of all material frames, a zero-energy mode).
    Free,
}

/// One clamped end of the loop, nondimensional.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EndFrame {
    /// Braid end the loop is attached to (clamp point).
    pub position: Vector3<f64>,
    /// Unit tangent of the loop there, in the loop's direction (start to finish).
    pub tangent: Vector3<f64>,
    /// Material director m1 of the clamp (normal to the tangent).
    pub director: Vector3<f64>,
    /// Rate at which the clamp turns about z per unit increase of theta (-1 at the
    /// start, +1 at the finish).
    pub turn_rate: f64,
    /// Rate at which the clamp's frame spins about its tangent, relative to
    /// parallel transport, per unit increase of theta.
    pub twist_rate: f64,
}

/// Boundary conditions of the loop: where it leaves the braid (start, strand A at
/// t = T) and where it re-enters it (finish, strand B at t = -T).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LoopBoundary {
    pub start: EndFrame,
    pub finish: EndFrame,
}

/// The half turn R about the y axis: (x, y, z) -> (-x, y, -z).
fn half_turn_y(v: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(-v.x, v.y, -v.z)
}

impl LoopBoundary {
    /// Clamps for unknotting number `n`, tilt `phi`, rotation `theta`, braid length
    /// `l_b_bar` and twist convention `twist` (see the module documentation).
    pub fn new(n: u32, phi: f64, theta: f64, l_b_bar: f64, twist: EndTwist) -> Self {
        let t = f64::from(n) * PI - theta;
        let (s, c) = t.sin_cos();
        let z = Vector3::z();
        let azimuth = Vector3::new(-s, c, 0.0);
        let (sp, cp) = phi.sin_cos();
        let tangent = z * cp + azimuth * sp;
        let rigid = azimuth * cp - z * sp;
        // Parallel transport along the tangent's circle about z differs from the
        // rigid turn by a spin of cos(phi) per radian about the tangent.
        let (director, twist_rate) = match twist {
            EndTwist::Clamped => (rigid, -cp),
            EndTwist::Transported | EndTwist::Free => {
                let (ss, cs) = (theta * cp).sin_cos();
                (rigid * cs + tangent.cross(&rigid) * ss, 0.0)
            }
        };
        let start = EndFrame {
            position: Vector3::new(c, s, 0.5 * l_b_bar),
            tangent,
            director,
            turn_rate: -1.0,
            twist_rate,
        };
        // R conjugates a turn about z into the opposite turn.
        let finish = EndFrame {
            position: half_turn_y(&start.position),
            tangent: -half_turn_y(&start.tangent),
            director: half_turn_y(&start.director),
            turn_rate: 1.0,
            twist_rate: -twist_rate,
        };
        Self { start, finish }
    }
}

/// The loop's equilibrium at one (theta, l̄_k), energies in EI/h (eq. 12).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LoopEquilibrium {
    pub theta: f64,
    pub l_k_bar: f64,
    /// Ē_l = f(phi, theta, l̄_k, epsilon), eq. (15).
    pub energy: f64,
    pub bending: f64,
    pub twisting: f64,
    pub stretching: f64,
    /// dĒ_l/dθ along the branch, from the clamps' reaction moments about z.
    pub denergy_dtheta: f64,
    /// Negative eigenvalues of the loop's stiffness with the clamps held (0: the
    /// loop itself is stable at this theta).
    pub negative_pivots: usize,
}

/// A converged state used by the secant predictor: positions divided by l̄_k.
#[derive(Clone, Debug)]
struct Snapshot {
    theta: f64,
    l_k_bar: f64,
    shape: Vec<f64>,
}

/// The loop rod at one point of a continuation path, with everything needed to
/// move it to a neighbouring (theta, l̄_k) and solve there.
#[derive(Clone, Debug)]
pub struct LoopSolver {
    params: Params,
    theta: f64,
    l_k_bar: f64,
    rod: Rod,
    stepper: Stepper,
    previous: Option<Snapshot>,
    newton_iterations: u64,
    grad: Vec<f64>,
    hess: BandedSym,
    ldlt: BandedLdlt,
}

impl LoopSolver {
    /// The loop in equilibrium at theta = 0 and closed-loop length `l_k_bar`,
    /// relaxed from a planar loop in the YZ plane.
    pub fn new(params: &Params, l_k_bar: f64) -> Result<Self, SimplifiedError> {
        params.validate()?;
        params.check_state(0.0, l_k_bar)?;
        let h = params.radius;
        let k = params.loop_nodes;
        let edge = params.l_l_bar(l_k_bar) / (k - 2) as f64;
        let straight: Vec<Vector3<f64>> = (0..k).map(|i| Vector3::x() * (i as f64 * edge * h)).collect();
        let mut rod = Rod::new(&straight, h, params.material)?;
        let bc = LoopBoundary::new(
            params.n,
            params.phi,
            0.0,
            params.l_b_bar(l_k_bar),
            params.end_twist,
        );
        for (i, x) in planar_loop(&bc, k, edge).iter().enumerate() {
            rod.set_node(i, x * h);
        }
        rod.rebase_frames();
        set_untwisted_frames(&mut rod, &bc);
        rod.clamp(End::Start);
        rod.clamp(End::Finish);
        if params.end_twist == EndTwist::Free {
            rod.fixed[theta_dof(k - 2)] = false;
        }
        let options = NewtonOptions {
            rtol: 1e-9,
            max_iterations: 40,
            max_halvings: 2,
            // Each continuation point is a new static problem: fresh Newton
            // converges quadratically where a reused matrix would not.
            reuse_factorization: false,
            ..NewtonOptions::default()
        };
        let stepper = Stepper::new(&rod, options);
        let n = rod.ndof();
        let mut solver = Self {
            params: *params,
            theta: 0.0,
            l_k_bar,
            rod,
            stepper,
            previous: None,
            newton_iterations: 0,
            grad: vec![0.0; n],
            hess: BandedSym::new(n, BANDWIDTH),
            ldlt: BandedLdlt::with_capacity(n, BANDWIDTH),
        };
        solver.solve_here()?;
        Ok(solver)
    }

    /// Current rotation angle theta.
    pub fn theta(&self) -> f64 {
        self.theta
    }

    /// Current closed-loop length l̄_k.
    pub fn l_k_bar(&self) -> f64 {
        self.l_k_bar
    }

    /// The parameters this loop was built with.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// The DER rod of the loop (physical units).
    pub fn rod(&self) -> &Rod {
        &self.rod
    }

    /// Newton iterations spent so far.
    pub fn newton_iterations(&self) -> u64 {
        self.newton_iterations
    }

    /// Loop centreline in units of h.
    pub fn centerline(&self) -> Vec<[f64; 3]> {
        let h = self.params.radius;
        (0..self.rod.nodes())
            .map(|i| {
                let x = self.rod.node(i) / h;
                [x.x, x.y, x.z]
            })
            .collect()
    }

    /// Follows the branch to (`theta`, `l_k_bar`) in substeps of at most 0.1 rad and
    /// 2 % in l̄_k, halving a substep whose Newton solve fails or whose solution
    /// lands farther from its prediction than one loop length per radian (a jump to
    /// another branch); fails after 10 halvings.
    pub fn move_to(&mut self, theta: f64, l_k_bar: f64) -> Result<(), SimplifiedError> {
        self.params.check_state(theta, l_k_bar)?;
        if theta == self.theta && l_k_bar == self.l_k_bar {
            return Ok(());
        }
        let dtheta = theta - self.theta;
        let dlog = (l_k_bar / self.l_k_bar).ln();
        let steps = (dtheta.abs() / MAX_DTHETA)
            .max(dlog.abs() / MAX_DLOG_LK)
            .ceil()
            .max(1.0);
        let mut pieces = steps as u64;
        let (theta0, log0) = (self.theta, self.l_k_bar.ln());
        let mut done = 0u64;
        let mut splits = 0;
        while done < pieces {
            let f = (done + 1) as f64 / pieces as f64;
            let (th, lk) = if done + 1 == pieces {
                (theta, l_k_bar)
            } else {
                (theta0 + f * dtheta, (log0 + f * dlog).exp())
            };
            let backup = (self.rod.clone(), self.previous.clone(), self.theta, self.l_k_bar);
            match self.advance(th, lk) {
                Ok(()) => done += 1,
                Err(e) => {
                    (self.rod, self.previous, self.theta, self.l_k_bar) = backup;
                    splits += 1;
                    if splits > MAX_SPLITS {
                        return Err(e);
                    }
                    done *= 2;
                    pieces *= 2;
                }
            }
        }
        Ok(())
    }

    /// One continuation substep: scale to the new l̄_k, move the clamps, predict, solve.
    fn advance(&mut self, theta: f64, l_k_bar: f64) -> Result<(), SimplifiedError> {
        let here = self.snapshot();
        let scale = l_k_bar / self.l_k_bar;
        if scale != 1.0 {
            self.scale_loop(scale);
        }
        self.theta = theta;
        self.l_k_bar = l_k_bar;
        self.apply_boundary();
        self.predict(&here);
        let predicted = self.rod.q.clone();
        self.solve_here()?;
        let h = self.params.radius;
        let moved = (0..self.rod.ndof())
            .filter(|&j| j % 4 != 3 && !self.rod.fixed[j])
            .fold(0.0f64, |m, j| m.max((self.rod.q[j] - predicted[j]).abs() / h));
        let reach = JUMP_RATE
            * ((theta - here.theta).abs() + (l_k_bar / here.l_k_bar).ln().abs()).max(1e-6)
            * self.params.l_l_bar(l_k_bar);
        if moved > reach {
            return Err(SimplifiedError::Stalled {
                theta,
                l_k_bar,
                reason: format!("the loop left its branch (moved {moved:.3e} h from the prediction)"),
            });
        }
        self.previous = Some(here);
        Ok(())
    }

    fn snapshot(&self) -> Snapshot {
        let mut shape = self.rod.q.clone();
        for (j, v) in shape.iter_mut().enumerate() {
            if j % 4 != 3 {
                *v /= self.l_k_bar;
            }
        }
        Snapshot {
            theta: self.theta,
            l_k_bar: self.l_k_bar,
            shape,
        }
    }

    /// Rescales the rod's rest state and configuration by `f` (a change of l̄_k).
    fn scale_loop(&mut self, f: f64) {
        let rod = &mut self.rod;
        for v in rod
            .rest_len
            .iter_mut()
            .chain(rod.voronoi.iter_mut())
            .chain(rod.mass.iter_mut())
        {
            *v *= f;
        }
        for j in 0..rod.ndof() {
            if j % 4 != 3 {
                rod.q[j] *= f;
                rod.q_old[j] *= f;
            }
        }
        rod.update_geometry();
    }

    /// Puts the clamped DOFs at their values for the current (theta, l̄_k).
    fn apply_boundary(&mut self) {
        let p = &self.params;
        let h = p.radius;
        let bc = LoopBoundary::new(p.n, p.phi, self.theta, p.l_b_bar(self.l_k_bar), p.end_twist);
        let half = 0.5 * p.l_l_bar(self.l_k_bar) / (p.loop_nodes - 2) as f64;
        let k = self.rod.nodes();
        let ends = [(0, 1, 0, &bc.start), (k - 2, k - 1, k - 2, &bc.finish)];
        for &(a, b, _, e) in &ends {
            self.rod.set_node(a, (e.position - e.tangent * half) * h);
            self.rod.set_node(b, (e.position + e.tangent * half) * h);
        }
        self.rod.update_geometry();
        for &(_, _, edge, e) in &ends {
            if self.rod.fixed[theta_dof(edge)] {
                let g = &self.rod.geo;
                let angle = signed_angle(&g.d1[edge], &e.director, &g.tangent[edge]);
                let th = unwrap_near(angle, self.rod.theta(edge));
                self.rod.set_theta(edge, th);
            }
        }
    }

    /// Initial guess of the free DOFs: secant extrapolation from the last two
    /// states when the step continues the previous one, else the scaled state.
    fn predict(&mut self, here: &Snapshot) {
        let mut ratio = 0.0;
        if let Some(prev) = &self.previous {
            let a = (
                here.theta - prev.theta,
                (here.l_k_bar - prev.l_k_bar) / LK_PER_RADIAN,
            );
            let b = (
                self.theta - here.theta,
                (self.l_k_bar - here.l_k_bar) / LK_PER_RADIAN,
            );
            let aa = a.0 * a.0 + a.1 * a.1;
            let bb = b.0 * b.0 + b.1 * b.1;
            if aa > 0.0 && aa < 0.25 && bb < 4.0 * aa {
                ratio = (a.0 * b.0 + a.1 * b.1) / aa;
            }
        }
        let lk = self.l_k_bar;
        let rod = &mut self.rod;
        for j in 0..rod.ndof() {
            if rod.fixed[j] {
                continue;
            }
            let mut target = rod.q_old[j];
            if let Some(prev) = &self.previous {
                let d = ratio * (here.shape[j] - prev.shape[j]);
                target += if j % 4 == 3 { d } else { d * lk };
            }
            rod.q[j] = target;
            rod.velocity[j] = (target - rod.q_old[j]) / STATIC_DT;
        }
    }

    fn solve_here(&mut self) -> Result<(), SimplifiedError> {
        let env = Environment::default();
        let report = self
            .stepper
            .step(&mut self.rod, &env, None, STATIC_DT)
            .map_err(|source| SimplifiedError::Loop {
                theta: self.theta,
                l_k_bar: self.l_k_bar,
                source,
            })?;
        self.newton_iterations += u64::from(report.newton_iterations);
        self.rod.velocity.fill(0.0);
        Ok(())
    }

    /// Energies, dĒ_l/dθ and stability of the current equilibrium.
    ///
    /// dĒ_l/dθ uses the envelope theorem: at equilibrium only the clamped DOFs
    /// contribute, dE/dθ = Σ_clamps [Σ_nodes g_x · (w z × x) + g_th s], with w the
    /// clamp's turn rate about z and s its twist rate (the reaction moments; the
    /// frames are rebased, so a twist angle varies by the spin about the tangent).
    pub fn equilibrium(&mut self) -> LoopEquilibrium {
        let rod = &self.rod;
        let e = energies::evaluate(rod, Terms::ALL, &mut self.grad, Some(&mut self.hess));
        let scale = rod.section.radius / rod.section.ei;
        let bc = LoopBoundary::new(
            self.params.n,
            self.params.phi,
            self.theta,
            0.0,
            self.params.end_twist,
        );
        let k = rod.nodes();
        let mut de = 0.0;
        for (nodes, edge, end) in [([0, 1], 0, bc.start), ([k - 2, k - 1], k - 2, bc.finish)] {
            let w = Vector3::z() * end.turn_rate;
            for a in nodes {
                let g = Vector3::from_column_slice(&self.grad[node_dof(a)..node_dof(a) + 3]);
                de += g.dot(&w.cross(&rod.node(a)));
            }
            de += self.grad[theta_dof(edge)] * end.twist_rate;
        }
        for j in 0..rod.ndof() {
            if rod.fixed[j] {
                self.hess.constrain(j);
            }
        }
        let negative_pivots = self.ldlt.factor(&self.hess).map_or(usize::MAX, |i| i.negative);
        LoopEquilibrium {
            theta: self.theta,
            l_k_bar: self.l_k_bar,
            energy: e.total() * scale,
            bending: e.bending * scale,
            twisting: e.twisting * scale,
            stretching: e.stretching * scale,
            denergy_dtheta: de * scale,
            negative_pivots,
        }
    }
}

/// A planar loop through the clamps at theta = 0 (in the plane of the braid axis
/// and the start's azimuthal direction): edge i has tangent angle alpha_i from z,
/// alpha rising from phi to pi and on to 2 pi - phi, symmetric about the middle;
/// the exponent of its profile is bisected so that the loop closes in z. The small
/// offset of the clamps normal to that plane is spread over the interior edges.
fn planar_loop(bc: &LoopBoundary, k: usize, edge: f64) -> Vec<Vector3<f64>> {
    let (s, f) = (&bc.start, &bc.finish);
    let phi = s.tangent.z.acos();
    let ez = Vector3::z();
    let eb = (s.tangent - ez * s.tangent.z).normalize();
    let normal = ez.cross(&eb);
    let ne = k - 1;
    let alpha = |i: usize, m: f64| {
        let u = i as f64 / (ne - 1) as f64;
        if u <= 0.5 {
            PI - (PI - phi) * (1.0 - 2.0 * u).powf(m)
        } else {
            PI + (PI - phi) * (2.0 * u - 1.0).powf(m)
        }
    };
    let start = s.position - s.tangent * (0.5 * edge);
    let end = f.position + f.tangent * (0.5 * edge);
    let dz = (end - start).dot(&ez);
    let closure = |m: f64| (0..ne).map(|i| edge * alpha(i, m).cos()).sum::<f64>() - dz;
    let (mut lo, mut hi) = (-7.0f64, 7.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if closure(mid.exp()) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let m = (0.5 * (lo + hi)).exp();
    let offset = (end - start).dot(&normal) / (ne - 2) as f64;
    let mut nodes = vec![start];
    for i in 0..ne {
        let a = alpha(i, m);
        let mut e = (ez * a.cos() + eb * a.sin()) * edge;
        if i > 0 && i + 1 < ne {
            e += normal * offset;
        }
        nodes.push(nodes[i] + e);
    }
    nodes
}

/// Sets every twist angle so that the material frame is space-parallel transported
/// from the start clamp's director (zero twist), then spreads the mismatch with
/// the finish clamp's director (taken in (-pi, pi]) evenly over the edges.
fn set_untwisted_frames(rod: &mut Rod, bc: &LoopBoundary) {
    let ne = rod.edges();
    let mut u = bc.start.director;
    let mut angles: Vec<f64> = Vec::with_capacity(ne);
    for i in 0..ne {
        let t = rod.geo.tangent[i];
        let raw = if i == 0 {
            signed_angle(&rod.geo.d1[0], &u, &t)
        } else {
            u = parallel_transport(&u, &rod.geo.tangent[i - 1], &t);
            u = (u - t * t.dot(&u)).normalize();
            // Zero twist: th_i - th_{i-1} + reference twist = 0 (eq. 5), not just mod 2 pi.
            unwrap_near(
                signed_angle(&rod.geo.d1[i], &u, &t),
                angles[i - 1] - rod.geo.ref_twist[i],
            )
        };
        angles.push(raw);
    }
    let last = ne - 1;
    let target = signed_angle(&rod.geo.d1[last], &bc.finish.director, &rod.geo.tangent[last]);
    let mismatch = unwrap_near(target, angles[last]) - angles[last];
    for (i, a) in angles.iter().enumerate() {
        rod.set_theta(i, a + mismatch * i as f64 / last as f64);
    }
    rod.rebase_frames();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simplified::braid::{Braid, Strand};

    const PHI: f64 = PI / 3.0;

    #[test]
    fn clamps_sit_on_the_braid_ends_with_the_tilted_helix_tangent() {
        for n in [2, 3] {
            for theta in [0.0, 0.7, 2.9] {
                let braid = Braid {
                    n,
                    theta,
                    l_b_bar: 56.6,
                };
                let bc = LoopBoundary::new(n, PHI, theta, braid.l_b_bar, EndTwist::Transported);
                let t = braid.half_span();
                assert!((bc.start.position - braid.point(Strand::A, t)).norm() < 1e-12);
                assert!((bc.finish.position - braid.point(Strand::B, -t)).norm() < 1e-12);
                for (e, helix) in [
                    (&bc.start, braid.tangent(Strand::A, t)),
                    (&bc.finish, braid.tangent(Strand::B, -t)),
                ] {
                    // Same azimuthal direction as the strand, pitch angle phi from the axis.
                    assert!((e.tangent.z - PHI.cos()).abs() < 1e-12);
                    let (a, b) = (
                        Vector3::new(e.tangent.x, e.tangent.y, 0.0),
                        Vector3::new(helix.x, helix.y, 0.0),
                    );
                    assert!((a.normalize() - b.normalize()).norm() < 1e-12);
                    assert!(e.director.dot(&e.tangent).abs() < 1e-12);
                    assert!((e.director.norm() - 1.0).abs() < 1e-12);
                }
                // Two-fold symmetry about y: x and z reversed, the loop's direction too.
                let r = |v: Vector3<f64>| Vector3::new(-v.x, v.y, -v.z);
                assert!((bc.finish.position - r(bc.start.position)).norm() < 1e-12);
                assert!((bc.finish.tangent + r(bc.start.tangent)).norm() < 1e-12);
                assert!((bc.finish.director - r(bc.start.director)).norm() < 1e-12);
            }
        }
    }

    #[test]
    fn transported_director_is_the_parallel_transport_along_the_tangent_path() {
        // Integrate parallel transport along the circle swept by the start tangent.
        let steps = 20000;
        let theta = 2.5;
        let mut u = LoopBoundary::new(3, PHI, 0.0, 50.0, EndTwist::Transported)
            .start
            .director;
        let mut t_prev = LoopBoundary::new(3, PHI, 0.0, 50.0, EndTwist::Transported)
            .start
            .tangent;
        for i in 1..=steps {
            let t = LoopBoundary::new(
                3,
                PHI,
                theta * i as f64 / steps as f64,
                50.0,
                EndTwist::Transported,
            )
            .start
            .tangent;
            u = parallel_transport(&u, &t_prev, &t);
            t_prev = t;
        }
        let bc = LoopBoundary::new(3, PHI, theta, 50.0, EndTwist::Transported);
        assert!(
            (u - bc.start.director).norm() < 1e-6,
            "transported {u:?} vs {:?}",
            bc.start.director
        );
        // The rigid convention differs from it by the spin theta cos(phi) about the tangent.
        let rigid = LoopBoundary::new(3, PHI, theta, 50.0, EndTwist::Clamped).start;
        let angle = signed_angle(&rigid.director, &bc.start.director, &rigid.tangent);
        assert!((angle - theta * PHI.cos()).abs() < 1e-12);
        assert!((rigid.twist_rate + PHI.cos()).abs() < 1e-15 && bc.start.twist_rate == 0.0);
    }

    #[test]
    fn planar_start_closes_exactly_with_the_clamps() {
        let bc = LoopBoundary::new(3, PHI, 0.0, 56.6, EndTwist::Transported);
        let k = 41;
        let edge = 80.9 / (k - 2) as f64;
        let nodes = planar_loop(&bc, k, edge);
        assert!((nodes[0] - (bc.start.position - bc.start.tangent * (0.5 * edge))).norm() < 1e-12);
        let end = bc.finish.position + bc.finish.tangent * (0.5 * edge);
        assert!(
            (nodes[k - 1] - end).norm() < 1e-9 * edge,
            "closure {:e}",
            (nodes[k - 1] - end).norm()
        );
        assert!(((nodes[1] - nodes[0]).normalize() - bc.start.tangent).norm() < 1e-12);
        assert!(((nodes[k - 1] - nodes[k - 2]).normalize() - bc.finish.tangent).norm() < 1e-12);
    }
}
