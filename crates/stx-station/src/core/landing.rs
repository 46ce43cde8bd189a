//! The landing, worked out once: when the drone reports `landed`, its GPS receiver's first 3-D
//! fix on the ground (measured at or after the drone's clock of that report) is where it came
//! down, and its distance from the drone's target as the station holds it is *the* miss. Every
//! page (header, map, viewer, recovery), the log, the recording's summary and a replay show this
//! figure and nothing else: the same flight was once reported 1, 2, 3 and 10 m off on four
//! screens, each working it out from its own position and target.
//!
//! The fix is the receiver's, not the station's estimate: it is what a person checks on the
//! field, and a replay of the recorded link bytes finds the same fix, so the same figure.

use nalgebra::Vector3;
use stx_gnc::mission::FlightStage;

use super::StationCore;
use crate::messages::{LandingView, LatLonAlt, Level};

/// Where the landing stands.
#[derive(Debug, Clone, Default)]
pub(crate) struct LandingWatch {
    /// The drone's clock when it reported `landed`, until a fix on the ground arrives.
    pending_since_s: Option<f64>,
    /// The landing, once measured.
    pub landing: Option<LandingView>,
}

impl StationCore {
    /// The drone's stage went from `previous` to `stage` at the drone's clock `drone_s`.
    pub(crate) fn landing_on_stage(
        &mut self,
        previous: Option<FlightStage>,
        stage: FlightStage,
        drone_s: f64,
    ) {
        if stage == FlightStage::Landed && previous.is_some_and(|p| p != FlightStage::Landed) {
            self.landing.pending_since_s = Some(drone_s);
            self.landing.landing = None;
        } else if stage != FlightStage::Landed && previous == Some(FlightStage::Landed) {
            // Flying again (a rehearsal restarted): the old landing is history.
            self.landing = LandingWatch::default();
        }
    }

    /// A 3-D fix of the GPS receiver at `lat_deg`, `lon_deg`, `alt_msl_m`, measured at the
    /// drone's clock `measured_s`: the landing's, if one is awaited and it was measured on the
    /// ground.
    pub(crate) fn landing_fix(
        &mut self,
        now_s: f64,
        measured_s: f64,
        lat_deg: f64,
        lon_deg: f64,
        alt_msl_m: f64,
    ) {
        let Some(since) = self.landing.pending_since_s else {
            return;
        };
        // A fix measured at the report's instant may still be in the air: the drone's clock of
        // the report is that of the burst the touchdown happened after.
        if measured_s <= since {
            return;
        }
        self.landing.pending_since_s = None;
        let position = LatLonAlt {
            lat_deg,
            lon_deg,
            alt_msl_m,
        };
        let target = self.sync.target.map(|_| {
            let (lat, lon, alt) = self.frame.to_geodetic(&self.guidance.plan().target_ned_m);
            LatLonAlt {
                lat_deg: lat,
                lon_deg: lon,
                alt_msl_m: alt,
            }
        });
        let miss_m = target.map(|t| {
            let here = self.frame.to_ned(lat_deg, lon_deg, alt_msl_m);
            let there = self.frame.to_ned(t.lat_deg, t.lon_deg, t.alt_msl_m);
            let d: Vector3<f64> = here - there;
            d.x.hypot(d.y)
        });
        let text = match miss_m {
            Some(m) => format!("landed {m:.1} m from the target (the drone's GPS on the ground)"),
            None => "landed (no target known: no miss)".to_string(),
        };
        self.landing.landing = Some(LandingView {
            time_s: measured_s,
            body: "drone".into(),
            position,
            target,
            miss_m,
        });
        self.log(now_s, Level::Info, "station", text);
    }

    /// The landing, once measured.
    pub fn landing(&self) -> Option<&LandingView> {
        self.landing.landing.as_ref()
    }
}
