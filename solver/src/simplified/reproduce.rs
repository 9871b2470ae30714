//! The paper's simplified-model results (Sec. 5, Figs. 13-15) in one call
//! (the `docs/SIMPLIFIED_MODEL.md` document is written from them by the
//! binary, `src/simplified_doc.rs`).
use super::bifurcation::{Bifurcation, BifurcationSpec, Fold, bifurcation};
use super::landscape::{Landscape, LandscapeSpec, landscape};
use super::loop_rod::{EndTwist, LoopSolver};
use super::{Params, SimplifiedError};
use serde::{Deserialize, Serialize};

/// What to reproduce; the defaults are the paper's cases.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ReproductionSpec {
    /// Model parameters of Figs. 13-14 (n = 3, epsilon = 0.7, phi = pi/3, h = 1.6 mm).
    pub params: Params,
    /// l̄_k of the energy landscape (Fig. 13 a, b).
    pub landscape_l_k_bar: f64,
    /// Grid points of the landscape on theta in [0, 5].
    pub landscape_points: usize,
    /// Rod radii of the h sweep (Fig. 14), m.
    pub radii: Vec<f64>,
    /// Unknotting numbers of the n sweep (Fig. 15, at `n_sweep_radius`).
    pub unknotting_numbers: Vec<u32>,
    pub n_sweep_radius: f64,
    /// Nodes per strand for the braid's discretisation check.
    pub braid_nodes: Vec<usize>,
    /// Loop nodes K for the discretisation study of the folds.
    pub loop_nodes: Vec<usize>,
    /// Angles of the dĒ_l/dθ check (reaction identity vs finite differences).
    pub derivative_thetas: Vec<f64>,
}

impl Default for ReproductionSpec {
    fn default() -> Self {
        Self {
            params: Params::default(),
            landscape_l_k_bar: 137.5,
            landscape_points: 100,
            radii: vec![1.5e-3, 2.0e-3, 2.5e-3, 3.0e-3, 3.5e-3],
            unknotting_numbers: vec![1, 2, 3, 4, 5],
            n_sweep_radius: 1.6e-3,
            braid_nodes: vec![20, 40, 80, 160, 320, 640],
            loop_nodes: vec![41, 81, 161],
            derivative_thetas: vec![0.5, 1.5, 2.5, 3.5, 4.5],
        }
    }
}

/// The DER braid energy against eq. (14).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BraidRow {
    pub nodes: usize,
    pub discrete: f64,
    pub closed_form: f64,
    pub relative_error: f64,
    /// Order from the previous row: ln(error ratio) / ln(spacing ratio), the
    /// spacing being 2T / (nodes - 2).
    pub observed_order: Option<f64>,
}

/// dĒ_l/dθ from the reaction identity against central differences of Ē_l.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DerivativeRow {
    pub theta: f64,
    pub identity: f64,
    pub finite_difference: f64,
}

/// Folds of one traced critical curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepRow {
    pub n: u32,
    pub radius: f64,
    pub loop_nodes: usize,
    /// The snap: the first fold from large l̄_k.
    pub snap_l_k_bar: Option<f64>,
    /// The other fold, where the second stable state is born.
    pub upper_l_k_bar: Option<f64>,
    /// Points on the traced critical curve (0: no critical point at l_k_max).
    pub curve_points: usize,
}

/// One twist convention of the loop's clamps.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConventionRow {
    pub end_twist: EndTwist,
    /// (theta, stable) of the critical points at the landscape's l̄_k.
    pub critical_points: Vec<(f64, bool)>,
    pub folds: Vec<Fold>,
    /// Why the landscape or the diagram could not be completed.
    pub failure: Option<String>,
}

impl ConventionRow {
    /// The paper's sequence: three critical points (stable, unstable, stable) at
    /// the landscape's l̄_k and two folds.
    pub fn matches_paper(&self) -> bool {
        let stability: Vec<bool> = self.critical_points.iter().map(|c| c.1).collect();
        stability == [true, false, true] && self.folds.len() == 2 && self.failure.is_none()
    }
}

/// Everything `docs/SIMPLIFIED_MODEL.md` reports.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reproduction {
    pub spec: ReproductionSpec,
    pub braid_convergence: Vec<BraidRow>,
    pub derivative_check: Vec<DerivativeRow>,
    pub landscape: Landscape,
    pub bifurcation: Bifurcation,
    pub loop_convergence: Vec<SweepRow>,
    pub radius_sweep: Vec<SweepRow>,
    pub n_sweep: Vec<SweepRow>,
    pub conventions: Vec<ConventionRow>,
    /// Loop centreline at theta = 0 and the landscape's l̄_k (units of h).
    pub planar_loop: Vec<[f64; 3]>,
}

/// DER braid energies at `nodes` per strand against eq. (14) (n, l̄_b from `params`).
pub fn braid_convergence(
    params: &Params,
    l_k_bar: f64,
    theta: f64,
    nodes: &[usize],
) -> Result<Vec<BraidRow>, SimplifiedError> {
    let braid = params.braid(theta, l_k_bar);
    let exact = braid.energy();
    let mut rows: Vec<BraidRow> = Vec::with_capacity(nodes.len());
    for &k in nodes {
        let discrete = braid.discrete_energy(k)?;
        let relative_error = (discrete / exact - 1.0).abs();
        let observed_order = rows
            .last()
            .map(|p| (p.relative_error / relative_error).ln() / ((k - 2) as f64 / (p.nodes - 2) as f64).ln());
        rows.push(BraidRow {
            nodes: k,
            discrete,
            closed_form: exact,
            relative_error,
            observed_order,
        });
    }
    Ok(rows)
}

/// dĒ_l/dθ by the reaction identity and by central differences of Ē_l (step
/// `step`) along the branch from theta = 0, at each of `thetas` (ascending).
pub fn derivative_check(
    params: &Params,
    l_k_bar: f64,
    thetas: &[f64],
    step: f64,
) -> Result<Vec<DerivativeRow>, SimplifiedError> {
    let mut solver = LoopSolver::new(params, l_k_bar)?;
    let mut rows = Vec::with_capacity(thetas.len());
    for &theta in thetas {
        solver.move_to(theta, l_k_bar)?;
        let identity = solver.equilibrium().denergy_dtheta;
        let mut probe = solver.clone();
        probe.move_to(theta + step, l_k_bar)?;
        let up = probe.equilibrium().energy;
        probe.move_to(theta - step, l_k_bar)?;
        let down = probe.equilibrium().energy;
        rows.push(DerivativeRow {
            theta,
            identity,
            finite_difference: (up - down) / (2.0 * step),
        });
    }
    Ok(rows)
}

/// The snap-through l̄_k of the paper's simplified model (epsilon = 0.7,
/// phi = pi/3) for `n` passes and rod radius `radius`: the dashed reference of
/// Figs 14 and 15; `None` where the model has no snap (n = 1).
pub fn snap_l_k_bar(n: u32, radius: f64) -> Result<Option<f64>, SimplifiedError> {
    let params = Params {
        n,
        radius,
        ..Params::default()
    };
    Ok(sweep_row(params)?.0.snap_l_k_bar)
}

/// The folds of the simplified model for `params` (one row of Figs. 14 and 15).
pub fn sweep_row(params: Params) -> Result<(SweepRow, Bifurcation), SimplifiedError> {
    let b = bifurcation(&BifurcationSpec::for_params(params))?;
    let row = SweepRow {
        n: params.n,
        radius: params.radius,
        loop_nodes: params.loop_nodes,
        snap_l_k_bar: b.snap.map(|f| f.l_k_bar),
        upper_l_k_bar: b.folds.get(1).map(|f| f.l_k_bar),
        curve_points: b.branch.len(),
    };
    Ok((row, b))
}

fn convention(params: Params, spec: &LandscapeSpec) -> ConventionRow {
    let mut row = ConventionRow {
        end_twist: params.end_twist,
        critical_points: Vec::new(),
        folds: Vec::new(),
        failure: None,
    };
    match landscape(&LandscapeSpec { params, ..*spec }) {
        Ok(l) => row.critical_points = l.critical_points.iter().map(|c| (c.theta, c.stable)).collect(),
        Err(e) => row.failure = Some(format!("landscape: {e}")),
    }
    match bifurcation(&BifurcationSpec::for_params(params)) {
        Ok(b) => row.folds = b.folds,
        Err(e) => {
            let text = format!("diagram: {e}");
            row.failure = Some(row.failure.map_or(text.clone(), |f| format!("{f}; {text}")));
        }
    }
    row
}

/// Runs every case of `spec` (a few tens of seconds at the defaults).
pub fn reproduce(spec: &ReproductionSpec) -> Result<Reproduction, SimplifiedError> {
    let p = spec.params;
    let lk = spec.landscape_l_k_bar;
    let lspec = LandscapeSpec {
        params: p,
        l_k_bar: lk,
        theta_min: 0.0,
        theta_max: 5.0,
        points: spec.landscape_points,
    };
    let braid_rows = braid_convergence(&p, lk, 0.0, &spec.braid_nodes)?;
    let derivative_rows = derivative_check(&p, lk, &spec.derivative_thetas, 1e-3)?;
    let land = landscape(&lspec)?;
    let (_, main) = sweep_row(p)?;
    let mut loop_rows = Vec::new();
    for &k in &spec.loop_nodes {
        loop_rows.push(sweep_row(Params { loop_nodes: k, ..p })?.0);
    }
    let mut radius_rows = Vec::new();
    for &h in &spec.radii {
        radius_rows.push(sweep_row(Params { radius: h, ..p })?.0);
    }
    let mut n_rows = Vec::new();
    for &n in &spec.unknotting_numbers {
        n_rows.push(
            sweep_row(Params {
                n,
                radius: spec.n_sweep_radius,
                ..p
            })?
            .0,
        );
    }
    let conventions = [EndTwist::Transported, EndTwist::Clamped, EndTwist::Free]
        .into_iter()
        .map(|t| convention(Params { end_twist: t, ..p }, &lspec))
        .collect();
    let planar_loop = LoopSolver::new(&p, lk)?.centerline();
    Ok(Reproduction {
        spec: spec.clone(),
        braid_convergence: braid_rows,
        derivative_check: derivative_rows,
        landscape: land,
        bifurcation: main,
        loop_convergence: loop_rows,
        radius_sweep: radius_rows,
        n_sweep: n_rows,
        conventions,
        planar_loop,
    })
}
