//! What a sweep is: a base case plus a grid (or a named preset), and its
//! expansion into validated cases. The parameters are `solver::case::CaseParams`
//! (the one definition): the base and every grid value are applied to it by
//! field name, so any field can be set or varied.
use knotsweep_worker::store::SnapshotChoice;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};
use solver::case::CaseParams;
pub use solver::case::FieldError;
use std::collections::hash_map::Entry;
use std::collections::{BTreeMap, HashMap};
use utoipa::ToSchema;

/// The limits of a submission ([`Limits::DEFAULT`] unless `serve` is told
/// otherwise); `GET /api/limits` serves them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Largest number of cases (the product of the grid's list lengths).
    pub max_cases: usize,
    /// Largest request body (bytes); larger bodies get 413.
    pub max_body_bytes: usize,
    /// Longest sweep name (characters).
    pub max_name_len: usize,
    /// Longest `Idempotency-Key` (characters).
    pub max_idempotency_key_len: usize,
}

impl Limits {
    /// 1000 cases per sweep, 64 KiB bodies, names and idempotency keys of at
    /// most 200 characters.
    pub const DEFAULT: Self = Self {
        max_cases: 1000,
        max_body_bytes: 64 * 1024,
        max_name_len: 200,
        max_idempotency_key_len: 200,
    };
}

impl Default for Limits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A sweep to run: a base case and a grid, or a named preset.
///
/// Every field is optional. `base` sets any case parameter (the rest take the
/// paper's defaults); `grid` maps parameter names to lists of values, and the
/// sweep is their cartesian product (axes in alphabetical order, the last axis
/// varying fastest). Besides the parameters, `base.material` and the axis
/// `material` take material names (`GET /api/materials`), each setting
/// `youngs_modulus`, `density` and `poisson_ratio`. With `preset`, the preset's base and grid are used and
/// `base` overrides the preset's base (e.g. a coarser `nodes`); `grid` is then
/// not allowed.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
#[schema(example = json!({"name": "h sweep", "base": {"n": 3, "mu": 0.1}, "grid": {"h": [0.0016, 0.0024, 0.0032]}}))]
pub struct SweepSpec {
    /// Display name (at most 200 characters).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// A preset name: `fig7`, `fig9`, `fig11`, `hysteresis`, `twist`,
    /// `knots`, `bends`, `hitches` or `materials` (see `GET /api/presets`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preset: Option<String>,
    /// Case parameters common to every case (a partial `CaseParams`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<Object>, schema_with = crate::openapi::partial_case_params)]
    pub base: Option<Map<String, Value>>,
    /// Parameter name -> list of values (distinct, at least one each).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(value_type = Option<BTreeMap<String, Vec<Object>>>, example = json!({"h": [0.0016, 0.002], "mu": [0.1, 0.2]}))]
    pub grid: Option<BTreeMap<String, Vec<Value>>>,
    /// Certify every point: also run each case's refined twin (time step
    /// halved, `solver::certify`), so that the phase diagram gives each
    /// inversion its numerical uncertainty. About 3 times the cost.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub certify: Option<bool>,
    /// Which snapshots the results keep: `all` (the default), `events` (those
    /// around each inversion or flip back) or `none`. The cases and their
    /// keys are the same whatever is kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schema(schema_with = crate::openapi::snapshot_choice)]
    pub snapshots: Option<SnapshotChoice>,
}

/// A named sweep reproducing one of the paper's phase diagrams.
#[derive(Clone, Debug, Serialize, ToSchema)]
pub struct Preset {
    pub name: String,
    /// The figure it reproduces and what is varied.
    pub description: String,
    /// The preset's base (partial parameters; the rest are the defaults).
    #[schema(value_type = Object)]
    pub base: Map<String, Value>,
    #[schema(value_type = BTreeMap<String, Vec<Object>>)]
    pub grid: BTreeMap<String, Vec<Value>>,
    /// The full parameters of the base case (defaults filled in).
    #[schema(schema_with = crate::openapi::case_params_ref)]
    pub base_params: Value,
    /// Number of cases.
    pub cases: usize,
}

fn numbers(values: &[f64]) -> Vec<Value> {
    values.iter().map(|v| Value::from(*v)).collect()
}

/// The presets: the paper's Figs 7, 9 and 11, under the default (adaptive)
/// pull, whose inversions match the reference pull's at a fraction of its
/// cost (BENCHMARKS.md, "Pull protocols"); a case's F bar series away from
/// the snap is then the fast approach's, which reads high.
pub fn presets() -> Vec<Preset> {
    let grid = |name: &str, description: &str, base: Value, axes: Vec<(&str, Vec<Value>)>| {
        let base = base.as_object().cloned().expect("a preset's base is an object");
        let base_params: CaseParams =
            serde_json::from_value(Value::Object(base.clone())).expect("preset base is valid");
        let cases = axes.iter().map(|(_, v)| v.len()).product();
        Preset {
            name: name.to_string(),
            description: description.to_string(),
            base,
            grid: axes.into_iter().map(|(a, v)| (a.to_string(), v)).collect(),
            base_params: serde_json::to_value(base_params).expect("params serialise"),
            cases,
        }
    };
    let make = |name: &str, description: &str, base: Value, axis: &str, values: Vec<Value>| {
        grid(name, description, base, vec![(axis, values)])
    };
    let turns = |t: f64| {
        if t == 0.0 {
            serde_json::json!([{"pull": {}}])
        } else {
            serde_json::json!([{"rotate": {"turns": t, "ends": "one"}}, {"pull": {}}])
        }
    };
    vec![
        make(
            "fig7",
            "Paper Fig. 7: inversion point vs rod radius h (n = 3, mu = 0.1, h = 1.6 ... 3.2 mm)",
            serde_json::json!({"n": 3, "mu": 0.1}),
            "h",
            numbers(&[1.6e-3, 2.0e-3, 2.4e-3, 2.8e-3, 3.2e-3]),
        ),
        make(
            "fig9",
            "Paper Fig. 9: inversion point vs number of passes n (h = 1.6 mm, mu = 0.1, n = 1 ... 5)",
            serde_json::json!({"h": 1.6e-3, "mu": 0.1}),
            "n",
            (1..=5).map(Value::from).collect(),
        ),
        make(
            "fig11",
            "Paper Fig. 11: inversion point vs friction mu (n = 3, h = 3.4 mm, mu = 0.1 ... 0.7)",
            serde_json::json!({"n": 3, "h": 3.4e-3}),
            "mu",
            numbers(&[0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7]),
        ),
        grid(
            "hysteresis",
            "Paper Sec. 5's hysteresis: tightened past the snap, then loosened back to the start; the loop flips back \
             (n = 2 ... 5, h = 1.6 mm, mu = 0.1, gravity off and on, -z)",
            serde_json::json!({"h": 1.6e-3, "mu": 0.1, "loading": [{"pull": {}}, {"release": {}}]}),
            vec![
                ("n", (2..=5).map(Value::from).collect()),
                (
                    "gravity",
                    vec![
                        serde_json::json!([0.0, 0.0, 0.0]),
                        serde_json::json!([0.0, 0.0, -9.81]),
                    ],
                ),
            ],
        ),
        make(
            "twist",
            "The ends' relative rotation (paper Sec. 2): the finish clamp turned by -2 ... 2 turns, then pulled \
             (n = 3, h = 1.6 mm, mu = 0.1)",
            serde_json::json!({"n": 3, "h": 1.6e-3, "mu": 0.1}),
            "loading",
            [-2.0, -1.0, 0.0, 1.0, 2.0].map(turns).to_vec(),
        ),
        make(
            "knots",
            "Knots beyond the overhand: the overhand knot with n = 1 ... 4, the figure-eight and the closures of \
             the braids s1^3 (the trefoil, tied otherwise than the overhand n = 1) and s1^3 s2 s1^-1 s2 (5_2), \
             pulled tight (h = 1.6 mm, mu = 0.1)",
            serde_json::json!({"h": 1.6e-3, "mu": 0.1}),
            KNOT_AXIS,
            (1..=4)
                .map(|n| serde_json::json!({"knot": "overhand", "n": n}))
                .chain([
                    serde_json::json!("figure_eight"),
                    serde_json::json!({"knot": "braid", "braid_word": "s1 s1 s1"}),
                    serde_json::json!({"knot": "braid", "braid_word": "s1^3 s2 s1^-1 s2"}),
                ])
                .collect(),
        ),
        grid(
            "bends",
            "Bends: two rods tied by the reef, granny, thief and grief knots, pulled by their standing ends, the \
             tails free, until tight or until they slip apart: holding force against mu (Patil et al., Science \
             2020), h = 1.6 mm, mu = 0.1 ... 0.5",
            serde_json::json!({"h": 1.6e-3}),
            vec![
                (
                    KNOT_AXIS,
                    ["reef", "granny", "thief", "grief"].map(Value::from).to_vec(),
                ),
                ("mu", numbers(&[0.1, 0.2, 0.3, 0.4, 0.5])),
            ],
        ),
        grid(
            "hitches",
            "The clove hitch on a rigid, fixed pole of radius 10 h and 20 h: holding force against mu (h = 1.6 mm, \
             mu = 0.1 ... 0.5)",
            serde_json::json!({"h": 1.6e-3}),
            vec![
                (
                    KNOT_AXIS,
                    [0.016, 0.032]
                        .map(|r| serde_json::json!({"knot": "clove_hitch", "cylinder_radius": r}))
                        .to_vec(),
                ),
                ("mu", numbers(&[0.1, 0.2, 0.3, 0.4, 0.5])),
            ],
        ),
        make(
            "materials",
            "Inversion does not depend on E or rho (paper Sec. 4): one knot (n = 3, h = 1.6 mm, L = 1 m, mu = 0.1) \
             in rubber, silicone, nylon, nitinol and steel (nu changes the twisting stiffness GJ/EI = 1/(1 + nu))",
            serde_json::json!({"n": 3, "h": 1.6e-3, "length": 1.0, "mu": 0.1}),
            MATERIAL_AXIS,
            solver::case::MATERIALS
                .iter()
                .map(|m| Value::from(m.name))
                .collect(),
        ),
    ]
}

/// The knot axis: each value a knot word (`"figure_eight"`) or an object of
/// the Knot group's parameters that pick a knot (`{"knot": "overhand", "n":
/// 2}`, `{"knot": "braid", "braid_word": "s1 s1 s1"}`), so that one axis
/// lists knots of different families.
pub const KNOT_AXIS: &str = "knot";

/// The parameters a knot-axis object may set.
const KNOT_FIELDS: [&str; 4] = ["knot", "n", "braid_word", "cylinder_radius"];

/// A grid axis that is not a parameter: a named material
/// (`solver::case::MATERIALS`), setting `youngs_modulus`, `density` and
/// `poisson_ratio` together.
pub const MATERIAL_AXIS: &str = "material";

/// The parameters a grid value of `axis` sets: the value itself, or a named
/// material's three constants.
fn axis_values(axis: &str, value: &Value) -> Vec<(String, Value)> {
    if let (KNOT_AXIS, Value::Object(knot)) = (axis, value) {
        return knot.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
    }
    match (axis, value.as_str().and_then(solver::case::material)) {
        (MATERIAL_AXIS, Some(m)) => vec![
            ("youngs_modulus".to_string(), Value::from(m.youngs_modulus)),
            ("density".to_string(), Value::from(m.density)),
            ("poisson_ratio".to_string(), Value::from(m.poisson_ratio)),
        ],
        _ => vec![(axis.to_string(), value.clone())],
    }
}

pub fn preset(name: &str) -> Option<Preset> {
    presets().into_iter().find(|p| p.name == name)
}

/// One case of an expanded sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct GridCase {
    pub params: CaseParams,
    /// The grid axes' values of this case, in axis order.
    pub varied: Vec<(String, Value)>,
}

/// A validated sweep, ready to enqueue.
#[derive(Clone, Debug, PartialEq)]
pub struct Expanded {
    pub name: Option<String>,
    pub preset: Option<String>,
    /// The effective base (preset base + given base) as given (partial).
    pub base: Map<String, Value>,
    /// Axis names in order.
    pub varied: Vec<String>,
    pub cases: Vec<GridCase>,
    /// With `certify`: each case's refined twin, in the cases' order.
    pub twins: Vec<CaseParams>,
}

/// The number of grid points of a spec (its preset's grid or its own; 1
/// without a grid): a sweep's first cases are its points, any further ones
/// their refined twins.
pub fn points(spec: &SweepSpec) -> usize {
    let preset = spec.preset.as_deref().and_then(preset);
    let grid = preset.as_ref().map(|p| &p.grid).or(spec.grid.as_ref());
    grid.map_or(1, |g| g.values().map(Vec::len).product())
}

/// The full parameters of a spec's base (preset base, then the given base),
/// or why they do not parse.
pub fn base_params(spec: &SweepSpec) -> Result<CaseParams, serde_json::Error> {
    let mut base = spec
        .preset
        .as_deref()
        .and_then(preset)
        .map(|p| p.base)
        .unwrap_or_default(); // no preset: the given base alone
    if let Some(given) = &spec.base {
        base.extend(with_material(given, &mut Vec::new()));
    }
    serde_json::from_value(Value::Object(base))
}

/// A base with its `material` (a name of `GET /api/materials`, as on the
/// grid's axis) replaced by the material's three constants; an unknown name,
/// or a constant given beside it, is an error.
fn with_material(given: &Map<String, Value>, errors: &mut Vec<FieldError>) -> Map<String, Value> {
    let mut base = given.clone();
    let Some(name) = base.remove(MATERIAL_AXIS) else {
        return base;
    };
    let values = axis_values(MATERIAL_AXIS, &name);
    if values.len() == 1 {
        let known: Vec<&str> = solver::case::MATERIALS.iter().map(|m| m.name).collect();
        errors.push(FieldError::new(
            format!("base.{MATERIAL_AXIS}"),
            format!("unknown material {name}; known: {}", known.join(", ")),
        ));
        return base;
    }
    for (constant, value) in values {
        if base.contains_key(&constant) {
            errors.push(FieldError::new(
                format!("base.{constant}"),
                format!("base.{MATERIAL_AXIS} sets it: give either the material or the constants"),
            ));
        }
        base.insert(constant, value);
    }
    base
}

/// Names of `CaseParams`'s fields (`solver::case::param_names`).
pub fn param_names() -> Vec<String> {
    solver::case::param_names()
}

/// Unknown names and values of the wrong type in a partial `CaseParams`
/// (`solver::case::partial_errors`, the words the Python binding shows too).
fn check_object(prefix: &str, object: &Map<String, Value>) -> Vec<FieldError> {
    solver::case::partial_errors(object)
        .into_iter()
        .map(|e| FieldError::new(format!("{prefix}.{}", e.field), e.reason))
        .collect()
}

/// Checks a spec against the limits and expands it into cases, or returns
/// every problem found (field and reason).
pub fn expand(spec: &SweepSpec, limits: &Limits) -> Result<Expanded, Vec<FieldError>> {
    let mut errors = Vec::new();
    let preset = check_header(spec, limits, &mut errors);
    let names = param_names();
    // No preset (an unknown one is already an error): the given base alone.
    let mut base = preset.as_ref().map(|p| p.base.clone()).unwrap_or_default();
    if let Some(given) = &spec.base {
        let given = with_material(given, &mut errors);
        errors.extend(check_object("base", &given));
        base.extend(given);
    }
    let grid = preset.as_ref().map(|p| &p.grid).or(spec.grid.as_ref());
    let axes = check_grid(grid, &names, &mut errors);
    for (axis, _) in &axes {
        if spec.base.as_ref().is_some_and(|given| given.contains_key(axis)) {
            let reason = match &preset {
                Some(p) => format!("the preset {} varies {axis}: leave it out of base", p.name),
                None => format!("{axis} is also a grid axis: give it in base or in grid, not both"),
            };
            errors.push(FieldError::new(format!("base.{axis}"), reason));
        }
    }
    if axes.iter().any(|(a, _)| a == MATERIAL_AXIS) {
        for (name, _) in axis_values(MATERIAL_AXIS, &Value::from(solver::case::MATERIALS[0].name)) {
            if base.contains_key(&name) || axes.iter().any(|(a, _)| *a == name) {
                errors.push(FieldError::new(
                    format!("base.{name}"),
                    "the grid's material axis sets it: give either the material or the constants",
                ));
            }
        }
    }
    let count = axes
        .iter()
        .fold(1usize, |n, (_, values)| n.saturating_mul(values.len()));
    let certify = spec.certify == Some(true);
    let total = if certify { count.saturating_mul(2) } else { count };
    if total > limits.max_cases {
        let twins = if certify { " with their refined twins" } else { "" };
        errors.push(FieldError::new(
            "grid",
            format!(
                "{total} cases{twins} exceed the limit of {} cases per sweep",
                limits.max_cases
            ),
        ));
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    let cases = cartesian(&base, &axes, count, &mut errors);
    if errors.is_empty() {
        same_cases(&cases, &axes, &mut errors);
    }
    let twins = if certify {
        refined_twins(&cases, &mut errors)
    } else {
        Vec::new()
    };
    if !errors.is_empty() {
        return Err(errors);
    }
    Ok(Expanded {
        name: spec.name.clone(),
        preset: spec.preset.clone(),
        base,
        varied: axes.into_iter().map(|(a, _)| a).collect(),
        cases,
        twins,
    })
}

/// The refined twin of each case ([`solver::certify::refined`]); a twin out
/// of range (a time step already at its smallest) refuses `certify`.
fn refined_twins(cases: &[GridCase], errors: &mut Vec<FieldError>) -> Vec<CaseParams> {
    let twins: Vec<CaseParams> = cases
        .iter()
        .map(|c| solver::certify::refined(&c.params))
        .collect();
    if let Some(problem) = twins.iter().find_map(|t| t.range_errors().into_iter().next()) {
        errors.push(FieldError::new(
            "certify",
            format!("a refined twin (time step halved) is out of range: {problem}"),
        ));
    }
    twins
}

/// Checks the name and the preset (known, and not given with a grid);
/// returns the preset.
fn check_header(spec: &SweepSpec, limits: &Limits, errors: &mut Vec<FieldError>) -> Option<Preset> {
    if let Some(name) = &spec.name
        && name.chars().count() > limits.max_name_len
    {
        errors.push(FieldError::new(
            "name",
            format!("at most {} characters", limits.max_name_len),
        ));
    }
    let preset = spec.preset.as_ref().and_then(|name| {
        let found = preset(name);
        if found.is_none() {
            let known: Vec<String> = presets().into_iter().map(|p| p.name).collect();
            errors.push(FieldError::new(
                "preset",
                format!("unknown preset {name:?}; known: {}", known.join(", ")),
            ));
        }
        found
    });
    if spec.preset.is_some() && spec.grid.is_some() {
        errors.push(FieldError::new(
            "grid",
            "a preset defines the grid: give either preset or grid",
        ));
    }
    preset
}

/// The grid's axes with their values, each a known parameter with at least
/// one value, values of the parameter's type (two values that make one case
/// are [`same_cases`]'s to find).
fn check_grid(
    grid: Option<&BTreeMap<String, Vec<Value>>>,
    names: &[String],
    errors: &mut Vec<FieldError>,
) -> Vec<(String, Vec<Value>)> {
    let mut axes = Vec::new();
    for (axis, values) in grid.into_iter().flatten() {
        if axis == MATERIAL_AXIS {
            let known: Vec<&str> = solver::case::MATERIALS.iter().map(|m| m.name).collect();
            for (i, v) in values.iter().enumerate() {
                if !v.as_str().is_some_and(|name| known.contains(&name)) {
                    errors.push(FieldError::new(
                        format!("grid.{axis}[{i}]"),
                        format!("unknown material {v}; known: {}", known.join(", ")),
                    ));
                }
            }
            axes.push((axis.clone(), values.clone()));
            continue;
        }
        if !names.contains(axis) {
            errors.push(FieldError::new(
                format!("grid.{axis}"),
                format!("unknown parameter; known: {}", names.join(", ")),
            ));
            continue;
        }
        if values.is_empty() {
            errors.push(FieldError::new(
                format!("grid.{axis}"),
                "needs at least one value",
            ));
            continue;
        }
        for (i, v) in values.iter().enumerate() {
            if let (KNOT_AXIS, Value::Object(knot)) = (axis.as_str(), v) {
                let at = format!("grid.{axis}[{i}]");
                for name in knot.keys().filter(|k| !KNOT_FIELDS.contains(&k.as_str())) {
                    errors.push(FieldError::new(
                        format!("{at}.{name}"),
                        format!("a knot of the grid sets only {}", KNOT_FIELDS.join(", ")),
                    ));
                }
                errors.extend(check_object(&at, knot));
            } else if let Some(reason) = solver::case::type_error(axis, v) {
                errors.push(FieldError::new(format!("grid.{axis}[{i}]"), reason));
            }
        }
        axes.push((axis.clone(), values.clone()));
    }
    axes
}

/// Points of the grid that are one case (one case key: equal values written
/// apart, as `1` and `1.0` or `0` and `-0.0`, a default spelt out, a null
/// given for an absent field): each later point named, with the earlier.
fn same_cases(cases: &[GridCase], axes: &[(String, Vec<Value>)], errors: &mut Vec<FieldError>) {
    let mut first: HashMap<String, usize> = HashMap::with_capacity(cases.len());
    for (position, case) in cases.iter().enumerate() {
        let earlier = match first.entry(knotsweep_worker::case_key(&case.params)) {
            Entry::Vacant(v) => {
                v.insert(position);
                continue;
            }
            Entry::Occupied(o) => *o.get(),
        };
        let (a, b) = (grid_index(earlier, axes), grid_index(position, axes));
        let at = |k: usize, index: &[usize]| format!("grid.{}[{}]", axes[k].0, index[k]);
        let differ: Vec<usize> = (0..axes.len()).filter(|&k| a[k] != b[k]).collect();
        let field = at(differ[0], &b);
        if errors.iter().any(|e| e.field == field) {
            continue;
        }
        let others = |index: &[usize]| {
            differ[1..]
                .iter()
                .map(|&k| at(k, index))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let reason = if differ.len() == 1 {
            format!("the same case as {}", at(differ[0], &a))
        } else {
            format!(
                "with {}, the same case as {} with {}",
                others(&b),
                at(differ[0], &a),
                others(&a)
            )
        };
        errors.push(FieldError::new(field, reason));
    }
}

/// Each axis's value index at `position` of the grid (last axis fastest).
fn grid_index(mut position: usize, axes: &[(String, Vec<Value>)]) -> Vec<usize> {
    let mut index = vec![0; axes.len()];
    for (k, (_, values)) in axes.iter().enumerate().rev() {
        index[k] = position % values.len();
        position /= values.len();
    }
    index
}

/// The `count` cases of the cartesian product of `axes` over `base`, last
/// axis fastest, each validated (the knot built once per distinct geometry);
/// stops after 50 problems.
fn cartesian(
    base: &Map<String, Value>,
    axes: &[(String, Vec<Value>)],
    count: usize,
    errors: &mut Vec<FieldError>,
) -> Vec<GridCase> {
    let mut cases = Vec::with_capacity(count);
    let mut builds = solver::case::BuildChecks::default();
    let mut index = vec![0usize; axes.len()];
    for _ in 0..count {
        let mut object = base.clone();
        let mut varied = Vec::with_capacity(axes.len());
        for ((axis, values), &i) in axes.iter().zip(&index) {
            object.extend(axis_values(axis, &values[i]));
            varied.push((axis.clone(), values[i].clone()));
        }
        match serde_json::from_value::<CaseParams>(Value::Object(object)) {
            Ok(params) => {
                if let Err(problems) = params.validate_in(&mut builds) {
                    for p in problems {
                        let on_axis = |axis: &str| {
                            axis == p.field || (axis == KNOT_AXIS && KNOT_FIELDS.contains(&p.field.as_str()))
                        };
                        let field = match axes.iter().zip(&index).find(|((axis, _), _)| on_axis(axis)) {
                            Some(((axis, _), i)) => format!("grid.{axis}[{i}]"),
                            None => format!("base.{}", p.field),
                        };
                        if !errors.iter().any(|e: &FieldError| e.field == field) {
                            errors.push(FieldError::new(field, p.reason));
                        }
                    }
                }
                cases.push(GridCase { params, varied });
            }
            Err(e) => errors.push(FieldError::new("base", e.to_string())),
        }
        for k in (0..index.len()).rev() {
            index[k] += 1;
            if index[k] < axes[k].1.len() {
                break;
            }
            index[k] = 0;
        }
        if errors.len() >= 50 {
            break;
        }
    }
    cases
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(json: Value) -> SweepSpec {
        serde_json::from_value(json).unwrap()
    }

    fn fields(r: Result<Expanded, Vec<FieldError>>) -> Vec<String> {
        r.unwrap_err().into_iter().map(|e| e.field).collect()
    }

    /// `snapshots` takes its three words (`all` when left out), names
    /// itself when refused, and leaves the cases and their keys alone.
    #[test]
    fn the_snapshot_choice_is_read_and_changes_no_case() {
        let keys = |json: Value| {
            let (spec, _) = crate::Core::parse_spec(json.to_string().as_bytes()).unwrap();
            let expanded = expand(&spec, &Limits::default()).unwrap();
            let keys: Vec<String> = (expanded.cases.iter())
                .map(|c| knotsweep_worker::case_key(&c.params))
                .collect();
            (spec.snapshots, keys)
        };
        let (choice, all) = keys(serde_json::json!({"preset": "hysteresis"}));
        assert_eq!(choice, None);
        for (word, expected) in [
            ("all", SnapshotChoice::All),
            ("events", SnapshotChoice::Events),
            ("none", SnapshotChoice::None),
        ] {
            let (choice, these) = keys(serde_json::json!({"preset": "hysteresis", "snapshots": word}));
            assert_eq!((choice, &these), (Some(expected), &all), "{word}");
        }
        let refused = crate::Core::parse_spec(br#"{"snapshots": "some"}"#).unwrap_err();
        match refused {
            crate::error::CoreError::Invalid(fields) => {
                assert_eq!(fields[0].field, "snapshots", "{fields:?}")
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn certify_adds_a_refined_twin_per_case_and_counts_it_against_the_limit() {
        let l = Limits::default();
        let plain = expand(&spec(serde_json::json!({"preset": "fig9"})), &l).unwrap();
        assert!(plain.twins.is_empty());
        let certified = expand(&spec(serde_json::json!({"preset": "fig9", "certify": true})), &l).unwrap();
        assert_eq!(
            certified.cases, plain.cases,
            "the points are the uncertified sweep's"
        );
        assert_eq!(certified.twins.len(), 5);
        for (twin, point) in certified.twins.iter().zip(&certified.cases) {
            assert_eq!(twin.time_step(), point.params.time_step() / 2.0);
            assert_eq!(twin.n, point.params.n);
        }
        assert_eq!(
            points(&spec(serde_json::json!({"preset": "fig9", "certify": true}))),
            5
        );
        assert_eq!(
            points(&spec(
                serde_json::json!({"grid": {"n": [2, 3], "mu": [0.1, 0.2, 0.3]}})
            )),
            6
        );
        assert_eq!(points(&spec(serde_json::json!({"base": {"n": 2}}))), 1);
        let small = Limits {
            max_cases: 6,
            ..Limits::default()
        };
        let grid = serde_json::json!({"grid": {"mu": [0.1, 0.2, 0.3, 0.4]}});
        assert!(expand(&spec(grid.clone()), &small).is_ok());
        let mut certified = grid;
        certified["certify"] = true.into();
        assert_eq!(
            fields(expand(&spec(certified), &small)),
            ["grid"],
            "8 cases with the twins"
        );
        let finest = serde_json::json!({"base": {"dt": 1.5e-9}, "certify": true});
        let errors = expand(&spec(finest), &l).unwrap_err();
        assert_eq!(errors[0].field, "certify", "{errors:?}");
        assert!(errors[0].reason.contains("dt"), "{errors:?}");
    }

    #[test]
    fn presets_are_the_papers_grids() {
        let l = Limits::default();
        let fig7 = expand(&spec(serde_json::json!({"preset": "fig7"})), &l).unwrap();
        assert_eq!(fig7.varied, ["h"]);
        let hs: Vec<f64> = fig7.cases.iter().map(|c| c.params.h).collect();
        assert_eq!(hs, [1.6e-3, 2.0e-3, 2.4e-3, 2.8e-3, 3.2e-3]);
        assert!(fig7.cases.iter().all(|c| c.params.n == 3 && c.params.mu == 0.1));
        let fig9 = expand(&spec(serde_json::json!({"preset": "fig9"})), &l).unwrap();
        let ns: Vec<u32> = fig9.cases.iter().map(|c| c.params.n).collect();
        assert_eq!(ns, [1, 2, 3, 4, 5]);
        assert!(
            fig9.cases
                .iter()
                .all(|c| c.params.h == 1.6e-3 && c.params.mu == 0.1)
        );
        let fig11 = expand(&spec(serde_json::json!({"preset": "fig11"})), &l).unwrap();
        let mus: Vec<f64> = fig11.cases.iter().map(|c| c.params.mu).collect();
        assert_eq!(mus, [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7]);
        assert!(
            fig11
                .cases
                .iter()
                .all(|c| c.params.n == 3 && c.params.h == 3.4e-3)
        );
        let coarse = expand(
            &spec(serde_json::json!({"preset": "fig9", "base": {"nodes": 161}})),
            &l,
        )
        .unwrap();
        assert!(
            coarse
                .cases
                .iter()
                .all(|c| c.params.nodes == Some(161) && c.params.h == 1.6e-3)
        );
    }

    /// The knot axis takes words and objects of knot parameters; the
    /// `knots` preset lists knots of every family, each named.
    #[test]
    fn the_knot_axis_lists_knots_of_every_family() {
        let l = Limits::default();
        let knots = expand(&spec(serde_json::json!({"preset": "knots"})), &l).unwrap();
        assert_eq!(knots.varied, ["knot"]);
        let labels: Vec<String> = knots.cases.iter().map(|c| c.params.knot_label()).collect();
        assert_eq!(
            labels,
            [
                "overhand n = 1",
                "overhand n = 2",
                "overhand n = 3",
                "overhand n = 4",
                "figure_eight",
                "braid s1 s1 s1",
                "braid s1^3 s2 s1^-1 s2"
            ]
        );
        assert!(
            knots
                .cases
                .iter()
                .all(|c| c.params.h == 1.6e-3 && c.params.mu == 0.1)
        );
        let bends = expand(&spec(serde_json::json!({"preset": "bends"})), &l).unwrap();
        assert_eq!(bends.varied, ["knot", "mu"]);
        let points: Vec<(String, f64)> = (bends.cases.iter())
            .map(|c| (c.params.knot_label(), c.params.mu))
            .collect();
        assert_eq!(points.len(), 20);
        assert_eq!(points[0], ("reef".to_string(), 0.1));
        assert_eq!(points[19], ("grief".to_string(), 0.5));
        let hitches = expand(&spec(serde_json::json!({"preset": "hitches"})), &l).unwrap();
        assert_eq!(hitches.varied, ["knot", "mu"]);
        let points: Vec<(String, f64, f64)> = (hitches.cases.iter())
            .map(|c| (c.params.knot_label(), c.params.pole_radius(), c.params.mu))
            .collect();
        assert_eq!(points.len(), 10);
        assert_eq!(points[0].1, 0.016);
        assert_eq!(points[9].1, 0.032);
        assert_eq!(points[0].0, "clove_hitch R = 0.016 m");
        assert_eq!(points[9].0, "clove_hitch R = 0.032 m");
        assert!(hitches.cases.iter().all(|c| c.params.h == 1.6e-3));
        let bad = spec(serde_json::json!({"grid": {"knot": [
            "figure_eight",
            {"knot": "overhand", "mu": 0.2},
            "granny_square"
        ]}}));
        assert_eq!(fields(expand(&bad, &l)), ["grid.knot[1].mu", "grid.knot[2]"]);
        let link = spec(serde_json::json!({"grid": {"knot": [
            "figure_eight",
            {"knot": "braid", "braid_word": "s1 s3"}
        ]}}));
        assert_eq!(fields(expand(&link, &l)), ["grid.knot[1]"]);
    }

    #[test]
    fn grid_is_the_cartesian_product_last_axis_fastest() {
        let e = expand(
            &spec(serde_json::json!({"base": {"nodes": 161}, "grid": {"n": [1, 2], "mu": [0.1, 0.2, 0.3]}})),
            &Limits::default(),
        )
        .unwrap();
        assert_eq!(e.varied, ["mu", "n"]);
        let got: Vec<(f64, u32)> = e.cases.iter().map(|c| (c.params.mu, c.params.n)).collect();
        assert_eq!(got, [(0.1, 1), (0.1, 2), (0.2, 1), (0.2, 2), (0.3, 1), (0.3, 2)]);
        assert!(e.cases.iter().all(|c| c.params.nodes == Some(161)));
        let single = expand(&SweepSpec::default(), &Limits::default()).unwrap();
        assert_eq!(single.cases.len(), 1);
        assert_eq!(single.cases[0].params, CaseParams::default());
    }

    #[test]
    fn bad_input_names_the_field() {
        let l = Limits::default();
        assert_eq!(
            fields(expand(&spec(serde_json::json!({"base": {"radius": 1}})), &l)),
            ["base.radius"]
        );
        assert_eq!(
            fields(expand(&spec(serde_json::json!({"base": {"n": 2.5}})), &l)),
            ["base.n"]
        );
        assert_eq!(
            fields(expand(&spec(serde_json::json!({"base": {"mu": "high"}})), &l)),
            ["base.mu"]
        );
        assert_eq!(
            fields(expand(&spec(serde_json::json!({"base": {"n": 9}})), &l)),
            ["base.n"]
        );
        assert_eq!(
            fields(expand(&spec(serde_json::json!({"grid": {"n": [1, 9]}})), &l)),
            ["grid.n[1]"]
        );
        assert_eq!(
            fields(expand(
                &spec(serde_json::json!({"grid": {"h": [0.001, 0.03]}})),
                &l
            )),
            ["grid.h[1]"]
        );
        assert_eq!(
            fields(expand(&spec(serde_json::json!({"grid": {"n": [1, 1.5]}})), &l)),
            ["grid.n[1]"]
        );
        assert_eq!(
            fields(expand(&spec(serde_json::json!({"grid": {"foo": [1]}})), &l)),
            ["grid.foo"]
        );
        assert_eq!(
            fields(expand(&spec(serde_json::json!({"grid": {"n": []}})), &l)),
            ["grid.n"]
        );
        assert_eq!(
            fields(expand(&spec(serde_json::json!({"grid": {"n": [1, 1]}})), &l)),
            ["grid.n[1]"]
        );
        assert_eq!(
            fields(expand(&spec(serde_json::json!({"preset": "fig8"})), &l)),
            ["preset"]
        );
        assert_eq!(
            fields(expand(
                &spec(serde_json::json!({"preset": "fig7", "grid": {"n": [1]}})),
                &l
            )),
            ["grid"]
        );
        let many: Vec<Value> = (0..40).map(|i| Value::from(0.01 * f64::from(i))).collect();
        let big = spec(serde_json::json!({"grid": {"mu": many, "relax_time": many}}));
        assert_eq!(fields(expand(&big, &l)), ["grid"]);
        assert_eq!(
            fields(expand(&spec(serde_json::json!({"name": "x".repeat(201)})), &l)),
            ["name"]
        );
    }
}
