//! The nodal contact pressure on quadratic slave faces (tri6, quad8, quad9): the L2 projection
//! of the multiplier field onto the face's standard (primal) basis.
//!
//! With the dual basis, the multiplier field is p_h = Σᵢ zᵢ ψᵢ, and ∫ p_h φ_j dA is the normal
//! force f_j the rows put on slave node j: f_j = Σᵢ c_ij λᵢ, the slave coefficients of the rows
//! (biorthogonality; on tri6 and quad8 through T⁻¹). The projection p = Σ_j p_j φ_j solves
//! M p = f with the face's consistent mass matrix M_jk = ∫ φ_j φ_k dA. A uniform pressure is
//! reproduced at every node, corners and edges alike, where λᵢ/D_ii alternates between corner
//! and edge nodes under a varying load (the modified basis weights them differently) and the
//! lumped f_j/∫ φ_j is undefined (∫ φ_j = 0 at a tri6 corner).

use std::collections::HashMap;
use std::ops::Range;

use crate::fem::facet::{facet_area_vector, facet_shape, fine_rule};
use crate::mesh::{Face, FacetKind, Mesh};

/// Relative residual at which the conjugate gradients on M stop.
const TOLERANCE: f64 = 1e-14;

/// One contact entry's slave face, for recovering its nodal pressures.
#[derive(Clone, Debug, Default)]
pub struct Recovery {
    /// The entry's contact rows.
    pub rows: Range<usize>,
    /// The local index of each face node.
    index: HashMap<usize, usize>,
    /// M_jk = ∫ φ_j φ_k dA by local row j: (k, M_jk).
    mass: Vec<Vec<(usize, f64)>>,
}

/// Whether a face has quadratic facets, whose nodal pressures are recovered by [`Recovery`].
pub fn is_quadratic(face: &Face) -> bool {
    face.facets.iter().any(|q| matches!(q.kind, FacetKind::Tri6 | FacetKind::Quad8 | FacetKind::Quad9))
}

impl Recovery {
    /// The mass matrix of slave face `face` (the rows `rows` are the entry's).
    pub fn new(mesh: &Mesh, face: &Face, rows: Range<usize>) -> Recovery {
        let nodes = face.nodes();
        let index: HashMap<usize, usize> = nodes.iter().enumerate().map(|(j, &v)| (v, j)).collect();
        let mut mass: Vec<HashMap<usize, f64>> = vec![HashMap::new(); nodes.len()];
        for q in &face.facets {
            let x: Vec<[f64; 3]> = q.nodes().iter().map(|&v| mesh.nodes[v]).collect();
            let local: Vec<usize> = q.nodes().iter().map(|v| index[v]).collect();
            for (xi, w) in fine_rule(q.kind) {
                let (phi, dphi) = facet_shape(q.kind, xi);
                let a = facet_area_vector(&x, &dphi);
                let wj = w * (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
                for (a, &j) in local.iter().enumerate() {
                    for (b, &k) in local.iter().enumerate() {
                        *mass[j].entry(k).or_default() += wj * phi[a] * phi[b];
                    }
                }
            }
        }
        let mass = mass.into_iter().map(|m| m.into_iter().collect()).collect();
        Recovery { rows, index, mass }
    }

    /// The nodal pressure at the slave node of each of the entry's rows, from the rows'
    /// couplings and normal multipliers `force` (indexed by contact row).
    pub fn pressures(&self, coupling: &[Vec<(usize, f64)>], slave: &[usize], force: &[f64]) -> Vec<f64> {
        let mut f = vec![0.0; self.mass.len()];
        for i in self.rows.clone() {
            for &(k, c) in &coupling[i] {
                if let Some(&j) = self.index.get(&k) {
                    f[j] += c * force[i];
                }
            }
        }
        let p = self.solve(&f);
        self.rows.clone().map(|i| p[self.index[&slave[i]]]).collect()
    }

    /// M x = b by conjugate gradients preconditioned with M's diagonal.
    fn solve(&self, b: &[f64]) -> Vec<f64> {
        let n = b.len();
        let apply = |x: &[f64]| -> Vec<f64> { self.mass.iter().map(|row| row.iter().map(|&(k, m)| m * x[k]).sum()).collect() };
        let diag: Vec<f64> = self.mass.iter().enumerate().map(|(j, row)| row.iter().find(|e| e.0 == j).map_or(1.0, |e| e.1)).collect();
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let mut x = vec![0.0; n];
        let mut r = b.to_vec();
        let stop = TOLERANCE * dot(b, b).sqrt();
        let mut z: Vec<f64> = r.iter().zip(&diag).map(|(r, d)| r / d).collect();
        let mut d = z.clone();
        let mut rz = dot(&r, &z);
        for _ in 0..10 * n + 10 {
            if dot(&r, &r).sqrt() <= stop {
                break;
            }
            let q = apply(&d);
            let alpha = rz / dot(&d, &q);
            for k in 0..n {
                x[k] += alpha * d[k];
                r[k] -= alpha * q[k];
            }
            z = r.iter().zip(&diag).map(|(r, d)| r / d).collect();
            let next = dot(&r, &z);
            for k in 0..n {
                d[k] = z[k] + next / rz * d[k];
            }
            rz = next;
        }
        x
    }
}
