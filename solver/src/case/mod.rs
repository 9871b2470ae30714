//! The one definition of a knot case: its parameters ([`CaseParams`], the
//! table [`PARAMETERS`] that documents and bounds them), their validation and
//! the case to run ([`ValidCase`]), shared by the CLI, the API, the queue and
//! the solver. SI units.
mod loading;
mod materials;
mod params;
mod partial;
mod scales;
mod shape;
mod table;

pub use crate::contact::{Candidates, ContactSolve, FrictionLaw, Geometry};
use crate::knot::{Knot, KnotSpec, StartShape};
use crate::words::display_as_word;
pub use loading::{Direction, Ends, Hold, LoadStage, Rotate, Soft, StageKind, Target, default_program};
pub use materials::{MATERIALS, NamedMaterial, material};
pub use params::{CaseParams, PARAMETERS};
pub use partial::{from_partial, param_names, partial_errors, type_error};
pub use scales::{
    EDGE_RADII, REFERENCE_DT, REFERENCE_EDGE, REFERENCE_RADIUS, Scales, default_nodes, pull_rate,
    reference_pull_rate,
};
use serde::{Deserialize, Serialize};
pub use shape::{EndRole, InitialShape, ShapeRod};
pub use table::{Bound, Group, Parameter, Range};

/// Revision of the physics: raised whenever a change to the model or its
/// defaults changes results, and part of every case's cache key, so that
/// results computed under older physics are never served as current. What
/// each revision changed, and why, is in CHANGELOG.md.
pub const PHYSICS_REVISION: u32 = 23;

/// How fast the clamps move along the pull (case parameter `protocol`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Protocol {
    /// The whole pull at `pull_speed` (the paper's protocol).
    Reference,
    /// Fast far from the snap, slow through it: the clamps speed up while the
    /// knot is far from its snap (damped, sparing the sliding along the rod,
    /// with checkpoints); once a snap is seen the pull goes back to a
    /// checkpoint before it, lets the knot settle and pulls through the snap
    /// at `pull_speed`. Its constants and what they were chosen on are in
    /// `solver::protocol`; the report's `stages` list what ran. Its
    /// inversions match the reference pull's (BENCHMARKS.md); its fast
    /// approach reads F bar high, so force curves are the reference's.
    #[default]
    Adaptive,
}

display_as_word!(Protocol, KnotKind);

/// Which knot of the catalog a case ties (case parameter `knot`,
/// [`crate::knot`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum KnotKind {
    /// The overhand knot with `n` passes (the paper's).
    #[default]
    Overhand,
    /// The figure-eight knot.
    FigureEight,
    /// The closure of `braid_word`.
    Braid,
    /// Two rods tied by the reef knot (square knot), pulled by their
    /// standing ends ([`crate::knot::bends`]).
    Reef,
    /// The granny knot: the reef with one half knot mirrored.
    Granny,
    /// The thief knot: the reef pulled by the other end of one rod.
    Thief,
    /// The grief knot: the granny pulled by the other end of one rod.
    Grief,
    /// The fisherman's knot: each rod's overhand knot round the other's
    /// standing part ([`crate::knot::fisherman`]).
    Fisherman,
    /// The clove hitch round a rigid, fixed cylinder ([`crate::knot::hitch`]).
    CloveHitch,
}

impl KnotKind {
    /// Whether it is held by friction against another body, with free
    /// tails, and may slip: a bend or a hitch.
    pub fn holds_by_friction(self) -> bool {
        self.bend().is_some() || self == KnotKind::CloveHitch
    }

    /// The bend it ties, if it is one.
    pub fn bend(self) -> Option<crate::knot::Bend> {
        use crate::knot::Bend;
        match self {
            KnotKind::Reef => Some(Bend::Reef),
            KnotKind::Granny => Some(Bend::Granny),
            KnotKind::Thief => Some(Bend::Thief),
            KnotKind::Grief => Some(Bend::Grief),
            KnotKind::Fisherman => Some(Bend::Fisherman),
            KnotKind::Overhand | KnotKind::FigureEight | KnotKind::Braid | KnotKind::CloveHitch => None,
        }
    }
}

/// F bar at which a bend's or a hitch's pull stops, tight, when
/// `max_force_bar` is not given (neither has an inversion, and their free
/// tails keep their own length from the stopping rule `min_l_k_bar`).
pub const BEND_TIGHT_FORCE_BAR: f64 = 0.05;
/// F bar to which a bend's first pull tightens it with its tails held, to
/// set it: half the default tight force, so that a bend that holds takes
/// twice its setting load with its tails free.
pub const BEND_SET_FORCE_BAR: f64 = 0.5 * BEND_TIGHT_FORCE_BAR;
/// F bar to which a set bend is eased, its tails still held, before they
/// are let go, when `eased_force_bar` is not given (a tenth of the setting
/// load): a bend let go under a load it cannot hold slides apart at once,
/// and its holding force would be read on that fall; let go nearly at rest,
/// the pull that follows loads it up to what it holds. Not zero: an end that
/// no longer pulls still drags its rod through the damping as it moves back.
/// Easing moves every end back towards the knot, so a lower eased load also
/// loosens the set bend more (docs/FIDELITY.md, Bends).
pub const BEND_EASED_FORCE_BAR: f64 = 0.1 * BEND_SET_FORCE_BAR;
/// F bar at which any other knot's tightening stops when `max_force_bar` is
/// not given: its rod stretched by a quarter (strain F bar / 4, EA / EI = 4 /
/// h^2), far past its linear elasticity. A knot that locks above
/// `min_l_k_bar` in its own length would otherwise be pulled on without end,
/// its rod stretching, since its own length cannot reach it; one held by
/// friction gives nothing until it slides (the paper's rod n = 6 at mu = 0.5
/// holds its own length from F bar 0.14 to 0.59 before it slides on, `knotsweep
/// run --n 6 --mu 0.5 --max-force-bar 10`), so that no rule on its give tells
/// a locked knot from a stuck one.
pub const STRETCH_LIMIT_FORCE_BAR: f64 = 1.0;
/// Largest node count K.
pub const MAX_NODES: usize = 4001;
/// h >= L / this: with edges of at most 4h ([`crate::knot::build`]) and at most
/// [`MAX_NODES`] nodes, a thinner rod cannot be meshed.
pub const MIN_RADIUS_DIVISOR: f64 = 16000.0;

/// A case whose parameters passed [`CaseParams::validated`], with the start
/// shape that validation built, so that running it builds no knot again.
#[derive(Clone, Debug, PartialEq)]
pub struct ValidCase {
    params: CaseParams,
    start: StartShape,
}

impl ValidCase {
    /// The validated parameters, with the node count and the pull speed
    /// resolved ([`CaseParams::node_count`], [`CaseParams::clamp_speed`]).
    pub fn params(&self) -> &CaseParams {
        &self.params
    }

    /// The shape the case starts from: `initial_shape` or the builder's knot.
    pub fn start(&self) -> &StartShape {
        &self.start
    }
}

/// The knots built so far in one validation pass, by spec, with the
/// builder's refusal if it refused ([`CaseParams::validate_in`]).
#[derive(Debug, Default)]
pub struct BuildChecks(Vec<(Knot, Result<f64, FieldError>)>);

/// A field and why its value was refused: a parameter of the wrong type or
/// outside its range, a knot that cannot be built. The service names its
/// fields with it too (`base.h`, `grid.n[2]`, `preset`, `body`, ...).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize, thiserror::Error)]
#[error("{field}: {reason}")]
pub struct FieldError {
    /// Where: a parameter's name, or the service's path to it.
    pub field: String,
    pub reason: String,
}

impl FieldError {
    pub fn new(field: impl Into<String>, reason: impl Into<String>) -> Self {
        Self {
            field: field.into(),
            reason: reason.into(),
        }
    }
}

impl CaseParams {
    /// Checks every documented range and that the case can start
    /// ([`CaseParams::validated`]); returns all violations.
    ///
    /// ```
    /// use solver::case::CaseParams;
    ///
    /// assert!(CaseParams::default().validate().is_ok());
    /// let errors = CaseParams { mu: -0.5, ..CaseParams::default() }.validate().unwrap_err();
    /// assert_eq!(errors.len(), 1);
    /// assert_eq!(errors[0].field, "mu");
    /// assert_eq!(errors[0].reason, "must be in [0, 2], got -0.5");
    /// ```
    pub fn validate(&self) -> Result<(), Vec<FieldError>> {
        self.validate_in(&mut BuildChecks::default())
    }

    /// [`CaseParams::validate`], building each distinct knot once per `checks`:
    /// a grid over parameters the start shape does not read (`mu`, speeds,
    /// ...) builds one knot, not one per case.
    pub fn validate_in(&self, checks: &mut BuildChecks) -> Result<(), Vec<FieldError>> {
        let errors = self.range_errors();
        if !errors.is_empty() {
            return Err(errors);
        }
        let start = if self.initial_shape.is_some() {
            let shape = self.start_shape().map_err(|e| vec![e])?;
            return self.loading_error(&shape).map_or(Ok(()), |e| Err(vec![e]));
        } else {
            let knot = self.knot().map_err(|e| vec![e])?;
            match checks.0.iter().find(|(k, _)| *k == knot) {
                Some((_, outcome)) => outcome.clone(),
                None => {
                    let outcome = self.start_shape().map(|s| self.l_k_bar_of(&s));
                    checks.0.push((knot, outcome.clone()));
                    outcome
                }
            }
        };
        let start = start.map_err(|e| vec![e])?;
        self.program_error(start, true).map_or(Ok(()), |e| Err(vec![e]))
    }

    /// The checks of [`CaseParams::validate`] and the start shape in one
    /// pass: the case to run.
    pub fn validated(&self) -> Result<ValidCase, Vec<FieldError>> {
        let errors = self.range_errors();
        if !errors.is_empty() {
            return Err(errors);
        }
        let start = self.start_shape().map_err(|e| vec![e])?;
        if let Some(e) = self.loading_error(&start) {
            return Err(vec![e]);
        }
        Ok(ValidCase {
            params: CaseParams {
                nodes: Some(self.node_count()),
                pull_speed: Some(self.clamp_speed()),
                ..self.clone()
            },
            start,
        })
    }

    /// l_k bar of a start shape (eq. 11; for a bend, the rods' rest lengths
    /// less the pulled clamps' distance, over h).
    fn l_k_bar_of(&self, start: &StartShape) -> f64 {
        let [a, b] = start.clamp_points();
        (self.rest_length() - (b - a).norm()) / self.h
    }

    /// Why the loading program cannot run from `start`, if it cannot.
    fn loading_error(&self, start: &StartShape) -> Option<FieldError> {
        let [a, b] = start.clamp_points();
        let span = b - a;
        let along_x = span.y.abs().max(span.z.abs()) <= 1e-9 * span.norm();
        self.program_error(self.l_k_bar_of(start), along_x)
    }

    /// Why the loading program cannot run from a knot starting at l_k bar
    /// `start` ([`loading::check`]), with soft stages on a knot not pulled
    /// along x (its springs act along x), or with soft or rotating stages on
    /// a bend (its standing ends alone are clamped), if it cannot.
    fn program_error(&self, start: f64, along_x: bool) -> Option<FieldError> {
        let program = self.loading.as_deref()?;
        let soft = program.iter().any(|s| matches!(s, LoadStage::Soft(_)));
        let turns = program.iter().any(|s| matches!(s, LoadStage::Rotate(_)));
        let reason = if self.knot.bend().is_some() && (soft || turns) {
            Err(format!(
                "knot \"{}\" is a bend: its standing ends are pulled, held or released; soft and rotate stages \
                 act on one rod's two clamps",
                self.knot
            ))
        } else if self.knot == KnotKind::CloveHitch && (soft || turns) {
            Err(format!(
                "knot \"{}\" lets its tail go once set: its standing end is pulled, held or released; soft and \
                 rotate stages act on two clamps",
                self.knot
            ))
        } else if soft && !along_x {
            Err("a soft stage needs the clamps on the x axis, as the builder's knots are: this initial_shape's \
                 ends are not"
                .to_string())
        } else {
            loading::check(program, start, self.rest_length() / self.h)
        };
        reason.err().map(|reason| FieldError {
            field: "loading".to_string(),
            reason,
        })
    }

    /// F bar above which a tightening stops, the knot tight:
    /// `max_force_bar`, or [`BEND_TIGHT_FORCE_BAR`] for a bend or a hitch,
    /// [`STRETCH_LIMIT_FORCE_BAR`] for any other knot.
    pub fn tight_force_bar(&self) -> f64 {
        match (self.max_force_bar, self.knot.holds_by_friction()) {
            (Some(given), _) => given,
            (None, true) => BEND_TIGHT_FORCE_BAR,
            (None, false) => STRETCH_LIMIT_FORCE_BAR,
        }
    }

    /// The rods' rest lengths summed: L, or 2L for a bend.
    pub fn rest_length(&self) -> f64 {
        match self.knot.bend() {
            Some(_) => 2.0 * self.length,
            None => self.length,
        }
    }

    /// The loading program: `loading`, or one tightening.
    pub fn program(&self) -> Vec<LoadStage> {
        self.loading.clone().unwrap_or_else(default_program)
    }

    /// Every range of [`PARAMETERS`] that does not hold, in the table's order.
    pub fn range_errors(&self) -> Vec<FieldError> {
        PARAMETERS.iter().filter_map(|p| p.check(self)).collect()
    }

    /// The overhand knot builder's input for this case (its `n` and shape).
    pub fn knot_spec(&self) -> KnotSpec {
        KnotSpec {
            n: self.n,
            length: self.length,
            nodes: self.node_count(),
            radius: self.h,
            clamp_span: self.end_to_end,
            pass_length: self.braid_length,
            loop_length: None,
        }
    }

    /// The node count K: `nodes` if given, else the points of
    /// `initial_shape`, else [`default_nodes`] (edges of at most
    /// [`EDGE_RADII`] h, at least the paper's 301).
    pub fn node_count(&self) -> usize {
        match (self.nodes, &self.initial_shape) {
            (Some(k), _) => k,
            (None, Some(shape)) => shape.nodes(),
            (None, None) => default_nodes(self.length, self.h, MAX_NODES),
        }
    }

    /// The (largest) time step: `dt` if given, else [`REFERENCE_DT`] scaled
    /// so that the rod's bending stiffness at the edge scale, EI / l_e^3,
    /// keeps its ratio to the inertial stiffness m / dt^2 with which the
    /// explicit contact solve pushes (Sec. 3.2, eq. 10: the mass-only
    /// Delassus operator) at the paper's: dt proportional to l_e^2 / (c h),
    /// c the simulated wave speed ([`Scales`]), at most
    /// [`scales::MAX_DT_RATIO`] times the paper's step at that wave speed.
    /// A longer step lets strands creep through sticking contacts. Rods
    /// thicker than the paper's keep the paper's step at their edge length,
    /// which the rule would shorten (Figs 7 and 11 are measured with it).
    pub fn time_step(&self) -> f64 {
        self.dt.unwrap_or_else(|| {
            let edge = self.length / (self.node_count().max(2) - 1) as f64;
            let thinner = (REFERENCE_RADIUS / self.h).max(1.0);
            let slowness = self.scales().slowness;
            let edges = (thinner * (edge / REFERENCE_EDGE).powi(2)).min(scales::MAX_DT_RATIO);
            REFERENCE_DT * slowness * edges
        })
    }

    /// Bending stiffness EI = (pi/4) E h^4 (eq. 11).
    pub fn bending_stiffness(&self) -> f64 {
        std::f64::consts::PI / 4.0 * self.youngs_modulus * self.h.powi(4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A validation pass that builds each distinct knot once gives every case
    /// the verdict validating it alone gives, refusals included.
    #[test]
    fn shared_build_checks_give_the_verdicts_of_lone_validation() {
        let cases: Vec<CaseParams> = [
            (3, 301, 0.1),
            (3, 101, 0.1),
            (3, 301, 0.4),
            (3, 101, 0.4),
            (4, 301, 0.2),
        ]
        .into_iter()
        .map(|(n, nodes, mu)| CaseParams {
            n,
            nodes: Some(nodes),
            mu,
            ..CaseParams::default()
        })
        .collect();
        let mut checks = BuildChecks::default();
        for c in &cases {
            assert_eq!(
                c.validate_in(&mut checks),
                c.validate(),
                "n {} nodes {:?} mu {}",
                c.n,
                c.nodes,
                c.mu
            );
        }
        assert!(cases[1].validate().is_err(), "K = 101 is too coarse for n = 3");
        assert_eq!(checks.0.len(), 3, "one build per distinct knot");
    }

    #[test]
    fn defaults_are_valid_and_bad_fields_are_named() {
        assert!(CaseParams::default().validate().is_ok());
        let bad = CaseParams {
            n: 0,
            h: 0.05,
            mu: -1.0,
            ..CaseParams::default()
        };
        let errors = bad.validate().unwrap_err();
        let fields: Vec<&str> = errors.iter().map(|e| e.field.as_str()).collect();
        assert_eq!(fields, ["n", "h", "mu"]);
    }

    /// The step is l_e^2 / (c h) times the paper's: squared in the edge,
    /// proportional to the radius of a thinner rod at its default node count
    /// and to the simulated wave time; a given dt is taken as it is.
    #[test]
    fn automatic_time_step_keeps_the_papers_contact_stiffness() {
        let with = |p: CaseParams| p.time_step() / REFERENCE_DT;
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert_eq!(with(CaseParams::default()), 1.0);
        let finer = CaseParams {
            nodes: Some(401),
            ..CaseParams::default()
        };
        assert!(close(with(finer), 0.75 * 0.75));
        let given = CaseParams {
            nodes: Some(401),
            dt: Some(2e-3),
            ..CaseParams::default()
        };
        assert_eq!(given.time_step(), 2e-3);
        let coarse = CaseParams {
            nodes: Some(51),
            ..CaseParams::default()
        };
        assert_eq!(with(coarse), scales::MAX_DT_RATIO);
        let thin = CaseParams {
            h: 4e-4,
            ..CaseParams::default()
        };
        assert_eq!(thin.node_count(), 1201);
        assert!(
            close(with(thin), 0.25),
            "edges 4 times shorter, the radius 4 times smaller"
        );
        let thick = CaseParams {
            h: 3.4e-3,
            ..CaseParams::default()
        };
        assert_eq!(with(thick), 1.0, "the paper's step at the paper's edge");
        let steel = CaseParams {
            youngs_modulus: 2e11,
            density: 7850.0,
            ..CaseParams::default()
        };
        let faster = (2e11 / 7850.0 / 1800.0f64).sqrt();
        assert!(
            close(with(steel.clone()) * faster, 1.0),
            "the paper's rate: steel's waves"
        );
        let at_3mm = CaseParams {
            pull_speed: Some(3e-3),
            ..steel
        };
        assert!(close(with(at_3mm), 1.0), "mass scaling: the paper's waves");
        let soft = CaseParams {
            youngs_modulus: 1.8e4,
            ..CaseParams::default()
        };
        assert!(close(with(soft), 10.0), "waves 10 times slower");
    }

    /// The builder's own knot is a valid start shape; each broken variant is
    /// refused with its reason.
    #[test]
    fn initial_shape_is_checked_like_a_built_knot() {
        let built = CaseParams::default().start_shape().unwrap();
        let points: Vec<[f64; 3]> = built.points().iter().map(|p| [p.x, p.y, p.z]).collect();
        let with = |pts: Vec<[f64; 3]>| CaseParams {
            initial_shape: Some(pts.into()),
            ..CaseParams::default()
        };
        let ok = with(points.clone());
        assert!(ok.validate().is_ok(), "{:?}", ok.validate());
        assert_eq!(ok.start_shape().unwrap().points(), built.points());
        let reason = |p: CaseParams| {
            let errors = p.validate().unwrap_err();
            assert_eq!(errors[0].field, "initial_shape");
            errors[0].reason.clone()
        };
        let given = CaseParams {
            nodes: Some(301),
            ..with(points[..300].to_vec())
        };
        assert!(reason(given).contains("300 points, but nodes = 301"));
        assert_eq!(
            with(points[..300].to_vec()).node_count(),
            300,
            "null nodes: the shape's"
        );
        let mut nan = points.clone();
        nan[7][1] = f64::NAN;
        assert!(reason(with(nan)).contains("point 7 is not finite"));
        let long: Vec<[f64; 3]> = points
            .iter()
            .map(|p| [1.1 * p[0], 1.1 * p[1], 1.1 * p[2]])
            .collect();
        assert!(reason(with(long)).contains("long, but length = 1 m"));
        let mut beyond = points.clone();
        beyond.swap(0, 1);
        assert!(reason(with(beyond)).contains("beyond an end"));
        // Nudge a braid node by h towards the nearest node of another strand.
        let mut close = points.clone();
        let (i, j) = (0..points.len())
            .flat_map(|i| (i + 10..points.len()).map(move |j| (i, j)))
            .min_by(|a, b| {
                let d = |(i, j): (usize, usize)| (built.points()[i] - built.points()[j]).norm();
                d(*a).total_cmp(&d(*b))
            })
            .unwrap();
        let towards = (built.points()[j] - built.points()[i]).normalize() * CaseParams::default().h;
        close[i] = (built.points()[i] + towards).into();
        assert!(reason(with(close)).contains("closer than 2h"));
        let wrong_n = CaseParams { n: 2, ..with(points) };
        assert!(reason(wrong_n).contains(
            "Alexander polynomial t^6 - t^5 + t^4 - t^3 + t^2 - t + 1, but the overhand knot with n = 2 passes \
             has t^4 - t^3 + t^2 - t + 1"
        ));
    }

    /// A knot's parameters are refused naming the field: a braid word that is
    /// missing, empty, malformed, on too many strands or closing to a link,
    /// or given to another knot; the overhand's shape given to another knot.
    #[test]
    fn knot_choices_are_checked_naming_the_field() {
        let refusal = |p: CaseParams| {
            let errors = p.validate().unwrap_err();
            (errors[0].field.clone(), errors[0].reason.clone())
        };
        let braid = |word: Option<&str>| CaseParams {
            knot: KnotKind::Braid,
            braid_word: word.map(str::to_string),
            ..CaseParams::default()
        };
        for (word, says) in [
            (None, "needs a braid word"),
            (Some(" "), "empty"),
            (Some("s1 t2"), "not a generator"),
            (Some("s1 s5"), "at most 5"),
            (Some("s1 s3"), "link of 2 components"),
        ] {
            let (field, reason) = refusal(braid(word));
            assert_eq!(field, "braid_word", "{word:?}");
            assert!(reason.contains(says), "{word:?}: {reason}");
        }
        assert!(braid(Some("s1 s2^-1 s1 s2^-1")).validate().is_ok());
        let figure_eight = CaseParams {
            knot: KnotKind::FigureEight,
            ..CaseParams::default()
        };
        assert!(figure_eight.validate().is_ok());
        let with_n = CaseParams {
            n: 4,
            ..figure_eight.clone()
        };
        assert_eq!(refusal(with_n).0, "n");
        let with_braid = CaseParams {
            braid_length: Some(0.2),
            ..figure_eight.clone()
        };
        assert_eq!(refusal(with_braid).0, "braid_length");
        let overhand_word = CaseParams {
            braid_word: Some("s1 s1 s1".to_string()),
            ..CaseParams::default()
        };
        assert_eq!(refusal(overhand_word).0, "braid_word");
        let unknown: Result<CaseParams, _> = serde_json::from_str(r#"{"knot": "granny_square"}"#);
        assert!(
            unknown
                .unwrap_err()
                .to_string()
                .contains("unknown variant `granny_square`")
        );
        let short = CaseParams {
            length: 0.3,
            ..figure_eight
        };
        let (field, reason) = refusal(short);
        assert_eq!(field, "length");
        assert!(reason.contains("needs a rod of at least"), "{reason}");
    }

    /// A set bend's eased load is a bend's alone and below its setting
    /// load: given to another knot, or out of (0, setting load), it is
    /// refused naming the field.
    #[test]
    fn the_eased_force_bar_belongs_to_a_bend() {
        let field = |p: CaseParams| p.validate().err().map(|errors| errors[0].field.clone());
        let reef = CaseParams {
            knot: KnotKind::Reef,
            ..CaseParams::default()
        };
        assert_eq!(reef.eased_force_bar(), BEND_EASED_FORCE_BAR);
        let eased = |bar: f64, knot: KnotKind| CaseParams {
            eased_force_bar: Some(bar),
            knot,
            ..reef.clone()
        };
        assert_eq!(field(eased(0.001, KnotKind::Reef)), None);
        assert_eq!(eased(0.001, KnotKind::Fisherman).eased_force_bar(), 0.001);
        for bad in [0.0, -0.001, BEND_SET_FORCE_BAR, 0.03] {
            assert_eq!(
                field(eased(bad, KnotKind::Reef)).as_deref(),
                Some("eased_force_bar"),
                "{bad}"
            );
        }
        for other in [KnotKind::Overhand, KnotKind::FigureEight, KnotKind::CloveHitch] {
            assert_eq!(
                field(eased(0.001, other)).as_deref(),
                Some("eased_force_bar"),
                "{other}"
            );
        }
    }

    /// The clove hitch is tied on its cylinder, whose radius only it reads:
    /// given to another knot, or not positive, it is refused naming the
    /// field; so are a start twist and a user's start shape.
    #[test]
    fn the_cylinder_radius_belongs_to_the_hitch() {
        let refusal = |p: CaseParams| {
            let errors = p.validate().unwrap_err();
            (errors[0].field.clone(), errors[0].reason.clone())
        };
        let hitch = CaseParams {
            knot: KnotKind::CloveHitch,
            ..CaseParams::default()
        };
        let valid = hitch.validated().unwrap();
        let cylinder = valid.start().cylinder.expect("a hitch has its cylinder");
        assert_eq!(cylinder.radius, 10.0 * hitch.h);
        assert_eq!(hitch.tight_force_bar(), BEND_TIGHT_FORCE_BAR);
        assert_eq!(CaseParams::default().tight_force_bar(), STRETCH_LIMIT_FORCE_BAR);
        assert_eq!(hitch.rest_length(), hitch.length);
        let given = CaseParams {
            cylinder_radius: Some(0.02),
            ..hitch.clone()
        };
        assert_eq!(given.validated().unwrap().start().cylinder.unwrap().radius, 0.02);
        for bad in [0.0, -0.01] {
            let (field, _) = refusal(CaseParams {
                cylinder_radius: Some(bad),
                ..hitch.clone()
            });
            assert_eq!(field, "cylinder_radius", "{bad}");
        }
        let (field, reason) = refusal(CaseParams {
            cylinder_radius: Some(0.02),
            ..CaseParams::default()
        });
        assert_eq!(field, "cylinder_radius");
        assert!(reason.contains("has none"), "{reason}");
        let (field, _) = refusal(CaseParams {
            start_twist: Some(0.0),
            ..hitch.clone()
        });
        assert_eq!(field, "start_twist");
        let (field, _) = refusal(CaseParams { n: 2, ..hitch });
        assert_eq!(field, "n");
    }

    #[test]
    fn unknown_fields_are_rejected() {
        let r: Result<CaseParams, _> = serde_json::from_str(r#"{"n": 3, "radius": 0.001}"#);
        assert!(r.is_err());
        let p: CaseParams = serde_json::from_str(r#"{"n": 4}"#).unwrap();
        assert_eq!(p.n, 4);
        assert_eq!(p.h, 1.6e-3);
    }
}
