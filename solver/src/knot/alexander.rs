//! The Alexander polynomial `Delta(t)` of a polygonal knot, the invariant a
//! knot of the catalog keeps: it tells the figure-eight (`t^2 - 3t + 1`)
//! from `5_1` (`t^4 - t^3 + t^2 - t + 1`), which share the determinant
//! `|Delta(-1)| = 5`.
//!
//! From a generic diagram of the closed curve ([`super::topology`]) with `c`
//! crossings and `c` arcs, each crossing gives a row of the Alexander matrix
//! (the Fox derivatives of its Wirtinger relation, abelianised): `1 - t` at
//! the over arc, and at the incoming and outgoing under arcs `t, -1` for a
//! right-handed crossing, `-1, t` for a left-handed one. `Delta` is the
//! determinant of any `(c-1) x (c-1)` minor, up to a unit `+-t^k`. The minor,
//! of degree at most `c - 1` in `t`, is evaluated exactly at `t = 1..=c`
//! modulo two 62-bit primes ([`super::topology::det_mod`]), interpolated and
//! recombined to integer coefficients (exact for `|coefficient| < 2^121`).
//! The result is normalised: no factor `t`, lowest coefficient positive, so
//! the trefoil's is `[1, -1, 1]`. A knot's polynomial has `Delta(1) = +-1`
//! and is palindromic; a diagram that gives otherwise is refused.
use super::topology::{
    Crossing, PRIMES, TopologyError, arc_of, closed_diagram, det_mod, diagram_along, mul_mod, open_diagram,
    pow_mod, recombine,
};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::fmt;

/// A normalised Alexander polynomial: integer coefficients, lowest power
/// first, no factor `t`, the lowest coefficient positive.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Alexander(Vec<i64>);

impl Alexander {
    /// The unknot's `1`.
    pub fn one() -> Self {
        Self(vec![1])
    }

    /// The polynomial with these coefficients (lowest power first),
    /// normalised; `None` if they are all zero.
    pub fn new(mut coefficients: Vec<i64>) -> Option<Self> {
        while coefficients.last() == Some(&0) {
            coefficients.pop();
        }
        let first = coefficients.iter().position(|&c| c != 0)?;
        coefficients.drain(..first);
        if coefficients[0] < 0 {
            coefficients.iter_mut().for_each(|c| *c = -*c);
        }
        Some(Self(coefficients))
    }

    /// The `(2, q)` torus knot's (`q` odd): `1 - t + t^2 - ... + t^(q-1)`,
    /// the closure of the overhand knot with `n = (q - 1) / 2` passes.
    pub fn torus_2(q: u32) -> Self {
        Self((0..q).map(|k| if k % 2 == 0 { 1 } else { -1 }).collect())
    }

    /// Coefficients, lowest power first.
    pub fn coefficients(&self) -> &[i64] {
        &self.0
    }

    /// The knot determinant `|Delta(-1)|`.
    pub fn determinant(&self) -> u64 {
        let alternating: i64 = self
            .0
            .iter()
            .enumerate()
            .map(|(k, c)| if k % 2 == 0 { *c } else { -*c })
            .sum();
        alternating.unsigned_abs()
    }
}

impl fmt::Display for Alexander {
    /// `t^2 - 3t + 1`: highest power first.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut first = true;
        for (k, &c) in self.0.iter().enumerate().rev() {
            if c == 0 {
                continue;
            }
            let sign = match (first, c < 0) {
                (true, true) => "-",
                (true, false) => "",
                (false, true) => " - ",
                (false, false) => " + ",
            };
            let magnitude = c.unsigned_abs();
            let number = if magnitude == 1 && k > 0 {
                String::new()
            } else {
                magnitude.to_string()
            };
            let power = match k {
                0 => String::new(),
                1 => "t".to_string(),
                _ => format!("t^{k}"),
            };
            write!(f, "{sign}{number}{power}")?;
            first = false;
        }
        Ok(())
    }
}

/// Alexander polynomial of an open polyline whose end nodes lie on the
/// pulling axis (the long knot), closed as in [`super::close_open_curve`].
pub fn alexander(points: &[Vector3<f64>]) -> Result<Alexander, TopologyError> {
    open_diagram(points, polynomial)
}

/// Alexander polynomial of a closed polygon (the last point joins the first).
pub fn closed_alexander(points: &[Vector3<f64>]) -> Result<Alexander, TopologyError> {
    closed_diagram(points, polynomial)
}

/// Alexander polynomial of a closed polygon from its projection along
/// `direction` only; [`TopologyError::DegenerateProjection`] if that diagram
/// is not generic.
pub fn alexander_along(
    points: &[Vector3<f64>],
    direction: &Vector3<f64>,
) -> Result<Alexander, TopologyError> {
    diagram_along(points, direction, polynomial)
}

/// The normalised polynomial of a diagram's crossings.
pub(super) fn polynomial(crossings: &[Crossing]) -> Result<Alexander, TopologyError> {
    let c = crossings.len();
    if c <= 1 {
        return Ok(Alexander::one());
    }
    let mut unders: Vec<f64> = crossings.iter().map(|x| x.under).collect();
    unders.sort_by(f64::total_cmp);
    // Each entry a + b t as (a, b), rows of the minor without the last
    // crossing and the last arc.
    let m = c - 1;
    let mut matrix = vec![(0i64, 0i64); m * m];
    for (row, crossing) in crossings.iter().take(m).enumerate() {
        let incoming = arc_of(&unders, crossing.under);
        let outgoing = (incoming + 1) % c;
        let (t_at, minus_one_at) = if crossing.positive {
            (incoming, outgoing)
        } else {
            (outgoing, incoming)
        };
        let over = arc_of(&unders, crossing.over);
        for (col, (a, b)) in [(over, (1, -1)), (t_at, (0, 1)), (minus_one_at, (-1, 0))] {
            if col < m {
                let entry = &mut matrix[row * m + col];
                *entry = (entry.0 + a, entry.1 + b);
            }
        }
    }
    // The minor's coefficients modulo each prime, from its values at t = 1..=c.
    let residues = PRIMES.map(|p| {
        let xs: Vec<u64> = (1..=c as u64).collect();
        let values: Vec<u64> = xs
            .iter()
            .map(|&x| {
                let at: Vec<i64> = matrix
                    .iter()
                    .map(|&(a, b)| {
                        let v = (i128::from(a) + i128::from(b) * i128::from(x)).rem_euclid(i128::from(p));
                        v as i64
                    })
                    .collect();
                det_mod(&at, m, p)
            })
            .collect();
        interpolate(&xs, &values, p)
    });
    let coefficients = (0..c)
        .map(|k| {
            i64::try_from(recombine([residues[0][k], residues[1][k]])).map_err(|_| TopologyError::Overflow)
        })
        .collect::<Result<Vec<i64>, _>>()?;
    let poly = Alexander::new(coefficients).ok_or(TopologyError::DegenerateProjection)?;
    let at_one: i64 = poly.0.iter().sum();
    let palindromic = poly.0.iter().eq(poly.0.iter().rev());
    if at_one.abs() != 1 || !palindromic {
        return Err(TopologyError::DegenerateProjection);
    }
    Ok(poly)
}

/// Coefficients (lowest power first) modulo the prime `p` of the polynomial
/// of degree below `xs.len()` taking `values` at the distinct `xs` (Lagrange).
fn interpolate(xs: &[u64], values: &[u64], p: u64) -> Vec<u64> {
    let n = xs.len();
    // master = prod (t - x_j), degree n.
    let mut master = vec![0u64; n + 1];
    master[0] = 1;
    for &x in xs {
        for k in (0..=n).rev() {
            let shifted = if k > 0 { master[k - 1] } else { 0 };
            master[k] = (shifted + p - mul_mod(master[k], x, p)) % p;
        }
    }
    let mut out = vec![0u64; n];
    let mut quotient = vec![0u64; n];
    for (i, &x) in xs.iter().enumerate() {
        // master / (t - x) by synthetic division, highest power first.
        let mut carry = 0;
        for k in (0..n).rev() {
            carry = (master[k + 1] + mul_mod(carry, x, p)) % p;
            quotient[k] = carry;
        }
        let denominator = xs
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != i)
            .fold(1, |acc, (_, &y)| mul_mod(acc, (x + p - y) % p, p));
        let scale = mul_mod(values[i], pow_mod(denominator, p - 2, p), p);
        for k in 0..n {
            out[k] = (out[k] + mul_mod(scale, quotient[k], p)) % p;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_recovers_a_polynomial() {
        // 3 - 2t + t^3, with -2 as p - 2.
        let p = PRIMES[0];
        let f = |x: u64| (3 + x * x * x + p - 2 * x) % p;
        let xs = [1, 2, 3, 4];
        let values = xs.map(f);
        assert_eq!(interpolate(&xs, &values, p), [3, p - 2, 0, 1]);
    }

    #[test]
    fn normalised_and_written_highest_power_first() {
        let f8 = Alexander::new(vec![0, -1, 3, -1, 0]).unwrap();
        assert_eq!(f8.coefficients(), [1, -3, 1]);
        assert_eq!(f8.to_string(), "t^2 - 3t + 1");
        assert_eq!(f8.determinant(), 5);
        assert_eq!(
            Alexander::torus_2(7).to_string(),
            "t^6 - t^5 + t^4 - t^3 + t^2 - t + 1"
        );
        assert_eq!(Alexander::torus_2(7).determinant(), 7);
        assert_eq!(Alexander::new(vec![0, 0]), None);
        assert_eq!(Alexander::one().to_string(), "1");
    }

    /// The standard trefoil diagram (three right-handed crossings) gives
    /// `t^2 - t + 1`; its mirror (left-handed) the same, normalised.
    #[test]
    fn standard_trefoil_diagram() {
        for positive in [true, false] {
            let crossings = [(0.5, 3.5), (2.5, 5.5), (4.5, 1.5)].map(|(over, under)| Crossing {
                over,
                under,
                positive,
            });
            assert_eq!(polynomial(&crossings).unwrap().coefficients(), [1, -1, 1]);
        }
    }
}
