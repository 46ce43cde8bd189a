//! A parameter as it travels: its name (1..=16 ASCII bytes, checked alike by both sides and
//! refused with [`ParamRequestError::BadName`]), its value as [`ParamValue`] and the
//! PARAM_VALUE that carries it, as `MAV_PARAM_TYPE_REAL32` or, for whole numbers, `INT32`.

use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;
use serde::{Deserialize, Serialize};

/// Longest parameter name, bytes.
pub const PARAM_NAME_LEN: usize = 16;

/// A parameter name and value as seen on the wire.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamValue {
    /// Name (≤ 16 ASCII bytes).
    pub name: String,
    /// Value.
    pub value: f32,
    /// Index in the vehicle's table.
    pub index: u16,
    /// Number of parameters in the vehicle's table.
    pub count: u16,
}

pub(super) fn name_to_wire(name: &str) -> mavlink::types::CharArray<16> {
    let mut bytes = [0_u8; PARAM_NAME_LEN];
    for (b, s) in bytes.iter_mut().zip(name.bytes()) {
        *b = s;
    }
    bytes.into()
}

pub(super) fn name_from_wire(id: &mavlink::types::CharArray<16>) -> String {
    let raw: &[u8] = &id[..];
    let end = raw.iter().position(|&b| b == 0).unwrap_or(raw.len());
    String::from_utf8_lossy(raw.get(..end).unwrap_or(&[])).into_owned()
}

/// The PARAM_VALUE carrying `p`: `REAL32`, or `INT32` for a parameter of whole numbers,
/// its value then cast to the float field as ArduPilot does ("C-cast" encoding), which
/// MAVProxy and pymavlink read as the number it is for a vehicle that is not PX4.
pub(super) fn param_value_msg(p: &ParamValue, integer: bool) -> MavMessage {
    MavMessage::PARAM_VALUE(mc::PARAM_VALUE_DATA {
        param_value: p.value,
        param_count: p.count,
        param_index: p.index,
        param_id: name_to_wire(&p.name),
        param_type: if integer {
            mc::MavParamType::MAV_PARAM_TYPE_INT32
        } else {
            mc::MavParamType::MAV_PARAM_TYPE_REAL32
        },
    })
}

/// Why a parameter operation could not start.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ParamRequestError {
    /// Name longer than 16 bytes or not ASCII.
    #[error("parameter name {name:?} is not 1..=16 ASCII bytes")]
    BadName { name: String },
    /// A list is already running.
    #[error("a parameter list is already in progress")]
    ListInProgress,
    /// An operation on the same name is already running.
    #[error("an operation on {name:?} is already in progress")]
    Busy { name: String },
}

pub(super) fn check_name(name: &str) -> Result<(), ParamRequestError> {
    if name.is_empty() || name.len() > PARAM_NAME_LEN || !name.is_ascii() || name.contains('\0') {
        return Err(ParamRequestError::BadName {
            name: name.to_string(),
        });
    }
    Ok(())
}
