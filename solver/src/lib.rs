//! knotsweep solver: discrete elastic rods (DER) with frictional self-contact,
//! following Sec. 3 of "Snap buckling of overhand knots" (the paper).
//!
//! Layout follows the paper: `rod` (DOFs and frames, Sec. 3.1), `energies`
//! (eq. 6), `external` (eq. 7c), `stepper` (eq. 7, over `linalg`'s banded
//! LDL^T), `contact` (Sec. 3.2), `pipeline` (one step), `knot` and
//! `protocol` with `measurements` (Sec. 4), `simplified` (Sec. 5); `case`
//! defines a case's parameters and validates them, `certify` a case's
//! refined twin and the uncertainty it gives; `snapshot` holds the
//! states of the knot a report keeps for viewers. Pure computation: no I/O,
//! deterministic for given inputs.
pub mod case;
pub mod certify;
pub mod contact;
pub mod counters;
pub mod energies;
pub mod external;
pub mod knot;
pub mod linalg;
pub mod material;
pub mod measurements;
pub mod pipeline;
pub mod protocol;
pub mod rod;
pub mod simplified;
pub mod snapshot;
pub mod snapshot_label;
pub mod stepper;
pub mod time_step;
pub mod validation;
mod words;
