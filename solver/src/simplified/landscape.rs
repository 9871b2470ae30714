//! The total energy Ē(θ) = Ē_b + Ē_l at fixed l̄_k (paper Sec. 5, Fig. 13 a, b):
//! the loop is followed along theta by continuation from the planar loop at
//! theta = 0; dĒ/dθ is the braid's closed form plus the loop's reaction-moment
//! identity. Critical points are the sign changes of dĒ/dθ, refined by the
//! Illinois method; a critical point is stable when d²Ē/dθ² > 0 (central
//! differences of dĒ/dθ along the branch).
use super::loop_rod::LoopSolver;
use super::{Params, SimplifiedError};
use serde::{Deserialize, Serialize};

/// Step of the central difference for d²Ē/dθ² at a critical point (rad).
const CURVATURE_STEP: f64 = 1e-3;

/// What to compute: Ē(θ) on an even grid of `points` angles in [theta_min, theta_max].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LandscapeSpec {
    pub params: Params,
    pub l_k_bar: f64,
    pub theta_min: f64,
    pub theta_max: f64,
    pub points: usize,
}

impl Default for LandscapeSpec {
    /// Fig. 13 (a, b): l̄_k = 137.5, theta in [0, 5], 100 points.
    fn default() -> Self {
        Self {
            params: Params::default(),
            l_k_bar: 137.5,
            theta_min: 0.0,
            theta_max: 5.0,
            points: 100,
        }
    }
}

/// Ē and its parts at one theta (energies in EI/h).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LandscapePoint {
    pub theta: f64,
    /// Ē_b, eq. (14).
    pub braid_energy: f64,
    /// Ē_l, eq. (15).
    pub loop_energy: f64,
    /// Twisting part of Ē_l.
    pub loop_twisting: f64,
    /// Ē = Ē_b + Ē_l.
    pub energy: f64,
    /// dĒ/dθ.
    pub denergy_dtheta: f64,
    /// Negative eigenvalues of the clamped loop's stiffness (0: loop stable).
    pub loop_negative_pivots: usize,
}

/// A critical point dĒ/dθ = 0.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CriticalPoint {
    pub theta: f64,
    pub energy: f64,
    pub d2energy_dtheta2: f64,
    /// Stable with respect to theta: d²Ē/dθ² > 0.
    pub stable: bool,
    /// Negative eigenvalues of the clamped loop's stiffness (0: loop stable).
    pub loop_negative_pivots: usize,
    /// Loop centreline there (units of h).
    pub loop_centerline: Vec<[f64; 3]>,
}

/// Ē(θ) along one loop branch and its critical points.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Landscape {
    pub spec: LandscapeSpec,
    pub points: Vec<LandscapePoint>,
    pub critical_points: Vec<CriticalPoint>,
    /// Newton iterations spent (grid, root refinement and curvatures).
    pub newton_iterations: u64,
}

/// Ē, dĒ/dθ and the loop's stability at the solver's current state.
pub(crate) fn evaluate(solver: &mut LoopSolver) -> LandscapePoint {
    let eq = solver.equilibrium();
    let braid = solver.params().braid(solver.theta(), solver.l_k_bar());
    let braid_energy = braid.energy();
    LandscapePoint {
        theta: solver.theta(),
        braid_energy,
        loop_energy: eq.energy,
        loop_twisting: eq.twisting,
        energy: braid_energy + eq.energy,
        denergy_dtheta: braid.energy_derivative() + eq.denergy_dtheta,
        loop_negative_pivots: eq.negative_pivots,
    }
}

/// dĒ/dθ after moving `solver` along its branch to (`theta`, `l_k_bar`).
pub(crate) fn gradient(solver: &mut LoopSolver, theta: f64, l_k_bar: f64) -> Result<f64, SimplifiedError> {
    solver.move_to(theta, l_k_bar)?;
    Ok(evaluate(solver).denergy_dtheta)
}

/// dĒ/dθ after moving `solver` to `theta` at its current l̄_k.
fn gradient_at(solver: &mut LoopSolver, theta: f64) -> Result<f64, SimplifiedError> {
    let lk = solver.l_k_bar();
    gradient(solver, theta, lk)
}

/// d²Ē/dθ² at the solver's state by central differences along the branch.
pub(crate) fn curvature_at(solver: &LoopSolver) -> Result<f64, SimplifiedError> {
    let theta = solver.theta();
    let mut probe = solver.clone();
    let up = gradient_at(&mut probe, theta + CURVATURE_STEP)?;
    let down = gradient_at(&mut probe, theta - CURVATURE_STEP)?;
    Ok((up - down) / (2.0 * CURVATURE_STEP))
}

/// Refines a root of dĒ/dθ bracketed by (a, ga), (b, gb) with the Illinois
/// method, moving `solver` (which starts at one end of the bracket) along the branch.
pub(crate) fn refine_root(
    solver: &mut LoopSolver,
    (mut a, mut ga): (f64, f64),
    (mut b, mut gb): (f64, f64),
) -> Result<f64, SimplifiedError> {
    let mut side = 0;
    for _ in 0..60 {
        let c = (a * gb - b * ga) / (gb - ga);
        let gc = gradient_at(solver, c)?;
        if gc == 0.0 || (b - a).abs() < 1e-11 {
            return Ok(c);
        }
        if (gc > 0.0) == (gb > 0.0) {
            b = c;
            gb = gc;
            if side == 1 {
                ga *= 0.5;
            }
            side = 1;
        } else {
            a = c;
            ga = gc;
            if side == -1 {
                gb *= 0.5;
            }
            side = -1;
        }
        if (b - a).abs() < 1e-10 {
            break;
        }
    }
    Ok((a * gb - b * ga) / (gb - ga))
}

/// The critical point bracketed by the last two grid points, from a copy of the solver.
fn critical_point(
    solver: &LoopSolver,
    left: (f64, f64),
    right: (f64, f64),
) -> Result<(CriticalPoint, u64), SimplifiedError> {
    let mut probe = solver.clone();
    let start = probe.newton_iterations();
    let theta = refine_root(&mut probe, left, right)?;
    probe.move_to(theta, probe.l_k_bar())?;
    let at = evaluate(&mut probe);
    let d2 = curvature_at(&probe)?;
    let point = CriticalPoint {
        theta,
        energy: at.energy,
        d2energy_dtheta2: d2,
        stable: d2 > 0.0,
        loop_negative_pivots: at.loop_negative_pivots,
        loop_centerline: probe.centerline(),
    };
    Ok((point, probe.newton_iterations() - start))
}

/// Ē(θ) on the grid of `spec`, following the loop branch that is planar at theta = 0.
pub fn landscape(spec: &LandscapeSpec) -> Result<Landscape, SimplifiedError> {
    if spec.points < 2 || spec.theta_max <= spec.theta_min || !spec.theta_max.is_finite() {
        return Err(SimplifiedError::InvalidParameter(
            "a landscape needs at least 2 points and theta_max > theta_min".into(),
        ));
    }
    let mut solver = LoopSolver::new(&spec.params, spec.l_k_bar)?;
    let mut points: Vec<LandscapePoint> = Vec::with_capacity(spec.points);
    let mut critical_points = Vec::new();
    let mut extra = 0;
    for i in 0..spec.points {
        let theta = spec.theta_min + (spec.theta_max - spec.theta_min) * i as f64 / (spec.points - 1) as f64;
        solver.move_to(theta, spec.l_k_bar)?;
        let p = evaluate(&mut solver);
        if let Some(prev) = points.last() {
            let (g0, g1) = (prev.denergy_dtheta, p.denergy_dtheta);
            if (g0 < 0.0 && g1 >= 0.0) || (g0 > 0.0 && g1 <= 0.0) {
                let (c, iterations) = critical_point(&solver, (prev.theta, g0), (theta, g1))?;
                critical_points.push(c);
                extra += iterations;
            }
        }
        points.push(p);
    }
    Ok(Landscape {
        spec: *spec,
        points,
        critical_points,
        newton_iterations: solver.newton_iterations() + extra,
    })
}
