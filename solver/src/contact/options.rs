//! The contact model's options (Sec. 3.2): friction law, solve, candidate
//! pairs, the Gauss-Seidel stopping rule, and their bundle [`ContactOptions`].
use crate::words::display_as_word;
use serde::{Deserialize, Serialize};

/// Which tangential forces Coulomb's law admits at a contact (eqs. 9-10).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrictionLaw {
    /// Friction anywhere in the tangent disk `|F_t| <= mu F_n`: a contact
    /// sticks against any tangential load below the bound (Coulomb's law;
    /// passes the capstan and inclined-rod closed forms).
    #[default]
    Isotropic,
    /// A literal reading of eqs. (9)-(10): friction acts along the sliding
    /// direction `t = u_t / |u_t|`, taken, like `d` and `n`, from the
    /// configuration at the start of the step (Sec. 3.2's explicit method),
    /// with `|F_t| <= mu F_n` on that line; where the contact has no relative
    /// tangential velocity yet, friction may point anywhere in the disk.
    /// Motion across the previous sliding direction meets no friction within
    /// a step, so a wrap can creep sideways: the capstan's tension ratio at
    /// mu = 0.1 over half a turn falls from exp(mu pi) = 1.37 to 1.02. Kept to
    /// study how much the knot's inversion owes to sticking across the
    /// sliding direction (docs/FIDELITY.md).
    SlidingDirection,
}

/// How each step's contact forces see the rods' response (Sec. 3.2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactSolve {
    /// The paper's explicit method: free velocities `v + dt M^-1 F(q_0)` and
    /// the mass-only Delassus operator `W = dt H^T M^-1 H`; the forces are then
    /// held fixed in the implicit step (eq. 7), which also feels the rods'
    /// stiffness, so a sticking contact holds for the explicit prediction, not
    /// for the motion the implicit step takes.
    #[default]
    Explicit,
    /// Consistent with the implicit step: the free velocities are those of a
    /// contact-free implicit step, and `W = H^T A^-1 H / dt` with `A` that
    /// step's Newton matrix (`M / dt^2` plus the elastic stiffness), so the
    /// forces make the step's own (linearised) motion satisfy eqs. 8-9.
    Implicit,
}

/// Which segment pairs get a contact force in a step (Sec. 3.2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Candidates {
    /// Every pair whose centre lines are within `r_a + r_b` plus a margin at
    /// the start of the step; of two pairs meeting at a node shared by
    /// adjacent segments, one.
    #[default]
    Detected,
    /// As the paper's code: only the pairs that a contact-free implicit step
    /// (a predictor) brings closer than `r_a + r_b`, all of them; a pair the
    /// predictor pulls apart gets no force in that step even if it touches.
    Predicted,
}

/// Which centre lines contacts are computed between (Sec. 3.2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Geometry {
    /// The C1 curves through the smoothed nodes ([`super::curve`]): gap, normal,
    /// contact points and the forces' weights on the nodes vary smoothly as
    /// one rod slides along another, so a pull meets no washboard at the
    /// edges' scale.
    #[default]
    Smooth,
    /// The paper's: closest points of the straight segments between the
    /// nodes (the polyline). As a node slides past a contact the normal and
    /// the gap kink and the chords' sag (`l^2 / (8 R)` on a bend of radius
    /// `R`) comes and goes, so force curves carry a sawtooth of one edge's
    /// period (docs/FIDELITY.md).
    Segment,
}

impl Geometry {
    /// The sweep cap ([`GaussSeidelOptions::max_sweeps`]) of the contact
    /// `solve`. The smooth rows' twelve-node stencils overlap along a line
    /// contact, whose nearly singular modes keep the explicit Gauss-Seidel
    /// from reaching 1e-6 in hundreds of sweeps. The warm start carries each
    /// solve on from the last step's forces, and n = 3's inversion, ripple
    /// and penetration do not move with the cap beyond what round-off alone
    /// moves them (12 to 200 sweeps: docs/FIDELITY.md, "The smooth solve's
    /// cap"). The implicit solve's rows couple every contact through the
    /// rods' Newton matrices and need their sweeps: capped at 12 a sticking
    /// contact slips 1.5e-3 of a free slide and the capstan's ratio falls
    /// 21 % short at mu phi = 0.6 pi; its cost is in building the Delassus
    /// operator, not in the sweeps.
    pub fn max_sweeps(self, solve: ContactSolve) -> usize {
        match (self, solve) {
            (Geometry::Smooth, ContactSolve::Explicit) => 12,
            _ => 200,
        }
    }

    /// The contact solve's over-relaxation ([`GaussSeidelOptions::relaxation`]).
    /// The segments' 1.5 reaches a line contact's solution in fewer sweeps;
    /// the smooth solve stops at its cap, where over-relaxed forces carry
    /// noise from one step to the next: under n = 3's reference pull 1.5 left
    /// a ripple of 0.97 % on F bar and took 279 402 Newton iterations, 1.1
    /// 0.38 % and 213 882 over the same steps (docs/FIDELITY.md, "The smooth
    /// solve's relaxation").
    pub fn relaxation(self) -> f64 {
        match self {
            Geometry::Segment => 1.5,
            Geometry::Smooth => 1.1,
        }
    }
}

display_as_word!(FrictionLaw, ContactSolve, Candidates, Geometry);

/// Stopping rule, relaxation and gap treatment.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GaussSeidelOptions {
    /// Sweep cap ([`Geometry::max_sweeps`] in a case).
    pub max_sweeps: usize,
    /// Over-relaxation factor `omega` in (0, 2) (projected SOR): contact `c`
    /// is updated by `r_c <- P(r_c - (omega / w_c) u_c)`, `P` the projection
    /// of Signorini and Coulomb's laws. `1` is plain Gauss-Seidel, whose local
    /// solves are exact. A line contact between two strands lying side by
    /// side has nearly singular modes (forces alternating along the strands,
    /// which move almost no node) that plain Gauss-Seidel damps only after
    /// hundreds of sweeps; `omega > 1` reaches the same solution in fewer
    /// sweeps (BENCHMARKS.md). A fixed point is a solution for every `omega`.
    /// [`Geometry::relaxation`] in a case.
    pub relaxation: f64,
    /// Stop when the largest force change over a sweep, or the natural-map
    /// residual ([`super::gauss_seidel::GaussSeidel::residual`], checked every 8 sweeps), is at
    /// most `tolerance` times the largest contact force.
    pub tolerance: f64,
    /// `true`: the free normal velocity gets `gap / dt`, so positive gaps may
    /// close and penetrations are removed within the step. `false`: only
    /// positive gaps are credited (`max(gap, 0) / dt`) and penetration is not
    /// pushed out (pure velocity-level Signorini).
    pub close_gap: bool,
}

impl Default for GaussSeidelOptions {
    fn default() -> Self {
        Self {
            max_sweeps: 200,
            relaxation: Geometry::Segment.relaxation(),
            tolerance: 1e-6,
            close_gap: true,
        }
    }
}

/// Contact model parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactOptions {
    /// Whether contact is detected and resolved at all.
    pub enabled: bool,
    /// Coulomb friction coefficient mu, eq. (9).
    pub friction: f64,
    /// Which tangential forces the friction bound admits (eqs. 9-10).
    pub friction_law: FrictionLaw,
    /// Friction acts at the rods' surfaces: a contact's relative velocity
    /// includes the touching surfaces' spin about each rod's axis (twist
    /// rates times the radius), and friction puts a torque on each twist, so
    /// a rod can roll on another. `false`: friction at the centre lines.
    pub rolling: bool,
    /// Detection margin added to r_a + r_b, as a fraction of the largest radius;
    /// the margin also grows with the fastest node's travel over the step.
    pub margin: f64,
    /// Fraction of a penetration removed within one step (1 = the paper's
    /// "gap closed in one step"; smaller values separate interpenetrating rods
    /// more gently).
    pub penetration_recovery: f64,
    /// The Gauss-Seidel stopping rule.
    pub solver: GaussSeidelOptions,
    /// Which free velocities and Delassus operator the contact solve uses.
    pub solve: ContactSolve,
    /// Which segment pairs get a contact force.
    pub candidates: Candidates,
    /// Which centre lines the contacts are computed between.
    pub geometry: Geometry,
}

impl Default for ContactOptions {
    fn default() -> Self {
        Self {
            enabled: true,
            friction: 0.1,
            friction_law: FrictionLaw::default(),
            rolling: true,
            margin: 0.25,
            penetration_recovery: 1.0,
            solver: GaussSeidelOptions::default(),
            solve: ContactSolve::default(),
            candidates: Candidates::default(),
            geometry: Geometry::default(),
        }
        .with_geometry(Geometry::default())
    }
}

impl ContactOptions {
    /// These options with contacts between `geometry`'s centre lines, solved
    /// with its sweep cap for [`ContactOptions::solve`] and its relaxation
    /// ([`Geometry::max_sweeps`], [`Geometry::relaxation`]).
    pub fn with_geometry(self, geometry: Geometry) -> Self {
        Self {
            geometry,
            solver: GaussSeidelOptions {
                max_sweeps: geometry.max_sweeps(self.solve),
                relaxation: geometry.relaxation(),
                ..self.solver
            },
            ..self
        }
    }
}
