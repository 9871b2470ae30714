//! The warm start of each contact solve: the forces of the last two solves
//! by segment pair.
use nalgebra::Vector3;

/// The contact forces of the last two solves, by segment pair, for the
/// next solve's warm start.
#[derive(Default)]
pub(super) struct ForceHistory {
    /// Pair ids (sorted) and forces of the last solve, and its step.
    ids: Vec<(usize, usize)>,
    forces: Vec<Vector3<f64>>,
    dt: f64,
    /// The same for the solve before it.
    prev_ids: Vec<(usize, usize)>,
    prev_forces: Vec<Vector3<f64>>,
    prev_dt: f64,
}

impl Clone for ForceHistory {
    fn clone(&self) -> Self {
        let mut copy = Self::default();
        copy.clone_from(self);
        copy
    }

    /// Reuses this history's buffers (a checkpoint every step allocates nothing).
    fn clone_from(&mut self, source: &Self) {
        self.ids.clone_from(&source.ids);
        self.forces.clone_from(&source.forces);
        self.dt = source.dt;
        self.prev_ids.clone_from(&source.prev_ids);
        self.prev_forces.clone_from(&source.prev_forces);
        self.prev_dt = source.prev_dt;
    }
}

impl ForceHistory {
    /// The warm start of each of `pair_ids` (sorted) for a step of `dt`:
    /// where the pair was in contact at the last two solves of this step
    /// size, the force extrapolated linearly from them (the pull changes
    /// the forces smoothly, so this is closer to the solution than the last
    /// force); where only at the last, that force; else, with `follow`, the
    /// last force of a neighbouring pair (segments `i +- 1`, `j +- 1`) that
    /// is no longer a contact: a smooth contact sliding into the next
    /// pieces (where merging keeps one pair of the neighbours), else zero.
    pub(super) fn warm_start(
        &self,
        pair_ids: &[(usize, usize)],
        dt: f64,
        follow: bool,
        out: &mut Vec<Vector3<f64>>,
    ) {
        out.clear();
        let extrapolate = self.dt == dt && self.prev_dt == dt;
        let (mut k, mut m) = (0, 0);
        for id in pair_ids {
            while k < self.ids.len() && self.ids[k] < *id {
                k += 1;
            }
            while m < self.prev_ids.len() && self.prev_ids[m] < *id {
                m += 1;
            }
            let last = (k < self.ids.len() && self.ids[k] == *id).then(|| self.forces[k]);
            let before = (m < self.prev_ids.len() && self.prev_ids[m] == *id).then(|| self.prev_forces[m]);
            out.push(match (last, before) {
                (Some(f1), Some(f0)) if extrapolate => 2.0 * f1 - f0,
                (Some(f1), _) => f1,
                _ if follow => self.followed(pair_ids, *id),
                _ => Vector3::zeros(),
            });
        }
    }

    /// The last force of the first neighbour of pair `(i, j)` (segments
    /// `i - 1 ... i + 1` by `j - 1 ... j + 1`) that was a contact at the last
    /// solve and is not among `pair_ids`; zero if none.
    fn followed(&self, pair_ids: &[(usize, usize)], (i, j): (usize, usize)) -> Vector3<f64> {
        for di in -1..=1 {
            for dj in -1..=1 {
                let (Some(a), Some(b)) = (i.checked_add_signed(di), j.checked_add_signed(dj)) else {
                    continue;
                };
                if (di, dj) == (0, 0) || pair_ids.binary_search(&(a, b)).is_ok() {
                    continue;
                }
                if let Ok(k) = self.ids.binary_search(&(a, b)) {
                    return self.forces[k];
                }
            }
        }
        Vector3::zeros()
    }

    /// Records a solve's forces: the last solve becomes the one before.
    pub(super) fn push(&mut self, pair_ids: &[(usize, usize)], forces: &[Vector3<f64>], dt: f64) {
        std::mem::swap(&mut self.ids, &mut self.prev_ids);
        std::mem::swap(&mut self.forces, &mut self.prev_forces);
        self.prev_dt = self.dt;
        self.ids.clear();
        self.ids.extend_from_slice(pair_ids);
        self.forces.clear();
        self.forces.extend_from_slice(forces);
        self.dt = dt;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A contact that slid from pair (3, 10) to (4, 11) starts from (3, 10)'s
    /// force when it follows, from zero when it does not, and a pair whose
    /// neighbour is still a contact does not take that neighbour's force.
    #[test]
    fn a_new_pair_follows_the_neighbour_that_left() {
        let (f, g) = (Vector3::new(1.0, 2.0, 3.0), Vector3::new(-4.0, 0.5, 0.0));
        let mut history = ForceHistory::default();
        history.push(&[(3, 10), (20, 40)], &[f, g], 1e-3);
        let mut out = Vec::new();
        history.warm_start(&[(4, 11), (20, 40)], 1e-3, true, &mut out);
        assert_eq!(out, [f, g]);
        history.warm_start(&[(4, 11), (20, 40)], 1e-3, false, &mut out);
        assert_eq!(out, [Vector3::zeros(), g]);
        history.warm_start(&[(3, 10), (4, 11)], 1e-3, true, &mut out);
        assert_eq!(out, [f, Vector3::zeros()]);
        // Two apart is no neighbour.
        history.warm_start(&[(5, 12)], 1e-3, true, &mut out);
        assert_eq!(out, [Vector3::zeros()]);
    }
}
