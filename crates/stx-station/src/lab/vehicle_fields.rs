//! The vehicle editor's fields: every number of the vehicle file by its dotted name
//! (`canopy.mass_kg`, `geometry.…​.1` for a vector's second component) with its unit read from
//! the name's suffix and the seed's (STRAPLEX) value beside it; edits applied to the seed's
//! vehicle and checked by the model's own validation (`VehicleConfig::validate`), so the Lab
//! refuses exactly what `stx sim --vehicle` would, naming the field and the rule.

use schemars::JsonSchema;
use serde::Serialize;
use serde_json::Value;
use stx_dynamics::vehicle::{Vehicle, VehicleConfig, VehicleError};

use super::VehicleEdits;

/// One editable number of the vehicle.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct VehicleField {
    /// Dotted name, as the vehicle file nests it.
    pub name: String,
    /// Unit (`kg`, `m`, `m/s²`, …; `1` when dimensionless or per radian as the name says).
    pub unit: String,
    /// The seed's (STRAPLEX, config/vehicle/straplex.toml) value.
    pub seed: f64,
}

/// `GET /api/lab/vehicle`: the fields of the vehicle editor.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct VehicleFieldsBody {
    /// Every number of the vehicle file, in the file's order.
    pub fields: Vec<VehicleField>,
}

/// An edit the Lab refuses: which field and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("vehicle field `{field}`: {reason}")]
pub struct FieldError {
    /// The dotted name.
    pub field: String,
    /// The rule it breaks.
    pub reason: String,
}

const UNITS: [(&str, &str); 12] = [
    ("_mps2", "m/s²"),
    ("_mps", "m/s"),
    ("_kg_m2", "kg·m²"),
    ("_kg", "kg"),
    ("_m2", "m²"),
    ("_m", "m"),
    ("_deg", "deg"),
    ("_rad", "rad"),
    ("_rad_s", "rad/s"),
    ("_per_s", "1/s"),
    ("_s", "s"),
    ("_n", "N"),
];

/// The unit a field's name states (the vehicle file's convention), `1` otherwise.
pub fn unit_of(name: &str) -> &'static str {
    // A vector's component names its vector's unit.
    let base = name
        .rsplit_once('.')
        .filter(|(_, last)| last.parse::<usize>().is_ok())
        .map_or(name, |(head, _)| head);
    UNITS
        .iter()
        .find(|(suffix, _)| base.ends_with(suffix))
        .map_or("1", |(_, unit)| unit)
}

fn flatten(prefix: &str, value: &Value, out: &mut Vec<(String, f64)>) {
    let join = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    match value {
        Value::Object(map) => map.iter().for_each(|(k, v)| flatten(&join(k), v, out)),
        Value::Array(items) => items
            .iter()
            .enumerate()
            .for_each(|(i, v)| flatten(&join(&i.to_string()), v, out)),
        Value::Number(n) => out.extend(n.as_f64().map(|v| (prefix.to_string(), v))),
        _ => {}
    }
}

fn seed_json() -> Value {
    serde_json::to_value(&Vehicle::straplex().config).unwrap_or(Value::Null)
}

/// The editor's fields with the seed's values.
pub fn fields() -> VehicleFieldsBody {
    let mut numbers = Vec::new();
    flatten("", &seed_json(), &mut numbers);
    VehicleFieldsBody {
        fields: numbers
            .into_iter()
            .map(|(name, seed)| VehicleField {
                unit: unit_of(&name).to_string(),
                name,
                seed,
            })
            .collect(),
    }
}

fn slot<'a>(root: &'a mut Value, name: &str) -> Option<&'a mut Value> {
    let mut at = root;
    for part in name.split('.') {
        at = match at {
            Value::Object(map) => map.get_mut(part)?,
            Value::Array(items) => items.get_mut(part.parse::<usize>().ok()?)?,
            _ => return None,
        };
    }
    at.is_number().then_some(at)
}

/// The seed's vehicle with `edits`, validated: the vehicle's description, or the first field
/// that is unknown, not finite, or breaks one of the model's rules.
pub fn edited_config(edits: &VehicleEdits) -> Result<VehicleConfig, FieldError> {
    let mut json = seed_json();
    for (name, value) in edits {
        let bad = |reason: &str| FieldError {
            field: name.clone(),
            reason: reason.to_string(),
        };
        let number = serde_json::Number::from_f64(*value).ok_or_else(|| bad("must be finite"))?;
        *slot(&mut json, name).ok_or_else(|| bad("no such vehicle parameter"))? =
            Value::Number(number);
    }
    let config: VehicleConfig = serde_json::from_value(json).map_err(|e| FieldError {
        field: String::new(),
        reason: e.to_string(),
    })?;
    config.clone().validate().map_err(|e| match e {
        VehicleError::Invalid { field, rule, .. } => FieldError {
            field: field.to_string(),
            reason: rule.to_string(),
        },
        other => FieldError {
            field: String::new(),
            reason: other.to_string(),
        },
    })?;
    Ok(config)
}

/// The validated vehicle of `edits`.
pub fn edited_vehicle(edits: &VehicleEdits) -> Result<Vehicle, FieldError> {
    edited_config(edits)?.validate().map_err(|e| FieldError {
        field: String::new(),
        reason: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edits(pairs: &[(&str, f64)]) -> VehicleEdits {
        pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect()
    }

    #[test]
    fn every_field_has_the_seed_value_and_its_unit() {
        let f = fields().fields;
        let get = |n: &str| f.iter().find(|x| x.name == n).expect(n);
        // config/vehicle/straplex.toml, from the seed's Table 3.1.
        assert_eq!(get("canopy.mass_kg").seed, 0.7);
        assert_eq!(get("canopy.mass_kg").unit, "kg");
        assert_eq!(get("canopy.span_m").seed, 3.3);
        assert_eq!(get("canopy.area_m2").unit, "m²");
        assert_eq!(get("gravity_mps2").unit, "m/s²");
        assert_eq!(get("canopy.aero.alpha_range_deg.1").unit, "deg");
        assert_eq!(get("canopy.aero.cl_alpha").unit, "1");
        assert!(f.len() > 40, "{}", f.len());
    }

    #[test]
    fn no_edit_gives_the_seed_vehicle() {
        let v = edited_vehicle(&VehicleEdits::new()).expect("valid");
        assert_eq!(v, Vehicle::straplex());
    }

    #[test]
    fn an_edit_reaches_the_vehicle() {
        let v = edited_vehicle(&edits(&[("canopy.mass_kg", 0.9)])).expect("valid");
        assert_eq!(v.config.canopy.mass_kg, 0.9);
        assert_eq!(v.canopy_mass_kg, 0.9);
    }

    #[test]
    fn the_models_rules_refuse_with_the_field_and_rule() {
        let e = edited_vehicle(&edits(&[("canopy.mass_kg", -1.0)])).expect_err("refused");
        assert_eq!(e.field, "canopy.mass_kg");
        assert!(e.reason.contains("> 0"), "{}", e.reason);
        let e = edited_vehicle(&edits(&[("canopy.thickness_m", 2.0)])).expect_err("refused");
        assert_eq!(e.field, "canopy.thickness_m");
        assert!(e.reason.contains("chord"), "{}", e.reason);
    }

    #[test]
    fn unknown_or_non_finite_fields_are_refused_by_name() {
        let e = edited_vehicle(&edits(&[("canopy.wings", 2.0)])).expect_err("refused");
        assert_eq!(e.field, "canopy.wings");
        let e = edited_vehicle(&edits(&[("canopy.span_m", f64::NAN)])).expect_err("refused");
        assert_eq!(e.field, "canopy.span_m");
    }
}
