//! The simplified knot model of paper Sec. 5 (eqs. 12-15): the closed loop of an
//! overhand knot split into a braid of two helical strands with a closed-form
//! bending energy (`braid`, eqs. 13-14) and a contact-free loop whose energy is
//! found with DER (`loop_rod`, eq. 15). The total Ē(θ) = Ē_b + Ē_l, its
//! critical points and their stability (`landscape`, Fig. 13 a, b), and the
//! critical points as functions of l̄_k with their two folds (`bifurcation`,
//! Fig. 13 c; the lower fold is the snap-through of Figs. 14-15).
//! `reproduce` runs the paper's cases (their figures and document are drawn outside the solver: `knotsweep_server::figures::simplified`, `src/simplified_doc.rs`).
//!
//! Units: lengths in rod radii h, energies in EI/h (eq. 12). The reconstruction of
//! the loop's boundary conditions (Fig. 12 is not in the text) is documented in
//! `loop_rod` and in `docs/SIMPLIFIED_MODEL.md`.
pub mod bifurcation;
pub mod braid;
pub mod landscape;
pub mod loop_rod;
pub mod reproduce;

pub use bifurcation::{Bifurcation, BifurcationSpec, BranchPoint, Fold, bifurcation};
pub use braid::{Braid, Strand};
pub use landscape::{CriticalPoint, Landscape, LandscapePoint, LandscapeSpec, landscape};
pub use loop_rod::{EndTwist, LoopBoundary, LoopEquilibrium, LoopSolver};
pub use reproduce::{Reproduction, ReproductionSpec, reproduce};

use crate::material::Material;
use crate::rod::RodError;
use crate::stepper::StepError;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use thiserror::Error;

/// Parameters of the simplified model; defaults are the paper's (Sec. 5):
/// n = 3, epsilon = 0.7, phi = pi/3, h = 1.6 mm, E = 1.8 MPa, nu = 0.5.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Params {
    /// Unknotting number n (half-turns of the braid strands about each other, eq. 13).
    pub n: u32,
    /// epsilon = l_b / l_l (eq. after 11).
    pub epsilon: f64,
    /// Tilt phi of the loop's end tangents away from the braid axis (rad).
    pub phi: f64,
    /// Rod radius h (m). The model is scale-free, so results depend on h only
    /// through the solver tolerance (paper Fig. 14).
    pub radius: f64,
    /// Nodes K of the DER loop.
    pub loop_nodes: usize,
    /// Twist boundary condition at the loop's ends.
    pub end_twist: EndTwist,
    /// Rod material (only the ratios EA : EI : GJ matter).
    pub material: Material,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            n: 3,
            epsilon: 0.7,
            phi: PI / 3.0,
            radius: 1.6e-3,
            loop_nodes: 81,
            end_twist: EndTwist::Transported,
            material: Material::default(),
        }
    }
}

impl Params {
    /// l̄_b = epsilon l̄_k / (1 + epsilon).
    pub fn l_b_bar(&self, l_k_bar: f64) -> f64 {
        self.epsilon * l_k_bar / (1.0 + self.epsilon)
    }

    /// l̄_l = l̄_k / (1 + epsilon).
    pub fn l_l_bar(&self, l_k_bar: f64) -> f64 {
        l_k_bar / (1.0 + self.epsilon)
    }

    /// The braid at rotation `theta` for closed-loop length `l_k_bar`.
    pub fn braid(&self, theta: f64, l_k_bar: f64) -> Braid {
        Braid {
            n: self.n,
            theta,
            l_b_bar: self.l_b_bar(l_k_bar),
        }
    }

    /// Checks that the parameters describe a knot the model can represent.
    pub fn validate(&self) -> Result<(), SimplifiedError> {
        let bad = |what: &str| Err(SimplifiedError::InvalidParameter(what.to_string()));
        if self.n == 0 {
            return bad("n must be at least 1");
        }
        if !(self.epsilon > 0.0 && self.epsilon < 1.0) {
            return bad("epsilon must lie in (0, 1): the loop must be longer than the braid");
        }
        if !(self.phi > 0.0 && self.phi < PI / 2.0) {
            return bad("phi must lie in (0, pi/2)");
        }
        if !(self.radius > 0.0 && self.radius.is_finite()) {
            return bad("radius must be positive");
        }
        if self.loop_nodes < 11 {
            return bad("the loop needs at least 11 nodes");
        }
        Ok(())
    }

    /// Checks a closed-loop length and rotation angle against these parameters.
    pub fn check_state(&self, theta: f64, l_k_bar: f64) -> Result<(), SimplifiedError> {
        if !(l_k_bar.is_finite() && l_k_bar > 0.0) {
            return Err(SimplifiedError::InvalidParameter(format!(
                "l_k_bar = {l_k_bar} must be positive"
            )));
        }
        if !(theta.is_finite() && theta < f64::from(self.n) * PI) {
            return Err(SimplifiedError::InvalidParameter(format!(
                "theta = {theta} must be below n pi = {}",
                f64::from(self.n) * PI
            )));
        }
        Ok(())
    }
}

/// Why a simplified-model computation failed.
#[derive(Debug, Error, PartialEq)]
pub enum SimplifiedError {
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    #[error("could not build the loop: {0}")]
    Rod(#[from] RodError),
    #[error("no loop equilibrium at theta = {theta}, l_k_bar = {l_k_bar}: {source}")]
    Loop {
        theta: f64,
        l_k_bar: f64,
        #[source]
        source: StepError,
    },
    #[error("continuation stalled at theta = {theta}, l_k_bar = {l_k_bar}: {reason}")]
    Stalled {
        theta: f64,
        l_k_bar: f64,
        reason: String,
    },
}
