//! The two forms of the frictional contact problem (Signorini and Coulomb,
//! eqs. 8-9) that the solvers take: on the lumped mass ([`MassProblem`],
//! [`super::gauss_seidel`]) and on a dense Delassus operator in local frames
//! ([`DenseProblem`], [`super::dense`]).
use super::point::{ContactPoint, SpinDofs};
use nalgebra::{Matrix3, Vector3};

/// Contacts between rods whose nodes have lumped isotropic masses: the
/// Delassus operator is `W = dt H^T M^-1 H`, never formed.
#[derive(Debug, Clone, Copy)]
pub struct MassProblem<'a> {
    /// The contacts.
    pub contacts: &'a [ContactPoint],
    /// Each node's inverse mass (0: held).
    pub inv_mass: &'a [f64],
    /// Each node's contact-free velocity at the end of the step.
    pub v_free: &'a [Vector3<f64>],
    /// The twist DOFs the contacts spin (rolling); `None`: friction at the
    /// centre lines.
    pub spin: Option<SpinDofs<'a>>,
    /// The time step.
    pub dt: f64,
}

/// The contact problem in local frames.
#[derive(Debug, Clone, Copy)]
pub struct DenseProblem<'a> {
    /// Delassus blocks, row-major by blocks: block `(c, d)` at `c * m + d`.
    pub w: &'a [Matrix3<f64>],
    /// Free relative velocity of each contact, gap term included.
    pub free: &'a [Vector3<f64>],
    /// Friction coefficient of each contact.
    pub mu: &'a [f64],
    /// Local sliding direction of each contact (zero: the whole disk).
    pub sliding: &'a [Vector3<f64>],
}
