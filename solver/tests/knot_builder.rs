use solver::knot::*;
use std::time::Instant;

#[test]
fn explore() {
    for h in [1.6e-3, 3.4e-3] {
        for k in [201usize, 301] {
            for n in 1..=8 {
                let mut spec = KnotSpec::paper(n);
                spec.radius = h;
                spec.nodes = k;
                let t = Instant::now();
                match build(&spec) {
                    Ok(s) => {
                        println!(
                            "h={h} K={k} n={n}: lb={:.3} ll={:.3} lt={:.3} lc={:.3} a={:.4} {:?}",
                            s.braid_length, s.loop_length, s.tail_length, s.end_to_end, s.helix_radius, t.elapsed()
                        );
                        if k == 301 {
                            std::fs::write(format!("/tmp/knot_{n}_{h}.json"), serde_json::to_string(&s).unwrap()).unwrap();
                        }
                    }
                    Err(e) => println!("h={h} K={k} n={n}: ERR {e} {:?}", t.elapsed()),
                }
            }
        }
    }
}
