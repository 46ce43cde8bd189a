//! Ascent winds on the station: every usable GPS fix of the balloon's ascent goes into the
//! pure [`AscentWindEstimator`]; the bands it measures are refitted at most every
//! [`REFIT_EVERY_S`], sent to the pages (`ascent_wind`) when they change, and joined to the
//! forecast into the profile every descent prediction flies in
//! ([`StationCore::wind_profile`]). A band the estimator refuses as implausible (faster than
//! any wind a balloon meets at its height, or too uncertain: `stx_gnc::ascent_wind`'s
//! `plausible.rs`) is sent with its reason and logged once, but never merged.
//!
//! **Clock.** Fixes are timed on the drone's clock (radio delays and accelerated rehearsals
//! do not distort it), continued across a restart of the drone: the estimator needs times
//! that only increase.
//!
//! **When the drone restarts** the station does not throw a measured ascent away: the air
//! the balloon drifted through is the same whatever the drone's computer did. A restart
//! mid-ascent (a brown-out, a watchdog) keeps the bands and goes on adding to them, the clock
//! continued from the last fix by the station's time since it. A restart before any fix was
//! used (on the pad), or after the ascent ended (on the ground after landing, ready for the
//! next flight), starts a fresh measurement: that is a new flight, whose air is another.
//! A second flight without a restart of the drone or the station keeps the first's bands
//! (the estimator has latched the end of that ascent): restart the station between flights.

use stx_dynamics::wind::{ProfileRow, WindProfile};
use stx_gnc::ascent_wind::{
    AscentFix, AscentWindConfig, AscentWindEstimator, Implausible, WindBand,
};

use super::StationCore;
use crate::messages::{AscentBandView, AscentWindMsg, Level};

/// Most often the bands are refitted, s of the station's clock: a refit costs milliseconds
/// for a long ascent (see [`AscentWindEstimator::profile`]), and a band takes minutes to fill.
pub const REFIT_EVERY_S: f64 = 2.0;

/// The station's ascent-wind measurement.
#[derive(Debug, Clone)]
pub(crate) struct AscentWinds {
    estimator: AscentWindEstimator,
    /// The bands of the last refit, lowest first.
    bands: Vec<WindBand>,
    /// A fix was used since the last refit.
    dirty: bool,
    next_refit_s: f64,
    /// Added to the drone's clock to give the estimator's, s (grows at each kept restart).
    clock_offset_s: f64,
    /// The estimator's clock and the station's of the last fix handed in, s.
    last_fix: Option<(f64, f64)>,
    /// Refused bands already logged: band index, and whether too fast (else too uncertain).
    said_refused: std::collections::BTreeSet<(i64, bool)>,
}

impl AscentWinds {
    /// A measurement with nothing yet; `config` is validated with the station's.
    pub(crate) fn new(config: AscentWindConfig) -> Self {
        let estimator = AscentWindEstimator::new(config).unwrap_or_else(|e| {
            // `StationConfig::validate` refuses such a configuration before a core exists.
            tracing::error!("ascent winds: {e}; the defaults are used");
            AscentWindEstimator::new(AscentWindConfig::default())
                .unwrap_or_else(|e| panic!("default ascent-wind settings invalid: {e}"))
        });
        Self {
            estimator,
            bands: Vec::new(),
            dirty: false,
            next_refit_s: 0.0,
            clock_offset_s: 0.0,
            last_fix: None,
            said_refused: Default::default(),
        }
    }

    /// Hands in a fix timed `drone_s` on the drone's clock, received at `now_s`.
    pub(crate) fn push(&mut self, now_s: f64, drone_s: f64, mut fix: AscentFix) {
        fix.time_s = drone_s + self.clock_offset_s;
        let before = self.estimator.counts();
        // Refused fixes are counted by the estimator; nothing else is to be done with them.
        let _ = self.estimator.push_fix(&fix);
        let after = self.estimator.counts();
        // A fix used, or the end of the ascent seen (its last window's fixes withdrawn).
        if after.used != before.used || after.withdrawn != before.withdrawn {
            self.dirty = true;
        }
        if self.last_fix.is_none_or(|(t, _)| fix.time_s > t) {
            self.last_fix = Some((fix.time_s, now_s));
        }
    }

    /// The drone restarted at `now_s`, its clock now reading `drone_s`: keeps a measurement
    /// under way (see the module doc) and says whether it did.
    pub(crate) fn on_drone_restart(&mut self, now_s: f64, drone_s: f64) -> bool {
        let under_way =
            self.estimator.counts().used > 0 && self.estimator.ascent_over_at_s().is_none();
        if under_way {
            if let Some((last_t, last_now)) = self.last_fix {
                let since = (now_s - last_now).max(1e-3);
                self.clock_offset_s = last_t + since - drone_s;
            }
        } else {
            let config = *self.estimator.config();
            let shown = std::mem::take(&mut self.bands);
            *self = Self::new(config);
            // The next refit compares the (empty) new bands with those the pages have, so
            // they learn that the old ones are gone.
            self.bands = shown;
            self.dirty = true;
        }
        under_way
    }

    /// Refits the bands when a fix was used and [`REFIT_EVERY_S`] has passed; true when they
    /// changed.
    pub(crate) fn refit(&mut self, now_s: f64) -> bool {
        if !self.dirty || now_s < self.next_refit_s {
            return false;
        }
        self.dirty = false;
        self.next_refit_s = now_s + REFIT_EVERY_S;
        let bands = self.estimator.profile();
        let changed = bands != self.bands;
        self.bands = bands;
        changed
    }

    /// The bands of the last refit, lowest first.
    pub(crate) fn bands(&self) -> &[WindBand] {
        &self.bands
    }
}

impl StationCore {
    /// A fix for the ascent winds from a GPS_RAW_INT with a 3-D fix; its velocity when the
    /// receiver gives speed and course and GLOBAL_POSITION_INT a vertical speed younger than
    /// a second (GPS_RAW_INT carries none), else positions alone. Built as a recording's
    /// fixes are ([`crate::recording::ascent::fix_from_gps`]); the time is set by
    /// `AscentWinds::push`.
    pub(crate) fn ascent_fix(
        &self,
        now_s: f64,
        g: &stx_link::telemetry::GpsRaw,
    ) -> Option<AscentFix> {
        let down = self
            .latest
            .position
            .filter(|(_, t)| now_s - t < 1.0)
            .map(|(p, _)| p.v_down_mps);
        crate::recording::ascent::fix_from_gps(&self.frame, 0.0, g, down)
    }

    /// Tells the ascent winds that the drone restarted, and the operators what became of
    /// the measurement.
    pub(crate) fn ascent_on_drone_restart(&mut self, now_s: f64, drone_s: f64) {
        let had = self.ascent.bands().len();
        if self.ascent.on_drone_restart(now_s, drone_s) {
            self.log(
                now_s,
                Level::Info,
                "station",
                format!("ascent winds: the {had} bands measured so far are kept across the drone's restart"),
            );
        }
    }

    /// Refits the ascent's bands when due and queues an `ascent_wind` message if they
    /// changed.
    pub(crate) fn refit_ascent_winds(&mut self, now_s: f64) {
        if self.ascent.refit(now_s) {
            let msg = self.ascent_wind_msg(now_s);
            let refused: Vec<(i64, Implausible, f64, f64)> = self
                .ascent
                .bands()
                .iter()
                .filter_map(|b| Some((b.band, b.refused?, b.altitude_min_m, b.altitude_max_m)))
                .collect();
            for (band, why, low, high) in refused {
                // Said once a band and kind of refusal: a refit every few seconds would
                // repeat it with numbers a little different.
                let kind = matches!(why, Implausible::TooFast { .. });
                if self.ascent.said_refused.insert((band, kind)) {
                    let msl = self.frame.alt_msl_m;
                    self.log(
                        now_s,
                        Level::Warning,
                        "station",
                        format!(
                            "ascent winds: the band {:.0}–{:.0} m MSL is refused, not used for predictions: {why}",
                            low + msl,
                            high + msl
                        ),
                    );
                }
            }
            self.outbound.push(super::Outbound::AscentWind(msg));
        }
    }

    /// The forecast as profile rows above the frame's origin, lowest first (the
    /// configuration's order need not be).
    fn forecast_rows(&self) -> Vec<ProfileRow> {
        let mut rows: Vec<ProfileRow> = self
            .config
            .forecast_wind
            .iter()
            .map(|r| ProfileRow {
                altitude_m: r.alt_msl_m - self.frame.alt_msl_m,
                speed_mps: r.speed_mps,
                from_deg: r.from_deg,
            })
            .collect();
        rows.sort_by(|a, b| a.altitude_m.total_cmp(&b.altitude_m));
        rows.dedup_by(|a, b| a.altitude_m == b.altitude_m);
        rows
    }

    /// The wind profile every descent prediction flies in, altitudes above the frame's
    /// origin: the ascent's measured bands, the forecast above the highest and below the
    /// lowest (see [`stx_gnc::ascent_wind::merge_with_forecast`]). `None` with neither a
    /// band nor a forecast.
    pub fn wind_profile(&self) -> Option<WindProfile> {
        match stx_gnc::ascent_wind::merge_with_forecast(self.ascent.bands(), &self.forecast_rows())
        {
            Ok(p) => Some(p),
            Err(stx_dynamics::wind::WindError::EmptyProfile) => None,
            Err(e) => {
                tracing::warn!("ascent winds: no profile: {e}");
                None
            }
        }
    }

    /// The `ascent_wind` message: the measured bands as the pages show them.
    pub fn ascent_wind_msg(&self, now_s: f64) -> AscentWindMsg {
        AscentWindMsg {
            kind: "ascent_wind",
            time_s: now_s,
            band_height_m: self.ascent.estimator.config().band_height_m,
            ascent_over: self.ascent.estimator.ascent_over_at_s().is_some(),
            fixes_used: self.ascent.estimator.counts().used,
            bands: self
                .ascent
                .bands()
                .iter()
                .map(|b| AscentBandView::of(b, self.frame.alt_msl_m))
                .collect(),
        }
    }
}
