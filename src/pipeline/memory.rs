//! The memory a run needs, estimated before the big allocations, and the refusal of a run that
//! would not fit (instead of the allocator's abort part-way).
//!
//! Per rank (the busiest), in named parts:
//! - `process`: the program with MPI and HDF5 loaded ([`PROCESS`]);
//! - `mesh`: the whole mesh as generated or read, on every rank — nodes [`NODE_BYTES`], cells
//!   [`ELEMENT_BYTES`], boundary facets [`FACET_BYTES`] (each array as built and as copied into
//!   the mesh, the load vectors; a box's counts by its cell type, [`box_counts`]), what the box
//!   generator holds while it cuts hexahedra into tetrahedra ([`tetrahedralize_bytes`]) and,
//!   for a Gmsh file, the file's bytes and the parser's arrays ([`GMSH_NODE_BYTES`],
//!   [`GMSH_ELEMENT_BYTES`]);
//! - `setup`: what every rank repeats for the plan and the partition (node graphs, METIS, the
//!   decomposition, B's rows): [`SETUP_PER_DOF`] per DOF of the whole mesh;
//! - `stiffness`: the rank's share of the DOFs (TFETI: interface nodes counted in every
//!   subdomain) × [`SHARE_PER_DOF`] (K's lower triangle, 41 entries per row, its vectors);
//! - `factors`: [`FACTOR_PER_NNZ`] × nnz(L) of the rank, nnz(L) the plan's count when the plan
//!   priced the decomposition, else the nested-dissection estimate [`nd_nnz_l`];
//! - `single-precision factors` (contact on TFETI, `solver.precision = "mixed"`):
//!   [`SINGLE_PER_NNZ`] × the same nnz(L);
//! - `contact blocks` (contact on the monolithic dual with explicit products): the trailing
//!   blocks of the factors, 8 bytes × (3 × contact nodes of a body)² per body of the rank;
//! - `dual`: [`ROW_BYTES`] per dual row (contact, gluing, Dirichlet: B, the solvers' vectors,
//!   the coarse problem and preconditioner) and [`GATHER_PER_NODE`] per node of the whole mesh
//!   (rank 0 gathers u and the stresses).
//!
//! The parts are summed although the setup's are freed before the factors are made: the
//! estimate errs on the safe side. The constants were fitted to the peaks (VmHWM) of the seed
//! scene at N = 16 … 41 (docs/performance.md, "The benchmark at growing size"): the estimate is 1.02–1.15× the measured peak.
//!
//! The limit is `--max-memory` ([`set_limit`]), else `TRESCA_FETI_MAX_MEMORY`, else
//! `MemAvailable` of `/proc/meminfo` or, where smaller, what `ulimit -v` leaves of the address
//! space; the ranks on one host share it (their estimates are
//! summed, hosts told apart by name). Without any of them nothing is checked.

use std::sync::OnceLock;

use crate::comm::Comm;
use crate::error::{human_bytes, Error, Result};
use crate::mesh::{Cell, CellKind, Facet};
use crate::model::Model;
use crate::scene::{DecompositionSettings, LoadedScene, Precision};

use super::plan::Candidate;

/// The process itself: code, MPI, HDF5 (measured: 26 MB after the `scene` phase).
pub const PROCESS: f64 = 30e6;
/// Per node of the mesh: coordinates as generated and in the mesh (2 × 24 B), the load vector
/// and one traction's unit loads (2 × 24 B).
pub const NODE_BYTES: f64 = 96.0;
/// Per cell of any type: a [`Cell`] (its type and room for ten node numbers, 96 B; the 216 B
/// that a cell of more than ten nodes keeps on the heap are not counted) as generated and in
/// the mesh.
pub const ELEMENT_BYTES: f64 = 2.0 * std::mem::size_of::<Cell>() as f64;
/// Per boundary facet of any type: a [`Facet`] (cell, type, room for nine nodes, 88 B) as
/// generated and in the mesh.
pub const FACET_BYTES: f64 = 2.0 * std::mem::size_of::<Facet>() as f64;
/// Per node of a Gmsh file, in the parser's arrays (coordinates and tag) besides ours.
pub const GMSH_NODE_BYTES: f64 = 32.0;
/// Per element of a Gmsh file, in the parser's arrays (8 node tags, the element tag).
pub const GMSH_ELEMENT_BYTES: f64 = 72.0;
/// Per DOF of the whole mesh, on every rank, during the setup (measured 157 B at N = 24 and 31).
pub const SETUP_PER_DOF: f64 = 200.0;
/// Per DOF of the rank's share: K (≈ 41 entries per column, 16 B each), the pieces' vectors.
pub const SHARE_PER_DOF: f64 = 700.0;
/// Per entry of L counted by the plan: 8 B stored × the supernodal excess (1.2–1.3) and the
/// factorization's workspace.
pub const FACTOR_PER_NNZ: f64 = 12.0;
/// Per entry of L, the single-precision copy of a contact solve's factors
/// (`solver.precision = "mixed"`): 4 B × the supernodal excess.
pub const SINGLE_PER_NNZ: f64 = 5.0;
/// Per dual row.
pub const ROW_BYTES: f64 = 1000.0;
/// Per node of the whole mesh on rank 0 (the gathered u and stresses).
pub const GATHER_PER_NODE: f64 = 64.0;

/// The sizes of a scene's mesh, known before it is generated or read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshCount {
    /// Nodes of the mesh.
    pub nodes: f64,
    /// Elements (volume cells) of the mesh.
    pub elements: f64,
    /// Boundary facets (quadrilaterals, triangles).
    pub facets: f64,
    /// Bytes of the Gmsh files (read whole) and the parser's arrays.
    pub files: f64,
    /// What the box generator holds only while it cuts one body into tetrahedra, the largest
    /// body's ([`tetrahedralize_bytes`]; the bodies are made one after the other).
    pub transient: f64,
    /// DOFs of every body.
    pub body_dofs: Vec<f64>,
    /// The scene key that sets the size (`mesh.n`, `body[i].box.nodes`, `body[i].gmsh.file`):
    /// the largest body's.
    pub key: String,
}

impl MeshCount {
    /// From the scene: box node counts, the Gmsh files' section headers ([`crate::mesh::gmsh::header_counts`];
    /// a file whose headers cannot be read counts nothing here, the reader will say why).
    pub fn of(ls: &LoadedScene) -> MeshCount {
        let scene = &ls.scene;
        let mut c = MeshCount::default();
        let mut largest = -1.0;
        for (i, b) in scene.bodies.iter().enumerate() {
            let key = key_of(ls, i);
            let (nodes, elements, facets) = if let Some(bx) = &b.boxed {
                let (n, kind) = (bx.nodes.unwrap_or([scene.mesh.n; 3]), crate::model::cell_kind(bx.cells.unwrap_or(scene.mesh.cells)));
                c.transient = c.transient.max(tetrahedralize_bytes(n, kind));
                box_counts(n, kind)
            } else if let Some((_, g)) = b.mesh_file() {
                let path = ls.dir().join(&g.file);
                let counts = match g.resolved_format() {
                    Some(crate::scene::MeshFormat::Abaqus) => crate::mesh::abaqus::counts(&path),
                    Some(crate::scene::MeshFormat::Med) => crate::mesh::med::counts(&path),
                    Some(crate::scene::MeshFormat::Exodus) => crate::mesh::exodus::counts(&path),
                    _ => crate::mesh::gmsh::header_counts(&path),
                };
                let (nodes, elements, bytes) = counts.map_or((0.0, 0.0, 0.0), |(n, e, s)| (n as f64, e as f64, s as f64));
                c.files += bytes + GMSH_NODE_BYTES * nodes + GMSH_ELEMENT_BYTES * elements;
                // a hexahedral mesh's boundary: about 6 e^(2/3) quadrilaterals
                (nodes, elements, 6.0 * elements.powf(2.0 / 3.0))
            } else {
                (0.0, 0.0, 0.0)
            };
            c.nodes += nodes;
            c.elements += elements;
            c.facets += facets;
            c.body_dofs.push(3.0 * nodes);
            if nodes > largest {
                (largest, c.key) = (nodes, key);
            }
        }
        c
    }

    /// From the built model (the bodies as read, the faces as made), with the key of
    /// [`MeshCount::of`]; no file bytes (freed once read).
    pub fn of_model(ls: &LoadedScene, model: &Model) -> MeshCount {
        let mesh = &model.mesh;
        let body_dofs: Vec<f64> = mesh.bodies.iter().map(|b| 3.0 * b.nodes.len() as f64).collect();
        let largest = (0..body_dofs.len()).max_by(|&a, &b| body_dofs[a].total_cmp(&body_dofs[b])).unwrap_or(0);
        MeshCount {
            nodes: model.size.nodes as f64,
            elements: model.size.elements as f64,
            facets: mesh.faces.iter().map(|f| f.facets.len() as f64).sum(),
            files: 0.0,
            transient: 0.0,
            body_dofs,
            key: key_of(ls, largest),
        }
    }

    /// DOFs of the mesh: 3 per node.
    pub fn dofs(&self) -> f64 {
        3.0 * self.nodes
    }

    /// The mesh as generated or read (every rank).
    pub fn bytes(&self) -> f64 {
        NODE_BYTES * self.nodes + ELEMENT_BYTES * self.elements + FACET_BYTES * self.facets + self.files + self.transient
    }
}

/// Nodes, cells and boundary facets of a box of `n` nodes per direction meshed with `kind`, as
/// [`crate::mesh::boxgen::try_generate_cells`] makes it: hexahedra and quadrilaterals; tet4 six
/// tetrahedra per hexahedron and two triangles per square; tet10 besides a node on every edge
/// of the tetrahedral mesh (the grid's edges, one diagonal per grid square, one per hexahedron:
/// ≈ 7 per grid node).
pub fn box_counts(n: [usize; 3], kind: CellKind) -> (f64, f64, f64) {
    let n = n.map(|v| v as f64);
    let e = n.map(|v| v - 1.0);
    let hexes = e[0] * e[1] * e[2];
    let squares = 2.0 * (e[0] * e[1] + e[1] * e[2] + e[0] * e[2]);
    let grid = n[0] * n[1] * n[2];
    match kind {
        CellKind::Hex8 | CellKind::Wedge6 | CellKind::Wedge15 | CellKind::Pyr5 => (grid, hexes, squares),
        CellKind::Hex20 | CellKind::Hex27 => {
            // the grid of 2n − 1 nodes per direction; hex20 without its face and cell centres
            let fine = (2.0 * n[0] - 1.0) * (2.0 * n[1] - 1.0) * (2.0 * n[2] - 1.0);
            let centres = hexes + e[0] * e[1] * n[2] + e[0] * n[1] * e[2] + n[0] * e[1] * e[2];
            (if kind == CellKind::Hex27 { fine } else { fine - centres }, hexes, squares)
        }
        CellKind::Tet4 => (grid, 6.0 * hexes, 2.0 * squares),
        CellKind::Tet10 => {
            let axis = e[0] * n[1] * n[2] + n[0] * e[1] * n[2] + n[0] * n[1] * e[2];
            let diagonals = e[0] * e[1] * n[2] + e[0] * n[1] * e[2] + n[0] * e[1] * e[2] + hexes;
            (grid + axis + diagonals, 6.0 * hexes, 2.0 * squares)
        }
    }
}

/// What the box generator holds only while it cuts a box of `n` nodes per direction into
/// tetrahedra (0 for hexahedra), besides the arrays [`MeshCount::bytes`] counts: the hexahedra
/// it cuts, the vector of every face of the tetrahedra that [`crate::mesh::topology::boundary_faces`]
/// sorts the boundary out of (4 faces per cell, a 32-byte entry: the packed key, the cell, the face)
/// and, for tet10, the map of edge nodes (≈ 32 B per edge).
pub fn tetrahedralize_bytes(n: [usize; 3], kind: CellKind) -> f64 {
    if !matches!(kind, CellKind::Tet4 | CellKind::Tet10) {
        return 0.0;
    }
    let (hex_nodes, hexes, _) = box_counts(n, CellKind::Hex8);
    let (nodes, cells, _) = box_counts(n, kind);
    let entry = std::mem::size_of::<crate::mesh::topology::FacetEntry>() as f64;
    let edges = nodes - hex_nodes;
    std::mem::size_of::<Cell>() as f64 * hexes + entry * 4.0 * cells + 32.0 * edges
}

/// The scene key that sets the size of body `i`.
fn key_of(ls: &LoadedScene, i: usize) -> String {
    let scene = &ls.scene;
    match scene.bodies.get(i) {
        Some(b) => match (&b.boxed, b.mesh_file()) {
            (Some(bx), _) if bx.nodes.is_none_or(|n| n == [scene.mesh.n; 3]) => "mesh.n".into(),
            (Some(_), _) => format!("body[{i}].box.nodes"),
            (_, Some((key, _))) => format!("body[{i}].{key}.file"),
            _ => format!("body[{i}]"),
        },
        None => "mesh".into(),
    }
}

/// nnz(L) of the factor of one piece of `dofs` DOFs of a 3-D hexahedral mesh under nested
/// dissection: 17.5 d^(4/3), growing by (d/10⁴)^0.1 above 10⁴ DOFs (the separators of these sizes
/// are still far from the asymptote). Fitted to the plan's counts on the seed scene, 2 800 to
/// 89 000 DOFs per piece: 1.05–1.23× the count.
pub fn nd_nnz_l(dofs: f64) -> f64 {
    17.5 * dofs.powf(4.0 / 3.0) * (dofs / 1e4).max(1.0).powf(0.1)
}

/// The DOFs of a body split into `parts` subdomains, interface nodes counted in every one:
/// × (1 + 3 (nodes per subdomain)^(-1/3)) (measured 1.31 at 930 nodes per subdomain).
pub fn with_interfaces(dofs: f64, parts: f64) -> f64 {
    if parts <= 1.0 {
        return dofs;
    }
    let per = (dofs / 3.0 / parts).max(1.0);
    dofs * (1.0 + 3.0 * per.powf(-1.0 / 3.0)).min(2.0)
}

/// One rank's estimate in named parts (bytes).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Estimate {
    /// The parts: (name, bytes).
    pub parts: Vec<(&'static str, f64)>,
    /// The decomposition the factors were estimated for, in words.
    pub basis: String,
}

impl Estimate {
    /// The whole estimate, in bytes.
    pub fn total(&self) -> f64 {
        self.parts.iter().map(|p| p.1).sum()
    }

    /// Bytes of part `name` (0 where there is none).
    pub fn part(&self, name: &str) -> f64 {
        self.parts.iter().find(|p| p.0 == name).map_or(0.0, |p| p.1)
    }

    /// `61.2 GB (process 30 MB, mesh 7.9 GB, …)`.
    pub fn describe(&self) -> String {
        let parts: Vec<String> = self.parts.iter().filter(|p| p.1 > 0.0).map(|(n, b)| format!("{n} {}", human_bytes(*b))).collect();
        format!("{} ({})", human_bytes(self.total()), parts.join(", "))
    }
}

/// The decomposition's pieces, for the factors and the share: (subdomains per body, whether
/// TFETI).
fn pieces(dec: &DecompositionSettings, body_dofs: &[f64]) -> (Vec<f64>, bool) {
    let dofs: Vec<usize> = body_dofs.iter().map(|&d| d as usize).collect();
    let parts: Vec<f64> = dofs.iter().map(|&d| dec.parts(d) as f64).collect();
    (parts, dec.is_tfeti(&dofs))
}

/// The parts every run has: process, mesh, setup and the share of K (`parts` subdomains per
/// body, interface nodes counted in each where `tfeti`).
fn common(count: &MeshCount, parts: &[f64], tfeti: bool, ranks: usize) -> Vec<(&'static str, f64)> {
    let p = ranks.max(1) as f64;
    let share: f64 = count.body_dofs.iter().zip(parts).map(|(&d, &s)| if tfeti { with_interfaces(d, s) } else { d }).sum::<f64>() / p;
    vec![("process", PROCESS), ("mesh", count.bytes()), ("setup", SETUP_PER_DOF * count.dofs()), ("stiffness", SHARE_PER_DOF * share)]
}

/// What a run needs before its mesh exists: the mesh, the setup, the share of K and — when the
/// scene sets the decomposition — the factors by [`nd_nnz_l`]; on `ranks` ranks.
pub fn before_mesh(count: &MeshCount, dec: &DecompositionSettings, ranks: usize) -> Estimate {
    let (parts, tfeti) = pieces(dec, &count.body_dofs);
    let mut e = Estimate { parts: common(count, &parts, tfeti, ranks), basis: "the mesh and setup; the plan fixes the factors".into() };
    if !super::plan::automatic(dec) {
        e.parts.push(("factors", FACTOR_PER_NNZ * set_factors(count, &parts, tfeti, ranks)));
        e.basis = format!("{}, nnz(L) estimated", decomposition_words(&parts, tfeti));
    }
    e
}

/// nnz(L) of the busiest rank for a decomposition set by the scene: every piece by
/// [`nd_nnz_l`], the monolithic dual's bodies on rank b mod P, TFETI's subdomains spread evenly.
fn set_factors(count: &MeshCount, parts: &[f64], tfeti: bool, ranks: usize) -> f64 {
    let ranks = ranks.max(1);
    if !tfeti {
        let mut per = vec![0.0; ranks];
        for (b, &d) in count.body_dofs.iter().enumerate() {
            per[super::owner(b, ranks)] += nd_nnz_l(d);
        }
        return per.into_iter().fold(0.0, f64::max);
    }
    let pieces: f64 = parts.iter().sum();
    let total: f64 = count.body_dofs.iter().zip(parts).map(|(&d, &s)| s * nd_nnz_l(d / s)).sum();
    // whole pieces per rank: the busiest holds ⌈S/P⌉ of them
    total * (pieces / ranks as f64).ceil() / pieces
}

fn decomposition_words(parts: &[f64], tfeti: bool) -> String {
    if tfeti {
        format!("TFETI {}", parts.iter().map(|p| p.to_string()).collect::<Vec<_>>().join("/"))
    } else {
        "monolithic".into()
    }
}

/// What a run needs once the model is built and the decomposition fixed: [`before_mesh`]'s
/// parts with the factors of the plan's chosen candidate (`chosen`, when the plan priced it) or
/// of [`nd_nnz_l`], and the dual.
pub fn after_plan(count: &MeshCount, model: &Model, dec: &DecompositionSettings, chosen: Option<&Candidate>, ranks: usize, precision: Precision) -> Estimate {
    let (parts, tfeti) = pieces(dec, &count.body_dofs);
    let p = ranks.max(1) as f64;
    let mut e = Estimate { parts: common(count, &parts, tfeti, ranks), basis: String::new() };
    let contact_rows = model.pairs.as_ref().map_or(0.0, |c| (c.len() * if c.has_friction() { 3 } else { 1 }) as f64);
    let (nnz, rows) = match chosen {
        Some(c) => (c.nnz_l_rank, c.dual_rows() as f64),
        None => {
            // gluing rows: one per duplicated DOF; Dirichlet rows: the constrained DOFs
            let dup = if tfeti { count.body_dofs.iter().zip(&parts).map(|(&d, &s)| with_interfaces(d, s) - d).sum::<f64>() } else { 0.0 };
            let dirichlet = if tfeti { model.constraints.len() as f64 } else { 0.0 };
            (set_factors(count, &parts, tfeti, ranks), contact_rows + dup + dirichlet)
        }
    };
    e.parts.push(("factors", FACTOR_PER_NNZ * nnz));
    // the explicit products' trailing blocks (3 DOFs per contact node, a square f64 matrix):
    // where the plan chose them, or — unplanned — where their lower half fits in the factor
    let mut blocks = vec![0.0; ranks.max(1)];
    if model.pairs.is_some() && !tfeti {
        for b in 0..model.mesh.bodies.len() {
            let n = 3.0 * super::contact_nodes(model, b).iter().filter(|&&l| l).count() as f64;
            blocks[super::owner(b, ranks.max(1))] += 8.0 * n * n;
        }
    }
    let blocks = blocks.into_iter().fold(0.0, f64::max);
    let explicit = blocks > 0.0 && chosen.map_or(blocks / 16.0 <= nnz, |c| c.explicit);
    if explicit {
        e.parts.push(("contact blocks", blocks));
    } else if precision != Precision::Double && model.pairs.is_some() {
        e.parts.push(("single-precision factors", SINGLE_PER_NNZ * nnz));
    }
    e.parts.push(("dual", ROW_BYTES * rows / if tfeti { p } else { 1.0 } + GATHER_PER_NODE * count.nodes));
    e.basis = match chosen {
        Some(c) => format!("{}, the plan's nnz(L)", c.label()),
        None => format!("{}, nnz(L) estimated", decomposition_words(&parts, tfeti)),
    };
    e
}

// ---------------------------------------------------------------------------------------------
// The limit

static LIMIT: OnceLock<f64> = OnceLock::new();

/// Sets the memory the run may use on each host (`--max-memory`), in place of `MemAvailable`;
/// the first call wins.
pub fn set_limit(bytes: u64) {
    let _ = LIMIT.set(bytes as f64);
}

/// `8G`, `500M`, `64k`, `1.5GB`, `4GiB` or plain bytes (k/M/G/T: powers of 1024); strict:
/// one number, then at most one unit with an optional `B` or `iB`, nothing else.
pub fn parse_size(s: &str) -> std::result::Result<u64, String> {
    let t = s.trim();
    let split = t.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let not_a_size = || format!("\"{s}\" is not a size (e.g. 8G, 500M, 4GiB, 1048576)");
    if num.is_empty() || !num.starts_with(|c: char| c.is_ascii_digit()) {
        return Err(not_a_size());
    }
    let v: f64 = num.parse().map_err(|_| not_a_size())?;
    let lower = unit.trim_start().to_ascii_lowercase();
    let (prefix, rest) = lower.split_at(lower.find(|c: char| c != 'k' && c != 'm' && c != 'g' && c != 't').unwrap_or(lower.len()).min(1));
    let scale = match prefix {
        "" => 1.0,
        "k" => 1024.0,
        "m" => 1024.0 * 1024.0,
        "g" => 1024.0 * 1024.0 * 1024.0,
        _ => 1024.0f64.powi(4),
    };
    let suffix_ok = match rest {
        "" => true,
        "b" => true,
        "ib" => !prefix.is_empty(),
        _ => false,
    };
    if !suffix_ok {
        return Err(format!("\"{s}\": unknown unit \"{}\" (k, M, G, T, with an optional B or iB)", unit.trim()));
    }
    let bytes = v * scale;
    if !(bytes.is_finite() && bytes >= 1.0) {
        return Err(format!("\"{s}\" must be at least one byte"));
    }
    Ok(bytes as u64)
}

/// The memory the ranks of this host may use and where that figure comes from; `None` where
/// nothing says.
/// nothing says. A `TRESCA_FETI_MAX_MEMORY` that is not a size is an error naming it.
pub fn available() -> Result<Option<(f64, String)>> {
    if let Some(&l) = LIMIT.get() {
        return Ok(Some((l, "--max-memory".into())));
    }
    if let Some(v) = std::env::var_os("TRESCA_FETI_MAX_MEMORY") {
        let b = parse_size(&v.to_string_lossy()).map_err(|e| Error::scene("TRESCA_FETI_MAX_MEMORY", e))?;
        return Ok(Some((b as f64, "TRESCA_FETI_MAX_MEMORY".into())));
    }
    let mem_available = || -> Option<f64> {
        let info = std::fs::read_to_string("/proc/meminfo").ok()?;
        info.lines().find(|l| l.starts_with("MemAvailable:"))?.split_whitespace().nth(1)?.parse().ok()
    };
    let host = mem_available().map(|kb| (kb * 1024.0, "MemAvailable in /proc/meminfo; set --max-memory to override".to_string()));
    // `ulimit -v` caps this process's address space: what is left of it, the estimate's own
    // `process` part given back (the mappings of MPI and HDF5 are counted in both)
    let limited = address_space_left().map(|b| (b + PROCESS, "ulimit -v (RLIMIT_AS) less this process's mappings".to_string()));
    Ok(match (host, limited) {
        (Some(h), Some(l)) => Some(if l.0 < h.0 { l } else { h }),
        (h, l) => h.or(l),
    })
}

/// The address space this process may still map under RLIMIT_AS (`ulimit -v`), if limited.
fn address_space_left() -> Option<f64> {
    let mut r = libc::rlimit { rlim_cur: 0, rlim_max: 0 };
    // SAFETY: getrlimit writes the struct it is given
    if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut r) } != 0 || r.rlim_cur == libc::RLIM_INFINITY {
        return None;
    }
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb: f64 = status.lines().find(|l| l.starts_with("VmSize:"))?.split_whitespace().nth(1)?.parse().ok()?;
    Some((r.rlim_cur as f64 - kb * 1024.0).max(0.0))
}

/// This host's name as a number (52 bits, exact in an f64), to count the ranks that share it.
fn host_id() -> f64 {
    let name = std::fs::read_to_string("/proc/sys/kernel/hostname").or_else(|_| std::env::var("HOSTNAME")).unwrap_or_default();
    // FNV-1a
    let h = name.trim().bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
    (h >> 12) as f64
}

/// How many ranks of `comm` run on this host (collective).
pub fn ranks_on_host<C: Comm>(comm: &C) -> usize {
    let me = host_id();
    comm.all_gather_f64(&[me]).iter().filter(|v| v.first() == Some(&me)).count().max(1)
}

/// Before the mesh is generated or read (phase `mesh`): refuses a run whose mesh, setup and
/// share of K (and factors, where the scene sets the decomposition) exceed the memory available
/// on `comm.size()` ranks. Collective.
pub fn check_before_mesh<C: Comm>(comm: &C, ls: &LoadedScene) -> Result<()> {
    let count = MeshCount::of(ls);
    check(comm, &count.key, &before_mesh(&count, &ls.scene.decomposition, comm.size()))
}

/// After the plan (before assembly and factorization): refuses a run whose estimate with the
/// decomposition's factors exceeds the memory available; `plan`: the priced candidates, when
/// the plan chose. Collective.
pub fn check_after_plan<C: Comm>(comm: &C, ls: &LoadedScene, model: &Model, plan: Option<&[Candidate]>) -> Result<()> {
    let count = MeshCount::of_model(ls, model);
    let chosen = plan.and_then(super::plan::cheapest);
    check(comm, &count.key, &after_plan(&count, model, &ls.scene.decomposition, chosen, comm.size(), ls.scene.solver.precision))
}

/// A memory error of METIS (its out-of-memory status) as the memory check's own: one line
/// naming the key of the mesh (`mesh.n` or the mesh file); other errors unchanged.
pub fn name_the_mesh(ls: &LoadedScene, e: Error) -> Error {
    match e {
        Error::Memory { what, msg } if what == crate::linalg::ordering::METIS_MEMORY => {
            Error::memory(MeshCount::of(ls).key, format!("{msg}: the run needs more memory than this host has for it; use a coarser mesh or more hosts"))
        }
        e => e,
    }
}

/// Refuses a run whose estimate (per rank) times the ranks on this host exceeds what is
/// available there: one line naming `key`, the estimate and its parts, and the limit.
/// Collective; every rank returns the same verdict.
pub fn check<C: Comm>(comm: &C, key: &str, e: &Estimate) -> Result<()> {
    let on_host = ranks_on_host(comm);
    comm.agree(available().and_then(|limit| verdict(key, e, on_host, comm.rank(), limit)))
}

/// The refusal, if any (pure: the estimate, the ranks on the host, the limit).
pub fn verdict(key: &str, e: &Estimate, on_host: usize, rank: usize, limit: Option<(f64, String)>) -> Result<()> {
    let Some((avail, source)) = limit else { return Ok(()) };
    let need = e.total() * on_host as f64;
    if need <= avail {
        return Ok(());
    }
    let host = if on_host > 1 { format!(" per rank, {} for the {on_host} ranks on this host,", human_bytes(need)) } else { format!(" on rank {rank}") };
    Err(Error::memory(key, format!("the run needs about {}{host} but {} are available ({source})", e.describe(), human_bytes(avail))))
}

/// The lines `check` prints: the estimate per rank on `ranks` ranks, its parts, what it was
/// based on, and the memory available here.
pub fn summary(e: &Estimate, ranks: usize) -> Result<String> {
    let all = e.total() * ranks as f64;
    let limit = match available()? {
        Some((b, source)) => {
            let fits = if all <= b { "fits" } else { "does not fit: solve refuses it" };
            format!("{} available on this host ({source}); {fits}", human_bytes(b))
        }
        None => "no figure of the available memory".into(),
    };
    let host = if ranks > 1 { format!(", {} for {ranks} ranks on one host", human_bytes(all)) } else { String::new() };
    Ok(format!("memory: about {} per rank{host}; {}\n  {limit}\n", e.describe(), e.basis))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The count of the seed scene at `n`, as [`MeshCount::of`] makes it from the scene (no
    /// mesh is built).
    fn seed(n: usize) -> MeshCount {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("run/seed.toml");
        MeshCount::of(&crate::scene::load(&path, &[format!("mesh.n={n}")]).unwrap())
    }

    #[test]
    fn sizes_parse_with_units() {
        assert_eq!(parse_size("1M"), Ok(1 << 20));
        assert_eq!(parse_size("8G"), Ok(8 << 30));
        assert_eq!(parse_size("500m"), Ok(500 << 20));
        assert_eq!(parse_size("4GiB"), Ok(4 << 30));
        assert_eq!(parse_size("1.5k"), Ok(1536));
        assert_eq!(parse_size("123456"), Ok(123456));
        assert!(parse_size("lots").is_err());
        assert!(parse_size("8X").is_err());
        assert!(parse_size("0").is_err());
        assert_eq!(parse_size("8gb"), Ok(8 << 30));
        assert_eq!(parse_size("2048B"), Ok(2048));
        for bad in ["8GBBBB", "8GiBiB", "-1", "", "lots", "8 G B", "1e9", "8iB", "8GG", ".5G"] {
            assert!(parse_size(bad).is_err(), "{bad:?}");
        }
    }

    #[test]
    fn the_mesh_part_counts_what_the_generator_allocates() {
        // N = 500: 2 × 125 M nodes, 2 × 124 M hexahedra; one body's hexahedra alone are the
        // 7.95 GB allocation the abort named
        let c = seed(500);
        assert_eq!(c.nodes, 2.5e8);
        assert_eq!(64.0 * c.elements / 2.0, 7_952_095_936.0);
        // every cell and facet type in one array: 96 B a cell (up to 10 nodes inline, more on the
        // heap), 88 B a facet (up to 9 nodes), each held twice
        assert_eq!((ELEMENT_BYTES, FACET_BYTES), (192.0, 176.0));
        assert!((c.bytes() - (96.0 * 2.5e8 + 192.0 * c.elements + 176.0 * c.facets)).abs() < 1.0);
        let e = before_mesh(&c, &DecompositionSettings::default(), 1);
        assert_eq!(e.part("setup"), SETUP_PER_DOF * 7.5e8);
        assert_eq!(e.part("factors"), 0.0, "the plan has not chosen the decomposition yet");
        assert!(e.total() > 150e9);
        // the share of K halves on two ranks, the replicated mesh and setup do not
        let e2 = before_mesh(&c, &DecompositionSettings::default(), 2);
        assert_eq!(e2.part("stiffness"), e.part("stiffness") / 2.0);
        assert_eq!(e2.part("mesh"), e.part("mesh"));
    }

    /// The box counts by cell type are the generator's exactly: nodes (tet10: with an edge node
    /// on every edge), cells and boundary facets. Catches an estimate that still counts
    /// hexahedra for a tetrahedral box (6× the cells, ≈ 8× the tet10 nodes).
    #[test]
    fn box_counts_match_the_generated_mesh_for_every_cell_type() {
        for n in [[2, 2, 2], [4, 3, 5], [6, 6, 6]] {
            for kind in [CellKind::Hex8, CellKind::Tet4, CellKind::Tet10, CellKind::Hex20, CellKind::Hex27] {
                let g = crate::mesh::boxgen::try_generate_cells([0.0; 3], [1.0, 2.0, 3.0], n, kind).unwrap();
                let facets: usize = g.faces.iter().map(|f| f.1.len()).sum();
                let counted = (g.nodes.len() as f64, g.cells.len() as f64, facets as f64);
                assert_eq!(box_counts(n, kind), counted, "{kind:?} {n:?}");
                assert_eq!(tetrahedralize_bytes(n, kind) == 0.0, !matches!(kind, CellKind::Tet4 | CellKind::Tet10));
            }
        }
        // N = 41: ≈ 7.7 nodes per grid node with tet10, six cells per hexahedron
        let (h, t4, t10) = (box_counts([41; 3], CellKind::Hex8), box_counts([41; 3], CellKind::Tet4), box_counts([41; 3], CellKind::Tet10));
        assert_eq!(t4.1, 6.0 * h.1);
        assert!((7.5..8.0).contains(&(t10.0 / h.0)), "{}", t10.0 / h.0);
    }

    #[test]
    fn the_factor_estimate_follows_the_counted_fill() {
        // the plan's counted nnz(L) on the seed scene: (DOFs per piece, nnz per piece)
        for (d, counted) in [(2793.0, 652e3), (12288.0, 4.12e6), (41472.0, 2.46e7), (89373.0, 7.2e7)] {
            let r = nd_nnz_l(d) / counted;
            assert!((1.0..1.25).contains(&r), "{d} DOFs: {r}");
        }
        // a set decomposition: more subdomains, less fill; on more ranks, less per rank
        let c = seed(24);
        let mono = before_mesh(&c, &DecompositionSettings { subdomains: Some(1), ..Default::default() }, 1);
        let s8 = before_mesh(&c, &DecompositionSettings { subdomains: Some(8), ..Default::default() }, 1);
        let s8r2 = before_mesh(&c, &DecompositionSettings { subdomains: Some(8), ..Default::default() }, 2);
        assert!(mono.part("factors") > s8.part("factors") && s8.part("factors") > 1.9 * s8r2.part("factors"));
        assert!(s8.part("stiffness") > mono.part("stiffness"), "interface nodes count in every subdomain");
        assert!((with_interfaces(3.0 * 27648.0, 32.0) / (3.0 * 27648.0) - 1.315).abs() < 0.01);
    }

    #[test]
    fn a_run_over_the_limit_is_refused_in_one_line() {
        let e = Estimate { parts: vec![("process", 30e6), ("mesh", 7.9e9), ("factors", 48e9)], basis: String::new() };
        assert!(verdict("mesh.n", &e, 1, 0, None).is_ok());
        assert!(verdict("mesh.n", &e, 1, 0, Some((1e12, "x".into()))).is_ok());
        let msg = verdict("mesh.n", &e, 1, 0, Some((21.3e9, "MemAvailable in /proc/meminfo".into()))).unwrap_err().to_string();
        assert_eq!(msg, "mesh.n: the run needs about 55.9 GB (process 30.0 MB, mesh 7.9 GB, factors 48.0 GB) on rank 0 but 21.3 GB are available (MemAvailable in /proc/meminfo)");
        // two ranks on one host need twice as much there
        let small = Estimate { parts: vec![("mesh", 6e9)], basis: String::new() };
        assert!(verdict("mesh.n", &small, 1, 0, Some((10e9, "x".into()))).is_ok());
        let msg = verdict("mesh.n", &small, 2, 0, Some((10e9, "x".into()))).unwrap_err().to_string();
        assert!(msg.contains("12.0 GB for the 2 ranks on this host") && !msg.contains('\n'), "{msg}");
    }
}
