//! Schemas the derive macros cannot produce: `CaseParams` lives in the solver
//! crate (no utoipa there), so its schema is generated from its serialisation
//! (every field, its JSON type and the paper's default) plus the descriptions
//! below (documentation only; the ranges are checked by
//! `CaseParams::validate`, which is authoritative).
use serde_json::Value;
use solver::case::CaseParams;
use utoipa::openapi::schema::{ObjectBuilder, Schema, SchemaType, Type};
use utoipa::openapi::{Ref, RefOr};

/// Documentation of each `CaseParams` field (SI units).
pub const PARAM_DOCS: &[(&str, &str)] = &[
    ("n", "Number of passes (unknotting number): an integer in 1..=8."),
    ("h", "Rod radius h (m): positive and below L/50. Paper: 1.6 mm."),
    ("mu", "Coulomb friction coefficient: 0..=2. Paper: 0.1."),
    (
        "friction_law",
        "Which tangential forces friction may take (eqs. 9-10): \"isotropic\" (default: Coulomb's disk |F_t| <= mu F_n) or \"sliding_direction\" (only along the previous step's sliding direction; fails the capstan check, kept for sensitivity studies, docs/FIDELITY.md).",
    ),
    (
        "rolling",
        "Friction acts at the rods' surfaces (default true): a contact's slip includes each rod's spin about its axis and friction torques the twist, so rods roll on each other (a rod on an inclined rod rolls at (2/3) g sin alpha). false: friction at the centre lines.",
    ),
    (
        "gravity",
        "Gravitational acceleration (m/s^2), three components each in [-1000, 1000]. Default [0, 0, 0], as in the paper's simulations; the pull is along x.",
    ),
    ("length", "Rod length L (m): 0.05..=100. Paper: 1 m."),
    (
        "nodes",
        "Node count K: 51..=4001 (the knot builder needs edges of at most 4h). Paper: 301.",
    ),
    (
        "youngs_modulus",
        "Young's modulus E (Pa): 1e3..=1e12. Paper: 1.8 MPa.",
    ),
    ("poisson_ratio", "Poisson's ratio: 0..=0.5. Paper: 0.5."),
    ("density", "Density (kg/m^3): 1..=1e5. Paper's code: 1000."),
    ("pull_speed", "Pulling speed of each clamp (m/s): 1e-5..=1."),
    (
        "dt",
        "Time step (s): 1e-6..=1e-2; with adaptive_dt the largest step; null: 0.5 ms (half the paper's code's 1 ms, converged within 0.4 %) at L = 1 m, K = 301, scaled with the square of the edge length L/(K-1).",
    ),
    (
        "adaptive_dt",
        "Halve the step (down to dt/64) while contacts penetrate and grow it back when calm; false: constant dt.",
    ),
    (
        "contact_tolerance",
        "Relative tolerance of each step's frictional contact solve (projected Gauss-Seidel, at most 200 sweeps): 1e-12..=1e-3.",
    ),
    (
        "relax_time",
        "Longest relaxation with the ends held before pulling (s): 0..=100.",
    ),
    (
        "relax_tolerance",
        "Relaxation ends when the kinetic energy falls below this times the elastic energy: 0..=1.",
    ),
    (
        "damping",
        "Mass-proportional viscous damping rate while pulling (1/s): 0..=1e4.",
    ),
    (
        "end_to_end",
        "Initial clamp-to-clamp distance (m), in (0, L]; null: the knot builder's default for n.",
    ),
    (
        "braid_length",
        "Strand length of a braid pass (m), in (0, L/2]; null: the builder's default.",
    ),
    (
        "sample_interval",
        "Series sampling interval in l_k bar: 1e-3..=100.",
    ),
    ("min_l_k_bar", "Stop when l_k bar falls below this: 0..=1e6."),
    (
        "stop_after_inversion",
        "Stop this far in l_k bar past a detected inversion; null: never early.",
    ),
    (
        "max_force_bar",
        "Stop when F bar exceeds this (the knot is tight); null: never.",
    ),
    (
        "initial_shape",
        "Start from these points instead of the builder's knot: an array of K = nodes points [x, y, z] (m); the polyline must be `length` long (within 1 %), every node between the ends along the line joining them (the clamps hold the first and last points), no two non-neighbouring segments closer than 2h, and of the knot type of an n-pass overhand knot. null: the builder's knot. Mind the body limit (64 KiB by default: about 700 points).",
    ),
];

fn param_schema(name: &str, default: &Value) -> Schema {
    let ty = match default {
        Value::Number(n) if n.is_u64() || n.is_i64() => SchemaType::Type(Type::Integer),
        Value::Number(_) => SchemaType::Type(Type::Number),
        Value::Null => SchemaType::from_iter([Type::Number, Type::Null]),
        Value::Bool(_) => SchemaType::Type(Type::Boolean),
        Value::Array(_) => SchemaType::Type(Type::Array),
        _ => SchemaType::Type(Type::String),
    };
    let doc = PARAM_DOCS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, d)| d.to_string());
    ObjectBuilder::new()
        .schema_type(ty)
        .description(doc)
        .default(Some(default.clone()))
        .into()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_parameter_is_documented() {
        for name in crate::spec::param_names() {
            assert!(
                PARAM_DOCS.iter().any(|(n, _)| *n == name),
                "undocumented parameter {name}"
            );
        }
        assert_eq!(
            PARAM_DOCS.len(),
            crate::spec::param_names().len(),
            "documentation of a removed parameter"
        );
    }
}
