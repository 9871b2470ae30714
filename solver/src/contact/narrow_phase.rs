//! The narrow phase's choices (paper Sec. 3.2): which candidate pairs from
//! the broad phase become contacts, and eq. (9)'s sliding direction.
use super::broad_phase::{CandidatePair, Segment};
use nalgebra::Vector3;

/// Whether candidate `k` duplicates a neighbour: its closest point lies on a
/// node shared with the adjacent segment of the same rod, and that segment also
/// pairs with the same partner. Such an endpoint pair has a normal tilted
/// towards the node, and closing its linearised gap would push back on a rod
/// sliding smoothly from one segment onto the next. When both pairs meet at the
/// shared node, the one with the lower segment index is kept.
pub(crate) fn redundant(pairs: &[CandidatePair], k: usize, segments: &[Segment]) -> bool {
    const END: f64 = 1e-9;
    let p = &pairs[k];
    let find = |i: usize, j: usize| {
        let key = if i < j { (i, j) } else { (j, i) };
        pairs
            .binary_search_by(|q| (q.i, q.j).cmp(&key))
            .ok() // Err: no such pair (not a failure)
            .map(|m| (m, key.0 == i))
    };
    // (this segment, partner, parameter on this segment)
    for (me, other, param) in [(p.i, p.j, p.closest.s), (p.j, p.i, p.closest.t)] {
        let seg = &segments[me];
        let neighbour = if param <= END {
            me.checked_sub(1)
        } else if param >= 1.0 - END {
            Some(me + 1)
        } else {
            None
        };
        let Some(n) = neighbour.filter(|&n| {
            n < segments.len() && segments[n].body == seg.body && segments[n].index.abs_diff(seg.index) == 1
        }) else {
            continue;
        };
        if n == other {
            continue;
        }
        if let Some((m, n_is_first)) = find(n, other) {
            let q = &pairs[m];
            let n_param = if n_is_first { q.closest.s } else { q.closest.t };
            let n_at_shared = if n < me {
                n_param >= 1.0 - END
            } else {
                n_param <= END
            };
            if !n_at_shared || n < me {
                return true;
            }
        }
    }
    false
}

/// Eq. (9)'s `t = u_t / |u_t|`: the tangential part of `u`, the relative
/// velocity of the contact points (A relative to B) at the start of the
/// step, against the contact's unit `normal`; zero when there is none.
pub(crate) fn sliding_direction(u: &Vector3<f64>, normal: &Vector3<f64>) -> Vector3<f64> {
    let ut = u - normal * u.dot(normal);
    let norm = ut.norm();
    if norm > 0.0 { ut / norm } else { Vector3::zeros() }
}
