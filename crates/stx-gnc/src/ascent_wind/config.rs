//! The ascent-wind estimator's settings, validated once by [`AscentWindConfig::validate`]
//! (which [`super::AscentWindEstimator::new`] calls).

use serde::{Deserialize, Serialize};
use stx_types::validate::{check, non_negative, positive};
use thiserror::Error;

/// Why an ascent-wind configuration was refused.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum AscentWindConfigError {
    /// A setting breaks its rule.
    #[error("ascent-wind setting `{field}` = {value} is invalid: must be {rule}")]
    Invalid {
        /// Name of the setting.
        field: &'static str,
        /// The value given, in the setting's unit.
        value: f64,
        /// The rule it breaks.
        rule: &'static str,
    },
}

/// Settings of the ascent-wind estimator. Every field has a default for a latex sounding
/// balloon rising at about 5 m/s with a 1–10 Hz GPS; a TOML or JSON file names only what it
/// changes, and unknown keys are refused.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields, default)]
pub struct AscentWindConfig {
    /// Height of an altitude band, m (> 0). Bands start at the frame's ground (altitude 0
    /// above the local origin) and stack upwards: band `k` holds altitudes in
    /// `[k·h, (k+1)·h)`. Thinner bands resolve shear better but hold fewer fixes.
    pub band_height_m: f64,
    /// Fewest fixes a band needs before it is reported (≥ 4): the position fit has three
    /// coefficients and needs residuals left over to judge its own scatter.
    pub min_samples_per_band: u32,
    /// The stack counts as ascending while its vertical speed, averaged over
    /// `vertical_rate_window_s`, is at least this, m/s (> 0). Below it (on the ground, at
    /// float, slowly leaking) fixes are ignored: a balloon that is not rising is not sampling
    /// new altitudes, and on the ground it does not drift with the wind at all.
    pub min_ascent_rate_mps: f64,
    /// Once the vertical speed averaged over the window falls to minus this, m/s (> 0), the
    /// ascent is over for good: the balloon has burst or been cut away, and from then on the
    /// stack flies (parafoil) or falls rather than drifts, so no later fix is used, even one
    /// rising in a thermal. Fixes from the last window before that moment are withdrawn too,
    /// because the window's average lags the burst.
    pub end_descent_rate_mps: f64,
    /// Length of the window the vertical speed is averaged over, s (> 0): long enough that GPS
    /// altitude noise does not make a standing balloon look like a rising one.
    pub vertical_rate_window_s: f64,
    /// Irreducible 1-σ error of a band's mean wind per component, m/s (≥ 0), added in
    /// quadrature to what the scatter says: slowly drifting GPS velocity and position errors
    /// (they do not average out within a band) and the balloon's imperfect following of the
    /// air (it lags changes of wind by a few seconds).
    pub velocity_floor_mps: f64,
    /// Amplitude of the payload's horizontal swing under the balloon, m (≥ 0). A swing of
    /// amplitude `A` moves a band's mean velocity by up to about `A/T` over a passage of `T`
    /// seconds; that term is added in quadrature.
    pub pendulum_amplitude_m: f64,
    /// Errors correlated over up to this long are counted in the scatter's standard error,
    /// s (> 0): the Newey–West window (see `fit.rs`). It should span several of the gusts'
    /// correlation times and the payload's swing period, but the lag it makes is capped at
    /// half a band's fixes, so about half a band's passage (100 s for 500 m at 5 m/s) is the
    /// useful most: a longer window catches more of the errors' correlation, a shorter one
    /// leaves the standard error more degrees of freedom. Longer-lived errors belong to
    /// `velocity_floor_mps`.
    pub correlation_window_s: f64,
    /// Fastest wind believed at the frame's ground, m/s (> 0); a band faster than the bound
    /// at its height is refused (see `plausible.rs` for the rule and why).
    pub max_wind_ground_mps: f64,
    /// Growth of that bound with height, m/s per km (≥ 0).
    pub max_wind_gain_mps_per_km: f64,
    /// Fastest wind believed at any height, m/s (> 0).
    pub max_wind_mps: f64,
    /// Largest component 1-σ of a band that is used, m/s (> 0); a less certain band is
    /// refused.
    pub max_sigma_mps: f64,
}

impl Default for AscentWindConfig {
    fn default() -> Self {
        Self {
            band_height_m: 500.0,
            min_samples_per_band: 20,
            min_ascent_rate_mps: 1.0,
            end_descent_rate_mps: 3.0,
            vertical_rate_window_s: 10.0,
            velocity_floor_mps: 0.05,
            pendulum_amplitude_m: 2.0,
            correlation_window_s: 45.0,
            max_wind_ground_mps: 40.0,
            max_wind_gain_mps_per_km: 10.0,
            max_wind_mps: 120.0,
            max_sigma_mps: 3.0,
        }
    }
}

stx_types::invalid_into!(AscentWindConfigError);

impl AscentWindConfig {
    /// Checks every setting; the error names the first one that breaks its rule.
    pub fn validate(&self) -> Result<(), AscentWindConfigError> {
        positive("band_height_m", self.band_height_m)?;
        check(
            "min_samples_per_band",
            f64::from(self.min_samples_per_band),
            self.min_samples_per_band >= 4,
            "≥ 4",
        )?;
        positive("min_ascent_rate_mps", self.min_ascent_rate_mps)?;
        positive("end_descent_rate_mps", self.end_descent_rate_mps)?;
        positive("vertical_rate_window_s", self.vertical_rate_window_s)?;
        non_negative("velocity_floor_mps", self.velocity_floor_mps)?;
        non_negative("pendulum_amplitude_m", self.pendulum_amplitude_m)?;
        positive("correlation_window_s", self.correlation_window_s)?;
        positive("max_wind_ground_mps", self.max_wind_ground_mps)?;
        non_negative("max_wind_gain_mps_per_km", self.max_wind_gain_mps_per_km)?;
        positive("max_wind_mps", self.max_wind_mps)?;
        positive("max_sigma_mps", self.max_sigma_mps)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_errors_name_the_field() {
        AscentWindConfig::default()
            .validate()
            .expect("defaults valid");
        let cases: [(AscentWindConfig, &str); 5] = [
            (
                AscentWindConfig {
                    band_height_m: 0.0,
                    ..Default::default()
                },
                "band_height_m",
            ),
            (
                AscentWindConfig {
                    min_samples_per_band: 3,
                    ..Default::default()
                },
                "min_samples_per_band",
            ),
            (
                AscentWindConfig {
                    min_ascent_rate_mps: f64::NAN,
                    ..Default::default()
                },
                "min_ascent_rate_mps",
            ),
            (
                AscentWindConfig {
                    velocity_floor_mps: -0.1,
                    ..Default::default()
                },
                "velocity_floor_mps",
            ),
            (
                AscentWindConfig {
                    correlation_window_s: f64::INFINITY,
                    ..Default::default()
                },
                "correlation_window_s",
            ),
        ];
        for (config, name) in cases {
            match config.validate() {
                Err(AscentWindConfigError::Invalid { field, .. }) => assert_eq!(field, name),
                other => panic!("expected an error naming {name}, got {other:?}"),
            }
        }
    }

    #[test]
    fn a_file_names_only_what_it_changes_and_unknown_keys_are_refused() {
        let c: AscentWindConfig = toml::from_str("band_height_m = 250.0").expect("parses");
        assert_eq!(c.band_height_m, 250.0);
        assert_eq!(c.min_samples_per_band, 20);
        assert!(toml::from_str::<AscentWindConfig>("band_height = 250.0").is_err());
    }
}
