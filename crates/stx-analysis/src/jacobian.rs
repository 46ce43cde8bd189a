//! Numerical Jacobians by central differences.
//!
//! Step choice: the central difference `(f(x+h) − f(x−h)) / 2h` has a truncation error of
//! order `h² f'''` and a rounding error of order `ε |f| / h`; the sum is smallest near
//! `h ≈ ε^{1/3}` in the variable's own scale. With `ε = 2.2e-16` that is `6e-6`, taken
//! relative to `max(|x_j|, scale_j)` so a state that sits at zero (most angles and rates of a
//! trimmed glide) still gets a step of a sensible size in its units. The flight model is
//! smooth at a trimmed glide (no saturation, no contact), so this is accurate to about
//! `1e-9` relative — the test with an analytic system checks it.

use nalgebra::{DMatrix, DVector};

/// Relative step of the central differences, `ε^{1/3}` (see the module doc).
pub const RELATIVE_STEP: f64 = 6.0e-6;

/// How a variable may be stepped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Step {
    /// Both ways: `(f(x+h) − f(x−h)) / 2h`.
    Central,
    /// Upwards only, `(f(x+h) − f(x)) / h`: for a variable at the bottom of its range (a
    /// released brake cannot be pulled below zero). First-order accurate in general, exact
    /// where `f` is linear in that variable.
    Forward,
}

/// The step for variable value `x` with typical size `scale`.
pub fn step_size(x: f64, scale: f64) -> f64 {
    RELATIVE_STEP * x.abs().max(scale)
}

/// `∂f/∂x` at `x0` (rows: outputs, columns: variables). `scales[j]` is variable j's typical
/// size (1 for m, m/s, rad …) and `steps[j]` how it may be stepped.
pub fn jacobian(
    mut f: impl FnMut(&DVector<f64>) -> DVector<f64>,
    x0: &DVector<f64>,
    scales: &[f64],
    steps: &[Step],
) -> DMatrix<f64> {
    let n = x0.len();
    assert_eq!(scales.len(), n, "one scale per variable");
    assert_eq!(steps.len(), n, "one step kind per variable");
    let f0 = f(x0);
    let mut jac = DMatrix::zeros(f0.len(), n);
    for j in 0..n {
        let h = step_size(x0[j], scales[j]);
        let mut xp = x0.clone();
        xp[j] += h;
        let column = match steps[j] {
            Step::Central => {
                let mut xm = x0.clone();
                xm[j] -= h;
                // Divide by the steps actually taken (x ± h is rounded).
                (f(&xp) - f(&xm)) / (xp[j] - xm[j])
            }
            Step::Forward => (f(&xp) - &f0) / (xp[j] - x0[j]),
        };
        jac.set_column(j, &column);
    }
    jac
}

#[cfg(test)]
mod tests {
    use super::*;

    /// f(x) = [x0² x1, sin x1 + e^{x0}, x0 x1 x2³]: Jacobian known in closed form.
    fn f(x: &DVector<f64>) -> DVector<f64> {
        DVector::from_vec(vec![
            x[0] * x[0] * x[1],
            x[1].sin() + x[0].exp(),
            x[0] * x[1] * x[2].powi(3),
        ])
    }

    fn exact(x: &DVector<f64>) -> DMatrix<f64> {
        DMatrix::from_row_slice(
            3,
            3,
            &[
                2.0 * x[0] * x[1],
                x[0] * x[0],
                0.0,
                x[0].exp(),
                x[1].cos(),
                0.0,
                x[1] * x[2].powi(3),
                x[0] * x[2].powi(3),
                3.0 * x[0] * x[1] * x[2] * x[2],
            ],
        )
    }

    #[test]
    fn central_differences_match_an_analytic_jacobian() {
        let x = DVector::from_vec(vec![0.7, -1.3, 0.0]);
        let j = jacobian(f, &x, &[1.0; 3], &[Step::Central; 3]);
        let err = (&j - exact(&x)).abs().max();
        assert!(err < 1e-9, "error {err:e}\n{j}");
        // Away from zero too, with a large variable.
        let x = DVector::from_vec(vec![2.0, 30.0, -4.0]);
        let j = jacobian(f, &x, &[1.0; 3], &[Step::Central; 3]);
        let rel = ((&j - exact(&x)).abs().max()) / exact(&x).abs().max();
        assert!(rel < 1e-9, "relative error {rel:e}");
    }

    #[test]
    fn forward_step_is_exact_for_a_linear_dependence_and_first_order_otherwise() {
        // Linear in x1 (as the servo lag is in its command): exact to rounding.
        let g = |x: &DVector<f64>| DVector::from_vec(vec![5.0 * (x[1] - x[0]) + x[0] * x[0]]);
        let x = DVector::from_vec(vec![0.3, 0.0]);
        let j = jacobian(g, &x, &[1.0, 1.0], &[Step::Forward, Step::Forward]);
        assert!((j[(0, 1)] - 5.0).abs() < 1e-9);
        // Nonlinear in x0: error of order h.
        let exact_00 = -5.0 + 0.6;
        let err = (j[(0, 0)] - exact_00).abs();
        assert!(err < 1e-4 && err > 1e-12, "{err:e}");
    }
}
