//! The files the subcommands read — scenarios, missions, vehicles, gains — by built-in name or
//! path. Every error here is the user's input ([`BadInput`], exit code 2).

use std::fs;
use std::path::Path;

use anyhow::Context;
use stx_dynamics::vehicle::Vehicle;
use stx_gnc::control::ControlGains;
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

/// A gains file (`stx tune` writes them), validated.
pub fn load_gains(path: &Path) -> anyhow::Result<ControlGains> {
    let text = read("gains file", path)?;
    ControlGains::from_toml_str(&text)
        .with_context(|| format!("gains file {}", path.display()))
        .map_err(|e| BadInput(e).into())
}
