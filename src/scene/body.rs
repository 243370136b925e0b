//! `[mesh]`, `[[material]]` and `[[body]]`: what the bodies are made of and meshed from
//! (structured boxes with an optional curved side, or Gmsh files).

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSettings {
    /// Nodes per edge of every box body that gives no `nodes` of its own (the paper's N).
    #[serde(default = "default_n")]
    pub n: usize,
    /// The cells of every box body that names none of its own: `hex8` (default), `tet4`,
    /// `tet10` (each hexahedron cut into six tetrahedra).
    #[serde(default, skip_serializing_if = "BoxCells::is_hex8")]
    pub cells: BoxCells,
}

/// The cells a box body is meshed with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BoxCells {
    #[default]
    Hex8,
    Tet4,
    Tet10,
}

impl BoxCells {
    pub fn is_hex8(&self) -> bool {
        *self == BoxCells::Hex8
    }
}

fn default_n() -> usize {
    8
}

impl Default for MeshSettings {
    fn default() -> Self {
        MeshSettings { n: default_n(), cells: BoxCells::Hex8 }
    }
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    pub name: String,
    /// Young's modulus (MPa).
    #[serde(rename = "E")]
    pub e: f64,
    /// Poisson's ratio.
    pub nu: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Body {
    pub name: String,
    pub material: String,
    /// A structured box; exactly one of `box` and `gmsh`.
    #[serde(rename = "box", default, skip_serializing_if = "Option::is_none")]
    pub boxed: Option<BoxDef>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gmsh: Option<GmshDef>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BoxDef {
    pub min: [f64; 3],
    pub max: [f64; 3],
    /// Nodes per direction; defaults to `[mesh.n; 3]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nodes: Option<[usize; 3]>,
    /// Bends the `zmin` or `zmax` side into a cylinder (axis along y through the side's centre
    /// line, bulging outward); the nodes between follow linearly so the opposite side stays flat.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cylinder: Option<Cylinder>,
    /// Bends the `zmin` or `zmax` side into a spherical cap (pole above `centre`, bulging
    /// outward); the nodes between follow linearly so the opposite side stays flat.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere: Option<Sphere>,
    /// The cells; defaults to `mesh.cells`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cells: Option<BoxCells>,
}

/// The side of a box a cylinder or sphere bends (`body.box.cylinder.side`,
/// `body.box.sphere.side`).
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Zmin,
    Zmax,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Cylinder {
    pub side: Side,
    pub radius: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Sphere {
    pub side: Side,
    pub radius: f64,
    /// The pole's (x, y); defaults to the side's centre. A quarter model puts it at a corner.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre: Option<[f64; 2]>,
}

impl Sphere {
    /// The pole's (x, y) on the box `bx`.
    pub fn pole(&self, bx: &BoxDef) -> [f64; 2] {
        self.centre.unwrap_or([0.5 * (bx.min[0] + bx.max[0]), 0.5 * (bx.min[1] + bx.max[1])])
    }

    /// The largest distance from the pole's line to a point of the side: the farthest corner.
    pub fn reach(&self, bx: &BoxDef) -> f64 {
        let c = self.pole(bx);
        let dx = (bx.min[0] - c[0]).abs().max((bx.max[0] - c[0]).abs());
        let dy = (bx.min[1] - c[1]).abs().max((bx.max[1] - c[1]).abs());
        dx.hypot(dy)
    }
}

impl BoxDef {
    /// How far the curved side lies outside the flat box at (x, y). Cylinder: √(R² − (x − x_c)²)
    /// − √(R² − h²) (h the half-width in x): the full sagitta on the centre line, 0 at the edges.
    /// Sphere: √(R² − r²) − √(R² − h²), r the distance from the pole's line and h its largest
    /// value over the side (the farthest corner): the full sagitta at the pole, 0 at that corner.
    pub fn bulge(&self, x: f64, y: f64) -> f64 {
        if let Some(c) = &self.cylinder {
            let (xc, h, r) = (0.5 * (self.min[0] + self.max[0]), 0.5 * (self.max[0] - self.min[0]), c.radius);
            return (r * r - (x - xc) * (x - xc)).max(0.0).sqrt() - (r * r - h * h).max(0.0).sqrt();
        }
        if let Some(s) = &self.sphere {
            let (c, h, r) = (s.pole(self), s.reach(self), s.radius);
            let d2 = (x - c[0]) * (x - c[0]) + (y - c[1]) * (y - c[1]);
            return (r * r - d2).max(0.0).sqrt() - (r * r - h * h).max(0.0).sqrt();
        }
        0.0
    }

    /// The curved side of a cylinder or sphere, if any.
    pub fn curved_side(&self) -> Option<Side> {
        self.cylinder.as_ref().map(|c| c.side).or(self.sphere.as_ref().map(|s| s.side))
    }
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GmshDef {
    /// Path of a Gmsh 4.1 `.msh`, relative to the scene file.
    pub file: PathBuf,
    /// Physical volume to take (default: every hexahedron of the file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub volume: Option<String>,
    /// Shift applied to all node coordinates.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translate: Option<[f64; 3]>,
}

/// Most nodes of one body: its 3 DOFs per node must fit the 32-bit indices of METIS.
pub const MAX_BODY_NODES: usize = i32::MAX as usize / 3;
