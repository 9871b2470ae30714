//! A map's refinement (`POST /api/sweeps/{id}/refine`): where the outcome of
//! a sweep's cases changes between two neighbours of a grid line (an
//! inversion or none, a clean snap or not), the line is bisected until the
//! two cases bracketing the change are no further apart than the tolerance.
//!
//! Every new case is one sweep of its own (the line's case with the axis at
//! the bracket's middle), queued, cached and shown like any other; a round
//! bisects every open bracket at once. A middle whose outcome differs from
//! both ends splits its bracket in two. The refinement's view (its points
//! and brackets) is stored at every round; one left running when its server
//! stopped starts again when one starts, its cases cached.
use crate::core::Core;
use crate::error::CoreError;
use crate::fit::parse_view;
use crate::spec::{FieldError, SweepSpec};
use crate::views::{SweepCaseView, SweepStatus};
use knotsweep_worker::store::{CaseStatus, SnapshotChoice};
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};
use solver::case::Range;
use std::collections::BTreeMap;
use std::time::Duration;
use utoipa::ToSchema;

/// A refinement to run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(example = json!({"tolerance": {"h": 2e-4, "mu": 0.02}}))]
pub struct RefineSpec {
    /// Per varied axis, the distance (in the parameter's SI unit) within
    /// which the bracketing pair of each refined line must land; an axis left
    /// out is not refined. An integer axis stops at neighbouring integers.
    #[schema(value_type = BTreeMap<String, f64>)]
    pub tolerance: BTreeMap<String, f64>,
}

impl RefineSpec {
    /// Checks the tolerances against sweep `id`'s varied axes: at least one,
    /// each on a numeric varied axis, each positive.
    pub fn check(&self, id: i64, varied: &[String]) -> Result<(), CoreError> {
        let mut errors = Vec::new();
        if self.tolerance.is_empty() {
            errors.push(FieldError::new(
                "tolerance",
                format!(
                    "give at least one varied axis of the sweep: {}",
                    varied.join(", ")
                ),
            ));
        }
        for (axis, tol) in &self.tolerance {
            let numeric = (solver::case::PARAMETERS.iter()).any(|p| {
                p.name == axis
                    && matches!(
                        p.range,
                        Range::Interval(..) | Range::LengthOver(..) | Range::Integers(..)
                    )
            });
            if !varied.contains(axis) {
                errors.push(FieldError::new(
                    format!("tolerance.{axis}"),
                    format!(
                        "not a varied axis of sweep {id} (those are: {})",
                        varied.join(", ")
                    ),
                ));
            } else if !numeric {
                errors.push(FieldError::new(
                    format!("tolerance.{axis}"),
                    "only a numeric axis can be bisected",
                ));
            }
            if !(tol.is_finite() && *tol > 0.0) {
                errors.push(FieldError::new(
                    format!("tolerance.{axis}"),
                    "must be a positive number",
                ));
            }
        }
        match errors.is_empty() {
            true => Ok(()),
            false => Err(CoreError::Invalid(errors)),
        }
    }
}

/// What a case gave, as the map tells them apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// The case ran to its stop without an inversion.
    NoInversion,
    /// An inversion through which F̄ falls.
    CleanSnap,
    /// An inversion through which F̄ keeps rising (a loop lying down under load).
    NotClean,
}

/// Where a refinement is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum RefineStatus {
    Running,
    Done,
    Failed,
}

/// One end of a bracket: the case at `value` on the line and its outcome.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct End {
    pub value: f64,
    pub case_id: i64,
    pub outcome: Outcome,
    /// Its inversion's l̄_k (null without one).
    pub l_k_bar: Option<f64>,
}

/// A change of outcome along one grid line: the two nearest cases on either
/// side of it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct Bracket {
    /// The axis the line runs along.
    pub axis: String,
    /// The other varied parameters' values on the line.
    #[schema(value_type = BTreeMap<String, Object>)]
    pub at: BTreeMap<String, Value>,
    /// The end at the lower value of the axis and the one at the higher.
    pub low: End,
    pub high: End,
    /// high - low, in the axis' SI unit.
    pub width: f64,
    /// The width is within the tolerance (or the ends are neighbouring integers).
    pub settled: bool,
    /// Why the bracket stopped short of the tolerance (a case without an outcome).
    pub reason: Option<String>,
}

/// A case the refinement added.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct RefinedPoint {
    pub case_id: i64,
    /// Its values of the sweep's varied parameters.
    #[schema(value_type = BTreeMap<String, Object>)]
    pub params: BTreeMap<String, Value>,
    /// Null when the case has no outcome (failed; see `reason`).
    pub outcome: Option<Outcome>,
    pub l_k_bar: Option<f64>,
    pub reason: Option<String>,
}

/// A refinement and where it is (`GET /api/sweeps/{id}/refinement`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct RefinementView {
    pub sweep_id: i64,
    pub status: RefineStatus,
    #[schema(value_type = BTreeMap<String, f64>)]
    pub tolerance: BTreeMap<String, f64>,
    /// Rounds of bisection run.
    pub rounds: usize,
    /// Why it failed.
    pub reason: Option<String>,
    /// The sweeps of its cases, one per case.
    pub sweeps: Vec<i64>,
    /// The cases it added, in the order they ran.
    pub points: Vec<RefinedPoint>,
    /// Every change of outcome along a refined line (those of the grid
    /// first, then those a middle split off).
    pub brackets: Vec<Bracket>,
}

/// A point of the grid: its varied values and outcome.
#[derive(Clone, Debug, PartialEq)]
pub struct GridPoint {
    pub case_id: i64,
    pub params: BTreeMap<String, Value>,
    pub outcome: Option<Outcome>,
    pub l_k_bar: Option<f64>,
}

/// Rounds of bisection at most (each halves every open bracket).
const MAX_ROUNDS: usize = 40;

/// How often a refinement looks at its cases' sweeps.
const POLL: Duration = Duration::from_millis(300);

/// Whether parameter `name` takes whole numbers.
fn integer(name: &str) -> bool {
    (solver::case::PARAMETERS.iter()).any(|p| p.name == name && matches!(p.range, Range::Integers(..)))
}

/// The brackets of a grid: along each axis with a tolerance, every pair of
/// neighbours on a line (the other axes held) whose outcomes differ.
pub fn grid_brackets(points: &[GridPoint], tolerance: &BTreeMap<String, f64>) -> Vec<Bracket> {
    let mut brackets = Vec::new();
    for (axis, &tol) in tolerance {
        // The lines: the points grouped by their other values.
        let mut lines: BTreeMap<String, Vec<(f64, &GridPoint)>> = BTreeMap::new();
        for p in points {
            let Some(x) = p.params.get(axis).and_then(Value::as_f64) else {
                continue;
            };
            let others: BTreeMap<&String, &Value> = p.params.iter().filter(|(k, _)| *k != axis).collect();
            let key = serde_json::to_string(&others).expect("values serialise");
            lines.entry(key).or_default().push((x, p));
        }
        for line in lines.values_mut() {
            line.sort_by(|a, b| a.0.total_cmp(&b.0));
            for pair in line.windows(2) {
                let [(xa, a), (xb, b)] = [pair[0], pair[1]];
                let (Some(oa), Some(ob)) = (a.outcome, b.outcome) else {
                    continue;
                };
                if oa == ob {
                    continue;
                }
                let end = |value, p: &GridPoint, outcome| End {
                    value,
                    case_id: p.case_id,
                    outcome,
                    l_k_bar: p.l_k_bar,
                };
                let at = a.params.iter().filter(|(k, _)| *k != axis);
                brackets.push(bracket(
                    axis,
                    at.map(|(k, v)| (k.clone(), v.clone())).collect(),
                    end(xa, a, oa),
                    end(xb, b, ob),
                    tol,
                ));
            }
        }
    }
    brackets
}

/// A bracket between `low` and `high`, settled when within `tol`.
fn bracket(axis: &str, at: BTreeMap<String, Value>, low: End, high: End, tol: f64) -> Bracket {
    let width = high.value - low.value;
    Bracket {
        axis: axis.to_string(),
        at,
        low,
        high,
        width,
        // Within a rounding of the tolerance: halving 1 mm four times lands on 62.5 µm, not below it.
        settled: width <= tol * (1.0 + 1e-9) || (integer(axis) && width <= 1.0),
        reason: None,
    }
}

/// The value at which an open bracket is bisected next; none for a settled
/// bracket or one that stopped.
pub fn middle(b: &Bracket) -> Option<f64> {
    if b.settled || b.reason.is_some() {
        return None;
    }
    let mid = 0.5 * (b.low.value + b.high.value);
    Some(if integer(&b.axis) { mid.floor() } else { mid })
}

/// The brackets a bisection of `b` at `mid` leaves: the half (or both
/// halves) across which the outcome changes.
pub fn split(b: &Bracket, mid: End, tol: f64) -> Vec<Bracket> {
    let halves = [(b.low, mid), (mid, b.high)];
    (halves.into_iter())
        .filter(|(lo, hi)| lo.outcome != hi.outcome)
        .map(|(lo, hi)| bracket(&b.axis, b.at.clone(), lo, hi, tol))
        .collect()
}

/// A case's outcome: an inversion (clean when F̄ falls through it) or, for a
/// case that ran to its stop, none; null without a result.
fn outcome(c: &SweepCaseView) -> Option<Outcome> {
    match &c.inversion {
        Some(i) if i.f_bar_after < i.f_bar_before => Some(Outcome::CleanSnap),
        Some(_) => Some(Outcome::NotClean),
        None if c.status == CaseStatus::COMPLETED => Some(Outcome::NoInversion),
        None => None,
    }
}

fn status_word(status: RefineStatus) -> &'static str {
    match status {
        RefineStatus::Running => "running",
        RefineStatus::Done => "done",
        RefineStatus::Failed => "failed",
    }
}

impl Core {
    /// Checks a refinement of sweep `id` (each tolerance on a numeric varied
    /// axis, positive), stores it and starts it; answers at once. 409 while
    /// one of the sweep runs.
    pub async fn submit_refinement(&self, id: i64, spec: RefineSpec) -> Result<RefinementView, CoreError> {
        let detail = self.sweep(id).await?;
        spec.check(id, &detail.varied)?;
        if let Some(json) = self.store().refinement(id).await? {
            let before: RefinementView = parse_view(&format!("sweep {id}'s refinement"), &json)?;
            if before.status == RefineStatus::Running {
                return Err(CoreError::Conflict(format!(
                    "sweep {id} is being refined: wait until its refinement is done"
                )));
            }
        }
        let view = RefinementView {
            sweep_id: id,
            status: RefineStatus::Running,
            tolerance: spec.tolerance,
            rounds: 0,
            reason: None,
            sweeps: Vec::new(),
            points: Vec::new(),
            brackets: Vec::new(),
        };
        self.save_refinement(&view).await?;
        tracing::info!(sweep_id = id, tolerance = ?view.tolerance, "refinement accepted");
        self.spawn_refinement(view.clone());
        Ok(view)
    }

    /// Sweep `id`'s refinement; 404 when it has none.
    pub async fn refinement(&self, id: i64) -> Result<RefinementView, CoreError> {
        self.sweep(id).await?;
        match self.store().refinement(id).await? {
            Some(json) => parse_view(&format!("sweep {id}'s refinement"), &json),
            None => Err(CoreError::NotFound(format!("a refinement of sweep {id}"))),
        }
    }

    /// Takes up the refinements and fits left running by a server that
    /// stopped (their cases are cached); returns how many.
    pub async fn resume_searches(&self) -> Result<usize, CoreError> {
        let mut resumed = self.resume_fits().await?;
        for (id, json) in self.store().refinements_with_status("running").await? {
            let view: RefinementView = parse_view(&format!("sweep {id}'s refinement"), &json)?;
            tracing::info!(sweep_id = id, "refinement taken up again");
            self.spawn_refinement(RefinementView {
                rounds: 0,
                sweeps: Vec::new(),
                points: Vec::new(),
                brackets: Vec::new(),
                ..view
            });
            resumed += 1;
        }
        Ok(resumed)
    }

    async fn save_refinement(&self, view: &RefinementView) -> Result<(), CoreError> {
        let json = serde_json::to_string(view).expect("view serialises");
        Ok(self
            .store()
            .put_refinement(view.sweep_id, status_word(view.status), &json)
            .await?)
    }

    fn spawn_refinement(&self, mut view: RefinementView) {
        let core = self.clone();
        tokio::spawn(async move {
            match core.run_refinement(&mut view).await {
                Ok(()) => view.status = RefineStatus::Done,
                Err(reason) => {
                    tracing::warn!(sweep_id = view.sweep_id, %reason, "refinement failed");
                    view.status = RefineStatus::Failed;
                    view.reason = Some(reason);
                }
            }
            if let Err(e) = core.save_refinement(&view).await {
                tracing::error!(sweep_id = view.sweep_id, error = %e, "storing the refinement's end failed");
            }
        });
    }

    /// Sweep `id` once it is done; why not when it was cancelled.
    async fn finished_sweep(&self, id: i64) -> Result<crate::views::SweepDetail, String> {
        loop {
            let detail = self.sweep(id).await.map_err(|e| e.to_string())?;
            match detail.summary.status {
                SweepStatus::Done => return Ok(detail),
                SweepStatus::Cancelled => return Err(format!("sweep {id} was cancelled")),
                _ => tokio::time::sleep(POLL).await,
            }
        }
    }

    /// The refinement to its end: the grid's brackets (once the sweep is
    /// done), then rounds of bisection, each stored as it lands.
    async fn run_refinement(&self, view: &mut RefinementView) -> Result<(), String> {
        let id = view.sweep_id;
        let detail = self.finished_sweep(id).await?;
        let grid: Vec<GridPoint> = (detail.cases.iter())
            .filter(|c| c.twin_of.is_none())
            .map(|c| GridPoint {
                case_id: c.case_id,
                params: c.params.clone(),
                outcome: outcome(c),
                l_k_bar: c.inversion.map(|i| i.l_k_bar),
            })
            .collect();
        view.brackets = grid_brackets(&grid, &view.tolerance);
        self.save_refinement(view).await.map_err(|e| e.to_string())?;
        loop {
            let open: Vec<(usize, f64)> = (view.brackets.iter().enumerate())
                .filter_map(|(k, b)| Some((k, middle(b)?)))
                .collect();
            if open.is_empty() {
                return Ok(());
            }
            if view.rounds >= MAX_ROUNDS {
                return Err(format!("brackets still open after {MAX_ROUNDS} rounds"));
            }
            view.rounds += 1;
            let mut submitted = Vec::new();
            for &(k, mid) in &open {
                let sweep = self
                    .bisection_sweep(id, &view.brackets[k], mid, view.rounds)
                    .await?;
                let raw = serde_json::to_value(&sweep).expect("spec serialises");
                let done = self.submit(sweep, &raw, None).await.map_err(|e| e.to_string())?;
                view.sweeps.push(done.sweep.summary.id);
                submitted.push((k, mid, done.sweep.summary.id));
            }
            let mut next = Vec::new();
            let mut split_off = vec![Vec::new(); view.brackets.len()];
            for (k, mid, sweep_id) in submitted {
                let detail = self.finished_sweep(sweep_id).await?;
                let case = detail
                    .cases
                    .iter()
                    .find(|c| c.twin_of.is_none())
                    .ok_or_else(|| format!("sweep {sweep_id} has no case"))?;
                let b = &view.brackets[k];
                let mut params = b.at.clone();
                params.insert(b.axis.clone(), Value::from(mid));
                let found = outcome(case);
                view.points.push(RefinedPoint {
                    case_id: case.case_id,
                    params,
                    outcome: found,
                    l_k_bar: case.inversion.map(|i| i.l_k_bar),
                    reason: case.reason.clone(),
                });
                let tol = view.tolerance[&b.axis];
                split_off[k] = match found {
                    Some(o) => split(
                        b,
                        End {
                            value: mid,
                            case_id: case.case_id,
                            outcome: o,
                            l_k_bar: case.inversion.map(|i| i.l_k_bar),
                        },
                        tol,
                    ),
                    None => vec![Bracket {
                        reason: Some(format!(
                            "case {} at {} = {mid} has no outcome: {}",
                            case.case_id,
                            b.axis,
                            case.reason.as_deref().unwrap_or("no result")
                        )),
                        ..b.clone()
                    }],
                };
                next.push(k);
            }
            // Each bisected bracket gives way to its halves, in place.
            let mut brackets = Vec::new();
            for (k, b) in view.brackets.iter().enumerate() {
                if next.contains(&k) {
                    brackets.append(&mut split_off[k]);
                } else {
                    brackets.push(b.clone());
                }
            }
            view.brackets = brackets;
            self.save_refinement(view).await.map_err(|e| e.to_string())?;
        }
    }

    /// The sweep of one bisection: the low end's case with the axis at `mid`.
    async fn bisection_sweep(
        &self,
        id: i64,
        b: &Bracket,
        mid: f64,
        round: usize,
    ) -> Result<SweepSpec, String> {
        let record = (self.store().get_case(b.low.case_id).await)
            .map_err(|e| e.to_string())?
            .ok_or_else(|| format!("case {} is gone", b.low.case_id))?;
        let Value::Object(mut base) = serde_json::to_value(&record.params).expect("params serialise") else {
            return Err(format!("case {}'s parameters are not an object", record.id));
        };
        base.remove(&b.axis);
        let at: Vec<String> = b.at.iter().map(|(k, v)| format!("{k} = {v}")).collect();
        let value = if integer(&b.axis) {
            Value::from(mid as i64)
        } else {
            Value::from(mid)
        };
        Ok(SweepSpec {
            name: Some(format!(
                "refining sweep {id} (round {round}): {} at {}",
                b.axis,
                if at.is_empty() {
                    "the base".to_string()
                } else {
                    at.join(", ")
                }
            )),
            base: Some(Map::from_iter(base)),
            grid: Some(BTreeMap::from([(b.axis.clone(), vec![value])])),
            snapshots: Some(SnapshotChoice::Events),
            ..SweepSpec::default()
        })
    }

    /// What a map draws of sweep `id`'s refinement on axes `x` and `y` (each
    /// scaled by `scale`): the points it added, and each bracket's two ends.
    pub(crate) async fn map_refinement(
        &self,
        id: i64,
        [x, y]: [&str; 2],
        scale: impl Fn(&str) -> f64,
    ) -> Result<(Vec<report::map::MapPoint>, Vec<report::map::MapBracket>), CoreError> {
        let Some(json) = self.store().refinement(id).await? else {
            return Ok((Vec::new(), Vec::new()));
        };
        let view: RefinementView = parse_view(&format!("sweep {id}'s refinement"), &json)?;
        let at = |params: &BTreeMap<String, Value>| {
            Some((
                params.get(x)?.as_f64()? * scale(x),
                params.get(y)?.as_f64()? * scale(y),
            ))
        };
        let points = (view.points.iter())
            .filter(|p| p.outcome.is_some())
            .filter_map(|p| {
                let (px, py) = at(&p.params)?;
                Some(report::map::MapPoint {
                    x: px,
                    y: py,
                    l_k_bar: p.l_k_bar,
                })
            })
            .collect();
        let brackets = (view.brackets.iter())
            .filter_map(|b| {
                let end = |e: &End| {
                    let mut params = b.at.clone();
                    params.insert(b.axis.clone(), Value::from(e.value));
                    at(&params)
                };
                Some(report::map::MapBracket {
                    ends: [end(&b.low)?, end(&b.high)?],
                    settled: b.settled,
                })
            })
            .collect();
        Ok((points, brackets))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid over (h, mu) whose outcome is known everywhere: no inversion
    /// below the line mu = 0.2 + 100 (h - 2e-3), a clean snap above.
    fn truth(h: f64, mu: f64) -> Outcome {
        if mu < 0.2 + 100.0 * (h - 2e-3) {
            Outcome::NoInversion
        } else {
            Outcome::CleanSnap
        }
    }

    fn point(case_id: i64, h: f64, mu: f64) -> GridPoint {
        GridPoint {
            case_id,
            params: BTreeMap::from([
                ("h".to_string(), Value::from(h)),
                ("mu".to_string(), Value::from(mu)),
            ]),
            outcome: Some(truth(h, mu)),
            l_k_bar: None,
        }
    }

    #[test]
    fn bisection_lands_every_change_within_the_tolerance() {
        let (hs, mus) = ([1.6e-3, 2.4e-3, 3.2e-3], [0.1, 0.3, 0.5]);
        let grid: Vec<GridPoint> = (hs.iter().enumerate())
            .flat_map(|(i, &h)| {
                mus.iter()
                    .enumerate()
                    .map(move |(j, &mu)| point((3 * i + j) as i64, h, mu))
            })
            .collect();
        let tolerance = BTreeMap::from([("h".to_string(), 1e-5), ("mu".to_string(), 0.01)]);
        let mut brackets = grid_brackets(&grid, &tolerance);
        // Along mu: each h's line crosses the boundary (at mu = 0.16, 0.24, 0.32).
        // Along h: only mu = 0.3's (at h = 3 mm; mu = 0.1's and 0.5's lie at 1 and 5 mm, off the grid).
        assert_eq!(brackets.iter().filter(|b| b.axis == "mu").count(), 3);
        assert_eq!(brackets.iter().filter(|b| b.axis == "h").count(), 1);
        let mut next_id = 100;
        for _ in 0..MAX_ROUNDS {
            let mut after = Vec::new();
            for b in &brackets {
                let Some(mid) = middle(b) else {
                    after.push(b.clone());
                    continue;
                };
                let (h, mu) = match b.axis.as_str() {
                    "h" => (mid, b.at["mu"].as_f64().unwrap()),
                    _ => (b.at["h"].as_f64().unwrap(), mid),
                };
                next_id += 1;
                let end = End {
                    value: mid,
                    case_id: next_id,
                    outcome: truth(h, mu),
                    l_k_bar: None,
                };
                after.extend(split(b, end, tolerance[&b.axis]));
            }
            brackets = after;
        }
        assert_eq!(brackets.len(), 4);
        for b in &brackets {
            assert!(b.settled && b.width <= tolerance[&b.axis], "{b:?}");
            assert_ne!(b.low.outcome, b.high.outcome);
            // The true boundary lies between the pair.
            let boundary = match b.axis.as_str() {
                "mu" => 0.2 + 100.0 * (b.at["h"].as_f64().unwrap() - 2e-3),
                _ => 2e-3 + (b.at["mu"].as_f64().unwrap() - 0.2) / 100.0,
            };
            assert!(
                b.low.value <= boundary && boundary <= b.high.value,
                "{b:?} vs {boundary}"
            );
        }
    }

    #[test]
    fn a_middle_unlike_both_ends_splits_the_bracket() {
        let end = |value, outcome| End {
            value,
            case_id: 0,
            outcome,
            l_k_bar: None,
        };
        let b = bracket(
            "mu",
            BTreeMap::new(),
            end(0.1, Outcome::CleanSnap),
            end(0.5, Outcome::NoInversion),
            0.01,
        );
        let halves = split(&b, end(0.3, Outcome::NotClean), 0.01);
        assert_eq!(halves.len(), 2);
        assert_eq!((halves[0].low.value, halves[0].high.value), (0.1, 0.3));
        assert_eq!((halves[1].low.value, halves[1].high.value), (0.3, 0.5));
        assert_eq!(split(&b, end(0.3, Outcome::CleanSnap), 0.01)[0].low.value, 0.3);
    }

    #[test]
    fn an_integer_axis_stops_at_neighbours() {
        let end = |value: f64| End {
            value,
            case_id: 0,
            outcome: if value < 4.0 {
                Outcome::CleanSnap
            } else {
                Outcome::NoInversion
            },
            l_k_bar: None,
        };
        let b = bracket("n", BTreeMap::new(), end(2.0), end(5.0), 0.5);
        assert_eq!(middle(&b), Some(3.0));
        let b = split(&b, end(3.0), 0.5).remove(0);
        assert_eq!(middle(&b), Some(4.0));
        let b = split(&b, end(4.0), 0.5).remove(0);
        assert!(b.settled && middle(&b).is_none(), "{b:?}");
        assert_eq!((b.low.value, b.high.value), (3.0, 4.0));
    }
}
