//! Simplified-model benchmarks: one energy landscape (100 angles, paper Fig. 13 a, b)
//! and one bifurcation diagram (Fig. 13 c) at the paper's parameters.
use criterion::{Criterion, criterion_group, criterion_main};
use solver::simplified::{BifurcationSpec, LandscapeSpec, bifurcation, landscape};
use std::hint::black_box;
use std::time::Duration;

fn benches(c: &mut Criterion) {
    let spec = LandscapeSpec::default();
    c.bench_function("simplified/landscape_100_points/n3_lk137.5", |b| {
        b.iter(|| landscape(black_box(&spec)).expect("landscape"))
    });
    let spec = BifurcationSpec::default();
    let mut group = c.benchmark_group("simplified");
    group.measurement_time(Duration::from_secs(12));
    group.bench_function("bifurcation_diagram/n3", |b| {
        b.iter(|| bifurcation(black_box(&spec)).expect("diagram"))
    });
    group.finish();
}

criterion_group! {
    name = simplified;
    config = Criterion::default().sample_size(10);
    targets = benches
}
criterion_main!(simplified);
