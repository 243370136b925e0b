//! Scene files: TOML → [`Scene`] (serde, unknown keys rejected with their dotted path),
//! command-line overrides (`--set key=value`), defaults, and validation of every value with the
//! offending key in the message. Checks that need the mesh (face names, element counts) live in
//! [`crate::model`].
//!
//! This file owns the [`Scene`] itself (its sections, defaults filled in by [`Scene::resolve`],
//! lookups); each section's settings live in a file of their own and are re-exported here:
//!
//! - `units`: `[units]`, the names of the length and force units;
//! - `body`: `[mesh]`, `[[material]]` and `[[body]]` (boxes, their curved sides, Gmsh files);
//! - `face`: `[[face]]`, named faces cut out of others by a region;
//! - `loads`: `[[dirichlet]]`, `[[traction]]` and the load path `[load]`;
//! - `contact`: `[contact]` and its pairs, friction laws, `[[tie]]`;
//! - `solver`: `[solver]`, read per method;
//! - `decomposition`: `[decomposition]` and `[factorization]`;
//! - `output`: `[output]`;
//! - [`range`]: the magnitudes double precision carries;
//! - `parse`: reading a file, `--set` overrides, [`LoadedScene`];
//! - `validate`: [`Scene::validate`], one check per section;
//! - [`keys`]: every key the parser accepts, read from the serde definitions above.

use serde::{Deserialize, Serialize};

mod body;
mod contact;
mod decomposition;
mod face;
pub mod keys;
mod loads;
mod output;
mod parse;
pub mod range;
mod solver;
#[cfg(test)]
mod tests;
mod units;
mod validate;

pub use body::*;
pub use contact::*;
pub use decomposition::*;
pub use face::*;
pub use loads::*;
pub use output::*;
pub use parse::*;
pub use solver::*;
pub use units::*;

/// Serde default `true`.
fn yes() -> bool {
    true
}

/// Serde default `1`.
fn one() -> usize {
    1
}

/// A whole scene: bodies, materials, boundary conditions, contact, solver, decomposition, output.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Free text, printed in the summary and stored in the report; default empty.
    #[serde(default)]
    pub title: String,
    /// The units the scene's numbers are in, for printing and the report only.
    #[serde(default, skip_serializing_if = "Units::is_empty")]
    pub units: Units,
    /// `[mesh]`: the defaults of the box bodies.
    #[serde(default)]
    pub mesh: MeshSettings,
    /// The `[[material]]` entries (at least one).
    #[serde(rename = "material")]
    pub materials: Vec<Material>,
    /// The `[[body]]` entries (at least one).
    #[serde(rename = "body")]
    pub bodies: Vec<Body>,
    /// Extra named faces, cut out of existing ones.
    #[serde(default, rename = "face", skip_serializing_if = "Vec::is_empty")]
    pub faces: Vec<FaceDef>,
    /// The `[[dirichlet]]` entries: prescribed displacements.
    #[serde(default)]
    pub dirichlet: Vec<Dirichlet>,
    /// The `[[traction]]` entries: surface loads.
    #[serde(default)]
    pub traction: Vec<Traction>,
    /// The quasi-static load path: `[load] steps = K`.
    #[serde(default)]
    pub load: LoadSettings,
    /// `[contact]` and its pairs.
    #[serde(default)]
    pub contact: ContactSettings,
    /// Bonded interfaces between bodies (mesh tying by the mortar operator).
    #[serde(default, rename = "tie", skip_serializing_if = "Vec::is_empty")]
    pub ties: Vec<Tie>,
    /// Read by [`SolverSettings::from_table`] (each key checked against the method).
    #[serde(default, skip_deserializing)]
    pub solver: SolverSettings,
    /// `[decomposition]`: the monolithic dual or TFETI, and how each body is split.
    #[serde(default)]
    pub decomposition: DecompositionSettings,
    /// `[factorization]`: the sparse Cholesky factorizations.
    #[serde(default)]
    pub factorization: Factorization,
    /// `[output]`: what is written.
    #[serde(default)]
    pub output: OutputSettings,
}

impl Scene {
    /// Fills in what defaults to other values (box node counts from `mesh.n`).
    pub fn resolve(&mut self) {
        // tied interfaces are equality rows of the TFETI dual
        if !self.ties.is_empty() {
            self.decomposition.tfeti = true;
        }
        let n = self.mesh.n;
        for b in &mut self.bodies {
            if let Some(bx) = &mut b.boxed {
                bx.nodes.get_or_insert([n; 3]);
            }
        }
    }

    /// The resolved scene as TOML (what `check` prints and the result file stores).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_else(|e| format!("# scene could not be serialized: {e}"))
    }

    /// The material named `name` (a scan: for one lookup; [`Scene::material_index`] for many).
    pub fn material(&self, name: &str) -> Option<&Material> {
        self.materials.iter().find(|m| m.name == name)
    }

    /// Material name → index, for looking up every body's material in linear time.
    pub fn material_index(&self) -> std::collections::HashMap<&str, usize> {
        self.materials.iter().enumerate().map(|(i, m)| (m.name.as_str(), i)).collect()
    }
}
