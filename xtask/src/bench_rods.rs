//! Any rod on a researcher's bench: the cost and the inversion of knots in
//! rods of other materials and slenderness than the paper's, measured in one
//! run against the paper's rubber rod (BENCHMARKS.md and docs/FIDELITY.md,
//! "Any rod"). Each case is a `knotsweep run` child process; its CPU time is
//! the child's user + system time (`wait4`), so that cases run side by side
//! (`--jobs`) are still measured alone.
use anyhow::{Context, Result, bail, ensure};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

#[derive(clap::Args)]
pub struct Args {
    /// The `knotsweep` binary [default: the one next to this program].
    #[arg(long)]
    knotsweep: Option<PathBuf>,
    /// Which table: `materials` (E, rho and the named materials), `slenderness`
    /// (L/h), `check` (the rods of the acceptance check), `rates` (the paper's rod
    /// pulled faster, physical inertia) or `all`.
    #[arg(long, default_value = "all")]
    table: String,
    /// Cases run at once.
    #[arg(long, default_value_t = 1)]
    jobs: usize,
    /// Give every case its node count explicitly (edges of 2.08 h), for a
    /// `knotsweep` from before the default node count grew with L/h.
    #[arg(long)]
    explicit_nodes: bool,
    /// Keep each case's JSON report in this directory.
    #[arg(long)]
    keep: Option<PathBuf>,
}

/// One rod: a label and its `knotsweep run` flags.
struct Rod {
    label: String,
    flags: Vec<String>,
}

fn rod(label: &str, flags: &str) -> Rod {
    Rod {
        label: label.to_string(),
        flags: flags.split_whitespace().map(str::to_string).collect(),
    }
}

/// The tables' rods; each table starts with the paper's rod, its unit of cost.
fn table(name: &str) -> Result<Vec<Rod>> {
    let paper = || rod("the paper's rubber rod, n = 3", "--n 3");
    let mut rods = vec![paper()];
    match name {
        "materials" => {
            for (e, rho) in [
                (1e4, 1000.0),
                (1e5, 1000.0),
                (1.8e8, 1000.0),
                (2e11, 1000.0),
                (1.8e6, 500.0),
                (1.8e6, 8000.0),
                (1e4, 8000.0),
                (2e11, 7850.0),
            ] {
                rods.push(rod(
                    &format!("E = {e:e} Pa, rho = {rho}"),
                    &format!("--n 3 --youngs-modulus {e:e} --density {rho}"),
                ));
            }
            rods.push(rod(
                "steel pulled at 3 mm/s (mass scaling)",
                "--n 3 --youngs-modulus 2e11 --density 7850 --pull-speed 3e-3",
            ));
            for m in solver::case::MATERIALS {
                rods.push(rod(
                    &format!(
                        "{} (E {:e} Pa, rho {}, nu {})",
                        m.name, m.youngs_modulus, m.density, m.poisson_ratio
                    ),
                    &format!(
                        "--n 3 --youngs-modulus {:e} --density {} --poisson-ratio {}",
                        m.youngs_modulus, m.density, m.poisson_ratio
                    ),
                ));
            }
        }
        "slenderness" => {
            for h in ["8e-4", "4e-4", "2e-4"] {
                let ratio = 1.0 / h.parse::<f64>()?;
                rods.push(rod(
                    &format!("L/h = {ratio:.0} (h = {h} m)"),
                    &format!("--n 3 --h {h}"),
                ));
            }
        }
        "check" => {
            rods.push(rod("E = 1.8e8 Pa", "--n 3 --youngs-modulus 1.8e8"));
            rods.push(rod("steel", "--n 3 --youngs-modulus 2e11 --density 7850"));
            rods.push(rod("L/h = 2500 (h = 0.4 mm)", "--n 3 --h 4e-4"));
            rods.push(rod(
                "nylon line (L 0.5 m, h 0.25 mm, mu 0.2)",
                "--n 3 --length 0.5 --h 2.5e-4 --youngs-modulus 3e9 --density 1140 --poisson-ratio 0.4 --mu 0.2",
            ));
            rods.push(rod(
                "steel wire, n = 4 (h 0.5 mm, mu 0.12)",
                "--n 4 --h 5e-4 --youngs-modulus 2e11 --density 7850 --poisson-ratio 0.3 --mu 0.12",
            ));
        }
        "rates" => {
            rods = vec![rod("reference pull, 3 mm/s", "--n 3 --protocol reference")];
            for u in ["1e-2", "3e-2", "6e-2"] {
                rods.push(rod(
                    &format!("reference pull, {u} m/s, physical inertia"),
                    &format!("--n 3 --protocol reference --mass-scaling false --pull-speed {u}"),
                ));
            }
            for u in ["1e-2", "3e-2"] {
                rods.push(rod(
                    &format!("adaptive pull, {u} m/s, physical inertia"),
                    &format!("--n 3 --mass-scaling false --pull-speed {u}"),
                ));
            }
        }
        other => bail!("unknown table {other:?}: materials, slenderness, check, rates or all"),
    }
    Ok(rods)
}

/// What one case cost and gave.
struct Measured {
    cpu: f64,
    report: Value,
}

/// Runs `knotsweep run` with `flags` and a report file; returns its CPU time
/// and report.
fn measure(binary: &Path, flags: &[String], out: &Path) -> Result<Measured> {
    let child = Command::new(binary)
        .arg("run")
        .args(flags)
        .arg("--out")
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .with_context(|| format!("starting {}", binary.display()))?;
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    // SAFETY: `usage` is a plain C struct that wait4 fills; the pid is our child's.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let waited = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    ensure!(
        waited == pid,
        "wait4 on {pid} failed: {}",
        std::io::Error::last_os_error()
    );
    let seconds = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    let cpu = seconds(usage.ru_utime) + seconds(usage.ru_stime);
    let text = std::fs::read_to_string(out)
        .with_context(|| format!("knotsweep run {} wrote no report", flags.join(" ")))?;
    Ok(Measured {
        cpu,
        report: serde_json::from_str(&text)?,
    })
}

/// A report's steps by phase (settle, approach, snap, after, reference, ...;
/// `stages` in reports from before physics revision 8).
fn phase_steps(report: &Value) -> String {
    let mut totals: Vec<(String, u64)> = Vec::new();
    let (list, key) = match report.get("phases") {
        Some(p) => (p, "phase"),
        None => (&report["stages"], "stage"),
    };
    for span in list.as_array().into_iter().flatten() {
        let stage = span[key].as_str().unwrap_or("?").to_string();
        let steps = span["steps"].as_u64().unwrap_or(0);
        match totals.iter_mut().find(|(s, _)| *s == stage) {
            Some((_, n)) => *n += steps,
            None => totals.push((stage, steps)),
        }
    }
    totals
        .iter()
        .map(|(s, n)| format!("{s} {n}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The rod's slack at the inversion without its stretch, (arc length -
/// l_c) / h, from the snapshot at the inversion: l_k bar = (L - l_c) / h
/// (eq. 11) also counts the rod's elastic elongation, strain F / EA = F bar / 4.
fn slack(report: &Value) -> Option<f64> {
    let h = report["params"]["h"].as_f64()?;
    let shots = report
        .get("snapshots")
        .or_else(|| report.get("frames"))?
        .as_array()?;
    let at = shots.iter().find(|s| s["label"] == "at_inversion")?;
    let points: Vec<[f64; 3]> = serde_json::from_value(at["points"].clone()).ok()?;
    let dist = |a: &[f64; 3], b: &[f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let arc: f64 = points.windows(2).map(|w| dist(&w[0], &w[1])).sum();
    Some((arc - dist(points.first()?, points.last()?)) / h)
}

/// One table row.
fn row(rod: &Rod, m: &Measured, unit: f64) -> String {
    let r = &m.report;
    let inv = &r["inversion"];
    let l_k = inv["l_k_bar"]
        .as_f64()
        .map_or("none".to_string(), |l| format!("{l:.2}"));
    let clean = match (inv["F_bar_before"].as_f64(), inv["F_bar_after"].as_f64()) {
        (Some(b), Some(a)) if a < b => "yes",
        (Some(_), Some(_)) => "no (F bar rises)",
        _ => "-",
    };
    let quasi = &r["quasi_static"];
    let ratio = quasi["kinetic_ratio"].as_f64().map_or("-".to_string(), |k| {
        format!(
            "{k:.1e}{}",
            if quasi["holds"] == false {
                " (not quasi-static)"
            } else {
                ""
            }
        )
    });
    let scaling = &r["scaling"];
    format!(
        "| {} | {} | {} | {} | {:.2} | {:.1}x | {} | {} | {} | {} | {} | {} |",
        rod.label,
        r["status"].as_str().unwrap_or("?"),
        r["params"]["nodes"],
        r["stats"]["steps"],
        m.cpu,
        m.cpu / unit,
        l_k,
        slack(r).map_or("-".to_string(), |s| format!("{s:.1}")),
        clean,
        ratio,
        scaling["mass_scale"]
            .as_f64()
            .map_or("-".to_string(), |s| format!("{s:.3e}")),
        phase_steps(r),
    )
}

pub fn run(args: Args) -> Result<String> {
    let binary = match &args.knotsweep {
        Some(p) => p.clone(),
        None => std::env::current_exe()?.with_file_name(format!("knotsweep{}", std::env::consts::EXE_SUFFIX)),
    };
    ensure!(
        binary.is_file(),
        "no knotsweep binary at {}: build it (`cargo build --release`) or give --knotsweep",
        binary.display()
    );
    let names: Vec<&str> = match args.table.as_str() {
        "all" => vec!["check", "materials", "slenderness", "rates"],
        one => vec![one],
    };
    let dir = tempfile::tempdir()?;
    let keep = args.keep.clone().unwrap_or_else(|| dir.path().to_path_buf());
    std::fs::create_dir_all(&keep)?;
    let mut doc = String::new();
    for name in names {
        let mut rods = table(name)?;
        if args.explicit_nodes {
            for r in &mut rods {
                let flag = |f: &str, default: f64| {
                    r.flags
                        .iter()
                        .position(|x| x == f)
                        .and_then(|i| r.flags.get(i + 1))
                        .and_then(|v| v.parse().ok())
                        .unwrap_or(default)
                };
                let k = solver::case::default_nodes(
                    flag("--length", 1.0),
                    flag("--h", 1.6e-3),
                    flag("--mu", solver::case::CaseParams::default().mu),
                    solver::case::MAX_NODES,
                );
                r.flags.extend(["--nodes".to_string(), k.to_string()]);
            }
        }
        let measured = run_all(&binary, &rods, args.jobs.max(1), &keep.join(name))?;
        let unit = measured[0].cpu;
        writeln!(doc, "\n### {name}\n")?;
        writeln!(
            doc,
            "`cargo run --release -p xtask -- bench-rods --table {name}`\n"
        )?;
        writeln!(
            doc,
            "| rod | status | K | steps | CPU (s) | CPU / first row | l_k bar | (arc - l_c) / h | F bar falls | \
             kinetic / elastic | mass scale | steps by phase |"
        )?;
        writeln!(doc, "|---|---|---|---|---|---|---|---|---|---|---|---|")?;
        for (r, m) in rods.iter().zip(&measured) {
            writeln!(doc, "{}", row(r, m, unit))?;
        }
    }
    Ok(doc)
}

/// Runs every rod, `jobs` at a time, in order.
fn run_all(binary: &Path, rods: &[Rod], jobs: usize, dir: &Path) -> Result<Vec<Measured>> {
    std::fs::create_dir_all(dir)?;
    let mut results: Vec<Option<Measured>> = (0..rods.len()).map(|_| None).collect();
    for (chunk_start, chunk) in rods.chunks(jobs).enumerate().map(|(i, c)| (i * jobs, c)) {
        let outcomes: Vec<Result<Measured>> = std::thread::scope(|s| {
            let handles: Vec<_> = chunk
                .iter()
                .enumerate()
                .map(|(i, r)| {
                    let out = dir.join(format!("{}.json", chunk_start + i));
                    s.spawn(move || measure(binary, &r.flags, &out))
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("a measuring thread panicked"))
                .collect()
        });
        for (i, outcome) in outcomes.into_iter().enumerate() {
            eprintln!("{}: done", rods[chunk_start + i].label);
            results[chunk_start + i] = Some(outcome?);
        }
    }
    Ok(results
        .into_iter()
        .map(|m| m.expect("every rod measured"))
        .collect())
}
