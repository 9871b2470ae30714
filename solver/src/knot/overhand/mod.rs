//! Overhand-knot builder: the initial centreline of an overhand knot with `n`
//! passes (paper Sec. 2 and 4), resampled to `K` nodes with equal edges.
//!
//! The shape is that of [`geometry`]: braid arc with a double helix,
//! loop closing the ring, two tails bent onto the pulling axis `x`. Given the
//! rod length `L`, the strand length `l_b` of each braid pass and the loop
//! length `l_l`, each tail has length `l_t = (L - 2 l_b - l_l) / 2`; the
//! requested clamp-to-clamp distance `l_c` then fixes how much the braid arc
//! turns (a straight braid and straight tails give the largest `l_c`), and the
//! loop shape closes the ring. The helix radius is `a = (1 + gap) h`, with the
//! gap raised in steps until every pair of non-neighbouring segments (index
//! gap `> ceil(2h / edge) + 1`) is at least `2h` apart.
mod geometry;

use super::alexander::Alexander;
use super::polyline::{check_clearance, equal_chords};
use super::twist::paper_twist;
use super::{Family, KnotError, StartShape, check_knot};
use geometry::{Braid, Dense, Plan, loop_drift, sinc};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::ops::Range;

/// Largest number of passes.
pub const MAX_PASSES: u32 = 8;
/// The radius must satisfy `h < L * MAX_RADIUS_RATIO`.
pub const MAX_RADIUS_RATIO: f64 = 1.0 / 50.0;
/// Edges may be at most this many radii long.
pub const MAX_EDGE_RADII: f64 = 4.0;
/// Each braid pass (half twist) needs at least this many edges.
pub const MIN_EDGES_PER_PASS: f64 = 4.0;
/// The helix pitch per radian is at least this many helix radii.
pub const MIN_PITCH: f64 = 1.0;
/// Bend radii of loop and tails are at least this many helix radii.
pub const MIN_BEND: f64 = 3.0;
/// The default braid is at least this factor above the shortest one.
pub const BRAID_MARGIN: f64 = 1.1;
/// Gaps `(a - h) / h` tried in turn.
const GAPS: [f64; 4] = [0.1, 0.2, 0.35, 0.5];
/// Largest half turning angle of the braid arc.
const MAX_THETA: f64 = 0.75 * PI;
/// Largest `|alpha|` of the loop profile.
const MAX_ALPHA: f64 = 0.8;
/// Samples of the braid angle when bracketing the feasible end-to-end range.
const SCAN: usize = 48;
/// The reported end-to-end range is shrunk by this fraction of its width at
/// each end (the resampling excess moves its edges slightly).
const WINDOW_MARGIN: f64 = 2e-3;
/// The default end-to-end distance stays this fraction of the width inside.
const DEFAULT_MARGIN: f64 = 0.05;

/// The default knot's size in radii: its lengths are fractions of the knot
/// length `min(L, KNOT_RADII h)` (the paper's L/h), the tails taking the rest
/// of a longer rod, so that a slender rod's knot starts as tight, in l_k bar,
/// as the paper's.
pub const KNOT_RADII: f64 = 625.0;
/// Default strand length per braid pass, loop remainder and end-to-end
/// distance, as fractions of the knot length ([`KNOT_RADII`]), for
/// `n = 1..=8` (`n <= 4`: the relaxed knots of the paper at `h = 1.6 mm`;
/// beyond, extrapolated with the braid growing and the loop shrinking).
const DEFAULT_BRAID: [f64; 8] = [0.12, 0.19, 0.24, 0.28, 0.30, 0.315, 0.33, 0.345];
const DEFAULT_TAIL: [f64; 8] = [0.08, 0.075, 0.055, 0.05, 0.045, 0.04, 0.04, 0.035];
const DEFAULT_END_TO_END: [f64; 8] = [0.28, 0.30, 0.31, 0.32, 0.31, 0.30, 0.29, 0.28];

/// What to build. Lengths in metres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KnotSpec {
    /// Number of passes (unknotting number) `n`, `1..=8`.
    pub n: u32,
    /// Rod length `L` (rest length of the resampled polyline).
    pub length: f64,
    /// Node count `K`.
    pub nodes: usize,
    /// Cross-section radius `h`, below `L / 50`.
    pub radius: f64,
    /// Clamp-to-clamp distance `l_c`. Default: `[0.28, 0.30, 0.31, 0.32, 0.31,
    /// 0.30, 0.29, 0.28][n-1] L_k + L - L_k` with the knot length `L_k`
    /// ([`KNOT_RADII`]), moved into the feasible range if needed.
    #[serde(default)]
    pub clamp_span: Option<f64>,
    /// Strand length of each braid pass `l_b`. Default: `[0.12, 0.19, 0.24,
    /// 0.28, 0.30, 0.315, 0.33, 0.345][n-1] L_k`, but at least
    /// [`BRAID_MARGIN`] times the shortest braid for radius `h`.
    #[serde(default)]
    pub pass_length: Option<f64>,
    /// Loop length `l_l`. Default: `L_k - 2 l_b - 2 t L_k` with the tail fraction
    /// `t = [0.08, 0.075, 0.055, 0.05, 0.045, 0.04, 0.04, 0.035][n-1]`.
    #[serde(default)]
    pub loop_length: Option<f64>,
}

impl KnotSpec {
    /// The knot length `L_k = min(L, KNOT_RADII h)` the default lengths are
    /// fractions of ([`KNOT_RADII`]).
    pub fn knot_length(&self) -> f64 {
        let scaled = KNOT_RADII * self.radius;
        // The paper's rod (L = 625 h up to rounding) keeps L itself.
        if scaled < self.length * (1.0 - 1e-9) {
            scaled
        } else {
            self.length
        }
    }

    /// The paper's setting: `L = 1 m`, `K = 301`, `h = 1.6 mm`, default shape.
    pub fn paper(n: u32) -> Self {
        Self {
            n,
            length: 1.0,
            nodes: 301,
            radius: 1.6e-3,
            clamp_span: None,
            pass_length: None,
            loop_length: None,
        }
    }
}

/// Node index ranges of the parts of the knot, in rod order; they partition
/// `0..K`. A node belongs to the part containing its arc-length position on
/// the designed curve.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Regions {
    /// From clamp A to the braid.
    pub tail_a: Range<usize>,
    /// First pass through the braid (strand A).
    pub braid_a: Range<usize>,
    /// The loop.
    pub loop_arc: Range<usize>,
    /// Second pass through the braid (strand B).
    pub braid_b: Range<usize>,
    /// From the braid to clamp B.
    pub tail_b: Range<usize>,
}

/// A built knot. Nodes 0, 1 and K-2, K-1 lie on the x axis (the pulling axis)
/// with `x_0 < x_1` and `x_{K-2} < x_{K-1}`; all `K - 1` edges have length
/// `L / (K - 1)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KnotShape {
    /// Node positions.
    pub points: Vec<Vector3<f64>>,
    /// Parts of the knot.
    pub regions: Regions,
    /// Edge length `L / (K - 1)`.
    pub edge_length: f64,
    /// Clamp-to-clamp distance `x_{K-1} - x_0`.
    pub clamp_span: f64,
    /// Mean strand length of one braid pass (designed curve).
    pub pass_length: f64,
    /// Loop length (designed curve).
    pub loop_length: f64,
    /// Length of each tail (designed curve).
    pub tail_length: f64,
    /// Helix radius `a` of the braid strands about the braid centreline.
    pub helix_radius: f64,
}

impl Family for KnotSpec {
    /// The `(2, 2n + 1)` torus knot's: the overhand knot closes to it.
    fn alexander(&self) -> Alexander {
        Alexander::torus_2(2 * self.n + 1)
    }

    fn tie(&self) -> Result<StartShape, KnotError> {
        build(self).map(|shape| {
            let middle = (shape.regions.loop_arc.start + shape.regions.loop_arc.end) / 2;
            StartShape::one_rod(shape.points, middle, self.alexander())
        })
    }

    fn twist(&self, writhe: f64) -> f64 {
        paper_twist(self.n, writhe)
    }
}

/// Builds the knot described by `spec`.
pub fn build(spec: &KnotSpec) -> Result<KnotShape, KnotError> {
    validate(spec)?;
    let lengths = lengths(spec)?;
    let mut clearance = None;
    for gap in GAPS {
        match attempt(spec, &lengths, gap) {
            Err(e @ KnotError::Clearance { .. }) => clearance = Some(e),
            // A larger gap may make the shape infeasible; report the clearance.
            Err(e) => return Err(clearance.unwrap_or(e)),
            Ok(shape) => return Ok(shape),
        }
    }
    Err(clearance.expect("every gap failed the clearance"))
}

fn validate(spec: &KnotSpec) -> Result<(), KnotError> {
    if !(1..=MAX_PASSES).contains(&spec.n) {
        return Err(KnotError::Passes(spec.n));
    }
    let optional = [
        ("clamp_span", spec.clamp_span),
        ("pass_length", spec.pass_length),
        ("loop_length", spec.loop_length),
    ];
    let given = optional.into_iter().filter_map(|(name, v)| v.map(|v| (name, v)));
    for (name, value) in [("length", spec.length), ("radius", spec.radius)]
        .into_iter()
        .chain(given)
    {
        if !(value.is_finite() && value > 0.0) {
            return Err(KnotError::InvalidParameter { name, value });
        }
    }
    let max = spec.length * MAX_RADIUS_RATIO;
    if spec.radius >= max {
        return Err(KnotError::RadiusTooLarge {
            radius: spec.radius,
            max,
        });
    }
    Ok(())
}

/// Lengths and constraints of one attempt (fixed helix radius).
struct Design {
    braid: Braid,
    strands: StrandTable,
    strand_length: f64,
    straight_centreline: f64,
    loop_length: f64,
    loop_steps: usize,
    edge: f64,
    spacing: f64,
    /// The length each tail has beyond the knot's: `(L - L_k) / 2`.
    extra_tail: f64,
}

/// Precomputed Simpson samples of `cos psi` and `(a dpsi/du)^2` for strand lengths.
struct StrandTable {
    weights: Vec<f64>,
    cos_psi: Vec<f64>,
    twist: Vec<f64>,
}

impl StrandTable {
    fn new(braid: &Braid) -> Self {
        let m = 1024;
        let (mut weights, mut cos_psi, mut twist) = (vec![], vec![], vec![]);
        for i in 0..=m {
            let w = if i == 0 || i == m { 1.0 } else { [2.0, 4.0][i % 2] };
            let (psi, dpsi) = braid.phase(i as f64 / m as f64);
            weights.push(w / (3.0 * m as f64));
            cos_psi.push(psi.cos());
            twist.push((braid.radius * dpsi).powi(2));
        }
        Self {
            weights,
            cos_psi,
            twist,
        }
    }
}

impl Design {
    /// Helix radius `(1 + gap) h`, lengths still unset.
    fn new(spec: &KnotSpec, gap: f64) -> Self {
        let braid = Braid {
            passes: spec.n,
            radius: (1.0 + gap) * spec.radius,
        };
        let edge = spec.length / (spec.nodes.max(2) - 1) as f64;
        Self {
            braid,
            strands: StrandTable::new(&braid),
            strand_length: 0.0,
            straight_centreline: 0.0,
            loop_length: 0.0,
            loop_steps: 0,
            edge,
            spacing: edge.min(braid.radius) / 4.0,
            extra_tail: 0.5 * (spec.length - spec.knot_length()),
        }
    }

    /// Mean strand length over a braid of centreline `b` and half angle
    /// `theta`, with its derivative in `b`.
    fn strand(&self, b: f64, theta: f64) -> (f64, f64) {
        let side = 2.0 * self.braid.radius * theta;
        let t = &self.strands;
        let mut acc = (0.0, 0.0);
        for ((w, c), tw) in t.weights.iter().zip(&t.cos_psi).zip(&t.twist) {
            for along in [b + side * c, b - side * c] {
                let speed = (along * along + tw).sqrt();
                acc.0 += 0.5 * w * speed;
                acc.1 += 0.5 * w * along / speed;
            }
        }
        acc
    }

    /// Sets the strand and loop lengths.
    fn set_lengths(&mut self, strand: f64, loop_length: f64) {
        self.strand_length = strand;
        self.straight_centreline = self.newton(strand, 0.0);
        self.loop_length = loop_length;
        self.loop_steps = (loop_length / self.spacing).ceil() as usize;
    }

    /// Braid centreline giving the strand length at half angle `theta`
    /// (it differs from the straight braid's only at second order in `theta`).
    fn centreline(&self, theta: f64) -> f64 {
        self.newton(self.straight_centreline, theta)
    }

    /// Newton iteration for the centreline, from `b`.
    fn newton(&self, mut b: f64, theta: f64) -> f64 {
        for _ in 0..30 {
            let (len, dlen) = self.strand(b, theta);
            let step = (len - self.strand_length) / dlen;
            b -= step;
            if step.abs() <= 1e-15 * b {
                break;
            }
        }
        b
    }

    /// The straight end of a tail, on the pull axis at its clamp: a quarter
    /// of the knot's tail (at least 2.5 edges) and the length a rod longer
    /// than its knot adds to each tail ([`KnotSpec::knot_length`]).
    fn clamp_section(&self, tail: f64) -> f64 {
        (2.5 * self.edge).max(0.25 * (tail - self.extra_tail)) + self.extra_tail
    }

    /// Half clamp-to-clamp distance at braid half angle `theta`.
    fn half_span(&self, tail: f64, theta: f64) -> f64 {
        let clamp = self.clamp_section(tail);
        0.5 * self.centreline(theta) * sinc(theta) + (tail - clamp) * sinc(theta) + clamp
    }

    /// The largest `|alpha|` keeping the loop's bend radius at `MIN_BEND a`.
    fn alpha_bound(&self, theta: f64) -> f64 {
        let mean_radius = self.loop_length / (2.0 * PI - 2.0 * theta);
        (mean_radius / (MIN_BEND * self.braid.radius) - 1.0).min(MAX_ALPHA)
    }

    /// The loop-shape bound and closure target at `theta`, if the loop can close.
    fn loop_closure(&self, theta: f64, b: f64) -> Option<(f64, f64)> {
        let bound = self.alpha_bound(theta);
        let target = -b * sinc(theta) / self.loop_length;
        let drift = |alpha| loop_drift(theta, alpha, self.loop_steps);
        (bound >= 0.0 && drift(-bound) <= target && drift(bound) >= target).then_some((bound, target))
    }

    /// The plan at `theta` with the loop still unsolved (`alpha = 0`), if
    /// all constraints can hold.
    fn candidate(&self, tail: f64, theta: f64) -> Option<(Plan, f64, f64)> {
        let b = self.centreline(theta);
        let (bound, target) = self.loop_closure(theta, b)?;
        let plan = Plan {
            braid: self.braid,
            theta,
            centreline: b,
            loop_length: self.loop_length,
            alpha: 0.0,
            loop_steps: self.loop_steps,
            tail_length: tail,
            clamp_section: self.clamp_section(tail),
        };
        let a = self.braid.radius;
        let tails_ok = plan.tail_radius() >= MIN_BEND * a && plan.tail_min_x() >= 2.0 * a;
        tails_ok.then_some((plan, bound, target))
    }

    /// The plan at `theta`, its loop closed, if all constraints hold.
    fn plan(&self, tail: f64, theta: f64) -> Option<Plan> {
        let (mut plan, bound, target) = self.candidate(tail, theta)?;
        let closure = |alpha| loop_drift(theta, alpha, self.loop_steps) - target;
        plan.alpha = increasing_root(closure, -bound, bound, 1e-15);
        Some(plan)
    }

    /// Range of feasible braid half angles `[lo, hi]`.
    fn feasible_angles(&self, tail: f64) -> Option<(f64, f64)> {
        let ok = |theta| self.candidate(tail, theta).is_some();
        let grid: Vec<f64> = (0..=SCAN).map(|k| MAX_THETA * k as f64 / SCAN as f64).collect();
        let first = grid.iter().position(|&t| ok(t))?;
        let last = grid.iter().rposition(|&t| ok(t))?;
        // Refine each end between its feasible sample and the infeasible neighbour.
        let refine = |mut good: f64, mut bad: f64| {
            for _ in 0..20 {
                let mid = 0.5 * (good + bad);
                if ok(mid) { good = mid } else { bad = mid }
            }
            good
        };
        let lo = if first == 0 {
            0.0
        } else {
            refine(grid[first], grid[first - 1])
        };
        let hi = if last == SCAN {
            MAX_THETA
        } else {
            refine(grid[last], grid[last + 1])
        };
        Some((lo, hi))
    }

    /// Braid half angle giving the half span (decreasing in `theta`), if
    /// some angle in `[0, MAX_THETA]` does.
    fn angle_for(&self, tail: f64, half_span: f64) -> Option<f64> {
        let excess = |theta| half_span - self.half_span(tail, theta);
        let theta = increasing_root(excess, 0.0, MAX_THETA, 1e-15 * half_span);
        (excess(theta).abs() <= 1e-12 * half_span).then_some(theta)
    }
}

/// Strand length per braid pass, loop length and tail length, resolved from
/// the spec and checked with the smallest helix radius.
#[derive(Clone, Copy)]
struct Lengths {
    strand: f64,
    loop_length: f64,
    tail: f64,
}

fn lengths(spec: &KnotSpec) -> Result<Lengths, KnotError> {
    let (length, h) = (spec.length, spec.radius);
    let index = spec.n as usize - 1;
    let design = Design::new(spec, GAPS[0]);
    let shortest = design.strand(design.braid.min_centreline(MIN_PITCH), 0.0).0;
    let knot = spec.knot_length();
    let strand = spec
        .pass_length
        .unwrap_or((DEFAULT_BRAID[index] * knot).max(BRAID_MARGIN * shortest));
    if strand < shortest {
        return Err(KnotError::BraidTooShort {
            pass_length: strand,
            min: shortest,
        });
    }
    let max_edge = (MAX_EDGE_RADII * h).min(strand / (MIN_EDGES_PER_PASS * design.braid.half_twists()));
    if design.edge > max_edge {
        return Err(KnotError::TooFewNodes {
            nodes: spec.nodes,
            min: ((length / max_edge).ceil() as usize).saturating_add(1),
        });
    }
    let loop_length = spec
        .loop_length
        .unwrap_or(knot - 2.0 * strand - 2.0 * DEFAULT_TAIL[index] * knot);
    let tail = 0.5 * (length - 2.0 * strand - loop_length);
    let min_tail = 3.0 * design.edge;
    if tail < min_tail {
        return Err(KnotError::TailsTooShort {
            tail_length: tail,
            min: min_tail,
        });
    }
    Ok(Lengths {
        strand,
        loop_length,
        tail,
    })
}

/// Root of an increasing `f` with `f(lo) <= 0 <= f(hi)`, to `|f| <= tol` or
/// an interval at rounding level (regula falsi, Illinois variant).
fn increasing_root(mut f: impl FnMut(f64) -> f64, mut lo: f64, mut hi: f64, tol: f64) -> f64 {
    let (mut f_lo, mut f_hi) = (f(lo), f(hi));
    if f_lo >= 0.0 {
        return lo;
    }
    if f_hi <= 0.0 {
        return hi;
    }
    let mut last_side = 0;
    for _ in 0..200 {
        let secant = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        let x = if secant > lo && secant < hi {
            secant
        } else {
            0.5 * (lo + hi)
        };
        if x <= lo || x >= hi {
            return x;
        }
        let fx = f(x);
        if fx.abs() <= tol {
            return x;
        }
        if fx < 0.0 {
            (lo, f_lo) = (x, fx);
            if last_side < 0 {
                f_hi *= 0.5;
            }
            last_side = -1;
        } else {
            (hi, f_hi) = (x, fx);
            if last_side > 0 {
                f_lo *= 0.5;
            }
            last_side = 1;
        }
    }
    0.5 * (lo + hi)
}

/// Feasible clamp-to-clamp distances `[min, max]`.
struct Window {
    min: f64,
    max: f64,
}

impl Window {
    /// `fraction * L_k + L - L_k` (the knot length `L_k` and the rod's
    /// `L`, [`KnotSpec::knot_length`]), moved `DEFAULT_MARGIN` of the width
    /// inside the window.
    fn default(&self, fraction: f64, spec: &KnotSpec) -> f64 {
        let margin = DEFAULT_MARGIN * (self.max - self.min);
        let knot = spec.knot_length();
        (fraction * knot + (spec.length - knot)).clamp(self.min + margin, self.max - margin)
    }

    /// The range reported to users: shrunk by `WINDOW_MARGIN` of the width,
    /// since the window moves slightly with the end-to-end distance (through
    /// the resampling excess).
    fn reported(&self) -> (f64, f64) {
        let margin = WINDOW_MARGIN * (self.max - self.min);
        (self.min + margin, self.max - margin)
    }
}

/// A resampled knot: its plan, dense curve, nodes and their arc positions on
/// the dense curve.
struct Resampled {
    plan: Plan,
    dense: Dense,
    points: Vec<Vector3<f64>>,
    positions: Vec<f64>,
}

impl Design {
    fn infeasible(&self, tail: f64) -> KnotError {
        KnotError::Infeasible {
            pass_length: self.strand_length,
            loop_length: self.loop_length,
            tail_length: tail,
        }
    }

    /// The end-to-end window for tails of length `tail`.
    fn window(&self, tail: f64) -> Result<Window, KnotError> {
        let (lo, hi) = self.feasible_angles(tail).ok_or_else(|| self.infeasible(tail))?;
        Ok(Window {
            min: 2.0 * self.half_span(tail, hi),
            max: 2.0 * self.half_span(tail, lo),
        })
    }

    /// Resamples the knot with clamp-to-clamp distance `clamp_span` to
    /// `nodes` equal chords. These consume slightly more than `L` of curve,
    /// so the designed curve (initially `curve` long) is lengthened, in the
    /// tails, by that excess until the last node lands on clamp B. Returns
    /// the knot and the converged curve length, or `None` if some iterate
    /// has no feasible shape.
    fn resample(&self, clamp_span: f64, mut curve: f64, nodes: usize) -> Option<(Resampled, f64)> {
        // Beyond clamp B, more than the excess (a few per mille of L).
        let extension = 4.0 * self.edge + 0.02 * curve;
        let mut result = None;
        for _ in 0..8 {
            let tail = 0.5 * (curve - 2.0 * self.strand_length - self.loop_length);
            let theta = self.angle_for(tail, 0.5 * clamp_span)?;
            let plan = self.plan(tail, theta)?;
            let dense = plan.dense(self.spacing, extension);
            let (points, positions) = equal_chords(&dense.points, &dense.arc, self.edge, nodes)?;
            let excess = positions[positions.len() - 1] - dense.arc[dense.marks[4]];
            curve += excess;
            result = Some(Resampled {
                plan,
                dense,
                points,
                positions,
            });
            if excess.abs() <= 1e-13 * curve {
                break;
            }
        }
        result.map(|r| (r, curve))
    }
}

fn attempt(spec: &KnotSpec, lengths: &Lengths, gap: f64) -> Result<KnotShape, KnotError> {
    let (n, length, h) = (spec.n, spec.length, spec.radius);
    let fraction = DEFAULT_END_TO_END[n as usize - 1];
    let Lengths {
        strand,
        loop_length,
        tail,
    } = *lengths;
    let mut design = Design::new(spec, gap);
    design.set_lengths(strand, loop_length);

    // A provisional knot gives the resampling excess; the window is then
    // computed for the tails lengthened by it.
    let window = design.window(tail)?;
    let provisional = spec.clamp_span.map_or_else(
        || window.default(fraction, spec),
        |l| l.clamp(window.min, window.max),
    );
    let (_, curve) = design
        .resample(provisional, length, spec.nodes)
        .ok_or_else(|| design.infeasible(tail))?;
    let window = design.window(0.5 * (curve - 2.0 * strand - loop_length))?;
    let (min, max) = window.reported();
    let out_of_range = |clamp_span| KnotError::EndToEndOutOfRange { clamp_span, min, max };
    let clamp_span = match spec.clamp_span {
        Some(l) if l < window.min || l > window.max => return Err(out_of_range(l)),
        Some(l) => l,
        None => window.default(fraction, spec),
    };
    let (knot, _) = design
        .resample(clamp_span, curve, spec.nodes)
        .ok_or_else(|| out_of_range(clamp_span))?;

    let Resampled {
        plan,
        dense,
        points,
        positions,
    } = knot;
    let cut = |mark: usize| positions.partition_point(|&s| s < dense.arc[dense.marks[mark]]);
    let [a, b, c, d] = [0, 1, 2, 3].map(cut);
    let regions = Regions {
        tail_a: 0..a,
        braid_a: a..b,
        loop_arc: b..c,
        braid_b: c..d,
        tail_b: d..points.len(),
    };
    check_clearance(&points, h, design.edge)?;
    check_knot(&points, &spec.alexander())?;
    Ok(KnotShape {
        clamp_span: points[points.len() - 1].x - points[0].x,
        points,
        regions,
        edge_length: design.edge,
        pass_length: strand,
        loop_length,
        tail_length: plan.tail_length,
        helix_radius: design.braid.radius,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn increasing_root_converges_and_clamps() {
        let x = increasing_root(|x| x * x * x - 2.0, 0.0, 2.0, 1e-15);
        assert!((x - 2f64.cbrt()).abs() < 1e-14);
        assert_eq!(increasing_root(|x| x + 1.0, 0.0, 1.0, 1e-15), 0.0);
        assert_eq!(increasing_root(|x| x - 5.0, 0.0, 1.0, 1e-15), 1.0);
    }
}
