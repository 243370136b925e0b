//! Cell and facet types of a mixed mesh: hex8, hex20, hex27, tet4, tet10, wedge6, wedge15 and
//! pyr5 cells, their outward faces, and the boundary facets (tri3, quad4, tri6, quad8, quad9) they
//! make.
//!
//! Node orders are Gmsh's (= VTK's for the linear types): hex8 bottom 0-1-2-3 counter-clockwise
//! seen from above, top 4-5-6-7 above it; tet4 corners 0-3 with (x₁−x₀, x₂−x₀, x₃−x₀)
//! right-handed; tet10 then its edge nodes 4:(0,1) 5:(1,2) 6:(2,0) 7:(3,0) 8:(3,2) 9:(3,1);
//! wedge6 bottom triangle 0-1-2 counter-clockwise seen from above, top 3-4-5 (3 above 0);
//! pyr5 (Gmsh type 7, = VTK's) base 0-1-2-3 counter-clockwise seen from the apex, apex 4.
//! Hex20 (Gmsh type 17) then its edge nodes 8:(0,1) 9:(0,3) 10:(0,4) 11:(1,2) 12:(1,5)
//! 13:(2,3) 14:(2,6) 15:(3,7) 16:(4,5) 17:(4,7) 18:(5,6) 19:(6,7) ([`HEX20_EDGES`]; VTK's
//! order differs); hex27 (type 12) then the face centres 20:(0,1,2,3) 21:(0,1,5,4)
//! 22:(0,3,7,4) 23:(1,2,6,5) 24:(2,3,7,6) 25:(4,5,6,7) and the centre 26; wedge15 (type 18)
//! the wedge6's corners, then 6:(0,1) 7:(0,2) 8:(0,3) 9:(1,2) 10:(1,4) 11:(2,5) 12:(3,4)
//! 13:(3,5) 14:(4,5) ([`WEDGE15_EDGES`]).
//! A facet lists its corners first (right-hand rule = outward normal of its cell), then for
//! tri6 the edge nodes (0,1), (1,2), (2,0); for quad8 (0,1), (1,2), (2,3), (3,0); quad9 adds
//! its centre.

/// The corner pairs of the tet10's edge nodes 4…9 (Gmsh's order).
pub const TET10_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [3, 0], [3, 2], [3, 1]];

/// The corner pairs of the hex20's (and hex27's) edge nodes 8…19 (Gmsh's order).
pub const HEX20_EDGES: [[usize; 2]; 12] = [[0, 1], [0, 3], [0, 4], [1, 2], [1, 5], [2, 3], [2, 6], [3, 7], [4, 5], [4, 7], [5, 6], [6, 7]];

/// The corners of the hex27's face-centre nodes 20…25 (Gmsh's order).
pub const HEX27_FACES: [[usize; 4]; 6] = [[0, 1, 2, 3], [0, 1, 5, 4], [0, 3, 7, 4], [1, 2, 6, 5], [2, 3, 7, 6], [4, 5, 6, 7]];

/// The corner pairs of the wedge15's edge nodes 6…14 (Gmsh's order).
pub const WEDGE15_EDGES: [[usize; 2]; 9] = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 4], [2, 5], [3, 4], [3, 5], [4, 5]];

/// The most nodes a cell has (hex27).
pub const MAX_CELL_NODES: usize = 27;
/// The most DOFs a cell has.
pub const MAX_CELL_DOFS: usize = 3 * MAX_CELL_NODES;
/// The most nodes a facet has (quad9).
pub const MAX_FACET_NODES: usize = 9;

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
    /// 20-node hexahedron (quadratic serendipity).
    Hex20,
    /// 27-node hexahedron (triquadratic Lagrange).
    Hex27,
    /// 15-node wedge (quadratic serendipity prism).
    Wedge15,
    /// 5-node pyramid (rational shape functions; base quad, apex).
    Pyr5,
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
    /// 9-node quadrilateral (biquadratic Lagrange).
    Quad9,
}

const HEX8_FACES: [&[usize]; 6] = [&[0, 3, 2, 1], &[4, 5, 6, 7], &[0, 1, 5, 4], &[1, 2, 6, 5], &[2, 3, 7, 6], &[3, 0, 4, 7]];
const TET4_FACES: [&[usize]; 4] = [&[0, 2, 1], &[0, 1, 3], &[0, 3, 2], &[1, 2, 3]];
const TET10_FACES: [&[usize]; 4] = [&[0, 2, 1, 6, 5, 4], &[0, 1, 3, 4, 9, 7], &[0, 3, 2, 7, 8, 6], &[1, 2, 3, 5, 8, 9]];
const WEDGE6_FACES: [&[usize]; 5] = [&[0, 2, 1], &[3, 4, 5], &[0, 1, 4, 3], &[1, 2, 5, 4], &[2, 0, 3, 5]];
const HEX20_FACES: [&[usize]; 6] = [
    &[0, 3, 2, 1, 9, 13, 11, 8],
    &[4, 5, 6, 7, 16, 18, 19, 17],
    &[0, 1, 5, 4, 8, 12, 16, 10],
    &[1, 2, 6, 5, 11, 14, 18, 12],
    &[2, 3, 7, 6, 13, 15, 19, 14],
    &[3, 0, 4, 7, 9, 10, 17, 15],
];
const HEX27_FACES_LOCAL: [&[usize]; 6] = [
    &[0, 3, 2, 1, 9, 13, 11, 8, 20],
    &[4, 5, 6, 7, 16, 18, 19, 17, 25],
    &[0, 1, 5, 4, 8, 12, 16, 10, 21],
    &[1, 2, 6, 5, 11, 14, 18, 12, 23],
    &[2, 3, 7, 6, 13, 15, 19, 14, 24],
    &[3, 0, 4, 7, 9, 10, 17, 15, 22],
];
const PYR5_FACES: [&[usize]; 5] = [&[0, 3, 2, 1], &[0, 1, 4], &[1, 2, 4], &[2, 3, 4], &[3, 0, 4]];
const WEDGE15_FACES: [&[usize]; 5] =
    [&[0, 2, 1, 7, 9, 6], &[3, 4, 5, 12, 14, 13], &[0, 1, 4, 3, 6, 10, 12, 8], &[1, 2, 5, 4, 9, 11, 14, 10], &[2, 0, 3, 5, 7, 8, 13, 11]];

impl CellKind {
    /// Every cell type.
    pub const ALL: [CellKind; 8] =
        [CellKind::Hex8, CellKind::Tet4, CellKind::Tet10, CellKind::Wedge6, CellKind::Hex20, CellKind::Hex27, CellKind::Wedge15, CellKind::Pyr5];
    /// The number of cell types (the length of per-type count arrays indexed by [`Self::code`]).
    pub const COUNT: usize = 8;

    /// Number of nodes.
    #[allow(clippy::len_without_is_empty)]
    pub const fn len(self) -> usize {
        match self {
            CellKind::Hex8 => 8,
            CellKind::Tet4 => 4,
            CellKind::Tet10 => 10,
            CellKind::Wedge6 => 6,
            CellKind::Hex20 => 20,
            CellKind::Hex27 => 27,
            CellKind::Wedge15 => 15,
            CellKind::Pyr5 => 5,
        }
    }

    /// Number of corner nodes (the linear geometry).
    pub const fn corners(self) -> usize {
        match self {
            CellKind::Tet10 => 4,
            CellKind::Hex20 | CellKind::Hex27 => 8,
            CellKind::Wedge15 => 6,
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
            CellKind::Hex20 => &HEX20_FACES,
            CellKind::Hex27 => &HEX27_FACES_LOCAL,
            CellKind::Wedge15 => &WEDGE15_FACES,
            CellKind::Pyr5 => &PYR5_FACES,
        }
    }

    /// The facet type of a face with `n` nodes of this cell.
    pub fn facet_kind(self, n: usize) -> FacetKind {
        match (self, n) {
            (CellKind::Tet10, _) | (CellKind::Wedge15, 6) => FacetKind::Tri6,
            (CellKind::Hex20, _) | (CellKind::Wedge15, _) => FacetKind::Quad8,
            (CellKind::Hex27, _) => FacetKind::Quad9,
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
            CellKind::Hex20 => "20-node hexahedra",
            CellKind::Hex27 => "27-node hexahedra",
            CellKind::Wedge15 => "15-node wedges",
            CellKind::Pyr5 => "pyramids",
        }
    }

    /// The XDMF topology type name.
    pub fn xdmf_name(self) -> &'static str {
        match self {
            CellKind::Hex8 => "Hexahedron",
            CellKind::Tet4 => "Tetrahedron",
            CellKind::Tet10 => "Tetrahedron_10",
            CellKind::Wedge6 => "Wedge",
            CellKind::Hex20 => "Hexahedron_20",
            CellKind::Hex27 => "Hexahedron_27",
            CellKind::Wedge15 => "Wedge_15",
            CellKind::Pyr5 => "Pyramid",
        }
    }

    /// The XDMF type number in a Mixed topology.
    pub fn xdmf_id(self) -> usize {
        match self {
            CellKind::Hex8 => 9,
            CellKind::Tet4 => 6,
            CellKind::Tet10 => 38,
            CellKind::Wedge6 => 8,
            CellKind::Hex20 => 48,
            CellKind::Hex27 => 50,
            CellKind::Wedge15 => 40,
            CellKind::Pyr5 => 7,
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
            FacetKind::Quad9 => 9,
        }
    }

    /// Number of corner nodes (3 or 4).
    pub const fn corners(self) -> usize {
        match self {
            FacetKind::Tri3 | FacetKind::Tri6 => 3,
            FacetKind::Quad4 | FacetKind::Quad8 | FacetKind::Quad9 => 4,
        }
    }

    /// The plural name in messages.
    pub fn plural(self) -> &'static str {
        match self {
            FacetKind::Tri3 => "triangles",
            FacetKind::Quad4 => "quadrilaterals",
            FacetKind::Tri6 => "6-node triangles",
            FacetKind::Quad8 => "8-node quadrilaterals",
            FacetKind::Quad9 => "9-node quadrilaterals",
        }
    }
}

/// The most nodes a cell keeps inline (tet10); cells with more keep them on the heap, so that a
/// mesh of linear or tet10 cells pays nothing for the 27 nodes a hex27 has.
const INLINE_NODES: usize = 10;

/// One volume cell: its type and global (or local) node indices.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Cell {
    /// The cell's type.
    pub kind: CellKind,
    n: [usize; INLINE_NODES],
    /// The nodes of a cell with more than [`INLINE_NODES`] (then `n` is unused).
    big: Option<Box<[usize; MAX_CELL_NODES]>>,
}

impl Cell {
    /// A cell of type `kind` on `nodes` (`nodes.len() == kind.len()`).
    pub fn new(kind: CellKind, nodes: &[usize]) -> Self {
        assert_eq!(nodes.len(), kind.len(), "{kind:?} has {} nodes", kind.len());
        let mut c = Cell { kind, n: [0; INLINE_NODES], big: (nodes.len() > INLINE_NODES).then(|| Box::new([0; MAX_CELL_NODES])) };
        c.nodes_mut().copy_from_slice(nodes);
        c
    }

    /// A hex8 cell on `nodes`.
    pub fn hex8(nodes: [usize; 8]) -> Self {
        Cell::new(CellKind::Hex8, &nodes)
    }

    /// Its nodes, `kind.len()` of them.
    #[inline]
    pub fn nodes(&self) -> &[usize] {
        match &self.big {
            Some(b) => &b[..self.kind.len()],
            None => &self.n[..self.kind.len()],
        }
    }

    /// Its nodes, mutable.
    #[inline]
    pub fn nodes_mut(&mut self) -> &mut [usize] {
        let k = self.kind.len();
        match &mut self.big {
            Some(b) => &mut b[..k],
            None => &mut self.n[..k],
        }
    }

    /// The same cell with every node mapped by `f`.
    pub fn map(&self, f: impl Fn(usize) -> usize) -> Self {
        let mut c = self.clone();
        for v in c.nodes_mut() {
            *v = f(*v);
        }
        c
    }

    /// The outward facet of local face `f`.
    pub fn facet(&self, elem: usize, f: usize) -> Facet {
        let local = self.kind.faces()[f];
        let (all, mut n) = (self.nodes(), [0; MAX_FACET_NODES]);
        for (v, &l) in n.iter_mut().zip(local) {
            *v = all[l];
        }
        Facet { elem, kind: self.kind.facet_kind(local.len()), n }
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
        let mut hex20 = hex.clone();
        for [a, b] in HEX20_EDGES {
            hex20.push(mid(hex[a], hex[b]));
        }
        let mut hex27 = hex20.clone();
        for [a, _, c, _] in HEX27_FACES {
            hex27.push(mid(hex[a], hex[c]));
        }
        hex27.push([0.5; 3]);
        let mut wedge15 = wedge.clone();
        for [a, b] in WEDGE15_EDGES {
            wedge15.push(mid(wedge[a], wedge[b]));
        }
        let pyr: Vec<[f64; 3]> = vec![[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.], [0.5, 0.5, 1.]];
        let all = [
            (CellKind::Hex8, hex),
            (CellKind::Tet4, tet4),
            (CellKind::Tet10, tet10),
            (CellKind::Wedge6, wedge),
            (CellKind::Hex20, hex20),
            (CellKind::Hex27, hex27),
            (CellKind::Wedge15, wedge15),
            (CellKind::Pyr5, pyr),
        ];
        for (kind, x) in all {
            let n = x.len() as f64;
            let c = x.iter().fold([0.0; 3], |s, p| [s[0] + p[0] / n, s[1] + p[1] / n, s[2] + p[2] / n]);
            let cell = Cell::new(kind, &(0..kind.len()).collect::<Vec<_>>());
            for f in 0..kind.faces().len() {
                let fc = cell.facet(0, f);
                let p = fc.nodes();
                let nrm = cross(sub(x[p[1]], x[p[0]]), sub(x[p[2]], x[p[0]]));
                assert!(dot(nrm, sub(x[p[0]], c)) > 0.0, "{kind:?} face {f} points inward");
                let nc = fc.kind.corners();
                if fc.kind.len() > nc {
                    for e in 0..nc {
                        let (a, b) = (e, (e + 1) % nc);
                        assert_eq!(x[p[nc + e]], mid(x[p[a]], x[p[b]]), "{kind:?} face {f} edge node {e}");
                    }
                }
                if fc.kind == FacetKind::Quad9 {
                    assert_eq!(x[p[8]], mid(x[p[0]], x[p[2]]), "{kind:?} face {f} centre");
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
