//! Meshes: hexahedral bodies with named boundary faces.
//!
//! Owns the [`Mesh`] (all bodies, global node and element numbering, one node set per body —
//! bodies never share nodes), the structured box generator ([`boxgen`]), the Gmsh 4.1 importer
//! ([`gmsh`]), the boundary topology shared by both ([`topology`]) and a body's rigid motions
//! ([`rigid`]). Node order inside a hexahedron is the VTK/Gmsh/XDMF one: bottom face 0-1-2-3
//! counter-clockwise seen from above, top face 4-5-6-7 above it.

pub mod boxgen;
pub mod gmsh;
pub mod rigid;
pub mod topology;

use std::ops::Range;

use crate::error::{Error, Result};

/// An empty vector with room for `n` items, or the error naming `what` and the bytes asked for
/// (instead of the allocator's abort).
pub fn try_vec<T>(what: &str, n: usize) -> Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| Error::alloc(what, n.saturating_mul(std::mem::size_of::<T>())))?;
    Ok(v)
}

/// Room for `extra` more items in `v`, or the error naming `what`.
pub fn try_grow<T>(v: &mut Vec<T>, what: &str, extra: usize) -> Result<()> {
    v.try_reserve_exact(extra).map_err(|_| Error::alloc(what, v.len().saturating_add(extra).saturating_mul(std::mem::size_of::<T>())))
}

/// One quadrilateral of a named face: the element it bounds and its four nodes, ordered so that
/// the right-hand rule gives the outward normal of that element.
#[derive(Clone, Debug, PartialEq)]
pub struct FaceQuad {
    pub elem: usize,
    pub nodes: [usize; 4],
}

/// A named part of a body's boundary, e.g. `upper.zmax` or a Gmsh physical surface.
#[derive(Clone, Debug)]
pub struct Face {
    /// Full name, `<body>.<face>`.
    pub name: String,
    pub body: usize,
    pub quads: Vec<FaceQuad>,
}

impl Face {
    /// The distinct nodes of the face, sorted.
    pub fn nodes(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self.quads.iter().flat_map(|q| q.nodes).collect();
        v.sort_unstable();
        v.dedup();
        v
    }
}

/// The part of the global numbering that belongs to one body.
#[derive(Clone, Debug)]
pub struct BodyMesh {
    pub name: String,
    pub nodes: Range<usize>,
    pub elems: Range<usize>,
}

/// A body's mesh in local numbering, as a generator or importer produces it.
#[derive(Clone, Debug, Default)]
pub struct BodyGeometry {
    pub nodes: Vec<[f64; 3]>,
    pub hexes: Vec<[usize; 8]>,
    /// (short face name, quads in local numbering)
    pub faces: Vec<(String, Vec<FaceQuad>)>,
}

/// All bodies of a scene in one global numbering.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub nodes: Vec<[f64; 3]>,
    pub hexes: Vec<[usize; 8]>,
    pub bodies: Vec<BodyMesh>,
    pub faces: Vec<Face>,
}

impl Mesh {
    /// Appends a body, shifting its local numbering to the global one; panics where memory runs
    /// out ([`Mesh::try_push_body`] returns the error).
    pub fn push_body(&mut self, name: &str, geom: BodyGeometry) {
        self.try_push_body(name, geom).unwrap_or_else(|e| panic!("{e}"))
    }

    /// [`Mesh::push_body`], with a failed allocation of the mesh's node or element arrays as
    /// an error.
    pub fn try_push_body(&mut self, name: &str, geom: BodyGeometry) -> Result<()> {
        try_grow(&mut self.nodes, "mesh nodes", geom.nodes.len())?;
        try_grow(&mut self.hexes, "mesh hexahedra", geom.hexes.len())?;
        let n0 = self.nodes.len();
        let e0 = self.hexes.len();
        let body = self.bodies.len();
        self.nodes.extend_from_slice(&geom.nodes);
        self.hexes.extend(geom.hexes.iter().map(|h| h.map(|v| v + n0)));
        for (fname, quads) in geom.faces {
            self.faces.push(Face {
                name: format!("{name}.{fname}"),
                body,
                quads: quads
                    .into_iter()
                    .map(|q| FaceQuad { elem: q.elem + e0, nodes: q.nodes.map(|v| v + n0) })
                    .collect(),
            });
        }
        self.bodies.push(BodyMesh {
            name: name.to_string(),
            nodes: n0..self.nodes.len(),
            elems: e0..self.hexes.len(),
        });
        Ok(())
    }

    pub fn face(&self, name: &str) -> Option<&Face> {
        self.faces.iter().find(|f| f.name == name)
    }

    pub fn face_names(&self) -> Vec<&str> {
        self.faces.iter().map(|f| f.name.as_str()).collect()
    }

    /// Body index of every element.
    pub fn elem_body(&self) -> Vec<usize> {
        let mut out = vec![0; self.hexes.len()];
        for (b, body) in self.bodies.iter().enumerate() {
            out[body.elems.clone()].fill(b);
        }
        out
    }

    /// Corner coordinates of element `e`.
    pub fn hex_coords(&self, e: usize) -> [[f64; 3]; 8] {
        self.hexes[e].map(|v| self.nodes[v])
    }

    pub fn quad_coords(&self, q: &FaceQuad) -> [[f64; 3]; 4] {
        q.nodes.map(|v| self.nodes[v])
    }
}
