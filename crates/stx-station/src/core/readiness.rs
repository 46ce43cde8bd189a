//! The go/no-go board: the checks the station can work out itself from what it holds (the
//! link, the drone's GPS, plan, fence, parameters and battery, the recording, the forecast, the
//! last plan's reach), and the checklist file's manual items, each ticked by an operator with
//! who and when (said in the event log, so the recording keeps it). When the drone reports its
//! launch with checks open, the station says which in a warning every page shows.

use std::collections::BTreeMap;

use stx_gnc::mission::FlightStage;

use super::StationCore;
use super::sync::TargetSource;
use crate::checklist::{ChecklistItem, parse_checklist, parse_params};
use crate::keep_out::FenceState;
use crate::messages::{CheckStatus, CheckView, Level, ReadinessView, StateMsg};

/// A parameter equals its saved value within the wire's float32 rounding.
const PARAM_TOLERANCE: f64 = 1e-6;

/// A tick: who, and when (Unix ms).
#[derive(Debug, Clone)]
struct Tick {
    by: String,
    wall_ms: u64,
}

/// What the board remembers between states.
#[derive(Debug, Default)]
pub(crate) struct Readiness {
    items: Vec<ChecklistItem>,
    checklist_error: Option<String>,
    /// The saved parameter set; `Err` says why it is not there.
    saved_params: Option<Result<BTreeMap<String, f64>, String>>,
    ticks: BTreeMap<String, Tick>,
    /// Whether the daemon's recording is on; `None` where nothing records.
    recording_on: Option<bool>,
    /// The share of the last plan's samples that reach its target, 0…1.
    reach_share: Option<f64>,
    launched_with_open: Vec<String>,
}

/// Why a tick was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TickError {
    /// No checklist item has that id.
    #[error("the checklist has no item {0:?}")]
    UnknownItem(String),
}

fn check(id: &str, label: &str, status: CheckStatus, detail: String) -> CheckView {
    CheckView {
        id: id.into(),
        label: label.into(),
        manual: false,
        status,
        detail,
        ticked_by: None,
        ticked_wall_ms: None,
    }
}

fn go_if(ok: bool) -> CheckStatus {
    if ok {
        CheckStatus::Go
    } else {
        CheckStatus::NoGo
    }
}

impl StationCore {
    /// Takes the checklist file's text (or why it could not be read).
    pub fn load_checklist(&mut self, now_s: f64, file: &str, text: Result<String, String>) {
        match text.and_then(|t| parse_checklist(&t).map_err(|e| e.to_string())) {
            Ok(items) => {
                let n = items.len();
                self.readiness.items = items;
                self.readiness.checklist_error = None;
                self.log(
                    now_s,
                    Level::Info,
                    "readiness",
                    format!("checklist read from {file}: {n} items"),
                );
            }
            Err(reason) => {
                let reason = format!("checklist NOT read from {file}: {reason}");
                self.readiness.checklist_error = Some(reason.clone());
                self.log(now_s, Level::Error, "readiness", reason);
            }
        }
    }

    /// Takes the saved parameter set's text (or why it could not be read).
    pub fn load_saved_params(&mut self, now_s: f64, file: &str, text: Result<String, String>) {
        let parsed = text.and_then(|t| parse_params(&t).map_err(|e| e.to_string()));
        if let Err(reason) = &parsed {
            let text = format!("saved parameter set NOT read from {file}: {reason}");
            self.log(now_s, Level::Error, "readiness", text);
        }
        self.readiness.saved_params = Some(parsed);
    }

    /// The daemon says whether its recording is on.
    pub fn set_recording_on(&mut self, on: bool) {
        self.readiness.recording_on = Some(on);
    }

    /// The last plan made: the share of its samples from which steering reaches its target.
    pub fn note_plan_reach(&mut self, share: Option<f64>) {
        self.readiness.reach_share = share;
    }

    /// An operator ticks (or unticks) checklist item `id`; said in the event log.
    pub fn tick_checklist(
        &mut self,
        now_s: f64,
        who: &str,
        id: &str,
        ticked: bool,
    ) -> Result<(), TickError> {
        let Some(item) = self.readiness.items.iter().find(|i| i.id == id) else {
            return Err(TickError::UnknownItem(id.into()));
        };
        let text = item.text.clone();
        if ticked {
            let tick = Tick {
                by: who.into(),
                wall_ms: self.wall_ms(now_s),
            };
            self.readiness.ticks.insert(id.into(), tick);
        } else {
            self.readiness.ticks.remove(id);
        }
        let what = if ticked { "ticked" } else { "unticked" };
        self.log(
            now_s,
            Level::Info,
            "readiness",
            format!("checklist: \"{text}\" {what} by {who}"),
        );
        Ok(())
    }

    /// On a stage change: a launch with checks open is announced.
    pub(crate) fn readiness_on_stage(&mut self, now_s: f64, from: FlightStage, to: FlightStage) {
        if from != FlightStage::PreLaunch || to == FlightStage::PreLaunch {
            return;
        }
        let board = self.state_msg_now(now_s).readiness;
        let open: Vec<String> = board
            .checks
            .iter()
            .filter(|c| c.status != CheckStatus::Go)
            .map(|c| c.label.clone())
            .collect();
        if !open.is_empty() {
            let text = format!(
                "LAUNCHED with {} check(s) open: {}",
                open.len(),
                open.join("; ")
            );
            self.log(now_s, Level::Warning, "readiness", text);
        }
        self.readiness.launched_with_open = open;
    }

    /// The board for the state `s` the station is about to send.
    pub(crate) fn readiness_view(&self, s: &StateMsg) -> ReadinessView {
        let r = &self.readiness;
        let mut checks = self.station_checks(s);
        for item in &r.items {
            let tick = r.ticks.get(&item.id);
            checks.push(CheckView {
                id: item.id.clone(),
                label: item.text.clone(),
                manual: true,
                status: go_if(tick.is_some()),
                detail: match tick {
                    Some(t) => format!("ticked by {}", t.by),
                    None => "not ticked".into(),
                },
                ticked_by: tick.map(|t| t.by.clone()),
                ticked_wall_ms: tick.map(|t| t.wall_ms),
            });
        }
        let open = checks
            .iter()
            .filter(|c| c.status != CheckStatus::Go)
            .count();
        ReadinessView {
            checks,
            open: u32::try_from(open).unwrap_or(u32::MAX),
            launched_with_open: r.launched_with_open.clone(),
            checklist_error: r.checklist_error.clone(),
        }
    }

    fn station_checks(&self, s: &StateMsg) -> Vec<CheckView> {
        use CheckStatus::{Go, NoGo, Unknown};
        let r = &self.readiness;
        let config = &self.config.readiness;
        let heard = s.vehicle.as_ref().filter(|v| !v.stale);
        let link = {
            let (status, detail) = if !s.link.connected || s.link.stale {
                (NoGo, "no fresh telemetry".to_string())
            } else if !self.config.link.signing_on() {
                (NoGo, "up, but unsigned: no signing key configured".into())
            } else {
                (Go, format!("up and signed, {:.0} Hz", s.link.rate_hz))
            };
            check("link", "Link up and signed", status, detail)
        };
        let gps = {
            let fix = self.latest.gps.map(|(g, _)| g).filter(|_| heard.is_some());
            let (status, detail) = match fix {
                None => (Unknown, "no GPS heard".to_string()),
                Some(g) => (
                    go_if(g.has_3d_fix()),
                    format!(
                        "{:?}, {} satellites",
                        g.fix,
                        g.satellites.map_or("?".into(), |n| n.to_string())
                    ),
                ),
            };
            check("gps", "GPS 3-D fix", status, detail)
        };
        let plan = {
            let (status, detail) = match self.sync.target {
                Some(TargetSource::DronePlan) => (Go, "read back from the drone".to_string()),
                Some(TargetSource::Operator) => (
                    NoGo,
                    "sent and acknowledged, not read back from the drone yet".into(),
                ),
                Some(TargetSource::DroneTelemetry) => (
                    NoGo,
                    "known from its guidance telemetry only, the plan not read".into(),
                ),
                None => (Unknown, "the drone's plan is not known".into()),
            };
            check(
                "plan",
                "The drone's plan is the station's target",
                status,
                detail,
            )
        };
        let fence = {
            let view = self.fence.view();
            let (status, detail) = match view.state {
                FenceState::Held => (Go, "the drone holds the zones".to_string()),
                FenceState::None => (Go, "no zones configured".into()),
                FenceState::Waiting | FenceState::Sending => {
                    (NoGo, "not yet acknowledged by the drone".into())
                }
                FenceState::Failed => (
                    NoGo,
                    format!(
                        "the drone does not hold them: {}",
                        view.last_error.unwrap_or_default()
                    ),
                ),
            };
            check(
                "fence",
                "Keep-out zones held by the drone's fence",
                status,
                detail,
            )
        };
        let params = {
            let (status, detail) = match &r.saved_params {
                None => (
                    Unknown,
                    "no saved set configured (readiness.params_file)".to_string(),
                ),
                Some(Err(reason)) => (NoGo, reason.clone()),
                Some(Ok(_)) if !self.params.complete => {
                    (Unknown, "the drone's parameters are not read yet".into())
                }
                Some(Ok(saved)) => {
                    let differ: Vec<String> = saved
                        .iter()
                        .filter_map(|(name, want)| {
                            // Compared as f64, shown as the f32 the wire carries ("0.0145").
                            let have = self.params.values.get(name).map(|p| p.value);
                            match have.map(|v| (v, f64::from(v))) {
                                Some((_, v))
                                    if (v - want).abs()
                                        <= PARAM_TOLERANCE * want.abs().max(1.0) =>
                                {
                                    None
                                }
                                Some((shown, _)) => Some(format!("{name} {shown} (saved {want})")),
                                None => Some(format!("{name} missing")),
                            }
                        })
                        .collect();
                    if differ.is_empty() {
                        (Go, format!("{} equal the saved set", saved.len()))
                    } else {
                        (NoGo, differ.join(", "))
                    }
                }
            };
            check(
                "params",
                "Drone parameters equal the saved set",
                status,
                detail,
            )
        };
        let battery = {
            let volts = heard
                .and_then(|v| v.power.as_ref())
                .and_then(|p| p.voltage_v);
            let (status, detail) = match volts {
                None => (Unknown, "no battery reading".to_string()),
                Some(v) => (
                    go_if(v >= config.battery_min_v),
                    format!("{v:.2} V, at least {:.2} V", config.battery_min_v),
                ),
            };
            check("battery", "Battery", status, detail)
        };
        let recording = {
            let (status, detail) = match r.recording_on {
                Some(true) => (Go, "recording".to_string()),
                Some(false) => (NoGo, "not recording".into()),
                None => (Unknown, "nothing records here".into()),
            };
            check("recording", "Recording on", status, detail)
        };
        let forecast = check(
            "forecast",
            "Forecast loaded",
            go_if(!s.forecast_wind.is_empty()),
            format!("{} levels", s.forecast_wind.len()),
        );
        let reach = {
            let (status, detail) = match r.reach_share {
                None => (Unknown, "no plan made yet (Plan page)".to_string()),
                Some(share) => (
                    go_if(share >= config.reach_share_min),
                    format!(
                        "{:.0} % of the plan's samples reach the target, at least {:.0} %",
                        share * 100.0,
                        config.reach_share_min * 100.0
                    ),
                ),
            };
            check("reach", "The plan reaches its target", status, detail)
        };
        vec![
            link, gps, plan, fence, params, battery, recording, forecast, reach,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{core, hear_stage as stage};
    use super::*;

    const CHECKLIST: &str = "[[item]]\nid = \"chute\"\ntext = \"Round chute packed\"\n";

    fn status_of(board: &ReadinessView, id: &str) -> CheckStatus {
        board.checks.iter().find(|c| c.id == id).expect(id).status
    }

    #[test]
    fn a_ticked_item_is_go_with_who_and_when_and_said_in_the_log() {
        let mut core = core();
        core.load_checklist(0.0, "checklist.toml", Ok(CHECKLIST.into()));
        let board = core.state_msg_now(1.0).readiness;
        assert_eq!(status_of(&board, "chute"), CheckStatus::NoGo);
        assert_eq!(
            core.tick_checklist(2.0, "ana", "nope", true),
            Err(TickError::UnknownItem("nope".into()))
        );
        core.tick_checklist(2.0, "ana", "chute", true)
            .expect("known");
        let board = core.state_msg_now(3.0).readiness;
        let item = board.checks.iter().find(|c| c.id == "chute").expect("item");
        assert_eq!((item.status, item.manual), (CheckStatus::Go, true));
        assert_eq!(item.ticked_by.as_deref(), Some("ana"));
        assert_eq!(item.ticked_wall_ms, Some(core.wall_ms(2.0)));
        assert!(
            core.events
                .iter()
                .any(|e| e.text == "checklist: \"Round chute packed\" ticked by ana")
        );
        core.tick_checklist(4.0, "ben", "chute", false)
            .expect("known");
        assert_eq!(
            status_of(&core.state_msg_now(5.0).readiness, "chute"),
            CheckStatus::NoGo
        );
    }

    #[test]
    fn the_stations_own_checks_follow_what_it_holds() {
        let mut core = core();
        let board = core.state_msg_now(0.0).readiness;
        // Nothing heard: link no-go, GPS and battery unknown; the shipped forecast is loaded.
        assert_eq!(status_of(&board, "link"), CheckStatus::NoGo);
        assert_eq!(status_of(&board, "gps"), CheckStatus::Unknown);
        assert_eq!(status_of(&board, "forecast"), CheckStatus::Go);
        assert_eq!(status_of(&board, "recording"), CheckStatus::Unknown);
        core.set_recording_on(true);
        core.note_plan_reach(Some(0.85));
        let board = core.state_msg_now(0.0).readiness;
        assert_eq!(status_of(&board, "recording"), CheckStatus::Go);
        let reach = board
            .checks
            .iter()
            .find(|c| c.id == "reach")
            .expect("reach");
        assert_eq!(
            reach.status,
            CheckStatus::NoGo,
            "85 % is under the 90 % asked"
        );
        assert_eq!(
            board.open as usize,
            board
                .checks
                .iter()
                .filter(|c| c.status != CheckStatus::Go)
                .count()
        );
        core.load_saved_params(0.0, "flight.toml", Ok("GN_HK1 = 0.01\n".into()));
        let board = core.state_msg_now(0.0).readiness;
        assert_eq!(
            status_of(&board, "params"),
            CheckStatus::Unknown,
            "not read yet"
        );
        core.load_saved_params(0.0, "flight.toml", Err("No such file".into()));
        assert_eq!(
            status_of(&core.state_msg_now(0.0).readiness, "params"),
            CheckStatus::NoGo
        );
    }

    #[test]
    fn a_launch_with_checks_open_is_announced_once_with_them() {
        let mut core = core();
        core.load_checklist(0.0, "checklist.toml", Ok(CHECKLIST.into()));
        stage(&mut core, 1.0, FlightStage::PreLaunch);
        stage(&mut core, 2.0, FlightStage::Ascent);
        let board = core.state_msg_now(3.0).readiness;
        assert!(
            board
                .launched_with_open
                .contains(&"Round chute packed".to_string()),
            "{board:?}"
        );
        let warnings: Vec<_> = core
            .events
            .iter()
            .filter(|e| e.text.starts_with("LAUNCHED with"))
            .collect();
        assert_eq!(warnings.len(), 1);
        assert!(warnings[0].text.contains("Round chute packed"));
        // Later stages are not launches.
        stage(&mut core, 4.0, FlightStage::RoundChute);
        assert_eq!(
            core.events
                .iter()
                .filter(|e| e.text.starts_with("LAUNCHED"))
                .count(),
            1
        );
    }
}
