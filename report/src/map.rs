//! A sweep over two axes as a map (`GET /api/sweeps/{id}/figures/map.svg`):
//! each grid point's cell coloured by its critical l̄_k, contours of l̄_k
//! between the points, and the points without an inversion crossed; with a
//! refinement, the cases it added and where the outcome changes.
use crate::charts::compact;
use crate::symbols::L_K_BAR;
use anyhow::{Result, anyhow};
use plotters::prelude::*;

/// A grid point of the map: its two coordinates and its inversion's l̄_k
/// (none without one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapPoint {
    pub x: f64,
    pub y: f64,
    pub l_k_bar: Option<f64>,
}

/// A change of outcome on a refined grid line: the two cases bracketing it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapBracket {
    pub ends: [(f64, f64); 2],
    /// The ends are within the refinement's tolerance.
    pub settled: bool,
}

/// A map: the points of a grid over two axes, with titles.
pub struct MapFigure {
    pub title: String,
    /// What is held fixed.
    pub caption: String,
    pub x_label: String,
    pub y_label: String,
    pub points: Vec<MapPoint>,
    /// Cases a refinement added between the grid's points.
    pub refined: Vec<MapPoint>,
    /// Where the outcome changes along refined lines.
    pub brackets: Vec<MapBracket>,
}

/// The colour of `t` in 0..1: a perceptually ordered ramp (viridis' ends
/// and middle), dark blue to yellow.
fn ramp(t: f64) -> RGBColor {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (0.0, [68.0, 1.0, 84.0]),
        (0.25, [59.0, 82.0, 139.0]),
        (0.5, [33.0, 145.0, 140.0]),
        (0.75, [94.0, 201.0, 98.0]),
        (1.0, [253.0, 231.0, 37.0]),
    ];
    let t = t.clamp(0.0, 1.0);
    let k = STOPS
        .iter()
        .rposition(|(s, _)| *s <= t)
        .unwrap_or(0)
        .min(STOPS.len() - 2);
    let ((s0, a), (s1, b)) = (STOPS[k], STOPS[k + 1]);
    let f = (t - s0) / (s1 - s0);
    let mix = |i: usize| (a[i] + f * (b[i] - a[i])).round() as u8;
    RGBColor(mix(0), mix(1), mix(2))
}

/// The sorted distinct values of `values`.
fn distinct(values: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut v: Vec<f64> = values.collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    v
}

/// The cell edges of sorted grid values: midpoints between neighbours, the
/// ends half a step out (a step of 1 for a lone value).
fn edges(values: &[f64]) -> Vec<f64> {
    let step = |i: usize| match values.len() {
        1 => 1.0,
        _ if i == 0 => values[1] - values[0],
        _ => values[i] - values[i - 1],
    };
    let mut e = vec![values[0] - step(0) / 2.0];
    e.extend(values.windows(2).map(|w| (w[0] + w[1]) / 2.0));
    e.push(values[values.len() - 1] + step(values.len() - 1) / 2.0);
    e
}

/// Contour segments of `level` over a grid of values (`None`: no inversion;
/// squares with one are skipped), by marching squares with linear
/// interpolation along the square's edges.
pub fn contour(
    xs: &[f64],
    ys: &[f64],
    value: &dyn Fn(usize, usize) -> Option<f64>,
    level: f64,
) -> Vec<[(f64, f64); 2]> {
    let mut segments = Vec::new();
    for i in 0..xs.len().saturating_sub(1) {
        for j in 0..ys.len().saturating_sub(1) {
            let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let Some(v) = corners
                .iter()
                .map(|&(a, b)| value(a, b))
                .collect::<Option<Vec<f64>>>()
            else {
                continue;
            };
            // Where the level crosses each edge of the square (corner k to k + 1).
            let crossings: Vec<(f64, f64)> = (0..4)
                .filter_map(|k| {
                    let (a, b) = (v[k], v[(k + 1) % 4]);
                    if (a < level) == (b < level) {
                        return None;
                    }
                    let t = (level - a) / (b - a);
                    let (p, q) = (corners[k], corners[(k + 1) % 4]);
                    Some((
                        xs[p.0] + t * (xs[q.0] - xs[p.0]),
                        ys[p.1] + t * (ys[q.1] - ys[p.1]),
                    ))
                })
                .collect();
            match crossings.len() {
                2 => segments.push([crossings[0], crossings[1]]),
                // A saddle: pair the crossings by the square's mean.
                4 => {
                    let mean = v.iter().sum::<f64>() / 4.0;
                    if (mean < level) == (v[0] < level) {
                        segments.push([crossings[0], crossings[3]]);
                        segments.push([crossings[1], crossings[2]]);
                    } else {
                        segments.push([crossings[0], crossings[1]]);
                        segments.push([crossings[2], crossings[3]]);
                    }
                }
                _ => {}
            }
        }
    }
    segments
}

/// Height of the legend's strip under the map, in pixels.
const LEGEND_HEIGHT: i32 = 52;

/// The colour of a bracket (where a refined line's outcome changes).
const RED_BRACKET: RGBColor = RGBColor(213, 34, 34);

/// The legend under the map, two entries a row: a glyph and its words, for
/// each kind of mark the map has.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    figure: &MapFigure,
) -> Result<()> {
    let grey = RGBColor(200, 200, 200);
    let mut entries: Vec<(usize, String)> = vec![(
        0,
        format!("a grid point (its cell: its critical {L_K_BAR}; white: contours)"),
    )];
    if figure.points.iter().any(|p| p.l_k_bar.is_none()) {
        entries.push((1, "no inversion (grey)".to_string()));
    }
    if !figure.refined.is_empty() {
        entries.push((
            2,
            format!("a case of the refinement (its critical {L_K_BAR}'s colour; grey: none)"),
        ));
    }
    if !figure.brackets.is_empty() {
        entries.push((3, "the outcome changes between these cases".to_string()));
    }
    let style = ("sans-serif", 13).into_font().color(&BLACK);
    let e = |r: std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>>| r.map_err(|e| anyhow!("{e}"));
    for (k, (glyph, text)) in entries.iter().enumerate() {
        let (x, y) = (16 + 372 * (k as i32 % 2), 12 + 22 * (k as i32 / 2));
        match glyph {
            0 => e(area.draw(&Circle::new((x + 9, y), 3, BLACK.filled())))?,
            1 => e(area.draw(&Cross::new((x + 9, y), 6, BLACK.stroke_width(2))))?,
            2 => {
                e(area.draw(&Circle::new((x + 9, y), 4, grey.filled())))?;
                e(area.draw(&Circle::new((x + 9, y), 4, BLACK.stroke_width(1))))?;
            }
            _ => e(area.draw(&PathElement::new(
                vec![(x, y), (x + 18, y)],
                RED_BRACKET.stroke_width(4),
            )))?,
        }
        e(area.draw_text(text, &style, (x + 26, y - 7)))?;
    }
    Ok(())
}

/// The map as SVG: cells coloured by l̄_k (a colour bar beside), contours at
/// round levels, grid points as dots, points without an inversion crossed.
pub fn map_chart(figure: &MapFigure) -> Result<String> {
    let xs = distinct(figure.points.iter().map(|p| p.x));
    let ys = distinct(figure.points.iter().map(|p| p.y));
    if xs.is_empty() || ys.is_empty() {
        return Err(anyhow!("a map needs points"));
    }
    let at = |i: usize, j: usize| {
        figure
            .points
            .iter()
            .find(|p| p.x == xs[i] && p.y == ys[j])
            .and_then(|p| p.l_k_bar)
    };
    let values: Vec<f64> = figure.points.iter().filter_map(|p| p.l_k_bar).collect();
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    let span = if hi > lo { hi - lo } else { 1.0 };
    let t = |v: f64| (v - lo) / span;
    let (ex, ey) = (edges(&xs), edges(&ys));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (760, 580)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let height = root.dim_in_pixel().1 as i32;
        let (area, below) = root.split_vertically(height - 28 - LEGEND_HEIGHT);
        let (legend, foot) = below.split_vertically(LEGEND_HEIGHT);
        draw_legend(&legend, figure)?;
        if !figure.caption.is_empty() {
            let style = ("sans-serif", 14).into_font().color(&RGBColor(60, 60, 60));
            foot.draw_text(&figure.caption, &style, (12, 2))
                .map_err(|e| anyhow!("{e}"))?;
        }
        let (plot, bar) = area.split_horizontally(640);
        let mut chart = ChartBuilder::on(&plot)
            .caption(&figure.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d(ex[0]..ex[ex.len() - 1], ey[0]..ey[ey.len() - 1])
            .map_err(|e| anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 15))
            .x_desc(&figure.x_label)
            .y_desc(&figure.y_label)
            .x_label_formatter(&|v| compact(*v))
            .y_label_formatter(&|v| compact(*v))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        let grey = RGBColor(200, 200, 200);
        chart
            .draw_series(
                (0..xs.len())
                    .flat_map(|i| (0..ys.len()).map(move |j| (i, j)))
                    .map(|(i, j)| {
                        let fill = at(i, j).map_or(grey, |v| ramp(t(v)));
                        Rectangle::new([(ex[i], ey[j]), (ex[i + 1], ey[j + 1])], fill.filled())
                    }),
            )
            .map_err(|e| anyhow!("{e}"))?;
        // Contours at round levels inside the data's range.
        let step = [1.0, 2.0, 5.0, 10.0, 20.0, 50.0]
            .into_iter()
            .find(|s| span / s <= 6.0)
            .unwrap_or(100.0);
        let mut level = (lo / step).ceil() * step;
        while level <= hi && values.len() > 1 {
            let segments = contour(&xs, &ys, &at, level);
            chart
                .draw_series(
                    segments
                        .iter()
                        .map(|[a, b]| PathElement::new(vec![*a, *b], WHITE.stroke_width(2))),
                )
                .map_err(|e| anyhow!("{e}"))?;
            if let Some([a, b]) = segments.get(segments.len() / 2) {
                let mid = ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0);
                chart
                    .draw_series([Text::new(
                        compact(level),
                        mid,
                        ("sans-serif", 13).into_font().color(&WHITE),
                    )])
                    .map_err(|e| anyhow!("{e}"))?;
            }
            level += step;
        }
        chart
            .draw_series(
                figure
                    .points
                    .iter()
                    .filter(|p| p.l_k_bar.is_some())
                    .map(|p| Circle::new((p.x, p.y), 3, BLACK.filled())),
            )
            .map_err(|e| anyhow!("{e}"))?;
        if figure.points.iter().any(|p| p.l_k_bar.is_none()) {
            chart
                .draw_series(
                    figure
                        .points
                        .iter()
                        .filter(|p| p.l_k_bar.is_none())
                        .map(|p| Cross::new((p.x, p.y), 6, BLACK.stroke_width(2))),
                )
                .map_err(|e| anyhow!("{e}"))?;
        }
        if !figure.refined.is_empty() {
            chart
                .draw_series(figure.refined.iter().map(|p| {
                    let fill = p.l_k_bar.map_or(grey, |v| ramp(t(v)));
                    EmptyElement::at((p.x, p.y))
                        + Circle::new((0, 0), 4, fill.filled())
                        + Circle::new((0, 0), 4, BLACK.stroke_width(1))
                }))
                .map_err(|e| anyhow!("{e}"))?;
        }
        if !figure.brackets.is_empty() {
            chart
                .draw_series((figure.brackets.iter()).map(|b| {
                    PathElement::new(
                        b.ends.to_vec(),
                        RED_BRACKET.stroke_width(if b.settled { 4 } else { 2 }),
                    )
                }))
                .map_err(|e| anyhow!("{e}"))?;
        }
        // The colour bar.
        let mut scale = ChartBuilder::on(&bar)
            .margin_top(44)
            .margin_bottom(60)
            .margin_right(48)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..1.0, lo..lo + span)
            .map_err(|e| anyhow!("{e}"))?;
        scale
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 15))
            .y_desc(format!("critical {L_K_BAR}"))
            .y_label_formatter(&|v| compact(*v))
            .draw()
            .map_err(|e| anyhow!("{e}"))?;
        let bands = 64;
        scale
            .draw_series((0..bands).map(|k| {
                let (a, b) = (k as f64 / bands as f64, (k + 1) as f64 / bands as f64);
                Rectangle::new(
                    [(0.0, lo + a * span), (1.0, lo + b * span)],
                    ramp((a + b) / 2.0).filled(),
                )
            }))
            .map_err(|e| anyhow!("{e}"))?;
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contours_of_a_plane_are_its_level_lines() {
        // v = 10 x + 20 y on a 3 x 3 grid: the level 25 is the line y = (25 - 10 x) / 20.
        let (xs, ys) = ([0.0, 1.0, 2.0], [0.0, 1.0, 2.0]);
        let value = |i: usize, j: usize| Some(10.0 * xs[i] + 20.0 * ys[j]);
        let segments = contour(&xs, &ys, &value, 25.0);
        assert!(!segments.is_empty());
        for [a, b] in segments {
            for (x, y) in [a, b] {
                assert!((10.0 * x + 20.0 * y - 25.0).abs() < 1e-9, "({x}, {y})");
            }
        }
        // A square with a point without an inversion has no contour.
        let holed = |i: usize, j: usize| ((i, j) != (1, 1)).then(|| 10.0 * xs[i] + 20.0 * ys[j]);
        assert!(contour(&xs, &ys, &holed, 25.0).is_empty());
    }

    #[test]
    fn a_map_has_a_cell_per_point_and_crosses_the_points_without_inversion() {
        let points: Vec<MapPoint> = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| MapPoint {
                x: 1.6 + 0.4 * i as f64,
                y: 0.1 * (j + 1) as f64,
                l_k_bar: (i + j < 4).then_some(100.0 + 10.0 * i as f64 + 20.0 * j as f64),
            })
            .collect();
        let svg = map_chart(&MapFigure {
            title: "map".into(),
            caption: "held fixed: n = 3".into(),
            x_label: "h (mm)".into(),
            y_label: "μ".into(),
            points,
            refined: vec![MapPoint {
                x: 2.2,
                y: 0.25,
                l_k_bar: None,
            }],
            brackets: vec![MapBracket {
                ends: [(2.0, 0.25), (2.4, 0.25)],
                settled: true,
            }],
        })
        .unwrap();
        assert!(svg.contains("no inversion (grey)") && svg.contains("held fixed: n = 3"));
        assert!(
            svg.contains("the outcome changes between these cases"),
            "the bracket's legend"
        );
        // Nine cells: eight coloured and one grey, the refined case without an inversion and the
        // legend's ring (besides the colour bar's bands).
        assert_eq!(
            svg.matches("fill=\"#C8C8C8\"").count(),
            3,
            "the grey cell, point and ring"
        );
    }

    #[test]
    fn cell_edges_are_midpoints() {
        assert_eq!(edges(&[1.0, 2.0, 4.0]), vec![0.5, 1.5, 3.0, 5.0]);
        assert_eq!(edges(&[3.0]), vec![2.5, 3.5]);
    }
}
