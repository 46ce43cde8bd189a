//! What the drone sends each control period, built from what it knows (its measurements as
//! they reach its computer, its estimate, its servos, its guidance) and scheduled by its
//! telemetry streams ([`super::telemetry`]).

use nalgebra::Vector3;
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::model::{Body, Kinematics};
use stx_dynamics::rotation::euler_from_t;
use stx_dynamics::state::idx;
use stx_gnc::estimate::Estimate;
use stx_gnc::measurement::Measurement;
use stx_gnc::mission::{FlightMode, FlightStage};
use stx_gnc::predict::{PredictorConfig, predict};
use stx_link::telemetry::{Attitude, GuidanceStatus, PredictedLanding, SystemStatus, Telemetry};
use stx_types::stack::{BODY_ATTITUDE_PERIOD_S, BodyImu};

use super::telemetry::{self, msg};
use super::{Drone, Output};

/// SYS_STATUS sensor bits (MAV_SYS_STATUS_SENSOR): magnetometer (the AHRS's heading),
/// absolute and differential pressure, GPS, motor outputs (the servos), AHRS, battery.
mod sensor_bits {
    pub const MAG: u32 = 4;
    pub const ABSOLUTE_PRESSURE: u32 = 8;
    pub const DIFFERENTIAL_PRESSURE: u32 = 16;
    pub const GPS: u32 = 32;
    pub const SERVOS: u32 = 32_768;
    pub const GEOFENCE: u32 = 1_048_576;
    pub const AHRS: u32 = 2_097_152;
    pub const BATTERY: u32 = 33_554_432;
    pub const ALL: u32 =
        MAG | ABSOLUTE_PRESSURE | DIFFERENTIAL_PRESSURE | GPS | SERVOS | AHRS | BATTERY | GEOFENCE;
}

impl Drone {
    /// Raw sensor telemetry, as each measurement reaches the drone's computer.
    pub(super) fn raw_telemetry(&mut self, arrival_s: f64, m: &Measurement) {
        match m {
            Measurement::Gps(fix) => {
                self.last_gps_arrival_s = Some(arrival_s);
                if self.streams.due(msg::GPS_RAW_INT, arrival_s) {
                    self.send(Telemetry::GpsRaw(telemetry::gps_raw(&self.frame, fix)));
                }
                if self.streams.due(msg::GPS_INPUT, arrival_s) {
                    let solution = telemetry::gps_solution(&self.frame, fix);
                    self.send(Telemetry::GpsSolution(solution));
                }
            }
            Measurement::Attitude(a) => {
                if self.streams.due(msg::ATTITUDE, arrival_s) {
                    let att = telemetry::attitude(a, self.last_attitude.as_ref());
                    self.send(Telemetry::Attitude(att));
                }
                self.last_attitude = Some(*a);
            }
            Measurement::AirData(a) => {
                self.last_air = Some(*a);
                if self.streams.due(msg::SCALED_PRESSURE, arrival_s) {
                    self.send(Telemetry::AirData(telemetry::air_data(a)));
                }
            }
        }
    }

    /// Each other body's attitude as its own IMU would report it (see
    /// [`super::telemetry`]): the 14-DOF model's truth, every [`BODY_ATTITUDE_PERIOD_S`],
    /// under the parafoil until touchdown. Before deployment the stack hangs as one swinging
    /// mass in the simulator, so there is no other body's attitude to report.
    fn body_attitudes(&mut self, t: f64) {
        if t + 1e-6 < self.next_body_attitude_s || self.physics.touchdown().is_some() {
            return;
        }
        let Some((_, x)) = self.physics.parafoil() else {
            return;
        };
        self.next_body_attitude_s = t + BODY_ATTITUDE_PERIOD_S;
        let k = Kinematics::new(self.physics.vehicle(), x, x[idx::MAIN_LINE]);
        for body in BodyImu::ALL {
            let i = match body {
                BodyImu::Canopy => Body::Canopy,
                BodyImu::Capsule => Body::Capsule,
                BodyImu::Transponder => Body::Transponder,
            } as usize;
            let euler = euler_from_t(&k.t_i_body[i]);
            let omega = k.omega_body[i];
            let telemetry = Telemetry::Attitude(Attitude {
                time_boot_ms: telemetry::boot_ms(t),
                roll_rad: euler.x,
                pitch_rad: euler.y,
                yaw_rad: euler.z,
                // A gyro measures the body rates.
                roll_rate_radps: omega.x,
                pitch_rate_radps: omega.y,
                yaw_rate_radps: omega.z,
            });
            self.push(Output::Body { body, telemetry });
        }
    }

    pub(super) fn periodic_telemetry(&mut self, t: f64, stage: FlightStage) {
        self.body_attitudes(t);
        let travel = self.physics.vehicle().main_line_travel_m;
        let est = self.estimate;
        // Messages asked for while the sensor-driven ones had nothing new.
        if self.streams.take_request(msg::ATTITUDE)
            && let Some(a) = self.last_attitude
        {
            self.send(Telemetry::Attitude(telemetry::attitude(&a, None)));
        }
        if self.streams.take_request(msg::SCALED_PRESSURE)
            && let Some(a) = self.last_air
        {
            self.send(Telemetry::AirData(telemetry::air_data(&a)));
        }
        let gps_silent = self.last_gps_arrival_s.is_none_or(|a| t - a > 1.0);
        let whole_second = (t - t.floor()) < 1e-6;
        if gps_silent && (whole_second || self.streams.take_request(msg::GPS_RAW_INT)) {
            self.send(Telemetry::GpsRaw(telemetry::gps_no_fix(t)));
        }
        if let Some(e) = &est {
            if self.streams.due(msg::GLOBAL_POSITION_INT, t) {
                self.send(Telemetry::Position(telemetry::position(&self.frame, e)));
            }
            if self.streams.due(msg::VFR_HUD, t) {
                self.send(Telemetry::Hud(telemetry::hud(&self.frame, e)));
            }
            if self.streams.due(msg::WIND_COV, t) {
                self.send(Telemetry::Wind(telemetry::wind(&self.frame, e)));
            }
            if self.streams.due(msg::NAV_CONTROLLER_OUTPUT, t) {
                let g = self.guidance_status(e);
                self.send(Telemetry::Guidance(g));
            }
            if self.streams.due(msg::POSITION_TARGET_GLOBAL_INT, t)
                && let Some(p) = self.predict(stage, e)
            {
                self.send(Telemetry::PredictedLanding(p));
            }
        }
        if self.streams.due(msg::SERVO_OUTPUT_RAW, t) {
            // Where the servos are (lagging their commands, or stuck), not where they were sent.
            let a = telemetry::actuators(t, &self.physics.servo_positions(), travel);
            self.send(Telemetry::Actuators(a));
        }
        if self.streams.due(msg::SYS_STATUS, t) {
            let s = self.system_status(t);
            self.send(Telemetry::System(s));
        }
        if self.streams.due(msg::BATTERY_STATUS, t) {
            self.send(Telemetry::Battery(self.battery.status()));
        }
    }

    fn system_status(&self, t: f64) -> SystemStatus {
        let mut health = sensor_bits::ALL;
        if self.last_gps_arrival_s.is_none_or(|a| t - a > 1.0) {
            health &= !sensor_bits::GPS;
        }
        let est = self.estimate.as_ref();
        if !est.is_some_and(|e| e.attitude_ok) {
            health &= !(sensor_bits::AHRS | sensor_bits::MAG);
        }
        if !est.is_some_and(|e| e.air_data_ok) {
            health &= !(sensor_bits::ABSOLUTE_PRESSURE | sensor_bits::DIFFERENTIAL_PRESSURE);
        }
        if self.servo_fault.active_at(t) {
            health &= !sensor_bits::SERVOS;
        }
        // The geofence (keep-out zones): present always (the drone keeps out of a fence
        // uploaded to it), enabled while it holds zones, and unhealthy when the payload is
        // headed into one: the onboard landing prediction (or, landed, the stack itself) lies
        // in a zone. Flying over a zone high up is not a breach: zones are places not to land.
        let zones = self.onboard.guidance().keep_out();
        let mut enabled = sensor_bits::ALL;
        if zones.zones.is_empty() {
            enabled &= !sensor_bits::GEOFENCE;
        } else if self
            .touchdown_ne_m()
            .is_some_and(|p| zones.zone_at(p).is_some())
        {
            health &= !sensor_bits::GEOFENCE;
        }
        SystemStatus {
            battery_voltage_v: Some(self.battery.voltage_v()),
            battery_current_a: Some(self.battery.current_a()),
            battery_remaining_pct: Some(self.battery.remaining_pct()),
            load_pct: 0.0,
            comm_drop_rate_pct: 0.0,
            comm_errors: 0,
            sensors_present: sensor_bits::ALL,
            sensors_enabled: enabled,
            // A subsystem the drone does not have is reported healthy, as ArduPilot and PX4
            // do: ground stations read a clear health bit as a fault whatever `present`
            // says (MAVProxy announced "fence breach" for the geofence the drone lacks).
            sensors_health: health | !sensor_bits::ALL,
        }
    }

    /// Where the payload comes down (north, east), m: where it lies once landed, else where
    /// the onboard prediction puts it.
    fn touchdown_ne_m(&self) -> Option<[f64; 2]> {
        match self.landing() {
            Some(l) => Some(l.position_ne_m),
            None => self.predicted_landing_ne_m(),
        }
    }

    /// NAV_CONTROLLER_OUTPUT: what guidance is after, per mode.
    fn guidance_status(&self, e: &Estimate) -> GuidanceStatus {
        let g = self.onboard.guidance();
        let plan = g.plan();
        let to_target = plan.target_ned_m - e.position_ned_m;
        let bearing = to_target
            .y
            .atan2(to_target.x)
            .to_degrees()
            .rem_euclid(360.0);
        let position = [e.position_ned_m.x, e.position_ned_m.y];
        let (desired_heading_deg, xtrack_error_m, alt_error_m) = match g.mode() {
            FlightMode::Heading => (plan.heading_rad.to_degrees(), 0.0, 0.0),
            FlightMode::Course => (plan.course_rad.to_degrees(), 0.0, 0.0),
            FlightMode::Localizer => (
                plan.localizer.course_rad.to_degrees(),
                plan.localizer.cross_track_m(position),
                0.0,
            ),
            FlightMode::SpiralLanding => {
                let s = g.spiral_status();
                (bearing, 0.0, s.final_approach_height_m - s.height_m)
            }
            FlightMode::Uncontrolled | FlightMode::Manual => (e.heading_rad.to_degrees(), 0.0, 0.0),
        };
        GuidanceStatus {
            desired_roll_deg: 0.0,
            desired_heading_deg: desired_heading_deg.rem_euclid(360.0).round(),
            bearing_to_target_deg: bearing.round(),
            distance_to_target_m: if self.onboard.has_target() {
                to_target.x.hypot(to_target.y).round().min(65_535.0)
            } else {
                0.0
            },
            alt_error_m: if alt_error_m.is_finite() {
                alt_error_m
            } else {
                0.0
            },
            xtrack_error_m,
        }
    }

    /// The predicted landing point (see the module documentation).
    fn predict(&mut self, stage: FlightStage, e: &Estimate) -> Option<PredictedLanding> {
        let ne = match stage {
            FlightStage::PreLaunch | FlightStage::Ascent | FlightStage::RoundChute => {
                self.physics
                    .forecast_round_chute_landing(&e.position_ned_m, self.forecast.as_ref())?
                    .0
            }
            FlightStage::ParafoilDeploy | FlightStage::Parafoil => {
                let g = self.onboard.guidance();
                // The glide learned in flight, as guidance plans with it, and the stack's
                // own hang height: the station predicts the same way.
                let p = predict(
                    e,
                    g,
                    &g.learned_performance(),
                    &StandardAtmosphere,
                    self.frame.alt_msl_m,
                    &PredictorConfig {
                        hang_height_m: g.config().spiral.hang_height_m,
                        ..PredictorConfig::default()
                    },
                );
                let manual = g.mode() == FlightMode::Manual;
                if manual || g.mode() == FlightMode::Uncontrolled || stage != FlightStage::Parafoil
                {
                    p.uncontrolled.position_ne_m
                } else {
                    p.planned.position_ne_m
                }
            }
            FlightStage::Landed => return None,
        };
        if !(ne[0].is_finite() && ne[1].is_finite()) {
            return None;
        }
        self.prediction = Some(ne);
        let (lat_deg, lon_deg, alt_msl_m) =
            self.frame.to_geodetic(&Vector3::new(ne[0], ne[1], 0.0));
        Some(PredictedLanding {
            time_boot_ms: telemetry::boot_ms(e.time_s),
            lat_deg,
            lon_deg,
            alt_msl_m,
        })
    }
}
