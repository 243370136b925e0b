//! The one post-solve path of both duals: each rank checks K u = f − Bᵀλ on its pieces (bodies
//! or TFETI subdomains), computes their element stresses (phase `stress`), and rank 0 gathers u,
//! the stresses and each piece's figures (phase `gather`); a node shared by several pieces is
//! written by the first of them and the others' copies give the gluing jump. Each rank reads
//! only its own pieces' part of the mesh ([`PieceLayout`]).

use serde::{Deserialize, Serialize};

use super::accuracy::Equilibrium;
use super::{LocalFields, LocalMesh, Solution, Timings};
use crate::comm::Comm;
use crate::error::{Error, Result};
use crate::fem::cell::cell_center_stress;
use crate::fem::material::von_mises;
use crate::fem::material::Lame;
use crate::linalg::sparse::SymCsc;
use crate::model::MeshSize;

/// A piece of this rank (a body, or a TFETI subdomain): its part of the mesh, all that the
/// post-solve path reads of it.
#[derive(Clone, Debug)]
pub struct PieceLayout {
    /// The piece's index over all ranks (bodies, subdomains).
    pub index: usize,
    pub body: usize,
    /// Global node ids, ascending: the piece-local index of a node is its position here.
    pub nodes: Vec<usize>,
    /// Coordinates of `nodes`.
    pub coords: Vec<[f64; 3]>,
    /// Whether this piece writes the node (each node is written by one piece: the first that
    /// has it).
    pub writes: Vec<bool>,
    /// Global element indices, ascending.
    pub elems: Vec<usize>,
    /// The elements' nodes, piece-local.
    pub cells: Vec<crate::mesh::Cell>,
    /// Nodes shared with other pieces (TFETI), 0 for a body.
    pub interface_nodes: usize,
    /// The piece in messages ("body \"upper\"", "subdomain 3 (body \"upper\")").
    pub name: String,
}

impl PieceLayout {
    /// Body `b` of `mesh` whole (bodies share no nodes).
    pub fn body(mesh: &crate::mesh::Mesh, b: usize) -> Self {
        let body = &mesh.bodies[b];
        let n0 = body.nodes.start;
        PieceLayout {
            index: b,
            body: b,
            nodes: body.nodes.clone().collect(),
            coords: mesh.nodes[body.nodes.clone()].to_vec(),
            writes: vec![true; body.nodes.len()],
            elems: body.elems.clone().collect(),
            cells: mesh.cells[body.elems.clone()].iter().map(|h| h.map(|v| v - n0)).collect(),
            interface_nodes: 0,
            name: format!("body \"{}\"", body.name),
        }
    }
}

/// A piece on this rank with its solution: K x = rhs on the DOFs K acts on, and u at every node
/// of the piece.
pub struct PieceSolution<'a> {
    pub k: &'a SymCsc,
    pub nnz_l: usize,
    pub x: &'a [f64],
    pub rhs: &'a [f64],
    /// Entries of x held by Dirichlet conditions inside K's DOFs (0 in x; their rows carry
    /// reactions and are not checked).
    pub held: &'a [usize],
    /// u at the layout's nodes (prescribed values included).
    pub nodal: Vec<[f64; 3]>,
}

impl PieceSolution<'_> {
    /// Its recovered equilibrium K x = rhs ([`Equilibrium`]: what the accuracy guard and the
    /// post-solve check judge).
    pub fn equilibrium(&self) -> Equilibrium {
        Equilibrium::of(self.k, self.x, self.rhs, self.held)
    }
}

/// Figures of one piece.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct PieceStats {
    pub body: usize,
    pub nodes: usize,
    pub elements: usize,
    /// DOFs its K acts on.
    pub dofs: usize,
    #[serde(rename = "nnz_K_lower")]
    pub nnz_k: usize,
    #[serde(rename = "nnz_L")]
    pub nnz_l: usize,
    /// ‖K u − (f − Bᵀλ)‖ / ‖f − Bᵀλ‖.
    #[serde(rename = "relative_residual")]
    pub residual: f64,
    pub rank: usize,
}

/// Per piece in the gathered buffer: index, nodes, elements, interface nodes, body.
const HEAD_LEN: usize = 5;
const STATS_LEN: usize = 4;

/// What [`finish`] returns: the solution, every piece's figures and interface nodes, the
/// relative gluing jump.
pub type Finished = (Solution, Vec<(PieceStats, usize)>, f64);

/// Checks, stresses and gathers the pieces (phases `stress` and `gather`): `layout` and `mine`
/// are this rank's pieces, in the same order, of `pieces` over all ranks on a mesh of `size`;
/// `lame` the bodies' constants. `hint` ends the
/// message of a piece whose K u = rhs does not hold. Returns the solution (fields on rank 0,
/// this rank's rows and mesh everywhere), the figures and interface nodes of every piece in
/// index order and the relative gluing jump (both on rank 0). Nothing here reads the whole mesh.
#[allow(clippy::too_many_arguments)]
pub fn finish<C: Comm>(
    comm: &C,
    lame: &[Lame],
    size: MeshSize,
    pieces: usize,
    layout: &[PieceLayout],
    mine: &[PieceSolution<'_>],
    hint: &str,
    t: &mut Timings,
) -> Result<Finished> {
    assert_eq!(layout.len(), mine.len(), "one layout per piece of this rank");
    // the equilibrium of every piece, judged against the rounding of the whole problem
    let eqs: Vec<Equilibrium> = mine.iter().map(PieceSolution::equilibrium).collect();
    let mut scale = [eqs.iter().map(|e| e.scale).fold(0.0, f64::max)];
    comm.max_f64(&mut scale);
    let (packed, local, local_mesh) = t.phase(comm, "stress", || {
        let mut buf = Vec::new();
        let mut local = LocalFields::default();
        let mut lm = LocalMesh::default();
        for ((pl, ps), eq) in layout.iter().zip(mine).zip(&eqs) {
            let residual = eq.relative();
            if eq.excess(scale[0]) > 1.0 {
                return Err(Error::numerical(pl.name.clone(), format!("K u = f − Bᵀλ does not hold (relative residual {residual:.1e}): {hint}")));
            }
            buf.extend([pl.index, pl.nodes.len(), pl.elems.len(), pl.interface_nodes, pl.body].map(|x| x as f64));
            // a node the piece does not write goes as −(v + 1): a copy, for the gluing jump
            buf.extend(pl.nodes.iter().zip(&pl.writes).map(|(&v, &w)| if w { v as f64 } else { -(v as f64) - 1.0 }));
            buf.extend(ps.nodal.iter().flatten());
            for (l, &v) in pl.nodes.iter().enumerate().filter(|&(l, _)| pl.writes[l]) {
                local.nodes.push(v);
                local.displacement.push(ps.nodal[l]);
                lm.coordinates.push(pl.coords[l]);
            }
            let lame = lame[pl.body];
            buf.extend(pl.elems.iter().map(|&e| e as f64));
            for (&e, cell) in pl.elems.iter().zip(&pl.cells) {
                let x: Vec<[f64; 3]> = cell.nodes().iter().map(|&l| pl.coords[l]).collect();
                let u: Vec<[f64; 3]> = cell.nodes().iter().map(|&l| ps.nodal[l]).collect();
                let vm = von_mises(&cell_center_stress(cell.kind, &x, &u, lame));
                buf.push(vm);
                local.cells.push(e);
                local.von_mises.push(vm);
                lm.cells.push(cell.map(|l| pl.nodes[l]));
                lm.cell_body.push(pl.body);
                lm.cell_piece.push(pl.index);
            }
            buf.extend([ps.x.len() as f64, ps.k.nnz() as f64, ps.nnz_l as f64, residual]);
        }
        Ok((buf, local, lm))
    })?;
    let (mut sol, stats, jump) = t.phase(comm, "gather", || {
        let Some(all) = comm.gather_f64(0, &packed) else {
            return Ok((Solution::default(), vec![], 0.0));
        };
        let mut sol = Solution { displacement: vec![[0.0; 3]; size.nodes], von_mises: vec![0.0; size.elements], ..Default::default() };
        let mut copies: Vec<(usize, [f64; 3])> = Vec::new();
        let mut stats: Vec<Option<(PieceStats, usize)>> = vec![None; pieces];
        for (rank, data) in all.iter().enumerate() {
            let mut c = 0;
            while c < data.len() {
                let [index, nn, ne, interface, body] = std::array::from_fn(|i| data[c + i] as usize);
                c += HEAD_LEN;
                let (ids, u) = (&data[c..c + nn], &data[c + nn..c + 4 * nn]);
                for (&id, uv) in ids.iter().zip(u.chunks_exact(3)) {
                    let uv = [uv[0], uv[1], uv[2]];
                    if id >= 0.0 {
                        sol.displacement[id as usize] = uv;
                    } else {
                        copies.push(((-id - 1.0) as usize, uv));
                    }
                }
                c += 4 * nn;
                for (&e, &vm) in data[c..c + ne].iter().zip(&data[c + ne..c + 2 * ne]) {
                    sol.von_mises[e as usize] = vm;
                }
                c += 2 * ne;
                let s = &data[c..c + STATS_LEN];
                let piece = PieceStats { body, nodes: nn, elements: ne, dofs: s[0] as usize, nnz_k: s[1] as usize, nnz_l: s[2] as usize, residual: s[3], rank };
                stats[index] = Some((piece, interface));
                c += STATS_LEN;
            }
        }
        let stats = stats.into_iter().map(|s| s.expect("every piece lies on one rank")).collect();
        let umax = sol.displacement.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs())).max(f64::MIN_POSITIVE);
        let jump = copies.iter().map(|(v, uv)| (0..3).map(|c| (uv[c] - sol.displacement[*v][c]).abs()).fold(0.0, f64::max)).fold(0.0, f64::max);
        Ok((sol, stats, jump / umax))
    })?;
    sol.local = local;
    sol.local_mesh = local_mesh;
    Ok((sol, stats, jump))
}
