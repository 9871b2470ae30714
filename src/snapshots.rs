//! `knotsweep snapshots`: side views of the knot at given l_c / L, framed as
//! the paper's Fig. 1 (the pull horizontal, the rod drawn with its true
//! radius), so a run can be compared with the paper's photographs by eye.
use anyhow::{Context, Result, bail};
use nalgebra::Vector3;
use solver::protocol::{self, Status};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub(crate) params: crate::run::ParamFlags,
    /// Clamp-to-clamp distances l_c / L at which to draw the knot, ascending
    /// (the first sample at or past each is drawn).
    #[arg(long, value_delimiter = ',', required = true)]
    at: Vec<f64>,
    /// Directory for the SVG files (`n<N>_lc<l_c/L>.svg`).
    #[arg(long, default_value = "snapshots")]
    out: PathBuf,
}

/// One captured shape.
struct Snapshot {
    target: f64,
    l_c_over_l: f64,
    l_k_bar: f64,
    points: Vec<Vector3<f64>>,
}

pub fn run(args: Args) -> Result<()> {
    let params = args.params.params()?;
    let mut targets = args.at.clone();
    if targets.iter().any(|t| !(t.is_finite() && *t > 0.0 && *t < 1.0)) {
        bail!("--at: each l_c / L must be in (0, 1), got {:?}", args.at);
    }
    targets.sort_by(f64::total_cmp);
    // Stop one sample past the last view (the run completes, so its
    // inversion is reported).
    let mut stopped = params.clone();
    stopped.stop_after_inversion = None;
    let last_l_k_bar = (1.0 - targets[targets.len() - 1]) * params.length / params.h;
    stopped.min_l_k_bar = stopped.min_l_k_bar.min(last_l_k_bar - params.sample_interval);
    let case = crate::run::validated(&stopped)?;
    let mut shots: Vec<Snapshot> = Vec::new();
    let report = protocol::run_observed(&case, &mut |p, points| {
        if p.steps == 0 {
            return true; // the relaxation: no view is taken before the pull
        }
        let l_c_over_l = 1.0 - p.l_k_bar * params.h / params.length;
        while shots.len() < targets.len() && l_c_over_l >= targets[shots.len()] {
            shots.push(Snapshot {
                target: targets[shots.len()],
                l_c_over_l,
                l_k_bar: p.l_k_bar,
                points: points.to_vec(),
            });
        }
        true
    });
    if report.status != Status::Completed {
        bail!("case ended with status {}: {}", report.status, report.reason);
    }
    if shots.len() < targets.len() {
        bail!(
            "the pull stopped at l_k bar {:.1} before l_c / L reached {}",
            report.series.last().map_or(f64::NAN, |s| s.l_k_bar),
            targets[shots.len()]
        );
    }
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let inverted_at = report.inversion.map(|i| i.l_c_over_l);
    for shot in &shots {
        let state = match inverted_at {
            Some(at) if shot.l_c_over_l > at => "after the inversion",
            _ => "before the inversion",
        };
        let title = format!(
            "n = {}, l_c/L = {:.3} (l_k bar {:.1}), {state}",
            params.n, shot.l_c_over_l, shot.l_k_bar
        );
        let svg = report::snapshot::side_view(&shot.points, params.h, &title)?;
        let path = args.out.join(format!("n{}_lc{}.svg", params.n, shot.target));
        std::fs::write(&path, svg).with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    match report.inversion {
        Some(i) => println!(
            "inversion at l_c/L {:.3} (l_k bar {:.1})",
            i.l_c_over_l, i.l_k_bar
        ),
        None => println!("no inversion before the last view"),
    }
    Ok(())
}
