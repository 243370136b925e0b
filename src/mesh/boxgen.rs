//! Structured meshes of an axis-aligned box, with the six sides tagged
//! `xmin, xmax, ymin, ymax, zmin, zmax`: hexahedra, or each hexahedron cut into six tetrahedra
//! along its main diagonal (Kuhn's conforming subdivision), linear or with edge nodes.

use std::collections::HashMap;

use super::cell::{Cell, CellKind, Facet};
use super::{try_vec, BodyGeometry};
use crate::error::Result;

/// The outward facet of local face `f` of hexahedron `e`.
fn hex_face(hexes: &[Cell], e: usize, f: usize) -> Facet {
    hexes[e].facet(e, f)
}

/// Names of the box sides, in the order of the local hex faces that lie on them.
pub const SIDES: [(&str, usize); 6] = [("xmin", 5), ("xmax", 3), ("ymin", 2), ("ymax", 4), ("zmin", 0), ("zmax", 1)];

/// A box `[min, max]` with `n = [nx, ny, nz]` nodes per direction (each ≥ 2); panics where
/// memory runs out ([`try_generate`] returns the error). For the unit tests.
#[cfg(test)]
pub fn generate(min: [f64; 3], max: [f64; 3], n: [usize; 3]) -> BodyGeometry {
    try_generate(min, max, n).unwrap_or_else(|e| panic!("{e}"))
}

/// A box `[min, max]` with `n = [nx, ny, nz]` nodes per direction (each ≥ 2), with an allocation
/// that fails (nodes, hexahedra, side quads) as an error.
pub fn try_generate(min: [f64; 3], max: [f64; 3], n: [usize; 3]) -> Result<BodyGeometry> {
    let [nx, ny, nz] = n;
    assert!(nx >= 2 && ny >= 2 && nz >= 2, "box needs at least 2 nodes per direction");
    let id = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
    let coord = |d: usize, i: usize, nd: usize| min[d] + (max[d] - min[d]) * i as f64 / (nd - 1) as f64;
    let count = |a: usize, b: usize, c: usize| a.checked_mul(b).and_then(|x| x.checked_mul(c)).unwrap_or(usize::MAX);
    let mut nodes = try_vec::<[f64; 3]>("box nodes", count(nx, ny, nz))?;
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                nodes.push([coord(0, i, nx), coord(1, j, ny), coord(2, k, nz)]);
            }
        }
    }
    let (ex, ey, ez) = (nx - 1, ny - 1, nz - 1);
    let mut hexes = try_vec::<Cell>("box hexahedra", count(ex, ey, ez))?;
    for k in 0..ez {
        for j in 0..ey {
            for i in 0..ex {
                hexes.push(Cell::hex8([
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                    id(i, j, k + 1),
                    id(i + 1, j, k + 1),
                    id(i + 1, j + 1, k + 1),
                    id(i, j + 1, k + 1),
                ]));
            }
        }
    }
    let eid = |i: usize, j: usize, k: usize| i + ex * (j + ey * k);
    let mut faces = Vec::with_capacity(6);
    for (name, lf) in SIDES {
        let side = match name {
            "xmin" | "xmax" => ey * ez,
            "ymin" | "ymax" => ex * ez,
            _ => ex * ey,
        };
        let mut quads = try_vec("box side quadrilaterals", side)?;
        match name {
            "xmin" | "xmax" => {
                let i = if name == "xmin" { 0 } else { ex - 1 };
                for k in 0..ez {
                    for j in 0..ey {
                        quads.push(hex_face(&hexes, eid(i, j, k), lf));
                    }
                }
            }
            "ymin" | "ymax" => {
                let j = if name == "ymin" { 0 } else { ey - 1 };
                for k in 0..ez {
                    for i in 0..ex {
                        quads.push(hex_face(&hexes, eid(i, j, k), lf));
                    }
                }
            }
            _ => {
                let k = if name == "zmin" { 0 } else { ez - 1 };
                for j in 0..ey {
                    for i in 0..ex {
                        quads.push(hex_face(&hexes, eid(i, j, k), lf));
                    }
                }
            }
        }
        faces.push((name.to_string(), quads));
    }
    Ok(BodyGeometry { nodes, cells: hexes, faces })
}

/// The box of [`try_generate`] meshed with cells of type `kind`: hexahedra as there; tet4 and
/// tet10 cut each hexahedron into six tetrahedra (tet10: a node at the middle of every edge);
/// hex20 and hex27 the same hexahedra with a node at the middle of every edge (hex27 also of
/// every face and cell: the grid of 2n − 1 nodes per direction). Wedges and pyramids are not
/// generated.
pub fn try_generate_cells(min: [f64; 3], max: [f64; 3], n: [usize; 3], kind: CellKind) -> Result<BodyGeometry> {
    let hex = try_generate(min, max, n)?;
    match kind {
        CellKind::Hex8 => Ok(hex),
        CellKind::Tet4 | CellKind::Tet10 => Ok(tetrahedralize(hex, min, max, kind == CellKind::Tet10)),
        CellKind::Hex20 | CellKind::Hex27 => Ok(quadratic_hexes(min, max, n, kind)?),
        CellKind::Wedge6 | CellKind::Wedge15 | CellKind::Pyr5 => panic!("the box generator makes no wedges or pyramids"),
    }
}

/// The hexahedra of the grid of 2n − 1 nodes per direction, each on 3 × 3 × 3 of its nodes
/// (hex20: the corners and edge midpoints, the grid's unused face and cell centres left out).
fn quadratic_hexes(min: [f64; 3], max: [f64; 3], n: [usize; 3], kind: CellKind) -> Result<BodyGeometry> {
    let fine = try_generate(min, max, n.map(|v| 2 * v - 1))?;
    let m = n.map(|v| 2 * v - 1);
    let id = |i: usize, j: usize, k: usize| i + m[0] * (j + m[1] * k);
    let refs = crate::fem::quadratic::hex27_ref();
    let mut cells = Vec::with_capacity(fine.cells.len() / 8);
    for k in 0..n[2] - 1 {
        for j in 0..n[1] - 1 {
            for i in 0..n[0] - 1 {
                let v: Vec<usize> = refs[..kind.len()]
                    .iter()
                    .map(|r| id(2 * i + (r[0] + 1.0) as usize, 2 * j + (r[1] + 1.0) as usize, 2 * k + (r[2] + 1.0) as usize))
                    .collect();
                cells.push(Cell::new(kind, &v));
            }
        }
    }
    // keep the nodes the cells use, in grid order
    let mut new = vec![usize::MAX; fine.nodes.len()];
    for c in &cells {
        for &v in c.nodes() {
            new[v] = 0;
        }
    }
    let mut nodes = Vec::with_capacity(fine.nodes.len());
    for (v, slot) in new.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = nodes.len();
            nodes.push(fine.nodes[v]);
        }
    }
    let cells: Vec<Cell> = cells.iter().map(|c| c.map(|v| new[v])).collect();
    let faces = side_faces(&nodes, &cells, min, max);
    Ok(BodyGeometry { nodes, cells, faces })
}

/// The six Kuhn tetrahedra of a hexahedron (local corners 0…7 in hex8 order): the paths
/// 0 → a → a+b → 6 along the cube's edges, one per order of the three axes.
const KUHN: [[usize; 4]; 6] = [[0, 1, 2, 6], [0, 1, 5, 6], [0, 3, 2, 6], [0, 3, 7, 6], [0, 4, 5, 6], [0, 4, 7, 6]];

fn tetrahedralize(hex: BodyGeometry, min: [f64; 3], max: [f64; 3], quadratic: bool) -> BodyGeometry {
    let mut nodes = hex.nodes;
    let mut cells = Vec::with_capacity(6 * hex.cells.len());
    let mut mids: HashMap<(usize, usize), usize> = HashMap::new();
    for h in &hex.cells {
        let c = h.nodes();
        for t in KUHN {
            let mut v = t.map(|l| c[l]);
            let e = |a: usize, b: usize| std::array::from_fn::<f64, 3, _>(|i| nodes[v[b]][i] - nodes[v[a]][i]);
            let (a, b, d) = (e(0, 1), e(0, 2), e(0, 3));
            let det = a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) + a[2] * (b[0] * d[1] - b[1] * d[0]);
            if det < 0.0 {
                v.swap(1, 2);
            }
            if quadratic {
                let mut all = v.to_vec();
                for [p, q] in super::cell::TET10_EDGES {
                    let key = (v[p].min(v[q]), v[p].max(v[q]));
                    let m = *mids.entry(key).or_insert_with(|| {
                        let (x, y) = (nodes[key.0], nodes[key.1]);
                        nodes.push(std::array::from_fn(|i| 0.5 * (x[i] + y[i])));
                        nodes.len() - 1
                    });
                    all.push(m);
                }
                cells.push(Cell::new(CellKind::Tet10, &all));
            } else {
                cells.push(Cell::new(CellKind::Tet4, &v));
            }
        }
    }
    let faces = side_faces(&nodes, &cells, min, max);
    BodyGeometry { nodes, cells, faces }
}

/// The boundary facets of `cells` sorted onto the six sides of the box (by their corners).
fn side_faces(nodes: &[[f64; 3]], cells: &[Cell], min: [f64; 3], max: [f64; 3]) -> Vec<(String, Vec<Facet>)> {
    let mut boundary: Vec<Facet> = super::topology::boundary_faces(cells).into_values().collect();
    boundary.sort_unstable_by_key(|f| (f.elem, f.key()));
    let tol = |d: usize| 1e-9 * (max[d] - min[d]);
    SIDES
        .iter()
        .enumerate()
        .map(|(s, (name, _))| {
            let (d, at) = (s / 2, if s % 2 == 0 { min[s / 2] } else { max[s / 2] });
            let on: Vec<Facet> = boundary.iter().filter(|f| f.corners().iter().all(|&v| (nodes[v][d] - at).abs() <= tol(d))).copied().collect();
            (name.to_string(), on)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn normal(g: &BodyGeometry, q: &[usize]) -> [f64; 3] {
        let p: Vec<[f64; 3]> = q.iter().map(|&v| g.nodes[v]).collect();
        let a = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
        let b = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    }

    #[test]
    fn sides_are_outward_and_complete() {
        let g = generate([0.0, 0.0, 1.0], [2.0, 1.0, 2.0], [4, 3, 5]);
        assert_eq!(g.nodes.len(), 60);
        assert_eq!(g.cells.len(), 3 * 2 * 4);
        let expect = [(0, -1.0, 8), (0, 1.0, 8), (1, -1.0, 12), (1, 1.0, 12), (2, -1.0, 6), (2, 1.0, 6)];
        for ((name, quads), (axis, sign, count)) in g.faces.iter().zip(expect) {
            assert_eq!(quads.len(), count, "{name}");
            for q in quads {
                let n = normal(&g, q.nodes());
                assert!(n[axis] * sign > 0.0, "{name} not outward");
                assert!(n[(axis + 1) % 3].abs() < 1e-14 && n[(axis + 2) % 3].abs() < 1e-14);
            }
        }
        let boundary = crate::mesh::topology::boundary_faces(&g.cells);
        assert_eq!(boundary.len(), g.faces.iter().map(|f| f.1.len()).sum::<usize>());
    }

    /// Tetrahedral boxes: positive volumes summing to the box's, conforming (every interior
    /// face shared by two cells: the boundary is only the six sides, two triangles per square),
    /// outward sides; tet10 edge nodes shared.
    #[test]
    fn tetrahedral_boxes_are_conforming_and_fill_the_box() {
        for kind in [CellKind::Tet4, CellKind::Tet10] {
            let g = try_generate_cells([0.0, 0.0, 1.0], [2.0, 1.0, 2.0], [4, 3, 5], kind).unwrap();
            assert_eq!(g.cells.len(), 6 * 24);
            let vol: f64 = g
                .cells
                .iter()
                .map(|c| {
                    let x = c.coords(&g.nodes);
                    let e = |b: usize| std::array::from_fn::<f64, 3, _>(|i| x[b][i] - x[0][i]);
                    let (a, b, d) = (e(1), e(2), e(3));
                    let det = a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) + a[2] * (b[0] * d[1] - b[1] * d[0]);
                    assert!(det > 0.0);
                    det / 6.0
                })
                .sum();
            assert!((vol - 2.0).abs() < 1e-12, "{vol}");
            let expect = [(0, -1.0, 16), (0, 1.0, 16), (1, -1.0, 24), (1, 1.0, 24), (2, -1.0, 12), (2, 1.0, 12)];
            for ((name, facets), (axis, sign, count)) in g.faces.iter().zip(expect) {
                assert_eq!(facets.len(), count, "{kind:?} {name}");
                for q in facets {
                    assert!(normal(&g, q.nodes())[axis] * sign > 0.0, "{name} not outward");
                }
            }
            let boundary = crate::mesh::topology::boundary_faces(&g.cells);
            assert_eq!(boundary.len(), 104);
            if kind == CellKind::Tet10 {
                // nodes: 60 corners + one per edge of the tetrahedral mesh (Euler: V − E + F − C = 1)
                let interior_faces = (4 * g.cells.len() - 104) / 2;
                let edges = 60 + (104 + interior_faces) - g.cells.len() - 1;
                assert_eq!(g.nodes.len(), 60 + edges);
            }
        }
    }
}
