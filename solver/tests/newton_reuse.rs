//! Reusing the previous step's factored Newton matrix
//! (`NewtonOptions::reuse_factorization`) changes how each step converges,
//! not what it converges to: the trajectory matches fresh Newton at every
//! step, with far fewer factorisations.
use nalgebra::Vector3;
use solver::external::Environment;
use solver::material::Material;
use solver::rod::{End, Rod};
use solver::stepper::{NewtonOptions, Stepper};
use solver::validation::dynamics::arc;

/// A rod bent into an arc, clamped at one end, whose other clamp is pulled
/// away while it swings (L = 10 cm, h = 1 mm, K = 31), stepped `steps` times.
fn swing(reuse: bool, steps: usize) -> (Vec<Vec<f64>>, u64) {
    let mut rod = Rod::new(&arc(31, 0.1, 1.5), 1e-3, Material::default()).expect("valid arc");
    rod.clamp(End::Start);
    rod.clamp(End::Finish);
    rod.move_clamp(End::Finish, Vector3::new(0.02, 0.0, 0.01));
    let env = Environment {
        gravity: Vector3::new(0.0, -9.81, 0.0),
        damping: 0.0,
    };
    let options = NewtonOptions {
        rtol: 1e-9,
        reuse_factorization: reuse,
        ..NewtonOptions::default()
    };
    let mut stepper = Stepper::new(&rod, options);
    let mut states = Vec::with_capacity(steps);
    for _ in 0..steps {
        stepper.step(&mut rod, &env, None, 1e-3).expect("step converges");
        states.push(rod.q.clone());
    }
    (states, stepper.factorizations())
}

#[test]
fn reused_factorisation_follows_fresh_newton() {
    let steps = 400;
    let (fresh, fresh_factors) = swing(false, steps);
    let (reused, reused_factors) = swing(true, steps);
    let scale = 0.1;
    let worst = fresh
        .iter()
        .zip(&reused)
        .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
        .fold(0.0f64, f64::max);
    // Both converge each step to forces of 1e-9 EI/L^2; positions then agree
    // far below the rod's length even after 400 steps.
    assert!(worst <= 1e-7 * scale, "largest DOF difference {worst:e}");
    assert!(fresh_factors >= steps as u64, "fresh Newton factors every step");
    assert!(
        reused_factors * 2 <= fresh_factors,
        "reuse factored {reused_factors} times, fresh {fresh_factors}"
    );
}
