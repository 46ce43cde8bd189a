//! One flight's draw from a [`Dispersions`] set: the vehicle it really is, its sensors, its
//! servos' errors and its wind's shape, all from one seed.

use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Serialize;
use stx_dynamics::state::Controls;
use stx_dynamics::vehicle::{Vehicle, VehicleConfig, VehicleError};

use super::config::Dispersions;
use crate::sensors::{SensorConfig, rng_for};

/// A standard normal draw clipped at ±3 σ: no dispersed coefficient changes sign.
fn clipped_gauss(rng: &mut ChaCha8Rng) -> f64 {
    let g: f64 = StandardNormal.sample(rng);
    g.clamp(-3.0, 3.0)
}

/// `value · (1 + σ·g)`.
fn scaled(rng: &mut ChaCha8Rng, value: &mut f64, sigma: f64) {
    *value *= 1.0 + sigma * clipped_gauss(rng);
}

/// The shape of a flight's wind around its mean speed and direction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
pub struct WindShape {
    /// Speed change from the ground to the release height, fraction of the mean (−max … max).
    pub shear_fraction: f64,
    /// Direction change over the same height, degrees.
    pub veer_deg: f64,
    /// Turbulence intensity relative to the nominal 10 % of the mean.
    pub gust_factor: f64,
    /// Turn of the wind near the ground (complete below `low_level_height_m`), degrees.
    pub low_level_turn_deg: f64,
    /// Height below which the low-level turn is complete, m.
    pub low_level_height_m: f64,
}

impl WindShape {
    /// Draws the shape. The first two draws are the ones the Monte Carlo always made, so a
    /// nominal campaign flies the winds it flew before dispersions existed.
    pub fn draw(d: &Dispersions, rng: &mut ChaCha8Rng) -> Self {
        let w = &d.wind;
        // Written as `2m·u − m`, the very arithmetic the campaign used before.
        let shear_fraction =
            2.0 * w.shear_max_fraction * rng.random::<f64>() - w.shear_max_fraction;
        let veer_deg = 2.0 * w.veer_max_deg * rng.random::<f64>() - w.veer_max_deg;
        let gust_factor = 1.0 + (w.gust_factor_max - 1.0) * rng.random::<f64>();
        let low_level_turn_deg = w.low_level_turn_max_deg * (2.0 * rng.random::<f64>() - 1.0);
        Self {
            shear_fraction,
            veer_deg,
            gust_factor,
            low_level_turn_deg,
            low_level_height_m: w.low_level_height_m,
        }
    }
}

/// Servo errors of one flight: what the servos do with a command.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct ServoErrors {
    /// Main-line zero offset, m.
    pub main_line_bias_m: f64,
    /// Right and left brake zero offsets, fraction of travel.
    pub brake_bias: [f64; 2],
    /// Main-line dead band, m.
    pub main_line_dead_band_m: f64,
    /// Brake dead band, fraction of travel.
    pub brake_dead_band: f64,
}

impl ServoErrors {
    /// What the servos settle at for `command` when they stand at `standing` (the previous
    /// outcome): offset by their biases, and not moved by a change within the dead band.
    pub fn apply(&self, command: Controls, standing: Controls, travel_m: f64) -> Controls {
        let hold = |target: f64, now: f64, band: f64| {
            if (target - now).abs() <= band {
                now
            } else {
                target
            }
        };
        Controls {
            main_line_m: hold(
                command.main_line_m + self.main_line_bias_m,
                standing.main_line_m,
                self.main_line_dead_band_m,
            ),
            brake_right: hold(
                command.brake_right + self.brake_bias[0],
                standing.brake_right,
                self.brake_dead_band,
            ),
            brake_left: hold(
                command.brake_left + self.brake_bias[1],
                standing.brake_left,
                self.brake_dead_band,
            ),
        }
        .saturated(travel_m)
    }

    /// Whether the servos do exactly what they are told.
    pub fn is_perfect(&self) -> bool {
        *self == Self::default()
    }
}

/// Everything one flight draws from a dispersion set.
#[derive(Debug, Clone)]
pub struct DispersedFlight {
    /// The vehicle as it really flies.
    pub vehicle: Vehicle,
    /// The sensors' settings (their per-flight biases are drawn by the sensor suite from the
    /// flight's sensor seed).
    pub sensors: SensorConfig,
    /// The servos' errors.
    pub servos: ServoErrors,
    /// A few of the drawn factors, for a report to name (lift slope, zero-lift drag, brake
    /// lift, total mass, all relative to nominal; rigging change in degrees).
    pub summary: DrawSummary,
}

/// The drawn factors most telling of how a flight's vehicle differs from nominal.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct DrawSummary {
    /// Canopy lift slope, relative to nominal.
    pub cl_alpha: f64,
    /// Canopy zero-lift drag, relative to nominal.
    pub cd0: f64,
    /// Brake lift term, relative to nominal.
    pub cl_ds: f64,
    /// Total mass, relative to nominal.
    pub mass: f64,
    /// Rigging angle change, degrees.
    pub rigging_deg: f64,
}

/// Streams of the independent draws of one flight.
mod stream {
    pub const VEHICLE: u64 = 31;
    pub const SERVOS: u64 = 32;
    pub const GPS_DROPOUTS: u64 = 33;
}

impl DispersedFlight {
    /// Draws flight `seed`'s vehicle from `nominal`, and its sensors from `sensors`.
    pub fn draw(
        d: &Dispersions,
        nominal: &VehicleConfig,
        sensors: &SensorConfig,
        seed: u64,
    ) -> Result<Self, VehicleError> {
        let (config, summary) = disperse_vehicle(d, nominal, &mut rng_for(seed, stream::VEHICLE));
        let mut vehicle = config.validate()?;
        let mut rng = rng_for(seed, stream::VEHICLE ^ 0x100);
        let inertia_sigma = d.mass.inertia_sigma;
        vehicle.canopy_inertia *= 1.0 + inertia_sigma * clipped_gauss(&mut rng);
        vehicle.drone_inertia *= 1.0 + inertia_sigma * clipped_gauss(&mut rng);
        let servos = {
            let s = &d.servos;
            let mut rng = rng_for(seed, stream::SERVOS);
            ServoErrors {
                main_line_bias_m: s.main_line_bias_sigma_m * clipped_gauss(&mut rng),
                brake_bias: [
                    s.brake_bias_sigma * clipped_gauss(&mut rng),
                    s.brake_bias_sigma * clipped_gauss(&mut rng),
                ],
                main_line_dead_band_m: s.main_line_dead_band_m,
                brake_dead_band: s.brake_dead_band,
            }
        };
        Ok(Self {
            vehicle,
            sensors: disperse_sensors(d, sensors, &mut rng_for(seed, stream::GPS_DROPOUTS)),
            servos,
            summary,
        })
    }
}

/// Changes `v`'s rigging angle by `deg`: turns the canopy's pressure centre and its lines'
/// canopy ends about the canopy's pitch axis (a right-handed turn about its y axis, x forward
/// and z down), which turns the canopy's trim against its lines by that angle.
///
/// The rigging angle is not a field of the vehicle file, so what "a rigging change" means is
/// defined only here: a dispersed flight draws one, and identification (stx-analysis) fits
/// one. Both call this, so a fitted angle is the same change the Monte Carlo disperses.
pub fn rotate_rigging(v: &mut VehicleConfig, deg: f64) {
    let (sin, cos) = deg.to_radians().sin_cos();
    let g = &mut v.geometry;
    for p in [
        &mut g.canopy_pressure_centre_m,
        &mut g.right_line_on_canopy_m,
        &mut g.left_line_on_canopy_m,
    ] {
        let [x, y, z] = *p;
        *p = [cos * x + sin * z, y, -sin * x + cos * z];
    }
}

fn disperse_vehicle(
    d: &Dispersions,
    nominal: &VehicleConfig,
    rng: &mut ChaCha8Rng,
) -> (VehicleConfig, DrawSummary) {
    let mut v = nominal.clone();
    let a = &mut v.canopy.aero;
    let s = d.aero.canopy_sigma;
    for c in [
        &mut a.cd0,
        &mut a.cd_alpha2,
        &mut a.cy_beta,
        &mut a.cl0,
        &mut a.cl_alpha,
        &mut a.clp,
        &mut a.cmq,
        &mut a.cnr,
        &mut a.cn_beta,
    ] {
        scaled(rng, c, s);
    }
    let b = &mut v.canopy.brakes;
    for c in [&mut b.cl_ds, &mut b.cd_ds, &mut b.cl_da, &mut b.cn_da] {
        scaled(rng, c, d.aero.brake_sigma);
    }
    let s = d.aero.body_sigma;
    for c in [
        &mut v.drone.cd,
        &mut v.drone.clp,
        &mut v.drone.cmq,
        &mut v.drone.cnr,
        &mut v.capsule.cd,
        &mut v.transponder.cd,
    ] {
        scaled(rng, c, s);
    }
    let s = d.mass.mass_sigma;
    for m in [
        &mut v.canopy.mass_kg,
        &mut v.drone.mass_kg,
        &mut v.capsule.mass_kg,
        &mut v.transponder.mass_kg,
    ] {
        scaled(rng, m, s);
    }
    let rigging_deg = d.rigging.angle_sigma_deg * clipped_gauss(rng);
    rotate_rigging(&mut v, rigging_deg);
    let g = &mut v.geometry;
    let line = 1.0 + d.rigging.line_length_sigma * clipped_gauss(rng);
    for l in [&mut g.right_line_m, &mut g.left_line_m] {
        *l = l.map(|c| c * line);
    }
    scaled(
        rng,
        &mut g.capsule_line_length_m,
        d.rigging.line_length_sigma,
    );
    scaled(
        rng,
        &mut g.transponder_line_length_m,
        d.rigging.line_length_sigma,
    );
    let mass = |c: &VehicleConfig| {
        c.canopy.mass_kg + c.drone.mass_kg + c.capsule.mass_kg + c.transponder.mass_kg
    };
    let summary = DrawSummary {
        cl_alpha: v.canopy.aero.cl_alpha / nominal.canopy.aero.cl_alpha,
        cd0: v.canopy.aero.cd0 / nominal.canopy.aero.cd0,
        cl_ds: v.canopy.brakes.cl_ds / nominal.canopy.brakes.cl_ds,
        mass: mass(&v) / mass(nominal),
        rigging_deg,
    };
    (v, summary)
}

fn disperse_sensors(d: &Dispersions, base: &SensorConfig, rng: &mut ChaCha8Rng) -> SensorConfig {
    let n = &d.sensors;
    let mut s = base.clone();
    let set = |target: &mut f64, value: Option<f64>| {
        if let Some(v) = value {
            *target = v;
        }
    };
    set(
        &mut s.gps.horizontal_bias_sigma_m,
        n.gps_horizontal_bias_sigma_m,
    );
    set(
        &mut s.gps.vertical_bias_sigma_m,
        n.gps_vertical_bias_sigma_m,
    );
    set(
        &mut s.gps.velocity_bias_sigma_mps,
        n.gps_velocity_bias_sigma_mps,
    );
    set(&mut s.gps.horizontal_wander_m, n.gps_horizontal_wander_m);
    set(
        &mut s.ahrs.yaw_bias_sigma_deg,
        n.ahrs_heading_bias_sigma_deg,
    );
    set(&mut s.pitot.differential_scale_sigma, n.pitot_scale_sigma);
    set(
        &mut s.pitot.differential_offset_sigma_pa,
        n.pitot_offset_sigma_pa,
    );
    if let Some(mean) = n.gps_dropouts_per_flight.filter(|m| *m > 0.0) {
        let [shortest, longest] = n.gps_dropout_s.unwrap_or([2.0, 10.0]);
        let span = n.gps_dropout_span_s.unwrap_or(200.0);
        // Poisson count by Knuth's product of uniforms: means are a few per flight.
        let limit = (-mean).exp();
        let mut product = rng.random::<f64>();
        let mut count = 0;
        while product > limit && count < 100 {
            count += 1;
            product *= rng.random::<f64>();
        }
        for _ in 0..count {
            let start = span * rng.random::<f64>();
            let length = shortest + (longest - shortest) * rng.random::<f64>();
            s.gps.dropouts_s.push([start, start + length]);
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nominal() -> VehicleConfig {
        Vehicle::straplex().config
    }

    #[test]
    fn the_nominal_set_draws_the_nominal_vehicle_sensors_and_perfect_servos() {
        let d = Dispersions::nominal();
        let base = SensorConfig::default();
        for seed in 0..5 {
            let f = DispersedFlight::draw(&d, &nominal(), &base, seed).unwrap();
            assert_eq!(f.vehicle.config, nominal());
            assert_eq!(f.vehicle.canopy_inertia, Vehicle::straplex().canopy_inertia);
            assert_eq!(f.sensors, base);
            assert!(f.servos.is_perfect());
        }
    }

    #[test]
    fn realistic_draws_spread_the_lift_slope_by_about_its_sigma_and_are_repeatable() {
        let d = Dispersions::realistic();
        let base = SensorConfig::default();
        let factors: Vec<f64> = (0..400)
            .map(|seed| {
                DispersedFlight::draw(&d, &nominal(), &base, seed)
                    .unwrap()
                    .summary
                    .cl_alpha
            })
            .collect();
        let mean = factors.iter().sum::<f64>() / factors.len() as f64;
        let sd = (factors.iter().map(|f| (f - mean).powi(2)).sum::<f64>()
            / (factors.len() - 1) as f64)
            .sqrt();
        // 400 draws: the sample mean is within 3 standard errors (0.03) of 1 and the
        // standard deviation within 15 % of 0.20 (clipping at 3 σ removes 0.3 % of the mass).
        assert!((mean - 1.0).abs() < 0.03, "mean {mean}");
        assert!((sd - 0.20).abs() < 0.03, "sd {sd}");
        assert!(
            factors
                .iter()
                .all(|f| *f >= 0.4 - 1e-12 && *f <= 1.6 + 1e-12)
        );
        let again = DispersedFlight::draw(&d, &nominal(), &base, 7).unwrap();
        assert_eq!(
            again.vehicle.config,
            DispersedFlight::draw(&d, &nominal(), &base, 7)
                .unwrap()
                .vehicle
                .config
        );
    }

    #[test]
    fn realistic_sensors_get_their_biases_and_a_few_dropouts_per_flight() {
        let d = Dispersions::realistic();
        let base = SensorConfig::default();
        let flights: Vec<SensorConfig> = (0..300)
            .map(|seed| {
                DispersedFlight::draw(&d, &nominal(), &base, seed)
                    .unwrap()
                    .sensors
            })
            .collect();
        let mean_dropouts = flights
            .iter()
            .map(|s| s.gps.dropouts_s.len())
            .sum::<usize>() as f64
            / 300.0;
        assert!((mean_dropouts - 2.0).abs() < 0.3, "{mean_dropouts}");
        for s in &flights {
            assert_eq!(s.ahrs.yaw_bias_sigma_deg, 5.0);
            assert_eq!(s.pitot.differential_scale_sigma, 0.10);
            s.validate().unwrap();
            for [from, to] in &s.gps.dropouts_s {
                assert!(*from >= 0.0 && *to - *from >= 2.0 && *to - *from <= 10.0);
            }
        }
    }

    #[test]
    fn servos_hold_within_their_dead_band_and_add_their_bias() {
        let servos = ServoErrors {
            main_line_bias_m: 0.002,
            brake_bias: [0.05, -0.05],
            main_line_dead_band_m: 0.001,
            brake_dead_band: 0.02,
        };
        let standing = Controls {
            main_line_m: 0.0025,
            brake_right: 0.5,
            brake_left: 0.0,
        };
        let command = Controls {
            main_line_m: 0.0,
            brake_right: 0.46,
            brake_left: 0.5,
        };
        let out = servos.apply(command, standing, 0.03);
        assert_eq!(
            out.main_line_m, 0.0025,
            "0.002 is within 1 mm of 2.5 mm: held"
        );
        assert_eq!(out.brake_right, 0.5, "0.51 is within 0.02 of 0.5: held");
        assert!((out.brake_left - 0.45).abs() < 1e-12);
        let released = servos.apply(Controls::default(), standing, 0.03);
        assert_eq!(
            released.brake_left, 0.0,
            "a negative bias saturates at released"
        );
    }

    #[test]
    fn a_wrong_value_is_named() {
        let text =
            super::super::config::REALISTIC_TOML.replace("brake_sigma = 0.30", "brake_sigma = 0.9");
        let err = Dispersions::from_toml_str(&text).unwrap_err().to_string();
        assert!(err.contains("aero.brake_sigma"), "{err}");
        let err = Dispersions::from_toml_str("name = \"x\"").unwrap_err();
        assert!(matches!(err, super::super::DispersionsError::Parse(_)));
    }
}
