//! Boundary topology of mixed meshes: the map from a boundary facet (as a node set) to the cell
//! it bounds, with the facet oriented outward of that cell.

use std::collections::{HashMap, HashSet};

use rustc_hash::FxHashMap;

use super::cell::{corner_key, Cell, Facet};

/// One facet in the sort of [`boundary_faces`]: its corners packed into one `u128`, its cell,
/// its place in the cell.
pub type FacetEntry = (u128, u32, u32);

/// The boundary facets keyed by their sorted corners ([`corner_key`]).
pub type Boundary = FxHashMap<[usize; 4], Facet>;

/// All boundary facets (faces that belong to exactly one cell), keyed by their sorted corners.
///
/// Sort-based: every facet with its key in one vector, sorted by key, the keys met once kept
/// (a hash map of every facet of a million-cell mesh costs seconds; the sort a fraction). Where
/// every node index fits in 32 bits the key is packed into one `u128` (32-byte entries).
pub fn boundary_faces(cells: &[Cell]) -> Boundary {
    let total: usize = cells.iter().map(|c| c.kind.faces().len()).sum();
    let narrow = cells.len() <= u32::MAX as usize && cells.iter().flat_map(Cell::nodes).all(|&v| v < u32::MAX as usize);
    let mut boundary = Boundary::default();
    if narrow {
        // (packed key, cell, local facet): the facet is rebuilt for the kept ones
        let pack = |k: [usize; 4]| k.iter().fold(0u128, |a, &v| (a << 32) | v.min(u32::MAX as usize) as u128);
        let mut all: Vec<FacetEntry> = Vec::with_capacity(total);
        for (e, c) in cells.iter().enumerate() {
            for f in 0..c.kind.faces().len() {
                all.push((pack(c.facet(e, f).key()), e as u32, f as u32));
            }
        }
        all.sort_unstable_by_key(|&(k, _, _)| k);
        for run in all.chunk_by(|a, b| a.0 == b.0) {
            if let [(_, e, f)] = run {
                let q = cells[*e as usize].facet(*e as usize, *f as usize);
                boundary.insert(q.key(), q);
            }
        }
        return boundary;
    }
    let mut all: Vec<([usize; 4], usize, usize)> = Vec::with_capacity(total);
    for (e, c) in cells.iter().enumerate() {
        for f in 0..c.kind.faces().len() {
            all.push((c.facet(e, f).key(), e, f));
        }
    }
    all.sort_unstable_by_key(|&(k, _, _)| k);
    for run in all.chunk_by(|a, b| a.0 == b.0) {
        if let [(k, e, f)] = run {
            boundary.insert(*k, cells[*e].facet(*e, *f));
        }
    }
    boundary
}

/// Looks a facet up among the boundary facets by its corners, whatever their order.
pub fn find_boundary_facet<'a>(boundary: &'a Boundary, corners: &[usize]) -> Option<&'a Facet> {
    boundary.get(&corner_key(corners))
}

/// The boundary facets in cell order (each cell's facets in its face order): the list that many
/// node sets are filtered from (one pass over the cells, not one per set).
pub fn boundary_in_cell_order(cells: &[Cell], boundary: &Boundary) -> Vec<Facet> {
    let mut list = Vec::with_capacity(boundary.len());
    for (c, cell) in cells.iter().enumerate() {
        for f in 0..cell.kind.faces().len() {
            let q = cell.facet(c, f);
            if boundary.contains_key(&q.key()) {
                list.push(q);
            }
        }
    }
    list
}

/// The boundary facets, in cell order (a deterministic order), all of whose nodes lie in `set`:
/// the face a node set (Abaqus `*SURFACE, TYPE=NODE`, an Exodus node set) makes.
pub fn facets_on_nodes(cells: &[Cell], boundary: &Boundary, set: &HashSet<usize>) -> Vec<Facet> {
    on_nodes(&boundary_in_cell_order(cells, boundary), set)
}

/// The facets of `ordered` (a [`boundary_in_cell_order`] list) all of whose nodes lie in `set`,
/// in its order: one node set's face, for a reader with many sets.
pub fn on_nodes(ordered: &[Facet], set: &HashSet<usize>) -> Vec<Facet> {
    ordered.iter().filter(|q| q.nodes().iter().all(|v| set.contains(v))).copied().collect()
}

/// Named faces gathered from a file's surfaces and sets: merged by name (case-insensitive, the
/// first spelling kept), each facet once, empty lists left out.
#[derive(Default)]
pub struct NamedFaces {
    faces: Vec<(String, Vec<Facet>)>,
    seen: Vec<HashSet<(usize, [usize; 4])>>,
    by_name: HashMap<String, usize>,
}

impl NamedFaces {
    /// Adds the facets `list` to the face `name`.
    pub fn add(&mut self, name: &str, list: Vec<Facet>) {
        if list.is_empty() {
            return;
        }
        let f = *self.by_name.entry(name.to_ascii_uppercase()).or_insert_with(|| {
            self.faces.push((name.to_string(), Vec::new()));
            self.seen.push(HashSet::new());
            self.faces.len() - 1
        });
        for q in list {
            if self.seen[f].insert((q.elem, q.key())) {
                self.faces[f].1.push(q);
            }
        }
    }

    /// The faces in the order their names first came.
    pub fn into_faces(self) -> Vec<(String, Vec<Facet>)> {
        self.faces
    }
}
