//! The experiment of paper Sec. 4: build the knot, clamp both ends (equal
//! material frames, no relative rotation), relax with the ends held, then
//! run the case's loading program ([`crate::case::LoadStage`]: by default one
//! tightening, the clamps pulled apart along the line joining them), sampling
//! the measurements of eq. (11), the knot's own length, the energies and the
//! linking number.
//!
//! Which length each rule acts on: samples are taken every
//! `sample_interval` of eq. 11's l_k bar (the clamps' travel), and events are
//! detected over windows of it, as the paper's Fig. 5 reads them; the
//! stopping rules (`min_l_k_bar`, `stop_after_inversion`, the stages'
//! `to_l_k_bar`) and the adaptive schedule's windows act on the knot's own
//! length l_k arc bar, which the tails' elastic stretch does not move, so that
//! a rod longer than its knot stops, and restarts, where the paper's rod would
//! (eq. 11's l_k bar of a rubber rod of L/h = 2000 trails it by 30 radii at
//! F bar 0.06).
//!
//! - `report.rs`: what a case reports ([`CaseReport`], [`Event`], ...);
//! - `adaptive.rs`: the adaptive schedule of a pull or release ([`Phase`]);
//! - `runner.rs`: the run itself, relaxation and the program's walk;
//! - `travel.rs`: a pull, release or soft stage; `still.rs`: hold and rotate;
//! - `events.rs`: inversions and flips back; `snapshots.rs`: the states kept
//!   for viewers; `twist.rs`: the linking number and the clamps' turns.
mod adaptive;
mod events;
mod report;
mod runner;
mod snapshots;
mod still;
mod travel;
mod twist;

pub use crate::snapshot::{Snapshot, SnapshotContact};
pub use adaptive::{ADAPTIVE_MAX_MU, ADAPTIVE_MAX_RATE, MAX_RESTARTS, Outcome, Phase, pulls_fast};
pub use report::{
    BendSample, CaseReport, Event, EventKind, Hysteresis, PhaseSpan, Progress, QUASI_STATIC_LIMIT,
    QuasiStatic, Scaling, Stats, Status,
};

use crate::case::{CaseParams, FieldError, ValidCase};
use nalgebra::Vector3;

/// A case's cost in node-steps, to the order of magnitude: a pull over the
/// rod's length at `pull_speed` and the largest step, each step linear in
/// the node count, the fast factor fewer steps when the approach runs fast.
/// Queues hand out the costliest cases first, so that a long case does not
/// start last and leave the other workers idle.
pub fn work_estimate(params: &CaseParams) -> f64 {
    let steps = params.length / (params.clamp_speed() * params.time_step());
    let fast = if pulls_fast(params) {
        adaptive::FAST_FACTOR
    } else {
        1.0
    };
    let stages = params.loading.as_ref().map_or(1, Vec::len) as f64;
    steps * params.node_count() as f64 * stages / fast
}

/// Runs one case: validates `params`, building the start shape once, and
/// runs it ([`run_valid`]); invalid parameters give a report with
/// [`Status::Invalid`] and the reasons. `observer` sees progress after every
/// sample and, during the relaxation, every few dozen steps (with no pull
/// steps yet), and returns `false` to cancel.
///
/// A short rod with one pass, pulled quickly at a constant speed (the
/// reference protocol: no stage goes back) until the knot's own length
/// (`measurements::l_k_arc_bar`) falls below 130:
/// ```
/// use solver::case::{CaseParams, Protocol};
/// use solver::protocol::{self, Status};
///
/// let params = CaseParams {
///     n: 1,
///     length: 0.3,
///     nodes: Some(102),
///     relax_time: Some(0.1),
///     pull_speed: Some(0.01),
///     min_l_k_bar: 130.0,
///     protocol: Protocol::Reference,
///     ..CaseParams::default()
/// };
/// let mut samples = 0;
/// let report = protocol::run(&params, &mut |p| {
///     samples += usize::from(p.steps > 0); // not the relaxation's calls
///     true
/// });
/// assert_eq!(report.status, Status::Completed, "{}", report.reason);
/// assert_eq!(report.determinant_initial, Some(3), "a trefoil: 2n + 1");
/// assert_eq!(report.series.len(), samples);
/// let l_k_bar: Vec<f64> = report.series.iter().map(|s| s.l_k_bar).collect();
/// assert!(l_k_bar.windows(2).all(|w| w[1] < w[0]), "the pull shortens the knot");
/// let last = &report.series[report.series.len() - 1];
/// assert!(l_k_bar[0] > 135.0 && last.l_k_arc_bar < 130.0 && last.l_k_bar < 130.0);
/// ```
pub fn run(params: &CaseParams, observer: &mut dyn FnMut(&Progress) -> bool) -> CaseReport {
    let started = std::time::Instant::now();
    match params.validated() {
        Ok(case) => runner::run(&case, started, &mut |progress, _| observer(progress)),
        Err(errors) => {
            let mut report = CaseReport::empty(params.clone(), Status::Invalid);
            report.reason = reasons(&errors);
            report
        }
    }
}

/// [`run`] for a case already validated, from the start shape its validation built.
pub fn run_valid(case: &ValidCase, observer: &mut dyn FnMut(&Progress) -> bool) -> CaseReport {
    runner::run(case, std::time::Instant::now(), &mut |progress, _| {
        observer(progress)
    })
}

/// [`run_valid`] with the rod's centre line (node positions) handed to the
/// observer with every progress report.
pub fn run_observed(
    case: &ValidCase,
    observer: &mut dyn FnMut(&Progress, &[Vector3<f64>]) -> bool,
) -> CaseReport {
    runner::run(case, std::time::Instant::now(), observer)
}

/// Parameter errors as one line.
fn reasons(errors: &[FieldError]) -> String {
    errors
        .iter()
        .map(|e| e.to_string())
        .collect::<Vec<_>>()
        .join("; ")
}

#[cfg(test)]
mod tests {
    use super::{Phase, Status};
    use crate::case::Protocol;

    #[test]
    fn enum_words_are_the_serde_names() {
        for s in Status::ALL {
            assert_eq!(serde_json::to_value(s).unwrap(), s.to_string());
        }
        for p in [Protocol::Reference, Protocol::Adaptive] {
            assert_eq!(serde_json::to_value(p).unwrap(), p.to_string());
        }
        assert_eq!(Phase::Settle.to_string(), "settle");
        assert_eq!(serde_json::to_value(Phase::Approach).unwrap(), "approach");
    }

    /// A cancel is seen during the relaxation, which takes no samples: the
    /// observer is asked after the first `RELAX_OBSERVED` steps, with the
    /// progress at 0, and the case ends there.
    #[test]
    fn a_cancel_stops_the_relaxation() {
        let mut calls = Vec::new();
        let report = super::run(&crate::case::CaseParams::default(), &mut |p| {
            calls.push((p.fraction, p.steps));
            false
        });
        assert_eq!(report.status, Status::Cancelled, "{}", report.reason);
        assert_eq!(calls, [(0.0, 0)]);
        assert_eq!(report.stats.relax_steps, super::runner::RELAX_OBSERVED);
        assert!(report.series.is_empty());
    }
}
