//! What the station knows about the drone's parameters beyond their names and values (the
//! wire carries nothing else): range, units and meaning, for the parameter editor.

/// One parameter's description.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    /// Name on the wire (≤ 16 characters).
    pub name: &'static str,
    /// Smallest value the drone accepts.
    pub min: f64,
    /// Largest value the drone accepts.
    pub max: f64,
    /// Units.
    pub units: &'static str,
    /// What it does.
    pub description: &'static str,
}

/// The drone's parameters the station describes.
const CATALOG: &[ParamSpec] = &[];

/// The description of a parameter, if the station knows it.
pub fn describe(name: &str) -> Option<&'static ParamSpec> {
    CATALOG.iter().find(|p| p.name == name)
}
