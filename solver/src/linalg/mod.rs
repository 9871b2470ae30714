//! Linear algebra for the Newton systems: a banded LDL^T (the DER Hessian is
//! banded in the DOF order of eq. 1).
pub mod banded;
