//! The TFETI dual operator (a [`crate::qp::Operator`]): A = P̃FP̃ᵀ with F = B K⁺ Bᵀ applied
//! matrix-free (one K_s⁺ solve per subdomain of this rank, the neighbour exchanges of
//! [`Distribution`]) on distributed dual vectors, and the
//! right-hand side b̃ = P̃(d̃ − Fλ̂), d̃ = B K⁺ f − c (docs/method.md, "TFETI and H-TFETI"). The solvers minimize
//! ½yᵀAy − yᵀb̃ over Y = R^{n_E} × Λ; [`TfetiDual::recover_with`] maps y back to λ = λ̂ + P̃ᵀy, the
//! rigid-body amplitudes α = C⁻¹G_E(c_E − B_E ũ) and u_s = ũ_s + R_sα_s (+ g_s on the DOFs held
//! inside the subdomain), ũ = K⁺(f̂ − Bᵀλ).
//! The gradient the solvers see is P̃(Fλ − d̃); its contact part is −(Bu − c)_I, as in the
//! monolithic dual, so the contact status and KKT residuals read the same. The FETI
//! preconditioner of the gluing and Dirichlet block ([`FetiPreconditioner`]) is built here too.

use super::cluster::ClusterSystem;
use super::coarse::Coarse;
use super::constraints::Constraints;
use super::distribution::{Clock, Distribution};
use super::precond::Scaling;
use crate::comm::Comm;
use crate::dual::Recovered;
use crate::error::{Error, Result};
use crate::linalg::schur::{Form, Schur};
use crate::qp::{self, Layout, Operator, Preconditioner, ProductCounter};
use crate::scene::Preconditioner as PreconditionerKind;

/// A piece of this rank — a cluster of subdomains ([`super::cluster`]; one subdomain unless
/// `decomposition.subdomains_per_cluster` > 1) — with its B entries (position in its sorted
/// rows, DOF in the cluster, coefficient).
pub struct LocalPiece {
    pub sys: ClusterSystem,
    pub entries: Vec<(usize, usize, f64)>,
    /// Number of its rows.
    pub nrows: usize,
}

/// A = P̃ F P̃ᵀ over the subdomains of all ranks, on distributed dual vectors.
pub struct TfetiDual<'c, C: Comm> {
    pub dist: Distribution<'c, C>,
    /// The layout of this rank's components.
    pub layout: Layout,
    pub pieces: Vec<LocalPiece>,
    pub coarse: Coarse,
    /// c on the owned rows (+ the last load step's tangential jump, [`TfetiDual::set_load`]).
    c: Vec<f64>,
    /// c without that jump.
    c0: Vec<f64>,
    /// λ̂ on the local rows, Gλ̂ = e: (G_Eᵀ C⁻¹ e, 0) where every body is held by Dirichlet
    /// conditions (λ̂_I = 0), λ_e = Gᵀ(GGᵀ)⁻¹e where one is held by contact alone.
    pub lambda_hat: Vec<f64>,
    /// d̃ − Fλ̂ (before projection, owned): the right-hand side once λ = λ̂ + λ̃.
    pub d_hat: Vec<f64>,
    counter: ProductCounter,
    /// First E (gluing, Dirichlet) row of the global numbering.
    e_start: usize,
    /// The preconditioner's scaling and its S_s (one per local subdomain), once built.
    precond: Option<(Scaling, Vec<Schur>)>,
    /// H-TFETI: the null space W of F (the B_c rows as combinations of B's rows), owned
    /// indices, orthonormal; products, preconditioner and b̃ are kept orthogonal to it.
    null: Vec<Vec<(usize, f64)>>,
    /// Mixed precision: the measured relative error η of a product with the single-precision
    /// factors ([`TfetiDual::keep_single`]), and whether the products use them now
    /// ([`Operator::allow_error`]).
    single: Option<f64>,
    single_now: std::cell::Cell<bool>,
}

/// The relative shift of G Π Gᵀ that picks the smallest rigid amplitudes where the kept rows
/// barely determine them ([`TfetiDual::recover_with`]).
const SHIFT: f64 = 1e-10;

/// A contact row not kept may end this far inside the master (relative to the largest residual
/// of the rows) before the recovery takes the shifted α.
const PENETRATION: f64 = 1e-6;

impl<'c, C: Comm> TfetiDual<'c, C> {
    /// The operator over this rank's factorized pieces `pieces` (ascending global index
    /// `sys.index`, as in `dist`; `cons`: the rows of B per piece), and b̃ on the owned rows.
    pub fn new(dist: Distribution<'c, C>, cons: &Constraints, pieces: Vec<ClusterSystem>, coarse: Coarse) -> (Self, Vec<f64>) {
        let pieces: Vec<LocalPiece> = pieces
            .into_iter()
            .zip(&dist.subs)
            .map(|(sys, sr)| {
                assert_eq!(sys.index, sr.index, "subdomains in the distribution's order");
                let rows = cons.sorted_rows(sys.index);
                let entries = cons.rows[sys.index].iter().map(|&(r, j, c)| (rows.binary_search(&r).expect("row"), j, c)).collect();
                LocalPiece { sys, entries, nrows: rows.len() }
            })
            .collect();
        let c = dist.restrict(&cons.c);
        let layout = dist.layout;
        let e_start = cons.layout.contact_dim();
        let mut dual = TfetiDual {
            dist,
            layout,
            pieces,
            coarse,
            c0: c.clone(),
            c,
            lambda_hat: vec![],
            d_hat: vec![],
            counter: ProductCounter::default(),
            e_start,
            precond: None,
            null: vec![],
            single: None,
            single_now: Default::default(),
        };
        let b = dual.rhs();
        (dual, b)
    }

    /// A new load state on the same subdomains and rows (a step of a load path): f_s and the
    /// held values g_s of each member of each local piece, e = Rᵀf (all pieces), c on the owned rows, and
    /// the tangential rows of c moved by `jump` (owned; B_T u of the last step,
    /// [`TfetiDual::jump`]): friction acts on the slip increment. Returns b̃.
    pub fn set_load(&mut self, f: Vec<Vec<(Vec<f64>, Vec<f64>)>>, e: Vec<f64>, c: Vec<f64>, jump: &[f64]) -> Vec<f64> {
        for (s, fs) in self.pieces.iter_mut().zip(f) {
            s.sys.set_load(fs);
        }
        self.coarse.e = e;
        self.c0 = c;
        self.c = self.c0.clone();
        crate::dual::add_tangential(self.layout, jump, &mut self.c);
        self.rhs()
    }

    /// B u on the owned tangential rows (prescribed parts included, 0 elsewhere) from the gap
    /// c − Bu of a recovered solution: what the next load step's slip is measured from.
    pub fn jump(&self, gap: &[f64]) -> Vec<f64> {
        crate::dual::tangential_jump(self.layout, &self.c, &self.c0, gap)
    }

    /// Sets the null space W of F (H-TFETI: [`super::cluster::Clustering::null`], global rows;
    /// each vector's rows lie on one rank; empty for TFETI) and deflates it from b̃ (`b`).
    pub fn set_null(&mut self, null: &[Vec<(usize, f64)>], b: &mut [f64]) {
        let owned = &self.dist.owned;
        self.null = null
            .iter()
            .filter(|w| owned.binary_search(&w[0].0).is_ok())
            .map(|w| w.iter().map(|&(r, x)| (owned.binary_search(&r).expect("a null vector's rows lie on one rank"), x)).collect())
            .collect();
        self.deflate(b);
    }

    /// y ← y − W Wᵀ y (no communication: each vector of W lies on one rank).
    fn deflate(&self, y: &mut [f64]) {
        for w in &self.null {
            let h: f64 = w.iter().map(|&(i, x)| x * y[i]).sum();
            w.iter().for_each(|&(i, x)| y[i] -= h * x);
        }
    }

    /// λ̂ and d̃ − Fλ̂ = B K⁺ (f − Bᵀλ̂) − c from the current f, e and c; returns b̃ = P̃(d̃ − Fλ̂),
    /// or P(d̃ − Fλ̂) with the orthogonal projector. Gλ̂ = e: λ̂ = (G_Eᵀ C⁻¹ e, 0) where every body
    /// is held by Dirichlet conditions, else λ_e = Gᵀ(GGᵀ)⁻¹e over every row (a body held by
    /// contact alone: part of e is the contact's to carry).
    fn rhs(&mut self) -> Vec<f64> {
        let orthogonal = self.coarse.orthogonal();
        self.lambda_hat = if self.coarse.held() { self.coarse.lambda_hat_local(&self.dist) } else { self.coarse.lambda_e_local(&self.dist) };
        let mut b = vec![0.0; self.layout.dim()];
        let z = self.pinv_of_rhs(&self.lambda_hat);
        self.gather(&z, &mut b);
        b.iter_mut().zip(&self.c).for_each(|(bi, ci)| *bi -= ci);
        self.d_hat = b.clone();
        if orthogonal {
            self.coarse.project_orthogonal(&self.dist, &mut b);
        } else {
            self.coarse.project(&self.dist, &mut b);
        }
        self.deflate(&mut b);
        b
    }

    /// SMALSE-M's start where a body is held by contact alone: λ = ΠGᵀ(GΠGᵀ)⁻¹e (owned) with
    /// Π the touching pairs (gap c ≤ 1e-9·max |c|, with their tangential rows): the load put on
    /// the pairs that touch instead of spread over every row (a pressed sphere then grows its
    /// contact zone from the pole instead of shedding most pairs; run/results/warm_start_floating2.txt).
    /// `None` where those rows do not fix the rigid motions (GΠGᵀ singular on some rank).
    pub fn touching_start(&self) -> Option<Vec<f64>> {
        let l = self.layout;
        let mut cmax = [(0..l.m).map(|i| self.c[l.normal(i)].abs()).fold(0.0f64, f64::max)];
        self.dist.comm().max_f64(&mut cmax);
        let gap = 1e-9 * cmax[0];
        let mut free = vec![false; l.contact_dim()];
        for i in (0..l.m).filter(|&i| self.c[l.normal(i)] <= gap) {
            free[l.normal(i)] = true;
            if l.friction {
                free[l.tangent(i, 0)] = true;
                free[l.tangent(i, 1)] = true;
            }
        }
        let (free_all, _) = self.global_pi(&free, &[]);
        let chol = self.coarse.restricted(&self.dist, &free_all, &[]);
        let mut bad = [f64::from(u8::from(chol.is_none()))];
        self.dist.comm().max_f64(&mut bad);
        if bad[0] > 0.0 {
            return None;
        }
        Some(self.coarse.lambda_restricted_owned(&self.dist, chol.as_ref().expect("checked"), &free_all))
    }

    /// The contact rows that fix a body's rigid motion with the E rows, Π ([`Coarse::restricted`]),
    /// from this rank's free contact components and sliding directions (owned indices), summed
    /// over the ranks: (free per global contact row, sliding (global first row, t)).
    pub(crate) fn global_pi(&self, free: &[bool], slides: &[(usize, [f64; 2])]) -> (Vec<bool>, Vec<(usize, [f64; 2])>) {
        let ni = self.e_start;
        let owned = &self.dist.owned;
        let mut w = vec![0.0; 3 * ni];
        for (i, &r) in owned.iter().enumerate().take_while(|(_, &r)| r < ni) {
            w[r] = if free[i] { 1.0 } else { 0.0 };
        }
        for &(k, t) in slides {
            let r = owned[k];
            w[ni + r] = 1.0;
            w[2 * ni + r] = t[0];
            w[2 * ni + r + 1] = t[1];
        }
        self.dist.reduce(&mut w);
        let free_all: Vec<bool> = w[..ni].iter().map(|&v| v == 1.0).collect();
        let slides_all: Vec<(usize, [f64; 2])> = (0..ni).filter(|&r| w[ni + r] == 1.0).map(|r| (r, [w[2 * ni + r], w[2 * ni + r + 1]])).collect();
        (free_all, slides_all)
    }

    /// λ, α and u from the solvers' y. Oblique projector: λ = λ̂ + P̃ᵀy, α = C⁻¹G_E(c − Bũ)_E.
    /// Orthogonal (SMALSE-M solves for λ itself): λ = y, closed to Gλ = e through the E rows
    /// where C is regular; where a body is held by contact alone, α closes the E rows and the
    /// contact rows in Π — `pi`: this rank's free contact components and sliding directions
    /// (owned indices; the pairs' states), or by default every component of the pairs with
    /// λν > 0. `None` when GΠGᵀ is singular (a rigid motion held by nothing at this solution).
    pub fn recover_with(&self, y: &[f64], pi: Option<(&[bool], &[(usize, [f64; 2])])>) -> Option<Recovered> {
        let orthogonal = self.coarse.orthogonal();
        let mut lambda = self.dist.ghosted(y);
        if !orthogonal {
            self.coarse.project_t_local(&self.dist, &mut lambda);
            lambda.iter_mut().zip(&self.lambda_hat).for_each(|(a, b)| *a += b);
        } else if self.coarse.held() {
            self.coarse.close_local(&self.dist, &mut lambda);
        }
        let feasibility = self.coarse.feasibility(&self.dist, &lambda);
        let mut rhs = self.rhs_of(&lambda);
        let mut u: Vec<Vec<f64>> = rhs.clone();
        // ũ = K⁺(f̂ − Bᵀλ); a cluster's corner forces join its members' right-hand sides
        Clock::time(&self.dist.clock.pinv, || {
            for ((s, us), fs) in self.pieces.iter().zip(&mut u).zip(&mut rhs) {
                let mu = s.sys.pinv_corners(us);
                s.sys.sub_corner_forces(&mu, fs);
            }
        });
        // w = c − B ũ; its E part (and Π's contact rows) enter α
        let mut w = vec![0.0; self.layout.dim()];
        self.gather(&u, &mut w);
        w.iter_mut().zip(&self.c).for_each(|(a, c)| *a = c - *a);
        let alpha = if self.coarse.held() {
            self.coarse.alpha(&self.dist, &w)
        } else {
            let owned_lambda = self.dist.owned_part(&lambda);
            let l = self.layout;
            let (free, slides) = match pi {
                Some((f, s)) => (f.to_vec(), s.to_vec()),
                None => {
                    let lmax = (0..l.m).map(|i| owned_lambda[l.normal(i)]).fold(0.0, f64::max);
                    let mut f = vec![false; l.contact_dim()];
                    for i in (0..l.m).filter(|&i| owned_lambda[l.normal(i)] > 1e-9 * lmax) {
                        f[l.normal(i)] = true;
                        if l.friction {
                            f[l.tangent(i, 0)] = true;
                            f[l.tangent(i, 1)] = true;
                        }
                    }
                    (f, vec![])
                }
            };
            // Πw on the owned rows: E rows whole, free contact rows whole, sliding pairs along t
            let mut pw: Vec<f64> = w.iter().enumerate().map(|(i, &v)| if i >= l.contact_dim() || free[i] { v } else { 0.0 }).collect();
            for &(k, t) in &slides {
                let s = t[0] * w[k] + t[1] * w[k + 1];
                (pw[k], pw[k + 1]) = (t[0] * s, t[1] * s);
            }
            let (free_all, slides_all) = self.global_pi(&free, &slides);
            // α from the kept rows; where they barely fix a rigid motion (a body touching along
            // one line) the exact α may drive the other contact rows deep into the master: then
            // the smallest amplitudes that close the kept rows (a shifted G Π Gᵀ) are taken
            let mut alpha = None;
            for tau in [0.0, SHIFT] {
                let chol = self.coarse.restricted_shifted(&self.dist, &free_all, &slides_all, tau);
                // every rank must agree: a rank without the factor makes all of them fail
                let mut bad = [f64::from(u8::from(chol.is_none()))];
                self.dist.comm().max_f64(&mut bad);
                if bad[0] > 0.0 {
                    return None;
                }
                let a = self.coarse.alpha_restricted(&self.dist, chol.as_ref().expect("checked"), &pw);
                let r = self.coarse.residual_after(&self.dist, &a, &w);
                // the deepest penetration of a contact row not kept, against the largest |w|
                let mut worst =
                    [(0..l.m).filter(|&i| !free[l.normal(i)]).map(|i| -r[l.normal(i)]).fold(0.0f64, f64::max), w.iter().fold(0.0f64, |m, v| m.max(v.abs()))];
                let comm = self.dist.comm();
                comm.max_f64(&mut worst);
                alpha = Some(a);
                if worst[0] <= PENETRATION * worst[1] {
                    break;
                }
            }
            alpha.expect("one try at least")
        };
        for (s, us) in self.pieces.iter().zip(&mut u) {
            s.sys.add_r_mul(&alpha[self.coarse.range(s.sys.index)], us);
            s.sys.set_held(us);
        }
        let mut gap = vec![0.0; self.layout.dim()];
        self.gather(&u, &mut gap);
        gap.iter_mut().zip(&self.c).for_each(|(a, c)| *a = c - *a);
        Some(Recovered { lambda: self.dist.owned_part(&lambda), alpha, u, rhs, gap, feasibility })
    }

    /// Builds the FETI preconditioner of [`DualPreconditioner`] (`None`: drops it). Dirichlet
    /// factorizes each subdomain's K_ii (the DOFs its rows of B do not touch).
    /// `weight[s]` = Δ_s, the stiffness weighting of every subdomain.
    pub fn set_preconditioner(&mut self, kind: PreconditionerKind, cons: &Constraints, weight: Vec<f64>) -> Result<()> {
        let form = match kind {
            PreconditionerKind::Lumped => Form::Lumped,
            PreconditionerKind::Superlumped => Form::Superlumped,
            PreconditionerKind::Dirichlet => Form::MatrixFree,
            PreconditionerKind::DirichletDense => Form::Dense,
            PreconditionerKind::None | PreconditionerKind::Auto => {
                self.precond = None;
                return Ok(());
            }
        };
        let scaling = Scaling::new(cons, weight, &self.dist.owned)?;
        let mut pieces = Vec::with_capacity(self.pieces.len());
        for s in &self.pieces {
            let touched: Vec<usize> = s.entries.iter().map(|x| x.1).collect();
            let schur = Schur::new(&s.sys.k_free(), &touched, form).map_err(|err| {
                Error::numerical(format!("the Dirichlet preconditioner of subdomain {}", s.sys.index), format!("{err}; try solver.preconditioner = \"lumped\""))
            })?;
            pieces.push(schur);
        }
        self.precond = Some((scaling, pieces));
        Ok(())
    }

    /// Bᵀ_s x for each local subdomain, x on the local rows.
    fn scatter(&self, xl: &[f64]) -> Vec<Vec<f64>> {
        self.pieces
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
            .pieces
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

    /// z_s ← K_s⁺ z_s for each local subdomain (in single precision when `single`).
    fn pinv_all(&self, z: &mut [Vec<f64>], single: bool) {
        Clock::time(&self.dist.clock.pinv, || {
            for (s, zs) in self.pieces.iter().zip(z) {
                s.sys.pinv_in_place_as(zs, single);
            }
        });
    }

    /// Keeps single-precision copies of the local factors and measures η, the relative error
    /// ‖F̃v − Fv‖/‖Fv‖ of F with them on a fixed vector (the same on every rank count; two
    /// uncounted products). Returns η.
    pub fn keep_single(&mut self) -> f64 {
        self.pieces.iter_mut().for_each(|p| {
            p.sys.keep_single();
        });
        let v: Vec<f64> = (0..self.layout.dim()).map(|i| crate::linalg::probe(qp::Space::global_index(&self.dist, i))).collect();
        let (mut fd, mut fs) = (vec![0.0; v.len()], vec![0.0; v.len()]);
        let wl = self.dist.ghosted(&v);
        self.apply_f_local_as(&wl, &mut fd, false);
        self.apply_f_local_as(&wl, &mut fs, true);
        let d: Vec<f64> = fd.iter().zip(&fs).map(|(a, b)| a - b).collect();
        let eta = self.dist.dot(&d, &d).sqrt() / self.dist.dot(&fd, &fd).sqrt().max(f64::MIN_POSITIVE);
        self.single = Some(eta);
        eta
    }

    /// η of [`TfetiDual::keep_single`], when single-precision factors are kept.
    pub fn single_error(&self) -> Option<f64> {
        self.single
    }

    /// K_s⁺(f_s − B_sᵀλ) for each local subdomain (λ on the local rows).
    fn pinv_of_rhs(&self, lambda_local: &[f64]) -> Vec<Vec<f64>> {
        let mut z = self.rhs_of(lambda_local);
        self.pinv_all(&mut z, false);
        z
    }

    /// f_s − B_sᵀλ for each local subdomain (λ on the local rows).
    fn rhs_of(&self, lambda_local: &[f64]) -> Vec<Vec<f64>> {
        let mut z = self.scatter(lambda_local);
        for (s, zs) in self.pieces.iter().zip(&mut z) {
            zs.iter_mut().zip(&s.sys.f).for_each(|(v, f)| *v = f - *v);
        }
        z
    }

    /// y = F w (owned) from w on the local rows (not counted).
    fn apply_f_local(&self, wl: &[f64], y: &mut [f64]) {
        self.apply_f_local_as(wl, y, false);
    }

    fn apply_f_local_as(&self, wl: &[f64], y: &mut [f64], single: bool) {
        let mut z = self.scatter(wl);
        self.pinv_all(&mut z, single);
        self.gather(&z, y);
    }

    /// y = F x on owned vectors (not counted).
    pub(crate) fn apply_f(&self, x: &[f64], y: &mut [f64]) {
        self.apply_f_local(&self.dist.ghosted(x), y);
    }

    /// The preconditioner, when one was built.
    pub fn preconditioner(&self) -> Option<DualPreconditioner<'_, 'c, C>> {
        self.precond.as_ref().map(|(scaling, schur)| DualPreconditioner { dual: self, scaling, schur })
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
            self.apply_f_local_as(&wl, y, self.single_now.get());
            self.coarse.project(&self.dist, y);
            self.deflate(y);
        });
    }

    fn products(&self) -> usize {
        self.counter.get()
    }

    /// F x: for x ∈ Ker G, P̃ᵀx = x and A x = P̃ F x = F x − Gᵀ(…).
    fn apply_kernel(&self, x: &[f64], y: &mut [f64]) {
        self.counter.tick();
        Clock::time(&self.dist.clock.apply, || {
            self.apply_f_local_as(&self.dist.ghosted(x), y, self.single_now.get());
            self.deflate(y);
        });
    }

    /// Products with single-precision factors while their measured error η is within `rel`.
    fn allow_error(&self, rel: f64) -> bool {
        self.single_now.set(self.single.is_some_and(|eta| eta <= rel));
        self.single_now.get()
    }

    /// dᵢ = Σ_s Σ_j (B_s)ᵢⱼ² / (K_s)_jj on the owned rows (the projection P̃ left out).
    fn diagonal_estimate(&self) -> Option<Vec<f64>> {
        let v: Vec<Vec<f64>> = self
            .pieces
            .iter()
            .map(|s| {
                let k = s.sys.k_free();
                let mut v = vec![0.0; s.nrows];
                for &(p, j, c) in &s.entries {
                    let kjj = k.position(j, j).map_or(0.0, |q| k.values[q]);
                    if kjj > 0.0 {
                        v[p] += c * c / kjj;
                    }
                }
                v
            })
            .collect();
        let mut d = vec![0.0; self.layout.dim()];
        self.dist.assemble(&v, &mut d);
        Some(d)
    }

    /// y ← P̃ y.
    fn finish_kernel(&self, y: &mut [f64]) {
        Clock::time(&self.dist.clock.apply, || {
            self.coarse.project(&self.dist, y);
            self.deflate(y);
        });
    }
}

/// M⁻¹ = (BBᵀ)⁻¹ (Σ_s B_s S_s B_sᵀ) (BBᵀ)⁻¹ on every row of the dual (gluing, Dirichlet and
/// contact: [`super::precond`]); the solver projects it with its coarse space.
pub struct DualPreconditioner<'a, 'c, C: Comm> {
    dual: &'a TfetiDual<'c, C>,
    scaling: &'a Scaling,
    schur: &'a [Schur],
}

impl<C: Comm> Preconditioner for DualPreconditioner<'_, '_, C> {
    fn block(&self) -> std::ops::Range<usize> {
        0..self.dual.layout.dim()
    }

    fn apply(&self, x: &[f64], y: &mut [f64]) {
        let d = self.dual;
        let mut xs = x.to_vec();
        self.scaling.apply(&d.dist, &mut xs);
        let mut z = d.scatter(&d.dist.ghosted(&xs));
        for ((zs, schur), s) in z.iter_mut().zip(self.schur).zip(&d.pieces) {
            schur.apply_in_place(zs);
            let w = self.scaling.weight[s.sys.index];
            zs.iter_mut().for_each(|v| *v *= w * w);
        }
        d.gather(&z, y);
        self.scaling.apply(&d.dist, y);
        d.deflate(y);
    }
}

/// The coarse space of the inner solves: G = RᵀBᵀ over every row, restricted to a Newton
/// step's subspace W (its free contact components and sliding directions; λ_E always free).
impl<C: Comm> qp::Coarse for TfetiDual<'_, C> {
    fn restrict<'a>(&'a self, free: &[bool], slides: &[(usize, [f64; 2])]) -> Option<Box<dyn qp::CoarseProjector + 'a>> {
        let (free_all, slides_all) = self.global_pi(free, slides);
        let clock = &self.dist.clock;
        let chol = Clock::time(&clock.restricted, || Clock::time(&clock.restricted_factor, || self.coarse.restricted(&self.dist, &free_all, &slides_all)))?;
        Some(Box::new(Restricted { dual: self, chol }))
    }
}

/// P_W's coarse part: x ← x − Gᵀ(GΠGᵀ)⁻¹Gx.
struct Restricted<'a, 'c, C: Comm> {
    dual: &'a TfetiDual<'c, C>,
    chol: crate::linalg::cholesky::Cholesky,
}

impl<C: Comm> qp::CoarseProjector for Restricted<'_, '_, C> {
    fn apply(&self, x: &mut [f64]) {
        self.dual.coarse.project_restricted(&self.dual.dist, &self.chol, x);
    }
}
