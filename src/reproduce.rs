//! `knotsweep reproduce`: reruns the paper's Sec. 4 checks with the full model
//! and writes `docs/VALIDATION.md` (a table of command, figure and pass/fail)
//! with SVG curves of F bar and H bar for the n sweep (paper Fig. 8 a, b) and
//! the perturbation study's start shapes, the files its commands name.
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use report::validation::{Job, PERTURBATION};
use solver::case::{Candidates, CaseParams, FrictionLaw, Geometry, Protocol};
use solver::protocol::{self, CaseReport};
use std::path::Path;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Markdown report to write.
    #[arg(long, default_value = "docs/VALIDATION.md")]
    out: PathBuf,
    /// Directory for the SVG figures (and, under `starts/`, the perturbed start shapes).
    #[arg(long, default_value = "docs/validation")]
    figures: PathBuf,
    /// Also write each case's full JSON report into this directory.
    #[arg(long)]
    raw: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

/// The validation's base case: the defaults under the paper's pull
/// (`Protocol::Reference`; the default protocol is the adaptive one).
fn base() -> CaseParams {
    CaseParams {
        protocol: Protocol::Reference,
        ..CaseParams::default()
    }
}

fn job(key: &str, f: impl FnOnce(&mut CaseParams)) -> Job {
    let mut params = base();
    f(&mut params);
    Job {
        key: key.to_string(),
        params,
        shape_file: None,
    }
}

/// The built knot for `n` with every node but the two clamped at each end moved
/// by a random vector of length at most `PERTURBATION` h (seeded, uniform in the
/// ball), to start from the file `starts/{key}.txt` of `figures`.
fn perturbed(key: &'static str, n: u32, seed: u64, figures: &Path) -> Result<Job> {
    let mut params = CaseParams { n, ..base() };
    let shape = solver::knot::build(&params.knot_spec())?;
    let mut rng = solver::validation::rng::SplitMix64::new(seed);
    let r = PERTURBATION * params.h;
    let last = shape.points.len() - 2;
    let points: Vec<[f64; 3]> = shape
        .points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut d = nalgebra::Vector3::new(1.0, 1.0, 1.0);
            while d.norm() > 1.0 {
                d = nalgebra::Vector3::from_fn(|_, _| rng.uniform(-1.0, 1.0));
            }
            let x = if (2..last).contains(&i) { p + d * r } else { *p };
            [x.x, x.y, x.z]
        })
        .collect();
    params.initial_shape = Some(points.into());
    let file = figures.join("starts").join(format!("{key}.txt"));
    Ok(Job {
        key: key.to_string(),
        params,
        shape_file: Some(file.display().to_string()),
    })
}

/// Writes each job's start shape to its file, as `--initial-shape` reads it
/// (`x y z` per line, every digit kept: the run from the file is the run here).
fn write_shapes(jobs: &[Job]) -> Result<()> {
    for j in jobs {
        let (Some(file), Some(points)) = (
            &j.shape_file,
            j.params.initial_shape.as_ref().and_then(|s| s.points()),
        ) else {
            continue;
        };
        let path = Path::new(file);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
        let mut text = format!(
            "# {}: the built n = {} knot, nodes moved by up to {PERTURBATION} h; x y z (m) per node\n",
            j.key, j.params.n
        );
        for p in points {
            text.push_str(&format!("{} {} {}\n", p[0], p[1], p[2]));
        }
        std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

fn jobs(figures: &Path) -> Result<Vec<Job>> {
    let mut v = vec![
        job("n3", |_| {}),
        job("n1", |p| p.n = 1),
        job("n2", |p| p.n = 2),
        job("n4", |p| p.n = 4),
        job("n5", |p| p.n = 5),
    ];
    // Sensitivity of the n = 3 and n = 4 inversions (docs/FIDELITY.md).
    for n in [3, 4] {
        let key = |what: &str| format!("n{n}_{what}");
        v.push(job(&key("untwisted"), |p| {
            p.n = n;
            p.start_twist = Some(0.0);
        }));
        v.push(job(&key("rolling"), |p| {
            p.n = n;
            p.rolling = true;
        }));
        v.push(job(&key("rev4"), |p| {
            p.n = n;
            p.rolling = true;
            p.start_twist = Some(0.0);
        }));
        v.push(job(&key("mu0"), |p| {
            p.n = n;
            p.mu = 0.0;
        }));
        v.push(job(&key("sliding"), |p| {
            p.n = n;
            p.friction_law = FrictionLaw::SlidingDirection;
        }));
        v.push(job(&key("gravity"), |p| {
            p.n = n;
            p.gravity = [0.0, 0.0, -9.81];
        }));
        v.push(job(&key("segment"), |p| {
            p.n = n;
            p.contact_geometry = Geometry::Segment;
        }));
        v.push(job(&key("paper"), |p| {
            p.n = n;
            p.contact_geometry = Geometry::Segment;
            p.contact_candidates = Candidates::Predicted;
            p.dt = Some(1e-3);
            p.adaptive_dt = false;
        }));
    }
    // Perturbation study: gravity in the other directions, random start shapes.
    for (key, n, g) in [
        ("n3_gravity_y", 3, [0.0, -9.81, 0.0]),
        ("n4_gravity_y", 4, [0.0, -9.81, 0.0]),
        ("n3_gravity_up", 3, [0.0, 0.0, 9.81]),
        ("n4_gravity_up", 4, [0.0, 0.0, 9.81]),
    ] {
        v.push(job(key, |p| {
            p.n = n;
            p.gravity = g;
        }));
    }
    for (key, n, seed) in [
        ("n3_seed1", 3, 1),
        ("n3_seed2", 3, 2),
        ("n3_seed3", 3, 3),
        ("n4_seed1", 4, 1),
        ("n4_seed2", 4, 2),
        ("n4_seed3", 4, 3),
    ] {
        v.push(perturbed(key, n, seed, figures)?);
    }
    // The service's presets of Figs 7 and 11 (Fig. 9's are the n jobs above).
    for j in preset_jobs("fig7")?.into_iter().chain(preset_jobs("fig11")?) {
        if !v.iter().any(|k| k.key == j.key) {
            v.push(j);
        }
    }
    v.push(job("dt_half", |p| p.dt = Some(p.time_step() / 2.0)));
    v.push(job("dt_fixed", |p| p.adaptive_dt = false));
    v.push(job("K401", |p| p.nodes = Some(401)));
    v.push(job("speed_half", |p| {
        p.pull_speed = Some(p.clamp_speed() / 2.0);
        p.mass_scaling = false;
    }));
    v.push(job("speed_1mm", |p| {
        p.pull_speed = Some(1e-3);
        p.mass_scaling = false;
    }));
    v.push(job("contact_tight", |p| p.contact_tolerance /= 100.0));
    v.push(job("adaptive", |p| p.protocol = Protocol::Adaptive));
    Ok(v)
}

/// The cases of the service's preset `name` (`knotsweep_server::spec`) under
/// the reference pull, the paper's protocol (the presets pull adaptively),
/// keyed `{name}_{axis}{value}`; the default case is keyed `n3`.
fn preset_jobs(name: &str) -> Result<Vec<Job>> {
    let preset = knotsweep_server::spec::preset(name).with_context(|| format!("no preset {name}"))?;
    let mut jobs = Vec::new();
    for (axis, values) in &preset.grid {
        for value in values {
            let mut fields = preset.base_params.as_object().cloned().unwrap_or_default();
            fields.insert(axis.clone(), value.clone());
            fields.insert("protocol".into(), serde_json::to_value(Protocol::Reference)?);
            let params: CaseParams = serde_json::from_value(serde_json::Value::Object(fields))?;
            let key = if params == base() {
                "n3".to_string()
            } else {
                format!("{name}_{axis}{value}")
            };
            jobs.push(Job {
                key,
                params,
                shape_file: None,
            });
        }
    }
    Ok(jobs)
}

pub fn run(args: Args) -> Result<()> {
    let jobs = jobs(&args.figures)?;
    std::fs::create_dir_all(&args.figures).with_context(|| format!("creating {}", args.figures.display()))?;
    write_shapes(&jobs)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0))
        .build()?;
    let bar = ProgressBar::new(jobs.len() as u64).with_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} cases {elapsed_precise} {msg}")
            .expect("valid template"),
    );
    let reports: Vec<CaseReport> = pool.install(|| {
        jobs.par_iter()
            .map(|j| {
                let r = protocol::run(&j.params, &mut |_| true);
                tracing::info!(case = j.key.as_str(), status = ?r.status, inversion = ?r.inversion.map(|i| i.l_k_bar), wall = r.stats.wall_time, "case done");
                bar.inc(1);
                r
            })
            .collect()
    });
    bar.finish_and_clear();
    let simplified: Vec<(u32, Option<f64>)> = pool.install(|| {
        (2..=5u32)
            .into_par_iter()
            .map(|n| {
                let snap = solver::simplified::reproduce::snap_l_k_bar(n, CaseParams::default().h)
                    .map_err(|e| tracing::warn!(n, error = %e, "simplified model failed"))
                    .ok()
                    .flatten();
                (n, snap)
            })
            .collect()
    });
    if let Some(dir) = &args.raw {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        for (j, r) in jobs.iter().zip(&reports) {
            let path = dir.join(format!("{}.json", j.key));
            std::fs::write(&path, serde_json::to_string(r)?)
                .with_context(|| format!("writing {}", path.display()))?;
        }
    }
    let get = |key: &str| {
        jobs.iter()
            .position(|j| j.key == key)
            .map(|i| (&jobs[i], &reports[i]))
    };
    let keys = |name| -> Result<Vec<String>> { Ok(preset_jobs(name)?.into_iter().map(|j| j.key).collect()) };
    let doc = report::validation::markdown(&get, &keys("fig7")?, &keys("fig11")?, &simplified)?;
    for (file, svg) in report::validation::n_sweep_figures(&get)? {
        std::fs::write(args.figures.join(file), svg)?;
    }
    if let Some(parent) = args.out.parent() {
        std::fs::create_dir_all(parent)?;
    }
    std::fs::write(&args.out, doc).with_context(|| format!("writing {}", args.out.display()))?;
    println!("wrote {}", args.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The perturbation study's random starts are knots the case accepts:
    /// same knot type, 2h clearance, clamps at the ends.
    #[test]
    fn perturbed_starts_are_valid_cases() {
        for n in [3, 4] {
            let j = perturbed("t", n, 1, Path::new("starts")).unwrap();
            if let Err(errors) = j.params.validate() {
                panic!("n = {n}: {errors:?}");
            }
            let built = solver::knot::build(&j.params.knot_spec()).unwrap();
            let moved = j.params.initial_shape.as_ref().and_then(|s| s.points()).unwrap();
            let largest = built
                .points
                .iter()
                .zip(moved)
                .map(|(a, b)| (nalgebra::Vector3::from(*b) - a).norm())
                .fold(0.0, f64::max);
            assert!(largest > 0.0 && largest <= PERTURBATION * j.params.h);
        }
    }

    /// A start shape read back from its file is the shape the case ran from,
    /// to the last bit: the documented command reruns the documented case.
    #[test]
    fn start_shapes_read_back_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let j = perturbed("n3_seed1", 3, 1, dir.path()).unwrap();
        write_shapes(std::slice::from_ref(&j)).unwrap();
        let text = std::fs::read_to_string(j.shape_file.as_ref().unwrap()).unwrap();
        assert_eq!(
            crate::run::read_shape(&text).unwrap(),
            j.params.initial_shape.unwrap()
        );
    }
}
