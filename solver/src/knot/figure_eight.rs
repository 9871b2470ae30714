//! The figure-eight knot `4_1` (Baek et al. 2021; Patil et al. 2020): the
//! closure of the braid `s1 s2^-1 s1 s2^-1`, tied as [`super::braid`] ties
//! a word.
use super::alexander::Alexander;
use super::braid::{self, BraidSpec, BraidWord};
use super::{Family, KnotError, StartShape};
use serde::{Deserialize, Serialize};

/// The figure-eight's braid word.
pub const WORD: &str = "s1 s2^-1 s1 s2^-1";

/// A figure-eight knot to tie. Lengths in metres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FigureEightSpec {
    /// Rod length `L`.
    pub length: f64,
    /// Node count `K`.
    pub nodes: usize,
    /// Cross-section radius `h`.
    pub radius: f64,
}

impl Family for FigureEightSpec {
    /// The knot tables' `t^2 - 3t + 1`.
    fn alexander(&self) -> Alexander {
        Alexander::new(vec![1, -3, 1]).expect("non-zero")
    }

    fn tie(&self) -> Result<StartShape, KnotError> {
        let spec = BraidSpec {
            word: BraidWord::parse(WORD).expect("the figure-eight's word is a knot"),
            length: self.length,
            nodes: self.nodes,
            radius: self.radius,
        };
        braid::tie(&spec, self.alexander())
    }

    /// None: the knot starts as if its ends had turned freely while it was
    /// tied (it is amphichiral: no handedness to favour).
    fn twist(&self, _writhe: f64) -> f64 {
        0.0
    }
}
