//! The knot catalog's builders and topology checks (paper Sec. 2, 4): knot
//! determinants and Alexander polynomials of standard knots from their
//! textbook parametrisations, and the geometry and topology of the built
//! knots (overhand, figure-eight, braid closures).
use nalgebra::{Rotation3, Unit, Vector3};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use solver::knot::{
    BraidSpec, BraidWord, Family, FigureEightSpec, KnotError, KnotShape, KnotSpec, TopologyError, alexander,
    alexander_along, build, close_open_curve, closed_alexander, closed_knot_determinant, determinant_along,
    expected_determinant, knot_determinant,
};
use std::f64::consts::PI;
use std::time::{Duration, Instant};

type Curve = Vec<Vector3<f64>>;

/// `samples` points of the closed curve `f(t)`, `t in [0, 2 pi)`.
fn sample(samples: usize, f: impl Fn(f64) -> Vector3<f64>) -> Curve {
    (0..samples)
        .map(|i| f(2.0 * PI * i as f64 / samples as f64))
        .collect()
}

fn circle() -> Curve {
    sample(200, |t| Vector3::new(t.cos(), t.sin(), 0.0))
}

/// Trefoil `(sin t + 2 sin 2t, cos t - 2 cos 2t, -sin 3t)`.
fn trefoil() -> Curve {
    sample(400, |t| {
        Vector3::new(
            t.sin() + 2.0 * (2.0 * t).sin(),
            t.cos() - 2.0 * (2.0 * t).cos(),
            -(3.0 * t).sin(),
        )
    })
}

/// Figure-eight knot `((2 + cos 2t) cos 3t, (2 + cos 2t) sin 3t, sin 4t)`.
fn figure_eight() -> Curve {
    sample(600, |t| {
        let r = 2.0 + (2.0 * t).cos();
        Vector3::new(r * (3.0 * t).cos(), r * (3.0 * t).sin(), (4.0 * t).sin())
    })
}

/// Torus knot `T(p, q)`: `(r cos pt, r sin pt, -sin qt)`, `r = 2 + cos qt`.
fn torus_knot(p: f64, q: f64) -> Curve {
    sample(1000, |t| {
        let r = 2.0 + (q * t).cos();
        Vector3::new(r * (p * t).cos(), r * (p * t).sin(), -(q * t).sin())
    })
}

/// An unknot whose projection on the xy plane is a simple star-shaped curve,
/// lifted to large random heights: crumpled in space, many crossings in
/// generic projections, unknotted by construction.
fn crumpled_unknot(seed: u64) -> Curve {
    let mut rng = StdRng::seed_from_u64(seed);
    let terms: Vec<(f64, f64, f64)> = (1..=24)
        .map(|k| (k as f64, rng.gen_range(-3.0..3.0), rng.gen_range(0.0..2.0 * PI)))
        .collect();
    sample(2000, |t| {
        let r = 2.0 + 0.5 * (5.0 * t).sin() + 0.3 * (3.0 * t).cos();
        let z = terms
            .iter()
            .map(|(k, amp, phase)| amp * (k * t + phase).sin())
            .sum();
        Vector3::new(r * t.cos(), r * t.sin(), z)
    })
}

/// Standard knots and their determinants `|Delta(-1)|` (knot tables).
fn standard_knots() -> Vec<(&'static str, Curve, u64)> {
    vec![
        ("circle", circle(), 1),
        ("crumpled unknot", crumpled_unknot(7), 1),
        ("trefoil 3_1", trefoil(), 3),
        ("figure-eight 4_1", figure_eight(), 5),
        ("T(2,3) = 3_1", torus_knot(2.0, 3.0), 3),
        ("T(2,5) = 5_1", torus_knot(2.0, 5.0), 5),
        ("T(2,7) = 7_1", torus_knot(2.0, 7.0), 7),
        ("T(3,4) = 8_19", torus_knot(3.0, 4.0), 3),
        ("T(3,5) = 10_124", torus_knot(3.0, 5.0), 1),
    ]
}

/// Opens a closed curve at its vertex of largest x and runs the two ends out
/// to a pulling axis (parallel to y, beyond the curve in x): the closure of
/// `knot_determinant` then only adds a path in the empty half-space `x > max
/// x`, so the knot type is that of the closed curve.
fn open_on_axis(closed: &[Vector3<f64>]) -> Curve {
    let m = (0..closed.len())
        .max_by(|&a, &b| closed[a].x.total_cmp(&closed[b].x))
        .unwrap();
    let p = closed[m];
    let size = closed.iter().map(|q| (q - p).norm()).fold(0.0, f64::max);
    let eps = 1e-6 * size;
    let axis_x = p.x + size;
    let at = |y: f64| Vector3::new(axis_x, y, p.z);
    let mut open = vec![
        at(p.y + 2.0 * size),
        at(p.y + eps),
        p + Vector3::new(0.0, eps, 0.0),
    ];
    open.extend((1..closed.len()).map(|k| closed[(m + k) % closed.len()]));
    open.extend([
        p - Vector3::new(0.0, eps, 0.0),
        at(p.y - eps),
        at(p.y - 2.0 * size),
    ]);
    open
}

fn random_rotation(rng: &mut StdRng) -> Rotation3<f64> {
    let axis = Vector3::new(
        rng.gen_range(-1.0..1.0),
        rng.gen_range(-1.0..1.0),
        rng.gen_range(-1.0..1.0),
    );
    Rotation3::from_axis_angle(&Unit::new_normalize(axis), rng.gen_range(0.0..2.0 * PI))
}

fn random_direction(rng: &mut StdRng) -> Vector3<f64> {
    loop {
        let d = Vector3::new(
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
            rng.gen_range(-1.0..1.0),
        );
        if d.norm() > 0.1 && d.norm() <= 1.0 {
            return d;
        }
    }
}

#[test]
fn standard_knots_have_their_table_determinants() {
    for (name, curve, det) in standard_knots() {
        assert_eq!(closed_knot_determinant(&curve), Ok(det), "{name}");
        assert_eq!(
            knot_determinant(&open_on_axis(&curve)),
            Ok(det),
            "{name} opened onto an axis"
        );
    }
}

#[test]
fn determinant_is_invariant_under_rotations_and_projection_directions() {
    let mut rng = StdRng::seed_from_u64(11);
    for (name, curve, det) in standard_knots() {
        for _ in 0..8 {
            let rotation = random_rotation(&mut rng);
            let rotated: Curve = curve.iter().map(|p| rotation * p).collect();
            assert_eq!(closed_knot_determinant(&rotated), Ok(det), "{name} rotated");
            assert_eq!(
                knot_determinant(&open_on_axis(&rotated)),
                Ok(det),
                "{name} rotated, opened"
            );
            let direction = random_direction(&mut rng);
            assert_eq!(
                determinant_along(&curve, &direction),
                Ok(det),
                "{name} along {direction:?}"
            );
        }
    }
}

/// Alexander polynomials of the knot tables (lowest power first): the
/// torus knots' `(t^pq - 1)(t - 1) / ((t^p - 1)(t^q - 1))`.
fn table_polynomial(name: &str) -> Vec<i64> {
    match name {
        "circle" | "crumpled unknot" => vec![1],
        "trefoil 3_1" | "T(2,3) = 3_1" => vec![1, -1, 1],
        "figure-eight 4_1" => vec![1, -3, 1],
        "T(2,5) = 5_1" => vec![1, -1, 1, -1, 1],
        "T(2,7) = 7_1" => vec![1, -1, 1, -1, 1, -1, 1],
        "T(3,4) = 8_19" => vec![1, -1, 0, 1, 0, -1, 1],
        "T(3,5) = 10_124" => vec![1, -1, 0, 1, -1, 1, 0, -1, 1],
        other => panic!("no table entry for {other}"),
    }
}

/// The polynomial tells 4_1 from 5_1 (both of determinant 5) and 10_124
/// from the unknot (both 1), whatever the rotation, projection or opening.
#[test]
fn standard_knots_have_their_table_alexander_polynomials() {
    let mut rng = StdRng::seed_from_u64(5);
    for (name, curve, det) in standard_knots() {
        let want = table_polynomial(name);
        let got = closed_alexander(&curve).unwrap();
        assert_eq!(got.coefficients(), want, "{name}");
        assert_eq!(got.determinant(), det, "{name}: |Delta(-1)| is the determinant");
        for _ in 0..4 {
            let rotation = random_rotation(&mut rng);
            let rotated: Curve = curve.iter().map(|p| rotation * p).collect();
            let opened = alexander(&open_on_axis(&rotated)).unwrap();
            assert_eq!(opened.coefficients(), want, "{name} rotated, opened");
            let direction = random_direction(&mut rng);
            match alexander_along(&curve, &direction) {
                Ok(p) => assert_eq!(p.coefficients(), want, "{name} along {direction:?}"),
                Err(e) => assert_eq!(e, TopologyError::DegenerateProjection, "{name}"),
            }
        }
    }
}

/// The built overhand knot with n passes carries the (2, 2n + 1) torus
/// knot's polynomial, `1 - t + ... + t^2n`, and the family says so.
#[test]
fn overhand_knots_carry_the_torus_knots_polynomial() {
    for n in 1..=4 {
        let spec = KnotSpec::paper(n);
        let want: Vec<i64> = (0..=2 * n).map(|k| if k % 2 == 0 { 1 } else { -1 }).collect();
        assert_eq!(spec.alexander().coefficients(), want, "n = {n}");
        let shape = build(&spec).unwrap();
        assert_eq!(alexander(&shape.points).unwrap().coefficients(), want, "n = {n}");
    }
}

/// Braid closures tied in a rod: `s1 s1 s1` is the trefoil, `s1 s2^-1 s1
/// s2^-1` the figure-eight (as the figure-eight family ties it), `s1^3 s2
/// s1^-1 s2` the knot `5_2` and `s1 s2 s1 s2 s1 s2 s1 s2` the (3, 4) torus
/// knot `8_19`; each shape is loose and
/// contact-free with equal edges, its ends on the pulling axis, and keeps
/// its polynomial under random rotations.
#[test]
fn braid_closures_tie_their_knots() {
    let (length, nodes, radius) = (1.0, 301, 1.6e-3);
    let braid = |word: &str| BraidSpec {
        word: BraidWord::parse(word).unwrap(),
        length,
        nodes,
        radius,
    };
    let figure_eight = FigureEightSpec {
        length,
        nodes,
        radius,
    };
    let cases: Vec<(Box<dyn Family>, Vec<i64>)> = vec![
        (Box::new(braid("s1 s1 s1")), vec![1, -1, 1]),
        (Box::new(braid("s1 s2^-1 s1 s2^-1")), vec![1, -3, 1]),
        (Box::new(figure_eight), vec![1, -3, 1]),
        (Box::new(braid("s1^3 s2 s1^-1 s2")), vec![2, -3, 2]),
        (
            Box::new(braid("s1 s2 s1 s2 s1 s2 s1 s2")),
            vec![1, -1, 0, 1, 0, -1, 1],
        ),
    ];
    let mut rng = StdRng::seed_from_u64(17);
    for (family, want) in cases {
        assert_eq!(family.alexander().coefficients(), want);
        let shape = family.tie().unwrap();
        let points = shape.points();
        assert_eq!(points.len(), nodes);
        let edge = length / (nodes - 1) as f64;
        assert!(
            points
                .windows(2)
                .all(|w| ((w[1] - w[0]).norm() - edge).abs() < 1e-9 * edge)
        );
        let (first, last) = (points[0], points[nodes - 1]);
        assert!(first.y.abs() + first.z.abs() + last.y.abs() + last.z.abs() < 1e-12);
        assert!(
            points.iter().all(|p| p.x >= first.x && p.x <= last.x),
            "every node between the clamps"
        );
        assert!(min_non_neighbour_distance(points, radius, edge) >= 2.0 * radius);
        assert_eq!(alexander(points).unwrap().coefficients(), want);
        for _ in 0..4 {
            let rotation = random_rotation(&mut rng);
            let rotated: Curve = points.iter().map(|p| rotation * p).collect();
            assert_eq!(alexander(&rotated).unwrap().coefficients(), want, "rotated");
        }
    }
}

/// A rod too short or too coarse for a braid's knot is refused, saying
/// what it needs.
#[test]
fn braid_knots_need_room_and_nodes() {
    let spec = BraidSpec {
        word: BraidWord::parse("s1 s2 s3 s4 s1 s2 s3 s4").unwrap(),
        length: 0.4,
        nodes: 301,
        radius: 1.6e-3,
    };
    assert!(matches!(spec.tie(), Err(KnotError::RodTooShort { .. })));
    let coarse = BraidSpec {
        word: BraidWord::parse("s1^3").unwrap(),
        length: 1.0,
        nodes: 101,
        radius: 1.6e-3,
    };
    assert!(matches!(coarse.tie(), Err(KnotError::TooFewNodes { min, .. }) if min > 250));
}

#[test]
fn crumpled_unknots_have_determinant_one() {
    let mut rng = StdRng::seed_from_u64(3);
    for seed in 0..6 {
        let curve = crumpled_unknot(seed);
        assert_eq!(closed_knot_determinant(&curve), Ok(1));
        for _ in 0..4 {
            assert_eq!(determinant_along(&curve, &random_direction(&mut rng)), Ok(1));
        }
    }
}

#[test]
fn straight_and_bent_open_rods_are_unknotted() {
    let straight: Curve = (0..50).map(|i| Vector3::new(i as f64, 0.0, 0.0)).collect();
    assert_eq!(knot_determinant(&straight), Ok(1));
    // A U-shaped rod whose ends lie on the x axis.
    let mut u: Curve = (0..20).map(|i| Vector3::new(i as f64 - 30.0, 0.0, 0.0)).collect();
    u.extend((0..=40).map(|i| {
        let t = PI * i as f64 / 40.0;
        Vector3::new(-10.0 * t.cos(), 10.0 * t.sin(), 0.0)
    }));
    u.extend((1..20).map(|i| Vector3::new(10.0 + i as f64, 0.0, 0.0)));
    assert_eq!(knot_determinant(&u), Ok(1));
}

#[test]
fn closure_extends_the_ends_beyond_the_curve() {
    let open = open_on_axis(&trefoil());
    let closed = close_open_curve(&open).unwrap();
    assert_eq!(&closed[..open.len()], &open[..]);
    assert_eq!(closed.len(), open.len() + 4);
    let (first, last) = (open[0], open[open.len() - 1]);
    let mid = 0.5 * (first + last);
    let radius = open.iter().map(|p| (p - mid).norm()).fold(0.0, f64::max);
    let axis = (last - first).normalize();
    let far = &closed[open.len()..];
    // Extensions along the axis, joined outside the bounding sphere.
    assert!(((far[0] - last).normalize() - axis).norm() < 1e-12);
    assert!(((far[3] - first).normalize() + axis).norm() < 1e-12);
    assert!(far.iter().all(|p| (p - mid).norm() > radius));
}

#[test]
fn topology_errors() {
    let p = Vector3::new(1.0, 2.0, 3.0);
    assert_eq!(
        knot_determinant(&[p]),
        Err(TopologyError::TooFewPoints { got: 1, min: 2 })
    );
    assert_eq!(
        closed_knot_determinant(&[p, p]),
        Err(TopologyError::TooFewPoints { got: 2, min: 3 })
    );
    let nan = Vector3::new(f64::NAN, 0.0, 0.0);
    assert_eq!(knot_determinant(&[p, nan, p]), Err(TopologyError::NonFinite(1)));
    let ring = [Vector3::x(), p, Vector3::x()];
    assert_eq!(knot_determinant(&ring), Err(TopologyError::DegenerateAxis));
    assert_eq!(
        determinant_along(&circle(), &Vector3::zeros()),
        Err(TopologyError::InvalidDirection)
    );
    // The circle seen edge-on is degenerate.
    assert_eq!(
        determinant_along(&circle(), &Vector3::x()),
        Err(TopologyError::DegenerateProjection)
    );
    assert_eq!(expected_determinant(1), 3);
    assert_eq!(expected_determinant(4), 9);
}

#[test]
fn determinant_of_a_301_node_knot_takes_microseconds() {
    let shape = build(&KnotSpec::paper(3)).unwrap();
    assert_eq!(shape.points.len(), 301);
    let mut times: Vec<Duration> = (0..21)
        .map(|_| {
            let start = Instant::now();
            assert_eq!(knot_determinant(&shape.points), Ok(7));
            start.elapsed()
        })
        .collect();
    times.sort();
    assert!(times[10] < Duration::from_millis(5), "median {:?}", times[10]);
}

/// Distance between segments `[p0, p1]` and `[q0, q1]`: the minimum of the
/// interior critical point and the four endpoint-to-segment distances.
fn segment_distance(p0: &Vector3<f64>, p1: &Vector3<f64>, q0: &Vector3<f64>, q1: &Vector3<f64>) -> f64 {
    let point_segment = |x: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>| {
        let d = b - a;
        let t = ((x - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
        (a + t * d - x).norm()
    };
    let mut best = point_segment(p0, q0, q1)
        .min(point_segment(p1, q0, q1))
        .min(point_segment(q0, p0, p1))
        .min(point_segment(q1, p0, p1));
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, b, c, d, e) = (d1.dot(&d1), d1.dot(&d2), d2.dot(&d2), d1.dot(&r), d2.dot(&r));
    let denom = a * c - b * b;
    if denom > 1e-12 * a * c {
        let s = (b * e - c * d) / denom;
        let t = (a * e - b * d) / denom;
        if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
            best = best.min((p0 + s * d1 - q0 - t * d2).norm());
        }
    }
    best
}

/// Smallest distance between segments whose indices differ by more than
/// `ceil(2h / edge) + 1`.
fn min_non_neighbour_distance(points: &[Vector3<f64>], h: f64, edge: f64) -> f64 {
    let gap = (2.0 * h / edge).ceil() as usize + 1;
    let segments = points.len() - 1;
    let mut best = f64::INFINITY;
    for i in 0..segments {
        for j in i + gap + 1..segments {
            best = best.min(segment_distance(
                &points[i],
                &points[i + 1],
                &points[j],
                &points[j + 1],
            ));
        }
    }
    best
}

/// Every property the issue asks of a built knot.
fn check_shape(spec: &KnotSpec, shape: &KnotShape) {
    let label = format!(
        "n={} L={} K={} h={}",
        spec.n, spec.length, spec.nodes, spec.radius
    );
    let (p, k, length, h) = (&shape.points, spec.nodes, spec.length, spec.radius);
    assert_eq!(p.len(), k, "{label}");
    let edges: Vec<f64> = p.windows(2).map(|w| (w[1] - w[0]).norm()).collect();
    let total: f64 = edges.iter().sum();
    assert!((total - length).abs() <= 1e-9 * length, "{label}: length {total}");
    let edge = length / (k - 1) as f64;
    assert!((shape.edge_length - edge).abs() <= 1e-15 * length);
    for (i, e) in edges.iter().enumerate() {
        assert!(
            (e - edge).abs() <= 1e-6 * edge,
            "{label}: edge {i} = {e}, expected {edge}"
        );
    }
    // Clamped end edges on the x axis, pointing outward.
    for i in [0, 1, k - 2, k - 1] {
        assert!(
            p[i].y.abs() <= 1e-12 * length && p[i].z.abs() <= 1e-12 * length,
            "{label}: node {i} {:?}",
            p[i]
        );
    }
    assert!(p[1].x > p[0].x && p[k - 1].x > p[k - 2].x, "{label}");
    assert!((shape.clamp_span - (p[k - 1].x - p[0].x)).abs() <= 1e-15 * length);
    let clearance = min_non_neighbour_distance(p, h, edge);
    assert!(clearance >= 2.0 * h, "{label}: clearance {clearance} < 2h");
    assert_eq!(knot_determinant(p), Ok(2 * u64::from(spec.n) + 1), "{label}");
    // Regions partition the nodes in rod order and match the designed lengths.
    let r = &shape.regions;
    let parts = [&r.tail_a, &r.braid_a, &r.loop_arc, &r.braid_b, &r.tail_b];
    assert_eq!(parts[0].start, 0);
    assert_eq!(parts[4].end, k);
    for w in parts.windows(2) {
        assert_eq!(w[0].end, w[1].start, "{label}");
    }
    let lengths = [
        shape.tail_length,
        shape.pass_length,
        shape.loop_length,
        shape.pass_length,
        shape.tail_length,
    ];
    for (part, expected) in parts.iter().zip(lengths) {
        let got = part.len() as f64 * edge;
        assert!(
            (got - expected).abs() <= 2.0 * edge,
            "{label}: region {part:?} vs {expected}"
        );
    }
    let designed = 2.0 * (shape.tail_length + shape.pass_length) + shape.loop_length;
    assert!(
        (designed - length).abs() <= 1e-2 * length,
        "{label}: designed length {designed}"
    );
}

#[test]
fn built_knots_close_to_torus_knots_with_exact_geometry() {
    let cases = [
        (1.0, 301, 1.6e-3),
        (1.0, 301, 3.4e-3),
        (1.0, 201, 1.6e-3),
        (1.0, 201, 3.4e-3),
        (1.0, 401, 1.6e-3),
        (1.0, 401, 3.4e-3),
        (0.5, 301, 1.0e-3),
        (2.0, 601, 5.0e-3),
    ];
    for (length, nodes, radius) in cases {
        for n in 1..=8 {
            let spec = KnotSpec {
                length,
                nodes,
                radius,
                ..KnotSpec::paper(n)
            };
            let shape = build(&spec).unwrap_or_else(|e| panic!("n={n} L={length} K={nodes} h={radius}: {e}"));
            check_shape(&spec, &shape);
        }
    }
}

#[test]
fn defaults_follow_the_paper_relaxed_shapes() {
    // Strand length per braid pass, loop length (L = 1 m, h = 1.6 mm).
    let paper = [(0.12, 0.60), (0.19, 0.47), (0.24, 0.41), (0.28, 0.34)];
    for (n, (braid, loop_length)) in (1..=4).zip(paper) {
        let shape = build(&KnotSpec::paper(n)).unwrap();
        assert!((shape.pass_length - braid).abs() < 1e-12, "n={n}");
        assert!((shape.loop_length - loop_length).abs() < 1e-12, "n={n}");
        assert!(
            (0.27..=0.33).contains(&shape.clamp_span),
            "n={n}: {}",
            shape.clamp_span
        );
    }
    for n in 5..=8 {
        let (shorter, longer) = (
            build(&KnotSpec::paper(n - 1)).unwrap(),
            build(&KnotSpec::paper(n)).unwrap(),
        );
        assert!(longer.pass_length > shorter.pass_length && longer.loop_length < shorter.loop_length);
    }
}

#[test]
fn explicit_parameters_are_honoured() {
    let spec = KnotSpec {
        clamp_span: Some(0.29),
        pass_length: Some(0.25),
        loop_length: Some(0.42),
        ..KnotSpec::paper(3)
    };
    let shape = build(&spec).unwrap();
    check_shape(&spec, &shape);
    assert!((shape.clamp_span - 0.29).abs() < 1e-9);
    assert_eq!(shape.pass_length, 0.25);
    assert_eq!(shape.loop_length, 0.42);
    assert!((shape.tail_length - (1.0 - 0.5 - 0.42) / 2.0).abs() < 1e-3);
}

#[test]
fn build_is_deterministic_and_serialisable() {
    let spec = KnotSpec::paper(2);
    let shape = build(&spec).unwrap();
    assert!(build(&spec).unwrap() == shape, "bitwise identical rebuild");
    let json = serde_json::to_string(&shape).unwrap();
    let back: KnotShape = serde_json::from_str(&json).unwrap();
    assert_eq!(back.regions, shape.regions);
    assert!(
        back.points
            .iter()
            .zip(&shape.points)
            .all(|(a, b)| (a - b).norm() <= 1e-15)
    );
    assert!((back.helix_radius - shape.helix_radius).abs() <= 1e-18);
    let parsed: KnotSpec =
        serde_json::from_str(r#"{"n": 2, "length": 1.0, "nodes": 301, "radius": 0.0016}"#).unwrap();
    assert_eq!(parsed, spec);
}

#[test]
fn impossible_inputs_are_rejected() {
    let paper = KnotSpec::paper(3);
    let with = |f: &dyn Fn(&mut KnotSpec)| {
        let mut spec = paper.clone();
        f(&mut spec);
        build(&spec).unwrap_err()
    };
    assert_eq!(with(&|s| s.n = 0), KnotError::Passes(0));
    assert_eq!(with(&|s| s.n = 9), KnotError::Passes(9));
    assert!(matches!(
        with(&|s| s.length = -1.0),
        KnotError::InvalidParameter { name: "length", .. }
    ));
    assert!(matches!(
        with(&|s| s.radius = f64::NAN),
        KnotError::InvalidParameter { name: "radius", .. }
    ));
    assert!(matches!(
        with(&|s| s.clamp_span = Some(0.0)),
        KnotError::InvalidParameter {
            name: "clamp_span",
            ..
        }
    ));
    assert!(matches!(with(&|s| s.radius = 0.02), KnotError::RadiusTooLarge { max, .. } if max == 0.02));
    let KnotError::TooFewNodes { min, .. } = with(&|s| s.nodes = 101) else {
        panic!("too few nodes")
    };
    // The reported minimum is enough.
    build(&KnotSpec {
        nodes: min,
        ..paper.clone()
    })
    .unwrap();
    assert!(matches!(with(&|s| s.nodes = 2), KnotError::TooFewNodes { .. }));
    assert!(matches!(
        with(&|s| s.pass_length = Some(0.05)),
        KnotError::BraidTooShort { .. }
    ));
    assert!(matches!(
        with(&|s| s.loop_length = Some(0.6)),
        KnotError::TailsTooShort { .. }
    ));
    assert!(matches!(
        with(&|s| s.loop_length = Some(0.05)),
        KnotError::Infeasible { .. }
    ));
    let KnotError::EndToEndOutOfRange { min, max, .. } = with(&|s| s.clamp_span = Some(0.6)) else {
        panic!("end-to-end out of range")
    };
    assert!(min < max && max < 0.6);
    for l in [min, 0.5 * (min + max), max] {
        let spec = KnotSpec {
            clamp_span: Some(l),
            ..paper.clone()
        };
        let shape = build(&spec).unwrap_or_else(|e| panic!("end-to-end {l} in [{min}, {max}]: {e}"));
        assert!((shape.clamp_span - l).abs() < 1e-9);
    }
    // Thick rods leave no room for many passes.
    assert!(matches!(
        build(&KnotSpec {
            radius: 0.012,
            ..KnotSpec::paper(8)
        }),
        Err(KnotError::Infeasible { .. })
    ));
}

/// Segments `j` whose xy projection crosses that of segment `i`, with the
/// crossing's parameters along `i` and `j`.
fn xy_crossings(p: &[Vector3<f64>], i: usize) -> Vec<(usize, f64, f64)> {
    let cross = |a: Vector3<f64>, b: Vector3<f64>| a.x * b.y - a.y * b.x;
    let (a, r) = (p[i], p[i + 1] - p[i]);
    (0..p.len() - 1)
        .filter(|&j| j + 1 < i || j > i + 1)
        .filter_map(|j| {
            let (b, v) = (p[j], p[j + 1] - p[j]);
            let denom = cross(r, v);
            let t = cross(b - a, v) / denom;
            let s = cross(b - a, r) / denom;
            ((0.0..1.0).contains(&t) && (0.0..1.0).contains(&s)).then_some((j, t, s))
        })
        .collect()
}

#[test]
fn flipping_one_braid_crossing_changes_the_determinant() {
    for n in 1..=8 {
        let shape = build(&KnotSpec::paper(n)).unwrap();
        let mut p = shape.points.clone();
        let (braid_a, braid_b) = (&shape.regions.braid_a, &shape.regions.braid_b);
        // The crossing (seen along z) of strand A with strand B nearest the
        // middle of the braid among those whose two neighbouring segments on
        // either side cross nothing.
        let middle = (braid_a.start + braid_a.end) / 2;
        let (i, j, t, s) = (braid_a.start + 2..braid_a.end - 2)
            .filter_map(|i| {
                let quiet = [i - 2, i - 1, i + 1, i + 2]
                    .iter()
                    .all(|&k| xy_crossings(&p, k).is_empty());
                match xy_crossings(&p, i)[..] {
                    [(j, t, s)] if quiet && braid_b.contains(&j) => Some((i, j, t, s)),
                    _ => None,
                }
            })
            .min_by_key(|&(i, ..)| i.abs_diff(middle))
            .expect("a braid crossing");
        let za = p[i].z + t * (p[i + 1].z - p[i].z);
        let zb = p[j].z + s * (p[j + 1].z - p[j].z);
        // Move segments i-1..=i+1 of strand A along z to the other side of
        // strand B: the diagram is unchanged but for this one crossing.
        let shift = (zb - za) + (zb - za).signum() * 4.0 * shape.helix_radius;
        for node in &mut p[i - 1..=i + 2] {
            node.z += shift;
        }
        let det = knot_determinant(&p).unwrap();
        assert_eq!(
            det,
            2 * u64::from(n) - 1,
            "n={n}: T(2, 2n+1) with a crossing flipped is T(2, 2n-1)"
        );
        assert_ne!(det, expected_determinant(n));
    }
}

/// Defect 15.11: the coarsest mesh the builder accepts for n = 3 (K = 158:
/// edges of at most 4h) holds its knot type through a whole pull at
/// mu = 0.2, and one node fewer is refused with the minimum in the message.
#[test]
fn the_coarsest_accepted_mesh_keeps_its_knot_through_the_pull() {
    use solver::case::CaseParams;
    use solver::protocol::{self, Status};
    let coarse = CaseParams {
        nodes: Some(158),
        mu: 0.2,
        ..CaseParams::default()
    };
    let report = protocol::run(&coarse, &mut |_| true);
    assert_eq!(report.status, Status::Completed, "{}", report.reason);
    assert_eq!(report.determinant_final, Some(7));
    assert!(report.inversion.is_some());
    let errors = CaseParams {
        nodes: Some(157),
        ..coarse
    }
    .validate()
    .unwrap_err();
    assert!(
        errors
            .iter()
            .any(|e| e.field == "nodes" && e.reason.contains("need 158")),
        "{errors:?}"
    );
}
