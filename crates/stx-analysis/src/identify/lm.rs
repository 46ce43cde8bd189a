//! Levenberg–Marquardt for identification: residuals of whole simulated flights, Jacobian by
//! forward differences.
//!
//! Written here rather than taken from a crate: the `levenberg-marquardt` crate (rust-cv) is
//! the maintained Rust LM over nalgebra, but it ties itself to its own nalgebra release (the
//! workspace is on 0.35) and runs to completion with no way to stop it; an identification
//! flies the model `p + 1` times per iteration over minutes of flight, so the Lab page must
//! be able to cancel it and watch it. (Whether a newer release lifts either limit has not been
//! checked.) The method is the textbook one (Marquardt 1963,
//! Nielsen's damping update): solve `(JᵀJ + λ·diag JᵀJ) δ = −Jᵀr`, accept a step that lowers
//! the cost and shrink λ, else grow λ and try again.

use std::sync::atomic::{AtomicBool, Ordering};

use nalgebra::{DMatrix, DVector};

/// Why the minimisation stopped.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Stop {
    /// The cost or the step became negligible.
    Converged,
    /// The iteration limit was reached.
    MaxIterations,
    /// No step lowered the cost, whatever the damping.
    Stalled,
    /// The caller cancelled.
    Cancelled,
}

/// A minimisation's end.
#[derive(Debug, Clone)]
pub struct Minimum {
    /// The parameters.
    pub x: DVector<f64>,
    /// The residuals there.
    pub residuals: DVector<f64>,
    /// The Jacobian there.
    pub jacobian: DMatrix<f64>,
    /// Iterations (accepted or not).
    pub iterations: usize,
    /// Residual evaluations.
    pub evaluations: usize,
    /// Why it stopped.
    pub stop: Stop,
}

/// Settings.
#[derive(Debug, Clone, Copy)]
pub struct LmOptions {
    /// Most iterations.
    pub max_iterations: usize,
    /// Finite-difference step, as a fraction of each parameter's scale.
    pub relative_step: f64,
    /// Converged when the cost falls by less than this fraction in an accepted step …
    pub cost_tolerance: f64,
    /// … or every step component is below this fraction of its parameter's scale.
    pub step_tolerance: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        Self {
            max_iterations: 30,
            relative_step: 1e-4,
            cost_tolerance: 1e-7,
            step_tolerance: 1e-6,
        }
    }
}

/// Progress, after each iteration.
#[derive(Debug, Clone, Copy)]
pub struct Step {
    /// Iteration number, from 1.
    pub iteration: usize,
    /// Residual evaluations so far.
    pub evaluations: usize,
    /// Current cost, `½|r|²`.
    pub cost: f64,
}

/// Minimises `½|r(x)|²` from `x0`. `residuals` returns `None` where the model cannot be
/// evaluated (that point is refused). `scale` gives each parameter's magnitude at a value.
/// Returns `None` when `x0` itself cannot be evaluated.
pub fn minimize(
    residuals: &mut dyn FnMut(&DVector<f64>) -> Option<DVector<f64>>,
    scale: &dyn Fn(usize, f64) -> f64,
    x0: DVector<f64>,
    options: &LmOptions,
    cancel: &AtomicBool,
    progress: &mut dyn FnMut(Step),
) -> Option<Minimum> {
    let mut evaluations = 1;
    let mut x = x0;
    let mut r = residuals(&x)?;
    let mut cost = 0.5 * r.norm_squared();
    let mut lambda = 1e-3;
    let mut j = jacobian(residuals, scale, options, &x, &r, &mut evaluations)?;
    let mut iterations = 0;
    let stop = loop {
        if cancel.load(Ordering::Relaxed) {
            break Stop::Cancelled;
        }
        if iterations >= options.max_iterations {
            break Stop::MaxIterations;
        }
        iterations += 1;
        let a = j.transpose() * &j;
        let g = j.transpose() * &r;
        let mut accepted = None;
        for _ in 0..12 {
            let mut damped = a.clone();
            for k in 0..x.len() {
                damped[(k, k)] += lambda * a[(k, k)].max(1e-12);
            }
            let Some(delta) = damped.lu().solve(&(-&g)) else {
                lambda *= 4.0;
                continue;
            };
            let candidate = &x + &delta;
            evaluations += 1;
            match residuals(&candidate) {
                Some(rc) if 0.5 * rc.norm_squared() < cost => {
                    accepted = Some((candidate, rc, delta));
                    lambda = (lambda / 3.0).max(1e-9);
                    break;
                }
                _ => lambda *= 4.0,
            }
        }
        let Some((xn, rn, delta)) = accepted else {
            break Stop::Stalled;
        };
        let new_cost = 0.5 * rn.norm_squared();
        let small_step =
            (0..x.len()).all(|k| delta[k].abs() < options.step_tolerance * scale(k, x[k]));
        let small_fall = (cost - new_cost) < options.cost_tolerance * cost;
        x = xn;
        r = rn;
        cost = new_cost;
        progress(Step {
            iteration: iterations,
            evaluations,
            cost,
        });
        match jacobian(residuals, scale, options, &x, &r, &mut evaluations) {
            Some(jn) => j = jn,
            None => break Stop::Stalled,
        }
        if small_step || small_fall {
            break Stop::Converged;
        }
    };
    Some(Minimum {
        x,
        residuals: r,
        jacobian: j,
        iterations,
        evaluations,
        stop,
    })
}

/// Forward differences of `residuals` at `x` (where they are `r`), or `None` when a stepped
/// point cannot be evaluated.
fn jacobian(
    residuals: &mut dyn FnMut(&DVector<f64>) -> Option<DVector<f64>>,
    scale: &dyn Fn(usize, f64) -> f64,
    options: &LmOptions,
    x: &DVector<f64>,
    r: &DVector<f64>,
    evaluations: &mut usize,
) -> Option<DMatrix<f64>> {
    let mut j = DMatrix::zeros(r.len(), x.len());
    for i in 0..x.len() {
        let h = options.relative_step * scale(i, x[i]);
        let mut xh = x.clone();
        xh[i] += h;
        *evaluations += 1;
        let ri = residuals(&xh)?;
        j.set_column(i, &((ri - r) / h));
    }
    Some(j)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_an_exponential_decay() {
        // y = a·exp(−b t) with a = 3, b = 0.7, from (1, 1).
        let t: Vec<f64> = (0..20).map(|i| f64::from(i) * 0.25).collect();
        let y: Vec<f64> = t.iter().map(|t| 3.0 * (-0.7 * t).exp()).collect();
        let mut r = |p: &DVector<f64>| {
            Some(DVector::from_iterator(
                t.len(),
                t.iter().zip(&y).map(|(t, y)| p[0] * (-p[1] * t).exp() - y),
            ))
        };
        let m = minimize(
            &mut r,
            &|_, v| v.abs().max(1e-3),
            DVector::from_vec(vec![1.0, 1.0]),
            &LmOptions::default(),
            &AtomicBool::new(false),
            &mut |_| {},
        )
        .unwrap();
        assert_eq!(m.stop, Stop::Converged);
        assert!(
            (m.x[0] - 3.0).abs() < 1e-5 && (m.x[1] - 0.7).abs() < 1e-5,
            "{}",
            m.x
        );
        let cancelled = minimize(
            &mut r,
            &|_, v| v.abs().max(1e-3),
            DVector::from_vec(vec![1.0, 1.0]),
            &LmOptions::default(),
            &AtomicBool::new(true),
            &mut |_| {},
        )
        .unwrap();
        assert_eq!(cancelled.stop, Stop::Cancelled);
    }
}
