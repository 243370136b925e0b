//! The independent reference: the primal second-order cone program of the same discrete contact
//! problem, solved by the interior-point solver Clarabel,
//!
//! ```text
//! min ½uᵀKu − fᵀu + Σᵢ ‖Gᵢ(Tᵢu − cτ,ᵢ)‖   s.t.  Nu ≤ cν,
//! ```
//!
//! with u the free DOFs of all bodies (Dirichlet eliminated, as in the monolithic dual),
//! Gᵢ = diag(a, b) the semi-axes of pair i's friction ellipse (a = b = gᵢ for a disc: the support
//! function of the ellipse is ‖Gᵢw‖) and c = B K⁻¹f − b the dual problem's shift. The friction
//! term becomes tᵢ ≥ ‖Gᵢ(Tᵢu − cτ,ᵢ)‖ with tᵢ in the objective: one 3-dimensional second-order
//! cone per pair. The multipliers come back as λν = z_ν (the non-negative cone) and
//! λ̄τ,ᵢ = −Gᵢ z_{τ,ᵢ} (the cones). Variables and objective are scaled to O(1) (u = s·v with
//! s = max|f|/max Kⱼⱼ, objective divided by s·max|f|).

use std::time::Instant;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SecondOrderConeT, SolverStatus, SupportedConeT};

use crate::comm::Comm;
use crate::dual::monolithic::MonolithicDual;
use crate::error::{Error, Result};
use crate::qp::lambda::Lambda;
use crate::qp::sets::TangentSet;
use crate::qp::Layout;

/// The assembled SOCP (Clarabel's form: min ½xᵀPx + qᵀx, Ax + s = h, s ∈ cones).
pub struct PrimalSocp {
    p: CscMatrix<f64>,
    q: Vec<f64>,
    a: CscMatrix<f64>,
    h: Vec<f64>,
    cones: Vec<SupportedConeT<f64>>,
    layout: Layout,
    /// Offsets of the bodies' free DOFs in x, and their counts.
    offsets: Vec<usize>,
    sizes: Vec<usize>,
    /// Semi-axes (a, b) of each pair's tangential set.
    axes: Vec<[f64; 2]>,
    /// Rows of B over x (unscaled) and c = B K⁻¹ f − b, for the gradient r = c − Bu.
    brows: Vec<Vec<(usize, f64)>>,
    c: Vec<f64>,
    scale: f64,
    fmax: f64,
    /// Seconds spent building it (c needs one solve per body).
    pub build_s: f64,
}

/// Clarabel's answer mapped back to the dual problem's quantities.
pub struct SocpSolution {
    /// Free DOFs per body (as `DualProblem::recover` of the monolithic dual returns them).
    pub u: Vec<Vec<f64>>,
    /// The multipliers λ on the dual problem's layout.
    pub lambda: Vec<f64>,
    /// r = c − Bu (= −(Aλ − b) at the dual solution's sign convention: the dual gradient).
    pub gradient: Vec<f64>,
    /// Clarabel's iterations.
    pub iterations: u32,
    /// Clarabel's final status.
    pub status: String,
    /// Wall time of Clarabel's solve, in seconds.
    pub solve_s: f64,
}

impl PrimalSocp {
    /// The SOCP of the problem behind `dual` (all bodies on this rank) with right-hand side `b`.
    pub fn new<C: Comm>(dual: &MonolithicDual<C>, b: &[f64], set: &Lambda) -> Result<Self> {
        let t0 = Instant::now();
        let layout = dual.layout;
        if layout.free != 0 {
            return Err(Error::numerical("the primal SOCP", "is built from the monolithic dual only (this one has gluing or Dirichlet multipliers)"));
        }
        let (m, nd) = (layout.m, layout.dim());
        let sizes: Vec<usize> = dual.blocks.iter().map(|blk| blk.local.dofs.nfree).collect();
        let offsets: Vec<usize> = sizes
            .iter()
            .scan(0, |o, s| {
                let v = *o;
                *o += s;
                Some(v)
            })
            .collect();
        let nu: usize = sizes.iter().sum();
        let axes: Vec<[f64; 2]> = set
            .tangent
            .iter()
            .map(|t| match t {
                TangentSet::Disc(d) => [d.radius, d.radius],
                TangentSet::Ellipse(e) => [e.a, e.b],
            })
            .collect();
        let mut bkf = vec![0.0; nd];
        let (mut pi, mut pj, mut pv) = (vec![], vec![], vec![]);
        let mut q = vec![0.0; nu + if layout.friction { m } else { 0 }];
        let mut brows: Vec<Vec<(usize, f64)>> = vec![vec![]; nd];
        for (blk, &o) in dual.blocks.iter().zip(&offsets) {
            let k = &blk.local.sys.k;
            for j in 0..k.n {
                for p in k.col_ptr[j]..k.col_ptr[j + 1] {
                    pi.push(o + j);
                    pj.push(o + k.row_idx[p]);
                    pv.push(k.values[p]);
                }
            }
            for (j, f) in blk.local.sys.f.iter().enumerate() {
                q[o + j] = -f;
            }
            let mut kf = blk.local.sys.f.clone();
            blk.local.chol.solve_in_place(&mut kf);
            for &(row, j, coef) in &blk.b {
                bkf[row] += coef * kf[j];
                brows[row].push((o + j, coef));
            }
        }
        let c: Vec<f64> = bkf.iter().zip(b).map(|(x, y)| x - y).collect();
        let fmax = q.iter().fold(0.0f64, |a, v| a.max(v.abs())).max(f64::MIN_POSITIVE);
        let kmax = dual.blocks.iter().flat_map(|blk| blk.local.sys.k.values.iter()).fold(0.0f64, |a, v| a.max(v.abs()));
        let scale = fmax / kmax;
        pv.iter_mut().for_each(|v| *v /= kmax);
        q.iter_mut().for_each(|v| *v /= fmax);
        if layout.friction {
            // tᵢ = s·τᵢ like u: the weight 1 of tᵢ becomes 1/max|f|
            q[nu..].fill(1.0 / fmax);
        }
        let cs: Vec<f64> = c.iter().map(|v| v / scale).collect();
        // rows 0..m: s = cν − Nu ≥ 0; per pair (tᵢ, Gᵢ(Tᵢu − cτ,ᵢ)) ∈ SOC: A = −(e_t; GT), h = (0; −Gcτ)
        let rows = if layout.friction { 4 * m } else { m };
        let (mut ai, mut aj, mut av) = (vec![], vec![], vec![]);
        let mut h = vec![0.0; rows];
        for i in 0..m {
            for &(col, coef) in &brows[layout.normal(i)] {
                ai.push(i);
                aj.push(col);
                av.push(coef);
            }
            h[i] = cs[layout.normal(i)];
            if !layout.friction {
                continue;
            }
            let r0 = m + 3 * i;
            ai.push(r0);
            aj.push(nu + i);
            av.push(-1.0);
            for kk in 0..2 {
                let row = layout.tangent(i, kk);
                let g = axes[i][kk];
                for &(col, coef) in &brows[row] {
                    ai.push(r0 + 1 + kk);
                    aj.push(col);
                    av.push(-g * coef);
                }
                h[r0 + 1 + kk] = -g * cs[row];
            }
        }
        let nx = q.len();
        let p = CscMatrix::new_from_triplets(nx, nx, pi, pj, pv);
        let a = CscMatrix::new_from_triplets(rows, nx, ai, aj, av);
        let mut cones = vec![NonnegativeConeT(m)];
        if layout.friction {
            cones.extend((0..m).map(|_| SecondOrderConeT(3)));
        }
        Ok(PrimalSocp { p, q, a, h, cones, layout, offsets, sizes, axes, brows, c, scale, fmax, build_s: t0.elapsed().as_secs_f64() })
    }

    /// Solves with Clarabel's gap and feasibility tolerances at `tol` (its defaults: 1e-8), one
    /// thread, faer's sparse LDLᵀ for the KKT systems. Statuses other than solved / almost solved are errors.
    pub fn solve(&self, tol: f64) -> Result<SocpSolution> {
        let t0 = Instant::now();
        let settings = DefaultSettings {
            verbose: false,
            tol_gap_abs: tol,
            tol_gap_rel: tol,
            tol_feas: tol,
            tol_ktratio: tol.clamp(1e-10, 1e-6),
            max_iter: 200,
            max_threads: 1,
            // faer's supernodal LDLᵀ: 3D stiffness fill makes QDLDL (the default) 20× slower
            direct_solve_method: "faer".into(),
            ..DefaultSettings::default()
        };
        let mut solver =
            DefaultSolver::new(&self.p, &self.q, &self.a, &self.h, &self.cones, settings).map_err(|e| Error::numerical("Clarabel", format!("{e:?}")))?;
        solver.solve();
        let status = solver.solution.status;
        if !matches!(status, SolverStatus::Solved | SolverStatus::AlmostSolved) {
            return Err(Error::numerical("Clarabel on the primal SOCP", format!("stopped with status {status:?} after {} iterations", solver.info.iterations)));
        }
        let (layout, m) = (self.layout, self.layout.m);
        let x: Vec<f64> = solver.solution.x.iter().map(|v| v * self.scale).collect();
        let z: Vec<f64> = solver.solution.z.iter().map(|v| v * self.fmax).collect();
        let u = self.offsets.iter().zip(&self.sizes).map(|(&o, &s)| x[o..o + s].to_vec()).collect();
        let mut lambda = vec![0.0; layout.dim()];
        for i in 0..m {
            lambda[layout.normal(i)] = z[i];
            if layout.friction {
                for kk in 0..2 {
                    lambda[layout.tangent(i, kk)] = -self.axes[i][kk] * z[m + 3 * i + 1 + kk];
                }
            }
        }
        let gradient = self.brows.iter().zip(&self.c).map(|(row, c)| c - row.iter().map(|&(j, coef)| coef * x[j]).sum::<f64>()).collect();
        Ok(SocpSolution { u, lambda, gradient, iterations: solver.info.iterations, status: format!("{status:?}"), solve_s: t0.elapsed().as_secs_f64() })
    }
}
