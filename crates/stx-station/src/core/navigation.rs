//! Navigation on the station: the drone's telemetry feeds the station's own estimator (the
//! same code as onboard) with the GPS, AHRS and pitot measurements, on the drone's clock so
//! radio delays and accelerated rehearsals do not distort it; each tick runs the guidance
//! replica on the new estimate and keeps the track and the plots' history; landing
//! predictions run as detached jobs, off the telemetry path.

use nalgebra::Vector3;
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::wind::{WindField, WindProfile};
use stx_gnc::estimate::Estimate;
use stx_gnc::estimator::{Estimator, EstimatorConfig};
use stx_gnc::guidance::{Guidance, Plan};
use stx_gnc::measurement::{AirDataSample, AttitudeSample, GpsFix, Measurement};
use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
use stx_gnc::predict::{LandingPrediction, PredictorConfig, predict_in_wind};
use stx_link::telemetry::Telemetry;

use super::StationCore;
use crate::messages::{Level, StateMsg, TrackPoint};

/// States kept for the plots of a newly connected page: 5 minutes at 1 Hz.
const MAX_HISTORY: usize = 300;
/// Seconds between track points.
const TRACK_PERIOD_S: f64 = 1.0;
/// Most track points kept: a long day (hours on the pad, then the flight) must not grow the
/// station, nor the `history` every new page is sent. Past it, the older half is thinned.
pub(crate) const MAX_TRACK_POINTS: usize = 4096;

/// Drops every other point of the older half of `track`, keeping its first point: the recent
/// half stays at full resolution, and the further back, the coarser (each thinning halves
/// what is older again), so the shape of the whole flight stays on the map.
pub(crate) fn thin_track(track: &mut Vec<TrackPoint>) {
    let half = track.len() / 2;
    let mut i = 0;
    track.retain(|_| {
        let keep = i >= half || i % 2 == 0;
        i += 1;
        keep
    });
}

/// Seconds of the drone's clock between two landing predictions.
pub const PREDICTION_EVERY_S: f64 = 1.0;

/// A GPS_INPUT this close to the drone's clock, s, means the drone sends its receiver's
/// solution, and GPS_RAW_INT is not fed to the estimator as well.
const SOLUTION_FRESH_S: f64 = 2.0;

/// A GPS measurement from the receiver's solution (GPS_INPUT), as the onboard estimator takes
/// it: at the time the receiver measured it when its stamp is on the drone's clock (`drone_s`,
/// within 10 s before it), else at `drone_s`; `None` without a 3-D fix (at a position:
/// `stx_link::telemetry::has_position_fix`) or a velocity.
fn solution_measurement(
    frame: &stx_gnc::geo::LocalFrame,
    drone_s: f64,
    g: &stx_link::telemetry::GpsSolution,
) -> Option<Measurement> {
    if !g.has_3d_fix() {
        return None;
    }
    let [vn, ve, vd] = g.velocity_ned_mps?;
    Some(Measurement::Gps(GpsFix {
        time_s: receiver_time_s(g.time_usec, drone_s),
        position_ned_m: frame.to_ned(g.lat_deg, g.lon_deg, g.alt_msl_m),
        velocity_ned_mps: Vector3::new(vn, ve, vd),
        horizontal_accuracy_m: g.horizontal_accuracy_m.unwrap_or(2.5),
        vertical_accuracy_m: g.vertical_accuracy_m.unwrap_or(5.0),
        speed_accuracy_mps: g.speed_accuracy_mps.unwrap_or(0.3),
    }))
}

/// When a GPS receiver measured a fix stamped `time_usec`, on the drone's clock whose newest
/// time is `drone_s`: the stamp itself when it is on that clock (µs since boot, up to 10 s
/// old), else `drone_s` (a stamp in Unix time, which MAVLink allows).
fn receiver_time_s(time_usec: u64, drone_s: f64) -> f64 {
    let stamp_s = time_usec as f64 / 1e6;
    if (drone_s - 10.0..=drone_s + 0.5).contains(&stamp_s) {
        stamp_s
    } else {
        drone_s
    }
}

/// Seconds the drone's clock may step back before the station takes it for a reboot.
const REBOOT_STEP_BACK_S: f64 = 5.0;

/// The station's estimator for a local frame whose origin is `ground_altitude_msl_m` above sea
/// level: the barometer's altitude is referred to it, as the drone's is to its site. (With the
/// default 0 m, at Évora's 245 m, the station's air was thinner than the drone's and its
/// airspeed and wind parted from the drone's by 0.3 m/s after every restart.)
pub(crate) fn new_estimator(ground_altitude_msl_m: f64) -> Estimator {
    let config = EstimatorConfig {
        ground_altitude_msl_m,
        ..EstimatorConfig::default()
    };
    match Estimator::new(config) {
        Ok(e) => e,
        // The default configuration is validated by the estimator's own tests, and the
        // station's origin by its configuration's.
        Err(e) => panic!("the station's estimator configuration is invalid: {e}"),
    }
}

/// What a telemetry message's time stamp says about the drone's control instants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Stamp {
    /// A measurement, stamped when it was taken: the drone updated its guidance at every
    /// instant before it without it.
    Measured,
    /// Periodic telemetry, sent after the update of the instant it is stamped with.
    AfterControl,
}

/// Everything a landing prediction needs, detached from the station so it can run on another
/// thread while telemetry keeps flowing.
pub struct PredictionJob {
    estimate: Estimate,
    guidance: Guidance,
    performance: stx_gnc::performance::GlidePerformance,
    ground_altitude_msl_m: f64,
    config: PredictorConfig,
    /// When the sensor data behind the estimate arrived (mission time, s).
    data_s: Option<f64>,
    /// The ascent's measured winds with the forecast outside them (altitudes above the
    /// frame's origin): the wind below the drone; `None`: the estimate's wind everywhere.
    wind_profile: Option<WindProfile>,
}

/// A finished [`PredictionJob`].
pub struct Predicted {
    prediction: LandingPrediction,
    data_s: Option<f64>,
}

impl PredictionJob {
    /// The wind profile below the drone this job flies in, if any.
    pub fn wind_profile(&self) -> Option<&WindProfile> {
        self.wind_profile.as_ref()
    }

    /// Flies the plan and the uncontrolled glide from the estimate (milliseconds), in the
    /// wind profile below the drone when there is one.
    pub fn run(&self) -> Predicted {
        Predicted {
            prediction: predict_in_wind(
                &self.estimate,
                &self.guidance,
                &self.performance,
                &StandardAtmosphere,
                self.ground_altitude_msl_m,
                &self.config,
                self.wind_profile.as_ref().map(|p| p as &dyn WindField),
            ),
            data_s: self.data_s,
        }
    }
}

impl StationCore {
    /// Advances the drone's clock with a message's time stamp; a clock that steps far back
    /// means the drone restarted, and navigation starts over.
    fn observe_drone_clock(&mut self, now_s: f64, time_boot_ms: u32) -> f64 {
        let t = f64::from(time_boot_ms) / 1000.0;
        match self.drone_time_s {
            Some(last) if last - t > REBOOT_STEP_BACK_S => {
                self.estimator = new_estimator(self.frame.alt_msl_m);
                self.estimate = None;
                self.log(
                    now_s,
                    Level::Warning,
                    "vehicle",
                    format!("the drone's clock went back from {last:.1} s to {t:.1} s: it restarted; navigation starts over"),
                );
                self.drone_time_s = Some(t);
                self.mission_clock.restart();
                self.mission_clock.observe(now_s, t);
                self.guided_at_s = None;
                self.ascent_on_drone_restart(now_s, t);
                self.want_plan_download(now_s);
            }
            Some(last) => {
                self.drone_time_s = Some(last.max(t));
                self.mission_clock.observe(now_s, t);
            }
            None => {
                self.drone_time_s = Some(t);
                self.mission_clock.observe(now_s, t);
            }
        }
        t
    }

    pub(crate) fn on_telemetry(&mut self, now_s: f64, telemetry: Telemetry) {
        self.latest.any_s = Some(now_s);
        match telemetry {
            Telemetry::Status(s) => {
                let previous = self.latest.status.map(|(p, _)| p);
                self.latest.status = Some((s, now_s));
                if s.phase == GuidancePhase::FinalApproach
                    && previous.map(|p| p.phase) != Some(GuidancePhase::FinalApproach)
                {
                    self.latest.final_approaches += 1;
                }
                self.replica_on_stage(now_s, previous.map(|p| p.stage), s);
                let drone_s = self.drone_time_s.unwrap_or(0.0);
                self.landing_on_stage(previous.map(|p| p.stage), s.stage, drone_s);
                if previous.map(|p| p.mode) != Some(s.mode) {
                    let at = self.drone_time_s.unwrap_or(0.0);
                    self.guidance.set_mode(s.mode, at);
                }
                if let Some(p) = previous
                    && p.stage != s.stage
                {
                    self.log(
                        now_s,
                        Level::Info,
                        "vehicle",
                        format!("stage: {:?} → {:?}", p.stage, s.stage),
                    );
                    self.readiness_on_stage(now_s, p.stage, s.stage);
                }
            }
            Telemetry::GpsRaw(g) => {
                self.latest.gps = Some((g, now_s));
                self.latest.sensors_s = Some(now_s);
                // GPS_RAW_INT's time may be the receiver's (Unix) clock: it is stamped with
                // the drone's clock of the burst it came in.
                if let Some(t) = self.drone_time_s {
                    if g.has_3d_fix() {
                        let measured_s = receiver_time_s(g.time_usec, t);
                        self.landing_fix(now_s, measured_s, g.lat_deg, g.lon_deg, g.alt_msl_m);
                    }
                    if !self.has_gps_solution(t)
                        && let Some(m) = self.gps_measurement(t, &g)
                    {
                        self.estimator.handle(t, &m);
                    }
                    if let Some(fix) = self.ascent_fix(now_s, &g) {
                        self.ascent.push(now_s, t, fix);
                    }
                }
            }
            Telemetry::GpsSolution(g) => {
                self.latest.sensors_s = Some(now_s);
                if let Some(t) = self.drone_time_s
                    && let Some(m) = solution_measurement(&self.frame, t, &g)
                {
                    self.latest.gps_solution_s = Some(t);
                    self.estimator.handle(t, &m);
                }
            }
            Telemetry::Position(p) => {
                self.replica_catch_up(now_s, p.time_boot_ms, Stamp::AfterControl);
                self.observe_drone_clock(now_s, p.time_boot_ms);
                self.latest.position = Some((p, now_s));
            }
            Telemetry::Attitude(a) => {
                self.replica_catch_up(now_s, a.time_boot_ms, Stamp::Measured);
                let t = self.observe_drone_clock(now_s, a.time_boot_ms);
                self.latest.attitude = Some((a, now_s));
                self.latest.sensors_s = Some(now_s);
                let m = Measurement::Attitude(AttitudeSample {
                    time_s: t,
                    roll_rad: a.roll_rad,
                    pitch_rad: a.pitch_rad,
                    yaw_rad: a.yaw_rad,
                });
                self.estimator.handle(self.drone_time_s.unwrap_or(t), &m);
            }
            Telemetry::AirData(a) => {
                self.replica_catch_up(now_s, a.time_boot_ms, Stamp::Measured);
                let t = self.observe_drone_clock(now_s, a.time_boot_ms);
                self.latest.air = Some((a, now_s));
                self.latest.sensors_s = Some(now_s);
                let m = Measurement::AirData(AirDataSample {
                    time_s: t,
                    differential_pressure_pa: a.diff_pressure_pa,
                    static_pressure_pa: a.abs_pressure_pa,
                    temperature_k: a.temperature_c + 273.15,
                });
                self.estimator.handle(self.drone_time_s.unwrap_or(t), &m);
            }
            Telemetry::Actuators(a) => self.latest.actuators = Some((a, now_s)),
            Telemetry::System(s) => self.latest.system = Some((s, now_s)),
            Telemetry::Battery(b) => self.latest.battery = Some((b, now_s)),
            Telemetry::Wind(w) => self.latest.wind = Some((w, now_s)),
            Telemetry::Guidance(g) => {
                self.latest.guidance = Some((g, now_s));
                self.on_guidance_status(now_s, g);
            }
            Telemetry::PredictedLanding(p) => {
                self.replica_catch_up(now_s, p.time_boot_ms, Stamp::AfterControl);
                self.observe_drone_clock(now_s, p.time_boot_ms);
                self.latest.predicted_landing = Some((p, now_s));
            }
            // VFR_HUD repeats GLOBAL_POSITION_INT and the air data; STATUSTEXT arrives as
            // `GroundEvent::StatusText`.
            Telemetry::Hud(_) | Telemetry::StatusText(_) => {}
        }
    }

    /// Whether the drone sends its receiver's whole solution (GPS_INPUT), which its estimator
    /// then takes instead of GPS_RAW_INT: one within [`SOLUTION_FRESH_S`] of the drone's clock
    /// `drone_s`.
    fn has_gps_solution(&self, drone_s: f64) -> bool {
        self.latest
            .gps_solution_s
            .is_some_and(|t| (drone_s - t).abs() <= SOLUTION_FRESH_S)
    }

    /// A GPS measurement from GPS_RAW_INT, for a drone that sends no GPS_INPUT. GPS_RAW_INT
    /// carries no vertical velocity: the drone's own estimate (GLOBAL_POSITION_INT) stands in
    /// for it when it is of the same second of the drone's clock.
    fn gps_measurement(
        &self,
        drone_s: f64,
        g: &stx_link::telemetry::GpsRaw,
    ) -> Option<Measurement> {
        if !g.has_3d_fix() {
            return None;
        }
        let position = self.frame.to_ned(g.lat_deg, g.lon_deg, g.alt_msl_m);
        let speed = g.ground_speed_mps?;
        let course = g.course_deg.unwrap_or(0.0).to_radians();
        let down = self
            .latest
            .position
            .filter(|(p, _)| (drone_s - f64::from(p.time_boot_ms) / 1000.0).abs() < 1.0)
            .map_or(0.0, |(p, _)| p.v_down_mps);
        Some(Measurement::Gps(GpsFix {
            time_s: drone_s,
            position_ned_m: position,
            velocity_ned_mps: Vector3::new(speed * course.cos(), speed * course.sin(), down),
            horizontal_accuracy_m: g.h_acc_m.unwrap_or(2.5),
            vertical_accuracy_m: g.v_acc_m.unwrap_or(5.0),
            speed_accuracy_mps: 0.3,
        }))
    }

    /// Runs navigation, the guidance replica and the core's timers
    /// ([`StationCore::handle_timeout`]) and returns the `state` message for `now_s`.
    /// The landing prediction is not run here (it flies the plan in fast time, too slow for the
    /// telemetry path): see [`StationCore::prediction_job`].
    pub fn tick(&mut self, now_s: f64) -> StateMsg {
        let est = self.drone_time_s.map(|t| self.estimator.estimate(t));
        let usable = est.filter(|e| e.position_sigma_m.iter().all(|s| s.is_finite()));
        if let Some(est) = usable {
            if !self.replica_flies() {
                // The drone holds its servos neutral before its parafoil flies.
                self.replica_command = stx_dynamics::state::Controls::default();
            }
            // The replica itself is stepped as telemetry arrives, at the drone's control
            // instants ([`StationCore::replica_catch_up`]); mode and plan changes log here.
            self.log_guidance_events(now_s);
            // One point per second of flight, also when a rehearsal runs faster than real time.
            if est.time_s >= self.next_track_s {
                self.next_track_s = est.time_s + TRACK_PERIOD_S;
                let (lat, lon, alt) = self.frame.to_geodetic(&est.position_ned_m);
                self.track.push(TrackPoint {
                    time_s: now_s,
                    mission_time_s: est.time_s,
                    lat_deg: lat,
                    lon_deg: lon,
                    alt_msl_m: alt,
                });
                if self.track.len() > MAX_TRACK_POINTS {
                    thin_track(&mut self.track);
                }
            }
            self.estimate = Some(est);
        } else {
            self.estimate = None;
        }
        self.refit_ascent_winds(now_s);
        self.update_flight_path(now_s);
        self.handle_timeout(now_s);
        self.watch_keep_out(now_s);
        let state = self.state_msg_now(now_s);
        if now_s >= self.next_history_s {
            self.next_history_s = now_s + 1.0;
            if self.history.len() >= MAX_HISTORY {
                self.history.pop_front();
            }
            self.history.push_back(state.clone());
        }
        state
    }

    /// A landing prediction from the current estimate and plan, to be run away from the
    /// telemetry path, when one is due: under the parafoil (or while the drone has not said
    /// its stage), once the drone's clock has moved [`PREDICTION_EVERY_S`] past the estimate the
    /// last one started from. Predictions keep to the drone's clock, so a rehearsal flown at
    /// any speed is predicted as often per second of flight.
    pub fn prediction_job(&mut self) -> Option<PredictionJob> {
        let estimate = self.estimate?;
        if !matches!(
            self.drone_stage(),
            None | Some(FlightStage::ParafoilDeploy | FlightStage::Parafoil)
        ) {
            return None;
        }
        if self
            .predicted_from_s
            .is_some_and(|t| estimate.time_s - t < PREDICTION_EVERY_S && estimate.time_s >= t)
        {
            return None;
        }
        self.predicted_from_s = Some(estimate.time_s);
        Some(PredictionJob {
            data_s: self.latest.sensors_s,
            estimate,
            guidance: self.guidance.clone(),
            // The glide as learned in flight, as the replica plans with it: flown with the
            // configured polar, a stack 20 % off it was predicted 10–18 m long at 100 m.
            performance: self.guidance.learned_performance(),
            ground_altitude_msl_m: self.frame.alt_msl_m,
            wind_profile: self.wind_profile(),
            config: PredictorConfig {
                hang_height_m: self.config.guidance.spiral.hang_height_m,
                ..PredictorConfig::default()
            },
        })
    }

    /// Takes the result of a [`PredictionJob`].
    pub fn set_prediction(&mut self, predicted: Predicted) {
        if !matches!(
            self.drone_stage(),
            None | Some(FlightStage::ParafoilDeploy | FlightStage::Parafoil)
        ) {
            // Started under the parafoil, finished on the ground.
            return;
        }
        self.prediction = Some(predicted.prediction);
        self.prediction_data_s = predicted.data_s;
    }

    /// The plan the guidance replica flies.
    pub fn replica_plan(&self) -> &Plan {
        self.guidance.plan()
    }

    /// The mode the drone reports (uncontrolled before the first heartbeat).
    pub fn vehicle_mode(&self) -> FlightMode {
        self.latest
            .status
            .map_or(FlightMode::Uncontrolled, |(s, _)| s.mode)
    }
}

#[cfg(test)]
mod track_tests {
    use super::*;

    #[test]
    fn a_long_day_keeps_a_bounded_track_with_its_ends_and_recent_points() {
        let mut track = Vec::new();
        // Twelve hours at 1 Hz.
        for t in 0..43_200 {
            track.push(TrackPoint {
                time_s: f64::from(t),
                mission_time_s: f64::from(t),
                lat_deg: 50.0,
                lon_deg: 14.0,
                alt_msl_m: 300.0,
            });
            if track.len() > MAX_TRACK_POINTS {
                thin_track(&mut track);
            }
        }
        assert!(track.len() <= MAX_TRACK_POINTS, "{}", track.len());
        assert!(track.len() > MAX_TRACK_POINTS / 2, "{}", track.len());
        assert_eq!(track[0].time_s, 0.0);
        assert_eq!(track.last().map(|p| p.time_s), Some(43_199.0));
        assert!(track.windows(2).all(|w| w[0].time_s < w[1].time_s));
        // The last 1,000 s are whole.
        let recent = track.iter().filter(|p| p.time_s >= 42_200.0).count();
        assert_eq!(recent, 1000);
    }
}
