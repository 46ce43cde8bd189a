//! The keep-out zones in the station: held in the mission's local frame for the checks and as
//! the GeoJSON the operators wrote for the pages; set from the configured file at start or by
//! an operator's edit (checked here, written to the file by the adapter before it is applied);
//! asked whether a landing target lies in a zone; and watched against the landing predictions,
//! raising an alarm when one comes down in a zone.
//!
//! An alarm is logged once as a warning when a prediction enters a zone and once as an info
//! when it has stayed out of every zone for [`CLEAR_AFTER_S`]: a prediction wandering along a
//! zone's edge (its noise, or the uncontrolled glide turning with the spiral) does not fill
//! the log with pairs of messages, and the alarm is not dropped on one lucky sample.

use serde_json::Value;
use stx_gnc::keep_out::{KeepOutZone, KeepOutZones, from_geojson};

use super::StationCore;
use super::requests::ApiError;
use crate::keep_out::{KeepOutAlarmView, KeepOutMsg, PredictionKind};
use crate::messages::Level;

/// Seconds a prediction must stay out of every zone before its alarm clears, s.
pub const CLEAR_AFTER_S: f64 = 5.0;
/// Most features an edit may hold.
const MAX_FEATURES: usize = 100;
/// Longest zone name, characters.
const MAX_NAME_CHARS: usize = 80;

/// The zones in force and the alarms they raised.
#[derive(Debug, Clone)]
pub(crate) struct KeepOut {
    pub zones: KeepOutZones,
    /// The FeatureCollection as set.
    pub geojson: Value,
    /// Why the configured file was not read at start.
    pub load_error: Option<String>,
    pub changed_by: Option<String>,
    alarms: Vec<Alarm>,
}

impl Default for KeepOut {
    fn default() -> Self {
        Self {
            zones: KeepOutZones::default(),
            geojson: empty_collection(),
            load_error: None,
            changed_by: None,
            alarms: Vec::new(),
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
struct Alarm {
    prediction: PredictionKind,
    zone: String,
    since_s: f64,
    /// Since when the prediction has been out of every zone.
    outside_since_s: Option<f64>,
}

fn empty_collection() -> Value {
    serde_json::json!({"type": "FeatureCollection", "features": []})
}

/// Zones an operator sent, checked: ready to be written to the file and applied.
#[derive(Debug, Clone)]
pub struct CheckedZones {
    zones: KeepOutZones,
    geojson: Value,
}

impl CheckedZones {
    /// The file's new content: pretty GeoJSON, one trailing newline.
    pub fn file_text(&self) -> String {
        let mut text = serde_json::to_string_pretty(&self.geojson).unwrap_or_default();
        text.push('\n');
        text
    }
}

/// Every feature named (the name is how operators, the log and the refusals speak of a zone).
fn check_names(geojson: &Value) -> Result<Vec<String>, ApiError> {
    if geojson.get("type").and_then(Value::as_str) != Some("FeatureCollection") {
        return Err(ApiError::bad_request(
            "keep-out zones must be a GeoJSON FeatureCollection",
        ));
    }
    let Some(features) = geojson.get("features").and_then(Value::as_array) else {
        return Err(ApiError::bad_request(
            "keep-out zones: `features` must be an array",
        ));
    };
    if features.len() > MAX_FEATURES {
        return Err(ApiError::bad_request(format!(
            "keep-out zones: at most {MAX_FEATURES} features"
        )));
    }
    let mut names = Vec::new();
    for (i, f) in features.iter().enumerate() {
        let name = f
            .pointer("/properties/name")
            .and_then(Value::as_str)
            .map(str::trim)
            .unwrap_or_default();
        if name.is_empty() {
            return Err(ApiError::bad_request(format!(
                "keep-out feature {i}: a zone needs a name (properties.name)"
            )));
        }
        if name.chars().count() > MAX_NAME_CHARS {
            return Err(ApiError::bad_request(format!(
                "keep-out feature {i}: names are at most {MAX_NAME_CHARS} characters"
            )));
        }
        names.push(name.to_string());
    }
    Ok(names)
}

fn names_of(zones: &KeepOutZones) -> String {
    let mut names: Vec<&str> = zones.zones.iter().map(|z| z.name.as_str()).collect();
    names.dedup();
    if names.is_empty() {
        "none".into()
    } else {
        names
            .iter()
            .map(|n| format!("'{n}'"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl StationCore {
    /// The zones in force.
    pub fn keep_out_zones(&self) -> &KeepOutZones {
        &self.keep_out.zones
    }

    /// Takes the configured file's content read at start (`text`), or why it could not be
    /// read; a file that is not valid zones is refused with the reason, logged as an error
    /// and shown on every page, and the station runs on without zones.
    pub fn load_keep_out(&mut self, now_s: f64, file: &str, text: Result<String, String>) {
        let parsed = text.and_then(|text| {
            let geojson: Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
            let zones = from_geojson(&text, &self.frame).map_err(|e| e.to_string())?;
            Ok((zones, geojson))
        });
        match parsed {
            Ok((zones, geojson)) => {
                let text = format!(
                    "keep-out zones read from {file}: {} ({} areas)",
                    names_of(&zones),
                    zones.zones.len()
                );
                self.keep_out = super::keep_out::KeepOut {
                    zones,
                    geojson,
                    ..Default::default()
                };
                self.log(now_s, Level::Info, "keep_out", text);
                self.fence_changed(now_s);
            }
            Err(reason) => {
                let reason = format!("keep-out zones NOT loaded from {file}: {reason}");
                self.keep_out = KeepOut {
                    load_error: Some(reason.clone()),
                    ..Default::default()
                };
                self.log(now_s, Level::Error, "keep_out", reason);
            }
        }
        let msg = self.keep_out_msg(now_s);
        self.outbound.push(super::Outbound::KeepOut(msg));
    }

    /// Checks zones an operator sent: a FeatureCollection of named Polygons and MultiPolygons
    /// on the globe, with closed rings.
    pub fn check_keep_out(&self, geojson: Value) -> Result<CheckedZones, ApiError> {
        check_names(&geojson)?;
        let text = serde_json::to_string(&geojson).unwrap_or_default();
        let zones =
            from_geojson(&text, &self.frame).map_err(|e| ApiError::bad_request(e.to_string()))?;
        Ok(CheckedZones { zones, geojson })
    }

    /// Puts zones an operator sent in force (`saved`: written to the configured file);
    /// logged with who and what changed, and sent to every page.
    pub fn set_keep_out(
        &mut self,
        now_s: f64,
        who: &str,
        checked: CheckedZones,
        saved: Option<&str>,
    ) -> KeepOutMsg {
        let before: Vec<String> = self
            .keep_out
            .zones
            .zones
            .iter()
            .map(|z| z.name.clone())
            .collect();
        let after: Vec<String> = checked.zones.zones.iter().map(|z| z.name.clone()).collect();
        let added: Vec<&String> = after.iter().filter(|n| !before.contains(n)).collect();
        let removed: Vec<&String> = before.iter().filter(|n| !after.contains(n)).collect();
        let list = |v: &[&String]| {
            v.iter()
                .map(|n| format!("'{n}'"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let mut what = Vec::new();
        if !added.is_empty() {
            what.push(format!("added {}", list(&added)));
        }
        if !removed.is_empty() {
            what.push(format!("removed {}", list(&removed)));
        }
        if what.is_empty() {
            what.push("changed".into());
        }
        let kept = match saved {
            Some(file) => format!("saved to {file}"),
            None => {
                "not kept across a restart: the station config names no keep_out file".to_string()
            }
        };
        let text = format!(
            "{who}: keep-out zones {}; now {} ({kept})",
            what.join(", "),
            names_of(&checked.zones)
        );
        self.keep_out.zones = checked.zones;
        self.keep_out.geojson = checked.geojson;
        self.keep_out.changed_by = Some(who.to_string());
        self.keep_out.load_error = None;
        let level = if saved.is_some() {
            Level::Info
        } else {
            Level::Warning
        };
        self.log(now_s, level, "keep_out", text);
        self.fence_changed(now_s);
        self.watch_keep_out(now_s);
        let msg = self.keep_out_msg(now_s);
        self.outbound.push(super::Outbound::KeepOut(msg.clone()));
        msg
    }

    /// The `keep_out` message.
    pub fn keep_out_msg(&self, now_s: f64) -> KeepOutMsg {
        KeepOutMsg {
            kind: "keep_out",
            zones: self.keep_out.geojson.clone(),
            areas: u32::try_from(self.keep_out.zones.zones.len()).unwrap_or(u32::MAX),
            file: self
                .config
                .keep_out
                .as_ref()
                .map(|p| p.display().to_string()),
            load_error: self.keep_out.load_error.clone(),
            changed_by: self.keep_out.changed_by.clone(),
            fence: self.fence.view(),
            time_s: now_s,
        }
    }

    /// The zone a landing point (north, east, m) lies in.
    pub(crate) fn keep_out_zone_at(&self, ne: [f64; 2]) -> Option<&KeepOutZone> {
        self.keep_out.zones.zone_at(ne)
    }

    /// The predicted landings in a zone now, for the `state` message.
    pub(crate) fn keep_out_alarms(&self) -> Vec<KeepOutAlarmView> {
        self.keep_out
            .alarms
            .iter()
            .map(|a| KeepOutAlarmView {
                prediction: a.prediction,
                zone: a.zone.clone(),
                since_s: a.since_s,
            })
            .collect()
    }

    /// Compares the newest predictions with the zones: an alarm is raised (a warning) when one
    /// enters a zone, and cleared (an info) once it has stayed out for [`CLEAR_AFTER_S`].
    pub(crate) fn watch_keep_out(&mut self, now_s: f64) {
        let plan_known = self.plan_known_for(self.guidance.mode());
        let points = self.prediction.map(|p| {
            [
                (
                    PredictionKind::Planned,
                    plan_known.then_some(p.planned.position_ne_m),
                ),
                (
                    PredictionKind::Uncontrolled,
                    Some(p.uncontrolled.position_ne_m),
                ),
            ]
        });
        for (kind, point) in points.into_iter().flatten() {
            let hit = point
                .and_then(|ne| self.keep_out_zone_at(ne))
                .map(|z| z.name.clone());
            let index = self
                .keep_out
                .alarms
                .iter()
                .position(|a| a.prediction == kind);
            match (hit, index) {
                (Some(zone), Some(i)) if self.keep_out.alarms[i].zone == zone => {
                    self.keep_out.alarms[i].outside_since_s = None;
                }
                (Some(zone), index) => {
                    if let Some(i) = index {
                        self.keep_out.alarms.remove(i);
                    }
                    self.keep_out.alarms.push(Alarm {
                        prediction: kind,
                        zone: zone.clone(),
                        since_s: now_s,
                        outside_since_s: None,
                    });
                    self.log(
                        now_s,
                        Level::Warning,
                        "keep_out",
                        format!(
                            "{} landing predicted inside keep-out zone '{zone}'",
                            kind.name()
                        ),
                    );
                }
                (None, Some(i)) => {
                    let alarm = &mut self.keep_out.alarms[i];
                    let outside = *alarm.outside_since_s.get_or_insert(now_s);
                    if now_s - outside >= CLEAR_AFTER_S {
                        let alarm = self.keep_out.alarms.remove(i);
                        self.log(
                            now_s,
                            Level::Info,
                            "keep_out",
                            format!(
                                "{} landing prediction clear of keep-out zone '{}'",
                                kind.name(),
                                alarm.zone
                            ),
                        );
                    }
                }
                (None, None) => {}
            }
        }
    }
}

#[cfg(test)]
#[path = "keep_out_tests.rs"]
pub(super) mod tests;
