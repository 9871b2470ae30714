//! Frictional contact between rods (paper Sec. 3.2): the data model
//! ([`point`], [`problem`], [`options`], [`report`], [`error`]), detection
//! ([`broad_phase`], [`segment`] or the smooth [`curve`], [`narrow_phase`]), the friction cone
//! ([`cone`]), a rigid obstacle ([`cylinder`]) and the solvers ([`gauss_seidel`] and [`apgd`] on the lumped
//! mass, [`dense`] on a dense Delassus operator).
pub mod apgd;
pub mod broad_phase;
pub mod cone;
pub mod curve;
pub mod cylinder;
pub mod dense;
pub mod error;
pub mod gauss_seidel;
pub mod narrow_phase;
pub mod options;
pub mod point;
pub mod problem;
pub mod report;
pub mod segment;

pub use cylinder::Cylinder;
pub use error::ContactError;
pub use options::{Candidates, ContactOptions, ContactSolve, FrictionLaw, GaussSeidelOptions, Geometry};
pub use point::{ContactPoint, SpinDofs};
pub use problem::{DenseProblem, MassProblem};
pub use report::SolveReport;
