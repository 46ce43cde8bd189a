//! The reachable footprint on the station (issue 15 item 1): while the stack flies under the
//! parafoil, a detached [`FootprintJob`] computes from the station's estimate the ground it can
//! still reach (`stx_gnc::footprint`), off the telemetry path like the landing prediction, and
//! the dashboard draws its 50 % and 95 % regions.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::wind::{WindField, WindProfile};
use stx_gnc::descent_wind::{DEFAULT_FADE_HEIGHT_M, DescentWind};
use stx_gnc::estimate::Estimate;
use stx_gnc::footprint::{
    Footprint, FootprintConfig, FootprintError, FootprintInput, ValidFootprintConfig, footprint,
};
use stx_gnc::mission::FlightStage;
use stx_gnc::performance::GlidePerformance;

use super::StationCore;
use crate::messages::{FootprintContourView, FootprintView, FootprintZoneHit};

/// A footprint older than this is shown as stale, s: two refreshes missed at the longest
/// period the issue allows (5 s).
const STALE_AFTER_S: f64 = 10.0;
/// Most points sent per ring: the map needs no more, and the state message goes to every
/// page several times a second.
const MAX_RING_POINTS: usize = 160;

/// Everything one footprint needs, detached from the station so it runs on another thread.
pub struct FootprintJob {
    estimate: Estimate,
    performance: GlidePerformance,
    /// The wind below the drone: the ascent's measured bands joined to the forecast, when
    /// there are any.
    wind_profile: Option<WindProfile>,
    ground_altitude_msl_m: f64,
    config: ValidFootprintConfig,
    computed_s: f64,
}

/// A finished [`FootprintJob`].
pub struct FootprintDone {
    footprint: Result<Footprint, FootprintError>,
    computed_s: f64,
}

impl FootprintJob {
    /// Computes the footprint (tens of milliseconds; see `crates/stx-gnc/benches/footprint.rs`).
    /// Seeded from the estimate's time, so a replay computes the same footprint.
    pub fn run(&self) -> FootprintDone {
        // The measured profile is corrected by the wind the drone measures now, the correction
        // fading below it, as the landing prediction does.
        let below = self
            .wind_profile
            .as_ref()
            .map(|p| DescentWind::below_estimate(&self.estimate, Some(p), DEFAULT_FADE_HEIGHT_M));
        let input = FootprintInput {
            estimate: &self.estimate,
            performance: &self.performance,
            wind_below: below.as_ref().map(|w| w as &dyn WindField),
            atmosphere: &StandardAtmosphere,
            ground_altitude_msl_m: self.ground_altitude_msl_m,
        };
        let seed = (self.estimate.time_s * 1000.0) as u64;
        FootprintDone {
            footprint: footprint(&input, &self.config, &mut ChaCha8Rng::seed_from_u64(seed)),
            computed_s: self.computed_s,
        }
    }
}

impl StationCore {
    fn under_parafoil(&self) -> bool {
        matches!(
            self.latest.status.map(|(s, _)| s.stage),
            Some(FlightStage::ParafoilDeploy | FlightStage::Parafoil)
        )
    }

    /// A footprint from the current estimate, to be run away from the telemetry path; `None`
    /// unless the stack flies under the parafoil with a navigation solution.
    pub fn footprint_job(&self, now_s: f64) -> Option<FootprintJob> {
        if !self.under_parafoil() {
            return None;
        }
        let config = FootprintConfig {
            hang_height_m: self.config.guidance.spiral.hang_height_m,
            ..FootprintConfig::default()
        };
        let config = match config.validate() {
            Ok(c) => c,
            Err(e) => {
                tracing::warn!("no footprint: {e}");
                return None;
            }
        };
        Some(FootprintJob {
            estimate: self.estimate?,
            performance: self.config.guidance.performance,
            wind_profile: self.wind_profile(),
            ground_altitude_msl_m: self.frame.alt_msl_m,
            config,
            computed_s: now_s,
        })
    }

    /// Takes the result of a [`FootprintJob`]; an estimate it could not use keeps the last
    /// footprint, which then ages into stale.
    pub fn set_footprint(&mut self, done: FootprintDone) {
        match done.footprint {
            Ok(f) => {
                let hits = f.zone_hits(self.keep_out_zones());
                self.footprint = Some((f, done.computed_s, hits));
            }
            Err(e) => tracing::debug!("no footprint: {e}"),
        }
    }

    /// The footprint as the dashboard draws it; `null` off the parafoil.
    pub(crate) fn footprint_view(&self, now_s: f64) -> Option<FootprintView> {
        let (f, computed_s, hits) = self.footprint.as_ref().filter(|_| self.under_parafoil())?;
        let geodetic = |ne: &[f64; 2]| {
            let (lat, lon, _) = self
                .frame
                .to_geodetic(&nalgebra::Vector3::new(ne[0], ne[1], 0.0));
            [lat, lon]
        };
        let ring = |points: &Vec<[f64; 2]>| -> Vec<[f64; 2]> {
            let stride = points.len().div_ceil(MAX_RING_POINTS).max(1);
            let mut out: Vec<[f64; 2]> = points.iter().step_by(stride).map(geodetic).collect();
            if let Some(last) = points.last() {
                out.push(geodetic(last));
            }
            out
        };
        let age_s = (now_s - computed_s).max(0.0);
        Some(FootprintView {
            computed_s: *computed_s,
            age_s,
            stale: age_s > STALE_AFTER_S,
            height_m: f.height_m,
            draws: u32::try_from(f.draws).unwrap_or(u32::MAX),
            contours: f
                .contours
                .iter()
                .map(|c| FootprintContourView {
                    level: c.level,
                    polygons: c
                        .polygons
                        .iter()
                        .map(|p| {
                            std::iter::once(ring(&p.exterior_ne_m))
                                .chain(p.holes_ne_m.iter().map(ring))
                                .collect()
                        })
                        .collect(),
                })
                .collect(),
            zone_hits: hits
                .iter()
                .map(|h| FootprintZoneHit {
                    zone: h.name.clone(),
                    level: h.level,
                })
                .collect(),
        })
    }
}
