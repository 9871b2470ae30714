//! Critical points theta*(l̄_k) of Ē (paper Fig. 13 c) by pseudo-arclength
//! continuation of the curve G(θ, l̄_k) = dĒ/dθ = 0, its folds, and the snap
//! l̄_k (the lower fold, where the critical point that is stable at large l̄_k
//! meets the unstable one, paper Sec. 5).
//!
//! The curve is parametrised by arclength in (θ, l̄_k / 20); each point is
//! corrected by Newton's method on (G = 0, tangent · (x - x_pred) = 0) with the
//! partial derivatives of G by central differences along the loop branch, which
//! is carried from point to point. A fold is where the tangent's l̄_k component
//! changes sign; there l̄_k(θ) on the curve is extremal and is located by
//! successive parabolic interpolation, solving G = 0 for l̄_k at each trial θ.
use super::landscape::{evaluate, gradient, refine_root};
use super::loop_rod::LoopSolver;
use super::{Params, SimplifiedError};
use serde::{Deserialize, Serialize};

/// Units of l̄_k per radian of theta in the arclength metric.
const LK_SCALE: f64 = 20.0;
/// Central-difference steps for dG/dθ (rad) and dG/dl̄_k.
const FD_THETA: f64 = 1e-3;
const FD_LK: f64 = 1e-3 * LK_SCALE;
/// Step of the coarse theta scan that brackets the first critical point.
const SCAN_STEP: f64 = 0.05;

/// What to trace: the critical points for l̄_k from `l_k_max` down, along the
/// connected curve through the critical point at `l_k_max` nearest to theta = 0
/// on the side dĒ/dθ(0) points to, until l̄_k leaves [l_k_min, l_k_max] or
/// theta leaves [theta_min, theta_max].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BifurcationSpec {
    pub params: Params,
    pub l_k_max: f64,
    pub l_k_min: f64,
    pub theta_min: f64,
    pub theta_max: f64,
    /// Largest arclength step in (theta, l̄_k / 20).
    pub max_step: f64,
    /// Cap on the number of curve points.
    pub max_points: usize,
}

impl BifurcationSpec {
    /// A window that holds both folds for the paper's epsilon and phi: the fold
    /// lengths grow about as n², so l̄_k runs from 25 n² + 50 down to 8 n², and
    /// theta from -1 up to min(5, n pi - 0.05) (the braid needs theta < n pi).
    pub fn for_params(params: Params) -> Self {
        let n2 = f64::from(params.n).powi(2);
        Self {
            params,
            l_k_max: 25.0 * n2 + 50.0,
            l_k_min: 8.0 * n2,
            theta_min: -1.0,
            theta_max: (f64::from(params.n) * std::f64::consts::PI - 0.05).min(5.0),
            max_step: 0.15,
            max_points: 2000,
        }
    }
}

impl Default for BifurcationSpec {
    /// `for_params` of the paper's parameters (n = 3).
    fn default() -> Self {
        Self::for_params(Params::default())
    }
}

/// One point of the critical curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BranchPoint {
    pub l_k_bar: f64,
    pub theta: f64,
    pub energy: f64,
    pub d2energy_dtheta2: f64,
    /// d²Ē/dθ² > 0.
    pub stable: bool,
    /// Negative eigenvalues of the clamped loop's stiffness (0: loop stable).
    pub loop_negative_pivots: usize,
}

/// A fold (saddle-node) of the critical curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fold {
    pub l_k_bar: f64,
    pub theta: f64,
}

/// The traced critical curve, its folds in the order met from l_k_max, and the
/// snap: the first fold met, where the critical point stable at l_k_max ends.
/// With no critical point at l_k_max (theta in [theta_min, theta_max]) the branch is empty.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bifurcation {
    pub spec: BifurcationSpec,
    pub branch: Vec<BranchPoint>,
    pub folds: Vec<Fold>,
    pub snap: Option<Fold>,
}

/// A converged curve point with its gradient of G and the solver there.
struct Node {
    theta: f64,
    lk: f64,
    g_theta: f64,
    g_lk: f64,
    energy: f64,
    negative_pivots: usize,
    solver: LoopSolver,
}

/// G at (theta, lk) from a copy of `solver`.
fn probe(solver: &LoopSolver, theta: f64, lk: f64) -> Result<f64, SimplifiedError> {
    let mut copy = solver.clone();
    gradient(&mut copy, theta, lk)
}

/// (dG/dθ, dG/dl̄_k) at the solver's state by central differences.
fn partials(solver: &LoopSolver) -> Result<(f64, f64), SimplifiedError> {
    let (t, l) = (solver.theta(), solver.l_k_bar());
    let gt = (probe(solver, t + FD_THETA, l)? - probe(solver, t - FD_THETA, l)?) / (2.0 * FD_THETA);
    let gl = (probe(solver, t, l + FD_LK)? - probe(solver, t, l - FD_LK)?) / (2.0 * FD_LK);
    Ok((gt, gl))
}

fn node(mut solver: LoopSolver) -> Result<Node, SimplifiedError> {
    let at = evaluate(&mut solver);
    let (g_theta, g_lk) = partials(&solver)?;
    Ok(Node {
        theta: solver.theta(),
        lk: solver.l_k_bar(),
        g_theta,
        g_lk,
        energy: at.energy,
        negative_pivots: at.loop_negative_pivots,
        solver,
    })
}

/// Unit tangent of the curve in (theta, l̄_k / LK_SCALE), oriented along `along`.
fn tangent(n: &Node, along: (f64, f64)) -> (f64, f64) {
    let (a, b) = (-n.g_lk * LK_SCALE, n.g_theta);
    let norm = a.hypot(b);
    let (a, b) = (a / norm, b / norm);
    if a * along.0 + b * along.1 < 0.0 {
        (-a, -b)
    } else {
        (a, b)
    }
}

/// Newton corrector from the predictor `(tp, lp)` on G = 0 and tangent · (x - x_p) = 0,
/// with the Jacobian of the last point (chord method).
fn correct(last: &Node, tau: (f64, f64), (tp, lp): (f64, f64)) -> Result<(LoopSolver, u32), SimplifiedError> {
    let mut solver = last.solver.clone();
    let (mut t, mut l) = (tp, lp);
    let (a, b) = (last.g_theta, last.g_lk * LK_SCALE);
    let det = a * tau.1 - b * tau.0;
    for iteration in 1..=8 {
        let g = gradient(&mut solver, t, l)?;
        let c = tau.0 * (t - tp) + tau.1 * (l - lp) / LK_SCALE;
        // Solve [a b; tau0 tau1] (dt, dl/LK_SCALE) = -(g, c).
        let dt = -(g * tau.1 - b * c) / det;
        let dl = -(a * c - tau.0 * g) / det * LK_SCALE;
        t += dt;
        l += dl;
        if dt.abs() < 1e-8 && (dl / LK_SCALE).abs() < 1e-8 {
            solver.move_to(t, l)?;
            return Ok((solver, iteration));
        }
    }
    Err(SimplifiedError::Stalled {
        theta: t,
        l_k_bar: l,
        reason: "pseudo-arclength corrector did not converge".into(),
    })
}

/// l̄_k on the curve at fixed theta (secant iterations on G from `solver`'s state).
fn lk_on_curve(solver: &mut LoopSolver, theta: f64) -> Result<f64, SimplifiedError> {
    let mut l0 = solver.l_k_bar();
    let mut g0 = gradient(solver, theta, l0)?;
    let mut l1 = l0 + FD_LK;
    let mut g1 = gradient(solver, theta, l1)?;
    for _ in 0..30 {
        if g1 == g0 {
            break;
        }
        let l2 = l1 - g1 * (l1 - l0) / (g1 - g0);
        (l0, g0) = (l1, g1);
        l1 = l2;
        g1 = gradient(solver, theta, l1)?;
        if (l1 - l0).abs() < 1e-10 * l1 {
            break;
        }
    }
    Ok(l1)
}

/// The extremum of l̄_k(θ) on the curve between two points where the tangent's
/// l̄_k component changes sign, by successive parabolic interpolation.
fn locate_fold(a: &Node, b: &Node) -> Result<Fold, SimplifiedError> {
    let mut solver = a.solver.clone();
    let mid = 0.5 * (a.theta + b.theta);
    let lm = lk_on_curve(&mut solver, mid)?;
    let mut pts = [(a.theta, a.lk), (mid, lm), (b.theta, b.lk)];
    // A maximum of l̄_k if the middle point lies above the chord.
    let chord = a.lk + (b.lk - a.lk) * (mid - a.theta) / (b.theta - a.theta);
    let sign = if lm > chord { 1.0 } else { -1.0 };
    for _ in 0..30 {
        pts.sort_by(|p, q| p.0.total_cmp(&q.0));
        let [(x0, y0), (x1, y1), (x2, y2)] = [pts[0], pts[1], pts[2]];
        let d1 = (y1 - y0) / (x1 - x0);
        let d2 = (y2 - y1) / (x2 - x1);
        let curv = (d2 - d1) / (x2 - x0);
        if curv == 0.0 {
            break;
        }
        let x = 0.5 * (x0 + x1) - d1 / (2.0 * curv);
        let x = x.clamp(x0.min(x2), x0.max(x2));
        if pts.iter().any(|p| (p.0 - x).abs() < 1e-9) {
            break;
        }
        let y = lk_on_curve(&mut solver, x)?;
        // Replace the point with the least extreme l̄_k.
        let worst = (0..3)
            .min_by(|&i, &j| (sign * pts[i].1).total_cmp(&(sign * pts[j].1)))
            .unwrap_or(0);
        pts[worst] = (x, y);
    }
    let best = pts
        .iter()
        .copied()
        .max_by(|p, q| (sign * p.1).total_cmp(&(sign * q.1)))
        .unwrap_or((mid, lm));
    Ok(Fold {
        l_k_bar: best.1,
        theta: best.0,
    })
}

/// Moves the solver to the critical point nearest to theta = 0 at its l̄_k,
/// scanning downhill (up if dĒ/dθ(0) < 0, else down); false if there is none in
/// [theta_min, theta_max].
fn first_critical_point(
    solver: &mut LoopSolver,
    theta_min: f64,
    theta_max: f64,
) -> Result<bool, SimplifiedError> {
    let lk = solver.l_k_bar();
    let mut prev = (0.0, gradient(solver, 0.0, lk)?);
    let (step, end) = if prev.1 < 0.0 {
        (SCAN_STEP, theta_max)
    } else {
        (-SCAN_STEP, theta_min)
    };
    let mut theta = 0.0;
    while (end - theta) * step > 0.0 {
        theta = if step > 0.0 {
            (theta + step).min(end)
        } else {
            (theta + step).max(end)
        };
        let g = gradient(solver, theta, lk)?;
        if (prev.1 < 0.0) != (g < 0.0) {
            let root = refine_root(solver, prev, (theta, g))?;
            solver.move_to(root, lk)?;
            return Ok(true);
        }
        prev = (theta, g);
    }
    Ok(false)
}

fn branch_point(n: &Node) -> BranchPoint {
    BranchPoint {
        l_k_bar: n.lk,
        theta: n.theta,
        energy: n.energy,
        d2energy_dtheta2: n.g_theta,
        stable: n.g_theta > 0.0,
        loop_negative_pivots: n.negative_pivots,
    }
}

/// Traces the critical curve of `spec` (see [`BifurcationSpec`]).
pub fn bifurcation(spec: &BifurcationSpec) -> Result<Bifurcation, SimplifiedError> {
    let ordered = spec.l_k_max > spec.l_k_min && spec.l_k_min > 0.0 && spec.theta_max > spec.theta_min;
    if !ordered
        || spec.theta_min > 0.0
        || spec.theta_max < 0.0
        || spec.max_step <= 0.0
        || spec.max_step.is_nan()
    {
        return Err(SimplifiedError::InvalidParameter(
            "a bifurcation diagram needs 0 < l_k_min < l_k_max, theta_min <= 0 <= theta_max and a positive step".into(),
        ));
    }
    let mut solver = LoopSolver::new(&spec.params, spec.l_k_max)?;
    if !first_critical_point(&mut solver, spec.theta_min, spec.theta_max)? {
        return Ok(Bifurcation {
            spec: *spec,
            branch: Vec::new(),
            folds: Vec::new(),
            snap: None,
        });
    }
    let mut last = node(solver)?;
    let mut tau = tangent(&last, (0.0, -1.0));
    let mut branch = vec![branch_point(&last)];
    let mut folds = Vec::new();
    let mut ds = spec.max_step;
    let min_step = spec.max_step * 1e-4;
    while branch.len() < spec.max_points {
        let predicted = (last.theta + ds * tau.0, last.lk + ds * tau.1 * LK_SCALE);
        let corrected = correct(&last, tau, predicted).and_then(|(s, it)| Ok((node(s)?, it)));
        let (next, iterations) = match corrected {
            Ok(v) => v,
            Err(_)
                if predicted.0 > spec.theta_max
                    || predicted.0 < spec.theta_min
                    || predicted.1 < spec.l_k_min =>
            {
                break;
            }
            Err(e) => {
                ds *= 0.5;
                if ds < min_step {
                    return Err(e);
                }
                continue;
            }
        };
        let next_tau = tangent(&next, tau);
        if (next_tau.1 > 0.0) != (tau.1 > 0.0) {
            folds.push(locate_fold(&last, &next)?);
        }
        branch.push(branch_point(&next));
        let outside = next.lk < spec.l_k_min
            || next.lk > spec.l_k_max
            || next.theta < spec.theta_min
            || next.theta > spec.theta_max;
        last = next;
        tau = next_tau;
        if outside {
            break;
        }
        if iterations <= 3 {
            ds = (ds * 1.5).min(spec.max_step);
        } else if iterations >= 6 {
            ds *= 0.5;
        }
    }
    Ok(Bifurcation {
        spec: *spec,
        branch,
        snap: folds.first().copied(),
        folds,
    })
}
