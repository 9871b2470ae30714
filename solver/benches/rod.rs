//! Rod benchmarks at K = 301: assembly, one Newton iteration, one time step.
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Vector3;
use solver::energies::{self, BANDWIDTH, Terms};
use solver::external::Environment;
use solver::linalg::banded::{BandedLdlt, BandedSym};
use solver::material::Material;
use solver::rod::{End, Rod};
use solver::stepper::{NewtonOptions, Stepper};
use std::hint::black_box;

/// A 1 m rod of K = 301 nodes (paper's h = 1.6 mm) bent into a helix-like arc, clamped at both ends.
fn bent_rod() -> Rod {
    let k = 301;
    let nodes: Vec<Vector3<f64>> = (0..k)
        .map(|i| {
            let s = i as f64 / (k - 1) as f64;
            let a = 3.0 * s;
            Vector3::new(0.3 * a.sin(), 0.3 * (1.0 - a.cos()), 0.05 * s)
        })
        .collect();
    let mut rod = Rod::new(&nodes, 1.6e-3, Material::default()).expect("valid rod");
    rod.clamp(End::Start);
    rod.clamp(End::Finish);
    rod
}

fn benches(c: &mut Criterion) {
    let rod = bent_rod();
    let n = rod.ndof();
    let mut grad = vec![0.0; n];
    let mut hess = BandedSym::new(n, BANDWIDTH);
    let mut ldlt = BandedLdlt::with_capacity(n, BANDWIDTH);
    let mut rhs = vec![0.0; n];

    c.bench_function("rod/assembly_energy_grad_hess/K301", |b| {
        b.iter(|| energies::evaluate(black_box(&rod), Terms::ALL, &mut grad, Some(&mut hess)))
    });

    let mut moving = rod.clone();
    let dt = 1e-3;
    c.bench_function("rod/newton_iteration/K301", |b| {
        b.iter(|| {
            moving.update_geometry();
            energies::evaluate(&moving, Terms::ALL, &mut grad, Some(&mut hess));
            for j in 0..n {
                hess.add_diagonal(j, moving.mass[j] / (dt * dt));
                rhs[j] = -grad[j];
                if moving.fixed[j] {
                    hess.constrain(j);
                    rhs[j] = 0.0;
                }
            }
            ldlt.factor(&hess).expect("definite");
            ldlt.solve_in_place(&mut rhs);
            black_box(&rhs);
        })
    });

    c.bench_function("rod/time_step_bent_relaxing/K301", |b| {
        b.iter_batched_ref(
            || (rod.clone(), Stepper::new(&rod, NewtonOptions::default())),
            |(r, s)| {
                s.step(r, &Environment::default(), None, dt)
                    .expect("step converges")
            },
            criterion::BatchSize::LargeInput,
        )
    });
}

criterion_group!(rod, benches);
criterion_main!(rod);
