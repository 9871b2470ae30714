//! Overhand knots (paper Sec. 2 and 4): the builder of the initial centreline,
//! the check of a user's start shape and the topology check (knot determinant
//! of the closed curve).
mod builder;
mod geometry;
mod start;
pub mod topology;
mod twist;

pub use builder::{
    BRAID_MARGIN, KNOT_RADII, KnotError, KnotShape, KnotSpec, MAX_EDGE_RADII, MAX_PASSES, MAX_RADIUS_RATIO,
    MIN_BEND, MIN_EDGES_PER_PASS, MIN_PITCH, Regions, build,
};
pub use start::{StartShape, built_start, checked_start};
pub use topology::{
    TopologyError, close_open_curve, closed_knot_determinant, determinant_along, expected_determinant,
    knot_determinant,
};
pub use twist::{paper_twist, writhe, writhe_change};
