//! Bends: two rods tied loose and contact-free, their diagrams told apart by
//! their crossings, their symmetry, and the case parameters that choose them.
use nalgebra::Vector3;
use solver::case::{CaseParams, InitialShape, KnotKind};
use solver::knot::{Bend, BendSpec, StartShape};
use solver::rod::End;

/// The bends tied as two interlocked bights (the fisherman's: tests/fisherman.rs).
const BENDS: [Bend; 4] = [Bend::Reef, Bend::Granny, Bend::Thief, Bend::Grief];

/// Runs a case that must complete (a slipped bend completes).
fn completed(params: &CaseParams) -> solver::protocol::CaseReport {
    let report = solver::protocol::run(params, &mut |_| true);
    assert_eq!(
        report.status,
        solver::protocol::Status::Completed,
        "{}",
        report.reason
    );
    report
}

/// The reef knot's case at friction `mu`, the other parameters the defaults.
fn reef(mu: f64) -> CaseParams {
    CaseParams {
        knot: KnotKind::Reef,
        mu,
        ..CaseParams::default()
    }
}

fn tie(bend: Bend) -> (BendSpec, StartShape) {
    let spec = BendSpec {
        bend,
        length: 1.0,
        nodes: 301,
        radius: 1.6e-3,
    };
    let shape = spec.tie().unwrap_or_else(|e| panic!("{bend:?}: {e}"));
    (spec, shape)
}

/// Closest distance between segments `p0 p1` and `q0 q1` (sampled finely:
/// an independent check of the builder's broad-phase clearance test).
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

/// Each bend: two rods of K nodes and rest length L, clamped at their first
/// nodes on either side of the knot, no two strands of different rods
/// within 2h, and close where they cross: within 2 LIFT = 3.6 h.
#[test]
fn bends_are_tied_loose_and_contact_free() {
    for bend in BENDS {
        let (spec, shape) = tie(bend);
        assert_eq!(shape.rods.len(), 2);
        assert!(shape.alexander.is_none(), "a bend has no Alexander polynomial");
        for rod in &shape.rods {
            assert_eq!(rod.len(), spec.nodes);
            let edge = spec.length / (spec.nodes - 1) as f64;
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
        assert!(
            a.x < -0.3 && b.x > 0.3,
            "{bend:?}: standing ends on either side: {a:?} {b:?}"
        );
        let (r0, r1) = (&shape.rods[0], &shape.rods[1]);
        let near = |p: &Vector3<f64>, q: &Vector3<f64>| (p - q).norm() < 0.05;
        let mut closest = f64::INFINITY;
        for i in 0..r0.len() - 1 {
            for j in 0..r1.len() - 1 {
                if near(&r0[i], &r1[j]) {
                    closest = closest.min(segment_distance(&r0[i], &r0[i + 1], &r1[j], &r1[j + 1]));
                }
            }
        }
        let h = spec.radius;
        assert!(
            closest >= 2.0 * h && closest < 3.6 * h,
            "{bend:?}: closest {} h",
            closest / h
        );
    }
}

/// The rods' crossings seen along z: sign +1 where the upper strand's
/// direction turns counter-clockwise onto the lower's.
fn crossing_signs(shape: &StartShape) -> Vec<f64> {
    let (a, b) = (&shape.rods[0], &shape.rods[1]);
    let mut signs = Vec::new();
    for i in 0..a.len() - 1 {
        for j in 0..b.len() - 1 {
            let (d, e, r) = (a[i + 1] - a[i], b[j + 1] - b[j], b[j] - a[i]);
            let den = d.x * e.y - d.y * e.x;
            if den.abs() < 1e-18 {
                continue;
            }
            let s = (r.x * e.y - r.y * e.x) / den;
            let t = (r.x * d.y - r.y * d.x) / den;
            if !((0.0..1.0).contains(&s) && (0.0..1.0).contains(&t)) {
                continue;
            }
            let (za, zb) = (a[i].z + s * d.z, b[j].z + t * e.z);
            let (upper, lower) = if za > zb { (d, e) } else { (e, d) };
            signs.push((upper.x * lower.y - upper.y * lower.x).signum());
        }
    }
    signs
}

/// The diagrams: six crossings between the rods; the reef's and thief's
/// signs sum to zero (the square knot is a knot and its mirror), the
/// granny's and grief's all agree (the rods twist about each other).
#[test]
fn crossing_signs_tell_the_reef_from_the_granny() {
    for bend in BENDS {
        let (_, shape) = tie(bend);
        let signs = crossing_signs(&shape);
        assert_eq!(signs.len(), 6, "{bend:?}");
        let sum: f64 = signs.iter().sum();
        match bend {
            Bend::Reef | Bend::Thief => assert_eq!(sum, 0.0, "{bend:?}: {signs:?}"),
            Bend::Granny | Bend::Grief => assert_eq!(sum.abs(), 6.0, "{bend:?}: {signs:?}"),
            Bend::Fisherman => unreachable!("not among BENDS: tests/fisherman.rs"),
        }
    }
}

/// The reef and granny are symmetric under a half turn about the y axis,
/// which swaps the rods node by node; the thief and grief pull rod 1 by the
/// other end: the same curves, rod 1 read backwards.
#[test]
fn the_reef_and_granny_swap_their_rods_under_a_half_turn() {
    for bend in [Bend::Reef, Bend::Granny] {
        let (spec, shape) = tie(bend);
        let turned = shape.rods[0].iter().map(|p| Vector3::new(-p.x, p.y, -p.z));
        let worst = turned
            .zip(&shape.rods[1])
            .map(|(p, q)| (p - q).norm())
            .fold(0.0, f64::max);
        assert!(worst < 1e-9 * spec.length, "{bend:?}: {worst}");
    }
    for (pulled, by_other_end) in [(Bend::Reef, Bend::Thief), (Bend::Granny, Bend::Grief)] {
        let (_, a) = tie(pulled);
        let (_, b) = tie(by_other_end);
        assert_eq!(a.rods[0], b.rods[0]);
        let standing = b.clamp_points()[1];
        assert!(standing.y > 0.0 && a.clamp_points()[1].y < 0.0);
        // Rod 1's tail end in the reef is near where the thief's is pulled from.
        let tail = a.rods[1][a.rods[1].len() - 1];
        assert!((tail.y - standing.y).abs() < 1e-9, "{tail:?} {standing:?}");
    }
}

/// A bend is chosen by `knot`; its case refuses the one-rod knot's
/// parameters, a start twist and rotating or soft stages, naming the field.
#[test]
fn bend_cases_are_checked_naming_the_field() {
    let reef = CaseParams {
        knot: KnotKind::Reef,
        ..CaseParams::default()
    };
    assert!(reef.validate().is_ok(), "{:?}", reef.validate());
    assert_eq!(reef.knot_label(), "reef");
    assert_eq!(reef.rest_length(), 2.0 * reef.length);
    assert_eq!(reef.tight_force_bar(), solver::case::BEND_TIGHT_FORCE_BAR);
    let field = |p: CaseParams| p.validate().unwrap_err()[0].field.clone();
    assert_eq!(field(CaseParams { n: 4, ..reef.clone() }), "n");
    assert_eq!(
        field(CaseParams {
            start_twist: Some(1.0),
            ..reef.clone()
        }),
        "start_twist"
    );
    let rotate: Vec<solver::case::LoadStage> =
        serde_json::from_str(r#"[{"rotate": {"turns": 1}}, {"pull": {}}]"#).unwrap();
    assert_eq!(
        field(CaseParams {
            loading: Some(rotate),
            ..reef.clone()
        }),
        "loading"
    );
    assert_eq!(
        field(CaseParams {
            initial_shape: Some(vec![[0.0; 3]; 3].into()),
            ..reef.clone()
        }),
        "initial_shape"
    );
    assert_eq!(field(CaseParams { length: 0.2, ..reef }), "length");
}

/// The reef knot pulled by its standing ends (mu = 0.2): the two clamps pull
/// alike at every sample, while they set the knot, while they ease it and
/// once its tails are free (within 1 % where either pulls more than F bar
/// 0.001, a twenty-fifth of the setting load), and the two rods, which a
/// half turn swaps, hold the same energy at every sample where they hold any
/// (within 2 % where a rod's energy is above a tenth of the largest); F bar
/// is the clamps' mean throughout. The case completes with the rods parted
/// or tight, its holding force the largest F bar with the tails free, which
/// are let go once the set knot has been eased.
#[test]
fn the_reef_pulls_symmetrically_and_reports_its_holding_force() {
    let params = CaseParams {
        knot: KnotKind::Reef,
        mu: 0.2,
        ..CaseParams::default()
    };
    let report = completed(&params);
    assert_eq!(report.bend_series.len(), report.series.len());
    let setting = 0.5 * solver::case::BEND_TIGHT_FORCE_BAR;
    // The set: the last sample before the clamps turn back to ease the knot
    // (met at a step, so the sample averages up to it).
    let set = (1..report.series.len())
        .find(|&i| report.series[i].l_k_bar > report.series[i - 1].l_k_bar)
        .expect("the clamps turn back to ease the set knot")
        - 1;
    assert!(
        report.series[set].f_bar >= 0.9 * setting,
        "set at F bar {}",
        report.series[set].f_bar
    );
    let largest_energy = (report.bend_series.iter())
        .map(|b| b.energy_bar[0].max(b.energy_bar[1]))
        .fold(0.0, f64::max);
    let (mut clamps, mut energies) = (0.0f64, 0.0f64);
    for (s, b) in report.series.iter().zip(&report.bend_series) {
        let [f0, f1] = b.f_bar;
        assert!((0.5 * (f0 + f1) - s.f_bar).abs() <= 1e-9 * s.f_bar.abs() + 1e-12);
        if f0.abs().max(f1.abs()) > setting / 25.0 {
            let apart = (f0 - f1).abs() / f0.abs().max(f1.abs());
            assert!(apart <= 0.01, "at {}: {f0} {f1}", s.l_k_bar);
            clamps = clamps.max(apart);
        }
        let [e0, e1] = b.energy_bar;
        if e0.max(e1) > 0.1 * largest_energy {
            let apart = (e0 - e1).abs() / e0.max(e1);
            assert!(apart <= 0.02, "at {}: {e0} {e1}", s.l_k_bar);
            energies = energies.max(apart);
        }
    }
    eprintln!(
        "the clamps' F bar within {:.2} %, the rods' energies within {:.2} %",
        100.0 * clamps,
        100.0 * energies
    );
    let holding = report
        .holding_force_bar
        .expect("a bend reports its holding force");
    let free_largest = (report.series.iter().zip(&report.bend_series))
        .filter(|(_, b)| b.tails_free)
        .map(|(s, _)| s.f_bar)
        .fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(holding, free_largest);
    let slipped = report
        .events
        .iter()
        .any(|e| e.kind == solver::protocol::EventKind::SlipThrough);
    assert_eq!(report.tied, Some(!slipped));
    assert!(report.alexander_initial.is_none() && report.determinant_final.is_none());
    // Eased, let go: the tails are let go once the knot has been eased
    // below a fifth of the setting load (the eased load, a tenth, is met at
    // a step; the sample averages the easing's last stretch); no snap is
    // read before.
    let freed = (report.bend_series.iter().position(|b| b.tails_free)).expect("the tails are let go");
    assert!(set < freed, "set at sample {set}, let go at {freed}");
    let eased = report.series[freed - 1];
    assert!(
        eased.f_bar < 0.2 * setting,
        "set at l_k bar {}, let go at F bar {}",
        report.series[set].l_k_bar,
        eased.f_bar
    );
    for snap in (report.events.iter()).filter(|e| e.kind == solver::protocol::EventKind::Snap) {
        assert!(
            snap.at.sample >= freed,
            "a snap before the tails are let go: {snap:?}"
        );
    }
}

/// docs/validation/starts/reef.json, the start shape docs/API.md's command
/// reads, is the builder's reef at the defaults written out: read back, it
/// is the same start (`UPDATE_DOCS=1` rewrites it).
#[test]
fn documented_reef_start_is_the_builders() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/validation/starts/reef.json");
    let params = CaseParams {
        knot: KnotKind::Reef,
        ..CaseParams::default()
    };
    let built = params.validated().unwrap();
    if std::env::var_os("UPDATE_DOCS").is_some() {
        let text = serde_json::to_string(&InitialShape::from(built.start())).unwrap();
        std::fs::write(&path, text + "\n").unwrap();
    }
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let read = CaseParams {
        initial_shape: Some(serde_json::from_str(&text).unwrap()),
        ..params
    }
    .validated()
    .unwrap();
    assert_eq!(read.start(), built.start());
}

/// Sampling observes and does not steer: under the reference pull the reef
/// (mu = 0.3) is set, eased and let go at the same step whether it is
/// sampled every 0.5 or every 0.25 in l_k bar (the set met at a step, the
/// easing ended at one), so its set snapshot and the first sample with its
/// tails free lie at the same l_k bar and time.
#[test]
fn the_sampling_does_not_move_where_a_bend_is_set_and_let_go() {
    let run = |sample_interval: f64| {
        let params = CaseParams {
            knot: KnotKind::Reef,
            mu: 0.3,
            protocol: solver::case::Protocol::Reference,
            pull_speed: Some(0.05),
            min_l_k_bar: 150.0,
            sample_interval,
            ..CaseParams::default()
        };
        let report = completed(&params);
        let set = (report.snapshots.iter())
            .find(|s| s.label == solver::snapshot::SnapshotLabel::Set)
            .map(|s| (s.l_k_bar, s.time))
            .expect("a set snapshot");
        let freed = (report.bend_series.iter().position(|b| b.tails_free)).expect("the tails are let go");
        let held = report.series[freed - 1];
        (set, (held.l_k_bar, held.time))
    };
    let (coarse, fine) = (run(0.5), run(0.25));
    assert_eq!(
        coarse, fine,
        "set and let go (l_k bar, s) at sample intervals 0.5 and 0.25"
    );
}

/// The adaptive pull reads a bend's holding force as the reference pull
/// does: it goes back to before the set and pulls through the setting's
/// end, the release and the holding point at `pull_speed`. The reef at mu =
/// 0.2 (K = 301) holds 0.00373 against the reference pull's 0.00377 (the
/// fast approach's own reading, before physics revision 22: 0.00367).
#[test]
fn the_adaptive_pull_reads_a_bends_holding_force_as_the_reference_pull() {
    let hold = |protocol| {
        let report = completed(&CaseParams {
            protocol,
            ..reef(0.2)
        });
        assert_eq!(report.tied, Some(false), "the reef at mu = 0.2 comes undone");
        report.holding_force_bar.expect("a holding force")
    };
    let (adaptive, reference) = (
        hold(solver::case::Protocol::Adaptive),
        hold(solver::case::Protocol::Reference),
    );
    assert!(
        (adaptive / reference - 1.0).abs() <= 0.02,
        "holding force: adaptive {adaptive}, reference {reference}"
    );
}

/// `eased_force_bar` sets how far a set bend is eased before its tails are
/// let go: the reef (mu = 0.2) eased to F bar 0.001 lets its tails go under
/// less than twice that (each end stops moving back once it pulls less; the
/// sample averages the easing's last stretch), below the default's eased
/// load, and further back (the ends have moved further towards the knot).
#[test]
fn a_bend_is_let_go_at_the_eased_load_it_is_given() {
    let release = |eased_force_bar| {
        let report = completed(&CaseParams {
            eased_force_bar,
            ..reef(0.2)
        });
        let freed = (report.bend_series.iter().position(|b| b.tails_free)).expect("the tails are let go");
        report.series[freed - 1]
    };
    let (low, default) = (release(Some(0.001)), release(None));
    assert!(low.f_bar < 0.002, "let go at F bar {}", low.f_bar);
    assert!(
        low.f_bar < default.f_bar,
        "{} against {}",
        low.f_bar,
        default.f_bar
    );
    assert!(
        low.l_k_bar > default.l_k_bar,
        "{} against {}",
        low.l_k_bar,
        default.l_k_bar
    );
}

/// A bend that springs open flings its rods apart, still bending as they
/// vibrate: the reef at mu = 0.2 is found parted at the first sample whose
/// rods are nowhere within a diameter of each other, not once they have
/// straightened (docs/FIDELITY.md, Left open). Checked against the final
/// shape's node distances (a segment lies within half an edge of a node,
/// so the rods' surfaces are at least the nodes' distance less an edge and
/// 2h apart) and the rods' energies, above the straightness rule's 0.02
/// EI / h when they are found parted.
#[test]
fn a_bend_flung_apart_is_parted_while_its_rods_still_bend() {
    let params = reef(0.2);
    let report = completed(&params);
    assert_eq!(report.tied, Some(false));
    let parted = (report.bend_series.iter().position(|b| b.apart)).expect("the rods part");
    assert_eq!(parted + 1, report.series.len(), "the case ends where they part");
    let [e0, e1] = report.bend_series[parted].energy_bar;
    assert!(e0.max(e1) > 0.02, "still bending: {e0} {e1}");
    let last = report.snapshots.last().expect("a final snapshot");
    let split = last.rods[0];
    let (h, edge) = (params.h, params.length / (split - 1) as f64);
    let node = |p: &[f64; 3]| Vector3::from(*p);
    let gap = (last.points[..split].iter())
        .flat_map(|p| {
            last.points[split..]
                .iter()
                .map(move |q| (node(p) - node(q)).norm())
        })
        .fold(f64::INFINITY, f64::min);
    assert!(
        gap - edge - 2.0 * h > 2.0 * h,
        "surfaces {} h apart at most",
        (gap - edge) / h - 2.0
    );
}
