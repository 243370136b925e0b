//! Fill-reducing orderings: METIS nested dissection of a graph (`METIS_NodeND`, not wrapped by the
//! `metis` crate, hence `metis-sys`), and its expansion from mesh nodes to their DOFs.

use crate::error::{Error, Result};

/// Runs a METIS call alone in the process: METIS seeds one process-wide random state at the
/// start of each call, so calls from several threads (the test harness runs tests in parallel)
/// that interleave give the same graph different parts. Every METIS call goes through here.
pub fn metis_exclusive<T>(f: impl FnOnce() -> T) -> T {
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    f()
}

/// What a [`Error::Memory`] of METIS names until the pipeline names the mesh
/// ([`crate::pipeline::memory::name_the_mesh`]).
pub const METIS_MEMORY: &str = "the METIS ordering";

/// Nested-dissection permutation of an undirected graph given in CSR form without self loops.
/// Returns `perm` with `perm[new] = old`.
pub fn nested_dissection(xadj: &[usize], adjncy: &[usize]) -> Result<Vec<usize>> {
    let n = xadj.len().saturating_sub(1);
    if n <= 1 || adjncy.is_empty() {
        return Ok((0..n).collect());
    }
    let to_idx = |v: usize| i32::try_from(v).map_err(|_| Error::numerical("METIS ordering", "graph too large for 32-bit indices"));
    let mut nv = to_idx(n)?;
    let mut xadj: Vec<i32> = xadj.iter().map(|&v| to_idx(v)).collect::<Result<_>>()?;
    let mut adj: Vec<i32> = adjncy.iter().map(|&v| to_idx(v)).collect::<Result<_>>()?;
    let mut options = [0i32; metis_sys::METIS_NOPTIONS as usize];
    let mut perm = vec![0i32; n];
    let mut iperm = vec![0i32; n];
    // SAFETY: METIS reads n+1 offsets and xadj[n] neighbours and writes n entries to perm/iperm;
    // all buffers have exactly those sizes and outlive the calls.
    let status = metis_exclusive(|| unsafe {
        metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
        metis_sys::METIS_NodeND(&mut nv, xadj.as_mut_ptr(), adj.as_mut_ptr(), std::ptr::null_mut(), options.as_mut_ptr(), perm.as_mut_ptr(), iperm.as_mut_ptr())
    });
    if status == metis_sys::rstatus_et_METIS_ERROR_MEMORY {
        return Err(Error::memory(METIS_MEMORY, format!("METIS ran out of memory ordering a graph of {n} nodes and {} edges", adjncy.len() / 2)));
    }
    if status != metis_sys::rstatus_et_METIS_OK {
        return Err(Error::numerical("METIS ordering", format!("METIS_NodeND failed with status {status}")));
    }
    Ok(perm.into_iter().map(|v| v as usize).collect())
}

/// Nested dissection of the nodes not marked `last`, followed by the `last` ones (ascending):
/// their block of the factor is then its trailing one ([`super::cholesky::Cholesky::trailing_block`]).
pub fn nested_dissection_last(xadj: &[usize], adjncy: &[usize], last: &[bool]) -> Result<Vec<usize>> {
    let n = xadj.len().saturating_sub(1);
    let mut sub = vec![usize::MAX; n];
    let kept: Vec<usize> = (0..n).filter(|&v| !last[v]).collect();
    for (i, &v) in kept.iter().enumerate() {
        sub[v] = i;
    }
    let (mut sx, mut sa) = (vec![0usize], vec![]);
    for &v in &kept {
        sa.extend(adjncy[xadj[v]..xadj[v + 1]].iter().filter_map(|&w| (sub[w] != usize::MAX).then_some(sub[w])));
        sx.push(sa.len());
    }
    let mut perm: Vec<usize> = nested_dissection(&sx, &sa)?.into_iter().map(|i| kept[i]).collect();
    perm.extend((0..n).filter(|&v| last[v]));
    Ok(perm)
}

/// A factor that orders the `last` nodes last may hold at most this multiple of the entries of
/// one ordered by nested dissection alone ([`order_last_if_cheap`]).
pub const LAST_GROWTH: f64 = 2.0;

/// A node order for a factor and the fill it gives ([`order_last_if_cheap`]).
#[derive(Clone, Debug)]
pub struct NodeOrder {
    /// `perm[new] = old`.
    pub perm: Vec<usize>,
    /// Whether the `last` nodes come last.
    pub last: bool,
    /// The fill of `perm`.
    pub fill: Fill,
}

/// The `last` nodes ordered last ([`nested_dissection_last`]) when that factor holds at most
/// [`LAST_GROWTH`] × the entries of plain nested dissection's (both counted, `free` DOFs per
/// node), else plain nested dissection.
pub fn order_last_if_cheap(xadj: &[usize], adjncy: &[usize], last: &[bool], free: &[u8]) -> Result<NodeOrder> {
    let plain = nested_dissection(xadj, adjncy)?;
    let plain_fill = fill(xadj, adjncy, &plain, free);
    if !last.iter().any(|&l| l) {
        return Ok(NodeOrder { perm: plain, last: false, fill: plain_fill });
    }
    let ordered = nested_dissection_last(xadj, adjncy, last)?;
    let ordered_fill = fill(xadj, adjncy, &ordered, free);
    if ordered_fill.nnz_l <= LAST_GROWTH * plain_fill.nnz_l {
        Ok(NodeOrder { perm: ordered, last: true, fill: ordered_fill })
    } else {
        Ok(NodeOrder { perm: plain, last: false, fill: plain_fill })
    }
}

/// Expands a node permutation to DOFs: the DOFs of node `perm[0]` first, then `perm[1]`, …
/// `dof_of(node)` lists the DOF indices of a node (constrained DOFs omitted).
pub fn expand_to_dofs(node_perm: &[usize], ndof: usize, dof_of: impl Fn(usize) -> [Option<usize>; 3]) -> Vec<usize> {
    let mut out = Vec::with_capacity(ndof);
    for &v in node_perm {
        out.extend(dof_of(v).into_iter().flatten());
    }
    out
}

/// The fill of a Cholesky factor, counted without factorizing.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Fill {
    /// nnz(L) by unknowns, diagonal included.
    pub nnz_l: f64,
    /// Σ over the columns of L of (entries in the column)²: the factorization's work.
    pub flops: f64,
}

/// The fill of the factor of a matrix with the node-block pattern of the graph `(xadj, adj)`
/// (CSR without self loops, `dofs[v]` unknowns at node v, all coupled) eliminated in the node
/// order `perm` (`perm[new] = old`): the elimination tree (Liu's algorithm with path
/// compression), then every row's subtree walked once — O(nnz(L)) at node level, no numeric
/// work. Supernodal storage may keep a little more than this count.
pub fn fill(xadj: &[usize], adj: &[usize], perm: &[usize], dofs: &[u8]) -> Fill {
    const NONE: usize = usize::MAX;
    let n = perm.len();
    let mut inv = vec![0; n];
    for (new, &old) in perm.iter().enumerate() {
        inv[old] = new;
    }
    let (mut parent, mut ancestor) = (vec![NONE; n], vec![NONE; n]);
    for (i, &v) in perm.iter().enumerate() {
        for &w in &adj[xadj[v]..xadj[v + 1]] {
            let mut r = inv[w];
            if r >= i {
                continue;
            }
            while ancestor[r] != NONE && ancestor[r] != i {
                let next = ancestor[r];
                ancestor[r] = i;
                r = next;
            }
            if ancestor[r] == NONE {
                ancestor[r] = i;
                parent[r] = i;
            }
        }
    }
    // colw[j]: unknowns in the rows below the diagonal block of node column j
    let (mut colw, mut mark) = (vec![0usize; n], vec![NONE; n]);
    for (i, &v) in perm.iter().enumerate() {
        mark[i] = i;
        let d = dofs[v] as usize;
        for &w in &adj[xadj[v]..xadj[v + 1]] {
            let mut j = inv[w];
            if j >= i {
                continue;
            }
            while mark[j] != i {
                colw[j] += d;
                mark[j] = i;
                j = parent[j];
            }
        }
    }
    let mut f = Fill::default();
    for (j, &v) in perm.iter().enumerate() {
        let d = dofs[v] as usize;
        for c in 0..d {
            let count = (d - c + colw[j]) as f64;
            f.nnz_l += count;
            f.flops += count * count;
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nd_of_a_grid_is_a_permutation() {
        // 5×5 grid graph
        let k = 5;
        let mut xadj = vec![0];
        let mut adj = vec![];
        for j in 0..k {
            for i in 0..k {
                if i > 0 {
                    adj.push(j * k + i - 1);
                }
                if i + 1 < k {
                    adj.push(j * k + i + 1);
                }
                if j > 0 {
                    adj.push((j - 1) * k + i);
                }
                if j + 1 < k {
                    adj.push((j + 1) * k + i);
                }
                xadj.push(adj.len());
            }
        }
        let mut p = nested_dissection(&xadj, &adj).unwrap();
        p.sort_unstable();
        assert_eq!(p, (0..k * k).collect::<Vec<_>>());
    }

    #[test]
    fn fill_matches_dense_elimination() {
        // 6×6 grid with diagonals
        let k = 6;
        let mut xadj = vec![0];
        let mut adj = vec![];
        for j in 0..k {
            for i in 0..k {
                for (di, dj) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1), (1, 1), (-1, -1)] {
                    let (a, b) = (i as i64 + di, j as i64 + dj);
                    if a >= 0 && b >= 0 && a < k as i64 && b < k as i64 {
                        adj.push(b as usize * k + a as usize);
                    }
                }
                xadj.push(adj.len());
            }
        }
        let perm = nested_dissection(&xadj, &adj).unwrap();
        // 2 unknowns at even nodes, 3 at odd ones
        let dofs: Vec<u8> = (0..k * k).map(|v| 2 + (v % 2) as u8).collect();
        let f = fill(&xadj, &adj, &perm, &dofs);
        // independent count: dense boolean elimination of the unknowns in the same order
        let mut first = vec![0; k * k + 1];
        for v in 0..k * k {
            first[v + 1] = first[v] + dofs[v] as usize;
        }
        let n = first[k * k];
        let mut pos = vec![0; n];
        let mut next = 0;
        for &v in &perm {
            for c in 0..dofs[v] as usize {
                pos[first[v] + c] = next;
                next += 1;
            }
        }
        let mut p = vec![vec![false; n]; n];
        for v in 0..k * k {
            let nb: Vec<usize> = adj[xadj[v]..xadj[v + 1]].iter().copied().chain([v]).collect();
            for &w in &nb {
                for a in first[v]..first[v + 1] {
                    for b in first[w]..first[w + 1] {
                        p[pos[a]][pos[b]] = true;
                    }
                }
            }
        }
        let (mut nnz, mut flops) = (0.0, 0.0);
        for j in 0..n {
            let rows: Vec<usize> = (j + 1..n).filter(|&i| p[i][j]).collect();
            for &a in &rows {
                for &b in &rows {
                    p[a][b] = true;
                }
            }
            let count = (rows.len() + 1) as f64;
            nnz += count;
            flops += count * count;
        }
        assert_eq!((f.nnz_l, f.flops), (nnz, flops));
    }
}
