//! `docs/SIMPLIFIED_MODEL.md`: the simplified model's results (paper Sec. 5,
//! `solver::simplified::reproduce`) as markdown and the SVG figures it links
//! ([`crate::simplified`]); `knotsweep simplified doc` writes them.
use crate::markdown::{Align, left, right, table};
use crate::simplified::{self as svg, BraidError, CriticalShape, SnapPoint};
use anyhow::Result;
use solver::simplified::reproduce::{Reproduction, SweepRow};
use solver::simplified::{BifurcationSpec, Params};

/// A generated document: markdown and the SVG figures it links (relative to
/// the markdown file, under `simplified/`).
#[derive(Clone, Debug, PartialEq)]
pub struct Document {
    pub markdown: String,
    pub figures: Vec<Figure>,
}

/// One SVG figure: file name (in the `simplified/` folder next to the document) and content.
#[derive(Clone, Debug, PartialEq)]
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

/// Writes `docs/SIMPLIFIED_MODEL.md` and its figures from a [`Reproduction`].
pub trait SimplifiedDocument {
    fn document(&self) -> Result<Document>;
    fn markdown(&self) -> String;
}

impl SimplifiedDocument for Reproduction {
    /// `docs/SIMPLIFIED_MODEL.md` and its figures.
    fn document(&self) -> Result<Document> {
        let p = &self.spec.params;
        let lk = self.spec.landscape_l_k_bar;
        let figure = |name: &str, svg: Result<String>| {
            svg.map(|svg| Figure {
                file_name: name.to_string(),
                svg,
            })
        };
        let critical: Vec<CriticalShape> = (self.landscape.critical_points.iter())
            .map(|c| CriticalShape {
                theta: c.theta,
                stable: c.stable,
                centerline: c.loop_centerline.clone(),
            })
            .collect();
        let radius: Vec<SnapPoint> = (self.radius_sweep.iter())
            .map(|r| SnapPoint {
                x: r.radius * 1e3,
                snap: r.snap_l_k_bar,
            })
            .collect();
        let mean = {
            let v: Vec<f64> = radius.iter().filter_map(|r| r.snap).collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        };
        let ns: Vec<SnapPoint> = (self.n_sweep.iter())
            .map(|r| SnapPoint {
                x: f64::from(r.n),
                snap: r.snap_l_k_bar,
            })
            .collect();
        let braid: Vec<BraidError> = (self.braid_convergence.iter())
            .map(|r| BraidError {
                nodes: r.nodes,
                relative_error: r.relative_error,
            })
            .collect();
        let figures = vec![
            figure(
                "schematic.svg",
                svg::schematic(p, lk, 0.0, &self.planar_loop, 1.0),
            )?,
            figure("critical_shapes.svg", svg::critical_shapes(p, lk, &critical))?,
            figure("landscape.svg", svg::landscape(&self.landscape))?,
            figure(
                "bifurcation.svg",
                svg::bifurcation(&self.bifurcation, &[(lk, format!("l̄_k = {lk}"))]),
            )?,
            figure(
                "snap_vs_radius.svg",
                svg::snap_sweep(
                    &format!("snap l̄_k vs rod radius (n = {}), cf. Fig. 14", p.n),
                    "h (mm)",
                    &radius,
                    Some((0.8 * mean, 1.2 * mean)),
                ),
            )?,
            figure(
                "snap_vs_n.svg",
                svg::snap_sweep(
                    &format!(
                        "snap l̄_k vs unknotting number (h = {:.2} mm), cf. Fig. 15",
                        self.spec.n_sweep_radius / 1e-3
                    ),
                    "n",
                    &ns,
                    None,
                ),
            )?,
            figure("braid_convergence.svg", svg::braid_convergence(&braid))?,
        ];
        Ok(Document {
            markdown: self.markdown(),
            figures,
        })
    }

    fn markdown(&self) -> String {
        [
            intro(self),
            GEOMETRY.to_string(),
            SCHEMATIC.to_string(),
            braid_section(self),
            loop_section(self),
            landscape_section(self),
            bifurcation_section(self),
            radius_section(self),
            n_section(self),
            conventions_section(self),
            LIMITATIONS.to_string(),
        ]
        .concat()
    }
}

/// The title, how the document is made and the model's parameters.
fn intro(r: &Reproduction) -> String {
    let p = &r.spec.params;
    format!(
        "# The simplified knot model (paper Sec. 5)\n\n\
         Generated by `knotsweep simplified doc` (library: `solver::simplified::reproduce(&ReproductionSpec::default())` \
         then `Reproduction::document()`); do not edit by hand. Source: `solver/src/simplified/`.\n\n\
         Parameters: n = {}, ε = {}, φ = {:.4} rad (π/3 = 1.0472), h = {:.2} mm, E = {:.2} MPa, ν = {}, \
         loop nodes K = {}, twist convention `{:?}`. Lengths are in rod radii h and energies in EI/h \
         (eq. 12): l̄_b = ε l̄_k/(1+ε), l̄_l = l̄_k/(1+ε).\n\n",
        p.n,
        p.epsilon,
        p.phi,
        p.radius / 1e-3,
        p.material.youngs_modulus / 1e6,
        p.material.poisson_ratio,
        p.loop_nodes,
        p.end_twist
    )
}

/// The braid's energy, DER against eq. (14), and its convergence figure.
fn braid_section(r: &Reproduction) -> String {
    let rows = r.braid_convergence.iter().map(|b| {
        [
            b.nodes.to_string(),
            format!("{:.8}", b.discrete),
            format!("{:.8}", b.closed_form),
            format!("{:.3e}", b.relative_error),
            opt(b.observed_order, 3),
        ]
    });
    let columns = right(&[
        "nodes per strand",
        "Ē_b (DER)",
        "Ē_b (eq. 14)",
        "relative error",
        "observed order",
    ]);
    format!(
        "{BRAID}{}![braid convergence](simplified/braid_convergence.svg)\n\n",
        table(&columns, rows)
    )
}

/// dĒ_l/dθ from the reaction identity against central differences.
fn loop_section(r: &Reproduction) -> String {
    let rows = r.derivative_check.iter().map(|d| {
        [
            format!("{:.2}", d.theta),
            format!("{:.8}", d.identity),
            format!("{:.8}", d.finite_difference),
            format!(
                "{:.1e}",
                ((d.identity - d.finite_difference) / d.finite_difference).abs()
            ),
        ]
    });
    let columns = right(&[
        "θ",
        "dĒ_l/dθ (reaction identity)",
        "central difference of Ē_l (δθ = 1e-3)",
        "relative difference",
    ]);
    format!("{LOOP}{}", table(&columns, rows))
}

/// The energy landscape and its critical points (Fig. 13 a, b).
fn landscape_section(r: &Reproduction) -> String {
    let (l, lk) = (&r.landscape, r.spec.landscape_l_k_bar);
    let rows = l.critical_points.iter().map(|c| {
        [
            format!("{:.4}", c.theta),
            format!("{:.5}", c.energy),
            format!("{:+.4}", c.d2energy_dtheta2),
            if c.stable { "stable" } else { "unstable" }.to_string(),
            c.loop_negative_pivots.to_string(),
        ]
    });
    let columns = [
        ("θ*", Align::Right),
        ("Ē", Align::Right),
        ("d²Ē/dθ²", Align::Right),
        ("stability in θ", Align::Left),
        ("negative pivots of the loop", Align::Right),
    ];
    let pattern: Vec<bool> = l.critical_points.iter().map(|c| c.stable).collect();
    let verdict = if pattern == [true, false, true] {
        "Three critical points, the outer two stable and the middle one unstable, as in the paper's Fig. 13 (a, b)."
    } else {
        "This does NOT match the paper's three critical points (stable, unstable, stable)."
    };
    let twisting = l.points.first().map_or(String::new(), |first| {
        format!(
            "At θ = 0 the loop's twisting energy is {:.1e} of its energy (the clamps sit ±h off its plane).\n\n",
            first.loop_twisting / first.loop_energy
        )
    });
    let unstable_loop = l.points.iter().filter(|q| q.loop_negative_pivots > 0).count();
    format!(
        "## Energy landscape at l̄_k = {lk} (Fig. 13 a, b)\n\n\
         Ē(θ) on {} points of θ ∈ [0, 5], one continuation from θ = 0 ({} Newton iterations in all, \
         including the refinement of the critical points). Critical points (sign changes of dĒ/dθ \
         refined by the Illinois method; stability from d²Ē/dθ² by central differences):\n\n{}{twisting}\
         {verdict} Grid points where the loop itself is unstable at fixed θ (negative pivots of its clamped \
         stiffness): {unstable_loop} of {}.\n\n\
         ![energy landscape](simplified/landscape.svg)\n\n\
         Braid and loop at each critical point (same view as (a) above):\n\n\
         ![loop at the critical points](simplified/critical_shapes.svg)\n\n",
        l.points.len(),
        l.newton_iterations,
        table(&columns, rows),
        l.points.len()
    )
}

/// The critical curve, its folds and the loop's discretisation (Fig. 13 c).
fn bifurcation_section(r: &Reproduction) -> String {
    let b = &r.bifurcation;
    let folds = b.folds.iter().enumerate().map(|(i, f)| {
        [
            if i == 0 {
                "snap (first met from large l̄_k)"
            } else {
                "birth of the second stable state"
            }
            .to_string(),
            format!("{:.3}", f.l_k_bar),
            format!("{:.4}", f.theta),
        ]
    });
    let mut convergence: Vec<[String; 3]> = (r.loop_convergence.iter())
        .map(|k| {
            [
                k.loop_nodes.to_string(),
                opt(k.snap_l_k_bar, 3),
                opt(k.upper_l_k_bar, 3),
            ]
        })
        .collect();
    convergence.push([
        "extrapolated".to_string(),
        opt(extrapolate(&r.loop_convergence, |k| k.snap_l_k_bar), 3),
        opt(extrapolate(&r.loop_convergence, |k| k.upper_l_k_bar), 3),
    ]);
    format!(
        "## Bifurcation diagram (Fig. 13 c)\n\n{BIFURCATION}Traced from l̄_k = {} down to {} ({} points):\n\n{}\
         ![bifurcation diagram](simplified/bifurcation.svg)\n\n\
         Discretisation of the loop (second order in 1/(K-2); Richardson extrapolation from the last two rows):\n\n{}",
        b.spec.l_k_max,
        b.spec.l_k_min,
        b.branch.len(),
        table(
            &[("fold", Align::Left), ("l̄_k", Align::Right), ("θ", Align::Right)],
            folds
        ),
        table(&right(&["K", "snap l̄_k", "upper fold l̄_k"]), convergence)
    )
}

/// The snap against the rod radius (Fig. 14): independent of h.
fn radius_section(r: &Reproduction) -> String {
    let snaps: Vec<f64> = r.radius_sweep.iter().filter_map(|k| k.snap_l_k_bar).collect();
    let (lo, hi) = (snaps.iter()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(*v), b.max(*v))
    });
    let rows = r.radius_sweep.iter().map(|k| {
        [
            format!("{:.1}", k.radius * 1e3),
            opt(k.snap_l_k_bar, 6),
            opt(k.upper_l_k_bar, 6),
        ]
    });
    format!(
        "## Snap l̄_k against the rod radius (Fig. 14, n = {})\n\n\
         In the model h enters only through the nondimensionalisation (the braid radius is h, the loop \
         length l̄_l h, EA : EI : GJ scale as 1 : h² : h²), so the snap l̄_k must be independent of h up to \
         the solver's tolerance. Relative spread over the sweep: {:.1e}.\n\n{}\
         ![snap vs radius](simplified/snap_vs_radius.svg)\n\n",
        r.spec.params.n,
        (hi - lo) / lo,
        table(&right(&["h (mm)", "snap l̄_k", "upper fold l̄_k"]), rows)
    )
}

/// The snap against the unknotting number (Fig. 15).
fn n_section(r: &Reproduction) -> String {
    let rows = r
        .n_sweep
        .iter()
        .map(|k| [k.n.to_string(), opt(k.snap_l_k_bar, 3), opt(k.upper_l_k_bar, 3)]);
    let snaps: Vec<(u32, f64)> = (r.n_sweep.iter())
        .filter_map(|k| k.snap_l_k_bar.map(|v| (k.n, v)))
        .collect();
    let increasing = snaps.windows(2).all(|w| w[1].1 > w[0].1);
    let without: String = (r.n_sweep.iter())
        .filter(|k| k.snap_l_k_bar.is_none())
        .map(|k| {
            let window = BifurcationSpec::for_params(Params {
                n: k.n,
                ..r.spec.params
            });
            if k.curve_points == 0 {
                format!(
                    "For n = {} there is no critical point at l̄_k = {}: no snap.\n",
                    k.n, window.l_k_max
                )
            } else {
                format!(
                    "For n = {} the traced critical curve has no fold in l̄_k ∈ [{}, {}]: no snap.\n",
                    k.n, window.l_k_min, window.l_k_max
                )
            }
        })
        .collect();
    format!(
        "## Snap l̄_k against the unknotting number (Fig. 15, h = {:.2} mm)\n\n{}\
         The snap l̄_k {} with n over the unknotting numbers that have a snap ({}); the paper's Fig. 15 has it \
         growing. The full model's inversion points (DER with frictional contact, same h and n values) are in \
         `docs/VALIDATION.md`, regenerated by `knotsweep reproduce`.\n{without}{N_TREND}\
         ![snap vs n](simplified/snap_vs_n.svg)\n\n",
        r.spec.n_sweep_radius / 1e-3,
        table(&right(&["n", "snap l̄_k", "upper fold l̄_k"]), rows),
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
    )
}

/// The clamps' twist conventions against the paper's sequence.
fn conventions_section(r: &Reproduction) -> String {
    let lk = r.spec.landscape_l_k_bar;
    let rows = r.conventions.iter().map(|c| {
        let cps: Vec<String> = (c.critical_points.iter())
            .map(|(t, st)| format!("{t:.3} {}", if *st { "s" } else { "u" }))
            .collect();
        let folds: Vec<String> = c.folds.iter().map(|f| format!("{:.2}", f.l_k_bar)).collect();
        let listed = |v: Vec<String>| if v.is_empty() { "—".into() } else { v.join(", ") };
        [
            format!("`{:?}`", c.end_twist),
            listed(cps),
            listed(folds),
            if c.matches_paper() { "yes" } else { "no" }.to_string(),
            c.failure.clone().unwrap_or_default(),
        ]
    });
    let points = format!("critical points at l̄_k = {lk} (θ, s: stable, u: unstable)");
    format!(
        "## Twist conventions of the clamps\n\n{CONVENTIONS}{}",
        table(
            &left(&["convention", &points, "folds (l̄_k)", "paper's sequence", "notes"]),
            rows
        )
        .trim_end_matches('\n')
    ) + "\n"
}

const SCHEMATIC: &str = "![braid and loop at θ = 0](simplified/schematic.svg)\n\n(a) The braid (strands A, B) and the \
    equilibrium loop at θ = 0 with the clamp points and tangents; (b) the braid's ends seen down z at θ = 0 (open) and \
    θ = 1 (filled).\n\n";

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

#[cfg(test)]
mod tests {
    use super::*;
    use solver::simplified::{ReproductionSpec, reproduce};

    /// Checks that `svg` is one well-nested XML element tree rooted at <svg>.
    fn assert_well_formed(svg: &str) {
        assert!(svg.starts_with("<svg "), "{}", &svg[..40.min(svg.len())]);
        let mut stack: Vec<String> = Vec::new();
        let mut rest = svg;
        while let Some(start) = rest.find('<') {
            let end = start + rest[start..].find('>').expect("tag closed");
            let tag = &rest[start + 1..end];
            assert!(!rest[..start].contains('>'), "stray '>' in text");
            if let Some(name) = tag.strip_prefix('/') {
                assert_eq!(stack.pop().as_deref(), Some(name.trim()));
            } else if !tag.ends_with('/') {
                stack.push(tag.split_whitespace().next().expect("name").to_string());
            }
            assert_eq!(tag.matches('"').count() % 2, 0, "unbalanced quotes in <{tag}>");
            rest = &rest[end + 1..];
        }
        assert!(stack.is_empty(), "unclosed {stack:?}");
    }

    #[test]
    fn the_document_links_every_figure_and_every_figure_is_well_formed() {
        let spec = ReproductionSpec {
            params: Params {
                loop_nodes: 23,
                ..Params::default()
            },
            landscape_points: 30,
            radii: vec![2e-3],
            unknotting_numbers: vec![3],
            braid_nodes: vec![20, 40],
            loop_nodes: vec![23],
            derivative_thetas: vec![1.0],
            ..ReproductionSpec::default()
        };
        let r = reproduce(&spec).expect("reproduction");
        let doc = r.document().expect("figures draw");
        for f in &doc.figures {
            assert!(f.file_name.ends_with(".svg"));
            assert!(
                doc.markdown.contains(&format!("simplified/{}", f.file_name)),
                "{} not linked",
                f.file_name
            );
            assert_well_formed(&f.svg);
        }
        assert!(
            doc.markdown
                .contains("Three critical points, the outer two stable")
        );
        assert_well_formed(&svg::landscape(&r.landscape).unwrap());
        assert_well_formed(&svg::bifurcation(&r.bifurcation, &[]).unwrap());
    }
}
