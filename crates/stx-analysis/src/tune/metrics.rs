//! How a step response is judged: rise time, overshoot, settling time and actuator use, and
//! the tuning cost that adds them up (see the [tuner's documentation](super)).

use serde::Serialize;

/// A sampled step response (one sample per control period).
#[derive(Debug, Clone, Serialize)]
pub struct StepResponse {
    /// Sample times, s.
    pub time_s: Vec<f64>,
    /// The controlled quantity, SI (rad or m).
    pub output: Vec<f64>,
    /// The actuator command: main line (m) or symmetric brake (0…1).
    pub command: Vec<f64>,
    /// Where the output started.
    pub initial: f64,
    /// Where it was asked to go.
    pub reference: f64,
}

/// What a step response is judged by.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct StepMetrics {
    /// 10–90 % rise time, s (None: never reached 90 %).
    pub rise_time_s: Option<f64>,
    /// Overshoot beyond the reference, % of the step.
    pub overshoot_pct: f64,
    /// Time after which the output stays within 5 % of the step of the reference, s (None:
    /// still outside at the end).
    pub settling_time_s: Option<f64>,
    /// Largest |command − trim command|, in the command's unit.
    pub peak_command: f64,
    /// RMS of the command's deviation from trim over its authority (main-line limit, or the
    /// brake's room from the trim), 1.
    pub command_use: f64,
    /// Share of samples with the command at a limit.
    pub saturated_fraction: f64,
    /// |output − reference| at the end, % of the step.
    pub final_error_pct: f64,
    /// The tuning cost of this response.
    pub cost: f64,
}

/// Fraction of the step that counts as settled.
pub const SETTLING_BAND: f64 = 0.05;

/// Scores a response. `authority` is the command range that counts as full use and
/// `trim_command` the command at trim.
pub fn metrics(
    r: &StepResponse,
    trim_command: f64,
    authority: f64,
    limits: (f64, f64),
    duration_s: f64,
) -> StepMetrics {
    let step = r.reference - r.initial;
    let norm: Vec<f64> = r.output.iter().map(|y| (y - r.initial) / step).collect();
    let crossing = |level: f64| -> Option<f64> {
        norm.iter().position(|&v| v >= level).map(|k| {
            if k == 0 {
                r.time_s[0]
            } else {
                // Linear interpolation between the samples around the crossing.
                let (v0, v1) = (norm[k - 1], norm[k]);
                let (t0, t1) = (r.time_s[k - 1], r.time_s[k]);
                t0 + (level - v0) / (v1 - v0) * (t1 - t0)
            }
        })
    };
    let rise = match (crossing(0.1), crossing(0.9)) {
        (Some(a), Some(b)) => Some(b - a),
        _ => None,
    };
    let overshoot = norm.iter().fold(0.0f64, |m, &v| m.max(v - 1.0)) * 100.0;
    let settled = match norm.iter().rposition(|&v| (v - 1.0).abs() > SETTLING_BAND) {
        None => Some(r.time_s[0]),
        Some(k) if k + 1 < norm.len() => Some(r.time_s[k + 1]),
        Some(_) => None,
    };
    let deviations: Vec<f64> = r.command.iter().map(|u| u - trim_command).collect();
    let peak = deviations.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    let rms =
        (deviations.iter().map(|d| d * d).sum::<f64>() / deviations.len().max(1) as f64).sqrt();
    let saturated = r
        .command
        .iter()
        .filter(|&&u| u <= limits.0 + 1e-9 || u >= limits.1 - 1e-9)
        .count() as f64
        / r.command.len().max(1) as f64;
    let final_error = norm.last().map_or(1.0, |v| (v - 1.0).abs()) * 100.0;
    let mut m = StepMetrics {
        rise_time_s: rise,
        overshoot_pct: overshoot,
        settling_time_s: settled,
        peak_command: peak,
        command_use: rms / authority,
        saturated_fraction: saturated,
        final_error_pct: final_error,
        cost: 0.0,
    };
    m.cost = cost(&m, duration_s);
    m
}

/// The tuning cost (see the module doc): times as shares of the run, overshoot weighted ×2,
/// actuator use ×0.5, saturation ×0.5; a response that never rises or settles costs as if it
/// took twice the run, plus its final error.
pub fn cost(m: &StepMetrics, duration_s: f64) -> f64 {
    let never = 2.0 * duration_s;
    let rise = m.rise_time_s.unwrap_or(never) / duration_s;
    let settle = m.settling_time_s.unwrap_or(never) / duration_s;
    let unsettled = if m.settling_time_s.is_none() {
        m.final_error_pct / 100.0
    } else {
        0.0
    };
    rise + settle
        + 2.0 * m.overshoot_pct / 100.0
        + 0.5 * m.command_use
        + 0.5 * m.saturated_fraction
        + unsettled
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sampled(f: impl Fn(f64) -> f64, duration: f64, dt: f64) -> StepResponse {
        let n = (duration / dt).round() as usize;
        let time_s: Vec<f64> = (0..=n).map(|k| k as f64 * dt).collect();
        StepResponse {
            output: time_s.iter().map(|&t| f(t)).collect(),
            command: vec![0.0; time_s.len()],
            time_s,
            initial: 0.0,
            reference: 1.0,
        }
    }

    #[test]
    fn metrics_of_a_first_order_lag_match_its_closed_form() {
        let tau = 2.0;
        let r = sampled(|t| 1.0 - (-t / tau).exp(), 40.0, 0.01);
        let m = metrics(&r, 0.0, 1.0, (-1.0, 1.0), 40.0);
        // 10–90 % rise: τ ln 9; 5 % settling: τ ln 20; no overshoot.
        let rise = m.rise_time_s.expect("rises");
        assert!((rise - tau * 9f64.ln()).abs() < 0.02, "{rise}");
        let settle = m.settling_time_s.expect("settles");
        assert!((settle - tau * 20f64.ln()).abs() < 0.02, "{settle}");
        assert_eq!(m.overshoot_pct, 0.0);
        assert!(m.final_error_pct < 1e-3);
    }

    #[test]
    fn overshoot_of_a_second_order_system_matches_its_closed_form() {
        let (zeta, omega) = (0.3f64, 1.5f64);
        let wd = omega * (1.0 - zeta * zeta).sqrt();
        let phi = (1.0 - zeta * zeta).sqrt().atan2(zeta);
        let y = |t: f64| {
            1.0 - (-zeta * omega * t).exp() * (wd * t + phi).sin() / (1.0 - zeta * zeta).sqrt()
        };
        let r = sampled(y, 60.0, 0.005);
        let m = metrics(&r, 0.0, 1.0, (-1.0, 1.0), 60.0);
        let expected = 100.0 * (-std::f64::consts::PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
        assert!(
            (m.overshoot_pct - expected).abs() < 0.05,
            "{} vs {expected}",
            m.overshoot_pct
        );
        // A decreasing step (initial 1 → reference 0) scores the same as its mirror.
        let mut down = r.clone();
        down.output.iter_mut().for_each(|v| *v = 1.0 - *v);
        down.initial = 1.0;
        down.reference = 0.0;
        let md = metrics(&down, 0.0, 1.0, (-1.0, 1.0), 60.0);
        assert!((md.overshoot_pct - m.overshoot_pct).abs() < 1e-9);
        assert_eq!(md.settling_time_s, m.settling_time_s);
    }

    #[test]
    fn a_response_that_never_arrives_costs_more_than_any_that_does() {
        let never = sampled(|t| 0.5 * (1.0 - (-t).exp()), 40.0, 0.25);
        let slow = sampled(|t| 1.0 - (-t / 12.0).exp(), 40.0, 0.25);
        let mn = metrics(&never, 0.0, 1.0, (-1.0, 1.0), 40.0);
        let ms = metrics(&slow, 0.0, 1.0, (-1.0, 1.0), 40.0);
        assert!(mn.rise_time_s.is_none() && mn.settling_time_s.is_none());
        assert!(mn.cost > ms.cost, "{} vs {}", mn.cost, ms.cost);
        assert!(mn.cost > 4.0);
    }
}
