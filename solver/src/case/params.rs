//! `CaseParams` and its table, [`PARAMETERS`]: each parameter's unit,
//! default, range, paper value and documentation, written once.
use super::table::{Bound, Group, Parameter, Range, UNCHECKED, Value};
use super::{
    BEND_EASED_FORCE_BAR, BEND_SET_FORCE_BAR, Candidates, ContactSolve, FieldError, FrictionLaw, Geometry,
    InitialShape, KnotKind, LoadStage, MAX_NODES, MIN_RADIUS_DIVISOR, Protocol,
};
use crate::knot::{
    self, BendSpec, BraidSpec, BraidWord, CloveHitchSpec, FigureEightSpec, Knot, KnotError, MAX_PASSES,
    MAX_RADIUS_RATIO, StartShape,
};
use serde::{Deserialize, Serialize};

/// Parameters of one knot-tightening case, SI units; [`PARAMETERS`]
/// documents every field.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CaseParams {
    /// The knot of the catalog.
    pub knot: KnotKind,
    /// Passes n of the overhand knot.
    pub n: u32,
    /// The braid word of a braid knot.
    pub braid_word: Option<String>,
    /// The radius of a hitch's cylinder (m); `None`: [`CaseParams::pole_radius`]'s.
    pub cylinder_radius: Option<f64>,
    /// Rod radius h (m).
    pub h: f64,
    /// Friction coefficient mu.
    pub mu: f64,
    /// Friction's admissible forces.
    pub friction_law: FrictionLaw,
    /// Friction at the surfaces (rods roll) or at the centre lines.
    pub rolling: bool,
    /// How contact forces see the rods' response.
    pub contact_solve: ContactSolve,
    /// Which pairs get a contact force.
    pub contact_candidates: Candidates,
    /// Which centre lines contacts are computed between.
    pub contact_geometry: Geometry,
    /// Start twist (turns); `None`: the paper's code's.
    pub start_twist: Option<f64>,
    /// Gravitational acceleration (m/s^2).
    pub gravity: [f64; 3],
    /// Rod length L (m).
    pub length: f64,
    /// Node count K; `None`: [`CaseParams::node_count`]'s.
    pub nodes: Option<usize>,
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio nu.
    pub poisson_ratio: f64,
    /// Density rho (kg/m^3).
    pub density: f64,
    /// Scale the inertia up to the paper's pull rate ([`CaseParams::scales`]).
    pub mass_scaling: bool,
    /// Clamp speed (m/s); `None`: [`CaseParams::clamp_speed`]'s.
    pub pull_speed: Option<f64>,
    /// Pull schedule.
    pub protocol: Protocol,
    /// (Largest) time step (s); `None`: [`CaseParams::time_step`]'s.
    pub dt: Option<f64>,
    /// Adaptive time step.
    pub adaptive_dt: bool,
    /// Contact solve's relative tolerance.
    pub contact_tolerance: f64,
    /// Longest relaxation (s); `None`: [`CaseParams::relax_limit`]'s.
    pub relax_time: Option<f64>,
    /// Relaxation's kinetic-to-elastic energy ratio.
    pub relax_tolerance: f64,
    /// Damping rate while pulling (1/s).
    pub damping: f64,
    /// Initial clamp-to-clamp distance (m).
    pub end_to_end: Option<f64>,
    /// Braid pass strand length (m).
    pub braid_length: Option<f64>,
    /// Sampling interval in l_k bar.
    pub sample_interval: f64,
    /// Stop below this l_k bar.
    pub min_l_k_bar: f64,
    /// Stop this far in l_k bar past the inversion.
    pub stop_after_inversion: Option<f64>,
    /// Stop above this F bar.
    pub max_force_bar: Option<f64>,
    /// F bar to which a set bend is eased before its tails are let go;
    /// `None`: [`BEND_EASED_FORCE_BAR`].
    pub eased_force_bar: Option<f64>,
    /// The user's start shape (m), checked by [`InitialShape::checked`].
    pub initial_shape: Option<InitialShape>,
    /// The loading program; `None`: one tightening ([`super::default_program`]).
    pub loading: Option<Vec<LoadStage>>,
}

impl Default for CaseParams {
    fn default() -> Self {
        Self {
            knot: KnotKind::Overhand,
            n: 3,
            braid_word: None,
            cylinder_radius: None,
            h: 1.6e-3,
            mu: 0.1,
            friction_law: FrictionLaw::default(),
            rolling: false,
            contact_solve: ContactSolve::default(),
            contact_candidates: Candidates::default(),
            contact_geometry: Geometry::default(),
            start_twist: None,
            gravity: [0.0; 3],
            length: 1.0,
            nodes: None,
            youngs_modulus: 1.8e6,
            poisson_ratio: 0.5,
            density: 1000.0,
            mass_scaling: true,
            pull_speed: None,
            protocol: Protocol::default(),
            dt: None,
            adaptive_dt: true,
            contact_tolerance: 1e-6,
            relax_time: None,
            relax_tolerance: 1e-4,
            damping: 0.0,
            end_to_end: None,
            braid_length: None,
            sample_interval: 0.5,
            min_l_k_bar: 60.0,
            stop_after_inversion: Some(10.0),
            max_force_bar: None,
            eased_force_bar: None,
            initial_shape: None,
            loading: None,
        }
    }
}

const fn closed(lo: f64, hi: f64) -> Range {
    Range::Interval(Bound::Closed(lo), Bound::Closed(hi))
}

/// Every `CaseParams` field, documented once.
pub const PARAMETERS: &[Parameter] = &[
    Parameter {
        name: "knot",
        group: Group::Knot,
        unit: "",
        default: "\"overhand\"",
        range: Range::Words(&[
            "overhand",
            "figure_eight",
            "braid",
            "reef",
            "granny",
            "thief",
            "grief",
            "fisherman",
            "clove_hitch",
        ]),
        null: None,
        paper: "\"overhand\"",
        doc: "The knot tied in the rod: \"overhand\" with n passes (the paper's), \"figure_eight\" (4_1) or \
              \"braid\", the closure of braid_word opened into a long knot. Each is tied loose and contact-free, \
              clamped at both ends and pulled apart; its Alexander polynomial is checked on the start shape and \
              at the end and reported (alexander_initial, alexander_final: coefficients, lowest power first), and \
              the knot determinant |Delta(-1)| at every sample (docs/FIDELITY.md, a section per knot). The bends \
              \"reef\", \"granny\", \"thief\", \"grief\" and \"fisherman\" (two overhand knots, each round the \
              other rod) tie two rods of length L together, set them (the standing ends pulled apart to F bar \
              0.025 with the tails held, then every end eased back to eased_force_bar, default F bar 0.0025), let the tails go and pull \
              the standing ends apart until tight (max_force_bar, default 0.05) or until the rods slip apart, and report whether the rods still hold each other and the holding force (the largest F bar \
              before they part), with l_k bar = (2L - the pulled clamps' distance) / h. \"clove_hitch\" ties the rod \
              round a rigid, fixed cylinder of radius cylinder_radius (frictional contact with the same mu), pulls \
              its two ends apart, away from the cylinder, until the hitch has set (F bar 0.025), eases both back \
              to F bar 0.005, lets the tail go with a weight of F bar 0.005 on it and pulls the standing end until tight (max_force_bar, default \
              0.05) or until the rod slips round the cylinder (less than one and a half turns left on it): tied and \
              holding_force_bar as for a bend, \
              l_k bar = (L - the standing end's distance from where the tail was held) / h; the report carries \
              the cylinder.",
        value: UNCHECKED,
    },
    Parameter {
        name: "n",
        group: Group::Knot,
        unit: "",
        default: "3",
        range: Range::Integers(1, MAX_PASSES as u64),
        null: None,
        paper: "",
        doc: "Number of passes (unknotting number) of the overhand knot; other knots have none (leave it out).",
        value: |p| Some(Value::Integer(u64::from(p.n))),
    },
    Parameter {
        name: "braid_word",
        group: Group::Knot,
        unit: "",
        default: "null",
        range: Range::BraidWord,
        null: Some("no braid: for every knot but \"braid\""),
        paper: "",
        doc: "The braid whose closure knot \"braid\" ties: generators s1 ... s4 (s_i crosses strands i and i + 1, \
              the one moving up passing over; s_i^-1 the mirror crossing), each with an optional power such as \
              s2^-1 or s1^3, separated by spaces; at most 5 strands and 64 letters, and the closure must be a \
              knot (one component). \"s1 s1 s1\" is the trefoil, \"s1 s2^-1 s1 s2^-1\" the figure-eight.",
        value: UNCHECKED,
    },
    Parameter {
        name: "cylinder_radius",
        group: Group::Knot,
        unit: "m",
        default: "null",
        range: Range::LengthOver(Bound::Open(f64::INFINITY), Bound::Closed(20.0)),
        null: Some("for \"clove_hitch\", 10 h; no cylinder for the other knots"),
        paper: "",
        doc: "Radius R of the rigid, fixed cylinder (a pole, its axis z through the origin) that knot \
              \"clove_hitch\" is tied round; other knots have none (leave it out). At most L/20: the rod must wrap \
              it twice and keep its ends.",
        value: |p| p.cylinder_radius.map(Value::Number),
    },
    Parameter {
        name: "h",
        group: Group::Rod,
        unit: "m",
        default: "1.6e-3",
        range: Range::LengthOver(
            Bound::Closed(MIN_RADIUS_DIVISOR),
            Bound::Open(1.0 / MAX_RADIUS_RATIO),
        ),
        null: None,
        paper: "1.6 mm",
        doc: "Rod radius h, from L/16000 (the knot builder's edges of at most 4h within 4001 nodes) to below L/50 \
              (a knot needs room in L).",
        value: |p| Some(Value::Number(p.h)),
    },
    Parameter {
        name: "mu",
        group: Group::Friction,
        unit: "",
        default: "0.1",
        range: closed(0.0, 2.0),
        null: None,
        paper: "0.1",
        doc: "Coulomb friction coefficient.",
        value: |p| Some(Value::Number(p.mu)),
    },
    Parameter {
        name: "friction_law",
        group: Group::Friction,
        unit: "",
        default: "\"isotropic\"",
        range: Range::Words(&["isotropic", "sliding_direction"]),
        null: None,
        paper: "",
        doc: "Which tangential forces friction may take (eqs. 9-10): \"isotropic\", Coulomb's disk |F_t| <= mu F_n, \
              or \"sliding_direction\", only along the previous step's sliding direction (fails the capstan check, \
              kept for sensitivity studies, docs/FIDELITY.md).",
        value: UNCHECKED,
    },
    Parameter {
        name: "rolling",
        group: Group::Friction,
        unit: "",
        default: "false",
        range: Range::Flag,
        null: None,
        paper: "false",
        doc: "Friction acts at the rods' surfaces: a contact's slip includes each rod's spin about its axis and \
              friction torques the twist, so rods roll on each other (a rod on an inclined rod rolls at (2/3) g \
              sin alpha). false: friction at the centre lines, as in the paper's method and code, the model that \
              reproduces the paper's Figs 1, 7, 9 and 11 together with its start twist. The inversions of both \
              are in docs/VALIDATION.md (\"Sensitivity\"), set beside the paper's in docs/FIDELITY.md.",
        value: UNCHECKED,
    },
    Parameter {
        name: "contact_solve",
        group: Group::Solver,
        unit: "",
        default: "\"explicit\"",
        range: Range::Words(&["explicit", "implicit"]),
        null: None,
        paper: "\"explicit\"",
        doc: "How each step's contact forces see the rods' response: \"explicit\" (the paper's method: free \
              velocities v + dt M^-1 F and the mass-only Delassus operator, the forces then held fixed in the \
              implicit step) or \"implicit\" (the free velocities of a contact-free implicit step and the Delassus \
              operator of its Newton matrix, so a sticking contact holds for the motion the step takes, without \
              creep; a banded solve per contact axis and a dense contact solve each step, many times the explicit \
              solve's cost: BENCHMARKS.md).",
        value: UNCHECKED,
    },
    Parameter {
        name: "contact_candidates",
        group: Group::Solver,
        unit: "",
        default: "\"detected\"",
        range: Range::Words(&["detected", "predicted"]),
        null: None,
        paper: "\"predicted\" (the code)",
        doc: "Which segment pairs get a contact force each step: \"detected\" (every pair within reach at the start \
              of the step, one of two pairs meeting at a shared node) or \"predicted\" (as the paper's code: only \
              the pairs that a contact-free implicit predictor step brings closer than 2h, so a touching pair that \
              the predictor pulls apart gets no force in that step; a second Newton solve per step). With dt 1 ms \
              fixed (adaptive_dt false) and the reference protocol, \"predicted\" is the paper's code's scheme: \
              its inversions are in docs/VALIDATION.md (\"Sensitivity\"), beside the paper's code's in \
              docs/FIDELITY.md.",
        value: UNCHECKED,
    },
    Parameter {
        name: "contact_geometry",
        group: Group::Solver,
        unit: "",
        default: "\"smooth\"",
        range: Range::Words(&["segment", "smooth"]),
        null: None,
        paper: "\"segment\"",
        doc: "Which centre lines contacts are computed between: \"smooth\" (C1 cubic curves through the nodes \
              smoothed by an eighth towards their neighbours, half the chords' sag inside the nodes' circle: gap, \
              normal and the forces' weights on the nodes vary smoothly as one rod slides along another) or \
              \"segment\" (the paper's, the default before revision 17: the straight segments between the \
              nodes, whose kinks and sag make a sliding contact ride a washboard, a sawtooth of one edge's period in \
              force curves, and a frictionless knot lose 8 % of the clamps' work at the paper's K). A rope pulled \
              over a rod wavers by 0.15 % of its normal force against 9 %; n = 3's sawtooth is 0.88 % of F bar \
              against 8.1 %, its inversion 133.12 against 136.15, at 1.25 times the \
              segments' instructions (docs/FIDELITY.md, \"Contact geometry\").",
        value: UNCHECKED,
    },
    Parameter {
        name: "start_twist",
        group: Group::Knot,
        unit: "turns",
        default: "null",
        range: closed(-20.0, 20.0),
        null: Some(
            "for the overhand knot the paper's code's, which gives the rod the linking number 2n with the pull \
             axis (sign of the knot's writhe); 0 for the other knots",
        ),
        paper: "null (the code)",
        doc: "Twist the knot starts with between its clamps, spread evenly along the rod; 0: none, as if the \
              knot's ends had turned freely while it was tied. The report gives the twist used and the knot's \
              writhe; docs/VALIDATION.md (\"Sensitivity\") the inversions with and without it.",
        value: |p| p.start_twist.map(Value::Number),
    },
    Parameter {
        name: "gravity",
        group: Group::Loading,
        unit: "m/s^2",
        default: "[0.0, 0.0, 0.0]",
        range: Range::Components(-1e3, 1e3),
        null: None,
        paper: "[0, 0, 0]",
        doc: "Gravitational acceleration, a vector; the pull is along x.",
        value: |p| Some(Value::Vector(p.gravity)),
    },
    Parameter {
        name: "length",
        group: Group::Rod,
        unit: "m",
        default: "1.0",
        range: closed(0.05, 100.0),
        null: None,
        paper: "1 m",
        doc: "Rod length L.",
        value: |p| Some(Value::Number(p.length)),
    },
    Parameter {
        name: "nodes",
        group: Group::Solver,
        unit: "",
        default: "null",
        range: Range::Integers(51, MAX_NODES as u64),
        null: Some(
            "edges of at most 2.08 h (the paper's L = 1 m, h = 1.6 mm, K = 301), at least 301 nodes, at most \
             4001; with initial_shape, its point count",
        ),
        paper: "301",
        doc: "Node count K. The knot builder needs edges of at most 4h; the default resolves every knot as the \
              paper's rod is resolved (docs/FIDELITY.md, \"Any rod\": the convergence in K). The report's params \
              give the K used.",
        value: |p| p.nodes.map(|k| Value::Integer(k as u64)),
    },
    Parameter {
        name: "youngs_modulus",
        group: Group::Rod,
        unit: "Pa",
        default: "1.8e6",
        range: closed(1e3, 1e12),
        null: None,
        paper: "1.8 MPa",
        doc: "Young's modulus E. Named materials with their sources: docs/API.md, \"Materials\" \
              (GET /api/materials). Without gravity the inversion does not depend on E or density: the default \
              pull is the paper's rate for the rod.",
        value: |p| Some(Value::Number(p.youngs_modulus)),
    },
    Parameter {
        name: "poisson_ratio",
        group: Group::Rod,
        unit: "",
        default: "0.5",
        range: closed(0.0, 0.5),
        null: None,
        paper: "0.5",
        doc: "Poisson's ratio nu. It sets the twisting stiffness GJ/EI = 1/(1 + nu), which moves the \
              inversion: it is a material constant the geometry does not absorb (docs/FIDELITY.md, \"Any rod\").",
        value: |p| Some(Value::Number(p.poisson_ratio)),
    },
    Parameter {
        name: "density",
        group: Group::Rod,
        unit: "kg/m^3",
        default: "1000.0",
        range: closed(1.0, 1e5),
        null: None,
        paper: "1000 (the code)",
        doc: "Density rho. Its weight is physical under gravity; its inertia sets the rod's wave speed \
              sqrt(E / rho), the time unit the case is computed in.",
        value: |p| Some(Value::Number(p.density)),
    },
    Parameter {
        name: "mass_scaling",
        group: Group::Solver,
        unit: "",
        default: "true",
        range: Range::Flag,
        null: None,
        paper: "false",
        doc: "Compute a rod whose waves are faster than the paper's rod's, relative to pull_speed, with its inertia \
              scaled up to the paper's pull rate pull_speed / sqrt(E / rho) (mass scaling; its weight stays \
              physical): inversion is quasi-static, so its l_k bar does not depend on E or rho, and a steel rod \
              then costs what the paper's rubber rod costs. The report gives the scale (mass_scale) and whether \
              the case stayed quasi-static. false: the physical inertia, for studies of the pull's speed.",
        value: UNCHECKED,
    },
    Parameter {
        name: "pull_speed",
        group: Group::Loading,
        unit: "m/s",
        default: "null",
        range: closed(1e-7, 100.0),
        null: Some(
            "the paper's pull rate for this rod: 3 mm/s times its wave speed sqrt(E / rho) over the paper's rod's \
             (3 mm/s for the paper's rubber, 0.36 m/s for steel), a quasi-static pull of any rod at the paper's cost",
        ),
        paper: "1 mm/s (the text), 3 mm/s (the code)",
        doc: "Pulling speed of each clamp. A speed slower than the rod's paper's rate is computed at that rate with \
              mass scaling (mass_scaling); a faster one with the physical inertia, and the report says whether the \
              pull stayed quasi-static.",
        value: |p| p.pull_speed.map(Value::Number),
    },
    Parameter {
        name: "protocol",
        group: Group::Loading,
        unit: "",
        default: "\"adaptive\"",
        range: Range::Words(&["reference", "adaptive"]),
        null: None,
        paper: "\"reference\"",
        doc: "How the clamps move: \"reference\" pulls at pull_speed throughout, as in the paper. \"adaptive\" pulls \
              fast while the knot is far from its snap (damped, sparing the sliding along the rod, keeping \
              checkpoints); once it sees a snap it goes back to a checkpoint before it, lets the knot settle and \
              pulls through the snap at pull_speed (solver::protocol holds its constants; at the largest frictions \
              it pulls as \"reference\" does). Its inversions match the reference's at a fraction of the cost, \
              but its fast approach reads F bar high (BENCHMARKS.md, \"Pull protocols\"): choose \"reference\" for \
              force curves.",
        value: UNCHECKED,
    },
    Parameter {
        name: "dt",
        group: Group::Solver,
        unit: "s",
        default: "null",
        range: closed(1e-9, 1.0),
        null: Some(
            "0.5 ms for the paper's rod (half its code's 1 ms, converged within 0.4 %), scaled as l_e^2 / (c h) \
             with the edge length l_e, the simulated wave speed c and, for rods thinner than the paper's, the \
             radius h, so that every rod's contacts are stepped as the paper's; at most 20 times the step of the \
             rod's waves at the paper's resolution",
        ),
        paper: "1 ms (the code)",
        doc: "Time step; with adaptive_dt the largest step.",
        value: |p| p.dt.map(Value::Number),
    },
    Parameter {
        name: "adaptive_dt",
        group: Group::Solver,
        unit: "",
        default: "true",
        range: Range::Flag,
        null: None,
        paper: "false",
        doc: "Halve the step (down to dt/64) while contacts penetrate and grow it back when calm; false: the \
              constant dt of the paper's scheme.",
        value: UNCHECKED,
    },
    Parameter {
        name: "contact_tolerance",
        group: Group::Solver,
        unit: "",
        default: "1e-6",
        range: closed(1e-12, 1e-3),
        null: None,
        paper: "",
        doc: "Relative tolerance of each step's frictional contact solve (projected Gauss-Seidel): the forces are \
              accepted when a sweep changes none by more than this times the largest, or the natural-map residual \
              is this small (at most 200 sweeps; 12 with the smooth contact geometry, whose solves stop at the \
              cap: docs/FIDELITY.md, \"The smooth solve's cap\").",
        value: |p| Some(Value::Number(p.contact_tolerance)),
    },
    Parameter {
        name: "relax_time",
        group: Group::Solver,
        unit: "s",
        default: "null",
        range: closed(0.0, 100.0),
        null: Some(
            "2 s in the case's time unit: the paper's rod's 2 s, scaled as its knot's dynamics (report's time_unit)",
        ),
        paper: "",
        doc: "Longest relaxation with the ends held before pulling.",
        value: |p| p.relax_time.map(Value::Number),
    },
    Parameter {
        name: "relax_tolerance",
        group: Group::Solver,
        unit: "",
        default: "1e-4",
        range: closed(0.0, 1.0),
        null: None,
        paper: "",
        doc: "Relaxation ends when the kinetic energy falls below this times the elastic energy.",
        value: |p| Some(Value::Number(p.relax_tolerance)),
    },
    Parameter {
        name: "damping",
        group: Group::Solver,
        unit: "1/s",
        default: "0.0",
        range: closed(0.0, 1e4),
        null: None,
        paper: "",
        doc: "Mass-proportional viscous damping rate while pulling.",
        value: |p| Some(Value::Number(p.damping)),
    },
    Parameter {
        name: "end_to_end",
        group: Group::Knot,
        unit: "m",
        default: "null",
        range: Range::LengthOver(Bound::Open(f64::INFINITY), Bound::Closed(1.0)),
        null: Some("the knot builder's default for n"),
        paper: "",
        doc: "Initial clamp-to-clamp distance of the overhand knot.",
        value: |p| p.end_to_end.map(Value::Number),
    },
    Parameter {
        name: "braid_length",
        group: Group::Knot,
        unit: "m",
        default: "null",
        range: Range::LengthOver(Bound::Open(f64::INFINITY), Bound::Closed(2.0)),
        null: Some("the knot builder's default"),
        paper: "",
        doc: "Strand length of a braid pass in the overhand knot's initial shape.",
        value: |p| p.braid_length.map(Value::Number),
    },
    Parameter {
        name: "sample_interval",
        group: Group::Solver,
        unit: "",
        default: "0.5",
        range: closed(1e-3, 100.0),
        null: None,
        paper: "",
        doc: "Series sampling interval in l_k bar.",
        value: |p| Some(Value::Number(p.sample_interval)),
    },
    Parameter {
        name: "min_l_k_bar",
        group: Group::Loading,
        unit: "",
        default: "60.0",
        range: closed(0.0, 1e6),
        null: None,
        paper: "",
        doc: "Stop when the knot's own length l_k arc bar, (arc length - l_c) / h (l_k bar less the rod's stretch), \
              falls below this.",
        value: |p| Some(Value::Number(p.min_l_k_bar)),
    },
    Parameter {
        name: "stop_after_inversion",
        group: Group::Loading,
        unit: "",
        default: "10.0",
        range: closed(0.0, 1e6),
        null: Some("never early"),
        paper: "",
        doc: "Stop this far past a detected inversion, in the knot's own length l_k arc bar.",
        value: |p| p.stop_after_inversion.map(Value::Number),
    },
    Parameter {
        name: "max_force_bar",
        group: Group::Loading,
        unit: "",
        default: "null",
        range: Range::Interval(Bound::Open(0.0), Bound::Open(f64::INFINITY)),
        null: Some("a bend's or a hitch's 0.05; any other knot's 1, its rod stretched by a quarter"),
        paper: "",
        doc: "Stop when F bar exceeds this (the knot is tight).",
        value: |p| p.max_force_bar.map(Value::Number),
    },
    Parameter {
        name: "eased_force_bar",
        group: Group::Loading,
        unit: "",
        default: "null",
        range: Range::Interval(Bound::Open(0.0), Bound::Open(BEND_SET_FORCE_BAR)),
        null: Some("0.0025, a tenth of the setting load, for a bend; no easing for the other knots"),
        paper: "",
        doc: "A bend's eased load: once set (F bar 0.025, its tails held) each of its four ends moves back towards \
              the knot, for at most 10 radii, while it pulls harder than this F bar; then the tails are let go. \
              Below the setting load; bends only (a hitch is eased to its tail's weight, F bar 0.005). Easing \
              loosens the set knot as well as unloading it, so the holding force of a bend that comes apart \
              soon after its release depends on it (docs/FIDELITY.md, Bends, \"Convergence\").",
        value: |p| p.eased_force_bar.map(Value::Number),
    },
    Parameter {
        name: "initial_shape",
        group: Group::Knot,
        unit: "m",
        default: "null",
        range: Range::Points,
        null: Some("the builder's knot"),
        paper: "",
        doc: "Start from these points instead of the builder's knot: the polyline must be `length` long (within \
              1 %), every node between the ends along the line joining them (the clamps hold the first and last \
              points), no two non-neighbouring pieces of its centre line closer than 2h by more than 1 % \
              (strands pressed together, as in a relaxed snapshot a case wrote), measured on the centre lines \
              contact_geometry computes contacts between, and carry the Alexander polynomial of the knot chosen \
              (knot, n, braid_word). A bend's two rods: {\"rods\": [{\"points\": [...], \"start\": \
              \"pulled\", \"finish\": \"free\"}, {...}]}, each rod `length` long with K points and one end \
              pulled, the other free (its tail), no two pieces closer than 2h by more than 1 % (docs/API.md, \
              \"Start shapes\"). Mind the request body limit (GET /api/limits).",
        value: UNCHECKED,
    },
    Parameter {
        name: "loading",
        group: Group::Loading,
        unit: "",
        default: "null",
        range: Range::Program,
        null: Some("one tightening: [{\"pull\": {}}], to the stopping rules"),
        paper: "null",
        doc: "The loading program: the stages the clamps go through after the knot has relaxed, in order, each an \
              object with one key. {\"pull\": {\"to_l_k_bar\": X}} tightens at pull_speed to X (null X: to the \
              stopping rules min_l_k_bar, stop_after_inversion and max_force_bar); {\"release\": {\"to_l_k_bar\": X}} \
              loosens at pull_speed to X (null X: back to where the program started); {\"hold\": {\"seconds\": T}} \
              holds the clamps still; {\"rotate\": {\"turns\": N, \"ends\": \"one\" or \"both\"}} turns the finish \
              clamp (or both, in opposite senses) by N turns in all about the pull axis, right-handed from the start \
              clamp to the finish clamp; {\"soft\": {\"stiffness_bar\": k, \"to_l_k_bar\": X}} moves the grips at \
              pull_speed with the clamps on springs of stiffness k h^3 / EI along the pull, to X. Every X is the \
              knot's own length l_k arc bar, (arc length - l_c) / h, which the rod's stretch does not move. \
              protocol = \"adaptive\" runs pulls and releases fast far from events. Events (inversions, flips back) \
              are detected in every stage (docs/API.md, \"Loading programs\").",
        value: UNCHECKED,
    },
];

impl CaseParams {
    /// A knot builder's refusal as the error of the parameter to change.
    fn knot_error(&self, e: KnotError) -> FieldError {
        let braid_or_h = if self.braid_length.is_some() {
            "braid_length"
        } else {
            "h"
        };
        let field = match &e {
            KnotError::Passes(_) | KnotError::Topology(_) | KnotError::WrongKnot { .. } => match self.knot {
                KnotKind::Overhand => "n",
                KnotKind::Braid => "braid_word",
                _ => "knot",
            },
            KnotError::Braid(_) => "braid_word",
            KnotError::RodTooShort { .. } => "length",
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
        let mut reason = match self.knot {
            KnotKind::Overhand => format!("the knot with n = {} passes cannot be built: {e}", self.n),
            kind => format!("knot \"{kind}\" cannot be built: {e}"),
        };
        if let KnotError::TooFewNodes { min, .. } = e
            && min > MAX_NODES
        {
            reason.push_str(&format!(
                " (more than the {MAX_NODES} allowed: use a larger h or a shorter length)"
            ));
        }
        FieldError {
            field: field.to_string(),
            reason,
        }
    }

    /// The shape the case starts from: `initial_shape`, checked
    /// ([`InitialShape::checked`]), or the knot builder's ([`crate::knot::build`]
    /// itself, so that a case accepted by [`CaseParams::validate`] can always
    /// start); a failure names the parameter to change.
    pub(super) fn start_shape(&self) -> Result<StartShape, FieldError> {
        let knot = self.knot()?;
        match &self.initial_shape {
            Some(_) if matches!(knot, Knot::CloveHitch(_)) => Err(FieldError {
                field: "initial_shape".to_string(),
                reason: format!(
                    "initial_shape gives a knot's rods; {} is tied round its cylinder by the solver: leave it out",
                    knot.name()
                ),
            }),
            Some(shape) => shape.checked(
                &knot,
                (self.length, self.node_count(), self.h),
                self.contact_geometry,
            ),
            None => knot.tie().map_err(|e| self.knot_error(e)),
        }
    }

    /// The knot in a few words: `"overhand n = 3"`, `"figure_eight"`,
    /// `"braid s1 s1 s1"` (the word as given), `"clove_hitch R = 0.032 m"`
    /// (a pole's radius when given).
    pub fn knot_label(&self) -> String {
        match (self.knot, &self.braid_word, self.cylinder_radius) {
            (KnotKind::Overhand, ..) => format!("overhand n = {}", self.n),
            (KnotKind::Braid, Some(word), _) => format!("braid {}", word.trim()),
            (KnotKind::CloveHitch, _, Some(radius)) => format!("clove_hitch R = {radius} m"),
            (kind, ..) => kind.to_string(),
        }
    }

    /// The F bar to which a set bend is eased before its tails are let go:
    /// `eased_force_bar`, or [`BEND_EASED_FORCE_BAR`].
    pub fn eased_force_bar(&self) -> f64 {
        self.eased_force_bar.unwrap_or(BEND_EASED_FORCE_BAR)
    }

    /// The radius of a hitch's cylinder: `cylinder_radius`, or
    /// [`knot::hitch::DEFAULT_RADIUS`] h.
    pub fn pole_radius(&self) -> f64 {
        self.cylinder_radius
            .unwrap_or(knot::hitch::DEFAULT_RADIUS * self.h)
    }

    /// The knot of the catalog this case ties; a parameter that does not
    /// belong to the chosen knot, or a refused braid word, is named.
    pub fn knot(&self) -> Result<Knot, FieldError> {
        let refuse = |field: &str, reason: String| FieldError {
            field: field.to_string(),
            reason,
        };
        let kind = self.knot;
        if kind != KnotKind::Overhand {
            let default = CaseParams::default();
            let overhand_only = [
                ("n", self.n != default.n),
                ("end_to_end", self.end_to_end.is_some()),
                ("braid_length", self.braid_length.is_some()),
            ];
            if let Some((field, _)) = overhand_only.into_iter().find(|(_, given)| *given) {
                return Err(refuse(
                    field,
                    format!("{field} shapes the overhand knot; knot \"{kind}\" has none: leave it out"),
                ));
            }
        }
        if kind.bend().is_some() && self.start_twist.is_some() {
            return Err(refuse(
                "start_twist",
                format!("knot \"{kind}\" is a bend: its tails are free, so no twist is held between clamps"),
            ));
        }
        if kind == KnotKind::CloveHitch && self.start_twist.is_some() {
            return Err(refuse(
                "start_twist",
                format!("knot \"{kind}\" lets its tail go once set, so no twist is held between clamps"),
            ));
        }
        if kind.bend().is_none() && self.eased_force_bar.is_some() {
            return Err(refuse(
                "eased_force_bar",
                format!(
                    "eased_force_bar is a set bend's eased load; knot \"{kind}\" is no bend: leave it out"
                ),
            ));
        }
        if kind != KnotKind::CloveHitch && self.cylinder_radius.is_some() {
            return Err(refuse(
                "cylinder_radius",
                format!(
                    "cylinder_radius is the radius of a hitch's cylinder; knot \"{kind}\" has none: leave it out"
                ),
            ));
        }
        let word = match (kind, &self.braid_word) {
            (KnotKind::Braid, None) => {
                return Err(refuse(
                    "braid_word",
                    "knot \"braid\" needs a braid word, e.g. \"s1 s2^-1 s1 s2^-1\"".to_string(),
                ));
            }
            (KnotKind::Braid, Some(text)) => {
                Some(BraidWord::parse(text).map_err(|e| refuse("braid_word", e.to_string()))?)
            }
            (_, Some(_)) => {
                return Err(refuse(
                    "braid_word",
                    format!("only knot \"braid\" reads a braid word; knot is \"{kind}\""),
                ));
            }
            (_, None) => None,
        };
        let (length, nodes, radius) = (self.length, self.node_count(), self.h);
        Ok(match (kind, word) {
            (KnotKind::Overhand, _) => Knot::Overhand(self.knot_spec()),
            (KnotKind::FigureEight, _) => Knot::FigureEight(FigureEightSpec {
                length,
                nodes,
                radius,
            }),
            (KnotKind::Braid, word) => Knot::Braid(BraidSpec {
                word: word.expect("read above"),
                length,
                nodes,
                radius,
            }),
            (KnotKind::CloveHitch, _) => Knot::CloveHitch(CloveHitchSpec {
                length,
                nodes,
                radius,
                cylinder_radius: self.pole_radius(),
            }),
            (kind, _) => Knot::Bend(BendSpec {
                bend: kind.bend().expect("every other knot is a bend"),
                length,
                nodes,
                radius,
            }),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{Value as Json, json};

    /// The table lists every field once, in the order of the struct, and
    /// each entry's default is the field's.
    #[test]
    fn the_table_holds_every_field_and_its_default() {
        let defaults = serde_json::to_value(CaseParams::default()).unwrap();
        let Json::Object(fields) = &defaults else { panic!() };
        let names: Vec<&str> = PARAMETERS.iter().map(|p| p.name).collect();
        let mut sorted = names.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), names.len(), "a parameter listed twice");
        assert_eq!(sorted, fields.keys().map(String::as_str).collect::<Vec<_>>());
        for p in PARAMETERS {
            let default: Json = serde_json::from_str(p.default).unwrap();
            assert_eq!(default, fields[p.name], "{}", p.name);
        }
    }

    /// Each word of a word range is accepted; a null may be given exactly
    /// where the table says so.
    #[test]
    fn words_and_nulls_are_what_serde_accepts() {
        for p in PARAMETERS {
            if let Range::Words(words) = p.range {
                for w in words {
                    let r: Result<CaseParams, _> = serde_json::from_value(json!({ p.name: w }));
                    assert!(r.is_ok(), "{} = {w}", p.name);
                }
            }
            let null: Result<CaseParams, _> = serde_json::from_value(json!({ p.name: null }));
            assert_eq!(null.is_ok(), p.null.is_some(), "{} = null", p.name);
        }
    }

    /// Every range check reads a value of its kind: defaults and every
    /// optional number set are checked without a mismatch, and pass.
    #[test]
    fn every_range_reads_its_kind_of_value() {
        let set = CaseParams {
            start_twist: Some(0.0),
            dt: Some(1e-3),
            nodes: Some(401),
            relax_time: Some(1.0),
            pull_speed: Some(3e-3),
            end_to_end: Some(0.3),
            braid_length: Some(0.2),
            stop_after_inversion: Some(5.0),
            max_force_bar: Some(1.0),
            ..CaseParams::default()
        };
        for p in PARAMETERS {
            assert_eq!(p.check(&CaseParams::default()), None, "{}", p.name);
            assert_eq!(p.check(&set), None, "{}", p.name);
        }
    }
}
