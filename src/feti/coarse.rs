//! The natural coarse space of TFETI: G = RᵀBᵀ (a row per column of each piece's kernel — a
//! subdomain's, or an H-TFETI cluster's: six for a floating one, fewer where held DOFs are
//! eliminated), e = Rᵀf, the coarse
//! matrix C = G_E G_Eᵀ (sparse, factorized once) and the oblique projector of docs/method.md, "TFETI and H-TFETI",
//!
//! ```text
//! P̃x = x − Gᵀ C⁻¹ G_E x_E,    P̃ᵀy = y − [G_E 0]ᵀ C⁻¹ G y,    λ̂ = (G_Eᵀ C⁻¹ e, 0),
//! ```
//!
//! with P̃Gᵀ = 0, G(λ̂ + P̃ᵀy) = e for every y, and (P̃ᵀy)_I = y_I: the contact multipliers
//! pass through unchanged, so Λ stays a product of small blocks. G_E has full row rank when
//! every body is held by Dirichlet conditions; otherwise C is singular and the factorization
//! says so.
//!
//! Each rank builds the blocks of G it reads — its own pieces' and those of the pieces touching
//! its rows (the halo) — and the column blocks of C = G_E G_Eᵀ of its own pieces (each block
//! summed over its rows in ascending order, as a whole G would); the blocks are gathered and
//! every rank factorizes C (replicated coarse problem): applying P̃ costs one reduction of G x
//! (k_s per piece, each entry from the one rank that holds the piece), one C⁻¹ solve and Gᵀ on
//! the rows the rank needs. With [`Coarse::make_explicit`] a rank keeps instead only the rows of
//! C⁻¹ (and (GGᵀ)⁻¹) of its own pieces — ESPRESO's explicit coarse inverse, held distributed —
//! and a C⁻¹ solve becomes those rows' products with the reduced G x and a second reduction
//! of the result: no triangular solve of dimension 6S on every rank. Vectors are distributed
//! ([`Distribution`]); the measurements behind both are in docs/performance.md, "Scale-out: many subdomains".

use super::constraints::Constraints;
use super::distribution::{Clock, Distribution};
use crate::comm::Comm;
use crate::error::{Error, Result};
use crate::linalg::cholesky::{Cholesky, Ordering, Symbolic};
use crate::linalg::ordering::nested_dissection;
use crate::linalg::sparse::SymCsc;

/// One piece's part of G (a subdomain's, or a cluster's: [`super::cluster`]); `rows` and `g`
/// are empty for a piece this rank does not read.
struct Block {
    /// The multipliers whose rows touch it (ascending).
    rows: Vec<usize>,
    /// G_s = R_sᵀB_sᵀ on them, column-major k × len (each row's k values together).
    g: Vec<f64>,
    /// Columns of its kernel R_s, and the first of its coarse unknowns.
    k: usize,
    off: usize,
}

/// How this rank applies X⁻¹ for a coarse matrix X (C, or GGᵀ).
enum Inverse {
    /// X factorized, held whole by every rank.
    Factor(Cholesky),
    /// The rows of X⁻¹ of this rank's pieces ([`Coarse::make_explicit`]).
    Explicit(Rows),
}

/// Rows of X⁻¹: per piece (ascending), its k rows, each of the coarse dimension (row-major).
struct Rows {
    pieces: Vec<(usize, Vec<f64>)>,
}

impl Rows {
    /// The rows of `pieces` from X's factor: X⁻¹'s columns (X is symmetric) by one solve with
    /// the k unit vectors of each piece, so a piece's rows are the same digits on every rank.
    fn new(chol: &Cholesky, blocks: &[Block], pieces: &[usize]) -> Rows {
        let n = chol.n();
        let pieces = pieces
            .iter()
            .map(|&s| {
                let b = &blocks[s];
                let mut x = vec![0.0; n * b.k];
                (0..b.k).for_each(|j| x[j * n + b.off + j] = 1.0);
                chol.solve_many_in_place(&mut x, b.k);
                (s, x)
            })
            .collect();
        Rows { pieces }
    }

    fn bytes(&self) -> usize {
        self.pieces.iter().map(|(_, r)| 8 * r.len()).sum()
    }

    /// x ← X⁻¹x on the entries of the rows held (zero elsewhere); each a dot product in index
    /// order, so independent of the rank that takes it.
    fn solve_mine(&self, blocks: &[Block], x: &mut [f64]) {
        let n = x.len();
        let mut out = vec![0.0; n];
        for (s, r) in &self.pieces {
            let b = &blocks[*s];
            for (j, row) in r.chunks_exact(n).enumerate() {
                out[b.off + j] = row.iter().zip(x.iter()).map(|(a, v)| a * v).sum();
            }
        }
        x.copy_from_slice(&out);
    }
}

/// The most bytes of explicit coarse-inverse rows a rank may hold
/// (`decomposition.coarse_solve = "explicit"`).
pub const MAX_EXPLICIT_BYTES: usize = 1 << 30;

/// [`Coarse::inverse_costs`]: C's factor and one solve with it; one rank's explicit rows.
#[derive(Clone, Copy, Debug)]
pub struct InverseCosts {
    pub nnz_l: usize,
    pub factor_solve_s: f64,
    pub rows_setup_s: f64,
    pub rows_solve_s: f64,
    pub rows_bytes: usize,
}

/// G, e and the factorized C.
pub struct Coarse {
    blocks: Vec<Block>,
    /// First λ_E index.
    e_start: usize,
    /// e = Rᵀf, k_s per piece.
    pub e: Vec<f64>,
    /// C = G_E G_Eᵀ's inverse; `None` when a body is held by contact alone (orthogonal
    /// projector only: then GGᵀ over every row is what is regular).
    chol: Option<Inverse>,
    /// GGᵀ's inverse, for the orthogonal projector (SMALSE-M) only.
    full: Option<Inverse>,
    /// Nonzeros of the lower triangle of C.
    pub nnz_c: usize,
    /// The pattern of GGᵀ with C's values and G's contact columns, built at the first
    /// [`Coarse::restricted`].
    pattern: std::cell::OnceCell<Pattern>,
}

/// G Π Gᵀ's pieces: the lower-triangle pattern of GGᵀ over all rows carrying C = G_E G_Eᵀ's
/// values, and per contact row its column of G as (coarse index, value).
struct Pattern {
    c: SymCsc,
    contact: Vec<Vec<(usize, f64)>>,
    /// The analysis of c's pattern, once (every GΠGᵀ has it).
    symbolic: Symbolic,
}

/// R_sᵀ f_s for the modes `r` (columns of f's length, column-major).
fn rigid_work(r: &[f64], f: &[f64]) -> Vec<f64> {
    let nd = f.len();
    r.chunks_exact(nd).map(|c| c.iter().zip(f).map(|(a, b)| a * b).sum()).collect()
}

/// The coarse matrices a TFETI dual factorizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// C = G_E G_Eᵀ: the oblique projector P̃.
    Oblique,
    /// C and GGᵀ over every row: SMALSE-M's orthogonal projector P.
    Orthogonal,
    /// GGᵀ alone: a body held by contact alone makes C singular (SMALSE-M).
    ContactHeld,
}

impl Coarse {
    /// The pieces whose blocks of G this rank reads: its own and those touching its local rows
    /// (ascending). `kernels` of [`Coarse::new`] needs these.
    pub fn pieces_read<C: Comm>(dist: &Distribution<'_, C>) -> Vec<usize> {
        let mut p: Vec<usize> = dist.subs.iter().map(|sr| sr.index).collect();
        (0..dist.local_len()).for_each(|l| p.extend(dist.touching(l).iter().map(|&(s, _)| s)));
        p.sort_unstable();
        p.dedup();
        p
    }

    /// Builds this rank's blocks of G and e for the pieces — subdomains or clusters, whose rows
    /// `cons` lists — (`kernels[s]` = (R_s, k_s), at least for [`Coarse::pieces_read`];
    /// `loads[s]` = f_s for this rank's pieces) and factorizes what `kind` needs; `body` names
    /// a piece's body in errors. Collective.
    pub fn new<C: Comm>(
        dist: &Distribution<'_, C>,
        kernels: &[Option<(Vec<f64>, usize)>],
        cons: &Constraints,
        loads: &[Vec<f64>],
        kind: Kind,
        body: &dyn Fn(usize) -> String,
    ) -> Result<Coarse> {
        let e_start = cons.e_start();
        // k of every piece, from the ranks that hold them (one contributor per entry)
        let mut ks = vec![0.0; kernels.len()];
        for sr in &dist.subs {
            ks[sr.index] = kernels[sr.index].as_ref().expect("a kernel for every piece of this rank").1 as f64;
        }
        dist.reduce(&mut ks);
        let mut blocks = Vec::with_capacity(kernels.len());
        let mut off = 0;
        for (s, kernel) in kernels.iter().enumerate() {
            let k = ks[s] as usize;
            let block = match kernel {
                Some((r, kr)) => {
                    debug_assert_eq!(*kr, k);
                    let rows = cons.sorted_rows(s);
                    let nd = r.len().checked_div(k).unwrap_or(0);
                    let mut g = vec![0.0; k * rows.len()];
                    for &(row, dof, coef) in &cons.rows[s] {
                        let p = rows.binary_search(&row).expect("row listed");
                        for j in 0..k {
                            g[p * k + j] += coef * r[j * nd + dof];
                        }
                    }
                    Block { rows, g, k, off }
                }
                None => Block { rows: vec![], g: vec![], k, off },
            };
            off += k;
            blocks.push(block);
        }
        let mut coarse = Coarse { blocks, e_start, e: vec![0.0; off], chol: None, full: None, nnz_c: 0, pattern: Default::default() };
        coarse.e = coarse.rigid_loads(dist, &|s| kernels[s].as_ref().expect("a kernel for every piece of this rank").0.as_slice(), loads);
        if kind != Kind::Oblique {
            coarse.full = Some(Inverse::Factor(coarse_matrix(&coarse.blocks, dist, 0, body)?.0));
        }
        if kind != Kind::ContactHeld {
            let (c, nnz) = coarse_matrix(&coarse.blocks, dist, e_start, body)?;
            (coarse.chol, coarse.nnz_c) = (Some(Inverse::Factor(c)), nnz);
        }
        Ok(coarse)
    }

    /// e = Rᵀf: the load's work in each piece's kernel motions (`kernel(s)` = R_s and
    /// `loads[s]` = f_s for this rank's pieces; R_s vanishes on held DOFs: Rᵀf = Rᵀ(f − Kg)),
    /// reduced over the ranks (one contributor per entry). Collective.
    pub fn rigid_loads<'k, C: Comm>(&self, dist: &Distribution<'_, C>, kernel: &dyn Fn(usize) -> &'k [f64], loads: &[Vec<f64>]) -> Vec<f64> {
        let mut e = vec![0.0; self.dim()];
        for sr in &dist.subs {
            let r = kernel(sr.index);
            let b = &self.blocks[sr.index];
            e[b.off..b.off + b.k].copy_from_slice(&rigid_work(r, &loads[sr.index]));
        }
        dist.reduce(&mut e);
        e
    }

    /// Size of the coarse problem, k_s per piece.
    pub fn dim(&self) -> usize {
        self.e.len()
    }

    /// Subdomain `s`'s coarse unknowns (its α_s).
    pub fn range(&self, s: usize) -> std::ops::Range<usize> {
        let b = &self.blocks[s];
        b.off..b.off + b.k
    }

    /// a = G x (G_E x_E when `e_only`) from `xl` on the local rows: this rank's subdomains'
    /// blocks, reduced over the ranks (one contributor per entry: exact).
    fn g_mul<C: Comm>(&self, dist: &Distribution<'_, C>, xl: &[f64], e_only: bool) -> Vec<f64> {
        let mut out = vec![0.0; self.dim()];
        for sr in &dist.subs {
            let b = &self.blocks[sr.index];
            if b.k == 0 {
                continue;
            }
            let acc = &mut out[b.off..b.off + b.k];
            for ((&r, gp), &l) in b.rows.iter().zip(b.g.chunks_exact(b.k)).zip(&sr.rows) {
                if !e_only || r >= self.e_start {
                    let x = xl[l];
                    acc.iter_mut().zip(gp).for_each(|(a, g)| *a += g * x);
                }
            }
        }
        dist.reduce(&mut out);
        out
    }

    /// v[i] −= (Gᵀa)_r for each (i, local row l of r) (only the E rows when `e_only`); the
    /// subdomains touching r in ascending order.
    fn sub_gt<C: Comm>(&self, dist: &Distribution<'_, C>, a: &[f64], v: &mut [f64], rows: impl Iterator<Item = (usize, usize)>, e_only: bool) {
        for (i, l) in rows {
            if e_only && dist.local_rows[l] < self.e_start {
                continue;
            }
            for &(s, p) in dist.touching(l) {
                let b = &self.blocks[s];
                let gp = &b.g[p * b.k..(p + 1) * b.k];
                v[i] -= gp.iter().zip(&a[b.off..b.off + b.k]).map(|(g, x)| g * x).sum::<f64>();
            }
        }
    }

    /// (index, local row) of every owned row.
    fn owned_rows<'a, C: Comm>(dist: &'a Distribution<'_, C>) -> impl Iterator<Item = (usize, usize)> + 'a {
        dist.owned_pos.iter().copied().enumerate()
    }

    /// (index, local row) of every local row.
    fn local_rows<C: Comm>(dist: &Distribution<'_, C>) -> impl Iterator<Item = (usize, usize)> {
        (0..dist.local_len()).map(|l| (l, l))
    }

    /// x ← X⁻¹ x on every rank, timed on `dist`'s clock: with X's factor, or with the rows of
    /// this rank's pieces followed by a reduction (one contributor per entry: exact, so the
    /// digits do not depend on the rank count).
    fn inverse<C: Comm>(&self, dist: &Distribution<'_, C>, inv: &Inverse, x: &mut [f64]) {
        match inv {
            Inverse::Factor(chol) => Clock::time(&dist.clock.coarse_solve, || chol.solve_in_place(x)),
            Inverse::Explicit(rows) => {
                Clock::time(&dist.clock.coarse_solve, || rows.solve_mine(&self.blocks, x));
                dist.reduce(x);
            }
        }
    }

    /// x ← C⁻¹ x.
    fn c_solve<C: Comm>(&self, dist: &Distribution<'_, C>, x: &mut [f64]) {
        let inv = self.chol.as_ref().expect("C = G_E G_Eᵀ is regular (every body held by Dirichlet conditions)");
        self.inverse(dist, inv, x);
    }

    /// x ← (GGᵀ)⁻¹ x.
    pub(crate) fn full_solve<C: Comm>(&self, dist: &Distribution<'_, C>, x: &mut [f64]) {
        let inv = self.full.as_ref().expect("coarse problem built for the orthogonal projector");
        self.inverse(dist, inv, x);
    }

    /// Replaces the factors of C (and GGᵀ) by the rows of their inverses of this rank's pieces
    /// and drops the factors. Fails on every rank, naming `decomposition.coarse_solve`, when a
    /// rank would hold more than `max_bytes` ([`MAX_EXPLICIT_BYTES`] in the pipeline). Returns
    /// the bytes held (max over the ranks).
    pub fn make_explicit<C: Comm>(&mut self, dist: &Distribution<'_, C>, max_bytes: usize) -> Result<usize> {
        let pieces: Vec<usize> = dist.subs.iter().map(|sr| sr.index).filter(|&s| self.blocks[s].k > 0).collect();
        let per: usize = pieces.iter().map(|&s| 8 * self.blocks[s].k * self.dim()).sum();
        let held = usize::from(self.chol.is_some()) + usize::from(self.full.is_some());
        let mut mx = [(per * held) as f64];
        dist.comm().max_f64(&mut mx);
        let bytes = mx[0] as usize;
        if bytes > max_bytes {
            return Err(Error::scene(
                "decomposition.coarse_solve",
                format!(
                    "\"explicit\" would hold {:.2} GB of coarse-inverse rows on a rank (coarse dimension {}; at most {:.2} GB); use \"factor\", more ranks or larger clusters",
                    bytes as f64 / 1e9,
                    self.dim(),
                    max_bytes as f64 / 1e9
                ),
            ));
        }
        for inv in [&mut self.chol, &mut self.full].into_iter().flatten() {
            if let Inverse::Factor(chol) = inv {
                *inv = Inverse::Explicit(Rows::new(chol, &self.blocks, &pieces));
            }
        }
        Ok(bytes)
    }

    /// What C⁻¹ costs one rank that holds `pieces` pieces (the first ones with a kernel), for
    /// the `bench-coarse` study: one solve with C's factor, and that rank's explicit rows —
    /// their setup from the factor, one product with them (without the reductions around it),
    /// their bytes. Times are the fastest of `repeat`. `None` without C's factor.
    pub fn inverse_costs(&self, pieces: usize, repeat: usize) -> Option<InverseCosts> {
        let Some(Inverse::Factor(chol)) = &self.chol else { return None };
        let n = self.dim();
        let x0: Vec<f64> = (0..n).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
        let fastest = |f: &mut dyn FnMut()| {
            (0..repeat.max(1))
                .map(|_| {
                    let t = std::time::Instant::now();
                    f();
                    t.elapsed().as_secs_f64()
                })
                .fold(f64::INFINITY, f64::min)
        };
        let mut x = x0.clone();
        let factor_solve_s = fastest(&mut || {
            x.copy_from_slice(&x0);
            chol.solve_in_place(&mut x)
        });
        let mine: Vec<usize> = (0..self.blocks.len()).filter(|&s| self.blocks[s].k > 0).take(pieces).collect();
        let t = std::time::Instant::now();
        let rows = Rows::new(chol, &self.blocks, &mine);
        let rows_setup_s = t.elapsed().as_secs_f64();
        let rows_solve_s = fastest(&mut || {
            x.copy_from_slice(&x0);
            rows.solve_mine(&self.blocks, &mut x)
        });
        Some(InverseCosts { nnz_l: chol.nnz_l(), factor_solve_s, rows_setup_s, rows_solve_s, rows_bytes: rows.bytes() })
    }

    /// Whether the orthogonal projector's GGᵀ was built (SMALSE-M).
    pub fn orthogonal(&self) -> bool {
        self.full.is_some()
    }

    /// Whether C = G_E G_Eᵀ is regular: every body held by its Dirichlet conditions.
    pub fn held(&self) -> bool {
        self.chol.is_some()
    }

    /// z ← P̃ z = z − Gᵀ C⁻¹ G_E z_E (z owned).
    pub fn project<C: Comm>(&self, dist: &Distribution<'_, C>, z: &mut [f64]) {
        let zl = dist.ghosted(z);
        let mut a = self.g_mul(dist, &zl, true);
        self.c_solve(dist, &mut a);
        self.sub_gt(dist, &a, z, Self::owned_rows(dist), false);
    }

    /// z ← P_E z = z − [G_Eᵀ C⁻¹ G_E z_E]_E, the orthogonal projector of the E block onto
    /// Ker G_E (C = G_E G_Eᵀ; contact components unchanged; z owned).
    pub fn project_e<C: Comm>(&self, dist: &Distribution<'_, C>, z: &mut [f64]) {
        let zl = dist.ghosted(z);
        let mut a = self.g_mul(dist, &zl, true);
        self.c_solve(dist, &mut a);
        self.sub_gt(dist, &a, z, Self::owned_rows(dist), true);
    }

    /// yl ← P̃ᵀ yl = yl − [G_E 0]ᵀ C⁻¹ G yl on the local rows (yl ghosted).
    pub fn project_t_local<C: Comm>(&self, dist: &Distribution<'_, C>, yl: &mut [f64]) {
        let mut a = self.g_mul(dist, yl, false);
        self.c_solve(dist, &mut a);
        self.sub_gt(dist, &a, yl, Self::local_rows(dist), true);
    }

    /// x ← P x = x − Gᵀ(GGᵀ)⁻¹G x, the orthogonal projector onto Ker G (built with
    /// `orthogonal = true` only; x owned).
    pub fn project_orthogonal<C: Comm>(&self, dist: &Distribution<'_, C>, x: &mut [f64]) {
        let xl = dist.ghosted(x);
        let mut a = self.g_mul(dist, &xl, false);
        self.full_solve(dist, &mut a);
        self.sub_gt(dist, &a, x, Self::owned_rows(dist), false);
    }

    fn pattern<C: Comm>(&self, dist: &Distribution<'_, C>) -> &Pattern {
        self.pattern.get_or_init(|| {
            // the contact rows enter the pattern with weight 0
            let (c, _) = gram(&self.blocks, dist, 0, |r| if r >= self.e_start { 1.0 } else { 0.0 });
            let contact = columns(&self.blocks, dist, self.e_start);
            let symbolic = Symbolic::analyze(&c, block_nested_dissection(&self.blocks, &c)).expect("a valid permutation of GGᵀ's pattern");
            Pattern { c, contact, symbolic }
        })
    }

    /// G Π Gᵀ factorized, Π = I on the E rows, and on the contact rows: the rows where
    /// `weight` is 1 (free), the combination t₀g_k + t₁g_{k+1} for the sliding pairs (first
    /// row k, t) of `slides`, nothing for the others (global row indices). `None` if singular.
    /// Collective (the first call gathers the pattern).
    pub fn restricted<C: Comm>(&self, dist: &Distribution<'_, C>, free: &[bool], slides: &[(usize, [f64; 2])]) -> Option<Cholesky> {
        self.restricted_shifted(dist, free, slides, 0.0)
    }

    /// [`Coarse::restricted`] of G Π Gᵀ + τ·max diag·I: for a rigid motion the kept rows barely
    /// determine (a cylinder touching along one line), the shift picks the smallest amplitudes.
    pub fn restricted_shifted<C: Comm>(&self, dist: &Distribution<'_, C>, free: &[bool], slides: &[(usize, [f64; 2])], tau: f64) -> Option<Cholesky> {
        let pat = self.pattern(dist);
        let mut c = pat.c.clone();
        let mut add = |list: &[(usize, f64)]| {
            for &(i, x) in list {
                for &(j, y) in list {
                    if i >= j {
                        let p = c.position(i, j).expect("in GGᵀ's pattern");
                        c.values[p] += x * y;
                    }
                }
            }
        };
        for (r, list) in pat.contact.iter().enumerate() {
            if free[r] {
                add(list);
            }
        }
        for &(k, t) in slides {
            let mut merged: std::collections::BTreeMap<usize, f64> = Default::default();
            for (row, w) in [(k, t[0]), (k + 1, t[1])] {
                for &(i, x) in &pat.contact[row] {
                    *merged.entry(i).or_insert(0.0) += w * x;
                }
            }
            add(&merged.into_iter().collect::<Vec<_>>());
        }
        if tau > 0.0 {
            let diag: Vec<usize> = (0..c.n).map(|i| c.position(i, i).expect("GGᵀ's diagonal")).collect();
            let max = diag.iter().fold(0.0f64, |a, &p| a.max(c.values[p]));
            diag.iter().for_each(|&p| c.values[p] += tau * max);
        }
        Cholesky::with_symbolic(pat.symbolic.clone(), &c).ok()
    }

    /// The rows' residual once the rigid amplitudes α close them: w − Gᵀα on owned vectors.
    pub fn residual_after<C: Comm>(&self, dist: &Distribution<'_, C>, alpha: &[f64], w: &[f64]) -> Vec<f64> {
        let mut r = w.to_vec();
        self.sub_gt(dist, alpha, &mut r, Self::owned_rows(dist), false);
        r
    }

    /// x ← x − Gᵀ(GΠGᵀ)⁻¹ G x on owned vectors, with `chol` from [`Coarse::restricted`].
    pub fn project_restricted<C: Comm>(&self, dist: &Distribution<'_, C>, chol: &Cholesky, x: &mut [f64]) {
        Clock::time(&dist.clock.restricted, || {
            let xl = dist.ghosted(x);
            let mut a = self.g_mul(dist, &xl, false);
            chol.solve_in_place(&mut a);
            self.sub_gt(dist, &a, x, Self::owned_rows(dist), false);
        });
    }

    /// λ̂ = (G_Eᵀ C⁻¹ e, 0) on the local rows.
    pub fn lambda_hat_local<C: Comm>(&self, dist: &Distribution<'_, C>) -> Vec<f64> {
        let mut a = self.e.clone();
        self.c_solve(dist, &mut a);
        let mut l = vec![0.0; dist.local_len()];
        self.sub_gt(dist, &a, &mut l, Self::local_rows(dist), true);
        l.iter_mut().for_each(|v| *v = -*v);
        l
    }

    /// λ = ΠGᵀ(GΠGᵀ)⁻¹e on the owned rows, with `chol` from [`Coarse::restricted`] and
    /// `free` its contact rows (global): the least-norm solution of Gλ = e on the E rows and
    /// the kept contact rows alone (the others 0).
    pub fn lambda_restricted_owned<C: Comm>(&self, dist: &Distribution<'_, C>, chol: &Cholesky, free: &[bool]) -> Vec<f64> {
        let mut a = self.e.clone();
        Clock::time(&dist.clock.coarse_solve, || chol.solve_in_place(&mut a));
        let mut l = vec![0.0; dist.owned.len()];
        self.sub_gt(dist, &a, &mut l, Self::owned_rows(dist), false);
        for (v, &r) in l.iter_mut().zip(&dist.owned) {
            *v = if r < self.e_start && !free[r] { 0.0 } else { -*v };
        }
        l
    }

    /// λ_e = Gᵀ(GGᵀ)⁻¹e on the local rows (every row: with bodies held by contact alone part of
    /// e is the contact's to carry): the least-norm solution of Gλ = e (orthogonal projector).
    pub fn lambda_e_local<C: Comm>(&self, dist: &Distribution<'_, C>) -> Vec<f64> {
        let mut a = self.e.clone();
        self.full_solve(dist, &mut a);
        let mut l = vec![0.0; dist.local_len()];
        self.sub_gt(dist, &a, &mut l, Self::local_rows(dist), false);
        l.iter_mut().for_each(|v| *v = -*v);
        l
    }

    /// λ ← λ − [G_E 0]ᵀ C⁻¹ (Gλ − e) on the local rows: closes Gλ = e exactly through the E
    /// rows alone (the contact components unchanged).
    pub fn close_local<C: Comm>(&self, dist: &Distribution<'_, C>, lambda: &mut [f64]) {
        let mut a = self.g_mul(dist, lambda, false);
        a.iter_mut().zip(&self.e).for_each(|(x, e)| *x -= e);
        self.c_solve(dist, &mut a);
        self.sub_gt(dist, &a, lambda, Self::local_rows(dist), true);
    }

    /// α = (GΠGᵀ)⁻¹ G Πw with `chol` from [`Coarse::restricted`] and `pw` = Πw (owned): the
    /// rigid-body amplitudes that best close the residual w of the E rows and the contact rows
    /// in Π (a body held by contact alone).
    pub fn alpha_restricted<C: Comm>(&self, dist: &Distribution<'_, C>, chol: &Cholesky, pw: &[f64]) -> Vec<f64> {
        let wl = dist.ghosted(pw);
        let mut a = self.g_mul(dist, &wl, false);
        Clock::time(&dist.clock.coarse_solve, || chol.solve_in_place(&mut a));
        a
    }

    /// α = C⁻¹ G_E w_E: the rigid-body amplitudes that best close the E rows' residual w (owned).
    pub fn alpha<C: Comm>(&self, dist: &Distribution<'_, C>, w: &[f64]) -> Vec<f64> {
        let wl = dist.ghosted(w);
        let mut a = self.g_mul(dist, &wl, true);
        self.c_solve(dist, &mut a);
        a
    }

    /// ‖G λ − e‖ / ‖e‖ (or the absolute value when e = 0), λ on the local rows.
    pub fn feasibility<C: Comm>(&self, dist: &Distribution<'_, C>, lambda_local: &[f64]) -> f64 {
        let g = self.g_mul(dist, lambda_local, false);
        let num = g.iter().zip(&self.e).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        let den = self.e.iter().map(|v| v * v).sum::<f64>().sqrt();
        if den > 0.0 {
            num / den
        } else {
            num
        }
    }
}

/// G_F G_Fᵀ over the rows from `first` on (λ_E: C; all: GGᵀ), factorized; with its nnz.
fn coarse_matrix<C: Comm>(blocks: &[Block], dist: &Distribution<'_, C>, first: usize, body: &dyn Fn(usize) -> String) -> Result<(Cholesky, usize)> {
    let (c, touched) = gram(blocks, dist, first, |_| 1.0);
    if let Some(s) = (0..blocks.len()).find(|&s| blocks[s].k > 0 && !touched[s]) {
        return Err(Error::numerical(
            "TFETI coarse problem",
            format!("C = G_E G_Eᵀ is singular (body \"{}\"): every body needs Dirichlet conditions that stop its rigid motion", body(s)),
        ));
    }
    let chol = Cholesky::factorize(&c, block_nested_dissection(blocks, &c))
        .map_err(|_| Error::numerical("TFETI coarse problem", "C = G_E G_Eᵀ is singular: every body needs Dirichlet conditions that stop its rigid motion"))?;
    Ok((chol, c.nnz()))
}

/// METIS nested dissection of C's block graph (one vertex per subdomain, an edge where two
/// subdomains' k × k blocks couple), expanded to the blocks' unknowns; AMD if METIS fails.
fn block_nested_dissection(blocks: &[Block], c: &SymCsc) -> Ordering {
    let nb = blocks.len();
    let block_of: Vec<usize> = blocks.iter().enumerate().flat_map(|(s, b)| std::iter::repeat_n(s, b.k)).collect();
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); nb];
    for j in 0..c.n {
        for &i in &c.row_idx[c.col_ptr[j]..c.col_ptr[j + 1]] {
            let (bi, bj) = (block_of[i], block_of[j]);
            if bi != bj {
                adj[bi].push(bj);
                adj[bj].push(bi);
            }
        }
    }
    let mut xadj = vec![0];
    let mut adjncy = Vec::new();
    for a in &mut adj {
        a.sort_unstable();
        a.dedup();
        adjncy.extend_from_slice(a);
        xadj.push(adjncy.len());
    }
    match nested_dissection(&xadj, &adjncy) {
        Ok(perm) => Ordering::Custom(perm.iter().flat_map(|&b| blocks[b].off..blocks[b].off + blocks[b].k).collect()),
        Err(_) => Ordering::Amd,
    }
}

/// The columns of G of the rows below `last` (the contact rows): (coarse index, value) per row,
/// the pieces in ascending order; each rank builds its owned rows' and they are gathered.
fn columns<C: Comm>(blocks: &[Block], dist: &Distribution<'_, C>, last: usize) -> Vec<Vec<(usize, f64)>> {
    // per owned row: row, count, then (index, value) pairs
    let mut mine = Vec::new();
    for (&row, &l) in dist.owned.iter().zip(&dist.owned_pos).take_while(|(&r, _)| r < last) {
        let at = mine.len();
        mine.extend([row as f64, 0.0]);
        for &(s, p) in dist.touching(l) {
            let b = &blocks[s];
            for j in 0..b.k {
                mine.extend([(b.off + j) as f64, b.g[p * b.k + j]]);
            }
        }
        mine[at + 1] = ((mine.len() - at - 2) / 2) as f64;
    }
    let mut by_row: Vec<Vec<(usize, f64)>> = vec![Vec::new(); last];
    for part in dist.comm().all_gather_f64(&mine) {
        let mut i = 0;
        while i < part.len() {
            let (row, n) = (part[i] as usize, part[i + 1] as usize);
            by_row[row] = (0..n).map(|q| (part[i + 2 + 2 * q] as usize, part[i + 3 + 2 * q])).collect();
            i += 2 + 2 * n;
        }
    }
    by_row
}

/// Σ_r w(r) g_r g_rᵀ over the rows from `first` on (g_r: row r's column of G), in k × k blocks
/// of piece pairs (b, a), b ≤ a: the rank holding a sums block (b, a) over a's rows in ascending
/// order (every row that touches both is a's, and b is in its halo), and the blocks are
/// gathered — the same sums in the same order whatever the rank count. Returns the lower
/// triangle, and per piece whether a row touched it (its diagonal block exists). Collective.
fn gram<C: Comm>(blocks: &[Block], dist: &Distribution<'_, C>, first: usize, w: impl Fn(usize) -> f64) -> (SymCsc, Vec<bool>) {
    // this rank's column blocks: (b, a, values) flattened as b, a, len, values…
    let mut mine = Vec::new();
    for sr in &dist.subs {
        let a = sr.index;
        let ba = &blocks[a];
        if ba.k == 0 {
            continue;
        }
        let mut acc: std::collections::BTreeMap<usize, Vec<f64>> = Default::default();
        for ((pa, &r), &l) in ba.rows.iter().enumerate().zip(&sr.rows).filter(|((_, &r), _)| r >= first) {
            let wr = w(r);
            for &(b, pb) in dist.touching(l).iter().filter(|x| x.0 <= a) {
                let bb = &blocks[b];
                if bb.k == 0 {
                    continue;
                }
                let blk = acc.entry(b).or_insert_with(|| vec![0.0; ba.k * bb.k]);
                for jj in 0..bb.k {
                    let y = bb.g[pb * bb.k + jj];
                    for ii in (if a == b { jj } else { 0 })..ba.k {
                        blk[jj * ba.k + ii] += wr * ba.g[pa * ba.k + ii] * y;
                    }
                }
            }
        }
        for (b, v) in acc {
            mine.extend([b as f64, a as f64, v.len() as f64]);
            mine.extend(v);
        }
    }
    // (column block, row block) → k_row × k_col values, column-major
    let mut acc: std::collections::BTreeMap<(usize, usize), Vec<f64>> = Default::default();
    for part in dist.comm().all_gather_f64(&mine) {
        let mut i = 0;
        while i < part.len() {
            let (b, a, n) = (part[i] as usize, part[i + 1] as usize, part[i + 2] as usize);
            acc.insert((b, a), part[i + 3..i + 3 + n].to_vec());
            i += 3 + n;
        }
    }
    let nc = blocks.last().map_or(0, |b| b.off + b.k);
    let mut c = SymCsc { n: nc, col_ptr: vec![0], row_idx: vec![], values: vec![] };
    let mut touched = vec![false; blocks.len()];
    for (b, bb) in blocks.iter().enumerate() {
        touched[b] = acc.contains_key(&(b, b));
        for jj in 0..bb.k {
            for (&(_, a), blk) in acc.range((b, 0)..(b + 1, 0)) {
                let ba = &blocks[a];
                for ii in (if a == b { jj } else { 0 })..ba.k {
                    c.row_idx.push(ba.off + ii);
                    c.values.push(blk[jj * ba.k + ii]);
                }
            }
            c.col_ptr.push(c.row_idx.len());
        }
    }
    (c, touched)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::feti::decomposition::Decomposition;
    use crate::feti::subdomain_loads;

    /// The subdomains' kernels, nothing held.
    fn kernels(model: &crate::model::Model, d: &Decomposition) -> Vec<(Vec<f64>, usize)> {
        crate::feti::cluster::Clustering::singletons(d).kernels(&model.mesh, d, &vec![vec![]; d.subdomains.len()])
    }

    /// The coarse problem on one rank holding every piece.
    fn build<'c>(
        model: &crate::model::Model,
        d: &Decomposition,
        cons: &Constraints,
        kind: Kind,
        comm: &'c crate::comm::SerialComm,
    ) -> (Coarse, Distribution<'c, crate::comm::SerialComm>) {
        let dist = Distribution::new(comm, cons, &vec![0; d.subdomains.len()]);
        let k: Vec<_> = kernels(model, d).into_iter().map(Some).collect();
        let c =
            Coarse::new(&dist, &k, cons, &subdomain_loads(d, &model.loads, &(0..d.subdomains.len()).collect::<Vec<_>>()), kind, &|_| String::new()).unwrap();
        (c, dist)
    }

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// P̃Gᵀ = 0, G(λ̂ + P̃ᵀy) = e for every y, (P̃ᵀy)_I = y_I, P̃ and the orthogonal P idempotent,
    /// P symmetric, on the seed scene at N = 5 with 3 subdomains per body (one rank: the owned
    /// rows are all rows).
    #[test]
    fn projector_identities() {
        let (model, d, cons) = crate::feti::seed_fixture(5, 3);
        let comm = crate::comm::SerialComm;
        let (c, dist) = build(&model, &d, &cons, Kind::Orthogonal, &comm);
        let n = cons.layout.dim();
        let ni = cons.e_start();
        assert!(ni > 0 && n > ni);
        assert_eq!(dist.owned, (0..n).collect::<Vec<_>>());
        assert_eq!(dist.local_rows, dist.owned);
        let mut s = 5u64;
        let y: Vec<f64> = (0..n).map(|_| lcg(&mut s)).collect();
        let z: Vec<f64> = (0..n).map(|_| lcg(&mut s)).collect();
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        // λ = λ̂ + P̃ᵀy is feasible and keeps y_I
        let mut l = y.clone();
        c.project_t_local(&dist, &mut l);
        assert_eq!(&l[..ni], &y[..ni]);
        let lh = c.lambda_hat_local(&dist);
        assert!(lh[..ni].iter().all(|&v| v == 0.0));
        let lam: Vec<f64> = l.iter().zip(&lh).map(|(a, b)| a + b).collect();
        assert!(c.feasibility(&dist, &lam) < 1e-12, "{}", c.feasibility(&dist, &lam));
        // P̃ Gᵀα = 0
        let alpha: Vec<f64> = (0..c.dim()).map(|_| lcg(&mut s)).collect();
        let mut gta = vec![0.0; n];
        c.sub_gt(&dist, &alpha, &mut gta, Coarse::local_rows(&dist), false);
        let before = norm(&gta);
        c.project(&dist, &mut gta);
        assert!(norm(&gta) < 1e-12 * before);
        // idempotent; P̃ᵀ is the adjoint of P̃: zᵀP̃y = (P̃ᵀz)ᵀy
        let mut p1 = y.clone();
        c.project(&dist, &mut p1);
        let mut p2 = p1.clone();
        c.project(&dist, &mut p2);
        assert!(p1.iter().zip(&p2).all(|(a, b)| (a - b).abs() < 1e-12 * norm(&p1)));
        let mut pz = z.clone();
        c.project_t_local(&dist, &mut pz);
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        assert!((dot(&z, &p1) - dot(&pz, &y)).abs() < 1e-12 * norm(&z) * norm(&y));
        // the orthogonal projector: G P x = 0, symmetric
        let mut py = y.clone();
        c.project_orthogonal(&dist, &mut py);
        assert!(norm(&c.g_mul(&dist, &py, false)) < 1e-12 * norm(&y));
        let mut pzo = z.clone();
        c.project_orthogonal(&dist, &mut pzo);
        assert!((dot(&z, &py) - dot(&pzo, &y)).abs() < 1e-12 * norm(&z) * norm(&y));
        // on Ker G, P̃ᵀ is the identity (the projected CG's products skip it: apply_kernel)
        let mut t = py.clone();
        c.project_t_local(&dist, &mut t);
        assert!(t.iter().zip(&py).all(|(a, b)| (a - b).abs() < 1e-12 * norm(&py)));
        // and P̃ maps F x and F x + Gᵀα alike (finish_kernel after the sum)
        let mut f1 = z.clone();
        let mut f2: Vec<f64> = z.iter().zip(&gta_raw(&c, &dist, &alpha, n)).map(|(a, b)| a + b).collect();
        c.project(&dist, &mut f1);
        c.project(&dist, &mut f2);
        assert!(f1.iter().zip(&f2).all(|(a, b)| (a - b).abs() < 1e-12 * norm(&f1).max(1.0)));
    }

    /// The explicit rows of C⁻¹ and (GGᵀ)⁻¹ give the factors' projections (to rounding), and a
    /// rank that would hold more than the limit is refused naming the key.
    #[test]
    fn explicit_inverse_rows_agree_with_the_factors() {
        let (model, d, cons) = crate::feti::seed_fixture(5, 3);
        let comm = crate::comm::SerialComm;
        let new = || build(&model, &d, &cons, Kind::Orthogonal, &comm).0;
        let dist = Distribution::new(&comm, &cons, &vec![0; d.subdomains.len()]);
        let (f, mut x) = (new(), new());
        let bytes = x.make_explicit(&dist, usize::MAX).unwrap();
        // both inverses whole on one rank
        assert_eq!(bytes, 2 * 8 * f.dim() * f.dim());
        assert!(matches!(x.chol, Some(Inverse::Explicit(_))) && matches!(x.full, Some(Inverse::Explicit(_))));
        let n = cons.layout.dim();
        let mut s = 11u64;
        let y: Vec<f64> = (0..n).map(|_| lcg(&mut s)).collect();
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let close = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max) <= 1e-12 * norm(b).max(1.0);
        for project in [Coarse::project::<crate::comm::SerialComm>, Coarse::project_orthogonal, Coarse::project_e] {
            let (mut a, mut b) = (y.clone(), y.clone());
            project(&f, &dist, &mut a);
            project(&x, &dist, &mut b);
            assert!(close(&b, &a) && a != y);
        }
        assert!(close(&x.lambda_hat_local(&dist), &f.lambda_hat_local(&dist)));
        assert!(close(&x.lambda_e_local(&dist), &f.lambda_e_local(&dist)));
        let mut small = new();
        let e = small.make_explicit(&dist, 1000).unwrap_err().to_string();
        assert!(e.contains("decomposition.coarse_solve") && e.contains("\"factor\""), "{e}");
    }

    /// Gᵀα on every row.
    fn gta_raw<C: crate::comm::Comm>(c: &Coarse, dist: &Distribution<'_, C>, alpha: &[f64], n: usize) -> Vec<f64> {
        let mut v = vec![0.0; n];
        c.sub_gt(dist, alpha, &mut v, Coarse::local_rows(dist), false);
        v.iter().map(|x| -x).collect()
    }

    /// The restricted projector: for x ∈ W (free rows, sliding pairs' t directions, E rows),
    /// Π(x − Gᵀ(GΠGᵀ)⁻¹Gx) lies in Ker G ∩ W and is idempotent.
    #[test]
    fn restricted_projector_maps_into_ker_g_on_w() {
        let (model, d, cons) = crate::feti::seed_fixture(5, 3);
        let comm = crate::comm::SerialComm;
        let (c, dist) = build(&model, &d, &cons, Kind::Oblique, &comm);
        let n = cons.layout.dim();
        let (m, ni) = (cons.layout.m, cons.e_start());
        let mut s = 9u64;
        // every third normal free, pairs alternating stick / slide / fixed
        let mut free = vec![false; ni];
        let mut slides = Vec::new();
        for i in 0..m {
            free[i] = i % 3 == 0;
            let k = m + 2 * i;
            match i % 3 {
                0 => (free[k], free[k + 1]) = (true, true),
                1 => {
                    let a = lcg(&mut s) * 3.0;
                    slides.push((k, [a.cos(), a.sin()]));
                }
                _ => {}
            }
        }
        let pi = |x: &mut Vec<f64>| {
            let mut y = x.clone();
            for r in 0..ni {
                if !free[r] {
                    y[r] = 0.0;
                }
            }
            for &(k, t) in &slides {
                let a = t[0] * x[k] + t[1] * x[k + 1];
                y[k] = a * t[0];
                y[k + 1] = a * t[1];
            }
            *x = y;
        };
        let chol = c.restricted(&dist, &free, &slides).expect("GΠGᵀ regular");
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let mut x: Vec<f64> = (0..n).map(|_| lcg(&mut s)).collect();
        pi(&mut x);
        let mut y = x.clone();
        c.project_restricted(&dist, &chol, &mut y);
        pi(&mut y);
        let gy = c.g_mul(&dist, &y, false);
        assert!(norm(&gy) < 1e-12 * norm(&x), "G y = {:e}", norm(&gy));
        let mut z = y.clone();
        c.project_restricted(&dist, &chol, &mut z);
        pi(&mut z);
        assert!(y.iter().zip(&z).all(|(a, b)| (a - b).abs() < 1e-12 * norm(&y)));
        // orthogonal: (x − y) ⊥ y
        let dot: f64 = x.iter().zip(&y).map(|(a, b)| (a - b) * b).sum();
        assert!(dot.abs() < 1e-12 * norm(&x) * norm(&y), "{dot:e}");
    }
}
