//! Locating an event's time inside one step.
//!
//! The Illinois variant of regula falsi keeps a bracket around the root at every iteration, so
//! the answer can be taken from the side where the event has already happened, and it converges
//! superlinearly on the smooth functions an interpolant gives. Should it ever stall, it falls
//! back to bisection, so the bracket always shrinks to the tolerance.

/// Time tolerance to which an event's time is located, s. Beyond about 10⁶ s the spacing of
/// `f64` times is coarser than this, and the tolerance widens to a few units of it.
pub const EVENT_TIME_TOLERANCE_S: f64 = 1e-9;

/// Iterations of regula falsi before the search switches to plain bisection.
const FALSI_ITERATIONS: usize = 60;
/// Bisection halves the bracket; 200 halvings take any finite bracket below any tolerance.
const BISECTION_ITERATIONS: usize = 200;

/// Finds where `g` crosses from positive to non-positive between `before` and `after`, given
/// as `(time_s, g)` pairs with `g(before) > 0 ≥ g(after)`.
///
/// Returns the end of the final bracket on the non-positive side: a time at or just past the
/// crossing, within the tolerance, so the state reported there satisfies the event's
/// condition and restarting from it does not fire the same event again.
pub(crate) fn locate_crossing<E>(
    mut g: impl FnMut(f64) -> Result<f64, E>,
    before: (f64, f64),
    after: (f64, f64),
) -> Result<f64, E> {
    let (mut low_s, mut g_low) = before;
    let (mut high_s, mut g_high) = after;
    debug_assert!(g_low > 0.0 && g_high <= 0.0 && low_s <= high_s);
    if g_high == 0.0 {
        return Ok(high_s);
    }
    // Values of g used in the secant; the Illinois rule halves the one at a retained end.
    let (mut secant_low, mut secant_high) = (g_low, g_high);
    let mut last_side_moved: Option<bool> = None;

    for iteration in 0..FALSI_ITERATIONS + BISECTION_ITERATIONS {
        let tolerance_s = EVENT_TIME_TOLERANCE_S.max(4.0 * f64::EPSILON * high_s.abs());
        if high_s - low_s <= tolerance_s {
            break;
        }
        let midpoint_s = 0.5 * (low_s + high_s);
        let mut trial_s = if iteration < FALSI_ITERATIONS {
            (low_s * secant_high - high_s * secant_low) / (secant_high - secant_low)
        } else {
            midpoint_s
        };
        if !(trial_s > low_s && trial_s < high_s) {
            trial_s = midpoint_s;
        }
        if !(trial_s > low_s && trial_s < high_s) {
            // The bracket is down to adjacent floating-point numbers.
            break;
        }
        let g_trial = g(trial_s)?;
        if g_trial > 0.0 {
            low_s = trial_s;
            g_low = g_trial;
            secant_low = g_trial;
            if last_side_moved == Some(true) {
                secant_high *= 0.5;
            }
            last_side_moved = Some(true);
        } else {
            high_s = trial_s;
            g_high = g_trial;
            secant_high = g_trial;
            if g_trial == 0.0 {
                break;
            }
            if last_side_moved == Some(false) {
                secant_low *= 0.5;
            }
            last_side_moved = Some(false);
        }
    }
    debug_assert!(g_low > 0.0 && g_high <= 0.0);
    Ok(high_s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::convert::Infallible;

    fn locate(g: impl Fn(f64) -> f64, low: f64, high: f64) -> (f64, usize) {
        let mut calls = 0;
        let root = locate_crossing::<Infallible>(
            |t| {
                calls += 1;
                Ok(g(t))
            },
            (low, g(low)),
            (high, g(high)),
        )
        .unwrap();
        (root, calls)
    }

    #[test]
    fn finds_a_simple_root_from_the_non_positive_side_quickly() {
        let (root, calls) = locate(|t| 2.0 - t * t, 0.0, 3.0);
        assert!(root >= std::f64::consts::SQRT_2);
        assert!(root - std::f64::consts::SQRT_2 <= EVENT_TIME_TOLERANCE_S);
        assert!(calls < 20, "{calls} evaluations");
    }

    #[test]
    fn converges_on_a_function_that_stalls_plain_regula_falsi() {
        // Strongly convex: plain regula falsi keeps one end fixed for ever.
        let (root, calls) = locate(|t| (1.0 - t).powi(9), 0.0, 5.0);
        assert!(
            root >= 1.0 && root - 1.0 <= EVENT_TIME_TOLERANCE_S,
            "root {root}"
        );
        assert!(calls <= FALSI_ITERATIONS + BISECTION_ITERATIONS);
        let (root, _) = locate(|t| (-t).exp() - 1e-3, 0.0, 100.0);
        assert!(root >= 1e3_f64.ln() && root - 1e3_f64.ln() <= EVENT_TIME_TOLERANCE_S);
    }

    #[test]
    fn a_step_end_exactly_on_zero_is_the_root() {
        let (root, calls) = locate(|t| 1.0 - t, 0.0, 1.0);
        assert_eq!((root, calls), (1.0, 0));
    }
}
