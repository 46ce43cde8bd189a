//! The pitot: the air's speed along the drone's x axis, projected with the attitude of the
//! sample's instant (the AHRS's own, interpolated between two AHRS samples, or the angle
//! filters'), its uncertainty added to the noise; and the restart of the air velocity when the
//! pitot keeps contradicting the state.

use nalgebra::{SMatrix, Vector2, Vector3};
use stx_types::rotation::wrap_pi;

use super::angle::AngleFilter;
use super::config::Tuning;
use super::ekf::{MIN_SPEED_FOR_DIRECTION_MPS, N, Nav, Outcome, ix};
use crate::measurement::{AirDataSample, AttitudeSample};

/// Longest gap between two AHRS samples across which a pitot sample's attitude is
/// interpolated, s; beyond it the angle filters' estimate is used.
pub(crate) const MAX_INTERPOLATION_S: f64 = 1.0;

/// The drone's x axis in NED for pitch θ and yaw ψ (roll does not move it):
/// `e_x = [cos θ cos ψ, cos θ sin ψ, −sin θ]`.
pub(crate) fn x_axis_ned(pitch: f64, yaw: f64) -> Vector3<f64> {
    let (st, ct) = pitch.sin_cos();
    let (sp, cp) = yaw.sin_cos();
    Vector3::new(ct * cp, ct * sp, -st)
}

/// `∂(e_x·v)/∂θ` and `∂(e_x·v)/∂ψ`: how pitch and heading errors become pitot errors.
fn x_axis_projection_gradient(pitch: f64, yaw: f64, v: &Vector3<f64>) -> (f64, f64) {
    let (st, ct) = pitch.sin_cos();
    let (sp, cp) = yaw.sin_cos();
    let along = cp * v.x + sp * v.y;
    let across = -sp * v.x + cp * v.y;
    (-st * along - ct * v.z, ct * across)
}

/// Pitch and heading at `time_s` with their variances: the AHRS's own if sampled at that
/// instant, else interpolated between the AHRS samples around it when both are known (the
/// drone swings too fast for the angle filters' extrapolation), else the angle filters'.
pub(super) fn attitude_at(
    attitude: &[AngleFilter; 3],
    last_attitude: Option<AttitudeSample>,
    time_s: f64,
    next: Option<&AttitudeSample>,
    t: &Tuning,
) -> (f64, f64, f64, f64) {
    let [_, pitch, yaw] = attitude;
    let filtered = (
        pitch.angle_rad,
        pitch.angle_variance(),
        yaw.angle_rad,
        yaw.angle_variance(),
    );
    let Some(before) = last_attitude else {
        return filtered;
    };
    if before.time_s == time_s {
        // Sampled together (the drone's 4 Hz loop): the AHRS's own angles.
        return (before.pitch_rad, t.r_roll_pitch, before.yaw_rad, t.r_yaw);
    }
    let Some(after) = next else {
        return filtered;
    };
    let span_s = after.time_s - before.time_s;
    if !(before.time_s <= time_s && time_s <= after.time_s && span_s <= MAX_INTERPOLATION_S) {
        return filtered;
    }
    let f = if span_s > 0.0 {
        (time_s - before.time_s) / span_s
    } else {
        0.0
    };
    let d_pitch = after.pitch_rad - before.pitch_rad;
    let d_yaw = wrap_pi(after.yaw_rad - before.yaw_rad);
    // The swing between the samples is not a straight line: allow for the chord's error.
    let bow = 0.5 * f.min(1.0 - f);
    (
        before.pitch_rad + f * d_pitch,
        t.r_roll_pitch + (bow * d_pitch).powi(2),
        wrap_pi(before.yaw_rad + f * d_yaw),
        t.r_yaw + (bow * d_yaw).powi(2),
    )
}

/// Consecutive pitot samples that read a healthy airspeed along the drone's x axis while the
/// state put the air beside or behind it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Pitot {
    contradicting_in_row: u32,
}

impl Pitot {
    pub(super) const fn new() -> Self {
        Self {
            contradicting_in_row: 0,
        }
    }

    /// Pitot: indicated airspeed `z = k·(e_x·v_air)`, the air along the drone's x axis from
    /// the AHRS's pitch and its heading less the heading-bias state `δψ`; their uncertainty is
    /// added to the noise. `attitude` is the pitch, its variance, the AHRS heading and its
    /// variance at the sample's instant ([`attitude_at`]).
    ///
    /// `∂z/∂δψ = −k·cos θ·(e_y·a_h)`: the bias shows where the air comes from beside the x
    /// axis, in the drone's swing and in turns; in a straight, steady glide the pitot hardly
    /// sees it (the parent module's documentation says where it is observable).
    /// `ground_known`: whether a GPS fix has just set the ground velocity (see
    /// [`Pitot::contradicted`]).
    pub(super) fn update(
        &mut self,
        nav: &mut Nav,
        a: &AirDataSample,
        attitude: (f64, f64, f64, f64),
        ground_known: bool,
        t: &Tuning,
    ) -> Outcome {
        let measured = a.indicated_airspeed_mps();
        let (pitch, pitch_variance, measured_yaw, yaw_variance) = attitude;
        let yaw = measured_yaw - nav.x[ix::HEADING_BIAS];
        let air = nav.air_ned();
        let e_x = x_axis_ned(pitch, yaw);
        let along_x = e_x.dot(&air);
        let scale = nav.x[ix::SCALE];
        let floor = t.pitot_min_airspeed_mps.max(MIN_SPEED_FOR_DIRECTION_MPS);
        if measured < floor {
            return Outcome::Unused;
        }
        if scale * along_x < floor {
            // The pitot reads the air coming from ahead, the state has it from beside or
            // behind. A swinging drone does that for a moment; for seconds on end it means the
            // state has turned its air velocity (and so the wind) the wrong way — a solution
            // that every other measurement also fits (the GPS sees only their sum, and the
            // straight-flight sideslip is zero for a reversed air velocity too), so nothing
            // else would ever correct it. Monte Carlo seed 4 run 157 flew on a wind 19 m/s
            // off, seed 3 run 354 on one 7 m/s off.
            return self.contradicted(nav, measured, yaw, ground_known, t, Outcome::Unused);
        }
        let density = a.density_kg_per_m3();
        let (d_pitch, d_yaw) = x_axis_projection_gradient(pitch, yaw, &air);
        // σ_u = σ_Δp / (ρ·u) from u = √(2Δp/ρ), plus the attitude's share and a floor.
        let variance = (t.differential_pressure_noise_pa / (density * measured)).powi(2)
            + (scale * d_pitch).powi(2) * pitch_variance
            + (scale * d_yaw).powi(2) * yaw_variance
            + t.pitot_floor_variance;
        let mut h = SMatrix::<f64, 1, N>::zeros();
        for k in 0..3 {
            h[(0, ix::AIR + k)] = scale * e_x[k];
        }
        h[(0, ix::SCALE)] = along_x;
        h[(0, ix::HEADING_BIAS)] = -scale * d_yaw;
        let y = SMatrix::<f64, 1, 1>::new(measured - scale * along_x);
        if nav.update(
            &y,
            &h,
            &SMatrix::<f64, 1, 1>::new(variance),
            Some(t.gate_nis[0]),
        ) {
            self.contradicting_in_row = 0;
            Outcome::Used
        } else {
            // Refused for seconds on end, the pitot contradicts a state just as sure of a wrong
            // air velocity: after a GPS outage in the swinging final approach (one-source GPS
            // dispersions, seed 1 run 102) the dead-reckoned air velocity had turned away, the
            // returning fixes then held air and wind wrong by 10 m/s in a sum that fitted
            // them, and the gate refused the pitot (7 m/s read, 17 m/s predicted) for 30 s.
            self.contradicted(nav, measured, yaw, ground_known, t, Outcome::Gated)
        }
    }

    /// One more pitot sample that contradicts the state (`meanwhile` is what it counts as).
    /// After as many in a row as GPS rejections that restart the filter, the air velocity is
    /// restarted along the drone's x axis (heading `yaw`, the bias taken off) at the pitot's
    /// speed. With `ground_known` (a fix just now) the ground velocity is kept and the wind
    /// is what is left of it; without, the wind is kept and the ground velocity follows.
    ///
    /// Between fixes the ground velocity is dead-reckoned from the very air velocity the
    /// pitot contradicts, and the wind, learned over minutes, is the surer of the two: in a
    /// realistic Monte Carlo run (seed 1 run 277 with the anemometer, on a variant of
    /// guidance) the stack turned through 180° on its final 3.3 s into a GPS dropout, the
    /// restart kept a ground velocity 9 m/s off, the wind jumped by 9 m/s and the capsule
    /// landed 197 m from the target.
    fn contradicted(
        &mut self,
        nav: &mut Nav,
        measured: f64,
        yaw: f64,
        ground_known: bool,
        t: &Tuning,
        meanwhile: Outcome,
    ) -> Outcome {
        self.contradicting_in_row += 1;
        if self.contradicting_in_row < t.reset_after_rejections {
            return meanwhile;
        }
        self.contradicting_in_row = 0;
        let air = nav.air_ned();
        let ground = air + nav.wind_ned();
        let speed = measured / nav.x[ix::SCALE].max(0.1);
        let horizontal = (speed * speed - air.z * air.z).max(0.0).sqrt();
        let (sin_yaw, cos_yaw) = yaw.sin_cos();
        let new_air = Vector2::new(horizontal * cos_yaw, horizontal * sin_yaw);
        let restarted: &[usize] = if ground_known {
            &[ix::AIR, ix::AIR + 1, ix::WIND, ix::WIND + 1]
        } else {
            &[ix::AIR, ix::AIR + 1]
        };
        for k in 0..2 {
            nav.x[ix::AIR + k] = new_air[k];
            if ground_known {
                nav.x[ix::WIND + k] = ground[k] - new_air[k];
            }
        }
        for &i in restarted {
            for j in 0..N {
                nav.p[(i, j)] = 0.0;
                nav.p[(j, i)] = 0.0;
            }
        }
        for k in 0..2 {
            // The drone's heading is only the stack's give or take its swing: the new air
            // velocity is uncertain by that much, and so is the wind when it is what the
            // ground velocity leaves, tied to the air through the sum.
            let variance = t.initial_wind_variance.min((0.5 * horizontal).powi(2));
            nav.p[(ix::AIR + k, ix::AIR + k)] = variance;
            if ground_known {
                nav.p[(ix::WIND + k, ix::WIND + k)] = variance;
                nav.p[(ix::AIR + k, ix::WIND + k)] = -variance;
                nav.p[(ix::WIND + k, ix::AIR + k)] = -variance;
            }
        }
        Outcome::Reset
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stx_types::rotation::t_from_euler;

    #[test]
    fn the_x_axis_is_the_first_row_of_the_models_euler_matrix() {
        let (roll, pitch, yaw) = (0.3, -0.5, 2.9);
        let model = t_from_euler(&Vector3::new(roll, pitch, yaw));
        let row = model.row(0).transpose();
        assert!((x_axis_ned(pitch, yaw) - row).norm() < 1e-12);
    }

    /// A state sure (0.3 m/s) of its air velocity and wind (north, east), m/s, and of a
    /// pitot scale of 1.
    fn sure_of(air: [f64; 2], wind: [f64; 2]) -> Nav {
        let mut x = crate::estimator::ekf::StateVec::zeros();
        for k in 0..2 {
            x[ix::AIR + k] = air[k];
            x[ix::WIND + k] = wind[k];
        }
        x[ix::SCALE] = 1.0;
        let mut p = crate::estimator::ekf::Covariance::identity() * 0.09;
        p[(ix::SCALE, ix::SCALE)] = 1e-4;
        Nav { x, p }
    }

    /// A pitot sample reading `airspeed_mps` at sea level.
    fn pitot_reading(airspeed_mps: f64) -> AirDataSample {
        let (pressure_pa, temperature_k) = (101_325.0, 288.15);
        let density = pressure_pa / (crate::measurement::AIR_GAS_CONSTANT * temperature_k);
        AirDataSample {
            time_s: 0.0,
            differential_pressure_pa: 0.5 * density * airspeed_mps * airspeed_mps,
            static_pressure_pa: pressure_pa,
            temperature_k,
        }
    }

    /// The state after a GPS outage in seed 1 run 102 (one-source GPS dispersions), reduced:
    /// sure, within 0.3 m/s, that the stack flies north at 17 m/s through a 10-m/s headwind,
    /// when it flies at 7 m/s in still air; the ground velocity, 7 m/s north, fits either.
    #[test]
    fn a_pitot_the_gate_keeps_refusing_restarts_a_confidently_wrong_air_velocity() {
        let t = Tuning::new(&crate::estimator::EstimatorConfig::default());
        let mut nav = sure_of([17.0, 0.0], [-10.0, 0.0]);
        let sample = pitot_reading(7.0);
        let level_north = (0.0, t.r_roll_pitch, 0.0, t.r_yaw);
        let mut pitot = Pitot::new();
        for _ in 1..t.reset_after_rejections {
            let outcome = pitot.update(&mut nav, &sample, level_north, true, &t);
            assert_eq!(outcome, Outcome::Gated);
            assert_eq!(nav.x[ix::AIR], 17.0, "a refused sample changes nothing");
        }
        let outcome = pitot.update(&mut nav, &sample, level_north, true, &t);
        assert_eq!(outcome, Outcome::Reset);
        let (air, wind) = (nav.air_ned(), nav.wind_ned());
        assert!(
            (air.x - 7.0).abs() < 0.05 && air.y.abs() < 1e-9,
            "air {air:?}"
        );
        assert!(wind.x.abs() < 0.05, "wind {wind:?}");
        assert!(nav.p[(ix::AIR, ix::AIR)] > 9.0, "and unsure of it again");
    }

    /// Seed 1 run 277 (anemometer, a variant of guidance), reduced: 3.3 s into a GPS
    /// dropout the stack had turned to fly east at 4 m/s through a 3.4 m/s south-westerly
    /// drift, while the dead-reckoned state still had it flying west: a restart that kept that
    /// ground velocity made the wind 9 m/s wrong. Without a fix the wind is kept.
    #[test]
    fn between_fixes_a_pitot_restart_keeps_the_wind() {
        let t = Tuning::new(&crate::estimator::EstimatorConfig::default());
        let sample = pitot_reading(5.1);
        let level_east = (0.0, t.r_roll_pitch, std::f64::consts::FRAC_PI_2, t.r_yaw);
        let restart = |ground_known: bool| {
            let mut nav = sure_of([0.7, -4.9], [-3.4, -0.6]);
            let mut pitot = Pitot::new();
            let outcomes: Vec<Outcome> = (0..t.reset_after_rejections)
                .map(|_| pitot.update(&mut nav, &sample, level_east, ground_known, &t))
                .collect();
            assert_eq!(outcomes.last(), Some(&Outcome::Reset));
            nav
        };
        let between = restart(false);
        let (air, wind) = (between.air_ned(), between.wind_ned());
        assert!(
            air.x.abs() < 1e-9 && (air.y - 5.1).abs() < 0.05,
            "air {air:?}"
        );
        assert_eq!([wind.x, wind.y], [-3.4, -0.6], "the wind is kept");
        assert!(
            between.p[(ix::AIR + 1, ix::AIR + 1)] > 1.0,
            "the air unsure again"
        );
        assert_eq!(
            between.p[(ix::WIND, ix::WIND)],
            0.09,
            "the wind as sure as it was"
        );
        // Just after a fix the ground velocity is kept, as before: here it moves the wind
        // by 9 m/s, which is what the fix said.
        let fixed = restart(true).wind_ned();
        assert!(
            (fixed.y - (-4.9 - 0.6 - 5.1)).abs() < 0.05,
            "wind {fixed:?}"
        );
    }

    #[test]
    fn projection_gradient_matches_finite_differences() {
        let v = Vector3::new(-6.0, 3.0, 2.5);
        let (pitch, yaw) = (-0.4, 3.0);
        let (d_pitch, d_yaw) = x_axis_projection_gradient(pitch, yaw, &v);
        let h = 1e-6;
        let f = |p: f64, y: f64| x_axis_ned(p, y).dot(&v);
        assert!((d_pitch - (f(pitch + h, yaw) - f(pitch - h, yaw)) / (2.0 * h)).abs() < 1e-6);
        assert!((d_yaw - (f(pitch, yaw + h) - f(pitch, yaw - h)) / (2.0 * h)).abs() < 1e-6);
    }
}
