//! The files the subcommands read — scenarios, missions, vehicles, gains — by built-in name or
//! path. Every error here is the user's input ([`BadInput`], exit code 2).

use std::fs;
use std::path::Path;

use anyhow::Context;
use stx_dynamics::vehicle::Vehicle;
use stx_gnc::control::ControlGains;
use stx_gnc::performance::GlidePerformance;
use stx_sim::drone::MissionConfig;
use stx_sim::scenario::Scenario;

use crate::BadInput;

/// Whether `name_or_path` names a file rather than a built-in.
fn is_file(name_or_path: &str) -> bool {
    name_or_path.ends_with(".toml") || Path::new(name_or_path).exists()
}

fn read(what: &str, path: &Path) -> anyhow::Result<String> {
    fs::read_to_string(path)
        .with_context(|| format!("cannot read {what} {}", path.display()))
        .map_err(|e| BadInput(e).into())
}

/// A scenario by built-in name or path.
pub fn load_scenario(name_or_path: &str) -> anyhow::Result<Scenario> {
    if is_file(name_or_path) {
        let text = read("scenario file", Path::new(name_or_path))?;
        Scenario::from_toml_str(name_or_path, &text).map_err(|e| BadInput(e.into()).into())
    } else {
        Scenario::builtin(name_or_path).map_err(|e| BadInput(e.into()).into())
    }
}

/// A mission by built-in name or path.
pub fn load_mission(name_or_path: &str) -> anyhow::Result<MissionConfig> {
    if is_file(name_or_path) {
        let text = read("mission file", Path::new(name_or_path))?;
        MissionConfig::from_toml_str(name_or_path, &text).map_err(|e| BadInput(e.into()).into())
    } else {
        MissionConfig::builtin(name_or_path).map_err(|e| BadInput(e.into()).into())
    }
}

/// A vehicle file, or the shipped vehicle.
pub fn load_vehicle(path: Option<&Path>) -> anyhow::Result<Vehicle> {
    match path {
        None => Ok(Vehicle::straplex()),
        Some(path) => {
            let text = read("vehicle file", path)?;
            Vehicle::from_toml_str(&text)
                .with_context(|| format!("vehicle file {}", path.display()))
                .map_err(|e| BadInput(e).into())
        }
    }
}

/// The steady-glide table guidance plans with for the vehicle file `path`, trimmed at each of
/// the table's brake settings ([`stx_analysis::performance::glide_performance_of`]); `what`
/// names the file in errors (a flag, or "vehicle file"). A file that does not load, or a vehicle
/// with no steady glide at one of the settings, is [`BadInput`].
pub fn load_polar(what: &str, path: &Path) -> anyhow::Result<GlidePerformance> {
    let vehicle = load_vehicle(Some(path)).map_err(|e| match e.downcast::<BadInput>() {
        Ok(BadInput(e)) => BadInput(e.context(what.to_string())).into(),
        Err(e) => e.context(what.to_string()),
    })?;
    // The error's message holds its cause already: as text, so the chain is not printed twice.
    stx_analysis::performance::glide_performance_of(&vehicle)
        .map_err(|e| BadInput(anyhow::anyhow!("{what} {}: {e}", path.display())).into())
}

/// A gains file (`stx tune` writes them), validated.
pub fn load_gains(path: &Path) -> anyhow::Result<ControlGains> {
    let text = read("gains file", path)?;
    ControlGains::from_toml_str(&text)
        .with_context(|| format!("gains file {}", path.display()))
        .map_err(|e| BadInput(e).into())
}
