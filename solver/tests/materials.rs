//! Any rod: a knot's inversion is the same in the units of eq. (11) whatever
//! E and rho, at the same cost (the paper's Sec. 4: "the influence of Young's
//! modulus is ignorable"); the cost follows the slenderness, not the
//! material. On the coarsest n = 3 mesh (K = 158), stopped soon after the start.
use solver::case::CaseParams;
use solver::protocol::{self, CaseReport, Status};

fn run(params: CaseParams) -> CaseReport {
    let report = protocol::run(
        &CaseParams {
            nodes: Some(158),
            min_l_k_bar: 400.0,
            ..params
        },
        &mut |_| true,
    );
    assert_eq!(report.status, Status::Completed, "{}", report.reason);
    report
}

/// Steel, a soft gel and the paper's rubber, each pulled at its own paper's
/// rate (the default) or steel at 3 mm/s with its inertia scaled: the same
/// series in eq. (11)'s units, step for step.
#[test]
fn every_material_gives_the_papers_rods_series() {
    let rubber = run(CaseParams::default());
    for (e, rho, speed) in [
        (2e11, 7850.0, None),
        (1e4, 8000.0, None),
        (2e11, 7850.0, Some(3e-3)),
    ] {
        let other = run(CaseParams {
            youngs_modulus: e,
            density: rho,
            pull_speed: speed,
            ..CaseParams::default()
        });
        assert_eq!(other.stats.steps, rubber.stats.steps, "E {e} rho {rho}");
        for (a, b) in rubber.series.iter().zip(&other.series) {
            assert!(
                (a.l_k_bar - b.l_k_bar).abs() < 1e-9 * a.l_k_bar,
                "E {e} rho {rho}"
            );
            assert!(
                (a.f_bar - b.f_bar).abs() < 1e-6 * a.f_bar.abs().max(1e-3),
                "E {e} rho {rho}"
            );
        }
        let scaling = other.scaling.unwrap();
        let paper = solver::case::reference_pull_rate();
        assert!((scaling.simulated_pull_rate / paper - 1.0).abs() < 1e-9);
        assert_eq!(scaling.mass_scale > 1.0, speed.is_some());
    }
}

/// A pull far faster than the rod's waves allow is computed with its
/// physical inertia and reported as not quasi-static.
#[test]
fn a_pull_too_fast_for_the_rod_says_so() {
    let fast = run(CaseParams {
        pull_speed: Some(0.5),
        ..CaseParams::default()
    });
    let quasi = fast.quasi_static.expect("measured");
    assert!(!quasi.holds, "{quasi:?}");
    assert!(run(CaseParams::default()).quasi_static.unwrap().holds);
}

/// The default node count and the knot follow the slenderness: a rod four
/// times thinner gets edges of at most 2.08 h and starts at the paper's
/// l_k bar.
#[test]
fn a_thin_rods_knot_is_the_papers_in_radii() {
    let thin = CaseParams {
        h: 4e-4,
        ..CaseParams::default()
    };
    assert_eq!(thin.node_count(), 1201);
    let paper = CaseParams::default().validated().unwrap();
    let case = thin.validated().unwrap();
    let l_k_bar = |c: &solver::case::ValidCase| {
        let p = c.start().points();
        (c.params().length - (p[p.len() - 1] - p[0]).norm()) / c.params().h
    };
    assert!(
        (l_k_bar(&case) - l_k_bar(&paper)).abs() < 0.01,
        "{} against {}",
        l_k_bar(&case),
        l_k_bar(&paper)
    );
    assert_eq!(case.params().nodes, Some(1201));
}
