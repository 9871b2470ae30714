//! `knotsweep run`: one tightening case from the command line, with a progress
//! bar; writes the JSON report, optionally the series as CSV and SVG plots.
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use knotsweep_server::figures::{CaseCurve, Quantity, tightening_chart};
use serde::Serialize;
use solver::case::CaseParams;
use solver::protocol::{self, CaseReport, Status};
use std::path::PathBuf;

/// Case parameters as flags; any flag left out takes the paper's default
/// (the defaults live in `solver::case::CaseParams`).
#[derive(clap::Args, Serialize, Default)]
pub struct ParamFlags {
    /// Number of passes n (1..8) [default 3].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    n: Option<u32>,
    /// Rod radius h (m) [default 1.6e-3].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    h: Option<f64>,
    /// Friction coefficient mu [default 0.1].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    mu: Option<f64>,
    /// Friction law: isotropic (Coulomb's disk) or sliding_direction (along the previous sliding direction only) [default isotropic].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    friction_law: Option<String>,
    /// Friction at the rods' surfaces, so rods roll on each other; false: at the centre lines [default true].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    rolling: Option<bool>,
    /// Gravity (m/s^2) as gx,gy,gz [default 0,0,0, as in the paper's simulations].
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    #[serde(skip_serializing_if = "Option::is_none")]
    gravity: Option<Vec<f64>>,
    /// Rod length L (m) [default 1].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    length: Option<f64>,
    /// Node count K [default 301].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    nodes: Option<usize>,
    /// Young's modulus E (Pa) [default 1.8e6].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    youngs_modulus: Option<f64>,
    /// Poisson's ratio [default 0.5].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    poisson_ratio: Option<f64>,
    /// Density (kg/m^3) [default 1000].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    density: Option<f64>,
    /// Pull speed of each clamp (m/s) [default 3e-3].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    pull_speed: Option<f64>,
    /// Time step (s), the largest one when adaptive [default: 5e-4 at L = 1 m, K = 301, scaled with the squared edge length].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    dt: Option<f64>,
    /// Adapt the time step to the penetration, between dt/64 and dt [default true].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    adaptive_dt: Option<bool>,
    /// Relative tolerance of each step's contact solve [default 1e-6].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    contact_tolerance: Option<f64>,
    /// Longest relaxation before pulling (s) [default 2].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    relax_time: Option<f64>,
    /// Viscous damping rate while pulling (1/s) [default 0].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    damping: Option<f64>,
    /// Initial clamp-to-clamp distance (m) [default: builder's].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    end_to_end: Option<f64>,
    /// Strand length of a braid pass (m) [default: builder's].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    braid_length: Option<f64>,
    /// Sampling interval in l_k bar [default 0.5].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    sample_interval: Option<f64>,
    /// Stop at this l_k bar [default 60].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    min_l_k_bar: Option<f64>,
    /// Stop this far (in l_k bar) past the inversion [default 10].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    stop_after_inversion: Option<f64>,
    /// Stop when F bar exceeds this [default: never].
    #[arg(long)]
    #[serde(skip_serializing_if = "Option::is_none")]
    max_force_bar: Option<f64>,
    /// Start from this knot instead of the builder's: a text file of K = nodes
    /// points `x y z` (m), one per line, comma or whitespace separated, extra
    /// columns ignored, `#` comments [default: the builder's knot].
    #[arg(long)]
    #[serde(skip)]
    initial_shape: Option<PathBuf>,
}

impl ParamFlags {
    /// The case parameters: the given flags over the paper's defaults.
    pub fn params(&self) -> Result<CaseParams> {
        let value = serde_json::to_value(self)?;
        let mut params: CaseParams = serde_json::from_value(value)?;
        if let Some(path) = &self.initial_shape {
            let text =
                std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
            params.initial_shape =
                Some(read_points(&text).with_context(|| format!("--initial-shape {}", path.display()))?);
        }
        Ok(params)
    }
}

/// Points `x y z` from text: one per line, comma or whitespace separated,
/// extra columns ignored, blank lines and `#` comments skipped.
fn read_points(text: &str) -> Result<Vec<[f64; 3]>> {
    let mut points = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let values: Vec<&str> = line
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|v| !v.is_empty())
            .collect();
        if values.len() < 3 {
            anyhow::bail!("line {}: {} values, need x y z", k + 1, values.len());
        }
        let mut p = [0.0; 3];
        for (c, v) in p.iter_mut().zip(&values) {
            *c = v
                .parse()
                .with_context(|| format!("line {}: {v:?} is not a number", k + 1))?;
        }
        points.push(p);
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::read_points;

    #[test]
    fn points_in_any_separator_with_extra_columns() {
        let text = "# x y z w\n0 0 0 9\n1.5,2,-3\n\n4\t5 6, 7\n";
        assert_eq!(
            read_points(text).unwrap(),
            vec![[0.0, 0.0, 0.0], [1.5, 2.0, -3.0], [4.0, 5.0, 6.0]]
        );
        let err = read_points("1 2\n").unwrap_err().to_string();
        assert!(err.contains("line 1"), "{err}");
        assert!(read_points("1 2 x\n").is_err());
    }
}

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    params: ParamFlags,
    /// Write the JSON report here.
    #[arg(long, default_value = "case.json")]
    out: PathBuf,
    /// Write the series as CSV here.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Write SVG plots of F bar and H bar against l_k bar (paper Fig. 5 a, b) into this directory.
    #[arg(long)]
    plot: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    let params = args.params.params()?;
    if let Err(errors) = params.validate() {
        let text: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
        anyhow::bail!("invalid parameters: {}", text.join("; "));
    }
    tracing::info!(n = params.n, h = params.h, mu = params.mu, "running case");
    let bar = ProgressBar::new(1000).with_style(
        ProgressStyle::with_template("{bar:40} {percent:>3}% {elapsed_precise} eta {eta} {msg}")
            .expect("valid template"),
    );
    let report = protocol::run(&params, &mut |p| {
        bar.set_position((p.fraction * 1000.0) as u64);
        bar.set_message(format!("l_k bar {:.1}  H bar {:.2}", p.l_k_bar, p.h_bar));
        true
    });
    bar.finish_and_clear();
    summarise(&report);
    std::fs::write(&args.out, serde_json::to_string(&report)?)
        .with_context(|| format!("writing {}", args.out.display()))?;
    if let Some(path) = &args.csv {
        std::fs::write(path, solver::measurements::series_csv(&report.series))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(dir) = &args.plot {
        write_plots(&report, dir)?;
    }
    if report.status != Status::Completed {
        anyhow::bail!("case ended with status {}: {}", report.status, report.reason);
    }
    Ok(())
}

/// F bar and H bar against l_k bar, with the inversion marked.
fn write_plots(report: &CaseReport, dir: &std::path::Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let p = &report.params;
    let label = format!("n = {}, h = {} mm, mu = {}", p.n, p.h * 1e3, p.mu);
    let case = [CaseCurve {
        label: label.clone(),
        series: &report.series,
        inversion: report.inversion.map(|i| i.l_k_bar),
    }];
    for (file, quantity) in [("F_bar.svg", Quantity::FBar), ("H_bar.svg", Quantity::HBar)] {
        let svg = tightening_chart(&label, quantity, &case)?;
        let path = dir.join(file);
        std::fs::write(&path, svg).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

fn summarise(report: &CaseReport) {
    println!("status: {} {}", report.status, report.reason);
    match &report.inversion {
        Some(inv) => println!(
            "inversion at l_k bar {:.2} (l_c/L {:.4}), F bar {:.4} -> {:.4}",
            inv.l_k_bar, inv.l_c_over_l, inv.f_bar_before, inv.f_bar_after
        ),
        None => println!("no inversion"),
    }
    let s = &report.stats;
    println!(
        "{} steps ({} relaxing), {} Newton iterations, {} contact sweeps, {:.1} s wall (detection {:.1} s, contact {:.1} s, rods {:.1} s)",
        s.steps,
        s.relax_steps,
        s.newton_iterations,
        s.contact_sweeps,
        s.wall_time,
        s.detection_time,
        s.contact_time,
        s.dynamics_time
    );
}
