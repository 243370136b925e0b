//! `[mesh]`, `[[material]]` and `[[body]]`: what the bodies are made of and meshed from
//! (structured boxes with an optional curved side, or Gmsh, Abaqus or MED files).

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// `[mesh]`: the defaults of every box body that gives none of its own.
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
    /// `hex8`: 8-node hexahedra (the default).
    #[default]
    Hex8,
    /// `tet4`: each hexahedron cut into six 4-node tetrahedra.
    Tet4,
    /// `tet10`: each hexahedron cut into six 10-node tetrahedra.
    Tet10,
    /// `hex20`: 20-node (serendipity) hexahedra.
    Hex20,
    /// `hex27`: 27-node (triquadratic) hexahedra.
    Hex27,
}

impl BoxCells {
    /// Whether these are the default `hex8` cells (not written to the resolved scene then).
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

/// One `[[material]]`: an isotropic linear-elastic material.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// The name bodies refer to (unique).
    pub name: String,
    /// Young's modulus (MPa).
    #[serde(rename = "E")]
    pub e: f64,
    /// Poisson's ratio.
    pub nu: f64,
}

/// One `[[body]]`: an elastic body, either a structured box or one physical volume of a Gmsh
/// file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Body {
    /// The body's name (unique, non-empty, no `.`): its faces are `name.face`.
    pub name: String,
    /// Its material: a `material.name`.
    pub material: String,
    /// A structured box; exactly one of `box`, `mesh` and `gmsh`.
    #[serde(rename = "box", default, skip_serializing_if = "Option::is_none")]
    pub boxed: Option<BoxDef>,
    /// A body read from a mesh file (Abaqus `.inp`, Gmsh 4.1 `.msh` or MED `.med`); exactly one of `box`,
    /// `mesh` and `gmsh`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<MeshDef>,
    /// A body read from a Gmsh 4.1 `.msh` (`mesh` with `format = "gmsh"`); exactly one of
    /// `box`, `mesh` and `gmsh`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gmsh: Option<GmshDef>,
}

impl Body {
    /// The body's mesh file as `body.mesh` (the `gmsh` alias converted, its format Gmsh), and
    /// the key it was given under (`mesh` or `gmsh`); `None` for a box.
    pub fn mesh_file(&self) -> Option<(&'static str, MeshDef)> {
        match (&self.mesh, &self.gmsh) {
            (Some(m), _) => Some(("mesh", m.clone())),
            (None, Some(g)) => {
                Some(("gmsh", MeshDef { file: g.file.clone(), volume: g.volume.clone(), format: Some(MeshFormat::Gmsh), translate: g.translate }))
            }
            (None, None) => None,
        }
    }
}

/// The format of a mesh file (`body.mesh.format`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MeshFormat {
    /// `abaqus`: an Abaqus input file (`.inp`).
    Abaqus,
    /// `gmsh`: a Gmsh 4.1 `.msh` (ASCII or binary).
    Gmsh,
    /// `med`: a Salome / code_aster MED file (`.med`, MED 3.x/4.x on HDF5).
    Med,
    /// `exodus`: an Exodus II file (`.exo`, `.e`, `.ex2`; netCDF-4 or netCDF-3).
    Exodus,
}

impl MeshFormat {
    /// The format a file's extension names (`.inp`: Abaqus, `.msh`: Gmsh, `.med`: MED,
    /// `.exo`/`.e`/`.ex2`: Exodus; any case).
    pub fn of_extension(file: &std::path::Path) -> Option<MeshFormat> {
        match file.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "inp" => Some(MeshFormat::Abaqus),
            "msh" => Some(MeshFormat::Gmsh),
            "med" => Some(MeshFormat::Med),
            "exo" | "e" | "ex2" => Some(MeshFormat::Exodus),
            _ => None,
        }
    }
}

/// `body.mesh`: a body read from a mesh file (hex8, tet4, tet10 and wedge6 cells, mixed or not).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MeshDef {
    /// Path of the mesh file, relative to the scene file.
    pub file: PathBuf,
    /// The part of the file that is this body: a Gmsh physical volume, an Abaqus element set or
    /// instance, a MED group of volume cells or Exodus element blocks (default: every volume
    /// element of the file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub volume: Option<String>,
    /// The file's format; defaults to the one its extension names (`.inp`, `.msh`, `.med`, `.exo`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub format: Option<MeshFormat>,
    /// Shift applied to all node coordinates.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translate: Option<[f64; 3]>,
}

impl MeshDef {
    /// The file's format: `format`, else the one its extension names.
    pub fn resolved_format(&self) -> Option<MeshFormat> {
        self.format.or_else(|| MeshFormat::of_extension(&self.file))
    }
}

/// `body.box`: a structured box mesh (faces `xmin` … `zmax`).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BoxDef {
    /// Lower corner (m).
    pub min: [f64; 3],
    /// Upper corner (m), > `min` in every direction.
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
    /// `zmin`: the box's lower z side.
    Zmin,
    /// `zmax`: the box's upper z side.
    Zmax,
}

/// `body.box.cylinder`: bends a side of the box into a cylinder (axis along y).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Cylinder {
    /// The side that is bent.
    pub side: Side,
    /// Cylinder radius (m), at least half the box's x-width; the bulge must stay below the
    /// box's height.
    pub radius: f64,
}

/// `body.box.sphere`: bends a side of the box into a spherical cap (Hertz models).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Sphere {
    /// The side that is bent.
    pub side: Side,
    /// Sphere radius (m), greater than the distance from the pole to the side's farthest corner.
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

/// `body.gmsh`: a body read from a Gmsh 4.1 `.msh` (ASCII or binary; hex8, tet4, tet10 and
/// wedge6 cells, mixed or not).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GmshDef {
    /// Path of a Gmsh 4.1 `.msh`, relative to the scene file.
    pub file: PathBuf,
    /// Physical volume to take (default: every volume element of the file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub volume: Option<String>,
    /// Shift applied to all node coordinates.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translate: Option<[f64; 3]>,
}

/// Most nodes of one body: its 3 DOFs per node must fit the 32-bit indices of METIS.
pub const MAX_BODY_NODES: usize = i32::MAX as usize / 3;
