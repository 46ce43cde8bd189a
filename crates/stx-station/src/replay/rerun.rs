//! A re-run of a recording: the link bytes the station received go through a ground endpoint
//! and a station core of their own, on the recording's clock (mission time 0 at the
//! recording's first message, each datagram at its log time). What the core does then depends
//! on the recording alone, never on how fast it is played, nor on pauses: a paused replay
//! holds the state of its moment (nothing ages into stale), and a seek rebuilds the core by
//! running the same bytes from the start without pacing to the state a replay played through
//! has at that moment.
//!
//! [`Rerun`] stands in for what the link driver and the station loop do for a live station,
//! in the same order: each datagram into the endpoint, the endpoint's events into the core,
//! the core's link actions back into the endpoint and their outcomes into the core; a
//! telemetry burst answered by one tick of the core 1 ms (the loop's coalescing window) after
//! its first frame; every 250 ms the endpoint's statistics, and a tick if none came. What the
//! endpoint sends goes nowhere: nothing answers a replay. The drone's answers to the live
//! station's plan downloads are in the bytes, and [`PlanListener`] hands each plan the drone
//! told to the core when the live station got it, whether or not this endpoint's own
//! download (timed by this core) meets them.
//!
//! Landing predictions and footprints run beside it as they do live (the station loop's
//! timers); [`Rerun::settle`] computes them once at the end of a rebuild.

use std::time::Duration;

use stx_link::endpoint::{GroundConfig, GroundEndpoint, GroundEvent};
use stx_link::plan::{PlanEvent, PlanItem};
use stx_link::sansio::SansIo;
use stx_link::signing::SigningConfig;

use super::plan_listener::PlanListener;
use crate::config::StationConfig;
use crate::core::StationCore;
use crate::link::{LinkReport, StationLink};
use crate::messages::StateMsg;

/// Telemetry arriving within this of a burst's first frame is answered by one tick (the
/// station loop's `COALESCE`).
const COALESCE_NS: u64 = 1_000_000;
/// The station loop's state period: a tick in silence, and the link statistics.
const TIMER_NS: u64 = 250_000_000;

/// The recording's link bytes through a station core.
#[derive(Debug)]
pub struct Rerun {
    link: StationLink,
    plan: PlanListener,
    /// The recording's first log time, ns: mission time 0.
    origin_ns: u64,
    /// The first telemetry of a burst no tick has answered yet, ns.
    burst_from_ns: Option<u64>,
    /// When the statistics (and a tick, if none came) are next due, ns.
    next_timer_ns: u64,
    last_tick_ns: Option<u64>,
    /// The plan this endpoint's own download read, while the datagram that ended it is
    /// handled (the listener then has nothing to add).
    downloaded: Option<Vec<PlanItem>>,
}

impl Rerun {
    /// A re-run of a recording whose first log time is `origin_ns`, with `config`'s link
    /// (signing key included: the recorded frames are checked as the station checks them).
    pub fn new(config: &StationConfig, origin_ns: u64) -> Self {
        let mut ground = GroundConfig::default();
        // The daemon refuses to start a station whose key cannot be read, so it reads here.
        let key = config.link.signing_key().ok().flatten();
        let unix_now = Duration::from_nanos(origin_ns);
        ground.link = ground
            .link
            .with_signing(key.map(|k| SigningConfig::new(k, 0, unix_now)));
        let vehicle_system = ground.vehicle.0;
        Self {
            link: StationLink::new(GroundEndpoint::new(ground, Duration::ZERO)),
            plan: PlanListener::new(vehicle_system),
            origin_ns,
            burst_from_ns: None,
            next_timer_ns: origin_ns,
            last_tick_ns: None,
            downloaded: None,
        }
    }

    /// A core that has heard nothing of the recording, with `station`'s configuration and
    /// keep-out zones (the zones are the station's, not what it heard; their alarms are
    /// raised again by the predictions of the re-run).
    pub fn fresh_core(&self, station: &StationCore) -> StationCore {
        let mut core = StationCore::new(station.config().clone(), self.origin_ns / 1_000_000);
        let zones = &station.keep_out;
        core.keep_out.zones = zones.zones.clone();
        core.keep_out.geojson = zones.geojson.clone();
        core.keep_out.load_error = zones.load_error.clone();
        core.keep_out.changed_by = zones.changed_by.clone();
        core
    }

    /// The endpoint's clock and the mission time at log time `t_ns`.
    fn clock(&self, t_ns: u64) -> (Duration, f64) {
        let since = Duration::from_nanos(t_ns.saturating_sub(self.origin_ns));
        (since, since.as_secs_f64())
    }

    /// One datagram the station received at log time `t_ns`.
    pub fn received(&mut self, core: &mut StationCore, t_ns: u64, datagram: &[u8]) {
        let (now, now_s) = self.clock(t_ns);
        self.downloaded = None;
        self.link.handle_datagram_on(0, now, datagram);
        let telemetry = self.pump(core, t_ns);
        if let Some(items) = self.plan.received(datagram)
            && self.downloaded.take().as_ref() != Some(&items)
        {
            core.on_plan_downloaded(now_s, &items);
            self.pump(core, t_ns);
        }
        if telemetry && self.burst_from_ns.is_none() {
            self.burst_from_ns = Some(t_ns);
        }
    }

    /// The next log time something is due without a datagram (a burst to answer, the
    /// timers), ns.
    pub fn deadline(&self) -> u64 {
        self.burst_from_ns.map_or(self.next_timer_ns, |b| {
            (b + COALESCE_NS).min(self.next_timer_ns)
        })
    }

    /// Runs what is due at `t_ns` (at or after [`Rerun::deadline`]); the `state` when the
    /// core ticked.
    pub fn at(&mut self, core: &mut StationCore, t_ns: u64) -> Option<StateMsg> {
        let mut state = None;
        if self.burst_from_ns.is_some_and(|b| b + COALESCE_NS <= t_ns) {
            self.burst_from_ns = None;
            state = Some(self.tick(core, t_ns));
        }
        if t_ns >= self.next_timer_ns {
            while self.next_timer_ns <= t_ns {
                self.next_timer_ns += TIMER_NS;
            }
            let (now, _) = self.clock(t_ns);
            self.link.sample_stats(now);
            self.pump(core, t_ns);
            if self.last_tick_ns.is_none_or(|l| t_ns >= l + TIMER_NS) {
                state = Some(self.tick(core, t_ns));
            }
        }
        state
    }

    /// The end of a rebuild at `t_ns`: the statistics and the core as they are at that
    /// moment, with the landing prediction and the footprint a live station would have by
    /// then (it computes them off the telemetry path, once a second and every 2 s).
    pub fn settle(&mut self, core: &mut StationCore, t_ns: u64) -> StateMsg {
        let (now, now_s) = self.clock(t_ns);
        self.link.sample_stats(now);
        self.pump(core, t_ns);
        if let Some(job) = core.prediction_job() {
            core.set_prediction(job.run());
        }
        if let Some(job) = core.footprint_job(now_s) {
            core.set_footprint(job.run());
        }
        self.tick(core, t_ns)
    }

    fn tick(&mut self, core: &mut StationCore, t_ns: u64) -> StateMsg {
        let (_, now_s) = self.clock(t_ns);
        self.last_tick_ns = Some(t_ns);
        let state = core.tick(now_s);
        self.pump(core, t_ns);
        state
    }

    /// The endpoint's timers, its events into the core and the core's link actions into it,
    /// until both are quiet; whether telemetry came.
    fn pump(&mut self, core: &mut StationCore, t_ns: u64) -> bool {
        let (now, now_s) = self.clock(t_ns);
        if self.link.poll_timeout().is_some_and(|due| due <= now) {
            self.link.handle_timeout(now);
        }
        let mut telemetry = false;
        loop {
            let mut heard = false;
            while let Some(report) = self.link.poll_event() {
                heard = true;
                match report {
                    LinkReport::Event(event) => {
                        match &event {
                            GroundEvent::Telemetry { .. } => telemetry = true,
                            GroundEvent::Plan(PlanEvent::DownloadDone { items }) => {
                                self.downloaded = Some(items.clone());
                            }
                            _ => {}
                        }
                        core.on_link_event(now_s, event);
                    }
                    LinkReport::Outcome { id, result } => {
                        core.on_action_outcome(now_s, id, result);
                    }
                    LinkReport::Stats(stats) => core.set_link_stats(now_s, stats),
                }
            }
            let actions = core.take_link_actions(now_s);
            if actions.is_empty() && !heard {
                break;
            }
            for action in actions {
                self.link.apply(now, now_s, action);
            }
        }
        // Nothing answers a replay: what the station would send is dropped.
        while self.link.poll_transmit(now).is_some() {}
        telemetry
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::DEFAULT_STATION_TOML;
    use crate::replay::plan_listener::tests::drone_answers;

    const T0: u64 = 1_800_000_000_000_000_000;
    const MS: u64 = 1_000_000;

    #[test]
    fn a_plan_the_drone_told_unasked_is_flown_exactly() {
        // The drone's answers to a download this re-run's endpoint never asked for (another
        // station's, or one before this recording's first heartbeat): the replica adopts
        // them as the live station did, to the drone's degE7.
        let config = StationConfig::from_toml_str(DEFAULT_STATION_TOML).unwrap();
        let target = PlanItem::Land {
            lat_deg: 38.536_003_1,
            lon_deg: -7.860_227_8,
            alt_msl_m: 245.0,
            approach_heading_deg: None,
        };
        let mut rerun = Rerun::new(&config, T0);
        let mut core = rerun.fresh_core(&StationCore::new(config.clone(), 0));
        assert!(core.state_msg_now(0.0).guidance.unwrap().target.is_none());
        for (i, datagram) in drone_answers(1, vec![target]).iter().enumerate() {
            rerun.received(&mut core, T0 + i as u64 * MS, datagram);
        }
        let state = rerun.settle(&mut core, T0 + 10 * MS);
        assert_eq!(state.time_s, 0.01, "on the recording's clock");
        let guidance = state.guidance.unwrap();
        assert_eq!(guidance.target_source, Some("drone_plan"));
        let adopted = guidance.target.unwrap();
        assert!((adopted.lat_deg - 38.536_003_1).abs() < 1e-9, "{adopted:?}");
        assert!((adopted.lon_deg + 7.860_227_8).abs() < 1e-9, "{adopted:?}");
    }

    #[test]
    fn bursts_are_answered_a_millisecond_on_and_silence_every_quarter_second() {
        let config = StationConfig::from_toml_str(DEFAULT_STATION_TOML).unwrap();
        let mut rerun = Rerun::new(&config, T0);
        let mut core = rerun.fresh_core(&StationCore::new(config.clone(), 0));
        assert_eq!(rerun.deadline(), T0, "the timers from the start");
        assert!(rerun.at(&mut core, T0).is_some(), "a tick in silence");
        assert_eq!(rerun.deadline(), T0 + 250 * MS);
        let mut encoder = stx_link::frame::FrameEncoder::new(1, 1);
        let mut datagram = Vec::new();
        let sample = stx_link::fixtures::telemetry_sample(0).to_mavlink();
        encoder.encode_into(Duration::ZERO, &sample, &mut datagram);
        rerun.received(&mut core, T0 + 100 * MS, &datagram);
        assert_eq!(rerun.deadline(), T0 + 101 * MS, "the burst's answer");
        let state = rerun.at(&mut core, T0 + 101 * MS).expect("a tick");
        assert_eq!(state.time_s, 0.101);
        assert!(state.vehicle.is_some(), "the telemetry is in");
        assert_eq!(rerun.deadline(), T0 + 250 * MS);
        assert!(
            rerun.at(&mut core, T0 + 250 * MS).is_none(),
            "no tick in silence within 250 ms of the last"
        );
    }
}
