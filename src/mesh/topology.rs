//! Boundary topology of hexahedral meshes: the six faces of a hex8 with outward orientation,
//! and the map from a boundary quadrilateral (as a node set) to the element it bounds.

use std::collections::HashMap;

use super::FaceQuad;

/// Local node indices of the six faces of a hex8, ordered for an outward normal
/// (right-hand rule): z−, z+, y−, x+, y+, x−.
pub const HEX_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [3, 0, 4, 7],
];

/// The outward-oriented quad of local face `f` of element `e`.
pub fn hex_face(hexes: &[[usize; 8]], e: usize, f: usize) -> FaceQuad {
    FaceQuad { elem: e, nodes: HEX_FACES[f].map(|l| hexes[e][l]) }
}

fn key(nodes: [usize; 4]) -> [usize; 4] {
    let mut k = nodes;
    k.sort_unstable();
    k
}

/// All boundary quads (faces that belong to exactly one element), keyed by their sorted nodes.
pub fn boundary_faces(hexes: &[[usize; 8]]) -> HashMap<[usize; 4], FaceQuad> {
    let mut count: HashMap<[usize; 4], (usize, FaceQuad)> = HashMap::with_capacity(hexes.len() * 3);
    for e in 0..hexes.len() {
        for f in 0..6 {
            let q = hex_face(hexes, e, f);
            count.entry(key(q.nodes)).and_modify(|c| c.0 += 1).or_insert((1, q));
        }
    }
    count.into_iter().filter(|(_, (c, _))| *c == 1).map(|(k, (_, q))| (k, q)).collect()
}

/// Looks a quadrilateral up among the boundary quads, whatever its node order.
pub fn find_boundary_quad(
    boundary: &HashMap<[usize; 4], FaceQuad>,
    nodes: [usize; 4],
) -> Option<&FaceQuad> {
    boundary.get(&key(nodes))
}
