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
            // Worded as every page words it: the body, the figure to 0.1 m, the target.
            Some(m) => format!("landed: drone {m:.1} m from the target (its GPS on the ground)"),
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

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;
    use stx_gnc::mission::FlightStage as S;

    use crate::core::TargetSource;
    use crate::core::tests::core;

    #[test]
    fn the_landing_is_the_first_fix_measured_after_the_landed_report_and_measured_once() {
        let mut c = core();
        let mut plan = *c.guidance.plan();
        plan.target_ned_m = Vector3::new(300.0, 400.0, 0.0);
        c.guidance.set_plan(plan, 0.0);
        c.sync.target = Some(TargetSource::DronePlan);
        let at = |north: f64, east: f64| c.frame.to_geodetic(&Vector3::new(north, east, 0.0));
        let (air, down, later) = (at(330.0, 400.0), at(303.0, 404.0), at(310.0, 420.0));

        c.landing_on_stage(Some(S::Parafoil), S::Landed, 1000.0);
        // Measured at the report's instant: maybe still in the air.
        c.landing_fix(50.0, 1000.0, air.0, air.1, air.2);
        assert!(c.landing().is_none());
        c.landing_fix(50.1, 1000.2, down.0, down.1, down.2);
        let l = c.landing().cloned().expect("measured");
        assert_eq!((l.time_s, l.body.as_str()), (1000.2, "drone"));
        let miss = l.miss_m.expect("a target");
        assert!((miss - 5.0).abs() < 0.01, "3-4-5 m: {miss}");
        // The GPS wanders on the ground: the figure does not.
        c.landing_fix(50.2, 1000.4, later.0, later.1, later.2);
        assert_eq!(c.landing(), Some(&l));
        let said: Vec<String> = c.events_since(0.0).into_iter().map(|e| e.text).collect();
        assert_eq!(
            said.iter()
                .filter(|t| t.contains("from the target"))
                .collect::<Vec<_>>(),
            vec!["landed: drone 5.0 m from the target (its GPS on the ground)"]
        );
        // Flying again (a rehearsal restarted): the old landing is history.
        c.landing_on_stage(Some(S::Landed), S::PreLaunch, 0.0);
        assert!(c.landing().is_none());
    }
}
