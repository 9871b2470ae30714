//! Knots from braid words: the closure of a braid on at most
//! [`MAX_STRANDS`] strands, opened into a long knot in one rod.
//!
//! A word is read as generators `s1 ... s4` (`s_i` crosses strands `i` and
//! `i + 1`, the one moving from position `i` to `i + 1` passing over;
//! `s_i^-1` the mirror crossing), each with an optional power `^k`, separated
//! by spaces: `"s1 s2^-1 s1 s2^-1"` is the figure-eight knot. The closure
//! must be one component (the word's permutation one cycle).
//!
//! The shape, in the plane `z = 0` up to the crossings: the braid runs along
//! `x` with its strands `s` apart in `y` (position 0 lowest), one letter per
//! `CROSSING h` of `x`, the crossing strands lifted to `z = +-a` at its middle.
//! Each position `k >= 1` returns from the braid's right end to its left end
//! along a stadium of radius `Y - k s` about the line `y = Y`, so the return
//! paths nest without crossing; position 0's return is cut: its ends run
//! straight along `x` to the clamps, the long knot's tails. Projected along
//! `z`, this is the closed braid's diagram cut at an arc outside every
//! crossing, so the long knot has the closure's type.
use super::alexander::{Alexander, polynomial};
use super::polyline::{Dense, check_clearance, equal_chords};
use super::topology::Crossing;
use super::{Family, KnotError, StartShape, check_knot};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::fmt;
use thiserror::Error;

/// Most strands a word may braid.
pub const MAX_STRANDS: usize = 5;
/// Most letters a word may have (powers expanded).
pub const MAX_LETTERS: usize = 64;
/// Lateral spacing of the braid's strands, in radii h.
const SPACING: f64 = 4.0;
/// Height of a crossing's strands above and below the plane, in radii h.
const LIFT: f64 = 1.4;
/// Length of one letter along the braid, in radii h.
const CROSSING: f64 = 10.0;
/// Radius of the innermost return path, in radii h.
const MIN_LOOP: f64 = 10.0;
/// Longest edge, in radii h: a letter spans at least four edges.
const MAX_EDGE: f64 = CROSSING / 4.0;

/// Why a braid word was refused.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum BraidError {
    #[error("the braid word is empty: give generators such as \"s1 s2^-1 s1 s2^-1\"")]
    Empty,
    #[error("{0:?} is not a generator: write s1 ... s4, each optionally with a power such as s2^-1")]
    Token(String),
    #[error("{token:?} braids {strands} strands: at most {MAX_STRANDS} (generators s1 ... s4)")]
    TooManyStrands { token: String, strands: usize },
    #[error("the word has {0} letters (powers expanded): at most {MAX_LETTERS}")]
    TooLong(usize),
    #[error("the braid closes to a link of {0} components, not a knot: its permutation must be one cycle")]
    Components(usize),
}

/// A braid word whose closure is a knot: letters `+i` for `s_i`, `-i` for
/// `s_i^-1`.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct BraidWord(Vec<i8>);

impl BraidWord {
    /// Reads `text` (see the module's doc) and checks that its closure is a
    /// knot on at most [`MAX_STRANDS`] strands.
    pub fn parse(text: &str) -> Result<Self, BraidError> {
        let mut letters = Vec::new();
        for token in text.split_whitespace() {
            let bad = || BraidError::Token(token.to_string());
            let rest = token.strip_prefix(['s', 'S']).ok_or_else(bad)?;
            let (index, power) = match rest.split_once('^') {
                Some((i, k)) => (i, k.parse::<i32>().map_err(|_| bad())?),
                None => (rest, 1),
            };
            let index: usize = index.parse().map_err(|_| bad())?;
            if index == 0 || power == 0 {
                return Err(bad());
            }
            if index >= MAX_STRANDS {
                return Err(BraidError::TooManyStrands {
                    token: token.to_string(),
                    strands: index + 1,
                });
            }
            let count = power.unsigned_abs() as usize;
            if letters.len() + count > MAX_LETTERS {
                return Err(BraidError::TooLong(letters.len() + count));
            }
            letters.extend(std::iter::repeat_n(power.signum() as i8 * index as i8, count));
        }
        if letters.is_empty() {
            return Err(BraidError::Empty);
        }
        let word = Self(letters);
        match word.components() {
            1 => Ok(word),
            k => Err(BraidError::Components(k)),
        }
    }

    /// Number of strands: the largest generator's index plus one.
    pub fn strands(&self) -> usize {
        self.0
            .iter()
            .map(|l| l.unsigned_abs() as usize)
            .max()
            .unwrap_or(0)
            + 1
    }

    /// Letters, `+i` for `s_i` and `-i` for `s_i^-1`.
    pub fn letters(&self) -> &[i8] {
        &self.0
    }

    /// Where the strand entering at `position` leaves the braid.
    fn permute(&self, mut position: usize) -> usize {
        for &letter in &self.0 {
            position = word_step(position, letter.unsigned_abs() as usize);
        }
        position
    }

    /// Components of the closure: cycles of the permutation.
    fn components(&self) -> usize {
        let m = self.strands();
        let mut seen = vec![false; m];
        let mut cycles = 0;
        for start in 0..m {
            if seen[start] {
                continue;
            }
            cycles += 1;
            let mut p = start;
            while !seen[p] {
                seen[p] = true;
                p = self.permute(p);
            }
        }
        cycles
    }

    /// The passes of the closed braid's single strand from position 0, in
    /// order: the position each pass enters the braid at.
    fn passes(&self) -> Vec<usize> {
        let mut passes = vec![0];
        for _ in 1..self.strands() {
            passes.push(self.permute(passes[passes.len() - 1]));
        }
        passes
    }

    /// The Alexander polynomial of the closure, from the closed braid's
    /// diagram read off the word (no geometry): crossing `k` is met twice,
    /// on the passes through positions `i - 1` and `i` of its letter.
    pub fn alexander(&self) -> Alexander {
        let letters = self.0.len();
        let mut visits: Vec<[f64; 2]> = vec![[0.0; 2]; letters];
        for (pass, &entry) in self.passes().iter().enumerate() {
            let mut position = entry;
            for (k, &letter) in self.0.iter().enumerate() {
                let i = letter.unsigned_abs() as usize;
                let at = (pass * letters + k) as f64 + 0.5;
                if position + 1 == i {
                    // Moving up: over for s_i, under for s_i^-1.
                    visits[k][usize::from(letter < 0)] = at;
                    position = i;
                } else if position == i {
                    visits[k][usize::from(letter > 0)] = at;
                    position = i - 1;
                }
            }
        }
        let crossings: Vec<Crossing> = visits
            .iter()
            .zip(&self.0)
            .map(|(&[over, under], &letter)| Crossing {
                over,
                under,
                // Viewed from +z with the strands along +x, the strand
                // moving up passes over in s_i: a left-handed crossing.
                positive: letter < 0,
            })
            .collect();
        polynomial(&crossings).expect("a closed braid's diagram is a knot diagram")
    }
}

impl fmt::Display for BraidWord {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let words: Vec<String> = self
            .0
            .iter()
            .map(|&l| {
                if l > 0 {
                    format!("s{l}")
                } else {
                    format!("s{}^-1", -l)
                }
            })
            .collect();
        write!(f, "{}", words.join(" "))
    }
}

/// A braid knot to tie. Lengths in metres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BraidSpec {
    pub word: BraidWord,
    /// Rod length `L`.
    pub length: f64,
    /// Node count `K`.
    pub nodes: usize,
    /// Cross-section radius `h`.
    pub radius: f64,
}

impl Family for BraidSpec {
    /// The closure's, from the word ([`BraidWord::alexander`]).
    fn alexander(&self) -> Alexander {
        self.word.alexander()
    }

    fn tie(&self) -> Result<StartShape, KnotError> {
        tie(self, self.alexander())
    }

    /// None: the knot starts as if its ends had turned freely while it was tied.
    fn twist(&self, _writhe: f64) -> f64 {
        0.0
    }
}

/// Ties `spec`'s word, checked to carry `expected`.
pub(super) fn tie(spec: &BraidSpec, expected: Alexander) -> Result<StartShape, KnotError> {
    let (h, length) = (spec.radius, spec.length);
    for (name, value) in [("length", length), ("radius", h)] {
        if !(value.is_finite() && value > 0.0) {
            return Err(KnotError::InvalidParameter { name, value });
        }
    }
    let edge = length / (spec.nodes.max(2) - 1) as f64;
    if edge > MAX_EDGE * h {
        return Err(KnotError::TooFewNodes {
            nodes: spec.nodes,
            min: (length / (MAX_EDGE * h)).ceil() as usize + 1,
        });
    }
    let spacing = edge.min(h) / 4.0;
    let knot = knot_curve(&spec.word, h, spacing);
    let knot_length = Dense::new(knot.clone()).length();
    let widest = MIN_LOOP + SPACING * (spec.word.strands() - 2) as f64;
    // Each tail reaches past the widest return path by four edges.
    let shortest_tail = widest * h + 4.0 * edge;
    let tail = 0.5 * (length - knot_length);
    if tail < shortest_tail {
        return Err(KnotError::RodTooShort {
            needed: knot_length + 2.0 * shortest_tail,
            length,
        });
    }
    let braid = CROSSING * h * spec.word.letters().len() as f64;
    let straight = |from: f64, to: f64| {
        let steps = ((to - from) / spacing).ceil().max(1.0) as usize;
        (0..steps).map(move |k| Vector3::new(from + (to - from) * k as f64 / steps as f64, 0.0, 0.0))
    };
    // Beyond clamp B, more than the chords' shortfall of the arc length.
    let extension = 4.0 * edge + 0.02 * length;
    let mut points: Vec<Vector3<f64>> = straight(-tail, 0.0).collect();
    points.extend(knot);
    points.extend(straight(braid, braid + tail + extension).skip(1));
    let centre = Vector3::new(0.5 * braid, 0.0, 0.0);
    points.iter_mut().for_each(|p| *p -= centre);
    let dense = Dense::new(points);
    let (points, _) =
        equal_chords(&dense.points, &dense.arc, edge, spec.nodes).expect("the extension outlasts the chords");
    check_clearance(&points, h, edge)?;
    check_knot(&points, &expected)?;
    let middle = points.len() / 2;
    Ok(StartShape::one_rod(points, middle, expected))
}

/// The knot's dense curve from the braid's left end on position 0 to its
/// right end on position 0, points at most `spacing` apart.
fn knot_curve(word: &BraidWord, h: f64, spacing: f64) -> Vec<Vector3<f64>> {
    let (s, a, c) = (SPACING * h, LIFT * h, CROSSING * h);
    let braid = c * word.letters().len() as f64;
    let centre_y = MIN_LOOP * h + s * (word.strands() - 1) as f64;
    let per_letter = (c / spacing).ceil() as usize;
    let mut points = vec![Vector3::zeros()];
    for entry in word.passes() {
        let mut position = entry;
        for (k, &letter) in word.letters().iter().enumerate() {
            let i = letter.unsigned_abs() as usize;
            let (from, to) = (position, word_step(position, i));
            // Over (z > 0) moving up in s_i and moving down in s_i^-1.
            let lift = if to == from {
                0.0
            } else if (to > from) == (letter > 0) {
                1.0
            } else {
                -1.0
            };
            for step in 1..=per_letter {
                let u = step as f64 / per_letter as f64;
                let smooth = u * u * (3.0 - 2.0 * u);
                let y = s * (from as f64 + (to as f64 - from as f64) * smooth);
                let z = lift * a * (PI * u).sin().powi(2);
                points.push(Vector3::new(c * (k as f64 + u), y, z));
            }
            position = to;
        }
        if position == 0 {
            break;
        }
        // Back along the stadium of this position.
        let radius = centre_y - s * position as f64;
        let arc_steps = (PI * radius / spacing).ceil() as usize;
        let arc = |x0: f64, from: f64| {
            (1..=arc_steps).map(move |k| {
                let phi = from + PI * k as f64 / arc_steps as f64;
                Vector3::new(x0 + radius * phi.cos(), centre_y + radius * phi.sin(), 0.0)
            })
        };
        points.extend(arc(braid, -0.5 * PI));
        let top_steps = (braid / spacing).ceil() as usize;
        points.extend((1..top_steps).map(|k| {
            Vector3::new(
                braid * (1.0 - k as f64 / top_steps as f64),
                centre_y + radius,
                0.0,
            )
        }));
        points.extend(arc(0.0, 0.5 * PI));
    }
    points
}

/// The position after a letter on generator `i` of a strand at `position`.
fn word_step(position: usize, i: usize) -> usize {
    if position + 1 == i {
        i
    } else if position == i {
        i - 1
    } else {
        position
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_are_read_and_refused_with_their_reason() {
        let f8 = BraidWord::parse("s1 s2^-1 s1 s2^-1").unwrap();
        assert_eq!(f8.letters(), [1, -2, 1, -2]);
        assert_eq!(f8.strands(), 3);
        assert_eq!(f8.to_string(), "s1 s2^-1 s1 s2^-1");
        assert_eq!(BraidWord::parse(" S1^3 ").unwrap().letters(), [1, 1, 1]);
        assert_eq!(BraidWord::parse("  "), Err(BraidError::Empty));
        assert_eq!(BraidWord::parse("s1 x2"), Err(BraidError::Token("x2".into())));
        assert_eq!(BraidWord::parse("s0"), Err(BraidError::Token("s0".into())));
        assert_eq!(BraidWord::parse("s1^0"), Err(BraidError::Token("s1^0".into())));
        assert!(matches!(
            BraidWord::parse("s1 s5"),
            Err(BraidError::TooManyStrands { strands: 6, .. })
        ));
        assert_eq!(BraidWord::parse("s1 s3"), Err(BraidError::Components(2)));
        assert_eq!(BraidWord::parse("s1^2"), Err(BraidError::Components(2)));
        assert_eq!(BraidWord::parse("s2 s2 s2"), Err(BraidError::Components(2)));
        assert_eq!(BraidWord::parse("s1^65"), Err(BraidError::TooLong(65)));
    }

    /// The closures' polynomials from the word alone: the torus knots
    /// `T(2, q)` from `s1^q`, the figure-eight and the `(3, 4)` torus knot
    /// `8_19`, `t^6 - t^5 + t^3 - t + 1`, and `5_2`, `2t^2 - 3t + 2`.
    #[test]
    fn closures_have_their_table_polynomials() {
        let of = |w: &str| BraidWord::parse(w).unwrap().alexander();
        assert_eq!(of("s1 s1 s1"), Alexander::torus_2(3));
        assert_eq!(of("s1^-3"), Alexander::torus_2(3));
        assert_eq!(of("s1^5"), Alexander::torus_2(5));
        assert_eq!(of("s1 s2^-1 s1 s2^-1").coefficients(), [1, -3, 1]);
        assert_eq!(
            of("s1 s2 s1 s2 s1 s2 s1 s2").coefficients(),
            [1, -1, 0, 1, 0, -1, 1]
        );
        assert_eq!(of("s1^3 s2 s1^-1 s2").coefficients(), [2, -3, 2], "5_2");
        assert_eq!(of("s1 s2"), Alexander::one(), "a 3-strand unknot");
    }
}
