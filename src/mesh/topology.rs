//! Boundary topology of mixed meshes: the map from a boundary facet (as a node set) to the cell
//! it bounds, with the facet oriented outward of that cell.

use std::collections::HashMap;

use super::cell::{corner_key, Cell, Facet};

/// All boundary facets (faces that belong to exactly one cell), keyed by their sorted corners.
pub fn boundary_faces(cells: &[Cell]) -> HashMap<[usize; 4], Facet> {
    let mut count: HashMap<[usize; 4], (usize, Facet)> = HashMap::with_capacity(cells.len() * 3);
    for (e, c) in cells.iter().enumerate() {
        for f in 0..c.kind.faces().len() {
            let q = c.facet(e, f);
            count.entry(q.key()).and_modify(|c| c.0 += 1).or_insert((1, q));
        }
    }
    count.into_iter().filter(|(_, (c, _))| *c == 1).map(|(k, (_, q))| (k, q)).collect()
}

/// Looks a facet up among the boundary facets by its corners, whatever their order.
pub fn find_boundary_facet<'a>(boundary: &'a HashMap<[usize; 4], Facet>, corners: &[usize]) -> Option<&'a Facet> {
    boundary.get(&corner_key(corners))
}
