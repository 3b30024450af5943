//! Small dense linear algebra that works in place (no allocation): Cholesky factorisation and solve.

use nalgebra::{DMatrix, DVector};

/// Overwrites the lower triangle of the symmetric positive-definite matrix `a` (only its lower triangle is
/// read) with its Cholesky factor `L` (`a = L Lᵀ`). Returns `false` if a pivot is not positive and finite.
pub fn cholesky_in_place(a: &mut DMatrix<f64>) -> bool {
    let n = a.nrows();
    debug_assert_eq!(n, a.ncols());
    // Column-major storage: element (i, j) at j * n + i. Left-looking (column by column) factorisation.
    let data = a.as_mut_slice();
    for j in 0..n {
        // d = a_jj - sum_k L_jk^2
        let mut d = data[j * n + j];
        for k in 0..j {
            let l = data[k * n + j];
            d -= l * l;
        }
        if d.is_nan() || d <= 0.0 || d.is_infinite() {
            return false;
        }
        let ljj = d.sqrt();
        data[j * n + j] = ljj;
        let inv = 1.0 / ljj;
        // Column j below the diagonal: a_ij - sum_k L_ik L_jk, for i > j.
        for k in 0..j {
            let ljk = data[k * n + j];
            if ljk != 0.0 {
                let (head, tail) = data.split_at_mut(j * n);
                let col_k = &head[k * n + j + 1..k * n + n];
                let col_j = &mut tail[j + 1..n];
                for (cj, ck) in col_j.iter_mut().zip(col_k) {
                    *cj -= ljk * ck;
                }
            }
        }
        for v in &mut data[j * n + j + 1..j * n + n] {
            *v *= inv;
        }
    }
    true
}

/// Solves `L Lᵀ x = b` in place (`b` becomes `x`), with `l` from [`cholesky_in_place`].
pub fn cholesky_solve_in_place(l: &DMatrix<f64>, b: &mut DVector<f64>) {
    let n = l.nrows();
    let data = l.as_slice();
    let x = b.as_mut_slice();
    // Forward: L y = b (column oriented).
    for j in 0..n {
        let yj = x[j] / data[j * n + j];
        x[j] = yj;
        if yj != 0.0 {
            for i in j + 1..n {
                x[i] -= data[j * n + i] * yj;
            }
        }
    }
    // Backward: Lᵀ x = y (row i of Lᵀ = column i of L).
    for i in (0..n).rev() {
        let mut s = x[i];
        for k in i + 1..n {
            s -= data[i * n + k] * x[k];
        }
        x[i] = s / data[i * n + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_matches_nalgebra() {
        let n = 7;
        let b = DMatrix::from_fn(n, n, |i, j| ((i * 7 + j * 3) % 11) as f64 * 0.3 - 1.0);
        let a = &b * b.transpose() + DMatrix::identity(n, n) * 0.5;
        let rhs = DVector::from_fn(n, |i, _| i as f64 - 2.0);
        let mut l = a.clone();
        assert!(cholesky_in_place(&mut l));
        let mut x = rhs.clone();
        cholesky_solve_in_place(&l, &mut x);
        let residual = &a * &x - &rhs;
        assert!(residual.norm() < 1e-10, "residual {residual}");
        let reference = a.clone().cholesky().unwrap().solve(&rhs);
        assert!((x - reference).norm() < 1e-10);
    }

    #[test]
    fn cholesky_rejects_indefinite() {
        let mut a = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(!cholesky_in_place(&mut a));
        let mut nan = DMatrix::from_row_slice(1, 1, &[f64::NAN]);
        assert!(!cholesky_in_place(&mut nan));
    }
}
