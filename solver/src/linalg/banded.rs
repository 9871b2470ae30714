//! Symmetric banded matrices and their LDL^T factorisation.
//!
//! The DER Hessian in the DOF order of eq. 1 is banded with half-bandwidth 10,
//! so a banded LDL^T solves the Newton system in O(n kd^2) time.

use nalgebra::{DMatrix, SMatrix};
use thiserror::Error;

/// Pivots with `|d_i| <= PIVOT_RTOL * max_i |A_ii|` are rejected as singular.
pub const PIVOT_RTOL: f64 = 1e-14;

/// Symmetric `n x n` matrix with half-bandwidth `kd` (`A[i][j] = 0` for `|i - j| > kd`).
///
/// Storage is the lower band by columns (LAPACK's `'L'` band layout): column `j`
/// holds `A[j..=j+kd][j]` (diagonal first) at `data[j*(kd+1)..(j+1)*(kd+1)]`, i.e.
/// `A[j + t][j]` sits at `data[j*(kd+1) + t]`. Slots with `j + t >= n` are padding
/// and stay zero.
///
/// `A[i][j]` and `A[j][i]` are one stored entry, so writers accumulate into the
/// lower triangle only: when assembling a full symmetric local block, add only
/// its entries with `i >= j` (or use [`BandedSym::add_block`]).
#[derive(Debug, Clone, PartialEq)]
pub struct BandedSym {
    n: usize,
    kd: usize,
    data: Vec<f64>,
}

impl BandedSym {
    /// Zero matrix of dimension `n` and half-bandwidth `kd`.
    pub fn new(n: usize, kd: usize) -> Self {
        Self {
            n,
            kd,
            data: vec![0.0; n * (kd + 1)],
        }
    }

    /// Dimension.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Half-bandwidth.
    pub fn kd(&self) -> usize {
        self.kd
    }

    /// Sets every entry to zero without reallocating.
    pub fn clear(&mut self) {
        self.data.fill(0.0);
    }

    /// Index into `data` of the lower-band entry `(i, j)`, `i >= j`.
    #[inline]
    fn index_lower(&self, i: usize, j: usize) -> usize {
        assert!(
            i < self.n && j <= i && i - j <= self.kd,
            "entry ({i}, {j}) outside the lower band (n = {}, kd = {})",
            self.n,
            self.kd
        );
        j * (self.kd + 1) + i - j
    }

    /// Accumulates `v` into the symmetric entry `A[i][j] = A[j][i]`.
    ///
    /// `add(i, j, v)` and `add(j, i, v)` hit the same entry, so for an off-diagonal
    /// pair add only one of them. Panics if `|i - j| > kd` or an index is `>= n`.
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        let k = self.index_lower(i.max(j), i.min(j));
        self.data[k] += v;
    }

    /// Accumulates `v` into the lower-triangle entry `A[i][j]`, `i >= j`.
    #[inline]
    pub fn add_lower(&mut self, i: usize, j: usize, v: f64) {
        debug_assert!(i >= j, "add_lower({i}, {j}) above the diagonal");
        let k = self.index_lower(i, j);
        self.data[k] += v;
    }

    /// Accumulates `v` into the diagonal entry `A[i][i]`.
    #[inline]
    pub fn add_diagonal(&mut self, i: usize, v: f64) {
        let k = self.index_lower(i, i);
        self.data[k] += v;
    }

    /// Accumulates the lower triangle of the symmetric block `block` into rows and
    /// columns `offset..offset + N` (the strict upper triangle of `block` is ignored).
    ///
    /// Panics unless `N <= kd + 1` and `offset + N <= n`.
    #[inline]
    pub fn add_block<const N: usize>(&mut self, offset: usize, block: &SMatrix<f64, N, N>) {
        assert!(
            N <= self.kd + 1 && offset + N <= self.n,
            "{N}x{N} block at {offset} does not fit (n = {}, kd = {})",
            self.n,
            self.kd
        );
        let w = self.kd + 1;
        // Column c of the block's lower triangle (rows c..N) is contiguous in both.
        for (c, src) in block.as_slice().chunks_exact(N).enumerate() {
            let dst = &mut self.data[(offset + c) * w..][..N - c];
            for (x, v) in dst.iter_mut().zip(&src[c..]) {
                *x += v;
            }
        }
    }

    /// Entry `A[i][j]` (zero outside the band). Panics if an index is `>= n`.
    #[inline]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        assert!(
            i < self.n && j < self.n,
            "entry ({i}, {j}) out of range (n = {})",
            self.n
        );
        if i.abs_diff(j) > self.kd {
            0.0
        } else {
            self.data[self.index_lower(i.max(j), i.min(j))]
        }
    }

    /// Zeros row and column `i` and sets `A[i][i] = 1` (Dirichlet DOF).
    ///
    /// Entries added afterwards accumulate as usual; constrain after assembly.
    /// The caller also sets `b[i]` to the prescribed value (zero for a Newton step).
    pub fn constrain(&mut self, i: usize) {
        assert!(i < self.n, "constrain({i}) out of range (n = {})", self.n);
        let w = self.kd + 1;
        for c in i.saturating_sub(self.kd)..i {
            self.data[c * w + i - c] = 0.0;
        }
        let col = &mut self.data[i * w..(i + 1) * w];
        col.fill(0.0);
        col[0] = 1.0;
    }

    /// `y = A x`.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        assert!(x.len() == self.n && y.len() == self.n, "mul_vec: length mismatch");
        let (n, kd) = (self.n, self.kd);
        y.fill(0.0);
        for (j, col) in self.data.chunks_exact(kd + 1).enumerate() {
            let m = kd.min(n - 1 - j);
            let xj = x[j];
            let (y_head, y_tail) = y.split_at_mut(j + 1);
            let mut acc = col[0] * xj;
            for ((a, xi), yi) in col[1..=m].iter().zip(&x[j + 1..]).zip(y_tail) {
                acc += a * xi;
                *yi += a * xj;
            }
            y_head[j] += acc;
        }
    }

    /// Dense copy (for tests and debugging).
    pub fn to_dense(&self) -> DMatrix<f64> {
        DMatrix::from_fn(self.n, self.n, |i, j| self.get(i, j))
    }
}

/// Signs of the LDL^T pivots: by Sylvester's law of inertia, the number of
/// positive and negative eigenvalues of `A` (zero pivots are a [`FactorError`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Inertia {
    /// Number of positive pivots.
    pub positive: usize,
    /// Number of negative pivots.
    pub negative: usize,
}

/// Failure of the unpivoted LDL^T factorisation.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum FactorError {
    /// A pivot is NaN or infinite (non-finite matrix entries, or overflow).
    #[error("LDL^T pivot {index} is not finite ({pivot})")]
    NonFinitePivot {
        /// Elimination step of the pivot.
        index: usize,
        /// Pivot value.
        pivot: f64,
    },
    /// A pivot is zero or tiny relative to `scale = max |A_ii|`: the matrix is
    /// singular or too ill-conditioned to factor without pivoting.
    #[error("LDL^T pivot {index} = {pivot:e} is zero or tiny relative to max|A_ii| = {scale:e}")]
    SmallPivot {
        /// Elimination step of the pivot.
        index: usize,
        /// Pivot value.
        pivot: f64,
        /// Largest absolute diagonal entry of the matrix.
        scale: f64,
    },
}

/// Calls `$fixed::<K>($args)` for `kd = K` in `1..=16`, else `$dynamic`: the
/// common half-bandwidths get kernels specialised at compile time (unrolled, with
/// the per-step scratch in registers), about 3x faster than the generic ones.
macro_rules! dispatch_kd {
    ($kd:expr, $fixed:ident($($arg:expr),*), $dynamic:expr) => {
        match $kd {
            1 => $fixed::<1>($($arg),*),
            2 => $fixed::<2>($($arg),*),
            3 => $fixed::<3>($($arg),*),
            4 => $fixed::<4>($($arg),*),
            5 => $fixed::<5>($($arg),*),
            6 => $fixed::<6>($($arg),*),
            7 => $fixed::<7>($($arg),*),
            8 => $fixed::<8>($($arg),*),
            9 => $fixed::<9>($($arg),*),
            10 => $fixed::<10>($($arg),*),
            11 => $fixed::<11>($($arg),*),
            12 => $fixed::<12>($($arg),*),
            13 => $fixed::<13>($($arg),*),
            14 => $fixed::<14>($($arg),*),
            15 => $fixed::<15>($($arg),*),
            16 => $fixed::<16>($($arg),*),
            _ => $dynamic,
        }
    };
}

/// Unpivoted LDL^T factorisation `A = L D L^T` of a [`BandedSym`].
///
/// `L` is unit lower banded, stored like [`BandedSym`] (by columns; the unit
/// diagonal is implicit). Buffers are reused: once sized, [`BandedLdlt::factor`]
/// does not allocate.
///
/// The second-difference matrix (2 on the diagonal, -1 beside it), symmetric
/// positive definite with half-bandwidth 1:
/// ```
/// use solver::linalg::banded::{BandedLdlt, BandedSym};
///
/// let n = 6;
/// let mut a = BandedSym::new(n, 1);
/// for i in 0..n {
///     a.add_diagonal(i, 2.0);
///     if i > 0 {
///         a.add_lower(i, i - 1, -1.0);
///     }
/// }
/// let x: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
/// let mut b = vec![0.0; n];
/// a.mul_vec(&x, &mut b);
/// let mut ldlt = BandedLdlt::new();
/// let inertia = ldlt.factor(&a).unwrap();
/// assert_eq!((inertia.positive, inertia.negative), (n, 0));
/// ldlt.solve_in_place(&mut b);
/// assert!(b.iter().zip(&x).all(|(got, want)| (got - want).abs() < 1e-12));
/// ```
#[derive(Debug, Clone, Default)]
pub struct BandedLdlt {
    n: usize,
    kd: usize,
    factored: bool,
    inertia: Inertia,
    l: Vec<f64>,
    d: Vec<f64>,
    d_inv: Vec<f64>,
    scratch: Vec<f64>,
}

/// One right-looking elimination step on band columns of width `w`: `col` is the
/// pivot column, `rest` the following columns, `m` the number of rows below the
/// pivot. Stores `L` in `col[1..=m]` and applies the Schur update
/// `A[j+1+t][j+1+q] -= L[j+1+t][j] u_q` (`u_q = L[j+1+q][j] d_j`, `t >= q`).
/// `u` and `lv` are scratch of length `>= m`.
#[inline(always)]
fn eliminate(col: &mut [f64], rest: &mut [f64], w: usize, m: usize, inv: f64, u: &mut [f64], lv: &mut [f64]) {
    let (u, lv) = (&mut u[..m], &mut lv[..m]);
    for ((x, ut), lt) in col[1..=m].iter_mut().zip(u.iter_mut()).zip(lv.iter_mut()) {
        *ut = *x;
        *lt = *x * inv;
        *x = *lt;
    }
    for (q, uq) in u.iter().enumerate() {
        for (x, lt) in rest[q * w..q * w + m - q].iter_mut().zip(&lv[q..]) {
            *x -= uq * lt;
        }
    }
}

/// Factorisation kernel for half-bandwidth `K` known at compile time. Writes `L`
/// into `l` (a copy of `A`), the pivots into `d` and their inverses into `d_inv`.
#[inline(never)]
fn factor_fixed<const K: usize>(l: &mut [f64], d: &mut [f64], d_inv: &mut [f64]) {
    let w = K + 1;
    let n = d.len();
    for j in 0..n {
        let (col, rest) = l[j * w..].split_at_mut(w);
        let inv = col[0].recip();
        d[j] = col[0];
        d_inv[j] = inv;
        let m = K.min(n - 1 - j);
        // Separate scratch per branch keeps the full-width one in registers.
        if m == K {
            let (mut u, mut lv) = ([0.0; K], [0.0; K]);
            eliminate(col, &mut rest[..K * w], w, K, inv, &mut u, &mut lv);
        } else {
            let (mut u, mut lv) = ([0.0; K], [0.0; K]);
            eliminate(col, rest, w, m, inv, &mut u, &mut lv);
        }
    }
}

/// [`factor_fixed`] for any half-bandwidth; `scratch` is resized to `2 kd`.
fn factor_dyn(kd: usize, l: &mut [f64], d: &mut [f64], d_inv: &mut [f64], scratch: &mut Vec<f64>) {
    let w = kd + 1;
    let n = d.len();
    scratch.clear();
    scratch.resize(2 * kd, 0.0);
    let (u, lv) = scratch.split_at_mut(kd);
    for j in 0..n {
        let (col, rest) = l[j * w..].split_at_mut(w);
        let inv = col[0].recip();
        d[j] = col[0];
        d_inv[j] = inv;
        eliminate(col, rest, w, kd.min(n - 1 - j), inv, u, lv);
    }
}

/// `b <- D^-1 L^-1 b` then `b <- L^-T b`, for any half-bandwidth.
fn solve_dyn(kd: usize, l: &[f64], d_inv: &[f64], b: &mut [f64]) {
    let n = b.len();
    for (j, (col, di)) in l.chunks_exact(kd + 1).zip(d_inv).enumerate() {
        let m = kd.min(n - 1 - j);
        let (head, tail) = b.split_at_mut(j + 1);
        let y = head[j];
        for (x, c) in tail[..m].iter_mut().zip(&col[1..]) {
            *x -= c * y;
        }
        head[j] = y * di;
    }
    for (i, col) in l.chunks_exact(kd + 1).enumerate().rev() {
        let m = kd.min(n - 1 - i);
        let (head, tail) = b.split_at_mut(i + 1);
        // Nearest (most recently computed) term last, to shorten the dependency chain.
        head[i] = col[1..=m]
            .iter()
            .zip(&tail[..m])
            .rev()
            .fold(head[i], |s, (c, x)| s - c * x);
    }
}

/// [`solve_dyn`] for half-bandwidth `K` known at compile time: the `K` pending
/// entries of the triangular solves live in registers. Same operations in the
/// same order, so the result is bit-identical to [`solve_dyn`].
#[inline(never)]
fn solve_fixed<const K: usize>(l: &[f64], d_inv: &[f64], b: &mut [f64]) {
    let n = b.len();
    if n <= K {
        return solve_dyn(K, l, d_inv, b);
    }
    let w = K + 1;
    // Forward: z[t] holds the partially eliminated b[j + t].
    let mut z = [0.0; K];
    z.copy_from_slice(&b[..K]);
    for (j, (col, di)) in l.chunks_exact(w).zip(d_inv).take(n - K).enumerate() {
        let y = z[0];
        b[j] = y * di;
        for t in 0..K - 1 {
            z[t] = z[t + 1] - col[t + 1] * y;
        }
        z[K - 1] = b[j + K] - col[K] * y;
    }
    b[n - K..].copy_from_slice(&z);
    for j in n - K..n {
        let (head, tail) = b.split_at_mut(j + 1);
        let y = head[j];
        for (x, c) in tail.iter_mut().zip(&l[j * w + 1..]) {
            *x -= c * y;
        }
        head[j] = y * d_inv[j];
    }
    // Backward: x[t] holds the solution entry x[i + 1 + t].
    for i in (n - K..n).rev() {
        let (head, tail) = b.split_at_mut(i + 1);
        head[i] = l[i * w + 1..]
            .iter()
            .zip(tail.iter())
            .rev()
            .fold(head[i], |s, (c, x)| s - c * x);
    }
    let mut x = [0.0; K];
    x.copy_from_slice(&b[n - K..]);
    for (i, col) in l.chunks_exact(w).enumerate().take(n - K).rev() {
        let xi = col[1..].iter().zip(&x).rev().fold(b[i], |s, (c, x)| s - c * x);
        for t in (1..K).rev() {
            x[t] = x[t - 1];
        }
        x[0] = xi;
        b[i] = xi;
    }
}

impl BandedLdlt {
    /// Empty factorisation; buffers grow on the first [`BandedLdlt::factor`].
    pub fn new() -> Self {
        Self::default()
    }

    /// Empty factorisation with buffers sized for dimension `n`, half-bandwidth `kd`.
    pub fn with_capacity(n: usize, kd: usize) -> Self {
        Self {
            l: Vec::with_capacity(n * (kd + 1)),
            d: Vec::with_capacity(n),
            d_inv: Vec::with_capacity(n),
            scratch: Vec::with_capacity(2 * kd),
            ..Self::default()
        }
    }

    /// Dimension of the last factored matrix.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Pivots `D` of the last factorisation (after a failure, meaningless from the
    /// failing pivot on).
    pub fn d(&self) -> &[f64] {
        &self.d
    }

    /// Factors `a` (right-looking, no pivoting) and returns the inertia.
    ///
    /// Fails on the first pivot that is non-finite or has
    /// `|d_i| <= PIVOT_RTOL * max|A_ii|`; the factorisation is then unusable until
    /// the next successful call.
    pub fn factor(&mut self, a: &BandedSym) -> Result<Inertia, FactorError> {
        let (n, kd) = (a.n, a.kd);
        self.n = n;
        self.kd = kd;
        self.factored = false;
        self.l.clear();
        self.l.extend_from_slice(&a.data);
        self.d.clear();
        self.d.resize(n, 0.0);
        self.d_inv.clear();
        self.d_inv.resize(n, 0.0);
        let (l, d, d_inv) = (&mut self.l[..], &mut self.d[..], &mut self.d_inv[..]);
        dispatch_kd!(
            kd,
            factor_fixed(l, d, d_inv),
            factor_dyn(kd, l, d, d_inv, &mut self.scratch)
        );
        // A bad pivot only poisons later entries (no panics), so the pivots are
        // checked afterwards, off the elimination's critical path.
        let scale = a
            .data
            .iter()
            .step_by(kd + 1)
            .fold(0.0, |s: f64, v| if v.abs() > s { v.abs() } else { s });
        let tol = PIVOT_RTOL * scale;
        if let Some(index) = self.d.iter().position(|p| !(p.abs() > tol && p.is_finite())) {
            let pivot = self.d[index];
            return Err(if pivot.is_finite() {
                FactorError::SmallPivot { index, pivot, scale }
            } else {
                FactorError::NonFinitePivot { index, pivot }
            });
        }
        let negative = self.d.iter().filter(|&&p| p < 0.0).count();
        let inertia = Inertia {
            positive: n - negative,
            negative,
        };
        self.factored = true;
        self.inertia = inertia;
        Ok(inertia)
    }

    /// The inertia of the last successful factorisation (`None` if there is none).
    pub fn inertia(&self) -> Option<Inertia> {
        self.factored.then_some(self.inertia)
    }

    /// Solves `A x = b` in place with the last successful factorisation.
    ///
    /// Panics if there is none or if `b.len() != n`.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        assert!(self.factored, "solve_in_place without a successful factor");
        assert_eq!(b.len(), self.n, "solve_in_place: length mismatch");
        let (l, d_inv) = (&self.l[..], &self.d_inv[..]);
        dispatch_kd!(self.kd, solve_fixed(l, d_inv, b), solve_dyn(self.kd, l, d_inv, b));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DVector, SymmetricEigen};
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    /// Random symmetric banded matrix with the given diagonal, built both as a
    /// `BandedSym` (via `add`, half the entries through the upper triangle) and
    /// independently as a dense matrix.
    fn random_banded(rng: &mut StdRng, diag: &[f64], kd: usize, noise: f64) -> (BandedSym, DMatrix<f64>) {
        let n = diag.len();
        let mut a = BandedSym::new(n, kd);
        let mut dense = DMatrix::zeros(n, n);
        for i in 0..n {
            a.add_diagonal(i, diag[i]);
            dense[(i, i)] += diag[i];
            for j in i.saturating_sub(kd)..i {
                let v = noise * rng.gen_range(-1.0..1.0);
                if rng.gen_bool(0.5) {
                    a.add(i, j, v);
                } else {
                    a.add(j, i, v);
                }
                dense[(i, j)] += v;
                dense[(j, i)] += v;
            }
        }
        (a, dense)
    }

    /// SPD by diagonal dominance: each row has at most 2 kd off-diagonals of size < 1.
    fn random_spd(rng: &mut StdRng, n: usize, kd: usize) -> (BandedSym, DMatrix<f64>) {
        let diag: Vec<f64> = (0..n)
            .map(|_| 2.0 * kd as f64 + rng.gen_range(0.5..5.0))
            .collect();
        random_banded(rng, &diag, kd, 1.0)
    }

    fn random_indefinite(rng: &mut StdRng, n: usize, kd: usize) -> (BandedSym, DMatrix<f64>) {
        let diag: Vec<f64> = (0..n)
            .map(|_| {
                let m = rng.gen_range(1.0..10.0);
                if rng.gen_bool(0.4) { -m } else { m }
            })
            .collect();
        random_banded(rng, &diag, kd, 0.05)
    }

    fn random_vec(rng: &mut StdRng, n: usize) -> Vec<f64> {
        (0..n).map(|_| rng.gen_range(-1.0..1.0)).collect()
    }

    fn rel_err(x: &[f64], y: &[f64]) -> f64 {
        let num = x.iter().zip(y).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        let den = y.iter().map(|b| b * b).sum::<f64>().sqrt();
        num / den
    }

    fn dense_solve(dense: &DMatrix<f64>, b: &[f64]) -> Vec<f64> {
        let x = dense
            .clone()
            .lu()
            .solve(&DVector::from_column_slice(b))
            .expect("dense LU");
        x.as_slice().to_vec()
    }

    fn negative_eigenvalues(dense: &DMatrix<f64>) -> usize {
        SymmetricEigen::new(dense.clone())
            .eigenvalues
            .iter()
            .filter(|&&e| e < 0.0)
            .count()
    }

    #[test]
    fn to_dense_and_mul_vec_match_dense() {
        let mut rng = StdRng::seed_from_u64(1);
        for &(n, kd) in &[(1, 0), (5, 0), (7, 3), (10, 12), (40, 10)] {
            let (a, dense) = random_indefinite(&mut rng, n, kd);
            assert_eq!(a.to_dense(), dense);
            let x = random_vec(&mut rng, n);
            let mut y = vec![f64::NAN; n];
            a.mul_vec(&x, &mut y);
            let y_ref = &dense * DVector::from_column_slice(&x);
            assert!(rel_err(&y, y_ref.as_slice()) < 1e-14, "n = {n}, kd = {kd}");
        }
    }

    #[test]
    fn get_add_and_block_assembly() {
        let mut a = BandedSym::new(6, 2);
        a.add(1, 3, 2.0);
        a.add(3, 1, 0.5);
        a.add_lower(3, 1, 0.5);
        assert_eq!(a.get(1, 3), 3.0);
        assert_eq!(a.get(3, 1), 3.0);
        assert_eq!(a.get(0, 5), 0.0);

        let block = nalgebra::Matrix3::new(1.0, 2.0, 3.0, 2.0, 4.0, 5.0, 3.0, 5.0, 6.0);
        let mut b = BandedSym::new(6, 2);
        b.add_block(3, &block);
        b.add_block(2, &block);
        let mut dense = DMatrix::zeros(6, 6);
        for offset in [3, 2] {
            let mut view = dense.view_mut((offset, offset), (3, 3));
            view += &block;
        }
        assert_eq!(b.to_dense(), dense);

        b.clear();
        assert_eq!(b.to_dense(), DMatrix::zeros(6, 6));
    }

    #[test]
    #[should_panic(expected = "outside the lower band")]
    fn add_outside_band_panics() {
        BandedSym::new(6, 2).add(0, 3, 1.0);
    }

    #[test]
    fn ldlt_matches_dense_lu_spd() {
        let mut rng = StdRng::seed_from_u64(2);
        let mut ldlt = BandedLdlt::new();
        // Specialised (kd <= 16) and generic kernels, including n <= kd + 1 tails.
        let cases = [
            (1, 0),
            (9, 0),
            (3, 10),
            (11, 10),
            (12, 10),
            (200, 10),
            (123, 4),
            (60, 1),
            (40, 16),
            (17, 16),
            (50, 17),
            (18, 20),
        ];
        for &(n, kd) in &cases {
            let (a, dense) = random_spd(&mut rng, n, kd);
            let b = random_vec(&mut rng, n);
            let inertia = ldlt.factor(&a).expect("SPD factor");
            assert_eq!(
                inertia,
                Inertia {
                    positive: n,
                    negative: 0
                }
            );
            let mut x = b.clone();
            ldlt.solve_in_place(&mut x);
            assert!(
                rel_err(&x, &dense_solve(&dense, &b)) < 1e-10,
                "n = {n}, kd = {kd}"
            );
        }
    }

    #[test]
    fn ldlt_matches_dense_lu_and_inertia_indefinite() {
        let mut rng = StdRng::seed_from_u64(3);
        let mut ldlt = BandedLdlt::with_capacity(300, 10);
        for &(n, kd) in &[(2, 1), (15, 10), (300, 10), (77, 3), (64, 6), (90, 24)] {
            let (a, dense) = random_indefinite(&mut rng, n, kd);
            let b = random_vec(&mut rng, n);
            let inertia = ldlt.factor(&a).expect("nonsingular factor");
            let negative = negative_eigenvalues(&dense);
            assert!(negative > 0 || n < 5);
            assert_eq!(
                inertia,
                Inertia {
                    positive: n - negative,
                    negative
                }
            );
            assert_eq!(ldlt.inertia(), Some(inertia));
            let mut x = b.clone();
            ldlt.solve_in_place(&mut x);
            assert!(
                rel_err(&x, &dense_solve(&dense, &b)) < 1e-10,
                "n = {n}, kd = {kd}"
            );
        }
    }

    #[test]
    fn factor_reuses_buffers() {
        let mut rng = StdRng::seed_from_u64(4);
        let (a, _) = random_spd(&mut rng, 100, 10);
        let mut ldlt = BandedLdlt::with_capacity(100, 10);
        let ptr = ldlt.l.as_ptr();
        ldlt.factor(&a).expect("SPD factor");
        ldlt.factor(&a).expect("SPD factor");
        assert_eq!(ldlt.l.as_ptr(), ptr);
    }

    #[test]
    fn fixed_and_generic_kernels_agree() {
        let mut rng = StdRng::seed_from_u64(6);
        for &(n, kd) in &[(5, 10), (11, 10), (100, 10), (64, 3), (33, 16)] {
            let (a, _) = random_indefinite(&mut rng, n, kd);
            let (mut l_fixed, mut d_fixed, mut inv_fixed) = (a.data.clone(), vec![0.0; n], vec![0.0; n]);
            let (mut l_dyn, mut d_dyn, mut inv_dyn) = (a.data.clone(), vec![0.0; n], vec![0.0; n]);
            dispatch_kd!(
                kd,
                factor_fixed(&mut l_fixed, &mut d_fixed, &mut inv_fixed),
                unreachable!()
            );
            factor_dyn(kd, &mut l_dyn, &mut d_dyn, &mut inv_dyn, &mut Vec::new());
            assert_eq!((&l_fixed, &d_fixed), (&l_dyn, &d_dyn), "n = {n}, kd = {kd}");

            let b = random_vec(&mut rng, n);
            let (mut x_fixed, mut x_dyn) = (b.clone(), b);
            dispatch_kd!(
                kd,
                solve_fixed(&l_fixed, &inv_fixed, &mut x_fixed),
                unreachable!()
            );
            solve_dyn(kd, &l_dyn, &inv_dyn, &mut x_dyn);
            assert_eq!(x_fixed, x_dyn, "n = {n}, kd = {kd}");
        }
    }

    #[test]
    fn constrain_fixes_dofs() {
        let mut rng = StdRng::seed_from_u64(5);
        let (n, kd) = (30, 4);
        let (mut a, mut dense) = random_spd(&mut rng, n, kd);
        let fixed = [0, 13, 29];
        for &i in &fixed {
            a.constrain(i);
            dense.row_mut(i).fill(0.0);
            dense.column_mut(i).fill(0.0);
            dense[(i, i)] = 1.0;
        }
        assert_eq!(a.to_dense(), dense);
        let mut b = random_vec(&mut rng, n);
        for &i in &fixed {
            b[i] = 0.0;
        }
        let mut ldlt = BandedLdlt::new();
        assert_eq!(
            ldlt.factor(&a),
            Ok(Inertia {
                positive: n,
                negative: 0
            })
        );
        let mut x = b.clone();
        ldlt.solve_in_place(&mut x);
        for &i in &fixed {
            assert_eq!(x[i], 0.0);
        }
        assert!(rel_err(&x, &dense_solve(&dense, &b)) < 1e-12);
    }

    #[test]
    fn singular_matrix_is_rejected() {
        // Laplacian of a free chain: singular (constant null vector).
        let n = 8;
        let mut a = BandedSym::new(n, 1);
        for i in 0..n - 1 {
            a.add_diagonal(i, 1.0);
            a.add_diagonal(i + 1, 1.0);
            a.add_lower(i + 1, i, -1.0);
        }
        let mut ldlt = BandedLdlt::new();
        match ldlt.factor(&a) {
            Err(FactorError::SmallPivot { index, .. }) => assert_eq!(index, n - 1),
            other => panic!("expected SmallPivot, got {other:?}"),
        }
        assert_eq!(ldlt.inertia(), None);
        assert!(matches!(
            ldlt.factor(&BandedSym::new(3, 1)),
            Err(FactorError::SmallPivot { index: 0, .. })
        ));
        let mut nan = BandedSym::new(3, 1);
        nan.add_diagonal(0, 1.0);
        nan.add_diagonal(1, f64::NAN);
        nan.add_diagonal(2, 1.0);
        assert!(matches!(
            ldlt.factor(&nan),
            Err(FactorError::NonFinitePivot { index: 1, .. })
        ));
    }
}
