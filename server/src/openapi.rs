//! Schemas the derive macros cannot produce: `CaseParams` and `FieldError`
//! live in the solver crate (no utoipa there). `CaseParams`'s schema is generated from its serialisation
//! (every field, its JSON type and the paper's default) plus the table
//! `solver::case::PARAMETERS`: each field's description, its words and its
//! bounds where they are fixed numbers (`CaseParams::validate` checks the
//! same table and is authoritative), its group as `x-group` (the web
//! form's sections), its SI unit as `x-unit` and the paper's symbol as
//! `x-symbol` (`report::symbols`).
use knotsweep_worker::store::SnapshotChoice;
use serde_json::Value;
use solver::case::{Bound, CaseParams, PARAMETERS, Parameter, Range};
use solver::snapshot::SnapshotLabel;
use utoipa::openapi::extensions::Extensions;
use utoipa::openapi::schema::{ArrayBuilder, ObjectBuilder, Schema, SchemaType, Type};
use utoipa::openapi::{Ref, RefOr};

fn param_schema(name: &str, default: &Value) -> Schema {
    let parameter = PARAMETERS.iter().find(|p| p.name == name);
    let integer = parameter.is_some_and(|p| matches!(p.range, Range::Integers(..)));
    let text = parameter.is_some_and(|p| p.range == Range::BraidWord);
    let shape = parameter.is_some_and(|p| p.range == Range::Points);
    let ty = match default {
        Value::Null if text => SchemaType::from_iter([Type::String, Type::Null]),
        Value::Null if shape => SchemaType::from_iter([Type::Array, Type::Object, Type::Null]),
        Value::Number(n) if n.is_u64() || n.is_i64() => SchemaType::Type(Type::Integer),
        Value::Number(_) => SchemaType::Type(Type::Number),
        Value::Null if integer => SchemaType::from_iter([Type::Integer, Type::Null]),
        Value::Null => SchemaType::from_iter([Type::Number, Type::Null]),
        Value::Bool(_) => SchemaType::Type(Type::Boolean),
        Value::Array(_) => SchemaType::Type(Type::Array),
        _ => SchemaType::Type(Type::String),
    };
    let object = ObjectBuilder::new()
        .schema_type(ty)
        .default(Some(default.clone()));
    match parameter {
        Some(p) => {
            let group = Extensions::from_iter([
                ("x-group", serde_json::to_value(p.group).expect("a word")),
                ("x-unit", Value::from(p.unit)),
                ("x-symbol", Value::from(report::symbols::symbol(p.name))),
            ]);
            with_range(object.description(Some(p.description())), p).extensions(Some(group))
        }
        None => object,
    }
    .into()
}

/// The schema's `enum`, `minimum` and `maximum` (or their exclusive forms)
/// from the parameter's range, where the range is fixed.
fn with_range(object: ObjectBuilder, p: &Parameter) -> ObjectBuilder {
    match p.range {
        Range::Words(words) => object.enum_values(Some(words.iter().copied())),
        Range::Integers(lo, hi) => object.minimum(Some(lo as f64)).maximum(Some(hi as f64)),
        Range::Interval(lo, hi) => {
            let object = match lo {
                Bound::Closed(x) => object.minimum(Some(x)),
                Bound::Open(x) => object.exclusive_minimum(Some(x)),
            };
            match hi {
                Bound::Closed(y) => object.maximum(Some(y)),
                Bound::Open(y) if y.is_finite() => object.exclusive_maximum(Some(y)),
                Bound::Open(_) => object,
            }
        }
        _ => object,
    }
}

/// The `CaseParams` object schema: every field with its type and default.
pub fn case_params_schema() -> Schema {
    let defaults = serde_json::to_value(CaseParams::default()).expect("params serialise");
    let mut object = ObjectBuilder::new().description(Some(
        "Parameters of one overhand-knot tightening case (solver::case::CaseParams), SI units. \
         Every field is optional in requests and defaults to the paper's value; unknown fields are refused.",
    ));
    if let Value::Object(map) = &defaults {
        for (name, default) in map {
            object = object.property(name, param_schema(name, default));
        }
    }
    object
        .additional_properties(Some(utoipa::openapi::schema::AdditionalProperties::FreeForm(
            false,
        )))
        .into()
}

/// A reference to the `CaseParams` component.
pub fn case_params_ref() -> RefOr<Schema> {
    RefOr::Ref(Ref::from_schema_name("CaseParams"))
}

/// A partial `CaseParams` (base of a sweep): same schema, all optional.
pub fn partial_case_params() -> RefOr<Schema> {
    case_params_ref()
}

/// A sweep's `snapshots`: one of the words of `SnapshotChoice`, `all` by
/// default.
pub fn snapshot_choice() -> Schema {
    let words = SnapshotChoice::ALL.map(SnapshotChoice::as_str);
    ObjectBuilder::new()
        .schema_type(SchemaType::Type(Type::String))
        .description(Some(
            "Which snapshots the results keep: all, events (those around each inversion or flip back) or none. \
             The cases and their keys are the same whatever is kept.",
        ))
        .enum_values(Some(words))
        .default(Some(Value::from(SnapshotChoice::default().as_str())))
        .into()
}

/// What a snapshot labelled `label` shows, in words.
fn label_text(label: SnapshotLabel) -> String {
    use solver::case::StageKind;
    use solver::protocol::EventKind;
    use solver::snapshot::EventWhen;
    let event = |kind| match kind {
        EventKind::Inversion => "inversion",
        EventKind::FlipBack => "flip back",
        EventKind::Snap => "snap",
        EventKind::SlipThrough => "slip through",
    };
    match label {
        SnapshotLabel::Relaxed => "relaxed start".to_string(),
        SnapshotLabel::Stage(kind) => match kind {
            StageKind::Pull => "pulling",
            StageKind::Release => "releasing",
            StageKind::Hold => "holding",
            StageKind::Rotate => "rotating",
            StageKind::Soft => "pulling on springs",
        }
        .to_string(),
        SnapshotLabel::Set => "the bend set, its tails let go".to_string(),
        SnapshotLabel::Event(when, kind) => match when {
            EventWhen::Near => format!("approaching the {}", event(kind)),
            EventWhen::Before => format!("just before the {}", event(kind)),
            EventWhen::At => event(kind).to_string(),
            EventWhen::After => format!("after the {}", event(kind)),
        },
        SnapshotLabel::Final => "end of the program".to_string(),
        SnapshotLabel::Failure => "where it failed".to_string(),
        SnapshotLabel::Sample => "a sample".to_string(),
    }
}

/// The `SnapshotLabel` component: the words a stored snapshot's `label`
/// takes (`solver::snapshot::SnapshotLabel`), and as `x-labels` each word's
/// `description`, the `event` it is around (an event `kind`, or null) and
/// whether it is the snapshot `at_event`: the web page reads the labels
/// from here.
pub fn snapshot_label_schema() -> Schema {
    let kept: Vec<SnapshotLabel> = (SnapshotLabel::all().into_iter())
        .filter(|l| *l != SnapshotLabel::Sample)
        .collect();
    let labels: serde_json::Map<String, Value> = (kept.iter())
        .map(|&label| {
            let at_event = matches!(label, SnapshotLabel::Event(solver::snapshot::EventWhen::At, _));
            let about = serde_json::json!({
                "description": label_text(label),
                "event": label.event(),
                "at_event": at_event,
            });
            (label.to_string(), about)
        })
        .collect();
    let extensions = Extensions::from_iter([("x-labels", Value::Object(labels))]);
    ObjectBuilder::new()
        .schema_type(SchemaType::Type(Type::String))
        .description(Some(
            "What a snapshot shows: the relaxed start, a stage's regular snapshots (by the stage's key), those \
             around an event (`near_`, `before_`, `at_`, `after_` and the event's kind), the end (`final`) or \
             where the case failed (`failure`).",
        ))
        .enum_values(Some(kept.iter().map(|l| l.to_string())))
        .extensions(Some(extensions))
        .into()
}

/// The `FieldError` component (`solver::case::FieldError`).
pub fn field_error_schema() -> Schema {
    let text = |description: &str| {
        ObjectBuilder::new()
            .schema_type(SchemaType::Type(Type::String))
            .description(Some(description))
    };
    ObjectBuilder::new()
        .description(Some("A field and why its value was refused."))
        .property(
            "field",
            text("Where: `base.h`, `grid.n[2]`, `grid`, `preset`, `name`, `body`, a header's name, ..."),
        )
        .required("field")
        .property("reason", text("Why, in the words of the parameter table."))
        .required("reason")
        .into()
}

/// A list of `FieldError`s.
pub fn field_errors() -> Schema {
    ArrayBuilder::new()
        .items(Ref::from_schema_name("FieldError"))
        .build()
        .into()
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// The table's words, bounds and texts reach the schema.
    #[test]
    fn the_table_reaches_the_schema() {
        let schema = serde_json::to_value(case_params_schema()).unwrap();
        let props = &schema["properties"];
        assert_eq!(props["protocol"]["enum"], json!(["reference", "adaptive"]));
        assert_eq!(props["mu"]["minimum"].as_f64(), Some(0.0));
        assert_eq!(props["mu"]["maximum"].as_f64(), Some(2.0));
        assert_eq!(props["max_force_bar"]["exclusiveMinimum"].as_f64(), Some(0.0));
        assert!(props["max_force_bar"].get("exclusiveMaximum").is_none());
        assert_eq!(props["mu"]["x-group"], json!("friction"));
        assert_eq!(props["nodes"]["type"], json!(["integer", "null"]));
        let h = props["h"]["description"].as_str().unwrap();
        assert!(h.contains("Range: [L/16000, L/50) m."), "{h}");
    }

    /// Every stored label is listed with its description, and the
    /// snapshots at an event are the `at_` ones.
    #[test]
    fn the_snapshot_labels_reach_the_schema() {
        let schema = serde_json::to_value(snapshot_label_schema()).unwrap();
        let words = schema["enum"].as_array().unwrap();
        let labels = schema["x-labels"].as_object().unwrap();
        assert_eq!(words.len(), labels.len());
        assert!(!labels.contains_key("sample"), "never stored");
        for word in words {
            let label = SnapshotLabel::parse(word.as_str().unwrap()).unwrap();
            let about = &labels[&label.to_string()];
            assert!(!about["description"].as_str().unwrap().is_empty());
            assert_eq!(about["event"], serde_json::to_value(label.event()).unwrap());
        }
        assert_eq!(
            labels["at_inversion"],
            json!({"description": "inversion", "event": "inversion", "at_event": true})
        );
        assert_eq!(labels["before_flip_back"]["at_event"], json!(false));
        assert_eq!(
            labels["pull"],
            json!({"description": "pulling", "event": null, "at_event": false})
        );
    }

    #[test]
    fn every_parameter_is_documented() {
        for name in crate::spec::param_names() {
            assert!(
                PARAMETERS.iter().any(|p| p.name == name),
                "undocumented parameter {name}"
            );
        }
        assert_eq!(
            PARAMETERS.len(),
            crate::spec::param_names().len(),
            "documentation of a removed parameter"
        );
    }
}
