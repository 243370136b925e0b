//! Decomposition of each body into S subdomains (TFETI, docs/method.md, "TFETI and H-TFETI"): a METIS k-way partition of
//! the body's element graph (elements adjacent when they share a face, `ncommon = 4`; contiguous
//! parts requested, `METIS_OPTION_CONTIG`, so that every floating subdomain has exactly six
//! rigid-body modes), the nodes of each subdomain in a local numbering (sorted global ids, so
//! the order is deterministic), and for every mesh node its copies — one per subdomain that
//! touches it: interface nodes are duplicated and glued later by the B_E rows.

use crate::error::{Error, Result};
use crate::mesh::Mesh;

/// One subdomain: a set of elements of one body and the nodes they touch.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Subdomain {
    pub body: usize,
    /// Global element indices, ascending.
    pub elems: Vec<usize>,
    /// Global node ids, ascending; the local index of a node is its position here.
    pub nodes: Vec<usize>,
}

impl Subdomain {
    /// The local index of a global node, if the subdomain has it.
    pub fn local(&self, node: usize) -> Option<usize> {
        self.nodes.binary_search(&node).ok()
    }
}

/// The subdomains of all bodies and the copies of every node.
#[derive(Clone, Debug, Default)]
pub struct Decomposition {
    /// Subdomains ordered by body, then by METIS part.
    pub subdomains: Vec<Subdomain>,
    /// For every global node: the (subdomain, local index) of each of its copies.
    pub copies: Vec<Vec<(usize, usize)>>,
}

impl Decomposition {
    /// Nodes with more than one copy (on an interface between subdomains).
    pub fn interface_nodes(&self) -> usize {
        self.copies.iter().filter(|c| c.len() > 1).count()
    }
}

/// Splits every body into `parts` subdomains.
#[cfg(test)]
pub fn decompose(mesh: &Mesh, parts: usize) -> Result<Decomposition> {
    decompose_each(mesh, &vec![parts; mesh.bodies.len()])
}

/// Splits body b into `parts[b]` subdomains.
pub fn decompose_each(mesh: &Mesh, parts: &[usize]) -> Result<Decomposition> {
    let mut subdomains = Vec::new();
    for (b, body) in mesh.bodies.iter().enumerate() {
        let parts = parts[b];
        let ne = body.elems.len();
        if parts == 0 || parts > ne {
            return Err(Error::scene("decomposition.subdomains", format!("body \"{}\" has {ne} elements; cannot split it into {parts} subdomains", body.name)));
        }
        let part = partition(mesh, body.elems.clone(), parts).map_err(|m| Error::numerical(format!("METIS partition of body \"{}\"", body.name), m))?;
        let mut elems = vec![Vec::new(); parts];
        for (k, e) in body.elems.clone().enumerate() {
            elems[part[k]].push(e);
        }
        for (p, es) in elems.into_iter().enumerate() {
            if es.is_empty() {
                return Err(Error::numerical(
                    format!("METIS partition of body \"{}\"", body.name),
                    format!("part {p} of {parts} is empty; ask for fewer subdomains"),
                ));
            }
            let mut nodes: Vec<usize> = es.iter().flat_map(|&e| mesh.cells[e].nodes().to_vec()).collect();
            nodes.sort_unstable();
            nodes.dedup();
            subdomains.push(Subdomain { body: b, elems: es, nodes });
        }
    }
    let mut copies = vec![Vec::new(); mesh.nodes.len()];
    for (s, sd) in subdomains.iter().enumerate() {
        for (l, &v) in sd.nodes.iter().enumerate() {
            copies[v].push((s, l));
        }
    }
    Ok(Decomposition { subdomains, copies })
}

/// METIS k-way part of each element of `elems` (face-adjacency graph, contiguous parts).
fn partition(mesh: &Mesh, elems: std::ops::Range<usize>, parts: usize) -> std::result::Result<Vec<usize>, String> {
    let ne = elems.len();
    if parts == 1 {
        return Ok(vec![0; ne]);
    }
    let idx = |v: usize| metis::Idx::try_from(v).map_err(|_| "mesh too large for 32-bit METIS indices".to_string());
    // the body's elements with their nodes renumbered 0..nn
    let mut eptr = Vec::with_capacity(ne + 1);
    let mut eind = Vec::with_capacity(8 * ne);
    let mut map = std::collections::HashMap::new();
    eptr.push(0);
    // corners only (a tet10's edge nodes would join cells that share an edge); cells that share a
    // face share 4 corners in a hexahedral mesh, 3 where triangles occur
    let hex_only = elems.clone().all(|e| mesh.cells[e].kind == crate::mesh::CellKind::Hex8);
    let ncommon = if hex_only { 4 } else { 3 };
    for e in elems {
        let c = &mesh.cells[e];
        for v in &c.nodes()[..c.kind.corners()] {
            let next = map.len();
            eind.push(idx(*map.entry(v).or_insert(next))?);
        }
        eptr.push(idx(eind.len())?);
    }
    let mut part = vec![0; ne];
    crate::linalg::ordering::metis_exclusive(|| -> std::result::Result<(), String> {
        let dual = metis::mesh_to_dual(&eptr, &eind, ncommon).map_err(|e| format!("dual graph: {e}"))?;
        let (xadj, adjncy) = (dual.xadj().to_vec(), dual.adjncy().to_vec());
        metis::Graph::new(1, idx(parts)?, &xadj, &adjncy)
            .map_err(|e| format!("{e}"))?
            .set_option(metis::option::Contig(true))
            .set_option(metis::option::Seed(1))
            .part_kway(&mut part)
            .map_err(|e| format!("{e}"))?;
        Ok(())
    })?;
    Ok(part.into_iter().map(|p| p as usize).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seed_mesh(n: usize) -> Mesh {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("run/seed.toml");
        let ls = crate::scene::load(&path, &[format!("mesh.n={n}")]).unwrap();
        crate::model::build(&ls).unwrap().mesh
    }

    #[test]
    fn parts_cover_each_body_once_and_interfaces_are_duplicated() {
        let mesh = seed_mesh(7);
        for s in [1, 2, 4, 8] {
            let d = decompose(&mesh, s).unwrap();
            assert_eq!(d.subdomains.len(), 2 * s);
            // every element in exactly one subdomain of its own body
            let mut seen = vec![0; mesh.cells.len()];
            for sd in &d.subdomains {
                for &e in &sd.elems {
                    seen[e] += 1;
                    assert!(mesh.bodies[sd.body].elems.contains(&e));
                }
                assert!(!sd.elems.is_empty());
                // the local numbering is consistent
                for (l, &v) in sd.nodes.iter().enumerate() {
                    assert_eq!(sd.local(v), Some(l));
                }
            }
            assert!(seen.iter().all(|&c| c == 1));
            // every node has a copy, copies point back at it, and S = 1 has no interface
            for (v, c) in d.copies.iter().enumerate() {
                assert!(!c.is_empty());
                for &(s_, l) in c {
                    assert_eq!(d.subdomains[s_].nodes[l], v);
                }
            }
            if s == 1 {
                assert_eq!(d.interface_nodes(), 0);
            } else {
                assert!(d.interface_nodes() > 0);
                // balanced: METIS' default imbalance is 3 %, allow a little more on small meshes
                let sizes: Vec<usize> = d.subdomains.iter().map(|sd| sd.elems.len()).collect();
                let avg = 216.0 / s as f64;
                assert!(sizes.iter().all(|&k| (k as f64) <= 1.3 * avg), "{sizes:?}");
            }
            // contiguous: each subdomain's elements are face-connected
            for sd in &d.subdomains {
                assert_eq!(components(&mesh, &sd.elems), 1, "subdomain of body {} is split", sd.body);
            }
        }
    }

    #[test]
    fn too_many_subdomains_is_an_error_naming_the_key() {
        let mesh = seed_mesh(3);
        let e = decompose(&mesh, 9).unwrap_err().to_string();
        assert!(e.starts_with("decomposition.subdomains"), "{e}");
    }

    /// Connected components of a set of cells under face adjacency.
    fn components(mesh: &Mesh, elems: &[usize]) -> usize {
        let mut faces: std::collections::HashMap<[usize; 4], Vec<usize>> = std::collections::HashMap::new();
        for (k, &e) in elems.iter().enumerate() {
            let c = &mesh.cells[e];
            for f in 0..c.kind.faces().len() {
                faces.entry(c.facet(e, f).key()).or_default().push(k);
            }
        }
        let mut parent: Vec<usize> = (0..elems.len()).collect();
        fn find(p: &mut [usize], i: usize) -> usize {
            let mut r = i;
            while p[r] != r {
                r = p[r];
            }
            p[i] = r;
            r
        }
        for ks in faces.values().filter(|v| v.len() == 2) {
            let (a, b) = (find(&mut parent, ks[0]), find(&mut parent, ks[1]));
            parent[a] = b;
        }
        (0..elems.len()).filter(|&i| find(&mut parent, i) == i).count()
    }
}
