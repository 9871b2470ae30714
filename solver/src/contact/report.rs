//! What a contact solve reports.
use serde::{Deserialize, Serialize};

/// Outcome of a contact solve ([`super::gauss_seidel`], [`super::dense`]).
/// The natural-map residual of the result is asked of the solver
/// (`GaussSeidel::residual`): a step's solve has no use for it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SolveReport {
    /// Sweeps performed.
    pub sweeps: usize,
    /// Whether a stopping criterion was met before the sweep cap.
    pub converged: bool,
}
