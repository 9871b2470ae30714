//! Banded LDL^T benchmarks at the DER Newton-system size (K = 301 nodes: n = 4K - 1).
use criterion::{Criterion, criterion_group, criterion_main};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use solver::linalg::banded::{BandedLdlt, BandedSym};
use std::hint::black_box;

const N: usize = 1203;
const KD: usize = 10;
const ID: &str = "n1203_kd10";

/// Random SPD banded matrix (diagonally dominant).
fn spd_banded(n: usize, kd: usize) -> BandedSym {
    let mut rng = StdRng::seed_from_u64(42);
    let mut a = BandedSym::new(n, kd);
    for i in 0..n {
        a.add_diagonal(i, 2.0 * kd as f64 + rng.gen_range(0.5..5.0));
        for j in i.saturating_sub(kd)..i {
            a.add_lower(i, j, rng.gen_range(-1.0..1.0));
        }
    }
    a
}

fn bench_banded(c: &mut Criterion) {
    let a = spd_banded(N, KD);
    let b: Vec<f64> = (0..N).map(|i| (i as f64 * 0.37).sin()).collect();
    let mut ldlt = BandedLdlt::with_capacity(N, KD);
    let mut x = b.clone();

    c.benchmark_group("banded_factor_solve")
        .bench_function(ID, |bench| {
            bench.iter(|| {
                ldlt.factor(black_box(&a)).expect("SPD factor");
                x.copy_from_slice(&b);
                ldlt.solve_in_place(black_box(&mut x));
            })
        });
    c.benchmark_group("banded_factor").bench_function(ID, |bench| {
        bench.iter(|| ldlt.factor(black_box(&a)).expect("SPD factor"))
    });
    ldlt.factor(&a).expect("SPD factor");
    c.benchmark_group("banded_solve").bench_function(ID, |bench| {
        bench.iter(|| {
            x.copy_from_slice(&b);
            ldlt.solve_in_place(black_box(&mut x));
        })
    });
}

criterion_group!(benches, bench_banded);
criterion_main!(benches);
