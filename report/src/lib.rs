//! knotsweep's presentation, one home for every figure and document the CLI
//! and the service write (pure string building from the solver's results, no
//! I/O):
//! - [`charts`]: F bar and H bar against l_k bar, phase diagrams (plotters);
//! - [`map`]: a sweep over two axes as a map of its critical l_k bar;
//! - [`pdf`]: those charts as PDF for journals;
//! - [`simplified`]: the simplified model's drawings (paper Sec. 5, Figs 12-15);
//! - [`snapshot`]: side views of the knot framed as the paper's Fig. 1;
//! - [`simplified_doc`] and [`validation`]: `docs/SIMPLIFIED_MODEL.md` and
//!   `docs/VALIDATION.md` with the figures they link;
//! - [`parameters`]: the parameter table of `docs/API.md`;
//! - [`tables`]: phase diagrams as CSV, columns named by [`symbols`];
//! - [`markdown`]: the tables of those documents;
//! - [`vtk`]: a case's snapshots as ParaView files (VTK XML `.vtp` and `.pvd`).
pub mod charts;
pub mod map;
pub mod markdown;
pub mod parameters;
pub mod pdf;
pub mod simplified;
pub mod simplified_doc;
pub mod snapshot;
pub mod symbols;
pub mod tables;
pub mod validation;
pub mod vtk;
