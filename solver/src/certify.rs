//! Certified inversion points: a case's numerical uncertainty, measured by a
//! refined twin.
//!
//! The twin is the case with its (largest) time step halved: of the
//! convergence study's refinements (docs/VALIDATION.md, the convergence rows)
//! it is the one that moves the inversion most per unit of cost (a finer mesh
//! also shrinks the step, with the square of the edge length, and costs more),
//! so that a certified sweep costs about 3 times an uncertified one.
use crate::case::CaseParams;
use crate::measurements::Inversion;
use serde::{Deserialize, Serialize};

/// Relative uncertainty above which a point is flagged as unconverged.
pub const CONVERGED_WITHIN: f64 = 0.02;

/// The refined twin of `params`: the same case with its largest time step
/// halved.
pub fn refined(params: &CaseParams) -> CaseParams {
    CaseParams {
        dt: Some(params.time_step() / 2.0),
        ..params.clone()
    }
}

/// The numerical uncertainty of an inversion point from its refined twin.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Uncertainty {
    /// The twin's inversion l_k bar (null when it has none or has not run).
    pub refined_l_k_bar: Option<f64>,
    /// |refined - default| in l_k bar (null unless both inverted).
    pub absolute: Option<f64>,
    /// `absolute` over the default's l_k bar.
    pub relative: Option<f64>,
    /// `relative` is at most [`CONVERGED_WITHIN`]; false when only one of the
    /// two inverted, null while the twin has no result.
    pub converged: Option<bool>,
}

impl Uncertainty {
    /// From the default case's inversion and the twin's, `refined` being
    /// `None` while the twin has no result.
    pub fn new(default: Option<&Inversion>, refined: Option<Option<&Inversion>>) -> Self {
        let Some(refined) = refined else {
            return Self {
                refined_l_k_bar: None,
                absolute: None,
                relative: None,
                converged: None,
            };
        };
        let refined_l_k_bar = refined.map(|r| r.l_k_bar);
        match (default, refined) {
            (Some(d), Some(r)) => {
                let absolute = (r.l_k_bar - d.l_k_bar).abs();
                let relative = absolute / d.l_k_bar;
                Self {
                    refined_l_k_bar,
                    absolute: Some(absolute),
                    relative: Some(relative),
                    converged: Some(relative <= CONVERGED_WITHIN),
                }
            }
            (None, None) => Self {
                refined_l_k_bar,
                absolute: None,
                relative: None,
                converged: Some(true),
            },
            _ => Self {
                refined_l_k_bar,
                absolute: None,
                relative: None,
                converged: Some(false),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(l_k_bar: f64) -> Inversion {
        Inversion {
            l_k_bar,
            l_k_arc_bar: l_k_bar,
            l_c_over_l: 0.0,
            f_bar_before: 0.0,
            f_bar_after: 0.0,
            h_bar_before: 0.0,
            h_bar_after: 0.0,
            kinetic_energy_ratio: 0.0,
            sample: 0,
        }
    }

    #[test]
    fn the_twin_halves_the_step_only() {
        let p = CaseParams::default();
        let twin = refined(&p);
        assert_eq!(twin.time_step(), p.time_step() / 2.0);
        assert_eq!(CaseParams { dt: p.dt, ..twin }, p);
    }

    #[test]
    fn uncertainty_is_the_twins_distance() {
        let u = Uncertainty::new(Some(&at(100.0)), Some(Some(&at(101.5))));
        assert_eq!(u.absolute, Some(1.5));
        assert!((u.relative.unwrap() - 0.015).abs() < 1e-12);
        assert_eq!(u.converged, Some(true));
        let far = Uncertainty::new(Some(&at(100.0)), Some(Some(&at(97.0))));
        assert_eq!(far.converged, Some(false), "3 % is above the threshold");
        let lost = Uncertainty::new(Some(&at(100.0)), Some(None));
        assert_eq!((lost.absolute, lost.converged), (None, Some(false)));
        let neither = Uncertainty::new(None, Some(None));
        assert_eq!(neither.converged, Some(true), "both agree there is no inversion");
        let pending = Uncertainty::new(Some(&at(100.0)), None);
        assert_eq!(pending.converged, None);
    }
}
