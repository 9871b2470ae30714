//! Frictional contact between rod segments (paper Sec. 3.2).
pub mod broad_phase;
pub mod cone;
pub mod dense;
pub mod gauss_seidel;
pub mod narrow_phase;
pub mod segment;

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

display_as_word!(FrictionLaw, ContactSolve, Candidates);
