//! Sparse assembly of a stiffness K (one body, or one TFETI subdomain) into the lower triangle
//! of a [`SymCsc`], with Dirichlet DOFs eliminated where the [`DofMap`] marks them (their
//! prescribed values are lifted into the right-hand side at the element level), and consistent
//! face loads.

use std::ops::Range;

use super::cell::{cell_min_jacobian, cell_stiffness};
use super::facet::{facet_area_vector, facet_nodal_areas, facet_rule, facet_shape};
use super::material::Lame;
use crate::error::{Error, Result};
use crate::linalg::sparse::SymCsc;
use crate::mesh::{try_vec, Cell, Face, Mesh, MAX_CELL_DOFS, MAX_CELL_NODES};

/// Marks a constrained DOF in [`DofMap::free`].
pub const FIXED: usize = usize::MAX;

/// Numbering of the free DOFs of a set of nodes: node-major, component-minor; constrained DOFs
/// carry their prescribed value.
#[derive(Clone, Debug)]
pub struct DofMap {
    /// Global node range covered (one body).
    pub nodes: Range<usize>,
    /// Local DOF `3·(node − nodes.start) + c` → free index, or [`FIXED`].
    pub free: Vec<usize>,
    /// Prescribed value of every local DOF (0 where free).
    pub prescribed: Vec<f64>,
    /// Number of free DOFs.
    pub nfree: usize,
}

impl DofMap {
    /// `constraints`: (global node, component, value); a later entry for the same DOF wins.
    pub fn new(nodes: Range<usize>, constraints: &[(usize, usize, f64)]) -> Self {
        let nd = 3 * nodes.len();
        let mut fixed = vec![false; nd];
        let mut prescribed = vec![0.0; nd];
        for &(v, c, val) in constraints {
            if nodes.contains(&v) {
                let d = 3 * (v - nodes.start) + c;
                fixed[d] = true;
                prescribed[d] = val;
            }
        }
        let mut free = vec![FIXED; nd];
        let mut nfree = 0;
        for d in 0..nd {
            if !fixed[d] {
                free[d] = nfree;
                nfree += 1;
            }
        }
        DofMap { nodes, free, prescribed, nfree }
    }

    /// Local DOF of global node `v`, component `c`.
    #[inline]
    pub fn local(&self, v: usize, c: usize) -> usize {
        3 * (v - self.nodes.start) + c
    }

    /// Free indices of the three DOFs of global node `v`.
    pub fn node_dofs(&self, v: usize) -> [Option<usize>; 3] {
        [0, 1, 2].map(|c| Some(self.free[self.local(v, c)]).filter(|&d| d != FIXED))
    }

    /// Nodal displacements of the body from the free values.
    pub fn expand(&self, x: &[f64]) -> Vec<[f64; 3]> {
        (0..self.nodes.len())
            .map(|v| {
                [0, 1, 2].map(|c| {
                    let d = 3 * v + c;
                    if self.free[d] == FIXED {
                        self.prescribed[d]
                    } else {
                        x[self.free[d]]
                    }
                })
            })
            .collect()
    }

    /// Restriction of a full local DOF vector to the free DOFs.
    pub fn restrict(&self, full: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.nfree];
        for (d, &f) in self.free.iter().enumerate() {
            if f != FIXED {
                out[f] = full[d];
            }
        }
        out
    }
}

/// Node adjacency of the elements `elems` in a local node numbering `local` (0..nn; CSR,
/// sorted, without the node itself).
pub fn node_graph(cells: &[Cell], elems: impl Iterator<Item = usize>, nn: usize, local: impl Fn(usize) -> usize) -> (Vec<usize>, Vec<usize>) {
    let mut nbr: Vec<Vec<u32>> = vec![Vec::new(); nn];
    for e in elems {
        let h = cells[e].map(&local);
        for &a in h.nodes() {
            for &b in h.nodes() {
                if a != b {
                    nbr[a].push(b as u32);
                }
            }
        }
    }
    let mut xadj = Vec::with_capacity(nn + 1);
    let mut adj = Vec::new();
    xadj.push(0);
    for list in &mut nbr {
        list.sort_unstable();
        list.dedup();
        adj.extend(list.iter().map(|&v| v as usize));
        xadj.push(adj.len());
    }
    (xadj, adj)
}

/// Why [`assemble_elements`] failed.
#[derive(Debug)]
pub enum AssemblyError {
    /// An element (its index) and what is wrong with it.
    Element(usize, &'static str),
    /// An array of the matrix that could not be allocated.
    Memory(Error),
}

/// One body's (or subdomain's) assembled system K_ff u_f = f_f.
pub struct BodySystem {
    /// The stiffness matrix K_ff of the free DOFs (lower triangle).
    pub k: SymCsc,
    /// The load vector f_f of the free DOFs.
    pub f: Vec<f64>,
    /// Node adjacency (local numbering), for the fill-reducing ordering.
    pub graph: (Vec<usize>, Vec<usize>),
}

/// Assembles the free-DOF stiffness of body `body` and the right-hand side
/// `f_f = loads_f − K_fc u_c`; `loads` holds nodal forces per local DOF (those on constrained
/// DOFs are dropped).
pub fn assemble_body(mesh: &Mesh, body: usize, lame: Lame, dofs: &DofMap, loads: &[f64]) -> Result<BodySystem> {
    let b = &mesh.bodies[body];
    let start = b.nodes.start;
    assemble_elements(&mesh.nodes, &mesh.cells, b.elems.clone(), b.nodes.len(), |v| v - start, lame, dofs, loads).map_err(|e| match e {
        AssemblyError::Element(e, msg) => Error::mesh(format!("body {}", b.name), format!("element {} is {msg}", e - b.elems.start)),
        AssemblyError::Memory(e) => e,
    })
}

/// Assembles K_ff and f_f over the elements `elems` of (`nodes`, `cells`), whose nodes are
/// numbered `local(v)` in 0..nn; DOF `3·local(v) + c` of `dofs` (its `nodes` range is not
/// used). On an inverted element returns the element and what is wrong with it.
pub fn assemble_elements(
    nodes: &[[f64; 3]],
    cells: &[Cell],
    elems: impl Iterator<Item = usize> + Clone,
    nn: usize,
    local: impl Fn(usize) -> usize,
    lame: Lame,
    dofs: &DofMap,
    loads: &[f64],
) -> std::result::Result<BodySystem, AssemblyError> {
    let (xadj, adj) = node_graph(cells, elems.clone(), nn, &local);
    // pattern: column of free DOF (v, c) holds free DOFs of v (components ≥ c) and of every
    // neighbour w > v, all three components — node-major numbering makes them sorted.
    // The largest arrays (row indices and values, nnz each) are reserved first: counted here.
    let free_of = |v: usize| (0..3).filter(|&c| dofs.free[3 * v + c] != FIXED).count();
    let nnz: usize = (0..nn)
        .map(|v| {
            let own = free_of(v);
            let nbr: usize = adj[xadj[v]..xadj[v + 1]].iter().filter(|&&w| w > v).map(|&w| free_of(w)).sum();
            own * (own + 1) / 2 + own * nbr
        })
        .sum();
    let mut col_ptr = try_vec::<usize>("stiffness column pointers", dofs.nfree + 1).map_err(AssemblyError::Memory)?;
    let mut row_idx = try_vec::<usize>("stiffness row indices", nnz).map_err(AssemblyError::Memory)?;
    let mut values = try_vec::<f64>("stiffness values", nnz).map_err(AssemblyError::Memory)?;
    values.resize(nnz, 0.0);
    col_ptr.push(0);
    for v in 0..nn {
        for c in 0..3 {
            let j = dofs.free[3 * v + c];
            if j == FIXED {
                continue;
            }
            for cc in c..3 {
                let i = dofs.free[3 * v + cc];
                if i != FIXED {
                    row_idx.push(i);
                }
            }
            for &w in adj[xadj[v]..xadj[v + 1]].iter().filter(|&&w| w > v) {
                for cc in 0..3 {
                    let i = dofs.free[3 * w + cc];
                    if i != FIXED {
                        row_idx.push(i);
                    }
                }
            }
            col_ptr.push(row_idx.len());
        }
    }
    debug_assert_eq!(row_idx.len(), nnz);
    let mut k = SymCsc { n: dofs.nfree, col_ptr, row_idx, values };
    let mut f = dofs.restrict(loads);
    let mut xbuf = [[0.0; 3]; MAX_CELL_NODES];
    for e in elems {
        let cell = &cells[e];
        let x = cell.coords_in(nodes, &mut xbuf);
        if cell_min_jacobian(cell.kind, x) <= 0.0 {
            return Err(AssemblyError::Element(e, "inverted or degenerate (non-positive Jacobian)"));
        }
        let ke = cell_stiffness(cell.kind, x, lame);
        let (nd, ke) = ke.rows();
        let mut ld = [0usize; MAX_CELL_DOFS];
        for (r, d) in ld[..nd].iter_mut().enumerate() {
            *d = 3 * local(cell.nodes()[r / 3]) + r % 3;
        }
        let ld = &ld[..nd];
        lift(ke, ld, dofs, &mut f);
        for q in 0..nd {
            let j = dofs.free[ld[q]];
            if j == FIXED {
                continue;
            }
            for p in 0..nd {
                let i = dofs.free[ld[p]];
                if i != FIXED && i >= j {
                    let pos = k.position(i, j).expect("assembly pattern covers every element entry");
                    k.values[pos] += ke[p * nd + q];
                }
            }
        }
    }
    Ok(BodySystem { k, f, graph: (xadj, adj) })
}

/// f_f −= K_fc u_c of one element (`ke` its stiffness row by row, `ld` its local DOFs).
fn lift(ke: &[f64], ld: &[usize], dofs: &DofMap, f: &mut [f64]) {
    let nd = ld.len();
    for q in 0..nd {
        let uc = dofs.prescribed[ld[q]];
        if dofs.free[ld[q]] != FIXED || uc == 0.0 {
            continue;
        }
        for p in 0..nd {
            let i = dofs.free[ld[p]];
            if i != FIXED {
                f[i] -= ke[p * nd + q] * uc;
            }
        }
    }
}

/// The right-hand side `loads_f − K_fc u_c` of body `body` alone (a new load state on the same
/// constrained DOFs): only the elements with a nonzero prescribed value are integrated.
pub fn body_rhs(mesh: &Mesh, body: usize, lame: Lame, dofs: &DofMap, loads: &[f64]) -> Vec<f64> {
    let b = &mesh.bodies[body];
    let mut f = dofs.restrict(loads);
    for e in b.elems.clone() {
        let cell = &mesh.cells[e];
        let ld: Vec<usize> = (0..3 * cell.kind.len()).map(|r| 3 * (cell.nodes()[r / 3] - b.nodes.start) + r % 3).collect();
        if ld.iter().all(|&d| dofs.free[d] != FIXED || dofs.prescribed[d] == 0.0) {
            continue;
        }
        lift(cell_stiffness(cell.kind, &mesh.cell_coords(e), lame).rows().1, &ld, dofs, &mut f);
    }
    f
}

/// Consistent nodal forces of a uniform pressure `p` on `face`, normal to it and positive into
/// the body: −p ∫ N_a n dA per facet, n the outward normal of the facet's true (curved) map.
pub fn add_pressure(mesh: &Mesh, face: &Face, p: f64, node0: usize, loads: &mut [f64]) {
    for q in &face.facets {
        let x = mesh.facet_coords(q);
        for (xi, wq) in facet_rule(q.kind) {
            let (n, d) = facet_shape(q.kind, xi);
            let c = facet_area_vector(&x, &d);
            for (a, &v) in q.nodes().iter().enumerate() {
                for k in 0..3 {
                    loads[3 * (v - node0) + k] -= p * wq * n[a] * c[k];
                }
            }
        }
    }
}

/// Consistent nodal forces of a uniform traction `p` on `face` (∫ N_a dA per facet), added into
/// `loads` (per local DOF of the body that starts at node `node0`).
pub fn add_traction(mesh: &Mesh, face: &Face, p: [f64; 3], node0: usize, loads: &mut [f64]) {
    for q in &face.facets {
        let w = facet_nodal_areas(q.kind, &mesh.facet_coords(q));
        for (a, &v) in q.nodes().iter().enumerate() {
            for c in 0..3 {
                loads[3 * (v - node0) + c] += w[a] * p[c];
            }
        }
    }
}
