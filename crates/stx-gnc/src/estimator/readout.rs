//! The estimate read out of the navigation state: velocity, course, airspeed, sink rate and
//! glide ratios, the stack's heading and turn rate, the wind, and what has been learnt of the
//! pitot's scale and the AHRS's heading bias, each with its 1-σ.

use nalgebra::{Matrix3, SMatrix, Vector2, Vector3};
use stx_types::rotation::wrap_pi;

use super::ekf::{N, Nav, ix};
use crate::estimate::Estimate;

/// Below this sink rate a glide ratio means nothing and is reported as infinite, m/s.
const MIN_SINK_FOR_GLIDE_MPS: f64 = 0.05;

/// Fills in `e` what the navigation state `nav` knows.
pub(super) fn read_nav(e: &mut Estimate, nav: &Nav) {
    let air = nav.air_ned();
    let velocity = air + nav.wind_ned();
    // Velocity covariance over (air, wind).
    let mut j = SMatrix::<f64, 3, N>::zeros();
    for k in 0..3 {
        j[(k, ix::AIR + k)] = 1.0;
    }
    j[(0, ix::WIND)] = 1.0;
    j[(1, ix::WIND + 1)] = 1.0;
    j[(2, ix::WIND_DOWN)] = 1.0;
    let velocity_cov = j * nav.p * j.transpose();

    let sigma = |variance: f64| variance.max(0.0).sqrt();
    e.position_ned_m = nav.x.fixed_rows::<3>(ix::POSITION).into_owned();
    e.position_sigma_m = Vector3::from_fn(|k, _| sigma(nav.p[(k, k)]));
    e.velocity_ned_mps = velocity;
    e.velocity_sigma_mps = Vector3::from_fn(|k, _| sigma(velocity_cov[(k, k)]));

    let ground_speed = velocity.x.hypot(velocity.y);
    e.course_rad = wrap_pi(velocity.y.atan2(velocity.x));
    e.course_sigma_rad = if ground_speed > 1e-3 {
        // Gradient of atan2(v_E, v_N) is [−v_E, v_N]/|v|².
        let g = Vector2::new(-velocity.y, velocity.x) / (ground_speed * ground_speed);
        let cov = velocity_cov.fixed_view::<2, 2>(0, 0);
        sigma((g.transpose() * cov * g)[(0, 0)]).min(std::f64::consts::PI)
    } else {
        std::f64::consts::PI
    };

    let airspeed = air.norm();
    let air_cov = nav.p.fixed_view::<3, 3>(ix::AIR, ix::AIR);
    e.airspeed_mps = airspeed;
    e.airspeed_sigma_mps = if airspeed > 1e-6 {
        let n = air / airspeed;
        sigma((n.transpose() * air_cov * n)[(0, 0)])
    } else {
        sigma(air_cov.trace())
    };
    e.sink_rate_mps = velocity.z;
    e.sink_rate_sigma_mps = e.velocity_sigma_mps.z;
    // Through the air mass with the air-relative sink; over the ground with the height
    // lost (they differ by the vertical wind).
    let glide = |distance_rate: f64, sink: f64| {
        if sink > MIN_SINK_FOR_GLIDE_MPS {
            distance_rate / sink
        } else {
            f64::INFINITY
        }
    };
    e.glide_ratio_air = glide(air.x.hypot(air.y), air.z);
    e.glide_ratio_ground = glide(ground_speed, velocity.z);
    e.glide_ratio_air_sigma = glide_sigma(&air, &air_cov.into_owned());
    e.glide_ratio_ground_sigma = glide_sigma(&velocity, &velocity_cov);
    // The vehicle's heading is where the stack flies through the air, not where the
    // swinging drone points: the direction of the horizontal air velocity, turning at ω.
    // Guidance steers on it; the drone's own yaw stays in the angle filters.
    let horizontal_air = air.x.hypot(air.y);
    if horizontal_air > 0.5 {
        e.heading_rad = wrap_pi(air.y.atan2(air.x));
        let g = Vector2::new(-air.y, air.x) / (horizontal_air * horizontal_air);
        let cov = air_cov.fixed_view::<2, 2>(0, 0);
        e.heading_sigma_rad = sigma((g.transpose() * cov * g)[(0, 0)]).min(std::f64::consts::PI);
        e.heading_rate_rad_s = nav.x[ix::TURN];
        e.heading_rate_sigma_rad_s = sigma(nav.p[(ix::TURN, ix::TURN)]);
    }
    e.wind_ned_mps = Vector3::new(nav.x[ix::WIND], nav.x[ix::WIND + 1], 0.0);
    e.wind_sigma_mps = Vector3::new(
        sigma(nav.p[(ix::WIND, ix::WIND)]),
        sigma(nav.p[(ix::WIND + 1, ix::WIND + 1)]),
        0.0,
    );
    e.heading_bias_rad = nav.x[ix::HEADING_BIAS];
    e.heading_bias_sigma_rad = sigma(nav.p[(ix::HEADING_BIAS, ix::HEADING_BIAS)]);
    e.pitot_scale = nav.x[ix::SCALE];
    e.pitot_scale_sigma = sigma(nav.p[(ix::SCALE, ix::SCALE)]);
}

/// 1-σ of the glide ratio `g = |v_h|/v_D` of velocity `v` with covariance `cov`, to first
/// order: `∂g/∂v = [v_N/(|v_h| v_D), v_E/(|v_h| v_D), −|v_h|/v_D²]`. Infinite where the ratio is.
fn glide_sigma(v: &Vector3<f64>, cov: &Matrix3<f64>) -> f64 {
    let horizontal = v.x.hypot(v.y);
    let sink = v.z;
    if sink <= MIN_SINK_FOR_GLIDE_MPS {
        return f64::INFINITY;
    }
    let j = if horizontal > 1e-9 {
        Vector3::new(
            v.x / (horizontal * sink),
            v.y / (horizontal * sink),
            -horizontal / (sink * sink),
        )
    } else {
        Vector3::new(0.0, 0.0, 0.0)
    };
    (j.transpose() * cov * j)[(0, 0)].max(0.0).sqrt()
}
