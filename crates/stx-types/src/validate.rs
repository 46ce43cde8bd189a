//! One number of a configuration against its rule: the check every settings type of the
//! workspace makes (the vehicle in stx-dynamics; flight path, plan, estimator and ascent
//! winds in stx-gnc; sensors in stx-sim). Each keeps its own error type, whose `Invalid` variant takes
//! an [`Invalid`] through `From`, so `check(…)?` reads the same everywhere.
//!
//! Ours rather than a validation crate's: the rule is one comparison and a name, and the
//! errors must stay `Copy` values the callers already match on.

use thiserror::Error;

/// A setting that breaks its rule. Non-finite values break every rule.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
#[error("`{field}` = {value} is invalid: must be {rule}")]
pub struct Invalid {
    /// Name (or path) of the setting.
    pub field: &'static str,
    /// The value given, in the setting's unit.
    pub value: f64,
    /// The rule it breaks, as the error shows it.
    pub rule: &'static str,
}

/// `Ok` when `value` is finite and `ok` holds; else `field`, `value` and `rule` as an error.
pub fn check(field: &'static str, value: f64, ok: bool, rule: &'static str) -> Result<(), Invalid> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        Err(Invalid { field, value, rule })
    }
}

/// A finite value > 0 (rule "finite and > 0").
pub fn positive(field: &'static str, value: f64) -> Result<(), Invalid> {
    check(field, value, value > 0.0, "finite and > 0")
}

/// A finite value ≥ 0 (rule "finite and ≥ 0").
pub fn non_negative(field: &'static str, value: f64) -> Result<(), Invalid> {
    check(field, value, value >= 0.0, "finite and ≥ 0")
}

/// `impl From<Invalid> for $error` into its `Invalid { field, value, rule }` variant.
#[macro_export]
macro_rules! invalid_into {
    ($error:ty) => {
        impl From<$crate::validate::Invalid> for $error {
            fn from(i: $crate::validate::Invalid) -> Self {
                Self::Invalid {
                    field: i.field,
                    value: i.value,
                    rule: i.rule,
                }
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_values_break_every_rule() {
        assert_eq!(positive("a", 1.0), Ok(()));
        assert_eq!(non_negative("a", 0.0), Ok(()));
        assert!(positive("a", 0.0).is_err());
        for v in [f64::NAN, f64::INFINITY] {
            let e = check("b", v, true, "finite").unwrap_err();
            assert_eq!((e.field, e.rule), ("b", "finite"));
        }
    }
}
