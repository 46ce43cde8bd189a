//! A forecast file as forecast rows: GFS GRIB2 files or a radiosonde sounding
//! (`stx_weather`) read down to the wind-versus-altitude rows the planner and the station fly
//! through, for `stx plan --gfs`/`--sounding` and the station's `[forecast_file]`.
//!
//! The planner takes one profile over altitude (`stx_gnc::flight_path::Forecast`), not a wind
//! that changes along the flight: a GFS field is taken at one instant (the launch time, or
//! the first forecast hour) over the launch site, and its levels become the rows. The wind
//! the balloon meets two hours later and 100 km downwind differs from that; the plan's wind
//! spread (`default_wind_sigma_mps`, which these rows leave to the planner) is what covers it.
//!
//! The files are read here (`std::fs`, no tokio), once, before anything starts.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use stx_gnc::flight_path::ForecastRow;
use stx_weather::{GfsField, OffsetDateTime, Sounding, WindLevel};

/// `[forecast_file]` of the station config: one forecast file in place of `forecast_wind`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForecastFileConfig {
    /// GRIB2 files of one GFS run (`pgrb2` 0.25° or 0.5°, whole or a NOMADS filter subset
    /// with `UGRD`, `VGRD` and `HGT` on isobaric levels around the launch site), paths as the
    /// station is started from. Empty: `sounding` instead.
    #[serde(default)]
    pub gfs: Vec<PathBuf>,
    /// The instant the GFS wind is taken at, RFC 3339 (`2026-11-30T12:00:00Z`), within the
    /// files' forecast hours; absent: their first forecast time.
    #[serde(default)]
    pub valid_time: Option<String>,
    /// A radiosonde sounding, University of Wyoming `TEXT:LIST` text; only without `gfs`.
    #[serde(default)]
    pub sounding: Option<PathBuf>,
}

impl ForecastFileConfig {
    /// The first rule it breaks, as `(field under forecast_file, rule)`.
    pub fn invalid(&self) -> Option<(&'static str, String)> {
        match (self.gfs.is_empty(), &self.sounding) {
            (true, None) => return Some(("gfs", "name GFS files or a sounding".into())),
            (false, Some(_)) => {
                return Some(("sounding", "give GFS files or a sounding, not both".into()));
            }
            _ => {}
        }
        if let Some(t) = &self.valid_time {
            if self.gfs.is_empty() {
                return Some((
                    "valid_time",
                    "only with gfs (a sounding is one instant)".into(),
                ));
            }
            if let Err(e) = stx_weather::parse_time(t) {
                return Some(("valid_time", format!("an RFC 3339 time: {e}")));
            }
        }
        None
    }

    /// Reads the files and gives their rows at the launch site `lat_deg`, `lon_deg`; the
    /// message names the file and what is wrong with it.
    pub fn rows(&self, lat_deg: f64, lon_deg: f64) -> Result<Vec<ForecastRow>, String> {
        if let Some((field, rule)) = self.invalid() {
            return Err(format!("forecast_file.{field}: {rule}"));
        }
        if let Some(path) = &self.sounding {
            return read_sounding(path);
        }
        let at = self
            .valid_time
            .as_deref()
            .map(stx_weather::parse_time)
            .transpose()
            .map_err(|e| format!("forecast_file.valid_time: {e}"))?;
        let field = read_gfs(&self.gfs)?;
        gfs_rows(&field, lat_deg, lon_deg, at)
    }
}

/// The wind field of GRIB2 `files` (one GFS run), read from disk.
pub fn read_gfs(files: &[PathBuf]) -> Result<GfsField, String> {
    let bytes = files
        .iter()
        .map(|p| {
            std::fs::read(p)
                .map(|b| (p.display().to_string(), b))
                .map_err(|e| format!("cannot read the GFS file {}: {e}", p.display()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    GfsField::from_files(bytes.iter().map(|(n, b)| (n.as_str(), b.as_slice())))
        .map_err(|e| e.to_string())
}

/// The rows of `field` over `lat_deg`, `lon_deg` at `at` (default: its first forecast time).
pub fn gfs_rows(
    field: &GfsField,
    lat_deg: f64,
    lon_deg: f64,
    at: Option<OffsetDateTime>,
) -> Result<Vec<ForecastRow>, String> {
    let at = at.unwrap_or_else(|| field.valid_times()[0]);
    let levels = field
        .profile(lat_deg, lon_deg, at)
        .map_err(|e| e.to_string())?;
    Ok(rows(&levels))
}

/// The rows of the sounding in the file at `path`.
pub fn read_sounding(path: &Path) -> Result<Vec<ForecastRow>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read the sounding {}: {e}", path.display()))?;
    let sounding = Sounding::parse(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(rows(&sounding.levels))
}

/// Wind levels as forecast rows, each without a sigma (the planner's default applies).
pub fn rows(levels: &[WindLevel]) -> Vec<ForecastRow> {
    levels
        .iter()
        .map(|l| ForecastRow {
            alt_msl_m: l.alt_msl_m,
            speed_mps: l.speed_mps(),
            from_deg: l.from_deg(),
            sigma_mps: None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::StationConfig;

    fn testdata(name: &str) -> String {
        format!(
            "{}/../stx-weather/testdata/{name}",
            env!("CARGO_MANIFEST_DIR")
        )
    }

    /// The shipped config without its `[[forecast_wind]]` rows, and `forecast_file` after it.
    fn config_with(forecast_file: &str) -> String {
        let mut in_rows = false;
        let mut text = String::new();
        for line in crate::config::DEFAULT_STATION_TOML.lines() {
            in_rows = line.starts_with("[[forecast_wind]]") || (in_rows && !line.is_empty());
            if !in_rows {
                text.push_str(line);
                text.push('\n');
            }
        }
        format!("{text}\n{forecast_file}")
    }

    #[test]
    fn a_configured_gfs_file_becomes_the_forecast_wind_over_the_origin() {
        let toml = config_with(&format!(
            "[forecast_file]\ngfs = [\"{}\"]\nvalid_time = \"2026-11-30T07:30:00Z\"\n",
            testdata("gfs_0p25_subset.grib2")
        ));
        let mut config = StationConfig::from_toml_str(&toml).unwrap();
        // The file's box is 36–40° N, 10–5° W; the shipped origin is Évora, 38.5° N 7.9° W.
        config.origin.lat_deg = 38.0;
        config.origin.lon_deg = -8.0;
        assert!(config.forecast_wind.is_empty());
        config.load_forecast_file().unwrap();
        config.validate().unwrap();
        assert_eq!(config.forecast_wind.len(), 11);
        let field = read_gfs(&[PathBuf::from(testdata("gfs_0p25_subset.grib2"))]).unwrap();
        let at = stx_weather::parse_time("2026-11-30T07:30:00Z").unwrap();
        assert_eq!(
            config.forecast_wind,
            gfs_rows(&field, 38.0, -8.0, Some(at)).unwrap()
        );
    }

    #[test]
    fn bad_forecast_file_settings_are_refused_naming_the_field() {
        let gfs = testdata("gfs_0p25_subset.grib2");
        let cases = [
            ("[forecast_file]\n".to_string(), "forecast_file.gfs"),
            (
                format!("[forecast_file]\ngfs = [\"{gfs}\"]\nsounding = \"s.txt\"\n"),
                "forecast_file.sounding",
            ),
            (
                format!("[forecast_file]\ngfs = [\"{gfs}\"]\nvalid_time = \"noon\"\n"),
                "forecast_file.valid_time",
            ),
            (
                "[forecast_file]\nsounding = \"s.txt\"\nvalid_time = \"2026-11-30T07:30:00Z\"\n"
                    .to_string(),
                "forecast_file.valid_time",
            ),
        ];
        for (table, field) in cases {
            let e = StationConfig::from_toml_str(&config_with(&table))
                .unwrap_err()
                .to_string();
            assert!(e.contains(field), "{table}: {e}");
        }
        // With the shipped rows too: which one holds is ambiguous.
        let both = format!(
            "{}\n[forecast_file]\ngfs = [\"{gfs}\"]\n",
            crate::config::DEFAULT_STATION_TOML
        );
        let e = StationConfig::from_toml_str(&both).unwrap_err().to_string();
        assert!(e.contains("not both"), "{e}");
        // A launch site outside the file's box.
        let mut far = StationConfig::from_toml_str(&config_with(&format!(
            "[forecast_file]\ngfs = [\"{gfs}\"]\n"
        )))
        .unwrap();
        far.origin.lat_deg = 45.0;
        let e = far.load_forecast_file().unwrap_err().to_string();
        assert!(
            e.contains("forecast_file") && e.contains("outside the file's box"),
            "{e}"
        );
    }
}
