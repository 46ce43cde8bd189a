//! The filter proper: three angle filters and the navigation EKF, advanced one measurement at a
//! time in timestamp order (the buffering around it lives in the parent module). `Copy`, so
//! the parent can keep a committed copy and replay late measurements onto a clone.
//!
//! This file keeps the parts together and hands each measurement to its update: the EKF's
//! state, prediction and Kalman update are in `ekf.rs`; GPS fixes in `gps.rs`; the pitot in
//! `pitot.rs`; static pressure (barometric height, air density) in `baro.rs`; the
//! straight-flight sideslip in `sideslip.rs`; the estimate read out of the state in
//! `readout.rs`. The equations are in the parent module's documentation; the comments say how
//! the code follows them.

use nalgebra::Vector3;

use super::angle::AngleFilter;
use super::baro::{Barometer, air_density};
use super::config::Tuning;
use super::ekf::{Nav, Outcome, ix};
use super::gps::GpsGate;
use super::pitot::{Pitot, attitude_at};
use super::readout::read_nav;
use super::sideslip::StraightFlight;
use crate::estimate::Estimate;
use crate::measurement::{AirDataSample, AttitudeSample, GpsFix, Measurement};

/// A GPS fix at most this old has set the ground velocity a pitot restart keeps, s: four
/// fix periods at 4 Hz. Older, the ground velocity is dead-reckoned (`pitot.rs`).
const GROUND_KNOWN_S: f64 = 1.0;

/// The filter at one instant: three angle filters and, once started by a GPS fix, the
/// navigation EKF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct NavFilter {
    /// Instant the state describes, s.
    pub time_s: f64,
    /// Whether any measurement has set the time.
    started: bool,
    /// Roll, pitch, yaw of the drone.
    pub attitude: [AngleFilter; 3],
    /// Navigation state, once a GPS fix (with an attitude) has started it.
    pub nav: Option<Nav>,
    /// Instants of the last GPS fix used, AHRS sample and pitot sample received, s.
    pub last_gps_s: f64,
    pub last_attitude_s: f64,
    pub last_air_data_s: f64,
    /// The GPS fixes' rejections in a row.
    gps: GpsGate,
    /// The pitot's contradictions of the state in a row.
    pitot: Pitot,
    /// Whether a static pressure has set the barometric bias.
    baro: Barometer,
    /// The latest AHRS sample, to interpolate the attitude of a pitot sample that falls
    /// between two.
    last_attitude: Option<AttitudeSample>,
    /// Since when the flight has been straight.
    straight: StraightFlight,
    /// Air density of the latest air-data sample and its 1-σ, kg/m³.
    density: Option<(f64, f64)>,
}

impl NavFilter {
    pub const fn new() -> Self {
        Self {
            time_s: 0.0,
            started: false,
            attitude: [AngleFilter::new(); 3],
            nav: None,
            last_gps_s: f64::NEG_INFINITY,
            last_attitude_s: f64::NEG_INFINITY,
            last_air_data_s: f64::NEG_INFINITY,
            gps: GpsGate::new(),
            pitot: Pitot::new(),
            baro: Barometer::new(),
            last_attitude: None,
            straight: StraightFlight::new(),
            density: None,
        }
    }

    /// What the navigation state has learnt of the sensors, each as (value, variance): the
    /// pitot's scale and the AHRS's heading bias; `None` before it started.
    pub fn calibration(&self) -> Option<((f64, f64), (f64, f64))> {
        self.nav.as_ref().map(|n| {
            let kept = |i: usize| (n.x[i], n.p[(i, i)]);
            (kept(ix::SCALE), kept(ix::HEADING_BIAS))
        })
    }

    /// Instant of the latest AHRS sample applied, s (−∞ before the first).
    pub fn last_attitude_time_s(&self) -> f64 {
        self.last_attitude.map_or(f64::NEG_INFINITY, |a| a.time_s)
    }

    fn attitude_started(&self) -> bool {
        self.attitude.iter().all(|a| a.started)
    }

    /// Advances everything to `time_s` (never backwards).
    pub fn predict_to(&mut self, time_s: f64, t: &Tuning) {
        if !self.started {
            self.time_s = time_s;
            self.started = true;
            return;
        }
        let dt_s = time_s - self.time_s;
        if dt_s <= 0.0 {
            return;
        }
        if let Some(nav) = &mut self.nav {
            nav.predict(dt_s, t);
        }
        let [roll, pitch, yaw] = &mut self.attitude;
        roll.predict(dt_s, t.q_roll_pitch);
        pitch.predict(dt_s, t.q_roll_pitch);
        yaw.predict(dt_s, t.q_yaw);
        self.time_s = time_s;
    }

    /// Advances to the measurement's instant and feeds it. `next_attitude` is the first AHRS
    /// sample after it, if already received: a pitot sample between two AHRS samples is
    /// projected with the attitude interpolated between them.
    pub fn apply(
        &mut self,
        m: &Measurement,
        next_attitude: Option<&AttitudeSample>,
        t: &Tuning,
    ) -> Outcome {
        self.predict_to(m.time_s(), t);
        let outcome = match m {
            Measurement::Attitude(a) => self.apply_attitude(a, t),
            Measurement::Gps(g) => self.apply_gps(g, t),
            Measurement::AirData(a) => self.apply_air_data(a, next_attitude, t),
        };
        self.heal();
        outcome
    }

    /// Finite but absurd input (positions of 1e300 m, a gap of centuries) can overflow the
    /// arithmetic; a non-finite state would then stay so for ever. Such a part is dropped and
    /// starts again from the next measurement instead.
    fn heal(&mut self) {
        for angle in &mut self.attitude {
            let finite = angle.angle_rad.is_finite()
                && angle.rate_rad_s.is_finite()
                && angle.covariance.iter().all(|v| v.is_finite());
            if !finite {
                *angle = AngleFilter::new();
            }
        }
        let nav_finite = self.nav.as_ref().is_none_or(|nav| {
            nav.x.iter().all(|v| v.is_finite()) && nav.p.iter().all(|v| v.is_finite())
        });
        if !nav_finite || !self.time_s.is_finite() {
            self.nav = None;
        }
        if !self.time_s.is_finite() {
            *self = Self::new();
        }
    }

    fn apply_attitude(&mut self, a: &AttitudeSample, t: &Tuning) -> Outcome {
        self.last_attitude_s = a.time_s;
        self.last_attitude = Some(*a);
        let measured = [a.roll_rad, a.pitch_rad, a.yaw_rad];
        let variances = [t.r_roll_pitch, t.r_roll_pitch, t.r_yaw];
        let mut started = false;
        for k in 0..3 {
            started |= self.attitude[k].update(measured[k], variances[k], t.max_angular_rate_rad_s);
        }
        if started {
            return Outcome::Reset;
        }
        if let Some(nav) = &mut self.nav {
            self.straight.update(nav, &self.attitude[2], a.time_s, t);
        }
        Outcome::Used
    }

    fn apply_gps(&mut self, g: &GpsFix, t: &Tuning) -> Outcome {
        if !self.attitude_started() {
            return Outcome::Unused;
        }
        let step = self.gps.apply(self.nav, g, t);
        self.nav = Some(step.nav);
        if step.restarted {
            self.baro.restart();
        }
        if step.outcome != Outcome::Gated {
            self.last_gps_s = g.time_s;
        }
        step.outcome
    }

    fn apply_air_data(
        &mut self,
        a: &AirDataSample,
        next_attitude: Option<&AttitudeSample>,
        t: &Tuning,
    ) -> Outcome {
        self.last_air_data_s = a.time_s;
        self.density = Some(air_density(a, t));
        if !self.attitude_started() {
            return Outcome::Unused;
        }
        let Some(mut nav) = self.nav else {
            return Outcome::Unused;
        };
        let baro = self.baro.update(&mut nav, a, t);
        let attitude = attitude_at(
            &self.attitude,
            self.last_attitude,
            a.time_s,
            next_attitude,
            t,
        );
        let ground_known = a.time_s - self.last_gps_s <= GROUND_KNOWN_S;
        let pitot = self.pitot.update(&mut nav, a, attitude, ground_known, t);
        self.nav = Some(nav);
        match (baro, pitot) {
            (Outcome::Gated, _) | (_, Outcome::Gated) => Outcome::Gated,
            (Outcome::Used, _) | (_, Outcome::Used) => Outcome::Used,
            (Outcome::Reset, _) => Outcome::Reset,
            _ => Outcome::Unused,
        }
    }

    /// The estimate at `now_s`: this state predicted forward (never backward) and read out.
    /// A non-finite `now_s` reads the state out as it is, at its own instant.
    pub fn estimate(&self, now_s: f64, t: &Tuning, timeouts: &Timeouts) -> Estimate {
        if !now_s.is_finite() {
            return self.read_out(self.time_s, timeouts);
        }
        let mut f = *self;
        if now_s > f.time_s {
            f.predict_to(now_s, t);
        }
        f.read_out(now_s, timeouts)
    }

    fn read_out(&self, now_s: f64, timeouts: &Timeouts) -> Estimate {
        let [roll, pitch, yaw] = &self.attitude;
        let unknown = Vector3::repeat(f64::INFINITY);
        let gps_age_s = now_s - self.last_gps_s;
        let mut e = Estimate {
            time_s: now_s,
            position_ned_m: Vector3::zeros(),
            position_sigma_m: unknown,
            velocity_ned_mps: Vector3::zeros(),
            velocity_sigma_mps: unknown,
            heading_rad: yaw.angle_rad,
            heading_sigma_rad: yaw.angle_sigma_rad(),
            heading_rate_rad_s: yaw.rate_rad_s,
            heading_rate_sigma_rad_s: yaw.rate_sigma_rad_s(),
            drone_yaw_rad: yaw.angle_rad,
            drone_yaw_rate_rad_s: yaw.rate_rad_s,
            course_rad: 0.0,
            course_sigma_rad: f64::INFINITY,
            roll_rad: roll.angle_rad,
            pitch_rad: pitch.angle_rad,
            airspeed_mps: 0.0,
            airspeed_sigma_mps: f64::INFINITY,
            sink_rate_mps: 0.0,
            sink_rate_sigma_mps: f64::INFINITY,
            glide_ratio_air: 0.0,
            glide_ratio_air_sigma: f64::INFINITY,
            glide_ratio_ground: 0.0,
            glide_ratio_ground_sigma: f64::INFINITY,
            air_density_kg_per_m3: self.density.map_or(0.0, |d| d.0),
            air_density_sigma_kg_per_m3: self.density.map_or(f64::INFINITY, |d| d.1),
            wind_ned_mps: Vector3::zeros(),
            wind_sigma_mps: Vector3::new(f64::INFINITY, f64::INFINITY, 0.0),
            heading_bias_rad: 0.0,
            heading_bias_sigma_rad: f64::INFINITY,
            pitot_scale: 1.0,
            pitot_scale_sigma: f64::INFINITY,
            gps_ok: self.nav.is_some() && gps_age_s <= timeouts.gps_s,
            gps_age_s,
            attitude_ok: now_s - self.last_attitude_s <= timeouts.attitude_s,
            air_data_ok: now_s - self.last_air_data_s <= timeouts.air_data_s,
        };
        let Some(nav) = &self.nav else {
            return e;
        };
        read_nav(&mut e, nav);
        e
    }
}

/// The status timeouts, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Timeouts {
    pub gps_s: f64,
    pub attitude_s: f64,
    pub air_data_s: f64,
}
