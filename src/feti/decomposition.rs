//! Decomposition of each body into S subdomains (TFETI, docs/method.md, "TFETI and H-TFETI"): a METIS k-way partition of
//! the body's element graph (elements adjacent when they share a face, `ncommon = 4`; contiguous
//! parts requested, `METIS_OPTION_CONTIG`, so that every floating subdomain has exactly six
//! rigid-body modes), the nodes of each subdomain in a local numbering (sorted global ids, so
//! the order is deterministic), and for every mesh node its copies — one per subdomain that
//! touches it: interface nodes are duplicated and glued later by the B_E rows.

use crate::comm::Comm;
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
    check_parts(mesh, parts)?;
    let duals = DualGraphs::new(mesh);
    let part: Vec<Vec<usize>> = (0..mesh.bodies.len()).map(|b| duals.partition(b, parts[b])).collect::<Result<_>>()?;
    assemble(mesh, parts, |b, k| part[b][k])
}

/// [`decompose_each`] with each body's METIS partition made by one rank (body b by rank
/// b % size) and shared with the others: every rank gets the same decomposition, and the ranks
/// share the METIS work instead of each repeating all of it. The bodies' element graphs come
/// from `duals` (built on first use, kept for the next count).
pub fn decompose_shared<C: Comm>(comm: &C, duals: &DualGraphs, parts: &[usize]) -> Result<Decomposition> {
    let mesh = duals.mesh;
    check_parts(mesh, parts)?;
    let (me, size) = (comm.rank(), comm.size());
    // the part of every cell, filled by the rank that partitions its body, summed over the ranks
    let mut part = vec![0u64; mesh.cells.len()];
    let mut failed = Ok(());
    for b in (me..mesh.bodies.len()).step_by(size) {
        match duals.partition(b, parts[b]) {
            Ok(p) => part[mesh.bodies[b].elems.clone()].iter_mut().zip(p).for_each(|(x, p)| *x = p as u64),
            Err(e) => {
                failed = Err(e);
                break;
            }
        }
    }
    comm.agree(failed)?;
    if size > 1 {
        comm.sum_u64(&mut part);
    }
    assemble(mesh, parts, |b, k| part[mesh.bodies[b].elems.start + k] as usize)
}

/// Every body has at least as many elements as subdomains asked of it.
fn check_parts(mesh: &Mesh, parts: &[usize]) -> Result<()> {
    for (b, body) in mesh.bodies.iter().enumerate() {
        let (parts, ne) = (parts[b], body.elems.len());
        if parts == 0 || parts > ne {
            return Err(Error::scene("decomposition.subdomains", format!("body \"{}\" has {ne} elements; cannot split it into {parts} subdomains", body.name)));
        }
    }
    Ok(())
}

/// The subdomains from the part of every element (`part(b, k)`: body b's k-th element) and the
/// copies of every node.
fn assemble(mesh: &Mesh, parts: &[usize], part: impl Fn(usize, usize) -> usize) -> Result<Decomposition> {
    let mut subdomains = Vec::new();
    for (b, body) in mesh.bodies.iter().enumerate() {
        let parts = parts[b];
        let mut elems = vec![Vec::new(); parts];
        for (k, e) in body.elems.clone().enumerate() {
            elems[part(b, k)].push(e);
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

/// The element graphs of a mesh's bodies (elements adjacent when they share a face), each built
/// once on first use: the graph METIS partitions for every subdomain count of the body.
pub struct DualGraphs<'m> {
    mesh: &'m Mesh,
    graphs: Vec<std::sync::OnceLock<Dual>>,
}

/// One body's element graph in METIS's CSR form.
struct Dual {
    xadj: Vec<metis::Idx>,
    adjncy: Vec<metis::Idx>,
}

impl<'m> DualGraphs<'m> {
    /// No graph built yet.
    pub fn new(mesh: &'m Mesh) -> Self {
        DualGraphs { mesh, graphs: mesh.bodies.iter().map(|_| std::sync::OnceLock::new()).collect() }
    }

    /// The METIS k-way part of each element of body b (in the body's element order; contiguous
    /// parts).
    fn partition(&self, b: usize, parts: usize) -> Result<Vec<usize>> {
        let body = &self.mesh.bodies[b];
        let failed = |m: String| Error::numerical(format!("METIS partition of body \"{}\"", body.name), m);
        if parts == 1 {
            return Ok(vec![0; body.elems.len()]);
        }
        let dual = match self.graphs[b].get() {
            Some(d) => d,
            None => {
                let d = dual_graph(self.mesh, body.elems.clone(), body.nodes.start).map_err(failed)?;
                self.graphs[b].get_or_init(|| d)
            }
        };
        kway(dual, parts).map_err(failed)
    }
}

/// The face-adjacency graph of the elements `elems` (METIS's dual graph: elements adjacent when
/// they share `ncommon` corners); the body's nodes are `first..`, numbered for METIS in the order
/// they are first met.
fn dual_graph(mesh: &Mesh, elems: std::ops::Range<usize>, first: usize) -> std::result::Result<Dual, String> {
    let ne = elems.len();
    let too_large = || "mesh too large for 32-bit METIS indices".to_string();
    // the body's elements with their nodes renumbered 0..nn (a flat array over the body's node
    // range, not a hash map)
    let mut eptr = Vec::with_capacity(ne + 1);
    let mut eind = Vec::with_capacity(8 * ne);
    let mut map: Vec<metis::Idx> = Vec::new();
    let mut next: metis::Idx = 0;
    eptr.push(0);
    // corners only (a tet10's edge nodes would join cells that share an edge); cells that share a
    // face share 4 corners in a hexahedral mesh, 3 where triangles occur
    let hex_only = elems.clone().all(|e| mesh.cells[e].kind == crate::mesh::CellKind::Hex8);
    let ncommon = if hex_only { 4 } else { 3 };
    for e in elems {
        let c = &mesh.cells[e];
        for &v in &c.nodes()[..c.kind.corners()] {
            let l = v.checked_sub(first).ok_or_else(|| format!("element {e} has node {v} outside its body"))?;
            if l >= map.len() {
                map.resize(l + 1, -1);
            }
            if map[l] < 0 {
                map[l] = next;
                next = next.checked_add(1).ok_or_else(too_large)?;
            }
            eind.push(map[l]);
        }
        eptr.push(metis::Idx::try_from(eind.len()).map_err(|_| too_large())?);
    }
    Ok(mesh_to_dual(&eptr, &eind, next as usize, ncommon))
}

/// METIS's dual graph of a mesh in CSR form (`eptr`, `eind`, nodes `0..nn`): the elements that
/// share at least `ncommon` nodes with an element (or all but one of the smaller element's
/// nodes), in the order METIS 5.1's `CreateGraphDual` lists them — the neighbours as first met
/// through the element's nodes and each node's elements in ascending order — so that the
/// partitions are METIS's own. One pass instead of METIS's two (count, then fill).
fn mesh_to_dual(eptr: &[metis::Idx], eind: &[metis::Idx], nn: usize, ncommon: metis::Idx) -> Dual {
    let ne = eptr.len() - 1;
    let at = |x: metis::Idx| x as usize;
    // node → elements, ascending
    let mut nptr = vec![0usize; nn + 1];
    for &v in eind {
        nptr[at(v) + 1] += 1;
    }
    for i in 0..nn {
        nptr[i + 1] += nptr[i];
    }
    let mut fill = nptr.clone();
    let mut nind = vec![0 as metis::Idx; eind.len()];
    for e in 0..ne {
        for &v in &eind[at(eptr[e])..at(eptr[e + 1])] {
            nind[fill[at(v)]] = e as metis::Idx;
            fill[at(v)] += 1;
        }
    }
    drop(fill);
    let mut marker = vec![0 as metis::Idx; ne];
    let mut nbrs: Vec<metis::Idx> = Vec::new();
    let mut xadj = Vec::with_capacity(ne + 1);
    let mut adjncy = Vec::with_capacity(6 * ne);
    xadj.push(0);
    for q in 0..ne {
        let nodes = &eind[at(eptr[q])..at(eptr[q + 1])];
        let elen = nodes.len() as metis::Idx;
        nbrs.clear();
        for &v in nodes {
            for &e in &nind[nptr[at(v)]..nptr[at(v) + 1]] {
                if marker[at(e)] == 0 {
                    nbrs.push(e);
                }
                marker[at(e)] += 1;
            }
        }
        // the element itself is met through each of its nodes: dropped here
        marker[q] = 0;
        for &l in &nbrs {
            let overlap = marker[at(l)];
            if overlap >= ncommon || overlap >= elen - 1 || overlap >= eptr[at(l) + 1] - eptr[at(l)] - 1 {
                adjncy.push(l);
            }
            marker[at(l)] = 0;
        }
        xadj.push(adjncy.len() as metis::Idx);
    }
    Dual { xadj, adjncy }
}

/// METIS k-way part of each vertex of the graph `dual` (contiguous parts, seed 1).
fn kway(dual: &Dual, parts: usize) -> std::result::Result<Vec<usize>, String> {
    let nparts = metis::Idx::try_from(parts).map_err(|_| "too many parts for 32-bit METIS indices".to_string())?;
    let mut part = vec![0; dual.xadj.len() - 1];
    crate::linalg::ordering::metis_exclusive(|| -> std::result::Result<(), String> {
        metis::Graph::new(1, nparts, &dual.xadj, &dual.adjncy)
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
    fn a_kept_element_graph_partitions_as_a_fresh_one() {
        // one set of element graphs partitioned for several counts (built by the first), against
        // fresh partitions of each count
        let mesh = seed_mesh(6);
        let duals = DualGraphs::new(&mesh);
        for s in [4, 2, 8, 3] {
            let kept = decompose_shared(&crate::comm::SerialComm, &duals, &vec![s; mesh.bodies.len()]).unwrap();
            let fresh = decompose(&mesh, s).unwrap();
            assert_eq!(kept.subdomains, fresh.subdomains, "{s} subdomains");
            assert_eq!(kept.copies, fresh.copies);
        }
        assert!(duals.graphs.iter().all(|g| g.get().is_some()));
    }

    #[test]
    fn the_dual_graph_is_metis_own() {
        // hexahedra (4 and 3 common corners) and tetrahedra: the same neighbours in the same order
        // as METIS's METIS_MeshToDual
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let tet = crate::model::build(&crate::scene::load(&root.join("run/validation/hertz3d_tet4.toml"), &[]).unwrap()).unwrap().mesh;
        let mut compared = 0;
        for (mesh, ncommons) in [(seed_mesh(5), vec![4, 3, 1]), (tet, vec![3, 2])] {
            for body in &mesh.bodies {
                let mut map = vec![-1; body.nodes.len()];
                let (mut eptr, mut eind, mut next) = (vec![0], vec![], 0);
                for e in body.elems.clone() {
                    let c = &mesh.cells[e];
                    for &v in &c.nodes()[..c.kind.corners()] {
                        if map[v - body.nodes.start] < 0 {
                            map[v - body.nodes.start] = next;
                            next += 1;
                        }
                        eind.push(map[v - body.nodes.start]);
                    }
                    eptr.push(eind.len() as metis::Idx);
                }
                for &ncommon in &ncommons {
                    let ours = mesh_to_dual(&eptr, &eind, next as usize, ncommon);
                    let theirs = metis::mesh_to_dual(&eptr, &eind, ncommon).unwrap();
                    assert_eq!(ours.xadj, theirs.xadj(), "ncommon {ncommon}");
                    assert_eq!(ours.adjncy, theirs.adjncy(), "ncommon {ncommon}");
                    assert!(ours.adjncy.len() > eptr.len());
                    compared += 1;
                }
            }
        }
        assert!(compared >= 8);
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
