//! Parallel transport and angles used for the reference frames (paper Sec. 3.1):
//! frames are carried from step to step by time-parallel transport, and the
//! reference twist of eq. (5) is measured by space-parallel transport.
use nalgebra::Vector3;

/// Transports `v` from unit tangent `a` to unit tangent `b` by the rotation about
/// `a x b` that takes `a` to `b` (the minimal rotation).
#[inline]
pub fn parallel_transport(v: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> Vector3<f64> {
    transport_by(v, a, &a.cross(b), a.dot(b))
}

/// [`parallel_transport`] given `c = a x b` and `d = a . b` (the curvature
/// binormal's ingredients, which the caller already has).
#[inline(always)]
pub fn transport_by(v: &Vector3<f64>, a: &Vector3<f64>, c: &Vector3<f64>, d: f64) -> Vector3<f64> {
    if 1.0 + d > 1e-12 {
        v * d + c.cross(v) + c * (c.dot(v) / (1.0 + d))
    } else {
        half_turn(v, a)
    }
}

/// Antiparallel tangents: any axis normal to `a` is a minimal rotation by pi.
#[cold]
fn half_turn(v: &Vector3<f64>, a: &Vector3<f64>) -> Vector3<f64> {
    let k = perpendicular(a);
    -v + k * (2.0 * k.dot(v))
}

/// A unit vector perpendicular to the unit vector `a`.
pub fn perpendicular(a: &Vector3<f64>) -> Vector3<f64> {
    let trial = if a.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    (trial - a * a.dot(&trial)).normalize()
}

/// Signed angle from `u` to `v` about the axis `n` (both normal to `n`), in (-pi, pi].
#[inline]
pub fn signed_angle(u: &Vector3<f64>, v: &Vector3<f64>, n: &Vector3<f64>) -> f64 {
    u.cross(v).dot(n).atan2(u.dot(v))
}

/// The representative of `angle` modulo 2 pi that is closest to `near`.
#[inline]
pub fn unwrap_near(angle: f64, near: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let turns = (near - angle) / two_pi;
    // Within half a turn (the usual case) `turns` rounds to zero: skip the call.
    if turns.abs() < 0.5 {
        angle
    } else {
        angle + two_pi * turns.round()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transport_maps_tangent_and_preserves_angles() {
        let a = Vector3::new(0.3, -0.2, 0.9).normalize();
        let b = Vector3::new(-0.5, 0.4, 0.1).normalize();
        let t = parallel_transport(&a, &a, &b);
        assert!((t - b).norm() < 1e-14);
        let u = perpendicular(&a);
        let pu = parallel_transport(&u, &a, &b);
        assert!(pu.dot(&b).abs() < 1e-14);
        assert!((pu.norm() - 1.0).abs() < 1e-14);
        // A vector along a x b is left unchanged.
        let axis = a.cross(&b).normalize();
        assert!((parallel_transport(&axis, &a, &b) - axis).norm() < 1e-14);
        // Antiparallel case still maps a to b and stays orthogonal.
        let pm = parallel_transport(&u, &a, &(-a));
        assert!(pm.dot(&a).abs() < 1e-14);
    }

    #[test]
    fn signed_angle_and_unwrap() {
        let n = Vector3::z();
        let u = Vector3::x();
        let v = Vector3::new(0.0, 1.0, 0.0);
        assert!((signed_angle(&u, &v, &n) - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!((signed_angle(&v, &u, &n) + std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!((unwrap_near(0.1, 6.3) - (0.1 + std::f64::consts::TAU)).abs() < 1e-15);
        // Within half a turn the angle stays; just beyond, it moves by a turn.
        assert_eq!(unwrap_near(3.0, -0.1), 3.0);
        assert!((unwrap_near(3.2, 0.0) - (3.2 - std::f64::consts::TAU)).abs() < 1e-15);
        assert!((unwrap_near(-3.2, 0.0) - (-3.2 + std::f64::consts::TAU)).abs() < 1e-15);
    }
}
