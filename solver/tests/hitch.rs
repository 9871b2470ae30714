//! The clove hitch on its rigid cylinder, through the whole case: tied,
//! set, its tail let go, pulled until tight or until it slips round the
//! cylinder; its holding force grows with friction.
use solver::case::{CaseParams, KnotKind};
use solver::protocol::{CaseReport, EventKind, Status};

fn hitch(mu: f64) -> CaseReport {
    let params = CaseParams {
        knot: KnotKind::CloveHitch,
        mu,
        ..CaseParams::default()
    };
    solver::protocol::run(&params, &mut |_| true)
}

/// At mu = 0.1, 0.3 and 0.5 the hitch completes (a slip is an outcome),
/// reports its cylinder, whether it still holds and its holding force,
/// which grows with mu; a slip's holding force is the largest F bar with
/// the tail free before it.
#[test]
fn the_clove_hitch_holds_more_with_more_friction() {
    let mut holding = Vec::new();
    for mu in [0.1, 0.3, 0.5] {
        let report = hitch(mu);
        assert_eq!(report.status, Status::Completed, "mu {mu}: {}", report.reason);
        let cylinder = report.cylinder.expect("the report carries the cylinder");
        assert_eq!(cylinder.radius, 10.0 * report.params.h);
        let force = report.holding_force_bar.expect("a holding force");
        let slipped = report.events.iter().any(|e| e.kind == EventKind::SlipThrough);
        assert_eq!(report.tied, Some(!slipped), "mu {mu}");
        let free_largest = (report.series.iter().zip(&report.bend_series))
            .filter(|(_, b)| b.tails_free)
            .map(|(s, _)| s.f_bar)
            .fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(force, free_largest, "mu {mu}");
        let released = report
            .bend_series
            .iter()
            .position(|b| b.tails_free)
            .expect("the tail let go");
        let last = report.series.len() - 1;
        println!(
            "clove hitch mu {mu}: holding force {force:.5}, {} at l_k bar {:.2} ({} samples after the tail was let \
             go at {:.2}), {} steps",
            if slipped { "slipped" } else { "held" },
            report.series[last].l_k_bar,
            last - released,
            report.series[released].l_k_bar,
            report.stats.steps
        );
        holding.push((force, slipped));
    }
    for pair in holding.windows(2) {
        let ((f0, slipped0), (f1, _)) = (pair[0], pair[1]);
        // A hitch that held to the tight force is a lower bound only.
        assert!(f1 > f0 || !slipped0, "holding forces {holding:?}");
    }
    assert!(holding[2].0 > holding[0].0, "holding forces {holding:?}");
}
