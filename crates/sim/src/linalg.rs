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

/// A symmetric matrix with the sparsity pattern of a [`TreeCholesky`], packed row by row: for every degree of
/// freedom `k`, its diagonal entry then the entries `(k, i)` of its ancestors `i`, nearest ancestor first (the
/// entries of the lower triangle that a kinematic tree's mass matrix may have non-zero
/// [Featherstone 2008, §6.5]). Build it with [`TreeCholesky::matrix`]; [`TreeCholesky::diagonal_index`] and
/// [`TreeCholesky::index`] give the place of an entry in [`TreeMatrix::values`].
#[derive(Clone, Debug, PartialEq)]
pub struct TreeMatrix {
    values: Vec<f64>,
}

impl TreeMatrix {
    /// The entries of the pattern, row by row.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The entries of the pattern, to write.
    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Copies `other` (a matrix of the same tree; no allocation).
    pub fn copy_from(&mut self, other: &TreeMatrix) {
        self.values.copy_from_slice(&other.values);
    }
}

/// Cholesky factorisation `H = Lᵀ L` that exploits the branch-induced sparsity of a kinematic tree's mass
/// matrix [Featherstone 2008, §6.5] (the "LTL" factorisation): `H[i][j]` may be non-zero only when
/// `i` is an ancestor of `j` or the reverse, and that pattern survives the factorisation (no fill-in). Adding
/// `Jᵀ G J` for the Jacobian of one frame keeps the pattern, since the columns of such a Jacobian lie on one
/// path from the root.
///
/// The matrix and the factor are packed ([`TreeMatrix`]): the elimination of row `k` subtracts `l_ki` times
/// the tail of row `k` from the row of each ancestor `i` (whose own ancestors are that tail), one contiguous
/// AXPY per ancestor. Row `k` of `L` depends only on the rows of the subtree of `k`, so the factor is kept
/// per **branch**: the *trunk* is the chain from the root down to the first degree of freedom with several
/// children (the six base DoFs of a floating-base robot), the branches are the subtrees below it (the legs,
/// the torso with arms and head). Each branch keeps its update of the trunk's rows, and
/// [`TreeCholesky::refactor`] recomputes only the branches whose entries changed plus the small trunk: a
/// changed contact on a foot touches only the entries of its leg and of the trunk.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeCholesky {
    /// `parent[k]`: the ancestor of degree of freedom `k` closest to it (`None` for a root).
    parent: Vec<Option<usize>>,
    /// Ancestors of every DoF, nearest first, concatenated; those of `k` are
    /// `ancestors[offsets[k]..offsets[k + 1]]`.
    ancestors: Vec<usize>,
    offsets: Vec<usize>,
    /// Where row `k` starts in [`TreeMatrix::values`] (its diagonal entry): `offsets[k] + k`.
    starts: Vec<usize>,
    /// `starts` of each entry of `ancestors`: where the row of that ancestor starts.
    ancestor_starts: Vec<usize>,
    /// Number of trunk DoFs (`0..trunk`, whose rows are `values[..starts[trunk]]`).
    trunk: usize,
    /// Branch of each DoF (`None` on the trunk).
    branch: Vec<Option<usize>>,
    /// The DoFs of each branch, increasing.
    branch_rows: Vec<Vec<usize>>,
    /// The factor `L`.
    factor: TreeMatrix,
    /// Each branch's elimination update of the trunk's rows, to be subtracted from them.
    trunk_updates: Vec<Vec<f64>>,
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
        let n = parent.len();
        let mut ancestors = Vec::new();
        let mut offsets = vec![0];
        for k in 0..n {
            let mut i = parent[k];
            while let Some(ii) = i {
                ancestors.push(ii);
                i = parent[ii];
            }
            offsets.push(ancestors.len());
        }
        let starts: Vec<usize> = (0..=n).map(|k| offsets[k] + k).collect();
        let ancestor_starts = ancestors.iter().map(|&i| starts[i]).collect();
        let trunk = trunk_length(&parent);
        let mut branch = vec![None; n];
        let mut branch_rows: Vec<Vec<usize>> = Vec::new();
        for k in trunk..n {
            let b = match parent[k].and_then(|p| branch[p]) {
                Some(b) => b,
                None => {
                    branch_rows.push(Vec::new());
                    branch_rows.len() - 1
                }
            };
            branch[k] = Some(b);
            branch_rows[b].push(k);
        }
        let factor = TreeMatrix {
            values: vec![0.0; starts[n]],
        };
        let trunk_updates = vec![vec![0.0; starts[trunk]]; branch_rows.len()];
        Some(Self {
            parent,
            ancestors,
            offsets,
            starts,
            ancestor_starts,
            trunk,
            branch,
            branch_rows,
            factor,
            trunk_updates,
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

    /// A zero matrix with this tree's pattern.
    pub fn matrix(&self) -> TreeMatrix {
        TreeMatrix {
            values: vec![0.0; self.starts[self.len()]],
        }
    }

    /// Where the diagonal entry `(k, k)` lies in [`TreeMatrix::values`].
    pub fn diagonal_index(&self, k: usize) -> usize {
        self.starts[k]
    }

    /// Where the entry `(k, ancestor)` lies in [`TreeMatrix::values`]; `ancestor` must be an ancestor of `k`.
    pub fn index(&self, ancestor: usize, k: usize) -> usize {
        debug_assert!(self.ancestors_of(k).contains(&ancestor));
        self.starts[k] + self.depth(k) - self.depth(ancestor)
    }

    /// Where the lower-triangle entry `(row, col)` (`row ≥ col`) lies in [`TreeMatrix::values`]: the
    /// diagonal when `row == col`, else [`TreeCholesky::index`] (`col` must be an ancestor of `row`).
    pub fn lower_index(&self, row: usize, col: usize) -> usize {
        if row == col {
            self.diagonal_index(row)
        } else {
            self.index(col, row)
        }
    }

    /// The branch of degree of freedom `k` (`None` on the trunk; see the type's documentation).
    pub fn branch_of(&self, k: usize) -> Option<usize> {
        self.branch[k]
    }

    /// Number of branches.
    pub fn branch_count(&self) -> usize {
        self.branch_rows.len()
    }

    /// Copies the pattern's entries of the dense symmetric matrix `h` (its lower triangle) into `out` (the
    /// tests' reference for the entries written in place, [`TreeCholesky::lower_index`]).
    #[cfg(test)]
    pub fn gather(&self, h: &DMatrix<f64>, out: &mut TreeMatrix) {
        let n = self.len();
        let a = h.as_slice();
        for k in 0..n {
            let row = &mut out.values[self.starts[k]..self.starts[k + 1]];
            row[0] = a[k * n + k];
            for (v, &i) in row[1..].iter_mut().zip(self.ancestors_of(k)) {
                *v = a[i * n + k];
            }
        }
    }

    fn ancestors_of(&self, k: usize) -> &[usize] {
        &self.ancestors[self.offsets[k]..self.offsets[k + 1]]
    }

    /// Number of ancestors of `k`.
    fn depth(&self, k: usize) -> usize {
        self.offsets[k + 1] - self.offsets[k]
    }

    /// Factorises `h` into the factor this value keeps. Returns `false` if a pivot is not positive and finite.
    pub fn factor(&mut self, h: &TreeMatrix) -> bool {
        (0..self.branch_count()).all(|b| self.factor_branch(h, b)) && self.factor_trunk(h)
    }

    /// Factorises `h` after a [`TreeCholesky::factor`] of a matrix that differed from `h` only in the entries
    /// of the branches marked in `changed` (one flag per branch) and of the trunk: recomputes those branches
    /// and the trunk, and gives the same factor as [`TreeCholesky::factor`] of `h`. Returns `false` if a
    /// pivot is not positive and finite.
    pub fn refactor(&mut self, h: &TreeMatrix, changed: &[bool]) -> bool {
        (0..self.branch_count())
            .filter(|b| changed[*b])
            .all(|b| self.factor_branch(h, b))
            && self.factor_trunk(h)
    }

    /// Eliminates the rows of branch `b` (leaves first) from `h`'s, into the factor and the branch's trunk
    /// update.
    fn factor_branch(&mut self, h: &TreeMatrix, b: usize) -> bool {
        let update = &mut self.trunk_updates[b];
        update.fill(0.0);
        let values = &mut self.factor.values;
        for &k in &self.branch_rows[b] {
            let row = self.starts[k]..self.starts[k + 1];
            values[row.clone()].copy_from_slice(&h.values[row]);
        }
        for &k in self.branch_rows[b].iter().rev() {
            let targets = &self.ancestor_starts[self.offsets[k]..self.offsets[k + 1]];
            let (head, tail) = values.split_at_mut(self.starts[k]);
            let Some(row_k) = eliminate(&mut tail[..=targets.len()]) else {
                return false;
            };
            // Row `i` (diagonal, then its ancestors) is updated by `l_ki` times row k from `l_ki` on. The
            // ancestors are the branch's (nearest first), then the whole trunk.
            let in_branch = targets.len() - self.trunk;
            for (idx, &target) in targets[..in_branch].iter().enumerate() {
                let lki = row_k[idx];
                if lki != 0.0 {
                    let source = &row_k[idx..];
                    axpy(&mut head[target..target + source.len()], -lki, source);
                }
            }
            let trunk_part = &row_k[in_branch..];
            match (
                <&[f64; 6]>::try_from(trunk_part),
                <&mut [f64; 21]>::try_from(update.as_mut_slice()),
            ) {
                (Ok(l), Ok(u)) => rank_one_six_chain(u, l),
                _ => {
                    for (t, &target) in targets[in_branch..].iter().enumerate() {
                        let lki = trunk_part[t];
                        if lki != 0.0 {
                            let source = &trunk_part[t..];
                            axpy(&mut update[target..target + source.len()], lki, source);
                        }
                    }
                }
            }
        }
        true
    }

    /// The trunk's rows of `h` minus every branch's update, then their elimination.
    fn factor_trunk(&mut self, h: &TreeMatrix) -> bool {
        let trunk_end = self.starts[self.trunk];
        let values = &mut self.factor.values;
        values[..trunk_end].copy_from_slice(&h.values[..trunk_end]);
        for update in &self.trunk_updates {
            axpy(&mut values[..trunk_end], -1.0, update);
        }
        for k in (0..self.trunk).rev() {
            let targets = &self.ancestor_starts[self.offsets[k]..self.offsets[k + 1]];
            let (head, tail) = values.split_at_mut(self.starts[k]);
            let Some(row_k) = eliminate(&mut tail[..=targets.len()]) else {
                return false;
            };
            for (idx, &target) in targets.iter().enumerate() {
                let lki = row_k[idx];
                if lki != 0.0 {
                    let source = &row_k[idx..];
                    axpy(&mut head[target..target + source.len()], -lki, source);
                }
            }
        }
        true
    }

    /// Solves `H x = b` in place with the factor of the last [`TreeCholesky::factor`] or
    /// [`TreeCholesky::refactor`].
    pub fn solve(&self, b: &mut DVector<f64>) {
        let n = self.len();
        let l = &self.factor.values;
        let x = b.as_mut_slice();
        // Below a floating base's six-DoF trunk, every row's last six ancestors are the trunk's DoFs
        // 5, 4, …, 0: those entries are read as an array of known length (loops the compiler unrolls).
        let first_below_trunk = if self.trunk == 6 { 6 } else { n };
        let in_branch = |k: usize| {
            let depth = self.depth(k);
            if k >= first_below_trunk {
                depth - 6
            } else {
                depth
            }
        };
        // Lᵀ y = b.
        for k in (0..n).rev() {
            let row = &l[self.starts[k]..self.starts[k + 1]];
            x[k] /= row[0];
            let xk = x[k];
            let (values, nb) = (&row[1..], in_branch(k));
            for (&i, v) in self.ancestors_of(k)[..nb].iter().zip(&values[..nb]) {
                x[i] -= v * xk;
            }
            if let Ok(trunk) = <&[f64; 6]>::try_from(&values[nb..]) {
                for (t, v) in trunk.iter().enumerate() {
                    x[5 - t] -= v * xk;
                }
            }
        }
        // L x = y.
        for k in 0..n {
            let row = &l[self.starts[k]..self.starts[k + 1]];
            let mut s = x[k];
            let (values, nb) = (&row[1..], in_branch(k));
            for (&i, v) in self.ancestors_of(k)[..nb].iter().zip(&values[..nb]) {
                s -= v * x[i];
            }
            if let Ok(trunk) = <&[f64; 6]>::try_from(&values[nb..]) {
                for (t, v) in trunk.iter().enumerate() {
                    s -= v * x[5 - t];
                }
            }
            x[k] = s / row[0];
        }
    }
}

/// Length of the chain from the root that a tree with a single root starts with, up to and including the first
/// node with several children or none (0 for a forest).
fn trunk_length(parent: &[Option<usize>]) -> usize {
    if parent.iter().filter(|p| p.is_none()).count() != 1 || parent[0].is_some() {
        return 0;
    }
    let mut children = vec![0usize; parent.len()];
    for p in parent.iter().flatten() {
        children[*p] += 1;
    }
    // With parents before children, the only child of node k of the chain is k + 1.
    (0..parent.len())
        .find(|&k| children[k] != 1)
        .map_or(parent.len(), |k| k + 1)
}

/// The elimination of one row `[h_kk, h_k,anc…]` (its updates from the subtree already subtracted): the
/// diagonal becomes `l_kk = √h_kk` and the rest is divided by it. Returns the row's off-diagonal part, or
/// `None` when the pivot `h_kk` is not positive and finite.
fn eliminate(row: &mut [f64]) -> Option<&[f64]> {
    let (d, rest) = row.split_first_mut()?;
    if d.is_nan() || *d <= 0.0 || d.is_infinite() {
        return None;
    }
    *d = d.sqrt();
    let inv = 1.0 / *d;
    for v in rest.iter_mut() {
        *v *= inv;
    }
    Some(rest)
}

/// `y += a x` (same lengths), entry by entry. Written as a loop over pairs: the tree's rows are short
/// (most under a dozen entries), and the compiler's vectorized loop for a plain `zip` spends more on its
/// set-up and scalar remainder than on these few products (measured: docs/performance.md, "Issue 12: the
/// start-up, the simulator's factorization and `/tf`").
fn axpy(y: &mut [f64], a: f64, x: &[f64]) {
    debug_assert_eq!(y.len(), x.len());
    let n = y.len().min(x.len());
    let (y, x) = (&mut y[..n], &x[..n]);
    let mut i = 0;
    while i + 2 <= n {
        y[i] += a * x[i];
        y[i + 1] += a * x[i + 1];
        i += 2;
    }
    if i < n {
        y[i] += a * x[i];
    }
}

/// `u += l lᵀ` on the packed rows of a six-DoF chain (a floating base's trunk: row `a` is
/// `[u_aa, u_a,a-1, …, u_a0]` at `a (a + 1) / 2`), row `a = 5 − t` updated by `l_t` times `l[t..]` for
/// `t = 0, …, 5`, a zero `l_t` skipped: the products and sums of [`axpy`] on each row, in the same order, with
/// every length known to the compiler (unrolled; the general loop's overhead per row is larger than its six
/// or fewer products).
fn rank_one_six_chain(u: &mut [f64; 21], l: &[f64; 6]) {
    for t in 0..6 {
        let a = 5 - t;
        let start = a * (a + 1) / 2;
        let lt = l[t];
        if lt != 0.0 {
            for j in 0..=a {
                u[start + j] += lt * l[t + j];
            }
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

    /// `y += a x`, the plain loop.
    fn plain_axpy(y: &mut [f64], a: f64, x: &[f64]) {
        for (y, x) in y.iter_mut().zip(x) {
            *y += a * x;
        }
    }

    #[test]
    fn the_pairwise_axpy_is_the_plain_loop_bit_for_bit() {
        for n in 0..14 {
            let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() * 1e3).collect();
            let y0: Vec<f64> = (0..n).map(|i| (i as f64 * 1.3).cos() / 7.0).collect();
            for a in [-0.123_456_789, 3.0e-9, 1.0] {
                let (mut y, mut plain) = (y0.clone(), y0.clone());
                axpy(&mut y, a, &x);
                plain_axpy(&mut plain, a, &x);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&y), bits(&plain), "n = {n}, a = {a}");
            }
        }
    }

    /// The factorization and solve as written before the six-DoF trunk kernels (every update a plain
    /// `y += a x` loop, every solve entry through the ancestor list): the reference they match bit for bit.
    fn reference_factor_solve(tree: &TreeCholesky, h: &TreeMatrix, b: &mut [f64]) -> Vec<f64> {
        let mut values = h.values.clone();
        let trunk_end = tree.starts[tree.trunk];
        let mut updates = vec![vec![0.0; trunk_end]; tree.branch_count()];
        fn eliminate_rows(
            tree: &TreeCholesky,
            values: &mut [f64],
            rows: &[usize],
            mut update: Option<&mut Vec<f64>>,
        ) {
            let trunk_end = tree.starts[tree.trunk];
            for &k in rows.iter().rev() {
                let targets = &tree.ancestor_starts[tree.offsets[k]..tree.offsets[k + 1]];
                let (head, tail) = values.split_at_mut(tree.starts[k]);
                let row_k = eliminate(&mut tail[..=targets.len()]).expect("positive pivot");
                for (idx, &target) in targets.iter().enumerate() {
                    let lki = row_k[idx];
                    if lki == 0.0 {
                        continue;
                    }
                    let source = &row_k[idx..];
                    match update.as_deref_mut() {
                        Some(u) if target < trunk_end => {
                            plain_axpy(&mut u[target..target + source.len()], lki, source)
                        }
                        _ => plain_axpy(&mut head[target..target + source.len()], -lki, source),
                    }
                }
            }
        }
        for (rows, update) in tree.branch_rows.iter().zip(&mut updates) {
            eliminate_rows(tree, &mut values, rows, Some(update));
        }
        for update in &updates {
            plain_axpy(&mut values[..trunk_end], -1.0, update);
        }
        let trunk_rows: Vec<usize> = (0..tree.trunk).collect();
        eliminate_rows(tree, &mut values, &trunk_rows, None);
        let n = tree.len();
        for k in (0..n).rev() {
            let row = &values[tree.starts[k]..tree.starts[k + 1]];
            b[k] /= row[0];
            let xk = b[k];
            for (&i, v) in tree.ancestors_of(k).iter().zip(&row[1..]) {
                b[i] -= v * xk;
            }
        }
        for k in 0..n {
            let row = &values[tree.starts[k]..tree.starts[k + 1]];
            let mut s = b[k];
            for (&i, v) in tree.ancestors_of(k).iter().zip(&row[1..]) {
                s -= v * b[i];
            }
            b[k] = s / row[0];
        }
        values
    }

    #[test]
    fn floating_base_kernels_match_the_general_loops_bit_for_bit() {
        // A floating base (six-DoF chain) with two legs of six, a torso of three carrying two arms of
        // seven and a head of two; and a fixed-base tree (no six-DoF trunk) for the general path.
        let mut parent: Vec<Option<usize>> = (0..6usize).map(|k| k.checked_sub(1)).collect();
        let chain = |parent: &mut Vec<Option<usize>>, from: usize, n: usize| {
            let mut p = from;
            for _ in 0..n {
                parent.push(Some(p));
                p = parent.len() - 1;
            }
            p
        };
        chain(&mut parent, 5, 6);
        chain(&mut parent, 5, 6);
        let torso = chain(&mut parent, 5, 3);
        chain(&mut parent, torso, 7);
        chain(&mut parent, torso, 7);
        chain(&mut parent, torso, 2);
        let fixed_base = vec![None, Some(0), Some(1), Some(1), Some(3), Some(0), Some(5)];
        for parent in [parent, fixed_base] {
            let mut tree = TreeCholesky::new(parent).unwrap();
            let mut h = tree.matrix();
            let mut seed = 0x2545_f491_4f6c_dd1d_u64;
            let mut next = || {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            };
            for k in 0..tree.len() {
                let row = tree.starts[k]..tree.starts[k + 1];
                for (j, v) in h.values[row].iter_mut().enumerate() {
                    // Some exact zeros: their updates are skipped.
                    *v = if j == 0 {
                        10.0 + next()
                    } else if j % 5 == 3 {
                        0.0
                    } else {
                        next() * 0.2
                    };
                }
            }
            assert!(tree.factor(&h));
            let rhs: Vec<f64> = (0..tree.len()).map(|i| i as f64 * 0.3 - 2.0).collect();
            let mut x = DVector::from_column_slice(&rhs);
            tree.solve(&mut x);
            let mut reference = rhs.clone();
            let factor = reference_factor_solve(&tree, &h, &mut reference);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&tree.factor.values), bits(&factor));
            assert_eq!(bits(x.as_slice()), bits(&reference));
        }
    }

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
        let mut tree = tree;
        let mut packed = tree.matrix();
        tree.gather(&h, &mut packed);
        assert!(tree.factor(&packed));
        let mut x = b.clone();
        tree.solve(&mut x);
        assert!((&h * &x - &b).norm() < 1e-10);
        // Trunk 0 - 1 - 2, branches {3, 4} and {5, 6}.
        assert_eq!(tree.branch_count(), 2);
        assert_eq!(tree.branch_of(2), None);
        assert_eq!(tree.branch_of(4), Some(0));
        assert_eq!(tree.branch_of(6), Some(1));
        assert_eq!(packed.values()[tree.index(1, 4)], h[(4, 1)]);
        assert_eq!(packed.values()[tree.diagonal_index(4)], h[(4, 4)]);

        // Changing entries of the branch {5, 6} and of the trunk: the refactorisation of that branch and the
        // trunk gives the factor of the new matrix, to the last bit.
        let mut changed = h.clone();
        for (r, c, v) in [(6, 6, 0.7), (6, 2, 0.1), (5, 0, -0.2), (1, 1, 0.3)] {
            changed[(r, c)] += v;
            changed[(c, r)] = changed[(r, c)];
        }
        tree.gather(&changed, &mut packed);
        assert!(tree.refactor(&packed, &[false, true]));
        let mut x = b.clone();
        tree.solve(&mut x);
        let mut fresh = TreeCholesky::new(parent.clone()).unwrap();
        assert!(fresh.factor(&packed));
        let mut y = b.clone();
        fresh.solve(&mut y);
        assert_eq!(x, y);
        assert!((&changed * &x - &b).norm() < 1e-10);
        // A forest and a single chain factorise too (no trunk, no branch).
        for parent in [
            vec![None, Some(0), None, Some(2)],
            vec![None, Some(0), Some(1)],
        ] {
            let mut tree = TreeCholesky::new(parent.clone()).unwrap();
            let n = parent.len();
            let h = DMatrix::from_fn(n, n, |r, c| {
                let related = r == c
                    || parent[r] == Some(c)
                    || parent[c] == Some(r)
                    || (parent[r].and_then(|p| parent[p]) == Some(c))
                    || (parent[c].and_then(|p| parent[p]) == Some(r));
                if r == c {
                    4.0
                } else if related {
                    0.5
                } else {
                    0.0
                }
            });
            let mut packed = tree.matrix();
            tree.gather(&h, &mut packed);
            assert!(tree.factor(&packed));
            let mut x = b.rows(0, n).into_owned();
            tree.solve(&mut x);
            assert!((&h * &x - b.rows(0, n)).norm() < 1e-12);
        }
    }

    /// The humanoid's mass matrix written straight into the floating-base pattern (`mass_matrix_lower` +
    /// `lower_index`, as the implicit step does) is the dense CRBA matrix gathered, bit for bit.
    #[test]
    fn mass_matrix_written_into_the_pattern_is_the_gathered_dense_one() {
        use std::sync::Arc;
        let model = Arc::new(stride_model::bundled::model().unwrap());
        let mut kd = stride_model::KinDyn::new(Arc::clone(&model));
        let mut state = stride_model::bundled::standing_state(&model).unwrap();
        state
            .joint_velocities
            .iter_mut()
            .enumerate()
            .for_each(|(j, v)| *v = 0.1 * j as f64 - 1.0);
        state
            .joint_positions
            .iter_mut()
            .enumerate()
            .for_each(|(j, q)| *q += 0.05 * (j as f64).sin());
        kd.set_state(&state).unwrap();
        let tree = TreeCholesky::floating_base(&model).unwrap();
        let mut dense = DMatrix::zeros(model.nv(), model.nv());
        kd.mass_matrix(&mut dense).unwrap();
        let mut gathered = tree.matrix();
        tree.gather(&dense, &mut gathered);
        let mut direct = tree.matrix();
        let values = direct.values_mut();
        values.fill(f64::NAN);
        kd.mass_matrix_lower(|row, col, v| values[tree.lower_index(row, col)] = v);
        let bits = |m: &TreeMatrix| m.values().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&direct), bits(&gathered));
    }

    #[test]
    fn cholesky_rejects_indefinite() {
        let mut a = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(!cholesky_in_place(&mut a));
        let mut nan = DMatrix::from_row_slice(1, 1, &[f64::NAN]);
        assert!(!cholesky_in_place(&mut nan));
    }
}
