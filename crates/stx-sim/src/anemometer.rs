//! The simulated ground anemometer: a cup-and-vane instrument on a mast by the target, as the
//! station would read one (NMEA 0183 `MWV`), reporting the wind it measured as a mean over its
//! averaging time, with its errors, every few seconds; what guidance is given as the surface
//! wind ([`SurfaceWind`]).
//!
//! It samples the run's own wind field (mean profile and turbulence) at the mast's top once a
//! second, so it sees the same low-level turn and gusts the stack flies through on its final;
//! a report is the vector mean of the last `averaging_s` of samples, its speed scaled by a
//! calibration error drawn once per instrument and its direction off by a vane error drawn
//! once, plus a little noise per report.
//!
//! [`mwv_sentence`] writes a report as the instrument would send it to the station; the
//! runner (`stx drone --anemometer-to`) sends those sentences over UDP.

use std::collections::VecDeque;

use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Serialize;
use stx_gnc::guidance::SurfaceWind;
use stx_types::mwv::{MwvReference, format_mwv};
use stx_types::wind::WindField;

/// The anemometer's settings, with units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AnemometerConfig {
    /// Height of the cups above the target's ground, m (a 10-m mast is the meteorological
    /// standard; field masts are often lower).
    pub mast_height_m: f64,
    /// Where the mast stands from the target (north, east), m, the target being the frame's
    /// origin (as in Monte Carlo runs); [`AnemometerConfig::beside`] puts it by a target
    /// elsewhere.
    pub offset_ne_m: [f64; 2],
    /// Each report is the mean wind over this long, s.
    pub averaging_s: f64,
    /// A report is sent this often, s.
    pub period_s: f64,
    /// Speed calibration error, 1-σ fraction, drawn once per instrument.
    pub speed_scale_sigma: f64,
    /// Vane alignment error, 1-σ, degrees, drawn once per instrument.
    pub direction_bias_sigma_deg: f64,
    /// Noise on each report's speed, 1-σ, m/s.
    pub speed_noise_mps: f64,
}

impl Default for AnemometerConfig {
    fn default() -> Self {
        Self {
            mast_height_m: 10.0,
            offset_ne_m: [0.0, 0.0],
            averaging_s: 10.0,
            period_s: 5.0,
            speed_scale_sigma: 0.05,
            direction_bias_sigma_deg: 5.0,
            speed_noise_mps: 0.1,
        }
    }
}

impl AnemometerConfig {
    /// The same instrument by a target at `target_ne_m` (north, east of the frame's origin,
    /// m) instead of at the origin: its offset then counts from that target.
    pub fn beside(self, target_ne_m: [f64; 2]) -> Self {
        Self {
            offset_ne_m: [
                target_ne_m[0] + self.offset_ne_m[0],
                target_ne_m[1] + self.offset_ne_m[1],
            ],
            ..self
        }
    }
}

/// One simulated anemometer.
#[derive(Debug, Clone)]
pub struct Anemometer {
    config: AnemometerConfig,
    /// Samples of the last averaging time: (time, north, east).
    samples: VecDeque<(f64, f64, f64)>,
    next_sample_s: f64,
    next_report_s: f64,
    speed_scale: f64,
    direction_bias_rad: f64,
    rng: ChaCha8Rng,
}

impl Anemometer {
    /// An instrument whose errors are drawn from `seed`.
    pub fn new(config: AnemometerConfig, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x00A7_E40E_7E50);
        let mut gauss = || -> f64 { StandardNormal.sample(&mut rng) };
        let speed_scale = 1.0 + config.speed_scale_sigma * gauss().clamp(-3.0, 3.0);
        let direction_bias_rad =
            (config.direction_bias_sigma_deg * gauss().clamp(-3.0, 3.0)).to_radians();
        // Reports fall at a random phase of the period, as a real instrument's would.
        let first_report_s = config.averaging_s + config.period_s * rng.random::<f64>();
        Self {
            config,
            samples: VecDeque::new(),
            next_sample_s: 0.0,
            next_report_s: first_report_s,
            speed_scale,
            direction_bias_rad,
            rng,
        }
    }

    /// Moves the instrument on to `now_s` in `wind`; a report when one is due.
    pub fn step(&mut self, now_s: f64, wind: &dyn WindField) -> Option<SurfaceWind> {
        let c = self.config;
        let mast = Vector3::new(c.offset_ne_m[0], c.offset_ne_m[1], -c.mast_height_m);
        while self.next_sample_s <= now_s {
            let w = wind.wind_ned_mps(self.next_sample_s, &mast);
            self.samples.push_back((self.next_sample_s, w.x, w.y));
            self.next_sample_s += 1.0;
        }
        while self
            .samples
            .front()
            .is_some_and(|(t, _, _)| *t < now_s - c.averaging_s)
        {
            self.samples.pop_front();
        }
        if now_s < self.next_report_s || self.samples.is_empty() {
            return None;
        }
        self.next_report_s += c.period_s;
        let n = self.samples.len() as f64;
        let north = self.samples.iter().map(|s| s.1).sum::<f64>() / n;
        let east = self.samples.iter().map(|s| s.2).sum::<f64>() / n;
        let noise: f64 = StandardNormal.sample(&mut self.rng);
        let speed = (north.hypot(east) * self.speed_scale + c.speed_noise_mps * noise).max(0.0);
        let direction = east.atan2(north) + self.direction_bias_rad;
        Some(SurfaceWind {
            ne_mps: [speed * direction.cos(), speed * direction.sin()],
            time_s: now_s,
        })
    }
}

/// Where a report's wind blows from, degrees clockwise from true north in 0..360, and its
/// speed, m/s: what an anemometer writes. The report's `ne_mps` is where the air goes, the
/// opposite; a calm has no direction and is said to come from the north.
pub fn from_deg_and_speed(report: &SurfaceWind) -> (f64, f64) {
    let [north, east] = report.ne_mps;
    stx_types::wind::from_deg_and_speed(north, east)
}

/// The NMEA 0183 MWV sentence of `report` (true reference, m/s), CR LF included, as the
/// instrument sends it.
pub fn mwv_sentence(report: &SurfaceWind) -> String {
    let (from_deg, speed_mps) = from_deg_and_speed(report);
    format_mwv(from_deg, MwvReference::True, speed_mps)
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Steady(Vector3<f64>);

    impl WindField for Steady {
        fn wind_ned_mps(&self, _: f64, _: &Vector3<f64>) -> Vector3<f64> {
            self.0
        }
    }

    #[test]
    fn a_perfect_anemometer_reports_the_wind_at_its_mast_every_period() {
        let config = AnemometerConfig {
            speed_scale_sigma: 0.0,
            direction_bias_sigma_deg: 0.0,
            speed_noise_mps: 0.0,
            ..AnemometerConfig::default()
        };
        let mut anemometer = Anemometer::new(config, 7);
        let wind = Steady(Vector3::new(-2.0, 1.0, 0.0));
        let reports: Vec<(f64, SurfaceWind)> = (0..240)
            .filter_map(|k| {
                let t = 0.25 * k as f64;
                anemometer.step(t, &wind).map(|r| (t, r))
            })
            .collect();
        // 60 s, the first report after the averaging time, then one every 5 s.
        assert!((10..=11).contains(&reports.len()), "{}", reports.len());
        assert!(reports[0].0 >= config.averaging_s);
        for pair in reports.windows(2) {
            assert!((pair[1].0 - pair[0].0 - config.period_s).abs() <= 0.25);
        }
        for (t, r) in &reports {
            assert_eq!(r.time_s, *t);
            assert!((r.ne_mps[0] + 2.0).abs() < 1e-9 && (r.ne_mps[1] - 1.0).abs() < 1e-9);
        }
    }

    /// The air's velocity is where it is sampled, in km: a report says where the mast is.
    struct WhereAmI;

    impl WindField for WhereAmI {
        fn wind_ned_mps(&self, _: f64, p: &Vector3<f64>) -> Vector3<f64> {
            p / 1000.0
        }
    }

    #[test]
    fn an_instrument_beside_a_target_samples_the_wind_there() {
        let config = AnemometerConfig {
            offset_ne_m: [10.0, -20.0],
            speed_scale_sigma: 0.0,
            direction_bias_sigma_deg: 0.0,
            speed_noise_mps: 0.0,
            ..AnemometerConfig::default()
        }
        .beside([300.0, 2500.0]);
        assert_eq!(config.offset_ne_m, [310.0, 2480.0]);
        let mut anemometer = Anemometer::new(config, 3);
        let report = (0..100)
            .find_map(|k| anemometer.step(0.25 * k as f64, &WhereAmI))
            .expect("a report within 25 s");
        assert!((report.ne_mps[0] - 0.31).abs() < 1e-9, "{report:?}");
        assert!((report.ne_mps[1] - 2.48).abs() < 1e-9, "{report:?}");
    }

    #[test]
    fn a_report_turns_into_where_the_wind_comes_from_and_its_sentence() {
        let report = |north: f64, east: f64| SurfaceWind {
            ne_mps: [north, east],
            time_s: 0.0,
        };
        // Air going south comes from the north; going east, from the west; going north-west,
        // from the south-east.
        for ((north, east), from, speed) in [
            ((-3.0, 0.0), 0.0, 3.0),
            ((0.0, 2.0), 270.0, 2.0),
            ((1.0, -1.0), 135.0, 2f64.sqrt()),
            ((0.0, -4.0), 90.0, 4.0),
            ((2.0, 0.0), 180.0, 2.0),
            ((-1.0, 1e-18), 0.0, 1.0),
            ((0.0, 0.0), 0.0, 0.0),
        ] {
            let (from_deg, speed_mps) = from_deg_and_speed(&report(north, east));
            assert!(
                (0.0..360.0).contains(&from_deg) && (from_deg - from).abs() < 1e-9,
                "({north}, {east}): from {from_deg}"
            );
            assert!((speed_mps - speed).abs() < 1e-12);
        }
        // A wind blowing from the mission profile's 300° at 2 m/s reads back as such.
        let (sin, cos) = 300f64.to_radians().sin_cos();
        let line = mwv_sentence(&report(-2.0 * cos, -2.0 * sin));
        assert!(line.starts_with("$WIMWV,300.0,T,2.0,M,A*"), "{line}");
        let reading = stx_types::mwv::parse_mwv(&line).expect("valid");
        assert!((reading.from_deg - 300.0).abs() < 1e-9 && reading.speed_mps == 2.0);
    }

    #[test]
    fn an_instrument_keeps_its_drawn_errors_and_another_seed_draws_others() {
        let wind = Steady(Vector3::new(3.0, 0.0, 0.0));
        let direction_of = |seed| {
            let mut a = Anemometer::new(AnemometerConfig::default(), seed);
            let reports: Vec<SurfaceWind> = (0..400)
                .filter_map(|k| a.step(0.25 * k as f64, &wind))
                .collect();
            let directions: Vec<f64> = reports
                .iter()
                .map(|r| r.ne_mps[1].atan2(r.ne_mps[0]))
                .collect();
            // One bias per instrument: every report of it points the same way.
            assert!(directions.iter().all(|d| (d - directions[0]).abs() < 1e-9));
            directions[0]
        };
        assert_ne!(direction_of(1), direction_of(2));
        assert!(direction_of(1).abs() < 15f64.to_radians());
    }
}
