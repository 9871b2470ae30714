//! Implicit Euler time stepping with Newton's method, eq. (7):
//! M/dt ((q_new - q_old)/dt - v_old) - F_int(q_new) - F_ext = 0.
//!
//! Each Newton iterate solves the banded system (M/dt^2 + H) dq = -r in time
//! linear in K, with a backtracking line search on the incremental potential
//! Phi(q) = 1/(2 dt^2) |q - q_old - dt v_old|_M^2 + E(q) - F_ext.q whose gradient
//! is the residual r. A step whose Newton iteration fails is retried as two half
//! steps, up to `max_halvings` times; then the step ends with a `StepError`.
//! By default a step reuses the previous step's factored matrix while that
//! converges quickly (`NewtonOptions::reuse_factorization`).
//! Viscous damping F = -gamma M v (v = (q - q_old)/dt) folds into the inertia
//! coefficient: (1 + gamma dt)/dt^2 M (q - q_old) - M v_old/dt.
use crate::energies::{self, BANDWIDTH, Energies, Terms};
use crate::external::{self, Environment};
use crate::linalg::banded::{BandedLdlt, BandedSym};
use crate::rod::{End, Rod};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Newton and time-step control.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct NewtonOptions {
    /// Convergence: every free force entry below `rtol * F_s` and every free
    /// moment entry below `rtol * F_s * mean edge length`, where F_s is the
    /// problem's force scale (`force_scale`, by default EI/L^2 plus the weight).
    /// The force tolerance never drops below the roundoff floor of the
    /// stretching forces, 100 eps EA X / l_e (X: largest node coordinate or L, l_e: mean
    /// edge length), which no iterate can beat.
    pub rtol: f64,
    /// Force scale F_s (N); `None` takes EI/L^2 + |g| rho A L.
    pub force_scale: Option<f64>,
    /// Newton iterations per attempt.
    pub max_iterations: u32,
    /// Line-search halvings per Newton iterate.
    pub max_backtracks: u32,
    /// Time-step halvings before a step is declared failed.
    pub max_halvings: u32,
    /// Modified Newton across steps: a step of the same size (same inertia
    /// coefficient) starts from the previous step's factored Newton matrix
    /// instead of assembling and factoring a new one, and assembles a new one
    /// as soon as a reused one fails to cut the residual tenfold in a full
    /// Newton step. Each step still converges to `rtol`.
    pub reuse_factorization: bool,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        Self {
            rtol: 1e-6,
            force_scale: None,
            max_iterations: 30,
            max_backtracks: 12,
            max_halvings: 8,
            reuse_factorization: true,
        }
    }
}

/// What one call to `Stepper::step` did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StepReport {
    /// Substeps taken (1 unless Newton failed and the step was split).
    pub substeps: u32,
    /// Smallest substep used (s).
    pub min_dt: f64,
    /// Newton iterations summed over the substeps (failed attempts included).
    pub newton_iterations: u32,
    /// Largest free-DOF force residual at convergence (N).
    pub residual: f64,
    /// Negative pivots of the last Newton matrix (an indefinite Hessian).
    pub negative_pivots: usize,
    /// Elastic energies at the end of the step.
    pub energies: Energies,
}

/// Why a time step failed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum StepError {
    #[error("Newton's method failed after {halvings} time-step halvings (dt down to {dt:.3e} s): {reason}")]
    NotConverged {
        halvings: u32,
        dt: f64,
        reason: NewtonFailure,
    },
}

/// Why one Newton solve failed.
#[derive(Debug, Error, Clone, Copy, PartialEq)]
pub enum NewtonFailure {
    #[error("the Newton matrix could not be factorised")]
    Singular,
    #[error("the Newton direction is not a descent direction (indefinite Hessian)")]
    NotDescent,
    #[error("the line search found no decrease")]
    LineSearch,
    #[error("no convergence within the iteration cap (scaled residual {0:.3e})")]
    IterationCap(f64),
}

/// Implicit Euler stepper for one rod; owns every buffer of the Newton loop so
/// that a step allocates nothing.
#[derive(Clone, Debug)]
pub struct Stepper {
    pub options: NewtonOptions,
    grad: Vec<f64>,
    /// The DOFs at which `grad` is the final Newton iterate's (NaN: none).
    grad_q: Vec<f64>,
    resid: Vec<f64>,
    ext: Vec<f64>,
    delta: Vec<f64>,
    q_base: Vec<f64>,
    hess: BandedSym,
    /// Two factorisations: `ldlt[active]` is the current one; the other takes
    /// a new factorisation while the current one is kept for a rollback.
    ldlt: [BandedLdlt; 2],
    active: usize,
    /// The inertia coefficient `c_in` of the matrix factored in
    /// `ldlt[active]`, while that factorisation may be reused by the next step.
    factored_c_in: Option<f64>,
    /// `(active, factored_c_in)` at the last [`Stepper::checkpoint`].
    saved: Option<(usize, Option<f64>)>,
    factorizations: u64,
}

/// A converged Newton solve.
struct Attempt {
    iterations: u32,
    residual: f64,
    negative_pivots: usize,
    energies: Energies,
}

/// Where a Newton solve stands.
struct Iterate {
    energies: Energies,
    /// The incremental potential Phi.
    phi: f64,
    /// The largest free residual entry over its tolerance ([`scaled_norm`]).
    scaled: f64,
    /// Negative pivots of the factorisation in use.
    negative_pivots: usize,
    /// The assembled Hessian is this iterate's.
    hessian_current: bool,
    /// The factorisation in use is an earlier step's, not yet found wanting.
    stale: bool,
}

impl Iterate {
    /// The solve, converged after `iterations` with the force residual `residual`.
    fn converged(self, iterations: u32, residual: f64) -> Attempt {
        Attempt {
            iterations,
            residual,
            negative_pivots: self.negative_pivots,
            energies: self.energies,
        }
    }
}

/// The convergence test's tolerances on free forces (N) and moments (N m).
#[derive(Clone, Copy)]
struct Tolerances {
    force: f64,
    moment: f64,
}

impl Stepper {
    /// A stepper sized for `rod`.
    pub fn new(rod: &Rod, options: NewtonOptions) -> Self {
        let n = rod.ndof();
        Self {
            options,
            grad: vec![0.0; n],
            grad_q: vec![f64::NAN; n],
            resid: vec![0.0; n],
            ext: vec![0.0; n],
            delta: vec![0.0; n],
            q_base: vec![0.0; n],
            hess: BandedSym::new(n, BANDWIDTH),
            ldlt: [
                BandedLdlt::with_capacity(n, BANDWIDTH),
                BandedLdlt::with_capacity(n, BANDWIDTH),
            ],
            active: 0,
            factored_c_in: None,
            saved: None,
            factorizations: 0,
        }
    }

    /// Advances `rod` by `dt` under `env` and the constant extra forces `extra`
    /// (e.g. contact forces, eq. 7c), splitting the step when Newton fails.
    pub fn step(
        &mut self,
        rod: &mut Rod,
        env: &Environment,
        extra: Option<&[f64]>,
        dt: f64,
    ) -> Result<StepReport, StepError> {
        self.set_external(rod, env, extra);
        let mut report = StepReport {
            min_dt: dt,
            ..Default::default()
        };
        let mut remaining = dt;
        let mut h = dt;
        let mut halvings = 0;
        while remaining > 1e-12 * dt {
            h = h.min(remaining);
            match self.attempt(rod, env, h) {
                Ok(a) => {
                    rod.accept_step(h);
                    remaining -= h;
                    report.substeps += 1;
                    report.newton_iterations += a.iterations;
                    report.residual = a.residual;
                    report.negative_pivots = a.negative_pivots;
                    report.energies = a.energies;
                    report.min_dt = report.min_dt.min(h);
                }
                Err((reason, iterations)) => {
                    rod.restore();
                    report.newton_iterations += iterations;
                    halvings += 1;
                    if halvings > self.options.max_halvings {
                        return Err(StepError::NotConverged {
                            halvings: halvings - 1,
                            dt: h,
                            reason,
                        });
                    }
                    h /= 2.0;
                }
            }
        }
        self.grad_q.copy_from_slice(&rod.q);
        Ok(report)
    }

    /// The linearly implicit step: one Newton iteration of the step of length
    /// `dt` under `env` and `extra` from the guess `q_0 + dt v_0`, with the
    /// factorisation at hand when it is one of a step of that length (as
    /// [`Stepper::step`] reuses it), else one assembled at the guess.
    /// `velocity` gets `(q_1 - q_0) / dt` (prescribed at fixed DOFs). The rod
    /// is left at its last accepted state and the matrix factored for
    /// [`Stepper::solve_newton`]: a contact problem linearised about the
    /// start of the step.
    pub fn linear_step(
        &mut self,
        rod: &mut Rod,
        env: &Environment,
        extra: Option<&[f64]>,
        dt: f64,
        velocity: &mut [f64],
    ) -> Result<(), NewtonFailure> {
        self.set_external(rod, env, extra);
        let c_in = env.damping_factor(dt) / (dt * dt);
        guess(rod, dt);
        let reuse = self.options.reuse_factorization && self.factored_c_in == Some(c_in);
        let energies = energies::evaluate(
            rod,
            Terms::ALL,
            &mut self.grad,
            (!reuse).then_some(&mut self.hess),
        );
        if !reuse {
            self.factor(rod, c_in)?;
        }
        self.residual_and_potential(rod, dt, c_in, energies.total());
        self.solve_direction(rod);
        for (v, ((q, d), q0)) in velocity
            .iter_mut()
            .zip(rod.q.iter().zip(&self.delta).zip(&rod.q_old))
        {
            *v = (q + d - q0) / dt;
        }
        rod.restore();
        Ok(())
    }

    /// Applies the inverse of the factored Newton matrix `A = c_in M + H_E`
    /// (fixed DOFs held) of a step of length `dt` under `env` to `b`, in
    /// place: to first order, the extra displacement of that step under the
    /// extra generalised force `b`. Entries at fixed DOFs are ignored and come
    /// out zero. `false` (and `b` unchanged) when the factorisation at hand is
    /// not one of a step of that length.
    pub fn solve_newton(&self, rod: &Rod, env: &Environment, dt: f64, b: &mut [f64]) -> bool {
        if self.factored_c_in != Some(env.damping_factor(dt) / (dt * dt)) {
            return false;
        }
        for (x, fixed) in b.iter_mut().zip(&rod.fixed) {
            if *fixed {
                *x = 0.0;
            }
        }
        self.ldlt[self.active].solve_in_place(b);
        true
    }

    /// The elastic gradient (eq. 6) at `rod`'s current DOFs when the last
    /// step ended there: its final Newton iterate evaluated it, so the next
    /// step's explicit forces need not evaluate it again.
    pub fn elastic_gradient(&self, rod: &Rod) -> Option<&[f64]> {
        (self.grad_q == rod.q).then_some(&self.grad)
    }

    /// Keeps the current factorisation for [`Stepper::rollback`] (no copy: a
    /// new factorisation goes to the other buffer).
    pub fn checkpoint(&mut self) {
        self.saved = Some((self.active, self.factored_c_in));
    }

    /// Returns to the factorisation kept by the last [`Stepper::checkpoint`],
    /// so that a step redone from the same rod state repeats exactly.
    pub fn rollback(&mut self) {
        if let Some((active, c_in)) = self.saved {
            self.active = active;
            self.factored_c_in = c_in;
        }
    }

    /// Drops the factorisation at hand, so that the next step assembles one:
    /// after the rod's constraints or springs change.
    pub fn forget_factorization(&mut self) {
        self.factored_c_in = None;
    }

    /// Newton matrices assembled and factored since the stepper was made.
    pub fn factorizations(&self) -> u64 {
        self.factorizations
    }

    /// Force the clamp at `end` exerts on the rod after the last step (N), and
    /// its torque about the end edge (N m).
    pub fn clamp_reaction(&self, rod: &Rod, end: End) -> (Vector3<f64>, f64) {
        let d = rod.clamp_dofs(end);
        let f = Vector3::new(
            self.resid[d[0]] + self.resid[d[3]],
            self.resid[d[1]] + self.resid[d[4]],
            self.resid[d[2]] + self.resid[d[5]],
        );
        (f, self.resid[d[6]])
    }

    /// The problem's force scale F_s (N) used by the convergence test.
    pub fn force_scale(&self, rod: &Rod, env: &Environment) -> f64 {
        self.options.force_scale.unwrap_or_else(|| {
            let l = rod.length();
            rod.section.ei / (l * l) + env.gravity.norm() * rod.section.linear_density * l
        })
    }

    /// One Newton solve of the step of length `h` from the guess `q_0 + h
    /// v_0`: on failure, why and after how many iterations.
    fn attempt(&mut self, rod: &mut Rod, env: &Environment, h: f64) -> Result<Attempt, (NewtonFailure, u32)> {
        let c_in = env.damping_factor(h) / (h * h);
        let tol = self.tolerances(rod, env);
        guess(rod, h);
        let mut it = self.first_iterate(rod, h, c_in, tol);
        for iteration in 0..self.options.max_iterations {
            if it.scaled <= 1.0 {
                return Ok(it.converged(iteration, force_norm(rod, &self.resid)));
            }
            if !it.stale {
                self.refactor(rod, c_in, &mut it).map_err(|f| (f, iteration))?;
            }
            self.solve_direction(rod);
            let slope = self.slope(rod);
            if slope >= 0.0 || slope.is_nan() {
                if it.stale {
                    // The reused matrix gives no descent: factor this iterate's.
                    it.stale = false;
                    continue;
                }
                return Err((NewtonFailure::NotDescent, iteration));
            }
            self.line_search(rod, (h, c_in), tol, slope, &mut it)
                .map_err(|f| (f, iteration + 1))?;
        }
        if it.scaled <= 1.0 {
            return Ok(it.converged(self.options.max_iterations, force_norm(rod, &self.resid)));
        }
        Err((
            NewtonFailure::IterationCap(it.scaled),
            self.options.max_iterations,
        ))
    }

    /// The convergence test's tolerances (see [`NewtonOptions::rtol`]).
    fn tolerances(&self, rod: &Rod, env: &Environment) -> Tolerances {
        let edge = rod.length() / rod.edges() as f64;
        let extent = (0..rod.nodes())
            .map(|i| rod.node(i).amax())
            .fold(rod.length(), f64::max);
        let floor = 100.0 * f64::EPSILON * rod.section.ea * extent / edge;
        let force = (self.options.rtol * self.force_scale(rod, env)).max(floor);
        Tolerances {
            force,
            moment: force * edge,
        }
    }

    /// The iterate at the guess, with the factorisation at hand reused when
    /// it is one of a step of this length
    /// ([`NewtonOptions::reuse_factorization`]).
    fn first_iterate(&mut self, rod: &Rod, h: f64, c_in: f64, tol: Tolerances) -> Iterate {
        let reuse = self.options.reuse_factorization && self.factored_c_in == Some(c_in);
        let energies = if reuse {
            energies::evaluate(rod, Terms::ALL, &mut self.grad, None)
        } else {
            energies::evaluate(rod, Terms::ALL, &mut self.grad, Some(&mut self.hess))
        };
        let phi = self.residual_and_potential(rod, h, c_in, energies.total());
        let scaled = scaled_norm(rod, &self.resid, tol);
        // A reused matrix keeps the inertia it was factored with.
        let negative_pivots = match self.ldlt[self.active].inertia() {
            Some(inertia) if reuse => inertia.negative,
            _ => 0,
        };
        Iterate {
            energies,
            phi,
            scaled,
            negative_pivots,
            hessian_current: !reuse,
            stale: reuse,
        }
    }

    /// Factors the Newton matrix at the iterate, assembling its Hessian
    /// first unless that is at hand.
    fn refactor(&mut self, rod: &Rod, c_in: f64, it: &mut Iterate) -> Result<(), NewtonFailure> {
        if !it.hessian_current {
            energies::evaluate(rod, Terms::ALL, &mut self.grad, Some(&mut self.hess));
        }
        it.negative_pivots = self.factor(rod, c_in)?;
        Ok(())
    }

    /// The Newton direction `delta = -A^-1 r` (zero at fixed DOFs) with the
    /// current factorisation.
    fn solve_direction(&mut self, rod: &Rod) {
        for j in 0..rod.ndof() {
            self.delta[j] = if rod.fixed[j] { 0.0 } else { -self.resid[j] };
        }
        self.ldlt[self.active].solve_in_place(&mut self.delta);
    }

    /// The slope `r . delta` of Phi along the direction, over the free DOFs.
    fn slope(&self, rod: &Rod) -> f64 {
        let mut slope = 0.0;
        for j in 0..rod.ndof() {
            if !rod.fixed[j] {
                slope += self.resid[j] * self.delta[j];
            }
        }
        slope
    }

    /// Backtracking along the direction from the iterate `it` of the step
    /// `(h, c_in)`: the first step length, halving from 1, that decreases
    /// Phi enough (Armijo) or cuts the scaled residual becomes the iterate.
    /// A reused factorisation turns stale when it needed a backtrack or cut
    /// the residual less than tenfold.
    fn line_search(
        &mut self,
        rod: &mut Rod,
        (h, c_in): (f64, f64),
        tol: Tolerances,
        slope: f64,
        it: &mut Iterate,
    ) -> Result<(), NewtonFailure> {
        self.q_base.copy_from_slice(&rod.q);
        let mut alpha = 1.0;
        let mut backtracks = 0;
        loop {
            for ((q, b), d) in rod.q.iter_mut().zip(&self.q_base).zip(&self.delta) {
                *q = b + alpha * d;
            }
            rod.update_geometry();
            // Gradient only: the Hessian is assembled if another iteration follows.
            let trial = energies::evaluate(rod, Terms::ALL, &mut self.grad, None);
            let phi_trial = self.residual_and_potential(rod, h, c_in, trial.total());
            let scaled_trial = scaled_norm(rod, &self.resid, tol);
            let finite = phi_trial.is_finite() && scaled_trial.is_finite();
            if finite && (phi_trial <= it.phi + 1e-4 * alpha * slope || scaled_trial < it.scaled) {
                if it.stale && (backtracks > 0 || scaled_trial > 0.1 * it.scaled) {
                    it.stale = false;
                }
                it.energies = trial;
                it.phi = phi_trial;
                it.scaled = scaled_trial;
                it.hessian_current = false;
                return Ok(());
            }
            backtracks += 1;
            if backtracks > self.options.max_backtracks {
                return Err(NewtonFailure::LineSearch);
            }
            alpha *= 0.5;
        }
    }

    /// Factors `c_in M` plus the assembled Hessian (fixed DOFs held) into the
    /// buffer not kept for a rollback; returns the negative pivots.
    fn factor(&mut self, rod: &Rod, c_in: f64) -> Result<usize, NewtonFailure> {
        for j in 0..rod.ndof() {
            self.hess.add_diagonal(j, c_in * rod.mass[j]);
        }
        for spring in &rod.springs {
            self.hess.add_diagonal(spring.dof, spring.stiffness);
        }
        for j in 0..rod.ndof() {
            if rod.fixed[j] {
                self.hess.constrain(j);
            }
        }
        if self.saved.is_some_and(|(kept, _)| kept == self.active) {
            self.active = 1 - self.active;
        }
        self.factored_c_in = None;
        let inertia = self.ldlt[self.active]
            .factor(&self.hess)
            .map_err(|_| NewtonFailure::Singular)?;
        self.factored_c_in = Some(c_in);
        self.factorizations += 1;
        Ok(inertia.negative)
    }

    /// F_ext of eq. (7c): gravity and the extra forces.
    fn set_external(&mut self, rod: &Rod, env: &Environment, extra: Option<&[f64]>) {
        external::assemble(rod, env, extra, &mut self.ext);
    }

    /// Fills the residual r = grad Phi for every DOF (at a fixed DOF it is the
    /// reaction the constraint supplies) and returns Phi over the free DOFs.
    fn residual_and_potential(&mut self, rod: &Rod, h: f64, c_in: f64, elastic: f64) -> f64 {
        let mut phi = elastic;
        for j in 0..rod.ndof() {
            let m = rod.mass[j];
            let dq = rod.q[j] - rod.q_old[j];
            let inertia = c_in * m * dq - m * rod.velocity[j] / h;
            self.resid[j] = inertia + self.grad[j] - self.ext[j];
            if !rod.fixed[j] {
                let target = rod.velocity[j] / (h * c_in);
                phi += 0.5 * c_in * m * (dq - target) * (dq - target) - self.ext[j] * rod.q[j];
            }
        }
        for spring in &rod.springs {
            let force = spring.force(&rod.q, spring.anchor_after(h));
            self.resid[spring.dof] -= force;
            phi += 0.5 * force * force / spring.stiffness;
        }
        phi
    }
}

/// Sets the rod's DOFs to the step's first guess `q_0 + h v_0` (the
/// prescribed velocity at fixed DOFs).
fn guess(rod: &mut Rod, h: f64) {
    for j in 0..rod.ndof() {
        let v = if rod.fixed[j] {
            rod.prescribed_velocity[j]
        } else {
            rod.velocity[j]
        };
        rod.q[j] = rod.q_old[j] + h * v;
    }
    rod.update_geometry();
}

/// max over free DOFs of |r_j| / tol_j (forces and moments against their tolerances).
fn scaled_norm(rod: &Rod, r: &[f64], tol: Tolerances) -> f64 {
    let mut s: f64 = 0.0;
    for (j, v) in r.iter().enumerate() {
        if !rod.fixed[j] {
            let tol = if j % 4 == 3 { tol.moment } else { tol.force };
            s = s.max(v.abs() / tol);
        }
    }
    s
}

/// Largest free force (not moment) residual entry (N).
fn force_norm(rod: &Rod, r: &[f64]) -> f64 {
    r.iter()
        .enumerate()
        .filter(|(j, _)| !rod.fixed[*j] && j % 4 != 3)
        .fold(0.0, |m, (_, v)| m.max(v.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::rod::{End, Spring, node_dof};

    /// A straight rod clamped at its start, its far end free along the axis
    /// on a spring whose anchor moves by D and stops: at rest the spring
    /// carries D k k_r / (k + k_r), the axial stiffness k_r = EA / l of the
    /// rod's free length l (the clamp holds its first edge) in series with the
    /// spring's k.
    #[test]
    fn a_spring_in_series_with_the_rod_carries_the_series_force() {
        let k = 21;
        let points: Vec<Vector3<f64>> = (0..k).map(|i| Vector3::new(i as f64 / 20.0, 0.0, 0.0)).collect();
        let mut rod = Rod::new(&points, 1e-3, Material::default()).unwrap();
        rod.clamp(End::Start);
        rod.clamp(End::Finish);
        let far = node_dof(k - 1);
        for d in [node_dof(k - 2), far] {
            rod.fixed[d] = false;
        }
        let rod_stiffness = rod.section.ea / 0.95;
        let stiffness = 2.0 * rod_stiffness;
        let (distance, speed) = (1e-3, 1e-2);
        rod.springs.push(Spring {
            dof: far,
            stiffness,
            anchor: rod.q[far],
            velocity: speed,
        });
        let env = Environment {
            damping: 50.0,
            ..Environment::default()
        };
        let mut stepper = Stepper::new(&rod, NewtonOptions::default());
        let dt = 1e-3;
        let moving = (distance / speed / dt).round() as usize;
        for step in 0..moving + 4000 {
            if step == moving {
                rod.springs[0].velocity = 0.0;
            }
            stepper.step(&mut rod, &env, None, dt).unwrap();
        }
        let spring = rod.springs[0];
        let force = spring.force(&rod.q, spring.anchor);
        let series = distance * stiffness * rod_stiffness / (stiffness + rod_stiffness);
        assert!((spring.anchor - 1.0 - distance).abs() < 1e-12);
        assert!((force / series - 1.0).abs() < 1e-6, "{force} against {series}");
        let start = -stepper.clamp_reaction(&rod, End::Start).0.x;
        assert!(
            (start / series - 1.0).abs() < 1e-6,
            "the clamp holds what the spring pulls: {start}"
        );
    }
}
