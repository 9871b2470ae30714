use solver::simplified::*;

fn show(params: Params, lk: f64) {
    let spec = LandscapeSpec { params, l_k_bar: lk, theta_min: 0.0, theta_max: 5.0, points: 51 };
    match landscape(&spec) {
        Ok(l) => {
            let s: Vec<String> = l.points.iter().step_by(2).map(|p| format!("{:+.3}", p.denergy_dtheta)).collect();
            let e: Vec<String> = l.points.iter().step_by(5).map(|p| format!("{:.3}/{:.3}", p.loop_energy, p.loop_twisting)).collect();
            eprintln!("phi {:.2} tw {:?} lk {lk}: crit {:?}\n  G {}\n  El {}", params.phi, params.end_twist,
              l.critical_points.iter().map(|c| (format!("{:.3}", c.theta), c.stable)).collect::<Vec<_>>(), s.join(" "), e.join(" "));
        }
        Err(e) => eprintln!("phi {:.2} tw {:?} lk {lk}: ERR {e}", params.phi, params.end_twist),
    }
}

#[test]
fn explore() {
    for tw in [EndTwist::Transported, EndTwist::Clamped, EndTwist::Free] {
        for phi in [std::f64::consts::PI / 3.0] {
            for lk in [100.0, 137.5, 200.0, 400.0] {
                show(Params { phi, end_twist: tw, ..Params::default() }, lk);
            }
        }
    }
}
