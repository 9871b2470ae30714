//! How finely and how fast a case is computed: its node count, time step,
//! inertia and time unit, from its rod and pull.
//!
//! Inversion is quasi-static: its l_k bar depends on the geometry (n, L/h),
//! mu and nu, not on E or rho (the paper's Sec. 4 and supplement). The
//! solver's cost does depend on them, through two ratios:
//! - The pull rate Pi = u / c, the clamp speed u over the rod's wave speed
//!   c = sqrt(E / rho). A pull takes a number of steps proportional to 1/Pi
//!   (the step is bounded by the rod's dynamics at the edge scale, the pull's
//!   length by the knot). Where Pi is below the paper's rod's
//!   ([`reference_pull_rate`]: 3 mm/s on E = 1.8 MPa, rho = 1000), the
//!   inertia is scaled up by s = (Pi_ref / Pi)^2 (mass scaling): the case then
//!   has the paper's pull rate, which converges the paper's inversion within
//!   0.2 % (docs/VALIDATION.md, the pull-speed rows), and the paper's cost.
//!   Weight stays physical (the simulated gravity is g / s), so that gravity
//!   keeps its part (through the gravito-bending length (E h^2 / 8 rho g)^(1/3)).
//!   Whether a case was quasi-static is measured, not assumed
//!   (`protocol::QuasiStatic`).
//! - The slenderness L/h. The knot's lengths scale with h
//!   ([`crate::knot::KNOT_RADII`]), so edges of [`EDGE_RADII`] h resolve it
//!   as the paper's K = 301 resolves its rod, and the default node count grows
//!   with L/h ([`default_nodes`]). The time step keeps the ratio of the rod's
//!   bending stiffness at the edge scale to the contact's inertial stiffness
//!   m / dt^2 (Sec. 3.2, eq. 10) at the paper's (`CaseParams::time_step`), so
//!   that it is proportional to h: the pull, also proportional to h, takes the
//!   paper's number of steps, and the cost grows as K, linearly in L/h.
//!
//! The time unit T of a case is the time its knot's dynamics takes over the
//! paper's rod's: times and rates of the protocol (relaxation, settling,
//! damping) are the paper's rod's scaled by it.
use super::CaseParams;

/// The paper's rod: radius h (m), length L (m), node count K, Young's modulus
/// E (Pa), density rho (kg/m^3) and clamp speed (m/s) of its code.
pub const REFERENCE_RADIUS: f64 = 1.6e-3;
pub const REFERENCE_LENGTH: f64 = 1.0;
pub const REFERENCE_NODES: usize = 301;
pub const REFERENCE_YOUNGS_MODULUS: f64 = 1.8e6;
pub const REFERENCE_DENSITY: f64 = 1000.0;
pub const REFERENCE_PULL_SPEED: f64 = 3e-3;
/// The paper's edge length (m): L = 1 m with K = 301 nodes.
pub const REFERENCE_EDGE: f64 = REFERENCE_LENGTH / (REFERENCE_NODES - 1) as f64;
/// The default (largest) time step (s) of the paper's rod: half the paper's
/// code's 1 ms (docs/VALIDATION.md's convergence rows: halving it moves the
/// n = 3 inversion by 0.4 %).
pub const REFERENCE_DT: f64 = 5e-4;
/// The default edge length over the radius: the paper's, 2.08.
pub const EDGE_RADII: f64 = REFERENCE_EDGE / REFERENCE_RADIUS;
/// The paper's rod's longest relaxation (s).
pub const REFERENCE_RELAX_TIME: f64 = 2.0;
/// The largest time step taken without one given, over the paper's rod's
/// step in the rod's time unit (a coarse mesh's step is capped).
pub const MAX_DT_RATIO: f64 = 20.0;

/// Pi = u / sqrt(E / rho): the clamp speed over the rod's wave speed.
pub fn pull_rate(pull_speed: f64, youngs_modulus: f64, density: f64) -> f64 {
    pull_speed / (youngs_modulus / density).sqrt()
}

/// The paper's rod's pull rate, 7.1e-5.
pub fn reference_pull_rate() -> f64 {
    pull_rate(REFERENCE_PULL_SPEED, REFERENCE_YOUNGS_MODULUS, REFERENCE_DENSITY)
}

/// The default node count for a rod of `length` and radius `h`: edges of
/// at most [`EDGE_RADII`] h and at least the paper's 301 nodes, at most
/// `max`. One rule for every friction: strands slide along each other's
/// smooth centre lines without the polyline's bumps, so the frictionless
/// knot is reversible at the paper's K (docs/FIDELITY.md, "Reversibility
/// without friction").
pub fn default_nodes(length: f64, h: f64, max: usize) -> usize {
    let edges = (length / (EDGE_RADII * h) * (1.0 - 1e-12)).ceil() as usize;
    (edges + 1).clamp(REFERENCE_NODES, max)
}

/// The inertia and time unit a case is computed with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scales {
    /// s >= 1: the factor on the rod's density in its inertia (mass scaling;
    /// 1 where the rod pulls faster than the paper's or scaling is off).
    pub mass_scale: f64,
    /// The paper's rod's wave speed over the simulated one,
    /// sqrt(E_ref / rho_ref) / sqrt(E / (s rho)).
    pub slowness: f64,
    /// T: the case's time over the paper's rod's, the slowness times h / h_ref
    /// (at most the slowness: a thicker rod's knot is not slower).
    pub time_unit: f64,
    /// The simulated pull rate over the paper's rod's, at least 1 with mass
    /// scaling.
    pub pull_rate_ratio: f64,
}

impl CaseParams {
    /// The clamps' speed (m/s): `pull_speed`, else the paper's pull rate for
    /// this rod, [`REFERENCE_PULL_SPEED`] times its wave speed over the
    /// paper's rod's.
    pub fn clamp_speed(&self) -> f64 {
        self.pull_speed.unwrap_or_else(|| {
            let waves = (self.youngs_modulus / self.density) / (REFERENCE_YOUNGS_MODULUS / REFERENCE_DENSITY);
            REFERENCE_PULL_SPEED * waves.sqrt()
        })
    }

    /// The case's physical pull rate Pi ([`pull_rate`]).
    pub fn pull_rate(&self) -> f64 {
        pull_rate(self.clamp_speed(), self.youngs_modulus, self.density)
    }

    /// The longest relaxation (s): `relax_time`, else
    /// [`REFERENCE_RELAX_TIME`] in the case's time unit.
    pub fn relax_limit(&self) -> f64 {
        self.relax_time
            .unwrap_or_else(|| REFERENCE_RELAX_TIME * self.scales().time_unit)
    }

    /// The mass scaling and time unit of this case (module documentation).
    pub fn scales(&self) -> Scales {
        let ratio = reference_pull_rate() / self.pull_rate();
        let mass_scale = if self.mass_scaling && ratio > 1.0 {
            ratio * ratio
        } else {
            1.0
        };
        let speed = self.clamp_speed();
        let pull_rate_ratio =
            pull_rate(speed, self.youngs_modulus, self.density * mass_scale) / reference_pull_rate();
        let slowness = pull_rate_ratio * (REFERENCE_PULL_SPEED / speed);
        Scales {
            mass_scale,
            slowness,
            time_unit: slowness * (self.h / REFERENCE_RADIUS).min(1.0),
            pull_rate_ratio,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_papers_rod_is_the_unit() {
        let paper = CaseParams::default();
        assert_eq!(
            paper.scales(),
            Scales {
                mass_scale: 1.0,
                slowness: 1.0,
                time_unit: 1.0,
                pull_rate_ratio: 1.0,
            }
        );
        assert_eq!(default_nodes(1.0, 1.6e-3, 4001), 301);
        assert_eq!(default_nodes(1.0, 3.4e-3, 4001), 301);
        assert_eq!(default_nodes(1.0, 4e-4, 4001), 1201);
        assert_eq!(default_nodes(1.0, 1e-4, 4001), 4001);
    }

    /// By default every rod is pulled at the paper's rate: the same
    /// problem in the units of eq. (11), with the time unit of its waves.
    #[test]
    fn the_default_pull_is_at_the_papers_rate() {
        for (e, rho) in [(1e4, 8000.0), (1.8e6, 1000.0), (2e11, 7850.0), (3e9, 500.0)] {
            let p = CaseParams {
                youngs_modulus: e,
                density: rho,
                ..CaseParams::default()
            };
            let s = p.scales();
            assert_eq!(s.mass_scale, 1.0);
            assert!((p.pull_rate() / reference_pull_rate() - 1.0).abs() < 1e-12);
            let waves = (e / rho / 1800.0).sqrt();
            assert!((s.time_unit * waves - 1.0).abs() < 1e-12, "E {e} rho {rho}");
        }
        assert_eq!(CaseParams::default().clamp_speed(), REFERENCE_PULL_SPEED);
    }

    /// Mass scaling makes the simulated wave speed u / Pi_ref: a rod 100
    /// times stiffer pulled at 3 mm/s gets 100 times the inertia and the
    /// paper's time unit; a faster pull than the paper's is computed with the
    /// physical inertia.
    #[test]
    fn mass_scaling_gives_the_papers_pull_rate() {
        let at_3mm = |e: f64, rho: f64| CaseParams {
            youngs_modulus: e,
            density: rho,
            pull_speed: Some(3e-3),
            ..CaseParams::default()
        };
        let s = at_3mm(1.8e8, 1000.0).scales();
        assert!((s.mass_scale - 100.0).abs() < 1e-9 && (s.time_unit - 1.0).abs() < 1e-12);
        let steel = at_3mm(2e11, 7850.0);
        let simulated = pull_rate(3e-3, 2e11, 7850.0 * steel.scales().mass_scale);
        assert!((simulated / reference_pull_rate() - 1.0).abs() < 1e-12);
        assert!((steel.scales().pull_rate_ratio - 1.0).abs() < 1e-12);
        let slow = CaseParams {
            pull_speed: Some(1e-3),
            ..CaseParams::default()
        };
        let s = slow.scales();
        assert!((s.mass_scale - 9.0).abs() < 1e-9 && (s.time_unit - 3.0).abs() < 1e-12);
        let soft = at_3mm(1.8e4, 1000.0).scales();
        assert_eq!(soft.mass_scale, 1.0);
        assert!((soft.time_unit - 10.0).abs() < 1e-9, "waves 10 times slower");
        assert!(
            (soft.pull_rate_ratio - 10.0).abs() < 1e-9,
            "a pull 10 times the paper's rate"
        );
        let physical = CaseParams {
            mass_scaling: false,
            ..at_3mm(1.8e8, 1000.0)
        };
        assert_eq!(physical.scales().mass_scale, 1.0);
        assert!((physical.scales().time_unit - 0.1).abs() < 1e-12);
        let thin = CaseParams {
            h: 4e-4,
            ..CaseParams::default()
        };
        assert!((thin.scales().time_unit - 0.25).abs() < 1e-12);
    }
}
