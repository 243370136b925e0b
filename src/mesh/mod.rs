//! Meshes: bodies of hexahedra, tetrahedra and wedges (mixed) with named boundary faces.
//!
//! Owns the [`Mesh`] (all bodies, global node and cell numbering, one node set per body —
//! bodies never share nodes), the cell and facet types ([`cell`]), the structured box generator
//! ([`boxgen`]), the Gmsh 4.1, Abaqus `.inp`, MED `.med` and Exodus II importers ([`gmsh`], [`abaqus`], [`med`], [`exodus`]), the boundary topology shared by them
//! ([`topology`]) and a body's rigid motions ([`rigid`]).

pub mod abaqus;
pub mod boxgen;
pub(crate) mod cell;
pub mod exodus;
pub mod gmsh;
pub mod med;
pub(crate) mod rigid;
pub(crate) mod tags;
pub(crate) mod topology;

use std::ops::Range;

use crate::error::{Error, Result};

pub use cell::{Cell, CellKind, Facet, FacetKind, HEX20_EDGES, HEX27_FACES, MAX_CELL_DOFS, MAX_CELL_NODES, WEDGE15_EDGES};

/// What a mesh file offers a scene, from one parse: the names a body's `volume` may take and
/// the bodies of every volume cell together (first) and of each name, in that order (each its
/// own error where it cannot be a body).
pub type Survey = (Vec<String>, Vec<Result<BodyGeometry>>);

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

/// A named part of a body's boundary, e.g. `upper.zmax` or a Gmsh physical surface.
#[derive(Clone, Debug)]
pub struct Face {
    /// Full name, `<body>.<face>`.
    pub name: String,
    /// Index of the body it bounds.
    pub body: usize,
    /// Its facets, in global numbering.
    pub facets: Vec<Facet>,
}

impl Face {
    /// The distinct nodes of the face, sorted.
    pub fn nodes(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self.facets.iter().flat_map(|q| q.nodes().to_vec()).collect();
        v.sort_unstable();
        v.dedup();
        v
    }
}

/// The part of the global numbering that belongs to one body.
#[derive(Clone, Debug)]
pub struct BodyMesh {
    /// Name of the body.
    pub name: String,
    /// Its nodes in the global numbering.
    pub nodes: Range<usize>,
    /// Its elements in the global numbering.
    pub elems: Range<usize>,
}

/// A body's mesh in local numbering, as a generator or importer produces it.
#[derive(Clone, Debug, Default)]
pub struct BodyGeometry {
    /// Coordinates of the nodes.
    pub nodes: Vec<[f64; 3]>,
    /// The cells, on local node indices.
    pub cells: Vec<Cell>,
    /// (short face name, facets in local numbering)
    pub faces: Vec<(String, Vec<Facet>)>,
}

/// All bodies of a scene in one global numbering.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Coordinates of every node (global numbering).
    pub nodes: Vec<[f64; 3]>,
    /// Every cell, on global node indices.
    pub cells: Vec<Cell>,
    /// The bodies' ranges of nodes and elements, in order.
    pub bodies: Vec<BodyMesh>,
    /// The named faces of all bodies.
    pub faces: Vec<Face>,
}

impl Mesh {
    /// Appends a body, shifting its local numbering to the global one; panics where memory runs
    /// out ([`Mesh::try_push_body`] returns the error). For the unit tests.
    #[cfg(test)]
    pub fn push_body(&mut self, name: &str, geom: BodyGeometry) {
        self.try_push_body(name, geom).unwrap_or_else(|e| panic!("{e}"))
    }

    /// Appends a body, shifting its local numbering to the global one, with a failed allocation of the mesh's node or element arrays as
    /// an error.
    pub fn try_push_body(&mut self, name: &str, geom: BodyGeometry) -> Result<()> {
        try_grow(&mut self.nodes, "mesh nodes", geom.nodes.len())?;
        try_grow(&mut self.cells, "mesh cells", geom.cells.len())?;
        let n0 = self.nodes.len();
        let e0 = self.cells.len();
        let body = self.bodies.len();
        self.nodes.extend_from_slice(&geom.nodes);
        self.cells.extend(geom.cells.iter().map(|h| h.map(|v| v + n0)));
        for (fname, facets) in geom.faces {
            self.faces.push(Face { name: format!("{name}.{fname}"), body, facets: facets.into_iter().map(|q| q.map(q.elem + e0, |v| v + n0)).collect() });
        }
        self.bodies.push(BodyMesh { name: name.to_string(), nodes: n0..self.nodes.len(), elems: e0..self.cells.len() });
        Ok(())
    }

    /// The face of full name `name` (`<body>.<face>`).
    pub fn face(&self, name: &str) -> Option<&Face> {
        self.faces.iter().find(|f| f.name == name)
    }

    /// The full names of all faces.
    pub fn face_names(&self) -> Vec<&str> {
        self.faces.iter().map(|f| f.name.as_str()).collect()
    }

    /// Body index of every element.
    pub fn elem_body(&self) -> Vec<usize> {
        let mut out = vec![0; self.cells.len()];
        for (b, body) in self.bodies.iter().enumerate() {
            out[body.elems.clone()].fill(b);
        }
        out
    }

    /// Node coordinates of cell `e`.
    pub fn cell_coords(&self, e: usize) -> Vec<[f64; 3]> {
        self.cells[e].coords(&self.nodes)
    }

    /// Node coordinates of facet `q`.
    pub fn facet_coords(&self, q: &Facet) -> Vec<[f64; 3]> {
        q.nodes().iter().map(|&v| self.nodes[v]).collect()
    }

    /// How many cells of each type (types in [`CellKind::ALL`] order, absent ones left out).
    pub fn cell_counts(&self) -> Vec<(CellKind, usize)> {
        cell_counts(&self.cells)
    }
}

/// How many of `cells` are of each type (in [`CellKind::ALL`] order, absent ones left out).
pub fn cell_counts(cells: &[Cell]) -> Vec<(CellKind, usize)> {
    let mut n = [0usize; CellKind::COUNT];
    for c in cells {
        n[c.kind.code()] += 1;
    }
    CellKind::ALL.iter().zip(n).filter(|(_, k)| *k > 0).map(|(&t, k)| (t, k)).collect()
}

/// "1000 hexahedra", "24 4-node tetrahedra and 8 wedges" from (count, plural name) pairs (zero
/// counts left out); `none` when all are zero.
pub fn describe_counts<'a>(counts: impl IntoIterator<Item = (usize, &'a str)>, none: &str) -> String {
    let parts: Vec<String> = counts.into_iter().filter(|(n, _)| *n > 0).map(|(n, name)| format!("{n} {name}")).collect();
    if parts.is_empty() {
        none.into()
    } else {
        parts.join(" and ")
    }
}

/// "1000 hexahedra", "24 4-node tetrahedra and 8 wedges".
pub fn describe_cells(cells: &[Cell]) -> String {
    describe_counts(cell_counts(cells).into_iter().map(|(t, k)| (k, t.plural())), "no cells")
}

/// "64 quadrilaterals", "32 triangles and 8 quadrilaterals".
pub fn describe_facets(facets: &[Facet]) -> String {
    let kinds = [FacetKind::Tri3, FacetKind::Quad4, FacetKind::Tri6, FacetKind::Quad8];
    describe_counts(kinds.map(|k| (facets.iter().filter(|f| f.kind == k).count(), k.plural())), "no facets")
}
