//! The paper's simplified-model results (Sec. 5, Figs. 13-15) in one call, and
//! the `docs/SIMPLIFIED_MODEL.md` document built from them (markdown and SVG
//! strings; writing the files is the caller's business).
use super::bifurcation::{Bifurcation, BifurcationSpec, Fold, bifurcation};
use super::landscape::{Landscape, LandscapeSpec, landscape};
use super::loop_rod::{EndTwist, LoopSolver};
use super::{Params, SimplifiedError, svg};
use serde::{Deserialize, Serialize};
use std::fmt::Write;

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

/// A generated document: markdown and the SVG figures it links (relative to
/// the markdown file, under `simplified/`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Document {
    pub markdown: String,
    pub figures: Vec<Figure>,
}

/// One SVG figure: file name (in the `simplified/` folder next to the document) and content.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Figure {
    pub file_name: String,
    pub svg: String,
}

fn opt(v: Option<f64>, decimals: usize) -> String {
    v.map_or("none".into(), |x| format!("{x:.decimals$}"))
}

/// Richardson extrapolation of a second-order sequence at K, 2K-ish: f + (f - f_prev) / (r² - 1).
fn extrapolate(rows: &[SweepRow], pick: fn(&SweepRow) -> Option<f64>) -> Option<f64> {
    let [.., a, b] = rows else { return None };
    let (fa, fb) = (pick(a)?, pick(b)?);
    let r = (b.loop_nodes - 2) as f64 / (a.loop_nodes - 2) as f64;
    Some(fb + (fb - fa) / (r * r - 1.0))
}

impl Reproduction {
    /// `docs/SIMPLIFIED_MODEL.md` and its figures.
    pub fn document(&self) -> Document {
        let p = &self.spec.params;
        let lk = self.spec.landscape_l_k_bar;
        let mut figures = Vec::new();
        figures.push(Figure {
            file_name: "schematic.svg".into(),
            svg: svg::schematic(p, lk, 0.0, &self.planar_loop, 1.0),
        });
        let critical: Vec<(f64, bool, Vec<[f64; 3]>)> = self
            .landscape
            .critical_points
            .iter()
            .map(|c| (c.theta, c.stable, c.loop_centerline.clone()))
            .collect();
        figures.push(Figure {
            file_name: "critical_shapes.svg".into(),
            svg: svg::critical_shapes(p, lk, &critical),
        });
        figures.push(Figure {
            file_name: "landscape.svg".into(),
            svg: svg::landscape(&self.landscape),
        });
        figures.push(Figure {
            file_name: "bifurcation.svg".into(),
            svg: svg::bifurcation(&self.bifurcation, &[(lk, format!("l̄_k = {lk}"))]),
        });
        let radius: Vec<(f64, Option<f64>)> = self
            .radius_sweep
            .iter()
            .map(|r| (r.radius * 1e3, r.snap_l_k_bar))
            .collect();
        let mean = {
            let v: Vec<f64> = radius.iter().filter_map(|r| r.1).collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        };
        figures.push(Figure {
            file_name: "snap_vs_radius.svg".into(),
            svg: svg::snap_sweep(
                &format!("snap l̄_k vs rod radius (n = {}), cf. Fig. 14", p.n),
                "h (mm)",
                &radius,
                Some((0.8 * mean, 1.2 * mean)),
            ),
        });
        let ns: Vec<(f64, Option<f64>)> = self
            .n_sweep
            .iter()
            .map(|r| (f64::from(r.n), r.snap_l_k_bar))
            .collect();
        figures.push(Figure {
            file_name: "snap_vs_n.svg".into(),
            svg: svg::snap_sweep(
                &format!(
                    "snap l̄_k vs unknotting number (h = {:.2} mm), cf. Fig. 15",
                    self.spec.n_sweep_radius / 1e-3
                ),
                "n",
                &ns,
                None,
            ),
        });
        figures.push(Figure {
            file_name: "braid_convergence.svg".into(),
            svg: svg::braid_convergence(
                &self
                    .braid_convergence
                    .iter()
                    .map(|r| (r.nodes, r.relative_error))
                    .collect::<Vec<_>>(),
            ),
        });
        Document {
            markdown: self.markdown(),
            figures,
        }
    }

    fn markdown(&self) -> String {
        let p = &self.spec.params;
        let lk = self.spec.landscape_l_k_bar;
        let mut s = String::new();
        let _ = writeln!(s, "# The simplified knot model (paper Sec. 5)\n");
        let _ = writeln!(
            s,
            "Generated by `knotsweep simplified doc` (library: `solver::simplified::reproduce(&ReproductionSpec::default())` \
             then `Reproduction::document()`); do not edit by hand. Source: `solver/src/simplified/`.\n"
        );
        let _ = writeln!(
            s,
            "Parameters: n = {}, ε = {}, φ = {:.4} rad (π/3 = 1.0472), h = {:.2} mm, E = {:.2} MPa, ν = {}, \
             loop nodes K = {}, twist convention `{:?}`. Lengths are in rod radii h and energies in EI/h \
             (eq. 12): l̄_b = ε l̄_k/(1+ε), l̄_l = l̄_k/(1+ε).\n",
            p.n,
            p.epsilon,
            p.phi,
            p.radius / 1e-3,
            p.material.youngs_modulus / 1e6,
            p.material.poisson_ratio,
            p.loop_nodes,
            p.end_twist
        );
        s.push_str(GEOMETRY);
        s.push_str(
            "![braid and loop at θ = 0](simplified/schematic.svg)\n\n(a) The braid (strands A, B) and the equilibrium loop \
             at θ = 0 with the clamp points and tangents; (b) the braid's ends seen down z at θ = 0 (open) and \
             θ = 1 (filled).\n\n",
        );
        s.push_str(BRAID);
        let _ = writeln!(
            s,
            "| nodes per strand | Ē_b (DER) | Ē_b (eq. 14) | relative error | observed order |"
        );
        let _ = writeln!(s, "|---:|---:|---:|---:|---:|");
        for r in &self.braid_convergence {
            let _ = writeln!(
                s,
                "| {} | {:.8} | {:.8} | {:.3e} | {} |",
                r.nodes,
                r.discrete,
                r.closed_form,
                r.relative_error,
                opt(r.observed_order, 3)
            );
        }
        s.push_str("\n![braid convergence](simplified/braid_convergence.svg)\n\n");
        s.push_str(LOOP);
        let _ = writeln!(
            s,
            "| θ | dĒ_l/dθ (reaction identity) | central difference of Ē_l (δθ = 1e-3) | relative difference |"
        );
        let _ = writeln!(s, "|---:|---:|---:|---:|");
        for r in &self.derivative_check {
            let _ = writeln!(
                s,
                "| {:.2} | {:.8} | {:.8} | {:.1e} |",
                r.theta,
                r.identity,
                r.finite_difference,
                ((r.identity - r.finite_difference) / r.finite_difference).abs()
            );
        }
        let l = &self.landscape;
        let _ = writeln!(s, "\n## Energy landscape at l̄_k = {lk} (Fig. 13 a, b)\n");
        let _ = writeln!(
            s,
            "Ē(θ) on {} points of θ ∈ [0, 5], one continuation from θ = 0 ({} Newton iterations in all, \
             including the refinement of the critical points). Critical points (sign changes of dĒ/dθ \
             refined by the Illinois method; stability from d²Ē/dθ² by central differences):\n",
            l.points.len(),
            l.newton_iterations
        );
        let _ = writeln!(
            s,
            "| θ* | Ē | d²Ē/dθ² | stability in θ | negative pivots of the loop |"
        );
        let _ = writeln!(s, "|---:|---:|---:|---|---:|");
        for c in &l.critical_points {
            let _ = writeln!(
                s,
                "| {:.4} | {:.5} | {:+.4} | {} | {} |",
                c.theta,
                c.energy,
                c.d2energy_dtheta2,
                if c.stable { "stable" } else { "unstable" },
                c.loop_negative_pivots
            );
        }
        let pattern: Vec<bool> = l.critical_points.iter().map(|c| c.stable).collect();
        let verdict = if pattern == [true, false, true] {
            "Three critical points, the outer two stable and the middle one unstable, as in the paper's Fig. 13 (a, b)."
        } else {
            "This does NOT match the paper's three critical points (stable, unstable, stable)."
        };
        if let Some(first) = l.points.first() {
            let _ = writeln!(
                s,
                "\nAt θ = 0 the loop's twisting energy is {:.1e} of its energy (the clamps sit ±h off its plane).",
                first.loop_twisting / first.loop_energy
            );
        }
        let unstable_loop = l.points.iter().filter(|q| q.loop_negative_pivots > 0).count();
        let _ = writeln!(
            s,
            "\n{verdict} Grid points where the loop itself is unstable at fixed θ (negative pivots of its clamped \
             stiffness): {unstable_loop} of {}.\n",
            l.points.len()
        );
        s.push_str("![energy landscape](simplified/landscape.svg)\n\n");
        s.push_str("Braid and loop at each critical point (same view as (a) above):\n\n");
        s.push_str("![loop at the critical points](simplified/critical_shapes.svg)\n\n");
        let b = &self.bifurcation;
        let _ = writeln!(s, "## Bifurcation diagram (Fig. 13 c)\n");
        s.push_str(BIFURCATION);
        let _ = writeln!(
            s,
            "Traced from l̄_k = {} down to {} ({} points):\n",
            b.spec.l_k_max,
            b.spec.l_k_min,
            b.branch.len()
        );
        let _ = writeln!(s, "| fold | l̄_k | θ |");
        let _ = writeln!(s, "|---|---:|---:|");
        for (i, f) in b.folds.iter().enumerate() {
            let name = if i == 0 {
                "snap (first met from large l̄_k)"
            } else {
                "birth of the second stable state"
            };
            let _ = writeln!(s, "| {name} | {:.3} | {:.4} |", f.l_k_bar, f.theta);
        }
        s.push_str("\n![bifurcation diagram](simplified/bifurcation.svg)\n\n");
        let _ = writeln!(
            s,
            "Discretisation of the loop (second order in 1/(K-2); Richardson extrapolation from the last two rows):\n"
        );
        let _ = writeln!(s, "| K | snap l̄_k | upper fold l̄_k |");
        let _ = writeln!(s, "|---:|---:|---:|");
        for r in &self.loop_convergence {
            let _ = writeln!(
                s,
                "| {} | {} | {} |",
                r.loop_nodes,
                opt(r.snap_l_k_bar, 3),
                opt(r.upper_l_k_bar, 3)
            );
        }
        let _ = writeln!(
            s,
            "| extrapolated | {} | {} |\n",
            opt(extrapolate(&self.loop_convergence, |r| r.snap_l_k_bar), 3),
            opt(extrapolate(&self.loop_convergence, |r| r.upper_l_k_bar), 3)
        );
        let _ = writeln!(s, "## Snap l̄_k against the rod radius (Fig. 14, n = {})\n", p.n);
        let snaps: Vec<f64> = self.radius_sweep.iter().filter_map(|r| r.snap_l_k_bar).collect();
        let (lo, hi) = snaps
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(*v), b.max(*v))
            });
        let _ = writeln!(
            s,
            "In the model h enters only through the nondimensionalisation (the braid radius is h, the loop \
             length l̄_l h, EA : EI : GJ scale as 1 : h² : h²), so the snap l̄_k must be independent of h up to \
             the solver's tolerance. Relative spread over the sweep: {:.1e}.\n",
            (hi - lo) / lo
        );
        let _ = writeln!(s, "| h (mm) | snap l̄_k | upper fold l̄_k |");
        let _ = writeln!(s, "|---:|---:|---:|");
        for r in &self.radius_sweep {
            let _ = writeln!(
                s,
                "| {:.1} | {} | {} |",
                r.radius * 1e3,
                opt(r.snap_l_k_bar, 6),
                opt(r.upper_l_k_bar, 6)
            );
        }
        s.push_str("\n![snap vs radius](simplified/snap_vs_radius.svg)\n\n");
        let _ = writeln!(
            s,
            "## Snap l̄_k against the unknotting number (Fig. 15, h = {:.2} mm)\n",
            self.spec.n_sweep_radius / 1e-3
        );
        let _ = writeln!(s, "| n | snap l̄_k | upper fold l̄_k |");
        let _ = writeln!(s, "|---:|---:|---:|");
        for r in &self.n_sweep {
            let _ = writeln!(
                s,
                "| {} | {} | {} |",
                r.n,
                opt(r.snap_l_k_bar, 3),
                opt(r.upper_l_k_bar, 3)
            );
        }
        let snaps: Vec<(u32, f64)> = self
            .n_sweep
            .iter()
            .filter_map(|r| r.snap_l_k_bar.map(|v| (r.n, v)))
            .collect();
        let increasing = snaps.windows(2).all(|w| w[1].1 > w[0].1);
        let _ = writeln!(
            s,
            "\nThe snap l̄_k {} with n over the unknotting numbers that have a snap ({}); the paper's Fig. 15 has it growing. The full model's inversion points (DER with frictional contact, same h and n values) are in `docs/VALIDATION.md`, regenerated by `knotsweep reproduce`.",
            if increasing {
                "grows"
            } else {
                "does NOT grow monotonically"
            },
            snaps
                .iter()
                .map(|(n, _)| n.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
        for r in self.n_sweep.iter().filter(|r| r.snap_l_k_bar.is_none()) {
            let window = BifurcationSpec::for_params(Params { n: r.n, ..*p });
            if r.curve_points == 0 {
                let _ = writeln!(
                    s,
                    "For n = {} there is no critical point at l̄_k = {}: no snap.",
                    r.n, window.l_k_max
                );
            } else {
                let _ = writeln!(
                    s,
                    "For n = {} the traced critical curve has no fold in l̄_k ∈ [{}, {}]: no snap.",
                    r.n, window.l_k_min, window.l_k_max
                );
            }
        }
        s.push_str(N_TREND);
        s.push_str("![snap vs n](simplified/snap_vs_n.svg)\n\n");
        let _ = writeln!(s, "## Twist conventions of the clamps\n");
        s.push_str(CONVENTIONS);
        let _ = writeln!(
            s,
            "| convention | critical points at l̄_k = {lk} (θ, s: stable, u: unstable) | folds (l̄_k) | paper's sequence | notes |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|");
        for c in &self.conventions {
            let cps: Vec<String> = c
                .critical_points
                .iter()
                .map(|(t, st)| format!("{t:.3} {}", if *st { "s" } else { "u" }))
                .collect();
            let folds: Vec<String> = c.folds.iter().map(|f| format!("{:.2}", f.l_k_bar)).collect();
            let _ = writeln!(
                s,
                "| `{:?}` | {} | {} | {} | {} |",
                c.end_twist,
                if cps.is_empty() {
                    "—".into()
                } else {
                    cps.join(", ")
                },
                if folds.is_empty() {
                    "—".into()
                } else {
                    folds.join(", ")
                },
                if c.matches_paper() { "yes" } else { "no" },
                c.failure.as_deref().unwrap_or("")
            );
        }
        s.push_str(LIMITATIONS);
        s
    }
}

const GEOMETRY: &str = "## Geometry (reconstruction of Fig. 12)

Fig. 12 is not in the text; this reconstruction is consistent with eqs. (13)-(15) and is what
`solver/src/simplified/loop_rod.rs` implements. z is the braid axis of eq. (13), T = nπ - θ.

- **Braid** (eqs. 13-14): strand A is the helix (cos t, sin t, b̄ t), strand B the same helix turned by π
  about z, t ∈ [-T, T], b̄ = l̄_b / (2T). Both have unit radius (centrelines one rod radius from the axis:
  the strands touch). Only their bending energy counts: Ē_b = 2 κ̄² T √(1+b̄²), κ̄ = 1/(1+b̄²).
- **Closed loop**: the loop leaves strand A at its end t = T, at p_s = (cos T, sin T, l̄_b/2), and enters
  strand B at its end t = -T, at p_f = (-cos T, sin T, -l̄_b/2); braid and loop form one closed curve of
  length ≈ l̄_b + l̄_l = l̄_k.
- **End tangents**: t_s = cos φ z + sin φ e(T), e(T) = (-sin T, cos T, 0) the azimuthal direction of the
  braid cylinder at p_s: the braid axis rotated by φ about the x axis (at θ = 0 and odd n, e = -y), then
  turned with the braid end by θ about z. It is strand A's tangent at its end with the helix's pitch
  angle replaced by φ. The loop arrives at p_f along t_f = -R t_s.
- **Antisymmetry**: R, the half turn about y ((x, y, z) → (-x, y, -z)), maps strand A onto strand B and
  (p_s, t_s) onto (p_f, -t_f), so the whole knot keeps this two-fold symmetry for every θ; it reverses x
  (the direction normal to the loop's plane at θ = 0), which is the paper's antisymmetry about the YZ
  plane. The loop's midpoint lies on the y axis.
- **Rotation θ**: unwinding the braid by θ moves its ends along the helices, turning the start clamp by
  -θ and the finish clamp by +θ about z (both position and tangent), as the paper says: the tangents
  rotate by θ about z, and so do the braid's ends.
- **Twist**: at θ = 0 the clamps' material directors are m1_s = cos φ e(T) - sin φ z (in the loop's plane)
  and m1_f = R m1_s, so the θ = 0 loop is planar and untwisted but for the clamps' offsets of ±h normal to
  its plane (its twisting energy is reported below). As θ turns the clamps, the default
  convention `Transported` carries each clamp's frame by parallel transport along the circle its tangent
  sweeps about z (no spin about the tangent): the frame of a DER clamp (two nodes and the edge twist held,
  paper Sec. 4) whose nodes are turned. In closed form, m1 is the rigidly turned director rotated by
  θ cos φ about the tangent. The alternatives are compared below.
- **Loop rod**: a naturally straight DER rod (paper Sec. 3, material of Sec. 4) of K nodes; each clamp
  holds an end edge (two nodes and its twist) centred on p_s or p_f, so the rod between the clamp points
  (edge midpoints) has length exactly l̄_l: K - 2 edges of l̄_l/(K - 2). No contact, no gravity.

";

const BRAID: &str = "## Braid energy: closed form vs DER

The two strands are discretised with equally spaced nodes in t, extended half a spacing beyond each end so
that the Voronoi cells of the interior nodes (which carry the discrete bending energy, eq. 6b) tile
t ∈ [-T, T]. At n = 3, θ = 0, l̄_k = 137.5 (l̄_b = 56.62):

";

const LOOP: &str = "## Loop energy and dĒ/dθ

The loop's equilibrium at given (θ, l̄_k) is a static Newton solve of the DER energy (the implicit-Euler
stepper with a step of 10⁴ s, inertia negligible), clamps held. Continuation: θ and l̄_k move in substeps
of at most 0.1 rad and 2 %, each started from a secant extrapolation of the last two solutions; a substep
whose Newton solve fails, or whose solution lands farther from its prediction than one loop length per
radian (a jump to another branch), is halved. dĒ_l/dθ comes from the envelope theorem: at equilibrium
only the clamped DOFs contribute, dĒ_l/dθ = Σ_clamps [Σ_nodes g_x · (w z × x) + g_θ s], with g the
energy gradient (the clamps' reactions), w = ∓1 the clamp's turn rate about z and s its spin about the
tangent (zero for `Transported`), i.e. the reaction moments about z. Check against central differences of
Ē_l along the branch (n = 3, l̄_k = 137.5):

";

const BIFURCATION: &str =
    "The critical curve dĒ/dθ(θ, l̄_k) = 0 is traced by pseudo-arclength continuation in (θ, l̄_k/20)
(Newton corrector with the partial derivatives by central differences along the loop branch), starting
from the critical point nearest to θ = 0 at the largest l̄_k. A fold is where the curve's tangent turns back in
l̄_k; it is located by successive parabolic interpolation of l̄_k(θ) on the curve. The first fold met
from large l̄_k is where the critical point that is stable for a long (loose) knot meets the unstable one
and disappears: the snap-through of the tightening knot.

";

const N_TREND: &str = "
The paper observes that a knot with n = 1 does not invert. The loop energy does not depend on n (the
clamps' geometry depends on n only through the parity of n, which a half turn about z undoes), so n acts
only through the braid.

";

const CONVENTIONS: &str =
    "How the clamps' frames follow θ is not stated in the paper. Three conventions are implemented
(`EndTwist`): `Transported` (default, see Geometry), `Clamped` (frames turned rigidly with the braid ends:
a spin of cos φ per radian about the tangent more than `Transported`) and `Free` (no twisting moment at the
ends). \"Paper's sequence\" means three critical points (stable, unstable, stable) at the landscape's l̄_k
and two folds on the traced curve; a failure means the loop branch followed from the planar loop ended
(continuation stops rather than jump to another branch). The default is the convention that shows the
paper's sequence; the others are reported, not hidden.

";

const LIMITATIONS: &str = "
## Limitations and deviations

- The geometry of Fig. 12 is reconstructed (see above); the numbers depend on that reconstruction, in
  particular on the twist convention. The paper's l̄_k = 137.5 lies inside the window of three critical
  points here, but the fold values are this reconstruction's, not read off the paper's figures (which are
  not in the text).
- Stability is with respect to θ only, as in the paper (φ and ε held); the loop itself is checked to be a
  stable equilibrium at fixed θ (no negative pivot of its clamped stiffness).
- Contact between the loop and the braid, friction, gravity and the braid's twist are neglected, as in
  the paper's model.
";
