//! Publication-style SVG charts (plotters' SVG backend, no fonts needed): the
//! same F bar and H bar charts for `knotsweep run --plot`, `knotsweep
//! reproduce`, the sweep API and the web page's downloads, and the API's phase
//! diagram.
use crate::symbols::{self, F_BAR, H_BAR, L_K_BAR};
use anyhow::{Result, anyhow};
use plotters::coord::ranged1d::ValueFormatter;
use plotters::prelude::*;
use solver::case::{CaseParams, Direction, LoadStage};
use solver::measurements::Sample;
use solver::protocol::{Event, EventKind};

/// What a tightening chart plots against l̄_k (paper Fig. 5 a, b).
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

    /// The paper's symbol.
    pub fn symbol(self) -> &'static str {
        match self {
            Self::FBar => F_BAR,
            Self::HBar => H_BAR,
        }
    }

    pub fn axis_label(self) -> &'static str {
        match self {
            Self::FBar => "F̄ = F h² / EI",
            Self::HBar => "H̄ = H / W",
        }
    }

    pub fn of(self, s: &Sample) -> f64 {
        match self {
            Self::FBar => s.f_bar,
            Self::HBar => s.h_bar,
        }
    }
}

/// The x axis of every tightening chart.
pub const L_K_AXIS: &str = "l̄_k = (L − l_c) / h";

/// One case's tightening curve: its label, series, the direction of each
/// stage of its loading program (by `Sample::stage`) and its events
/// (inversions, flips back) at their l̄_k.
pub struct CaseCurve<'a> {
    pub label: String,
    pub series: &'a [Sample],
    pub directions: Vec<Direction>,
    pub events: Vec<(EventKind, f64)>,
}

impl<'a> CaseCurve<'a> {
    /// A case's curve: the directions of its program, its events.
    pub fn new(label: String, params: &CaseParams, series: &'a [Sample], events: &[Event]) -> Self {
        Self {
            label,
            series,
            directions: params.program().iter().map(LoadStage::direction).collect(),
            events: events.iter().map(|e| (e.kind, e.at.l_k_bar)).collect(),
        }
    }
}

/// The line style of a stage's direction: tightening solid, loosening
/// dashed, holding or rotating dotted.
fn direction_style(d: Direction) -> Style {
    match d {
        Direction::Tighten => Style::Line,
        Direction::Loosen => Style::Dashed,
        Direction::Still => Style::Dotted,
    }
}

/// F̄ or H̄ against l̄_k for one or more cases (paper Figs 5, 6, 8, 10 a, b):
/// each stage of a case's program in its direction's style (tightening
/// solid, loosening dashed, holding dotted), its inversions as filled and
/// its flips back as open circles on the curve, and `measured` inversions
/// (l̄_k, error) as labelled vertical lines; `caption` says what is held fixed.
pub fn tightening_chart(
    title: &str,
    caption: &str,
    quantity: Quantity,
    cases: &[CaseCurve],
    measured: &[(f64, f64)],
) -> Result<String> {
    let mut series = Vec::new();
    let directions: std::collections::BTreeSet<u8> = cases
        .iter()
        .flat_map(|c| {
            c.series
                .iter()
                .map(|s| c.directions.get(s.stage).copied().unwrap_or(Direction::Tighten) as u8)
        })
        .collect();
    let styled = directions.len() > 1;
    let black = BLACK.to_rgba();
    for (k, c) in cases.iter().enumerate() {
        let colour = Palette99::pick(k).to_rgba();
        // Runs of one stage, each starting where the one before ended.
        let mut start = 0;
        let mut first = true;
        while start < c.series.len() {
            let stage = c.series[start].stage;
            let end = (start..c.series.len())
                .find(|&i| c.series[i].stage != stage)
                .unwrap_or(c.series.len());
            let from = start.saturating_sub(1);
            let direction = c.directions.get(stage).copied().unwrap_or(Direction::Tighten);
            series.push(Series {
                label: if first && cases.len() > 1 {
                    c.label.clone()
                } else {
                    String::new()
                },
                points: c.series[from..end]
                    .iter()
                    .map(|s| (s.l_k_bar, quantity.of(s)))
                    .collect(),
                colour,
                style: direction_style(direction),
            });
            first = false;
            start = end;
        }
        for (kind, at) in &c.events {
            let Some(y) = value_at(c.series, *at, quantity) else {
                continue;
            };
            series.push(Series {
                label: String::new(),
                points: vec![(*at, y)],
                colour,
                style: Style::Dots {
                    filled: *kind == EventKind::Inversion,
                },
            });
        }
    }
    // Legend entries of the styles, in black: what each line and mark means.
    if styled {
        for (d, name) in [
            (Direction::Tighten, "tightening"),
            (Direction::Loosen, "loosening"),
            (Direction::Still, "holding"),
        ] {
            if directions.contains(&(d as u8)) {
                series.push(Series {
                    label: name.to_string(),
                    points: Vec::new(),
                    colour: black,
                    style: direction_style(d),
                });
            }
        }
    }
    for (kind, name, filled) in [
        (EventKind::Inversion, "inversion", true),
        (EventKind::FlipBack, "flip back", false),
    ] {
        if cases.iter().any(|c| c.events.iter().any(|(k, _)| *k == kind)) {
            series.push(Series {
                label: name.to_string(),
                points: Vec::new(),
                colour: black,
                style: Style::Dots { filled },
            });
        }
    }
    let plot = Plot {
        title: title.to_string(),
        caption: caption.to_string(),
        x_label: L_K_AXIS.to_string(),
        y_label: quantity.axis_label().to_string(),
        series,
        markers: (measured.iter())
            .map(|(l, e)| (*l, format!("measured {} ± {}", compact(*l), compact(*e))))
            .collect(),
        pad_x: false,
        ..Plot::default()
    };
    plots_svg(&[plot], (720, 480))
}

/// `quantity` at the sample of `series` nearest `l_k_bar`.
fn value_at(series: &[Sample], l_k_bar: f64, quantity: Quantity) -> Option<f64> {
    series
        .iter()
        .min_by(|a, b| {
            (a.l_k_bar - l_k_bar)
                .abs()
                .total_cmp(&(b.l_k_bar - l_k_bar).abs())
        })
        .map(|s| quantity.of(s))
}

/// The parameters a caption names: the knot, the rod and its material.
const CAPTIONED: [&str; 7] = [
    "n",
    "h",
    "mu",
    "length",
    "youngs_modulus",
    "density",
    "poisson_ratio",
];

/// What a case's figure holds fixed: n, h, μ, L, the material's E, ρ and ν,
/// and its loading program when it is not the default pull.
pub fn case_caption(params: &CaseParams) -> String {
    let json = serde_json::to_value(params).expect("params serialise");
    let mut parts: Vec<String> = CAPTIONED
        .iter()
        .map(|name| symbols::value(name, &json[*name]))
        .collect();
    if params.loading.is_some() {
        let stages: Vec<String> = params.program().iter().map(|s| s.kind().to_string()).collect();
        parts.push(format!("loading {}", stages.join(" → ")));
    }
    parts.join(", ")
}

/// What every case of a sweep shares (its base), less the varied parameters.
pub fn sweep_caption(base: &serde_json::Value, varied: &[String]) -> String {
    CAPTIONED
        .iter()
        .filter(|name| {
            !varied
                .iter()
                .any(|v| v == *name || (v == "material" && MATERIAL_CONSTANTS.contains(*name)))
        })
        .filter(|name| !base[**name].is_null())
        .map(|name| symbols::value(name, &base[*name]))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The constants a named material sets.
const MATERIAL_CONSTANTS: [&str; 3] = ["youngs_modulus", "density", "poisson_ratio"];

/// One case's F̄ or H̄ chart, its caption holding its parameters: the figure
/// of `knotsweep run --plot` and of `GET /api/cases/{id}/figures/*.svg`.
pub fn case_chart(
    params: &CaseParams,
    series: &[Sample],
    events: &[Event],
    quantity: Quantity,
) -> Result<String> {
    let curve = CaseCurve::new(String::new(), params, series, events);
    tightening_chart(
        &format!("{} against {L_K_BAR}", quantity.symbol()),
        &case_caption(params),
        quantity,
        &[curve],
        &[],
    )
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Style {
    Line,
    Dashed,
    /// Short dashes: a stage that holds or rotates.
    Dotted,
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
    /// A line under the chart: what is held fixed (empty: none).
    pub caption: String,
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
    /// The x axis counts (n): ticks at whole numbers only.
    pub integer_x: bool,
}

impl Default for Plot {
    fn default() -> Self {
        Self {
            title: String::new(),
            caption: String::new(),
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
            integer_x: false,
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

/// The size of a caption's text.
const CAPTION_FONT: u32 = 14;

/// `area` less a strip at its foot holding `caption` (the area itself when
/// the caption is empty).
fn with_caption<'a>(
    area: &DrawingArea<SVGBackend<'a>, plotters::coord::Shift>,
    caption: &str,
) -> Result<DrawingArea<SVGBackend<'a>, plotters::coord::Shift>> {
    if caption.is_empty() {
        return Ok(area.clone());
    }
    let height = area.dim_in_pixel().1 as i32;
    let (chart, foot) = area.split_vertically(height - 2 * CAPTION_FONT as i32);
    let style = ("sans-serif", CAPTION_FONT)
        .into_font()
        .color(&RGBColor(60, 60, 60));
    foot.draw_text(caption, &style, (12, 2))
        .map_err(|e| anyhow!("{e}"))?;
    Ok(chart)
}

/// How many ticks an x axis over `x` gets: whole numbers only on an
/// integer axis (at most 10, so that the step is a whole number too).
fn x_ticks(x: (f64, f64), integer: bool, labels: usize) -> usize {
    if !integer {
        return labels;
    }
    let whole = (x.1.floor() - x.0.ceil()) as i64 + 1;
    whole.clamp(1, 10) as usize
}

/// A tick label of an integer axis: whole numbers, nothing between them.
fn integer_tick(v: f64) -> String {
    if (v - v.round()).abs() < 1e-9 {
        format!("{}", v.round() as i64)
    } else {
        String::new()
    }
}

/// Draws `plot` on `area`.
fn draw(plot: &Plot, area: &DrawingArea<SVGBackend, plotters::coord::Shift>) -> Result<()> {
    let xs = plot.series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
    let ys = plot.series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
    let x = plot.x_range.unwrap_or_else(|| span(xs, plot.log, plot.pad_x));
    let y = plot.y_range.unwrap_or_else(|| span(ys, plot.log, true));
    let area = with_caption(area, &plot.caption)?;
    let mut builder = ChartBuilder::on(&area);
    builder
        .caption(&plot.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(64);
    if plot.log {
        let chart = builder
            .build_cartesian_2d((x.0..x.1).log_scale(), (y.0..y.1).log_scale())
            .map_err(|e| anyhow!("{e}"))?;
        fill(plot, chart, x, y)
    } else {
        let chart = builder
            .build_cartesian_2d(x.0..x.1, y.0..y.1)
            .map_err(|e| anyhow!("{e}"))?;
        fill(plot, chart, x, y)
    }
}

/// The mesh, series, markers and legend of `plot` on `chart`, whose ranges are `x` and `y`.
fn fill<'a, X, Y>(
    plot: &Plot,
    mut chart: ChartContext<'a, SVGBackend<'a>, Cartesian2d<X, Y>>,
    x: (f64, f64),
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
        .x_labels(x_ticks(x, plot.integer_x, labels))
        .y_labels(labels)
        .x_label_formatter(&|v| {
            if plot.integer_x {
                integer_tick(*v)
            } else {
                compact(*v)
            }
        })
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
            Style::Dotted => chart.draw_series(DashedLineSeries::new(points.clone(), 2, 4, line)),
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
                Style::Dashed | Style::Dotted => {
                    let (dash, gap) = if s.style == Style::Dashed { (7, 4) } else { (2, 3) };
                    drawn.label(&s.label).legend(move |(x, y)| {
                        let piece = |a: i32| PathElement::new(vec![(a, 0), ((a + dash).min(18), 0)], line);
                        EmptyElement::at((x, y)) + piece(0) + piece(dash + gap) + piece(2 * (dash + gap))
                    })
                }
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

/// A phase-diagram point: x, the inversion's l̄_k and, for a certified
/// point, its numerical uncertainty (l̄_k) and whether it is within the
/// convergence threshold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseMark {
    pub x: f64,
    pub l_k_bar: f64,
    pub uncertainty: Option<f64>,
    pub converged: bool,
}

/// A measured inversion drawn beside the simulations: x, l̄_k and its error bar.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    pub x: f64,
    pub l_k_bar: f64,
    pub error: f64,
}

/// One sweep's points in a phase diagram, with their legend entry.
pub struct PhaseSet<'a> {
    pub label: String,
    pub marks: &'a [PhaseMark],
}

/// A phase diagram (paper Figs 7, 9, 11, 14, 15): each sweep's critical l̄_k
/// against the varied parameter (error bars where certified, unconverged
/// points ringed red), measured points with their error bars, and the
/// simplified model's line where given.
pub struct PhaseFigure<'a> {
    pub title: String,
    /// What is held fixed.
    pub caption: String,
    pub x_label: String,
    /// The axis counts (n): ticks at whole numbers.
    pub integer_x: bool,
    pub sets: Vec<PhaseSet<'a>>,
    pub simplified: Vec<(f64, f64)>,
    pub measured: Vec<Measured>,
}

/// The phase diagram as SVG.
pub fn phase_chart(figure: &PhaseFigure) -> Result<String> {
    let marks = || figure.sets.iter().flat_map(|s| s.marks.iter());
    let points: Vec<(f64, f64)> = marks().map(|m| (m.x, m.l_k_bar)).collect();
    let bars: Vec<(f64, f64)> = marks()
        .filter_map(|m| {
            m.uncertainty
                .map(|u| [(m.x, m.l_k_bar - u), (m.x, m.l_k_bar + u)])
        })
        .flatten()
        .chain(
            figure
                .measured
                .iter()
                .flat_map(|m| [(m.x, m.l_k_bar - m.error), (m.x, m.l_k_bar + m.error)]),
        )
        .collect();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let area = with_caption(&root, &figure.caption)?;
        let all = points.iter().chain(&figure.simplified).chain(&bars);
        let (mut x0, mut x1, mut y0, mut y1) =
            (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
        for &(x, y) in all {
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
        if !x0.is_finite() {
            (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
        }
        let xp = if figure.integer_x {
            0.5
        } else {
            0.05 * (x1 - x0).max(1e-9)
        };
        let yp = 0.1 * (y1 - y0).max(1.0);
        let x = ((x0 - xp), (x1 + xp));
        let mut chart = ChartBuilder::on(&area)
            .caption(&figure.title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d(x.0..x.1, (y0 - yp).max(0.0)..(y1 + yp))
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc(&figure.x_label)
            .y_desc(format!("critical {L_K_BAR}"))
            .x_labels(x_ticks(x, figure.integer_x, 10))
            .x_label_formatter(&|v| {
                if figure.integer_x {
                    integer_tick(*v)
                } else {
                    compact(*v)
                }
            })
            .y_label_formatter(&|v| compact(*v))
            .light_line_style(WHITE)
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        for (k, set) in figure.sets.iter().enumerate() {
            let colour = Palette99::pick(if k == 0 { 0 } else { k + 1 }).to_rgba();
            let label = if set.label.is_empty() {
                "full model (inversion)".to_string()
            } else {
                set.label.clone()
            };
            chart
                .draw_series(
                    set.marks
                        .iter()
                        .map(|m| Circle::new((m.x, m.l_k_bar), 5, colour.filled())),
                )
                .map_err(|e| anyhow!("{e}"))?
                .label(label)
                .legend(move |(x, y)| Circle::new((x + 9, y), 5, colour.filled()));
        }
        if marks().any(|m| m.uncertainty.is_some()) {
            chart
                .draw_series(marks().filter_map(|m| {
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
        if marks().any(|m| !m.converged) {
            let red = RED.stroke_width(2);
            chart
                .draw_series(
                    marks()
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
        if !figure.measured.is_empty() {
            let ink = RGBColor(20, 20, 20).stroke_width(2);
            chart
                .draw_series(figure.measured.iter().map(|m| {
                    ErrorBar::new_vertical(m.x, m.l_k_bar - m.error, m.l_k_bar, m.l_k_bar + m.error, ink, 10)
                }))
                .map_err(|e| anyhow!("{e}"))?;
            chart
                .draw_series(
                    figure
                        .measured
                        .iter()
                        .map(|m| TriangleMarker::new((m.x, m.l_k_bar), 7, RGBColor(20, 20, 20).filled())),
                )
                .map_err(|e| anyhow!("{e}"))?
                .label("measured (± error)")
                .legend(|(x, y)| TriangleMarker::new((x + 9, y), 7, RGBColor(20, 20, 20).filled()));
        }
        if !figure.simplified.is_empty() {
            let red = Palette99::pick(1).to_rgba();
            chart
                .draw_series(LineSeries::new(
                    figure.simplified.iter().copied(),
                    red.stroke_width(2),
                ))
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
