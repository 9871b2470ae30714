//! Contact benchmarks (Sec. 3.2): broad phase on a tight knotted rod and a
//! Gauss-Seidel solve of its ~100 contacts.

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Vector3;
use solver::contact::broad_phase::{BroadPhase, Segment, neighbour_gap};
use solver::contact::gauss_seidel::{ContactPoint, GaussSeidel, GaussSeidelOptions};
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
    let options = GaussSeidelOptions {
        max_sweeps: 1000,
        tolerance: 1e-8,
        ..Default::default()
    };
    let mut gs = GaussSeidel::new();
    let report = gs
        .solve(&contacts, &inv_mass, &v_free, 1e-3, &options, None)
        .expect("valid contacts");
    println!("{} contacts, cold solve: {report:?}", contacts.len());
    c.bench_function(&format!("gauss_seidel/{}_contacts", contacts.len()), |b| {
        b.iter(|| {
            black_box(gs.solve(
                black_box(&contacts),
                &inv_mass,
                black_box(&v_free),
                1e-3,
                &options,
                None,
            ))
        })
    });
}

criterion_group!(benches, bench_contact);
criterion_main!(benches);
