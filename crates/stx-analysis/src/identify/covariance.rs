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
//! for correlated residuals and for a model that does not fit exactly. `S` is Newey–West's:
//! the products `g_k g_{k+l}ᵀ` within one flight up to lag `L`, with Bartlett weights
//! `1 − l/(L+1)` (positive semi-definite). Flights are independent: no products across them.
//!
//! Chosen over the alternatives: an effective-sample-size factor per channel scales all
//! parameters alike, while the correlation that matters is that of each parameter's scores
//! (a lift slope is told by the slow height errors, a turn term by the quick yaw errors); a
//! block bootstrap re-fits the model dozens of times, minutes of flight each, where the
//! sandwich costs nothing after the fit.
//!
//! The lag is the time the residuals take to forget: `correlation_s` of flight at the log's
//! mean interval, capped at a third of the flight's samples. Its default is 0 (White's
//! sandwich; why, in the module doc of [`super`]); the test below shows the lag at work on
//! a line fitted through errors that are correlated.
//!
//! The fitted residuals are orthogonal to `J`, so their scores sum to zero and a lagged sum
//! of them falls short of the errors' (for a line through AR(1) errors, 170 of 200 slopes
//! inside at best). As the ascent-wind fit of stx-gnc does for its scalar, each variance is
//! divided by the bias that white unit errors would give it: their expected meat is
//! `Σ A_k − Σ w·(A_k B A_{k+l} + A_{k+l} B A_k)` with `A_k = J_kᵀJ_k`, where the truth is
//! `JᵀJ`. At lag 0 this is the usual `m/(m − p)`-like correction. A long lag leaves few
//! independent pieces to judge the spread from, so the interval's half-width is a Student t
//! quantile for Newey–West's `ν ≈ 1.5·T/(L+1)` degrees of freedom (`T` samples over all
//! flights), not the normal 1.96.

use nalgebra::{DMatrix, DVector};
use stx_gnc::stats::student_t_975;

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

/// The sandwich covariance (see the module doc) with residuals correlated over
/// `correlation_s`, or `None` when `JᵀJ` is singular.
pub fn sandwich(
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    layout: &Layout,
    correlation_s: f64,
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
        let lag = ((correlation_s / interval_s.max(1e-9)).ceil() as usize).min(n / 3);
        lag_used = lag_used.max(lag);
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
    let dof = (1.5 * layout.samples() as f64 / (lag_used + 1) as f64).max(3.0);
    (0..p)
        .all(|i| matrix[(i, i)] > 0.0 && matrix[(i, i)].is_finite())
        .then_some(Covariance {
            matrix,
            t95: student_t_975(dof),
            lag: lag_used,
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    /// A straight line through 300 samples at 5 Hz whose errors are AR(1) with a correlation
    /// time of 2 s: the slope's interval with no lag is far too narrow, with a 6 s lag
    /// about right. Measured over 200 seeds: 64 and 179 inside (without the white-noise
    /// correction of the meat, 170).
    #[test]
    fn a_newey_west_lag_widens_the_intervals_of_correlated_errors_to_their_coverage() {
        let (n, dt, rho) = (300, 0.2, (-0.2_f64 / 2.0).exp());
        let t: Vec<f64> = (0..n).map(|k| k as f64 * dt).collect();
        let j = DMatrix::from_fn(n, 2, |k, c| if c == 0 { 1.0 } else { t[k] });
        let layout = Layout {
            flights: vec![((0..n).collect(), n)],
            intervals_s: vec![dt],
        };
        let (mut white, mut lagged) = (0, 0);
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
            for (lag_s, count) in [(0.0, &mut white), (6.0, &mut lagged)] {
                let c = sandwich(&j, &r, &layout, lag_s).unwrap();
                let half = c.t95 * c.matrix[(1, 1)].sqrt();
                *count += usize::from((x[1] - 0.5).abs() <= half);
            }
        }
        eprintln!("slope inside: {white} of {seeds} with no lag, {lagged} with 6 s");
        assert!(white < 100, "{white}");
        assert!(lagged >= 176, "{lagged}");
    }
}
