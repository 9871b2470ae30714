//! `knotsweep snapshots`: side views of the knot at given l_c / L, framed as
//! the paper's Fig. 1 (the pull horizontal, the rod drawn with its true
//! radius), so a run can be compared with the paper's photographs by eye.
use anyhow::{Context, Result, anyhow, bail};
use nalgebra::Vector3;
use plotters::prelude::*;
use solver::case::CaseParams;
use solver::protocol::{self, Status};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    params: crate::run::ParamFlags,
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
    if let Err(errors) = params.validate() {
        let text: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
        bail!("invalid parameters: {}", text.join("; "));
    }
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
    let mut shots: Vec<Snapshot> = Vec::new();
    let report = protocol::run_observed(&stopped, &mut |p, points| {
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
        let svg = side_view(&shot.points, &params, &title)?;
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

/// The knot seen along the direction in which it is thinnest (the loop
/// faces the viewer, as in the paper's photographs), the pull axis x
/// horizontal, framed on the knot; the stroke is 2h wide.
fn side_view(points: &[Vector3<f64>], params: &CaseParams, title: &str) -> Result<String> {
    let centre = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    // The in-plane vertical axis: the direction across x in which the knot spreads most.
    let (mut syy, mut syz, mut szz) = (0.0, 0.0, 0.0);
    for p in points {
        let d = p - centre;
        syy += d.y * d.y;
        syz += d.y * d.z;
        szz += d.z * d.z;
    }
    let angle = 0.5 * (2.0 * syz).atan2(syy - szz);
    let up = Vector3::new(0.0, angle.cos(), angle.sin());
    // Frame the knot: the nodes off the pull axis by more than 3h (the tails
    // lie on it), with a margin of a fifth of their extent.
    let (first, last) = (points[0], points[points.len() - 1]);
    let axis = (last - first).normalize();
    let off_axis = |p: &Vector3<f64>| {
        let d = p - first;
        (d - axis * d.dot(&axis)).norm() > 3.0 * params.h
    };
    let (lo, hi) = points
        .iter()
        .filter(|p| off_axis(p))
        .map(|p| (p - centre).x)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    let centre = if lo.is_finite() {
        centre + Vector3::x() * (0.5 * (lo + hi))
    } else {
        centre
    };
    let half_width = if lo.is_finite() { 0.6 * (hi - lo) } else { 0.06 }.max(20.0 * params.h);
    let (width_px, height_px) = (900u32, 540u32);
    let half_height = half_width * f64::from(height_px) / f64::from(width_px);
    let scale = f64::from(width_px) / (2.0 * half_width);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width_px, height_px + 40)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let (top, body) = root.split_vertically(40);
        top.titled(title, ("sans-serif", 20))
            .map_err(|e| anyhow!("{e}"))?;
        let to_px = |p: &Vector3<f64>| {
            let d = p - centre;
            let x = (d.x + half_width) * scale;
            let y = (half_height - d.dot(&up)) * scale;
            (x.round() as i32, y.round() as i32)
        };
        let stroke = ((2.0 * params.h * scale).round() as u32).max(1);
        let path: Vec<(i32, i32)> = points.iter().map(to_px).collect();
        body.draw(&PathElement::new(path.clone(), BLACK.stroke_width(stroke + 2)))
            .map_err(|e| anyhow!("{e}"))?;
        body.draw(&PathElement::new(
            path,
            RGBColor(220, 120, 40).stroke_width(stroke),
        ))
        .map_err(|e| anyhow!("{e}"))?;
        let bar = (0.01 * scale).round() as i32;
        let y = height_px as i32 - 20;
        body.draw(&PathElement::new(
            vec![(20, y), (20 + bar, y)],
            BLACK.stroke_width(2),
        ))
        .map_err(|e| anyhow!("{e}"))?;
        body.draw(&Text::new("1 cm", (20, y - 18), ("sans-serif", 14)))
            .map_err(|e| anyhow!("{e}"))?;
    }
    Ok(svg)
}
