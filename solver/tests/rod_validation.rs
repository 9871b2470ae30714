//! The rod-solver validation suite (the rows of `knotsweep validate`), asserted.
use solver::validation::{self, CaseResult};

fn assert_case(name: &str) {
    let case = validation::rod_cases()
        .into_iter()
        .find(|c| c.name == name)
        .expect("case exists");
    let rows: Vec<CaseResult> = (case.run)();
    assert!(!rows.is_empty());
    for r in &rows {
        assert!(
            r.pass,
            "{} failed: expected {:e}, got {:e}, error {:e} > {:e} ({})",
            r.case, r.expected, r.got, r.error, r.tolerance, r.quantity
        );
    }
}

#[test]
fn derivatives_match_finite_differences() {
    assert_case("derivatives");
}

#[test]
fn rigid_motions_change_nothing() {
    assert_case("rigid_motion");
}

#[test]
fn twisted_rod_matches_gj_phi_over_l() {
    assert_case("twist");
}

#[test]
fn clamped_column_buckles_at_euler_load() {
    assert_case("euler_buckling");
    let (_, _, deflection) = validation::statics::euler_buckling(101).expect("runs");
    // The 1e-4 L imperfection must have grown into a real buckle.
    assert!(deflection > 1e-2, "lateral deflection {deflection:e} L");
}

#[test]
fn cantilever_matches_beam_theory_and_elastica() {
    assert_case("cantilever");
}

#[test]
fn released_rod_loses_exactly_the_implicit_euler_dissipation() {
    assert_case("energy");
}
