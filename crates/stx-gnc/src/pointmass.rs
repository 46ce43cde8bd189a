//! A point-mass parafoil for planning and prediction: position, heading, a turn rate that lags
//! the main line, and airspeed and sink rate from [`GlidePerformance`] for the brake setting.
//!
//! It flies the same guidance as the real vehicle, thousands of times faster than the 14-DOF
//! model, so the landing predictor can ask "where does this plan land?" every second, and guidance
//! tests can fly whole landings in milliseconds.

use nalgebra::Vector3;
use stx_types::controls::Controls;
use stx_types::rotation::wrap_pi;

use crate::estimate::Estimate;
use crate::performance::GlidePerformance;

/// Servo rate constant of the point mass, 1/s (the seed's K = 5).
const SERVO_RATE_PER_S: f64 = 5.0;

/// The air the point mass flies in and how it deviates from the nominal parafoil.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Conditions {
    /// Wind, NED, m/s.
    pub wind_ned_mps: Vector3<f64>,
    /// Air density, kg/m³.
    pub density_kg_per_m3: f64,
    /// Airspeed relative to the nominal parafoil's.
    pub airspeed_scale: f64,
    /// Sink rate relative to the nominal parafoil's.
    pub sink_scale: f64,
}

impl Conditions {
    /// The nominal parafoil in wind `wind_ned_mps` and air of density `density_kg_per_m3`.
    pub fn nominal(wind_ned_mps: Vector3<f64>, density_kg_per_m3: f64) -> Self {
        Self {
            wind_ned_mps,
            density_kg_per_m3,
            airspeed_scale: 1.0,
            sink_scale: 1.0,
        }
    }
}

/// The point mass's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointMass {
    /// Time, s.
    pub time_s: f64,
    /// Position, local NED, m.
    pub position_ned_m: Vector3<f64>,
    /// Heading, rad.
    pub heading_rad: f64,
    /// Turn rate, rad/s.
    pub turn_rate_rad_s: f64,
    /// Main-line servo position, m.
    pub main_line_m: f64,
    /// Symmetric brake servo position, 0…1.
    pub brake: f64,
    /// Velocity over the ground at the last step, NED, m/s.
    pub velocity_ned_mps: Vector3<f64>,
    /// Sink rate at the last step, m/s.
    pub sink_rate_mps: f64,
}

impl PointMass {
    /// A point mass at rest in the air at `position_ned_m` heading `heading_rad`.
    pub fn new(time_s: f64, position_ned_m: Vector3<f64>, heading_rad: f64) -> Self {
        Self {
            time_s,
            position_ned_m,
            heading_rad,
            turn_rate_rad_s: 0.0,
            main_line_m: 0.0,
            brake: 0.0,
            velocity_ned_mps: Vector3::zeros(),
            sink_rate_mps: 0.0,
        }
    }

    /// Advances `dt_s` seconds with `controls` held in the conditions `air`.
    pub fn step(
        &mut self,
        perf: &GlidePerformance,
        controls: &Controls,
        air: &Conditions,
        dt_s: f64,
    ) {
        let Conditions {
            wind_ned_mps,
            density_kg_per_m3,
            airspeed_scale,
            sink_scale,
        } = *air;
        let servo = 1.0 - (-SERVO_RATE_PER_S * dt_s).exp();
        self.main_line_m += (controls.main_line_m - self.main_line_m) * servo;
        let brake_command = 0.5 * (controls.brake_right + controls.brake_left);
        self.brake += (brake_command - self.brake) * servo;
        let turn = 1.0 - (-dt_s / perf.turn_time_constant_s.max(1e-3)).exp();
        self.turn_rate_rad_s += (perf.turn_rate(self.main_line_m) - self.turn_rate_rad_s) * turn;
        self.heading_rad = wrap_pi(self.heading_rad + self.turn_rate_rad_s * dt_s);
        let horizontal = perf.horizontal_airspeed(self.brake, density_kg_per_m3) * airspeed_scale;
        let sink = perf.sink_rate(self.brake, self.turn_rate_rad_s, density_kg_per_m3) * sink_scale;
        let (s, c) = self.heading_rad.sin_cos();
        self.velocity_ned_mps = Vector3::new(
            horizontal * c + wind_ned_mps.x,
            horizontal * s + wind_ned_mps.y,
            sink,
        );
        self.sink_rate_mps = sink;
        self.position_ned_m += self.velocity_ned_mps * dt_s;
        self.time_s += dt_s;
    }

    /// What a perfect estimator would report for the point mass in wind `wind_ned_mps`.
    pub fn estimate(&self, wind_ned_mps: &Vector3<f64>) -> Estimate {
        let v = self.velocity_ned_mps;
        let air = v - Vector3::new(wind_ned_mps.x, wind_ned_mps.y, 0.0);
        let sink = self.sink_rate_mps;
        let horizontal_air = air.x.hypot(air.y);
        Estimate {
            time_s: self.time_s,
            position_ned_m: self.position_ned_m,
            position_sigma_m: Vector3::zeros(),
            velocity_ned_mps: v,
            velocity_sigma_mps: Vector3::zeros(),
            heading_rad: self.heading_rad,
            heading_sigma_rad: 0.0,
            heading_rate_rad_s: self.turn_rate_rad_s,
            heading_rate_sigma_rad_s: 0.0,
            drone_yaw_rad: self.heading_rad,
            drone_yaw_rate_rad_s: self.turn_rate_rad_s,
            course_rad: if v.x.hypot(v.y) > 1e-9 {
                v.y.atan2(v.x)
            } else {
                self.heading_rad
            },
            course_sigma_rad: 0.0,
            roll_rad: 0.0,
            pitch_rad: 0.0,
            airspeed_mps: air.norm(),
            airspeed_sigma_mps: 0.0,
            sink_rate_mps: sink,
            sink_rate_sigma_mps: 0.0,
            glide_ratio_air: if sink > 1e-6 {
                horizontal_air / sink
            } else {
                f64::INFINITY
            },
            glide_ratio_ground: if sink > 1e-6 {
                v.x.hypot(v.y) / sink
            } else {
                f64::INFINITY
            },
            glide_ratio_air_sigma: 0.0,
            glide_ratio_ground_sigma: 0.0,
            // A point mass has no pitot: guidance takes the density it is given.
            air_density_kg_per_m3: 0.0,
            air_density_sigma_kg_per_m3: f64::INFINITY,
            wind_ned_mps: Vector3::new(wind_ned_mps.x, wind_ned_mps.y, 0.0),
            wind_sigma_mps: Vector3::zeros(),
            // No AHRS, no pitot: nothing to be biased.
            heading_bias_rad: 0.0,
            heading_bias_sigma_rad: 0.0,
            pitot_scale: 1.0,
            pitot_scale_sigma: 0.0,
            gps_ok: true,
            gps_age_s: 0.0,
            attitude_ok: true,
            air_data_ok: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glides_two_to_one_in_still_air_and_drifts_with_the_wind() {
        let perf = GlidePerformance::default();
        let mut p = PointMass::new(0.0, Vector3::new(0.0, 0.0, -100.0), 0.0);
        for _ in 0..100 {
            let still = Conditions::nominal(Vector3::zeros(), 1.225);
            p.step(&perf, &Controls::default(), &still, 0.1);
        }
        let glide = p.position_ned_m.x / (p.position_ned_m.z + 100.0);
        assert!((glide - 2.05).abs() < 0.05, "{glide}");
        let mut q = PointMass::new(0.0, Vector3::zeros(), 0.0);
        for _ in 0..100 {
            let windy = Conditions::nominal(Vector3::new(0.0, 3.0, 0.0), 1.225);
            q.step(&perf, &Controls::default(), &windy, 0.1);
        }
        assert!((q.position_ned_m.y - 30.0).abs() < 1e-9);
    }

    #[test]
    fn the_main_line_turns_it_with_a_lag() {
        let perf = GlidePerformance::default();
        let mut p = PointMass::new(0.0, Vector3::zeros(), 0.0);
        let right = Controls {
            main_line_m: 0.01,
            ..Default::default()
        };
        p.step(
            &perf,
            &right,
            &Conditions::nominal(Vector3::zeros(), 1.225),
            0.1,
        );
        let early = p.turn_rate_rad_s;
        for _ in 0..100 {
            p.step(
                &perf,
                &right,
                &Conditions::nominal(Vector3::zeros(), 1.225),
                0.1,
            );
        }
        assert!(early > 0.0 && early < 0.5 * p.turn_rate_rad_s);
        assert!((p.turn_rate_rad_s - perf.turn_rate(0.01)).abs() < 1e-3);
    }
}
