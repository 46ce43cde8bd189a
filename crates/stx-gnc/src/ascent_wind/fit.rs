//! One band's fit against time and the standard error of the value wanted.
//!
//! The fit is ordinary least squares of a straight line in time, and the value wanted is the
//! line's value at mid-passage: the passage's mean, even for unevenly spaced samples, with a
//! steady trend (shear) kept out of the residuals. It is a linear combination `Σ hᵢ yᵢ` of
//! the samples. Its variance is estimated from the residuals by Newey–West (a
//! Bartlett-weighted sum of the residual products up to a lag), not by the textbook
//! `s²(XᵀX)⁻¹`: a fix's error is not independent of the next one's — gusts last seconds, the
//! payload swings, a GPS receiver filters — and the textbook formula states an uncertainty
//! several times too small at a few hertz. Newey–West also handles the swing: its positive
//! and negative correlations cancel as they do in the true error of a mean, where a lag-1
//! (AR(1)) correction would take it for a slow drift and inflate the error tenfold.
//!
//! A band is short against the errors' correlation (a hundred seconds against tens), which
//! costs Newey–West in two ways, both corrected:
//! - **bias**: the residuals are the errors with the fitted line taken out, and the fitted
//!   mean soaks up part of every slow error, so the sum comes out low (by a third or more
//!   once the lag is a third of the band). The sum is divided by its expectation for white errors of unit
//!   variance relative to the true variance, computed exactly for this design
//!   (`tr(K·D_h·M·D_h)/Σhᵢ²`, `M` the residual projector, `K` the Bartlett weights), which
//!   also replaces the textbook `n/(n − p)`;
//! - **noise**: the variance is known only to about `ν = 3n/(2(L+1))` degrees of freedom
//!   (the Bartlett window's equivalent degrees of freedom at zero frequency), five or so in a
//!   band. The standard error is scaled by `t₀.₉₇₅,ν / z₀.₉₇₅` so that a consumer taking the
//!   stated σ as Gaussian still gets a 2-σ interval that covers about 95 %.
//!
//! The lag is capped at half the band's samples so that `ν ≥ 3`.

use crate::stats::{Z_975, student_t_975};

/// The fitted value and its variance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Coefficient {
    /// Value at mid-passage, in the unit of `y`.
    pub value: f64,
    /// Variance from the residuals' scatter (Newey–West), same unit squared.
    pub variance: f64,
}

/// A straight-line fit in `τ = (t − t_mid)/half_span` of the samples' times, `t_mid` halfway
/// between the first and the last. Scaling τ into [−1, 1] keeps the normal equations well
/// conditioned at mission-clock times of thousands of seconds. With two coefficients the
/// normal equations are solved in closed form: at 10 Hz a band holds a thousand fixes and the
/// bias below sums over every pair within the lag, which a general matrix made four times
/// slower.
#[derive(Debug, Clone)]
pub(super) struct Design {
    /// τ per sample.
    tau: Vec<f64>,
    /// Weight of each sample in the value at mid-passage (row 0 of `(XᵀX)⁻¹Xᵀ`, `X = [1 τ]`).
    h: Vec<f64>,
    /// Weight of each sample in the slope over τ (row 1).
    g: Vec<f64>,
    /// Newey–West lag, in samples.
    lag: usize,
    /// Factor on the Newey–West sum: the inverse of its white-noise bias times the squared
    /// Student-t inflation.
    correction: f64,
}

/// Bartlett weight of lag `l` for a window of `lag`.
fn bartlett(l: usize, lag: usize) -> f64 {
    1.0 - l as f64 / (lag + 1) as f64
}

impl Design {
    /// A fit to samples at `times_s` (increasing), with errors taken as correlated over
    /// `correlation_s`. `None` with fewer than four samples (two residual degrees of freedom)
    /// or none spanning time.
    pub(super) fn new(times_s: &[f64], correlation_s: f64) -> Option<Self> {
        let n = times_s.len();
        let (first, last) = (*times_s.first()?, *times_s.last()?);
        let half_span = 0.5 * (last - first);
        if n < 4 || half_span.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let mid = 0.5 * (first + last);
        let tau: Vec<f64> = times_s.iter().map(|t| (t - mid) / half_span).collect();
        let s1: f64 = tau.iter().sum();
        let s2: f64 = tau.iter().map(|t| t * t).sum();
        let det = n as f64 * s2 - s1 * s1;
        if !(det.is_finite() && det > 0.0) {
            return None;
        }
        // (XᵀX)⁻¹ = [[s2, −s1], [−s1, n]] / det.
        let (c00, c01, c11) = (s2 / det, -s1 / det, n as f64 / det);
        let h: Vec<f64> = tau.iter().map(|t| c00 + c01 * t).collect();
        let g: Vec<f64> = tau.iter().map(|t| c01 + c11 * t).collect();
        let mean_step_s = (last - first) / (n - 1) as f64;
        // `as usize` saturates; a window shorter than one step still looks one step back.
        let lag = ((correlation_s / mean_step_s).ceil() as usize).clamp(1, n / 2);
        let mut design = Self {
            tau,
            h,
            g,
            lag,
            correction: 1.0,
        };
        let bias = design.white_noise_bias()?;
        let dof = 1.5 * n as f64 / (lag + 1) as f64;
        let t_over_z = student_t_975(dof) / Z_975;
        design.correction = t_over_z * t_over_z / bias;
        Some(design)
    }

    /// Expected Newey–West sum over the true variance of the value for white errors:
    /// `Σᵢⱼ K_ij hᵢ hⱼ M_ij / Σ hᵢ²`, with `M_ij = δ_ij − (hᵢ + gᵢτⱼ)` the residual projector.
    /// `None` if degenerate.
    fn white_noise_bias(&self) -> Option<f64> {
        let (tau, h, g) = (&self.tau, &self.h, &self.g);
        let n = tau.len();
        let projected = |i: usize, j: usize| h[i] + g[i] * tau[j];
        let mut expected = 0.0;
        let mut variance = 0.0;
        for i in 0..n {
            variance += h[i] * h[i];
            expected += h[i] * h[i] * (1.0 - projected(i, i));
            for l in 1..=self.lag.min(n - 1 - i) {
                let j = i + l;
                expected -= 2.0 * bartlett(l, self.lag) * h[i] * h[j] * projected(i, j);
            }
        }
        let bias = expected / variance;
        // The fit cannot take out more than it leaves; a tiny ratio means a degenerate design.
        (bias.is_finite() && bias > 0.05).then_some(bias)
    }

    /// Fits `y` (one value per time given to [`Design::new`]).
    pub(super) fn fit(&self, y: &[f64]) -> Coefficient {
        let dot = |w: &[f64]| w.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
        let (value, slope) = (dot(&self.h), dot(&self.g));
        // Each sample's contribution to the value's error: hᵢ·rᵢ.
        let z: Vec<f64> = self
            .h
            .iter()
            .zip(&self.tau)
            .zip(y)
            .map(|((h, t), y)| h * (y - value - slope * t))
            .collect();
        let mut sum = z.iter().map(|v| v * v).sum::<f64>();
        for l in 1..=self.lag {
            let cross: f64 = z.iter().zip(&z[l..]).map(|(a, b)| a * b).sum();
            sum += 2.0 * bartlett(l, self.lag) * cross;
        }
        Coefficient {
            value,
            // Bartlett weights keep the sum ≥ 0 in exact arithmetic; `max` guards rounding.
            variance: sum.max(0.0) * self.correction,
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    use super::*;

    #[test]
    fn a_line_gives_its_value_at_mid_passage_with_no_scatter() {
        let t: Vec<f64> = (0..50).map(|i| 1000.0 + 0.5 * f64::from(i)).collect();
        let v: Vec<f64> = t.iter().map(|t| 7.0 + 0.2 * (t - 1012.25)).collect();
        let mean = Design::new(&t, 10.0).expect("design").fit(&v);
        assert!((mean.value - 7.0).abs() < 1e-9, "{mean:?}");
        assert!(mean.variance < 1e-18, "{mean:?}");
    }

    #[test]
    fn too_few_samples_or_no_time_span_give_no_design() {
        assert!(Design::new(&[0.0, 1.0, 2.0], 10.0).is_none());
        assert!(Design::new(&[5.0; 10], 10.0).is_none());
        assert!(Design::new(&[], 10.0).is_none());
    }

    #[test]
    fn the_t_quantile_matches_the_tables() {
        for (dof, table) in [(3.0, 3.182), (5.0, 2.571), (10.0, 2.228), (30.0, 2.042)] {
            let t = student_t_975(dof);
            assert!(
                (t / table - 1.0).abs() < if dof < 4.0 { 8e-3 } else { 2e-3 },
                "ν {dof}: {t} vs {table}"
            );
        }
    }

    /// Fraction of `runs` series (from `noise`) whose fitted mean lies within 2 stated σ of
    /// zero, and the root mean square of error over σ.
    fn coverage(
        runs: u64,
        mut noise: impl FnMut(&mut ChaCha8Rng, usize) -> Vec<f64>,
    ) -> (f64, f64) {
        let t: Vec<f64> = (0..200).map(|i| 0.5 * f64::from(i)).collect();
        let design = Design::new(&t, 45.0).expect("design");
        let (mut inside, mut z2) = (0u64, 0.0);
        for seed in 0..runs {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let fit = design.fit(&noise(&mut rng, t.len()));
            let sigma = fit.variance.sqrt();
            inside += u64::from(fit.value.abs() <= 2.0 * sigma);
            z2 += (fit.value / sigma).powi(2);
        }
        (inside as f64 / runs as f64, (z2 / runs as f64).sqrt())
    }

    #[test]
    fn the_stated_error_covers_white_and_correlated_noise() {
        let gauss = |rng: &mut ChaCha8Rng| -> f64 { StandardNormal.sample(rng) };
        let white = coverage(2000, |rng, n| (0..n).map(|_| gauss(rng)).collect());
        // AR(1) with a 5-s correlation time at 2 Hz.
        let rho = (-0.1_f64).exp();
        let correlated = coverage(2000, |rng, n| {
            let mut x = gauss(rng);
            (0..n)
                .map(|_| {
                    x = rho * x + (1.0 - rho * rho).sqrt() * gauss(rng);
                    x
                })
                .collect()
        });
        for (name, (inside, rms_z)) in [("white", white), ("AR(1)", correlated)] {
            println!(
                "{name}: within 2σ {:.1} %, rms(err/σ) {rms_z:.2}",
                100.0 * inside
            );
            assert!(inside > 0.92 && inside < 0.99, "{name}: {inside} within 2σ");
            assert!(rms_z > 0.7 && rms_z < 1.15, "{name}: rms z {rms_z}");
        }
    }

    #[test]
    fn a_swing_adds_little_to_the_error_of_a_mean_over_many_periods() {
        // 100 s at 2 Hz of a 10-s swing of amplitude 1 m/s: the mean's true error is under
        // amplitude/(ω·T) ≈ 0.016 m/s; a lag-1 correction would say about 0.3.
        let t: Vec<f64> = (0..=200).map(|i| 0.5 * f64::from(i)).collect();
        let omega = 2.0 * std::f64::consts::PI / 10.0;
        let v: Vec<f64> = t.iter().map(|t| (omega * t + 0.4).sin()).collect();
        let mean = Design::new(&t, 30.0).expect("design").fit(&v);
        let sigma = mean.variance.sqrt();
        assert!(mean.value.abs() < 0.02, "{mean:?}");
        assert!(sigma < 0.1, "σ {sigma}");
        assert!(
            sigma > mean.value.abs() / 2.0,
            "σ {sigma} vs error {}",
            mean.value
        );
    }
}
