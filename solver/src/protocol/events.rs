//! Events in a stage's own samples: the overhand knot's inversion while it
//! tightens ([`measurements::detect_inversion`], paper Fig. 5) and its loop
//! flipping back while it loosens ([`measurements::detect_flip_back`]); any
//! other knot's snap while it tightens ([`detect_snap`]) and a bend's or a
//! hitch's slip-through.
use super::adaptive::Way;
use super::report::{self, BendSample, Event, EventKind};
use crate::case::Direction;
use crate::measurements::{self, InversionCriteria, Reading, Sample};

/// The overhand knot's first event (read on H bar) in the stage `stage`
/// whose samples start at `first` in `series`, moving `way`, a tightening's
/// kinetic energy read from `quiet_from` on ([`measurements::detect_fall`]);
/// its sample index is the series'.
pub(super) fn detect(
    series: &[Sample],
    (first, quiet_from): (usize, usize),
    way: Way,
    criteria: &InversionCriteria,
    stage: usize,
) -> Option<Event> {
    let own = &series[first..];
    let quiet = quiet_from.saturating_sub(first);
    let (kind, direction, found) = if way.0 > 0.0 {
        (
            EventKind::Inversion,
            Direction::Tighten,
            measurements::detect_fall(own, criteria, Reading::LoopHeight, quiet),
        )
    } else {
        (
            EventKind::FlipBack,
            Direction::Loosen,
            measurements::detect_flip_back(own, criteria),
        )
    };
    let mut at = found?;
    at.sample += first;
    let clean = match kind {
        EventKind::Inversion => at.f_bar_after < at.f_bar_before,
        _ => at.kinetic_energy_ratio >= criteria.kinetic_energy_spike,
    };
    Some(Event {
        stage,
        direction,
        kind,
        at,
        clean,
        restarts: 0,
    })
}

/// The event as reported: an inversion where its snap began
/// ([`measurements::snap_onset`]; the stage's samples start at `first` in
/// `series`), other events as found. The adaptive schedule acts where the
/// detector fired (its windows are measured from there).
pub(super) fn reported(series: &[Sample], first: usize, criteria: &InversionCriteria, event: Event) -> Event {
    if event.kind != EventKind::Inversion {
        return event;
    }
    let own = &series[first..];
    let found = measurements::Inversion {
        sample: event.at.sample - first,
        ..event.at
    };
    let mut at = measurements::snap_onset(own, found, criteria);
    if at == found {
        return event;
    }
    at.sample += first;
    Event {
        at,
        clean: at.f_bar_after < at.f_bar_before,
        ..event
    }
}

/// The first snap of a tightening stage, a knot's other than the
/// overhand's, in the samples of `series` from `from` on (those the detector
/// watches, [`super::travel`]): [`measurements::detect_fall`] read on F bar,
/// which must fall to `drop_fraction` of its largest value within `window`
/// before with a burst of kinetic energy (`kinetic_energy_spike`); its
/// sample index is the series'.
pub(super) fn detect_snap(
    series: &[Sample],
    from: usize,
    criteria: &InversionCriteria,
    stage: usize,
) -> Option<Event> {
    let mut at = measurements::detect_fall(&series[from..], criteria, Reading::Force, 0)?;
    at.sample += from;
    Some(Event {
        stage,
        direction: Direction::Tighten,
        kind: EventKind::Snap,
        at,
        clean: true,
        restarts: 0,
    })
}

/// A bend's slip-through in the stage whose samples start at `first` in
/// `series`, the rods having parted at its last sample: its
/// [`report::holding_point`] (its holding force).
pub(super) fn slip_through(
    series: &[Sample],
    bend: &[BendSample],
    first: usize,
    stage: usize,
) -> Option<Event> {
    let (i, held) = report::holding_point(series, bend, first)?;
    let last = series[series.len() - 1];
    Some(Event {
        stage,
        direction: Direction::Tighten,
        kind: EventKind::SlipThrough,
        at: measurements::Inversion {
            l_k_bar: held.l_k_bar,
            l_k_arc_bar: held.l_k_arc_bar,
            l_c_over_l: held.l_c_over_l,
            f_bar_before: held.f_bar,
            f_bar_after: last.f_bar,
            h_bar_before: 0.0,
            h_bar_after: 0.0,
            kinetic_energy_ratio: 0.0,
            sample: i,
        },
        clean: true,
        restarts: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples every 0.5 in l_k bar along `way` from 300, H bar from `h`,
    /// the kinetic energy spiking where `spike` says.
    fn series(way: f64, h: impl Fn(f64) -> f64, spike: impl Fn(f64) -> bool) -> Vec<Sample> {
        (0..80)
            .map(|i| 300.0 - way * 0.5 * f64::from(i))
            .map(|l_k_bar| Sample {
                l_k_bar,
                h_bar: h(l_k_bar),
                width: 1.0,
                f_bar: 0.05,
                kinetic_energy: if spike(l_k_bar) { 100.0 } else { 1.0 },
                ..Sample::default()
            })
            .collect()
    }

    /// A loop lying low (H bar 0.1) that stands up to 0.3 at l_k bar 320
    /// while the knot loosens flips back there; the tightening detector does
    /// not take a rise for an inversion, nor the loosening one a fall.
    #[test]
    fn a_loop_standing_up_while_loosening_flips_back() {
        let criteria = InversionCriteria::default();
        let rising = series(
            -1.0,
            |l| if l < 320.0 { 0.1 } else { 0.3 },
            |l| (320.0..322.0).contains(&l),
        );
        let event = detect(&rising, (0, 0), Way(-1.0), &criteria, 2).expect("a flip back");
        assert_eq!(
            (event.kind, event.direction, event.stage),
            (EventKind::FlipBack, Direction::Loosen, 2)
        );
        assert_eq!(event.at.l_k_bar, 319.5);
        assert!(event.clean);
        assert_eq!(detect(&rising, (0, 0), Way(1.0), &criteria, 2), None);
        let falling = series(-1.0, |l| if l < 320.0 { 0.3 } else { 0.1 }, |_| false);
        assert_eq!(detect(&falling, (0, 0), Way(-1.0), &criteria, 2), None);
    }

    /// An inversion that the detector reads a sample into its snap (H bar
    /// 0.3 to 0.19, above 0.6 of 0.3, then to 0.15) is reported at its
    /// onset, indexed in the series; a flip back is reported as found.
    #[test]
    fn an_inversion_is_reported_where_its_snap_began() {
        let criteria = InversionCriteria::default();
        let mut all = series(-1.0, |_| 0.1, |_| false);
        let first = all.len();
        all.extend(series(
            1.0,
            |l| match l {
                l if l > 280.25 => 0.3,
                l if l > 279.75 => 0.19,
                _ => 0.15,
            },
            |l| (279.0..281.0).contains(&l),
        ));
        let found = detect(&all, (first, first), Way(1.0), &criteria, 1).expect("an inversion");
        assert_eq!((found.at.l_k_bar, found.at.sample), (280.0, first + 40));
        let onset = reported(&all, first, &criteria, found);
        assert_eq!((onset.at.l_k_bar, onset.at.sample), (280.5, first + 39));
        assert_eq!((onset.at.h_bar_before, onset.at.h_bar_after), (0.3, 0.19));
        let rising = series(
            -1.0,
            |l| if l < 320.0 { 0.1 } else { 0.3 },
            |l| (320.0..322.0).contains(&l),
        );
        let back = detect(&rising, (0, 0), Way(-1.0), &criteria, 2).expect("a flip back");
        assert_eq!(reported(&rising, 0, &criteria, back), back);
    }

    /// A stage's event is found in its own samples, indexed in the series.
    #[test]
    fn events_are_found_in_the_stages_own_samples() {
        let criteria = InversionCriteria::default();
        let mut all = series(
            1.0,
            |l| if l > 280.0 { 0.3 } else { 0.05 },
            |l| (279.0..281.0).contains(&l),
        );
        let first = all.len();
        all.extend(series(
            -1.0,
            |l| if l < 320.0 { 0.1 } else { 0.3 },
            |l| (320.0..322.0).contains(&l),
        ));
        let inversion = detect(&all, (0, 0), Way(1.0), &criteria, 0).unwrap();
        assert_eq!(inversion.kind, EventKind::Inversion);
        let back = detect(&all, (first, first), Way(-1.0), &criteria, 1).unwrap();
        assert_eq!(
            back.at.sample,
            first + 39,
            "l_k bar 319.5 (before the rise) is the release's 40th sample"
        );
    }

    /// A knot's snap is read on F bar from `from` on: a fall of F bar (0.05
    /// to 0.02 at l_k bar 280) with a burst of kinetic energy is a snap with
    /// the force's fall and no H bar; the same fall without the burst, or H
    /// bar falling while F bar holds, is none, and so is the fall for a
    /// detector watching from its foot on.
    #[test]
    fn a_snap_is_a_fall_of_the_force_with_a_burst() {
        let criteria = InversionCriteria::default();
        let force = |spike: fn(f64) -> bool| {
            let mut all = series(1.0, |l| if l > 280.0 { 0.3 } else { 0.05 }, spike);
            for s in &mut all {
                s.f_bar = if s.l_k_bar > 280.0 { 0.05 } else { 0.02 };
            }
            all
        };
        let bursting = force(|l| (279.0..281.0).contains(&l));
        let snap = detect_snap(&bursting, 0, &criteria, 3).expect("a snap");
        assert_eq!(
            (snap.kind, snap.direction, snap.stage),
            (EventKind::Snap, Direction::Tighten, 3)
        );
        assert_eq!((snap.at.l_k_bar, snap.at.sample), (280.5, 39));
        assert_eq!((snap.at.f_bar_before, snap.at.f_bar_after), (0.05, 0.02));
        assert_eq!((snap.at.h_bar_before, snap.at.h_bar_after), (0.0, 0.0));
        assert_eq!(detect_snap(&force(|_| false), 0, &criteria, 3), None);
        assert_eq!(detect_snap(&bursting, 40, &criteria, 3), None);
        let loop_only = series(
            1.0,
            |l| if l > 280.0 { 0.3 } else { 0.05 },
            |l| (279.0..281.0).contains(&l),
        );
        assert_eq!(detect_snap(&loop_only, 0, &criteria, 3), None);
    }
}
