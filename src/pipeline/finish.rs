//! The one post-solve path of both duals: each rank checks K u = f − Bᵀλ on its pieces (bodies
//! or TFETI subdomains), computes their element stresses (phase `stress`), and rank 0 gathers u,
//! the stresses and each piece's figures (phase `gather`); a node shared by several pieces is
//! written by the first of them and the others' copies give the gluing jump.

use serde::{Deserialize, Serialize};

use super::{LocalFields, Solution, Timings};
use crate::comm::Comm;
use crate::error::{Error, Result};
use crate::fem::element::hex8_center_stress;
use crate::fem::material::von_mises;
use crate::linalg::sparse::SymCsc;
use crate::model::Model;

/// Where a piece lives; the same list on every rank, in the order rank 0 unpacks.
#[derive(Clone, Debug)]
pub struct PieceLayout {
    pub rank: usize,
    pub body: usize,
    /// Global node ids, ascending: the piece-local index of a node is its position here.
    pub nodes: Vec<usize>,
    /// Global element indices.
    pub elems: Vec<usize>,
    /// The piece in messages ("body \"upper\"", "subdomain 3 (body \"upper\")").
    pub name: String,
}

/// A piece on this rank with its solution: K x = rhs on the DOFs K acts on, and u at every node
/// of the piece.
pub struct PieceSolution<'a> {
    /// Index into the layout.
    pub piece: usize,
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

const STATS_LEN: usize = 4;

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Checks, stresses and gathers the pieces (phases `stress` and `gather`). `hint` ends the
/// message of a piece whose K u = rhs does not hold. Returns the solution (fields on rank 0,
/// this rank's rows everywhere), the figures of every piece and the relative gluing jump (both
/// on rank 0).
pub fn finish<C: Comm>(comm: &C, model: &Model, layout: &[PieceLayout], mine: &[PieceSolution<'_>], hint: &str, t: &mut Timings) -> Result<(Solution, Vec<PieceStats>, f64)> {
    let mesh = &model.mesh;
    // the piece that writes each node: the first that has it
    let mut writer = vec![usize::MAX; mesh.nodes.len()];
    for (p, pl) in layout.iter().enumerate().rev() {
        for &v in &pl.nodes {
            writer[v] = p;
        }
    }
    let (packed, local) = t.phase(comm, "stress", || {
        let mut buf = Vec::new();
        let mut local = LocalFields::default();
        for ps in mine {
            let pl = &layout[ps.piece];
            let mut kx = ps.k.mul(ps.x);
            ps.held.iter().for_each(|&d| kx[d] = ps.rhs[d]);
            let rn = norm(&kx.iter().zip(ps.rhs).map(|(a, b)| a - b).collect::<Vec<_>>());
            let fnorm = norm(ps.rhs);
            let residual = if fnorm > 0.0 { rn / fnorm } else { rn };
            if !residual.is_finite() || residual > 1e-6 {
                return Err(Error::numerical(pl.name.clone(), format!("K u = f − Bᵀλ does not hold (relative residual {residual:.1e}): {hint}")));
            }
            buf.extend(ps.nodal.iter().flatten());
            for (l, &v) in pl.nodes.iter().enumerate().filter(|(_, &v)| writer[v] == ps.piece) {
                local.nodes.push(v);
                local.displacement.push(ps.nodal[l]);
            }
            let lame = model.lame[pl.body];
            for &e in &pl.elems {
                let ue = mesh.hexes[e].map(|v| ps.nodal[pl.nodes.binary_search(&v).expect("element node in its piece")]);
                let vm = von_mises(&hex8_center_stress(&mesh.hex_coords(e), &ue, lame));
                buf.push(vm);
                local.cells.push(e);
                local.von_mises.push(vm);
            }
            buf.extend([ps.x.len() as f64, ps.k.nnz() as f64, ps.nnz_l as f64, residual]);
        }
        Ok((buf, local))
    })?;
    let (mut sol, stats, jump) = t.phase(comm, "gather", || {
        let Some(all) = comm.gather_f64(0, &packed) else {
            return Ok((Solution::default(), vec![], 0.0));
        };
        let mut sol = Solution { displacement: vec![[0.0; 3]; mesh.nodes.len()], von_mises: vec![0.0; mesh.hexes.len()], ..Default::default() };
        let mut copies: Vec<(usize, [f64; 3])> = Vec::new();
        let mut stats = Vec::with_capacity(layout.len());
        let mut cursor = vec![0usize; comm.size()];
        // pieces in the order each rank packed them (layout order per rank)
        for (p, pl) in layout.iter().enumerate() {
            let data = &all[pl.rank];
            let mut c = cursor[pl.rank];
            for &v in &pl.nodes {
                let uv = [data[c], data[c + 1], data[c + 2]];
                if writer[v] == p {
                    sol.displacement[v] = uv;
                } else {
                    copies.push((v, uv));
                }
                c += 3;
            }
            for &e in &pl.elems {
                sol.von_mises[e] = data[c];
                c += 1;
            }
            let s = &data[c..c + STATS_LEN];
            stats.push(PieceStats {
                body: pl.body,
                nodes: pl.nodes.len(),
                elements: pl.elems.len(),
                dofs: s[0] as usize,
                nnz_k: s[1] as usize,
                nnz_l: s[2] as usize,
                residual: s[3],
                rank: pl.rank,
            });
            cursor[pl.rank] = c + STATS_LEN;
        }
        let umax = sol.displacement.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs())).max(f64::MIN_POSITIVE);
        let jump = copies.iter().map(|(v, uv)| (0..3).map(|c| (uv[c] - sol.displacement[*v][c]).abs()).fold(0.0, f64::max)).fold(0.0, f64::max);
        Ok((sol, stats, jump / umax))
    })?;
    sol.local = local;
    let mut element_rank = vec![0; mesh.hexes.len()];
    for pl in layout {
        for &e in &pl.elems {
            element_rank[e] = pl.rank;
        }
    }
    sol.element_rank = element_rank;
    Ok((sol, stats, jump))
}
