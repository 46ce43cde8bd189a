//! Small statistics shared across the workspace: the quantiles of the fits that give 95 %
//! intervals (the ascent winds here, the identification of vehicle coefficients in
//! `stx-analysis`) and the one percentile every report uses (Monte Carlo campaigns in
//! `stx-sim`, agreement reports, the station benchmark). Written out rather than taken from a
//! statistics crate: two constants, a four-term expansion and one index are all that is needed.

/// The standard normal's 97.5 % quantile.
pub const Z_975: f64 = 1.959_963_984_540_054;

/// Student's t 97.5 % quantile for `dof` (≥ 3) degrees of freedom by the Cornish–Fisher
/// expansion about the normal (0.7 % low at 3 degrees, 0.13 % at 5, less above).
pub fn student_t_975(dof: f64) -> f64 {
    let z = Z_975;
    let (z3, z5, z7) = (z.powi(3), z.powi(5), z.powi(7));
    z + (z3 + z) / (4.0 * dof)
        + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * dof.powi(2))
        + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * dof.powi(3))
}

/// The nearest-rank `q`-percentile (`q` in [0, 1]) of `sorted`, ascending: the smallest value
/// with at least a fraction `q` of the sample at or below it (rank ⌈q·n⌉, at least the first),
/// always one of the values; NaN for an empty sample.
pub fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let rank = (q * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank_percentiles() {
        let v: Vec<f64> = (1..=20).map(f64::from).collect();
        assert_eq!(percentile(&v, 0.5), 10.0);
        assert_eq!(percentile(&v, 0.95), 19.0);
        assert_eq!(percentile(&v, 1.0), 20.0);
        assert_eq!(percentile(&v, 0.0), 1.0);
        assert!(percentile(&[], 0.5).is_nan());
    }

    /// Tables of Student's t (e.g. Abramowitz & Stegun, table 26.10): t(0.975) is 3.182 at 3
    /// degrees of freedom, 2.571 at 5, 2.228 at 10, 2.042 at 30; within 1 %.
    #[test]
    fn student_t_975_matches_the_tables_within_one_percent() {
        for (dof, table) in [(3.0, 3.182), (5.0, 2.571), (10.0, 2.228), (30.0, 2.042)] {
            let t = student_t_975(dof);
            assert!((t / table - 1.0).abs() < 0.01, "{dof}: {t} vs {table}");
        }
        assert!((student_t_975(1e9) - Z_975).abs() < 1e-6);
    }
}
