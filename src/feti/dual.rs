//! The TFETI dual operator (a [`crate::qp::Operator`] and [`DualProblem`]): A = P̃FP̃ᵀ with F = B K⁺ Bᵀ applied
//! matrix-free (one K_s⁺ solve per subdomain of this rank, the neighbour exchanges of
//! [`Distribution`]) on distributed dual vectors, and the
//! right-hand side b̃ = P̃(d̃ − Fλ̂), d̃ = B K⁺ f − c (DESIGN §2). The solvers minimize
//! ½yᵀAy − yᵀb̃ over Y = R^{n_E} × Λ; [`DualProblem::recover`] maps y back to λ = λ̂ + P̃ᵀy, the
//! rigid-body amplitudes α = C⁻¹G_E(c_E − B_E ũ) and u_s = ũ_s + R_sα_s, ũ = K⁺(f − Bᵀλ).
//! The gradient the solvers see is P̃(Fλ − d̃); its contact part is −(Bu − c)_I, as in the
//! monolithic dual, so the contact status and KKT residuals read the same. The FETI
//! preconditioner of the gluing and Dirichlet block ([`FetiPreconditioner`]) is built here too.

use super::coarse::Coarse;
use super::constraints::Constraints;
use super::distribution::{Clock, Distribution};
use super::subdomain::{SubdomainSystem, NR};
use crate::comm::Comm;
use crate::dual::{row_stiffness, scaled_entries, DualProblem, Recovered};
use crate::error::{Error, Result};
use crate::linalg::schur::Schur;
use crate::qp::{Layout, Operator, Preconditioner, ProductCounter};
use crate::scene::Preconditioner as PreconditionerKind;

/// A subdomain of this rank with its B entries (position in its sorted rows, local DOF,
/// coefficient).
pub struct LocalSubdomain {
    pub sys: SubdomainSystem,
    pub entries: Vec<(usize, usize, f64)>,
    /// Number of its rows.
    pub nrows: usize,
}

/// A = P̃ F P̃ᵀ over the subdomains of all ranks, on distributed dual vectors.
pub struct TfetiDual<'c, C: Comm> {
    pub dist: Distribution<'c, C>,
    /// The layout of this rank's components.
    pub layout: Layout,
    pub subs: Vec<LocalSubdomain>,
    pub coarse: Coarse,
    /// c on the owned rows.
    c: Vec<f64>,
    /// λ̂ = (G_Eᵀ C⁻¹ e, 0) on the local rows: Gλ̂ = e, λ̂_I = 0.
    pub lambda_hat: Vec<f64>,
    /// d̃ − Fλ̂ (before projection, owned): the right-hand side once λ = λ̂ + λ̃.
    pub d_hat: Vec<f64>,
    counter: ProductCounter,
    /// First E (gluing, Dirichlet) row of the global numbering.
    e_start: usize,
    /// The preconditioner's pieces (one per local subdomain), once built.
    precond: Option<Vec<PrecondPiece>>,
}

/// One subdomain's part of M_E: S_s (or K_s's block) and its scaled E entries D_s B_E,s
/// (position in its sorted rows, local DOF, coefficient).
struct PrecondPiece {
    schur: Schur,
    entries: Vec<(usize, usize, f64)>,
}

impl<'c, C: Comm> TfetiDual<'c, C> {
    /// The operator over this rank's factorized subdomains `subs` (ascending global index
    /// `sys.index`, as in `dist`), and b̃ on the owned rows.
    pub fn new(dist: Distribution<'c, C>, cons: &Constraints, subs: Vec<SubdomainSystem>, coarse: Coarse) -> (Self, Vec<f64>) {
        let subs: Vec<LocalSubdomain> = subs
            .into_iter()
            .zip(&dist.subs)
            .map(|(sys, sr)| {
                assert_eq!(sys.index, sr.index, "subdomains in the distribution's order");
                let rows = cons.sorted_rows(sys.index);
                let entries = cons.rows[sys.index].iter().map(|&(r, j, c)| (rows.binary_search(&r).expect("row"), j, c)).collect();
                LocalSubdomain { sys, entries, nrows: rows.len() }
            })
            .collect();
        let c = dist.restrict(&cons.c);
        let lambda_hat = coarse.lambda_hat_local(&dist);
        let layout = dist.layout;
        let e_start = cons.layout.contact_dim();
        let mut dual = TfetiDual { dist, layout, subs, coarse, c, lambda_hat, d_hat: vec![], counter: ProductCounter::default(), e_start, precond: None };
        // d̃ − Fλ̂ = B K⁺ (f − Bᵀλ̂) − c
        let mut b = vec![0.0; layout.dim()];
        let z = dual.pinv_of_rhs(&dual.lambda_hat);
        dual.gather(&z, &mut b);
        b.iter_mut().zip(&dual.c).for_each(|(bi, ci)| *bi -= ci);
        dual.d_hat = b.clone();
        dual.coarse.project(&dual.dist, &mut b);
        (dual, b)
    }

    /// Builds the FETI preconditioner M_E of [`FetiPreconditioner`] on the E rows (`None`:
    /// drops it). Dirichlet factorizes each subdomain's K_ii (the DOFs its E rows do not touch).
    pub fn set_preconditioner(&mut self, kind: PreconditionerKind) -> Result<()> {
        if kind == PreconditionerKind::None {
            self.precond = None;
            return Ok(());
        }
        let e_start = self.e_start;
        let dist = &self.dist;
        let e_entries: Vec<Vec<(usize, usize, f64)>> = self
            .subs
            .iter()
            .zip(&dist.subs)
            .map(|(s, sr)| s.entries.iter().copied().filter(|&(p, _, _)| dist.local_rows[sr.rows[p]] >= e_start).collect())
            .collect();
        let stiff: Vec<(Vec<f64>, Vec<f64>)> = self.subs.iter().zip(&e_entries).map(|(s, e)| row_stiffness(e, &s.sys.k, s.nrows)).collect();
        // totals over all subdomains touching each row, back on every subdomain's rows
        let per_row = |pick: fn(&(Vec<f64>, Vec<f64>)) -> &Vec<f64>| -> Vec<Vec<f64>> {
            let v: Vec<Vec<f64>> = stiff.iter().map(|x| pick(x).clone()).collect();
            let mut owned = vec![0.0; self.layout.dim()];
            dist.assemble(&v, &mut owned);
            let local = dist.ghosted(&owned);
            dist.subs.iter().map(|sr| sr.rows.iter().map(|&l| local[l]).collect()).collect()
        };
        let (total, count) = (per_row(|x| &x.0), per_row(|x| &x.1));
        let mut pieces = Vec::with_capacity(self.subs.len());
        for (i, (s, e)) in self.subs.iter().zip(&e_entries).enumerate() {
            let touched: Vec<usize> = e.iter().map(|x| x.1).collect();
            let schur = Schur::new(&s.sys.k, &touched, kind == PreconditionerKind::Dirichlet)
                .map_err(|err| Error::numerical(format!("the Dirichlet preconditioner of subdomain {}", s.sys.index), format!("{err}; try solver.preconditioner = \"lumped\"")))?;
            pieces.push(PrecondPiece { schur, entries: scaled_entries(e, &stiff[i].0, &total[i], &count[i]) });
        }
        self.precond = Some(pieces);
        Ok(())
    }

    /// Bᵀ_s x for each local subdomain, x on the local rows.
    fn scatter(&self, xl: &[f64]) -> Vec<Vec<f64>> {
        self.subs
            .iter()
            .zip(&self.dist.subs)
            .map(|(s, sr)| {
                let mut z = vec![0.0; s.sys.ndof()];
                for &(p, j, c) in &s.entries {
                    z[j] += c * xl[sr.rows[p]];
                }
                z
            })
            .collect()
    }

    /// y = Σ over subdomains and ranks of B_s z_s, on the owned rows.
    fn gather(&self, z: &[Vec<f64>], y: &mut [f64]) {
        let v: Vec<Vec<f64>> = self
            .subs
            .iter()
            .zip(z)
            .map(|(s, zs)| {
                let mut v = vec![0.0; s.nrows];
                for &(p, j, c) in &s.entries {
                    v[p] += c * zs[j];
                }
                v
            })
            .collect();
        self.dist.assemble(&v, y);
    }

    /// z_s ← K_s⁺ z_s for each local subdomain.
    fn pinv_all(&self, z: &mut [Vec<f64>]) {
        Clock::time(&self.dist.clock.pinv, || {
            for (s, zs) in self.subs.iter().zip(z) {
                s.sys.pinv_in_place(zs);
            }
        });
    }

    /// K_s⁺(f_s − B_sᵀλ) for each local subdomain (λ on the local rows).
    fn pinv_of_rhs(&self, lambda_local: &[f64]) -> Vec<Vec<f64>> {
        let mut z = self.rhs_of(lambda_local);
        self.pinv_all(&mut z);
        z
    }

    /// f_s − B_sᵀλ for each local subdomain (λ on the local rows).
    fn rhs_of(&self, lambda_local: &[f64]) -> Vec<Vec<f64>> {
        let mut z = self.scatter(lambda_local);
        for (s, zs) in self.subs.iter().zip(&mut z) {
            zs.iter_mut().zip(&s.sys.f).for_each(|(v, f)| *v = f - *v);
        }
        z
    }

    /// y = F w (owned) from w on the local rows (not counted).
    fn apply_f_local(&self, wl: &[f64], y: &mut [f64]) {
        let mut z = self.scatter(wl);
        self.pinv_all(&mut z);
        self.gather(&z, y);
    }

    /// y = F x on owned vectors (not counted).
    pub(crate) fn apply_f(&self, x: &[f64], y: &mut [f64]) {
        self.apply_f_local(&self.dist.ghosted(x), y);
    }

    /// The preconditioner, when one was built.
    pub fn preconditioner(&self) -> Option<FetiPreconditioner<'_, 'c, C>> {
        self.precond.as_ref().map(|pieces| FetiPreconditioner { dual: self, pieces })
    }
}

impl<C: Comm> DualProblem for TfetiDual<'_, C> {
    /// λ, α and u from the solvers' y: λ = λ̂ + P̃ᵀy, u = K⁺(f − Bᵀλ) + Rα.
    fn recover(&self, y: &[f64]) -> Recovered {
        let mut lambda = self.dist.ghosted(y);
        self.coarse.project_t_local(&self.dist, &mut lambda);
        lambda.iter_mut().zip(&self.lambda_hat).for_each(|(a, b)| *a += b);
        let feasibility = self.coarse.feasibility(&self.dist, &lambda);
        let rhs = self.rhs_of(&lambda);
        let mut u: Vec<Vec<f64>> = rhs.clone();
        self.pinv_all(&mut u);
        // w = c − B ũ; only its E part enters α
        let mut w = vec![0.0; self.layout.dim()];
        self.gather(&u, &mut w);
        w.iter_mut().zip(&self.c).for_each(|(a, c)| *a = c - *a);
        let alpha = self.coarse.alpha(&self.dist, &w);
        for (s, us) in self.subs.iter().zip(&mut u) {
            let i = s.sys.index;
            s.sys.add_r_mul(&alpha[NR * i..NR * (i + 1)], us);
        }
        let mut gap = vec![0.0; self.layout.dim()];
        self.gather(&u, &mut gap);
        gap.iter_mut().zip(&self.c).for_each(|(a, c)| *a = c - *a);
        Recovered { lambda: self.dist.owned_part(&lambda), alpha, u, rhs, gap, feasibility }
    }
}

impl<'c, C: Comm> Operator for TfetiDual<'c, C> {
    type Space = Distribution<'c, C>;
    fn space(&self) -> &Distribution<'c, C> {
        &self.dist
    }

    fn dim(&self) -> usize {
        self.layout.dim()
    }

    fn apply(&self, x: &[f64], y: &mut [f64]) {
        self.counter.tick();
        Clock::time(&self.dist.clock.apply, || {
            let mut wl = self.dist.ghosted(x);
            self.coarse.project_t_local(&self.dist, &mut wl);
            self.apply_f_local(&wl, y);
            self.coarse.project(&self.dist, y);
        });
    }

    fn products(&self) -> usize {
        self.counter.get()
    }
}

/// The FETI preconditioner of the symmetric inner solves (TSSN's CG) on the TFETI gluing and
/// Dirichlet block: `M_E = Σ_s B_E,s D_s S_s D_s B_E,sᵀ` over the subdomains s, S_s the Schur
/// complement of K_s onto the DOFs its E rows touch (Dirichlet) or just K_s's block there
/// (lumped), D_s the stiffness scaling of the rows (a row shared by subdomains s and o gets
/// k_o/(k_s + k_o), k the diagonal stiffness B sees; a row of one subdomain 1); applied as
/// `P_E M_E P_E` on the E rows, P_E the orthogonal projector onto Ker G_E. The E components
/// are free in every inner solve, so M_E acts on them unrestricted; the contact block is left to
/// the solver.
pub struct FetiPreconditioner<'a, 'c, C: Comm> {
    dual: &'a TfetiDual<'c, C>,
    pieces: &'a [PrecondPiece],
}

impl<C: Comm> Preconditioner for FetiPreconditioner<'_, '_, C> {
    fn block(&self) -> std::ops::Range<usize> {
        self.dual.layout.contact_dim()..self.dual.layout.dim()
    }

    fn apply(&self, x: &[f64], y: &mut [f64]) {
        let d = self.dual;
        let mut wl = d.dist.ghosted(x);
        d.coarse.project_e_local(&d.dist, &mut wl);
        let v: Vec<Vec<f64>> = self
            .pieces
            .iter()
            .zip(&d.subs)
            .zip(&d.dist.subs)
            .map(|((pc, s), sr)| {
                let mut z = vec![0.0; s.sys.ndof()];
                for &(p, j, c) in &pc.entries {
                    z[j] += c * wl[sr.rows[p]];
                }
                pc.schur.apply_in_place(&mut z);
                let mut vs = vec![0.0; s.nrows];
                for &(p, j, c) in &pc.entries {
                    vs[p] += c * z[j];
                }
                vs
            })
            .collect();
        d.dist.assemble(&v, y);
        // P_E reads and writes the E rows only
        d.coarse.project_e(&d.dist, y);
    }
}
