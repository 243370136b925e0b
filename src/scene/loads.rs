//! `[[dirichlet]]`, `[[traction]]` and `[load]`: the boundary conditions and the quasi-static
//! load path they follow.

use serde::{Deserialize, Serialize};

/// A displacement component a `[[dirichlet]]` entry holds (`dirichlet.components`).
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Component {
    /// `x`.
    X,
    /// `y`.
    Y,
    /// `z`.
    Z,
}

/// One `[[dirichlet]]`: a prescribed displacement on a face.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Dirichlet {
    /// The face (`body.face`).
    pub face: String,
    /// Prescribed displacement (default 0).
    #[serde(default)]
    pub value: [f64; 3],
    /// Constrained components (default all three).
    #[serde(default = "all_components")]
    pub components: Vec<Component>,
    /// `value` × f_k at load step k (default: the linear ramp k/K).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub factors: Option<Vec<f64>>,
}

fn all_components() -> Vec<Component> {
    vec![Component::X, Component::Y, Component::Z]
}

/// One `[[traction]]`: a constant traction or pressure on a face (consistent nodal loads).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Traction {
    /// The face (`body.face`).
    pub face: String,
    /// Surface traction (MPa), constant over the face, in global axes; or
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub p: Option<[f64; 3]>,
    /// a pressure (MPa) normal to each facet, positive into the body (give one of the two).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure: Option<f64>,
    /// `p` × f_k at load step k (default: the linear ramp k/K).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub factors: Option<Vec<f64>>,
}

/// `[load]`: a quasi-static load path of `steps` states, each solved from the last; friction
/// acts on each step's slip increment.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSettings {
    /// K, the number of load states solved in order (1 … [`MAX_LOAD_STEPS`]; > 1 needs
    /// contact); default 1.
    #[serde(default = "one")]
    pub steps: usize,
}

fn one() -> usize {
    1
}

impl Default for LoadSettings {
    fn default() -> Self {
        LoadSettings { steps: 1 }
    }
}

/// The factor f_k (k = 1…K) of an entry's `factors`, or the linear ramp k/K.
pub fn load_factor(factors: Option<&[f64]>, k: usize, steps: usize) -> f64 {
    factors.map_or(k as f64 / steps as f64, |f| f[k - 1])
}

/// Load steps at most: every step is a solve and a group in the result file.
pub const MAX_LOAD_STEPS: usize = 10_000;
