//! What a contact solve reports.
use serde::{Deserialize, Serialize};

/// Outcome of a contact solve ([`super::gauss_seidel`], [`super::dense`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SolveReport {
    /// Sweeps performed.
    pub sweeps: usize,
    /// Final natural-map residual: `max_c || r_c - P_K(r_c - u_hat_c / w_c) ||`
    /// over the largest `|r_c|` (zero at an exact solution of eqs. 8-9).
    pub residual: f64,
    /// Whether a stopping criterion was met before the sweep cap.
    pub converged: bool,
}
