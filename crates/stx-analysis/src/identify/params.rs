//! The vehicle parameters identification can fit, by the names the vehicle file uses
//! (`[canopy.aero]`, `[canopy.brakes]`), plus the rigging angle.
//!
//! The rigging angle is not a field of the file: it turns the canopy's pressure centre and
//! its lines' attachment points about its pitch axis ([`rotate_rigging`], the same change
//! stx-sim's dispersions draw), which turns the canopy's trim against its lines. It is
//! fitted as a change from the file's geometry, in degrees, starting at 0, and written into
//! the new file's geometry.

use serde::{Deserialize, Serialize};
use stx_dynamics::vehicle::VehicleConfig;
use stx_sim::dispersions::rotate_rigging;
use thiserror::Error;

/// A parameter name that is not one of [`Param::ALL`].
#[derive(Debug, Error, Clone, PartialEq)]
#[error("unknown parameter `{0}`; known: {list}", list = Param::ALL.map(Param::name).join(", "))]
pub struct UnknownParam(pub String);

/// A fittable parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Param {
    /// `canopy.aero.cd0`.
    Cd0,
    /// `canopy.aero.cd_alpha2`, 1/rad².
    CdAlpha2,
    /// `canopy.aero.cy_beta`, 1/rad.
    CyBeta,
    /// `canopy.aero.cl0`.
    Cl0,
    /// `canopy.aero.cl_alpha`, 1/rad.
    ClAlpha,
    /// `canopy.aero.clp`.
    Clp,
    /// `canopy.aero.cmq`.
    Cmq,
    /// `canopy.aero.cnr`.
    Cnr,
    /// `canopy.aero.cn_beta`, 1/rad.
    CnBeta,
    /// `canopy.brakes.cl_ds`.
    ClDs,
    /// `canopy.brakes.cd_ds`.
    CdDs,
    /// `canopy.brakes.cl_da`.
    ClDa,
    /// `canopy.brakes.cn_da`.
    CnDa,
    /// Rigging angle change, degrees (see the module doc).
    RiggingDeg,
}

impl Param {
    /// Every parameter.
    pub const ALL: [Param; 14] = [
        Param::Cd0,
        Param::CdAlpha2,
        Param::CyBeta,
        Param::Cl0,
        Param::ClAlpha,
        Param::Clp,
        Param::Cmq,
        Param::Cnr,
        Param::CnBeta,
        Param::ClDs,
        Param::CdDs,
        Param::ClDa,
        Param::CnDa,
        Param::RiggingDeg,
    ];

    /// The name, as in the vehicle file.
    pub fn name(self) -> &'static str {
        match self {
            Param::Cd0 => "cd0",
            Param::CdAlpha2 => "cd_alpha2",
            Param::CyBeta => "cy_beta",
            Param::Cl0 => "cl0",
            Param::ClAlpha => "cl_alpha",
            Param::Clp => "clp",
            Param::Cmq => "cmq",
            Param::Cnr => "cnr",
            Param::CnBeta => "cn_beta",
            Param::ClDs => "cl_ds",
            Param::CdDs => "cd_ds",
            Param::ClDa => "cl_da",
            Param::CnDa => "cn_da",
            Param::RiggingDeg => "rigging_deg",
        }
    }

    /// The parameter called `name` (case does not matter: `CL_alpha` is `cl_alpha`).
    pub fn parse(name: &str) -> Result<Param, UnknownParam> {
        let lower = name.trim().to_ascii_lowercase();
        Param::ALL
            .into_iter()
            .find(|p| p.name() == lower)
            .ok_or_else(|| UnknownParam(name.to_owned()))
    }

    /// A comma-separated list of names.
    pub fn parse_list(names: &str) -> Result<Vec<Param>, UnknownParam> {
        names
            .split(',')
            .filter(|n| !n.trim().is_empty())
            .map(Param::parse)
            .collect()
    }

    fn field(self, v: &mut VehicleConfig) -> Option<&mut f64> {
        let (a, b) = (&mut v.canopy.aero, &mut v.canopy.brakes);
        Some(match self {
            Param::Cd0 => &mut a.cd0,
            Param::CdAlpha2 => &mut a.cd_alpha2,
            Param::CyBeta => &mut a.cy_beta,
            Param::Cl0 => &mut a.cl0,
            Param::ClAlpha => &mut a.cl_alpha,
            Param::Clp => &mut a.clp,
            Param::Cmq => &mut a.cmq,
            Param::Cnr => &mut a.cnr,
            Param::CnBeta => &mut a.cn_beta,
            Param::ClDs => &mut b.cl_ds,
            Param::CdDs => &mut b.cd_ds,
            Param::ClDa => &mut b.cl_da,
            Param::CnDa => &mut b.cn_da,
            Param::RiggingDeg => return None,
        })
    }

    /// Its value in `v` (the rigging change of a file is 0).
    pub fn get(self, v: &VehicleConfig) -> f64 {
        let mut v = v.clone();
        self.field(&mut v).map_or(0.0, |f| *f)
    }

    /// `v` with this parameter set to `value`.
    pub fn set(self, v: &mut VehicleConfig, value: f64) {
        match self.field(v) {
            Some(f) => *f = value,
            None => rotate_rigging(v, value),
        }
    }

    /// A magnitude for finite-difference steps and convergence: the value itself, or a
    /// floor for parameters that may sit at 0.
    pub fn scale(self, value: f64) -> f64 {
        match self {
            Param::RiggingDeg => 1.0,
            _ => value.abs().max(1e-3),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stx_dynamics::vehicle::STRAPLEX_TOML;

    #[test]
    fn names_are_the_files_and_values_round_trip() {
        assert_eq!(Param::parse("CL_alpha"), Ok(Param::ClAlpha));
        assert_eq!(
            Param::parse_list("cd0, cn_da,rigging_deg"),
            Ok(vec![Param::Cd0, Param::CnDa, Param::RiggingDeg])
        );
        assert!(
            Param::parse("lift")
                .unwrap_err()
                .to_string()
                .contains("cl_alpha")
        );
        let mut v = VehicleConfig::from_toml_str(STRAPLEX_TOML).unwrap();
        assert_eq!(Param::ClAlpha.get(&v), 2.3);
        Param::CdDs.set(&mut v, 0.5);
        assert_eq!(v.canopy.brakes.cd_ds, 0.5);
        let before = v.geometry.canopy_pressure_centre_m;
        Param::RiggingDeg.set(&mut v, 2.0);
        assert_ne!(v.geometry.canopy_pressure_centre_m, before);
        assert_eq!(Param::RiggingDeg.get(&v), 0.0);
    }
}
