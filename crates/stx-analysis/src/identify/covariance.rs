//! The estimates' covariance from the residuals of a fit: a sandwich with a Newey–West meat,
//! summed over each flight's samples in time order.
//!
//! Why not `s²(JᵀJ)⁻¹`: that assumes every residual independent of the next and alike in
//! spread. A replay's residuals are neither: the channels are normalised by nominal noises
//! that a flight's sensors need not have, and on a real flight the GPS's wander and the wind
//! estimate's lag last seconds, tens of samples.
//!
//! The sandwich `B·S·B` with `B = (JᵀJ)⁻¹` and `S` the long-run covariance of the scores
//! `g_k = Σ_c J_kcᵀ r_kc` (one per recorded instant `k`, summed over its channels `c`) holds
//! for correlated residuals and for a model that does not fit exactly. `S` is Newey–West's
//! (heteroscedasticity and autocorrelation consistent):
//!
//! ```text
//! S = Σ_flights [ Σ_k g_k g_kᵀ + Σ_{l=1..L} (1 − l/(L+1)) Σ_k (g_k g_{k+l}ᵀ + g_{k+l} g_kᵀ) ]
//! ```
//!
//! with Bartlett weights (positive semi-definite), products within one flight only (flights
//! are independent).
//!
//! Chosen over the alternatives: an effective-sample-size factor per channel scales all
//! parameters alike, while the correlation that matters is that of each parameter's scores
//! (a lift slope is told by the slow height errors, a turn term by the quick yaw errors); a
//! block bootstrap re-fits the model dozens of times, minutes of flight each, where the
//! sandwich costs nothing after the fit.
//!
//! The lag `L` is found from the residuals, per flight: each channel's series (north error,
//! east error, …, one value per sample) forgets in `τ_c` samples, the first lag at which
//! its autocorrelation falls below 1/e; the lag is `L = 5·max_c τ_c`
//! ([`FORGETTING_TIMES`]), or `correlation_s` of flight at the log's mean interval if that
//! is longer, and never more than a third of the flight's samples. Five forgetting times,
//! because the Bartlett sum of an AR(1) with time constant `τ` falls short of its long-run
//! variance by about `τ/L`: a fifth. White residuals forget in one sample and get a lag of
//! 5, which changed nothing on white-noise flights; a GPS that wanders over 30 s gets the
//! third of the flight. The slowest channel decides, since one slow channel is enough to
//! make every parameter it informs over-confident. Andrews' (1991) AR(1) plug-in on the
//! scores was tried first and fell short (lags of 2–4 s on flights whose GPS wanders over
//! 30 s): a parameter's score sums slow channels with quick ones, whose noise hides the slow
//! part's memory from a lag-1 autocorrelation.
//!
//! Why the lag is needed (measured by the tests of [`super`], flights of 60 s, 20 trials
//! each, cl_alpha, cd0, cn_da; the table in [`super`]'s doc): a log whose GPS wanders
//! (first-order Gauss–Markov, 2 m and 3 m over 30 s) and whose wind estimate lags 10 s
//! behind a wind turning with height
//! ([`crate::flight_log::synthetic::SlowErrors::ublox_wind_shear`]) left the truth inside
//! the white-noise intervals in 4, 11 and 3 of 20; with the found lag and the quantile
//! below, in 18, 19 and 19. On white-noise flights, 20, 19, 20 before and 20, 18, 20 after.
//!
//! The fitted residuals are orthogonal to `J`, so their scores sum to zero and a lagged sum
//! of them falls short of the errors' (for a line through AR(1) errors, 170 of 200 slopes
//! inside at best). As the ascent-wind fit of stx-gnc does for its scalar, each variance is
//! divided by the bias that white unit errors would give it: their expected meat is
//! `Σ A_k − Σ w·(A_k B A_{k+l} + A_{k+l} B A_k)` with `A_k = J_kᵀJ_k`, where the truth is
//! `JᵀJ`. At lag 0 this is the usual `m/(m − p)`-like correction.
//!
//! A long lag leaves few independent pieces to judge the spread from, so the interval's
//! half-width is Kiefer and Vogelsang's fixed-b quantile for a Bartlett sum over the
//! fraction `b = (L+1)/T` of the samples (`T` over all flights; `fixed_b_975`): 1.97 at
//! lag 0, 2.98 at a third of one flight. It replaced a Student t for Newey–West's
//! `ν ≈ 1.5·T/(L+1)` degrees of freedom (2.66 at a third), which held the truth in 17, 19
//! and 16 of 20 on the flights with slow errors where this holds it in 18, 19, 19 (white
//! flights: 20, 18, 20 either way). The quantile allows for the shortfall of a sum of
//! fitted residuals as well as for its spread, and the variances are already divided by
//! that shortfall, so the two together are on the wide side for errors the lag spans; the
//! errors it does not span (the cap of a third of a flight) are what that margin covers.
//! The quantile alone on the uncorrected variances held the truth in 16, 19, 13.

use nalgebra::{DMatrix, DVector};

/// Where each recorded instant's residuals sit in the residual vector: per flight, the first
/// index of each sample's (the last sample's run to the flight's `end`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Layout {
    /// Per flight: the start index of each sample, and the flight's end index.
    pub flights: Vec<(Vec<usize>, usize)>,
    /// Per flight: the mean interval between samples, s.
    pub intervals_s: Vec<f64>,
}

impl Layout {
    /// Total samples.
    pub fn samples(&self) -> usize {
        self.flights.iter().map(|(s, _)| s.len()).sum()
    }
}

/// The estimates' covariance and the multiplier of their standard errors for a 95 % interval.
#[derive(Debug, Clone, PartialEq)]
pub struct Covariance {
    /// Covariance of the estimates, parameter units squared.
    pub matrix: DMatrix<f64>,
    /// Half-width of a 95 % interval in standard errors.
    pub t95: f64,
    /// The Newey–West lag used, samples.
    pub lag: usize,
}

/// The automatic lag in multiples of the residuals' forgetting time (see the module doc).
pub const FORGETTING_TIMES: usize = 5;

/// The sandwich covariance (see the module doc) with residuals correlated over at least
/// `correlation_s`, and over as long as their scores show when `automatic` (see the module doc),
/// or `None` when `JᵀJ` is singular.
pub fn sandwich(
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    layout: &Layout,
    correlation_s: f64,
    automatic: bool,
) -> Option<Covariance> {
    let p = j.ncols();
    let bread = (j.transpose() * j).try_inverse()?;
    let mut meat = DMatrix::<f64>::zeros(p, p);
    // What the meat would be for white unit errors, whose true value is JᵀJ (see the module
    // doc): Σ A_k − Σ w·A_k·B·A_{k+l} with A_k = J_kᵀJ_k.
    let mut white = DMatrix::<f64>::zeros(p, p);
    let mut lag_used = 0;
    for ((starts, end), interval_s) in layout.flights.iter().zip(&layout.intervals_s) {
        let n = starts.len();
        let rows = |k: usize| starts[k]..starts.get(k + 1).copied().unwrap_or(*end);
        let scores: Vec<DVector<f64>> = (0..n)
            .map(|k| {
                let mut g = DVector::zeros(p);
                for i in rows(k) {
                    g += j.row(i).transpose() * r[i];
                }
                g
            })
            .collect();
        let told = (correlation_s / interval_s.max(1e-9)).ceil() as usize;
        let found = if automatic {
            FORGETTING_TIMES * forgetting_samples(r, starts, *end, n / 3)
        } else {
            0
        };
        let lag = told.max(found).min(n / 3);
        lag_used = lag_used.max(lag);
        let blocks: Vec<DMatrix<f64>> = (0..n)
            .map(|k| {
                let rows = rows(k);
                let jk = j.rows(rows.start, rows.len());
                jk.transpose() * jk
            })
            .collect();
        for k in 0..n {
            meat += &scores[k] * scores[k].transpose();
            white += &blocks[k] - &blocks[k] * &bread * &blocks[k];
            for l in 1..=lag.min(n - 1 - k) {
                let w = 1.0 - l as f64 / (lag + 1) as f64;
                let cross = &scores[k] * scores[k + l].transpose();
                meat += (&cross + cross.transpose()) * w;
                let cross = &blocks[k] * &bread * &blocks[k + l];
                white -= (&cross + cross.transpose()) * w;
            }
        }
    }
    let raw = &bread * meat * &bread;
    let expected = &bread * white * &bread;
    // Each variance divided by its white-noise bias (the fitted residuals are orthogonal to
    // J, so a lagged sum of their scores falls short), correlations kept.
    let factor: Vec<f64> = (0..p).map(|i| bread[(i, i)] / expected[(i, i)]).collect();
    if factor.iter().any(|f| !(f.is_finite() && *f > 0.0)) {
        return None;
    }
    let matrix = DMatrix::from_fn(p, p, |a, b| raw[(a, b)] * (factor[a] * factor[b]).sqrt());
    let b = ((lag_used + 1) as f64 / layout.samples().max(1) as f64).min(1.0);
    (0..p)
        .all(|i| matrix[(i, i)] > 0.0 && matrix[(i, i)].is_finite())
        .then_some(Covariance {
            matrix,
            t95: fixed_b_975(b),
            lag: lag_used,
        })
}

/// Kiefer and Vogelsang's (2005) fixed-b 97.5 % quantile of a t statistic whose variance is
/// a Bartlett sum over a fraction `b` of the samples: their cubic fit
/// `1.96 + 2.9694·b + 0.4160·b² − 0.5324·b³`. Checked by simulating the mean of 400 white
/// samples 20,000 times: 2.22, 2.56, 2.97, 3.47, 4.79 at b = 0.1, 0.2, 1/3, 0.5, 1 against
/// the fit's 2.26, 2.57, 2.98, 3.48, 4.81.
fn fixed_b_975(b: f64) -> f64 {
    stx_gnc::stats::Z_975 + b * (2.9694 + b * (0.4160 - 0.5324 * b))
}

/// How many samples the slowest channel of one flight's residuals takes to forget: per
/// channel (the position in each sample's run of residuals), the first lag at which the
/// autocorrelation of its series falls below 1/e, or `most` if it does not by then.
fn forgetting_samples(r: &DVector<f64>, starts: &[usize], end: usize, most: usize) -> usize {
    let n = starts.len();
    let run = |k: usize| starts.get(k + 1).copied().unwrap_or(end) - starts[k];
    // Channels every sample has (a missing airspeed shortens some runs).
    let channels = (0..n).map(run).min().unwrap_or(0);
    (0..channels)
        .map(|c| {
            let x: Vec<f64> = starts.iter().map(|&s| r[s + c]).collect();
            let mean = x.iter().sum::<f64>() / n as f64;
            let x: Vec<f64> = x.iter().map(|v| v - mean).collect();
            let var: f64 = x.iter().map(|v| v * v).sum();
            if var <= 0.0 {
                return 0;
            }
            (1..=most)
                .find(|&l| {
                    let cov: f64 = (0..n - l).map(|k| x[k] * x[k + l]).sum();
                    cov / var < (-1.0_f64).exp()
                })
                .unwrap_or(most)
        })
        .max()
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    /// A straight line through 300 samples at 5 Hz whose errors are AR(1) with a correlation
    /// time of 2 s: the slope's interval with no lag is far too narrow, with a 6 s lag or the
    /// lag found from the residuals about right. Measured over 200 seeds: 64, 180 and 184
    /// inside (with the earlier Student t quantile, 64 and 179 and, without the white-noise
    /// correction of the meat, 170 at 6 s).
    #[test]
    fn a_newey_west_lag_widens_the_intervals_of_correlated_errors_to_their_coverage() {
        let (n, dt, rho) = (300, 0.2, (-0.2_f64 / 2.0).exp());
        let t: Vec<f64> = (0..n).map(|k| k as f64 * dt).collect();
        let j = DMatrix::from_fn(n, 2, |k, c| if c == 0 { 1.0 } else { t[k] });
        let layout = Layout {
            flights: vec![((0..n).collect(), n)],
            intervals_s: vec![dt],
        };
        let (mut white, mut lagged, mut found) = (0, 0, 0);
        let seeds = 200;
        for seed in 0..seeds {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let mut e = 0.0;
            let y = DVector::from_fn(n, |k, _| {
                let g: f64 = StandardNormal.sample(&mut rng);
                e = rho * e + (1.0 - rho * rho).sqrt() * g;
                1.0 + 0.5 * t[k] + e
            });
            let jtj = j.transpose() * &j;
            let x = jtj.clone().try_inverse().unwrap() * j.transpose() * &y;
            let r = &j * &x - &y;
            for (lag_s, automatic, count) in [
                (0.0, false, &mut white),
                (6.0, false, &mut lagged),
                (0.0, true, &mut found),
            ] {
                let c = sandwich(&j, &r, &layout, lag_s, automatic).unwrap();
                let half = c.t95 * c.matrix[(1, 1)].sqrt();
                *count += usize::from((x[1] - 0.5).abs() <= half);
            }
        }
        eprintln!("slope inside: {white} of {seeds} with no lag, {lagged} with 6 s, {found} found");
        assert!(white < 100, "{white}");
        assert!(lagged >= 176, "{lagged}");
        assert!(found >= 176, "{found}");
    }
}
