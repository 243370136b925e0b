//! The dual problem as a transform of the primal one (docs/method.md, "Code layout"): the multipliers λ of the
//! constraint rows B, the operator A = B K⁻¹ Bᵀ applied matrix-free (a [`crate::qp::Operator`]),
//! the right-hand side b, and the map back to the primal solution u = K⁻¹(f − Bᵀλ)
//! ([`DualProblem::recover`], PERMON's post-solve). [`monolithic`] is the paper's setting (one
//! piece per body, Dirichlet eliminated, dual vectors replicated); the TFETI dual
//! (`feti::dual`) implements the same traits on distributed dual vectors. Also the B-row
//! helpers both use.

pub(crate) mod fclib;
pub mod monolithic;

use crate::qp::{Layout, Operator};

/// A dual problem whose solution maps back to the primal one on this rank's pieces (bodies or
/// subdomains).
pub trait DualProblem: Operator {
    /// The primal solution from the solvers' y.
    fn recover(&self, y: &[f64]) -> Recovered;
}

/// The primal side of a dual solution, on this rank's pieces.
#[derive(Clone, Debug, Default)]
pub struct Recovered {
    /// u of each local piece, on the DOFs its K acts on (free DOFs of a body, all DOFs of a
    /// subdomain).
    pub u: Vec<Vec<f64>>,
    /// f − Bᵀλ of each local piece (K u must equal it).
    pub rhs: Vec<Vec<f64>>,
    /// The multipliers λ this rank owns.
    pub lambda: Vec<f64>,
    /// c − Bu on the rows this rank owns: the contact rows' current gap (the contact part of the
    /// gradient); what the other rows leave unsatisfied.
    pub gap: Vec<f64>,
    /// TFETI: α, six per subdomain (all subdomains); empty otherwise.
    pub alpha: Vec<f64>,
    /// TFETI: ‖Gλ − e‖/‖e‖; 0 otherwise.
    pub feasibility: f64,
}

/// The entries (row of B, local DOF, coefficient) of B acting on one piece (a body or a
/// subdomain): z = B_pᵀx on the piece's `ndof` DOFs.
pub fn scatter_rows(rows: &[(usize, usize, f64)], x: &[f64], ndof: usize) -> Vec<f64> {
    let mut z = vec![0.0; ndof];
    for &(r, j, c) in rows {
        z[j] += c * x[r];
    }
    z
}

/// y = Σ_p B_p z_p over the pieces of this rank, then summed over the ranks.
pub fn gather_rows<'a, C: crate::comm::Comm>(comm: &C, pieces: impl Iterator<Item = (&'a [(usize, usize, f64)], &'a [f64])>, y: &mut [f64]) {
    y.fill(0.0);
    for (rows, z) in pieces {
        for &(r, j, c) in rows {
            y[r] += c * z[j];
        }
    }
    comm.sum_f64(y);
}

/// B u = c − gap − c0 on the tangential rows of `layout` (the prescribed part of B u is
/// −c0), 0 elsewhere.
pub fn tangential_jump(layout: Layout, c: &[f64], c0: &[f64], gap: &[f64]) -> Vec<f64> {
    let mut j = vec![0.0; c.len()];
    if layout.friction {
        for i in 0..layout.m {
            for k in 0..2 {
                let r = layout.tangent(i, k);
                j[r] = c[r] - gap[r] - c0[r];
            }
        }
    }
    j
}

/// c += `jump` on the tangential rows of `layout`.
pub fn add_tangential(layout: Layout, jump: &[f64], c: &mut [f64]) {
    if layout.friction {
        for i in 0..layout.m {
            for k in 0..2 {
                let r = layout.tangent(i, k);
                c[r] += jump[r];
            }
        }
    }
}
