//! One time step of the paper's n = 3 knot (K = 301, h = 1.6 mm, dt = 1 ms)
//! with its self-contacts: detection, frictional contact solve and the implicit
//! rod step together, as a step in the middle of a pull.
use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use nalgebra::Vector3;
use solver::external::Environment;
use solver::knot::{self, KnotSpec};
use solver::material::Material;
use solver::pipeline::{ContactOptions, World};
use solver::rod::{End, Rod};
use solver::stepper::NewtonOptions;

fn relaxed_knot() -> World {
    let shape = knot::build(&KnotSpec::paper(3)).expect("paper knot builds");
    let mut rod = Rod::new(&shape.points, 1.6e-3, Material::default()).expect("valid rod");
    rod.clamp(End::Start);
    rod.clamp(End::Finish);
    let ei = rod.section.ei;
    let newton = NewtonOptions {
        force_scale: Some(ei / (1.6e-3 * 1.6e-3)),
        ..NewtonOptions::default()
    };
    let env = Environment {
        gravity: Vector3::zeros(),
        damping: 20.0,
    };
    let mut world = World::new(vec![rod], env, ContactOptions::default(), newton);
    for _ in 0..300 {
        world.step(1e-3).expect("relaxation step");
    }
    world.env.damping = 0.0;
    world.rods[0].move_clamp(End::Start, Vector3::new(-3e-3, 0.0, 0.0));
    world.rods[0].move_clamp(End::Finish, Vector3::new(3e-3, 0.0, 0.0));
    // Some pulling steps, so that the benchmarked step starts like a typical
    // one: warm-started contacts and a Newton matrix factored at this step size.
    for _ in 0..20 {
        world.step(1e-3).expect("pulling step");
    }
    world
}

fn bench(c: &mut Criterion) {
    let world = relaxed_knot();
    let contacts = world.clone().step(1e-3).expect("step").contacts;
    c.bench_function(&format!("knot/time_step_n3_K301_{contacts}contacts"), |b| {
        b.iter_batched_ref(
            || world.clone(),
            |w| w.step(1e-3).expect("step"),
            BatchSize::LargeInput,
        )
    });
}

criterion_group! {
    name = knot_step;
    config = Criterion::default().sample_size(30);
    targets = bench
}
criterion_main!(knot_step);
