//! `[units]`: the names of the scene's length and force units, for printing only.

use serde::{Deserialize, Serialize};

/// The units of a scene's lengths and forces (stresses and E are force / length²), named only
/// to print results with them: the solver is unit-free, every number is taken as given.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Units {
    /// The length unit (1–16 characters), printed after lengths (displacements).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length: Option<String>,
    /// The force unit (1–16 characters), printed after forces; with `length`, stresses print in
    /// force / length².
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<String>,
}

impl Units {
    /// Whether neither unit is named (no `units` table).
    pub fn is_empty(&self) -> bool {
        self.length.is_none() && self.force.is_none()
    }

    /// The stress unit, force / length² ("N" and "mm": "MPa"; "kN" and "m": "kPa"), where both
    /// are named.
    pub fn stress(&self) -> Option<String> {
        let (f, l) = (self.force.as_deref()?, self.length.as_deref()?);
        let known = match (f, l) {
            ("N", "m") => Some("Pa"),
            ("kN", "m") => Some("kPa"),
            ("MN", "m") | ("N", "mm") => Some("MPa"),
            ("GN", "m") | ("kN", "mm") => Some("GPa"),
            _ => None,
        };
        Some(known.map_or_else(|| format!("{f}/{l}²"), str::to_string))
    }
}
