//! The dense kernels of the null-space reduction, register-tiled: each works on a tile of at most
//! [`TILE`] consecutive entries of its output held in a fixed-size array (SSE2 registers), and streams its
//! inputs once per tile. Every output entry is accumulated in the same order, from the same starting
//! value, as the plain rank-one loops they replace (kept in the tests as the reference), so the results
//! are equal bit for bit: the tiling only removes the loads, stores and bounds checks of the output per
//! update (docs/performance.md, "Issue 12: the whole-body reduction's kernels").

use std::ops::Range;

/// Widest tile \[f64\]: four SSE2 registers of accumulators.
pub(crate) const TILE: usize = 8;

/// The tiles `(start, width)` covering `range`: widths 8 while they fit, then 4, 2 and 1.
pub(crate) fn tiles(range: Range<usize>) -> impl Iterator<Item = (usize, usize)> {
    let mut start = range.start;
    std::iter::from_fn(move || {
        let left = range.end.saturating_sub(start);
        let width = [TILE, 4, 2, 1].into_iter().find(|&w| w <= left)?;
        let tile = (start, width);
        start += width;
        Some(tile)
    })
}

/// `H += Σ_i s_i s_iᵀ` on the lower triangle (rows `c..nz` of column `c`), then the upper triangle from
/// the lower one. `h`: `nz × nz` column-major; `s`: the columns `s_i` (length `nz`), one after the other.
/// A zero `s_i[c]` skips its update of column `c`. Columns go in pairs: the pair's rows below its first
/// diagonal entry are tiled once for both columns, so each tile of `s_i` is loaded once for two updates.
pub(super) fn add_lower_gram(h: &mut [f64], s: &[f64], nz: usize) {
    for c in (0..nz).step_by(2) {
        gram_tile::<1>(&mut h[c * nz + c..c * nz + c + 1], s, nz, c, c);
        if c + 1 == nz {
            continue;
        }
        let (first, second) = h[c * nz..(c + 2) * nz].split_at_mut(nz);
        for (r0, width) in tiles(c + 1..nz) {
            let out = [&mut first[r0..r0 + width], &mut second[r0..r0 + width]];
            match width {
                TILE => gram_pair_tile::<TILE>(out, s, nz, c, r0),
                4 => gram_pair_tile::<4>(out, s, nz, c, r0),
                2 => gram_pair_tile::<2>(out, s, nz, c, r0),
                _ => gram_pair_tile::<1>(out, s, nz, c, r0),
            }
        }
    }
    for c in 0..nz {
        for r in c + 1..nz {
            h[r * nz + c] = h[c * nz + r];
        }
    }
}

/// Rows `r0..r0 + W` of columns `c` and `c + 1` of the Gram update (`out`, each of length `W`; row
/// `r0 = c + 1` of column `c + 1`'s is its diagonal entry).
fn gram_pair_tile<const W: usize>(out: [&mut [f64]; 2], s: &[f64], nz: usize, c: usize, r0: usize) {
    let [out0, out1] = out;
    let mut acc0 = [0.0; W];
    let mut acc1 = [0.0; W];
    acc0.copy_from_slice(out0);
    acc1.copy_from_slice(out1);
    for si in s.chunks_exact(nz) {
        let (f0, f1) = (si[c], si[c + 1]);
        let src = &si[r0..r0 + W];
        if f0 != 0.0 {
            for t in 0..W {
                acc0[t] += f0 * src[t];
            }
        }
        if f1 != 0.0 {
            for t in 0..W {
                acc1[t] += f1 * src[t];
            }
        }
    }
    out0.copy_from_slice(&acc0);
    out1.copy_from_slice(&acc1);
}

/// Rows `r0..r0 + W` of column `c` of the Gram update (`out`, length `W`).
fn gram_tile<const W: usize>(out: &mut [f64], s: &[f64], nz: usize, c: usize, r0: usize) {
    let mut acc = [0.0; W];
    acc.copy_from_slice(out);
    for si in s.chunks_exact(nz) {
        let f = si[c];
        if f == 0.0 {
            continue;
        }
        let src = &si[r0..r0 + W];
        for t in 0..W {
            acc[t] += f * src[t];
        }
    }
    out.copy_from_slice(&acc);
}

/// A task's matrix `A` (`rows × width`, column-major) with the variable ranges its columns cover:
/// `(range in x, first column of A)` per block, as [`crate::Task`] stores them.
pub(super) struct SparseColumns<'a> {
    pub(super) a: &'a [f64],
    pub(super) rows: usize,
    pub(super) blocks: &'a [(Range<usize>, usize)],
}

/// Row `i` of `A N` into `out` (length `nz`) and `a_i · x_p` returned, with `Nᵀ` (`nz × nx`,
/// column-major: row `j` of `N` contiguous). The nonzero entries of row `i` of `A` are gathered once into
/// `nonzeros` (at least as long as the task is wide), in the order of the blocks, and every tile of the
/// output sums over them only.
pub(super) fn project_row(
    a: &SparseColumns<'_>,
    i: usize,
    nt: &[f64],
    x_p: &[f64],
    nonzeros: &mut [(usize, f64)],
    out: &mut [f64],
) -> f64 {
    let mut count = 0;
    let mut shift = 0.0;
    for (range, offset) in a.blocks {
        for (k, j) in range.clone().enumerate() {
            let v = a.a[(offset + k) * a.rows + i];
            if v != 0.0 {
                shift += v * x_p[j];
                nonzeros[count] = (j, v);
                count += 1;
            }
        }
    }
    let nonzeros = &nonzeros[..count];
    let nz = out.len();
    for (e0, width) in tiles(0..nz) {
        let out = &mut out[e0..e0 + width];
        match width {
            TILE => project_tile::<TILE>(nonzeros, nt, nz, e0, out),
            4 => project_tile::<4>(nonzeros, nt, nz, e0, out),
            2 => project_tile::<2>(nonzeros, nt, nz, e0, out),
            _ => project_tile::<1>(nonzeros, nt, nz, e0, out),
        }
    }
    shift
}

/// Entries `e0..e0 + W` of `Σ_(j, v) v N_j` over the gathered nonzeros of a row of `A`.
fn project_tile<const W: usize>(
    nonzeros: &[(usize, f64)],
    nt: &[f64],
    nz: usize,
    e0: usize,
    out: &mut [f64],
) {
    let mut acc = [0.0; W];
    for &(j, v) in nonzeros {
        let n = &nt[j * nz + e0..j * nz + e0 + W];
        for t in 0..W {
            acc[t] += v * n[t];
        }
    }
    out.copy_from_slice(&acc);
}

/// The Householder reflectors of a QR factorization of an `nx × m` matrix: reflector `k` is
/// `I − τ_k v_k v_kᵀ` with `v_k` on rows `k..nx`, stored in column `k` of `v` (column-major, from row `k`).
pub(super) struct Reflectors<'a> {
    pub(super) v: &'a [f64],
    pub(super) tau: &'a [f64],
    pub(super) nx: usize,
}

/// `Nᵀ ← (H_0 ⋯ H_{m−1} Nᵀᵀ)ᵀ` on `nt` (`nz × nx`, column-major: row `j` of `N` contiguous): every
/// reflector, the last first, applied to each tile of columns of `N` (`N ← N − τ_k v_k (v_kᵀ N)`).
pub(super) fn apply_reflectors(h: &Reflectors<'_>, nt: &mut [f64], nz: usize) {
    for (e0, width) in tiles(0..nz) {
        match width {
            TILE => reflect_tile::<TILE>(h, nt, nz, e0),
            4 => reflect_tile::<4>(h, nt, nz, e0),
            2 => reflect_tile::<2>(h, nt, nz, e0),
            _ => reflect_tile::<1>(h, nt, nz, e0),
        }
    }
}

/// Columns `e0..e0 + W` of `N` through every reflector.
fn reflect_tile<const W: usize>(h: &Reflectors<'_>, nt: &mut [f64], nz: usize, e0: usize) {
    let nx = h.nx;
    for k in (0..h.tau.len()).rev() {
        let vk = &h.v[k * nx + k..(k + 1) * nx];
        // rows k.. of N, each as its tile
        let rows = || nt[k * nz..].chunks_exact(nz).map(|r| &r[e0..e0 + W]);
        let mut dots = [0.0; W];
        for (row, &v) in rows().zip(vk) {
            if v != 0.0 {
                for t in 0..W {
                    dots[t] += v * row[t];
                }
            }
        }
        for d in dots.iter_mut() {
            *d *= h.tau[k];
        }
        let rows = nt[k * nz..]
            .chunks_exact_mut(nz)
            .map(|r| &mut r[e0..e0 + W]);
        for (row, &v) in rows.zip(vk) {
            if v != 0.0 {
                for t in 0..W {
                    row[t] -= v * dots[t];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    //! Each kernel against the plain rank-one loops it replaced, bit for bit, on random data with zeros.

    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Uniform in [−1, 1], a third of the entries exactly zero.
    fn random(rng: &mut ChaCha8Rng, n: usize) -> Vec<f64> {
        (0..n)
            .map(|_| {
                if rng.random_bool(1.0 / 3.0) {
                    0.0
                } else {
                    rng.random_range(-1.0..1.0)
                }
            })
            .collect()
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    /// The reference: one rank-one update of the lower triangle per column of `s`.
    fn gram_reference(h: &mut [f64], s: &[f64], nz: usize) {
        for si in s.chunks_exact(nz) {
            for c in 0..nz {
                let f = si[c];
                if f == 0.0 {
                    continue;
                }
                for (hv, sv) in h[c * nz + c..(c + 1) * nz].iter_mut().zip(&si[c..]) {
                    *hv += f * sv;
                }
            }
        }
        for c in 0..nz {
            for r in c + 1..nz {
                h[r * nz + c] = h[c * nz + r];
            }
        }
    }

    #[test]
    fn tiles_cover_the_range_once() {
        for end in 0..40 {
            for start in 0..=end {
                let t: Vec<_> = tiles(start..end).collect();
                let covered: Vec<usize> = t.iter().flat_map(|&(s, w)| s..s + w).collect();
                assert_eq!(covered, (start..end).collect::<Vec<_>>());
                assert!(t.iter().all(|&(_, w)| [8, 4, 2, 1].contains(&w)));
            }
        }
    }

    #[test]
    fn the_tiled_gram_is_the_rank_one_loops_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for nz in [1, 2, 3, 7, 8, 9, 15, 26, 32, 38] {
            let rows = rng.random_range(0..60);
            let s = random(&mut rng, nz * rows);
            let mut h = vec![0.0; nz * nz];
            for c in 0..nz {
                h[c * nz + c] = 1e-6;
            }
            let mut expected = h.clone();
            gram_reference(&mut expected, &s, nz);
            add_lower_gram(&mut h, &s, nz);
            assert_eq!(bits(&h), bits(&expected), "nz {nz}, rows {rows}");
        }
    }

    /// The reference: `(A N)ᵀ` and `A x_p` summed column by column of `A`.
    fn project_reference(a: &SparseColumns<'_>, nt: &[f64], nz: usize, x_p: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; nz * a.rows];
        let mut shift = vec![0.0; a.rows];
        for (range, offset) in a.blocks {
            for (k, j) in range.clone().enumerate() {
                let ncol = &nt[j * nz..(j + 1) * nz];
                let acol = &a.a[(offset + k) * a.rows..(offset + k + 1) * a.rows];
                for (i, &v) in acol.iter().enumerate() {
                    if v != 0.0 {
                        shift[i] += v * x_p[j];
                        for (o, n) in out[i * nz..(i + 1) * nz].iter_mut().zip(ncol) {
                            *o += v * n;
                        }
                    }
                }
            }
        }
        out.extend(shift);
        out
    }

    #[test]
    fn the_tiled_projection_is_the_column_loops_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        for nz in [1, 5, 8, 13, 26, 32] {
            let nx = 50;
            let rows = rng.random_range(1..40);
            // two blocks of x out of order, as a task over (wrenches, accelerations) is
            let blocks = vec![(30..50, 0), (3..20, 20)];
            let a = random(&mut rng, rows * 37);
            let nt = random(&mut rng, nz * nx);
            let x_p = random(&mut rng, nx);
            let task = SparseColumns {
                a: &a,
                rows,
                blocks: &blocks,
            };
            let expected = project_reference(&task, &nt, nz, &x_p);
            let mut out = vec![f64::NAN; nz * rows];
            let mut shift = Vec::new();
            let mut nonzeros = vec![(0, 0.0); nx];
            for (i, row) in out.chunks_exact_mut(nz).enumerate() {
                shift.push(project_row(&task, i, &nt, &x_p, &mut nonzeros, row));
            }
            out.extend(shift);
            assert_eq!(bits(&out), bits(&expected), "nz {nz}, rows {rows}");
        }
    }

    /// The reference: each reflector on all of `N` at once.
    fn reflect_reference(h: &Reflectors<'_>, nt: &mut [f64], nz: usize) {
        let nx = h.nx;
        let mut dots = vec![0.0; nz];
        for k in (0..h.tau.len()).rev() {
            let vk = &h.v[k * nx + k..(k + 1) * nx];
            dots.fill(0.0);
            for (jj, &v) in vk.iter().enumerate() {
                if v != 0.0 {
                    for (d, n) in dots.iter_mut().zip(&nt[(k + jj) * nz..(k + jj + 1) * nz]) {
                        *d += v * n;
                    }
                }
            }
            for d in dots.iter_mut() {
                *d *= h.tau[k];
            }
            for (jj, &v) in vk.iter().enumerate() {
                if v != 0.0 {
                    let row = &mut nt[(k + jj) * nz..(k + jj + 1) * nz];
                    for (n, d) in row.iter_mut().zip(&dots) {
                        *n -= v * d;
                    }
                }
            }
        }
    }

    #[test]
    fn the_tiled_reflections_are_the_reflector_loops_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for (nx, m) in [(2, 1), (9, 3), (38, 12), (50, 18), (44, 6)] {
            let nz = nx - m;
            let v = random(&mut rng, nx * m);
            let tau: Vec<f64> = (0..m).map(|_| rng.random_range(0.0..2.0)).collect();
            let h = Reflectors {
                v: &v,
                tau: &tau,
                nx,
            };
            let mut nt = vec![0.0; nz * nx];
            for r in 0..nz {
                nt[(m + r) * nz + r] = 1.0;
            }
            let mut expected = nt.clone();
            reflect_reference(&h, &mut expected, nz);
            apply_reflectors(&h, &mut nt, nz);
            assert_eq!(bits(&nt), bits(&expected), "nx {nx}, m {m}");
        }
    }
}
