//! An independent reference: the inextensible elastica of a cantilever under its
//! own weight, EI theta'' = -q (L - s) cos(theta), theta(0) = 0, theta'(L) = 0,
//! solved by shooting on theta'(0) with RK4 and bisection (nondimensional, L = 1).

/// Integrates theta'' = -alpha (1 - s) cos(theta) from s = 0 with theta'(0) = k0;
/// returns (theta'(1), tip deflection int_0^1 sin(theta) ds).
fn shoot(alpha: f64, k0: f64) -> (f64, f64) {
    let n = 4000;
    let h = 1.0 / n as f64;
    let rhs = |s: f64, y: [f64; 3]| [y[1], -alpha * (1.0 - s) * y[0].cos(), y[0].sin()];
    let mut y = [0.0, k0, 0.0];
    for i in 0..n {
        let s = i as f64 * h;
        let add = |y: [f64; 3], k: [f64; 3], c: f64| [y[0] + c * k[0], y[1] + c * k[1], y[2] + c * k[2]];
        let k1 = rhs(s, y);
        let k2 = rhs(s + h / 2.0, add(y, k1, h / 2.0));
        let k3 = rhs(s + h / 2.0, add(y, k2, h / 2.0));
        let k4 = rhs(s + h, add(y, k3, h));
        for c in 0..3 {
            y[c] += h / 6.0 * (k1[c] + 2.0 * k2[c] + 2.0 * k3[c] + k4[c]);
        }
    }
    (y[1], y[2])
}

/// Tip deflection / L of a cantilever under distributed load alpha = q L^3 / EI.
/// theta'(1) decreases monotonically in theta'(0) on [0, alpha/2]: bisect there.
pub fn cantilever_tip_deflection(alpha: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, alpha / 2.0);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if shoot(alpha, mid).0 < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    shoot(alpha, 0.5 * (lo + hi)).1
}

#[cfg(test)]
mod tests {
    #[test]
    fn small_load_matches_euler_bernoulli() {
        let alpha = 1e-3;
        let w = super::cantilever_tip_deflection(alpha);
        assert!((w / (alpha / 8.0) - 1.0).abs() < 1e-4);
    }
}
