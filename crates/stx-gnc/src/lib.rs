//! Guidance, navigation and control of the STRAPLEX parafoil, the same code onboard the
//! (simulated) drone and in the ground station.
//!
//! - [`mission`] names the flight stages, the operator-selectable control modes and the phases
//!   of spiral-landing guidance: the vocabulary shared with the link and the dashboard, which
//!   lives in `stx-types` (with [`geo`], the keep-out zones, the plan items, the controls, the
//!   angle helpers, the atmosphere and the wind profiles) and is re-exported here; this crate
//!   depends on no simulator physics and the link on no guidance;
//! - [`measurement`] is what the drone's sensors report, [`estimate`] what the estimator makes
//!   of it;
//! - [`estimator`] turns measurements (late, out of order, with gaps) into that estimate: the
//!   wind, airspeed, heading and position with their uncertainties, onboard and in the station
//!   alike;
//! - [`control`] holds the seed's control laws (heading, course, localizer, glide slope);
//!   [`guidance`] picks and feeds them by mode, including the spiral landing. The spiral's
//!   final approach sets its brakes by inverting the glide performance
//!   ([`guidance::FinalLaw::GlideInversion`]), not with the seed's glide-slope law, which
//!   flies localizer mode's glide path and is the final's alternative
//!   ([`guidance::FinalLaw::GlideSlope`]): the Monte Carlo flew the inversion closer (see
//!   `GNC_NOTES.md` beside this crate's `Cargo.toml`, which also says how the estimator,
//!   the spiral and the landing prediction work and which seed equations they follow);
//! - [`performance`] summarises how the parafoil flies, [`pointmass`] flies that summary fast,
//!   and [`predict`] uses it to say where the vehicle will land, in the wind
//!   [`descent_wind`] puts below the drone (the estimate's, or a profile corrected by it);
//! - [`ascent_wind`] measures the wind profile from the balloon's drift during the ascent, by
//!   altitude band with its uncertainty, and joins it to the forecast for the predictions;
//! - [`footprint`] says which ground the stack can still reach from the estimate, with the
//!   probability of reaching each point under the wind's uncertainty (50 % and 95 % contours)
//!   and the keep-out zones it overlaps;
//! - [`keep_out`] reads the keep-out zones (GeoJSON polygons) into the local frame, where
//!   `stx-types` says whether a point lies in one and whether a leg crosses one;
//! - [`flight_path`] flies the whole stack unsteered — balloon ascent, round chute, parafoil
//!   deployment and glide — through a forecast wind, and its Monte Carlo spread gives the
//!   pre-flight plan: burst, deploy and landing regions and the target's reachability;
//! - [`geo`] links the mission's local NED frame to latitude, longitude and altitude;
//! - [`plan_upload`] turns an uploaded plan (waypoints, landing point) into guidance's plan,
//!   the same way on the drone and in the station's replica;
//! - [`params`] describes every onboard setting the station may read and write, once, for
//!   the drone's parameter table and the station's editor alike.
pub mod ascent_wind;
pub mod control;
pub mod descent_wind;
pub mod estimate;
pub mod estimator;
pub mod flight_path;
pub mod footprint;
pub mod guidance;
pub mod keep_out;
pub mod measurement;
pub mod params;
pub mod performance;
pub mod plan_upload;
pub mod pointmass;
pub mod predict;
pub mod stats;

pub use stx_types::{geo, mission};
