//! What the go/no-go board is configured with (`[readiness]` in the station file): its
//! thresholds, the checklist file of manual items and the saved parameter set the drone's must
//! equal. The two files are read at start by the daemon and parsed here; a missing or broken
//! one leaves its checks open with the reason, it does not stop the station (see
//! `core/readiness.rs`).

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// `[readiness]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReadinessConfig {
    /// The checklist of manual items (TOML: `[[item]]` with `id` and `text`), relative to the
    /// working directory. Absent: the board has the station's own checks only.
    #[serde(default)]
    pub checklist: Option<PathBuf>,
    /// A saved parameter set (TOML: `NAME = value`, e.g. `GN_HK1 = 0.00661`) the drone's
    /// parameters must equal before launch. Absent: that check stays open, "none saved".
    #[serde(default)]
    pub params_file: Option<PathBuf>,
    /// The drone's battery must read at least this, V.
    #[serde(default = "default_battery_min_v")]
    pub battery_min_v: f64,
    /// The last plan made (Plan page) must reach its target from at least this share of its
    /// dispersed samples, 0…1.
    #[serde(default = "default_reach_share_min")]
    pub reach_share_min: f64,
}

fn default_battery_min_v() -> f64 {
    11.5
}

fn default_reach_share_min() -> f64 {
    0.9
}

impl Default for ReadinessConfig {
    fn default() -> Self {
        Self {
            checklist: None,
            params_file: None,
            battery_min_v: default_battery_min_v(),
            reach_share_min: default_reach_share_min(),
        }
    }
}

impl ReadinessConfig {
    /// The rule a field breaks, as `(field, rule)`.
    pub fn invalid(&self) -> Option<(&'static str, &'static str)> {
        if !(self.battery_min_v.is_finite() && self.battery_min_v >= 0.0) {
            return Some(("readiness.battery_min_v", "a voltage of 0 V or more"));
        }
        if !(0.0..=1.0).contains(&self.reach_share_min) {
            return Some(("readiness.reach_share_min", "a share from 0 to 1"));
        }
        None
    }
}

/// One manual item of the checklist.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChecklistItem {
    /// Stable name, what a tick refers to: letters, digits, `_` and `-`.
    pub id: String,
    /// What the operator confirms.
    pub text: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ChecklistFile {
    #[serde(default)]
    item: Vec<ChecklistItem>,
}

/// Why a readiness file was refused.
#[derive(Debug, thiserror::Error)]
pub enum ChecklistError {
    /// Not TOML of the expected shape.
    #[error("not a valid file: {0}")]
    Parse(#[from] toml::de::Error),
    /// An item breaks a rule.
    #[error("item {index}: {rule}")]
    Item {
        /// 1-based, in the file's order.
        index: usize,
        /// The rule.
        rule: String,
    },
    /// A saved parameter is not a finite number.
    #[error("parameter {0}: not a finite number")]
    Param(String),
}

/// The items of a checklist file, in its order.
pub fn parse_checklist(text: &str) -> Result<Vec<ChecklistItem>, ChecklistError> {
    let file: ChecklistFile = toml::from_str(text)?;
    let mut seen = std::collections::HashSet::new();
    for (i, item) in file.item.iter().enumerate() {
        let rule = |rule: String| ChecklistError::Item { index: i + 1, rule };
        let id_ok = !item.id.is_empty()
            && item
                .id
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        if !id_ok {
            return Err(rule(format!(
                "id {:?} must be letters, digits, _ or -",
                item.id
            )));
        }
        if item.text.trim().is_empty() {
            return Err(rule("text must not be empty".into()));
        }
        if !seen.insert(item.id.as_str()) {
            return Err(rule(format!("id {:?} is used twice", item.id)));
        }
    }
    Ok(file.item)
}

/// The values of a saved parameter set, by name.
pub fn parse_params(text: &str) -> Result<BTreeMap<String, f64>, ChecklistError> {
    let values: BTreeMap<String, f64> = toml::from_str(text)?;
    match values.iter().find(|(_, v)| !v.is_finite()) {
        Some((name, _)) => Err(ChecklistError::Param(name.clone())),
        None => Ok(values),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_checklist_keeps_its_order_and_refuses_bad_or_repeated_ids() {
        let items = parse_checklist(
            "[[item]]\nid = \"chute\"\ntext = \"Round chute packed\"\n[[item]]\nid = \"notam\"\ntext = \"NOTAM filed\"\n",
        )
        .expect("valid");
        assert_eq!(
            items.iter().map(|i| i.id.as_str()).collect::<Vec<_>>(),
            ["chute", "notam"]
        );
        let twice = "[[item]]\nid = \"a\"\ntext = \"x\"\n[[item]]\nid = \"a\"\ntext = \"y\"\n";
        assert_eq!(
            parse_checklist(twice).unwrap_err().to_string(),
            "item 2: id \"a\" is used twice"
        );
        let spaced = "[[item]]\nid = \"a b\"\ntext = \"x\"\n";
        assert!(parse_checklist(spaced).is_err());
        let empty = "[[item]]\nid = \"a\"\ntext = \" \"\n";
        assert!(parse_checklist(empty).is_err());
        assert!(
            parse_checklist("[[item]]\nid = \"a\"\n").is_err(),
            "no text"
        );
    }

    #[test]
    fn a_saved_parameter_set_is_names_and_finite_numbers() {
        let p = parse_params("GN_HK1 = 0.00661\nMIS_DEPLOY_M = 1200\n").expect("valid");
        assert_eq!(p["MIS_DEPLOY_M"], 1200.0);
        assert!(parse_params("GN_HK1 = nan\n").is_err());
        assert!(parse_params("GN_HK1 = \"x\"\n").is_err());
    }

    #[test]
    fn thresholds_are_checked() {
        let mut c = ReadinessConfig::default();
        assert_eq!(c.invalid(), None);
        c.reach_share_min = 1.5;
        assert_eq!(
            c.invalid().map(|(f, _)| f),
            Some("readiness.reach_share_min")
        );
    }
}
