//! Synthetic flights whose every quantity is known exactly, for the estimator's tests:
//! constant-rate pieces in a constant wind, the measurements a drone would send along them, and
//! an estimator fed with them on a 20 Hz clock.

use nalgebra::Vector3;
use stx_gnc::estimate::Estimate;
use stx_gnc::estimator::{Estimator, EstimatorConfig};
use stx_gnc::measurement::{AirDataSample, AttitudeSample, GpsFix, Measurement};
use stx_types::atmosphere::{Atmosphere, StandardAtmosphere};
use stx_types::rotation::wrap_pi;

/// A flight whose air velocity turns at a constant rate in a constant wind (from `start_s` on;
/// [`pattern`] strings such pieces together).
#[derive(Clone, Copy, Debug)]
pub struct Flight {
    /// Wind, NED, m/s (horizontal).
    pub wind_ned_mps: Vector3<f64>,
    /// Horizontal speed through the air, m/s.
    pub airspeed_h_mps: f64,
    /// Sink rate through the air, m/s.
    pub sink_mps: f64,
    /// Instant the piece starts, s: the track and position below are those of this instant.
    pub start_s: f64,
    /// Direction of the horizontal air velocity at `start_s`, rad.
    pub track0_rad: f64,
    /// Its turn rate, rad/s.
    pub turn_rate_rad_s: f64,
    /// Heading minus air track, rad: the drone's sideslip offset (or a heading bias).
    pub heading_offset_rad: f64,
    /// The drone's sideslip in a turn per unit turn rate, s: its yaw is
    /// `track + heading_offset + this × turn rate` (a drone under a canopy yaws into a turn).
    pub sideslip_per_turn_rate_s: f64,
    /// The drone's swing under the canopy: its yaw swings by this amplitude, rad...
    pub swing_rad: f64,
    /// ...with this period, s.
    pub swing_period_s: f64,
    /// The AHRS's heading bias: it reports the drone's yaw plus this, rad (the pitot keeps
    /// reading along the true x axis).
    pub ahrs_heading_bias_rad: f64,
    pub pitch_rad: f64,
    pub roll_rad: f64,
    /// Pitot scale: the pitot reads `scale × u_x`.
    pub pitot_scale: f64,
    pub start_ned_m: Vector3<f64>,
}

impl Flight {
    pub fn straight(wind_from_deg: f64, wind_speed_mps: f64) -> Self {
        let (s, c) = wind_from_deg.to_radians().sin_cos();
        Self {
            wind_ned_mps: Vector3::new(-wind_speed_mps * c, -wind_speed_mps * s, 0.0),
            airspeed_h_mps: 6.5,
            sink_mps: 3.0,
            start_s: 0.0,
            track0_rad: 0.3,
            turn_rate_rad_s: 0.0,
            heading_offset_rad: 0.0,
            sideslip_per_turn_rate_s: 0.0,
            swing_rad: 0.0,
            swing_period_s: 1.0,
            ahrs_heading_bias_rad: 0.0,
            pitch_rad: -0.12,
            roll_rad: 0.02,
            pitot_scale: 1.0,
            start_ned_m: Vector3::new(0.0, 0.0, -1500.0),
        }
    }

    pub fn turning(wind_from_deg: f64, wind_speed_mps: f64, rate_rad_s: f64) -> Self {
        Self {
            turn_rate_rad_s: rate_rad_s,
            roll_rad: 0.3 * rate_rad_s.signum(),
            ..Self::straight(wind_from_deg, wind_speed_mps)
        }
    }

    pub fn track_rad(&self, t: f64) -> f64 {
        self.track0_rad + self.turn_rate_rad_s * (t - self.start_s)
    }

    pub fn air_ned(&self, t: f64) -> Vector3<f64> {
        let (s, c) = self.track_rad(t).sin_cos();
        Vector3::new(
            self.airspeed_h_mps * c,
            self.airspeed_h_mps * s,
            self.sink_mps,
        )
    }

    pub fn velocity_ned(&self, t: f64) -> Vector3<f64> {
        self.air_ned(t) + self.wind_ned_mps
    }

    pub fn position_ned(&self, t: f64) -> Vector3<f64> {
        let v = self.airspeed_h_mps;
        let r = self.turn_rate_rad_s;
        let (a0, a1) = (self.track0_rad, self.track_rad(t));
        let t = t - self.start_s;
        let (n, e) = if r.abs() < 1e-12 {
            let (s, c) = a0.sin_cos();
            (v * c * t, v * s * t)
        } else {
            (v * (a1.sin() - a0.sin()) / r, v * (a0.cos() - a1.cos()) / r)
        };
        self.start_ned_m + Vector3::new(n, e, self.sink_mps * t) + self.wind_ned_mps * t
    }

    /// The drone's true yaw: where its x axis, and so its pitot, points.
    pub fn yaw_rad(&self, t: f64) -> f64 {
        let swing = self.swing_rad * (std::f64::consts::TAU * t / self.swing_period_s).sin();
        let sideslip =
            self.heading_offset_rad + self.sideslip_per_turn_rate_s * self.turn_rate_rad_s + swing;
        wrap_pi(self.track_rad(t) + sideslip)
    }

    /// The three measurements of instant `t`.
    pub fn measurements(&self, t: f64) -> [Measurement; 3] {
        let p = self.position_ned(t);
        let air = StandardAtmosphere.air_at(-p.z);
        let (st, ct) = self.pitch_rad.sin_cos();
        let (sp, cp) = self.yaw_rad(t).sin_cos();
        let e_x = Vector3::new(ct * cp, ct * sp, -st);
        let u_x = self.pitot_scale * e_x.dot(&self.air_ned(t));
        [
            Measurement::Attitude(AttitudeSample {
                time_s: t,
                roll_rad: self.roll_rad,
                pitch_rad: self.pitch_rad,
                yaw_rad: wrap_pi(self.yaw_rad(t) + self.ahrs_heading_bias_rad),
            }),
            Measurement::Gps(GpsFix {
                time_s: t,
                position_ned_m: p,
                velocity_ned_mps: self.velocity_ned(t),
                horizontal_accuracy_m: 1.5,
                vertical_accuracy_m: 3.0,
                speed_accuracy_mps: 0.15,
            }),
            Measurement::AirData(AirDataSample {
                time_s: t,
                differential_pressure_pa: 0.5 * air.density_kg_per_m3 * u_x * u_x.abs(),
                static_pressure_pa: air.pressure_pa,
                temperature_k: air.temperature_k,
            }),
        ]
    }
}

/// Latencies of AHRS, GPS and pitot, s.
#[derive(Clone, Copy)]
pub struct Latency(pub [f64; 3]);

pub const ON_TIME: Latency = Latency([0.0, 0.0, 0.0]);
pub const USUAL: Latency = Latency([0.02, 0.25, 0.02]);

/// Sensor instants: every 0.25 s.
pub const PERIOD_S: f64 = 0.25;

/// Everything sampled in `[from_s, to_s)` that `keep` lets through, as (arrival, measurement)
/// in arrival order (ties in sensor order, as a radio would deliver them).
pub fn deliveries(
    flight: &Flight,
    from_s: f64,
    to_s: f64,
    latency: Latency,
    keep: impl Fn(&Measurement) -> bool,
) -> Vec<(f64, Measurement)> {
    let first = (from_s / PERIOD_S).ceil() as i64;
    let last = (to_s / PERIOD_S).ceil() as i64;
    let mut out: Vec<(f64, Measurement)> = (first..last)
        .flat_map(|k| {
            let t = k as f64 * PERIOD_S;
            flight
                .measurements(t)
                .into_iter()
                .zip(latency.0)
                .map(move |(m, l)| (t + l, m))
        })
        .filter(|(_, m)| keep(m))
        .collect();
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

pub fn estimator() -> Estimator {
    Estimator::new(EstimatorConfig::default()).expect("default config is valid")
}

/// Feeds `deliveries` as they arrive and returns the estimate at every 0.05-s tick, taken
/// after the arrivals due by then (`(instant, estimate)`).
pub fn feed(est: &mut Estimator, deliveries: &[(f64, Measurement)]) -> Vec<(f64, Estimate)> {
    let mut out = Vec::new();
    let mut next = 0;
    let end = deliveries.last().map_or(0.0, |d| d.0);
    // A 20 Hz control tick from the first tick at or before the first arrival.
    let first_tick = (deliveries.first().map_or(0.0, |d| d.0) / 0.05).floor() as i64;
    for tick in first_tick.. {
        let t = tick as f64 * 0.05;
        if t > end + 0.05 {
            break;
        }
        while next < deliveries.len() && deliveries[next].0 <= t + 1e-9 {
            est.handle(deliveries[next].0, &deliveries[next].1);
            next += 1;
        }
        out.push((t, est.estimate(t)));
    }
    out
}

pub fn horizontal(v: Vector3<f64>) -> f64 {
    v.x.hypot(v.y)
}

/// `first` followed by pieces of `(duration_s, turn_rate_rad_s)`, each going on from where the
/// one before ended: `(from_s, to_s, piece)`, the first starting at `first.start_s` and lasting
/// the first duration. A turning piece banks 0.3 rad towards its turn.
pub fn pattern(first: &Flight, pieces: &[(f64, f64)]) -> Vec<(f64, f64, Flight)> {
    let mut out: Vec<(f64, f64, Flight)> = Vec::new();
    let mut previous = *first;
    let mut from_s = first.start_s;
    for &(duration_s, rate) in pieces {
        let piece = Flight {
            start_s: from_s,
            track0_rad: previous.track_rad(from_s),
            start_ned_m: previous.position_ned(from_s),
            turn_rate_rad_s: rate,
            roll_rad: if rate == 0.0 {
                0.0
            } else {
                0.3 * rate.signum()
            },
            ..previous
        };
        out.push((from_s, from_s + duration_s, piece));
        previous = piece;
        from_s += duration_s;
    }
    out
}

/// Everything the pieces of a [`pattern`] send, as [`deliveries`] gives it.
pub fn pattern_deliveries(
    pieces: &[(f64, f64, Flight)],
    latency: Latency,
) -> Vec<(f64, Measurement)> {
    let mut d: Vec<(f64, Measurement)> = pieces
        .iter()
        .flat_map(|(from_s, to_s, piece)| deliveries(piece, *from_s, *to_s, latency, |_| true))
        .collect();
    d.sort_by(|a, b| a.0.total_cmp(&b.0));
    d
}

/// The piece of a [`pattern`] flying at `t`.
pub fn piece_at(pieces: &[(f64, f64, Flight)], t: f64) -> &Flight {
    pieces
        .iter()
        .find(|(from_s, to_s, _)| (*from_s..*to_s).contains(&t))
        .or(pieces.last())
        .map(|(_, _, piece)| piece)
        .expect("a pattern has pieces")
}
