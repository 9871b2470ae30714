//! A knot pulled tight: its own length no longer gives under the pull. A
//! tightening without a target or a force to stop at ends there as at
//! `min_l_k_bar`: a knot that locks above that length would otherwise be
//! pulled on while the rod stretches, since the knot's own length cannot
//! reach it (the paper's rod n = 6 pulled on past its inversion, `knotsweep
//! run --n 6 --stop-after-inversion 1000`, is tight at l_k arc bar 125.7 and
//! F bar 0.51, l_k bar 60.1).
//!
//! The rule reads the knot's compliance, its own length's give per F bar,
//! not the share of the clamps' travel it takes: on a rod longer than its
//! knot the tails take most of the travel at any force (a rubber tail of
//! 4 375 radii three quarters at F bar 0.17, [`super::adaptive`]), while a
//! tight knot gives a few radii per tenth of F bar whatever the tails do.
use crate::measurements::Sample;

/// The rise of F bar over which the knot's give is read...
pub(super) const TIGHT_FORCE_RISE: f64 = 0.1;
/// ...and the largest give (radii of its own length) of a tight knot over it.
/// A knot that tightens towards an inversion gives far more: the paper's rod
/// n = 3 gives 287 radii from its start to its inversion while F bar rises to
/// 0.045, 50 over its last 0.02 (`knotsweep run --n 3`); the paper's rod
/// n = 6 above, 4.8 over its last tenth of F bar.
pub(super) const TIGHT_GIVE: f64 = 5.0;

/// Whether the knot is tight at the last of `series` (a tightening stage's
/// samples, in order): since the last sample whose F bar lay
/// [`TIGHT_FORCE_RISE`] below the last one's, its own length has fallen by
/// less than [`TIGHT_GIVE`]. `false` until F bar has risen that far.
pub(super) fn is_tight(series: &[Sample]) -> bool {
    let Some(last) = series.last() else {
        return false;
    };
    series
        .iter()
        .rev()
        .find(|s| s.f_bar <= last.f_bar - TIGHT_FORCE_RISE)
        .is_some_and(|s| s.l_k_arc_bar - last.l_k_arc_bar < TIGHT_GIVE)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples every 0.5 in l_k bar from 400 down: the own length gives
    /// `give` radii per unit of F bar, which rises by `slope` per l_k bar.
    fn pull(give: f64, slope: f64, samples: usize) -> Vec<Sample> {
        (0..samples)
            .map(|i| {
                let travel = 0.5 * i as f64;
                let f_bar = 0.01 + slope * travel;
                Sample {
                    l_k_bar: 400.0 - travel,
                    l_k_arc_bar: 400.0 - give * (f_bar - 0.01),
                    f_bar,
                    ..Sample::default()
                }
            })
            .collect()
    }

    #[test]
    fn a_knot_is_tight_when_its_own_length_no_longer_gives() {
        // Locked: 24 radii per unit F bar (2.4 per tenth), however slowly the
        // force rises with the clamps' travel (long tails take most of it).
        assert!(is_tight(&pull(24.0, 0.004, 100)));
        assert!(is_tight(&pull(24.0, 0.0005, 600)));
        // Still tightening: 500 radii per unit F bar.
        assert!(!is_tight(&pull(500.0, 0.004, 100)));
        // Just above and below the give over a tenth of F bar.
        assert!(!is_tight(&pull(10.0 * TIGHT_GIVE * 1.05, 0.004, 100)));
        assert!(is_tight(&pull(10.0 * TIGHT_GIVE * 0.95, 0.004, 100)));
        // Not before F bar has risen by a tenth.
        assert!(!is_tight(&pull(24.0, 0.004, 40)));
        assert!(!is_tight(&[]));
    }
}
