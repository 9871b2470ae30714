//! Why a contact solve refused its problem.
use thiserror::Error;

/// Invalid contact-solve input.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ContactError {
    /// `inv_mass` and `v_free` lengths differ.
    #[error("{inv_mass} inverse masses but {v_free} free velocities")]
    LengthMismatch {
        /// `inv_mass.len()`.
        inv_mass: usize,
        /// `v_free.len()`.
        v_free: usize,
    },
    /// A contact refers to a node that does not exist.
    #[error("contact {contact} refers to node {node} of {nodes}")]
    NodeOutOfRange {
        /// Offending contact.
        contact: usize,
        /// Its node id.
        node: usize,
        /// Number of nodes.
        nodes: usize,
    },
    /// A contact has a non-unit normal, a sliding direction that is neither
    /// zero nor a unit tangent, a negative `mu` or non-finite data.
    #[error(
        "contact {0} has a non-unit normal, a sliding direction that is not a unit tangent, a negative friction coefficient or non-finite data"
    )]
    InvalidContact(usize),
    /// A node has a negative or non-finite inverse mass or velocity.
    #[error("node {0} has an invalid inverse mass or free velocity")]
    InvalidNode(usize),
    /// The over-relaxation factor is outside (0, 2).
    #[error("over-relaxation factor {0} is outside (0, 2)")]
    InvalidRelaxation(f64),
    /// The time step is not positive and finite.
    #[error("time step {0} is not positive and finite")]
    InvalidTimeStep(f64),
    /// A warm-start force is not finite.
    #[error("warm-start force {0} is not finite")]
    InvalidWarmStart(usize),
    /// The warm start does not have one force per contact.
    #[error("warm start has {got} forces for {expected} contacts")]
    WarmStartLength {
        /// Number of contacts.
        expected: usize,
        /// Number of warm-start forces.
        got: usize,
    },
    /// A dense problem's arrays do not all have one entry per contact
    /// (`w`: one block per contact pair).
    #[error("dense contact problem: {what} has {got} entries, expected {expected}")]
    ProblemShape {
        /// Which array.
        what: &'static str,
        /// Entries expected.
        expected: usize,
        /// Entries given.
        got: usize,
    },
}
