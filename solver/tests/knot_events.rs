//! Events of one-rod knots other than the overhand: read on the force, not
//! on the overhand's loop height H bar.
use solver::case::{CaseParams, KnotKind};
use solver::measurements::{InversionCriteria, Sample};
use solver::protocol::{self, EventKind, Status};

/// The figure-eight knot under the default adaptive pull (K = 301) through
/// l_k bar 254, where H bar, the overhand's loop measure, jumped as its
/// contacts moved between the lobes and was read as an inversion: H bar
/// still falls there to below `drop_fraction` of its largest within
/// `window` before (what the overhand's detector reads), yet no inversion
/// is reported, and any snap is a fall of the series' own F bar to
/// `drop_fraction` of its largest within `window` before.
#[test]
fn the_figure_eights_h_bar_jumps_are_no_inversions() {
    let params = CaseParams {
        knot: KnotKind::FigureEight,
        min_l_k_bar: 240.0,
        ..CaseParams::default()
    };
    let report = protocol::run(&params, &mut |_| true);
    assert_eq!(report.status, Status::Completed, "{}", report.reason);
    let criteria = InversionCriteria::default();
    let series = &report.series;
    let largest_before = |j: usize, value: fn(&Sample) -> f64| {
        (series[..j].iter().rev())
            .take_while(|s| s.l_k_bar - series[j].l_k_bar <= criteria.window)
            .map(value)
            .fold(0.0, f64::max)
    };
    let h_falls = (1..series.len())
        .filter(|&j| series[0].l_k_bar - series[j].l_k_bar >= criteria.window && series[j].width > 0.0)
        .any(|j| series[j].h_bar <= criteria.drop_fraction * largest_before(j, |s| s.h_bar));
    assert!(h_falls, "H bar falls as its contacts change lobes");
    assert!(report.inversion.is_none(), "{:?}", report.inversion);
    for event in &report.events {
        assert_eq!(event.kind, EventKind::Snap, "{event:?}");
        let j = event.at.sample + 1;
        let fell = (series[j..(j + 4).min(series.len())].iter())
            .any(|s| s.f_bar <= criteria.drop_fraction * largest_before(j, |s| s.f_bar));
        assert!(fell, "a snap is a fall of F bar: {event:?}");
    }
}
