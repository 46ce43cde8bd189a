//! Why a mission scenario was refused ([`MissionError`]): by name, by its TOML, or by a rule of
//! [`crate::drone::config::MissionConfig::validate`] (the failures table's own rules included).

use stx_gnc::params::ParamError;
use thiserror::Error;

/// Why a mission scenario was refused.
#[derive(Debug, Error)]
pub enum MissionError {
    /// No built-in mission has this name.
    #[error("unknown mission scenario `{name}`; built-in missions: {known}")]
    Unknown { name: String, known: String },
    /// Not valid TOML for a mission (unknown or missing field, wrong type).
    #[error("mission scenario `{name}` is not valid: {source}")]
    Parse {
        name: String,
        #[source]
        source: toml::de::Error,
    },
    /// A field breaks a rule.
    #[error("mission field `{field}` = {value} breaks the rule: {rule}")]
    Invalid {
        field: String,
        value: String,
        rule: &'static str,
    },
    /// The wind description is invalid.
    #[error("mission wind is invalid: {0}")]
    Wind(#[from] stx_dynamics::wind::WindError),
    /// The sensor description is invalid.
    #[error("mission sensors are invalid: {0}")]
    Sensors(#[from] crate::sensors::SensorConfigError),
    /// The estimator description is invalid.
    #[error("mission estimator is invalid: {0}")]
    Estimator(#[from] stx_gnc::estimator::EstimatorConfigError),
    /// An onboard setting (a parameter) is out of its range or contradicts another.
    #[error("mission onboard settings are invalid: {0}")]
    Onboard(#[from] ParamError),
}
