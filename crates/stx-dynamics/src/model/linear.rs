//! A small dense linear solver for the equations of motion.
//!
//! The 18×18 system is solved tens of thousands of times per simulated minute, and a general
//! LU factorisation spends most of its time on bookkeeping at this size. Gaussian elimination
//! with partial pivoting on a plain array, skipping rows whose multiplier is zero (many are:
//! the canopy's rows only involve its own accelerations and the main lines), does the same
//! arithmetic several times faster.

/// Solves `a · x = b` for a square system of size `N` by Gaussian elimination with partial
/// pivoting inside diagonal blocks ending at the indices in `block_ends` (increasing, the last
/// one `N`; `&[N]` is ordinary partial pivoting). Each diagonal block must be regular: pivots
/// are sought only inside the current block, so the zeros below the block diagonal that a
/// body-by-body ordering creates are never filled in by a row swap from another block.
///
/// Works in place, `b` becoming `x` and `a` its elimination: the system is 2.6 kB, and taken by
/// value it was copied at every model evaluation (about 1 % of a campaign's time).
/// Returns false, leaving both half-eliminated, when a pivot is zero or not finite (singular or
/// poisoned system).
pub fn solve_blocked_in_place<const N: usize>(
    a: &mut [[f64; N]; N],
    b: &mut [f64; N],
    block_ends: &[usize],
) -> bool {
    let mut block = 0;
    for k in 0..N {
        while block + 1 < block_ends.len() && k >= block_ends[block] {
            block += 1;
        }
        let block_end = block_ends.get(block).copied().unwrap_or(N).min(N);
        let mut pivot_row = k;
        let mut pivot_abs = a[k][k].abs();
        for (i, row) in a.iter().enumerate().take(block_end).skip(k + 1) {
            let candidate = row[k].abs();
            if candidate > pivot_abs {
                pivot_abs = candidate;
                pivot_row = i;
            }
        }
        if !(pivot_abs > 0.0 && pivot_abs.is_finite()) {
            return false;
        }
        if pivot_row != k {
            a.swap(k, pivot_row);
            b.swap(k, pivot_row);
        }
        let (upper, lower) = a.split_at_mut(k + 1);
        let pivot = &upper[k];
        let inverse = 1.0 / pivot[k];
        for (offset, row) in lower.iter_mut().enumerate() {
            let factor = row[k] * inverse;
            if factor != 0.0 {
                for (value, above) in row[k + 1..].iter_mut().zip(&pivot[k + 1..]) {
                    *value -= factor * above;
                }
                row[k] = 0.0;
                b[k + 1 + offset] -= factor * b[k];
            }
        }
    }
    for k in (0..N).rev() {
        let (head, known) = b.split_at_mut(k + 1);
        let sum: f64 = a[k][k + 1..]
            .iter()
            .zip(known.iter())
            .fold(head[k], |sum, (coefficient, known)| {
                sum - coefficient * known
            });
        head[k] = sum / a[k][k];
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{SMatrix, SVector};

    /// `x`, or `None` for a singular or poisoned system.
    fn solve_blocked<const N: usize>(
        mut a: [[f64; N]; N],
        mut b: [f64; N],
        block_ends: &[usize],
    ) -> Option<[f64; N]> {
        solve_blocked_in_place(&mut a, &mut b, block_ends).then_some(b)
    }

    #[test]
    fn agrees_with_lu_on_pseudo_random_systems_that_need_pivoting() {
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for _ in 0..50 {
            let mut a = [[0.0; 18]; 18];
            let mut b = [0.0; 18];
            for (i, (row, rhs)) in a.iter_mut().zip(b.iter_mut()).enumerate() {
                for (j, value) in row.iter_mut().enumerate() {
                    // Sparse, with zeros on the diagonal, so pivoting is exercised.
                    *value = if (i + 2 * j) % 3 == 0 { 0.0 } else { next() };
                }
                *rhs = next();
            }
            let x = solve_blocked(a, b, &[18]).expect("regular system");
            let m = SMatrix::<f64, 18, 18>::from_fn(|i, j| a[i][j]);
            let reference = m
                .lu()
                .solve(&SVector::<f64, 18>::from_column_slice(&b))
                .unwrap();
            for i in 0..18 {
                assert!((x[i] - reference[i]).abs() < 1e-9 * (1.0 + reference[i].abs()));
            }
        }
    }

    #[test]
    fn blocked_pivoting_solves_a_block_lower_coupled_system() {
        // Two 2×2 blocks, the second coupled to the first only through one column.
        let a = [
            [0.0, 2.0, 1.0, 0.0],
            [3.0, 1.0, 0.0, 1.0],
            [0.0, 0.0, 0.0, 4.0],
            [0.0, 5.0, 2.0, 1.0],
        ];
        let x_true = [1.0, -2.0, 0.5, 3.0];
        let b: [f64; 4] = std::array::from_fn(|i| (0..4).map(|j| a[i][j] * x_true[j]).sum::<f64>());
        let x = solve_blocked(a, b, &[2, 4]).expect("regular blocks");
        for i in 0..4 {
            assert!((x[i] - x_true[i]).abs() < 1e-12, "{x:?}");
        }
    }

    #[test]
    fn singular_and_poisoned_systems_are_refused() {
        let a = [[1.0, 2.0], [2.0, 4.0]];
        assert!(solve_blocked(a, [1.0, 1.0], &[2]).is_none());
        assert!(solve_blocked([[f64::NAN, 0.0], [0.0, 1.0]], [1.0, 1.0], &[2]).is_none());
        assert_eq!(
            solve_blocked([[2.0, 0.0], [0.0, 4.0]], [1.0, 1.0], &[2]),
            Some([0.5, 0.25])
        );
    }
}
