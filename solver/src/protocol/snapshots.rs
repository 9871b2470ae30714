//! The snapshots a report keeps for viewers (the size budget: about 50 kB
//! each at K = 301): one every `SNAPSHOT_SPACING` in l_k bar along a stage,
//! and every `EVENT_SPACING` within `EVENT_WINDOW` either side of each
//! stage's event, so that a viewer steps through the snap. The stage detects
//! its events ([`super::events`]) and hands each one here when it is found.
use super::adaptive::Way;
use super::report::{Event, EventKind};
use super::runner::{Case, SNAPSHOT_HISTORY};
use crate::snapshot::{EventWhen, Snapshot, SnapshotLabel};

const SNAPSHOT_SPACING: f64 = 20.0;
const EVENT_SPACING: f64 = 2.0;
const EVENT_WINDOW: f64 = 10.0;

/// Where a stage's next snapshots are due.
#[derive(Clone, Debug)]
pub(super) struct SnapshotPlan {
    way: Way,
    next: f64,
    /// After the event: its kind, the next dense snapshot and where the dense
    /// ones stop.
    after_event: Option<(EventKind, f64, f64)>,
}

impl SnapshotPlan {
    pub(super) fn new(way: Way, start: f64) -> Self {
        Self {
            way,
            next: way.on(start, SNAPSHOT_SPACING),
            after_event: None,
        }
    }
}

impl Case<'_> {
    /// Keeps the sample's snapshot in the history; the snapshots around
    /// `found`, the stage's event found at this sample, and after it; and the
    /// stage's periodic ones.
    pub(super) fn keep_snapshots(&mut self, plan: &mut SnapshotPlan, found: Option<Event>, l_k_bar: f64) {
        let history = &mut self.carried.history;
        if history.len() == SNAPSHOT_HISTORY {
            history.pop_front();
        }
        history.push_back(Snapshot::capture(
            &self.world,
            SnapshotLabel::Sample,
            l_k_bar,
            self.clock.elapsed,
        ));
        let way = plan.way;
        if let Some(event) = found {
            self.event_snapshots(plan, event.kind, event.at.l_k_bar);
        } else if let Some((kind, next, end)) = plan.after_event {
            if way.reached(l_k_bar, next) && !way.past(l_k_bar, end) {
                self.report.snapshots.push(Snapshot::capture(
                    &self.world,
                    SnapshotLabel::Event(EventWhen::After, kind),
                    l_k_bar,
                    self.clock.elapsed,
                ));
                plan.after_event = Some((kind, way.on(l_k_bar, EVENT_SPACING), end));
            }
        }
        if way.reached(l_k_bar, plan.next) {
            let label = SnapshotLabel::Stage(self.program[self.stage].kind());
            self.report
                .snapshots
                .push(Snapshot::capture(&self.world, label, l_k_bar, self.clock.elapsed));
            plan.next = way.on(l_k_bar, SNAPSHOT_SPACING);
        }
    }

    /// The snapshots before a bend's slip, which parted its rods at
    /// `parted` (the last sample), labelled as the slip's: those of a snap
    /// within the window, the same parting seen as a fall of F bar, are
    /// taken again from the history under the slip's label.
    pub(super) fn slip_snapshots(&mut self, plan: &mut SnapshotPlan, parted: f64) {
        self.report.snapshots.retain(|f| {
            !(f.label.event() == Some(EventKind::Snap) && (f.l_k_bar - parted).abs() <= EVENT_WINDOW)
        });
        self.event_snapshots(plan, EventKind::SlipThrough, parted);
    }

    /// The snapshots either side of the event at `at`, taken from the
    /// history (the detection lags the event).
    fn event_snapshots(&mut self, plan: &mut SnapshotPlan, kind: EventKind, at: f64) {
        let way = plan.way;
        let mut stored: Vec<f64> = Vec::new();
        let mut offset = EVENT_WINDOW;
        while offset >= -EVENT_WINDOW {
            let when = if offset == 0.0 {
                EventWhen::At
            } else if offset == EVENT_SPACING {
                EventWhen::Before
            } else if offset > 0.0 {
                EventWhen::Near
            } else {
                EventWhen::After
            };
            let target = way.back(at, offset);
            let distance = |f: &Snapshot| (f.l_k_bar - target).abs();
            let nearest = (self.carried.history.iter())
                .filter(|f| offset > 0.0 || way.reached(f.l_k_bar, at))
                .min_by(|a, b| distance(a).total_cmp(&distance(b)));
            if let Some(f) = nearest.filter(|f| distance(f) < EVENT_SPACING / 2.0) {
                if !stored.contains(&f.l_k_bar) {
                    stored.push(f.l_k_bar);
                    self.report.snapshots.push(Snapshot {
                        label: SnapshotLabel::Event(when, kind),
                        ..f.clone()
                    });
                }
            }
            offset -= EVENT_SPACING;
        }
        let furthest = stored
            .iter()
            .copied()
            .fold(at, |a, b| if way.past(b, a) { b } else { a });
        plan.after_event = Some((kind, way.on(furthest, EVENT_SPACING), way.on(at, EVENT_WINDOW)));
    }
}
