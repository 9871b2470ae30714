//! The knot catalog: one file per family, each behind [`Family`] (a spec
//! that ties its knot in a rod and names the invariant the knot keeps), and
//! the checks every family shares.
//!
//! - [`overhand`]: the overhand knot with `n` passes (paper Sec. 2 and 4);
//! - [`figure_eight`]: the figure-eight knot `4_1`;
//! - [`braid`]: the closure of any braid word on at most 5 strands;
//! - [`bends`]: two rods tied together, the reef, granny, thief and grief
//!   knots, and [`fisherman`]'s two overhand knots;
//! - [`hitch`]: the clove hitch, one rod tied round a rigid, fixed cylinder.
//!
//! A family's knot is a [`StartShape`]: its rods' centre lines with the two
//! pulled clamps (a one-rod knot's two ends; a bend's two standing ends, its
//! tails free) and, for a knot in one rod, its Alexander polynomial
//! ([`alexander`]), which the builder checks on the shape it ties and the
//! run on the shape at the end; a bend has none (its rods are open and
//! separate): the run reports whether its rods still hold each other; nor
//! has a hitch (its rod alone is unknotted): the run reports whether it
//! still holds the pole ([`StartShape::cylinder`]).
//! [`topology`] gives the cheaper knot determinant `|Delta(-1)|` checked at
//! every sample; [`twist`] the writhe and the start twist.
mod alexander;
pub mod bends;
pub mod braid;
pub mod figure_eight;
pub mod fisherman;
pub mod hitch;
pub mod overhand;
mod polyline;
mod start;
pub mod topology;
mod twist;

pub use alexander::{Alexander, alexander, alexander_along, closed_alexander};
pub use bends::{Bend, BendSpec};
pub use braid::{BraidError, BraidSpec, BraidWord};
pub use figure_eight::FigureEightSpec;
pub use hitch::{CloveHitchSpec, wrap_turns};
pub use overhand::{
    BRAID_MARGIN, KNOT_RADII, KnotShape, KnotSpec, MAX_EDGE_RADII, MAX_PASSES, MAX_RADIUS_RATIO, MIN_BEND,
    MIN_EDGES_PER_PASS, MIN_PITCH, Regions, build,
};
pub use polyline::{closest_approach, self_contact_span};
pub use start::{check_rods_clearance, checked_rod, checked_start};
pub use topology::{
    TopologyError, close_open_curve, closed_knot_determinant, determinant_along, expected_determinant,
    knot_determinant,
};
pub use twist::{paper_twist, writhe, writhe_change};

use crate::rod::End;
use nalgebra::Vector3;
use thiserror::Error;

/// A family of knots: a spec that ties its knot.
pub trait Family {
    /// The Alexander polynomial of the (long) knot it ties, from theory or
    /// algebra, not from its shape.
    fn alexander(&self) -> Alexander;

    /// A loose, contact-free start shape, checked to carry [`Family::alexander`].
    fn tie(&self) -> Result<StartShape, KnotError>;

    /// The twist (turns) the knot starts with when the case gives none, for
    /// a start shape of writhe `writhe`.
    fn twist(&self, writhe: f64) -> f64;
}

/// A knot of the catalog, ready to tie.
#[derive(Clone, Debug, PartialEq)]
pub enum Knot {
    Overhand(KnotSpec),
    FigureEight(FigureEightSpec),
    Braid(BraidSpec),
    Bend(BendSpec),
    CloveHitch(CloveHitchSpec),
}

impl Knot {
    /// The family of a knot in one rod (`None`: a bend).
    fn family(&self) -> Option<&dyn Family> {
        match self {
            Knot::Overhand(spec) => Some(spec),
            Knot::FigureEight(spec) => Some(spec),
            Knot::Braid(spec) => Some(spec),
            Knot::CloveHitch(spec) => Some(spec),
            Knot::Bend(_) => None,
        }
    }

    /// The knot in words: "the overhand knot with n = 3 passes".
    pub fn name(&self) -> String {
        match self {
            Knot::Overhand(spec) => format!("the overhand knot with n = {} passes", spec.n),
            Knot::FigureEight(_) => "the figure-eight knot".to_string(),
            Knot::Braid(spec) => format!("the closure of the braid {}", spec.word),
            Knot::Bend(spec) => spec.bend.name().to_string(),
            Knot::CloveHitch(_) => "the clove hitch".to_string(),
        }
    }

    /// The Alexander polynomial a knot in one rod keeps
    /// ([`Family::alexander`]); `None` for a bend and a hitch (held by
    /// another body, not by a knot type).
    pub fn alexander(&self) -> Option<Alexander> {
        match self {
            Knot::CloveHitch(_) => None,
            _ => self.family().map(Family::alexander),
        }
    }

    /// Its loose, contact-free start shape ([`Family::tie`], [`BendSpec::tie`]).
    pub fn tie(&self) -> Result<StartShape, KnotError> {
        match (self, self.family()) {
            (Knot::Bend(spec), _) => spec.tie(),
            (_, Some(family)) => family.tie(),
            (_, None) => unreachable!("every knot in one rod has a family"),
        }
    }

    /// The twist it starts with when the case gives none ([`Family::twist`];
    /// none for a bend, whose tails are free).
    pub fn twist(&self, writhe: f64) -> f64 {
        self.family().map_or(0.0, |f| f.twist(writhe))
    }
}

/// One of the two pulled clamps: an end of a rod.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Clamp {
    pub rod: usize,
    pub end: End,
}

/// The shape a case starts from: a family's knot, or a user's points
/// checked like one.
#[derive(Clone, Debug, PartialEq)]
pub struct StartShape {
    /// Centre line of each rod.
    pub rods: Vec<Vec<Vector3<f64>>>,
    /// A node of rod 0 in the middle of the knot's loop (where the braid
    /// search starts).
    pub loop_middle: usize,
    /// The Alexander polynomial a knot in one rod must keep; `None` for a
    /// bend.
    pub alexander: Option<Alexander>,
    /// The clamps pulled apart along the line joining them, the first
    /// towards its side, the second towards its: a one-rod knot's start and
    /// finish, a bend's standing ends, a hitch's standing end and tail.
    /// Every other end is free.
    pub clamps: [Clamp; 2],
    /// The rigid, fixed cylinder a hitch is tied round; `None` for a knot.
    pub cylinder: Option<crate::contact::Cylinder>,
    /// Each rod of a bend ties a knot of its own: the fisherman's overhand
    /// knots (found in the run by their self-contacts,
    /// [`self_contact_span`]).
    pub own_knots: bool,
}

impl StartShape {
    /// Rod 0's centre line.
    pub fn points(&self) -> &[Vector3<f64>] {
        &self.rods[0]
    }

    /// One rod clamped at both ends.
    pub fn one_rod(points: Vec<Vector3<f64>>, loop_middle: usize, alexander: Alexander) -> Self {
        Self {
            rods: vec![points],
            loop_middle,
            alexander: Some(alexander),
            clamps: [
                Clamp {
                    rod: 0,
                    end: End::Start,
                },
                Clamp {
                    rod: 0,
                    end: End::Finish,
                },
            ],
            cylinder: None,
            own_knots: false,
        }
    }

    /// Two rods pulled by their starts (their standing ends), the other ends
    /// free; `own_knots` when each rod ties a knot of its own.
    pub fn two_rods(rods: Vec<Vec<Vector3<f64>>>, own_knots: bool) -> Self {
        Self {
            rods,
            loop_middle: 0,
            alexander: None,
            clamps: [0, 1].map(|rod| Clamp { rod, end: End::Start }),
            cylinder: None,
            own_knots,
        }
    }

    /// Whether it is a bend (several rods).
    pub fn is_bend(&self) -> bool {
        self.rods.len() > 1
    }

    /// Whether it is a hitch (tied round a cylinder).
    pub fn is_hitch(&self) -> bool {
        self.cylinder.is_some()
    }

    /// The two pulled clamps' positions (the end nodes).
    pub fn clamp_points(&self) -> [Vector3<f64>; 2] {
        self.clamps.map(|c| {
            let rod = &self.rods[c.rod];
            match c.end {
                End::Start => rod[0],
                End::Finish => rod[rod.len() - 1],
            }
        })
    }
}

/// Why a knot could not be built.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum KnotError {
    #[error("number of passes n = {0} must be in 1..=8")]
    Passes(u32),
    #[error("{name} = {} must be finite and positive", Length(*.value))]
    InvalidParameter { name: &'static str, value: f64 },
    #[error(
        "radius h = {} m is too large: the rod length requires h < L/50 = {} m",
        Length(*.radius),
        Length(*.max)
    )]
    RadiusTooLarge { radius: f64, max: f64 },
    #[error(
        "{nodes} nodes cannot resolve the knot (edges at most 4h and a quarter of a braid pass): need {min}"
    )]
    TooFewNodes { nodes: usize, min: usize },
    #[error(
        "braid strand length {} m is too short for 2n+1 half twists of radius h: need {} m",
        Length(*.pass_length),
        Length(*.min)
    )]
    BraidTooShort { pass_length: f64, min: f64 },
    #[error(
        "tails of {} m (L - 2 braid - loop, halved) are too short: need {} m",
        Length(*.tail_length),
        Length(*.min)
    )]
    TailsTooShort { tail_length: f64, min: f64 },
    #[error(
        "no valid shape with braid passes of {} m, a loop of {} m and tails of {} m: the loop cannot close \
         around the braid, or the tails cannot reach the axis, with bend radii of at least 3 helix radii",
        Length(*.pass_length),
        Length(*.loop_length),
        Length(*.tail_length)
    )]
    Infeasible {
        pass_length: f64,
        loop_length: f64,
        tail_length: f64,
    },
    #[error(
        "end-to-end distance {} m is outside the feasible range [{}, {}] m",
        Length(*.clamp_span),
        Length(*.min),
        Length(*.max)
    )]
    EndToEndOutOfRange { clamp_span: f64, min: f64, max: f64 },
    #[error(
        "non-neighbouring segments are {} m apart, closer than 2h = {} m",
        Length(*.distance),
        Length(*.required)
    )]
    Clearance { distance: f64, required: f64 },
    #[error("topology check failed: {0}")]
    Topology(#[from] TopologyError),
    #[error("the built curve's Alexander polynomial is {got}, expected {expected}")]
    WrongKnot { got: Alexander, expected: Alexander },
    #[error("{0}")]
    Braid(#[from] BraidError),
    #[error(
        "the knot needs a rod of at least {} m (its return paths and tails reaching past them), got L = {} m",
        Length(*.needed),
        Length(*.length)
    )]
    RodTooShort { needed: f64, length: f64 },
}

/// A length (or another measure) in a message: four significant digits,
/// `0.4812`, `3.200e-3`.
struct Length(f64);

impl std::fmt::Display for Length {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        let x = self.0;
        let exponent = if x == 0.0 || !x.is_finite() {
            0
        } else {
            x.abs().log10().floor() as i32
        };
        if !(-2..4).contains(&exponent) {
            return write!(f, "{x:.3e}");
        }
        let text = format!("{x:.*}", (3 - exponent).max(0) as usize);
        match text.contains('.') {
            true => f.write_str(text.trim_end_matches('0').trim_end_matches('.')),
            false => f.write_str(&text),
        }
    }
}

/// Fails unless the long knot `points` has the Alexander polynomial `expected`.
fn check_knot(points: &[Vector3<f64>], expected: &Alexander) -> Result<(), KnotError> {
    let got = alexander(points)?;
    if got != *expected {
        return Err(KnotError::WrongKnot {
            got,
            expected: expected.clone(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lengths in messages: four significant digits, trailing zeros dropped.
    #[test]
    fn lengths_read_to_four_digits() {
        let written: Vec<String> = [
            3.2e-3,
            0.003199999999999999,
            0.48123456,
            0.02,
            1.0,
            12.345678,
            1e5,
            0.0,
        ]
        .into_iter()
        .map(|x| Length(x).to_string())
        .collect();
        assert_eq!(
            written,
            [
                "3.200e-3", "3.200e-3", "0.4812", "0.02", "1", "12.35", "1.000e5", "0"
            ]
        );
        let e = KnotError::Clearance {
            distance: 0.0031999999999999997,
            required: 3.2e-3,
        };
        assert_eq!(
            e.to_string(),
            "non-neighbouring segments are 3.200e-3 m apart, closer than 2h = 3.200e-3 m"
        );
    }
}
