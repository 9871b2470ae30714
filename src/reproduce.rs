//! `knotsweep reproduce`: reruns the paper's Sec. 4 checks with the full model
//! and writes `docs/VALIDATION.md` (a table of command, figure and pass/fail)
//! with SVG curves of F bar and H bar for the n sweep (paper Fig. 8 a, b).
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use knotsweep_server::figures::{CaseCurve, Quantity, tightening_chart};
use rayon::prelude::*;
use solver::case::{CaseParams, FrictionLaw};
use solver::protocol::{self, CaseReport, Status};
use std::fmt::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Markdown report to write.
    #[arg(long, default_value = "docs/VALIDATION.md")]
    out: PathBuf,
    /// Directory for the SVG figures.
    #[arg(long, default_value = "docs/validation")]
    figures: PathBuf,
    /// Also write each case's full JSON report into this directory.
    #[arg(long)]
    raw: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

/// A named case and the flags that reproduce it with `knotsweep run`.
struct Job {
    key: String,
    params: CaseParams,
    /// What `--initial-shape` holds, when the case starts from its own shape.
    start: Option<String>,
}

fn job(key: &str, f: impl FnOnce(&mut CaseParams)) -> Job {
    let mut params = CaseParams::default();
    f(&mut params);
    Job {
        key: key.to_string(),
        params,
        start: None,
    }
}

/// Largest random displacement of a start node in the perturbation study, over h.
const PERTURBATION: f64 = 0.1;

/// The built knot for `n` with every node but the two clamped at each end moved
/// by a random vector of length at most `PERTURBATION` h (seeded, uniform in the ball).
fn perturbed(key: &'static str, n: u32, seed: u64) -> Result<Job> {
    let mut params = CaseParams {
        n,
        ..CaseParams::default()
    };
    let shape = solver::knot::build(&params.knot_spec())?;
    let mut rng = solver::validation::rng::SplitMix64::new(seed);
    let r = PERTURBATION * params.h;
    let last = shape.points.len() - 2;
    let points = shape
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
    params.initial_shape = Some(points);
    Ok(Job {
        key: key.to_string(),
        params,
        start: Some(format!(
            "built knot, nodes moved by up to {PERTURBATION} h (seed {seed})"
        )),
    })
}

fn jobs() -> Result<Vec<Job>> {
    let mut v = vec![
        job("n3", |_| {}),
        job("n1", |p| p.n = 1),
        job("n2", |p| p.n = 2),
        job("n4", |p| p.n = 4),
        job("n5", |p| p.n = 5),
    ];
    // Sensitivity of the n = 3 and n = 4 inversions (docs/FIDELITY.md).
    for (n, keys) in [
        (3, ["n3_mu0", "n3_sliding", "n3_gravity", "n3_centre"]),
        (4, ["n4_mu0", "n4_sliding", "n4_gravity", "n4_centre"]),
    ] {
        v.push(job(keys[3], |p| {
            p.n = n;
            p.rolling = false;
        }));
        v.push(job(keys[0], |p| {
            p.n = n;
            p.mu = 0.0;
        }));
        v.push(job(keys[1], |p| {
            p.n = n;
            p.rolling = false;
            p.friction_law = FrictionLaw::SlidingDirection;
        }));
        v.push(job(keys[2], |p| {
            p.n = n;
            p.gravity = [0.0, 0.0, -9.81];
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
        v.push(perturbed(key, n, seed)?);
    }
    // The service's presets of Figs 7 and 11 (Fig. 9's are the n jobs above).
    for j in preset_jobs("fig7")?.into_iter().chain(preset_jobs("fig11")?) {
        if !v.iter().any(|k| k.key == j.key) {
            v.push(j);
        }
    }
    v.push(job("dt_half", |p| p.dt = Some(p.time_step() / 2.0)));
    v.push(job("dt_fixed", |p| p.adaptive_dt = false));
    v.push(job("K401", |p| p.nodes = 401));
    v.push(job("speed_half", |p| p.pull_speed /= 2.0));
    v.push(job("speed_1mm", |p| p.pull_speed = 1e-3));
    v.push(job("contact_tight", |p| p.contact_tolerance /= 100.0));
    Ok(v)
}

/// The cases of the service's preset `name` (`knotsweep_server::spec`),
/// keyed `{name}_{axis}{value}`; the default case is keyed `n3`.
fn preset_jobs(name: &str) -> Result<Vec<Job>> {
    let preset = knotsweep_server::spec::preset(name).with_context(|| format!("no preset {name}"))?;
    let mut jobs = Vec::new();
    for (axis, values) in &preset.grid {
        for value in values {
            let mut fields = preset.base_params.as_object().cloned().unwrap_or_default();
            fields.insert(axis.clone(), value.clone());
            let params: CaseParams = serde_json::from_value(serde_json::Value::Object(fields))?;
            let key = if params == CaseParams::default() {
                "n3".to_string()
            } else {
                format!("{name}_{axis}{value}")
            };
            jobs.push(Job {
                key,
                params,
                start: None,
            });
        }
    }
    Ok(jobs)
}

/// The `knotsweep run` command of a job.
fn command_of(j: &Job) -> String {
    match &j.start {
        Some(start) => format!("{} --initial-shape <{start}>", command(&j.params)),
        None => command(&j.params),
    }
}

/// The `knotsweep run` flags that differ from the defaults.
fn command(p: &CaseParams) -> String {
    let d = CaseParams::default();
    let mut s = String::from("knotsweep run");
    if p.n != d.n {
        write!(s, " --n {}", p.n).ok();
    }
    if p.h != d.h {
        write!(s, " --h {:e}", p.h).ok();
    }
    if p.mu != d.mu {
        write!(s, " --mu {}", p.mu).ok();
    }
    if p.nodes != d.nodes {
        write!(s, " --nodes {}", p.nodes).ok();
    }
    if let Some(dt) = p.dt {
        write!(s, " --dt {dt:e}").ok();
    }
    if p.adaptive_dt != d.adaptive_dt {
        write!(s, " --adaptive-dt {}", p.adaptive_dt).ok();
    }
    if p.pull_speed != d.pull_speed {
        write!(s, " --pull-speed {:e}", p.pull_speed).ok();
    }
    if p.contact_tolerance != d.contact_tolerance {
        write!(s, " --contact-tolerance {:e}", p.contact_tolerance).ok();
    }
    if p.friction_law != d.friction_law {
        let law = serde_json::to_value(p.friction_law).unwrap_or_default();
        write!(s, " --friction-law {}", law.as_str().unwrap_or_default()).ok();
    }
    if p.rolling != d.rolling {
        write!(s, " --rolling {}", p.rolling).ok();
    }
    if p.gravity != d.gravity {
        let [x, y, z] = p.gravity;
        write!(s, " --gravity {x},{y},{z}").ok();
    }
    s
}

pub fn run(args: Args) -> Result<()> {
    let jobs = jobs()?;
    std::fs::create_dir_all(&args.figures).with_context(|| format!("creating {}", args.figures.display()))?;
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
    let doc = report(&get, &simplified)?;
    for (file, quantity, name) in [
        ("n_sweep_F_bar.svg", Quantity::FBar, "F bar"),
        ("n_sweep_H_bar.svg", Quantity::HBar, "H bar"),
    ] {
        let curves: Vec<CaseCurve> = ["n1", "n2", "n3", "n4"]
            .into_iter()
            .filter_map(&get)
            .map(|(j, r)| CaseCurve {
                label: format!("n = {}", j.params.n),
                series: &r.series,
                inversion: None,
            })
            .collect();
        let svg = tightening_chart(
            &format!("{name} against l_k bar, h = 1.6 mm, mu = 0.1"),
            quantity,
            &curves,
        )?;
        std::fs::write(args.figures.join(file), svg)?;
    }
    if let Some(parent) = args.out.parent() {
        std::fs::create_dir_all(parent)?;
    }
    std::fs::write(&args.out, doc).with_context(|| format!("writing {}", args.out.display()))?;
    println!("wrote {}", args.out.display());
    Ok(())
}

type Lookup<'a> = dyn Fn(&str) -> Option<(&'a Job, &'a CaseReport)> + 'a;

fn inversion(r: &CaseReport) -> Option<f64> {
    (r.status == Status::Completed)
        .then_some(())
        .and(r.inversion.map(|i| i.l_k_bar))
}

fn describe(r: &CaseReport) -> String {
    match (r.status, r.inversion) {
        (Status::Completed, Some(i)) => format!("l_k bar {:.1} (l_c/L {:.3})", i.l_k_bar, i.l_c_over_l),
        (Status::Completed, None) => "no inversion".to_string(),
        (s, _) => format!("{s}: {}", r.reason),
    }
}

/// epsilon and phi of the sample before the snap.
fn braid_at_snap(r: &CaseReport) -> Option<(f64, f64)> {
    let i = r.inversion?;
    r.series.get(i.sample).map(|s| (s.epsilon, s.phi))
}

/// The paper's braid at inversion (Sec. 5): epsilon = 0.7, phi = pi/3.
const PAPER_EPSILON: f64 = 0.7;
const PAPER_PHI: f64 = std::f64::consts::FRAC_PI_3;
/// How near "approximately" is taken to be, relative.
const BRAID_TOLERANCE: f64 = 0.2;

fn report(get: &Lookup, simplified: &[(u32, Option<f64>)]) -> Result<String> {
    let mut rows: Vec<(String, String, String, bool)> = Vec::new();
    let base = get("n3").map(|(_, r)| r).context("base case missing")?;
    let base_l = inversion(base);
    // The paper's Fig. 1 (experiments and its simulations, L = 1 m, h = 1.6 mm,
    // mu = 0.1): n = 3 open at l_c/L 0.78 and inverted at 0.79, n = 4 open at
    // 0.66 and inverted at 0.68; the acceptance ranges (fidelity issue) bracket them.
    for (key, lo, hi, fig) in [
        (
            "n3",
            125.0,
            145.0,
            "open at l_c/L 0.78, inverted at 0.79: l_k bar 131-138",
        ),
        (
            "n4",
            190.0,
            225.0,
            "open at 0.66, inverted at 0.68: l_k bar 200-212",
        ),
    ] {
        let (j, r) = get(key).context("Fig. 1 case missing")?;
        rows.push((
            format!(
                "n = {}, h = 1.6 mm: inversion at l_k bar in [{lo}, {hi}] (paper Fig. 1: {fig})",
                j.params.n
            ),
            command_of(j),
            describe(r),
            inversion(r).is_some_and(|l| (lo..=hi).contains(&l)),
        ));
    }
    let n1 = get("n1").map(|(_, r)| r).context("n1 missing")?;
    rows.push((
        "n = 1: no inversion".into(),
        command_of(get("n1").unwrap().0),
        describe(n1),
        n1.status == Status::Completed && n1.inversion.is_none(),
    ));
    let ns: Vec<Option<f64>> = ["n2", "n3", "n4", "n5"]
        .iter()
        .map(|k| get(k).and_then(|(_, r)| inversion(r)))
        .collect();
    let grows = ns.iter().all(Option::is_some) && ns.windows(2).all(|w| w[1] > w[0]);
    rows.push((
        "n = 2 ... 5 at h = 1.6 mm: critical l_k bar grows with n (paper Fig. 9)".into(),
        "knotsweep run --n 2 / 3 / 4 / 5".into(),
        ["n2", "n3", "n4", "n5"]
            .iter()
            .map(|k| {
                format!(
                    "n{}: {}",
                    &k[1..],
                    get(k).map(|(_, r)| describe(r)).unwrap_or_default()
                )
            })
            .collect::<Vec<_>>()
            .join("; "),
        grows,
    ));
    let braids: Vec<(u32, Option<(f64, f64)>)> = (2..=5u32)
        .map(|n| {
            let key = ["n2", "n3", "n4", "n5"][n as usize - 2];
            (n, get(key).and_then(|(_, r)| braid_at_snap(r)))
        })
        .collect();
    let near = |x: f64, paper: f64| (x - paper).abs() <= BRAID_TOLERANCE * paper;
    rows.push((
        format!(
            "n = 2 ... 5: the braid before the snap has epsilon = l_b / l_l and phi near the paper's {PAPER_EPSILON} and pi/3 (within {} %, Sec. 5)",
            100.0 * BRAID_TOLERANCE
        ),
        "knotsweep run --n 2 / 3 / 4 / 5 (series columns epsilon, phi)".into(),
        braids
            .iter()
            .map(|(n, b)| match b {
                Some((e, p)) => format!("n{n}: epsilon {e:.2}, phi {:.0} deg", p.to_degrees()),
                None => format!("n{n}: -"),
            })
            .collect::<Vec<_>>()
            .join("; "),
        braids
            .iter()
            .all(|(_, b)| b.is_some_and(|(e, p)| near(e, PAPER_EPSILON) && near(p, PAPER_PHI))),
    ));
    let hs: Vec<Option<f64>> = preset_jobs("fig7")?
        .iter()
        .map(|j| get(&j.key).and_then(|(_, r)| inversion(r)))
        .collect();
    let (spread_text, spread_ok) = if hs.iter().all(Option::is_some) {
        let v: Vec<f64> = hs.iter().flatten().copied().collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(*x), b.max(*x))
        });
        let spread = (hi - lo) / mean;
        (
            format!(
                "{} ; spread (max - min)/mean = {:.1} %",
                v.iter().map(|x| format!("{x:.1}")).collect::<Vec<_>>().join(", "),
                100.0 * spread
            ),
            spread <= 0.15,
        )
    } else {
        ("a case did not invert".into(), false)
    };
    rows.push((
        "n = 3, h = 1.6 ... 3.2 mm: critical l_k bar nearly the same (spread <= 15 %)".into(),
        "knotsweep sweep --preset fig7".into(),
        spread_text,
        spread_ok,
    ));
    let mus: Vec<Option<f64>> = preset_jobs("fig11")?
        .iter()
        .map(|j| get(&j.key).and_then(|(_, r)| inversion(r)))
        .collect();
    let mu_ok = mus.iter().all(Option::is_some) && mus.windows(2).all(|w| w[1] >= w[0]) && mus[6] > mus[0];
    rows.push((
        "n = 3, h = 3.4 mm, mu = 0.1 ... 0.7: critical l_k bar grows with mu".into(),
        "knotsweep sweep --preset fig11".into(),
        mus.iter()
            .map(|m| m.map_or("-".to_string(), |x| format!("{x:.1}")))
            .collect::<Vec<_>>()
            .join(", "),
        mu_ok,
    ));
    for (key, what) in [
        ("dt_half", "largest dt halved"),
        ("dt_fixed", "constant dt (the paper's scheme)"),
        ("K401", "K = 401"),
        ("speed_half", "pull speed halved"),
        ("speed_1mm", "the paper's text's pull speed"),
        ("contact_tight", "contact solve 100 times tighter"),
    ] {
        let (j, r) = get(key).context("convergence case missing")?;
        let l = inversion(r);
        let change = match (l, base_l) {
            (Some(a), Some(b)) => Some((a - b).abs() / b),
            _ => None,
        };
        rows.push((
            format!(
                "convergence: {what} (step {} ms{}, {} mm/s), inversion within 3 % of the default",
                format!("{:.4}", j.params.time_step() * 1e3)
                    .trim_end_matches('0')
                    .trim_end_matches('.'),
                if j.params.adaptive_dt { " or less" } else { "" },
                j.params.pull_speed * 1e3
            ),
            command_of(j),
            format!(
                "{} ; change {}",
                describe(r),
                change.map_or("-".into(), |c| format!("{:.2} %", 100.0 * c))
            ),
            change.is_some_and(|c| c <= 0.03),
        ));
    }
    let mut doc = String::new();
    writeln!(doc, "# Validation: reproduction of the paper's Sec. 4\n")?;
    let d = CaseParams::default();
    writeln!(
        doc,
        "Regenerate with `cargo run --release -- reproduce` (writes this file and the SVG figures in `docs/validation/`; `--raw DIR` keeps every case's JSON report). Defaults: L = {} m, K = {}, E = {:e} Pa, nu = {}, rho = {} kg/m^3, time step {} ms ({}), pull speed {} mm/s per clamp, mu = {}, h = {} mm, contact solve tolerance {:e}, pull protocol `{}` (`solver::protocol::Protocol`; above mu = {} as `reference`).\n",
        d.length,
        d.nodes,
        d.youngs_modulus,
        d.poisson_ratio,
        d.density,
        d.time_step() * 1e3,
        if d.adaptive_dt {
            "the largest; adaptive, see `solver::time_step`; scaled with the square of the edge length, see `CaseParams::time_step`"
        } else {
            "constant"
        },
        d.pull_speed * 1e3,
        d.mu,
        d.h * 1e3,
        d.contact_tolerance,
        d.protocol,
        protocol::ADAPTIVE_MAX_MU,
    )?;
    writeln!(doc, "| check | command | figure | pass |\n|---|---|---|---|")?;
    let passed = rows.iter().filter(|r| r.3).count();
    for (what, cmd, fig, ok) in &rows {
        writeln!(
            doc,
            "| {what} | `{cmd}` | {fig} | {} |",
            if *ok { "yes" } else { "**no**" }
        )?;
    }
    writeln!(doc, "\n{passed} passed, {} failed\n", rows.len() - passed)?;
    writeln!(
        doc,
        "## Sensitivity of the n = 3 and n = 4 inversions\n\nNot checks: what moves the inversion (docs/FIDELITY.md; the paper's Fig. 1: n = 3 at l_k bar 131-138, n = 4 at 200-212).\n\n| variant | command | n = 3 | n = 4 |\n|---|---|---|---|"
    )?;
    for (what, k3, k4) in [
        (
            "defaults (Coulomb friction at the surfaces: rods roll, mu = 0.1)",
            "n3",
            "n4",
        ),
        (
            "friction at the centre lines (no rolling: physics revision 1's friction, at the current time step)",
            "n3_centre",
            "n4_centre",
        ),
        ("no friction (mu = 0)", "n3_mu0", "n4_mu0"),
        (
            "at the centre lines, only along the previous sliding direction (fails the capstan check)",
            "n3_sliding",
            "n4_sliding",
        ),
        (
            "gravity 9.81 m/s^2 along -z, across the pull",
            "n3_gravity",
            "n4_gravity",
        ),
    ] {
        let (j3, r3) = get(k3).context("sensitivity case missing")?;
        let (_, r4) = get(k4).context("sensitivity case missing")?;
        let cmd = command(&j3.params).replace(" --n 3", "");
        writeln!(
            doc,
            "| {what} | `{cmd} --n 3 / 4` | {} | {} |",
            describe(r3),
            describe(r4)
        )?;
    }
    writeln!(doc)?;
    perturbation_section(&mut doc, get)?;
    simplified_section(&mut doc, get, simplified)?;
    writeln!(
        doc,
        "F bar and H bar against l_k bar for n = 1..4 (paper Fig. 8 a, b):\n\n![F bar](validation/n_sweep_F_bar.svg)\n![H bar](validation/n_sweep_H_bar.svg)"
    )?;
    Ok(doc)
}

/// The perturbation study: is the snap a fold (insensitive to small
/// perturbations) or a delayed symmetry breaking (sensitive)?
fn perturbation_section(doc: &mut String, get: &Lookup) -> Result<()> {
    writeln!(
        doc,
        "## Perturbation study\n\nThe same cases with small perturbations that break the built knot's symmetry: gravity (9.81 m/s^2; the pull is along x) and random start shapes (every node but the clamped ones moved by up to {PERTURBATION} h, uniform in the ball, three seeds). A fold moves little under them; a delayed symmetry breaking moves a lot.\n\n| perturbation | command | n = 3 | n = 4 |\n|---|---|---|---|"
    )?;
    let rows = [
        ("none (defaults)", "n3", "n4"),
        ("gravity along -z", "n3_gravity", "n4_gravity"),
        ("gravity along +z", "n3_gravity_up", "n4_gravity_up"),
        ("gravity along -y", "n3_gravity_y", "n4_gravity_y"),
        ("random start, seed 1", "n3_seed1", "n4_seed1"),
        ("random start, seed 2", "n3_seed2", "n4_seed2"),
        ("random start, seed 3", "n3_seed3", "n4_seed3"),
    ];
    for (what, k3, k4) in rows {
        let (j3, r3) = get(k3).context("perturbation case missing")?;
        let (_, r4) = get(k4).context("perturbation case missing")?;
        let cmd = command_of(j3).replace(" --n 3", "");
        writeln!(
            doc,
            "| {what} | `{cmd} --n 3 / 4` | {} | {} |",
            describe(r3),
            describe(r4)
        )?;
    }
    for (n, keys) in [
        (3, ["n3", "n3_seed1", "n3_seed2", "n3_seed3"]),
        (4, ["n4", "n4_seed1", "n4_seed2", "n4_seed3"]),
    ] {
        let v: Vec<f64> = keys
            .iter()
            .filter_map(|k| get(k).and_then(|(_, r)| inversion(r)))
            .collect();
        if v.len() == keys.len() {
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(*x), b.max(*x))
            });
            writeln!(
                doc,
                "\nn = {n}: the built and the three random starts invert at l_k bar {lo:.1} to {hi:.1} (spread {:.1} % of the mean).",
                100.0 * (hi - lo) / mean
            )?;
        }
    }
    writeln!(doc)?;
    Ok(())
}

/// The full model's snap against the simplified model's (Sec. 5, Fig. 15),
/// with the braid the full model shows there.
fn simplified_section(doc: &mut String, get: &Lookup, simplified: &[(u32, Option<f64>)]) -> Result<()> {
    writeln!(
        doc,
        "## Full model against the simplified model (h = 1.6 mm, mu = 0.1)\n\nThe simplified model (Sec. 5; `knotsweep simplified`, docs/SIMPLIFIED_MODEL.md) holds epsilon = {PAPER_EPSILON} and phi = pi/3; the paper's full model sits 0-11 % above it (Fig. 15). The last two columns are the full model's braid just before its snap.\n\n| n | full model l_k bar | simplified model l_k bar | full / simplified | epsilon | phi (deg) |\n|---|---|---|---|---|---|"
    )?;
    for &(n, snap) in simplified {
        let key = ["n2", "n3", "n4", "n5"][n as usize - 2];
        let r = get(key).map(|(_, r)| r).context("n case missing")?;
        let full = inversion(r);
        let braid = braid_at_snap(r);
        let fmt = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{x:.1}"));
        writeln!(
            doc,
            "| {n} | {} | {} | {} | {} | {} |",
            fmt(full),
            fmt(snap),
            match (full, snap) {
                (Some(a), Some(b)) => format!("{:.3}", a / b),
                _ => "-".into(),
            },
            braid.map_or("-".into(), |b| format!("{:.2}", b.0)),
            braid.map_or("-".into(), |b| format!("{:.0}", b.1.to_degrees())),
        )?;
    }
    writeln!(doc)?;
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
            let j = perturbed("t", n, 1).unwrap();
            if let Err(errors) = j.params.validate() {
                panic!("n = {n}: {errors:?}");
            }
            let built = solver::knot::build(&j.params.knot_spec()).unwrap();
            let moved = j.params.initial_shape.as_ref().unwrap();
            let largest = built
                .points
                .iter()
                .zip(moved)
                .map(|(a, b)| (nalgebra::Vector3::from(*b) - a).norm())
                .fold(0.0, f64::max);
            assert!(largest > 0.0 && largest <= PERTURBATION * j.params.h);
        }
    }
}
