//! Fill-reducing orderings: METIS nested dissection of a graph (`METIS_NodeND`, not wrapped by the
//! `metis` crate, hence `metis-sys`), and its expansion from mesh nodes to their DOFs.

use crate::error::{Error, Result};

/// Nested-dissection permutation of an undirected graph given in CSR form without self loops.
/// Returns `perm` with `perm[new] = old`.
pub fn nested_dissection(xadj: &[usize], adjncy: &[usize]) -> Result<Vec<usize>> {
    let n = xadj.len().saturating_sub(1);
    if n <= 1 || adjncy.is_empty() {
        return Ok((0..n).collect());
    }
    let to_idx = |v: usize| {
        i32::try_from(v).map_err(|_| Error::numerical("METIS ordering", "graph too large for 32-bit indices"))
    };
    let mut nv = to_idx(n)?;
    let mut xadj: Vec<i32> = xadj.iter().map(|&v| to_idx(v)).collect::<Result<_>>()?;
    let mut adj: Vec<i32> = adjncy.iter().map(|&v| to_idx(v)).collect::<Result<_>>()?;
    let mut options = [0i32; metis_sys::METIS_NOPTIONS as usize];
    let mut perm = vec![0i32; n];
    let mut iperm = vec![0i32; n];
    // SAFETY: METIS reads n+1 offsets and xadj[n] neighbours and writes n entries to perm/iperm;
    // all buffers have exactly those sizes and outlive the calls.
    let status = unsafe {
        metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
        metis_sys::METIS_NodeND(
            &mut nv,
            xadj.as_mut_ptr(),
            adj.as_mut_ptr(),
            std::ptr::null_mut(),
            options.as_mut_ptr(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    };
    if status != metis_sys::rstatus_et_METIS_OK as i32 {
        return Err(Error::numerical("METIS ordering", format!("METIS_NodeND failed with status {status}")));
    }
    Ok(perm.into_iter().map(|v| v as usize).collect())
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
                if i > 0 { adj.push(j * k + i - 1); }
                if i + 1 < k { adj.push(j * k + i + 1); }
                if j > 0 { adj.push((j - 1) * k + i); }
                if j + 1 < k { adj.push((j + 1) * k + i); }
                xadj.push(adj.len());
            }
        }
        let mut p = nested_dissection(&xadj, &adj).unwrap();
        p.sort_unstable();
        assert_eq!(p, (0..k * k).collect::<Vec<_>>());
    }
}
