//! A user's start shape (`initial_shape`) as given: one rod's points, or
//! rods each with what its two ends do, and its check into the
//! [`StartShape`] a case starts from (docs/API.md, "Start shapes").
//!
//! ```json
//! {"rods": [
//!   {"points": [[x, y, z], ...], "start": "pulled", "finish": "free"},
//!   {"points": [[x, y, z], ...], "start": "pulled", "finish": "free"}
//! ]}
//! ```
//!
//! A `pulled` end is clamped (its end edge held, as the builder's clamps
//! are) and pulled: of the two pulled ends, in the order of the rods and
//! start before finish, the first moves away from the second along the line
//! joining them and the second away from the first. A `free` end is a bend's
//! tail: held while the bend relaxes and sets, as the builder's bends'
//! tails are, then free. A knot in one rod is pulled by both ends (a list
//! of points is that rod); each rod of a bend by one.
use super::FieldError;
use crate::contact::Geometry;
use crate::knot::{self, Clamp, Knot, StartShape};
use crate::rod::End;
use serde::{Deserialize, Deserializer, Serialize};
use serde_json::Value;

/// What an end of a rod of a start shape does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EndRole {
    /// Clamped and pulled.
    Pulled,
    /// A tail: held while the knot relaxes and sets, then free.
    Free,
}

/// A rod of a start shape: its centre line (m) and what its ends do.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeRod {
    pub points: Vec<[f64; 3]>,
    pub start: EndRole,
    pub finish: EndRole,
}

/// A user's start shape: one rod's points (pulled by both ends) or rods
/// with their ends' roles.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum InitialShape {
    Points(Vec<[f64; 3]>),
    Rods { rods: Vec<ShapeRod> },
}

/// The object form's keys, for its own error messages.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RodsForm {
    rods: Vec<ShapeRod>,
}

impl<'de> Deserialize<'de> for InitialShape {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        match Value::deserialize(deserializer)? {
            value @ Value::Array(_) => serde_json::from_value(value)
                .map(InitialShape::Points)
                .map_err(|e| D::Error::custom(format!("a list of points [x, y, z]: {e}"))),
            value @ Value::Object(_) => serde_json::from_value::<RodsForm>(value)
                .map(|form| InitialShape::Rods { rods: form.rods })
                .map_err(|e| D::Error::custom(format!("{{\"rods\": [...]}}: {e}"))),
            other => Err(D::Error::custom(format!(
                "expected a list of points [x, y, z] or {{\"rods\": [...]}}, got {other}"
            ))),
        }
    }
}

impl From<Vec<[f64; 3]>> for InitialShape {
    fn from(points: Vec<[f64; 3]>) -> Self {
        InitialShape::Points(points)
    }
}

impl From<&StartShape> for InitialShape {
    /// A start shape written as a user gives it: its rods with their pulled
    /// ends, every other end free.
    fn from(shape: &StartShape) -> Self {
        let role = |rod: usize, end: End| match shape.clamps.contains(&Clamp { rod, end }) {
            true => EndRole::Pulled,
            false => EndRole::Free,
        };
        let rods = (shape.rods.iter().enumerate())
            .map(|(r, points)| ShapeRod {
                points: points.iter().map(|p| [p.x, p.y, p.z]).collect(),
                start: role(r, End::Start),
                finish: role(r, End::Finish),
            })
            .collect();
        InitialShape::Rods { rods }
    }
}

impl InitialShape {
    /// The node count of its (first) rod.
    pub fn nodes(&self) -> usize {
        match self {
            InitialShape::Points(points) => points.len(),
            InitialShape::Rods { rods } => rods.first().map_or(0, |r| r.points.len()),
        }
    }

    /// The points of a shape given as one rod's list of points.
    pub fn points(&self) -> Option<&[[f64; 3]]> {
        match self {
            InitialShape::Points(points) => Some(points),
            InitialShape::Rods { .. } => None,
        }
    }

    /// The shape checked for `knot` with rods of (`length`, `nodes`, radius
    /// `h`) and the contact `geometry`: a knot in one rod by
    /// [`knot::checked_start`]; a bend's two rods each by
    /// [`knot::checked_rod`], one end of each pulled, and no two of their
    /// pieces closer than 2h by more than 1 % as `geometry` sees them
    /// ([`knot::check_rods_clearance`]). Its
    /// knot type is not checked: no invariant tells two open rods' tangles
    /// apart (the run reports whether they hold each other). An error names
    /// the field: `initial_shape`, or the rod or end within it
    /// (`initial_shape.rods[1].finish`).
    pub fn checked(
        &self,
        knot: &Knot,
        rod: (f64, usize, f64),
        geometry: Geometry,
    ) -> Result<StartShape, FieldError> {
        let two = matches!(knot, Knot::Bend(_));
        let rods = match (self, two) {
            (InitialShape::Points(points), false) => {
                return one_rod(points, knot, rod, geometry, "initial_shape");
            }
            (InitialShape::Points(_), true) => {
                return Err(FieldError::new(
                    "initial_shape",
                    format!(
                        "one rod given; {} ties two: give {{\"rods\": [...]}} with both (docs/API.md, \"Start \
                         shapes\")",
                        knot.name()
                    ),
                ));
            }
            (InitialShape::Rods { rods }, _) => rods,
        };
        let refuse =
            |field: String, reason: String| FieldError::new(format!("initial_shape.{field}"), reason);
        match (rods.len(), two) {
            (1, false) => {
                let r = &rods[0];
                for (name, role) in [("start", r.start), ("finish", r.finish)] {
                    if role != EndRole::Pulled {
                        return Err(refuse(
                            format!("rods[0].{name}"),
                            format!(
                                "{} is tied in one rod, pulled by both ends: \"pulled\"",
                                knot.name()
                            ),
                        ));
                    }
                }
                one_rod(&r.points, knot, rod, geometry, "initial_shape.rods[0].points")
            }
            (2, true) => bend(rods, rod, geometry).map_err(|(field, reason)| refuse(field, reason)),
            (count, _) => Err(refuse(
                "rods".to_string(),
                format!(
                    "{count} rods given; {} ties {}",
                    knot.name(),
                    if two { "two" } else { "one" }
                ),
            )),
        }
    }
}

/// A knot in one rod from its `points`, checked against its Alexander
/// polynomial and for clearance under `geometry`; errors naming `field`.
fn one_rod(
    points: &[[f64; 3]],
    knot: &Knot,
    rod: (f64, usize, f64),
    geometry: Geometry,
    field: &str,
) -> Result<StartShape, FieldError> {
    let Some(alexander) = knot.alexander() else {
        return Err(FieldError::new(
            field,
            format!(
                "{} has no knot type to check a rod against: the solver builds it, leave initial_shape out",
                knot.name()
            ),
        ));
    };
    knot::checked_start(points, rod, geometry, &knot.name(), &alexander)
        .map_err(|reason| FieldError::new(field, reason))
}

/// A bend's two rods, each pulled by one end, clear of each other under
/// `geometry`; an error is the field within `initial_shape` and the reason.
fn bend(
    rods: &[ShapeRod],
    (length, nodes, radius): (f64, usize, f64),
    geometry: Geometry,
) -> Result<StartShape, (String, String)> {
    let mut clamps = Vec::new();
    let mut centre_lines = Vec::new();
    for (r, rod) in rods.iter().enumerate() {
        let pulled: Vec<End> = [(End::Start, rod.start), (End::Finish, rod.finish)]
            .into_iter()
            .filter(|(_, role)| *role == EndRole::Pulled)
            .map(|(end, _)| end)
            .collect();
        let [end] = pulled[..] else {
            return Err((
                format!("rods[{r}]"),
                format!(
                    "each rod of a bend has one end pulled (its standing end) and one free (its tail); rod {r} has {}",
                    match pulled.len() {
                        0 => "none pulled",
                        _ => "both pulled",
                    }
                ),
            ));
        };
        clamps.push(Clamp { rod: r, end });
        let points =
            knot::checked_rod(&rod.points, (length, nodes)).map_err(|e| (format!("rods[{r}].points"), e))?;
        centre_lines.push(points);
    }
    knot::check_rods_clearance(&centre_lines, radius, geometry).map_err(|e| ("rods".to_string(), e))?;
    Ok(StartShape {
        rods: centre_lines,
        loop_middle: 0,
        alexander: None,
        clamps: [clamps[0], clamps[1]],
        cylinder: None,
        own_knots: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::{CaseParams, KnotKind, from_partial};

    fn reef() -> CaseParams {
        CaseParams {
            knot: KnotKind::Reef,
            ..CaseParams::default()
        }
    }

    /// The reef's built shape written out as a user gives it, and read back
    /// as JSON, is the case's start again: the same rods, node for node, and
    /// the same pulled ends.
    #[test]
    fn a_bend_written_out_and_read_back_is_the_same_start() {
        for knot in [KnotKind::Reef, KnotKind::Thief] {
            let params = CaseParams { knot, ..reef() };
            let built = params.validated().unwrap();
            let text = serde_json::to_string(&InitialShape::from(built.start())).unwrap();
            assert!(text.starts_with(r#"{"rods":[{"points":[["#), "{}", &text[..40]);
            assert!(text.contains(r#""start":"pulled","finish":"free"}"#));
            let again = CaseParams {
                initial_shape: Some(serde_json::from_str(&text).unwrap()),
                ..params.clone()
            };
            let read = again.validated().unwrap();
            assert_eq!(read.start(), built.start(), "{knot}");
            assert_eq!(read.params().node_count(), built.params().node_count());
        }
    }

    /// A knot in one rod given as one rod of the object form is the list of
    /// points.
    #[test]
    fn one_rod_pulled_by_both_ends_is_a_list_of_points() {
        let built = CaseParams::default().validated().unwrap();
        let points: Vec<[f64; 3]> = built.start().points().iter().map(|p| [p.x, p.y, p.z]).collect();
        let as_rods = InitialShape::Rods {
            rods: vec![ShapeRod {
                points: points.clone(),
                start: EndRole::Pulled,
                finish: EndRole::Pulled,
            }],
        };
        let start = |shape: InitialShape| {
            let params = CaseParams {
                initial_shape: Some(shape),
                ..CaseParams::default()
            };
            params.validated().unwrap().start().clone()
        };
        assert_eq!(start(as_rods), start(points.into()));
    }

    /// Each fault of a bend's start names the key to change.
    #[test]
    fn faults_name_the_rod_and_key() {
        let built = reef().validated().unwrap();
        let InitialShape::Rods { rods } = InitialShape::from(built.start()) else {
            panic!("rods");
        };
        let field = |params: CaseParams| params.validate().unwrap_err()[0].field.clone();
        let with = |rods: Vec<ShapeRod>| CaseParams {
            initial_shape: Some(InitialShape::Rods { rods }),
            ..reef()
        };
        let mut both = rods.clone();
        both[1].finish = EndRole::Pulled;
        assert_eq!(field(with(both)), "initial_shape.rods[1]");
        let mut short = rods.clone();
        short[1].points.pop();
        assert_eq!(field(with(short)), "initial_shape.rods[1].points");
        let mut onto = rods.clone();
        onto[1].points = onto[0].points.iter().map(|p| [p[0], p[1], p[2] + 1e-3]).collect();
        let errors = with(onto).validate().unwrap_err();
        assert_eq!(errors[0].field, "initial_shape.rods");
        assert!(
            errors[0].reason.contains("closer than 2h"),
            "{}",
            errors[0].reason
        );
        assert_eq!(field(with(vec![rods[0].clone(); 3])), "initial_shape.rods");
        assert_eq!(
            field(CaseParams {
                knot: KnotKind::Overhand,
                ..with(rods.clone())
            }),
            "initial_shape.rods"
        );
        let one: Vec<[f64; 3]> = rods[0].points.clone();
        let errors = CaseParams {
            initial_shape: Some(one.into()),
            ..reef()
        }
        .validate()
        .unwrap_err();
        assert_eq!(errors[0].field, "initial_shape");
        assert!(errors[0].reason.contains("ties two"), "{}", errors[0].reason);
        let object = serde_json::json!({"knot": "reef", "initial_shape": {"rods": [], "clamps": []}});
        let errors = from_partial(object.as_object().unwrap()).unwrap_err();
        assert_eq!(errors[0].field, "initial_shape");
        assert!(
            errors[0].reason.contains("unknown field `clamps`"),
            "{}",
            errors[0].reason
        );
        let object = serde_json::json!({"initial_shape": {"rods": [{"points": [], "start": "held", "finish": "free"}]}});
        let errors = from_partial(object.as_object().unwrap()).unwrap_err();
        assert!(
            errors[0].reason.contains("unknown variant `held`"),
            "{}",
            errors[0].reason
        );
    }
}
