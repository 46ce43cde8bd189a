//! [`SensorSuite`], the running sensor set: each sensor's schedule, its random errors drawn
//! from its own seeded streams, and the measurement it makes of the truth.

use std::f64::consts::FRAC_PI_2;

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use stx_dynamics::rotation::wrap_pi;
use stx_gnc::measurement::{AirDataSample, AttitudeSample, GpsFix, Measurement};

use super::config::{AhrsConfig, GpsConfig, PitotConfig, SensorConfig, SensorConfigError};
use super::{Delivery, Truth};

/// A standard normal draw.
fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

/// When a sensor samples and whether a sample gets through.
#[derive(Debug, Clone)]
struct Schedule {
    period_s: f64,
    phase_s: f64,
    latency_s: f64,
    dropouts_s: Vec<[f64; 2]>,
    dropout_probability: f64,
    /// Index `n` of the next due instant `phase + n·period`; counting instants rather than
    /// adding periods keeps long runs free of accumulated rounding.
    next_index: u64,
    /// Instant of the previous sample, s, to advance the noise processes by the real interval.
    last_sample_s: Option<f64>,
    /// Draws for random dropouts, apart from the noise so that they do not shift it.
    dropout_rng: ChaCha8Rng,
}

/// Slack on "due", s: control ticks summed in floating point land a hair early.
const DUE_TOLERANCE_S: f64 = 1e-6;

/// What the schedule decides at one call.
struct Due {
    /// Time since the sensor's previous sample, s (0 for its first).
    elapsed_s: f64,
    /// The sample gets through (false: dropped by a window or at random).
    delivered: bool,
}

impl Schedule {
    fn new(
        rate_hz: f64,
        phase_s: f64,
        latency_s: f64,
        dropouts_s: &[[f64; 2]],
        dropout_probability: f64,
        dropout_rng: ChaCha8Rng,
    ) -> Self {
        Self {
            period_s: 1.0 / rate_hz,
            phase_s,
            latency_s,
            dropouts_s: dropouts_s.to_vec(),
            dropout_probability,
            next_index: 0,
            last_sample_s: None,
            dropout_rng,
        }
    }

    /// Whether the sensor samples at `time_s`; if so, advances to the next due instant.
    fn poll(&mut self, time_s: f64) -> Option<Due> {
        let next_s = self.phase_s + self.next_index as f64 * self.period_s;
        if !time_s.is_finite() || time_s + DUE_TOLERANCE_S < next_s {
            return None;
        }
        // The next instant strictly after this call: skipped instants are not made up.
        let passed = ((time_s + DUE_TOLERANCE_S - self.phase_s) / self.period_s).floor();
        self.next_index = (passed.max(0.0) as u64).saturating_add(1);
        let elapsed_s = self.last_sample_s.map_or(0.0, |last| time_s - last);
        self.last_sample_s = Some(time_s);
        // Always draw, so the dropout stream stays aligned with the samples whatever the
        // windows are.
        let draw: f64 = rand::RngExt::random(&mut self.dropout_rng);
        let in_window = self
            .dropouts_s
            .iter()
            .any(|&[from_s, to_s]| (from_s..=to_s).contains(&time_s));
        Some(Due {
            elapsed_s,
            delivered: !in_window && draw >= self.dropout_probability,
        })
    }
}

/// A first-order Gauss–Markov process, started from its stationary distribution.
#[derive(Debug, Clone, Copy)]
struct GaussMarkov {
    value: f64,
    sigma: f64,
    correlation_s: f64,
}

impl GaussMarkov {
    fn new(sigma: f64, correlation_s: f64, rng: &mut ChaCha8Rng) -> Self {
        Self {
            value: sigma * gauss(rng),
            sigma,
            correlation_s,
        }
    }

    /// Advances by `dt_s` with the exact discrete transition (any step keeps the variance σ²).
    fn step(&mut self, dt_s: f64, rng: &mut ChaCha8Rng) -> f64 {
        let decay = (-dt_s / self.correlation_s).exp();
        self.value = decay * self.value + self.sigma * (1.0 - decay * decay).sqrt() * gauss(rng);
        self.value
    }
}

/// The GPS receiver's running errors.
#[derive(Debug, Clone)]
struct Gps {
    config: GpsConfig,
    schedule: Schedule,
    rng: ChaCha8Rng,
    wander: [GaussMarkov; 3],
    /// This run's constant position (m) and velocity (m/s) biases, NED.
    position_bias_m: [f64; 3],
    velocity_bias_mps: [f64; 3],
}

impl Gps {
    fn sample(&mut self, time_s: f64, truth: &Truth) -> Option<Delivery> {
        let due = self.schedule.poll(time_s)?;
        let c = &self.config;
        let rng = &mut self.rng;
        let mut position = truth.position_ned_m;
        let mut velocity = truth.velocity_ned_mps;
        for axis in 0..3 {
            let (noise_m, vel_noise_mps) = if axis < 2 {
                (c.horizontal_noise_m, c.velocity_noise_mps)
            } else {
                (c.vertical_noise_m, c.vertical_velocity_noise_mps)
            };
            position[axis] += self.position_bias_m[axis]
                + self.wander[axis].step(due.elapsed_s, rng)
                + noise_m * gauss(rng);
            velocity[axis] += self.velocity_bias_mps[axis] + vel_noise_mps * gauss(rng);
        }
        due.delivered.then_some(Delivery {
            arrival_s: time_s + self.schedule.latency_s,
            measurement: Measurement::Gps(GpsFix {
                time_s,
                position_ned_m: position,
                velocity_ned_mps: velocity,
                horizontal_accuracy_m: c.reported_horizontal_accuracy_m,
                vertical_accuracy_m: c.reported_vertical_accuracy_m,
                speed_accuracy_mps: c.reported_speed_accuracy_mps,
            }),
        })
    }
}

/// The AHRS's running errors.
#[derive(Debug, Clone)]
struct Ahrs {
    config: AhrsConfig,
    schedule: Schedule,
    rng: ChaCha8Rng,
    /// Roll, pitch, yaw biases, rad.
    bias_rad: [f64; 3],
}

impl Ahrs {
    fn sample(&mut self, time_s: f64, truth: &Truth) -> Option<Delivery> {
        let due = self.schedule.poll(time_s)?;
        let c = &self.config;
        let rng = &mut self.rng;
        self.bias_rad[2] +=
            c.yaw_bias_random_walk_deg_per_sqrt_s.to_radians() * due.elapsed_s.sqrt() * gauss(rng);
        let noise_rad = [c.roll_noise_deg, c.pitch_noise_deg, c.yaw_noise_deg]
            .map(|sigma_deg| sigma_deg.to_radians() * gauss(rng));
        let angle = |axis: usize| truth.euler_rad[axis] + self.bias_rad[axis] + noise_rad[axis];
        due.delivered.then_some(Delivery {
            arrival_s: time_s + self.schedule.latency_s,
            measurement: Measurement::Attitude(AttitudeSample {
                time_s,
                roll_rad: wrap_pi(angle(0)),
                // An AHRS reports pitch in [−90°, 90°]; noise cannot push it past.
                pitch_rad: angle(1).clamp(-FRAC_PI_2, FRAC_PI_2),
                yaw_rad: wrap_pi(angle(2)),
            }),
        })
    }
}

/// The pitot's running errors.
#[derive(Debug, Clone)]
struct Pitot {
    config: PitotConfig,
    schedule: Schedule,
    rng: ChaCha8Rng,
    differential_offset_pa: f64,
    /// `1 + k` of [`PitotConfig::differential_scale_sigma`].
    differential_scale: f64,
    static_bias_pa: f64,
    temperature_bias_k: f64,
}

impl Pitot {
    fn sample(&mut self, time_s: f64, truth: &Truth) -> Option<Delivery> {
        let due = self.schedule.poll(time_s)?;
        let c = &self.config;
        let rng = &mut self.rng;
        self.differential_offset_pa +=
            c.differential_offset_random_walk_pa_per_sqrt_s * due.elapsed_s.sqrt() * gauss(rng);
        let u_x = truth.air_velocity_body_mps.x;
        let rho = truth.air.density_kg_per_m3;
        let differential_pressure_pa = self.differential_scale * 0.5 * rho * u_x * u_x.abs()
            + self.differential_offset_pa
            + c.differential_noise_pa * gauss(rng);
        let static_pressure_pa =
            truth.air.pressure_pa + self.static_bias_pa + c.static_noise_pa * gauss(rng);
        let temperature_k =
            truth.air.temperature_k + self.temperature_bias_k + c.temperature_noise_k * gauss(rng);
        due.delivered.then_some(Delivery {
            arrival_s: time_s + self.schedule.latency_s,
            measurement: Measurement::AirData(AirDataSample {
                time_s,
                differential_pressure_pa,
                static_pressure_pa,
                temperature_k,
            }),
        })
    }
}

/// Stream numbers of the independent random sequences drawn from one seed.
mod stream {
    pub const GPS_NOISE: u64 = 1;
    pub const AHRS_NOISE: u64 = 2;
    pub const PITOT_NOISE: u64 = 3;
    pub const GPS_DROPOUT: u64 = 11;
    pub const AHRS_DROPOUT: u64 = 12;
    pub const PITOT_DROPOUT: u64 = 13;
    pub const GPS_BIAS: u64 = 21;
    pub const PITOT_SCALE: u64 = 23;
}

/// The generator of stream `stream` of `seed`: independent sequences from one seed.
pub(crate) fn rng_for(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

/// The running sensor set of one simulated flight.
#[derive(Debug, Clone)]
pub struct SensorSuite {
    gps: Gps,
    ahrs: Ahrs,
    pitot: Pitot,
}

impl SensorSuite {
    /// Validates `config` and draws this run's biases from `seed`.
    pub fn new(config: &SensorConfig, seed: u64) -> Result<Self, SensorConfigError> {
        config.validate()?;
        let g = &config.gps;
        let mut gps_rng = rng_for(seed, stream::GPS_NOISE);
        let wander = [
            g.horizontal_wander_m,
            g.horizontal_wander_m,
            g.vertical_wander_m,
        ]
        .map(|sigma| GaussMarkov::new(sigma, g.wander_correlation_s, &mut gps_rng));
        // A stream of their own, so that switching the biases on changes nothing else.
        let mut bias_rng = rng_for(seed, stream::GPS_BIAS);
        let position_bias_m = [
            g.horizontal_bias_sigma_m,
            g.horizontal_bias_sigma_m,
            g.vertical_bias_sigma_m,
        ]
        .map(|sigma| sigma * gauss(&mut bias_rng));
        let velocity_bias_mps =
            [g.velocity_bias_sigma_mps; 3].map(|sigma| sigma * gauss(&mut bias_rng));
        let gps = Gps {
            schedule: Schedule::new(
                g.rate_hz,
                g.phase_s,
                g.latency_s,
                &g.dropouts_s,
                g.dropout_probability,
                rng_for(seed, stream::GPS_DROPOUT),
            ),
            config: g.clone(),
            rng: gps_rng,
            wander,
            position_bias_m,
            velocity_bias_mps,
        };

        let a = &config.ahrs;
        let mut ahrs_rng = rng_for(seed, stream::AHRS_NOISE);
        let bias_rad = [
            a.roll_bias_sigma_deg,
            a.pitch_bias_sigma_deg,
            a.yaw_bias_sigma_deg,
        ]
        .map(|sigma_deg| sigma_deg.to_radians() * gauss(&mut ahrs_rng));
        let ahrs = Ahrs {
            schedule: Schedule::new(
                a.rate_hz,
                a.phase_s,
                a.latency_s,
                &a.dropouts_s,
                a.dropout_probability,
                rng_for(seed, stream::AHRS_DROPOUT),
            ),
            config: a.clone(),
            rng: ahrs_rng,
            bias_rad,
        };

        let p = &config.pitot;
        let mut pitot_rng = rng_for(seed, stream::PITOT_NOISE);
        let differential_offset_pa = p.differential_offset_sigma_pa * gauss(&mut pitot_rng);
        let static_bias_pa = p.static_bias_sigma_pa * gauss(&mut pitot_rng);
        let temperature_bias_k = p.temperature_bias_sigma_k * gauss(&mut pitot_rng);
        // Its own stream, so that a run without a scale error draws the same noise as before.
        let differential_scale = 1.0
            + p.differential_scale_sigma
                * gauss(&mut rng_for(seed, stream::PITOT_SCALE)).clamp(-3.0, 3.0);
        let pitot = Pitot {
            schedule: Schedule::new(
                p.rate_hz,
                p.phase_s,
                p.latency_s,
                &p.dropouts_s,
                p.dropout_probability,
                rng_for(seed, stream::PITOT_DROPOUT),
            ),
            config: p.clone(),
            rng: pitot_rng,
            differential_offset_pa,
            differential_scale,
            static_bias_pa,
            temperature_bias_k,
        };
        Ok(Self { gps, ahrs, pitot })
    }

    /// Samples every sensor that is due at `time_s` (call every control tick, times
    /// non-decreasing) and returns what gets through, in the order AHRS, GPS, pitot.
    pub fn sample(&mut self, time_s: f64, truth: &Truth) -> Vec<Delivery> {
        [
            self.ahrs.sample(time_s, truth),
            self.gps.sample(time_s, truth),
            self.pitot.sample(time_s, truth),
        ]
        .into_iter()
        .flatten()
        .collect()
    }

    /// This run's AHRS biases (roll, pitch, yaw), rad: what a test compares the estimator's
    /// heading error with.
    pub fn ahrs_bias_rad(&self) -> Vector3<f64> {
        Vector3::from(self.ahrs.bias_rad)
    }

    /// This run's pitot airspeed scale: the differential pressure reads `(1 + k)·q`, so the
    /// airspeed derived from it reads `√(1 + k)` times the true one (what the estimator's
    /// pitot scale should find).
    pub fn pitot_airspeed_scale(&self) -> f64 {
        self.pitot.differential_scale.sqrt()
    }

    /// This run's differential-pressure offset, Pa.
    pub fn differential_offset_pa(&self) -> f64 {
        self.pitot.differential_offset_pa
    }
}
