//! What the estimator tells guidance, the predictor and the operators: the vehicle's
//! navigation state with a 1-σ uncertainty for each quantity.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// Navigation estimate at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// Instant the estimate is for, s on the mission clock.
    pub time_s: f64,
    /// Drone position, local NED, m.
    pub position_ned_m: Vector3<f64>,
    /// 1-σ of each position component, m.
    pub position_sigma_m: Vector3<f64>,
    /// Velocity over the ground, NED, m/s.
    pub velocity_ned_mps: Vector3<f64>,
    /// 1-σ of each velocity component, m/s.
    pub velocity_sigma_mps: Vector3<f64>,
    /// Heading of the vehicle, rad in (−π, π]: the direction of its horizontal velocity
    /// through the air. Guidance steers on it, not on the drone's yaw: the drone swings and
    /// twists about its lines by tens of degrees in turns.
    pub heading_rad: f64,
    /// 1-σ of the heading, rad.
    pub heading_sigma_rad: f64,
    /// Heading rate (turn rate through the air), rad/s (positive turning right).
    pub heading_rate_rad_s: f64,
    /// 1-σ of the heading rate, rad/s.
    pub heading_rate_sigma_rad_s: f64,
    /// Yaw of the drone's x axis from north as its AHRS reports it (filtered), rad in
    /// (−π, π].
    pub drone_yaw_rad: f64,
    /// Rate of the drone's yaw, rad/s.
    pub drone_yaw_rate_rad_s: f64,
    /// Course over the ground, rad in (−π, π].
    pub course_rad: f64,
    /// 1-σ of the course, rad.
    pub course_sigma_rad: f64,
    /// Drone roll, rad (from the AHRS).
    pub roll_rad: f64,
    /// Drone pitch, rad (from the AHRS).
    pub pitch_rad: f64,
    /// True airspeed, m/s.
    pub airspeed_mps: f64,
    /// 1-σ of the airspeed, m/s.
    pub airspeed_sigma_mps: f64,
    /// Sink rate, m/s, positive descending.
    pub sink_rate_mps: f64,
    /// 1-σ of the sink rate, m/s.
    pub sink_rate_sigma_mps: f64,
    /// Horizontal airspeed over sink rate: the glide through the air mass.
    pub glide_ratio_air: f64,
    /// 1-σ of the air glide ratio (∞ while the sink rate is too small to divide by).
    #[serde(default)]
    pub glide_ratio_air_sigma: f64,
    /// Horizontal ground speed over sink rate: the glide over the ground.
    pub glide_ratio_ground: f64,
    /// 1-σ of the ground glide ratio.
    #[serde(default)]
    pub glide_ratio_ground_sigma: f64,
    /// Air density from the pitot's static pressure and temperature (ideal gas), kg/m³; 0
    /// before the first air-data sample. Guidance plans its speeds with it.
    #[serde(default)]
    pub air_density_kg_per_m3: f64,
    /// 1-σ of the air density, kg/m³ (∞ before the first sample).
    #[serde(default = "not_measured")]
    pub air_density_sigma_kg_per_m3: f64,
    /// Wind (the air's velocity), NED, m/s; the vertical component is taken as zero.
    pub wind_ned_mps: Vector3<f64>,
    /// 1-σ of the wind's north and east components (and 0 for down), m/s.
    pub wind_sigma_mps: Vector3<f64>,
    /// The AHRS's heading bias as the estimator has learnt it (the AHRS's yaw minus the
    /// drone's true yaw), rad; 0 before the navigation filter starts. Learnt in turns: in
    /// straight flight it cannot be told from the drone's own sideslip.
    #[serde(default)]
    pub heading_bias_rad: f64,
    /// 1-σ of the heading bias, rad (∞ before the navigation filter starts).
    #[serde(default = "not_measured")]
    pub heading_bias_sigma_rad: f64,
    /// The pitot's scale as the estimator has learnt it: the pitot reads this many times the
    /// air's true speed along the drone's x axis; 1 before the navigation filter starts.
    #[serde(default = "unit_scale")]
    pub pitot_scale: f64,
    /// 1-σ of the pitot scale (∞ before the navigation filter starts).
    #[serde(default = "not_measured")]
    pub pitot_scale_sigma: f64,
    /// A GPS fix was used within the estimator's GPS timeout.
    pub gps_ok: bool,
    /// Seconds since the last GPS fix used (∞ before the first).
    pub gps_age_s: f64,
    /// The AHRS is reporting.
    pub attitude_ok: bool,
    /// The pitot is reporting.
    pub air_data_ok: bool,
}

fn not_measured() -> f64 {
    f64::INFINITY
}

fn unit_scale() -> f64 {
    1.0
}

impl Estimate {
    /// Height above the local ground (the NED origin's level), m.
    pub fn height_m(&self) -> f64 {
        -self.position_ned_m.z
    }

    /// Horizontal ground speed, m/s.
    pub fn ground_speed_mps(&self) -> f64 {
        self.velocity_ned_mps.x.hypot(self.velocity_ned_mps.y)
    }

    /// Horizontal wind speed, m/s.
    pub fn wind_speed_mps(&self) -> f64 {
        self.wind_ned_mps.x.hypot(self.wind_ned_mps.y)
    }
}
