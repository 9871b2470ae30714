//! Publication-style SVG charts (plotters' SVG backend, no fonts needed): the
//! same F bar and H bar charts for `knotsweep run --plot`, `knotsweep
//! reproduce`, the sweep API and the web page's downloads, and the API's phase
//! diagram.
use anyhow::{Result, anyhow};
use plotters::coord::ranged1d::ValueFormatter;
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
    let plot = Plot {
        title: title.to_string(),
        x_label: x_label.to_string(),
        y_label: y_label.to_string(),
        series: (curves.iter().enumerate())
            .map(|(k, c)| Series {
                // A lone curve needs no legend: the title names it.
                label: if curves.len() > 1 {
                    c.label.to_string()
                } else {
                    String::new()
                },
                points: c.points.clone(),
                colour: Palette99::pick(k).to_rgba(),
                style: Style::Line,
            })
            .collect(),
        markers: markers.iter().map(|&m| (m, String::new())).collect(),
        pad_x: false,
        ..Plot::default()
    };
    plots_svg(&[plot], (720, 480))
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Style {
    Line,
    Dashed,
    /// Markers only, filled or open.
    Dots {
        filled: bool,
    },
    /// A line with filled markers.
    LineDots,
}

/// One series of a [`Plot`]: its legend entry (empty: none), points, colour and style.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub colour: RGBAColor,
    pub style: Style,
}

/// Where a plot's legend sits.
pub use plotters::chart::SeriesLabelPosition as LegendAt;

/// A chart of series on linear (or, with `log`, logarithmic) axes, with
/// optional labelled vertical markers and a line at y = 0: every chart of
/// this crate but the phase diagram's error bars is one.
pub struct Plot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    /// Axis ranges; `None`: the data's, padded by 5 %.
    pub x_range: Option<(f64, f64)>,
    pub y_range: Option<(f64, f64)>,
    /// Pad the data's x range (false: the curves reach the frame).
    pub pad_x: bool,
    /// Both axes logarithmic.
    pub log: bool,
    /// Vertical dashed lines at x, with their labels.
    pub markers: Vec<(f64, String)>,
    pub zero_line: bool,
    pub legend: LegendAt,
}

impl Default for Plot {
    fn default() -> Self {
        Self {
            title: String::new(),
            x_label: String::new(),
            y_label: String::new(),
            series: Vec::new(),
            x_range: None,
            y_range: None,
            pad_x: true,
            log: false,
            markers: Vec::new(),
            zero_line: false,
            legend: LegendAt::UpperRight,
        }
    }
}

/// `plots` side by side, each `size` pixels, as one SVG.
pub fn plots_svg(plots: &[Plot], size: (u32, u32)) -> Result<String> {
    let mut svg = String::new();
    {
        let root =
            SVGBackend::with_string(&mut svg, (size.0 * plots.len() as u32, size.1)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        for (plot, area) in plots.iter().zip(root.split_evenly((1, plots.len()))) {
            draw(plot, &area)?;
        }
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    Ok(svg)
}

/// The range of `values` (finite, and positive on a log axis), padded by 5 %
/// (a factor 1.5 on a log axis) when `pad`.
fn span(values: impl Iterator<Item = f64>, log: bool, pad: bool) -> (f64, f64) {
    let (lo, hi) = (values.filter(|v| v.is_finite() && (!log || *v > 0.0)))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return if log { (1.0, 10.0) } else { (0.0, 1.0) };
    }
    match (log, pad) {
        (true, true) => (lo / 1.5, hi * 1.5),
        (true, false) => (lo, hi),
        (false, _) => {
            let d = if hi - lo > 1e-12 * (lo.abs() + hi.abs()) {
                0.05 * (hi - lo)
            } else {
                0.05 * lo.abs().max(1.0)
            };
            (lo - if pad { d } else { 0.0 }, hi + d)
        }
    }
}

/// A compact tick label: at most 4 significant digits, e-notation for very
/// small or large values, no trailing zeros.
pub fn compact(v: f64) -> String {
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

/// Draws `plot` on `area`.
fn draw(plot: &Plot, area: &DrawingArea<SVGBackend, plotters::coord::Shift>) -> Result<()> {
    let xs = plot.series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
    let ys = plot.series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
    let x = plot.x_range.unwrap_or_else(|| span(xs, plot.log, plot.pad_x));
    let y = plot.y_range.unwrap_or_else(|| span(ys, plot.log, true));
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(&plot.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(64);
    if plot.log {
        let chart = builder
            .build_cartesian_2d((x.0..x.1).log_scale(), (y.0..y.1).log_scale())
            .map_err(|e| anyhow!("{e}"))?;
        fill(plot, chart, y)
    } else {
        let chart = builder
            .build_cartesian_2d(x.0..x.1, y.0..y.1)
            .map_err(|e| anyhow!("{e}"))?;
        fill(plot, chart, y)
    }
}

/// The mesh, series, markers and legend of `plot` on `chart`, whose y range is `y`.
fn fill<'a, X, Y>(
    plot: &Plot,
    mut chart: ChartContext<'a, SVGBackend<'a>, Cartesian2d<X, Y>>,
    y: (f64, f64),
) -> Result<()>
where
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let labels = if plot.log { 4 } else { 10 };
    chart
        .configure_mesh()
        .x_desc(&plot.x_label)
        .y_desc(&plot.y_label)
        .x_labels(labels)
        .y_labels(labels)
        .x_label_formatter(&|v| compact(*v))
        .y_label_formatter(&|v| compact(*v))
        .light_line_style(WHITE)
        .draw()
        .map_err(|e| anyhow!("{e}"))?;
    let grey = RGBColor(127, 127, 127);
    if plot.zero_line && y.0 < 0.0 && y.1 > 0.0 {
        let (x0, x1) = (chart.x_range().start, chart.x_range().end);
        chart
            .draw_series(LineSeries::new([(x0, 0.0), (x1, 0.0)], BLACK.stroke_width(1)))
            .map_err(|e| anyhow!("{e}"))?;
    }
    for (m, text) in &plot.markers {
        chart
            .draw_series(DashedLineSeries::new(
                [(*m, y.0), (*m, y.1)],
                3,
                4,
                grey.mix(0.8).into(),
            ))
            .map_err(|e| anyhow!("{e}"))?;
        if !text.is_empty() {
            let top = y.1 - 0.05 * (y.1 - y.0);
            chart
                .draw_series([Text::new(
                    text.clone(),
                    (*m, top),
                    ("sans-serif", 14).into_font().color(&grey),
                )])
                .map_err(|e| anyhow!("{e}"))?;
        }
    }
    for s in &plot.series {
        let colour = s.colour;
        let line = colour.stroke_width(2);
        let points = s
            .points
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite());
        let drawn = match s.style {
            Style::Line | Style::LineDots => chart.draw_series(LineSeries::new(points.clone(), line)),
            Style::Dashed => chart.draw_series(DashedLineSeries::new(points.clone(), 8, 5, line)),
            Style::Dots { filled } => chart.draw_series(points.clone().map(move |p| {
                Circle::new(
                    p,
                    4,
                    if filled {
                        colour.filled()
                    } else {
                        colour.stroke_width(2)
                    },
                )
            })),
        }
        .map_err(|e| anyhow!("{e}"))?;
        if !s.label.is_empty() {
            match s.style {
                Style::Dots { filled } => drawn.label(&s.label).legend(move |(x, y)| {
                    Circle::new(
                        (x + 9, y),
                        4,
                        if filled {
                            colour.filled()
                        } else {
                            colour.stroke_width(2)
                        },
                    )
                }),
                _ => drawn
                    .label(&s.label)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], line)),
            };
        }
        if s.style == Style::LineDots {
            chart
                .draw_series(points.map(|p| Circle::new(p, 4, colour.filled())))
                .map_err(|e| anyhow!("{e}"))?;
        }
    }
    if plot.series.iter().any(|s| !s.label.is_empty()) {
        chart
            .configure_series_labels()
            .position(plot.legend.clone())
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
    }
    Ok(())
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

#[cfg(test)]
mod tests {
    use super::compact;

    #[test]
    fn tick_labels_are_compact() {
        assert_eq!(compact(120.93409), "120.9");
        assert_eq!(compact(0.25), "0.25");
        assert_eq!(compact(1e-4), "1e-4");
        assert_eq!(compact(-0.0), "0");
        assert_eq!(compact(300.0), "300");
    }
}
