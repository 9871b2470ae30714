//! The fisherman's knot's regimes (docs/FIDELITY.md, "The fisherman's
//! knot"): from the reports of `knotsweep run --knot fisherman --out
//! FILE.json`, F bar and the two overhand knots' separation against l_k bar,
//! each sample in its regime read from the run's own measurements (Tong et
//! al.'s sliding and stretching): **setting** while the tails are held,
//! **sliding** once they are free while the overhands slide towards each
//! other, **stretching** from the first sample with the tails free from
//! which their separation falls by less than [`SLACK`] h more before an
//! overhand comes loose or the run ends (they have met and jammed: the pull
//! no longer brings them together), and **loose** once an overhand has no
//! two strands touching (its tail slips out of it: the knot fails). The
//! figure as SVG, and a markdown table of each regime's span in l_k bar,
//! F bar and separation.
use anyhow::{Context, Result, ensure};
use plotters::style::{Color, RGBColor};
use report::charts::{LegendAt, Plot, Series, Style, plots_svg};
use solver::protocol::{BendSample, CaseReport};
use std::fmt::Write as _;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// A fisherman's knot's report (`knotsweep run --knot fisherman --out FILE`); several: one curve each.
    #[arg(long = "report", required = true)]
    reports: Vec<PathBuf>,
    /// Write the figure (F bar and the overhands' separation against l_k bar) as SVG here.
    #[arg(long)]
    svg: Option<PathBuf>,
}

/// The overhands have jammed once their separation is to fall by less than
/// this (h) for the rest of the run.
const SLACK: f64 = 2.0;

/// A sample's regime.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Regime {
    Setting,
    Sliding,
    Stretching,
    Loose,
}

impl Regime {
    const ALL: [Self; 4] = [Self::Setting, Self::Sliding, Self::Stretching, Self::Loose];

    fn name(self) -> &'static str {
        match self {
            Self::Setting => "setting (tails held)",
            Self::Sliding => "sliding",
            Self::Stretching => "stretching (overhands jammed)",
            Self::Loose => "an overhand loose",
        }
    }

    fn style(self) -> Style {
        match self {
            Self::Setting => Style::Dotted,
            Self::Sliding => Style::Dashed,
            Self::Stretching => Style::Line,
            Self::Loose => Style::Dots { filled: false },
        }
    }
}

/// One run: its mu and, per sample, (l_k bar, F bar, separation, regime).
struct Run {
    mu: f64,
    samples: Vec<(f64, f64, f64, Regime)>,
    tied: Option<bool>,
    holding: Option<f64>,
}

impl Run {
    fn read(path: &PathBuf) -> Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
        let report: CaseReport =
            serde_json::from_str(&text).with_context(|| format!("{}", path.display()))?;
        ensure!(
            report.params.knot_label() == "fisherman",
            "{}: knot {}, not the fisherman's",
            path.display(),
            report.params.knot_label()
        );
        let measured: Vec<(f64, f64, Option<f64>, bool)> = (report.series.iter().zip(&report.bend_series))
            .map(|(s, b): (_, &BendSample)| (s.l_k_bar, s.f_bar, b.knots_apart_bar, b.tails_free))
            .collect();
        // The least separation from each sample on, until an overhand comes loose.
        let mut least = vec![f64::INFINITY; measured.len() + 1];
        for i in (0..measured.len()).rev() {
            least[i] = measured[i].2.map_or(f64::INFINITY, |a| a.min(least[i + 1]));
        }
        let stalls = |i: usize| measured[i].2.is_some_and(|a| a - least[i] < SLACK);
        let (mut jammed, mut loose) = (false, false);
        let samples = (0..measured.len())
            .map(|i| {
                let (l, f, apart, free) = measured[i];
                loose |= free && apart.is_none();
                jammed |= free && stalls(i);
                let regime = match (free, loose, jammed) {
                    (false, ..) => Regime::Setting,
                    (true, true, _) => Regime::Loose,
                    (true, false, false) => Regime::Sliding,
                    (true, false, true) => Regime::Stretching,
                };
                (l, f, apart.unwrap_or(f64::NAN), regime)
            })
            .collect();
        Ok(Self {
            mu: report.params.mu,
            samples,
            tied: report.tied,
            holding: report.holding_force_bar,
        })
    }

    fn of(&self, regime: Regime) -> impl Iterator<Item = &(f64, f64, f64, Regime)> {
        self.samples.iter().filter(move |s| s.3 == regime)
    }
}

/// Reads the reports, writes the figure if asked, and returns the table.
pub fn run(args: Args) -> Result<String> {
    let runs = args.reports.iter().map(Run::read).collect::<Result<Vec<_>>>()?;
    if let Some(path) = &args.svg {
        std::fs::write(path, figure(&runs)?).with_context(|| format!("{}", path.display()))?;
    }
    table(&runs)
}

/// Each regime's span per run: l_k bar from and to, F bar from and to (and
/// its largest), the separation from and to.
fn table(runs: &[Run]) -> Result<String> {
    let mut doc = String::new();
    writeln!(
        doc,
        "| mu | regime | samples | l_k bar | F bar | largest F bar | separation (h) |\n|---|---|---|---|---|---|---|"
    )?;
    for run in runs {
        for regime in Regime::ALL {
            let s: Vec<_> = run.of(regime).collect();
            let (Some(first), Some(last)) = (s.first(), s.last()) else {
                writeln!(doc, "| {} | {} | 0 | | | | |", run.mu, regime.name())?;
                continue;
            };
            let largest = s.iter().map(|x| x.1).fold(f64::NEG_INFINITY, f64::max);
            writeln!(
                doc,
                "| {} | {} | {} | {:.1} -> {:.1} | {:.5} -> {:.5} | {:.5} | {:.1} -> {:.1} |",
                run.mu,
                regime.name(),
                s.len(),
                first.0,
                last.0,
                first.1,
                last.1,
                largest,
                first.2,
                last.2
            )?;
        }
        writeln!(
            doc,
            "| {} | outcome | | | | holding {} | {} |",
            run.mu,
            run.holding.map_or("-".to_string(), |f| format!("{f:.5}")),
            match run.tied {
                Some(true) => "tied",
                Some(false) => "slipped through",
                None => "-",
            }
        )?;
    }
    Ok(doc)
}

/// F bar (left) and the overhands' separation (right) against l_k bar, a
/// colour per run, a line style per regime, the jam marked.
fn figure(runs: &[Run]) -> Result<String> {
    const COLOURS: [RGBColor; 3] = [RGBColor(0, 114, 178), RGBColor(213, 94, 0), RGBColor(0, 158, 115)];
    let mut force = Vec::new();
    let mut apart = Vec::new();
    let mut markers = Vec::new();
    for (i, run) in runs.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()].to_rgba();
        for regime in Regime::ALL {
            // Each regime's curve joins the previous one's last sample.
            let start = run.samples.iter().position(|s| s.3 == regime);
            let Some(start) = start else { continue };
            let from = start.saturating_sub(1);
            let end = run.samples.iter().rposition(|s| s.3 == regime).unwrap_or(start);
            let part = &run.samples[from..=end];
            let label = format!("mu = {}, {}", run.mu, regime.name());
            force.push(Series {
                label: label.clone(),
                points: part.iter().map(|s| (s.0, s.1)).collect(),
                colour,
                style: regime.style(),
            });
            apart.push(Series {
                label: String::new(),
                points: part
                    .iter()
                    .map(|s| (s.0, s.2))
                    .filter(|p| p.1.is_finite())
                    .collect(),
                colour,
                style: regime.style(),
            });
        }
        for (regime, what) in [(Regime::Stretching, "jam"), (Regime::Loose, "loose")] {
            let Some(at) = run.of(regime).next() else { continue };
            // One label for marks that fall together.
            match markers
                .iter_mut()
                .find(|m: &&mut (f64, String)| (m.0 - at.0).abs() < 10.0)
            {
                Some(m) => write!(m.1, ", {}", run.mu)?,
                None => markers.push((at.0, format!("{what} {}", run.mu))),
            }
        }
    }
    let largest = (runs.iter().flat_map(|r| r.samples.iter().map(|s| s.1))).fold(0.0, f64::max);
    let left = Plot {
        title: "The fisherman's knot: force".into(),
        caption: "Pulled from right to left; dotted: tails held, dashed: sliding, solid: stretching, circles: loose"
            .into(),
        x_label: "l_k bar = (2L - the clamps' distance) / h".into(),
        y_label: "F bar".into(),
        // Headroom above the curves for the legend, which sits under the marks' labels.
        y_range: Some((-0.002, 2.2 * largest)),
        series: force,
        markers: markers.clone(),
        legend: LegendAt::Coordinate(12, 40),
        ..Plot::default()
    };
    let right = Plot {
        title: "The overhands' separation".into(),
        caption: "Between the two overhand knots' centroids along the pull; marks: where they jam, where one comes loose"
            .into(),
        x_label: "l_k bar".into(),
        y_label: "separation / h".into(),
        series: apart,
        markers,
        legend: LegendAt::UpperLeft,
        ..Plot::default()
    };
    plots_svg(&[left, right], (640, 480))
}
