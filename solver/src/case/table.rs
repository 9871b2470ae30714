//! The form of the parameter table ([`super::PARAMETERS`]): each entry's
//! range as data, the range check [`CaseParams::validate`] runs, and the texts
//! the CLI, the OpenAPI schema and docs/API.md show.
use super::{CaseParams, FieldError};

/// One case parameter, documented once: the CLI flags (`--` and the name with
/// dashes), the OpenAPI schema, the web form's help and docs/API.md's table
/// are made from it, and [`CaseParams::validate`] checks its range.
#[derive(Clone, Copy, Debug)]
pub struct Parameter {
    /// The JSON key and `CaseParams` field.
    pub name: &'static str,
    /// The part of the case it belongs to (the web form's sections, the
    /// CLI's help headings, the Python docstring's).
    pub group: Group,
    /// SI unit; empty for pure numbers, words and flags.
    pub unit: &'static str,
    /// The default as JSON (`CaseParams::default`'s value, checked by a test).
    pub default: &'static str,
    /// The values it may take.
    pub range: Range,
    /// What `null` means, for a parameter that may be null.
    pub null: Option<&'static str>,
    /// The paper's value (its text or its code), empty when it has none.
    pub paper: &'static str,
    /// What it is, what it is for and what it does to the results.
    pub doc: &'static str,
    /// The value its range check reads; `None` when null.
    pub(super) value: fn(&CaseParams) -> Option<Value>,
}

/// The parts of a case, in the order forms show them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Group {
    /// The knot: passes, start shape and twist.
    Knot,
    /// The rod: its size and material.
    Rod,
    /// Friction between the strands.
    Friction,
    /// How the knot is loaded and when the case stops.
    Loading,
    /// The solver's numerical options (forms fold them away).
    Solver,
}

impl Group {
    /// Every group, in form order.
    pub const ALL: [Group; 5] = [
        Group::Knot,
        Group::Rod,
        Group::Friction,
        Group::Loading,
        Group::Solver,
    ];

    /// The group's heading.
    pub fn title(self) -> &'static str {
        match self {
            Group::Knot => "Knot",
            Group::Rod => "Rod and material",
            Group::Friction => "Friction",
            Group::Loading => "Loading",
            Group::Solver => "Solver (advanced)",
        }
    }
}

/// The values a parameter may take.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Range {
    /// An integer in `lo..=hi`.
    Integers(u64, u64),
    /// A finite number between the bounds.
    Interval(Bound, Bound),
    /// A finite number between the rod length L divided by each bound's value
    /// (so the lower bound has the larger divisor; infinity stands for 0).
    LengthOver(Bound, Bound),
    /// Three finite numbers, each in `[lo, hi]`.
    Components(f64, f64),
    /// `true` or `false`.
    Flag,
    /// One of these words.
    Words(&'static [&'static str]),
    /// K = `nodes` points `[x, y, z]`, or rods with their ends' roles,
    /// checked as a start shape ([`super::InitialShape::checked`]).
    Points,
    /// A loading program ([`super::LoadStage`]), checked against the start
    /// shape.
    Program,
    /// A braid word ([`crate::knot::BraidWord`]), checked with the knot.
    BraidWord,
}

/// One end of an interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bound {
    Closed(f64),
    Open(f64),
}

/// A parameter's value as its range check reads it.
#[derive(Clone, Copy, Debug)]
pub(super) enum Value {
    Integer(u64),
    Number(f64),
    Vector([f64; 3]),
}

/// The value reader of parameters whose type serde checks alone.
pub(super) const UNCHECKED: fn(&CaseParams) -> Option<Value> = |_| None;

impl Parameter {
    /// The range as users read it, `null or ...` for a parameter that may be null.
    pub fn range_text(&self) -> String {
        let values = match self.range {
            Range::Integers(lo, hi) => format!("integer in {lo}..={hi}"),
            Range::Interval(lo, hi) => interval_text(lo, hi, number),
            Range::LengthOver(lo, hi) => interval_text(lo, hi, length_over),
            Range::Components(lo, hi) => format!("three numbers, each in [{}, {}]", number(lo), number(hi)),
            Range::Flag => "true or false".to_string(),
            Range::Words(words) => words
                .iter()
                .map(|w| format!("\"{w}\""))
                .collect::<Vec<_>>()
                .join(" or "),
            Range::Points => "K = nodes points [x, y, z], or {\"rods\": [...]} (a bend's two)".to_string(),
            Range::BraidWord => {
                "a braid word such as \"s1 s2^-1 s1 s2^-1\" (generators s1 ... s4)".to_string()
            }
            Range::Program => format!(
                "a list of at most {} stages, each {{\"pull\" | \"release\" | \"hold\" | \"rotate\" | \"soft\": {{...}}}}",
                super::loading::MAX_STAGES
            ),
        };
        match self.null {
            Some(_) => format!("null or {values}"),
            None => values,
        }
    }

    /// The values it takes, as a refusal names them: `a whole number in
    /// 1..=8`, `a number in [0, 2]`, `a number in [L/16000, L/50) m`, `null
    /// or ...` for a parameter that may be null.
    pub fn expected(&self) -> String {
        let unit = self.unit_suffix();
        let values = match self.range {
            Range::Integers(lo, hi) => format!("a whole number in {lo}..={hi}"),
            Range::Interval(lo, hi) => format!("a number in {}{unit}", interval_text(lo, hi, number)),
            Range::LengthOver(lo, hi) => format!("a number in {}{unit}", interval_text(lo, hi, length_over)),
            Range::Components(lo, hi) => format!(
                "three numbers [x, y, z], each in [{}, {}]{unit}",
                number(lo),
                number(hi)
            ),
            _ => return self.range_text(),
        };
        match self.null {
            Some(_) => format!("null or {values}"),
            None => values,
        }
    }

    /// The whole entry in one text, for the CLI's help and the OpenAPI
    /// schema's description: doc, range with unit, null, default and the
    /// paper's value.
    pub fn description(&self) -> String {
        let mut text = format!("{} Range: {}{}.", self.doc, self.range_text(), self.unit_suffix());
        if let Some(null) = self.null {
            text.push_str(&format!(" null: {null}."));
        }
        text.push_str(&format!(" Default: {}.", self.default));
        if !self.paper.is_empty() {
            text.push_str(&format!(" Paper: {}.", self.paper));
        }
        text
    }

    /// Why `params` break this parameter's range, if they do.
    pub(super) fn check(&self, params: &CaseParams) -> Option<FieldError> {
        let unit = self.unit_suffix();
        let reason = match ((self.value)(params)?, self.range) {
            (Value::Integer(v), Range::Integers(lo, hi)) => {
                (!(lo..=hi).contains(&v)).then(|| format!("must be a whole number in {lo}..={hi}, got {v}"))
            }
            (Value::Number(v), Range::Interval(lo, hi)) => (!within(v, lo, hi))
                .then(|| format!("must be in {}{unit}, got {v}", interval_text(lo, hi, number))),
            (Value::Number(v), Range::LengthOver(lo, hi)) => {
                let (a, b) = (of_length(lo, params.length), of_length(hi, params.length));
                (!within(v, a, b)).then(|| {
                    format!(
                        "must be in {} = {}{unit}, got {v}",
                        interval_text(lo, hi, length_over),
                        interval_text(a, b, |x| format!("{x}"))
                    )
                })
            }
            (Value::Vector(v), Range::Components(lo, hi)) => {
                (!v.iter().all(|&c| within(c, Bound::Closed(lo), Bound::Closed(hi)))).then(|| {
                    format!(
                        "each component must be in [{}, {}]{unit}, got [{}, {}, {}]",
                        number(lo),
                        number(hi),
                        v[0],
                        v[1],
                        v[2]
                    )
                })
            }
            (value, range) => unreachable!("{}: a {value:?} cannot be checked against {range:?}", self.name),
        }?;
        Some(FieldError {
            field: self.name.to_string(),
            reason,
        })
    }

    fn unit_suffix(&self) -> String {
        let numeric = matches!(
            self.range,
            Range::Interval(..) | Range::LengthOver(..) | Range::Components(..)
        );
        if numeric && !self.unit.is_empty() {
            format!(" {}", self.unit)
        } else {
            String::new()
        }
    }
}

/// `v` finite and between the bounds.
fn within(v: f64, lo: Bound, hi: Bound) -> bool {
    v.is_finite()
        && match lo {
            Bound::Closed(x) => v >= x,
            Bound::Open(x) => v > x,
        }
        && match hi {
            Bound::Closed(x) => v <= x,
            Bound::Open(x) => v < x,
        }
}

/// L over the bound's divisor.
fn of_length(bound: Bound, length: f64) -> Bound {
    match bound {
        Bound::Closed(d) => Bound::Closed(length / d),
        Bound::Open(d) => Bound::Open(length / d),
    }
}

/// `[lo, hi)` and the like, each end written by `write`; `> lo` when there
/// is no upper end.
fn interval_text(lo: Bound, hi: Bound, write: impl Fn(f64) -> String) -> String {
    match (lo, hi) {
        (Bound::Open(x), Bound::Open(y)) if y == f64::INFINITY => format!("> {}", write(x)),
        _ => {
            let (open, x) = match lo {
                Bound::Closed(x) => ('[', x),
                Bound::Open(x) => ('(', x),
            };
            let (close, y) = match hi {
                Bound::Closed(y) => (']', y),
                Bound::Open(y) => (')', y),
            };
            format!("{open}{}, {}{close}", write(x), write(y))
        }
    }
}

/// A number as the table writes it: powers of ten from 1e3 up and from 1e-2
/// down as `1eN`, others in full.
fn number(x: f64) -> String {
    let exponent = x.abs().log10().round() as i32;
    let power = format!("1e{exponent}").parse::<f64>().is_ok_and(|p| p == x.abs());
    if x != 0.0 && power && !(-1..=2).contains(&exponent) {
        format!("{}1e{exponent}", if x < 0.0 { "-" } else { "" })
    } else {
        format!("{x}")
    }
}

/// A bound of [`Range::LengthOver`]: `0`, `L` or `L/d`.
fn length_over(divisor: f64) -> String {
    if divisor == f64::INFINITY {
        "0".to_string()
    } else if divisor == 1.0 {
        "L".to_string()
    } else {
        format!("L/{divisor}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_as_the_table_writes_them() {
        let written: Vec<String> = [1e3, 1e12, -1e3, 1e-2, 1e-12, 100.0, 0.5, 0.05, 0.0, 2.0, 1.0]
            .into_iter()
            .map(number)
            .collect();
        assert_eq!(
            written,
            [
                "1e3", "1e12", "-1e3", "1e-2", "1e-12", "100", "0.5", "0.05", "0", "2", "1"
            ]
        );
    }

    #[test]
    fn intervals_read_as_ranges() {
        let text = |lo, hi| interval_text(lo, hi, length_over);
        assert_eq!(text(Bound::Closed(16000.0), Bound::Open(50.0)), "[L/16000, L/50)");
        assert_eq!(text(Bound::Open(f64::INFINITY), Bound::Closed(1.0)), "(0, L]");
        assert_eq!(
            interval_text(Bound::Open(0.0), Bound::Open(f64::INFINITY), number),
            "> 0"
        );
    }
}
