//! SVG drawings of the simplified model (pure string building, no I/O): the
//! braid-and-loop schematic, Ē(θ) and dĒ/dθ (Fig. 13 a, b), the critical curve
//! (Fig. 13 c), the snap l̄_k against h and n (Figs. 14, 15) and convergence plots.
use nalgebra::Vector3;
use solver::simplified::Params;
use solver::simplified::bifurcation::Bifurcation;
use solver::simplified::braid::{Braid, Strand};
use solver::simplified::landscape::Landscape;
use solver::simplified::loop_rod::LoopBoundary;
use std::fmt::Write;

const BLUE: &str = "#1f77b4";
const ORANGE: &str = "#ff7f0e";
const GREEN: &str = "#2ca02c";
const RED: &str = "#d62728";
const GREY: &str = "#7f7f7f";

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    Solid,
    Dashed,
    /// Markers only: filled or open circles.
    Dots {
        filled: bool,
    },
    /// A solid line with filled markers.
    LineDots,
}

/// One data series of a chart.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend entry (empty: not listed).
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub color: &'static str,
    pub kind: Kind,
}

/// Where the legend goes inside the plot area.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Corner {
    #[default]
    TopRight,
    TopLeft,
    BottomRight,
}

/// A two-dimensional chart with linear or logarithmic axes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Chart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    /// Fixed axis ranges (default: the data's, padded).
    pub x_range: Option<(f64, f64)>,
    pub y_range: Option<(f64, f64)>,
    pub log_x: bool,
    pub log_y: bool,
    /// Vertical reference lines with labels.
    pub vlines: Vec<(f64, String)>,
    /// Draw y = 0.
    pub zero_line: bool,
    pub legend: Corner,
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// A compact decimal label with at most 4 significant digits.
fn label(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        return format!("{v:.1e}").replace(".0e", "e");
    }
    let decimals = (3 - a.log10().floor() as i32).clamp(0, 6) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Tick positions: 1-2-5 steps on a linear axis, decades on a log axis.
fn ticks(lo: f64, hi: f64, log: bool) -> Vec<f64> {
    if log {
        let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        let mantissas: &[f64] = if b - a <= 2 { &[1.0, 2.0, 5.0] } else { &[1.0] };
        return (a..=b)
            .flat_map(|e| mantissas.iter().map(move |m| m * 10f64.powi(e)))
            .filter(|t| *t >= lo * 0.999 && *t <= hi * 1.001)
            .collect();
    }
    let raw = (hi - lo) / 8.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    (first..=last).map(|i| i as f64 * step).collect()
}

fn padded(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if log {
        return (lo / 1.5, hi * 1.5);
    }
    if hi - lo < 1e-12 * (lo.abs() + hi.abs()).max(1e-300) {
        let d = 0.05 * lo.abs().max(1.0);
        return (lo - d, hi + d);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

/// Renders `chart` as a standalone SVG of `width` x `height` pixels.
pub fn chart(chart: &Chart, width: f64, height: f64) -> String {
    let (ml, mr, mt, mb) = (72.0, 16.0, 34.0, 50.0);
    let (pw, ph) = (width - ml - mr, height - mt - mb);
    let xr = chart.x_range.unwrap_or_else(|| {
        padded(
            chart.series.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
            chart.log_x,
        )
    });
    let yr = chart.y_range.unwrap_or_else(|| {
        padded(
            chart.series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
            chart.log_y,
        )
    });
    let map = |v: f64, (lo, hi): (f64, f64), log: bool| {
        if log {
            (v.log10() - lo.log10()) / (hi.log10() - lo.log10())
        } else {
            (v - lo) / (hi - lo)
        }
    };
    let sx = |x: f64| ml + pw * map(x, xr, chart.log_x);
    let sy = |y: f64| mt + ph * (1.0 - map(y, yr, chart.log_y));
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{width}" height="{height}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{:.1}" y="20" text-anchor="middle" font-size="14">{}</text>"#,
        ml + pw / 2.0,
        escape(&chart.title)
    );
    let _ = writeln!(
        s,
        r#"<defs><clipPath id="plot"><rect x="{ml}" y="{mt}" width="{pw}" height="{ph}"/></clipPath></defs>"#
    );
    for t in ticks(xr.0, xr.1, chart.log_x) {
        let x = sx(t);
        let _ = writeln!(
            s,
            r##"<line x1="{x:.1}" y1="{mt}" x2="{x:.1}" y2="{:.1}" stroke="#e5e5e5"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
            mt + ph,
            mt + ph + 16.0,
            label(t)
        );
    }
    for t in ticks(yr.0, yr.1, chart.log_y) {
        let y = sy(t);
        let _ = writeln!(
            s,
            r##"<line x1="{ml}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#e5e5e5"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
            ml + pw,
            ml - 6.0,
            y + 4.0,
            label(t)
        );
    }
    let _ = writeln!(
        s,
        r#"<rect x="{ml}" y="{mt}" width="{pw}" height="{ph}" fill="none" stroke="black"/>"#
    );
    let _ = writeln!(
        s,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
        ml + pw / 2.0,
        height - 12.0,
        escape(&chart.x_label)
    );
    let _ = writeln!(
        s,
        r#"<text transform="translate(16 {:.1}) rotate(-90)" text-anchor="middle">{}</text>"#,
        mt + ph / 2.0,
        escape(&chart.y_label)
    );
    let _ = writeln!(s, r#"<g clip-path="url(#plot)">"#);
    if chart.zero_line && yr.0 < 0.0 && yr.1 > 0.0 {
        let y = sy(0.0);
        let _ = writeln!(
            s,
            r#"<line x1="{ml}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="black" stroke-width="0.8"/>"#,
            ml + pw
        );
    }
    for (v, text) in &chart.vlines {
        let x = sx(*v);
        let _ = writeln!(
            s,
            r#"<line x1="{x:.1}" y1="{mt}" x2="{x:.1}" y2="{:.1}" stroke="{GREY}" stroke-dasharray="2 3"/><text x="{:.1}" y="{:.1}" fill="{GREY}">{}</text>"#,
            mt + ph,
            x + 3.0,
            mt + 14.0,
            escape(text)
        );
    }
    for series in &chart.series {
        let pts: Vec<(f64, f64)> = series
            .points
            .iter()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .map(|p| (sx(p.0), sy(p.1)))
            .collect();
        if matches!(series.kind, Kind::Solid | Kind::Dashed | Kind::LineDots) && pts.len() > 1 {
            let d: Vec<String> = pts.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
            let dash = if series.kind == Kind::Dashed {
                r#" stroke-dasharray="6 4""#
            } else {
                ""
            };
            let _ = writeln!(
                s,
                r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="1.8"{dash}/>"#,
                d.join(" "),
                series.color
            );
        }
        if let Kind::Dots { .. } | Kind::LineDots = series.kind {
            let fill = if series.kind == (Kind::Dots { filled: false }) {
                "white"
            } else {
                series.color
            };
            for (x, y) in &pts {
                let _ = writeln!(
                    s,
                    r#"<circle cx="{x:.1}" cy="{y:.1}" r="4" fill="{fill}" stroke="{}" stroke-width="1.5"/>"#,
                    series.color
                );
            }
        }
    }
    let _ = writeln!(s, "</g>");
    let entries: Vec<&Series> = chart.series.iter().filter(|s| !s.label.is_empty()).collect();
    if !entries.is_empty() {
        let text_w = entries.iter().map(|e| e.label.chars().count()).max().unwrap_or(0) as f64 * 7.0;
        let (bw, bh) = (text_w + 44.0, 16.0 * entries.len() as f64 + 8.0);
        let (bx, by) = match chart.legend {
            Corner::TopRight => (ml + pw - bw - 6.0, mt + 6.0),
            Corner::TopLeft => (ml + 6.0, mt + 6.0),
            Corner::BottomRight => (ml + pw - bw - 6.0, mt + ph - bh - 6.0),
        };
        let _ = writeln!(
            s,
            r##"<rect x="{bx:.1}" y="{by:.1}" width="{bw:.1}" height="{bh:.1}" fill="white" fill-opacity="0.85" stroke="#cccccc"/>"##
        );
        for (i, series) in entries.iter().enumerate() {
            let (x, ly) = (bx + 6.0, by + 18.0 + 16.0 * i as f64);
            match series.kind {
                Kind::Dots { filled } => {
                    let fill = if filled { series.color } else { "white" };
                    let _ = writeln!(
                        s,
                        r#"<circle cx="{:.1}" cy="{:.1}" r="4" fill="{fill}" stroke="{}" stroke-width="1.5"/>"#,
                        x + 12.0,
                        ly - 4.0,
                        series.color
                    );
                }
                kind => {
                    let dash = if kind == Kind::Dashed {
                        r#" stroke-dasharray="6 4""#
                    } else {
                        ""
                    };
                    let _ = writeln!(
                        s,
                        r#"<line x1="{x:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{}" stroke-width="1.8"{dash}/>"#,
                        ly - 4.0,
                        x + 24.0,
                        ly - 4.0,
                        series.color
                    );
                }
            }
            let _ = writeln!(
                s,
                r#"<text x="{:.1}" y="{ly:.1}">{}</text>"#,
                x + 30.0,
                escape(&series.label)
            );
        }
    }
    s.push_str("</svg>\n");
    s
}

/// Places standalone SVGs of the given widths and height `h` side by side in one SVG.
fn side_by_side_sized(parts: &[(String, f64)], h: f64) -> String {
    let total: f64 = parts.iter().map(|p| p.1).sum();
    let mut s = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{total}" height="{h}" viewBox="0 0 {total} {h}">"#
    );
    s.push('\n');
    let mut x = 0.0;
    for (i, (p, w)) in parts.iter().enumerate() {
        let inner = p.replacen("<svg ", &format!(r#"<svg x="{x}" y="0" "#), 1);
        // Ids must stay unique within one document.
        let inner = inner
            .replace("id=\"plot\"", &format!("id=\"plot{i}\""))
            .replace("url(#plot)", &format!("url(#plot{i})"))
            .replace("id=\"arrow\"", &format!("id=\"arrow{i}\""))
            .replace("url(#arrow)", &format!("url(#arrow{i})"));
        s.push_str(&inner);
        x += w;
    }
    s.push_str("</svg>\n");
    s
}

/// Places standalone SVGs of equal size `w` x `h` side by side in one SVG.
fn side_by_side(parts: &[String], w: f64, h: f64) -> String {
    let sized: Vec<(String, f64)> = parts.iter().map(|p| (p.clone(), w)).collect();
    side_by_side_sized(&sized, h)
}

/// Ē, Ē_b, Ē_l against theta and dĒ/dθ, with the critical points (filled:
/// stable, open: unstable); paper Fig. 13 (a, b).
pub fn landscape(l: &Landscape) -> String {
    let pts = |f: fn(&solver::simplified::LandscapePoint) -> f64| {
        l.points.iter().map(|p| (p.theta, f(p))).collect::<Vec<_>>()
    };
    let crit = |stable: bool, y: &dyn Fn(&solver::simplified::CriticalPoint) -> f64| Series {
        label: if stable {
            "stable".into()
        } else {
            "unstable".into()
        },
        points: l
            .critical_points
            .iter()
            .filter(|c| c.stable == stable)
            .map(|c| (c.theta, y(c)))
            .collect(),
        color: RED,
        kind: Kind::Dots { filled: stable },
    };
    let title = format!("n = {}, l̄_k = {}", l.spec.params.n, label(l.spec.l_k_bar));
    // Head room above the curves for the legend.
    let top = l.points.iter().map(|p| p.energy).fold(0.0f64, f64::max);
    let energy = Chart {
        title: format!("(a) total energy, {title}"),
        x_label: "θ (rad)".into(),
        y_label: "Ē = E h / EI".into(),
        series: vec![
            Series {
                label: "Ē".into(),
                points: pts(|p| p.energy),
                color: BLUE,
                kind: Kind::Solid,
            },
            Series {
                label: "Ē_b (braid)".into(),
                points: pts(|p| p.braid_energy),
                color: ORANGE,
                kind: Kind::Dashed,
            },
            Series {
                label: "Ē_l (loop)".into(),
                points: pts(|p| p.loop_energy),
                color: GREEN,
                kind: Kind::Dashed,
            },
            crit(true, &|c| c.energy),
            crit(false, &|c| c.energy),
        ],
        y_range: Some((0.0, 1.45 * top)),
        ..Chart::default()
    };
    let slope = Chart {
        title: format!("(b) dĒ/dθ, {title}"),
        x_label: "θ (rad)".into(),
        y_label: "dĒ/dθ".into(),
        series: vec![
            Series {
                label: "dĒ/dθ".into(),
                points: pts(|p| p.denergy_dtheta),
                color: BLUE,
                kind: Kind::Solid,
            },
            crit(true, &|_| 0.0),
            crit(false, &|_| 0.0),
        ],
        zero_line: true,
        legend: Corner::BottomRight,
        ..Chart::default()
    };
    side_by_side(
        &[chart(&energy, 520.0, 380.0), chart(&slope, 520.0, 380.0)],
        520.0,
        380.0,
    )
}

/// theta at the critical points against l̄_k (solid: stable, dashed: unstable),
/// the folds, and optional reference lengths; paper Fig. 13 (c).
pub fn bifurcation(b: &Bifurcation, marks: &[(f64, String)]) -> String {
    let mut series = Vec::new();
    let mut run: Vec<(f64, f64)> = Vec::new();
    let mut stable = b.branch.first().is_some_and(|p| p.stable);
    let mut labelled = [false, false];
    let mut flush = |run: &mut Vec<(f64, f64)>, stable: bool, series: &mut Vec<Series>| {
        if run.len() > 1 {
            let i = usize::from(stable);
            let label = if labelled[i] {
                String::new()
            } else if stable {
                "stable".into()
            } else {
                "unstable".into()
            };
            labelled[i] = true;
            series.push(Series {
                label,
                points: run.clone(),
                color: if stable { BLUE } else { RED },
                kind: if stable { Kind::Solid } else { Kind::Dashed },
            });
        }
        run.drain(..run.len().saturating_sub(1));
    };
    for p in &b.branch {
        if p.stable != stable {
            // Join the runs at the fold between the two points.
            run.push((p.l_k_bar, p.theta));
            flush(&mut run, stable, &mut series);
            stable = p.stable;
            continue;
        }
        run.push((p.l_k_bar, p.theta));
    }
    flush(&mut run, stable, &mut series);
    series.push(Series {
        label: "folds".into(),
        points: b.folds.iter().map(|f| (f.l_k_bar, f.theta)).collect(),
        color: "black",
        kind: Kind::Dots { filled: true },
    });
    let c = Chart {
        title: format!("(c) critical points, n = {}", b.spec.params.n),
        x_label: "l̄_k = l_k / h".into(),
        y_label: "θ* (rad)".into(),
        series,
        vlines: marks.to_vec(),
        ..Chart::default()
    };
    chart(&c, 560.0, 400.0)
}

/// The snap l̄_k (lower fold) against a swept parameter; `rows` pairs the
/// parameter with the snap length (None: no fold).
pub fn snap_sweep(
    title: &str,
    x_label: &str,
    rows: &[(f64, Option<f64>)],
    y_range: Option<(f64, f64)>,
) -> String {
    let c = Chart {
        title: title.into(),
        x_label: x_label.into(),
        y_label: "snap l̄_k".into(),
        series: vec![Series {
            label: "simplified model".into(),
            points: rows.iter().filter_map(|(x, y)| y.map(|y| (*x, y))).collect(),
            color: BLUE,
            kind: Kind::LineDots,
        }],
        y_range,
        legend: Corner::TopLeft,
        ..Chart::default()
    };
    chart(&c, 520.0, 360.0)
}

/// Relative error of the DER braid energy against eq. (14) on log-log axes, with
/// a reference line of slope -2.
pub fn braid_convergence(rows: &[(usize, f64)]) -> String {
    let pts: Vec<(f64, f64)> = rows.iter().map(|(k, e)| (*k as f64, *e)).collect();
    let mut series = vec![Series {
        label: "|Ē_b(DER)/Ē_b(eq. 14) - 1|".into(),
        points: pts.clone(),
        color: BLUE,
        kind: Kind::LineDots,
    }];
    if let Some(&(k0, e0)) = pts.first() {
        series.push(Series {
            label: "slope -2".into(),
            points: pts.iter().map(|(k, _)| (*k, e0 * (k0 / k).powi(2))).collect(),
            color: GREY,
            kind: Kind::Dashed,
        });
    }
    let c = Chart {
        title: "braid: DER discretisation vs closed form".into(),
        x_label: "nodes per strand".into(),
        y_label: "relative error".into(),
        series,
        log_x: true,
        log_y: true,
        ..Chart::default()
    };
    chart(&c, 520.0, 360.0)
}

/// Orthographic view: azimuth about z, then elevation; returns (right, up).
fn project(v: &Vector3<f64>, azimuth: f64, elevation: f64) -> (f64, f64) {
    let (sa, ca) = azimuth.sin_cos();
    let (se, ce) = elevation.sin_cos();
    let right = -sa * v.x + ca * v.y;
    let depth = ca * v.x + sa * v.y;
    (right, ce * v.z - se * depth)
}

/// Opening of a `w` x `h` schematic: white background, an arrow-head marker
/// (`url(#arrow)`) and a centred title.
fn figure_header(w: f64, h: f64, title: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="13">"#
    );
    let _ = writeln!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<defs><marker id="arrow" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" markerHeight="7" orient="auto"><path d="M0,0 L10,5 L0,10 z" fill="black"/></marker></defs>"#
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="22" text-anchor="middle" font-size="14">{}</text>"#,
        w / 2.0,
        escape(title)
    );
    s
}

fn path(points: &[(f64, f64)], map: &dyn Fn((f64, f64)) -> (f64, f64)) -> String {
    points
        .iter()
        .map(|p| {
            let (x, y) = map(*p);
            format!("{x:.1},{y:.1}")
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Side view (across the braid axis) of the braid at `theta` and one loop
/// centreline (units of h), drawn as tubes of the rod's diameter, with the clamp
/// points, the end tangents and the braid axis z.
fn side_view(
    params: &Params,
    l_k_bar: f64,
    theta: f64,
    centerline: &[[f64; 3]],
    title: &str,
    color: &str,
) -> String {
    let braid = params.braid(theta, l_k_bar);
    let bc = LoopBoundary::new(params.n, params.phi, theta, braid.l_b_bar, params.end_twist);
    let (az, el) = (0.35, 0.25);
    let t = braid.half_span();
    let strand = |s: Strand| -> Vec<(f64, f64)> {
        (0..=400)
            .map(|i| project(&braid.point(s, -t + 2.0 * t * i as f64 / 400.0), az, el))
            .collect()
    };
    let view: Vec<(f64, f64)> = centerline
        .iter()
        .map(|p| project(&Vector3::new(p[0], p[1], p[2]), az, el))
        .collect();
    let (sa, sb) = (strand(Strand::A), strand(Strand::B));
    let arrow = 0.18 * braid.l_b_bar;
    let tips: Vec<(f64, f64)> = [&bc.start, &bc.finish]
        .iter()
        .map(|e| project(&(e.position + e.tangent * arrow), az, el))
        .collect();
    let axis = [
        project(&Vector3::new(0.0, 0.0, -0.7 * braid.l_b_bar), az, el),
        project(&Vector3::new(0.0, 0.0, 0.7 * braid.l_b_bar), az, el),
    ];
    let (mut x0, mut x1, mut y0, mut y1) =
        (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for (x, y) in view.iter().chain(&sa).chain(&sb).chain(&tips).chain(&axis) {
        x0 = x0.min(*x);
        x1 = x1.max(*x);
        y0 = y0.min(*y);
        y1 = y1.max(*y);
    }
    let (w, h) = (400.0, 520.0);
    let scale = ((w - 120.0) / (x1 - x0)).min((h - 100.0) / (y1 - y0));
    let map = |(x, y): (f64, f64)| (50.0 + (x - x0) * scale, 50.0 + (y1 - y) * scale);
    let tube = 2.0 * scale;
    let mut s = figure_header(w, h, title);
    let (a0, a1) = (map(axis[0]), map(axis[1]));
    let _ = writeln!(
        s,
        r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{GREY}" stroke-dasharray="5 4" marker-end="url(#arrow)"/><text x="{:.1}" y="{:.1}" fill="{GREY}">z</text>"#,
        a0.0,
        a0.1,
        a1.0,
        a1.1,
        a1.0 + 6.0,
        a1.1 + 4.0
    );
    let _ = writeln!(
        s,
        r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="{tube:.1}" stroke-opacity="0.6" stroke-linejoin="round"/>"#,
        path(&view, &map)
    );
    for (pts, c, name) in [(&sa, BLUE, "strand A"), (&sb, ORANGE, "strand B")] {
        let _ = writeln!(
            s,
            r#"<polyline points="{}" fill="none" stroke="{c}" stroke-width="{tube:.1}" stroke-opacity="0.8"/>"#,
            path(pts, &map)
        );
        let at = if name == "strand A" {
            2 * pts.len() / 5
        } else {
            3 * pts.len() / 5
        };
        let mid = map(pts[at]);
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" fill="{c}">{name}</text>"#,
            mid.0 + tube + 4.0,
            mid.1 + 4.0
        );
    }
    for (e, tip, name) in [
        (&bc.start, tips[0], "p_s, t_s"),
        (&bc.finish, tips[1], "p_f, t_f"),
    ] {
        let p = map(project(&e.position, az, el));
        let q = map(tip);
        let _ = writeln!(
            s,
            r#"<circle cx="{:.1}" cy="{:.1}" r="4" fill="black"/><line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="black" stroke-width="2" marker-end="url(#arrow)"/><text x="{:.1}" y="{:.1}">{name}</text>"#,
            p.0,
            p.1,
            p.0,
            p.1,
            q.0,
            q.1,
            q.0 + 6.0,
            q.1 + 4.0
        );
    }
    s.push_str("</svg>\n");
    s
}

/// The braid and the loop at `theta`: (a) side view with the loop `centerline`
/// (units of h), (b) the view down z of the braid ends at theta = 0 and turned by
/// -`turned` (start, strand A) and +`turned` (finish, strand B), with the
/// horizontal parts of the end tangents.
pub fn schematic(params: &Params, l_k_bar: f64, theta: f64, centerline: &[[f64; 3]], turned: f64) -> String {
    let title = format!(
        "(a) n = {}, l̄_k = {}, θ = {}, φ = {}",
        params.n,
        label(l_k_bar),
        label(theta),
        label(params.phi)
    );
    let side = side_view(params, l_k_bar, theta, centerline, &title, GREEN);
    let top = top_view(params, &params.braid(turned, l_k_bar), turned);
    side_by_side_sized(&[(side, 400.0), (top, 520.0)], 520.0)
}

/// Side views of the loop at each critical point `(theta, stable, centerline)`.
pub fn critical_shapes(params: &Params, l_k_bar: f64, points: &[(f64, bool, Vec<[f64; 3]>)]) -> String {
    let parts: Vec<(String, f64)> = points
        .iter()
        .map(|(theta, stable, c)| {
            let title = format!(
                "θ* = {:.3} ({})",
                theta,
                if *stable { "stable" } else { "unstable" }
            );
            (
                side_view(
                    params,
                    l_k_bar,
                    *theta,
                    c,
                    &title,
                    if *stable { GREEN } else { RED },
                ),
                400.0,
            )
        })
        .collect();
    side_by_side_sized(&parts, 520.0)
}

/// View down the braid axis: the braid cross-section, the loop ends at theta = 0
/// (open) and at theta (filled), and the horizontal parts of the end tangents.
fn top_view(params: &Params, braid: &Braid, theta: f64) -> String {
    let (w, h) = (520.0, 520.0);
    let scale = 120.0;
    let (cx, cy) = (w / 2.0, h / 2.0 + 10.0);
    let map = |v: &Vector3<f64>| (cx + scale * v.x, cy - scale * v.y);
    let zero = LoopBoundary::new(params.n, params.phi, 0.0, braid.l_b_bar, params.end_twist);
    let now = LoopBoundary::new(params.n, params.phi, theta, braid.l_b_bar, params.end_twist);
    let mut s = figure_header(w, h, "(b) view down z: braid ends turned by ∓θ");
    for (a, b, t) in [((-1.8, 0.0), (1.8, 0.0), "x"), ((0.0, -1.8), (0.0, 1.8), "y")] {
        let p = map(&Vector3::new(a.0, a.1, 0.0));
        let q = map(&Vector3::new(b.0, b.1, 0.0));
        let _ = writeln!(
            s,
            r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{GREY}" marker-end="url(#arrow)"/><text x="{:.1}" y="{:.1}" fill="{GREY}">{t}</text>"#,
            p.0,
            p.1,
            q.0,
            q.1,
            q.0 + 6.0,
            q.1 - 4.0
        );
    }
    let _ = writeln!(
        s,
        r#"<circle cx="{cx}" cy="{cy}" r="{scale}" fill="none" stroke="{GREY}" stroke-dasharray="4 4"/><text x="{:.1}" y="{:.1}" fill="{GREY}">strand centrelines, radius h</text>"#,
        cx - scale,
        cy + scale + 22.0
    );
    for (e0, e1, c, name) in [
        (&zero.start, &now.start, BLUE, "start (A)"),
        (&zero.finish, &now.finish, ORANGE, "finish (B)"),
    ] {
        let p0 = map(&e0.position);
        let p1 = map(&e1.position);
        let _ = writeln!(
            s,
            r#"<circle cx="{:.1}" cy="{:.1}" r="6" fill="white" stroke="{c}" stroke-width="2"/><circle cx="{:.1}" cy="{:.1}" r="6" fill="{c}"/>"#,
            p0.0, p0.1, p1.0, p1.1
        );
        let horizontal = Vector3::new(e1.tangent.x, e1.tangent.y, 0.0);
        let q = map(&(e1.position + horizontal * 0.9));
        let _ = writeln!(
            s,
            r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{c}" stroke-width="2" marker-end="url(#arrow)"/><text x="{:.1}" y="{:.1}" fill="{c}">{name}</text>"#,
            p1.0,
            p1.1,
            q.0,
            q.1,
            q.0 + 6.0,
            q.1 + 14.0
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="20" y="{}">open: θ = 0; filled: θ = {}; arrows: horizontal part (sin φ) of the end tangents</text>"#,
        h - 16.0,
        label(theta)
    );
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_and_labels() {
        let close = |a: Vec<f64>, b: &[f64]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
        };
        assert!(close(ticks(0.0, 5.0, false), &[0.0, 1.0, 2.0, 3.0, 4.0, 5.0]));
        assert!(close(
            ticks(-0.23, 0.35, false),
            &[-0.2, -0.1, 0.0, 0.1, 0.2, 0.3]
        ));
        assert!(close(
            ticks(15.0, 700.0, true),
            &[20.0, 50.0, 100.0, 200.0, 500.0]
        ));
        assert_eq!(label(120.93409), "120.9");
        assert_eq!(label(0.25), "0.25");
        assert_eq!(label(1e-4), "1e-4");
        assert_eq!(escape("a < b & c"), "a &lt; b &amp; c");
    }
}
