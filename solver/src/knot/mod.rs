//! Overhand knots (paper Sec. 2 and 4): the builder of the initial centreline
//! and the topology check (knot determinant of the closed curve).
mod builder;
mod geometry;
pub mod topology;
mod twist;

pub use builder::{
    BRAID_MARGIN, KnotError, KnotShape, KnotSpec, MAX_EDGE_RADII, MAX_PASSES, MAX_RADIUS_RATIO, MIN_BEND,
    MIN_EDGES_PER_PASS, MIN_PITCH, Regions, build,
};
pub use topology::{
    TopologyError, close_open_curve, closed_knot_determinant, determinant_along, expected_determinant,
    knot_determinant,
};
pub use twist::{paper_twist, writhe};
