//! The one definition of a knot case's parameters, with the paper's defaults,
//! shared by the CLI, the API, the queue and the solver. SI units.
pub use crate::contact::{Candidates, ContactSolve, FrictionLaw};
use crate::knot::{self, KnotError, KnotSpec, StartShape};
use crate::words::serde_word;
use serde::{Deserialize, Serialize};

/// Revision of the physics: raised whenever a change to the model or its
/// defaults changes results, and part of every case's cache key, so that
/// results computed under older physics are never served as current.
/// Revision 1: the model of session 3 (friction at the centre lines).
/// Revision 2: friction at the surfaces, so rods roll on each other
/// (`rolling`, docs/FIDELITY.md).
/// Revision 3: the adaptive pull is the default protocol (`protocol`).
/// Revision 4: the contact solve steps each contact's normal force by the
/// exact normal entry of its Delassus block instead of the rolling block's
/// largest eigenvalue, and starts from the forces extrapolated from the last
/// two steps: the same solutions, reached in about a sixth of the sweeps, so
/// each step's forces are closer to them at the same tolerance.
/// Revision 5: the paper's model and start: friction at the centre lines
/// (`rolling` false), the knot starts with the paper's code's twist
/// (`start_twist`, linking number 2n), the reference pull is the default
/// protocol, and F bar is the clamp force averaged over each sample's
/// interval (docs/FIDELITY.md).
pub const PHYSICS_REVISION: u32 = 5;

/// Parameters of one overhand-knot tightening case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CaseParams {
    /// Number of passes (unknotting number) n, 1..=8.
    pub n: u32,
    /// Rod radius h (m); paper: 1.6 mm.
    pub h: f64,
    /// Coulomb friction coefficient mu; paper: 0.1.
    pub mu: f64,
    /// Which tangential forces friction may take (eqs. 9-10): `isotropic`
    /// (Coulomb's disk |F_t| <= mu F_n, default) or `sliding_direction` (only
    /// along the previous step's sliding direction; fails the capstan check).
    pub friction_law: FrictionLaw,
    /// Friction acts at the rods' surfaces: a contact's slip includes the
    /// surfaces' spin about each rod's axis, and friction torques the twist,
    /// so a rod can roll on another. `false` (default): friction at the centre
    /// lines, as in the paper's method and code (docs/FIDELITY.md).
    pub rolling: bool,
    /// How each step's contact forces see the rods' response: `explicit`
    /// (the paper's method, mass-only Delassus operator) or `implicit` (the
    /// compliance of the implicit step that follows, [`ContactSolve`]).
    pub contact_solve: ContactSolve,
    /// Which segment pairs get a contact force each step: `detected` (every
    /// pair within reach at the start of the step) or `predicted` (the
    /// paper's code: the pairs a contact-free predictor step brings into
    /// contact, [`Candidates`]).
    pub contact_candidates: Candidates,
    /// Twist (turns) the knot starts with between its clamps, spread evenly
    /// along the rod; `None`: the paper's code's, linking number 2n with the
    /// sign of the knot's writhe ([`crate::knot::paper_twist`]).
    pub start_twist: Option<f64>,
    /// Gravitational acceleration (m/s^2), a vector; the paper's simulations: zero.
    pub gravity: [f64; 3],
    /// Rod length L (m); paper: 1 m.
    pub length: f64,
    /// Node count K; paper: 301.
    pub nodes: usize,
    /// Young's modulus E (Pa); paper: 1.8 MPa.
    pub youngs_modulus: f64,
    /// Poisson's ratio nu; paper: 0.5.
    pub poisson_ratio: f64,
    /// Density rho (kg/m^3); the paper's code: 1000.
    pub density: f64,
    /// Pulling speed of each clamp (m/s); the paper's text 1 mm/s, its code 3 mm/s.
    pub pull_speed: f64,
    /// How the pull is scheduled: `reference` (at `pull_speed` throughout;
    /// the default) or `adaptive` (fast far from the snap, slow through it).
    pub protocol: Protocol,
    /// Time step (s), the largest one with `adaptive_dt`; `None`: the automatic
    /// step of [`CaseParams::time_step`] (0.5 ms at L = 1 m, K = 301).
    pub dt: Option<f64>,
    /// Adapt the step to the penetration (see `solver::time_step`): halve it
    /// down to dt/64 while contacts penetrate, grow it back to `dt` when calm.
    /// `false`: the constant step `dt` of the paper's scheme.
    pub adaptive_dt: bool,
    /// Relative tolerance of the frictional contact solve of each step
    /// (projected Gauss-Seidel, `solver::contact::gauss_seidel`): the forces
    /// are accepted when a sweep changes none by more than this times the
    /// largest, or the natural-map residual is this small (at most 200 sweeps).
    pub contact_tolerance: f64,
    /// Relaxation before pulling: the ends are held until the kinetic energy
    /// falls below `relax_tolerance` times the elastic energy, at most this long (s).
    pub relax_time: f64,
    /// See `relax_time`.
    pub relax_tolerance: f64,
    /// Mass-proportional viscous damping rate (1/s) while pulling.
    pub damping: f64,
    /// Initial clamp-to-clamp distance (m); `None`: the builder's default for n.
    pub end_to_end: Option<f64>,
    /// Strand length of a braid pass in the initial shape (m); `None`: builder default.
    pub braid_length: Option<f64>,
    /// Series sampling interval in l_k bar.
    pub sample_interval: f64,
    /// Stop when l_k bar falls below this.
    pub min_l_k_bar: f64,
    /// Stop this far in l_k bar past a detected inversion (`None`: never early).
    pub stop_after_inversion: Option<f64>,
    /// Stop when F bar exceeds this (the knot is fully tight); `None`: never.
    pub max_force_bar: Option<f64>,
    /// Start from these K = `nodes` points (m) instead of the builder's knot:
    /// the ends are clamped where they are and pulled apart along the line
    /// joining them. Checked like a built knot ([`knot::checked_start`]).
    pub initial_shape: Option<Vec<[f64; 3]>>,
}

impl Default for CaseParams {
    fn default() -> Self {
        Self {
            n: 3,
            h: 1.6e-3,
            mu: 0.1,
            friction_law: FrictionLaw::default(),
            rolling: false,
            contact_solve: ContactSolve::default(),
            contact_candidates: Candidates::default(),
            start_twist: None,
            gravity: [0.0; 3],
            length: 1.0,
            nodes: 301,
            youngs_modulus: 1.8e6,
            poisson_ratio: 0.5,
            density: 1000.0,
            pull_speed: 3e-3,
            protocol: Protocol::default(),
            dt: None,
            adaptive_dt: true,
            contact_tolerance: 1e-6,
            relax_time: 2.0,
            relax_tolerance: 1e-4,
            damping: 0.0,
            end_to_end: None,
            braid_length: None,
            sample_interval: 0.5,
            min_l_k_bar: 60.0,
            stop_after_inversion: Some(10.0),
            max_force_bar: None,
            initial_shape: None,
        }
    }
}

/// How fast the clamps move along the pull (case parameter `protocol`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Protocol {
    /// The whole pull at `pull_speed` (the paper's protocol).
    #[default]
    Reference,
    /// Fast far from the snap: the clamps ramp up to `FAST_FACTOR` times
    /// `pull_speed`, damped as in the relaxation and (with `adaptive_dt`)
    /// with steps up to `FAST_DT_FACTOR` times the case's, with a checkpoint every
    /// `CHECKPOINT_SPACING` in l_k bar. When a snap is detected, the pull
    /// goes back to the checkpoint `RESTART_BEFORE` before it, lets the knot
    /// settle with the clamps held (damped, steps up to `FAST_DT_FACTOR`
    /// times the case's), and pulls through the snap at `pull_speed`
    /// (`SNAP_FACTOR`) with the case's damping and step, fast again from
    /// `SLOW_AFTER` past it. A snap within `MIN_LEAD` of the restart means
    /// the restart was past the fold: it is redone from `RESTART_BEFORE`
    /// further back. A snap stage that finds no snap within `FALSE_ALARM`
    /// approaches fast again; a fast approach that reaches the end of the
    /// pull redoes its last `END_REVIEW` slowly. Above `ADAPTIVE_MAX_MU` the
    /// whole pull is the reference's. The report's `stages` list what ran.
    /// Its inversion lies within 1 % of the reference's, but the fast
    /// approach reads F bar 5-20 % high (BENCHMARKS.md, "Pull protocols").
    Adaptive,
}

impl std::fmt::Display for Protocol {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        serde_word(self, f)
    }
}

/// Largest node count K.
pub const MAX_NODES: usize = 4001;
/// h >= L / this: with edges of at most 4h ([`knot::build`]) and at most
/// [`MAX_NODES`] nodes, a thinner rod cannot be meshed.
pub const MIN_RADIUS_DIVISOR: f64 = 16000.0;

/// The default (largest) time step (s) at the paper's edge length
/// [`REFERENCE_EDGE`]: half the paper's code's 1 ms. With rods that roll, the
/// inversion at 1 ms differs by 1.5 % from the converged one, while 0.5 ms
/// agrees with 0.25 ms within 0.4 % (n = 3: 139.8, 137.4, 137.9; n = 4:
/// 226.7, 223.0, 223.0 at 1, 0.5, 0.25 ms; docs/FIDELITY.md).
pub const REFERENCE_DT: f64 = 5e-4;
/// The paper's edge length (m): L = 1 m with K = 301 nodes.
pub const REFERENCE_EDGE: f64 = 1.0 / 300.0;

/// A case whose parameters passed [`CaseParams::validated`], with the start
/// shape that validation built, so that running it builds no knot again.
#[derive(Clone, Debug, PartialEq)]
pub struct ValidCase {
    params: CaseParams,
    start: StartShape,
}

impl ValidCase {
    pub fn params(&self) -> &CaseParams {
        &self.params
    }

    /// The shape the case starts from: `initial_shape` or the builder's knot.
    pub fn start(&self) -> &StartShape {
        &self.start
    }
}

/// One case parameter: its name (the JSON key; the CLI flag is `--` and the
/// name with dashes) and its documentation (unit, range, default). Its type
/// and default come from [`CaseParams::default`]; its range is checked by
/// [`CaseParams::validate`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Parameter {
    pub name: &'static str,
    pub doc: &'static str,
}

/// Every `CaseParams` field, documented once: the CLI flags, the OpenAPI
/// schema and the web form are made from this table.
pub const PARAMETERS: &[Parameter] = &[
    Parameter {
        name: "n",
        doc: "Number of passes (unknotting number): an integer in 1..=8.",
    },
    Parameter {
        name: "h",
        doc: "Rod radius h (m): positive and below L/50. Paper: 1.6 mm.",
    },
    Parameter {
        name: "mu",
        doc: "Coulomb friction coefficient: 0..=2. Paper: 0.1.",
    },
    Parameter {
        name: "friction_law",
        doc: "Which tangential forces friction may take (eqs. 9-10): \"isotropic\" (default: Coulomb's disk |F_t| <= mu F_n) or \"sliding_direction\" (only along the previous step's sliding direction; fails the capstan check, kept for sensitivity studies, docs/FIDELITY.md).",
    },
    Parameter {
        name: "rolling",
        doc: "Friction acts at the rods' surfaces: a contact's slip includes each rod's spin about its axis and friction torques the twist, so rods roll on each other (a rod on an inclined rod rolls at (2/3) g sin alpha). false (default): friction at the centre lines, as in the paper's method and code, which with the paper's start twist reproduces Figs 1, 7, 9 and 11; true inverts 9-10 % later (n = 3: 124, n = 4: 193) and loses the clean snap at h = 3.4 mm, mu >= 0.4 (docs/FIDELITY.md).",
    },
    Parameter {
        name: "contact_solve",
        doc: "How each step's contact forces see the rods' response: \"explicit\" (default; the paper's method: free velocities v + dt M^-1 F and the mass-only Delassus operator, the forces then held fixed in the implicit step) or \"implicit\" (the free velocities of a contact-free implicit step and the Delassus operator of its Newton matrix, so a sticking contact holds for the motion the step takes; costs a banded solve per contact axis each step).",
    },
    Parameter {
        name: "contact_candidates",
        doc: "Which segment pairs get a contact force each step: \"detected\" (default: every pair within reach at the start of the step, one of two pairs meeting at a shared node) or \"predicted\" (as the paper's code: only the pairs that a contact-free implicit predictor step brings closer than 2h, so a touching pair that the predictor pulls apart gets no force in that step; costs a second Newton solve per step).",
    },
    Parameter {
        name: "start_twist",
        doc: "Twist (turns) the knot starts with between its clamps, spread evenly along the rod: -20..=20. null (default): the paper's code's, which gives the rod the linking number 2n with the pull axis (sign of the knot's writhe), about +1.0 to +1.3 turns for the builder's knots n = 1..5 (writhe -3.0 to -11.3); 0: none, as if the knot's ends had turned freely while it was tied. The report gives the twist used and the knot's writhe.",
    },
    Parameter {
        name: "gravity",
        doc: "Gravitational acceleration (m/s^2), three components each in [-1000, 1000]. Default [0, 0, 0], as in the paper's simulations; the pull is along x.",
    },
    Parameter {
        name: "length",
        doc: "Rod length L (m): 0.05..=100. Paper: 1 m.",
    },
    Parameter {
        name: "nodes",
        doc: "Node count K: 51..=4001 (the knot builder needs edges of at most 4h). Paper: 301.",
    },
    Parameter {
        name: "youngs_modulus",
        doc: "Young's modulus E (Pa): 1e3..=1e12. Paper: 1.8 MPa.",
    },
    Parameter {
        name: "poisson_ratio",
        doc: "Poisson's ratio: 0..=0.5. Paper: 0.5.",
    },
    Parameter {
        name: "density",
        doc: "Density (kg/m^3): 1..=1e5. Paper's code: 1000.",
    },
    Parameter {
        name: "pull_speed",
        doc: "Pulling speed of each clamp (m/s): 1e-5..=1.",
    },
    Parameter {
        name: "protocol",
        doc: "How the clamps move: \"reference\" (default) pulls at pull_speed throughout, as in the paper. \"adaptive\" ramps up to 16 times pull_speed (damped; with adaptive_dt, steps up to 4 times dt) while the knot is far from its snap, keeping a checkpoint every 2 in l_k bar; once a snap is detected it goes back to the checkpoint 10 before it (further if the knot then snaps within 2), lets the knot settle and pulls through the snap at pull_speed; above mu = 0.2 it pulls as \"reference\" does, since there the result depends on the pulling path. Its inversion lies within 1 % of the reference's at a tenth of the cost, but its fast approach reads F bar 5-20 % high (BENCHMARKS.md, \"Pull protocols\"): a quick look, not the curves.",
    },
    Parameter {
        name: "dt",
        doc: "Time step (s): 1e-6..=1e-2; with adaptive_dt the largest step; null: 0.5 ms (half the paper's code's 1 ms, converged within 0.4 %) at L = 1 m, K = 301, scaled with the square of the edge length L/(K-1).",
    },
    Parameter {
        name: "adaptive_dt",
        doc: "Halve the step (down to dt/64) while contacts penetrate and grow it back when calm; false: constant dt.",
    },
    Parameter {
        name: "contact_tolerance",
        doc: "Relative tolerance of each step's frictional contact solve (projected Gauss-Seidel, at most 200 sweeps): 1e-12..=1e-3.",
    },
    Parameter {
        name: "relax_time",
        doc: "Longest relaxation with the ends held before pulling (s): 0..=100.",
    },
    Parameter {
        name: "relax_tolerance",
        doc: "Relaxation ends when the kinetic energy falls below this times the elastic energy: 0..=1.",
    },
    Parameter {
        name: "damping",
        doc: "Mass-proportional viscous damping rate while pulling (1/s): 0..=1e4.",
    },
    Parameter {
        name: "end_to_end",
        doc: "Initial clamp-to-clamp distance (m), in (0, L]; null: the knot builder's default for n.",
    },
    Parameter {
        name: "braid_length",
        doc: "Strand length of a braid pass (m), in (0, L/2]; null: the builder's default.",
    },
    Parameter {
        name: "sample_interval",
        doc: "Series sampling interval in l_k bar: 1e-3..=100.",
    },
    Parameter {
        name: "min_l_k_bar",
        doc: "Stop when l_k bar falls below this: 0..=1e6.",
    },
    Parameter {
        name: "stop_after_inversion",
        doc: "Stop this far in l_k bar past a detected inversion; null: never early.",
    },
    Parameter {
        name: "max_force_bar",
        doc: "Stop when F bar exceeds this (the knot is tight); null: never.",
    },
    Parameter {
        name: "initial_shape",
        doc: "Start from these points instead of the builder's knot: an array of K = nodes points [x, y, z] (m); the polyline must be `length` long (within 1 %), every node between the ends along the line joining them (the clamps hold the first and last points), no two non-neighbouring segments closer than 2h, and of the knot type of an n-pass overhand knot. null: the builder's knot. Mind the body limit (64 KiB by default: about 700 points).",
    },
];

/// The knots built so far in one validation pass, by spec, with the
/// builder's refusal if it refused ([`CaseParams::validate_in`]).
#[derive(Debug, Default)]
pub struct BuildChecks(Vec<(KnotSpec, Option<ParamError>)>);

/// A parameter outside its documented range.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize, thiserror::Error)]
#[error("{field}: {reason}")]
pub struct ParamError {
    pub field: String,
    pub reason: String,
}

impl CaseParams {
    /// Checks every documented range and that the case can start
    /// ([`CaseParams::validated`]); returns all violations.
    pub fn validate(&self) -> Result<(), Vec<ParamError>> {
        self.validate_in(&mut BuildChecks::default())
    }

    /// [`CaseParams::validate`], building each distinct knot once per `checks`:
    /// a grid over parameters the start shape does not read (`mu`, speeds,
    /// ...) builds one knot, not one per case.
    pub fn validate_in(&self, checks: &mut BuildChecks) -> Result<(), Vec<ParamError>> {
        let errors = self.range_errors();
        if !errors.is_empty() {
            return Err(errors);
        }
        if self.initial_shape.is_some() {
            return self.start_shape().map(|_| ()).map_err(|e| vec![e]);
        }
        let spec = self.knot_spec();
        let outcome = match checks.0.iter().find(|(s, _)| *s == spec) {
            Some((_, outcome)) => outcome.clone(),
            None => {
                let outcome = self.start_shape().err();
                checks.0.push((spec, outcome.clone()));
                outcome
            }
        };
        outcome.map_or(Ok(()), |e| Err(vec![e]))
    }

    /// The checks of [`CaseParams::validate`] and the start shape in one
    /// pass: the case to run.
    pub fn validated(&self) -> Result<ValidCase, Vec<ParamError>> {
        let errors = self.range_errors();
        if !errors.is_empty() {
            return Err(errors);
        }
        let start = self.start_shape().map_err(|e| vec![e])?;
        Ok(ValidCase {
            params: self.clone(),
            start,
        })
    }

    /// Every documented range that does not hold.
    fn range_errors(&self) -> Vec<ParamError> {
        let mut errors = Vec::new();
        let mut check = |ok: bool, field: &str, reason: String| {
            if !ok {
                errors.push(ParamError {
                    field: field.to_string(),
                    reason,
                });
            }
        };
        let finite_in = |v: f64, lo: f64, hi: f64| v.is_finite() && v >= lo && v <= hi;
        check(
            (1..=8).contains(&self.n),
            "n",
            format!("must be an integer in 1..=8, got {}", self.n),
        );
        check(
            finite_in(self.length, 0.05, 100.0),
            "length",
            format!("must be in [0.05, 100] m, got {}", self.length),
        );
        check(
            self.h.is_finite() && self.h >= self.length / MIN_RADIUS_DIVISOR && self.h < self.length / 50.0,
            "h",
            format!(
                "must be in [L/{MIN_RADIUS_DIVISOR}, L/50) = [{}, {}) m (edges of at most 4h with at most \
                 4001 nodes; a knot needs room in L), got {}",
                self.length / MIN_RADIUS_DIVISOR,
                self.length / 50.0,
                self.h
            ),
        );
        if let Some(v) = self.start_twist {
            check(
                finite_in(v, -20.0, 20.0),
                "start_twist",
                format!("must be in [-20, 20] turns, got {v}"),
            );
        }
        check(
            finite_in(self.mu, 0.0, 2.0),
            "mu",
            format!("must be in [0, 2], got {}", self.mu),
        );
        check(
            self.gravity.iter().all(|g| g.is_finite() && g.abs() <= 1e3),
            "gravity",
            format!(
                "each component must be in [-1000, 1000] m/s^2, got [{}, {}, {}]",
                self.gravity[0], self.gravity[1], self.gravity[2]
            ),
        );
        check(
            (51..=MAX_NODES).contains(&self.nodes),
            "nodes",
            format!("must be in 51..={MAX_NODES}, got {}", self.nodes),
        );
        check(
            finite_in(self.youngs_modulus, 1e3, 1e12),
            "youngs_modulus",
            format!("must be in [1e3, 1e12] Pa, got {}", self.youngs_modulus),
        );
        check(
            finite_in(self.poisson_ratio, 0.0, 0.5),
            "poisson_ratio",
            format!("must be in [0, 0.5], got {}", self.poisson_ratio),
        );
        check(
            finite_in(self.density, 1.0, 1e5),
            "density",
            format!("must be in [1, 1e5] kg/m^3, got {}", self.density),
        );
        check(
            finite_in(self.pull_speed, 1e-5, 1.0),
            "pull_speed",
            format!("must be in [1e-5, 1] m/s, got {}", self.pull_speed),
        );
        if let Some(v) = self.dt {
            check(
                finite_in(v, 1e-6, 1e-2),
                "dt",
                format!("must be in [1e-6, 1e-2] s, got {v}"),
            );
        }
        check(
            finite_in(self.relax_time, 0.0, 100.0),
            "relax_time",
            format!("must be in [0, 100] s, got {}", self.relax_time),
        );
        check(
            finite_in(self.relax_tolerance, 0.0, 1.0),
            "relax_tolerance",
            format!("must be in [0, 1], got {}", self.relax_tolerance),
        );
        check(
            finite_in(self.damping, 0.0, 1e4),
            "damping",
            format!("must be in [0, 1e4] 1/s, got {}", self.damping),
        );
        check(
            finite_in(self.contact_tolerance, 1e-12, 1e-3),
            "contact_tolerance",
            format!("must be in [1e-12, 1e-3], got {}", self.contact_tolerance),
        );
        check(
            finite_in(self.sample_interval, 1e-3, 100.0),
            "sample_interval",
            format!("must be in [1e-3, 100], got {}", self.sample_interval),
        );
        check(
            finite_in(self.min_l_k_bar, 0.0, 1e6),
            "min_l_k_bar",
            format!("must be in [0, 1e6], got {}", self.min_l_k_bar),
        );
        if let Some(v) = self.end_to_end {
            check(
                finite_in(v, 0.0, self.length) && v > 0.0,
                "end_to_end",
                format!("must be in (0, L] m, got {v}"),
            );
        }
        if let Some(v) = self.braid_length {
            check(
                finite_in(v, 0.0, self.length / 2.0) && v > 0.0,
                "braid_length",
                format!("must be in (0, L/2] m, got {v}"),
            );
        }
        if let Some(v) = self.stop_after_inversion {
            check(
                finite_in(v, 0.0, 1e6),
                "stop_after_inversion",
                format!("must be in [0, 1e6], got {v}"),
            );
        }
        if let Some(v) = self.max_force_bar {
            check(
                v.is_finite() && v > 0.0,
                "max_force_bar",
                format!("must be positive, got {v}"),
            );
        }
        errors
    }

    /// The knot builder's input for this case.
    pub fn knot_spec(&self) -> KnotSpec {
        KnotSpec {
            n: self.n,
            length: self.length,
            nodes: self.nodes,
            radius: self.h,
            clamp_span: self.end_to_end,
            pass_length: self.braid_length,
            loop_length: None,
        }
    }

    /// The shape the case starts from: `initial_shape`, checked
    /// ([`knot::checked_start`]), or the knot builder's ([`knot::build`]
    /// itself, so that a case accepted by [`CaseParams::validate`] can always
    /// start); a failure names the parameter to change.
    fn start_shape(&self) -> Result<StartShape, ParamError> {
        match &self.initial_shape {
            Some(points) => knot::checked_start(&self.knot_spec(), points).map_err(|reason| ParamError {
                field: "initial_shape".to_string(),
                reason,
            }),
            None => knot::built_start(&self.knot_spec()).map_err(|e| self.knot_error(e)),
        }
    }

    fn knot_error(&self, e: KnotError) -> ParamError {
        let braid_or_h = if self.braid_length.is_some() {
            "braid_length"
        } else {
            "h"
        };
        let field = match &e {
            KnotError::Passes(_) | KnotError::Topology(_) | KnotError::WrongKnot { .. } => "n",
            KnotError::InvalidParameter { name, .. } => match *name {
                "radius" => "h",
                "clamp_span" => "end_to_end",
                "pass_length" => "braid_length",
                other => other,
            },
            KnotError::RadiusTooLarge { .. } | KnotError::Clearance { .. } => "h",
            KnotError::TooFewNodes { .. } => "nodes",
            KnotError::BraidTooShort { .. }
            | KnotError::TailsTooShort { .. }
            | KnotError::Infeasible { .. } => braid_or_h,
            KnotError::EndToEndOutOfRange { .. } => "end_to_end",
        };
        let mut reason = format!("the knot cannot be built: {e}");
        if let KnotError::TooFewNodes { min, .. } = e
            && min > MAX_NODES
        {
            reason.push_str(&format!(
                " (more than the {MAX_NODES} allowed: use a larger h or a shorter length)"
            ));
        }
        ParamError {
            field: field.to_string(),
            reason,
        }
    }

    /// The (largest) time step: `dt` if given, else [`REFERENCE_DT`] scaled by the square of
    /// the edge length relative to the paper's (L = 1 m, K = 301), capped at
    /// 10 ms. The contact forces are explicit with the mass-only Delassus
    /// operator (Sec. 3.2), which resists motion with a stiffness of about
    /// m / dt^2 per node against a bending stiffness of about EI / l_e^3; keeping
    /// their ratio as at the paper's resolution needs dt proportional to l_e^2.
    /// With a constant dt, a finer mesh lets strands creep through sticking
    /// contacts and the knot drifts along the rod.
    pub fn time_step(&self) -> f64 {
        self.dt.unwrap_or_else(|| {
            let edge = self.length / (self.nodes.max(2) - 1) as f64;
            (REFERENCE_DT * (edge / REFERENCE_EDGE).powi(2)).min(1e-2)
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
            nodes,
            mu,
            ..CaseParams::default()
        })
        .collect();
        let mut checks = BuildChecks::default();
        for c in &cases {
            assert_eq!(
                c.validate_in(&mut checks),
                c.validate(),
                "n {} nodes {} mu {}",
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

    #[test]
    fn automatic_time_step_scales_with_the_squared_edge() {
        let paper = CaseParams::default();
        assert!((paper.time_step() - REFERENCE_DT).abs() < 1e-15);
        let finer = CaseParams {
            nodes: 401,
            ..CaseParams::default()
        };
        assert!((finer.time_step() - REFERENCE_DT * 0.75 * 0.75).abs() < 1e-15);
        let given = CaseParams {
            nodes: 401,
            dt: Some(2e-3),
            ..CaseParams::default()
        };
        assert_eq!(given.time_step(), 2e-3);
        let coarse = CaseParams {
            nodes: 51,
            ..CaseParams::default()
        };
        assert_eq!(coarse.time_step(), 1e-2);
    }

    /// The builder's own knot is a valid start shape; each broken variant is
    /// refused with its reason.
    #[test]
    fn initial_shape_is_checked_like_a_built_knot() {
        let built = CaseParams::default().start_shape().unwrap();
        let points: Vec<[f64; 3]> = built.points.iter().map(|p| [p.x, p.y, p.z]).collect();
        let with = |pts: Vec<[f64; 3]>| CaseParams {
            initial_shape: Some(pts),
            ..CaseParams::default()
        };
        let ok = with(points.clone());
        assert!(ok.validate().is_ok(), "{:?}", ok.validate());
        assert_eq!(ok.start_shape().unwrap().points, built.points);
        let reason = |p: CaseParams| {
            let errors = p.validate().unwrap_err();
            assert_eq!(errors[0].field, "initial_shape");
            errors[0].reason.clone()
        };
        assert!(reason(with(points[..300].to_vec())).contains("300 points, but nodes = 301"));
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
                let d = |(i, j): (usize, usize)| (built.points[i] - built.points[j]).norm();
                d(*a).total_cmp(&d(*b))
            })
            .unwrap();
        let towards = (built.points[j] - built.points[i]).normalize() * CaseParams::default().h;
        close[i] = (built.points[i] + towards).into();
        assert!(reason(with(close)).contains("closer than 2h"));
        let wrong_n = CaseParams { n: 2, ..with(points) };
        assert!(reason(wrong_n).contains("knot determinant 7, but an overhand knot with n = 2 passes has 5"));
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
