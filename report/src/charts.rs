//! Publication-style SVG charts (plotters' SVG backend, no fonts needed): the
//! same F bar and H bar charts for `knotsweep run --plot`, `knotsweep
//! reproduce`, the sweep API and the web page's downloads, and the API's phase
//! diagram.
use anyhow::{Result, anyhow};
use plotters::prelude::*;
use solver::case::CaseParams;
use solver::measurements::Sample;

/// What a tightening chart plots against l_k bar (paper Fig. 5 a, b).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    FBar,
    HBar,
}

impl Quantity {
    /// Both, in the order figures list them.
    pub const ALL: [Self; 2] = [Self::FBar, Self::HBar];

    /// The figure's file stem: the paper's symbol, as in the series' names.
    pub fn stem(self) -> &'static str {
        match self {
            Self::FBar => "F_bar",
            Self::HBar => "H_bar",
        }
    }

    /// From a figure's file stem ([`Quantity::stem`]).
    pub fn parse(stem: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|q| q.stem() == stem)
    }

    pub fn axis_label(self) -> &'static str {
        match self {
            Self::FBar => "F bar = F h^2 / EI",
            Self::HBar => "H bar = H / W",
        }
    }

    pub fn of(self, s: &Sample) -> f64 {
        match self {
            Self::FBar => s.f_bar,
            Self::HBar => s.h_bar,
        }
    }
}

/// One case's tightening curve: its label, series and inversion l_k bar.
pub struct CaseCurve<'a> {
    pub label: String,
    pub series: &'a [Sample],
    pub inversion: Option<f64>,
}

/// F bar or H bar against l_k bar for one or more cases (paper Figs 5, 6, 8,
/// 10 a, b), the inversions marked by vertical lines.
pub fn tightening_chart(title: &str, quantity: Quantity, cases: &[CaseCurve]) -> Result<String> {
    let curves: Vec<Curve> = cases
        .iter()
        .map(|c| Curve {
            label: &c.label,
            points: c.series.iter().map(|s| (s.l_k_bar, quantity.of(s))).collect(),
        })
        .collect();
    let markers: Vec<f64> = cases.iter().filter_map(|c| c.inversion).collect();
    line_chart(
        title,
        "l_k bar = (L - l_c) / h",
        quantity.axis_label(),
        &curves,
        &markers,
    )
}

/// One case's F bar or H bar chart, titled with its n, h and mu: the figure
/// of `knotsweep run --plot` and of `GET /api/cases/{id}/figures/*.svg`.
pub fn case_chart(
    params: &CaseParams,
    series: &[Sample],
    inversion: Option<f64>,
    quantity: Quantity,
) -> Result<String> {
    let label = format!("n = {}, h = {} mm, mu = {}", params.n, params.h * 1e3, params.mu);
    let curve = CaseCurve {
        label: label.clone(),
        series,
        inversion,
    };
    tightening_chart(&label, quantity, &[curve])
}

/// One curve of a chart.
pub struct Curve<'a> {
    pub label: &'a str,
    pub points: Vec<(f64, f64)>,
}

/// A line chart of `curves` with axis labels and optional vertical markers at
/// the given x values; returns the SVG text.
pub fn line_chart(
    title: &str,
    x_label: &str,
    y_label: &str,
    curves: &[Curve],
    markers: &[f64],
) -> Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let all = curves
            .iter()
            .flat_map(|c| c.points.iter())
            .filter(|(x, y)| x.is_finite() && y.is_finite());
        let (mut x0, mut x1, mut y0, mut y1) =
            (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
        for &(x, y) in all {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
        if !x0.is_finite() {
            (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
        }
        let pad = 0.05 * (y1 - y0).max(1e-12);
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .light_line_style(WHITE)
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        for (k, curve) in curves.iter().enumerate() {
            let color = Palette99::pick(k).to_rgba();
            chart
                .draw_series(LineSeries::new(
                    curve.points.iter().copied(),
                    color.stroke_width(2),
                ))
                .map_err(|e| anyhow!("{e}"))?
                .label(curve.label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
        }
        for &m in markers {
            chart
                .draw_series(LineSeries::new([(m, y0 - pad), (m, y1 + pad)], BLACK.mix(0.5)))
                .map_err(|e| anyhow!("{e}"))?;
        }
        if curves.len() > 1 {
            legend(&mut chart)?;
        }
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    Ok(svg)
}

/// A phase diagram (paper Figs 7, 9, 11, 14, 15): the full model's critical
/// l_k bar as points against the varied parameter, and the simplified model's
/// as a line where given.
/// A phase-diagram point: x, the inversion's l_k bar and, for a certified
/// point, its numerical uncertainty (l_k bar) and whether it is within the
/// convergence threshold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseMark {
    pub x: f64,
    pub l_k_bar: f64,
    pub uncertainty: Option<f64>,
    pub converged: bool,
}

/// The phase diagram: inversions (error bars where certified, unconverged
/// points as open red circles) and the simplified model's line.
pub fn phase_chart(
    title: &str,
    x_label: &str,
    marks: &[PhaseMark],
    simplified: &[(f64, f64)],
) -> Result<String> {
    let points: Vec<(f64, f64)> = marks.iter().map(|m| (m.x, m.l_k_bar)).collect();
    let bars: Vec<(f64, f64)> = (marks.iter())
        .filter_map(|m| {
            m.uncertainty
                .map(|u| [(m.x, m.l_k_bar - u), (m.x, m.l_k_bar + u)])
        })
        .flatten()
        .collect();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let all = points.iter().chain(simplified).chain(&bars);
        let (mut x0, mut x1, mut y0, mut y1) =
            (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
        for &(x, y) in all {
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
        if !x0.is_finite() {
            (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
        }
        let (xp, yp) = (0.05 * (x1 - x0).max(1e-9), 0.1 * (y1 - y0).max(1.0));
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d((x0 - xp)..(x1 + xp), (y0 - yp).max(0.0)..(y1 + yp))
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc("critical l_k bar")
            .light_line_style(WHITE)
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        let blue = Palette99::pick(0).to_rgba();
        chart
            .draw_series(points.iter().map(|&p| Circle::new(p, 5, blue.filled())))
            .map_err(|e| anyhow!("{e}"))?
            .label("full model (inversion)")
            .legend(move |(x, y)| Circle::new((x + 9, y), 5, blue.filled()));
        if !bars.is_empty() {
            chart
                .draw_series(marks.iter().filter_map(|m| {
                    let u = m.uncertainty?;
                    Some(ErrorBar::new_vertical(
                        m.x,
                        m.l_k_bar - u,
                        m.l_k_bar,
                        m.l_k_bar + u,
                        BLACK.stroke_width(1),
                        8,
                    ))
                }))
                .map_err(|e| anyhow!("{e}"))?
                .label("numerical uncertainty (refined twin: time step halved)")
                .legend(|(x, y)| PathElement::new(vec![(x + 9, y - 6), (x + 9, y + 6)], BLACK));
        }
        if marks.iter().any(|m| !m.converged) {
            let red = RED.stroke_width(2);
            chart
                .draw_series(
                    marks
                        .iter()
                        .filter(|m| !m.converged)
                        .map(|m| Circle::new((m.x, m.l_k_bar), 9, red)),
                )
                .map_err(|e| anyhow!("{e}"))?
                .label(format!(
                    "unconverged (uncertainty above {} %)",
                    100.0 * solver::certify::CONVERGED_WITHIN
                ))
                .legend(move |(x, y)| Circle::new((x + 9, y), 7, red));
        }
        if !simplified.is_empty() {
            let red = Palette99::pick(1).to_rgba();
            chart
                .draw_series(LineSeries::new(simplified.iter().copied(), red.stroke_width(2)))
                .map_err(|e| anyhow!("{e}"))?
                .label("simplified model (Sec. 5)")
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], red.stroke_width(2)));
        }
        legend(&mut chart)?;
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    Ok(svg)
}

/// The boxed legend of a chart's labelled series.
fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
) -> Result<()> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| anyhow!("{e}"))
}
