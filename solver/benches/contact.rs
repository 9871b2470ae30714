//! Contact benchmarks (Sec. 3.2): broad phase on a tight knotted rod and a
//! Gauss-Seidel solve of its ~100 contacts, beside the accelerated projected
//! gradient (APGD) on the same problems.

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Vector3;
use solver::contact::apgd::Apgd;
use solver::contact::broad_phase::{BroadPhase, Segment, neighbour_gap};
use solver::contact::gauss_seidel::GaussSeidel;
use solver::contact::{ContactPoint, GaussSeidelOptions, MassProblem};
use std::f64::consts::TAU;
use std::hint::black_box;

/// Rod radius giving ~100 segment pairs within `2r` on the knot below.
const RADIUS: f64 = 0.2;
const NODES: usize = 301;

/// Open (2, 7) torus-knot rod: 90% of the closed curve, so the ends are apart.
fn knot() -> Vec<Vector3<f64>> {
    (0..NODES)
        .map(|k| {
            let phi = 0.9 * TAU * k as f64 / (NODES - 1) as f64;
            let rho = 1.5 + 0.5 * (7.0 * phi).cos();
            Vector3::new(
                rho * (2.0 * phi).cos(),
                rho * (2.0 * phi).sin(),
                -0.5 * (7.0 * phi).sin(),
            )
        })
        .collect()
}

fn segments(x: &[Vector3<f64>]) -> Vec<Segment> {
    x.windows(2)
        .enumerate()
        .map(|(index, w)| Segment {
            a: w[0],
            b: w[1],
            radius: RADIUS,
            body: 0,
            index,
        })
        .collect()
}

fn bench_contact(c: &mut Criterion) {
    let x = knot();
    let segs = segments(&x);
    let gaps = [neighbour_gap(2.0 * RADIUS, (x[1] - x[0]).norm())];
    let mut bp = BroadPhase::new();
    let contacts: Vec<ContactPoint> = bp
        .find_pairs(&segs, &gaps, 0.0)
        .expect("valid knot")
        .iter()
        .filter_map(|p| ContactPoint::from_pair([p.i, p.i + 1, p.j, p.j + 1], &p.closest, 2.0 * RADIUS, 0.1))
        .collect();

    c.bench_function(&format!("broad_phase/knot_{NODES}_nodes"), |b| {
        b.iter(|| black_box(bp.find_pairs(black_box(&segs), &gaps, 0.0).map(|p| p.len())))
    });

    let inv_mass = vec![1.0; NODES];
    let v_free: Vec<_> = x.iter().map(|p| Vector3::new(-p.x, -p.y, 0.0)).collect();
    let mut gs = GaussSeidel::new();
    bench_solve(c, &mut gs, "knot", &contacts, &inv_mass, &v_free);
    let (contacts, inv_mass, v_free) = line_contact(60);
    bench_solve(c, &mut gs, "line", &contacts, &inv_mass, &v_free);
}

/// Two strands of `m` segments lying side by side and pressed together, one
/// contact per segment pair: the nearly singular case (forces alternating
/// along the strands move almost no node).
fn line_contact(m: usize) -> (Vec<ContactPoint>, Vec<f64>, Vec<Vector3<f64>>) {
    let contacts = (0..m)
        .map(|c| {
            let s = 0.5 + 0.1 * (0.3 * c as f64).sin();
            let nodes = [c, c + 1, m + 1 + c, m + 2 + c];
            ContactPoint {
                nodes: [nodes, nodes, nodes].concat().try_into().expect("twelve nodes"),
                weights: [1.0 - s, s, s - 1.0, -s, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                width: 4,
                normal: Vector3::z(),
                gap: -1e-4,
                mu: 0.1,
                sliding_direction: Vector3::zeros(),
                spin: [(0, Vector3::zeros()); 2],
            }
        })
        .collect();
    let v_free = (0..2 * (m + 1))
        .map(|k| {
            let side = if k <= m { -1.0 } else { 1.0 };
            Vector3::new(0.01 * (k as f64).cos(), 0.0, side * 0.05)
        })
        .collect();
    (contacts, vec![1.0; 2 * (m + 1)], v_free)
}

/// Cold solves to 1e-8 with plain Gauss-Seidel, with the default
/// over-relaxation and with APGD; prints the sweeps (APGD: products `W r`)
/// each needs.
fn bench_solve(
    c: &mut Criterion,
    gs: &mut GaussSeidel,
    name: &str,
    contacts: &[ContactPoint],
    inv_mass: &[f64],
    v_free: &[Vector3<f64>],
) {
    for relaxation in [1.0, GaussSeidelOptions::default().relaxation] {
        let options = GaussSeidelOptions {
            max_sweeps: 10_000,
            tolerance: 1e-8,
            relaxation,
            ..Default::default()
        };
        let report = gs
            .solve(contacts, inv_mass, v_free, 1e-3, &options, None)
            .expect("valid contacts");
        println!(
            "{name}, {} contacts, omega {relaxation}: {report:?}",
            contacts.len()
        );
        let id = format!(
            "gauss_seidel/{name}_{}_contacts_omega_{relaxation}",
            contacts.len()
        );
        c.bench_function(&id, |b| {
            b.iter(|| {
                black_box(gs.solve(
                    black_box(contacts),
                    inv_mass,
                    black_box(v_free),
                    1e-3,
                    &options,
                    None,
                ))
            })
        });
    }
    let options = GaussSeidelOptions {
        max_sweeps: 10_000,
        tolerance: 1e-8,
        ..Default::default()
    };
    let problem = MassProblem {
        contacts,
        inv_mass,
        v_free,
        spin: None,
        dt: 1e-3,
    };
    let mut apgd = Apgd::new();
    let report = apgd
        .solve_problem(&problem, &options, None)
        .expect("valid contacts");
    println!("{name}, {} contacts, APGD: {report:?}", contacts.len());
    c.bench_function(&format!("apgd/{name}_{}_contacts", contacts.len()), |b| {
        b.iter(|| black_box(apgd.solve_problem(black_box(&problem), &options, None)))
    });
}

criterion_group!(benches, bench_contact);
criterion_main!(benches);
