//! The steady-glide table guidance plans with ([`GlidePerformance`]) for any vehicle, by
//! trimming the nonlinear model ([`crate::trim`]) at each of the table's brake settings.
//!
//! Guidance does not fly the 14-DOF model: it plans with a point-mass summary of it, by default
//! the shipped STRAPLEX stack's. A vehicle identified from flights (`stx identify`, the Lab)
//! flies a different glide; [`glide_performance_of`] turns it into the table guidance needs, so
//! that guidance plans with the stack it will fly rather than the shipped one.
//!
//! Only the straight glide is trimmed. The turn terms (turn rate against main line, its time
//! constant, the extra sink in a turn) are kept from the shipped table: a trim is a straight
//! glide and identifies none of them.

use stx_dynamics::state::{Controls, idx};
use stx_dynamics::vehicle::Vehicle;
use stx_gnc::performance::GlidePerformance;
use thiserror::Error;

use crate::trim::{TrimError, trim};

/// Height above sea level the table is given at, m: the shipped table's (see
/// [`GlidePerformance::default`]), so a trimmed table and the shipped one compare directly.
pub const REFERENCE_HEIGHT_M: f64 = 100.0;

/// Highest brake a trim is asked for, 0…1: [`trim`] takes brakes in [0, 1), so the table's
/// full brake (1) is trimmed just short of it; the glide changes little over the last
/// hundredth of brake.
pub const MAX_TRIM_BRAKE: f64 = 0.99;

/// Why no table could be made for a vehicle.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PerformanceError {
    /// The vehicle has no steady glide at one of the table's brake settings.
    #[error("no steady glide at symmetric brake {brake} (of 0…1): {source}")]
    Trim {
        /// The table's brake setting that failed, 0…1.
        brake: f64,
        /// Why the trim failed.
        #[source]
        source: TrimError,
    },
}

/// The steady-glide table of `vehicle`: airspeed and sink rate trimmed at each of the shipped
/// table's brake settings at [`REFERENCE_HEIGHT_M`], with the reference density of the air
/// there (as the trim at the first brake setting, brake 0, gives it). The turn terms are the
/// shipped table's, unchanged: a trim is a straight glide and does not identify them.
///
/// A brake setting with no steady glide (the trim refuses or does not converge) is
/// [`PerformanceError::Trim`], naming the setting.
pub fn glide_performance_of(vehicle: &Vehicle) -> Result<GlidePerformance, PerformanceError> {
    let mut table = GlidePerformance::default();
    for (k, &brake) in table.brake_points.iter().enumerate() {
        let t = trim(
            vehicle,
            REFERENCE_HEIGHT_M,
            Controls::symmetric_brake(brake.min(MAX_TRIM_BRAKE)),
        )
        .map_err(|source| PerformanceError::Trim { brake, source })?;
        table.airspeed_mps[k] = t.airspeed_mps;
        // The rate of the state's down position, as the shipped table's sink was measured.
        table.sink_rate_mps[k] = t.derivative[idx::POSITION + 2];
        if k == 0 {
            table.reference_density_kg_per_m3 = t.density_kg_per_m3;
        }
    }
    Ok(table)
}

#[cfg(test)]
mod tests {
    use stx_dynamics::vehicle::VehicleConfig;

    use super::*;

    /// Consistency of the two ways the shipped table could be had: trimming the shipped
    /// vehicle gives the table guidance ships with (measured by flying the model; the same 2 %
    /// as `crates/stx-sim/tests/sim/performance_matches_model.rs` allows), the turn terms
    /// untouched. A change to the model, the trim or the table shows up here.
    #[test]
    fn the_shipped_vehicle_trims_to_the_shipped_table_within_two_percent() {
        let trimmed = glide_performance_of(&Vehicle::straplex()).expect("the shipped stack glides");
        let shipped = GlidePerformance::default();
        assert_eq!(trimmed.brake_points, shipped.brake_points);
        for k in 0..shipped.brake_points.len() {
            for (what, t, s) in [
                ("airspeed", trimmed.airspeed_mps[k], shipped.airspeed_mps[k]),
                ("sink", trimmed.sink_rate_mps[k], shipped.sink_rate_mps[k]),
            ] {
                assert!(
                    (t / s - 1.0).abs() < 0.02,
                    "brake {}: trimmed {what} {t:.3} m/s, shipped {s:.3}",
                    shipped.brake_points[k]
                );
            }
        }
        assert!(
            (trimmed.reference_density_kg_per_m3 / shipped.reference_density_kg_per_m3 - 1.0).abs()
                < 1e-3
        );
        let turn_terms = |p: &GlidePerformance| {
            [
                p.max_turn_rate_rad_s,
                p.turn_main_line_scale_m,
                p.turn_time_constant_s,
                p.turn_sink_mps_per_rad2_s2,
            ]
        };
        assert_eq!(turn_terms(&trimmed), turn_terms(&shipped));
    }

    #[test]
    fn a_vehicle_without_a_steady_glide_is_refused_naming_the_brake_setting() {
        // No lift at all: the canopy falls flat, outside the coefficients' angles of attack.
        let mut config: VehicleConfig = Vehicle::straplex().config;
        config.canopy.aero.cl0 = 0.0;
        config.canopy.aero.cl_alpha = 0.0;
        config.canopy.brakes.cl_ds = 0.0;
        let vehicle = config.validate().expect("a valid, if lift-less, vehicle");
        let err = glide_performance_of(&vehicle).expect_err("no glide");
        let PerformanceError::Trim { brake, .. } = &err;
        assert_eq!(*brake, 0.0);
        assert!(err.to_string().contains("brake 0"), "{err}");
    }
}
