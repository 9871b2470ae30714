//! The adaptive time step (`solver::time_step`): a rollback redoes a step
//! exactly, and halving keeps contacts from penetrating where a constant
//! large step does not.
use nalgebra::Vector3;
use solver::external::Environment;
use solver::material::Material;
use solver::pipeline::{ContactOptions, World};
use solver::rod::{End, Rod};
use solver::stepper::NewtonOptions;
use solver::time_step::{AdaptiveOptions, TimeStep};

const H: f64 = 1e-3;

/// Two perpendicular clamped rods (L = 10 cm, h = 1 mm, K = 41); the upper one
/// moves down onto the lower one at `speed` (m/s).
fn crossing(speed: f64) -> World {
    let line = |a: Vector3<f64>, b: Vector3<f64>| -> Vec<Vector3<f64>> {
        (0..41).map(|i| a + (b - a) * (i as f64 / 40.0)).collect()
    };
    let z = 2.2 * H;
    let mut lower = Rod::new(
        &line(Vector3::new(-0.05, 0.0, 0.0), Vector3::new(0.05, 0.0, 0.0)),
        H,
        Material::default(),
    )
    .unwrap();
    let mut upper = Rod::new(
        &line(Vector3::new(0.0, -0.05, z), Vector3::new(0.0, 0.05, z)),
        H,
        Material::default(),
    )
    .unwrap();
    for rod in [&mut lower, &mut upper] {
        rod.clamp(End::Start);
        rod.clamp(End::Finish);
    }
    upper.move_clamp(End::Start, Vector3::new(0.0, 0.0, -speed));
    upper.move_clamp(End::Finish, Vector3::new(0.0, 0.0, -speed));
    let env = Environment {
        gravity: Vector3::zeros(),
        damping: 0.0,
    };
    // The segment contact: the press was set up on it (under the smooth
    // contact's explicit solve the adaptive clock meets it without a
    // rejection; docs/FIDELITY.md, "Left open").
    World::new(
        vec![lower, upper],
        env,
        ContactOptions::default().with_geometry(solver::contact::Geometry::Segment),
        NewtonOptions::default(),
    )
}

/// Largest end-of-step penetration / h while pressing for `duration` seconds.
fn worst_penetration(world: &mut World, clock: &mut TimeStep, duration: f64) -> f64 {
    let (mut t, mut worst): (f64, f64) = (0.0, 0.0);
    while t < duration {
        let step = clock.advance(world).expect("step");
        t += step.dt;
        worst = worst.max(step.report.max_penetration / H);
    }
    worst
}

#[test]
fn rollback_redoes_a_step_exactly() {
    let mut world = crossing(0.05);
    for _ in 0..20 {
        world.step(1e-3).unwrap();
    }
    world.checkpoint();
    world.step(1e-3).unwrap();
    let once = world.rods[1].q.clone();
    world.rollback();
    world.step(5e-4).unwrap();
    world.rollback();
    world.step(1e-3).unwrap();
    assert_eq!(world.rods[1].q, once);
}

#[test]
fn halving_keeps_a_fast_press_from_penetrating() {
    let (speed, duration, dt) = (0.05, 0.06, 4e-3);
    let mut fixed = crossing(speed);
    let constant = worst_penetration(
        &mut fixed,
        &mut TimeStep::new(AdaptiveOptions::fixed(dt)),
        duration,
    );
    let mut adaptive = crossing(speed);
    let mut clock = TimeStep::new(AdaptiveOptions::up_to(dt));
    let controlled = worst_penetration(&mut adaptive, &mut clock, duration);
    let o = clock.options;
    assert!(
        constant > o.reject_penetration,
        "constant step penetrates only {constant} h"
    );
    assert!(
        controlled <= o.reject_penetration,
        "adaptive step penetrates {controlled} h"
    );
    assert!(clock.rejected > 0 && clock.smallest < dt);
}
