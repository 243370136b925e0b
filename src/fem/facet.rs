//! Reference facets, mesh-free: the tri3, quad4, tri6, quad8 and quad9 shape functions on their
//! reference domains, the facet quadrature rules, the facet maps' area vectors and the
//! integrals built on them (consistent nodal weights, area-weighted normal, the area inside a
//! region), plus the small `[f64; 3]` algebra they and the contact code share. Used by the
//! mortar coupling ([`crate::contact::mortar`]), the cell/facet dispatch ([`super::cell`]) and
//! the element kernels ([`super::element`]); it works on plain coordinates and knows only the
//! facet's type ([`FacetKind`]).
//!
//! Node order (corners first, right-hand rule = outward normal): tri6's edge nodes (0,1),
//! (1,2), (2,0); quad8's (0,1), (1,2), (2,3), (3,0), quad9's the same and its centre. Triangles live on {ξ, η ≥ 0, ξ + η ≤ 1},
//! quadrilaterals on [−1, 1]².
//!
//! **Two rule families.** [`facet_rule`] (triangles Dunavant's 6 points, degree 4;
//! quadrilaterals 3 × 3 Gauss, η outer) serves the loads, nodal weights and normals;
//! [`fine_rule`] (triangles the 7-point degree-5 rule; quadrilaterals 4 × 4 Gauss, ξ outer) the
//! mortar's dual basis and facet areas; [`quad4_nodal_areas`] uses 2 × 2 Gauss (η outer). They
//! are kept apart on purpose: each caller's points, weights and summation order are those it
//! had before they were gathered here, so its results are unchanged bit for bit.

use crate::mesh::FacetKind;

/// The most nodes of a facet (quad9).
pub const MAX_NODES: usize = 9;

type V2 = [f64; 2];
type V3 = [f64; 3];

/// Reference coordinates of the quad4/quad8 corners, counter-clockwise from (−1, −1).
pub const QUAD_REF: [V2; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// Gauss points of the two-point rule on [−1, 1] (weights 1).
pub const GAUSS2: [f64; 2] = [-0.577_350_269_189_625_8, 0.577_350_269_189_625_8];

// ---------------------------------------------------------------------------------------------
// small [f64; 3] algebra

pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

pub fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}

pub fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// y += s x.
pub fn axpy(y: &mut V3, s: f64, x: V3) {
    for k in 0..3 {
        y[k] += s * x[k];
    }
}

// ---------------------------------------------------------------------------------------------
// reference facets

/// The facet type with `nodes` nodes (3 tri3, 4 quad4, 6 tri6, 8 quad8, 9 quad9).
pub fn kind_of(nodes: usize) -> Option<FacetKind> {
    match nodes {
        3 => Some(FacetKind::Tri3),
        4 => Some(FacetKind::Quad4),
        6 => Some(FacetKind::Tri6),
        8 => Some(FacetKind::Quad8),
        9 => Some(FacetKind::Quad9),
        _ => None,
    }
}

/// Triangle (tri3, tri6) or quadrilateral (quad4, quad8, quad9).
pub fn is_tri(kind: FacetKind) -> bool {
    matches!(kind, FacetKind::Tri3 | FacetKind::Tri6)
}

/// (edge node, its two corners) of a quadratic facet; empty for linear ones.
pub fn edges(kind: FacetKind) -> &'static [(usize, usize, usize)] {
    match kind {
        FacetKind::Tri3 | FacetKind::Quad4 => &[],
        FacetKind::Tri6 => &[(3, 0, 1), (4, 1, 2), (5, 2, 0)],
        FacetKind::Quad8 | FacetKind::Quad9 => &[(4, 0, 1), (5, 1, 2), (6, 2, 3), (7, 3, 0)],
    }
}

/// The reference centre: a triangle's centroid, a quadrilateral's (0, 0).
pub fn centre(kind: FacetKind) -> V2 {
    if is_tri(kind) {
        [1.0 / 3.0, 1.0 / 3.0]
    } else {
        [0.0, 0.0]
    }
}

/// Shape function values φ_a and reference derivatives [∂φ_a/∂ξ, ∂φ_a/∂η] at one point; the
/// entries past the facet's node count are 0.
pub struct Shape {
    pub phi: [f64; MAX_NODES],
    pub dphi: [V2; MAX_NODES],
}

/// The shape functions at `xi`: tri3 λ, tri6 corners λ(2λ − 1) and edges 4λ_aλ_b with
/// λ = (1 − ξ − η, ξ, η); quad4 bilinear; quad8 serendipity (corners as [`QUAD_REF`], then the
/// edge midpoints in the order of [`edges`]); quad9 the biquadratic Lagrange products (corners,
/// edge midpoints, centre).
pub fn shape(kind: FacetKind, xi: V2) -> Shape {
    let mut s = Shape { phi: [0.0; MAX_NODES], dphi: [[0.0; 2]; MAX_NODES] };
    match kind {
        FacetKind::Tri3 | FacetKind::Tri6 => tri_shape(kind, xi, &mut s),
        FacetKind::Quad4 => quad4_shape(xi, &mut s),
        FacetKind::Quad8 => quad8_shape(xi, &mut s),
        FacetKind::Quad9 => quad9_shape(xi, &mut s),
    }
    s
}

fn tri_shape(kind: FacetKind, [r, t]: V2, s: &mut Shape) {
    let l = [1.0 - r - t, r, t];
    let dl: [V2; 3] = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
    if kind == FacetKind::Tri3 {
        s.phi[..3].copy_from_slice(&l);
        s.dphi[..3].copy_from_slice(&dl);
        return;
    }
    for a in 0..3 {
        s.phi[a] = l[a] * (2.0 * l[a] - 1.0);
        s.dphi[a] = [(4.0 * l[a] - 1.0) * dl[a][0], (4.0 * l[a] - 1.0) * dl[a][1]];
    }
    for &(e, a, b) in edges(kind) {
        s.phi[e] = 4.0 * l[a] * l[b];
        s.dphi[e] = [4.0 * (l[a] * dl[b][0] + l[b] * dl[a][0]), 4.0 * (l[a] * dl[b][1] + l[b] * dl[a][1])];
    }
}

fn quad4_shape([r, t]: V2, s: &mut Shape) {
    for (a, [ra, ta]) in QUAD_REF.into_iter().enumerate() {
        s.phi[a] = 0.25 * (1.0 + ra * r) * (1.0 + ta * t);
        s.dphi[a] = [0.25 * ra * (1.0 + ta * t), 0.25 * ta * (1.0 + ra * r)];
    }
}

/// The 8-node serendipity quad.
fn quad8_shape([r, t]: V2, s: &mut Shape) {
    for (a, [ra, ta]) in QUAD_REF.into_iter().enumerate() {
        let (p, q) = (1.0 + ra * r, 1.0 + ta * t);
        s.phi[a] = 0.25 * p * q * (ra * r + ta * t - 1.0);
        s.dphi[a] = [0.25 * ra * q * (2.0 * ra * r + ta * t), 0.25 * ta * p * (ra * r + 2.0 * ta * t)];
    }
    for &(e, a, b) in edges(FacetKind::Quad8) {
        let [re, te] = [0.5 * (QUAD_REF[a][0] + QUAD_REF[b][0]), 0.5 * (QUAD_REF[a][1] + QUAD_REF[b][1])];
        if re == 0.0 {
            s.phi[e] = 0.5 * (1.0 - r * r) * (1.0 + te * t);
            s.dphi[e] = [-r * (1.0 + te * t), 0.5 * (1.0 - r * r) * te];
        } else {
            s.phi[e] = 0.5 * (1.0 + re * r) * (1.0 - t * t);
            s.dphi[e] = [0.5 * re * (1.0 - t * t), -t * (1.0 + re * r)];
        }
    }
}

/// The 9-node Lagrange quad: products of the 1D quadratics on {−1, 0, 1}.
fn quad9_shape([r, t]: V2, s: &mut Shape) {
    let l = |a: f64, x: f64| -> (f64, f64) {
        if a < 0.0 {
            (0.5 * x * (x - 1.0), x - 0.5)
        } else if a > 0.0 {
            (0.5 * x * (x + 1.0), x + 0.5)
        } else {
            (1.0 - x * x, -2.0 * x)
        }
    };
    let mut nodes = [[0.0; 2]; 9];
    nodes[..4].copy_from_slice(&QUAD_REF);
    for &(e, a, b) in edges(FacetKind::Quad9) {
        nodes[e] = [0.5 * (QUAD_REF[a][0] + QUAD_REF[b][0]), 0.5 * (QUAD_REF[a][1] + QUAD_REF[b][1])];
    }
    for (a, [ra, ta]) in nodes.into_iter().enumerate() {
        let ((p, dp), (q, dq)) = (l(ra, r), l(ta, t));
        s.phi[a] = p * q;
        s.dphi[a] = [dp * q, p * dq];
    }
}

/// Shape functions and their derivatives (∂/∂ξ, ∂/∂η) of a facet at reference point (ξ, η),
/// as vectors of the facet's node count ([`shape`]).
pub fn facet_shape(kind: FacetKind, xi: V2) -> (Vec<f64>, Vec<V2>) {
    let s = shape(kind, xi);
    let n = kind.len();
    (s.phi[..n].to_vec(), s.dphi[..n].to_vec())
}

// ---------------------------------------------------------------------------------------------
// quadrature

/// The 7-point degree-5 triangle rule (Radon; Dunavant 1985): barycentric points, weights
/// summing to 1.
pub fn dunavant7() -> [([f64; 3], f64); 7] {
    let r = 15f64.sqrt();
    let (a, b) = ((6.0 - r) / 21.0, (6.0 + r) / 21.0);
    let (wa, wb) = ((155.0 - r) / 1200.0, (155.0 + r) / 1200.0);
    let c = 1.0 / 3.0;
    [
        ([c, c, c], 9.0 / 40.0),
        ([a, a, 1.0 - 2.0 * a], wa),
        ([a, 1.0 - 2.0 * a, a], wa),
        ([1.0 - 2.0 * a, a, a], wa),
        ([b, b, 1.0 - 2.0 * b], wb),
        ([b, 1.0 - 2.0 * b, b], wb),
        ([1.0 - 2.0 * b, b, b], wb),
    ]
}

/// 4-point Gauss–Legendre on [−1, 1].
pub fn gauss4() -> [(f64, f64); 4] {
    let (p, q) = (0.339_981_043_584_856_3, 0.861_136_311_594_052_6);
    let (wp, wq) = (0.652_145_154_862_546_1, 0.347_854_845_137_453_9);
    [(-q, wq), (-p, wp), (p, wp), (q, wq)]
}

/// 3-point Gauss–Legendre on [−1, 1].
pub fn gauss3() -> [(f64, f64); 3] {
    [(-0.774_596_669_241_483_4, 5.0 / 9.0), (0.0, 8.0 / 9.0), (0.774_596_669_241_483_4, 5.0 / 9.0)]
}

/// The mortar's rule on the reference facet: triangles 7-point degree 5 ([`dunavant7`]),
/// quadrilaterals 4 × 4 Gauss (degree 7), ξ the outer loop.
pub fn fine_rule(kind: FacetKind) -> Vec<(V2, f64)> {
    if is_tri(kind) {
        return dunavant7().iter().map(|&(l, w)| ([l[1], l[2]], 0.5 * w)).collect();
    }
    let g = gauss4();
    let mut q = Vec::with_capacity(16);
    for &(a, wa) in &g {
        for &(b, wb) in &g {
            q.push(([a, b], wa * wb));
        }
    }
    q
}

/// A quadrature rule on the facet's reference domain: degree 4 on triangles (Dunavant's six
/// points), 3 × 3 Gauss on quadrilaterals (η the outer loop).
pub fn facet_rule(kind: FacetKind) -> Vec<(V2, f64)> {
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
        FacetKind::Quad4 | FacetKind::Quad8 | FacetKind::Quad9 => {
            let g = gauss3();
            g.iter().flat_map(|&(t, wt)| g.iter().map(move |&(s, ws)| ([s, t], ws * wt))).collect()
        }
    }
}

// ---------------------------------------------------------------------------------------------
// facet integrals

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
    cross(a, b)
}

/// ∫ N_a dA over a facet: the consistent nodal weights of a uniform surface density (a tri6's
/// corners get 0, its edge nodes a third of the area; a quad8's corners a negative share).
/// quad4 as [`quad4_nodal_areas`] (2 × 2 Gauss, exact).
pub fn facet_nodal_areas(kind: FacetKind, x: &[[f64; 3]]) -> Vec<f64> {
    if kind == FacetKind::Quad4 {
        return quad4_nodal_areas(x.try_into().expect("four corners")).to_vec();
    }
    let mut w = vec![0.0; kind.len()];
    for (xi, wq) in facet_rule(kind) {
        let (n, d) = facet_shape(kind, xi);
        let c = facet_area_vector(x, &d);
        let da = norm(c) * wq;
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
    facet_point(kind, x, centre(kind))
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
        norm(c)
    };
    let is_in = |xi: [f64; 2]| inside(facet_point(kind, x, xi));
    let mid = |a: [f64; 2], b: [f64; 2]| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    // a part: its corners (3 or 4) in the reference domain
    let mut stack: Vec<(Vec<[f64; 2]>, usize)> = match kind {
        FacetKind::Tri3 | FacetKind::Tri6 => vec![(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], 0)],
        FacetKind::Quad4 | FacetKind::Quad8 | FacetKind::Quad9 => vec![(vec![[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]], 0)],
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

/// ∫ N_a dA over a (possibly warped) bilinear quad, 2×2 Gauss: the consistent nodal weights of
/// a uniform surface density. A constant traction p gives nodal forces p·w_a; for a flat
/// rectangle w_a is a quarter of the area (the lumped nodal contact area).
pub fn quad4_nodal_areas(x: &[[f64; 3]; 4]) -> [f64; 4] {
    let mut w = [0.0; 4];
    for &eta in &GAUSS2 {
        for &xi in &GAUSS2 {
            let s = shape(FacetKind::Quad4, [xi, eta]);
            let da = norm(facet_area_vector(x, &s.dphi[..4]));
            for a in 0..4 {
                w[a] += s.phi[a] * da;
            }
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Shape functions: partition of unity, derivatives by finite differences, Kronecker at
    /// the nodes; nodal weights sum to the area and match the closed forms.
    #[test]
    fn facet_shapes_and_weights() {
        let nodes: [(FacetKind, Vec<[f64; 2]>); 5] = [
            (FacetKind::Tri3, vec![[0., 0.], [1., 0.], [0., 1.]]),
            (FacetKind::Tri6, vec![[0., 0.], [1., 0.], [0., 1.], [0.5, 0.], [0.5, 0.5], [0., 0.5]]),
            (FacetKind::Quad4, vec![[-1., -1.], [1., -1.], [1., 1.], [-1., 1.]]),
            (FacetKind::Quad8, vec![[-1., -1.], [1., -1.], [1., 1.], [-1., 1.], [0., -1.], [1., 0.], [0., 1.], [-1., 0.]]),
            (FacetKind::Quad9, vec![[-1., -1.], [1., -1.], [1., 1.], [-1., 1.], [0., -1.], [1., 0.], [0., 1.], [-1., 0.], [0., 0.]]),
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
                // 1/36, 4/36 and 16/36 of the area
                FacetKind::Quad9 => {
                    assert!(w[..4].iter().all(|v| (v - 2.0 / 3.0).abs() < 1e-13) && w[4..8].iter().all(|v| (v - 8.0 / 3.0).abs() < 1e-13));
                    assert!((w[8] - 32.0 / 3.0).abs() < 1e-13);
                }
            }
        }
    }
}
