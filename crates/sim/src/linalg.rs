//! Small dense linear algebra that works in place (no allocation): Cholesky factorisation and solve.

use nalgebra::{DMatrix, DVector, Vector3, Vector6};

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

/// Cholesky factorisation `H = Lᵀ L` that exploits the branch-induced sparsity of a kinematic tree's mass
/// matrix [Featherstone 2008, §6.5] (the "LTL" factorisation): `H[i][j]` may be non-zero only when
/// `i` is an ancestor of `j` or the reverse, and that pattern survives the factorisation (no fill-in). Adding
/// `Jᵀ G J` for the Jacobian of one frame keeps the pattern, since the columns of such a Jacobian lie on one
/// path from the root.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TreeCholesky {
    /// `parent[k]`: the ancestor of degree of freedom `k` closest to it (`None` for the first base DoF).
    parent: Vec<Option<usize>>,
    /// Ancestors of every DoF, nearest first, concatenated; those of `k` are
    /// `ancestors[offsets[k]..offsets[k + 1]]`.
    ancestors: Vec<usize>,
    offsets: Vec<usize>,
}

impl TreeCholesky {
    /// From the parent array of the degrees of freedom (each parent index smaller than its child).
    /// Returns `None` if a parent index is not smaller than its child.
    pub fn new(parent: Vec<Option<usize>>) -> Option<Self> {
        if !parent
            .iter()
            .enumerate()
            .all(|(k, p)| p.is_none_or(|p| p < k))
        {
            return None;
        }
        let mut ancestors = Vec::new();
        let mut offsets = vec![0];
        for k in 0..parent.len() {
            let mut i = parent[k];
            while let Some(ii) = i {
                ancestors.push(ii);
                i = parent[ii];
            }
            offsets.push(ancestors.len());
        }
        Some(Self {
            parent,
            ancestors,
            offsets,
        })
    }

    /// The floating-base tree of a model: the six base DoFs form a chain, each joint hangs below the joint
    /// of its parent body (or below the last base DoF).
    pub fn floating_base(model: &stride_model::Model) -> Option<Self> {
        let mut parent: Vec<Option<usize>> = (0..6)
            .map(|k| if k == 0 { None } else { Some(k - 1) })
            .collect();
        let bodies = model.bodies();
        for j in 0..model.dof() {
            // Body j + 1 is moved by joint j.
            let body = bodies.get(j + 1)?;
            let p = match body.parent? {
                0 => 5,
                b => 6 + bodies.get(b)?.joint?,
            };
            parent.push(Some(p));
        }
        Self::new(parent)
    }

    /// Number of degrees of freedom.
    pub fn len(&self) -> usize {
        self.parent.len()
    }

    /// `true` for an empty tree.
    pub fn is_empty(&self) -> bool {
        self.parent.is_empty()
    }

    fn ancestors_of(&self, k: usize) -> &[usize] {
        &self.ancestors[self.offsets[k]..self.offsets[k + 1]]
    }

    /// Factorises in place: afterwards the entries `(k, i)`, `i` ancestor of `k` or `i = k`, hold `L`. Only
    /// those entries of the lower triangle are read. Returns `false` if a pivot is not positive and finite.
    pub fn factor(&self, h: &mut DMatrix<f64>) -> bool {
        let n = self.parent.len();
        if h.nrows() != n || h.ncols() != n {
            return false;
        }
        let a = h.as_mut_slice();
        for k in (0..n).rev() {
            let hkk = a[k * n + k];
            if hkk.is_nan() || hkk <= 0.0 || hkk.is_infinite() {
                return false;
            }
            let lkk = hkk.sqrt();
            a[k * n + k] = lkk;
            let inv = 1.0 / lkk;
            let anc = self.ancestors_of(k);
            for &i in anc {
                a[i * n + k] *= inv;
            }
            // The ancestors of anc[idx] are anc[idx + 1..].
            for (idx, &i) in anc.iter().enumerate() {
                let lki = a[i * n + k];
                if lki != 0.0 {
                    a[i * n + i] -= lki * lki;
                    for &j in &anc[idx + 1..] {
                        a[j * n + i] -= lki * a[j * n + k];
                    }
                }
            }
        }
        true
    }

    /// Solves `H x = b` in place with the factor from [`TreeCholesky::factor`].
    pub fn solve(&self, l: &DMatrix<f64>, b: &mut DVector<f64>) {
        let n = self.parent.len();
        let a = l.as_slice();
        let x = b.as_mut_slice();
        // Lᵀ y = b.
        for k in (0..n).rev() {
            x[k] /= a[k * n + k];
            let xk = x[k];
            for &i in self.ancestors_of(k) {
                x[i] -= a[i * n + k] * xk;
            }
        }
        // L x = y.
        for k in 0..n {
            let mut s = x[k];
            for &i in self.ancestors_of(k) {
                s -= a[i * n + k] * x[i];
            }
            x[k] = s / a[k * n + k];
        }
    }
}

/// Linear part `[v₀, v₁, v₂]` of a `[linear; angular]` 6-vector.
pub(crate) fn lin(v: &Vector6<f64>) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}

/// Angular part `[v₃, v₄, v₅]` of a `[linear; angular]` 6-vector.
pub(crate) fn ang(v: &Vector6<f64>) -> Vector3<f64> {
    Vector3::new(v[3], v[4], v[5])
}

/// The 6-vector `[a; b]` (linear first).
pub(crate) fn join(a: &Vector3<f64>, b: &Vector3<f64>) -> Vector6<f64> {
    Vector6::new(a.x, a.y, a.z, b.x, b.y, b.z)
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
    fn tree_cholesky_matches_the_dense_solve_on_a_tree_pattern() {
        // A small tree: 0 - 1 - 2 - {3 - 4, 5 - 6}.
        let parent = vec![None, Some(0), Some(1), Some(2), Some(3), Some(2), Some(5)];
        let tree = TreeCholesky::new(parent.clone()).unwrap();
        let n = parent.len();
        let ancestors = |mut k: usize| {
            let mut v = vec![k];
            while let Some(p) = parent[k] {
                v.push(p);
                k = p;
            }
            v
        };
        // H = Σ over paths of Jᵀ J with J supported on a root path, plus a diagonal.
        let mut h = DMatrix::identity(n, n);
        for leaf in [4usize, 6, 2] {
            let path = ancestors(leaf);
            let j = DMatrix::from_fn(3, n, |r, c| {
                if path.contains(&c) {
                    ((r * 5 + c * 3) % 7) as f64 - 3.0
                } else {
                    0.0
                }
            });
            h += j.transpose() * j;
        }
        let b = DVector::from_fn(n, |i, _| (i as f64).sin());
        let mut l = h.clone();
        assert!(tree.factor(&mut l));
        let mut x = b.clone();
        tree.solve(&l, &mut x);
        assert!((&h * &x - &b).norm() < 1e-10);
    }

    #[test]
    fn cholesky_rejects_indefinite() {
        let mut a = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(!cholesky_in_place(&mut a));
        let mut nan = DMatrix::from_row_slice(1, 1, &[f64::NAN]);
        assert!(!cholesky_in_place(&mut nan));
    }
}
