//! Λ = R₊ᵐ × Π_i Λτ,ᵢ × R^free: the product of the contact pairs' blocks ([`HalfLine`] for
//! λν,ᵢ, a [`TangentSet`] for λ̄τ,ᵢ) and the unconstrained multipliers λ_E of TFETI (always
//! free), on the multiplier layout of [`Layout`]. Provides P_Λ, the largest
//! feasible step, the reduced gradient r̃_ρ(λ) = (λ − P_Λ(λ − ρ r))/ρ and the active sets (12)–(13).

use super::sets::{ConvexSet, HalfLine, TangentSet};

/// Layout of the multipliers: λ = (λν ∈ Rᵐ, λτ ∈ R²ᵐ, λ_E ∈ R^free), λτ absent when
/// frictionless; pair i owns λν\[i\] and λτ\[2i\], λτ\[2i+1\]. λ_E are the unconstrained
/// multipliers (TFETI's gluing and Dirichlet rows; none in the monolithic dual).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Number of contact pairs m.
    pub m: usize,
    /// Whether the pairs carry tangential multipliers λτ.
    pub friction: bool,
    /// Number of unconstrained multipliers λ_E.
    pub free: usize,
}

impl Layout {
    /// The contact multipliers only.
    pub fn contact(m: usize, friction: bool) -> Self {
        Layout { m, friction, free: 0 }
    }

    /// Number of contact multipliers (λν and λτ): the free ones start here.
    pub fn contact_dim(&self) -> usize {
        if self.friction {
            3 * self.m
        } else {
            self.m
        }
    }

    /// Length of λ: contact multipliers and λ_E.
    pub fn dim(&self) -> usize {
        self.contact_dim() + self.free
    }
    /// Index of λν,ᵢ.
    pub fn normal(&self, i: usize) -> usize {
        i
    }
    /// Index of the k-th tangential component of pair i (k = 0, 1).
    pub fn tangent(&self, i: usize, k: usize) -> usize {
        debug_assert!(self.friction);
        self.m + 2 * i + k
    }
}

/// The constraint set of the dual contact problem.
#[derive(Clone, Debug)]
pub struct Lambda {
    /// Layout of the multipliers.
    pub layout: Layout,
    /// One tangential set per pair (empty when frictionless).
    pub tangent: Vec<TangentSet>,
}

/// Active/inactive sets at λ (paper (12)–(13)) as a free mask over the components.
#[derive(Clone, Debug, Default)]
pub struct ActiveSets {
    /// Components CG may move: active normals and both components of sticking pairs.
    pub free: Vec<bool>,
    /// |A_ν|: pairs in contact.
    pub normal_active: usize,
    /// |A_ν ∩ A_τ|: pairs in contact that stick (for the counters; CG's mask is `free`).
    pub stick: usize,
    /// |A_ν ∩ I_τ|: pairs in contact that slide.
    pub slip: usize,
}

impl Lambda {
    /// Λ of `m` pairs: half-lines only when `tangent` is None (frictionless), else one tangential
    /// set per pair.
    pub fn new(m: usize, tangent: Option<Vec<TangentSet>>) -> Self {
        match tangent {
            Some(t) => {
                assert_eq!(t.len(), m, "one tangential set per pair");
                Lambda { layout: Layout::contact(m, true), tangent: t }
            }
            None => Lambda { layout: Layout::contact(m, false), tangent: vec![] },
        }
    }

    /// Only unconstrained components (TFETI without contact): Λ = R^free.
    pub fn unconstrained(free: usize) -> Self {
        Lambda { layout: Layout { m: 0, friction: false, free }, tangent: vec![] }
    }

    /// The blocks of the pairs `pairs` (ascending) only: a rank's part of Λ when the dual vectors
    /// are distributed.
    pub fn restrict(&self, pairs: &[usize]) -> Self {
        let layout = Layout { m: pairs.len(), friction: self.layout.friction, free: 0 };
        let tangent = if layout.friction { pairs.iter().map(|&i| self.tangent[i]).collect() } else { vec![] };
        Lambda { layout, tangent }
    }

    /// The same set with `free` unconstrained components appended (λ_E).
    pub fn with_free(mut self, free: usize) -> Self {
        self.layout.free = free;
        self
    }

    /// Index range of the unconstrained components.
    pub fn free_range(&self) -> std::ops::Range<usize> {
        self.layout.contact_dim()..self.layout.dim()
    }

    fn pair(&self, v: &[f64], i: usize) -> [f64; 2] {
        let k = self.layout.tangent(i, 0);
        [v[k], v[k + 1]]
    }

    /// out = P_Λ(y).
    pub fn project(&self, y: &[f64], out: &mut [f64]) {
        let m = self.layout.m;
        for i in 0..m {
            HalfLine.project(&y[i..i + 1], &mut out[i..i + 1]);
        }
        for (i, s) in self.tangent.iter().enumerate() {
            let k = self.layout.tangent(i, 0);
            s.project(&y[k..k + 2], &mut out[k..k + 2]);
        }
        let e = self.free_range();
        out[e.clone()].copy_from_slice(&y[e]);
    }

    /// Whether x ∈ Λ up to `tol` per block.
    pub fn contains(&self, x: &[f64], tol: f64) -> bool {
        (0..self.layout.m).all(|i| HalfLine.contains(&x[i..i + 1], tol)) && self.tangent.iter().enumerate().all(|(i, s)| s.contains(&self.pair(x, i), tol))
    }

    /// Largest α ≥ 0 with x − α d ∈ Λ (x ∈ Λ).
    pub fn max_step(&self, x: &[f64], d: &[f64]) -> f64 {
        let mut a = f64::INFINITY;
        for i in 0..self.layout.m {
            if d[i] != 0.0 {
                a = a.min(HalfLine.max_step(&x[i..i + 1], &d[i..i + 1]));
            }
        }
        for (i, s) in self.tangent.iter().enumerate() {
            let dd = self.pair(d, i);
            if dd != [0.0, 0.0] {
                a = a.min(s.max_step(&self.pair(x, i), &dd));
            }
        }
        a
    }

    /// out = r̃_ρ(λ) = (λ − P_Λ(λ − ρ r))/ρ.
    pub fn reduced_gradient(&self, lambda: &[f64], r: &[f64], rho: f64, out: &mut [f64]) {
        let y: Vec<f64> = lambda.iter().zip(r).map(|(l, g)| l - rho * g).collect();
        self.project(&y, out);
        for (o, l) in out.iter_mut().zip(lambda) {
            *o = (l - *o) / rho;
        }
    }

    /// The sets (12)–(13) at λ with gradient r.
    pub fn active_sets(&self, lambda: &[f64], r: &[f64], rho: f64) -> ActiveSets {
        self.active_sets_with(lambda, r, rho, None)
    }

    /// The sets (12)–(13) with ρᵢ = `normal_rho[i]` in the normal rows' decision λᵢ − ρᵢrᵢ ≥ 0
    /// (ρ when None; the tangential components keep ρ).
    pub fn active_sets_with(&self, lambda: &[f64], r: &[f64], rho: f64, normal_rho: Option<&[f64]>) -> ActiveSets {
        let n = self.layout.dim();
        let mut s = ActiveSets { free: vec![false; n], ..Default::default() };
        s.free[self.free_range()].fill(true);
        let rho_n = |i: usize| normal_rho.map_or(rho, |v| v[i]);
        for i in 0..self.layout.m {
            if lambda[i] - rho_n(i) * r[i] >= 0.0 {
                s.free[i] = true;
                s.normal_active += 1;
            }
        }
        for (i, set) in self.tangent.iter().enumerate() {
            let k = self.layout.tangent(i, 0);
            let y = [lambda[k] - rho * r[k], lambda[k + 1] - rho * r[k + 1]];
            // an open pair's tangential state is not counted (the Tresca bound acts there too)
            let closed = lambda[i] - rho_n(i) * r[i] >= 0.0;
            if set.is_outside(&y) {
                s.slip += usize::from(closed);
            } else {
                s.free[k] = true;
                s.free[k + 1] = true;
                s.stick += usize::from(closed);
            }
        }
        s
    }
}

/// A slant derivative D of P_Λ at a point y: block-diagonal, a 0/1 per normal component, a
/// 2×2 block (row-major) per tangential pair (identity inside the set, the ψ° of the set
/// outside) and the identity on the unconstrained components.
#[derive(Clone, Debug)]
pub struct SlantDerivative {
    layout: Layout,
    pub normal: Vec<f64>,
    pub tangent: Vec<[f64; 4]>,
}

impl SlantDerivative {
    /// x ← D x.
    pub fn apply_in_place(&self, x: &mut [f64]) {
        for (i, d) in self.normal.iter().enumerate() {
            x[i] *= d;
        }
        for (i, d) in self.tangent.iter().enumerate() {
            let k = self.layout.tangent(i, 0);
            let (a, b) = (x[k], x[k + 1]);
            x[k] = d[0] * a + d[1] * b;
            x[k + 1] = d[2] * a + d[3] * b;
        }
    }
}

impl Lambda {
    /// The slant derivative of P_Λ at y.
    pub fn slant(&self, y: &[f64]) -> SlantDerivative {
        let m = self.layout.m;
        let mut normal = vec![0.0; m];
        for i in 0..m {
            HalfLine.slant(&y[i..i + 1], &mut normal[i..i + 1]);
        }
        let tangent = self
            .tangent
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let k = self.layout.tangent(i, 0);
                let mut d = [0.0; 4];
                s.slant(&y[k..k + 2], &mut d);
                d
            })
            .collect();
        SlantDerivative { layout: self.layout, normal, tangent }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// λᵢ − ρᵢrᵢ ≥ 0 decides each normal row with its own ρᵢ: row 0 (λ 1, r 0.5) is active at
    /// ρ = 1 and fixed at ρ₀ = 4; row 1 (λ 0, r −1) is active either way; the tangential pair of
    /// row 0 is counted only while the row is closed.
    #[test]
    fn a_per_row_rho_decides_each_normal_row() {
        let set = Lambda::new(2, Some(vec![TangentSet::Disc(crate::qp::sets::Disc::new(1.0)); 2]));
        let lambda = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let r = [0.5, -1.0, 0.0, 0.0, 0.0, 0.0];
        let scalar = set.active_sets(&lambda, &r, 1.0);
        assert_eq!((scalar.normal_active, scalar.stick), (2, 2));
        assert_eq!(&scalar.free[..2], &[true, true]);
        let per_row = set.active_sets_with(&lambda, &r, 1.0, Some(&[4.0, 1.0]));
        assert_eq!((per_row.normal_active, per_row.stick), (1, 1));
        assert_eq!(&per_row.free[..2], &[false, true]);
    }
}
