//! `docs/VALIDATION.md` for `knotsweep reproduce`: the paper's Sec. 4 checks
//! with the full model as a markdown table of check, command, figure and
//! pass/fail, the studies around them, and the n sweep's F bar and H bar
//! charts (paper Fig. 8 a, b).
use crate::charts::{CaseCurve, Quantity, tightening_chart};
use crate::markdown::{left, right, table};
use anyhow::{Context, Result};
use serde_json::Value;
use solver::case::{CaseParams, PARAMETERS, Range};
use solver::protocol::{CaseReport, Status};
use std::fmt::Write;

/// A named case and the `knotsweep run` command that reproduces it.
pub struct Job {
    pub key: String,
    pub params: CaseParams,
    /// The file `--initial-shape` reads when the case starts from its own
    /// shape (`params.initial_shape`, written there by `knotsweep reproduce`).
    pub shape_file: Option<String>,
}

/// Largest random displacement of a start node in the perturbation study, over h.
pub const PERTURBATION: f64 = 0.1;

/// The `knotsweep run` command of a job: a flag for each parameter of the
/// table (`solver::case::PARAMETERS`, in its order) whose value differs from
/// the default, the start shape by its file.
pub fn command(job: &Job) -> String {
    let (mine, default) = (json(&job.params), json(&CaseParams::default()));
    let mut s = String::from("knotsweep run");
    for parameter in PARAMETERS {
        let flag = parameter.name.replace('_', "-");
        if parameter.range == Range::Points {
            if let Some(file) = &job.shape_file {
                write!(s, " --{flag} {file}").expect("writing to a String");
            }
            continue;
        }
        let value = &mine[parameter.name];
        if value != &default[parameter.name] && !value.is_null() {
            write!(s, " --{flag} {}", flag_text(value)).expect("writing to a String");
        }
    }
    s
}

fn json(p: &CaseParams) -> Value {
    serde_json::to_value(p).expect("case parameters serialise")
}

/// A value as the command line takes it: a word bare, a small or large
/// number in e-notation (1.6e-3), a list comma-separated.
fn flag_text(value: &Value) -> String {
    match value {
        Value::String(word) if word.contains(' ') => format!("\"{word}\""),
        Value::String(word) => word.clone(),
        Value::Number(n) if n.is_f64() => {
            let x = n.as_f64().expect("a number");
            if x == 0.0 || (1e-2..1e4).contains(&x.abs()) {
                x.to_string()
            } else {
                format!("{x:e}")
            }
        }
        Value::Array(items) => items.iter().map(flag_text).collect::<Vec<_>>().join(","),
        other => other.to_string(),
    }
}

/// A job and its report by key.
pub type Lookup<'a> = dyn Fn(&str) -> Option<(&'a Job, &'a CaseReport)> + 'a;

/// The job and report of `key`, or which is missing.
fn case<'a>(get: &Lookup<'a>, key: &str) -> Result<(&'a Job, &'a CaseReport)> {
    get(key).with_context(|| format!("case {key} missing"))
}

/// The inversion's l_k bar of a completed case.
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

/// Commands as code spans, joined.
fn commands<'a>(jobs: impl IntoIterator<Item = &'a Job>) -> String {
    jobs.into_iter()
        .map(|j| format!("`{}`", command(j)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// epsilon and phi of the sample before the snap.
fn braid_at_snap(r: &CaseReport) -> Option<(f64, f64)> {
    let i = r.inversion?;
    r.series.get(i.sample).map(|s| (s.epsilon, s.phi))
}

/// The spread (max - min) / mean of `values`, with their range.
fn spread(values: &[f64]) -> (f64, f64, f64) {
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    let (lo, hi) = (values.iter()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(*x), b.max(*x))
    });
    ((hi - lo) / mean, lo, hi)
}

/// The paper's braid at inversion (Sec. 5): epsilon = 0.7, phi = pi/3.
const PAPER_EPSILON: f64 = 0.7;
const PAPER_PHI: f64 = std::f64::consts::FRAC_PI_3;
/// How near "approximately" is taken to be, relative.
const BRAID_TOLERANCE: f64 = 0.2;
/// Fig. 7: the largest spread of the critical l_k bar over h that counts as
/// "nearly the same".
const H_SPREAD: f64 = 0.15;
/// A convergence refinement passes when it moves n = 3's inversion by at most this.
const CONVERGED: f64 = 0.03;
/// The n sweep: the Fig. 9 cases.
const N_KEYS: [&str; 4] = ["n2", "n3", "n4", "n5"];

/// One check of the table: what is checked, how to rerun it (code spans),
/// what came out and whether it passes.
struct Check {
    what: String,
    commands: String,
    figure: String,
    pass: bool,
}

/// `docs/VALIDATION.md`: the checks (pass or fail), the sensitivity and
/// perturbation studies and the comparison with the simplified model.
/// `fig7` and `fig11` are the keys of those presets' cases, in grid order;
/// `simplified` the simplified model's snap for n = 2 ... 5.
pub fn markdown(
    get: &Lookup,
    fig7: &[String],
    fig11: &[String],
    simplified: &[(u32, Option<f64>)],
) -> Result<String> {
    let mut checks = fig1_checks(get)?;
    checks.push(n1_check(get)?);
    checks.push(growth_check(get)?);
    checks.push(braid_check(get)?);
    checks.push(fig7_check(get, fig7)?);
    checks.push(fig11_check(get, fig11)?);
    checks.extend(convergence_checks(get)?);
    Ok([
        header(),
        checks_section(&checks),
        sensitivity_section(get)?,
        perturbation_section(get)?,
        simplified_section(get, simplified)?,
        figures_section(),
    ]
    .concat())
}

/// The title and the defaults every case starts from.
fn header() -> String {
    let d = CaseParams::default();
    format!(
        "# Validation: reproduction of the paper's Sec. 4\n\n\
         Regenerate with `cargo run --release -- reproduce` (writes this file, the SVG figures in `docs/validation/` \
         and the perturbation study's start shapes in `docs/validation/starts/`; `--raw DIR` keeps every case's JSON \
         report). Defaults: L = {} m, K = {}, E = {:e} Pa, nu = {}, rho = {} kg/m^3, time step {} ms ({}), pull \
         speed {} mm/s per clamp, mu = {}, h = {} mm, contact solve tolerance {:e}, friction at the {}, start twist \
         {} (`start_twist`), pull protocol `{}` (`solver::case::Protocol`; the checks below pull with `reference`, \
         the paper's protocol, as their commands say).\n\n",
        d.length,
        d.node_count(),
        d.youngs_modulus,
        d.poisson_ratio,
        d.density,
        d.time_step() * 1e3,
        if d.adaptive_dt {
            "the largest; adaptive, see `solver::time_step`; scaled with the square of the edge length, see `CaseParams::time_step`"
        } else {
            "constant"
        },
        d.clamp_speed() * 1e3,
        d.mu,
        d.h * 1e3,
        d.contact_tolerance,
        if d.rolling {
            "surfaces (rods roll)"
        } else {
            "centre lines"
        },
        d.start_twist
            .map_or("the paper's code's (linking number 2n)".to_string(), |t| format!(
                "{t} turns"
            )),
        d.protocol,
    )
}

/// The paper's Fig. 1 (experiments and its simulations, L = 1 m, h = 1.6 mm,
/// mu = 0.1): n = 3 open at l_c/L 0.78 and inverted at 0.79, n = 4 open at
/// 0.66 and inverted at 0.68; the acceptance ranges bracket them.
fn fig1_checks(get: &Lookup) -> Result<Vec<Check>> {
    let brackets = [
        (
            "n3",
            125.0,
            155.0,
            "open at l_c/L 0.78, inverted at 0.79: l_k bar 131-138; the paper's code: 148",
        ),
        (
            "n4",
            190.0,
            225.0,
            "open at 0.66, inverted at 0.68: l_k bar 200-212; the paper's code: 215",
        ),
    ];
    brackets
        .into_iter()
        .map(|(key, lo, hi, fig)| {
            let (j, r) = case(get, key)?;
            Ok(Check {
                what: format!(
                    "n = {}, h = 1.6 mm: inversion at l_k bar in [{lo}, {hi}] (paper Fig. 1: {fig})",
                    j.params.n
                ),
                commands: commands([j]),
                figure: describe(r),
                pass: inversion(r).is_some_and(|l| (lo..=hi).contains(&l)),
            })
        })
        .collect()
}

fn n1_check(get: &Lookup) -> Result<Check> {
    let (j, r) = case(get, "n1")?;
    Ok(Check {
        what: "n = 1: no inversion".into(),
        commands: commands([j]),
        figure: describe(r),
        pass: r.status == Status::Completed && r.inversion.is_none(),
    })
}

/// Fig. 9: the critical l_k bar grows with n.
fn growth_check(get: &Lookup) -> Result<Check> {
    let cases = N_KEYS.iter().map(|k| case(get, k)).collect::<Result<Vec<_>>>()?;
    let ns: Vec<Option<f64>> = cases.iter().map(|(_, r)| inversion(r)).collect();
    Ok(Check {
        what: "n = 2 ... 5 at h = 1.6 mm: critical l_k bar grows with n (paper Fig. 9)".into(),
        commands: commands(cases.iter().map(|(j, _)| *j)),
        figure: (cases.iter())
            .map(|(j, r)| format!("n{}: {}", j.params.n, describe(r)))
            .collect::<Vec<_>>()
            .join("; "),
        pass: ns.iter().all(Option::is_some) && ns.windows(2).all(|w| w[1] > w[0]),
    })
}

/// Sec. 5: the braid's shape before the snap.
fn braid_check(get: &Lookup) -> Result<Check> {
    let cases = N_KEYS.iter().map(|k| case(get, k)).collect::<Result<Vec<_>>>()?;
    let braids: Vec<(u32, Option<(f64, f64)>)> = (cases.iter())
        .map(|(j, r)| (j.params.n, braid_at_snap(r)))
        .collect();
    let near = |x: f64, paper: f64| (x - paper).abs() <= BRAID_TOLERANCE * paper;
    Ok(Check {
        what: format!(
            "n = 2 ... 5: the braid before the snap has epsilon = l_b / l_l and phi near the paper's {PAPER_EPSILON} and pi/3 (within {} %, Sec. 5)",
            100.0 * BRAID_TOLERANCE
        ),
        commands: format!(
            "{} (series columns epsilon, phi)",
            commands(cases.iter().map(|(j, _)| *j))
        ),
        figure: (braids.iter())
            .map(|(n, b)| match b {
                Some((e, p)) => format!("n{n}: epsilon {e:.2}, phi {:.0} deg", p.to_degrees()),
                None => format!("n{n}: -"),
            })
            .collect::<Vec<_>>()
            .join("; "),
        pass: (braids.iter())
            .all(|(_, b)| b.is_some_and(|(e, p)| near(e, PAPER_EPSILON) && near(p, PAPER_PHI))),
    })
}

/// Fig. 7: the critical l_k bar nearly independent of h.
fn fig7_check(get: &Lookup, keys: &[String]) -> Result<Check> {
    let hs: Vec<Option<f64>> = (keys.iter())
        .map(|k| case(get, k).map(|(_, r)| inversion(r)))
        .collect::<Result<_>>()?;
    let (figure, pass) = match hs.iter().copied().collect::<Option<Vec<f64>>>() {
        Some(v) => {
            let (spread, _, _) = spread(&v);
            (
                format!(
                    "{} ; spread (max - min)/mean = {:.1} %",
                    v.iter().map(|x| format!("{x:.1}")).collect::<Vec<_>>().join(", "),
                    100.0 * spread
                ),
                spread <= H_SPREAD,
            )
        }
        None => ("a case did not invert".into(), false),
    };
    Ok(Check {
        what: format!(
            "n = 3, h = 1.6 ... 3.2 mm: critical l_k bar nearly the same (spread <= {} %)",
            100.0 * H_SPREAD
        ),
        commands: "`knotsweep sweep --preset fig7 --set protocol=reference`".into(),
        figure,
        pass,
    })
}

/// Fig. 11: the critical l_k bar grows with mu, each event a snap.
fn fig11_check(get: &Lookup, keys: &[String]) -> Result<Check> {
    let reports: Vec<&CaseReport> = (keys.iter())
        .map(|k| case(get, k).map(|(_, r)| r))
        .collect::<Result<_>>()?;
    let mus: Vec<Option<f64>> = reports.iter().map(|r| inversion(r)).collect();
    let clean = (reports.iter()).all(|r| r.inversion.is_some_and(|i| i.f_bar_after < i.f_bar_before));
    let pass = clean
        && mus.iter().all(Option::is_some)
        && mus.windows(2).all(|w| w[1] >= w[0].map(|x| 0.98 * x))
        && mus.last().copied().flatten() >= mus[0].map(|x| 1.1 * x);
    Ok(Check {
        what: "n = 3, h = 3.4 mm, mu = 0.1 ... 0.7: critical l_k bar grows with mu (never falls by more than 2 % from one mu to the next, mu = 0.7 at least 10 % above mu = 0.1) with F bar falling through every snap (paper Fig. 11)".into(),
        commands: "`knotsweep sweep --preset fig11 --set protocol=reference`".into(),
        figure: (mus.iter())
            .map(|m| m.map_or("-".to_string(), |x| format!("{x:.1}")))
            .collect::<Vec<_>>()
            .join(", "),
        pass,
    })
}

/// Each refinement against the reference pull's n = 3.
fn convergence_checks(get: &Lookup) -> Result<Vec<Check>> {
    let base = inversion(case(get, "n3")?.1);
    let refinements = [
        ("dt_half", "largest dt halved"),
        ("dt_fixed", "constant dt (the paper's scheme)"),
        ("K401", "K = 401"),
        ("speed_half", "pull speed halved"),
        ("speed_1mm", "the paper's text's pull speed"),
        ("contact_tight", "contact solve 100 times tighter"),
        ("adaptive", "the adaptive pull protocol"),
    ];
    refinements
        .into_iter()
        .map(|(key, what)| {
            let (j, r) = case(get, key)?;
            let change = match (inversion(r), base) {
                (Some(a), Some(b)) => Some((a - b).abs() / b),
                _ => None,
            };
            let step = format!("{:.4}", j.params.time_step() * 1e3);
            Ok(Check {
                what: format!(
                    "convergence: {what} (step {} ms{}, {} mm/s), inversion within {} % of the reference pull's n = 3",
                    step.trim_end_matches('0').trim_end_matches('.'),
                    if j.params.adaptive_dt { " or less" } else { "" },
                    j.params.clamp_speed() * 1e3,
                    100.0 * CONVERGED
                ),
                commands: commands([j]),
                figure: format!(
                    "{} ; change {}",
                    describe(r),
                    change.map_or("-".into(), |c| format!("{:.2} %", 100.0 * c))
                ),
                pass: change.is_some_and(|c| c <= CONVERGED),
            })
        })
        .collect()
}

/// The checks as a table and the count of passes.
fn checks_section(checks: &[Check]) -> String {
    let passed = checks.iter().filter(|c| c.pass).count();
    let rows = checks.iter().map(|c| {
        [
            c.what.clone(),
            c.commands.clone(),
            c.figure.clone(),
            if c.pass { "yes" } else { "**no**" }.to_string(),
        ]
    });
    format!(
        "{}{passed} passed, {} failed\n\n",
        table(&left(&["check", "command", "figure", "pass"]), rows),
        checks.len() - passed
    )
}

/// A study's variant at n = 3 and n = 4: its description and the two cases' keys.
struct Variant {
    what: &'static str,
    n3: &'static str,
    n4: &'static str,
}

const fn variant(what: &'static str, n3: &'static str, n4: &'static str) -> Variant {
    Variant { what, n3, n4 }
}

/// Table rows of variants run at n = 3 and n = 4: both commands and both outcomes.
fn variant_table(get: &Lookup, variants: &[Variant]) -> Result<String> {
    let rows = variants
        .iter()
        .map(|v| {
            let ((j3, r3), (j4, r4)) = (case(get, v.n3)?, case(get, v.n4)?);
            Ok([v.what.to_string(), commands([j3, j4]), describe(r3), describe(r4)])
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(table(
        &left(&["variant", "commands (n = 3, n = 4)", "n = 3", "n = 4"]),
        rows,
    ))
}

/// What moves the n = 3 and n = 4 inversions (docs/FIDELITY.md).
fn sensitivity_section(get: &Lookup) -> Result<String> {
    let variants = [
        variant(
            "defaults (Coulomb friction at the centre lines, mu = 0.1, the paper's start twist)",
            "n3",
            "n4",
        ),
        variant("no start twist", "n3_untwisted", "n4_untwisted"),
        variant("friction at the surfaces: rods roll", "n3_rolling", "n4_rolling"),
        variant(
            "rods roll, no start twist (the model of physics revision 4, CHANGELOG.md)",
            "n3_rev4",
            "n4_rev4",
        ),
        variant("no friction (mu = 0)", "n3_mu0", "n4_mu0"),
        variant(
            "friction only along the previous sliding direction (fails the capstan check)",
            "n3_sliding",
            "n4_sliding",
        ),
        variant(
            "gravity 9.81 m/s^2 along -z, across the pull",
            "n3_gravity",
            "n4_gravity",
        ),
        variant(
            "the paper's contact between straight segments (the default before revision 17)",
            "n3_segment",
            "n4_segment",
        ),
        variant(
            "the paper's code's scheme: segment contact, its contact candidates and its constant 1 ms step",
            "n3_paper",
            "n4_paper",
        ),
    ];
    Ok(format!(
        "## Sensitivity of the n = 3 and n = 4 inversions\n\n\
         Not checks: what moves the inversion (docs/FIDELITY.md; the paper's Fig. 1: n = 3 at l_k bar 131-138, n = 4 \
         at 200-212; the paper's code: 148 and 215).\n\n{}",
        variant_table(get, &variants)?
    ))
}

/// The perturbation study: is the snap a fold (insensitive to small
/// perturbations) or a delayed symmetry breaking (sensitive)?
fn perturbation_section(get: &Lookup) -> Result<String> {
    let variants = [
        variant("none (defaults)", "n3", "n4"),
        variant("gravity along -z", "n3_gravity", "n4_gravity"),
        variant("gravity along +z", "n3_gravity_up", "n4_gravity_up"),
        variant("gravity along -y", "n3_gravity_y", "n4_gravity_y"),
        variant("random start, seed 1", "n3_seed1", "n4_seed1"),
        variant("random start, seed 2", "n3_seed2", "n4_seed2"),
        variant("random start, seed 3", "n3_seed3", "n4_seed3"),
    ];
    let mut text = format!(
        "## Perturbation study\n\n\
         The same cases with small perturbations that break the built knot's symmetry: gravity (9.81 m/s^2; the pull \
         is along x) and random start shapes (every node but the clamped ones moved by up to {PERTURBATION} h, uniform \
         in the ball, three seeds; the shapes are the files the commands name). A fold moves little under them; a \
         delayed symmetry breaking moves a lot.\n\n{}",
        variant_table(get, &variants)?
    );
    for n in [3, 4] {
        let keys = ["", "_seed1", "_seed2", "_seed3"].map(|s| format!("n{n}{s}"));
        let v: Option<Vec<f64>> = (keys.iter())
            .map(|k| get(k).and_then(|(_, r)| inversion(r)))
            .collect();
        if let Some(v) = v {
            let (spread, lo, hi) = spread(&v);
            writeln!(
                text,
                "n = {n}: the built and the three random starts invert at l_k bar {lo:.1} to {hi:.1} (spread {:.1} % of the mean).\n",
                100.0 * spread
            )?;
        }
    }
    Ok(text)
}

/// The full model's snap against the simplified model's (Sec. 5, Fig. 15),
/// with the braid the full model shows there.
fn simplified_section(get: &Lookup, simplified: &[(u32, Option<f64>)]) -> Result<String> {
    let fmt = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{x:.1}"));
    let rows = simplified
        .iter()
        .map(|&(n, snap)| {
            let r = case(get, &format!("n{n}"))?.1;
            let (full, braid) = (inversion(r), braid_at_snap(r));
            Ok([
                n.to_string(),
                fmt(full),
                fmt(snap),
                match (full, snap) {
                    (Some(a), Some(b)) => format!("{:.3}", a / b),
                    _ => "-".into(),
                },
                braid.map_or("-".into(), |b| format!("{:.2}", b.0)),
                braid.map_or("-".into(), |b| format!("{:.0}", b.1.to_degrees())),
            ])
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(format!(
        "## Full model against the simplified model (h = 1.6 mm, mu = 0.1)\n\n\
         The simplified model (Sec. 5; `knotsweep simplified`, docs/SIMPLIFIED_MODEL.md) holds epsilon = {PAPER_EPSILON} \
         and phi = pi/3; the paper's full model sits 0-11 % above it (Fig. 15). The last two columns are the full \
         model's braid just before its snap.\n\n{}",
        table(
            &right(&[
                "n",
                "full model l_k bar",
                "simplified model l_k bar",
                "full / simplified",
                "epsilon",
                "phi (deg)"
            ]),
            rows
        )
    ))
}

fn figures_section() -> String {
    "F bar and H bar against l_k bar for n = 1..4 (paper Fig. 8 a, b):\n\n\
     ![F bar](validation/n_sweep_F_bar.svg)\n![H bar](validation/n_sweep_H_bar.svg)\n"
        .to_string()
}

/// The n sweep's charts (paper Fig. 8 a, b) as (file name, SVG), the files
/// the markdown links under `validation/`.
pub fn n_sweep_figures(get: &Lookup) -> Result<Vec<(&'static str, String)>> {
    let mut figures = Vec::new();
    for (file, quantity, name) in [
        ("n_sweep_F_bar.svg", Quantity::FBar, "F̄"),
        ("n_sweep_H_bar.svg", Quantity::HBar, "H̄"),
    ] {
        let curves: Vec<CaseCurve> = ["n1", "n2", "n3", "n4"]
            .into_iter()
            .filter_map(get)
            .map(|(j, r)| CaseCurve::new(format!("n = {}", j.params.n), &j.params, &r.series, &[]))
            .collect();
        let svg = tightening_chart(
            &format!("{name} against l̄_k"),
            "held fixed: h = 1.6 mm, μ = 0.1",
            quantity,
            &curves,
            &[],
        )?;
        figures.push((file, svg));
    }
    Ok(figures)
}

#[cfg(test)]
mod tests {
    use super::{Job, command};
    use solver::case::{CaseParams, PARAMETERS, Protocol};

    fn job(params: CaseParams, shape_file: Option<&str>) -> Job {
        Job {
            key: "t".into(),
            params,
            shape_file: shape_file.map(str::to_string),
        }
    }

    #[test]
    fn the_command_names_every_changed_parameter_in_the_tables_order() {
        assert_eq!(command(&job(CaseParams::default(), None)), "knotsweep run");
        let p = CaseParams {
            n: 4,
            h: 3.4e-3,
            mu: 0.7,
            dt: Some(2.5e-4),
            adaptive_dt: false,
            protocol: Protocol::Reference,
            gravity: [0.0, 0.0, -9.81],
            ..CaseParams::default()
        };
        let flags = [
            "--n 4",
            "--h 3.4e-3",
            "--mu 0.7",
            "--protocol reference",
            "--dt 2.5e-4",
            "--adaptive-dt false",
            "--gravity 0,0,-9.81",
        ];
        let got = command(&job(p, None));
        for flag in flags {
            assert!(got.contains(&format!(" {flag}")), "{flag} in {got}");
        }
        assert_eq!(got.matches(" --").count(), flags.len(), "{got}");
        let order: Vec<usize> = (got.split(" --").skip(1))
            .map(|f| f.split(' ').next().unwrap().replace('-', "_"))
            .map(|name| PARAMETERS.iter().position(|p| p.name == name).unwrap())
            .collect();
        assert!(order.is_sorted(), "the table's order: {got}");
    }

    /// A start shape is named by its file, once, never by its points.
    #[test]
    fn a_start_shape_is_named_by_its_file() {
        let p = CaseParams {
            initial_shape: Some(vec![[0.0, 0.0, 0.0]; 301].into()),
            ..CaseParams::default()
        };
        assert_eq!(
            command(&job(p, Some("starts/n3_seed1.txt"))),
            "knotsweep run --initial-shape starts/n3_seed1.txt"
        );
    }
}
