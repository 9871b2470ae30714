//! A case's identity: blake3 of its canonical parameters and the solver version.
use solver::case::CaseParams;

/// The solver version that is part of every case key: results computed by
/// another version are never reused. The solver crate shares the workspace
/// version, so this is the solver's version too.
pub const SOLVER_VERSION: &str = concat!("knotsweep-solver/", env!("CARGO_PKG_VERSION"));

/// The canonical JSON of a case's parameters: every field present (defaults
/// filled in by [`CaseParams`]), object keys sorted, numbers in serde_json's
/// shortest round-trip form, `-0.0` written as `0.0`. Two parameter sets that
/// compare equal have the same canonical JSON.
pub fn canonical_json(params: &CaseParams) -> String {
    let value = serde_json::to_value(params).expect("CaseParams serialises to JSON");
    canonical_value(&value)
}

/// Canonical JSON text of any JSON value (sorted keys, `-0.0` as `0.0`).
pub fn canonical_value(value: &serde_json::Value) -> String {
    let mut out = String::new();
    write_canonical(value, &mut out);
    out
}

fn write_canonical(value: &serde_json::Value, out: &mut String) {
    use serde_json::Value;
    match value {
        Value::Object(map) => {
            let mut keys: Vec<&String> = map.keys().collect();
            keys.sort();
            out.push('{');
            for (i, k) in keys.into_iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                out.push_str(&serde_json::to_string(k).expect("string serialises"));
                out.push(':');
                write_canonical(&map[k], out);
            }
            out.push('}');
        }
        Value::Array(items) => {
            out.push('[');
            for (i, item) in items.iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                write_canonical(item, out);
            }
            out.push(']');
        }
        Value::Number(n) => match n.as_f64() {
            Some(f) if n.is_f64() && f == 0.0 => out.push_str("0.0"),
            _ => out.push_str(&n.to_string()),
        },
        other => out.push_str(&other.to_string()),
    }
}

/// The case key: hex blake3 of the solver version, the physics revision
/// (`solver::case::PHYSICS_REVISION`) and the canonical parameters.
pub fn case_key(params: &CaseParams) -> String {
    case_key_under(params, solver::case::PHYSICS_REVISION)
}

/// The key `params` has under physics revision `revision` ([`case_key`] is
/// the current revision's).
pub fn case_key_under(params: &CaseParams, revision: u32) -> String {
    let mut hasher = blake3::Hasher::new();
    hasher.update(SOLVER_VERSION.as_bytes());
    hasher.update(format!("\nphysics {revision}\n").as_bytes());
    hasher.update(canonical_json(params).as_bytes());
    hasher.finalize().to_hex().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_parameters_have_equal_keys_whatever_their_spelling() {
        let a: CaseParams = serde_json::from_str(r#"{"h": 0.0016, "mu": 0.1}"#).unwrap();
        let b: CaseParams = serde_json::from_str(r#"{"mu": 1e-1, "n": 3, "h": 1.6e-3}"#).unwrap();
        assert_eq!(case_key(&a), case_key(&b));
        assert_eq!(case_key(&a), case_key(&CaseParams::default()));
        let c = CaseParams {
            mu: 0.2,
            ..CaseParams::default()
        };
        assert_ne!(case_key(&a), case_key(&c));
        let zero = CaseParams {
            damping: -0.0,
            ..CaseParams::default()
        };
        assert_eq!(case_key(&zero), case_key(&CaseParams::default()));
    }

    #[test]
    fn canonical_json_sorts_keys_and_round_trips() {
        let json = canonical_json(&CaseParams::default());
        let back: CaseParams = serde_json::from_str(&json).unwrap();
        assert_eq!(back, CaseParams::default());
        assert!(json.find("\"density\"").unwrap() < json.find("\"h\"").unwrap());
    }
}
