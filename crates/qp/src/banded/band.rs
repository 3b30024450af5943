//! The banded symmetric matrix and its Cholesky kernels.

// Band algorithms index several arrays with the same loop counter; ranges read like the maths.
#![allow(clippy::needless_range_loop)]

use super::BandedQpError;

/// Half-bandwidth of every band matrix here (the DCM MPC's Newton matrices, x/y interleaved).
pub(crate) const BAND: usize = 5;

/// The `(d1, d2)`, `0 ≤ d2 ≤ d1 < BAND`, of the trailing window a Cholesky column updates (a constant
/// list, so the update loop unrolls fully).
const WINDOW_PAIRS: [(usize, usize); BAND * (BAND + 1) / 2] = {
    let mut pairs = [(0, 0); BAND * (BAND + 1) / 2];
    let mut k = 0;
    let mut d1 = 0;
    while d1 < BAND {
        let mut d2 = 0;
        while d2 <= d1 {
            pairs[k] = (d1, d2);
            k += 1;
            d2 += 1;
        }
        d1 += 1;
    }
    pairs
};

/// Banded symmetric matrix (lower band, row-major, fixed half-bandwidth `BAND` = 5): row `i` is an array
/// `R_i` with `R_i[c] = A(i, i − BAND + c)`, `c = 0..=BAND` (so `R_i[BAND]` is the diagonal). Entries
/// with a negative column stay zero, which lets the kernels run fixed-length loops.
#[derive(Debug, Clone)]
pub struct BandMatrix {
    n: usize,
    rows: Vec<[f64; BAND + 1]>,
    /// `1 / L(i,i)` after `cholesky_in_place` (divisions are the slow operation here).
    inverse_diagonal: Vec<f64>,
}

impl BandMatrix {
    /// The zero `n × n` band matrix.
    pub fn new(n: usize) -> Self {
        Self {
            n,
            rows: vec![[0.0; BAND + 1]; n],
            inverse_diagonal: vec![0.0; n],
        }
    }

    /// Number of rows (= columns).
    #[inline]
    pub fn n(&self) -> usize {
        self.n
    }

    /// Half-bandwidth (5: entries `(i, j)` with `|i − j| > 5` are zero).
    pub fn bandwidth(&self) -> usize {
        BAND
    }

    /// Adds `v` to the symmetric entry `(i, j)` (stored once, in the lower band); an entry outside the
    /// matrix or the band is refused.
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, v: f64) -> Result<(), BandedQpError> {
        let (r, c) = if i >= j { (i, j) } else { (j, i) };
        if r >= self.n || r - c > BAND {
            return Err(BandedQpError::OutsideBand {
                row: i,
                column: j,
                n: self.n,
            });
        }
        self.add_unchecked(i, j, v);
        Ok(())
    }

    /// [`BandMatrix::add`] for indices the caller knows to be in the band (the solver's own kernels).
    #[inline]
    pub(crate) fn add_unchecked(&mut self, i: usize, j: usize, v: f64) {
        let (r, c) = if i >= j { (i, j) } else { (j, i) };
        debug_assert!(r - c <= BAND);
        self.rows[r][BAND + c - r] += v;
    }

    /// Entry `(i, j)` of the symmetric matrix (zero outside the band and outside the matrix).
    #[inline]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (r, c) = if i >= j { (i, j) } else { (j, i) };
        if r >= self.n || r - c > BAND {
            0.0
        } else {
            self.rows[r][BAND + c - r]
        }
    }

    /// Diagonal entry `(i, i)`.
    #[inline]
    pub(crate) fn diagonal(&self, i: usize) -> f64 {
        self.rows[i][BAND]
    }

    /// Adds `v` to the diagonal entry `(i, i)`.
    #[inline]
    pub(crate) fn add_diagonal(&mut self, i: usize, v: f64) {
        self.rows[i][BAND] += v;
    }

    /// Sets every entry to zero.
    pub fn fill_zero(&mut self) {
        self.rows.iter_mut().for_each(|r| *r = [0.0; BAND + 1]);
    }

    /// Copies the entries of `other` (of the same size).
    pub(crate) fn copy_from(&mut self, other: &BandMatrix) {
        self.rows.copy_from_slice(&other.rows);
    }

    /// `y = A x` for the symmetric matrix (row by row: the lower band of row `i` and the column
    /// below the diagonal, read from the next `BAND` rows; no read-modify-write chains).
    #[inline]
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        let n = self.n.min(x.len()).min(y.len());
        for i in 0..n {
            let row = &self.rows[i];
            let mut sum = row[BAND] * x[i];
            if i >= BAND && i + BAND < n {
                let before = &x[i - BAND..i];
                for c in 0..BAND {
                    sum += row[c] * before[c];
                }
                let below = &self.rows[i + 1..=i + BAND];
                let after = &x[i + 1..=i + BAND];
                for d in 0..BAND {
                    sum += below[d][BAND - 1 - d] * after[d];
                }
            } else {
                for j in i.saturating_sub(BAND)..i {
                    sum += row[BAND + j - i] * x[j];
                }
                for k in i + 1..n.min(i + BAND + 1) {
                    sum += self.rows[k][BAND + i - k] * x[k];
                }
            }
            y[i] = sum;
        }
    }

    /// In-place Cholesky `A = L Lᵀ` (L kept in the band). Returns false if not positive definite.
    ///
    /// Right-looking (column by column): once column `j` is known, its outer product is subtracted from
    /// the trailing `BAND × BAND` window at once, written as `A(k,l) −= A(k,j) A(l,j) / A(j,j)` with the
    /// unscaled column, so the serial chain from one pivot to the next is one division, one product and
    /// one subtraction; the square root and the scaling of the column to `L(·, j)` are off that chain,
    /// and the fifteen window updates are independent of each other.
    #[inline]
    pub fn cholesky_in_place(&mut self) -> bool {
        let n = self.n;
        for j in 0..n {
            let pivot = self.rows[j][BAND];
            if !(pivot > 0.0 && pivot.is_finite()) {
                return false;
            }
            let inverse_pivot = 1.0 / pivot;
            let root = pivot.sqrt();
            let inverse_root = root * inverse_pivot;
            self.rows[j][BAND] = root;
            self.inverse_diagonal[j] = inverse_root;
            if j + BAND < n {
                let below = &mut self.rows[j + 1..=j + BAND];
                // column[d − 1] = A(j+d, j), scaled[d − 1] = A(j+d, j) / A(j,j)
                let mut column = [0.0; BAND];
                let mut scaled = [0.0; BAND];
                for d in 0..BAND {
                    let v = below[d][BAND - 1 - d];
                    column[d] = v;
                    scaled[d] = v * inverse_pivot;
                    below[d][BAND - 1 - d] = v * inverse_root;
                }
                // A(j+1+d1, j+1+d2) −= A(j+1+d1, j) A(j+1+d2, j) / A(j,j), 0 ≤ d2 ≤ d1 < BAND
                for &(d1, d2) in &WINDOW_PAIRS {
                    below[d1][BAND - d1 + d2] -= column[d1] * scaled[d2];
                }
            } else {
                let reach = n - 1 - j;
                let mut column = [0.0; BAND];
                let mut scaled = [0.0; BAND];
                for d in 0..reach {
                    let v = self.rows[j + 1 + d][BAND - 1 - d];
                    column[d] = v;
                    scaled[d] = v * inverse_pivot;
                    self.rows[j + 1 + d][BAND - 1 - d] = v * inverse_root;
                }
                for d1 in 0..reach {
                    let row = &mut self.rows[j + 1 + d1];
                    for d2 in 0..=d1 {
                        row[BAND - d1 + d2] -= column[d1] * scaled[d2];
                    }
                }
            }
        }
        true
    }

    /// Solves `L Lᵀ x = b` in place (after `cholesky_in_place`).
    ///
    /// Both substitutions keep the `BAND` values in flight in a local window (registers once the
    /// fixed-length loops are unrolled), so the serial chain has no store-to-load round trip; the last
    /// `BAND` rows, where the band is cut by the end of the matrix, run a general loop.
    #[inline]
    pub fn cholesky_solve(&self, b: &mut [f64]) {
        let n = self.n.min(b.len());
        let body = n.saturating_sub(BAND);
        // L y = b, column-oriented: window[d] holds b[j + d] minus the updates of the columns done.
        let mut window = [0.0; BAND];
        for (d, w) in window.iter_mut().enumerate() {
            if d < n {
                *w = b[d];
            }
        }
        for j in 0..body {
            let yj = window[0] * self.inverse_diagonal[j];
            b[j] = yj;
            let below = &self.rows[j + 1..=j + BAND];
            for d in 0..BAND - 1 {
                window[d] = window[d + 1] - below[d][BAND - 1 - d] * yj;
            }
            window[BAND - 1] = b[j + BAND] - below[BAND - 1][0] * yj;
        }
        for j in body..n {
            let yj = window[0] * self.inverse_diagonal[j];
            b[j] = yj;
            for d in 0..BAND - 1 {
                window[d] = window[d + 1];
            }
            window[BAND - 1] = 0.0;
            for d in 1..n - j {
                window[d - 1] -= self.rows[j + d][BAND - d] * yj;
            }
        }
        // Lᵀ x = y, row-oriented over Lᵀ: x_i = (y_i − Σ_d L(i+d, i) x_{i+d}) / L(i,i), with the last
        // BAND solutions kept locally (solved[d − 1] = x_{i+d}) and the newest term added last.
        let mut solved = [0.0; BAND];
        for i in (body..n).rev() {
            let mut dot = 0.0;
            for d in (1..n - i).rev() {
                dot += self.rows[i + d][BAND - d] * solved[d - 1];
            }
            let xi = (b[i] - dot) * self.inverse_diagonal[i];
            b[i] = xi;
            for d in (1..BAND).rev() {
                solved[d] = solved[d - 1];
            }
            solved[0] = xi;
        }
        for i in (0..body).rev() {
            let below = &self.rows[i + 1..=i + BAND];
            let mut dot = 0.0;
            for d in (1..=BAND).rev() {
                dot += below[d - 1][BAND - d] * solved[d - 1];
            }
            let xi = (b[i] - dot) * self.inverse_diagonal[i];
            b[i] = xi;
            for d in (1..BAND).rev() {
                solved[d] = solved[d - 1];
            }
            solved[0] = xi;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::banded::test_numbers::numbers;
    use nalgebra::{DMatrix, DVector};

    #[test]
    fn band_kernels_match_dense_linear_algebra() {
        for n in [1, 2, 3, 5, 6, 7, 10, 11, 12, 40] {
            let mut next = numbers(n as u64);
            let mut band = BandMatrix::new(n);
            let mut dense = DMatrix::zeros(n, n);
            for i in 0..n {
                for j in i.saturating_sub(BAND)..=i {
                    let v = if i == j { 10.0 + next().abs() } else { next() };
                    band.add(i, j, v).unwrap();
                    dense[(i, j)] = v;
                    dense[(j, i)] = v;
                }
            }
            let x = DVector::from_fn(n, |_, _| next());
            let mut y = vec![0.0; n];
            band.mul_vec(x.as_slice(), &mut y);
            assert!((DVector::from_vec(y) - &dense * &x).amax() < 1e-12);
            for i in 0..n {
                for j in 0..n {
                    assert_eq!(band.get(i, j), dense[(i, j)]);
                }
            }
            let b = DVector::from_fn(n, |_, _| next());
            assert!(band.cholesky_in_place());
            let mut solution = b.as_slice().to_vec();
            band.cholesky_solve(&mut solution);
            let expected = dense.cholesky().unwrap().solve(&b);
            assert!(
                (DVector::from_vec(solution) - expected).amax() < 1e-12,
                "n {n}"
            );
        }
        let mut indefinite = BandMatrix::new(3);
        indefinite.add(0, 0, 1.0).unwrap();
        indefinite.add(1, 1, -1.0).unwrap();
        indefinite.add(2, 2, 1.0).unwrap();
        assert_eq!(
            indefinite.add(0, 3, 1.0),
            Err(BandedQpError::OutsideBand {
                row: 0,
                column: 3,
                n: 3
            })
        );
        assert_eq!(indefinite.get(5, 5), 0.0);
        assert!(!indefinite.cholesky_in_place());
    }
}
