//! `knotsweep simplified`: the simplified knot model of paper Sec. 5 — the
//! energy landscape E bar(theta), the bifurcation diagram, and the document
//! `docs/SIMPLIFIED_MODEL.md` with its figures.
use anyhow::{Context, Result};
use report::simplified_doc::SimplifiedDocument;
use solver::simplified::{self, BifurcationSpec, LandscapeSpec, Params, ReproductionSpec};
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Subcommand)]
enum Command {
    /// E bar(theta), dE/dtheta and the critical points at one l_k bar (paper Fig. 13 a, b).
    Landscape(LandscapeArgs),
    /// Critical points theta* against l_k bar, the folds and the snap (paper Fig. 13 c).
    Bifurcation(BifurcationArgs),
    /// Regenerate docs/SIMPLIFIED_MODEL.md and its SVG figures.
    Doc(DocArgs),
}

#[derive(clap::Args)]
struct ModelArgs {
    /// Unknotting number n.
    #[arg(long, default_value_t = 3)]
    n: u32,
    /// epsilon = l_b / l_l.
    #[arg(long, default_value_t = 0.7)]
    epsilon: f64,
    /// Tilt phi of the loop's end tangents (rad) [default pi/3].
    #[arg(long)]
    phi: Option<f64>,
    /// Rod radius h (m).
    #[arg(long, default_value_t = 1.6e-3)]
    h: f64,
    /// Nodes of the DER loop.
    #[arg(long, default_value_t = 81)]
    loop_nodes: usize,
}

impl ModelArgs {
    fn params(&self) -> Params {
        let d = Params::default();
        Params {
            n: self.n,
            epsilon: self.epsilon,
            phi: self.phi.unwrap_or(d.phi),
            radius: self.h,
            loop_nodes: self.loop_nodes,
            ..d
        }
    }
}

#[derive(clap::Args)]
struct LandscapeArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// l_k bar = l_k / h.
    #[arg(long, default_value_t = 137.5)]
    l_k_bar: f64,
    /// Number of theta samples on [0, 5].
    #[arg(long, default_value_t = 100)]
    points: usize,
    /// Write the JSON here.
    #[arg(long, default_value = "landscape.json")]
    out: PathBuf,
    /// Also write an SVG plot here.
    #[arg(long)]
    svg: Option<PathBuf>,
}

#[derive(clap::Args)]
struct BifurcationArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Write the JSON here.
    #[arg(long, default_value = "bifurcation.json")]
    out: PathBuf,
    /// Also write an SVG plot here.
    #[arg(long)]
    svg: Option<PathBuf>,
}

#[derive(clap::Args)]
struct DocArgs {
    /// Markdown file to write.
    #[arg(long, default_value = "docs/SIMPLIFIED_MODEL.md")]
    out: PathBuf,
    /// Directory for the figures.
    #[arg(long, default_value = "docs/simplified")]
    figures: PathBuf,
}

pub fn run(args: Args) -> Result<()> {
    match args.command {
        Command::Landscape(a) => {
            let spec = LandscapeSpec {
                params: a.model.params(),
                l_k_bar: a.l_k_bar,
                points: a.points,
                ..LandscapeSpec::default()
            };
            let l = simplified::landscape(&spec)?;
            for c in &l.critical_points {
                println!("critical point theta = {:.4}, stable = {}", c.theta, c.stable);
            }
            write(&a.out, &serde_json::to_string_pretty(&l)?)?;
            if let Some(p) = &a.svg {
                write(p, &report::simplified::landscape(&l)?)?;
            }
        }
        Command::Bifurcation(a) => {
            let b = simplified::bifurcation(&BifurcationSpec::for_params(a.model.params()))?;
            for f in &b.folds {
                println!("fold at l_k bar = {:.3}, theta = {:.4}", f.l_k_bar, f.theta);
            }
            match &b.snap {
                Some(s) => println!("snap-through (second fold) at l_k bar = {:.3}", s.l_k_bar),
                None => println!("no snap-through fold"),
            }
            write(&a.out, &serde_json::to_string_pretty(&b)?)?;
            if let Some(p) = &a.svg {
                write(p, &report::simplified::bifurcation(&b, &[])?)?;
            }
        }
        Command::Doc(a) => {
            let doc = simplified::reproduce(&ReproductionSpec::default())?.document()?;
            std::fs::create_dir_all(&a.figures)
                .with_context(|| format!("creating {}", a.figures.display()))?;
            for f in &doc.figures {
                write(&a.figures.join(&f.file_name), &f.svg)?;
            }
            write(&a.out, &doc.markdown)?;
            println!("wrote {} and {} figures", a.out.display(), doc.figures.len());
        }
    }
    Ok(())
}

fn write(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))
}
