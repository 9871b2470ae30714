//! Contact cases (paper Sec. 3.2): crossing rods pressed together, a short rod
//! on an inclined fixed rod (stick/slide), the capstan equation, and energy
//! behaviour of frictionless bounces and of initially interpenetrating rods.
use crate::contact::curve::Piece;
use crate::contact::{ContactSolve, FrictionLaw, Geometry};
use crate::external::Environment;
use crate::material::Material;
use crate::pipeline::{ContactOptions, World, WorldError};
use crate::rod::{End, Rod, node_dof};
use crate::stepper::NewtonOptions;
use nalgebra::Vector3;
use std::f64::consts::PI;

fn polyline(a: Vector3<f64>, b: Vector3<f64>, k: usize) -> Vec<Vector3<f64>> {
    (0..k)
        .map(|i| a + (b - a) * (i as f64 / (k - 1) as f64))
        .collect()
}

fn fixed_rod(a: Vector3<f64>, b: Vector3<f64>, k: usize, radius: f64) -> Rod {
    let mut rod = Rod::new(&polyline(a, b, k), radius, Material::default()).expect("valid rod");
    rod.fixed.fill(true);
    rod
}

fn total_energy(world: &World) -> f64 {
    let mut grad = Vec::new();
    world
        .rods
        .iter()
        .map(|r| {
            grad.resize(r.ndof(), 0.0);
            crate::energies::evaluate(r, crate::energies::Terms::ALL, &mut grad, None).total()
                + r.kinetic_energy()
        })
        .sum()
}

/// Two perpendicular clamped rods (L = 10 cm, h = 1 mm), the upper one pressed
/// 2 mm down onto the lower one, then held. Returns (largest penetration / h
/// over the run, penetration / h at the end, whether the upper centre line
/// ever went below the lower one).
pub fn crossing_rods_pressed() -> Result<(f64, f64, bool), WorldError> {
    let h = 1e-3;
    let k = 21;
    let mut lower = Rod::new(
        &polyline(Vector3::new(-0.05, 0.0, 0.0), Vector3::new(0.05, 0.0, 0.0), k),
        h,
        Material::default(),
    )
    .expect("valid rod");
    let z = 2.0 * h + 0.2 * h;
    let mut upper = Rod::new(
        &polyline(Vector3::new(0.0, -0.05, z), Vector3::new(0.0, 0.05, z), k),
        h,
        Material::default(),
    )
    .expect("valid rod");
    for rod in [&mut lower, &mut upper] {
        rod.clamp(End::Start);
        rod.clamp(End::Finish);
    }
    let press_time = 0.5;
    let speed = 2e-3 / press_time;
    upper.move_clamp(End::Start, Vector3::new(0.0, 0.0, -speed));
    upper.move_clamp(End::Finish, Vector3::new(0.0, 0.0, -speed));
    let env = Environment {
        gravity: Vector3::zeros(),
        damping: 20.0,
    };
    let contact = ContactOptions {
        friction: 0.3,
        ..ContactOptions::default()
    };
    let mut world = World::new(vec![lower, upper], env, contact, NewtonOptions::default());
    let dt = 1e-3;
    let mut worst: f64 = 0.0;
    let mut passed_through = false;
    let mid = k / 2;
    for step in 0..1500 {
        if step == (press_time / dt) as usize {
            for end in [End::Start, End::Finish] {
                world.rods[1].move_clamp(end, Vector3::zeros());
            }
        }
        let r = world.step(dt)?;
        worst = worst.max(r.max_penetration);
        passed_through |= world.rods[1].node(mid).z < world.rods[0].node(mid).z;
    }
    let end_penetration = 2.0 * h - (world.rods[1].node(mid) - world.rods[0].node(mid)).norm();
    Ok((worst / h, end_penetration.max(0.0) / h, passed_through))
}

/// A short free rod (4 nodes, 2 cm, h = 1 mm) lying across a fixed rod inclined
/// by `alpha`, under gravity with friction `mu`, with friction at the surfaces
/// (`rolling`) or at the centre lines. Returns (measured acceleration along the
/// incline, the closed form). Rolling: a solid cylinder (I = m h^2 / 2) rolls
/// without slipping at a = (2/3) g sin(alpha) while tan(alpha) <= 3 mu, and
/// slides at g (sin(alpha) - mu cos(alpha)) beyond. At the centre lines the
/// rod cannot roll: it sticks while tan(alpha) <= mu and slides beyond.
pub fn inclined_rod(
    alpha: f64,
    mu: f64,
    rolling: bool,
    solve: ContactSolve,
) -> Result<(f64, f64), WorldError> {
    let g = 9.81;
    let h = 1e-3;
    let axis = Vector3::new(alpha.cos(), 0.0, alpha.sin());
    let normal = Vector3::new(-alpha.sin(), 0.0, alpha.cos());
    let fixed = fixed_rod(-axis * 0.3, axis * 0.1, 41, h);
    let centre = normal * (2.0 * h);
    let short = Rod::new(
        &polyline(
            centre - Vector3::new(0.0, 0.01, 0.0),
            centre + Vector3::new(0.0, 0.01, 0.0),
            4,
        ),
        h,
        Material::default(),
    )
    .expect("valid rod");
    let env = Environment {
        gravity: Vector3::new(0.0, 0.0, -g),
        damping: 0.0,
    };
    let contact = ContactOptions {
        friction: mu,
        rolling,
        solve,
        ..ContactOptions::default()
    };
    let mut world = World::new(vec![fixed, short], env, contact, NewtonOptions::default());
    let dt = 1e-3;
    let centre_along = |w: &World| {
        let r = &w.rods[1];
        (0..r.nodes()).map(|i| r.node(i)).sum::<Vector3<f64>>().dot(&axis) / r.nodes() as f64
    };
    let s0 = centre_along(&world);
    // Let the contact settle, then measure s(t) over the next 0.2 s and fit s = s1 + v1 t + a t^2 / 2.
    for _ in 0..50 {
        world.step(dt)?;
    }
    let mut samples = Vec::new();
    for n in 0..200 {
        world.step(dt)?;
        samples.push(((n + 1) as f64 * dt, centre_along(&world) - s0));
    }
    let accel = -2.0 * quadratic_coefficient(&samples);
    let grip = if rolling { 3.0 * mu } else { mu };
    let expected = match (alpha.tan() > grip, rolling) {
        (true, _) => g * (alpha.sin() - mu * alpha.cos()),
        (false, true) => 2.0 / 3.0 * g * alpha.sin(),
        (false, false) => 0.0,
    };
    Ok((accel, expected))
}

/// A free rod (5 nodes, 4 cm, h = 1 mm) resting on two fixed horizontal
/// crossbars 2.5 cm apart, its axis tilted by `alpha`, under gravity with
/// friction `mu` at the surfaces (`rolling`) or at the centre lines. Gravity
/// pulls it along its own axis, which rolling cannot relieve: it sticks
/// while tan(alpha) <= mu and slides at g (sin(alpha) - mu cos(alpha)) beyond.
/// Returns (measured acceleration along the rod, the closed form).
pub fn rod_on_crossbars(
    alpha: f64,
    mu: f64,
    rolling: bool,
    solve: ContactSolve,
) -> Result<(f64, f64), WorldError> {
    let g = 9.81;
    let h = 1e-3;
    let axis = Vector3::new(alpha.cos(), 0.0, alpha.sin());
    let up = Vector3::new(-alpha.sin(), 0.0, alpha.cos());
    let bar = |s: f64| {
        let c = axis * s;
        fixed_rod(c - Vector3::y() * 0.05, c + Vector3::y() * 0.05, 21, h)
    };
    let centre = up * (2.0 * h);
    let rod = Rod::new(
        &polyline(centre - axis * 0.02, centre + axis * 0.02, 5),
        h,
        Material::default(),
    )
    .expect("valid rod");
    let env = Environment {
        gravity: Vector3::new(0.0, 0.0, -g),
        damping: 0.0,
    };
    let contact = ContactOptions {
        friction: mu,
        rolling,
        solve,
        ..ContactOptions::default()
    };
    let mut world = World::new(
        vec![bar(-0.0125), bar(0.0125), rod],
        env,
        contact,
        NewtonOptions::default(),
    );
    let dt = 1e-3;
    let along = |w: &World| {
        let r = &w.rods[2];
        (0..r.nodes()).map(|i| r.node(i)).sum::<Vector3<f64>>().dot(&axis) / r.nodes() as f64
    };
    let s0 = along(&world);
    // Settle, then fit over 40 ms: a sliding rod moves about 4 mm.
    for _ in 0..20 {
        world.step(dt)?;
    }
    let mut samples = Vec::new();
    for n in 0..40 {
        world.step(dt)?;
        samples.push(((n + 1) as f64 * dt, along(&world) - s0));
    }
    let accel = -2.0 * quadratic_coefficient(&samples);
    let expected = if alpha.tan() > mu {
        g * (alpha.sin() - mu * alpha.cos())
    } else {
        0.0
    };
    Ok((accel, expected))
}

/// Least-squares coefficient c2 of s = c0 + c1 t + c2 t^2.
fn quadratic_coefficient(samples: &[(f64, f64)]) -> f64 {
    let mut m = nalgebra::Matrix3::<f64>::zeros();
    let mut rhs = Vector3::<f64>::zeros();
    for &(t, s) in samples {
        let phi = Vector3::new(1.0, t, t * t);
        m += phi * phi.transpose();
        rhs += phi * s;
    }
    m.lu().solve(&rhs).map(|c| c[2]).unwrap_or(f64::NAN)
}

/// Capstan: a thin rod (h = 0.3 mm, E = 100 MPa) wrapped by `phi` around a fixed
/// rod of radius 20 mm, loaded by a constant tension T = 0.1 N at one end and
/// pulled at 1 cm/s at the other once the load has been ramped in. Bending is negligible: EI / (R^2 T) = 1.5 %,
/// with R the wrap radius. Returns (mean pulling force / T during sliding,
/// exp(mu phi)) under friction law `law`.
pub fn capstan(mu: f64, phi: f64, law: FrictionLaw, solve: ContactSolve) -> Result<(f64, f64), WorldError> {
    capstan_on(Drum::FixedRod, mu, phi, law, solve, Geometry::default())
}

/// What the capstan's rope is wrapped on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drum {
    /// A rod with every DOF held.
    FixedRod,
    /// The world's rigid obstacle ([`crate::contact::Cylinder`]).
    Cylinder,
}

/// [`capstan`] on `drum`.
pub fn capstan_on(
    drum: Drum,
    mu: f64,
    phi: f64,
    law: FrictionLaw,
    solve: ContactSolve,
    geometry: Geometry,
) -> Result<(f64, f64), WorldError> {
    let (r_fixed, r_rod) = (0.02, 0.3e-3);
    let radius = r_fixed + r_rod + 0.02 * r_rod;
    let pitch = 4.0 * r_rod;
    let edge = 2e-3;
    let tail = 0.02;
    let load = 0.1;
    // Wrap from angle 0 (tangent point of the loaded tail) to phi about the y axis.
    let at = |psi: f64| Vector3::new(radius * psi.cos(), pitch * psi / (2.0 * PI), radius * psi.sin());
    let tangent = |psi: f64| Vector3::new(-psi.sin(), pitch / (2.0 * PI * radius), psi.cos()).normalize();
    let wrap_edges = ((radius * phi) / edge).ceil() as usize;
    let tail_edges = (tail / edge).round() as usize;
    let mut nodes = Vec::new();
    for i in (1..=tail_edges).rev() {
        nodes.push(at(0.0) + tangent(0.0) * (i as f64 * edge));
    }
    for i in 0..=wrap_edges {
        nodes.push(at(-phi * i as f64 / wrap_edges as f64));
    }
    for i in 1..=tail_edges {
        nodes.push(at(-phi) - tangent(-phi) * (i as f64 * edge));
    }
    let material = Material {
        youngs_modulus: 1e8,
        ..Material::default()
    };
    let mut rope = Rod::new(&nodes, r_rod, material).expect("valid rope");
    rope.clamp(End::Finish);
    let pull_dir = -tangent(-phi);
    let speed = 0.01;
    let load_dir = tangent(0.0);
    let y_extent = pitch * phi / (2.0 * PI);
    let cylinder = fixed_rod(
        Vector3::new(0.0, -0.02, 0.0),
        Vector3::new(0.0, y_extent + 0.02, 0.0),
        11,
        r_fixed,
    );
    let env = Environment {
        gravity: Vector3::zeros(),
        damping: 200.0,
    };
    let contact = ContactOptions {
        friction: mu,
        friction_law: law,
        solve,
        ..ContactOptions::default()
    }
    .with_geometry(geometry);
    let mut world = match drum {
        Drum::FixedRod => World::new(vec![rope, cylinder], env, contact, NewtonOptions::default()),
        Drum::Cylinder => {
            let [a, b] = [cylinder.node(0), cylinder.node(cylinder.nodes() - 1)];
            let mut world = World::new(vec![rope], env, contact, NewtonOptions::default());
            world.obstacle = Some(crate::contact::Cylinder {
                center: 0.5 * (a + b),
                axis: (b - a).normalize(),
                radius: r_fixed,
                length: (b - a).norm(),
            });
            world
        }
    };
    let dt = 2e-4;
    let steps = 2500;
    // The load is ramped in over `ramp` steps with the clamp still, then the clamp pulls.
    let ramp = 250;
    let mut sum = 0.0;
    let mut count = 0;
    for step in 0..steps {
        let scale = ((step + 1) as f64 / ramp as f64).min(1.0);
        for c in 0..3 {
            world.load_mut(0)[node_dof(0) + c] = scale * load * load_dir[c];
        }
        if step == ramp {
            world.rods[0].move_clamp(End::Finish, pull_dir * speed);
        }
        world.step(dt)?;
        if step >= steps / 2 {
            let (f, _) = world.stepper(0).clamp_reaction(&world.rods[0], End::Finish);
            sum += f.dot(&pull_dir);
            count += 1;
        }
    }
    Ok((sum / count as f64 / load, (mu * phi).exp()))
}

/// The washboard: a rope (h = 1 mm, E = 10 MPa, edges 2.08 h as the knot's
/// default mesh) draped over a fixed straight rod of the same radius, turned
/// by `phi` about it, loaded by a constant tension T = 0.1 N at one end and
/// pulled along its other tail at 1 cm/s, frictionless, contacts computed
/// between the centre lines of `geometry`. Without friction the pulling force
/// is T whatever the rope's position (the fixed rod pushes along its
/// normals, which do no work on sliding), and the rod carries
/// N = 2 T sin(phi / 2). Returns the pulling force's largest deviation from
/// its running mean over one edge of travel (the fluctuation at the edges'
/// scale) over N, and the mean pulling force over T.
pub fn washboard(phi: f64, geometry: Geometry) -> Result<(f64, f64), WorldError> {
    let h = 1e-3;
    let radius = 2.0 * h * (1.0 + 1e-3);
    let edge = 2.08 * h;
    let tail_edges = 40;
    let load = 0.1;
    let at = |psi: f64| Vector3::new(radius * psi.cos(), 0.0, radius * psi.sin());
    let tangent = |psi: f64| Vector3::new(-psi.sin(), 0.0, psi.cos());
    // Wrap from psi = pi/2 + phi/2 (the loaded tail's tangent point) down to pi/2 - phi/2.
    let (start, end) = (0.5 * (PI + phi), 0.5 * (PI - phi));
    let wrap_edges = ((radius * phi) / edge).ceil() as usize;
    let mut nodes = Vec::new();
    for i in (1..=tail_edges).rev() {
        nodes.push(at(start) + tangent(start) * (i as f64 * edge));
    }
    for i in 0..=wrap_edges {
        nodes.push(at(start + (end - start) * i as f64 / wrap_edges as f64));
    }
    for i in 1..=tail_edges {
        nodes.push(at(end) - tangent(end) * (i as f64 * edge));
    }
    let material = Material {
        youngs_modulus: 1e7,
        ..Material::default()
    };
    let mut rope = Rod::new(&nodes, h, material).expect("valid rope");
    rope.clamp(End::Finish);
    let pull_dir = -tangent(end);
    let load_dir = tangent(start);
    let bar = fixed_rod(Vector3::new(0.0, -0.02, 0.0), Vector3::new(0.0, 0.02, 0.0), 11, h);
    let env = Environment {
        gravity: Vector3::zeros(),
        damping: 50.0,
    };
    let contact = ContactOptions {
        friction: 0.0,
        ..ContactOptions::default()
    }
    .with_geometry(geometry);
    let mut world = World::new(vec![rope, bar], env, contact, NewtonOptions::default());
    let (dt, speed) = (2e-4, 0.01);
    // The load is ramped in and settles with the clamp still; then the clamp
    // pulls over eight edges, the first two left to the start's transient.
    let (ramp, settle) = (250, 1500);
    let pull_steps = (8.0 * edge / speed / dt).round() as usize;
    let skip = (2.0 * edge / speed / dt).round() as usize;
    let mut forces = Vec::with_capacity(pull_steps);
    for step in 0..ramp + settle + pull_steps {
        let scale = ((step + 1) as f64 / ramp as f64).min(1.0);
        for c in 0..3 {
            world.load_mut(0)[node_dof(0) + c] = scale * load * load_dir[c];
        }
        if step == ramp + settle {
            world.rods[0].move_clamp(End::Finish, pull_dir * speed);
        }
        world.step(dt)?;
        if step >= ramp + settle + skip {
            let (f, _) = world.stepper(0).clamp_reaction(&world.rods[0], End::Finish);
            forces.push(f.dot(&pull_dir));
        }
    }
    let window = (edge / speed / dt).round() as usize;
    let mean = forces.iter().sum::<f64>() / forces.len() as f64;
    let mut largest: f64 = 0.0;
    for k in window / 2..forces.len() - window / 2 {
        let around = &forces[k - window / 2..=k + window / 2];
        let running = around.iter().sum::<f64>() / around.len() as f64;
        largest = largest.max((forces[k] - running).abs());
    }
    let normal = 2.0 * load * (0.5 * phi).sin();
    Ok((largest / normal, mean / load))
}

/// A sticking contact under a stiff load path: a rod (10 cm, 20 nodes,
/// h = 1 mm, E = 10 MPa) clamped at x = 0 lies across a fixed bar at its
/// middle, pressed onto it by a load N = 0.1 N at the touching point (on
/// the nodes as a contact force there: the touching segment's two nodes, or
/// the smooth piece's six); its free end is pulled along the rod by a force
/// ramped from 0 to T = mu N / 2 over 0.2 s and then held for 0.2 s
/// (mu = 0.5, damped, dt = 1 ms), under the contact `geometry`. Coulomb: T
/// is inside the cone, the contact sticks and friction carries all of T, so
/// the rod's point in contact does not move along the rod and the clamped
/// half stays unloaded. Returns (that point's final displacement along the
/// rod, the displacement if the contact slid freely and the clamped half
/// carried T: T (L / 2) / EA). The point in contact is the middle of the
/// touching segment, on the smooth centre line under [`Geometry::Smooth`].
pub fn sticking_contact_creep(solve: ContactSolve, geometry: Geometry) -> Result<(f64, f64), WorldError> {
    let (h, length, k) = (1e-3, 0.1, 20);
    let material = Material {
        youngs_modulus: 1e7,
        ..Material::default()
    };
    let mut rod = Rod::new(
        &polyline(Vector3::zeros(), Vector3::new(length, 0.0, 0.0), k),
        h,
        material,
    )
    .expect("valid rod");
    rod.clamp(End::Start);
    // The bar crosses the middle of segment 9 (nodes 9 and 10), just touching.
    let mid = 0.5 * (rod.node(9) + rod.node(10));
    let bar = fixed_rod(
        mid + Vector3::new(0.0, -0.02, -2.0 * h),
        mid + Vector3::new(0.0, 0.02, -2.0 * h),
        9,
        h,
    );
    let (mu, normal) = (0.5, 0.1);
    let pull = 0.5 * mu * normal;
    let slide = pull * (length / 2.0) / (material.youngs_modulus * PI * h * h);
    let env = Environment {
        gravity: Vector3::zeros(),
        damping: 50.0,
    };
    let contact = ContactOptions {
        friction: mu,
        solve,
        ..ContactOptions::default()
    }
    .with_geometry(geometry);
    // The touching point's weights on the rod's nodes: the load presses
    // there, spread over the nodes as a contact force there is.
    let touching: Vec<(usize, f64)> = match geometry {
        Geometry::Segment => vec![(9, 0.5), (10, 0.5)],
        Geometry::Smooth => {
            let piece = Piece::new(rod.nodes(), 9, |i| rod.node(i));
            piece.nodes.iter().copied().zip(piece.weights(0.5)).collect()
        }
    };
    let at = |r: &Rod| touching.iter().map(|&(i, w)| w * r.node(i).x).sum::<f64>();
    let start = at(&rod);
    let mut world = World::new(vec![rod, bar], env, contact, NewtonOptions::default());
    for &(node, weight) in &touching {
        world.load_mut(0)[node_dof(node) + 2] = -weight * normal;
    }
    let (dt, ramp, hold) = (1e-3, 200, 200);
    for step in 0..ramp + hold {
        let scale = ((step + 1) as f64 / ramp as f64).min(1.0);
        world.load_mut(0)[node_dof(k - 1)] = scale * pull;
        world.step(dt)?;
    }
    Ok((at(&world.rods[0]) - start, slide))
}

/// A free rod thrown at a fixed rod with `mu = 0` and no damping: returns
/// (largest total energy over the run / initial energy, final / initial).
pub fn frictionless_bounce() -> Result<(f64, f64), WorldError> {
    let h = 1e-3;
    let fixed = fixed_rod(Vector3::new(-0.05, 0.0, 0.0), Vector3::new(0.05, 0.0, 0.0), 21, h);
    let mut ball = Rod::new(
        &polyline(
            Vector3::new(0.0, -0.025, 0.004),
            Vector3::new(0.0, 0.025, 0.004),
            11,
        ),
        h,
        Material::default(),
    )
    .expect("valid rod");
    for i in 0..ball.nodes() {
        let d = node_dof(i);
        ball.velocity[d + 2] = -0.2;
        ball.velocity[d] = 0.05;
    }
    let contact = ContactOptions {
        friction: 0.0,
        ..ContactOptions::default()
    };
    let mut world = World::new(
        vec![fixed, ball],
        Environment::default(),
        contact,
        NewtonOptions::default(),
    );
    let e0 = total_energy(&world);
    let mut worst: f64 = 0.0;
    let mut contacted = false;
    for _ in 0..200 {
        let r = world.step(1e-4)?;
        contacted |= r.active_contacts > 0;
        worst = worst.max(total_energy(&world));
    }
    if !contacted {
        return Ok((f64::NAN, f64::NAN));
    }
    Ok((worst / e0, total_energy(&world) / e0))
}

/// Two crossing rods at rest that start interpenetrated by 20 % of the radius:
/// returns (final gap / h, largest node speed reached in m/s).
pub fn interpenetration_recovery() -> Result<(f64, f64), WorldError> {
    let h = 1e-3;
    let k = 21;
    let a = Rod::new(
        &polyline(Vector3::new(-0.05, 0.0, 0.0), Vector3::new(0.05, 0.0, 0.0), k),
        h,
        Material::default(),
    )
    .expect("valid rod");
    let z = 2.0 * h - 0.2 * h;
    let b = Rod::new(
        &polyline(Vector3::new(0.0, -0.05, z), Vector3::new(0.0, 0.05, z), k),
        h,
        Material::default(),
    )
    .expect("valid rod");
    let env = Environment {
        gravity: Vector3::zeros(),
        damping: 0.0,
    };
    let mut world = World::new(
        vec![a, b],
        env,
        ContactOptions::default(),
        NewtonOptions::default(),
    );
    let mut fastest: f64 = 0.0;
    for _ in 0..50 {
        world.step(1e-3)?;
        for r in &world.rods {
            for i in 0..r.nodes() {
                fastest = fastest.max(r.node_velocity(i).norm());
            }
        }
    }
    let mid = k / 2;
    let gap = (world.rods[1].node(mid) - world.rods[0].node(mid)).norm() - 2.0 * h;
    Ok((gap / h, fastest))
}

/// Broad phase against brute force on a tight (2,7) torus-knot polyline of 301
/// nodes (h = 1.6 mm): returns (pairs found, brute-force pairs, mismatches).
pub fn broad_phase_vs_brute_force() -> (usize, usize, usize) {
    use crate::contact::broad_phase::{BroadPhase, brute_force, neighbour_gap, polyline_segments};
    let k = 301;
    let h = 1.6e-3;
    let points: Vec<Vector3<f64>> = (0..k)
        .map(|i| {
            let t = 2.0 * PI * i as f64 / (k - 1) as f64;
            let r = 0.012 + 0.004 * (3.5 * t).cos();
            Vector3::new(r * (2.0 * t).cos(), r * (2.0 * t).sin(), 0.004 * (3.5 * t).sin())
        })
        .collect();
    let segments = polyline_segments(&points, h, 0);
    let edge = (points[1] - points[0]).norm();
    let gaps = [neighbour_gap(2.0 * h, edge)];
    let margin = 0.25 * h;
    let mut broad = BroadPhase::new();
    let found: Vec<(usize, usize)> = match broad.find_pairs(&segments, &gaps, margin) {
        Ok(p) => p.iter().map(|c| (c.i, c.j)).collect(),
        Err(_) => return (0, 0, usize::MAX),
    };
    let brute: Vec<(usize, usize)> = match brute_force(&segments, &gaps, margin) {
        Ok(p) => p.iter().map(|c| (c.i, c.j)).collect(),
        Err(_) => return (0, 0, usize::MAX),
    };
    let missing = brute.iter().filter(|p| !found.contains(p)).count();
    let extra = found.iter().filter(|p| !brute.contains(p)).count();
    (found.len(), brute.len(), missing + extra)
}
