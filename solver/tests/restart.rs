//! A tool restarts from its own output: the relaxed snapshot a case reports
//! is a valid start shape (its strands pressed together within
//! `knot::START_OVERLAP` of 2h), and a case started from it validates and runs.
use solver::case::CaseParams;
use solver::protocol::{self, Status};

#[test]
fn a_relaxed_snapshot_starts_a_case_again() {
    // The paper's n = 3 knot on a 3.4 mm rod (Fig. 11's), pulled a little past its start.
    let params = CaseParams {
        h: 3.4e-3,
        mu: 0.3,
        min_l_k_bar: 200.0,
        ..CaseParams::default()
    };
    let report = protocol::run(&params, &mut |_| true);
    assert_eq!(report.status, Status::Completed, "{}", report.reason);
    let relaxed = report
        .snapshots
        .iter()
        .find(|s| s.label == solver::snapshot::SnapshotLabel::Relaxed)
        .expect("a relaxed snapshot");
    let again = CaseParams {
        initial_shape: Some(relaxed.points.clone().into()),
        ..params
    };
    if let Err(errors) = again.validated() {
        panic!("the relaxed snapshot is refused: {errors:?}");
    }
    let rerun = protocol::run(&again, &mut |_| true);
    assert_eq!(rerun.status, Status::Completed, "{}", rerun.reason);
}
