//! The simplified knot model (paper Sec. 5) against independent expectations:
//! closed forms, finite differences, convergence rates, symmetry, dimensional
//! analysis and cross-checks between the landscape and the bifurcation diagram.
use solver::simplified::reproduce::{braid_convergence, derivative_check};
use solver::simplified::*;

fn params(loop_nodes: usize) -> Params {
    Params {
        loop_nodes,
        ..Params::default()
    }
}

fn landscape_at(p: Params, l_k_bar: f64) -> Landscape {
    landscape(&LandscapeSpec {
        params: p,
        l_k_bar,
        ..LandscapeSpec::default()
    })
    .expect("landscape")
}

#[test]
fn braid_der_energy_converges_to_eq14_at_second_order() {
    for theta in [0.0, 2.0] {
        let rows =
            braid_convergence(&Params::default(), 137.5, theta, &[40, 80, 160, 320, 640]).expect("braid");
        for r in &rows[1..] {
            let order = r.observed_order.expect("order");
            assert!(
                (order - 2.0).abs() < 0.05,
                "theta {theta}: order {order} at {} nodes",
                r.nodes
            );
        }
        // The error is a pure series in the spacing squared: Richardson extrapolation
        // removes the leading term and what is left falls at fourth order.
        let extrapolated: Vec<f64> = rows
            .windows(2)
            .map(|w| {
                let r = (w[1].nodes - 2) as f64 / (w[0].nodes - 2) as f64;
                let e = w[1].discrete + (w[1].discrete - w[0].discrete) / (r * r - 1.0);
                (e / w[1].closed_form - 1.0).abs()
            })
            .collect();
        for w in extrapolated.windows(2) {
            assert!(
                w[1] < w[0] / 12.0,
                "theta {theta}: extrapolated errors {extrapolated:?}"
            );
        }
        assert!(extrapolated[3] < 1e-7, "theta {theta}: {extrapolated:?}");
    }
}

#[test]
fn loop_keeps_the_two_fold_symmetry_and_starts_nearly_untwisted() {
    let p = params(81);
    let mut solver = LoopSolver::new(&p, 137.5).expect("loop");
    let eq = solver.equilibrium();
    // At theta = 0 the clamps sit only ±h off the loop's plane: the loop is nearly
    // untwisted (twist from the (h / loop size)² misalignment).
    let size = p.l_l_bar(137.5) / std::f64::consts::TAU;
    assert!(
        eq.twisting < eq.bending / (size * size),
        "twist {:e} vs bending {:e}",
        eq.twisting,
        eq.bending
    );
    for theta in [0.0, 1.3, 2.6] {
        solver.move_to(theta, 137.5).expect("continuation");
        let c = solver.centerline();
        let k = c.len();
        let scale = p.l_l_bar(137.5);
        // The half turn about y maps node i onto node K-1-i.
        let worst = (0..k)
            .map(|i| {
                let (a, b) = (c[i], c[k - 1 - i]);
                ((a[0] + b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] + b[2]).powi(2)).sqrt()
            })
            .fold(0.0f64, f64::max);
        assert!(worst < 1e-6 * scale, "theta {theta}: symmetry defect {worst:e}");
        assert_eq!(
            solver.equilibrium().negative_pivots,
            0,
            "loop unstable at theta {theta}"
        );
    }
}

#[test]
fn loop_energy_derivative_identity_matches_finite_differences() {
    for twist in [EndTwist::Transported, EndTwist::Clamped] {
        let p = Params {
            end_twist: twist,
            ..params(41)
        };
        let rows = derivative_check(&p, 137.5, &[0.4, 1.6, 2.8, 4.0], 1e-3).expect("derivatives");
        for r in rows {
            let rel = (r.identity - r.finite_difference).abs() / r.finite_difference.abs().max(1e-3);
            assert!(
                rel < 2e-5,
                "{twist:?} theta {}: identity {} vs FD {}",
                r.theta,
                r.identity,
                r.finite_difference
            );
        }
    }
}

#[test]
fn landscape_at_paper_parameters_has_two_stable_states_around_an_unstable_one() {
    let l = landscape_at(params(81), 137.5);
    let stability: Vec<bool> = l.critical_points.iter().map(|c| c.stable).collect();
    assert_eq!(
        stability,
        [true, false, true],
        "critical points {:?}",
        l.critical_points
    );
    for c in &l.critical_points {
        assert!((0.0..=5.0).contains(&c.theta));
        assert_eq!(c.loop_negative_pivots, 0);
        // Stable points are local minima of the sampled energy, the unstable one a maximum.
        let i = l
            .points
            .iter()
            .position(|p| p.theta > c.theta)
            .expect("inside the grid");
        let nearby = l.points[i - 1].energy.min(l.points[i].energy);
        let farther = l.points[i.saturating_sub(3)]
            .energy
            .min(l.points[(i + 2).min(l.points.len() - 1)].energy);
        if c.stable {
            assert!(c.energy <= nearby + 1e-12 && c.energy < farther);
        } else {
            let top = l.points[i - 1].energy.max(l.points[i].energy);
            assert!(c.energy >= top - 1e-12);
        }
    }
    // One branch, no jump: the trapezoid integral of dE/dθ reproduces E.
    let mut integral = 0.0;
    for w in l.points.windows(2) {
        integral += 0.5 * (w[0].denergy_dtheta + w[1].denergy_dtheta) * (w[1].theta - w[0].theta);
        let de = w[1].energy - l.points[0].energy;
        assert!(
            (integral - de).abs() < 1e-4,
            "theta {}: integral {integral} vs {de}",
            w[1].theta
        );
    }
    assert!(l.points.iter().all(|p| p.loop_negative_pivots == 0));
    // Continuation reuses each solution: a few Newton iterations per point.
    let per_point = l.newton_iterations as f64 / l.points.len() as f64;
    assert!(per_point < 5.0, "{per_point} Newton iterations per point");
}

#[test]
fn folds_bound_the_window_of_three_critical_points() {
    let p = params(41);
    let b = bifurcation(&BifurcationSpec::for_params(p)).expect("diagram");
    assert_eq!(b.folds.len(), 2, "folds {:?}", b.folds);
    let (snap, upper) = (b.folds[0], b.folds[1]);
    assert_eq!(b.snap, Some(snap));
    assert!(snap.l_k_bar < 137.5 && 137.5 < upper.l_k_bar);
    // Stability changes exactly at the folds: stable, unstable, stable.
    let changes: Vec<usize> = b
        .branch
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[0].stable != w[1].stable)
        .map(|(i, _)| i)
        .collect();
    assert_eq!(changes.len(), 2);
    assert!(b.branch[0].stable && !b.branch[changes[0] + 1].stable && b.branch[changes[1] + 1].stable);
    assert!(b.branch.iter().all(|q| q.loop_negative_pivots == 0));
    // Independent check with landscapes: 1 % on either side of each fold.
    let count = |lk: f64| landscape_at(p, lk).critical_points.len();
    assert_eq!(count(0.99 * snap.l_k_bar), 1);
    assert_eq!(count(1.01 * snap.l_k_bar), 3);
    assert_eq!(count(0.99 * upper.l_k_bar), 3);
    assert_eq!(count(1.01 * upper.l_k_bar), 1);
    // Just above the snap, the merging pair sits near the fold's theta.
    let near = landscape_at(p, 1.001 * snap.l_k_bar);
    let pair = &near.critical_points[..2];
    assert!(
        pair.iter().all(|c| (c.theta - snap.theta).abs() < 0.1),
        "{pair:?} vs fold at {}",
        snap.theta
    );
}

#[test]
fn fold_lengths_converge_at_second_order_in_the_loop_resolution() {
    // K - 2 edges of l̄_l / (K - 2): 39, 79, 159.
    let ks = [41usize, 81, 161];
    let snaps: Vec<f64> = ks
        .iter()
        .map(|&k| {
            bifurcation(&BifurcationSpec::for_params(params(k)))
                .expect("diagram")
                .folds[0]
                .l_k_bar
        })
        .collect();
    let ratio = (snaps[1] - snaps[0]) / (snaps[2] - snaps[1]);
    let order = ratio.ln() / (159.0f64 / 79.0).ln();
    assert!((order - 2.0).abs() < 0.2, "snaps {snaps:?}, order {order}");
}

#[test]
fn snap_length_is_independent_of_the_rod_radius() {
    // h enters only through the scales, so the fold may move only within the
    // solver's tolerance: the stepper's force floor is 4e-7 EI/L² at h = 1.5 mm and
    // 2e-7 at 3.5 mm (it counts twist angles, not only coordinates, in its extent),
    // which bounds the relative error of dĒ/dθ and so of the fold length.
    let snap = |h: f64| {
        let p = Params {
            radius: h,
            ..params(41)
        };
        bifurcation(&BifurcationSpec::for_params(p))
            .expect("diagram")
            .snap
            .expect("snap")
            .l_k_bar
    };
    let (a, b) = (snap(1.5e-3), snap(3.5e-3));
    assert!((a - b).abs() < 1e-6 * a, "h = 1.5 mm: {a}, h = 3.5 mm: {b}");
}

#[test]
fn snap_length_grows_with_the_unknotting_number() {
    let run =
        |n: u32| bifurcation(&BifurcationSpec::for_params(Params { n, ..params(41) })).expect("diagram");
    let snaps: Vec<f64> = [2, 3, 4]
        .iter()
        .map(|&n| run(n).snap.expect("snap").l_k_bar)
        .collect();
    assert!(snaps[0] < snaps[1] && snaps[1] < snaps[2], "{snaps:?}");
    // n = 1: one critical point all along the window, no fold (the paper: no inversion).
    let one = run(1);
    assert!(!one.branch.is_empty() && one.folds.is_empty());
}

/// Numbers equal to 1e-12 relative, everything else exactly.
fn assert_close(a: &serde_json::Value, b: &serde_json::Value) {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().expect("f64"), y.as_f64().expect("f64"));
            assert!((x - y).abs() <= 1e-12 * x.abs().max(y.abs()), "{x} vs {y}");
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len());
            x.iter().zip(y).for_each(|(p, q)| assert_close(p, q));
        }
        (Value::Object(x), Value::Object(y)) => {
            assert_eq!(x.len(), y.len());
            for (k, v) in x {
                assert_close(v, &y[k]);
            }
        }
        _ => assert_eq!(a, b),
    }
}

#[test]
fn reproduction_round_trips_through_json() {
    let spec = ReproductionSpec {
        params: params(23),
        landscape_points: 30,
        radii: vec![2e-3],
        unknotting_numbers: vec![3],
        braid_nodes: vec![20, 40],
        loop_nodes: vec![23],
        derivative_thetas: vec![1.0],
        ..ReproductionSpec::default()
    };
    let r = reproduce(&spec).expect("reproduction");
    let json = serde_json::to_string(&r).expect("serialise");
    let back: Reproduction = serde_json::from_str(&json).expect("deserialise");
    assert_close(
        &serde_json::to_value(&back).expect("value"),
        &serde_json::to_value(&r).expect("value"),
    );
}
