//! Kernels by cell type (hex8, tet4, tet10, wedge6, pyr5, and hex20, hex27, wedge15 through
//! [`super::quadratic`]): the element stiffness, the inversion check and the centre stress of
//! any [`CellKind`] — dispatching to the pure per-type kernels — and the area of a mesh face.
//! The facet kernels (shape functions, rules, nodal weights ∫ N_a dA of any
//! [`crate::mesh::FacetKind`]) live in [`super::facet`] and are re-exported here.

use super::element::{hex8_center_stress, hex8_stiffness, hex_min_jacobian};
pub use super::facet::{facet_area_inside, facet_area_vector, facet_centre, facet_nodal_areas, facet_normal_area, facet_point, facet_rule, facet_shape};
use super::material::Lame;
use super::pyramid::{pyr5_min_jacobian, pyr5_stiffness, pyr5_strain, PYR5_CENTRE};
use super::quadratic::Quadratic;
use super::tet::{tet10_min_jacobian, tet10_stiffness, tet10_strain, tet4_gradients, tet4_stiffness, tet4_strain};
use super::wedge::{wedge6_min_jacobian, wedge6_stiffness, wedge6_strain};
use crate::mesh::CellKind;

/// An element stiffness, 3n × 3n for a cell of n nodes (DOF order 3a + i), on the stack (one
/// per element in the assembly loop: no allocation).
#[allow(clippy::large_enum_variant)]
pub enum CellMatrix {
    /// Of a hex8 cell.
    Hex8([[f64; 24]; 24]),
    /// Of a tet4 cell.
    Tet4([[f64; 12]; 12]),
    /// Of a tet10 cell.
    Tet10([[f64; 30]; 30]),
    /// Of a wedge6 cell.
    Wedge6([[f64; 18]; 18]),
    /// Of a pyr5 cell.
    Pyr5([[f64; 15]; 15]),
    /// Of a quadratic hexahedron or wedge (hex20, hex27, wedge15): 3n and the entries row by
    /// row, on the heap.
    Dense(usize, Vec<f64>),
}

impl CellMatrix {
    /// Its size 3n and its entries row by row.
    pub fn rows(&self) -> (usize, &[f64]) {
        match self {
            CellMatrix::Hex8(k) => (24, k.as_flattened()),
            CellMatrix::Tet4(k) => (12, k.as_flattened()),
            CellMatrix::Tet10(k) => (30, k.as_flattened()),
            CellMatrix::Wedge6(k) => (18, k.as_flattened()),
            CellMatrix::Pyr5(k) => (15, k.as_flattened()),
            CellMatrix::Dense(n, k) => (*n, k),
        }
    }
}

/// The kernel of a quadratic hexahedron or wedge.
fn quadratic(kind: CellKind) -> Option<Quadratic> {
    match kind {
        CellKind::Hex20 => Some(Quadratic::Hex20),
        CellKind::Hex27 => Some(Quadratic::Hex27),
        CellKind::Wedge15 => Some(Quadratic::Wedge15),
        _ => None,
    }
}

fn arr<const N: usize>(x: &[[f64; 3]]) -> &[[f64; 3]; N] {
    x.try_into().expect("node count of the cell type")
}

/// The stiffness of a cell of type `kind` with node coordinates `x`.
pub fn cell_stiffness(kind: CellKind, x: &[[f64; 3]], m: Lame) -> CellMatrix {
    match kind {
        CellKind::Hex8 => CellMatrix::Hex8(hex8_stiffness(arr(x), m)),
        CellKind::Tet4 => CellMatrix::Tet4(tet4_stiffness(arr(x), m)),
        CellKind::Tet10 => CellMatrix::Tet10(tet10_stiffness(arr(x), m)),
        CellKind::Wedge6 => CellMatrix::Wedge6(wedge6_stiffness(arr(x), m)),
        CellKind::Pyr5 => CellMatrix::Pyr5(pyr5_stiffness(arr(x), m)),
        CellKind::Hex20 | CellKind::Hex27 | CellKind::Wedge15 => {
            let q = quadratic(kind).expect("a quadratic kind");
            CellMatrix::Dense(3 * q.len(), q.stiffness(x, m))
        }
    }
}

/// The smallest det J over the quadrature points and corners: ≤ 0 means inverted or degenerate.
pub fn cell_min_jacobian(kind: CellKind, x: &[[f64; 3]]) -> f64 {
    match kind {
        CellKind::Hex8 => hex_min_jacobian(arr(x)),
        CellKind::Tet4 => tet4_gradients(arr(x)).1,
        CellKind::Tet10 => tet10_min_jacobian(arr(x)),
        CellKind::Wedge6 => wedge6_min_jacobian(arr(x)),
        CellKind::Pyr5 => pyr5_min_jacobian(arr(x)),
        CellKind::Hex20 | CellKind::Hex27 | CellKind::Wedge15 => quadratic(kind).expect("a quadratic kind").min_jacobian(x),
    }
}

/// The strain at the cell's centre from the nodal displacements `u`.
pub fn cell_center_strain(kind: CellKind, x: &[[f64; 3]], u: &[[f64; 3]]) -> [f64; 6] {
    match kind {
        CellKind::Hex8 => super::element::hex8_strain(arr(x), arr(u), [0.0; 3]),
        CellKind::Tet4 => tet4_strain(arr(x), arr(u)),
        CellKind::Tet10 => tet10_strain(arr(x), arr(u), [0.25; 3]),
        CellKind::Wedge6 => wedge6_strain(arr(x), arr(u), [1.0 / 3.0, 1.0 / 3.0, 0.0]),
        CellKind::Pyr5 => pyr5_strain(arr(x), arr(u), PYR5_CENTRE),
        CellKind::Hex20 | CellKind::Hex27 | CellKind::Wedge15 => {
            let q = quadratic(kind).expect("a quadratic kind");
            q.strain(x, u, q.centre())
        }
    }
}

/// The stress at the cell's centre.
pub fn cell_center_stress(kind: CellKind, x: &[[f64; 3]], u: &[[f64; 3]], m: Lame) -> [f64; 6] {
    match kind {
        CellKind::Hex8 => hex8_center_stress(arr(x), arr(u), m),
        k => m.stress(&cell_center_strain(k, x, u)),
    }
}

/// The area of a face (its facets' true maps) on the coordinates `x`.
pub fn face_area(face: &crate::mesh::Face, x: &[[f64; 3]]) -> f64 {
    face.facets.iter().map(|q| facet_nodal_areas(q.kind, &q.nodes().iter().map(|&v| x[v]).collect::<Vec<_>>()).iter().sum::<f64>()).sum()
}
