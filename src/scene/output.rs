//! `[output]`: the result file, the fields written and the extra exports.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::yes;

/// Output fields a scene can ask for (the contact ones are written only when contact is solved).
pub const FIELDS: [&str; 12] = [
    "displacement",
    "von_mises",
    "body",
    "subdomain",
    "rank",
    "contact_status",
    "contact_pressure",
    "contact_pressure_smooth",
    "contact_traction",
    "contact_traction_smooth",
    "gap",
    "slip",
];

/// `[output]`: what is written.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSettings {
    /// HDF5 file; the XDMF (`.xdmf`) and JSON report (`.json`) go beside it. Default
    /// `out/<scene file stem>.h5`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<PathBuf>,
    /// The fields written, a subset of [`FIELDS`]; default all.
    #[serde(default = "default_fields")]
    pub fields: Vec<String>,
    /// Write the XDMF sidecar ParaView opens; default true.
    #[serde(default = "yes")]
    pub xdmf: bool,
    /// Write the JSON report; default true.
    #[serde(default = "yes")]
    pub report: bool,
    /// After writing, every rank reads the HDF5 file back and checks that it holds the fields
    /// it has in memory, bit for bit (phase `verify`).
    #[serde(default)]
    pub verify: bool,
    /// Also write the solved dual problem of a Coulomb scene on the monolithic dual — the
    /// Delassus matrix W = B K⁻¹ Bᵀ, q = −b, μ per contact, our r = λ and u = W r + q, per
    /// contact in the order (normal, t₁, t₂) — to this HDF5 file, for other solvers
    /// (`run/peer/siconos_check.py`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub export_dual: Option<PathBuf>,
    /// Also write the solved problem in the FCLIB global format (HDF5: M = K, H = Bᵀ, f, w, μ and
    /// our solution as the guess; `dual::fclib`, `run/peer/fclib_check.py`); `--export-fclib`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub export_fclib: Option<PathBuf>,
    /// After each completed load step but the last, write what the next step needs to
    /// `<name>.checkpoint.h5` beside the result (`solve --checkpoint`; `solve --resume`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub checkpoint: bool,
}

fn default_fields() -> Vec<String> {
    FIELDS.iter().map(|s| s.to_string()).collect()
}

impl Default for OutputSettings {
    fn default() -> Self {
        OutputSettings {
            path: None,
            fields: default_fields(),
            xdmf: true,
            report: true,
            verify: false,
            export_dual: None,
            export_fclib: None,
            checkpoint: false,
        }
    }
}
