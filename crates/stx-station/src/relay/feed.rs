//! What a relay shows, decided on its own clock (`now_s` in, messages out; the sockets are the
//! adapter's): states from the upstream held back by the relay's delay, positions rounded to
//! its grid, and the public track rebuilt from the upstream's history and the states shown.
//!
//! Relays in a tree add up: a relay behind a relay delays by both and rounds to the coarser
//! grid of the two, and says so in each state (`delay_s`, `coarsen_m`).

use std::collections::VecDeque;

use thiserror::Error;

use super::public::{
    PublicHistoryMsg, PublicPoint, PublicStateMsg, PublicTrackPoint, UpstreamNews,
};

/// Longest delay a relay may add, s (a day's flight is over by then).
pub const MAX_DELAY_S: f64 = 3_600.0;
/// Coarsest grid, m.
pub const MAX_COARSEN_M: f64 = 10_000.0;
/// Most track points kept (a point a second: more than five hours).
const MAX_TRACK: usize = 20_000;
/// Most states held back by a delay (four a second over the longest delay, and some).
const MAX_HELD: usize = 16_000;
/// Metres per degree of latitude (mean).
const M_PER_DEG: f64 = 111_320.0;
/// The mission clock stepping back this far means the drone restarted: a new track.
const RESTART_STEP_BACK_S: f64 = 10.0;

/// How a relay changes what it passes on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelaySettings {
    /// Shown this long after the upstream sent it, s (0 to [`MAX_DELAY_S`]).
    pub delay_s: f64,
    /// Positions rounded to a grid this coarse, m (0, off, to [`MAX_COARSEN_M`]).
    pub coarsen_m: f64,
}

/// A setting out of its range.
#[derive(Debug, Error, PartialEq)]
pub enum RelaySettingsError {
    /// The delay.
    #[error("--delay {0} s: must be 0 to {MAX_DELAY_S} s")]
    Delay(f64),
    /// The grid.
    #[error("--coarsen {0} m: must be 0 (off) to {MAX_COARSEN_M} m")]
    Coarsen(f64),
}

impl RelaySettings {
    /// Checked settings.
    pub fn new(delay_s: f64, coarsen_m: f64) -> Result<Self, RelaySettingsError> {
        if !(0.0..=MAX_DELAY_S).contains(&delay_s) {
            return Err(RelaySettingsError::Delay(delay_s));
        }
        if !(0.0..=MAX_COARSEN_M).contains(&coarsen_m) {
            return Err(RelaySettingsError::Coarsen(coarsen_m));
        }
        Ok(Self { delay_s, coarsen_m })
    }
}

/// `lat, lon` rounded to a grid of `m` metres (rows of latitude, each row's longitude step as
/// wide on the ground), or unchanged for `m` = 0.
pub fn snap(lat_deg: f64, lon_deg: f64, m: f64) -> (f64, f64) {
    if m <= 0.0 {
        return (lat_deg, lon_deg);
    }
    let dlat = m / M_PER_DEG;
    let lat = (lat_deg / dlat).round() * dlat;
    let dlon = m / (M_PER_DEG * lat.to_radians().cos().max(0.01));
    (lat, (lon_deg / dlon).round() * dlon)
}

/// The relay's picture.
#[derive(Debug)]
pub struct Feed {
    settings: RelaySettings,
    /// States from the upstream, with when they may be shown (relay clock, s).
    held: VecDeque<(f64, PublicStateMsg)>,
    /// The upstream's history, not yet shown (its points later than the newest state shown).
    held_track: VecDeque<PublicTrackPoint>,
    /// The track shown.
    track: Vec<PublicTrackPoint>,
    /// The newest state shown.
    shown: Option<PublicStateMsg>,
    /// States dropped because too many were held.
    dropped: u64,
}

impl Feed {
    /// An empty picture.
    pub fn new(settings: RelaySettings) -> Self {
        Self {
            settings,
            held: VecDeque::new(),
            held_track: VecDeque::new(),
            track: Vec::new(),
            shown: None,
            dropped: 0,
        }
    }

    /// The settings.
    pub fn settings(&self) -> RelaySettings {
        self.settings
    }

    /// One message from the upstream at the relay's `now_s`.
    pub fn on_upstream(&mut self, now_s: f64, news: UpstreamNews) {
        match news {
            UpstreamNews::State(s) => {
                if self.held.len() >= MAX_HELD {
                    self.held.pop_front();
                    self.dropped += 1;
                }
                self.held
                    .push_back((now_s + self.settings.delay_s, self.public(s)));
            }
            UpstreamNews::History(points) => {
                // A (re)connected upstream tells the whole track again: it replaces ours.
                self.track.clear();
                self.held_track = points.into_iter().map(|p| self.public_point(p)).collect();
            }
            UpstreamNews::Other => {}
        }
    }

    /// The newest state due by `now_s`, if one came due since the last call: what the
    /// viewers are sent (the older ones due with it are only added to the track).
    pub fn due(&mut self, now_s: f64) -> Option<PublicStateMsg> {
        let mut newest = None;
        while self.held.front().is_some_and(|(at, _)| *at <= now_s) {
            let Some((_, s)) = self.held.pop_front() else {
                break;
            };
            self.show(&s);
            newest = Some(s);
        }
        if let Some(s) = &newest {
            self.shown = Some(s.clone());
        }
        newest
    }

    /// The newest state shown.
    pub fn latest(&self) -> Option<&PublicStateMsg> {
        self.shown.as_ref()
    }

    /// A new viewer's first message.
    pub fn history(&self) -> PublicHistoryMsg {
        PublicHistoryMsg {
            kind: "public_history".into(),
            track: self.track.clone(),
        }
    }

    /// The track shown.
    pub fn track(&self) -> &[PublicTrackPoint] {
        &self.track
    }

    /// States dropped because more were held than [`MAX_HELD`].
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    fn public(&self, mut s: PublicStateMsg) -> PublicStateMsg {
        let grid = self.grid(s.coarsen_m);
        if grid > s.coarsen_m {
            if let Some(p) = &mut s.position {
                (p.lat_deg, p.lon_deg) = snap(p.lat_deg, p.lon_deg, grid);
            }
            for q in [&mut s.landing, &mut s.target].into_iter().flatten() {
                *q = self.snap_point(*q, grid);
            }
        }
        s.coarsen_m = grid;
        s.delay_s += self.settings.delay_s;
        s
    }

    fn public_point(&self, mut p: PublicTrackPoint) -> PublicTrackPoint {
        (p.lat_deg, p.lon_deg) = snap(p.lat_deg, p.lon_deg, self.settings.coarsen_m);
        p
    }

    fn snap_point(&self, p: PublicPoint, grid: f64) -> PublicPoint {
        let (lat_deg, lon_deg) = snap(p.lat_deg, p.lon_deg, grid);
        PublicPoint { lat_deg, lon_deg }
    }

    /// The grid for a state already rounded to `upstream_m`: the coarser of the two.
    fn grid(&self, upstream_m: f64) -> f64 {
        self.settings.coarsen_m.max(upstream_m)
    }

    /// Adds a state shown to the track: first the upstream's history up to its mission time,
    /// then its own position, a point a second at most.
    fn show(&mut self, s: &PublicStateMsg) {
        let (Some(t), Some(p)) = (s.mission_time_s, s.position) else {
            return;
        };
        if self
            .track
            .last()
            .is_some_and(|last| last.mission_time_s - t > RESTART_STEP_BACK_S)
        {
            self.track.clear();
            self.held_track.clear();
        }
        while self
            .held_track
            .front()
            .is_some_and(|h| h.mission_time_s <= t)
        {
            if let Some(h) = self.held_track.pop_front() {
                self.push_track(h);
            }
        }
        if self
            .track
            .last()
            .is_none_or(|last| t - last.mission_time_s >= 1.0)
        {
            self.push_track(PublicTrackPoint {
                mission_time_s: t,
                lat_deg: p.lat_deg,
                lon_deg: p.lon_deg,
                alt_msl_m: p.alt_msl_m,
            });
        }
    }

    fn push_track(&mut self, p: PublicTrackPoint) {
        if self.track.len() >= MAX_TRACK {
            self.track.drain(..MAX_TRACK / 10);
        }
        self.track.push(p);
    }
}
