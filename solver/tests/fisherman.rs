//! The fisherman's knot: two rods tied loose and contact-free, each an
//! overhand knot (the trefoil) round the other's standing part, the
//! diagram's crossings, its half-turn symmetry, and its case.
use nalgebra::Vector3;
use solver::case::{CaseParams, KnotKind};
use solver::knot::{Alexander, Bend, BendSpec, StartShape, alexander};
use solver::rod::End;

fn tie() -> (BendSpec, StartShape) {
    let spec = BendSpec {
        bend: Bend::Fisherman,
        length: 1.0,
        nodes: 301,
        radius: 1.6e-3,
    };
    let shape = spec.tie().unwrap_or_else(|e| panic!("{e}"));
    (spec, shape)
}

/// Two rods of K nodes and rest length L each, clamped at their first nodes
/// on either side of the knot, closest to each other where they cross
/// (2 LIFT = 3.6 h apart) and nowhere within 2h.
#[test]
fn the_fisherman_is_tied_loose_and_contact_free() {
    let (spec, shape) = tie();
    let h = spec.radius;
    assert_eq!(shape.rods.len(), 2);
    assert!(shape.alexander.is_none(), "a bend has no one polynomial");
    let edge = spec.length / (spec.nodes - 1) as f64;
    for rod in &shape.rods {
        assert_eq!(rod.len(), spec.nodes);
        assert!(
            rod.windows(2)
                .all(|w| ((w[1] - w[0]).norm() - edge).abs() < 1e-9 * edge)
        );
    }
    assert_eq!(
        shape.clamps.map(|c| (c.rod, c.end)),
        [(0, End::Start), (1, End::Start)]
    );
    let [a, b] = shape.clamp_points();
    assert!(a.x < -0.3 && b.x > 0.3, "{a:?} {b:?}");
    let (r0, r1) = (&shape.rods[0], &shape.rods[1]);
    let closest = (0..r0.len() - 1)
        .flat_map(|i| (0..r1.len() - 1).map(move |j| (i, j)))
        .filter(|&(i, j)| (r0[i] - r1[j]).norm() < 0.05)
        .map(|(i, j)| segment_distance(&r0[i], &r0[i + 1], &r1[j], &r1[j + 1]))
        .fold(f64::INFINITY, f64::min);
    assert!(
        closest >= 2.0 * h && closest < 3.61 * h,
        "closest {} h",
        closest / h
    );
}

/// Each rod alone is an overhand knot: its Alexander polynomial, computed
/// from its own nodes, is the trefoil's 1 - t + t^2.
#[test]
fn each_rod_ties_an_overhand_knot() {
    let (_, shape) = tie();
    for rod in &shape.rods {
        assert_eq!(alexander(rod).unwrap(), Alexander::torus_2(3));
        assert_eq!(Alexander::torus_2(3).coefficients(), [1, -1, 1]);
    }
}

/// A half turn about z maps rod 0 onto rod 1 node by node; each rod ties
/// a knot of its own.
#[test]
fn a_half_turn_swaps_the_rods() {
    let (spec, shape) = tie();
    let worst = (shape.rods[0].iter().zip(&shape.rods[1]))
        .map(|(p, q)| (Vector3::new(-p.x, -p.y, p.z) - q).norm())
        .fold(0.0, f64::max);
    assert!(worst < 1e-9 * spec.length, "{worst}");
    assert!(shape.own_knots);
}

/// The diagram seen along z: three crossings in each rod (its overhand's)
/// and six between the rods, three on each overhand; rod 1's standing part
/// passes rod 0's overhand under, over, over (under the loop's far side,
/// over the tail that goes through the loop, over the loop's near side):
/// through the loop, beside the tail.
#[test]
fn the_other_standing_part_passes_through_the_loop() {
    let (_, shape) = tie();
    let (a, b) = (&shape.rods[0], &shape.rods[1]);
    assert_eq!(
        crossings(a, a).len(),
        2 * 3,
        "each self-crossing seen from both strands"
    );
    assert_eq!(crossings(b, b).len(), 2 * 3);
    let between = crossings(a, b);
    assert_eq!(between.len(), 6);
    // Rod 0's overhand lies at x > 0, round rod 1's standing part.
    let mut on_knot: Vec<_> = between.iter().filter(|c| a[c.0].x > 0.0).collect();
    assert_eq!(on_knot.len(), 3);
    on_knot.sort_by_key(|c| c.1);
    let rod1_over: Vec<bool> = on_knot.iter().map(|c| !c.2).collect();
    assert_eq!(rod1_over, [false, true, true]);
}

/// A fisherman's case: two rods, the bends' tight force; refused with `n`.
#[test]
fn the_fisherman_is_a_bend_case() {
    let params = CaseParams {
        knot: KnotKind::Fisherman,
        ..CaseParams::default()
    };
    assert!(params.validate().is_ok(), "{:?}", params.validate());
    assert_eq!(params.knot_label(), "fisherman");
    assert_eq!(params.rest_length(), 2.0 * params.length);
    assert_eq!(params.tight_force_bar(), solver::case::BEND_TIGHT_FORCE_BAR);
    let field = |p: CaseParams| p.validate().unwrap_err()[0].field.clone();
    assert_eq!(field(CaseParams { n: 4, ..params }), "n");
}

/// Pulled by its standing ends (mu = 0.5), the fisherman's knot shows Tong
/// et al.'s two regimes: once the tails are free the overhands slide
/// towards each other (their separation falls by more than 30 h) at low
/// force (F bar below a third of the largest the knot holds), then meet
/// (within 4 h) and jam, and the force rises past the setting load.
#[test]
fn the_fisherman_slides_then_jams() {
    let params = CaseParams {
        knot: KnotKind::Fisherman,
        mu: 0.5,
        ..CaseParams::default()
    };
    let report = solver::protocol::run(&params, &mut |_| true);
    assert_eq!(
        report.status,
        solver::protocol::Status::Completed,
        "{}",
        report.reason
    );
    let holding = report.holding_force_bar.expect("a bend's holding force");
    let free: Vec<(f64, f64)> = (report.series.iter().zip(&report.bend_series))
        .filter(|(_, b)| b.tails_free)
        .map_while(|(s, b)| b.knots_apart_bar.map(|a| (s.f_bar, a)))
        .collect();
    let met = free
        .iter()
        .position(|&(_, a)| a < 4.0)
        .expect("the overhands meet");
    let (first, last) = (free[0].1, free[met].1);
    assert!(first - last > 30.0, "slid from {first} h to {last} h");
    let sliding = free[..met].iter().map(|s| s.0).fold(0.0, f64::max);
    assert!(
        sliding < holding / 3.0,
        "sliding at F bar {sliding}, holding {holding}"
    );
    let jammed = free[met..].iter().map(|s| s.0).fold(0.0, f64::max);
    let setting = 0.5 * solver::case::BEND_TIGHT_FORCE_BAR;
    assert!(jammed > setting, "jammed at F bar {jammed}");
}

/// Crossings of polylines `a` and `b` (the same one: its non-neighbouring
/// segments) seen along z: `(segment of a, segment of b, a on top)`.
fn crossings(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> Vec<(usize, usize, bool)> {
    let same = std::ptr::eq(a, b);
    let mut found = Vec::new();
    for i in 0..a.len() - 1 {
        for j in 0..b.len() - 1 {
            if same && i.abs_diff(j) < 2 {
                continue;
            }
            let (d, e, r) = (a[i + 1] - a[i], b[j + 1] - b[j], b[j] - a[i]);
            let den = d.x * e.y - d.y * e.x;
            if den.abs() < 1e-18 {
                continue;
            }
            let s = (r.x * e.y - r.y * e.x) / den;
            let t = (r.x * d.y - r.y * d.x) / den;
            if (0.0..1.0).contains(&s) && (0.0..1.0).contains(&t) {
                found.push((i, j, a[i].z + s * d.z > b[j].z + t * e.z));
            }
        }
    }
    found
}

/// Closest distance between segments `p0 p1` and `q0 q1` (sampled finely).
fn segment_distance(p0: &Vector3<f64>, p1: &Vector3<f64>, q0: &Vector3<f64>, q1: &Vector3<f64>) -> f64 {
    let n = 24;
    let mut best = f64::INFINITY;
    for i in 0..=n {
        let p = p0 + (p1 - p0) * (i as f64 / n as f64);
        for j in 0..=n {
            let q = q0 + (q1 - q0) * (j as f64 / n as f64);
            best = best.min((p - q).norm());
        }
    }
    best
}
