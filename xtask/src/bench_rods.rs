//! Any rod on a researcher's bench: the cost and the inversion of knots in
//! rods of other materials and slenderness than the paper's, measured in one
//! run against the paper's rubber rod (BENCHMARKS.md and docs/FIDELITY.md,
//! "Any rod"), and the map of the rod space (`--table map`, its corners
//! `--table corners`): L/h by n by mu, the paper's rubber and a stiff thin
//! line, each case's cost against the paper's rod of the same n. Each case is
//! a `knotsweep run` child process; its CPU time is the child's user + system
//! time (`wait4`), so that cases run side by side (`--jobs`) are still
//! measured alone.
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
    /// pulled faster, physical inertia), `lengths` (the inversion against L/h
    /// at L = 1 m, n = 2 ... 5, and Fig. 7's h sweep), `all` (those five),
    /// `map` (`ratios` by `ns` by `mus`, rubber and a nylon line: by default
    /// L/h 625 ... 5000 by n 2 ... 6 by mu 0.05 ... 0.5, 120 cases) or
    /// `corners` (the map's corners: 16 by default).
    #[arg(long, default_value = "all")]
    table: String,
    /// With `map` or `corners`: the corners of L/h at most this also under
    /// the reference pull, and the adaptive pull's deviation from it (a
    /// reference pull costs about (L/h / 625)^2 times the paper's rod's over
    /// the same pull).
    #[arg(long)]
    reference_up_to: Option<f64>,
    /// With `reference_up_to`: only the corners of n at least this (a knot of
    /// more turns inverts sooner in the pull, so that its reference pull is
    /// shorter).
    #[arg(long, default_value_t = 0)]
    reference_from_n: u32,
    /// The map's L/h axis (its first and last values are the corners).
    #[arg(long, value_delimiter = ',', default_values_t = MAP_RATIOS)]
    ratios: Vec<f64>,
    /// The map's n axis.
    #[arg(long, value_delimiter = ',', default_values_t = MAP_NS)]
    ns: Vec<u32>,
    /// The map's mu axis.
    #[arg(long, value_delimiter = ',', default_values_t = MAP_MUS)]
    mus: Vec<f64>,
    /// Cases run at once.
    #[arg(long, default_value_t = 1)]
    jobs: usize,
    /// Give every case its node count explicitly (edges of 2.08 h), for a
    /// `knotsweep` from before the default node count grew with L/h.
    #[arg(long)]
    explicit_nodes: bool,
    /// Keep each case's JSON report and CPU time in this directory, in files
    /// named by its flags.
    #[arg(long)]
    keep: Option<PathBuf>,
    /// With `keep`: cases already measured there (by an earlier run of any
    /// table, the same flags) are read back instead of run again; their CPU
    /// is that earlier run's.
    #[arg(long)]
    resume: bool,
    /// With `keep` (not `map` or `corners`): only the cases measured there
    /// already, none run (a table of a run cut short).
    #[arg(long)]
    kept_only: bool,
    /// With `lengths`: also write its figure (the event's eq. 11 l_k bar and
    /// the knot's own length against L/h) as SVG here.
    #[arg(long)]
    svg: Option<PathBuf>,
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

/// The map's materials: the paper's rubber (L = 1 m, h = L / (L/h), as
/// Fig. 7 varies it) and a stiff thin nylon line (h = 0.25 mm, L = (L/h) h).
const MAP_MATERIALS: [(&str, &str); 2] = [
    (
        "rubber",
        "--youngs-modulus 1.8e6 --density 1000 --poisson-ratio 0.5",
    ),
    (
        "nylon line",
        "--youngs-modulus 3e9 --density 1140 --poisson-ratio 0.4",
    ),
];
const MAP_RATIOS: [f64; 4] = [625.0, 1250.0, 2500.0, 5000.0];
const MAP_NS: [u32; 5] = [2, 3, 4, 5, 6];
const MAP_MUS: [f64; 3] = [0.05, 0.2, 0.5];
const LINE_H: f64 = 2.5e-4;

/// A case of the map.
struct MapCase {
    material: usize,
    ratio: f64,
    n: u32,
    mu: f64,
}

impl MapCase {
    /// Its name in the progress lines.
    fn label(&self) -> String {
        let material = MAP_MATERIALS[self.material].0;
        format!(
            "{material}, L/h = {}, n = {}, mu = {}",
            self.ratio, self.n, self.mu
        )
    }

    /// Its `knotsweep run` flags.
    fn flags(&self, reference: bool) -> Vec<String> {
        let (length, h) = match self.material {
            0 => (1.0, 1.0 / self.ratio),
            _ => (self.ratio * LINE_H, LINE_H),
        };
        let protocol = if reference { " --protocol reference" } else { "" };
        let flags = format!(
            "--n {} --length {length} --h {h:e} --mu {} {}{protocol}",
            self.n, self.mu, MAP_MATERIALS[self.material].1
        );
        flags.split_whitespace().map(str::to_string).collect()
    }
}

/// The map's axes: L/h, n and mu.
struct Axes<'a> {
    ratios: &'a [f64],
    ns: &'a [u32],
    mus: &'a [f64],
}

impl Axes<'_> {
    /// The map's cases (`corners`: the first and last of every axis), both
    /// materials.
    fn cases(&self, corners: bool) -> Vec<MapCase> {
        let ends = |len: usize| -> Vec<usize> {
            match len {
                0 => vec![],
                _ if corners => {
                    let mut e = vec![0, len - 1];
                    e.dedup();
                    e
                }
                _ => (0..len).collect(),
            }
        };
        let mut cases = Vec::new();
        for material in 0..MAP_MATERIALS.len() {
            for &r in &ends(self.ratios.len()) {
                for &n in &ends(self.ns.len()) {
                    for &m in &ends(self.mus.len()) {
                        cases.push(MapCase {
                            material,
                            ratio: self.ratios[r],
                            n: self.ns[n],
                            mu: self.mus[m],
                        });
                    }
                }
            }
        }
        cases
    }

    /// Whether `c` is one of the map's corners.
    fn corner(&self, c: &MapCase) -> bool {
        let end = |v: f64, axis: &[f64]| axis.first() == Some(&v) || axis.last() == Some(&v);
        let ns: Vec<f64> = self.ns.iter().map(|&n| f64::from(n)).collect();
        end(c.ratio, self.ratios) && end(f64::from(c.n), &ns) && end(c.mu, self.mus)
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
        "lengths" => {
            rods.clear();
            for n in 2..=5 {
                for ratio in MAP_RATIOS {
                    rods.push(rod(
                        &format!("n = {n}, L/h = {ratio:.0}"),
                        &format!("--n {n} --h {:e}", 1.0 / ratio),
                    ));
                }
            }
            for h in ["2.0e-3", "2.4e-3", "2.8e-3", "3.2e-3"] {
                let ratio = 1.0 / h.parse::<f64>()?;
                rods.push(rod(
                    &format!("Fig. 7: n = 3, L/h = {ratio:.1} (h = {h} m)"),
                    &format!("--n 3 --h {h}"),
                ));
            }
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
        other => bail!(
            "unknown table {other:?}: materials, slenderness, check, rates, lengths, all, map or corners"
        ),
    }
    Ok(rods)
}

/// What one case cost and gave.
struct Measured {
    cpu: f64,
    report: Value,
}

/// Runs `knotsweep run` with `flags` and a report file `out`; returns its CPU
/// time and report, and keeps the CPU time beside the report (`out` with
/// the extension `cpu`). With `resume`, a report and CPU time already there
/// are read back instead.
fn measure(binary: &Path, flags: &[String], out: &Path, resume: bool) -> Result<Measured> {
    let cpu_file = out.with_extension("cpu");
    if resume && out.is_file() {
        if let Ok(cpu) = std::fs::read_to_string(&cpu_file) {
            let report = serde_json::from_str(&std::fs::read_to_string(out)?)?;
            return Ok(Measured {
                cpu: cpu.trim().parse()?,
                report,
            });
        }
    }
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
    std::fs::write(&cpu_file, format!("{cpu}\n"))?;
    Ok(Measured {
        cpu,
        report: serde_json::from_str(&text)?,
    })
}

/// A case's report file in `dir`: named by its flags.
fn report_file(dir: &Path, flags: &[String]) -> PathBuf {
    let name: String = (flags.iter().map(|f| f.trim_start_matches('-')))
        .collect::<Vec<_>>()
        .join("_")
        .chars()
        .map(|c| match c {
            '.' => 'p',
            c if c.is_ascii_alphanumeric() || c == '-' => c,
            _ => '_',
        })
        .collect();
    dir.join(format!("{name}.json"))
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

/// One table row.
fn row(rod: &Rod, m: &Measured, unit: f64) -> String {
    let r = &m.report;
    let inv = &r["inversion"];
    let length = |key: &str| {
        inv[key]
            .as_f64()
            .map_or("none".to_string(), |l| format!("{l:.2}"))
    };
    let (l_k, own) = (length("l_k_bar"), length("l_k_arc_bar"));
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
        "| {} | {} | {} | {} | {:.2} | {:.1}x | {} | {} | {} | {} | {} | {} | {} |",
        rod.label,
        r["status"].as_str().unwrap_or("?"),
        r["params"]["nodes"],
        r["stats"]["steps"],
        m.cpu,
        m.cpu / unit,
        l_k,
        own,
        clean,
        r["stats"]["restarts"],
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
    let dir = tempfile::tempdir()?;
    let keep = args.keep.clone().unwrap_or_else(|| dir.path().to_path_buf());
    std::fs::create_dir_all(&keep)?;
    let jobs = args.jobs.max(1);
    if let name @ ("map" | "corners") = args.table.as_str() {
        let axes = Axes {
            ratios: &args.ratios,
            ns: &args.ns,
            mus: &args.mus,
        };
        return map(&binary, name, &axes, &args, &keep);
    }
    let names: Vec<&str> = match args.table.as_str() {
        "all" => vec!["check", "materials", "slenderness", "rates", "lengths"],
        one => vec![one],
    };
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
                    solver::case::MAX_NODES,
                );
                r.flags.extend(["--nodes".to_string(), k.to_string()]);
            }
        }
        if args.kept_only {
            rods.retain(|r| {
                let out = report_file(&keep, &r.flags);
                out.is_file() && out.with_extension("cpu").is_file()
            });
        }
        let measured = run_all(&binary, &rods, jobs, &keep, args.resume || args.kept_only)?;
        let unit = measured[0].cpu;
        writeln!(doc, "\n### {name}\n")?;
        writeln!(
            doc,
            "`cargo run --release -p xtask -- bench-rods --table {name}`\n"
        )?;
        writeln!(
            doc,
            "| rod | status | K | steps | CPU (s) | CPU / first row | l_k bar | own length | F bar falls | restarts | \
             kinetic / elastic | mass scale | steps by phase |"
        )?;
        writeln!(doc, "|---|---|---|---|---|---|---|---|---|---|---|---|---|")?;
        for (r, m) in rods.iter().zip(&measured) {
            writeln!(doc, "{}", row(r, m, unit))?;
        }
        if name == "lengths" {
            let points = length_points(&rods, &measured)?;
            doc.push_str(&lengths_table(&points)?);
            if let Some(path) = &args.svg {
                std::fs::write(path, lengths_svg(&points)?)
                    .with_context(|| format!("writing {}", path.display()))?;
                writeln!(doc, "\nFigure: `{}`.", path.display())?;
            }
        }
    }
    Ok(doc)
}

/// A case of the `lengths` table (L = 1 m): n, L/h, the event's eq. 11 l_k
/// bar and the knot's own length, or, without one, the own length where the
/// pull stopped.
struct LengthPoint {
    n: u32,
    ratio: f64,
    event: Option<(f64, f64)>,
    stopped_at: f64,
    cpu: f64,
    restarts: u64,
}

/// The `lengths` table's points, read from each rod's flags and report.
fn length_points(rods: &[Rod], measured: &[Measured]) -> Result<Vec<LengthPoint>> {
    let flag = |r: &Rod, f: &str| -> Result<f64> {
        let at = r
            .flags
            .iter()
            .position(|x| x == f)
            .context(format!("{} has no {f}", r.label))?;
        Ok(r.flags[at + 1].parse()?)
    };
    let mut points = Vec::new();
    for (r, m) in rods.iter().zip(measured) {
        let inv = &m.report["inversion"];
        let last = m.report["series"].as_array().and_then(|s| s.last());
        points.push(LengthPoint {
            n: flag(r, "--n")? as u32,
            ratio: 1.0 / flag(r, "--h")?,
            event: inv["l_k_bar"].as_f64().zip(inv["l_k_arc_bar"].as_f64()),
            stopped_at: last.and_then(|s| s["l_k_arc_bar"].as_f64()).unwrap_or(f64::NAN),
            cpu: m.cpu,
            restarts: m.report["stats"]["restarts"].as_u64().unwrap_or(0),
        });
    }
    Ok(points)
}

/// The `lengths` table as n by L/h, each cell the event's eq. 11 l_k bar /
/// the knot's own length.
fn lengths_table(points: &[LengthPoint]) -> Result<String> {
    let mut ratios: Vec<f64> = points.iter().map(|p| p.ratio).collect();
    ratios.sort_by(f64::total_cmp);
    ratios.dedup();
    let mut ns: Vec<u32> = points.iter().map(|p| p.n).collect();
    ns.sort_unstable();
    ns.dedup();
    let mut doc = String::from(
        "\nEach cell: the event's eq. 11 l_k bar / the knot's own length (L = 1 m, mu = 0.1).\n\n| n |",
    );
    for r in &ratios {
        write!(doc, " L/h {r:.1} |")?;
    }
    writeln!(doc, "\n|---|{}", "---|".repeat(ratios.len()))?;
    for &n in &ns {
        write!(doc, "| {n} |")?;
        for r in &ratios {
            let cell = match points.iter().find(|p| p.n == n && p.ratio == *r) {
                Some(LengthPoint {
                    event: Some((l, own)),
                    ..
                }) => format!("{l:.2} / {own:.2}"),
                Some(p) => format!("none (own length {:.1} at the stop)", p.stopped_at),
                None => String::new(),
            };
            write!(doc, " {cell} |")?;
        }
        writeln!(doc)?;
    }
    write!(
        doc,
        "\nEach cell: CPU over the paper's rod of the same n (its L/h 625 case), restarts.\n\n| n |"
    )?;
    for r in &ratios {
        write!(doc, " L/h {r:.1} |")?;
    }
    writeln!(doc, "\n|---|{}", "---|".repeat(ratios.len()))?;
    for &n in &ns {
        write!(doc, "| {n} |")?;
        let unit = points
            .iter()
            .find(|p| p.n == n && (p.ratio - 625.0).abs() < 1e-6)
            .map(|p| p.cpu);
        for r in &ratios {
            let cell = match (points.iter().find(|p| p.n == n && p.ratio == *r), unit) {
                (Some(p), Some(u)) => format!("{:.1}x, {}", p.cpu / u, p.restarts),
                _ => String::new(),
            };
            write!(doc, " {cell} |")?;
        }
        writeln!(doc)?;
    }
    Ok(doc)
}

/// The `lengths` figure: for each n the knot's own length (solid) and eq.
/// 11's l_k bar (dashed) at the event against L/h, log-log, with Fig. 7's h
/// sweep (n = 3, L = 1 m, h 1.6 ... 3.2 mm) marked.
fn lengths_svg(points: &[LengthPoint]) -> Result<String> {
    use plotters::style::{Color, RGBColor};
    use report::charts::{LegendAt, Plot, Series, Style, plots_svg};
    const COLOURS: [RGBColor; 4] = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
    ];
    let mut ns: Vec<u32> = points.iter().map(|p| p.n).collect();
    ns.sort_unstable();
    ns.dedup();
    let curve = |n: u32, pick: fn(&(f64, f64)) -> f64, at_most: f64| -> Vec<(f64, f64)> {
        let mut v: Vec<(f64, f64)> = (points.iter())
            .filter(|p| p.n == n && p.ratio <= at_most)
            .filter_map(|p| p.event.as_ref().map(|e| (p.ratio, pick(e))))
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        v
    };
    let mut series = Vec::new();
    for (i, &n) in ns.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()].to_rgba();
        series.push(Series {
            label: format!("n = {n}, own length"),
            points: curve(n, |e| e.1, f64::INFINITY),
            colour,
            style: Style::LineDots,
        });
        series.push(Series {
            label: format!("n = {n}, eq. 11 l_k bar"),
            points: curve(n, |e| e.0, f64::INFINITY),
            colour,
            style: Style::Dashed,
        });
    }
    let fig7: Vec<(f64, f64)> = [|e: &(f64, f64)| e.1, |e: &(f64, f64)| e.0]
        .into_iter()
        .flat_map(|pick| curve(3, pick, 625.0 + 1e-6))
        .collect();
    series.push(Series {
        label: "Fig. 7's h sweep (n = 3, h 3.2 ... 1.6 mm)".into(),
        points: fig7,
        colour: RGBColor(0, 0, 0).to_rgba(),
        style: Style::Dots { filled: false },
    });
    let stopped: Vec<String> = (points.iter())
        .filter(|p| p.event.is_none())
        .map(|p| format!("n = {} at {:.0}", p.n, p.ratio))
        .collect();
    let plot = Plot {
        title: "The inversion against the slenderness (rubber, L = 1 m, mu = 0.1)".into(),
        caption: if stopped.is_empty() {
            String::new()
        } else {
            format!("No inversion (L/h): {}", stopped.join(", "))
        },
        x_label: "L/h".into(),
        y_label: "at the event: l_k bar (eq. 11), (arc - l_c)/h".into(),
        series,
        log: true,
        markers: vec![(625.0, "the paper's rod".into())],
        legend: LegendAt::LowerRight,
        ..Plot::default()
    };
    plots_svg(&[plot], (900, 600))
}

/// The map (or its corners) as a table, each case's CPU against the paper's
/// rod of the same n measured in the same run; the corners of L/h at most
/// `reference_up_to` (and n at least `reference_from_n`) against the
/// reference pull too. Runs the paper's rods, then the corners, then the rest.
fn map(binary: &Path, name: &str, axes: &Axes, args: &Args, dir: &Path) -> Result<String> {
    let mut cases = axes.cases(name == "corners");
    cases.sort_by_key(|c| !axes.corner(c));
    let compared: Vec<usize> = (0..cases.len())
        .filter(|&i| {
            let c = &cases[i];
            axes.corner(c)
                && c.n >= args.reference_from_n
                && args.reference_up_to.is_some_and(|r| c.ratio <= r)
        })
        .collect();
    let mut ns: Vec<u32> = cases.iter().map(|c| c.n).collect();
    ns.sort_unstable();
    ns.dedup();
    let mut rods: Vec<Rod> = ns
        .iter()
        .map(|n| rod(&format!("the paper's rod, n = {n}"), &format!("--n {n}")))
        .collect();
    let corners = cases.iter().filter(|c| axes.corner(c)).count();
    for c in &cases[..corners] {
        rods.push(Rod {
            label: c.label(),
            flags: c.flags(false),
        });
    }
    for &i in &compared {
        rods.push(Rod {
            label: format!("{}, reference pull", cases[i].label()),
            flags: cases[i].flags(true),
        });
    }
    for c in &cases[corners..] {
        rods.push(Rod {
            label: c.label(),
            flags: c.flags(false),
        });
    }
    let measured = run_all(binary, &rods, args.jobs.max(1), dir, args.resume)?;
    let (units, rest) = measured.split_at(ns.len());
    let (corner_runs, rest) = rest.split_at(corners);
    let (references, others) = rest.split_at(compared.len());
    let adaptive: Vec<&Measured> = corner_runs.iter().chain(others).collect();
    let mut doc = String::new();
    let list = |v: Vec<String>| v.join(",");
    let mut command = format!(
        "cargo run --release -p xtask -- bench-rods --table {name} --ratios {} --ns {} --mus {}",
        list(axes.ratios.iter().map(f64::to_string).collect()),
        list(axes.ns.iter().map(u32::to_string).collect()),
        list(axes.mus.iter().map(f64::to_string).collect()),
    );
    if let Some(r) = args.reference_up_to {
        write!(command, " --reference-up-to {r}")?;
        if args.reference_from_n > 0 {
            write!(command, " --reference-from-n {}", args.reference_from_n)?;
        }
    }
    writeln!(doc, "\n### {name}\n\n`{command}`\n")?;
    writeln!(
        doc,
        "| the paper's rod | steps | restarts | CPU (s) | event l_k bar | own length |"
    )?;
    writeln!(doc, "|---|---|---|---|---|---|")?;
    for (n, m) in ns.iter().zip(units) {
        let (l_k, own) = event_lengths(&m.report);
        writeln!(
            doc,
            "| n = {n} | {} | {} | {:.2} | {l_k} | {own} |",
            m.report["stats"]["steps"], m.report["stats"]["restarts"], m.cpu
        )?;
    }
    writeln!(
        doc,
        "\n| rod | L/h | n | mu | status | K | event l_k bar | own length | clean | steps | restarts | CPU (s) | \
         CPU / paper's n | reference l_k bar | deviation | reference own length | own deviation | steps by phase |"
    )?;
    writeln!(
        doc,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    )?;
    let (mut worst_restarts, mut worst_cost, mut worst_deviation, mut worst_own) =
        (0, 0.0f64, 0.0f64, 0.0f64);
    let (mut none, mut unclean, mut both_none) = (0, 0, 0);
    for (i, (c, m)) in cases.iter().zip(adaptive).enumerate() {
        let r = &m.report;
        let unit = units[ns.iter().position(|n| *n == c.n).expect("a unit per n")].cpu;
        let (l_k, own) = event_lengths(r);
        let event = r["events"].get(0);
        let clean = event.map_or("-", |e| if e["clean"] == true { "yes" } else { "no" });
        none += usize::from(event.is_none());
        unclean += usize::from(clean == "no");
        // One stage per case: its restarts are those of its event.
        let restarts = r["stats"]["restarts"].as_u64().unwrap_or(0);
        worst_restarts = worst_restarts.max(restarts);
        worst_cost = worst_cost.max(m.cpu / unit);
        let reference = compared.iter().position(|&j| j == i).map(|k| &references[k]);
        // The reference's event and the deviation from it in `key`: eq. 11's
        // l_k bar or the knot's own length.
        let against = |key: &str| match reference {
            Some(reference) => {
                let ours = r["inversion"][key].as_f64();
                let theirs = reference.report["inversion"][key].as_f64();
                let deviation = ours.zip(theirs).map(|(a, b)| (a - b).abs() / b.abs());
                let text = match (deviation, ours, theirs) {
                    (Some(d), ..) => format!("{:.2} %", 100.0 * d),
                    (None, None, None) => "none either".to_string(),
                    _ => "one none".to_string(),
                };
                let both = ours.is_none() && theirs.is_none();
                (
                    theirs.map_or("none".to_string(), |l| format!("{l:.2}")),
                    text,
                    deviation,
                    both,
                )
            }
            None => ("-".to_string(), "-".to_string(), None, false),
        };
        let (ref_l_k, deviation, d, both) = against("l_k_bar");
        worst_deviation = worst_deviation.max(d.unwrap_or(0.0));
        both_none += usize::from(both);
        let (ref_own, own_deviation, d_own, _) = against("l_k_arc_bar");
        worst_own = worst_own.max(d_own.unwrap_or(0.0));
        writeln!(
            doc,
            "| {} | {:.0} | {} | {} | {} | {} | {l_k} | {own} | {clean} | {} | {restarts} | {:.2} | {:.1}x | {ref_l_k} | \
             {deviation} | {ref_own} | {own_deviation} | {} |",
            MAP_MATERIALS[c.material].0,
            c.ratio,
            c.n,
            c.mu,
            r["status"].as_str().unwrap_or("?"),
            r["params"]["nodes"],
            r["stats"]["steps"],
            m.cpu,
            m.cpu / unit,
            phase_steps(r),
        )?;
    }
    writeln!(
        doc,
        "\n{} cases: at most {worst_restarts} restarts, at most {worst_cost:.1} times the paper's rod of \
         the same n, {none} without an event, {unclean} not clean{}.",
        cases.len(),
        if compared.is_empty() {
            String::new()
        } else {
            format!(
                "; on the {} corners compared, the adaptive pull's inversion at most {:.2} % from the reference \
                 pull's in eq. 11's l_k bar, {:.2} % in the knot's own length ({both_none} without one under \
                 either)",
                compared.len(),
                100.0 * worst_deviation,
                100.0 * worst_own
            )
        }
    )?;
    Ok(doc)
}

/// The first event's eq. 11 l_k bar and the knot's own length, as text.
fn event_lengths(report: &Value) -> (String, String) {
    let event = report["events"].get(0);
    let text = |key: &str| {
        event
            .and_then(|e| e[key].as_f64())
            .map_or("none".to_string(), |l| format!("{l:.2}"))
    };
    (text("l_k_bar"), text("l_k_arc_bar"))
}

/// Runs every rod, `jobs` at a time, in order (with `resume`, reading back
/// those measured in `dir` already).
fn run_all(binary: &Path, rods: &[Rod], jobs: usize, dir: &Path, resume: bool) -> Result<Vec<Measured>> {
    std::fs::create_dir_all(dir)?;
    let mut results: Vec<Option<Measured>> = (0..rods.len()).map(|_| None).collect();
    for (chunk_start, chunk) in rods.chunks(jobs).enumerate().map(|(i, c)| (i * jobs, c)) {
        let outcomes: Vec<Result<Measured>> = std::thread::scope(|s| {
            let handles: Vec<_> = chunk
                .iter()
                .map(|r| {
                    let out = report_file(dir, &r.flags);
                    s.spawn(move || measure(binary, &r.flags, &out, resume))
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("a measuring thread panicked"))
                .collect()
        });
        for (i, outcome) in outcomes.into_iter().enumerate() {
            let m = outcome?;
            eprintln!("{}: {:.1} s", rods[chunk_start + i].label, m.cpu);
            results[chunk_start + i] = Some(m);
        }
    }
    Ok(results
        .into_iter()
        .map(|m| m.expect("every rod measured"))
        .collect())
}
