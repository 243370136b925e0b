//! Scene files: TOML → [`Scene`] (serde, unknown keys rejected with their dotted path),
//! command-line overrides (`--set key=value`), defaults, and validation of every value with the
//! offending key in the message. Checks that need the mesh (face names, element counts) live in
//! [`crate::model`].

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::qp;

pub mod keys;

/// A whole scene: bodies, materials, boundary conditions, contact, solver, decomposition, output.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    #[serde(default)]
    pub title: String,
    /// The units the scene's numbers are in, for printing and the report only.
    #[serde(default, skip_serializing_if = "Units::is_empty")]
    pub units: Units,
    #[serde(default)]
    pub mesh: MeshSettings,
    #[serde(rename = "material")]
    pub materials: Vec<Material>,
    #[serde(rename = "body")]
    pub bodies: Vec<Body>,
    /// Extra named faces, cut out of existing ones.
    #[serde(default, rename = "face", skip_serializing_if = "Vec::is_empty")]
    pub faces: Vec<FaceDef>,
    #[serde(default)]
    pub dirichlet: Vec<Dirichlet>,
    #[serde(default)]
    pub traction: Vec<Traction>,
    /// The quasi-static load path: `[load] steps = K`.
    #[serde(default)]
    pub load: LoadSettings,
    #[serde(default)]
    pub contact: ContactSettings,
    /// Bonded interfaces between bodies (mesh tying by the mortar operator).
    #[serde(default, rename = "tie", skip_serializing_if = "Vec::is_empty")]
    pub ties: Vec<Tie>,
    /// Read by [`SolverSettings::from_table`] (each key checked against the method).
    #[serde(default, skip_deserializing)]
    pub solver: SolverSettings,
    #[serde(default)]
    pub decomposition: DecompositionSettings,
    #[serde(default)]
    pub factorization: Factorization,
    #[serde(default)]
    pub output: OutputSettings,
}

/// The units of a scene's lengths and forces (stresses and E are force / length²), named only
/// to print results with them: the solver is unit-free, every number is taken as given.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Units {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<String>,
}

impl Units {
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

    fn validate(&self) -> Result<()> {
        for (key, v) in [("units.length", &self.length), ("units.force", &self.force)] {
            if let Some(v) = v {
                if v.trim().is_empty() || v.chars().count() > 16 || v.chars().any(char::is_control) {
                    return Err(Error::scene(key, format!("a unit's name of 1–16 printable characters, got {v:?}")));
                }
            }
        }
        Ok(())
    }
}

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

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Cylinder {
    /// `zmin` or `zmax`.
    pub side: String,
    pub radius: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Sphere {
    /// `zmin` or `zmax`.
    pub side: String,
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

    /// The curved side (`zmin` or `zmax`) of a cylinder or sphere, if any.
    pub fn curved_side(&self) -> Option<&str> {
        self.cylinder.as_ref().map(|c| c.side.as_str()).or(self.sphere.as_ref().map(|s| s.side.as_str()))
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

/// `name` becomes the face `<body>.<name>`: the facets of `<body>.<from>` whose centres lie in
/// one region: the box `[min, max]`, a ball, an infinite cylinder, or a half-space.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FaceDef {
    pub name: String,
    pub body: String,
    pub from: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere: Option<SphereRegion>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cylinder: Option<CylinderRegion>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub half_space: Option<HalfSpaceRegion>,
}

/// The points within `radius` of `centre`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SphereRegion {
    pub centre: [f64; 3],
    pub radius: f64,
}

/// The points within `radius` of the line through `point` along `axis`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CylinderRegion {
    pub point: [f64; 3],
    pub axis: [f64; 3],
    pub radius: f64,
}

/// The points on the side of the plane through `point` that `normal` points to (the plane
/// included).
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HalfSpaceRegion {
    pub point: [f64; 3],
    pub normal: [f64; 3],
}

/// The region a `[[face]]` selects from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Region {
    Box([f64; 3], [f64; 3]),
    Sphere(SphereRegion),
    Cylinder(CylinderRegion),
    HalfSpace(HalfSpaceRegion),
}

impl Region {
    /// Whether `x` lies in the region (its boundary included, to 10⁻¹² of its size for the
    /// round ones).
    pub fn contains(&self, x: [f64; 3]) -> bool {
        let d = |a: [f64; 3], b: [f64; 3]| -> [f64; 3] { std::array::from_fn(|k| a[k] - b[k]) };
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        match *self {
            Region::Box(lo, hi) => (0..3).all(|k| x[k] >= lo[k] && x[k] <= hi[k]),
            Region::Sphere(s) => dot(d(x, s.centre), d(x, s.centre)).sqrt() <= s.radius * (1.0 + 1e-12),
            Region::Cylinder(c) => {
                let a = c.axis.map(|v| v / dot(c.axis, c.axis).sqrt());
                let r = d(x, c.point);
                let along = dot(r, a);
                (dot(r, r) - along * along).max(0.0).sqrt() <= c.radius * (1.0 + 1e-12)
            }
            Region::HalfSpace(h) => {
                let n = h.normal.map(|v| v / dot(h.normal, h.normal).sqrt());
                let scale = dot(h.point, h.point).sqrt().max(dot(x, x).sqrt());
                dot(d(x, h.point), n) >= -1e-12 * scale
            }
        }
    }

    /// "the box […]", "the sphere of radius r about c", …, for messages.
    pub fn describe(&self) -> String {
        let v = |a: [f64; 3]| format!("({}, {}, {})", a[0], a[1], a[2]);
        match self {
            Region::Box(lo, hi) => format!("the box {} – {}", v(*lo), v(*hi)),
            Region::Sphere(s) => format!("the ball of radius {} about {}", s.radius, v(s.centre)),
            Region::Cylinder(c) => format!("the cylinder of radius {} about the axis {} through {}", c.radius, v(c.axis), v(c.point)),
            Region::HalfSpace(h) => format!("the half-space through {} on the side of {}", v(h.point), v(h.normal)),
        }
    }
}

impl FaceDef {
    /// The region it selects from; `i` its index, for the error (exactly one region, each
    /// value finite, radii > 0, directions nonzero).
    pub fn region(&self, i: usize) -> Result<Region> {
        let key = |k: &str| format!("face[{i}].{k}");
        let finite =
            |k: &str, v: &[f64]| if v.iter().all(|x| x.is_finite()) { Ok(()) } else { Err(Error::scene(key(k), format!("must be finite, got {v:?}"))) };
        let positive = |k: &str, r: f64| if r.is_finite() && r > 0.0 { Ok(()) } else { Err(Error::scene(key(k), format!("must be > 0, got {r}"))) };
        let nonzero = |k: &str, v: [f64; 3]| {
            finite(k, &v)?;
            let l = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if l > 0.0 && l.is_finite() {
                Ok(())
            } else {
                Err(Error::scene(key(k), format!("must be a nonzero direction, got {v:?}")))
            }
        };
        let given = [self.min.is_some() || self.max.is_some(), self.sphere.is_some(), self.cylinder.is_some(), self.half_space.is_some()];
        if given.iter().filter(|&&g| g).count() != 1 {
            return Err(Error::scene(format!("face[{i}]"), "give exactly one region: `min` and `max` (a box), `sphere`, `cylinder` or `half_space`"));
        }
        if given[0] {
            let (Some(lo), Some(hi)) = (self.min, self.max) else {
                return Err(Error::scene(key(if self.min.is_none() { "min" } else { "max" }), "a box needs both `min` and `max`"));
            };
            finite("min", &lo)?;
            finite("max", &hi)?;
            return Ok(Region::Box(lo, hi));
        }
        if let Some(s) = self.sphere {
            finite("sphere.centre", &s.centre)?;
            positive("sphere.radius", s.radius)?;
            return Ok(Region::Sphere(s));
        }
        if let Some(c) = self.cylinder {
            finite("cylinder.point", &c.point)?;
            nonzero("cylinder.axis", c.axis)?;
            positive("cylinder.radius", c.radius)?;
            return Ok(Region::Cylinder(c));
        }
        let h = self.half_space.expect("one region is given");
        finite("half_space.point", &h.point)?;
        nonzero("half_space.normal", h.normal)?;
        Ok(Region::HalfSpace(h))
    }
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Component {
    X,
    Y,
    Z,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Dirichlet {
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

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Traction {
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

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSettings {
    /// `false` drops every contact pair: the bodies are solved as independent elastic problems.
    #[serde(default = "yes")]
    pub enabled: bool,
    #[serde(default)]
    pub pair: Vec<ContactPair>,
}

fn yes() -> bool {
    true
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings { enabled: true, pair: vec![] }
    }
}

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ContactPair {
    /// The slave face (its nodes carry the multipliers); with `master`, or alone with `faces`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub slave: String,
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub master: String,
    /// The two faces, where the slave is left to the rule of [`ContactPair::resolve`] (or named
    /// by `slave` or `master` alone).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub faces: Option<[String; 2]>,
    #[serde(default)]
    pub friction: Friction,
    /// Matching tolerance of slave and master node coordinates (m); default 1e-8 × model size.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// `"mortar"` or `"node-to-node"`; default: node-to-node where every slave node has a master
    /// node at its place, mortar otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub discretization: Option<Discretization>,
    /// Mortar: how far (m) along its normal a slave facet looks for master facets; default
    /// [`default_search_distance`] of the slave face.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search_distance: Option<f64>,
    /// The largest initial overlap taken as touching, as a fraction of the local element size
    /// (√ of the slave node's area); default [`DEFAULT_MAX_OVERLAP`]. A larger one is an error
    /// unless `interference`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_overlap: Option<f64>,
    /// A press fit: `true`, the bodies overlap as meshed by design and the solution removes the
    /// overlap (any depth within the search distance); a length δ, every slave node of the
    /// pair starts δ inside the master whatever the meshed gap (two faceted meshes of one
    /// curved face differ by their chords' sagittas).
    #[serde(default, skip_serializing_if = "Fit::is_none")]
    pub interference: Fit,
}

/// `contact.pair.interference`: none, as meshed (`true`), or a stated radial interference δ.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Fit {
    #[default]
    None,
    Meshed,
    Stated(f64),
}

impl Fit {
    pub fn is_none(&self) -> bool {
        *self == Fit::None
    }

    /// Whether the bodies may overlap as meshed.
    pub fn allows_overlap(&self) -> bool {
        !self.is_none()
    }
}

impl Serialize for Fit {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match *self {
            Fit::None => s.serialize_bool(false),
            Fit::Meshed => s.serialize_bool(true),
            Fit::Stated(d) => s.serialize_f64(d),
        }
    }
}

impl<'de> Deserialize<'de> for Fit {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Fit;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("true, false or an interference length")
            }
            fn visit_bool<E: serde::de::Error>(self, b: bool) -> std::result::Result<Fit, E> {
                Ok(if b { Fit::Meshed } else { Fit::None })
            }
            fn visit_f64<E: serde::de::Error>(self, x: f64) -> std::result::Result<Fit, E> {
                Ok(Fit::Stated(x))
            }
            fn visit_i64<E: serde::de::Error>(self, x: i64) -> std::result::Result<Fit, E> {
                Ok(Fit::Stated(x as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, x: u64) -> std::result::Result<Fit, E> {
                Ok(Fit::Stated(x as f64))
            }
        }
        d.deserialize_f64(V)
    }
}

/// The default largest initial overlap taken as touching: 10⁻³ of the local element size
/// (bodies meshed touching overlap by round-off and by the facets' chords: 10⁻⁶–10⁻⁴ h).
pub const DEFAULT_MAX_OVERLAP: f64 = 1e-3;

/// How a contact or tied interface is discretized.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Discretization {
    /// Dual mortar (biorthogonal multipliers on the slave face): any two meshes.
    Mortar,
    /// One pair per slave node and the master node at its place: matching meshes only.
    NodeToNode,
}

/// The default mortar search distance: a tenth of the slave face's bounding-box diagonal.
pub fn default_search_distance(diagonal: f64) -> f64 {
    0.1 * diagonal
}

/// A bonded interface: the slave face's displacement equals the master face's, weakly (the
/// mortar projection), in all three directions.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Tie {
    pub slave: String,
    pub master: String,
    /// As for contact pairs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search_distance: Option<f64>,
}

/// Friction law of a contact pair.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum Friction {
    #[default]
    None,
    /// Isotropic Tresca with slip bound g (MPa).
    Tresca { g: f64 },
    /// Orthotropic Tresca: slip bounds g1 along `direction` (projected onto the contact plane),
    /// g2 across it.
    Orthotropic { g1: f64, g2: f64, direction: [f64; 3] },
    /// Coulomb: ‖λτ,ᵢ‖ ≤ μ λν,ᵢ (`mu`), or orthotropic with `mu1` along `direction` and `mu2`
    /// across it; solved as a fixed point on the slip bounds (`qp::coulomb`).
    Coulomb {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mu: Option<f64>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mu1: Option<f64>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mu2: Option<f64>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        direction: Option<[f64; 3]>,
    },
}

impl Friction {
    /// The direction the pair's first tangent follows, when the law has one.
    pub fn direction(&self) -> Option<[f64; 3]> {
        match *self {
            Friction::Orthotropic { direction, .. } => Some(direction),
            Friction::Coulomb { direction, .. } => direction,
            _ => None,
        }
    }
}

pub use crate::qp::{CgStop, Method};

/// The FETI preconditioner of the TFETI dual (`solver.preconditioner`; where it applies is
/// decided by `pipeline::preconditioner`).
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Preconditioner {
    /// Dirichlet for the plain CG of a TFETI scene without contact, none elsewhere.
    #[default]
    Auto,
    None,
    /// K_s's block on the DOFs the rows touch.
    Lumped,
    /// The Schur complement of K_s onto those DOFs, applied through a K_ii solve.
    Dirichlet,
    /// The same Schur complement held as a dense matrix (from a partial factorization).
    DirichletDense,
}

impl Preconditioner {
    pub fn name(self) -> &'static str {
        match self {
            Preconditioner::Auto => "auto",
            Preconditioner::None => "none",
            Preconditioner::Lumped => "lumped",
            Preconditioner::Dirichlet => "dirichlet",
            Preconditioner::DirichletDense => "dirichlet-dense",
        }
    }
}

/// How the A-products use the factors (`solver.precision`).
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Precision {
    /// A contact solve keeps the factors also in single precision, and its inner CG iterations
    /// use them where their measured error is within what the iteration allows.
    #[default]
    Mixed,
    /// Double precision only.
    Double,
}

impl Precision {
    pub fn name(self) -> &'static str {
        match self {
            Precision::Mixed => "mixed",
            Precision::Double => "double",
        }
    }
}

/// The `[solver]` table: `method`, the settings every method reads ([`qp::Common`]), the
/// method's own ([`qp::MethodParams`]: a key the method does not read is an error) and the
/// FETI preconditioner and the products' precision. Defaults live with the solvers' parameter
/// structs.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverSettings {
    pub params: qp::Params,
    pub preconditioner: Preconditioner,
    pub precision: Precision,
    /// `method` absent (or `"auto"`): the method is chosen for the dual the scene is solved on
    /// (`pipeline::resolve_method`); `params` holds the default method's defaults until then.
    pub auto: bool,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings { params: qp::Params::default(), preconditioner: Preconditioner::Auto, precision: Precision::default(), auto: true }
    }
}

impl SolverSettings {
    /// Reads the `[solver]` table; errors name the key (`solver.<key>`).
    pub fn from_table(mut t: toml::Table) -> Result<Self> {
        fn value<T: serde::de::DeserializeOwned>(key: &str, v: toml::Value) -> Result<T> {
            serde_path_to_error::deserialize(v).map_err(|e| {
                let sub = e.path().to_string();
                let key = if sub == "." { format!("solver.{key}") } else { format!("solver.{sub}") };
                Error::scene(key, e.inner().message().replace('\n', " "))
            })
        }
        let auto = match t.get("method") {
            None => true,
            Some(toml::Value::String(m)) => m == "auto",
            Some(_) => false,
        };
        let method: Method = match t.remove("method") {
            Some(v) if !auto => value("method", v).map_err(|e| match e {
                Error::Scene { key, msg } => Error::Scene { key, msg: format!("{msg}, or `auto` (the default)") },
                e => e,
            })?,
            _ => Method::default(),
        };
        let preconditioner = t.remove("preconditioner").map_or(Ok(Preconditioner::Auto), |v| value("preconditioner", v))?;
        let precision = t.remove("precision").map_or(Ok(Precision::default()), |v| value("precision", v))?;
        let common_keys = Self::common_keys();
        let (common, own): (toml::Table, toml::Table) = t.into_iter().partition(|(k, _)| common_keys.contains(k));
        if let (true, Some(key)) = (auto, own.keys().next()) {
            return Err(Error::scene(
                format!("solver.{key}"),
                format!(
                    "not a setting every method reads ({}); name the method whose setting it is (solver.method), the automatic choice takes its defaults",
                    common_keys.join(", ")
                ),
            ));
        }
        let common: qp::Common = value("", toml::Value::Table(common))?;
        let mut track = serde_path_to_error::Track::new();
        let own = qp::MethodParams::deserialize(method, serde_path_to_error::Deserializer::new(toml::Value::Table(own), &mut track)).map_err(|e| {
            let msg = e.message().replace('\n', " ");
            match msg.strip_prefix("unknown field `").and_then(|r| r.split_once('`')) {
                Some((key, rest)) => {
                    let its = rest.trim_start_matches(", ").replace("expected one of ", "").replace("expected ", "");
                    let its = if its.contains("no fields") { "none".to_string() } else { its };
                    Error::scene(
                        format!("solver.{key}"),
                        format!("not a setting of method \"{}\" (its own: {its}; every method's: {})", method.name(), common_keys.join(", ")),
                    )
                }
                None => Error::scene(format!("solver.{}", track.path()), msg),
            }
        })?;
        let params = qp::Params { common, method: own };
        params.validate().map_err(|e| Error::scene(format!("solver.{}", e.key), e.msg))?;
        Ok(SolverSettings { params, preconditioner, precision, auto })
    }

    /// The keys of [`qp::Common`].
    fn common_keys() -> Vec<String> {
        toml::Table::try_from(qp::Common::default()).map(|t| t.keys().cloned().collect()).unwrap_or_default()
    }

    /// The table as [`SolverSettings::from_table`] reads it.
    pub fn to_table(&self) -> toml::Table {
        let mut t = toml::Table::new();
        t.insert("method".into(), if self.auto { "auto" } else { self.params.method().name() }.into());
        t.extend(toml::Table::try_from(&self.params.common).unwrap_or_default());
        if !self.auto {
            t.extend(toml::Table::try_from(&self.params.method).unwrap_or_default());
        }
        if self.preconditioner != Preconditioner::Auto {
            t.insert("preconditioner".into(), self.preconditioner.name().into());
        }
        if self.precision != Precision::default() {
            t.insert("precision".into(), self.precision.name().into());
        }
        t
    }
}

impl Serialize for SolverSettings {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        self.to_table().serialize(s)
    }
}

/// How each body is split (TFETI, docs/method.md, "TFETI and H-TFETI"): the `[decomposition]` table.
#[derive(Clone, Debug, Deserialize, Serialize)]
// `rename`: the messages for a malformed table keep saying "expected struct Decomposition"
#[serde(deny_unknown_fields, rename = "Decomposition")]
pub struct DecompositionSettings {
    /// METIS subdomains per body. 1 is the monolithic dual (Dirichlet eliminated, no gluing,
    /// no coarse problem) unless `tfeti = true`. Absent (with `target_dofs`): chosen by cost
    /// (`pipeline::plan`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub subdomains: Option<usize>,
    /// Instead of `subdomains`: as many subdomains per body as give about this many DOFs each.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_dofs: Option<usize>,
    /// TFETI even with one subdomain per body (all floating, Dirichlet as multiplier rows).
    #[serde(default)]
    pub tfeti: bool,
    /// Gluing rows of the interface DOFs.
    #[serde(default)]
    pub gluing: Gluing,
    /// How TFETI holds the Dirichlet conditions: multiplier rows on every copy, or eliminated
    /// inside the subdomains that carry them (hybrid).
    #[serde(default)]
    pub dirichlet: DirichletMode,
    /// How Gλ = e is kept: the oblique projector P̃ (one QP solve) or the orthogonal one with
    /// SMALSE-M's augmented-Lagrangian loop around the QP solver.
    #[serde(default)]
    pub projector: Projector,
    /// SMALSE-M's penalty ϱ as a multiple of σ_max(PFP) (orthogonal projector only).
    #[serde(default = "unit")]
    pub penalty: f64,
    /// The inner CG (TSSN's, plain CG's) runs projected onto Ker G ∩ W, W a Newton step's
    /// subspace, with the orthogonal projector of G = RᵀBᵀ restricted to W (oblique projector
    /// only); the FETI preconditioner acts there. Default true.
    #[serde(default = "yes")]
    pub projected_cg: bool,
    /// H-TFETI: subdomains per cluster (METIS on each body's subdomain graph); a cluster's
    /// subdomains are joined at a few corner nodes inside it and the coarse problem has six
    /// unknowns per cluster. 1 (default): TFETI.
    #[serde(default = "one")]
    pub subdomains_per_cluster: usize,
    /// How the coarse problems C = G_E G_Eᵀ (and SMALSE-M's GGᵀ) are solved: factorized on
    /// every rank, or as the rows of their inverses each rank reads (TSSN's restricted GΠGᵀ
    /// stays factorized).
    #[serde(default)]
    pub coarse_solve: CoarseSolve,
}

fn unit() -> f64 {
    1.0
}

impl Default for DecompositionSettings {
    fn default() -> Self {
        DecompositionSettings {
            subdomains: None,
            target_dofs: None,
            tfeti: false,
            gluing: Default::default(),
            dirichlet: Default::default(),
            projector: Default::default(),
            penalty: 1.0,
            projected_cg: true,
            subdomains_per_cluster: 1,
            coarse_solve: CoarseSolve::Factor,
        }
    }
}

impl DecompositionSettings {
    /// Subdomains for a body with `dofs` DOFs.
    pub fn parts(&self, dofs: usize) -> usize {
        match (self.target_dofs, self.subdomains) {
            (Some(t), _) => dofs.div_ceil(t).max(1),
            (None, Some(s)) => s,
            // automatic: fixed by cost before anything is assembled (`pipeline::plan`)
            (None, None) => 1,
        }
    }

    /// Whether bodies of `body_dofs` DOFs are solved by TFETI (else by the monolithic dual).
    pub fn is_tfeti(&self, body_dofs: &[usize]) -> bool {
        self.tfeti || body_dofs.iter().any(|&d| self.parts(d) > 1)
    }
}

/// How the copies of an interface DOF are glued.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Gluing {
    #[default]
    Orthonormal,
    Chain,
}

/// See [`DecompositionSettings::dirichlet`].
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum DirichletMode {
    /// One multiplier row per held DOF of every copy: every subdomain floating (total FETI).
    Multipliers,
    /// Held inside the subdomains that carry them: the held DOFs leave K_s, its kernel keeps
    /// the rigid motions they leave free (a subdomain that holds one only weakly keeps its rows).
    #[default]
    Eliminated,
}

/// See [`DecompositionSettings::projector`].
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Projector {
    #[default]
    Oblique,
    Orthogonal,
}

/// See [`DecompositionSettings::coarse_solve`].
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum CoarseSolve {
    /// Every rank factorizes C and solves with the whole factor (replicated).
    #[default]
    Factor,
    /// Every rank holds the rows of C⁻¹ of its own pieces, computed once from the factor,
    /// which is then dropped: a solve is those dense rows times the reduced G x, and one more
    /// reduction of the result.
    Explicit,
}

/// Fill-reducing ordering of the sparse Cholesky factorizations.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum OrderingKind {
    /// METIS nested dissection of the node graph, expanded to the DOFs.
    #[default]
    Metis,
    /// faer's approximate minimum degree.
    Amd,
}

#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Factorization {
    #[serde(default)]
    pub ordering: OrderingKind,
}

/// The magnitudes double precision carries through the whole computation: Young's modulus
/// (MPa), lengths (m: coordinates, element edges, radii), tractions, prescribed displacements
/// and slip bounds must lie in `[MIN, MAX]` = 1e-30 … 1e30 (0 where 0 means "none").
///
/// Why this range: the arithmetic multiplies these inputs several deep. A stiffness entry is
/// ~ E·h (≤ 1e60 when E and h are), an element volume ~ h³ (≤ 1e90), a nodal load ~ p·h²
/// (≤ 1e90), a displacement ~ p·h/E, a dual operator entry ~ 1/(E·h); the Cholesky
/// factorization and every squared norm (‖b‖², ‖Ku − f‖², the Gram matrices) multiply two of
/// them and sum up to ~1e10 terms: ≤ 1e190 at the extremes, inside the 1e±308 of a double
/// (and far above its subnormal range 1e-308, so no residual or stopping test underflows to 0).
/// With E = 1e200 instead, E² already overflows and the solver stops at once with u = 0. The
/// range is still 30 orders of magnitude either side of SI or mm/MPa units.
pub mod range {
    pub const MIN: f64 = 1e-30;
    pub const MAX: f64 = 1e30;
    /// The smallest 1 − 2ν (and 1 + ν) allowed: λ = Eν/((1+ν)(1−2ν)) is then at most ~1e8·E
    /// (≤ 1e38), and the stiffness's condition number grows by at most ~1e8 over a compressible
    /// material's, which leaves digits to solve at ε = 1e-8 on the meshes this code runs; ν
    /// nearer 1/2 gives a K that double precision cannot factorize meaningfully (at
    /// 1 − 2ν ~ 1e-16 not even 1 − 2ν itself has a correct digit). ν = 0.4999 (the stability
    /// suite's `run/stress/nu_04999.toml`) has 1 − 2ν = 2e-4.
    pub const POISSON_MARGIN: f64 = 1e-8;
    /// The largest ratio of an element's longest edge to its shortest: the stiffness's
    /// condition number grows with its square (1e14 here, two digits left to solve at
    /// ε = 1e-8). Measured on the seed's upper block thinned to t with 4 × 4 × 4 nodes (edges
    /// 0.67 and t/3): ratios 2e6 and 2e7 solve, 2e8 fails in the Cholesky factorization.
    pub const MAX_ASPECT: f64 = 1e7;

    /// Whether `v` lies in [MIN, MAX] (or is 0, when `zero_ok`).
    pub fn carries(v: f64, zero_ok: bool) -> bool {
        (zero_ok && v == 0.0) || (MIN..=MAX).contains(&v.abs())
    }
}

/// The one-line reason for a value outside [`range`].
fn out_of_range(what: &str, v: f64, unit: &str) -> String {
    format!(
        "{what} {v:e}{unit} lies outside {:e} … {:e}{unit}, the range double precision carries through the stiffness, loads and norms (scale the units)",
        range::MIN,
        range::MAX
    )
}

/// Most nodes of one body: its 3 DOFs per node must fit the 32-bit indices of METIS.
pub const MAX_BODY_NODES: usize = i32::MAX as usize / 3;

/// Load steps at most: every step is a solve and a group in the result file.
pub const MAX_LOAD_STEPS: usize = 10_000;

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

#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSettings {
    /// HDF5 file; the XDMF (`.xdmf`) and JSON report (`.json`) go beside it. Default
    /// `out/<scene file stem>.h5`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<PathBuf>,
    #[serde(default = "default_fields")]
    pub fields: Vec<String>,
    #[serde(default = "yes")]
    pub xdmf: bool,
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
}

fn default_fields() -> Vec<String> {
    FIELDS.iter().map(|s| s.to_string()).collect()
}

impl Default for OutputSettings {
    fn default() -> Self {
        OutputSettings { path: None, fields: default_fields(), xdmf: true, report: true, verify: false, export_dual: None, export_fclib: None }
    }
}

/// A scene as loaded: the values plus where it came from.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    pub scene: Scene,
    /// The scene file.
    pub path: PathBuf,
}

impl LoadedScene {
    /// Directory that relative paths in the scene are resolved against.
    pub fn dir(&self) -> PathBuf {
        self.path.parent().map(Path::to_path_buf).unwrap_or_default()
    }

    /// The resolved HDF5 output path.
    pub fn output_path(&self) -> PathBuf {
        self.scene.output.path.clone().unwrap_or_else(|| {
            let stem = self.path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or("result".into());
            PathBuf::from("out").join(format!("{stem}.h5"))
        })
    }
}

/// Reads, overrides (`key=value` pairs), resolves and validates a scene file.
pub fn load(path: &Path, overrides: &[String]) -> Result<LoadedScene> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path.display().to_string(), e))?;
    let scene = parse(&text, &path.display().to_string(), overrides)?;
    Ok(LoadedScene { scene, path: path.to_path_buf() })
}

/// Parses scene text (`file` is only used in messages).
pub fn parse(text: &str, file: &str, overrides: &[String]) -> Result<Scene> {
    let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| Error::Parse { file: file.into(), msg: one_line_toml_error(text, &e) })?;
    for o in overrides {
        apply_override(&mut table, o)?;
    }
    let solver = match table.remove("solver") {
        None => SolverSettings::default(),
        Some(toml::Value::Table(t)) => SolverSettings::from_table(t)?,
        Some(_) => return Err(Error::scene("solver", "must be a table")),
    };
    let mut scene: Scene = serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
        let path = e.path().to_string();
        let msg = e.inner().message().replace('\n', " ");
        Error::Scene { key: if path == "." { file.into() } else { path }, msg }
    })?;
    scene.solver = solver;
    scene.resolve();
    scene.validate()?;
    Ok(scene)
}

fn one_line_toml_error(text: &str, e: &toml::de::Error) -> String {
    let msg = e.message().trim().replace('\n', " ");
    match e.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let col = before.len() - before.rfind('\n').map_or(0, |p| p + 1) + 1;
            format!("line {line}, column {col}: {msg}")
        }
        None => msg,
    }
}

/// `a.b.0.c=value`: sets a (possibly new) key; numeric parts index arrays. The value is parsed as
/// TOML (`16`, `1e-8`, `"gimssn"`, `[0, 0, -1]`, `false`), and taken as a plain string otherwise.
pub fn apply_override(table: &mut toml::Table, assignment: &str) -> Result<()> {
    let bad = |msg: &str| Error::scene(format!("--set {assignment}"), msg);
    let (key, raw) = assignment.split_once('=').ok_or_else(|| bad("expected key=value"))?;
    let key = key.trim();
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(bad("empty key component"));
    }
    let value = match format!("v = {}", raw.trim()).parse::<toml::Table>() {
        Ok(mut t) => t.remove("v").unwrap_or(toml::Value::String(raw.into())),
        Err(_) => toml::Value::String(raw.trim().into()),
    };
    let mut root = toml::Value::Table(std::mem::take(table));
    let result = set_path(&mut root, &parts, value).map_err(|m| bad(&m));
    if let toml::Value::Table(t) = root {
        *table = t;
    }
    result
}

fn set_path(root: &mut toml::Value, parts: &[&str], value: toml::Value) -> std::result::Result<(), String> {
    let mut cur = root;
    for (i, part) in parts.iter().enumerate() {
        let last = i + 1 == parts.len();
        let here = parts[..i].join(".");
        cur = match cur {
            toml::Value::Table(t) => {
                if last {
                    t.insert(part.to_string(), value);
                    return Ok(());
                }
                t.entry(part.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()))
            }
            toml::Value::Array(a) => {
                let idx: usize = part.parse().map_err(|_| format!("`{part}` is not an index of the array `{here}`"))?;
                let len = a.len();
                let slot = a.get_mut(idx).ok_or_else(|| format!("index {idx} out of range: `{here}` has {len} entries"))?;
                if last {
                    *slot = value;
                    return Ok(());
                }
                slot
            }
            _ => return Err(format!("`{here}` is not a table")),
        };
    }
    Ok(())
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

    /// Checks every value that can be checked without the mesh.
    pub fn validate(&self) -> Result<()> {
        let finite = |key: String, v: &[f64]| -> Result<()> {
            if v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(Error::scene(key, format!("must be finite, got {v:?}")))
            }
        };
        self.units.validate()?;
        if self.mesh.n < 2 {
            return Err(Error::scene("mesh.n", format!("must be at least 2 nodes per edge, got {}", self.mesh.n)));
        }
        if self.materials.is_empty() {
            return Err(Error::scene("material", "at least one [[material]] is required"));
        }
        // name → index (a set per kind: linear, not a scan of the entries before each)
        let mut material_names = std::collections::HashSet::with_capacity(self.materials.len());
        for (i, m) in self.materials.iter().enumerate() {
            let k = |f: &str| format!("material[{i}].{f}");
            finite(k("E"), &[m.e])?;
            finite(k("nu"), &[m.nu])?;
            if m.e <= 0.0 {
                return Err(Error::scene(k("E"), format!("Young's modulus must be > 0, got {}", m.e)));
            }
            if !(m.nu > -1.0 && m.nu < 0.5) {
                return Err(Error::scene(k("nu"), format!("Poisson's ratio must lie in (-1, 0.5), got {}", m.nu)));
            }
            if !range::carries(m.e, false) {
                return Err(Error::scene(k("E"), out_of_range("Young's modulus", m.e, " MPa")));
            }
            for (what, margin) in [("1 − 2ν", 1.0 - 2.0 * m.nu), ("1 + ν", 1.0 + m.nu)] {
                if margin < range::POISSON_MARGIN {
                    return Err(Error::scene(
                        k("nu"),
                        format!(
                            "Poisson's ratio {} leaves {what} = {margin:.1e} < {:e}: λ = Eν/((1+ν)(1−2ν)) would swamp the stiffness (double precision cannot solve it)",
                            m.nu,
                            range::POISSON_MARGIN
                        ),
                    ));
                }
            }
            if !material_names.insert(m.name.as_str()) {
                return Err(Error::scene(k("name"), format!("duplicate material name \"{}\"", m.name)));
            }
        }
        if self.bodies.is_empty() {
            return Err(Error::scene("body", "at least one [[body]] is required"));
        }
        let mut body_names = std::collections::HashSet::with_capacity(self.bodies.len());
        for (i, b) in self.bodies.iter().enumerate() {
            let k = |f: &str| format!("body[{i}].{f}");
            if b.name.is_empty() || b.name.contains('.') {
                return Err(Error::scene(k("name"), format!("body names must be non-empty and contain no '.', got \"{}\"", b.name)));
            }
            if !body_names.insert(b.name.as_str()) {
                return Err(Error::scene(k("name"), format!("duplicate body name \"{}\"", b.name)));
            }
            if !material_names.contains(b.material.as_str()) {
                return Err(Error::scene(k("material"), format!("unknown material \"{}\"", b.material)));
            }
            match (&b.boxed, &b.gmsh) {
                (Some(bx), None) => {
                    finite(k("box.min"), &bx.min)?;
                    finite(k("box.max"), &bx.max)?;
                    if let Some(c) = &bx.cylinder {
                        if c.side != "zmin" && c.side != "zmax" {
                            return Err(Error::scene(k("box.cylinder.side"), format!("must be \"zmin\" or \"zmax\", got \"{}\"", c.side)));
                        }
                        let (h, t) = (0.5 * (bx.max[0] - bx.min[0]), bx.max[2] - bx.min[2]);
                        if !(c.radius.is_finite() && c.radius >= h) {
                            return Err(Error::scene(
                                k("box.cylinder.radius"),
                                format!("must be finite and at least the half-width {h} of the box in x, got {}", c.radius),
                            ));
                        }
                        if !range::carries(c.radius, false) {
                            return Err(Error::scene(k("box.cylinder.radius"), out_of_range("radius", c.radius, " m")));
                        }
                        if bx.bulge(0.5 * (bx.min[0] + bx.max[0]), bx.min[1]) >= t {
                            return Err(Error::scene(k("box.cylinder.radius"), format!("the curved side would bulge more than the box's height {t}")));
                        }
                    }
                    if let Some(s) = &bx.sphere {
                        if bx.cylinder.is_some() {
                            return Err(Error::scene(k("box.sphere"), "give at most one of `cylinder` and `sphere`"));
                        }
                        if s.side != "zmin" && s.side != "zmax" {
                            return Err(Error::scene(k("box.sphere.side"), format!("must be \"zmin\" or \"zmax\", got \"{}\"", s.side)));
                        }
                        if let Some(c) = s.centre {
                            finite(k("box.sphere.centre"), &c)?;
                            if c.iter().any(|v| v.abs() > range::MAX) {
                                return Err(Error::scene(k("box.sphere.centre"), format!("coordinates beyond ±{:e} m, got {c:?}", range::MAX)));
                            }
                        }
                        let h = s.reach(bx);
                        if !(s.radius.is_finite() && s.radius > h) {
                            return Err(Error::scene(
                                k("box.sphere.radius"),
                                format!("must be finite and exceed the distance {h} from the pole to the side's farthest corner, got {}", s.radius),
                            ));
                        }
                        if !range::carries(s.radius, false) {
                            return Err(Error::scene(k("box.sphere.radius"), out_of_range("radius", s.radius, " m")));
                        }
                        let pole = s.pole(bx);
                        let t = bx.max[2] - bx.min[2];
                        if bx.bulge(pole[0], pole[1]) >= t {
                            return Err(Error::scene(k("box.sphere.radius"), format!("the curved side would bulge more than the box's height {t}")));
                        }
                    }
                    if (0..3).any(|d| bx.max[d] <= bx.min[d]) {
                        return Err(Error::scene(k("box"), "max must exceed min in every direction"));
                    }
                    if (0..3).any(|d| !(bx.max[d] - bx.min[d]).is_finite()) {
                        return Err(Error::scene(k("box"), "max − min overflows: the box is too large for floating point"));
                    }
                    if let Some(n) = bx.nodes {
                        if n.iter().any(|&v| v < 2) {
                            return Err(Error::scene(k("box.nodes"), format!("need at least 2 nodes per direction, got {n:?}")));
                        }
                        // the length scale: element edges (extent / (nodes − 1)) and coordinates
                        let edges: Vec<f64> = (0..3).map(|d| (bx.max[d] - bx.min[d]) / (n[d] - 1) as f64).collect();
                        let (lo, hi) = edges.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &h| (a.min(h), b.max(h)));
                        for (h, bad) in [(lo, lo < range::MIN), (hi, hi > range::MAX)] {
                            if bad {
                                return Err(Error::scene(
                                    k("box"),
                                    format!("body \"{}\": element edges of {h:.3e} m (extent / (nodes − 1)) lie outside {:e} … {:e} m, the length scale double precision carries through element volumes (∝ h³) and stiffness (∝ E·h); scale the units", b.name, range::MIN, range::MAX),
                                ));
                            }
                        }
                        let far = bx.min.iter().chain(&bx.max).fold(0.0f64, |a, v| a.max(v.abs()));
                        if far > range::MAX {
                            return Err(Error::scene(
                                k("box"),
                                format!(
                                    "body \"{}\": coordinates up to {far:.3e} m lie outside ±{:e} m; move the box nearer the origin or scale the units",
                                    b.name,
                                    range::MAX
                                ),
                            ));
                        }
                        let total: f64 = n.iter().map(|&v| v as f64).product();
                        if total > MAX_BODY_NODES as f64 {
                            // the nodes come from mesh.n unless the box gives its own
                            let key = if n == [self.mesh.n; 3] { "mesh.n".to_string() } else { k("box.nodes") };
                            return Err(Error::scene(
                                key,
                                format!("body \"{}\" would have {total:.3e} nodes ({n:?}); at most {MAX_BODY_NODES} are supported", b.name),
                            ));
                        }
                        if hi / lo > range::MAX_ASPECT {
                            return Err(Error::scene(
                                k("box"),
                                format!("body \"{}\": element edges of {lo:.3e} against {hi:.3e} m (ratio {:.1e}) are thinner than the element can represent (ratio at most {:e}: the stiffness's condition number grows with its square); use more nodes along the long sides, fewer across, or a thicker body", b.name, hi / lo, range::MAX_ASPECT),
                            ));
                        }
                    }
                }
                (None, Some(g)) => {
                    if let Some(t) = g.translate {
                        finite(k("gmsh.translate"), &t)?;
                    }
                }
                _ => return Err(Error::scene(format!("body[{i}]"), "give exactly one of `box` and `gmsh`")),
            }
        }
        // a nonzero load or prescribed value outside the range (see [`range`])
        let carried = |key: String, what: &str, v: &[f64], unit: &str| -> Result<()> {
            match v.iter().find(|x| !range::carries(**x, true)) {
                Some(&x) => Err(Error::scene(key, out_of_range(what, x, unit))),
                None => Ok(()),
            }
        };
        for (i, f) in self.faces.iter().enumerate() {
            f.region(i)?;
            if f.name.is_empty() || f.name.contains('.') {
                return Err(Error::scene(format!("face[{i}].name"), "face names must be non-empty and contain no '.'"));
            }
        }
        if self.load.steps == 0 || self.load.steps > MAX_LOAD_STEPS {
            return Err(Error::scene("load.steps", format!("must lie in 1..={MAX_LOAD_STEPS}, got {}", self.load.steps)));
        }
        let entries = self.dirichlet.iter().map(|d| ("dirichlet", &d.factors)).chain(self.traction.iter().map(|t| ("traction", &t.factors)));
        let mut index = std::collections::HashMap::new();
        for (what, f) in entries {
            let i = index.entry(what).or_insert(0usize);
            if let Some(f) = f {
                let key = format!("{what}[{i}].factors");
                finite(key.clone(), f)?;
                if f.len() != self.load.steps {
                    return Err(Error::scene(key, format!("needs one factor per load step (load.steps = {}), got {}", self.load.steps, f.len())));
                }
            }
            *i += 1;
        }
        for (i, d) in self.dirichlet.iter().enumerate() {
            finite(format!("dirichlet[{i}].value"), &d.value)?;
            carried(format!("dirichlet[{i}].value"), "a nonzero prescribed displacement", &d.value, " m")?;
            if d.components.is_empty() {
                return Err(Error::scene(format!("dirichlet[{i}].components"), "must name at least one of x, y, z"));
            }
        }
        for (i, t) in self.traction.iter().enumerate() {
            match (&t.p, t.pressure) {
                (Some(p), None) => {
                    finite(format!("traction[{i}].p"), p)?;
                    carried(format!("traction[{i}].p"), "a nonzero traction", p, " MPa")?;
                }
                (None, Some(p)) => {
                    finite(format!("traction[{i}].pressure"), &[p])?;
                    carried(format!("traction[{i}].pressure"), "a nonzero pressure", &[p], " MPa")?;
                }
                (p, _) => {
                    let why = if p.is_some() {
                        "give either `p` (a traction vector) or `pressure`, not both"
                    } else {
                        "give `p` (a traction vector) or `pressure` (normal, positive into the body)"
                    };
                    return Err(Error::scene(format!("traction[{i}].{}", if p.is_some() { "pressure" } else { "p" }), why));
                }
            }
        }
        for (i, t) in self.ties.iter().enumerate() {
            if t.slave == t.master {
                return Err(Error::scene(format!("tie[{i}].master"), "slave and master must be different faces"));
            }
            if let Some(d) = t.search_distance {
                if !(d.is_finite() && d > 0.0) {
                    return Err(Error::scene(format!("tie[{i}].search_distance"), format!("must be > 0, got {d}")));
                }
            }
        }
        for (i, p) in self.contact.pair.iter().enumerate() {
            let k = |f: &str| format!("contact.pair[{i}].{f}");
            match (&p.faces, p.slave.is_empty(), p.master.is_empty()) {
                (None, false, false) => {}
                (None, _, _) => {
                    return Err(Error::scene(
                        k(if p.slave.is_empty() { "slave" } else { "master" }),
                        "name both `slave` and `master`, or the two faces as `faces = [\"a.x\", \"b.y\"]`",
                    ))
                }
                (Some(f), s, m) => {
                    if f[0] == f[1] {
                        return Err(Error::scene(k("faces"), "the two faces must be different"));
                    }
                    if !s && !m {
                        return Err(Error::scene(k("faces"), "with `faces`, name at most one of `slave` and `master`"));
                    }
                    let named = if s { &p.master } else { &p.slave };
                    if !named.is_empty() && !f.contains(named) {
                        return Err(Error::scene(k(if s { "master" } else { "slave" }), format!("\"{named}\" is not one of `faces`")));
                    }
                }
            }
            if p.slave == p.master && !p.slave.is_empty() {
                return Err(Error::scene(k("master"), "slave and master must be different faces"));
            }
            if let Some(t) = p.tolerance {
                if !(t.is_finite() && t > 0.0) {
                    return Err(Error::scene(k("tolerance"), format!("must be > 0, got {t}")));
                }
            }
            if let Some(t) = p.search_distance {
                if !(t.is_finite() && t > 0.0) {
                    return Err(Error::scene(k("search_distance"), format!("must be > 0, got {t}")));
                }
            }
            if let Some(t) = p.max_overlap {
                if !(0.0..1.0).contains(&t) {
                    return Err(Error::scene(k("max_overlap"), format!("a fraction of the element size in [0, 1), got {t}")));
                }
            }
            if let Fit::Stated(d) = p.interference {
                if !(d.is_finite() && d > 0.0) {
                    return Err(Error::scene(k("interference"), format!("true, false or a length > 0, got {d}")));
                }
            }
            match &p.friction {
                Friction::None => {}
                Friction::Tresca { g } => {
                    if !(g.is_finite() && *g >= 0.0) {
                        return Err(Error::scene(k("friction.g"), format!("slip bound must be finite and ≥ 0, got {g}")));
                    }
                    carried(k("friction.g"), "a nonzero slip bound", &[*g], " MPa")?;
                }
                Friction::Orthotropic { g1, g2, direction } => {
                    for (name, g) in [("g1", g1), ("g2", g2)] {
                        if !(g.is_finite() && *g >= 0.0) {
                            return Err(Error::scene(k(&format!("friction.{name}")), format!("slip bound must be finite and ≥ 0, got {g}")));
                        }
                        carried(k(&format!("friction.{name}")), "a nonzero slip bound", &[*g], " MPa")?;
                    }
                    finite(k("friction.direction"), direction)?;
                    if direction.iter().all(|&v| v == 0.0) {
                        return Err(Error::scene(k("friction.direction"), "must be a non-zero vector"));
                    }
                }
                Friction::Coulomb { mu, mu1, mu2, direction } => {
                    let coef = |name: &str, v: f64| {
                        if v.is_finite() && v >= 0.0 {
                            Ok(())
                        } else {
                            Err(Error::scene(k(&format!("friction.{name}")), format!("friction coefficient must be finite and ≥ 0, got {v}")))
                        }
                    };
                    match (mu, mu1, mu2, direction) {
                        (Some(m), None, None, None) => coef("mu", *m)?,
                        (None, Some(a), Some(b), Some(d)) => {
                            coef("mu1", *a)?;
                            coef("mu2", *b)?;
                            finite(k("friction.direction"), d)?;
                            if d.iter().all(|&v| v == 0.0) {
                                return Err(Error::scene(k("friction.direction"), "must be a non-zero vector"));
                            }
                        }
                        _ => return Err(Error::scene(k("friction"), "coulomb takes either mu, or mu1, mu2 and direction")),
                    }
                }
            }
        }
        if self.decomposition.subdomains == Some(0) {
            return Err(Error::scene("decomposition.subdomains", "must be at least 1"));
        }
        if self.decomposition.subdomains_per_cluster == 0 {
            return Err(Error::scene("decomposition.subdomains_per_cluster", "must be at least 1"));
        }
        if !(self.decomposition.penalty > 0.0 && self.decomposition.penalty.is_finite()) {
            return Err(Error::scene("decomposition.penalty", format!("must be a positive number, got {}", self.decomposition.penalty)));
        }
        if let Some(t) = self.decomposition.target_dofs {
            if t < 24 {
                return Err(Error::scene("decomposition.target_dofs", format!("must be at least 24 (one element), got {t}")));
            }
            if self.decomposition.subdomains.is_some() {
                return Err(Error::scene("decomposition.target_dofs", "give either `subdomains` or `target_dofs`, not both"));
            }
        }
        for (i, f) in self.output.fields.iter().enumerate() {
            if !FIELDS.contains(&f.as_str()) {
                return Err(Error::scene(format!("output.fields[{i}]"), format!("unknown field \"{f}\"; known: {}", FIELDS.join(", "))));
            }
        }
        Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;

    const SPHERE_SCENE: &str = r#"
[mesh]
n = 5
[[material]]
name = "m"
E = 1.0
nu = 0.3
[[body]]
name = "cap"
material = "m"
box = { min = [0.0, 0.0, 1.0], max = [1.0, 2.0, 2.0], nodes = [5, 9, 3], sphere = { side = "zmin", radius = 4.0, centre = [0.0, 0.0] } }
[[dirichlet]]
face = "cap.zmax"
[contact]
enabled = false
"#;

    #[test]
    fn sphere_bulge_geometry() {
        let scene = parse(SPHERE_SCENE, "t", &[]).expect("valid");
        let bx = scene.bodies[0].boxed.as_ref().unwrap();
        let (r, h2) = (4.0f64, 1.0f64 + 4.0);
        // pole at the corner (0, 0): full sagitta there, 0 at the farthest corner (1, 2)
        assert!((bx.bulge(0.0, 0.0) - (r - (r * r - h2).sqrt())).abs() < 1e-14);
        assert!(bx.bulge(1.0, 2.0).abs() < 1e-14);
        assert!((bx.bulge(0.6, 0.8) - ((r * r - 1.0).sqrt() - (r * r - h2).sqrt())).abs() < 1e-14);
        // rotationally symmetric about the pole's line, ≥ 0 over the side
        assert_eq!(bx.bulge(0.0, 1.0), bx.bulge(1.0, 0.0));
        for i in 0..=10 {
            for j in 0..=20 {
                assert!(bx.bulge(0.1 * i as f64, 0.1 * j as f64) >= -1e-15);
            }
        }
        // the default centre is the side's centre: the half-diagonal is the reach
        let mut centred = bx.clone();
        centred.sphere.as_mut().unwrap().centre = None;
        assert_eq!(centred.sphere.as_ref().unwrap().pole(&centred), [0.5, 1.0]);
        assert!((centred.sphere.as_ref().unwrap().reach(&centred) - 1.25f64.sqrt()).abs() < 1e-15);
        assert!(centred.bulge(0.0, 0.0).abs() < 1e-14 && centred.bulge(1.0, 2.0).abs() < 1e-14);
        // the built mesh: the zmin nodes lie on the sphere of radius R centred above the pole,
        // the zmax nodes stay flat, the ones between in proportion
        let model = crate::model::build(&LoadedScene { scene, path: "t.toml".into() }).expect("builds");
        let zc = 1.0 + (r * r - h2).sqrt(); // the sphere's centre: the far corner at z = 1
        let (mut low, mut top) = (0, 0);
        for p in &model.mesh.nodes {
            let b = (r * r - p[0] * p[0] - p[1] * p[1]).sqrt() - (r * r - h2).sqrt();
            if p[2] < 1.0 + 1e-12 {
                low += 1;
                assert!(((p[0] * p[0] + p[1] * p[1] + (p[2] - zc) * (p[2] - zc)).sqrt() - r).abs() < 1e-12, "{p:?} off the sphere");
            } else if (p[2] - 2.0).abs() < 1e-12 {
                top += 1;
            } else {
                assert!((p[2] - (1.5 - b * 0.5)).abs() < 1e-12, "{p:?} not in proportion");
            }
        }
        assert_eq!((low, top), (45, 45));
    }

    #[test]
    fn sphere_is_validated() {
        let bad = |from: &str, to: &str, key: &str| {
            let text = SPHERE_SCENE.replace(from, to);
            let e = parse(&text, "t", &[]).expect_err(to).to_string();
            assert!(e.contains(key), "{to}: {e}");
        };
        // the radius must exceed the reach √5 of the corner pole (and the half-diagonal by default)
        bad("radius = 4.0", "radius = 2.2", "box.sphere.radius");
        bad("radius = 4.0, centre = [0.0, 0.0]", "radius = 1.1", "box.sphere.radius");
        bad("side = \"zmin\"", "side = \"xmin\"", "box.sphere.side");
        bad("nodes = [5, 9, 3],", "nodes = [5, 9, 3], cylinder = { side = \"zmin\", radius = 4.0 },", "box.sphere");
        // a cap higher than the box
        bad("max = [1.0, 2.0, 2.0]", "max = [1.0, 2.0, 1.2]", "bulge more than");
        assert!(parse(&SPHERE_SCENE.replace(", centre = [0.0, 0.0]", ""), "t", &[]).is_ok());
    }
}
