//! A case's loading program (parameter `loading`): the ordered stages the
//! clamps go through after the knot has relaxed, each a JSON object with one
//! key. Without a program a case is one tightening ([`default_program`]).
use serde::{Deserialize, Serialize};

/// Most stages in one program.
pub const MAX_STAGES: usize = 32;
/// Largest rotation of one stage (turns) and longest hold (s).
pub const MAX_TURNS: f64 = 20.0;
pub const MAX_HOLD: f64 = 1e3;

/// One stage of a loading program.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum LoadStage {
    /// Tighten: the clamps move apart at `pull_speed` until the knot's own
    /// length l_k arc bar (`measurements::l_k_arc_bar`: l_k bar less the
    /// rod's stretch) falls to `to_l_k_bar` (null: the case's stopping rules,
    /// `min_l_k_bar`, `stop_after_inversion` and `max_force_bar`).
    Pull(Target),
    /// Loosen: the clamps move together at `pull_speed` until the knot's own
    /// length rises to `to_l_k_bar` (null: where the program started).
    Release(Target),
    /// The clamps held still for `seconds`.
    Hold(Hold),
    /// One clamp, or both in opposite senses, turned about the pull axis by
    /// `turns` in all (positive: right-handed about the axis from the start
    /// clamp to the finish clamp, applied to the finish clamp).
    Rotate(Rotate),
    /// The grips move apart at `pull_speed` while the clamps sit on springs of
    /// stiffness `stiffness_bar` (k h^3 / EI) along the pull axis, until the
    /// knot's own length falls to `to_l_k_bar` (null: the stopping rules).
    Soft(Soft),
}

/// Where a pull or release stops.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Target {
    #[serde(default)]
    pub to_l_k_bar: Option<f64>,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Hold {
    pub seconds: f64,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rotate {
    pub turns: f64,
    #[serde(default)]
    pub ends: Ends,
}

/// Which clamps a rotation turns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ends {
    /// The finish clamp turns by all the turns.
    #[default]
    One,
    /// Each clamp turns by half, in opposite senses.
    Both,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Soft {
    pub stiffness_bar: f64,
    #[serde(default)]
    pub to_l_k_bar: Option<f64>,
}

/// Which way a stage moves the clamps along the pull.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    Tighten,
    Loosen,
    /// Holding or rotating: the clamps keep their distance.
    Still,
}

/// A stage's kind: its one key in a program (its word, as `Display` writes it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StageKind {
    Pull,
    Release,
    Hold,
    Rotate,
    Soft,
}

crate::words::display_as_word!(StageKind);

impl StageKind {
    /// Every kind, in the order of [`LoadStage`]'s variants.
    pub const ALL: [Self; 5] = [Self::Pull, Self::Release, Self::Hold, Self::Rotate, Self::Soft];
}

impl LoadStage {
    /// The stage's kind (its one key).
    pub fn kind(&self) -> StageKind {
        match self {
            LoadStage::Pull(_) => StageKind::Pull,
            LoadStage::Release(_) => StageKind::Release,
            LoadStage::Hold(_) => StageKind::Hold,
            LoadStage::Rotate(_) => StageKind::Rotate,
            LoadStage::Soft(_) => StageKind::Soft,
        }
    }

    /// Which way it moves the clamps.
    pub fn direction(&self) -> Direction {
        match self {
            LoadStage::Pull(_) | LoadStage::Soft(_) => Direction::Tighten,
            LoadStage::Release(_) => Direction::Loosen,
            LoadStage::Hold(_) | LoadStage::Rotate(_) => Direction::Still,
        }
    }

    /// The l_k bar it ends at, if it names one.
    pub fn target(&self) -> Option<f64> {
        match self {
            LoadStage::Pull(t) | LoadStage::Release(t) => t.to_l_k_bar,
            LoadStage::Soft(s) => s.to_l_k_bar,
            LoadStage::Hold(_) | LoadStage::Rotate(_) => None,
        }
    }
}

/// The program of a case without one: a single tightening to the stopping
/// rules.
pub fn default_program() -> Vec<LoadStage> {
    vec![LoadStage::Pull(Target::default())]
}

/// Why `program` cannot run from a knot starting at l_k bar `start` on a rod
/// of slenderness `slenderness` (L/h), naming the stage: a bad number, or a
/// target on the wrong side of where the stage starts (a pull's or a soft
/// stage's must lie below it, a release's above it), where that is known: a
/// stage ending by the stopping rules leaves it unknown until a release to
/// the start or to a target.
pub fn check(program: &[LoadStage], start: f64, slenderness: f64) -> Result<(), String> {
    if program.is_empty() {
        return Err("an empty program: give at least one stage, or null for one tightening".to_string());
    }
    if program.len() > MAX_STAGES {
        return Err(format!(
            "{} stages, more than the {MAX_STAGES} allowed",
            program.len()
        ));
    }
    let mut at = Some(start);
    for (i, stage) in program.iter().enumerate() {
        let name = format!("stage {} ({})", i + 1, stage.kind());
        let bad = |what: String| Err(format!("{name}: {what}"));
        match *stage {
            LoadStage::Hold(Hold { seconds }) if !(seconds > 0.0 && seconds <= MAX_HOLD) => {
                return bad(format!("seconds must be in (0, {MAX_HOLD}], got {seconds}"));
            }
            LoadStage::Rotate(Rotate { turns, .. }) if !(turns.abs() <= MAX_TURNS && turns != 0.0) => {
                return bad(format!(
                    "turns must be nonzero and in [-{MAX_TURNS}, {MAX_TURNS}], got {turns}"
                ));
            }
            LoadStage::Soft(Soft { stiffness_bar, .. })
                if !(stiffness_bar > 0.0 && stiffness_bar.is_finite()) =>
            {
                return bad(format!(
                    "stiffness_bar must be positive and finite, got {stiffness_bar}"
                ));
            }
            _ => {}
        }
        if let Some(x) = stage.target()
            && !(x.is_finite() && x > 0.0 && x < slenderness)
        {
            return bad(format!(
                "to_l_k_bar must be in (0, L/h = {slenderness:.0}), got {x}"
            ));
        }
        let beyond = |x: f64, here: f64| match stage.direction() {
            Direction::Tighten => x >= here,
            Direction::Loosen => x <= here,
            Direction::Still => false,
        };
        if let (Some(x), Some(here)) = (stage.target(), at)
            && beyond(x, here)
        {
            let side = if stage.direction() == Direction::Tighten {
                "below"
            } else {
                "above"
            };
            return bad(format!(
                "to_l_k_bar {x} is not {side} {here:.1}, where the knot is when the stage starts"
            ));
        }
        at = match (stage.direction(), stage.target()) {
            (Direction::Still, _) => at,
            (Direction::Loosen, None) => {
                if at.is_some_and(|here| here >= start) {
                    return bad(format!(
                        "the knot is not tighter than where the program starts ({start:.1}): give to_l_k_bar"
                    ));
                }
                Some(start)
            }
            (_, target) => target,
        };
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn program(value: serde_json::Value) -> Vec<LoadStage> {
        serde_json::from_value(value).unwrap()
    }

    /// Each stage is an object with one key, in the words of the issue.
    #[test]
    fn stages_read_as_one_key_objects() {
        let p = program(json!([
            {"pull": {"to_l_k_bar": 250}}, {"release": {}}, {"hold": {"seconds": 2}},
            {"rotate": {"turns": 1, "ends": "both"}}, {"soft": {"stiffness_bar": 100, "to_l_k_bar": 190}}
        ]));
        assert_eq!(
            p[0],
            LoadStage::Pull(Target {
                to_l_k_bar: Some(250.0)
            })
        );
        assert_eq!(p[1], LoadStage::Release(Target { to_l_k_bar: None }));
        assert_eq!(
            p[3],
            LoadStage::Rotate(Rotate {
                turns: 1.0,
                ends: Ends::Both
            })
        );
        assert_eq!(
            serde_json::to_value(p[4]).unwrap(),
            json!({"soft": {"stiffness_bar": 100.0, "to_l_k_bar": 190.0}})
        );
        // A stage's kind is its key, each kind once.
        let keys: Vec<String> = (p.iter())
            .map(|s| {
                serde_json::to_value(s)
                    .unwrap()
                    .as_object()
                    .unwrap()
                    .keys()
                    .next()
                    .unwrap()
                    .clone()
            })
            .collect();
        let kinds: Vec<String> = p.iter().map(|s| s.kind().to_string()).collect();
        assert_eq!(kinds, keys);
        assert_eq!(kinds, StageKind::ALL.map(|k| k.to_string()));
        for bad in [
            json!([{"push": {}}]),
            json!([{"pull": {"to": 3}}]),
            json!([{"pull": {}, "hold": {"seconds": 1}}]),
        ] {
            assert!(
                serde_json::from_value::<Vec<LoadStage>>(bad.clone()).is_err(),
                "{bad}"
            );
        }
    }

    #[test]
    fn programs_that_cannot_run_are_refused_naming_the_stage() {
        let ok = |v| check(&program(v), 431.0, 625.0);
        assert_eq!(
            ok(json!([{"pull": {"to_l_k_bar": 250}}, {"release": {"to_l_k_bar": 350}}])),
            Ok(())
        );
        assert_eq!(ok(json!([{"rotate": {"turns": -2}}, {"pull": {}}])), Ok(()));
        assert_eq!(
            ok(json!([{"pull": {"to_l_k_bar": 120}}, {"release": {}}])),
            Ok(())
        );
        let reason = |v| ok(v).unwrap_err();
        assert!(
            reason(json!([{"pull": {"to_l_k_bar": 500}}]))
                .starts_with("stage 1 (pull): to_l_k_bar 500 is not below 431.0")
        );
        assert!(
            reason(json!([{"pull": {"to_l_k_bar": 250}}, {"release": {"to_l_k_bar": 200}}]))
                .starts_with("stage 2 (release)")
        );
        assert_eq!(
            ok(json!([{"pull": {}}, {"release": {}}, {"pull": {"to_l_k_bar": 200}}])),
            Ok(())
        );
        assert!(reason(json!([{"release": {}}])).contains("not tighter"));
        assert!(reason(json!([{"hold": {"seconds": 0}}])).contains("seconds"));
        assert!(reason(json!([{"rotate": {"turns": 0}}])).contains("turns"));
        assert!(reason(json!([{"soft": {"stiffness_bar": -1}}])).contains("stiffness_bar"));
        assert!(reason(json!([{"pull": {"to_l_k_bar": 900}}])).contains("L/h = 625"));
        assert!(reason(json!([])).contains("empty"));
    }
}
