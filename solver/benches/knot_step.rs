//! One time step of the paper's n = 3 knot (h = 1.6 mm) with its
//! self-contacts: detection, frictional contact solve and the implicit rod
//! step together, as a step in the middle of a pull. At K = 301 (the paper's
//! mesh, dt = 1 ms) and at K = 601 and 1201 with the time step scaled as
//! `CaseParams::time_step` does (with the square of the edge length), so that
//! the cost per node shows whether a step is linear in K. Friction as the
//! case defaults have it (at the centre lines); at K = 301 also with the
//! implicit contact solve (`contact_solve = implicit`).
use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use nalgebra::Vector3;
use solver::case::CaseParams;
use solver::contact::ContactSolve;
use solver::external::Environment;
use solver::knot::{self, KnotSpec};
use solver::material::Material;
use solver::pipeline::{ContactOptions, World};
use solver::rod::{End, Rod};
use solver::stepper::NewtonOptions;

/// The step at `nodes`: 1 ms at the paper's 301 nodes, scaled with the
/// square of the edge length.
fn time_step(nodes: usize) -> f64 {
    1e-3 * (300.0 / (nodes - 1) as f64).powi(2)
}

fn relaxed_knot(nodes: usize, solve: ContactSolve) -> World {
    let spec = KnotSpec {
        nodes,
        ..KnotSpec::paper(3)
    };
    let shape = knot::build(&spec).expect("paper knot builds");
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
    let dt = time_step(nodes);
    let contact = ContactOptions {
        rolling: CaseParams::default().rolling,
        solve,
        ..ContactOptions::default()
    };
    let mut world = World::new(vec![rod], env, contact, newton);
    for _ in 0..300 {
        world.step(dt).expect("relaxation step");
    }
    world.env.damping = 0.0;
    world.rods[0].move_clamp(End::Start, Vector3::new(-3e-3, 0.0, 0.0));
    world.rods[0].move_clamp(End::Finish, Vector3::new(3e-3, 0.0, 0.0));
    // Some pulling steps, so that the benchmarked step starts like a typical
    // one: warm-started contacts and a Newton matrix factored at this step size.
    for _ in 0..20 {
        world.step(dt).expect("pulling step");
    }
    world
}

fn bench(c: &mut Criterion) {
    for (nodes, solve) in [
        (301, ContactSolve::Explicit),
        (601, ContactSolve::Explicit),
        (1201, ContactSolve::Explicit),
        (301, ContactSolve::Implicit),
    ] {
        let world = relaxed_knot(nodes, solve);
        let dt = time_step(nodes);
        // The step's work, in the name: the cost per node is comparable
        // between meshes only at equal sweeps and Newton iterations.
        let r = world.clone().step(dt).expect("step");
        let name = format!(
            "knot/time_step_n3_K{nodes}_{solve:?}_{}contacts_{}sweeps_{}newton",
            r.contacts, r.contact_sweeps, r.newton_iterations
        );
        c.bench_function(&name, |b| {
            b.iter_batched_ref(
                || world.clone(),
                |w| w.step(dt).expect("step"),
                BatchSize::LargeInput,
            )
        });
    }
}

criterion_group! {
    name = knot_step;
    config = Criterion::default().sample_size(30);
    targets = bench
}
criterion_main!(knot_step);
