//! Frictional contact between rod segments (paper Sec. 3.2).
pub mod broad_phase;
pub mod cone;
pub mod gauss_seidel;
pub mod narrow_phase;
pub mod segment;

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
