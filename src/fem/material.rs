//! Isotropic linear elasticity: Lamé constants and the 6×6 constitutive matrix.
//! Voigt order: (xx, yy, zz, xy, yz, zx), engineering shear strains.

/// Lamé constants λ, μ of an isotropic material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lame {
    /// First Lamé constant λ (stress units).
    pub lambda: f64,
    /// Shear modulus μ, the second Lamé constant (stress units).
    pub mu: f64,
}

impl Lame {
    /// From Young's modulus `e` and Poisson's ratio `nu` (−1 < ν < 1/2, E > 0).
    pub fn from_young_poisson(e: f64, nu: f64) -> Self {
        Lame { lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), mu: e / (2.0 * (1.0 + nu)) }
    }

    /// Young's modulus E = μ(3λ + 2μ)/(λ + μ).
    pub fn young(&self) -> f64 {
        self.mu * (3.0 * self.lambda + 2.0 * self.mu) / (self.lambda + self.mu)
    }

    /// σ = D ε in Voigt notation.
    pub fn stress(&self, eps: &[f64; 6]) -> [f64; 6] {
        let tr = eps[0] + eps[1] + eps[2];
        let (l, m) = (self.lambda, self.mu);
        [l * tr + 2.0 * m * eps[0], l * tr + 2.0 * m * eps[1], l * tr + 2.0 * m * eps[2], m * eps[3], m * eps[4], m * eps[5]]
    }
}

/// von Mises equivalent stress of a Voigt stress vector.
pub fn von_mises(s: &[f64; 6]) -> f64 {
    let d = (s[0] - s[1]).powi(2) + (s[1] - s[2]).powi(2) + (s[2] - s[0]).powi(2);
    (0.5 * d + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5])).sqrt()
}
