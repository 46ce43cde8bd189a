//! `[recording]` of the station's TOML: whether and where the station records its runs, and
//! when a file is closed and the next one started.

use std::path::PathBuf;
use std::time::Duration;

use serde::{Deserialize, Serialize};

/// The station's recording settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordingSettings {
    /// Record every run of the station (MCAP files). Default: on.
    #[serde(default = "default_enabled")]
    pub enabled: bool,
    /// Directory of the recordings. Default: `recordings/` in the station's state directory
    /// (`$STATE_DIRECTORY`, `$XDG_STATE_HOME/stx` or `~/.local/state/stx`), filled in by
    /// `stx serve` from the environment; `stx serve --record-dir DIR` overrides it.
    #[serde(default)]
    pub dir: Option<PathBuf>,
    /// The vehicle flown, as the recordings' metadata names it (e.g. `STRAPLEX drone 2`).
    #[serde(default = "default_vehicle")]
    pub vehicle: String,
    /// The mission, as the recordings' metadata names it. Default: the station's `name`.
    #[serde(default)]
    pub mission: Option<String>,
    /// A file is closed and the next one started once it holds this much, MB (10⁶ B).
    #[serde(default = "default_max_file_mb")]
    pub max_file_mb: u64,
    /// … or once it has been open this long, hours.
    #[serde(default = "default_max_file_hours")]
    pub max_file_hours: f64,
}

fn default_enabled() -> bool {
    true
}

fn default_vehicle() -> String {
    "unnamed".into()
}

fn default_max_file_mb() -> u64 {
    1000
}

fn default_max_file_hours() -> f64 {
    12.0
}

impl Default for RecordingSettings {
    fn default() -> Self {
        Self {
            enabled: default_enabled(),
            dir: None,
            vehicle: default_vehicle(),
            mission: None,
            max_file_mb: default_max_file_mb(),
            max_file_hours: default_max_file_hours(),
        }
    }
}

impl RecordingSettings {
    /// The first rule broken, as `(field, rule)`.
    pub fn check(&self) -> Result<(), (&'static str, &'static str)> {
        if !(1..=1_000_000).contains(&self.max_file_mb) {
            return Err(("recording.max_file_mb", "from 1 to 1000000 MB"));
        }
        if !(self.max_file_hours > 0.0 && self.max_file_hours <= 24.0 * 7.0) {
            return Err(("recording.max_file_hours", "in (0, 168] hours"));
        }
        if self.dir.as_ref().is_some_and(|d| d.as_os_str().is_empty()) {
            return Err(("recording.dir", "a directory path (or leave it out)"));
        }
        Ok(())
    }

    /// File size limit, B.
    pub fn max_file_bytes(&self) -> u64 {
        self.max_file_mb.saturating_mul(1_000_000)
    }

    /// File duration limit.
    pub fn max_file_duration(&self) -> Duration {
        Duration::from_secs_f64(self.max_file_hours * 3600.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_limits_are_checked() {
        let ok = RecordingSettings::default();
        assert_eq!(ok.check(), Ok(()));
        assert_eq!(ok.max_file_bytes(), 1_000_000_000);
        assert_eq!(ok.max_file_duration(), Duration::from_secs(12 * 3600));
        let bad = |edit: fn(&mut RecordingSettings)| {
            let mut s = RecordingSettings::default();
            edit(&mut s);
            s.check().unwrap_err().0
        };
        assert_eq!(bad(|s| s.max_file_mb = 0), "recording.max_file_mb");
        assert_eq!(bad(|s| s.max_file_hours = 0.0), "recording.max_file_hours");
        assert_eq!(
            bad(|s| s.max_file_hours = f64::NAN),
            "recording.max_file_hours"
        );
        assert_eq!(bad(|s| s.dir = Some(PathBuf::new())), "recording.dir");
    }
}
