//! Structured hexahedral meshes of an axis-aligned box, with the six sides tagged
//! `xmin, xmax, ymin, ymax, zmin, zmax`.

use super::topology::hex_face;
use super::{try_vec, BodyGeometry};
use crate::error::Result;

/// Names of the box sides, in the order of the local hex faces that lie on them.
pub const SIDES: [(&str, usize); 6] =
    [("xmin", 5), ("xmax", 3), ("ymin", 2), ("ymax", 4), ("zmin", 0), ("zmax", 1)];

/// A box `[min, max]` with `n = [nx, ny, nz]` nodes per direction (each ≥ 2); panics where
/// memory runs out ([`try_generate`] returns the error).
pub fn generate(min: [f64; 3], max: [f64; 3], n: [usize; 3]) -> BodyGeometry {
    try_generate(min, max, n).unwrap_or_else(|e| panic!("{e}"))
}

/// [`generate`], with an allocation that fails (nodes, hexahedra, side quads) as an error.
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
    let mut hexes = try_vec::<[usize; 8]>("box hexahedra", count(ex, ey, ez))?;
    for k in 0..ez {
        for j in 0..ey {
            for i in 0..ex {
                hexes.push([
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                    id(i, j, k + 1),
                    id(i + 1, j, k + 1),
                    id(i + 1, j + 1, k + 1),
                    id(i, j + 1, k + 1),
                ]);
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
    Ok(BodyGeometry { nodes, hexes, faces })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn normal(g: &BodyGeometry, q: &[usize; 4]) -> [f64; 3] {
        let p = q.map(|v| g.nodes[v]);
        let a = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
        let b = [p[3][0] - p[0][0], p[3][1] - p[0][1], p[3][2] - p[0][2]];
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    }

    #[test]
    fn sides_are_outward_and_complete() {
        let g = generate([0.0, 0.0, 1.0], [2.0, 1.0, 2.0], [4, 3, 5]);
        assert_eq!(g.nodes.len(), 60);
        assert_eq!(g.hexes.len(), 3 * 2 * 4);
        let expect = [(0, -1.0, 8), (0, 1.0, 8), (1, -1.0, 12), (1, 1.0, 12), (2, -1.0, 6), (2, 1.0, 6)];
        for ((name, quads), (axis, sign, count)) in g.faces.iter().zip(expect) {
            assert_eq!(quads.len(), count, "{name}");
            for q in quads {
                let n = normal(&g, &q.nodes);
                assert!(n[axis] * sign > 0.0, "{name} not outward");
                assert!(n[(axis + 1) % 3].abs() < 1e-14 && n[(axis + 2) % 3].abs() < 1e-14);
            }
        }
        let boundary = crate::mesh::topology::boundary_faces(&g.hexes);
        assert_eq!(boundary.len(), g.faces.iter().map(|f| f.1.len()).sum::<usize>());
    }
}
