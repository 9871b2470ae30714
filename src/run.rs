//! `knotsweep run`: one tightening case from the command line, with a progress
//! bar; writes the JSON report, optionally the series as CSV and SVG plots.
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use report::charts::{Quantity, case_chart};
use serde_json::Value;
use solver::case::{CaseParams, Group, InitialShape, PARAMETERS, Parameter, Range, ValidCase};
use solver::certify::Uncertainty;
use solver::protocol::{self, CaseReport, Status};
use std::path::PathBuf;

/// Case parameters as flags, one per entry of `solver::case::PARAMETERS`
/// (`--pull-speed` for `pull_speed`, its help the entry's description); a
/// flag left out takes the paper's default (`CaseParams::default`).
#[derive(Clone, Debug, Default)]
pub struct ParamFlags {
    /// The given flags as JSON values, by parameter name.
    given: serde_json::Map<String, Value>,
    /// `--initial-shape FILE`: the points are read from a file on the CLI.
    shape_file: Option<PathBuf>,
    /// `--material NAME`: a named material's E, rho and nu.
    material: Option<String>,
}

/// The flag naming a material of `solver::case::MATERIALS` (as `base.material` of a sweep).
const MATERIAL: &str = "material";

/// Whether the CLI reads parameter `p` from a file: the start shape's points.
fn from_file(p: &Parameter) -> bool {
    p.range == Range::Points
}

impl clap::FromArgMatches for ParamFlags {
    fn from_arg_matches(matches: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut flags = Self::default();
        flags.update_from_arg_matches(matches)?;
        Ok(flags)
    }

    fn update_from_arg_matches(&mut self, matches: &clap::ArgMatches) -> Result<(), clap::Error> {
        self.material = matches.get_one::<String>(MATERIAL).cloned();
        for p in PARAMETERS {
            if from_file(p) {
                self.shape_file = matches.get_one::<PathBuf>(p.name).cloned();
            } else if let Some(v) = matches.get_one::<Value>(p.name) {
                self.given.insert(p.name.to_string(), v.clone());
            }
        }
        Ok(())
    }
}

impl clap::Args for ParamFlags {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        let defaults = serde_json::to_value(CaseParams::default()).expect("params serialise");
        let mut grouped: Vec<&Parameter> = PARAMETERS.iter().collect();
        grouped.sort_by_key(|p| Group::ALL.iter().position(|g| *g == p.group));
        let names: Vec<&str> = solver::case::MATERIALS.iter().map(|m| m.name).collect();
        let material = clap::Arg::new(MATERIAL)
            .long(MATERIAL)
            .help_heading(Group::Rod.title())
            .value_parser(clap::builder::PossibleValuesParser::new(names))
            .help("A named material: sets --youngs-modulus, --density and --poisson-ratio to its constants");
        cmd.args(grouped.into_iter().map(|p| flag(p, &defaults[p.name])))
            .arg(material)
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

/// The flag of parameter `p`, parsed to the JSON type of its `default`.
fn flag(p: &Parameter, default: &Value) -> clap::Arg {
    let arg = clap::Arg::new(p.name)
        .long(p.name.replace('_', "-"))
        .help_heading(p.group.title());
    if from_file(p) {
        return arg
            .value_name("FILE")
            .value_parser(clap::value_parser!(PathBuf))
            .help(
                "Start from this knot instead of the builder's: a text file of K = nodes points `x y z` (m), \
                 one per line, comma or whitespace separated, extra columns ignored, `#` comments; or JSON as the \
                 API's initial_shape, for a bend {\"rods\": [{\"points\": [[x, y, z], ...], \"start\": \"pulled\", \
                 \"finish\": \"free\"}, ...]} (docs/API.md, \"Start shapes\")",
            );
    }
    if p.range == Range::Program {
        return arg
            .value_name("JSON|FILE")
            .help(p.description())
            .value_parser(program);
    }
    // A braid word is text, though null by default.
    let kind = match p.range {
        Range::BraidWord => Value::String(String::new()),
        _ => default.clone(),
    };
    let integer = matches!(p.range, Range::Integers(..));
    let words = match p.range {
        Range::Words(words) => words,
        _ => &[],
    };
    let nullable = p.null.is_some();
    arg.help(p.description())
        .allow_negative_numbers(true)
        .value_parser(move |text: &str| {
            if nullable && text == "null" {
                return Ok(Value::Null);
            }
            if !words.is_empty() && !words.contains(&text) {
                let known: Vec<String> = words.iter().map(|w| format!("{w:?}")).collect();
                return Err(format!("must be one of {}", known.join(", ")));
            }
            parse(&kind, integer, text)
        })
}

/// A loading program given inline as JSON, or the path of a file holding it.
fn program(text: &str) -> Result<Value, String> {
    let json = match std::fs::read_to_string(text) {
        Ok(file) => file,
        Err(_) if text.trim_start().starts_with('[') => text.to_string(),
        Err(e) => return Err(format!("neither a JSON list nor a readable file: {e}")),
    };
    let value: Value = serde_json::from_str(&json).map_err(|e| format!("not JSON: {e}"))?;
    serde_json::from_value::<Vec<solver::case::LoadStage>>(value.clone()).map_err(|e| e.to_string())?;
    Ok(value)
}

/// A flag's text as a JSON value of the type of the parameter's default
/// (integers where the range is, numbers where the default is null; `x,y,z`
/// for vectors).
fn parse(default: &Value, integer: bool, text: &str) -> Result<Value, String> {
    let number = |v: &str| {
        v.trim()
            .parse::<f64>()
            .map(Value::from)
            .map_err(|e| format!("{v:?}: {e}"))
    };
    match default {
        Value::Bool(_) => text.parse::<bool>().map(Value::Bool).map_err(|e| e.to_string()),
        _ if integer => text.parse::<u64>().map(Value::from).map_err(|e| e.to_string()),
        Value::String(_) => Ok(Value::String(text.to_string())),
        Value::Array(_) => text
            .split(',')
            .map(number)
            .collect::<Result<Vec<_>, _>>()
            .map(Value::Array),
        _ => number(text),
    }
}

impl ParamFlags {
    /// The case parameters: the given flags over the paper's defaults.
    pub fn params(&self) -> Result<CaseParams> {
        let mut given = self.given.clone();
        if let Some(m) = self.material.as_deref().and_then(solver::case::material) {
            for (name, value) in [
                ("youngs_modulus", m.youngs_modulus),
                ("density", m.density),
                ("poisson_ratio", m.poisson_ratio),
            ] {
                if given.insert(name.to_string(), Value::from(value)).is_some() {
                    anyhow::bail!(
                        "--material {} sets --{}: give one or the other",
                        m.name,
                        name.replace('_', "-")
                    );
                }
            }
        }
        let mut params: CaseParams = serde_json::from_value(Value::Object(given))?;
        if let Some(path) = &self.shape_file {
            let text =
                std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
            params.initial_shape =
                Some(read_shape(&text).with_context(|| format!("--initial-shape {}", path.display()))?);
        }
        Ok(params)
    }
}

/// A start shape from a file's text: JSON (`[[x, y, z], ...]`, or a bend's
/// `{"rods": [...]}`, as the API's `initial_shape`) when it opens with `[`
/// or `{`, else one rod's points as [`read_points`] reads them.
pub(crate) fn read_shape(text: &str) -> Result<InitialShape> {
    match text.trim_start().chars().next() {
        Some('[' | '{') => serde_json::from_str(text).context("initial_shape"),
        _ => Ok(read_points(text)?.into()),
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
    use super::{read_points, read_shape};
    use solver::case::{CaseParams, InitialShape, KnotKind};
    use solver::protocol;

    /// A reef knot's built shape written to a file as JSON (a bend's rods,
    /// standing ends pulled, tails free) and read back by `--initial-shape`
    /// is the same case: the same start, and a short run gives the same
    /// series, bit for bit, and the same events.
    #[test]
    fn a_bend_read_from_its_file_runs_as_built() {
        let params = CaseParams {
            knot: KnotKind::Reef,
            length: 0.4,
            nodes: Some(121),
            relax_time: Some(0.1),
            pull_speed: Some(0.01),
            min_l_k_bar: 100.0,
            ..CaseParams::default()
        };
        let built = params.validated().unwrap();
        let text = serde_json::to_string_pretty(&InitialShape::from(built.start())).unwrap();
        let from_file = CaseParams {
            initial_shape: Some(read_shape(&text).unwrap()),
            ..params
        }
        .validated()
        .unwrap();
        assert_eq!(from_file.start(), built.start());
        let [a, b] = [&built, &from_file].map(|case| protocol::run_valid(case, &mut |_| true));
        assert_eq!(
            (a.status, b.status),
            (protocol::Status::Completed, protocol::Status::Completed)
        );
        let bits = |r: &protocol::CaseReport| -> Vec<(u64, u64)> {
            (r.series.iter())
                .map(|s| (s.l_k_bar.to_bits(), s.f_bar.to_bits()))
                .collect()
        };
        assert!(!a.series.is_empty());
        assert_eq!(bits(&a), bits(&b));
        assert_eq!(a.events, b.events);
        assert_eq!((a.tied, a.holding_force_bar), (b.tied, b.holding_force_bar));
    }

    /// A nullable parameter's flag takes `null` (its help says what null
    /// means); another's does not.
    #[test]
    fn a_nullable_flag_takes_null() {
        use clap::{Args, FromArgMatches};
        let parse = |args: &[&str]| {
            let cmd = super::ParamFlags::augment_args(clap::Command::new("run"));
            let matches = cmd.try_get_matches_from(args.iter().copied())?;
            super::ParamFlags::from_arg_matches(&matches)
        };
        let flags = parse(&["run", "--stop-after-inversion", "null"]).unwrap();
        assert_eq!(flags.params().unwrap().stop_after_inversion, None);
        let flags = parse(&["run", "--stop-after-inversion", "4"]).unwrap();
        assert_eq!(flags.params().unwrap().stop_after_inversion, Some(4.0));
        assert!(parse(&["run", "--mu", "null"]).is_err());
    }

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
    pub(crate) params: ParamFlags,
    /// Write the JSON report here.
    #[arg(long, default_value = "case.json")]
    out: PathBuf,
    /// Write the series as CSV here.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Write plots of F bar and H bar against l_k bar (paper Fig. 5 a, b) into this directory, as SVG and PDF.
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Write the snapshots for ParaView into this directory: <out's stem>.pvd over one .vtp per snapshot and part
    /// (centre line, contacts); docs/PARAVIEW.md.
    #[arg(long, value_name = "DIR")]
    vtk: Option<PathBuf>,
    #[arg(long, help = certify_help())]
    certify: bool,
}

/// `--certify`'s help, with the threshold of `solver::certify`.
fn certify_help() -> String {
    format!(
        "Also run the refined twin (time step halved) on another core and report the inversion's numerical \
         uncertainty, |refined - default| (the report's `uncertainty`; flagged unconverged above {} %)",
        100.0 * solver::certify::CONVERGED_WITHIN
    )
}

pub fn run(args: Args) -> Result<()> {
    let params = args.params.params()?;
    let case = validated(&params)?;
    tracing::info!(n = params.n, h = params.h, mu = params.mu, "running case");
    let bar = ProgressBar::new(1000).with_style(
        ProgressStyle::with_template("{bar:40} {percent:>3}% {elapsed_precise} eta {eta} {msg}")
            .expect("valid template"),
    );
    let twin = match args.certify {
        true => Some(validated(&solver::certify::refined(&params))?),
        false => None,
    };
    let (report, twin) = rayon::join(
        || {
            protocol::run_valid(&case, &mut |p| {
                bar.set_position((p.fraction * 1000.0) as u64);
                bar.set_message(format!("l_k bar {:.1}  H bar {:.2}", p.l_k_bar, p.h_bar));
                true
            })
        },
        || twin.map(|t| protocol::run_valid(&t, &mut |_| true)),
    );
    bar.finish_and_clear();
    summarise(&report);
    let mut json = serde_json::to_value(&report)?;
    if let Some(twin) = &twin {
        let u = Uncertainty::new(report.inversion.as_ref(), Some(twin.inversion.as_ref()));
        summarise_uncertainty(&u, twin);
        json["uncertainty"] = serde_json::to_value(&u)?;
    }
    std::fs::write(&args.out, serde_json::to_string(&json)?)
        .with_context(|| format!("writing {}", args.out.display()))?;
    if let Some(path) = &args.csv {
        std::fs::write(path, solver::measurements::series_csv(&report.series))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(dir) = &args.plot {
        write_plots(&report, dir)?;
    }
    if let Some(dir) = &args.vtk {
        let name = args
            .out
            .file_stem()
            .map_or("case".into(), |s| s.to_string_lossy());
        write_vtk(&report, &name, dir)?;
    }
    if report.status != Status::Completed {
        anyhow::bail!("case ended with status {}: {}", report.status, report.reason);
    }
    Ok(())
}

/// The case to run, or every parameter error in one message.
pub fn validated(params: &CaseParams) -> Result<ValidCase> {
    params.validated().map_err(|errors| {
        let text: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
        anyhow::anyhow!("invalid parameters: {}", text.join("; "))
    })
}

/// F bar and H bar against l_k bar, with the events marked, as SVG and PDF.
fn write_plots(report: &CaseReport, dir: &std::path::Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for quantity in Quantity::ALL {
        let svg = case_chart(&report.params, &report.series, &report.events, quantity)?;
        crate::sweep::write_figure(dir, quantity.stem(), &svg)?;
    }
    Ok(())
}

/// The snapshots as ParaView files under `dir`: `{name}.pvd` and `{name}/*.vtp`.
fn write_vtk(report: &CaseReport, name: &str, dir: &std::path::Path) -> Result<()> {
    std::fs::create_dir_all(dir.join(name)).with_context(|| format!("creating {}", dir.display()))?;
    for file in report::vtk::case_files(name, report.params.h, &report.snapshots) {
        let path = dir.join(&file.path);
        std::fs::write(&path, file.text).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

fn summarise_uncertainty(u: &Uncertainty, twin: &CaseReport) {
    let unconverged = format!(
        ": UNCONVERGED (above {} %)",
        100.0 * solver::certify::CONVERGED_WITHIN
    );
    let refined = u
        .refined_l_k_bar
        .map_or("none".to_string(), |l| format!("{l:.2}"));
    match (u.absolute, u.relative) {
        (Some(a), Some(r)) => println!(
            "refined twin (dt {:.3e} s): inversion at l_k bar {refined}; uncertainty {a:.2} ({:.2} %){}",
            twin.params.time_step(),
            100.0 * r,
            if u.converged == Some(true) {
                ""
            } else {
                &unconverged
            }
        ),
        _ => println!(
            "refined twin (dt {:.3e} s, status {}): inversion {refined}{}",
            twin.params.time_step(),
            twin.status,
            if u.converged == Some(true) {
                ""
            } else {
                ": UNCONVERGED (the twin disagrees)"
            }
        ),
    }
}

fn summarise(report: &CaseReport) {
    println!("status: {} {}", report.status, report.reason);
    match &report.inversion {
        Some(inv) => {
            println!(
                "inversion at l_k bar {:.2} (l_c/L {:.4}; the knot's own length {:.2}), F bar {:.4} -> {:.4}, kinetic energy {:.1} times its median",
                inv.l_k_bar,
                inv.l_c_over_l,
                inv.l_k_arc_bar,
                inv.f_bar_before,
                inv.f_bar_after,
                inv.kinetic_energy_ratio
            );
            if inv.f_bar_after >= inv.f_bar_before {
                println!(
                    "note: F bar does not fall through this event; a kinetic energy tens of times its median marks a snap, 5-10 times a loop lying down under the pull (docs/FIDELITY.md)"
                );
            }
        }
        None => match report.series.last() {
            Some(last) => println!(
                "no inversion down to l_k bar {:.2} (the knot's own length {:.2})",
                last.l_k_bar, last.l_k_arc_bar
            ),
            None => println!("no inversion"),
        },
    }
    if let Some(q) = &report.quasi_static {
        if q.holds {
            println!(
                "quasi-static: kinetic/elastic energy {:.1e} (median while pulled at pull_speed; limit {:.0e})",
                q.kinetic_ratio, q.limit
            );
        } else {
            println!(
                "NOT QUASI-STATIC: kinetic/elastic energy {:.1e} above {:.0e} while pulled at pull_speed: the pull is too \
                 fast for this rod; a slower pull_speed gives the quasi-static inversion",
                q.kinetic_ratio, q.limit
            );
        }
    }
    if let Some(c) = &report.scaling {
        println!(
            "computed with K = {}, time step {:.3e} s, inertia x {:.3e} (mass scaling), time unit {:.3} of the paper's rod's, \
             pull rate {:.2e} (simulated {:.2e}; the paper's rod: {:.2e})",
            report.params.node_count(),
            c.time_step,
            c.mass_scale,
            c.time_unit,
            c.pull_rate,
            c.simulated_pull_rate,
            solver::case::reference_pull_rate()
        );
    }
    let s = &report.stats;
    println!(
        "{} steps ({} relaxing, {} restarts), {} Newton iterations, {} contact sweeps, {:.1} s wall (detection {:.1} s, contact {:.1} s, rods {:.1} s)",
        s.steps,
        s.relax_steps,
        s.restarts,
        s.newton_iterations,
        s.contact_sweeps,
        s.wall_time,
        s.detection_time,
        s.contact_time,
        s.dynamics_time
    );
    let phases: Vec<String> = report
        .phases
        .iter()
        .map(|span| {
            let stage = span.stage.map_or(String::new(), |i| format!("stage {} ", i + 1));
            let outcome = span.outcome.map_or(String::new(), |o| format!(", {o}"));
            format!(
                "{stage}{} {:.1} -> {:.1} ({} steps, {} Newton iterations, {} sweeps{outcome})",
                span.phase,
                span.from_l_k_bar,
                span.to_l_k_bar,
                span.steps,
                span.newton_iterations,
                span.contact_sweeps
            )
        })
        .collect();
    println!("phases in l_k bar: {}", phases.join(", "));
    for e in &report.events {
        println!(
            "stage {} ({}): {} at l_k bar {:.2} (the knot's own length {:.2}), F bar {:.4} -> {:.4}, H bar {:.3} -> {:.3}{}",
            e.stage + 1,
            report.params.program()[e.stage].kind(),
            e.kind,
            e.at.l_k_bar,
            e.at.l_k_arc_bar,
            e.at.f_bar_before,
            e.at.f_bar_after,
            e.at.h_bar_before,
            e.at.h_bar_after,
            if e.clean { "" } else { " (not a clean snap)" }
        );
    }
    if let Some(h) = &report.hysteresis {
        println!(
            "hysteresis: inverts at l_k bar {:.2} tightening, flips back at {:.2} loosening: width {:.2}",
            h.inversion_l_k_bar, h.flip_back_l_k_bar, h.width
        );
    }
}
