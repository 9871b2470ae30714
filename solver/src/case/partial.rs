//! A partial case: some parameters by name as JSON values, the rest the
//! paper's defaults, as the API's `base` and grid axes and the Python
//! binding's keywords give them. Unknown names and values of the wrong type
//! are refused here, in the words both show.
use super::{CaseParams, FieldError, PARAMETERS, Range, ValidCase};
use serde_json::{Map, Value};

/// Names of `CaseParams`'s fields (from its serialisation: no second list).
pub fn param_names() -> Vec<String> {
    match serde_json::to_value(CaseParams::default()) {
        Ok(Value::Object(m)) => m.keys().cloned().collect(),
        _ => Vec::new(),
    }
}

/// Why `value` cannot be parameter `name`'s (its JSON type), if it cannot,
/// in the words of the table ([`Parameter::expected`](super::Parameter::expected)):
/// `must be a whole number in 1..=8, got "three"`. The range is not checked
/// here; a loading program's fault is its parser's to tell (which stage,
/// which key), as is a start shape's of rods (which key).
///
/// ```
/// use serde_json::json;
/// use solver::case::type_error;
///
/// assert_eq!(type_error("n", &json!("three")).unwrap(), "must be a whole number in 1..=8, got \"three\"");
/// assert_eq!(type_error("h", &json!([1])).unwrap(), "must be a number in [L/16000, L/50) m, got [1]");
/// assert_eq!(type_error("mu", &json!(1)), None, "a range is checked later");
/// ```
pub fn type_error(name: &str, value: &Value) -> Option<String> {
    let mut object = Map::new();
    object.insert(name.to_string(), value.clone());
    let error = serde_json::from_value::<CaseParams>(Value::Object(object)).err()?;
    Some(match PARAMETERS.iter().find(|p| p.name == name) {
        Some(p) if p.range == Range::Points && value.is_object() => error.to_string(),
        Some(p) if p.range != Range::Program => format!("must be {}, got {}", p.expected(), shown(value)),
        _ => error.to_string(),
    })
}

/// A value as a refusal quotes it: its JSON, cut after 40 characters.
fn shown(value: &Value) -> String {
    let text = value.to_string();
    match text.char_indices().nth(40) {
        Some((cut, _)) => format!("{}...", &text[..cut]),
        None => text,
    }
}

/// Unknown names and values of the wrong type in a partial `CaseParams`,
/// each naming its field.
pub fn partial_errors(object: &Map<String, Value>) -> Vec<FieldError> {
    let names = param_names();
    let mut errors = Vec::new();
    for (name, value) in object {
        let reason = if names.contains(name) {
            type_error(name, value)
        } else {
            Some(format!("unknown parameter; known: {}", names.join(", ")))
        };
        if let Some(reason) = reason {
            errors.push(FieldError {
                field: name.clone(),
                reason,
            });
        }
    }
    errors
}

/// The case of a partial `CaseParams` over the defaults, validated
/// ([`CaseParams::validated`]), or every problem: unknown names and wrong
/// types first, then the ranges and the start shape.
///
/// ```
/// use serde_json::json;
/// use solver::case::from_partial;
///
/// let object = json!({"mu": -1.0, "nu": 0.3});
/// let errors = from_partial(object.as_object().unwrap()).unwrap_err();
/// assert_eq!(errors[0].field, "nu");
/// assert!(errors[0].reason.starts_with("unknown parameter; known: "));
/// let errors = from_partial(json!({"mu": -1.0}).as_object().unwrap()).unwrap_err();
/// assert_eq!(errors[0].to_string(), "mu: must be in [0, 2], got -1");
/// ```
pub fn from_partial(object: &Map<String, Value>) -> Result<ValidCase, Vec<FieldError>> {
    let errors = partial_errors(object);
    if !errors.is_empty() {
        return Err(errors);
    }
    let params: CaseParams = serde_json::from_value(Value::Object(object.clone())).map_err(|e| {
        vec![FieldError {
            field: "params".to_string(),
            reason: e.to_string(),
        }]
    })?;
    params.validated()
}
