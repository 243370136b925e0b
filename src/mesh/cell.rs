//! Cell and facet types of a mixed mesh: hex8, tet4, tet10 and wedge6 cells, their outward
//! faces, and the boundary facets (tri3, quad4, tri6) they make.
//!
//! Node orders are Gmsh's (= VTK's for the linear types): hex8 bottom 0-1-2-3 counter-clockwise
//! seen from above, top 4-5-6-7 above it; tet4 corners 0-3 with (x₁−x₀, x₂−x₀, x₃−x₀)
//! right-handed; tet10 then its edge nodes 4:(0,1) 5:(1,2) 6:(2,0) 7:(3,0) 8:(3,2) 9:(3,1);
//! wedge6 bottom triangle 0-1-2 counter-clockwise seen from above, top 3-4-5 (3 above 0).
//! A facet lists its corners first (right-hand rule = outward normal of its cell), then for
//! tri6 the edge nodes (0,1), (1,2), (2,0).

/// The corner pairs of the tet10's edge nodes 4…9 (Gmsh's order).
pub const TET10_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [3, 0], [3, 2], [3, 1]];

/// The most nodes a cell has (tet10).
pub const MAX_CELL_NODES: usize = 10;
/// The most DOFs a cell has.
pub const MAX_CELL_DOFS: usize = 3 * MAX_CELL_NODES;
/// The most nodes a facet has (quad8).
pub const MAX_FACET_NODES: usize = 8;

/// The type of a volume cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CellKind {
    /// 8-node hexahedron (trilinear brick).
    Hex8,
    /// 4-node tetrahedron (linear).
    Tet4,
    /// 10-node tetrahedron (quadratic).
    Tet10,
    /// 6-node wedge (triangular prism).
    Wedge6,
}

/// The type of a surface facet.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum FacetKind {
    /// 3-node triangle.
    Tri3,
    /// 4-node quadrilateral.
    Quad4,
    /// 6-node triangle (quadratic).
    Tri6,
    /// 8-node quadrilateral (serendipity).
    Quad8,
}

const HEX8_FACES: [&[usize]; 6] = [&[0, 3, 2, 1], &[4, 5, 6, 7], &[0, 1, 5, 4], &[1, 2, 6, 5], &[2, 3, 7, 6], &[3, 0, 4, 7]];
const TET4_FACES: [&[usize]; 4] = [&[0, 2, 1], &[0, 1, 3], &[0, 3, 2], &[1, 2, 3]];
const TET10_FACES: [&[usize]; 4] = [&[0, 2, 1, 6, 5, 4], &[0, 1, 3, 4, 9, 7], &[0, 3, 2, 7, 8, 6], &[1, 2, 3, 5, 8, 9]];
const WEDGE6_FACES: [&[usize]; 5] = [&[0, 2, 1], &[3, 4, 5], &[0, 1, 4, 3], &[1, 2, 5, 4], &[2, 0, 3, 5]];

impl CellKind {
    /// Every cell type.
    pub const ALL: [CellKind; 4] = [CellKind::Hex8, CellKind::Tet4, CellKind::Tet10, CellKind::Wedge6];

    /// Number of nodes.
    #[allow(clippy::len_without_is_empty)]
    pub const fn len(self) -> usize {
        match self {
            CellKind::Hex8 => 8,
            CellKind::Tet4 => 4,
            CellKind::Tet10 => 10,
            CellKind::Wedge6 => 6,
        }
    }

    /// Number of corner nodes (the linear geometry).
    pub const fn corners(self) -> usize {
        match self {
            CellKind::Tet10 => 4,
            k => k.len(),
        }
    }

    /// Local nodes of each face, outward (right-hand rule), corners first.
    pub fn faces(self) -> &'static [&'static [usize]] {
        match self {
            CellKind::Hex8 => &HEX8_FACES,
            CellKind::Tet4 => &TET4_FACES,
            CellKind::Tet10 => &TET10_FACES,
            CellKind::Wedge6 => &WEDGE6_FACES,
        }
    }

    /// The facet type of a face with `n` nodes of this cell.
    pub fn facet_kind(self, n: usize) -> FacetKind {
        match (self, n) {
            (CellKind::Tet10, _) => FacetKind::Tri6,
            (_, 3) => FacetKind::Tri3,
            _ => FacetKind::Quad4,
        }
    }

    /// The plural name in messages ("hexahedra", "tetrahedra", …).
    pub fn plural(self) -> &'static str {
        match self {
            CellKind::Hex8 => "hexahedra",
            CellKind::Tet4 => "4-node tetrahedra",
            CellKind::Tet10 => "10-node tetrahedra",
            CellKind::Wedge6 => "wedges",
        }
    }

    /// The XDMF topology type name.
    pub fn xdmf_name(self) -> &'static str {
        match self {
            CellKind::Hex8 => "Hexahedron",
            CellKind::Tet4 => "Tetrahedron",
            CellKind::Tet10 => "Tetrahedron_10",
            CellKind::Wedge6 => "Wedge",
        }
    }

    /// The XDMF type number in a Mixed topology.
    pub fn xdmf_id(self) -> usize {
        match self {
            CellKind::Hex8 => 9,
            CellKind::Tet4 => 6,
            CellKind::Tet10 => 38,
            CellKind::Wedge6 => 8,
        }
    }

    /// A small stable code (stored in result files).
    pub fn code(self) -> usize {
        self as usize
    }
}

impl FacetKind {
    /// Number of nodes.
    #[allow(clippy::len_without_is_empty)]
    pub const fn len(self) -> usize {
        match self {
            FacetKind::Tri3 => 3,
            FacetKind::Quad4 => 4,
            FacetKind::Tri6 => 6,
            FacetKind::Quad8 => 8,
        }
    }

    /// Number of corner nodes (3 or 4).
    pub const fn corners(self) -> usize {
        match self {
            FacetKind::Tri3 | FacetKind::Tri6 => 3,
            FacetKind::Quad4 | FacetKind::Quad8 => 4,
        }
    }

    /// The plural name in messages.
    pub fn plural(self) -> &'static str {
        match self {
            FacetKind::Tri3 => "triangles",
            FacetKind::Quad4 => "quadrilaterals",
            FacetKind::Tri6 => "6-node triangles",
            FacetKind::Quad8 => "8-node quadrilaterals",
        }
    }
}

/// One volume cell: its type and global (or local) node indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cell {
    /// The cell's type.
    pub kind: CellKind,
    n: [usize; MAX_CELL_NODES],
}

impl Cell {
    /// A cell of type `kind` on `nodes` (`nodes.len() == kind.len()`).
    pub fn new(kind: CellKind, nodes: &[usize]) -> Self {
        assert_eq!(nodes.len(), kind.len(), "{kind:?} has {} nodes", kind.len());
        let mut n = [0; MAX_CELL_NODES];
        n[..nodes.len()].copy_from_slice(nodes);
        Cell { kind, n }
    }

    /// A hex8 cell on `nodes`.
    pub fn hex8(nodes: [usize; 8]) -> Self {
        Cell::new(CellKind::Hex8, &nodes)
    }

    /// Its nodes, `kind.len()` of them.
    #[inline]
    pub fn nodes(&self) -> &[usize] {
        &self.n[..self.kind.len()]
    }

    /// Its nodes, mutable.
    #[inline]
    pub fn nodes_mut(&mut self) -> &mut [usize] {
        let k = self.kind.len();
        &mut self.n[..k]
    }

    /// The same cell with every node mapped by `f`.
    pub fn map(&self, f: impl Fn(usize) -> usize) -> Self {
        let mut c = *self;
        for v in c.nodes_mut() {
            *v = f(*v);
        }
        c
    }

    /// The outward facet of local face `f`.
    pub fn facet(&self, elem: usize, f: usize) -> Facet {
        let local = self.kind.faces()[f];
        let nodes: Vec<usize> = local.iter().map(|&l| self.n[l]).collect();
        Facet::new(elem, self.kind.facet_kind(local.len()), &nodes)
    }

    /// The coordinates of its nodes.
    pub fn coords(&self, x: &[[f64; 3]]) -> Vec<[f64; 3]> {
        self.nodes().iter().map(|&v| x[v]).collect()
    }

    /// The coordinates of its nodes in `buf` (no allocation: the assembly loop).
    pub fn coords_in<'b>(&self, x: &[[f64; 3]], buf: &'b mut [[f64; 3]; MAX_CELL_NODES]) -> &'b [[f64; 3]] {
        let n = self.kind.len();
        for (b, &v) in buf[..n].iter_mut().zip(self.nodes()) {
            *b = x[v];
        }
        &buf[..n]
    }
}

/// One facet of a named face: the cell it bounds, its type and its nodes, corners ordered so
/// that the right-hand rule gives the outward normal of that cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Facet {
    /// Index of the cell it bounds.
    pub elem: usize,
    /// The facet's type.
    pub kind: FacetKind,
    n: [usize; MAX_FACET_NODES],
}

impl Facet {
    /// A facet of type `kind` of cell `elem` on `nodes` (`nodes.len() == kind.len()`).
    pub fn new(elem: usize, kind: FacetKind, nodes: &[usize]) -> Self {
        assert_eq!(nodes.len(), kind.len(), "{kind:?} has {} nodes", kind.len());
        let mut n = [0; MAX_FACET_NODES];
        n[..nodes.len()].copy_from_slice(nodes);
        Facet { elem, kind, n }
    }

    /// A quad4 facet of cell `elem` on `nodes`.
    pub fn quad4(elem: usize, nodes: [usize; 4]) -> Self {
        Facet::new(elem, FacetKind::Quad4, &nodes)
    }

    /// Its nodes, `kind.len()` of them.
    #[inline]
    pub fn nodes(&self) -> &[usize] {
        &self.n[..self.kind.len()]
    }

    /// The corner nodes.
    pub fn corners(&self) -> &[usize] {
        &self.n[..self.kind.corners()]
    }

    /// The same facet with nodes mapped by `f` and cell index `elem`.
    pub fn map(&self, elem: usize, f: impl Fn(usize) -> usize) -> Self {
        let mut c = *self;
        c.elem = elem;
        let k = c.kind.len();
        for v in &mut c.n[..k] {
            *v = f(*v);
        }
        c
    }

    /// The key of its node set, whatever the order: sorted corners (a triangle's padded with
    /// `usize::MAX`).
    pub fn key(&self) -> [usize; 4] {
        corner_key(self.corners())
    }
}

/// Sorted corners, padded with `usize::MAX` to four.
pub fn corner_key(corners: &[usize]) -> [usize; 4] {
    let mut k = [usize::MAX; 4];
    k[..corners.len()].copy_from_slice(corners);
    k.sort_unstable();
    k
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::facet::{cross, dot, sub};

    /// Each face's normal (right-hand rule on its first three corners) points away from the
    /// cell's centroid, and every edge node lies midway between the corners it names.
    #[test]
    fn faces_point_outward_and_edge_nodes_match() {
        let hex: Vec<[f64; 3]> = vec![[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.], [0., 0., 1.], [1., 0., 1.], [1., 1., 1.], [0., 1., 1.]];
        let tet4: Vec<[f64; 3]> = vec![[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]];
        let mid = |a: [f64; 3], b: [f64; 3]| [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0, (a[2] + b[2]) / 2.0];
        let mut tet10 = tet4.clone();
        for [a, b] in TET10_EDGES {
            tet10.push(mid(tet4[a], tet4[b]));
        }
        let wedge: Vec<[f64; 3]> = vec![[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.], [1., 0., 1.], [0., 1., 1.]];
        for (kind, x) in [(CellKind::Hex8, hex), (CellKind::Tet4, tet4), (CellKind::Tet10, tet10), (CellKind::Wedge6, wedge)] {
            let n = x.len() as f64;
            let c = x.iter().fold([0.0; 3], |s, p| [s[0] + p[0] / n, s[1] + p[1] / n, s[2] + p[2] / n]);
            let cell = Cell::new(kind, &(0..kind.len()).collect::<Vec<_>>());
            for f in 0..kind.faces().len() {
                let fc = cell.facet(0, f);
                let p = fc.nodes();
                let nrm = cross(sub(x[p[1]], x[p[0]]), sub(x[p[2]], x[p[0]]));
                assert!(dot(nrm, sub(x[p[0]], c)) > 0.0, "{kind:?} face {f} points inward");
                if fc.kind == FacetKind::Tri6 {
                    for (e, [a, b]) in [[0, 1], [1, 2], [2, 0]].into_iter().enumerate() {
                        assert_eq!(x[p[3 + e]], mid(x[p[a]], x[p[b]]), "{kind:?} face {f} edge node {e}");
                    }
                }
            }
        }
    }

    #[test]
    fn keys_ignore_order() {
        assert_eq!(Facet::new(0, FacetKind::Tri3, &[5, 2, 9]).key(), Facet::new(3, FacetKind::Tri3, &[9, 5, 2]).key());
        assert_ne!(Facet::new(0, FacetKind::Tri3, &[5, 2, 9]).key(), Facet::quad4(0, [5, 2, 9, 1]).key());
    }
}
