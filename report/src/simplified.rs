//! The simplified model's figures (paper Sec. 5), drawn with plotters as
//! every figure of this crate: Ē(θ) and dĒ/dθ (Fig. 13 a, b), the critical
//! curve (Fig. 13 c), the snap l̄_k against h and n (Figs. 14, 15) and the
//! braid's convergence as charts ([`crate::charts::Plot`]); the braid and
//! loop as drawings (Fig. 12).
use crate::charts::{LegendAt, Plot, Series, Style, compact as label, plots_svg};
use anyhow::{Result, anyhow};
use nalgebra::Vector3;
use plotters::coord::Shift;
use plotters::prelude::*;
use solver::simplified::Params;
use solver::simplified::bifurcation::Bifurcation;
use solver::simplified::braid::{Braid, Strand};
use solver::simplified::landscape::Landscape;
use solver::simplified::loop_rod::LoopBoundary;

const BLUE: RGBColor = RGBColor(31, 119, 180);
const ORANGE: RGBColor = RGBColor(255, 127, 14);
const GREEN: RGBColor = RGBColor(44, 160, 44);
const RED: RGBColor = RGBColor(214, 39, 40);
const GREY: RGBColor = RGBColor(127, 127, 127);

fn series(label: &str, points: Vec<(f64, f64)>, colour: RGBColor, style: Style) -> Series {
    Series {
        label: label.to_string(),
        points,
        colour: colour.to_rgba(),
        style,
    }
}

/// Ē, Ē_b, Ē_l against theta and dĒ/dθ, with the critical points (filled:
/// stable, open: unstable); paper Fig. 13 (a, b).
pub fn landscape(l: &Landscape) -> Result<String> {
    let pts = |f: fn(&solver::simplified::LandscapePoint) -> f64| {
        l.points.iter().map(|p| (p.theta, f(p))).collect::<Vec<_>>()
    };
    let crit = |stable: bool, y: &dyn Fn(&solver::simplified::CriticalPoint) -> f64| {
        series(
            if stable { "stable" } else { "unstable" },
            (l.critical_points.iter())
                .filter(|c| c.stable == stable)
                .map(|c| (c.theta, y(c)))
                .collect(),
            RED,
            Style::Dots { filled: stable },
        )
    };
    let title = format!("n = {}, l̄_k = {}", l.spec.params.n, label(l.spec.l_k_bar));
    // Head room above the curves for the legend.
    let top = l.points.iter().map(|p| p.energy).fold(0.0f64, f64::max);
    let energy = Plot {
        title: format!("(a) total energy, {title}"),
        x_label: "θ (rad)".into(),
        y_label: "Ē = E h / EI".into(),
        series: vec![
            series("Ē", pts(|p| p.energy), BLUE, Style::Line),
            series("Ē_b (braid)", pts(|p| p.braid_energy), ORANGE, Style::Dashed),
            series("Ē_l (loop)", pts(|p| p.loop_energy), GREEN, Style::Dashed),
            crit(true, &|c| c.energy),
            crit(false, &|c| c.energy),
        ],
        y_range: Some((0.0, 1.45 * top)),
        ..Plot::default()
    };
    let slope = Plot {
        title: format!("(b) dĒ/dθ, {title}"),
        x_label: "θ (rad)".into(),
        y_label: "dĒ/dθ".into(),
        series: vec![
            series("dĒ/dθ", pts(|p| p.denergy_dtheta), BLUE, Style::Line),
            crit(true, &|_| 0.0),
            crit(false, &|_| 0.0),
        ],
        zero_line: true,
        legend: LegendAt::LowerRight,
        ..Plot::default()
    };
    plots_svg(&[energy, slope], (520, 380))
}

/// theta at the critical points against l̄_k (solid: stable, dashed: unstable),
/// the folds, and optional reference lengths; paper Fig. 13 (c).
pub fn bifurcation(b: &Bifurcation, marks: &[(f64, String)]) -> Result<String> {
    let mut runs: Vec<Series> = Vec::new();
    let mut run: Vec<(f64, f64)> = Vec::new();
    let mut stable = b.branch.first().is_some_and(|p| p.stable);
    let mut labelled = [false, false];
    let mut flush = |run: &mut Vec<(f64, f64)>, stable: bool, runs: &mut Vec<Series>| {
        if run.len() > 1 {
            let i = usize::from(stable);
            let name = match (labelled[i], stable) {
                (true, _) => "",
                (false, true) => "stable",
                (false, false) => "unstable",
            };
            labelled[i] = true;
            runs.push(if stable {
                series(name, run.clone(), BLUE, Style::Line)
            } else {
                series(name, run.clone(), RED, Style::Dashed)
            });
        }
        run.drain(..run.len().saturating_sub(1));
    };
    for p in &b.branch {
        run.push((p.l_k_bar, p.theta));
        if p.stable != stable {
            // The runs join at the fold between the two points.
            flush(&mut run, stable, &mut runs);
            stable = p.stable;
        }
    }
    flush(&mut run, stable, &mut runs);
    runs.push(series(
        "folds",
        b.folds.iter().map(|f| (f.l_k_bar, f.theta)).collect(),
        BLACK,
        Style::Dots { filled: true },
    ));
    let plot = Plot {
        title: format!("(c) critical points, n = {}", b.spec.params.n),
        x_label: "l̄_k = l_k / h".into(),
        y_label: "θ* (rad)".into(),
        series: runs,
        markers: marks.to_vec(),
        ..Plot::default()
    };
    plots_svg(&[plot], (560, 400))
}

/// A swept parameter and the snap l̄_k there (none: no fold).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SnapPoint {
    pub x: f64,
    pub snap: Option<f64>,
}

/// The snap l̄_k (lower fold) against a swept parameter.
pub fn snap_sweep(
    title: &str,
    x_label: &str,
    points: &[SnapPoint],
    y_range: Option<(f64, f64)>,
) -> Result<String> {
    let plot = Plot {
        title: title.into(),
        x_label: x_label.into(),
        y_label: "snap l̄_k".into(),
        series: vec![series(
            "simplified model",
            points.iter().filter_map(|p| Some((p.x, p.snap?))).collect(),
            BLUE,
            Style::LineDots,
        )],
        y_range,
        legend: LegendAt::UpperLeft,
        ..Plot::default()
    };
    plots_svg(&[plot], (520, 360))
}

/// The braid's discretisation error at a node count.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BraidError {
    pub nodes: usize,
    pub relative_error: f64,
}

/// Relative error of the DER braid energy against eq. (14) on log-log axes, with
/// a reference line of slope -2.
pub fn braid_convergence(rows: &[BraidError]) -> Result<String> {
    let pts: Vec<(f64, f64)> = rows.iter().map(|r| (r.nodes as f64, r.relative_error)).collect();
    let mut lines = vec![series(
        "|Ē_b(DER)/Ē_b(eq. 14) - 1|",
        pts.clone(),
        BLUE,
        Style::LineDots,
    )];
    if let Some(&(k0, e0)) = pts.first() {
        lines.push(series(
            "slope -2",
            pts.iter().map(|(k, _)| (*k, e0 * (k0 / k).powi(2))).collect(),
            GREY,
            Style::Dashed,
        ));
    }
    let plot = Plot {
        title: "braid: DER discretisation vs closed form".into(),
        x_label: "nodes per strand".into(),
        y_label: "relative error".into(),
        series: lines,
        log: true,
        ..Plot::default()
    };
    plots_svg(&[plot], (520, 360))
}

/// Orthographic view: azimuth about z, then elevation; returns (right, up).
fn project(v: &Vector3<f64>, azimuth: f64, elevation: f64) -> (f64, f64) {
    let (sa, ca) = azimuth.sin_cos();
    let (se, ce) = elevation.sin_cos();
    let right = -sa * v.x + ca * v.y;
    let depth = ca * v.x + sa * v.y;
    (right, ce * v.z - se * depth)
}

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// A pixel position.
fn px((x, y): (f64, f64)) -> (i32, i32) {
    (x.round() as i32, y.round() as i32)
}

/// An arrow from `from` to `to` (pixels): a line with a filled head.
fn arrow(area: &Area, from: (f64, f64), to: (f64, f64), style: ShapeStyle) -> Result<()> {
    let (dx, dy) = (to.0 - from.0, to.1 - from.1);
    let len = (dx * dx + dy * dy).sqrt().max(1e-9);
    let (ux, uy) = (dx / len, dy / len);
    let head = [
        to,
        (to.0 - 9.0 * ux + 4.0 * uy, to.1 - 9.0 * uy - 4.0 * ux),
        (to.0 - 9.0 * ux - 4.0 * uy, to.1 - 9.0 * uy + 4.0 * ux),
    ];
    area.draw(&PathElement::new(vec![px(from), px(to)], style))
        .and_then(|_| area.draw(&Polygon::new(head.map(px).to_vec(), style.color.filled())))
        .map_err(|e| anyhow!("{e}"))
}

/// `text` at pixel `at` in `colour`.
fn text(area: &Area, text: &str, at: (f64, f64), colour: RGBColor) -> Result<()> {
    area.draw(&Text::new(
        text.to_string(),
        px(at),
        ("sans-serif", 13).into_font().color(&colour),
    ))
    .map_err(|e| anyhow!("{e}"))
}

/// A polyline through pixel points.
fn polyline(area: &Area, points: &[(f64, f64)], style: ShapeStyle) -> Result<()> {
    area.draw(&PathElement::new(
        points.iter().map(|p| px(*p)).collect::<Vec<_>>(),
        style,
    ))
    .map_err(|e| anyhow!("{e}"))
}

/// Side view (across the braid axis) of the braid at `theta` and one loop
/// centreline (units of h), drawn as tubes of the rod's diameter, with the clamp
/// points, the end tangents and the braid axis z.
fn side_view(
    area: &Area,
    view: &SideView,
    theta: f64,
    centerline: &[[f64; 3]],
    title: &str,
    colour: RGBColor,
) -> Result<()> {
    let (params, l_k_bar) = (view.params, view.l_k_bar);
    let braid = params.braid(theta, l_k_bar);
    let bc = LoopBoundary::new(params.n, params.phi, theta, braid.l_b_bar, params.end_twist);
    let (az, el) = (0.35, 0.25);
    let t = braid.half_span();
    let strand = |s: Strand| -> Vec<(f64, f64)> {
        (0..=400)
            .map(|i| project(&braid.point(s, -t + 2.0 * t * i as f64 / 400.0), az, el))
            .collect()
    };
    let loop_view: Vec<(f64, f64)> = (centerline.iter())
        .map(|p| project(&Vector3::new(p[0], p[1], p[2]), az, el))
        .collect();
    let (sa, sb) = (strand(Strand::A), strand(Strand::B));
    let reach = 0.18 * braid.l_b_bar;
    let tips: Vec<(f64, f64)> = [&bc.start, &bc.finish]
        .iter()
        .map(|e| project(&(e.position + e.tangent * reach), az, el))
        .collect();
    let axis = [
        project(&Vector3::new(0.0, 0.0, -0.7 * braid.l_b_bar), az, el),
        project(&Vector3::new(0.0, 0.0, 0.7 * braid.l_b_bar), az, el),
    ];
    let (mut x0, mut x1, mut y0, mut y1) =
        (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for (x, y) in loop_view.iter().chain(&sa).chain(&sb).chain(&tips).chain(&axis) {
        (x0, x1, y0, y1) = (x0.min(*x), x1.max(*x), y0.min(*y), y1.max(*y));
    }
    let area = area
        .titled(title, ("sans-serif", 14))
        .map_err(|e| anyhow!("{e}"))?;
    let (w, h) = area.dim_in_pixel();
    let scale = ((f64::from(w) - 120.0) / (x1 - x0)).min((f64::from(h) - 70.0) / (y1 - y0));
    let map = |(x, y): (f64, f64)| (50.0 + (x - x0) * scale, 25.0 + (y1 - y) * scale);
    let tube = (2.0 * scale).round() as u32;
    let many = |pts: &[(f64, f64)]| pts.iter().map(|p| map(*p)).collect::<Vec<_>>();
    let (a0, a1) = (map(axis[0]), map(axis[1]));
    arrow(&area, a0, a1, GREY.stroke_width(1))?;
    text(&area, "z", (a1.0 + 6.0, a1.1 - 4.0), GREY)?;
    polyline(&area, &many(&loop_view), colour.mix(0.6).stroke_width(tube))?;
    for (pts, c, name, at) in [
        (&sa, BLUE, "strand A", 2 * sa.len() / 5),
        (&sb, ORANGE, "strand B", 3 * sb.len() / 5),
    ] {
        polyline(&area, &many(pts), c.mix(0.8).stroke_width(tube))?;
        let mid = map(pts[at]);
        text(&area, name, (mid.0 + f64::from(tube) + 4.0, mid.1 - 6.0), c)?;
    }
    for (e, tip, name) in [
        (&bc.start, tips[0], "p_s, t_s"),
        (&bc.finish, tips[1], "p_f, t_f"),
    ] {
        let (p, q) = (map(project(&e.position, az, el)), map(tip));
        area.draw(&Circle::new(px(p), 4, BLACK.filled()))
            .map_err(|e| anyhow!("{e}"))?;
        arrow(&area, p, q, BLACK.stroke_width(2))?;
        text(&area, name, (q.0 + 6.0, q.1 - 6.0), BLACK)?;
    }
    Ok(())
}

/// What a side view shows: the model and the knot's length.
struct SideView<'a> {
    params: &'a Params,
    l_k_bar: f64,
}

/// Drawings of `widths` (pixels) side by side, `height` high, each drawn by
/// `draw` on its area: one SVG.
fn panels(widths: &[u32], height: u32, mut draw: impl FnMut(usize, &Area) -> Result<()>) -> Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (widths.iter().sum(), height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let mut rest = root.clone();
        for (i, w) in widths.iter().enumerate() {
            let (panel, right) = rest.split_horizontally(*w);
            draw(i, &panel)?;
            rest = right;
        }
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    Ok(svg)
}

/// The braid and the loop at `theta`: (a) side view with the loop `centerline`
/// (units of h), (b) the view down z of the braid ends at theta = 0 and turned by
/// -`turned` (start, strand A) and +`turned` (finish, strand B), with the
/// horizontal parts of the end tangents.
pub fn schematic(
    params: &Params,
    l_k_bar: f64,
    theta: f64,
    centerline: &[[f64; 3]],
    turned: f64,
) -> Result<String> {
    let title = format!(
        "(a) n = {}, l̄_k = {}, θ = {}, φ = {}",
        params.n,
        label(l_k_bar),
        label(theta),
        label(params.phi)
    );
    let view = SideView { params, l_k_bar };
    panels(&[400, 520], 520, |i, area| match i {
        0 => side_view(area, &view, theta, centerline, &title, GREEN),
        _ => top_view(area, params, &params.braid(turned, l_k_bar), turned),
    })
}

/// The loop at a critical point: theta, stability and centreline (units of h).
pub struct CriticalShape {
    pub theta: f64,
    pub stable: bool,
    pub centerline: Vec<[f64; 3]>,
}

/// Side views of the loop at each critical point.
pub fn critical_shapes(params: &Params, l_k_bar: f64, shapes: &[CriticalShape]) -> Result<String> {
    let view = SideView { params, l_k_bar };
    panels(&vec![400; shapes.len()], 520, |i, area| {
        let c = &shapes[i];
        let title = format!(
            "θ* = {:.3} ({})",
            c.theta,
            if c.stable { "stable" } else { "unstable" }
        );
        side_view(
            area,
            &view,
            c.theta,
            &c.centerline,
            &title,
            if c.stable { GREEN } else { RED },
        )
    })
}

/// View down the braid axis: the braid cross-section, the loop ends at theta = 0
/// (open) and at theta (filled), and the horizontal parts of the end tangents.
fn top_view(area: &Area, params: &Params, braid: &Braid, theta: f64) -> Result<()> {
    let area = area
        .titled("(b) view down z: braid ends turned by ∓θ", ("sans-serif", 14))
        .map_err(|e| anyhow!("{e}"))?;
    let (w, h) = area.dim_in_pixel();
    let scale = 120.0;
    let (cx, cy) = (f64::from(w) / 2.0, f64::from(h) / 2.0 - 10.0);
    let map = |v: &Vector3<f64>| (cx + scale * v.x, cy - scale * v.y);
    let zero = LoopBoundary::new(params.n, params.phi, 0.0, braid.l_b_bar, params.end_twist);
    let now = LoopBoundary::new(params.n, params.phi, theta, braid.l_b_bar, params.end_twist);
    for (a, b, name) in [((-1.8, 0.0), (1.8, 0.0), "x"), ((0.0, -1.8), (0.0, 1.8), "y")] {
        let (p, q) = (
            map(&Vector3::new(a.0, a.1, 0.0)),
            map(&Vector3::new(b.0, b.1, 0.0)),
        );
        arrow(&area, p, q, GREY.stroke_width(1))?;
        text(&area, name, (q.0 + 6.0, q.1 - 16.0), GREY)?;
    }
    let circle: Vec<(f64, f64)> = (0..=120)
        .map(|k| {
            let a = std::f64::consts::TAU * f64::from(k) / 120.0;
            (cx + scale * a.cos(), cy + scale * a.sin())
        })
        .collect();
    polyline(&area, &circle, GREY.stroke_width(1))?;
    text(
        &area,
        "strand centrelines, radius h",
        (cx - scale, cy + scale + 8.0),
        GREY,
    )?;
    for (e0, e1, c, name) in [
        (&zero.start, &now.start, BLUE, "start (A)"),
        (&zero.finish, &now.finish, ORANGE, "finish (B)"),
    ] {
        let (p0, p1) = (map(&e0.position), map(&e1.position));
        area.draw(&Circle::new(px(p0), 6, c.stroke_width(2)))
            .and_then(|_| area.draw(&Circle::new(px(p1), 6, c.filled())))
            .map_err(|e| anyhow!("{e}"))?;
        let horizontal = Vector3::new(e1.tangent.x, e1.tangent.y, 0.0);
        let q = map(&(e1.position + horizontal * 0.9));
        arrow(&area, p1, q, c.stroke_width(2))?;
        text(&area, name, (q.0 + 6.0, q.1 + 2.0), c)?;
    }
    text(
        &area,
        &format!(
            "open: θ = 0; filled: θ = {}; arrows: horizontal part (sin φ) of the end tangents",
            label(theta)
        ),
        (20.0, f64::from(h) - 24.0),
        BLACK,
    )
}
