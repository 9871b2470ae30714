//! A stage that moves the clamps along the pull: a pull (tightening), a
//! release (loosening) or a soft stage (the grips moving, the clamps on
//! springs). Samples every `sample_interval` in l_k bar (the clamps' travel);
//! stops where the knot's own length l_k arc bar reaches the stage's target or
//! the stopping rules (a rod longer than its knot stops where the paper's rod
//! would, its tails' stretch aside); events are detected in the stage's own
//! samples; a tightening also stops at its force
//! ([`crate::case::CaseParams::tight_force_bar`]); the adaptive schedule
//! ([`super::adaptive`]) runs pulls and releases fast far from them.
use super::adaptive::{
    self, Back, Checkpoints, END_REVIEW, FALSE_ALARM, LET_GO, MAX_RESTARTS, MIN_LEAD, Outcome, Phase,
    SET_LEAD, SETTLE_TIME, SLOW_AFTER, Way,
};
use super::events;
use super::report::{self, Event, EventKind};
use super::runner::{Carried, Case, Ending, Observer, Tails};
use super::snapshots::SnapshotPlan;
use crate::case::{Direction, KnotKind, LoadStage};
use crate::pipeline::World;
use crate::rod::{End, Spring, node_dof};
use crate::time_step::TimeStep;

/// Where a stage stands between samples, kept in checkpoints.
#[derive(Clone)]
pub(super) struct Travel {
    way: Way,
    /// The series index of the stage's first sample.
    first_sample: usize,
    next_sample: f64,
    snapshots: SnapshotPlan,
    phase: Phase,
    /// l_k bar where `phase` began (its speed ramps from there), and the
    /// knot's own length there.
    phase_start: f64,
    phase_start_arc: f64,
    /// The series index of the sample of the checkpoint the stage last went
    /// back to (its state before the settle).
    restored_at: Option<usize>,
    /// Where (the knot's own length) the fast approach saw the event that
    /// the slow phase is resolving.
    fast_event: Option<f64>,
    /// The stage's first event.
    event: Option<Event>,
    /// The stage's end has been redone slowly (`review_end`).
    reviewed: bool,
    /// The series index from which the fast approach watches for a smeared
    /// snap: past a fall the slow phase refuted.
    watch_from: usize,
    /// Restarts the stage has taken (carried over a restore).
    restarts: u32,
    /// The slow phase pulls a bend or a hitch from before it was set through
    /// its holding point, which the fast approach slid past, to where the
    /// rods part or the stage ends: the fast pull neither reads the holding
    /// force nor parts the rods where the reference pull does (the reef at
    /// mu = 0.3, K = 301, slid on to l_k bar 60 still tied).
    reads_hold: bool,
}

/// The state a fast approach can return to.
pub(super) struct Checkpoint {
    world: World,
    clock: TimeStep,
    carried: Carried,
    travel: Travel,
    series: usize,
    snapshots: usize,
    events: usize,
}

impl Case<'_> {
    /// Runs the current stage, a pull, release or soft stage, to its end.
    pub(super) fn travel(&mut self, stage: LoadStage, observer: &mut Observer) -> Result<(), Ending> {
        let soft = matches!(stage, LoadStage::Soft(_));
        let way = Way(if stage.direction() == Direction::Loosen {
            -1.0
        } else {
            1.0
        });
        let target = match stage {
            LoadStage::Release(t) => Some(t.to_l_k_bar.unwrap_or(self.program_start)),
            _ => stage.target(),
        };
        let phase = if adaptive::pulls_fast(self.params) && !soft {
            Phase::Approach
        } else {
            Phase::Reference
        };
        if let LoadStage::Soft(s) = stage {
            self.mount_springs(s.stiffness_bar);
        }
        let (start, start_arc) = (self.l_k_bar(), self.l_k_arc_bar());
        let first_sample = self.report.series.len();
        let mut travel = Travel {
            way,
            first_sample,
            next_sample: start,
            snapshots: SnapshotPlan::new(way, start),
            phase,
            phase_start: start,
            phase_start_arc: start_arc,
            restored_at: None,
            fast_event: None,
            event: None,
            reviewed: false,
            watch_from: first_sample,
            restarts: 0,
            reads_hold: false,
        };
        self.enter(&mut travel, phase);
        let mut saved = Checkpoints::new(start);
        let ending = loop {
            let (step, dt) = self.step(travel.phase)?;
            let l_k_bar = self.l_k_bar();
            let eased = self.ease_ends();
            if self.is_bend() && way.0 > 0.0 {
                let speed = travel.phase.speed(way.along(travel.phase_start, l_k_bar));
                if self.ease(speed) {
                    saved.anchor_at(way, way.back(self.l_k_arc_bar(), SET_LEAD));
                    travel.next_sample = self.moving(&travel).on(l_k_bar, self.params.sample_interval);
                }
            }
            let moving = self.moving(&travel);
            if !eased && !moving.reached(l_k_bar, travel.next_sample) {
                continue;
            }
            travel.next_sample = moving.on(l_k_bar, self.params.sample_interval);
            let points = self.sample(travel.phase, &step, dt, l_k_bar);
            let found = self.detect(&mut travel);
            self.keep_snapshots(&mut travel.snapshots, found, l_k_bar);
            self.topology(&points, || format!("at l_k bar {l_k_bar:.2}"))?;
            if eased {
                self.free_tails();
                self.pull_on(&mut travel, &mut saved, l_k_bar);
            }
            if self.report.bend_series.last().is_some_and(|b| b.apart) {
                if self.slipped(&mut travel, &mut saved)? {
                    continue;
                }
                break Ok(());
            }
            let sample = self.report.series.last().copied().unwrap_or_default();
            let arc = sample.l_k_arc_bar;
            let stop = self.stop_at(&travel, target);
            let within = way.along(start_arc, arc) / way.along(start_arc, stop);
            self.observe(observer, &points, l_k_bar, within)?;
            if self.schedule(&mut travel, &mut saved, l_k_bar, arc)? {
                continue;
            }
            let tight = way.0 > 0.0 && sample.f_bar > self.params.tight_force_bar();
            let overstretched =
                tight && self.params.max_force_bar.is_none() && !self.params.knot.holds_by_friction();
            let easing = matches!(self.carried.tails, Tails::Easing { .. });
            if (way.reached(arc, stop) || tight)
                && !easing
                && !self.review_end(&mut travel, &mut saved, arc, overstretched.then_some(l_k_bar))?
            {
                break Ok(());
            }
        };
        if soft {
            self.unmount_springs();
        }
        ending
    }

    /// Which way the clamps move l_k bar: the stage's, back while a set knot
    /// is eased ([`super::runner::Tails`]).
    fn moving(&self, travel: &Travel) -> Way {
        match self.carried.tails {
            Tails::Easing { .. } => Way(-travel.way.0),
            _ => travel.way,
        }
    }

    /// The set knot has been eased, sampled and its tails let go at
    /// `l_k_bar`: the pull goes on from here, its phase's speed ramping up
    /// again and, while fast, checkpointed (a restart after the holding
    /// point comes back to the tails free).
    fn pull_on(&mut self, travel: &mut Travel, saved: &mut Checkpoints<Checkpoint>, l_k_bar: f64) {
        travel.phase_start = l_k_bar;
        travel.next_sample = travel.way.on(l_k_bar, self.params.sample_interval);
        if travel.phase == Phase::Approach {
            let state = self.checkpoint(travel);
            saved.keep(travel.way, l_k_bar, self.l_k_arc_bar(), state);
        }
        self.drive(travel, l_k_bar);
    }

    /// A bend's rods have parted at the last sample: a fast approach goes
    /// back ([`Case::back_from`]) and pulls through the holding point slowly
    /// (returns `true`); otherwise the slip-through is recorded and the
    /// stage ends (returns `false`).
    fn slipped(&mut self, travel: &mut Travel, saved: &mut Checkpoints<Checkpoint>) -> Result<bool, Ending> {
        let slip = events::slip_through(
            &self.report.series,
            &self.report.bend_series,
            travel.first_sample,
            self.stage,
        );
        let Some(slip) = slip else {
            return Ok(false);
        };
        let held = slip.at.l_k_arc_bar;
        if travel.phase == Phase::Approach {
            let to = self.back_from(travel, saved, held);
            if self.restart(travel, saved, to, Some(held), Outcome::Restarted)? {
                travel.reads_hold = to == Back::Anchor;
                return Ok(true);
            }
        }
        let parted = self.report.series.last().map_or(slip.at.l_k_bar, |s| s.l_k_bar);
        self.slip_snapshots(&mut travel.snapshots, parted);
        self.record(Event {
            restarts: travel.restarts,
            ..slip
        });
        Ok(false)
    }

    /// Where a fast approach goes back to for its event at the knot's own
    /// length `at`: a set bend's or hitch's anchor, to be pulled through its
    /// setting, release and holding point at `pull_speed`
    /// ([`Travel::reads_hold`]; its snaps with the tails free are its giving
    /// way), else `restart_before` before `at`.
    fn back_from(&self, travel: &Travel, saved: &Checkpoints<Checkpoint>, at: f64) -> Back {
        if saved.anchored() {
            return Back::Anchor;
        }
        Back::Before(travel.way.back(at, travel.way.restart_before(self.turns())))
    }

    /// Where (the knot's own length) the current stage stops: its target; a
    /// tightening without one at the stopping rules (`min_l_k_bar`, or
    /// `stop_after_inversion` past its inversion).
    fn stop_at(&self, travel: &Travel, target: Option<f64>) -> f64 {
        let floor = self.params.min_l_k_bar;
        match (target, travel.event, self.params.stop_after_inversion) {
            (Some(x), ..) if travel.way.0 < 0.0 => x,
            (Some(x), ..) => x.max(floor),
            (None, Some(e), Some(margin)) if e.kind == EventKind::Inversion => {
                (e.at.l_k_arc_bar - margin).max(floor)
            }
            (None, ..) => floor,
        }
    }

    /// The adaptive schedule's moves after a sample at `l_k_bar`, the knot's
    /// own length `arc`: back to a checkpoint when the fast approach sees an
    /// event or, in an overhand knot, a smeared snap of H bar (returns
    /// `true`), checkpoints while fast, fast again past the event or after a
    /// false alarm; otherwise the clamps' speed.
    fn schedule(
        &mut self,
        travel: &mut Travel,
        saved: &mut Checkpoints<Checkpoint>,
        l_k_bar: f64,
        arc: f64,
    ) -> Result<bool, Ending> {
        let way = travel.way;
        if travel.reads_hold && travel.phase.at_pull_speed() {
            if self.letting_go(travel) {
                self.end_phase(Outcome::Confirmed);
                self.enter(travel, Phase::After);
            } else {
                self.drive(travel, l_k_bar);
            }
            return Ok(false);
        }
        if travel.phase == Phase::Approach && travel.event.is_none() && way.0 > 0.0 && self.reads_loop() {
            if let Some((began, fell)) = adaptive::smeared_snap(
                &self.report.series[travel.watch_from..],
                self.criteria().flat_loop,
            ) {
                let back = way.back(began, way.restart_before(self.turns()));
                if self.restart(travel, saved, Back::Before(back), Some(fell), Outcome::Restarted)? {
                    return Ok(true);
                }
            }
        }
        match (travel.phase, travel.event) {
            (Phase::Approach, Some(event)) => {
                let at = event.at.l_k_arc_bar;
                let to = self.back_from(travel, saved, at);
                if self.restart(travel, saved, to, Some(at), Outcome::Restarted)? {
                    travel.reads_hold = to == Back::Anchor;
                    return Ok(true);
                }
            }
            (Phase::Approach, None) if way.reached(l_k_bar, saved.next) => {
                let state = self.checkpoint(travel);
                saved.keep(way, l_k_bar, arc, state);
            }
            (Phase::Snap, event) if self.past_fold(travel, event) && !saved.list.is_empty() => {
                // The slow phase met its event, or its knot jumped, right
                // after its restart: the restart was already past the fold.
                // Go back further (from before the jump).
                let from = match (event, travel.restored_at) {
                    (None, Some(i)) => self.report.series[i].l_k_arc_bar,
                    _ => travel.phase_start_arc,
                };
                let (back, fast) = (
                    way.back(from, way.restart_before(self.turns())),
                    travel.fast_event,
                );
                if self.restart(travel, saved, Back::Before(back), fast, Outcome::TooLate)? {
                    return Ok(true);
                }
            }
            (Phase::Snap | Phase::Fallback, Some(event))
                if way.reached(arc, way.on(event.at.l_k_arc_bar, SLOW_AFTER)) =>
            {
                self.end_phase(Outcome::Confirmed);
                self.enter(travel, Phase::After);
            }
            (Phase::Snap, None) if self.alarm_passed(travel, arc) && self.fell_flat(travel) => {
                // The loop fell flat without a snap the detector read: the
                // restart came too close to the fold for the kinetic energy's
                // baseline to settle. Go back further.
                let (back, fast) = (
                    way.back(travel.phase_start_arc, way.restart_before(self.turns())),
                    travel.fast_event,
                );
                if self.restart(travel, saved, Back::Before(back), fast, Outcome::TooLate)? {
                    return Ok(true);
                }
                self.refute(travel, saved, l_k_bar);
            }
            (Phase::Snap | Phase::Fallback, None)
                if self.alarm_passed(travel, arc) && !self.snap_pending(travel) =>
            {
                self.refute(travel, saved, l_k_bar);
            }
            _ => self.drive(travel, l_k_bar),
        }
        Ok(false)
    }

    /// The slow phase passed `FALSE_ALARM` beyond the fast pull's event
    /// without one: that event was the fast pull's own swinging. Approach
    /// again, no longer watching the fall it saw, checkpointed from here
    /// (`l_k_bar`); past a fallback, the reference pull went through the
    /// stretch: the next event has restarts of its own, and none goes back
    /// into it.
    fn refute(&mut self, travel: &mut Travel, saved: &mut Checkpoints<Checkpoint>, l_k_bar: f64) {
        self.end_phase(Outcome::Refuted);
        travel.fast_event = None;
        if travel.phase == Phase::Fallback {
            travel.restarts = 0;
            saved.list.clear();
        }
        travel.watch_from = self.report.series.len();
        self.enter(travel, Phase::Approach);
        saved.next = l_k_bar;
    }

    /// Whether a slow phase has passed `FALSE_ALARM` beyond the fast pull's
    /// event, at the knot's own length `arc`.
    fn alarm_passed(&self, travel: &Travel, arc: f64) -> bool {
        let way = travel.way;
        travel
            .fast_event
            .is_some_and(|f| way.past(arc, way.on(f, FALSE_ALARM)))
    }

    /// Whether an overhand knot jumped in the last samples, a snap awaiting
    /// the detector's confirmation ([`adaptive::jumped_lately`]): no refute
    /// then, its jump having carried the knot's own length past the mark.
    fn snap_pending(&self, travel: &Travel) -> bool {
        let jump = self.criteria().knot_jump;
        self.reads_loop() && adaptive::jumped_lately(travel.way, &self.report.series, jump)
    }

    /// Whether the slow phase through a bend's holding point sees its rods
    /// coming apart: `SLOW_AFTER` past its largest F bar with the tails free,
    /// F bar has fallen to `LET_GO` of it.
    fn letting_go(&self, travel: &Travel) -> bool {
        let (series, from) = (&self.report.series, self.quiet_from(travel));
        let held = report::holding_point(series, &self.report.bend_series, from);
        held.zip(series.last()).is_some_and(|((_, held), last)| {
            travel.way.along(held.l_k_arc_bar, last.l_k_arc_bar) >= SLOW_AFTER
                && last.f_bar <= LET_GO * held.f_bar
        })
    }

    /// Whether an overhand knot's loop fell flat in the current phase: its
    /// H bar rose to `flat_loop` or above in it
    /// ([`crate::measurements::InversionCriteria::flat_loop`]) and lies below
    /// now.
    fn fell_flat(&self, travel: &Travel) -> bool {
        let flat = self.criteria().flat_loop;
        let from = travel.restored_at.map_or(self.report.series.len(), |i| i + 1);
        let phase = &self.report.series[from.min(self.report.series.len())..];
        self.reads_loop()
            && phase.iter().any(|s| s.h_bar >= flat)
            && phase.last().is_some_and(|s| s.h_bar < flat)
    }

    /// Whether a slow phase restarted past the fold: its `event` lies within
    /// `MIN_LEAD` of its start or, without one, an overhand knot has jumped
    /// from its checkpoint to the last sample ([`adaptive::knot_jumped`]:
    /// through the settle, with the clamps held, or right after it).
    fn past_fold(&self, travel: &Travel, event: Option<Event>) -> bool {
        let way = travel.way;
        match event {
            Some(e) => !way.reached(e.at.l_k_arc_bar, way.on(travel.phase_start_arc, MIN_LEAD)),
            None => {
                let (series, jump) = (&self.report.series, self.criteria().knot_jump);
                self.reads_loop()
                    && travel
                        .restored_at
                        .zip(series.last())
                        .is_some_and(|(i, now)| adaptive::knot_jumped(way, &series[i], now, jump))
            }
        }
    }

    /// Back to the checkpoint `to` names, the fast pull's event at
    /// `fast_event`, ending the current phase with `outcome`; `false` when
    /// no checkpoint or no restart is left.
    fn restart(
        &mut self,
        travel: &mut Travel,
        saved: &mut Checkpoints<Checkpoint>,
        to: Back,
        fast_event: Option<f64>,
        outcome: Outcome,
    ) -> Result<bool, Ending> {
        if travel.restarts >= MAX_RESTARTS {
            return Ok(false);
        }
        let Some(c) = saved.back(travel.way, to) else {
            return Ok(false);
        };
        self.end_phase(outcome);
        self.restore(c, travel)?;
        travel.fast_event = fast_event;
        Ok(true)
    }

    /// At the stop condition: a fast approach without an event redoes the
    /// last `END_REVIEW` of the stage (the knot's own length, from `arc`),
    /// a bend or a hitch that held most before that from the checkpoint
    /// before it was set, once, slowly to the end (returns `true`); not when
    /// a slow phase went through most of it (refuted within `END_REVIEW` of
    /// the end). A knot stopped at the rod's stretch limit at `tight` (l_k
    /// bar, [`crate::case::STRETCH_LIMIT_FORCE_BAR`]) redoes at most the last
    /// `END_REVIEW` of the clamps' travel: locked, it gives little of its own
    /// length to a long travel.
    fn review_end(
        &mut self,
        travel: &mut Travel,
        saved: &mut Checkpoints<Checkpoint>,
        arc: f64,
        tight: Option<f64>,
    ) -> Result<bool, Ending> {
        let (way, refuted) = (travel.way, travel.watch_from > travel.first_sample);
        let fast_since = way.along(travel.phase_start_arc, arc);
        if travel.phase != Phase::Approach || travel.reviewed || (refuted && fast_since < END_REVIEW) {
            return Ok(false);
        }
        let mut back = way.back(arc, END_REVIEW);
        let series = &self.report.series[travel.first_sample..];
        if let Some(travelled) = tight.and_then(|l| {
            series
                .iter()
                .rev()
                .find(|s| way.along(s.l_k_bar, l) >= END_REVIEW)
        }) {
            if way.reached(travelled.l_k_arc_bar, back) {
                back = travelled.l_k_arc_bar;
            }
        }
        // A bend or a hitch that held most before the redone stretch: from
        // before it was set, to read its holding force at pull_speed.
        let hold = saved.anchored() && {
            let (series, bend) = (&self.report.series, &self.report.bend_series);
            report::holding_point(series, bend, travel.first_sample)
                .is_some_and(|(_, s)| way.along(s.l_k_arc_bar, back) > 0.0)
        };
        let to = if hold { Back::Anchor } else { Back::Before(back) };
        if !self.restart(travel, saved, to, None, Outcome::Restarted)? {
            return Ok(false);
        }
        travel.reviewed = true;
        travel.reads_hold = hold;
        Ok(true)
    }

    /// The overhand knot's turns, which scale its restart window
    /// ([`Way::restart_before`]); `None` for other knots.
    fn turns(&self) -> Option<u32> {
        (self.params.knot == KnotKind::Overhand).then_some(self.params.n)
    }

    /// The state to come back to.
    fn checkpoint(&self, travel: &Travel) -> Checkpoint {
        Checkpoint {
            world: self.world.clone(),
            clock: self.clock.clone(),
            carried: self.carried.clone(),
            travel: travel.clone(),
            series: self.report.series.len(),
            snapshots: self.report.snapshots.len(),
            events: self.report.events.len(),
        }
    }

    /// Enters `phase` here, with the clamps at its speed.
    fn enter(&mut self, travel: &mut Travel, phase: Phase) {
        self.enter_phase(phase);
        travel.phase = phase;
        travel.phase_start = self.l_k_bar();
        travel.phase_start_arc = self.l_k_arc_bar();
        self.drive(travel, travel.phase_start);
    }

    /// Both pulled clamps (or, on springs, both grips) moving along the
    /// stage at the phase's speed at `l_k_bar`; an overhand knot's slow
    /// phases by what its tails' stretch takes up
    /// ([`adaptive::stretch_factor`]; other knots have no tails measured).
    fn drive(&mut self, travel: &Travel, l_k_bar: f64) {
        if matches!(self.carried.tails, Tails::Easing { .. }) {
            return; // each held end moves on its own (`Case::ease_ends`)
        }
        let pulled = travel.way.along(travel.phase_start, l_k_bar);
        let stretch = match travel.phase {
            Phase::Snap | Phase::Fallback if self.params.knot == KnotKind::Overhand => {
                let spec = self.params.knot_spec();
                let tails = (spec.length - spec.knot_length()) / self.params.h;
                adaptive::stretch_factor(&self.report.series[travel.first_sample..], tails)
            }
            _ => 1.0,
        };
        let speed = travel.phase.speed(pulled) * stretch * self.params.clamp_speed() * travel.way.0;
        let rod = &mut self.world.rods[0];
        if let [start, finish] = &mut rod.springs[..] {
            start.velocity = -speed;
            finish.velocity = speed;
            return;
        }
        let v = self.axis * speed;
        let [first, second] = self.clamps;
        self.move_held_clamp(first, -v);
        self.move_held_clamp(second, v);
    }

    /// Back to checkpoint `c` of a fast approach, to move slowly through the
    /// event: the series, snapshots and events after it are dropped, and the
    /// knot settles with the clamps held (the fast pull leaves it swinging)
    /// before the snap phase starts, or the fallback on the stage's last
    /// restart.
    fn restore(&mut self, c: Checkpoint, travel: &mut Travel) -> Result<(), Ending> {
        let restarts = travel.restarts + 1;
        self.world = c.world;
        self.clock = c.clock;
        self.carried = c.carried;
        *travel = c.travel;
        travel.restarts = restarts;
        travel.restored_at = c.series.checked_sub(1);
        self.report.stats.restarts += 1;
        self.report.series.truncate(c.series);
        self.report.bend_series.truncate(c.series);
        self.sample_phases.truncate(c.series);
        self.report.snapshots.truncate(c.snapshots);
        self.report.events.truncate(c.events);
        self.enter(travel, Phase::Settle);
        self.settle(SETTLE_TIME * self.scales.time_unit, None)?;
        let slow = if restarts < MAX_RESTARTS {
            Phase::Snap
        } else {
            Phase::Fallback
        };
        self.enter(travel, slow);
        Ok(())
    }

    /// Detects the current stage's first event in its own samples; returns
    /// it when found at this sample. The overhand knot's events are read on
    /// its loop's height H bar ([`events::detect`]); every other knot's on
    /// F bar ([`events::detect_snap`], tightening only: H bar, found from
    /// the contacts around the middle node, jumps between a figure-eight's
    /// or a braid closure's lobes, and a bend has none), from the tails'
    /// release on when they were held ([`Case::snap_watch`]).
    fn detect(&mut self, travel: &mut Travel) -> Option<Event> {
        if travel.event.is_some() {
            return None;
        }
        let criteria = self.criteria();
        let first = travel.first_sample;
        let found = if self.reads_loop() {
            events::detect(
                &self.report.series,
                (first, self.quiet_from(travel)),
                travel.way,
                &criteria,
                self.stage,
            )
        } else if travel.way.0 > 0.0 {
            self.snap_watch(first)
                .and_then(|from| events::detect_snap(&self.report.series, from, &criteria, self.stage))
        } else {
            None
        }
        .map(|e| Event {
            restarts: travel.restarts,
            ..e
        });
        travel.event = found;
        if let Some(event) = found {
            let reported = events::reported(&self.report.series, first, &criteria, event);
            self.record(reported);
        }
        found
    }

    /// The first sample taken at the current slow phase's pace: after a
    /// restart, the first since its checkpoint (the fast approach's before it
    /// are no baseline for its kinetic energy); otherwise the stage's first.
    fn quiet_from(&self, travel: &Travel) -> usize {
        match (travel.phase, travel.restored_at) {
            (Phase::Snap | Phase::Fallback | Phase::After, Some(i)) => i + 1,
            _ => travel.first_sample,
        }
    }

    /// Whether the knot's events are read on its loop's height H bar: the
    /// overhand knot's (the builder's or a user's), paper Fig. 5.
    fn reads_loop(&self) -> bool {
        self.params.knot == KnotKind::Overhand
    }

    /// The first sample of the stage starting at `first` that the snap
    /// detector watches: a bend's or a hitch's first with the tails free (F
    /// bar's fall as the setting load is let go is no snap; `None` while
    /// they are held), any other knot's first.
    fn snap_watch(&self, first: usize) -> Option<usize> {
        if !self.is_bend() {
            return Some(first);
        }
        let freed = self.report.bend_series[first..]
            .iter()
            .position(|b| b.tails_free)?;
        Some(first + freed)
    }

    /// Frees the clamps along the pull (the axis is x, checked at submit
    /// time) and ties each to a grip by a spring of stiffness `stiffness_bar`
    /// EI / h^3.
    fn mount_springs(&mut self, stiffness_bar: f64) {
        let stiffness = stiffness_bar * self.params.bending_stiffness() / self.params.h.powi(3);
        let rod = &mut self.world.rods[0];
        let k = rod.nodes();
        for i in [0, 1, k - 2, k - 1] {
            rod.fixed[node_dof(i)] = false;
        }
        rod.springs = [0, k - 1]
            .map(|i| Spring {
                dof: node_dof(i),
                stiffness,
                anchor: rod.q[node_dof(i)],
                velocity: 0.0,
            })
            .to_vec();
        self.world.forget_factorizations();
    }

    /// The clamps held where the springs left them.
    fn unmount_springs(&mut self) {
        let rod = &mut self.world.rods[0];
        rod.springs.clear();
        rod.clamp(End::Start);
        rod.clamp(End::Finish);
        self.world.forget_factorizations();
    }
}
