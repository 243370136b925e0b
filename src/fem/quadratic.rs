//! The quadratic hexahedra and wedge: hex20 (serendipity), hex27 (triquadratic Lagrange) on
//! [−1, 1]³ and wedge15 (serendipity prism) on {ξ, η ≥ 0, ξ + η ≤ 1} × [−1, 1], node orders
//! Gmsh's (see [`crate::mesh::cell`]). Shape functions and reference derivatives as pure
//! functions of the reference point; stiffness with 3 × 3 × 3 Gauss on the hexahedra and the
//! degree-4 six-point triangle rule × 3-point Gauss on the wedge (exact for the stiffness of
//! an affine cell); strain at a point; the smallest det J over the rule's points and nodes.

use super::element::{add_stiffness, physical_gradients, strain};
use super::facet::{facet_rule, gauss3};
use super::material::Lame;
use crate::mesh::cell::{HEX20_EDGES, HEX27_FACES, WEDGE15_EDGES};
use crate::mesh::FacetKind;

/// Reference coordinates of the hex8 corners (Gmsh's = VTK's order).
const CORNERS: [[f64; 3]; 8] =
    [[-1.0, -1.0, -1.0], [1.0, -1.0, -1.0], [1.0, 1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [1.0, 1.0, 1.0], [-1.0, 1.0, 1.0]];

/// Reference coordinates of the hex27's nodes (the hex20's are the first 20).
pub fn hex27_ref() -> [[f64; 3]; 27] {
    let mut r = [[0.0; 3]; 27];
    r[..8].copy_from_slice(&CORNERS);
    for (e, [a, b]) in HEX20_EDGES.iter().enumerate() {
        r[8 + e] = std::array::from_fn(|k| 0.5 * (CORNERS[*a][k] + CORNERS[*b][k]));
    }
    for (f, [a, _, c, _]) in HEX27_FACES.iter().enumerate() {
        r[20 + f] = std::array::from_fn(|k| 0.5 * (CORNERS[*a][k] + CORNERS[*c][k]));
    }
    r
}

/// Reference coordinates of the wedge15's nodes (ξ, η, ζ).
pub fn wedge15_ref() -> [[f64; 3]; 15] {
    let c = [[0.0, 0.0, -1.0], [1.0, 0.0, -1.0], [0.0, 1.0, -1.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]];
    let mut r = [[0.0; 3]; 15];
    r[..6].copy_from_slice(&c);
    for (e, [a, b]) in WEDGE15_EDGES.iter().enumerate() {
        r[6 + e] = std::array::from_fn(|k| 0.5 * (c[*a][k] + c[*b][k]));
    }
    r
}

/// Hex20 shape functions and reference derivatives at `xi`: corners
/// ⅛(1 + ξξ_a)(1 + ηη_a)(1 + ζζ_a)(ξξ_a + ηη_a + ζζ_a − 2), an edge node (its coordinate k
/// zero) ¼(1 − x_k²) Π_{j≠k}(1 + x_j a_j).
pub fn hex20_shape(xi: [f64; 3]) -> ([f64; 20], [[f64; 3]; 20]) {
    let r = hex27_ref();
    let mut n = [0.0; 20];
    let mut d = [[0.0; 3]; 20];
    for a in 0..20 {
        let ra = r[a];
        let f: [f64; 3] = std::array::from_fn(|k| 1.0 + ra[k] * xi[k]);
        if a < 8 {
            let s = ra[0] * xi[0] + ra[1] * xi[1] + ra[2] * xi[2];
            n[a] = 0.125 * f[0] * f[1] * f[2] * (s - 2.0);
            for k in 0..3 {
                let (j, l) = ((k + 1) % 3, (k + 2) % 3);
                d[a][k] = 0.125 * ra[k] * f[j] * f[l] * (s - 2.0 + f[k]);
            }
        } else {
            let k = (0..3).find(|&k| ra[k] == 0.0).expect("an edge node has one zero coordinate");
            let (j, l) = ((k + 1) % 3, (k + 2) % 3);
            let b = 1.0 - xi[k] * xi[k];
            n[a] = 0.25 * b * f[j] * f[l];
            d[a][k] = -0.5 * xi[k] * f[j] * f[l];
            d[a][j] = 0.25 * b * ra[j] * f[l];
            d[a][l] = 0.25 * b * f[j] * ra[l];
        }
    }
    (n, d)
}

/// The quadratic Lagrange polynomial on {−1, 0, 1} of node coordinate `a` and its derivative.
fn lagrange1(a: f64, s: f64) -> (f64, f64) {
    if a < 0.0 {
        (0.5 * s * (s - 1.0), s - 0.5)
    } else if a > 0.0 {
        (0.5 * s * (s + 1.0), s + 0.5)
    } else {
        (1.0 - s * s, -2.0 * s)
    }
}

/// Hex27 shape functions (products of the 1D quadratic Lagrange polynomials) and reference
/// derivatives at `xi`.
pub fn hex27_shape(xi: [f64; 3]) -> ([f64; 27], [[f64; 3]; 27]) {
    let r = hex27_ref();
    let mut n = [0.0; 27];
    let mut d = [[0.0; 3]; 27];
    for a in 0..27 {
        let l: [(f64, f64); 3] = std::array::from_fn(|k| lagrange1(r[a][k], xi[k]));
        n[a] = l[0].0 * l[1].0 * l[2].0;
        d[a] = [l[0].1 * l[1].0 * l[2].0, l[0].0 * l[1].1 * l[2].0, l[0].0 * l[1].0 * l[2].1];
    }
    (n, d)
}

/// Wedge15 shape functions and reference derivatives at `xi`, with L = (1 − ξ − η, ξ, η):
/// corners ½L_a[(2L_a − 1)(1 + ζζ_a) − (1 − ζ²)], triangle edge nodes 2L_aL_b(1 + ζζ_e),
/// vertical edge nodes L_a(1 − ζ²).
pub fn wedge15_shape(xi: [f64; 3]) -> ([f64; 15], [[f64; 3]; 15]) {
    let l = [1.0 - xi[0] - xi[1], xi[0], xi[1]];
    let z = xi[2];
    // derivatives by (L0, L1, L2, ζ), mapped to (ξ, η, ζ) after
    let mut n = [0.0; 15];
    let mut dl = [[0.0; 4]; 15];
    for c in 0..6 {
        let (a, za) = (c % 3, if c < 3 { -1.0 } else { 1.0 });
        let h = 1.0 + z * za;
        let q = 1.0 - z * z;
        n[c] = 0.5 * l[a] * ((2.0 * l[a] - 1.0) * h - q);
        dl[c][a] = 0.5 * ((4.0 * l[a] - 1.0) * h - q);
        dl[c][3] = 0.5 * l[a] * ((2.0 * l[a] - 1.0) * za + 2.0 * z);
    }
    for (e, [p, q]) in WEDGE15_EDGES.iter().enumerate() {
        let a = 6 + e;
        let (lp, lq) = (p % 3, q % 3);
        if lp == lq {
            // vertical edge
            n[a] = l[lp] * (1.0 - z * z);
            dl[a][lp] = 1.0 - z * z;
            dl[a][3] = -2.0 * z * l[lp];
        } else {
            let ze = if *p < 3 { -1.0 } else { 1.0 };
            let h = 1.0 + z * ze;
            n[a] = 2.0 * l[lp] * l[lq] * h;
            dl[a][lp] = 2.0 * l[lq] * h;
            dl[a][lq] = 2.0 * l[lp] * h;
            dl[a][3] = 2.0 * l[lp] * l[lq] * ze;
        }
    }
    let d = dl.map(|g| [g[1] - g[0], g[2] - g[0], g[3]]);
    (n, d)
}

/// The 27 points of 3 × 3 × 3 Gauss on [−1, 1]³ and their weights.
pub fn hex_rule_27() -> Vec<([f64; 3], f64)> {
    let g = gauss3();
    let mut v = Vec::with_capacity(27);
    for &(z, wz) in &g {
        for &(y, wy) in &g {
            for &(x, wx) in &g {
                v.push(([x, y, z], wx * wy * wz));
            }
        }
    }
    v
}

/// The 18 points of the wedge rule: the six-point degree-4 triangle rule times 3-point Gauss
/// in ζ; the weights sum to the reference volume 1.
pub fn wedge_rule_18() -> Vec<([f64; 3], f64)> {
    let tri = facet_rule(FacetKind::Tri6);
    gauss3().iter().flat_map(|&(z, wz)| tri.iter().map(move |&(p, w)| ([p[0], p[1], z], w * wz))).collect()
}

/// Which quadratic cell: its shape functions, rule and reference nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quadratic {
    /// 20-node serendipity hexahedron.
    Hex20,
    /// 27-node Lagrange hexahedron.
    Hex27,
    /// 15-node serendipity wedge.
    Wedge15,
}

impl Quadratic {
    /// Number of nodes.
    #[allow(clippy::len_without_is_empty)]
    pub fn len(self) -> usize {
        match self {
            Quadratic::Hex20 => 20,
            Quadratic::Hex27 => 27,
            Quadratic::Wedge15 => 15,
        }
    }

    /// Shape functions and reference derivatives at `xi` (vectors of [`Self::len`]).
    pub fn shape(self, xi: [f64; 3]) -> (Vec<f64>, Vec<[f64; 3]>) {
        match self {
            Quadratic::Hex20 => {
                let (n, d) = hex20_shape(xi);
                (n.to_vec(), d.to_vec())
            }
            Quadratic::Hex27 => {
                let (n, d) = hex27_shape(xi);
                (n.to_vec(), d.to_vec())
            }
            Quadratic::Wedge15 => {
                let (n, d) = wedge15_shape(xi);
                (n.to_vec(), d.to_vec())
            }
        }
    }

    /// The stiffness quadrature rule.
    pub fn rule(self) -> Vec<([f64; 3], f64)> {
        match self {
            Quadratic::Hex20 | Quadratic::Hex27 => hex_rule_27(),
            Quadratic::Wedge15 => wedge_rule_18(),
        }
    }

    /// Reference coordinates of the nodes.
    pub fn nodes(self) -> Vec<[f64; 3]> {
        match self {
            Quadratic::Hex20 => hex27_ref()[..20].to_vec(),
            Quadratic::Hex27 => hex27_ref().to_vec(),
            Quadratic::Wedge15 => wedge15_ref().to_vec(),
        }
    }

    /// Physical gradients and det J at `xi` of the cell with nodes `x`.
    pub fn gradients(self, x: &[[f64; 3]], xi: [f64; 3]) -> (Vec<[f64; 3]>, f64) {
        let d = self.shape(xi).1;
        match self {
            Quadratic::Hex20 => grad::<20>(x, &d),
            Quadratic::Hex27 => grad::<27>(x, &d),
            Quadratic::Wedge15 => grad::<15>(x, &d),
        }
    }

    /// The stiffness, 3n × 3n row by row (DOF order 3a + i).
    pub fn stiffness(self, x: &[[f64; 3]], m: Lame) -> Vec<f64> {
        let n = 3 * self.len();
        let mut k = vec![0.0; n * n];
        for (xi, w) in self.rule() {
            let (g, det) = self.gradients(x, xi);
            add_stiffness(&g, det * w, m, |r, c, v| k[r * n + c] += v);
        }
        k
    }

    /// Smallest det J over the quadrature points and the nodes.
    pub fn min_jacobian(self, x: &[[f64; 3]]) -> f64 {
        self.rule().into_iter().map(|p| p.0).chain(self.nodes()).map(|xi| self.gradients(x, xi).1).fold(f64::INFINITY, f64::min)
    }

    /// Strain at `xi` from the nodal displacements `u`.
    pub fn strain(self, x: &[[f64; 3]], u: &[[f64; 3]], xi: [f64; 3]) -> [f64; 6] {
        strain(&self.gradients(x, xi).0, u)
    }

    /// The reference centre.
    pub fn centre(self) -> [f64; 3] {
        match self {
            Quadratic::Hex20 | Quadratic::Hex27 => [0.0; 3],
            Quadratic::Wedge15 => [1.0 / 3.0, 1.0 / 3.0, 0.0],
        }
    }
}

fn grad<const N: usize>(x: &[[f64; 3]], d: &[[f64; 3]]) -> (Vec<[f64; 3]>, f64) {
    let x: &[[f64; 3]; N] = x.try_into().expect("node count of the cell type");
    let d: &[[f64; 3]; N] = d.try_into().expect("node count of the cell type");
    let (g, det) = physical_gradients(x, d);
    (g.to_vec(), det)
}

#[cfg(test)]
#[path = "quadratic_tests.rs"]
mod tests;
