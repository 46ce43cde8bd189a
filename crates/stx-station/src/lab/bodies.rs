//! The bodies of the Lab's endpoints around its files and answers (`/api/lab/…`): a started
//! job, a vehicle or gains to check, save or send, a saved file, the gains'
//! list. The jobs' own requests and results are in the module above.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::VehicleEdits;

/// `POST /api/lab/jobs`' answer: the job started.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct LabStartedBody {
    /// The job's number.
    pub id: u64,
    /// Its kind.
    pub kind: &'static str,
}

/// `POST /api/lab/rehearse`'s answer, and the rehearsal the Lab last started: the simulated
/// drone flies its mission again from the start with this vehicle as the truth.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct LabRehearsalBody {
    /// The simulated drone's mission (`rehearsal`, `mission-short`, …).
    pub mission: String,
    /// The vehicle flown: its parameters changed from the seed's.
    pub vehicle: VehicleEdits,
    /// Who started it.
    pub started_by: String,
}

/// `POST /api/lab/vehicle/check`, `/save` and `POST /api/lab/rehearse`: a vehicle as edited.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LabVehicleBody {
    /// Parameters changed from the seed's vehicle.
    #[serde(default)]
    pub vehicle: VehicleEdits,
    /// File name to save as (letters, digits, `-`, `_`; `.toml` is added), in the Lab's
    /// directory; ignored by `check`.
    #[serde(default)]
    pub name: Option<String>,
    /// Replace a file of that name.
    #[serde(default)]
    pub overwrite: bool,
}

/// `POST /api/lab/gains/save` and `/send`: control gains by parameter name (`GN_…`); `send`
/// takes the planning polar's parameters too (`PL_…`, as `stx polar --json` writes them).
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LabGainsBody {
    /// Gains by parameter name; those left out keep their built-in value.
    pub gains: BTreeMap<String, f64>,
    /// File name for `save` (as for a vehicle).
    #[serde(default)]
    pub name: Option<String>,
    /// Replace a file of that name.
    #[serde(default)]
    pub overwrite: bool,
    /// `send` only: the operator confirmed sending these gains to the drone.
    #[serde(default)]
    pub confirm: bool,
}

/// A file the Lab saved, or the gains it sent.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct LabSavedBody {
    /// The file written (`save`), else empty.
    pub path: String,
    /// The parameter requests sent (`send`), one id each as `GET /api/commands/{id}` knows it.
    pub request_ids: Vec<String>,
}

/// One control gain of `GET /api/lab/gains`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct LabGain {
    /// Parameter name on the drone.
    pub name: String,
    /// Units.
    pub units: String,
    /// Built-in value.
    pub value: f64,
    /// Smallest accepted.
    pub min: f64,
    /// Largest accepted.
    pub max: f64,
    /// What it does.
    pub description: String,
}

/// `GET /api/lab/gains`: the control gains and their built-in values.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct LabGainsListBody {
    /// Every `GN_` parameter.
    pub gains: Vec<LabGain>,
}
