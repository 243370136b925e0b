//! The TFETI dual operator behind [`DualOperator`]: A = P̃FP̃ᵀ with F = B K⁺ Bᵀ applied
//! matrix-free (one K_s⁺ solve per subdomain of this rank, one sum over the ranks) and the
//! right-hand side b̃ = P̃(d̃ − Fλ̂), d̃ = B K⁺ f − c (DESIGN §2). The solvers minimize
//! ½yᵀAy − yᵀb̃ over Y = R^{n_E} × Λ; [`TfetiDual::recover`] maps y back to λ = λ̂ + P̃ᵀy, the
//! rigid-body amplitudes α = C⁻¹G_E(c_E − B_E ũ) and u_s = ũ_s + R_sα_s, ũ = K⁺(f − Bᵀλ).
//! The gradient the solvers see is P̃(Fλ − d̃); its contact part is −(Bu − c)_I, as in the
//! monolithic dual, so the contact status and KKT residuals read the same.

use super::coarse::Coarse;
use super::constraints::Constraints;
use super::subdomain::{SubdomainSystem, NR};
use crate::comm::Comm;
use crate::dual::{gather_rows, scatter_rows, DualOperator, Layout, ProductCounter};

/// A subdomain of this rank with its B entries (row, local DOF, coefficient).
pub struct LocalSubdomain {
    pub sys: SubdomainSystem,
    pub rows: Vec<(usize, usize, f64)>,
}

/// A = P̃ F P̃ᵀ over the subdomains of all ranks.
pub struct TfetiDual<'c, C: Comm> {
    comm: &'c C,
    pub layout: Layout,
    pub subs: Vec<LocalSubdomain>,
    pub coarse: Coarse,
    c: Vec<f64>,
    /// λ̂ = (G_Eᵀ C⁻¹ e, 0): Gλ̂ = e, λ̂_I = 0.
    pub lambda_hat: Vec<f64>,
    /// d̃ − Fλ̂ (before projection): the right-hand side once λ = λ̂ + λ̃.
    pub d_hat: Vec<f64>,
    counter: ProductCounter,
}

/// What [`TfetiDual::recover`] returns.
pub struct Recovered {
    /// λ = λ̂ + P̃ᵀy.
    pub lambda: Vec<f64>,
    /// α, six per subdomain (all subdomains).
    pub alpha: Vec<f64>,
    /// u_s for each local subdomain (3·n_s values).
    pub u: Vec<Vec<f64>>,
    /// f_s − B_sᵀλ for each local subdomain.
    pub rhs: Vec<Vec<f64>>,
    /// c − Bu for every multiplier: the contact rows' gap (the contact part of the gradient),
    /// and what the E rows leave unsatisfied.
    pub gap: Vec<f64>,
}

impl<'c, C: Comm> TfetiDual<'c, C> {
    /// The operator over this rank's factorized subdomains `subs` (their global indices in
    /// `sys.index`), and b̃.
    pub fn new(comm: &'c C, cons: &Constraints, subs: Vec<SubdomainSystem>, coarse: Coarse) -> (Self, Vec<f64>) {
        let subs = subs.into_iter().map(|sys| LocalSubdomain { rows: cons.rows[sys.index].clone(), sys }).collect();
        let n = cons.layout.dim();
        let lambda_hat = coarse.lambda_hat(n);
        let mut dual =
            TfetiDual { comm, layout: cons.layout, subs, coarse, c: cons.c.clone(), lambda_hat, d_hat: vec![], counter: ProductCounter::default() };
        // d̃ − Fλ̂ = B K⁺ (f − Bᵀλ̂) − c
        let mut b = vec![0.0; n];
        let z = dual.pinv_of_rhs(&dual.lambda_hat);
        dual.gather(&z, &mut b);
        b.iter_mut().zip(&dual.c).for_each(|(bi, ci)| *bi -= ci);
        dual.d_hat = b.clone();
        dual.coarse.project(&mut b);
        (dual, b)
    }

    /// Bᵀ_s x for each local subdomain.
    fn scatter(&self, x: &[f64]) -> Vec<Vec<f64>> {
        self.subs.iter().map(|s| scatter_rows(&s.rows, x, s.sys.ndof())).collect()
    }

    /// y = Σ over subdomains and ranks of B_s z_s.
    fn gather(&self, z: &[Vec<f64>], y: &mut [f64]) {
        gather_rows(self.comm, self.subs.iter().zip(z).map(|(s, zs)| (s.rows.as_slice(), zs.as_slice())), y);
    }

    /// z_s ← K_s⁺ z_s for each local subdomain.
    fn pinv_all(&self, z: &mut [Vec<f64>]) {
        for (s, zs) in self.subs.iter().zip(z) {
            s.sys.pinv_in_place(zs);
        }
    }

    /// K_s⁺(f_s − B_sᵀλ) for each local subdomain.
    fn pinv_of_rhs(&self, lambda: &[f64]) -> Vec<Vec<f64>> {
        let mut z = self.rhs_of(lambda);
        self.pinv_all(&mut z);
        z
    }

    /// f_s − B_sᵀλ for each local subdomain.
    fn rhs_of(&self, lambda: &[f64]) -> Vec<Vec<f64>> {
        let mut z = self.scatter(lambda);
        for (s, zs) in self.subs.iter().zip(&mut z) {
            zs.iter_mut().zip(&s.sys.f).for_each(|(v, f)| *v = f - *v);
        }
        z
    }

    /// y = F x (not counted).
    pub(crate) fn apply_f(&self, x: &[f64], y: &mut [f64]) {
        let mut z = self.scatter(x);
        self.pinv_all(&mut z);
        self.gather(&z, y);
    }

    /// λ = λ̂ + P̃ᵀy.
    pub fn lambda_of(&self, y: &[f64]) -> Vec<f64> {
        let mut l = y.to_vec();
        self.coarse.project_t(&mut l);
        l.iter_mut().zip(&self.lambda_hat).for_each(|(a, b)| *a += b);
        l
    }

    /// λ, α and u from the solvers' y.
    pub fn recover(&self, y: &[f64]) -> Recovered {
        self.recover_lambda(self.lambda_of(y))
    }

    /// α and u from a feasible λ (Gλ = e).
    fn recover_lambda(&self, lambda: Vec<f64>) -> Recovered {
        let rhs = self.rhs_of(&lambda);
        let mut u: Vec<Vec<f64>> = rhs.clone();
        self.pinv_all(&mut u);
        // w = c − B ũ; only its E part enters α
        let mut w = vec![0.0; self.layout.dim()];
        self.gather(&u, &mut w);
        w.iter_mut().zip(&self.c).for_each(|(a, c)| *a = c - *a);
        let alpha = self.coarse.alpha(&w);
        for (s, us) in self.subs.iter().zip(&mut u) {
            let i = s.sys.index;
            s.sys.add_r_mul(&alpha[NR * i..NR * (i + 1)], us);
        }
        let mut gap = vec![0.0; self.layout.dim()];
        self.gather(&u, &mut gap);
        gap.iter_mut().zip(&self.c).for_each(|(a, c)| *a = c - *a);
        Recovered { lambda, alpha, u, rhs, gap }
    }
}

impl<C: Comm> DualOperator for TfetiDual<'_, C> {
    fn dim(&self) -> usize {
        self.layout.dim()
    }

    fn apply(&self, x: &[f64], y: &mut [f64]) {
        self.counter.tick();
        let mut w = x.to_vec();
        self.coarse.project_t(&mut w);
        self.apply_f(&w, y);
        self.coarse.project(y);
    }

    fn products(&self) -> usize {
        self.counter.get()
    }
}
