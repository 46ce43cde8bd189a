//! The parameter micro-protocol (PARAM_*): the station reads and edits the drone's tuning
//! parameters (gains, geometry, limits) with the retries the protocol needs over a lossy link.
//!
//! - [`ParamClient`] (ground): list all parameters (PARAM_REQUEST_LIST, then PARAM_VALUEs
//!   collected by index; missing indices re-requested with PARAM_REQUEST_READ after a quiet
//!   timeout), read one, set one (PARAM_SET, the echoed PARAM_VALUE is the value actually
//!   set). Outcomes are [`ParamEvent`]s.
//! - [`ParamTable`] (vehicle): named `f32` parameters with min / max / default and a
//!   description; answers list / read / set, refuses out-of-range or non-finite sets and
//!   those the application's [`ParamValidator`] refuses (the rules between parameters only
//!   the application knows), replying with the unchanged value and a text saying why, and
//!   reports changes to the application as [`ParamChange`]s. The validator runs inside the
//!   set, before the echo, so the only PARAM_VALUE a set produces is the value in force: a
//!   station never sees a value that is put back a moment later.
//!
//! Values travel as `MAV_PARAM_TYPE_REAL32`, those of parameters of whole numbers (choices,
//! flags: [`ParamSpec::whole`]) as `INT32` cast to the float field (ArduPilot's encoding), and a
//! set of a fraction to one of those is refused like any other refused set.
//!
//! ## Files
//! - `value.rs`: [`ParamValue`] and the name rules both sides share.
//! - `client.rs`: the ground side, [`ParamClient`], with its [`ParamConfig`] and
//!   [`ParamEvent`]s.
//! - `table.rs`: the vehicle side, [`ParamTable`] of [`ParamSpec`]s, with the
//!   [`ParamValidator`] it consults.

mod client;
mod table;
mod value;

pub use client::{ParamClient, ParamConfig, ParamEvent};
pub use table::{
    ParamChange, ParamRefusal, ParamSpec, ParamTable, ParamTableError, ParamTableStats,
    ParamValidator, RangeOnly,
};
pub use value::{PARAM_NAME_LEN, ParamRequestError, ParamValue};

#[cfg(test)]
mod tests;
