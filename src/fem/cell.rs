//! Kernels by cell and facet type: the element stiffness, the inversion check and the centre
//! stress of any [`CellKind`], and the consistent nodal weights ∫ N_a dA of any [`FacetKind`]
//! (tri3, tri6, quad4, quad8) — dispatching to the pure per-type kernels.

use super::element::{hex8_center_stress, hex8_stiffness, hex_min_jacobian, quad4_nodal_areas};
use super::material::Lame;
use super::tet::{tet10_min_jacobian, tet10_stiffness, tet10_strain, tet4_gradients, tet4_stiffness, tet4_strain};
use super::wedge::{wedge6_min_jacobian, wedge6_stiffness, wedge6_strain};
use crate::mesh::{CellKind, FacetKind};

/// An element stiffness, 3n × 3n for a cell of n nodes (DOF order 3a + i), on the stack (one
/// per element in the assembly loop: no allocation).
#[allow(clippy::large_enum_variant)]
pub enum CellMatrix {
    Hex8([[f64; 24]; 24]),
    Tet4([[f64; 12]; 12]),
    Tet10([[f64; 30]; 30]),
    Wedge6([[f64; 18]; 18]),
}

impl CellMatrix {
    /// Its size 3n and its entries row by row.
    pub fn rows(&self) -> (usize, &[f64]) {
        match self {
            CellMatrix::Hex8(k) => (24, k.as_flattened()),
            CellMatrix::Tet4(k) => (12, k.as_flattened()),
            CellMatrix::Tet10(k) => (30, k.as_flattened()),
            CellMatrix::Wedge6(k) => (18, k.as_flattened()),
        }
    }
}

fn arr<const N: usize>(x: &[[f64; 3]]) -> &[[f64; 3]; N] {
    x.try_into().expect("node count of the cell type")
}

/// The stiffness of a cell of type `kind` with node coordinates `x`.
pub fn cell_stiffness(kind: CellKind, x: &[[f64; 3]], m: Lame) -> CellMatrix {
    match kind {
        CellKind::Hex8 => CellMatrix::Hex8(hex8_stiffness(arr(x), m)),
        CellKind::Tet4 => CellMatrix::Tet4(tet4_stiffness(arr(x), m)),
        CellKind::Tet10 => CellMatrix::Tet10(tet10_stiffness(arr(x), m)),
        CellKind::Wedge6 => CellMatrix::Wedge6(wedge6_stiffness(arr(x), m)),
    }
}

/// The smallest det J over the quadrature points and corners: ≤ 0 means inverted or degenerate.
pub fn cell_min_jacobian(kind: CellKind, x: &[[f64; 3]]) -> f64 {
    match kind {
        CellKind::Hex8 => hex_min_jacobian(arr(x)),
        CellKind::Tet4 => tet4_gradients(arr(x)).1,
        CellKind::Tet10 => tet10_min_jacobian(arr(x)),
        CellKind::Wedge6 => wedge6_min_jacobian(arr(x)),
    }
}

/// The strain at the cell's centre from the nodal displacements `u`.
pub fn cell_center_strain(kind: CellKind, x: &[[f64; 3]], u: &[[f64; 3]]) -> [f64; 6] {
    match kind {
        CellKind::Hex8 => super::element::hex8_strain(arr(x), arr(u), [0.0; 3]),
        CellKind::Tet4 => tet4_strain(arr(x), arr(u)),
        CellKind::Tet10 => tet10_strain(arr(x), arr(u), [0.25; 3]),
        CellKind::Wedge6 => wedge6_strain(arr(x), arr(u), [1.0 / 3.0, 1.0 / 3.0, 0.0]),
    }
}

/// The stress at the cell's centre.
pub fn cell_center_stress(kind: CellKind, x: &[[f64; 3]], u: &[[f64; 3]], m: Lame) -> [f64; 6] {
    match kind {
        CellKind::Hex8 => hex8_center_stress(arr(x), arr(u), m),
        k => m.stress(&cell_center_strain(k, x, u)),
    }
}

/// Shape functions and their derivatives (∂/∂ξ, ∂/∂η) of a facet at reference point (ξ, η):
/// triangles on {ξ, η ≥ 0, ξ + η ≤ 1}, quadrilaterals on [−1, 1]².
pub fn facet_shape(kind: FacetKind, xi: [f64; 2]) -> (Vec<f64>, Vec<[f64; 2]>) {
    let [s, t] = xi;
    match kind {
        FacetKind::Tri3 => (vec![1.0 - s - t, s, t], vec![[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]]),
        FacetKind::Tri6 => {
            let l = [1.0 - s - t, s, t];
            let dl = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
            let mut n = vec![0.0; 6];
            let mut d = vec![[0.0; 2]; 6];
            for a in 0..3 {
                n[a] = l[a] * (2.0 * l[a] - 1.0);
                d[a] = dl[a].map(|v| (4.0 * l[a] - 1.0) * v);
            }
            for (e, (a, b)) in [(0, 1), (1, 2), (2, 0)].into_iter().enumerate() {
                n[3 + e] = 4.0 * l[a] * l[b];
                d[3 + e] = std::array::from_fn(|i| 4.0 * (dl[a][i] * l[b] + l[a] * dl[b][i]));
            }
            (n, d)
        }
        FacetKind::Quad4 => {
            let r = super::element::QUAD_REF;
            let n = r.iter().map(|c| 0.25 * (1.0 + c[0] * s) * (1.0 + c[1] * t)).collect();
            let d = r.iter().map(|c| [0.25 * c[0] * (1.0 + c[1] * t), 0.25 * (1.0 + c[0] * s) * c[1]]).collect();
            (n, d)
        }
        FacetKind::Quad8 => {
            let r = super::element::QUAD_REF;
            let mut n = vec![0.0; 8];
            let mut d = vec![[0.0; 2]; 8];
            for (a, c) in r.iter().enumerate() {
                let (p, q) = (1.0 + c[0] * s, 1.0 + c[1] * t);
                n[a] = 0.25 * p * q * (c[0] * s + c[1] * t - 1.0);
                d[a] = [0.25 * c[0] * q * (2.0 * c[0] * s + c[1] * t), 0.25 * c[1] * p * (c[0] * s + 2.0 * c[1] * t)];
            }
            // edge nodes (0,1), (1,2), (2,3), (3,0): at η = −1, ξ = 1, η = 1, ξ = −1
            n[4] = 0.5 * (1.0 - s * s) * (1.0 - t);
            d[4] = [-s * (1.0 - t), -0.5 * (1.0 - s * s)];
            n[5] = 0.5 * (1.0 + s) * (1.0 - t * t);
            d[5] = [0.5 * (1.0 - t * t), -(1.0 + s) * t];
            n[6] = 0.5 * (1.0 - s * s) * (1.0 + t);
            d[6] = [-s * (1.0 + t), 0.5 * (1.0 - s * s)];
            n[7] = 0.5 * (1.0 - s) * (1.0 - t * t);
            d[7] = [-0.5 * (1.0 - t * t), -(1.0 - s) * t];
            (n, d)
        }
    }
}

/// A quadrature rule on the facet's reference domain: degree 4 on triangles (Dunavant's six
/// points), 3 × 3 Gauss on quadrilaterals.
pub fn facet_rule(kind: FacetKind) -> Vec<([f64; 2], f64)> {
    match kind {
        FacetKind::Tri3 | FacetKind::Tri6 => {
            let (a1, b1, w1) = (0.445_948_490_915_965, 0.108_103_018_168_070, 0.223_381_589_678_011);
            let (a2, b2, w2) = (0.091_576_213_509_771, 0.816_847_572_980_459, 0.109_951_743_655_322);
            let mut v = Vec::with_capacity(6);
            for (a, b, w) in [(a1, b1, w1), (a2, b2, w2)] {
                for p in [[a, a], [b, a], [a, b]] {
                    v.push((p, 0.5 * w));
                }
            }
            v
        }
        FacetKind::Quad4 | FacetKind::Quad8 => {
            let g = [(-0.774_596_669_241_483_4, 5.0 / 9.0), (0.0, 8.0 / 9.0), (0.774_596_669_241_483_4, 5.0 / 9.0)];
            g.iter().flat_map(|&(t, wt)| g.iter().map(move |&(s, ws)| ([s, t], ws * wt))).collect()
        }
    }
}

/// The surface element's area vector ∂x/∂ξ × ∂x/∂η at a reference point (its length is the
/// area density, its direction the outward normal).
pub fn facet_area_vector(x: &[[f64; 3]], d: &[[f64; 2]]) -> [f64; 3] {
    let mut a = [0.0; 3];
    let mut b = [0.0; 3];
    for (p, g) in x.iter().zip(d) {
        for k in 0..3 {
            a[k] += g[0] * p[k];
            b[k] += g[1] * p[k];
        }
    }
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// ∫ N_a dA over a facet: the consistent nodal weights of a uniform surface density (a tri6's
/// corners get 0, its edge nodes a third of the area; a quad8's corners a negative share).
/// The area of a face (its facets' true maps) on the coordinates `x`.
pub fn face_area(face: &crate::mesh::Face, x: &[[f64; 3]]) -> f64 {
    face.facets.iter().map(|q| facet_nodal_areas(q.kind, &q.nodes().iter().map(|&v| x[v]).collect::<Vec<_>>()).iter().sum::<f64>()).sum()
}

/// quad4 as [`quad4_nodal_areas`] (2 × 2 Gauss, exact).
pub fn facet_nodal_areas(kind: FacetKind, x: &[[f64; 3]]) -> Vec<f64> {
    if kind == FacetKind::Quad4 {
        return quad4_nodal_areas(x.try_into().expect("four corners")).to_vec();
    }
    let mut w = vec![0.0; kind.len()];
    for (xi, wq) in facet_rule(kind) {
        let (n, d) = facet_shape(kind, xi);
        let c = facet_area_vector(x, &d);
        let da = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt() * wq;
        for a in 0..w.len() {
            w[a] += n[a] * da;
        }
    }
    w
}

/// The point of a facet's map at reference point `xi`.
pub fn facet_point(kind: FacetKind, x: &[[f64; 3]], xi: [f64; 2]) -> [f64; 3] {
    let n = facet_shape(kind, xi).0;
    std::array::from_fn(|k| x.iter().zip(&n).map(|(p, w)| w * p[k]).sum())
}

/// The image of the reference centre (a triangle's centroid, a quadrilateral's (0, 0)).
pub fn facet_centre(kind: FacetKind, x: &[[f64; 3]]) -> [f64; 3] {
    let xi = match kind {
        FacetKind::Tri3 | FacetKind::Tri6 => [1.0 / 3.0; 2],
        FacetKind::Quad4 | FacetKind::Quad8 => [0.0; 2],
    };
    facet_point(kind, x, xi)
}

/// The area of the part of a facet where `inside` holds: the reference domain is split in four
/// (a triangle by its edge midpoints) at least twice, and on to 2⁻⁹ of its size where the
/// region's edge crosses a part (its corners and centre disagree); each part is integrated by
/// its centre. Within about 10⁻³ of the facet's size times the cut's length.
pub fn facet_area_inside(kind: FacetKind, x: &[[f64; 3]], inside: impl Fn([f64; 3]) -> bool) -> f64 {
    const MIN_DEPTH: usize = 2;
    const MAX_DEPTH: usize = 9;
    let density = |xi: [f64; 2]| {
        let c = facet_area_vector(x, &facet_shape(kind, xi).1);
        (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()
    };
    let is_in = |xi: [f64; 2]| inside(facet_point(kind, x, xi));
    let mid = |a: [f64; 2], b: [f64; 2]| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    // a part: its corners (3 or 4) in the reference domain
    let mut stack: Vec<(Vec<[f64; 2]>, usize)> = match kind {
        FacetKind::Tri3 | FacetKind::Tri6 => vec![(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], 0)],
        FacetKind::Quad4 | FacetKind::Quad8 => vec![(vec![[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]], 0)],
    };
    let mut area = 0.0;
    while let Some((p, depth)) = stack.pop() {
        let n = p.len() as f64;
        let centre = [p.iter().map(|v| v[0]).sum::<f64>() / n, p.iter().map(|v| v[1]).sum::<f64>() / n];
        let c_in = is_in(centre);
        let uniform = depth >= MIN_DEPTH && p.iter().all(|&v| is_in(v) == c_in);
        if uniform || depth == MAX_DEPTH {
            if c_in {
                // the reference area of the part: a triangle's half cross product, a
                // parallelogram's cross product
                let cross = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
                area += density(centre) * if p.len() == 3 { 0.5 * cross.abs() } else { cross.abs() };
            }
            continue;
        }
        if p.len() == 3 {
            let (a, b, c) = (p[0], p[1], p[2]);
            let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
            for t in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
                stack.push((t.to_vec(), depth + 1));
            }
        } else {
            let m = [mid(p[0], p[1]), mid(p[1], p[2]), mid(p[2], p[3]), mid(p[3], p[0])];
            for q in [[p[0], m[0], centre, m[3]], [m[0], p[1], m[1], centre], [centre, m[1], p[2], m[2]], [m[3], centre, m[2], p[3]]] {
                stack.push((q.to_vec(), depth + 1));
            }
        }
    }
    area
}

/// The area-weighted outward normal of a facet, ∫ n dA (its length is the area).
pub fn facet_normal_area(kind: FacetKind, x: &[[f64; 3]]) -> [f64; 3] {
    let mut s = [0.0; 3];
    for (xi, wq) in facet_rule(kind) {
        let c = facet_area_vector(x, &facet_shape(kind, xi).1);
        for k in 0..3 {
            s[k] += wq * c[k];
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Shape functions: partition of unity, derivatives by finite differences, Kronecker at
    /// the nodes; nodal weights sum to the area and match the closed forms.
    #[test]
    fn facet_shapes_and_weights() {
        let nodes: [(FacetKind, Vec<[f64; 2]>); 4] = [
            (FacetKind::Tri3, vec![[0., 0.], [1., 0.], [0., 1.]]),
            (FacetKind::Tri6, vec![[0., 0.], [1., 0.], [0., 1.], [0.5, 0.], [0.5, 0.5], [0., 0.5]]),
            (FacetKind::Quad4, vec![[-1., -1.], [1., -1.], [1., 1.], [-1., 1.]]),
            (FacetKind::Quad8, vec![[-1., -1.], [1., -1.], [1., 1.], [-1., 1.], [0., -1.], [1., 0.], [0., 1.], [-1., 0.]]),
        ];
        for (kind, r) in &nodes {
            for (a, p) in r.iter().enumerate() {
                let (n, _) = facet_shape(*kind, *p);
                for (b, v) in n.iter().enumerate() {
                    assert!((v - if a == b { 1.0 } else { 0.0 }).abs() < 1e-14, "{kind:?} N{b} at node {a}");
                }
            }
            let xi = [0.21, 0.33];
            let (n, d) = facet_shape(*kind, xi);
            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            let h = 1e-6;
            for k in 0..2 {
                let mut p = xi;
                p[k] += h;
                let (np, _) = facet_shape(*kind, p);
                for a in 0..n.len() {
                    assert!(((np[a] - n[a]) / h - d[a][k]).abs() < 1e-5, "{kind:?} dN{a}/dξ{k}");
                }
            }
            // a flat facet scaled by 2 in x, 3 in y: area 6·(reference area)
            let x: Vec<[f64; 3]> = r.iter().map(|p| [2.0 * p[0], 3.0 * p[1], 1.0]).collect();
            let w = facet_nodal_areas(*kind, &x);
            let area = if kind.corners() == 3 { 3.0 } else { 24.0 };
            assert!((w.iter().sum::<f64>() - area).abs() < 1e-12, "{kind:?}");
            let nrm = facet_normal_area(*kind, &x);
            assert!((nrm[2] - area).abs() < 1e-12 && nrm[0].abs() < 1e-14);
            match kind {
                FacetKind::Tri3 => assert!(w.iter().all(|v| (v - 1.0).abs() < 1e-14)),
                FacetKind::Tri6 => assert!(w[..3].iter().all(|v| v.abs() < 1e-14) && w[3..].iter().all(|v| (v - 1.0).abs() < 1e-14)),
                FacetKind::Quad8 => assert!(w[..4].iter().all(|v| (v + 2.0).abs() < 1e-13) && w[4..].iter().all(|v| (v - 8.0).abs() < 1e-13)),
                FacetKind::Quad4 => assert!(w.iter().all(|v| (v - 6.0).abs() < 1e-14)),
            }
        }
    }
}
