//! A branch-free check that every entry of a slice is finite.

/// Lanes summed independently (the loop vectorizes over them).
const LANES: usize = 4;

/// `true` if no entry of `values` is `±∞` or NaN: the same answer as `values.iter().all(|v|
/// v.is_finite())`, without a branch per entry. `v · 0` is `±0` for a finite `v` and NaN for `±∞` and
/// NaN, and NaN survives any sum, so the sum of the products is zero exactly when every entry is finite.
pub(crate) fn all_finite(values: &[f64]) -> bool {
    let mut acc = [0.0; LANES];
    let chunks = values.chunks_exact(LANES);
    let tail = chunks.remainder();
    for chunk in chunks {
        for (a, v) in acc.iter_mut().zip(chunk) {
            *a += v * 0.0;
        }
    }
    for (a, v) in acc.iter_mut().zip(tail) {
        *a += v * 0.0;
    }
    acc.iter().sum::<f64>() == 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every length up to a few lanes past a multiple, every position of one non-finite entry, among
    /// entries of both signs and of extreme magnitudes (whose products with zero must stay zeros).
    #[test]
    fn agrees_with_the_entrywise_check() {
        let finite = [
            1.0,
            -2.5,
            f64::MAX,
            -f64::MAX,
            f64::MIN_POSITIVE,
            -0.0,
            0.0,
            5e-324,
            -3.0e300,
        ];
        for len in 0..=13 {
            let values: Vec<f64> = (0..len).map(|k| finite[k % finite.len()]).collect();
            assert!(all_finite(&values), "len {len}");
            for bad in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN, -f64::NAN] {
                for at in 0..len {
                    let mut v = values.clone();
                    v[at] = bad;
                    assert_eq!(
                        all_finite(&v),
                        v.iter().all(|x| x.is_finite()),
                        "len {len}, {bad} at {at}"
                    );
                    assert!(!all_finite(&v));
                }
            }
        }
        // +∞ and −∞ in different lanes: their zero products are NaN, not a cancelling pair
        let mut v = vec![0.0; 8];
        v[0] = f64::INFINITY;
        v[5] = f64::NEG_INFINITY;
        assert!(!all_finite(&v));
    }
}
