//! Nelder–Mead downhill simplex minimisation, derivative-free.
//!
//! The tuner's cost comes from simulated step responses with saturation and a sampled
//! controller: piecewise smooth, with no gradient worth trusting, and only two or three
//! variables. That is the case Nelder–Mead was made for. The standard coefficients
//! (reflection 1, expansion 2, contraction ½, shrink ½; Lagarias et al. 1998) are used, with
//! the simplex ordered on every iteration so ties resolve the same way each run.

/// Settings of one minimisation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NelderMeadOptions {
    /// Size of the initial simplex along each axis, in the variables' units.
    pub initial_step: f64,
    /// Stop when the spread of the simplex's costs falls below this.
    pub cost_tolerance: f64,
    /// Stop when every vertex is within this of the best, in the variables' units.
    pub position_tolerance: f64,
    /// Most cost evaluations.
    pub max_evaluations: usize,
}

impl Default for NelderMeadOptions {
    fn default() -> Self {
        Self {
            initial_step: 0.5,
            cost_tolerance: 1e-6,
            position_tolerance: 1e-4,
            max_evaluations: 400,
        }
    }
}

/// Where a minimisation ended.
#[derive(Debug, Clone, PartialEq)]
pub struct Minimum {
    /// Best point found.
    pub x: Vec<f64>,
    /// Its cost.
    pub cost: f64,
    /// Cost evaluations used.
    pub evaluations: usize,
    /// Whether a tolerance was met (false: the evaluation budget ran out).
    pub converged: bool,
}

/// Minimises `cost` from `start`. A non-finite cost counts as +∞, so a region where the
/// closed loop blows up is simply avoided. `progress(evaluations)` is called after each
/// evaluation.
pub fn minimize(
    mut cost: impl FnMut(&[f64]) -> f64,
    start: &[f64],
    options: &NelderMeadOptions,
    mut progress: impl FnMut(usize),
) -> Minimum {
    let n = start.len();
    // A Cell so the budget can be read while the closure that counts is alive.
    let evaluations = std::cell::Cell::new(0usize);
    let mut eval = |x: &[f64]| {
        evaluations.set(evaluations.get() + 1);
        progress(evaluations.get());
        let c = cost(x);
        if c.is_finite() { c } else { f64::INFINITY }
    };
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(n + 1);
    simplex.push((start.to_vec(), eval(start)));
    for i in 0..n {
        let mut x = start.to_vec();
        x[i] += options.initial_step;
        let c = eval(&x);
        simplex.push((x, c));
    }
    let mut converged = false;
    loop {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let best = simplex[0].1;
        let worst = simplex[n].1;
        let spread = if worst.is_finite() {
            worst - best
        } else {
            f64::INFINITY
        };
        let size = simplex[1..]
            .iter()
            .flat_map(|(x, _)| x.iter().zip(&simplex[0].0).map(|(a, b)| (a - b).abs()))
            .fold(0.0, f64::max);
        if spread <= options.cost_tolerance && size <= options.position_tolerance
            || size <= options.position_tolerance * 1e-3
        {
            converged = true;
            break;
        }
        if evaluations.get() >= options.max_evaluations {
            break;
        }
        let centroid: Vec<f64> = (0..n)
            .map(|k| simplex[..n].iter().map(|(x, _)| x[k]).sum::<f64>() / n as f64)
            .collect();
        let along = |t: f64| -> Vec<f64> {
            centroid
                .iter()
                .zip(&simplex[n].0)
                .map(|(c, w)| c + t * (c - w))
                .collect()
        };
        let reflected = along(1.0);
        let c_r = eval(&reflected);
        if c_r < simplex[0].1 {
            let expanded = along(2.0);
            let c_e = eval(&expanded);
            simplex[n] = if c_e < c_r {
                (expanded, c_e)
            } else {
                (reflected, c_r)
            };
            continue;
        }
        if c_r < simplex[n - 1].1 {
            simplex[n] = (reflected, c_r);
            continue;
        }
        // Contract: outside if the reflection beat the worst, inside otherwise.
        let (contracted, c_c) = if c_r < simplex[n].1 {
            let x = along(0.5);
            let c = eval(&x);
            (x, c)
        } else {
            let x = along(-0.5);
            let c = eval(&x);
            (x, c)
        };
        if c_c < simplex[n].1.min(c_r) {
            simplex[n] = (contracted, c_c);
            continue;
        }
        // Shrink towards the best vertex.
        let best_x = simplex[0].0.clone();
        for vertex in simplex.iter_mut().skip(1) {
            let x: Vec<f64> = vertex
                .0
                .iter()
                .zip(&best_x)
                .map(|(v, b)| b + 0.5 * (v - b))
                .collect();
            let c = eval(&x);
            *vertex = (x, c);
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (x, cost) = simplex.swap_remove(0);
    Minimum {
        x,
        cost,
        evaluations: evaluations.get(),
        converged,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_minimum_of_a_shifted_quadratic() {
        let m = minimize(
            |x| (x[0] - 3.0).powi(2) + 10.0 * (x[1] + 1.0).powi(2) + 2.0,
            &[0.0, 0.0],
            &NelderMeadOptions {
                position_tolerance: 1e-7,
                cost_tolerance: 1e-12,
                ..Default::default()
            },
            |_| {},
        );
        assert!(m.converged);
        assert!(
            (m.x[0] - 3.0).abs() < 1e-4 && (m.x[1] + 1.0).abs() < 1e-4,
            "{m:?}"
        );
        assert!((m.cost - 2.0).abs() < 1e-8);
    }

    #[test]
    fn follows_the_rosenbrock_valley() {
        let m = minimize(
            |x| 100.0 * (x[1] - x[0] * x[0]).powi(2) + (1.0 - x[0]).powi(2),
            &[-1.2, 1.0],
            &NelderMeadOptions {
                max_evaluations: 2000,
                position_tolerance: 1e-8,
                cost_tolerance: 1e-14,
                ..Default::default()
            },
            |_| {},
        );
        assert!(
            (m.x[0] - 1.0).abs() < 1e-3 && (m.x[1] - 1.0).abs() < 1e-3,
            "{m:?}"
        );
    }

    #[test]
    fn avoids_regions_where_the_cost_is_not_finite_and_respects_the_budget() {
        let mut calls = 0;
        let m = minimize(
            |x| {
                if x[0] < 0.0 {
                    f64::NAN
                } else {
                    (x[0] - 0.2).powi(2)
                }
            },
            &[1.0],
            &NelderMeadOptions {
                max_evaluations: 30,
                ..Default::default()
            },
            |n| calls = n,
        );
        assert!(m.x[0] >= 0.0 && m.cost.is_finite());
        assert!(m.evaluations <= 30 + 3, "{}", m.evaluations);
        assert_eq!(calls, m.evaluations);
    }
}
