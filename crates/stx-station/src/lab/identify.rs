//! The Lab's identification of vehicle parameters from a recorded flight (issue 16 item 3;
//! `stx identify` in the dashboard): the parameter names a page may ask for, checked before
//! a job starts, and what the page shows ([`IdentifySummary`]). The fitting is stx-lab's
//! (stx-analysis sits above the station, so the names are kept here and a test of stx-lab
//! holds them equal to the library's).

use schemars::JsonSchema;
use serde::Serialize;

/// The parameters identification fits, by the names the vehicle file uses (stx-analysis'
/// `identify::Param::ALL`).
pub const IDENTIFY_PARAMS: [&str; 14] = [
    "cd0",
    "cd_alpha2",
    "cy_beta",
    "cl0",
    "cl_alpha",
    "clp",
    "cmq",
    "cnr",
    "cn_beta",
    "cl_ds",
    "cd_ds",
    "cl_da",
    "cn_da",
    "rigging_deg",
];

/// Why `params` cannot be identified: none, one unknown, or one listed twice.
pub fn check_params(params: &[String]) -> Result<(), String> {
    if params.iter().all(|p| p.trim().is_empty()) {
        return Err(format!(
            "name at least one parameter to fit ({})",
            IDENTIFY_PARAMS.join(", ")
        ));
    }
    for (i, p) in params.iter().enumerate() {
        let name = p.trim().to_ascii_lowercase();
        if !IDENTIFY_PARAMS.contains(&name.as_str()) {
            return Err(format!(
                "unknown parameter {p:?}; known: {}",
                IDENTIFY_PARAMS.join(", ")
            ));
        }
        if params[..i]
            .iter()
            .any(|q| q.trim().eq_ignore_ascii_case(&name))
        {
            return Err(format!("parameter {p:?} is listed twice"));
        }
    }
    Ok(())
}

/// One fitted parameter.
#[derive(Debug, Clone, Default, Serialize, JsonSchema)]
pub struct IdentifiedParam {
    /// Name, as in the vehicle file (`rigging_deg`: change of rigging angle, degrees).
    pub name: String,
    /// Value before the fit (the vehicle as edited).
    pub nominal: f64,
    /// Fitted value.
    pub fitted: f64,
    /// Standard error (`null` when the flight does not determine it).
    pub std_error: Option<f64>,
    /// Low end of the 95 % interval (`null` with the standard error).
    pub interval95_low: Option<f64>,
    /// High end of the 95 % interval.
    pub interval95_high: Option<f64>,
}

/// Parameters fitted to a recording (`stx identify` in the Lab).
#[derive(Debug, Clone, Default, Serialize, JsonSchema)]
pub struct IdentifySummary {
    /// The recording's file name.
    pub recording: String,
    /// The vehicle parameters changed from the seed's before the fit (`name = value`).
    pub vehicle_changes: Vec<String>,
    /// Each parameter, in the order asked.
    pub params: Vec<IdentifiedParam>,
    /// Correlation matrix of the estimates, rows and columns in the order of `params`
    /// (`null` when the flight does not tell the parameters apart).
    pub correlation: Option<Vec<Vec<f64>>>,
    /// RMS of the residuals before the fit, in multiples of the sensor noise.
    pub residual_rms_before: f64,
    /// The same after.
    pub residual_rms_after: f64,
    /// Levenberg–Marquardt iterations.
    pub iterations: u32,
    /// Why the fit stopped (`converged`, …; `cancelled` when stopped early, the best point
    /// so far reported).
    pub stop: String,
    /// The fitted vehicle file (TOML).
    pub vehicle_toml: String,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn unknown_missing_or_repeated_parameters_are_refused_with_the_known_ones() {
        assert_eq!(check_params(&names(&["cl_alpha", "CD0"])), Ok(()));
        let e = check_params(&names(&["cl_alpha", "wingspan"])).unwrap_err();
        assert!(
            e.contains("\"wingspan\"") && e.contains("rigging_deg"),
            "{e}"
        );
        assert!(check_params(&[]).unwrap_err().contains("at least one"));
        assert!(check_params(&names(&[" "])).is_err());
        let e = check_params(&names(&["cd0", "Cd0"])).unwrap_err();
        assert!(e.contains("twice"), "{e}");
    }
}
