//! Measurements of paper eq. (11) and Sec. 4.1, and detection of the inversion.
//!
//! Definitions used here (the paper's Fig. 4 in words):
//! - l_c: distance between the two outermost (clamped) nodes; l_k = L - l_c,
//!   l_k bar = l_k / h.
//! - The knot's own length, l_k arc bar = (s - l_c) / h with s the arc length
//!   of the deformed rod between the clamps: eq. 11's l_k bar less the rod's
//!   elastic elongation. Straight tails add as much to s as to l_c, so that
//!   it measures the knot alone, whatever the tails' length and stretch (a
//!   rubber tail stretches by F bar / 4: 1.25 % at F bar 0.05, 17 radii over
//!   a tail of 1 375 radii).
//! - F: traction force, the clamps' reactions along the pulling axis (mean of
//!   the two ends); F bar = F h^2 / EI with EI = (pi/4) E h^4.
//! - Braid ends: the braid is where the part of the rod before the loop's middle
//!   node m touches the part after it (m starts at the middle of the builder's
//!   loop and follows the loop). Of the self-contacts (i, j) of segments
//!   i < m <= j, the first
//!   strand's braid is the longest run of consecutive i (gaps of at most
//!   `RUN_GAP` segments) and the second strand's the longest run of j. The loop
//!   runs from node P (just after the first run) to node Q (start of the
//!   second run). A loop that falls onto the braid after the inversion touches
//!   it outside these runs and does not move the braid ends.
//! - W = |x_Q - x_P|, the distance between the two ends of the braid region.
//! - H: along the loop's symmetric division (the plane bisecting the chord PQ),
//!   the distance from the chord to the farthest point where the loop crosses
//!   that plane; H bar = H / W.
//! - The braid's shape in the terms of the simplified model (Sec. 5, eq. 12):
//!   its axis is the principal direction of the nodes of both strands' runs,
//!   l_b their extent along it (the braid's axial length), l_l the arc length of
//!   the loop from P to Q, epsilon = l_b / l_l, and phi the angle between the
//!   axis and the loop's end tangents (edges P P+1 and Q-1 Q; mean of the two,
//!   in [0, pi/2]). The paper fixes epsilon = 0.7 and phi = pi/3 "at inversion".
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use std::fmt::Write;

/// One sample of the tightening series. Its JSON names are the paper's
/// symbols, as in the CSV ([`COLUMNS`]); the aliases read series stored
/// before they were.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Simulated time since the pull started (s).
    pub time: f64,
    pub l_k_bar: f64,
    /// The knot's own length (s - l_c) / h (module documentation; 0 in
    /// series stored before it was measured).
    #[serde(default)]
    pub l_k_arc_bar: f64,
    #[serde(rename = "l_c_over_L", alias = "l_c_over_l")]
    pub l_c_over_l: f64,
    /// Traction force F (N) and F bar.
    #[serde(rename = "F", alias = "force")]
    pub force: f64,
    #[serde(rename = "F_bar", alias = "f_bar")]
    pub f_bar: f64,
    /// Loop width W and height H (m), H bar = H / W (0 when no braid is found).
    #[serde(rename = "W", alias = "width")]
    pub width: f64,
    #[serde(rename = "H", alias = "height")]
    pub height: f64,
    #[serde(rename = "H_bar", alias = "h_bar")]
    pub h_bar: f64,
    /// Largest kinetic energy (J) over the steps since the previous sample, so
    /// that a snap shorter than the sampling interval is not missed.
    pub kinetic_energy: f64,
    /// Contacts within the detection margin and those carrying load.
    pub contacts: usize,
    pub active_contacts: usize,
    /// Largest penetration over h (dimensionless; the CSV column of the same name).
    pub max_penetration_over_h: f64,
    /// Braid shape at the sample (module documentation; 0 when no braid is found):
    /// epsilon = l_b / l_l and the loop's end tilt phi (rad).
    pub epsilon: f64,
    pub phi: f64,
    /// Newton iterations of the step that produced the sample.
    pub newton_iterations: u32,
    /// Time step (s) of the step that produced the sample.
    pub dt: f64,
    /// The elastic energies of eq. (6) over EI / h (eq. 12's unit): stretching,
    /// bending and twisting.
    #[serde(rename = "E_stretch_bar", default)]
    pub e_stretch_bar: f64,
    #[serde(rename = "E_bend_bar", default)]
    pub e_bend_bar: f64,
    #[serde(rename = "E_twist_bar", default)]
    pub e_twist_bar: f64,
    /// The elastic energy over EI / h of the braid's two strands, from each
    /// run's first contact to the loop's ends P and Q, and of the loop
    /// strictly between P and Q (by node, `energies::within`; 0 when no braid
    /// is found).
    #[serde(rename = "E_braid_bar", default)]
    pub e_braid_bar: f64,
    #[serde(rename = "E_loop_bar", default)]
    pub e_loop_bar: f64,
    /// The linking number Lk = Tw + Wr of the centre line closed along the
    /// pull axis (turns).
    #[serde(rename = "Lk", default)]
    pub lk: f64,
    /// How far the clamps have turned against each other (turns), and the
    /// torque they apply about the pull axis over EI / h.
    #[serde(default)]
    pub end_turns: f64,
    #[serde(rename = "M_bar", default)]
    pub m_bar: f64,
    /// Index of the loading program's stage the sample was taken in.
    #[serde(default)]
    pub stage: usize,
}

impl Sample {
    /// How much further (radii) the knot's own length fell than eq. 11's
    /// l_k bar (the clamps' travel) from this sample to `later`.
    pub fn knot_jump_to(&self, later: &Sample) -> f64 {
        (self.l_k_arc_bar - later.l_k_arc_bar) - (self.l_k_bar - later.l_k_bar)
    }

    /// The elastic energy over EI / h.
    pub fn elastic_bar(&self) -> f64 {
        self.e_stretch_bar + self.e_bend_bar + self.e_twist_bar
    }
}

/// A series column's values: real, or a count (written as an integer).
#[derive(Clone, Copy)]
pub enum Column {
    Real(fn(&Sample) -> f64),
    Count(fn(&Sample) -> u64),
}

/// The series' columns in order, by the names of the CSV header (and of
/// the Python binding's arrays), which are `Sample`'s JSON names: one per
/// field.
pub const COLUMNS: [(&str, Column); 26] = [
    ("time", Column::Real(|s| s.time)),
    ("l_k_bar", Column::Real(|s| s.l_k_bar)),
    ("l_k_arc_bar", Column::Real(|s| s.l_k_arc_bar)),
    ("l_c_over_L", Column::Real(|s| s.l_c_over_l)),
    ("F", Column::Real(|s| s.force)),
    ("F_bar", Column::Real(|s| s.f_bar)),
    ("W", Column::Real(|s| s.width)),
    ("H", Column::Real(|s| s.height)),
    ("H_bar", Column::Real(|s| s.h_bar)),
    ("kinetic_energy", Column::Real(|s| s.kinetic_energy)),
    ("contacts", Column::Count(|s| s.contacts as u64)),
    ("active_contacts", Column::Count(|s| s.active_contacts as u64)),
    (
        "max_penetration_over_h",
        Column::Real(|s| s.max_penetration_over_h),
    ),
    ("epsilon", Column::Real(|s| s.epsilon)),
    ("phi", Column::Real(|s| s.phi)),
    (
        "newton_iterations",
        Column::Count(|s| u64::from(s.newton_iterations)),
    ),
    ("dt", Column::Real(|s| s.dt)),
    ("E_stretch_bar", Column::Real(|s| s.e_stretch_bar)),
    ("E_bend_bar", Column::Real(|s| s.e_bend_bar)),
    ("E_twist_bar", Column::Real(|s| s.e_twist_bar)),
    ("E_braid_bar", Column::Real(|s| s.e_braid_bar)),
    ("E_loop_bar", Column::Real(|s| s.e_loop_bar)),
    ("Lk", Column::Real(|s| s.lk)),
    ("end_turns", Column::Real(|s| s.end_turns)),
    ("M_bar", Column::Real(|s| s.m_bar)),
    ("stage", Column::Count(|s| s.stage as u64)),
];

/// The series as CSV: a header of [`COLUMNS`]' names, one row per sample.
pub fn series_csv(series: &[Sample]) -> String {
    let names: Vec<&str> = COLUMNS.iter().map(|(name, _)| *name).collect();
    let mut out = names.join(",");
    out.push('\n');
    for s in series {
        for (i, (_, column)) in COLUMNS.iter().enumerate() {
            if i > 0 {
                out.push(',');
            }
            match column {
                Column::Real(value) => write!(out, "{}", value(s)),
                Column::Count(value) => write!(out, "{}", value(s)),
            }
            .expect("writing to a String");
        }
        out.push('\n');
    }
    out
}

/// The knot's own length l_k arc bar = (s - l_c) / h of the rod through
/// `points`, of radius `h` (module documentation).
pub fn l_k_arc_bar(points: &[Vector3<f64>], h: f64) -> f64 {
    let arc: f64 = points.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let chord = match points {
        [first, .., last] => (last - first).norm(),
        _ => 0.0,
    };
    (arc - chord) / h
}

/// The loop between the braid ends.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LoopGeometry {
    /// Node where the loop leaves the braid (P) and re-enters it (Q).
    pub start: usize,
    pub end: usize,
    pub width: f64,
    pub height: f64,
}

/// Largest gap (in segments) inside one run of braid contacts.
pub const RUN_GAP: usize = 3;

/// The braid's two strands: the runs of segments (first, last) of the rod
/// before and after the loop's middle node that touch each other.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Braid {
    pub first: (usize, usize),
    pub second: (usize, usize),
}

impl Braid {
    /// Loop ends (P, Q): the node after the first run and the second run's first node.
    pub fn loop_ends(&self) -> (usize, usize) {
        (self.first.1 + 1, self.second.0)
    }
}

/// The braid from the self-contact segment pairs (i, j), as defined in the
/// module documentation; `None` when no pair crosses the middle node `mid` or
/// the runs leave no loop between them.
pub fn braid(pairs: impl IntoIterator<Item = (usize, usize)>, mid: usize) -> Option<Braid> {
    let mut first = Vec::new();
    let mut second = Vec::new();
    for (i, j) in pairs {
        let (i, j) = if i < j { (i, j) } else { (j, i) };
        if i < mid && j >= mid {
            first.push(i);
            second.push(j);
        }
    }
    let first = longest_run(&mut first)?;
    let second = longest_run(&mut second)?;
    (first.1 + 1 < second.0).then_some(Braid { first, second })
}

/// The braid's shape in the simplified model's terms (module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BraidShape {
    /// Axial length of the braid and arc length of the loop (m).
    pub l_b: f64,
    pub l_l: f64,
    pub epsilon: f64,
    /// Tilt of the loop's end tangents from the braid axis (rad).
    pub phi: f64,
}

/// Shape of `braid` on the rod `points`.
pub fn braid_shape(points: &[Vector3<f64>], braid: &Braid) -> BraidShape {
    let strands = [braid.first, braid.second];
    let nodes = || strands.iter().flat_map(|&(a, b)| points[a..=b + 1].iter());
    let count = strands.iter().map(|(a, b)| b + 2 - a).sum::<usize>() as f64;
    let centre = nodes().sum::<Vector3<f64>>() / count;
    let covariance = nodes().fold(Matrix3::zeros(), |m, x| {
        m + (x - centre) * (x - centre).transpose()
    });
    let eigen = covariance.symmetric_eigen();
    let axis = eigen.eigenvectors.column(eigen.eigenvalues.imax()).into_owned();
    let (lo, hi) = nodes().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
        let s = (x - centre).dot(&axis);
        (lo.min(s), hi.max(s))
    });
    let (p, q) = braid.loop_ends();
    let l_l: f64 = (p..q).map(|k| (points[k + 1] - points[k]).norm()).sum();
    let tilt = |a: usize, b: usize| {
        (points[b] - points[a])
            .normalize()
            .dot(&axis)
            .abs()
            .min(1.0)
            .acos()
    };
    let l_b = hi - lo;
    BraidShape {
        l_b,
        l_l,
        epsilon: l_b / l_l,
        phi: 0.5 * (tilt(p, p + 1) + tilt(q - 1, q)),
    }
}

/// The longest run of values with gaps of at most `RUN_GAP` (first and last value).
fn longest_run(values: &mut [usize]) -> Option<(usize, usize)> {
    values.sort_unstable();
    let mut best: Option<(usize, usize)> = None;
    let mut start = *values.first()?;
    let mut prev = start;
    for &v in values.iter().skip(1).chain(std::iter::once(&usize::MAX)) {
        if v == usize::MAX || v > prev + RUN_GAP {
            if best.is_none_or(|(a, b)| prev - start > b - a) {
                best = Some((start, prev));
            }
            start = v;
        }
        prev = v;
    }
    best
}

/// W and H of the loop running along `points[start..=end]`.
pub fn loop_geometry(points: &[Vector3<f64>], start: usize, end: usize) -> LoopGeometry {
    let p = points[start];
    let q = points[end];
    let width = (q - p).norm();
    let mut height: f64 = 0.0;
    if width > 0.0 {
        let c = (q - p) / width;
        let m = (p + q) / 2.0;
        let along = |x: &Vector3<f64>| (x - m).dot(&c);
        for k in start..end {
            let (a, b) = (points[k], points[k + 1]);
            let (sa, sb) = (along(&a), along(&b));
            if (sa <= 0.0 && sb > 0.0) || (sa >= 0.0 && sb < 0.0) {
                let t = sa / (sa - sb);
                let x = a + (b - a) * t;
                let d = x - m;
                height = height.max((d - c * d.dot(&c)).norm());
            }
        }
    }
    LoopGeometry {
        start,
        end,
        width,
        height,
    }
}

/// The snap-through point (paper Fig. 5).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Inversion {
    /// l_k bar, the knot's own length and l_c / L of the last sample before
    /// H bar drops (as reported, where the snap began: [`snap_onset`]).
    pub l_k_bar: f64,
    #[serde(default)]
    pub l_k_arc_bar: f64,
    #[serde(rename = "l_c_over_L", alias = "l_c_over_l")]
    pub l_c_over_l: f64,
    /// F bar just before the drop and its minimum just after.
    #[serde(rename = "F_bar_before")]
    pub f_bar_before: f64,
    #[serde(rename = "F_bar_after")]
    pub f_bar_after: f64,
    /// H bar before and after the drop (aliases: the names stored before
    /// the paper's symbols were used).
    #[serde(rename = "H_bar_before", alias = "h_bar_before")]
    pub h_bar_before: f64,
    #[serde(rename = "H_bar_after", alias = "h_bar_after")]
    pub h_bar_after: f64,
    /// Peak kinetic energy around the drop over the median before it.
    pub kinetic_energy_ratio: f64,
    /// Index of the sample before the drop.
    pub sample: usize,
}

/// Detection thresholds.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct InversionCriteria {
    /// H bar must fall to at most this fraction of its value before the drop...
    pub drop_fraction: f64,
    /// ...within this many l_k bar.
    pub window: f64,
    /// Confirmation: the kinetic energy around the drop exceeds its median over
    /// the preceding samples by at least this factor...
    pub kinetic_energy_spike: f64,
    /// ...or a positive (pulling) F bar falls to at most this fraction of its
    /// value before the drop (the "rapid decrease" of F bar at the
    /// inversion, paper Fig. 5 a).
    pub force_drop: f64,
    /// H bar falling only to this fraction is a snap when both the kinetic
    /// energy and F bar confirm it and it falls no further below
    /// `drop_fraction` ([`detect_fall`]): n = 2 under the reference pull
    /// snaps with 93 times the kinetic energy and F bar 0.059 -> 0.042, its
    /// loop keeping 0.63 of its height.
    pub confirmed_drop_fraction: f64,
    /// Reading H bar, the knot's own length falling across the drop by more
    /// than this (radii) beyond the clamps' travel stands for F bar's fall in
    /// confirming a shallow fall: on a rod longer than its knot the tails'
    /// elastic stretch pours into the knot as it snaps, so that F bar falls
    /// by only the jump over the tails' compliance (rubber n = 2 at L/h 5000,
    /// mu = 0.05: own length 70.2 -> 62.9 within one sample, F bar 0.042 ->
    /// 0.038). On the paper's rod a jump this large releases a fifth of F
    /// bar at 0.06 (EA / EI = 4 / h^2 over L/h 625), which F bar's own fall
    /// confirms already.
    pub knot_jump: f64,
    /// A loop whose H bar stays below this within the window has no fall to
    /// read: it is flat, and its H bar is the contacts' noise (the paper's rod
    /// n = 6 once its loop has collapsed: about 0.03, under 0.04, over the
    /// samples after its inversion, `knotsweep run --n 6`; what older
    /// revisions read as inversions there is in CHANGELOG.md, physics revision
    /// 21). The loops that snap stand higher: over the 133 runs of
    /// BENCHMARKS.md's map (physics revision 21), H bar within the window
    /// before the inversion peaks at 0.141 or more (n = 6, the lowest loops).
    pub flat_loop: f64,
}

impl Default for InversionCriteria {
    fn default() -> Self {
        Self {
            drop_fraction: 0.6,
            window: 10.0,
            kinetic_energy_spike: 5.0,
            force_drop: 0.8,
            confirmed_drop_fraction: 0.75,
            knot_jump: 2.0,
            flat_loop: 0.1,
        }
    }
}

/// What a snap is read on ([`detect_fall`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reading {
    /// H bar, the overhand knot's loop (paper Fig. 5): a sample without a
    /// loop (width 0) does not drop, and F bar's own fall confirms a drop as
    /// the kinetic energy does.
    LoopHeight,
    /// F bar: only the kinetic energy confirms its fall (the force's fall is
    /// the drop itself); the found snap's H bar before and after are 0.
    Force,
}

impl Reading {
    /// The value that drops.
    fn level(self, s: &Sample) -> f64 {
        match self {
            Reading::LoopHeight => s.h_bar,
            Reading::Force => s.f_bar,
        }
    }

    /// Whether sample `s` may be a drop.
    fn may_drop(self, s: &Sample) -> bool {
        self == Reading::Force || s.width > 0.0
    }
}

/// The first sudden drop of H bar that the kinetic energy confirms, and the
/// force drop around it (paper Fig. 5): [`detect_fall`] read on H bar.
pub fn detect_inversion(series: &[Sample], criteria: &InversionCriteria) -> Option<Inversion> {
    detect_fall(series, criteria, Reading::LoopHeight, 0)
}

/// The first sudden fall of `reading` that the kinetic energy confirms, and
/// the force drop around it. Samples are ordered by decreasing l_k bar;
/// sample j drops when its value is at most `drop_fraction` times the
/// largest value of the samples within `window` before it. The snap is
/// confirmed when the peak kinetic energy from that largest sample to a few
/// samples after j exceeds the median over the samples before the drop
/// began by `kinetic_energy_spike`, or, reading H bar, when F bar falls
/// within those samples to `force_drop` times its value before the drop
/// (Fig. 5 a: F bar "rapidly decreases" at the inversion; a slow snap of
/// rolling strands may stir little kinetic energy). Reading H bar, a
/// shallower fall, to `confirmed_drop_fraction`, is a snap when both the
/// kinetic energy and F bar (or the knot's own length jumping by more than
/// `knot_jump`) confirm it and H bar stays above `drop_fraction`
/// of that largest value for the [`ONSET_SAMPLES`] samples after it (a
/// deeper fall there is read by the first rule, as before).
///
/// The kinetic energy is read only from sample `quiet_from` on: the samples
/// before it were taken at another pace (a fast approach, before a slow pull
/// restarted from its checkpoint), whose kinetic energy is no baseline for a
/// snap at `pull_speed` (the paper's rod n = 6 collapses its loop a few l_k
/// bar after such a restart: CHANGELOG.md, physics revision 21).
pub fn detect_fall(
    series: &[Sample],
    criteria: &InversionCriteria,
    reading: Reading,
    quiet_from: usize,
) -> Option<Inversion> {
    (1..series.len()).find_map(|j| {
        let fall = Fall::at(series, j, criteria, reading, quiet_from)?;
        let level = reading.level(&series[j]);
        let spiked = fall.ratio >= criteria.kinetic_energy_spike;
        let deep = level <= criteria.drop_fraction * fall.reference && (spiked || fall.force_dropped);
        let shallow_confirmed = reading == Reading::LoopHeight
            && level <= criteria.confirmed_drop_fraction * fall.reference
            && spiked
            && (fall.force_dropped || fall.knot_jump > criteria.knot_jump)
            && series.get(j + ONSET_SAMPLES).is_some()
            && series[j + 1..=j + ONSET_SAMPLES]
                .iter()
                .all(|s| reading.level(s) > criteria.drop_fraction * fall.reference);
        (deep || shallow_confirmed).then(|| fall.inversion(series, j, reading))
    })
}

/// A candidate fall at sample j ([`detect_fall`]): the window's largest
/// value before it, the kinetic energy's peak over its median before the
/// drop began, F bar's least value in the samples from j on, and how much
/// further the knot's own length fell than the clamps moved from sample j - 1
/// to j (radii).
struct Fall {
    reference: f64,
    ratio: f64,
    f_after: f64,
    force_dropped: bool,
    knot_jump: f64,
}

impl Fall {
    fn at(
        series: &[Sample],
        j: usize,
        criteria: &InversionCriteria,
        reading: Reading,
        quiet_from: usize,
    ) -> Option<Self> {
        let drop = &series[j];
        // A drop is judged against a full window of history (the first
        // samples of a pull may still carry the relaxation's transients).
        if !reading.may_drop(drop) || series[0].l_k_bar - drop.l_k_bar < criteria.window {
            return None;
        }
        let (start, reference) = series[..j]
            .iter()
            .enumerate()
            .rev()
            .take_while(|(_, s)| s.l_k_bar - drop.l_k_bar <= criteria.window)
            .map(|(i, s)| (i, reading.level(s)))
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        let flat = reading == Reading::LoopHeight && reference < criteria.flat_loop;
        if reference <= 0.0
            || flat
            || reading.level(drop) > criteria.drop_fraction.max(criteria.confirmed_drop_fraction) * reference
        {
            return None;
        }
        let before = &series[j - 1];
        let quiet = if j >= quiet_from { quiet_from } else { 0 };
        let start_quiet = start.max(quiet);
        let lo = start_quiet.saturating_sub(20).max(quiet);
        let mut ke: Vec<f64> = series[lo..start_quiet.max(lo + 1)]
            .iter()
            .map(|s| s.kinetic_energy)
            .collect();
        ke.sort_by(f64::total_cmp);
        let median = ke[ke.len() / 2].max(f64::MIN_POSITIVE);
        let hi = (j + 4).min(series.len());
        let peak = series[start_quiet..hi]
            .iter()
            .map(|s| s.kinetic_energy)
            .fold(0.0, f64::max);
        let f_after = series[j..hi]
            .iter()
            .map(|s| s.f_bar)
            .fold(f64::INFINITY, f64::min);
        let force_dropped = reading == Reading::LoopHeight
            && before.f_bar > 0.0
            && f_after <= criteria.force_drop * before.f_bar;
        Some(Self {
            reference,
            ratio: peak / median,
            f_after,
            force_dropped,
            knot_jump: before.knot_jump_to(drop),
        })
    }

    /// The snap reported for this fall: the sample before it.
    fn inversion(&self, series: &[Sample], j: usize, reading: Reading) -> Inversion {
        let before = &series[j - 1];
        let (h_bar_before, h_bar_after) = match reading {
            Reading::LoopHeight => (before.h_bar, series[j].h_bar),
            Reading::Force => (0.0, 0.0),
        };
        Inversion {
            l_k_bar: before.l_k_bar,
            l_k_arc_bar: before.l_k_arc_bar,
            l_c_over_l: before.l_c_over_l,
            f_bar_before: before.f_bar,
            f_bar_after: self.f_after,
            h_bar_before,
            h_bar_after,
            kinetic_energy_ratio: self.ratio,
            sample: j - 1,
        }
    }
}

/// Samples before the drop within which a snap's onset is looked for: a snap
/// at the paper's pull rate lasts up to about three samples (1.5 l_k bar).
/// A fall of H bar further back is not this snap's: a loop lying flat (n =
/// 6, H bar about 0.02) falls and rises by a quarter of its H bar from one
/// sample to the next.
pub const ONSET_SAMPLES: usize = 3;

/// Where the snap `at` that [`detect_inversion`] found in `series` began:
/// the sample before the largest one-sample fall of H bar within
/// [`ONSET_SAMPLES`] before the drop and after the window's largest H bar
/// (the later of equal falls), with F bar and H bar around it. A snap within
/// one sample is its own onset; the detector reads one that falls to just
/// above `drop_fraction` of the window's largest in its first sample a
/// sample or two into it (a friction-locked n = 2: H bar 0.280 to 0.195 in
/// one sample, the threshold 0.193; a snap spread over three samples, H bar
/// 0.286, 0.239, 0.223, 0.183), and this moves it back to where it began.
pub fn snap_onset(series: &[Sample], at: Inversion, criteria: &InversionCriteria) -> Inversion {
    let j = at.sample + 1;
    let drop = &series[j];
    let Some(start) = (0..j)
        .rev()
        .take_while(|&i| series[i].l_k_bar - drop.l_k_bar <= criteria.window)
        .max_by(|&a, &b| series[a].h_bar.total_cmp(&series[b].h_bar))
    else {
        return at;
    };
    let fall = |i: usize| series[i].h_bar - series[i + 1].h_bar;
    let onset = (start.max(j.saturating_sub(ONSET_SAMPLES))..j)
        .max_by(|&a, &b| fall(a).total_cmp(&fall(b)))
        .unwrap_or(at.sample);
    if onset == at.sample {
        return at;
    }
    let before = &series[onset];
    let hi = (j + 4).min(series.len());
    Inversion {
        l_k_bar: before.l_k_bar,
        l_k_arc_bar: before.l_k_arc_bar,
        l_c_over_l: before.l_c_over_l,
        f_bar_before: before.f_bar,
        f_bar_after: series[onset + 1..hi]
            .iter()
            .map(|s| s.f_bar)
            .fold(f64::INFINITY, f64::min),
        h_bar_before: before.h_bar,
        h_bar_after: series[onset + 1].h_bar,
        sample: onset,
        ..at
    }
}

/// The loop flipping back while the knot loosens (l_k bar increasing): the
/// first sample whose H bar has risen to at least `1 / drop_fraction` times
/// the smallest H bar of the samples within `window` before it, confirmed by
/// the kinetic energy from that smallest-H sample to a few samples after
/// exceeding `kinetic_energy_spike` times its median over the samples
/// before. The mirror of [`detect_inversion`]: a loop that lay flat after
/// the inversion stands up again on the other side, to at least
/// `flat_loop`.
pub fn detect_flip_back(series: &[Sample], criteria: &InversionCriteria) -> Option<Inversion> {
    for j in 1..series.len() {
        let rise = &series[j];
        let flat = rise.h_bar < criteria.flat_loop;
        if rise.width <= 0.0 || flat || rise.l_k_bar - series[0].l_k_bar < criteria.window {
            continue;
        }
        let Some((start, reference)) = series[..j]
            .iter()
            .enumerate()
            .rev()
            .take_while(|(_, s)| rise.l_k_bar - s.l_k_bar <= criteria.window)
            .filter(|(_, s)| s.width > 0.0)
            .map(|(i, s)| (i, s.h_bar))
            .min_by(|a, b| a.1.total_cmp(&b.1))
        else {
            continue;
        };
        if reference <= 0.0 || rise.h_bar * criteria.drop_fraction < reference {
            continue;
        }
        let before = &series[j - 1];
        let lo = start.saturating_sub(20);
        let mut ke: Vec<f64> = series[lo..start.max(lo + 1)]
            .iter()
            .map(|s| s.kinetic_energy)
            .collect();
        ke.sort_by(f64::total_cmp);
        let median = ke[ke.len() / 2].max(f64::MIN_POSITIVE);
        let hi = (j + 4).min(series.len());
        let peak = series[start..hi]
            .iter()
            .map(|s| s.kinetic_energy)
            .fold(0.0, f64::max);
        let ratio = peak / median;
        if ratio < criteria.kinetic_energy_spike {
            continue;
        }
        return Some(Inversion {
            l_k_bar: before.l_k_bar,
            l_k_arc_bar: before.l_k_arc_bar,
            l_c_over_l: before.l_c_over_l,
            f_bar_before: before.f_bar,
            f_bar_after: rise.f_bar,
            h_bar_before: before.h_bar,
            h_bar_after: rise.h_bar,
            kinetic_energy_ratio: ratio,
            sample: j - 1,
        });
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A circular loop of radius r through P = (-w/2, 0, 0) and Q = (w/2, 0, 0)
    /// bulging to +y: H = sqrt(r^2 - w^2/4) + r.
    #[test]
    fn circular_loop_has_known_width_and_height() {
        let (r, w): (f64, f64) = (0.05, 0.06);
        let c = Vector3::new(0.0, (r * r - w * w / 4.0).sqrt(), 0.0);
        let a0 = (-c.y).atan2(-w / 2.0);
        let a1 = (-c.y).atan2(w / 2.0) - 2.0 * PI;
        let pts: Vec<Vector3<f64>> = (0..=400)
            .map(|k| {
                let a = a0 + (a1 - a0) * k as f64 / 400.0;
                c + Vector3::new(r * a.cos(), r * a.sin(), 0.0)
            })
            .collect();
        let g = loop_geometry(&pts, 0, 400);
        assert!((g.width - w).abs() < 1e-12);
        let expected = c.y + r;
        assert!(
            (g.height - expected).abs() < 1e-4 * expected,
            "{} vs {expected}",
            g.height
        );
    }

    #[test]
    fn csv_has_one_row_per_sample_and_every_column() {
        let csv = series_csv(&[Sample::default(), Sample::default()]);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 3);
        assert!(lines.iter().all(|l| l.split(',').count() == COLUMNS.len()));
        let fields = serde_json::to_value(Sample::default()).unwrap();
        assert_eq!(
            COLUMNS.len(),
            fields.as_object().unwrap().len(),
            "a column per field"
        );
    }

    /// Every quantity has one name in JSON and CSV (the paper's symbols:
    /// `F_bar`, `H_bar`, `l_c_over_L`), and a series stored under the old
    /// JSON names still reads.
    #[test]
    fn each_quantity_has_one_name_in_json_and_csv() {
        let sample = Sample {
            l_c_over_l: 0.5,
            force: 1.0,
            f_bar: 2.0,
            width: 3.0,
            height: 4.0,
            h_bar: 5.0,
            ..Sample::default()
        };
        let json = serde_json::to_value(sample).unwrap();
        let names: Vec<&str> = json.as_object().unwrap().keys().map(String::as_str).collect();
        let mut columns: Vec<&str> = COLUMNS.iter().map(|(c, _)| *c).collect();
        columns.sort();
        let mut sorted = names.clone();
        sorted.sort();
        assert_eq!(sorted, columns);
        let old = r#"{"time": 0, "l_k_bar": 0, "l_c_over_l": 0.5, "force": 1, "f_bar": 2, "width": 3,
            "height": 4, "h_bar": 5, "kinetic_energy": 0, "contacts": 0, "active_contacts": 0,
            "max_penetration_over_h": 0, "epsilon": 0, "phi": 0, "newton_iterations": 0, "dt": 0}"#;
        assert_eq!(serde_json::from_str::<Sample>(old).unwrap(), sample);
    }

    /// Straight tails either side of a semicircular bump of radius r: the
    /// own length is (pi - 2) r / h, whatever the tails' length and however
    /// far they stretch along the line; eq. 11's l_k bar counts the stretch.
    #[test]
    fn the_knots_own_length_ignores_the_tails_and_their_stretch() {
        let (r, h) = (0.01, 1e-3);
        let rod = |tail: f64, stretch: f64| {
            let mut pts: Vec<Vector3<f64>> = (0..=100)
                .map(|k| Vector3::new(-tail * stretch * (1.0 - k as f64 / 100.0) - r, 0.0, 0.0))
                .collect();
            pts.extend((1..2000).map(|k| {
                let a = PI * (1.0 - k as f64 / 2000.0);
                Vector3::new(r * a.cos(), r * a.sin(), 0.0)
            }));
            pts.extend((0..=100).map(|k| Vector3::new(r + tail * stretch * k as f64 / 100.0, 0.0, 0.0)));
            pts
        };
        let expected = (PI - 2.0) * r / h;
        for (tail, stretch) in [(0.1, 1.0), (2.0, 1.0), (2.0, 1.0125)] {
            let own = l_k_arc_bar(&rod(tail, stretch), h);
            assert!((own / expected - 1.0).abs() < 1e-5, "{own} against {expected}");
        }
        // Eq. 11 with the unstretched length: the stretch of two tails of
        // 2 m (2.5 cm each) reads as 50 radii less knot.
        let length = 2.0 * 2.0 + PI * r;
        let l_c = 2.0 * (2.0 * 1.0125 + r);
        assert!(((length - l_c) / h - (expected - 50.0)).abs() < 1e-6);
    }

    #[test]
    fn flat_loop_has_zero_height() {
        let pts: Vec<Vector3<f64>> = (0..=10).map(|k| Vector3::new(k as f64, 0.0, 0.0)).collect();
        assert_eq!(loop_geometry(&pts, 0, 10).height, 0.0);
    }

    #[test]
    fn braid_from_contacts() {
        // Strand A (segments 40..60) contacts strand B (141..161), mid = 100;
        // an isolated loop-on-braid contact (80, 150) must not move the ends.
        let pairs = (40..60).map(|i| (i, 200 - i)).chain([(10, 20), (80, 150)]);
        let b = braid(pairs, 100).unwrap();
        assert_eq!((b.first, b.second), ((40, 59), (141, 160)));
        assert_eq!(b.loop_ends(), (60, 141));
        assert_eq!(braid([(10, 20)], 100), None);
    }

    /// Two straight strands of length 10 along z, 2 apart, closed by a loop of
    /// two straight legs rising c above them: l_b = 10, l_l = 2 sqrt(1 + c^2),
    /// phi = atan(1 / c).
    #[test]
    fn braid_shape_of_straight_strands_and_a_tent_loop() {
        let c = 1.7;
        let mut pts: Vec<Vector3<f64>> = (0..=10).map(|k| Vector3::new(-1.0, 0.0, k as f64)).collect();
        pts.push(Vector3::new(0.0, 0.0, 10.0 + c));
        pts.extend((0..=10).map(|k| Vector3::new(1.0, 0.0, 10.0 - k as f64)));
        let b = Braid {
            first: (0, 9),
            second: (12, 21),
        };
        assert_eq!(b.loop_ends(), (10, 12));
        let s = braid_shape(&pts, &b);
        let l_l = 2.0 * (1.0 + c * c).sqrt();
        assert!((s.l_b - 10.0).abs() < 1e-12, "{}", s.l_b);
        assert!((s.l_l - l_l).abs() < 1e-12);
        assert!((s.epsilon - 10.0 / l_l).abs() < 1e-12);
        assert!((s.phi - (1.0 / c).atan()).abs() < 1e-12, "{}", s.phi);
    }

    fn sample(l: f64, h_bar: f64, ke: f64, f: f64) -> Sample {
        Sample {
            l_k_bar: l,
            h_bar,
            kinetic_energy: ke,
            f_bar: f,
            width: 1.0,
            ..Sample::default()
        }
    }

    #[test]
    fn sudden_drop_with_energy_spike_is_an_inversion() {
        let mut s: Vec<Sample> = (0..40)
            .map(|k| sample(200.0 - k as f64, 0.8, 1e-9, 1.0 + 0.01 * k as f64))
            .collect();
        s.push(sample(160.0, 0.05, 1e-6, 0.6));
        s.push(sample(159.0, 0.04, 1e-8, 0.9));
        let inv = detect_inversion(&s, &InversionCriteria::default()).expect("detected");
        assert_eq!(inv.l_k_bar, 161.0);
        assert_eq!(inv.sample, 39);
        assert_eq!(inv.h_bar_after, 0.05);
        assert!(inv.f_bar_after < inv.f_bar_before);
    }

    /// A snap spread over several samples, with the kinetic energy already up
    /// when H bar crosses the threshold: the baseline is taken before the drop.
    #[test]
    fn drop_over_several_samples_is_an_inversion() {
        let mut s: Vec<Sample> = (0..40)
            .map(|k| sample(200.0 - k as f64, 0.8, 1e-9, 1.0))
            .collect();
        for (k, h) in [0.7, 0.55, 0.4, 0.25, 0.1, 0.08].into_iter().enumerate() {
            s.push(sample(160.0 - k as f64, h, 1e-6, 0.5));
        }
        let inv = detect_inversion(&s, &InversionCriteria::default()).expect("detected");
        assert_eq!(inv.h_bar_after, 0.4);
        assert_eq!(inv.l_k_bar, 159.0);
        assert!(inv.kinetic_energy_ratio > 100.0);
    }

    /// A snap with little kinetic energy, confirmed by the force drop.
    #[test]
    fn drop_with_a_force_drop_is_an_inversion() {
        let mut s: Vec<Sample> = (0..40)
            .map(|k| sample(200.0 - k as f64, 0.8, 1e-9, 1.0))
            .collect();
        s.push(sample(160.0, 0.4, 2e-9, 0.7));
        s.push(sample(159.0, 0.4, 1e-9, 0.8));
        let inv = detect_inversion(&s, &InversionCriteria::default()).expect("detected");
        assert_eq!(inv.l_k_bar, 161.0);
        assert_eq!(inv.f_bar_after, 0.7);
        let mut held = s.clone();
        held[40].f_bar = 0.9;
        held[41].f_bar = 0.95;
        assert!(detect_inversion(&held, &InversionCriteria::default()).is_none());
        // A compressive force that grows is no force drop.
        let mut pushed = s.clone();
        pushed[39].f_bar = -0.004;
        pushed[40].f_bar = -0.012;
        assert!(detect_inversion(&pushed, &InversionCriteria::default()).is_none());
    }

    /// A snap whose first sample leaves H bar just above the threshold (0.8
    /// to 0.49, the threshold 0.48) is read a sample later by the detector;
    /// its onset is the sample before the largest fall, with F bar around it.
    /// A snap within one sample, or a drop in equal steps, keeps the
    /// detector's sample.
    #[test]
    fn the_onset_of_a_snap_is_before_its_largest_fall() {
        let criteria = InversionCriteria::default();
        let mut s: Vec<Sample> = (0..40)
            .map(|k| sample(200.0 - k as f64, 0.8, 1e-9, 1.0))
            .collect();
        for (k, (h, f)) in [(0.49, 0.7), (0.47, 0.5), (0.45, 0.45)].into_iter().enumerate() {
            s.push(sample(160.0 - k as f64, h, 1e-9, f));
        }
        let found = detect_inversion(&s, &criteria).expect("detected");
        assert_eq!((found.l_k_bar, found.sample), (160.0, 40));
        let onset = snap_onset(&s, found, &criteria);
        assert_eq!((onset.l_k_bar, onset.sample), (161.0, 39));
        assert_eq!((onset.h_bar_before, onset.h_bar_after), (0.8, 0.49));
        assert_eq!((onset.f_bar_before, onset.f_bar_after), (1.0, 0.45));
        assert_eq!(onset.kinetic_energy_ratio, found.kinetic_energy_ratio);
        let mut sudden: Vec<Sample> = s[..40].to_vec();
        sudden.push(sample(160.0, 0.05, 1e-6, 0.6));
        sudden.push(sample(159.0, 0.04, 1e-8, 0.9));
        let found = detect_inversion(&sudden, &criteria).expect("detected");
        assert_eq!(snap_onset(&sudden, found, &criteria), found);
        let mut even: Vec<Sample> = s[..40].to_vec();
        for (k, h) in [0.75, 0.5, 0.25].into_iter().enumerate() {
            even.push(sample(160.0 - k as f64, h, 1e-6, 0.5));
        }
        let found = detect_inversion(&even, &criteria).expect("detected");
        assert_eq!(snap_onset(&even, found, &criteria), found);
        // A larger fall more than `ONSET_SAMPLES` before the drop is not
        // this snap's.
        let mut earlier: Vec<Sample> = s[..40].to_vec();
        earlier[35].h_bar = 0.6;
        for later in &mut earlier[36..40] {
            later.h_bar = 0.55;
        }
        earlier.push(sample(160.0, 0.45, 1e-6, 0.5));
        let found = detect_inversion(&earlier, &criteria).expect("detected");
        assert_eq!(found.sample, 39);
        assert_eq!(snap_onset(&earlier, found, &criteria), found);
    }

    /// A loop that keeps 0.7 of its height through a snap (0.8 to 0.56, above
    /// the 0.48 of `drop_fraction`) inverts when both the kinetic energy and
    /// F bar confirm it; with either alone it does not, nor before the
    /// samples after it are in; a deeper fall right after is read as before,
    /// at the deeper sample.
    #[test]
    fn shallow_fall_confirmed_twice_is_an_inversion() {
        let criteria = InversionCriteria::default();
        let held: Vec<Sample> = (0..40)
            .map(|k| sample(200.0 - k as f64, 0.8, 1e-9, 1.0))
            .collect();
        let snap = |ke: f64, f: f64, after: [f64; 3]| {
            let mut s = held.clone();
            s.push(sample(160.0, 0.56, ke, f));
            for (k, h) in after.into_iter().enumerate() {
                s.push(sample(159.0 - k as f64, h, 1e-9, f));
            }
            s
        };
        let both = snap(1e-6, 0.7, [0.57, 0.58, 0.58]);
        let inv = detect_inversion(&both, &criteria).expect("detected");
        assert_eq!((inv.l_k_bar, inv.sample), (161.0, 39));
        assert_eq!((inv.h_bar_before, inv.h_bar_after), (0.8, 0.56));
        assert_eq!((inv.f_bar_before, inv.f_bar_after), (1.0, 0.7));
        assert!(
            detect_inversion(&both[..42], &criteria).is_none(),
            "waits for the samples after"
        );
        assert!(detect_inversion(&snap(1e-9, 0.7, [0.57, 0.58, 0.58]), &criteria).is_none());
        assert!(detect_inversion(&snap(1e-6, 0.9, [0.57, 0.58, 0.58]), &criteria).is_none());
        let deeper = snap(1e-6, 0.7, [0.3, 0.3, 0.3]);
        let inv = detect_inversion(&deeper, &criteria).expect("detected");
        assert_eq!((inv.sample, inv.h_bar_after), (40, 0.3));
    }

    /// A rod longer than its knot (rubber n = 2 at L/h 5000, mu = 0.05,
    /// under the reference pull): H bar falls to 0.69 of the window's
    /// largest with a kinetic energy burst, F bar only to 0.9 of its value,
    /// the tails' stretch taken up by the knot, whose own length falls by
    /// 7.35 where the clamps move 0.5. The jump confirms the fall as F bar's
    /// would; a knot whose own length follows the clamps does not, nor does a
    /// jump without the burst.
    #[test]
    fn a_shallow_fall_with_the_knot_jumping_is_an_inversion() {
        let criteria = InversionCriteria::default();
        let snap = |jump: f64, ke: f64| -> Vec<Sample> {
            let mut s: Vec<Sample> = (0..40)
                .map(|k| Sample {
                    l_k_arc_bar: 250.0 - 0.8 * k as f64,
                    ..sample(200.0 - k as f64, 0.3, 1e-9, 0.042)
                })
                .collect();
            let before = s[39].l_k_arc_bar;
            for (k, h) in [0.205, 0.2, 0.2, 0.2].into_iter().enumerate() {
                s.push(Sample {
                    l_k_arc_bar: before - 0.5 - jump - 0.4 * k as f64,
                    ..sample(160.5 - 0.5 * k as f64, h, if k == 0 { ke } else { 1e-9 }, 0.038)
                });
            }
            s
        };
        let inv = detect_inversion(&snap(6.85, 1e-7), &criteria).expect("detected");
        assert_eq!((inv.sample, inv.l_k_bar), (39, 161.0));
        assert_eq!((inv.h_bar_before, inv.h_bar_after), (0.3, 0.205));
        assert!(inv.f_bar_after > criteria.force_drop * inv.f_bar_before);
        assert!(detect_inversion(&snap(0.0, 1e-7), &criteria).is_none(), "no jump");
        assert!(
            detect_inversion(&snap(6.85, 1e-9), &criteria).is_none(),
            "no burst"
        );
    }

    /// The snap of `sudden_drop_with_energy_spike_is_an_inversion` scaled
    /// down to a flat loop (H bar 0.03 -> 0.002, below `flat_loop`) is its
    /// contacts' noise, however the kinetic energy and F bar move; scaled to
    /// just above it, a snap.
    #[test]
    fn a_flat_loop_has_no_fall_to_read() {
        let criteria = InversionCriteria::default();
        let scaled = |top: f64| {
            let mut s: Vec<Sample> = (0..40)
                .map(|k| sample(200.0 - k as f64, top, 1e-9, 1.0 + 0.01 * k as f64))
                .collect();
            s.push(sample(160.0, top / 16.0, 1e-6, 0.6));
            s.push(sample(159.0, top / 20.0, 1e-8, 0.9));
            s
        };
        assert!(detect_inversion(&scaled(0.03), &criteria).is_none());
        let inv = detect_inversion(&scaled(1.01 * criteria.flat_loop), &criteria).expect("detected");
        assert_eq!(inv.l_k_bar, 161.0);
    }

    /// A slow pull restarted from a fast approach's checkpoint at sample 40:
    /// the fast samples' kinetic energy (1e-6) is no baseline for the slow
    /// pull's (2e-8), whose loop collapses with 30 times its own. Read from
    /// the restart on, the collapse is a snap; read across it, it is not.
    #[test]
    fn the_kinetic_energy_is_read_from_the_slow_pull_on() {
        let criteria = InversionCriteria::default();
        let mut s: Vec<Sample> = (0..40)
            .map(|k| sample(240.0 - k as f64, 0.2, 1e-6, 0.02))
            .collect();
        s.extend((0..4).map(|k| sample(200.0 - k as f64, 0.19, 2e-8, 0.02)));
        s.push(sample(196.0, 0.03, 6e-7, 0.021));
        s.push(sample(195.0, 0.03, 2e-8, 0.022));
        assert!(detect_fall(&s, &criteria, Reading::LoopHeight, 0).is_none());
        let inv = detect_fall(&s, &criteria, Reading::LoopHeight, 40).expect("a snap");
        assert_eq!((inv.l_k_bar, inv.sample), (197.0, 43));
        assert!((inv.kinetic_energy_ratio - 30.0).abs() < 1e-9, "{inv:?}");
    }

    #[test]
    fn slow_decline_or_no_energy_spike_is_not() {
        let slow: Vec<Sample> = (0..100)
            .map(|k| sample(200.0 - k as f64, 0.8 * (1.0 - k as f64 / 100.0), 1e-9, 1.0))
            .collect();
        assert!(detect_inversion(&slow, &InversionCriteria::default()).is_none());
        let mut quiet: Vec<Sample> = (0..40)
            .map(|k| sample(200.0 - k as f64, 0.8, 1e-9, 1.0))
            .collect();
        quiet.push(sample(160.0, 0.05, 1e-9, 1.0));
        assert!(detect_inversion(&quiet, &InversionCriteria::default()).is_none());
    }
}
