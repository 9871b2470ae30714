//! General sparse symmetric systems (faer), for couplings that break the band.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::LdltError;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLdltRef;
use faer::sparse::linalg::cholesky::{
    LdltRef, SymbolicCholeskyRaw, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{CreationError, FaerError, SparseColMat, Triplet};
use faer::{Conj, MatMut, Par, Side};
use thiserror::Error;

use super::banded::{BandedSym, FactorError, Inertia, PIVOT_RTOL};

/// Failure of [`SparseSym::solve`].
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum SparseError {
    /// The triplets could not be compressed into a sparse matrix.
    #[error("sparse assembly failed: {0:?}")]
    Assembly(CreationError),
    /// Allocation or index overflow inside faer.
    #[error("sparse factorisation failed: {0}")]
    Faer(#[from] FaerError),
    /// faer rejected a zero or non-finite pivot (index in the AMD order).
    #[error("sparse LDL^T: pivot {index} (AMD order) is zero or not finite")]
    RejectedPivot {
        /// Pivot index in the fill-reducing elimination order.
        index: usize,
    },
    /// A pivot is zero, non-finite or tiny (same test as [`BandedLdlt`](super::banded::BandedLdlt));
    /// its index is in the fill-reducing (AMD) elimination order.
    #[error("sparse LDL^T: {0}")]
    Pivot(#[from] FactorError),
}

/// Symmetric `n x n` matrix assembled from triplets of its lower triangle.
///
/// `A[i][j]` and `A[j][i]` are one entry: [`SparseSym::add`] stores `(max, min)`,
/// so for an off-diagonal pair add only one of the two. Repeated entries
/// accumulate.
#[derive(Debug, Clone, Default)]
pub struct SparseSym {
    n: usize,
    entries: Vec<Triplet<usize, usize, f64>>,
}

impl SparseSym {
    /// Zero matrix of dimension `n`.
    pub fn new(n: usize) -> Self {
        Self {
            n,
            entries: Vec::new(),
        }
    }

    /// Copy of a banded matrix (its nonzero lower-band entries).
    pub fn from_banded(a: &BandedSym) -> Self {
        let mut s = Self::new(a.n());
        for i in 0..a.n() {
            for j in i.saturating_sub(a.kd())..=i {
                let v = a.get(i, j);
                if v != 0.0 {
                    s.entries.push(Triplet::new(i, j, v));
                }
            }
        }
        s
    }

    /// Dimension.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of stored triplets (duplicates counted separately).
    pub fn nnz(&self) -> usize {
        self.entries.len()
    }

    /// Removes all entries, keeping the allocation.
    pub fn clear(&mut self) {
        self.entries.clear();
    }

    /// Accumulates `v` into the symmetric entry `A[i][j] = A[j][i]`.
    ///
    /// `add(i, j, v)` and `add(j, i, v)` hit the same entry. Panics if an index is `>= n`.
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        assert!(
            i < self.n && j < self.n,
            "entry ({i}, {j}) out of range (n = {})",
            self.n
        );
        self.entries.push(Triplet::new(i.max(j), i.min(j), v));
    }

    /// Zeros row and column `i` and sets `A[i][i] = 1` (Dirichlet DOF).
    ///
    /// Entries added afterwards accumulate as usual; constrain after assembly.
    pub fn constrain(&mut self, i: usize) {
        assert!(i < self.n, "constrain({i}) out of range (n = {})", self.n);
        self.entries.retain(|t| t.row != i && t.col != i);
        self.entries.push(Triplet::new(i, i, 1.0));
    }

    /// Solves `A x = b` with faer's sparse LDL^T (AMD ordering, no pivoting).
    /// Panics if `b.len() != n`.
    pub fn solve(&self, b: &[f64]) -> Result<Vec<f64>, SparseError> {
        self.solve_with_inertia(b).map(|(x, _)| x)
    }

    /// [`SparseSym::solve`], also returning the inertia of `A`.
    pub fn solve_with_inertia(&self, b: &[f64]) -> Result<(Vec<f64>, Inertia), SparseError> {
        assert_eq!(b.len(), self.n, "solve: length mismatch");
        let n = self.n;
        let mat = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &self.entries)
            .map_err(SparseError::Assembly)?;
        let symbolic = factorize_symbolic_cholesky(
            mat.symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )?;
        let scale = (0..n)
            .flat_map(|j| {
                mat.row_idx_of_col(j)
                    .zip(mat.val_of_col(j))
                    .filter(move |&(i, _)| i == j)
            })
            .fold(0.0_f64, |s, (_, v)| s.max(v.abs()));
        let par = Par::Seq;
        let mut mem = MemBuffer::try_new(StackReq::any_of(&[
            symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, par),
        ]))
        .map_err(FaerError::from)?;
        let mut values = vec![0.0; symbolic.len_val()];
        symbolic
            .factorize_numeric_ldlt(
                &mut values,
                mat.as_ref(),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|LdltError::ZeroPivot { index }| SparseError::RejectedPivot { index })?;

        let pivots: Vec<f64> = match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => s.col_ptr()[..n].iter().map(|&p| values[p]).collect(),
            SymbolicCholeskyRaw::Supernodal(s) => {
                let l = SupernodalLdltRef::new(s, &values);
                (0..s.n_supernodes())
                    .flat_map(|k| {
                        let v = l.supernode(k).val();
                        (0..v.ncols()).map(move |j| v[(j, j)])
                    })
                    .collect()
            }
        };
        let mut inertia = Inertia::default();
        for (index, &pivot) in pivots.iter().enumerate() {
            if !pivot.is_finite() {
                return Err(FactorError::NonFinitePivot { index, pivot }.into());
            }
            if pivot.abs() <= PIVOT_RTOL * scale {
                return Err(FactorError::SmallPivot { index, pivot, scale }.into());
            }
            if pivot > 0.0 {
                inertia.positive += 1;
            } else {
                inertia.negative += 1;
            }
        }

        let mut x = b.to_vec();
        LdltRef::new(&symbolic, &values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut x, n, 1),
            par,
            MemStack::new(&mut mem),
        );
        Ok((x, inertia))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::banded::BandedLdlt;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    fn rel_err(x: &[f64], y: &[f64]) -> f64 {
        let num = x.iter().zip(y).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        let den = y.iter().map(|b| b * b).sum::<f64>().sqrt();
        num / den
    }

    fn random_banded(rng: &mut StdRng, n: usize, kd: usize, indefinite: bool) -> BandedSym {
        let mut a = BandedSym::new(n, kd);
        for i in 0..n {
            let m = rng.gen_range(1.0..10.0);
            let d = if indefinite && rng.gen_bool(0.4) {
                -m
            } else {
                m + 2.0 * kd as f64
            };
            a.add_diagonal(i, d);
            for j in i.saturating_sub(kd)..i {
                a.add(
                    j,
                    i,
                    rng.gen_range(-1.0..1.0) * if indefinite { 0.05 } else { 1.0 },
                );
            }
        }
        a
    }

    #[test]
    fn sparse_matches_banded() {
        let mut rng = StdRng::seed_from_u64(10);
        let mut ldlt = BandedLdlt::new();
        let mut paths = [false; 2];
        for &(n, kd, indefinite) in &[
            (50, 10, false),
            (203, 10, true),
            (31, 2, true),
            (5, 0, false),
            (300, 120, true),
        ] {
            let mut a = random_banded(&mut rng, n, kd, indefinite);
            a.constrain(0);
            a.constrain(n - 1);
            let mut b: Vec<f64> = (0..n).map(|_| rng.gen_range(-1.0..1.0)).collect();
            b[0] = 0.0;
            b[n - 1] = 0.0;
            let inertia = ldlt.factor(&a).expect("banded factor");
            let mut x = b.clone();
            ldlt.solve_in_place(&mut x);
            let (xs, sparse_inertia) = SparseSym::from_banded(&a)
                .solve_with_inertia(&b)
                .expect("sparse solve");
            assert!(rel_err(&xs, &x) < 1e-10, "n = {n}, kd = {kd}");
            assert_eq!(sparse_inertia, inertia);
            paths[usize::from(is_supernodal(&SparseSym::from_banded(&a)))] = true;
        }
        assert_eq!(paths, [true, true], "simplicial and supernodal both covered");
    }

    fn is_supernodal(s: &SparseSym) -> bool {
        let mat = SparseColMat::<usize, f64>::try_new_from_triplets(s.n, s.n, &s.entries).expect("assembly");
        let symbolic = factorize_symbolic_cholesky(
            mat.symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .expect("symbolic");
        matches!(symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_))
    }

    #[test]
    fn triplet_assembly_and_constrain_match_banded() {
        let mut rng = StdRng::seed_from_u64(11);
        let (n, kd) = (40, 3);
        let mut a = BandedSym::new(n, kd);
        let mut s = SparseSym::new(n);
        for i in 0..n {
            a.add_diagonal(i, 8.0);
            s.add(i, i, 4.0);
            s.add(i, i, 4.0);
            for j in i.saturating_sub(kd)..i {
                let v = rng.gen_range(-1.0..1.0);
                a.add(i, j, v);
                s.add(j, i, v);
            }
        }
        for i in [5, 17] {
            a.constrain(i);
            s.constrain(i);
        }
        let mut b: Vec<f64> = (0..n).map(|_| rng.gen_range(-1.0..1.0)).collect();
        b[5] = 0.0;
        b[17] = 0.0;
        let mut ldlt = BandedLdlt::new();
        ldlt.factor(&a).expect("banded factor");
        let mut x = b.clone();
        ldlt.solve_in_place(&mut x);
        let xs = s.solve(&b).expect("sparse solve");
        assert!(rel_err(&xs, &x) < 1e-10);
        assert_eq!(xs[5], 0.0);
    }

    #[test]
    fn singular_sparse_is_rejected() {
        let mut s = SparseSym::new(3);
        s.add(0, 0, 1.0);
        s.add(1, 0, 1.0);
        s.add(1, 1, 1.0);
        s.add(2, 2, 1.0);
        assert!(matches!(
            s.solve(&[1.0, 2.0, 3.0]),
            Err(SparseError::RejectedPivot { .. } | SparseError::Pivot(_))
        ));
    }
}
