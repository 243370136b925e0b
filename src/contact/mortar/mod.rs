//! Dual (biorthogonal) mortar coupling of non-matching 3D contact surfaces, with the contact
//! search that feeds it.
//!
//! The module owns, for one slave surface and one master surface given as plain facet lists
//! over a global coordinate array, the rows of the contact constraints
//!
//! ```text
//! (N u)ᵢ = Σ_k c_ik (u_k · nᵢ) ≤ dᵢ          c_ii = +1 (slave),  c_ij = −M_ij / D_ii (master j)
//! ```
//!
//! (the tangential rows use the same coupling with tangents), i.e. the normalized mortar
//! matrices D, M, the averaged slave normals nᵢ and the normalized weighted gaps
//! dᵢ = −Σ_k c_ik (x_k · nᵢ). On matching flat linear meshes it reduces exactly to
//! node-to-node pairing ({(s, +1), (m, −1)}, D_ii = ∫ φᵢ dA, dᵢ = (x_m − x_s)·nᵢ).
//!
//! **Method.**
//! - Dual basis (Wohlmuth 2000, "A mortar finite element method using dual spaces for the
//!   Lagrange multiplier", SIAM J. Numer. Anal. 38): per slave facet e, ψᵢ = Σ_j a_ij φ_j with
//!   A_e = D_e M_e⁻¹, D_e = diag(∫_e φ_j), M_e = (∫_e φᵢ φ_j), integrated numerically on the facet
//!   (so warped quads are fine); biorthogonality ∫_e ψᵢ φ_k = δ_ik ∫_e φ_k. For tri3 this is
//!   ψᵢ = 4λᵢ − 1 = 3λᵢ − λ_j − λ_k.
//! - Search: an R*-tree ([`rstar`]) over the master facets' bounding boxes inflated by
//!   [`MortarParams::search_distance`]; each slave facet queries its own box.
//! - Segment-based integration (Puso & Laursen 2004, "A mortar segment-to-segment contact method
//!   for large deformation solid mechanics", CMAME 193; Popp, Gee, Wall 2009, "A finite
//!   deformation mortar contact formulation using a primal–dual active set strategy", IJNME 79;
//!   Popp, Gitterle, Gee, Wall 2010, "A dual mortar approach for 3D finite deformation contact
//!   with consistent linearization", IJNME 83): for each candidate (slave facet, master facet)
//!   whose normals oppose, both are projected along the slave facet's centre normal n₀ onto the
//!   auxiliary plane through its centre, the polygons are clipped (Sutherland–Hodgman), the clip
//!   polygon is triangulated from its centroid and integrated with the 7-point degree-5 rule
//!   (Radon/Dunavant). At each Gauss point the slave and master parametric coordinates are found
//!   by Newton along n₀, and with the slave surface Jacobian J (slave area per plane area)
//!   `M_ij += w J ψᵢ(ξ_s) φ_j(ξ_m)`, `D_ii += w J ψᵢ(ξ_s)`. D is lumped over the covered segments
//!   only, so Σ_j M_ij = D_ii exactly and a rigid translation of the master leaves the weighted
//!   gap unchanged (the patch test); on fully covered slave facets D_ii = ∫ φᵢ dA.
//! - Partly covered slave facets (at the edge of the master face): the dual basis is rebuilt on
//!   the covered part, A = D̂ M̂⁻¹ with D̂, M̂ integrated over the facet's segments (Cichosz &
//!   Bischoff 2011, "Consistent treatment of boundaries with mortar contact formulations using
//!   dual Lagrange multipliers", CMAME 200; Popp, Wohlmuth, Gee, Wall 2012/2013), so that
//!   biorthogonality, D_ii = ∫_covered φᵢ dA > 0 and the reproduction of linear gaps hold there
//!   too; the coefficients −M_ij/D_ii then extrapolate from the covered part to the node and grow
//!   as the covered part shrinks (see [`MortarParams::min_coverage`]). A node beyond the
//!   master's edge (its normal line misses the master, less than half its support covered)
//!   keeps no row: its unnormalized row is shared among its neighbours that keep theirs, a
//!   modified dual basis at the boundary of the contact zone ([`MortarParams::trim_edge`]).
//! - Normals: the unit average of the slave facet normals around the node, weighted by the
//!   facet areas.
//!
//! **Coverage rule.** A master facet counts for a slave facet when their normals oppose
//! (−n_m·n₀ > [`MortarParams::min_opposition`]), the projected polygons overlap with positive
//! area, and the normal distance (x_m − x_s)·n₀ at some vertex of the overlap is at most
//! `search_distance` in magnitude. A slave node none of whose facets has such a master facet is
//! *uncovered*: by default that is [`MortarError::NoMaster`] naming the node (so a slave face
//! that extends beyond the master face by a whole facet is an error: choose the smaller face as
//! slave, or set [`MortarParams::allow_uncovered`] to drop those nodes and count them in
//! [`MortarInfo::nodes_uncovered`]). A covered node with D_ii ≤ `min_coverage` · ∫ φᵢ dA (a
//! sliver) gets no row and is counted in [`MortarInfo::rows_dropped`].
//!
//! **Facets.** tri3, quad4 (bilinear, may be warped), tri6, quad8 (serendipity) and quad9
//! (biquadratic), each with a convex projected corner polygon; the clipping uses the corner polygons (exact for
//! straight-edged facets), the integration the true facet maps. Quadratic slave facets use the
//! modified basis φ̃ = T φ of Popp, Wohlmuth, Gee, Wall 2012 ("Dual quadratic mortar finite
//! element methods for 3D finite deformation contact", SIAM J. Sci. Comput. 34): per edge node
//! e between corners a, b, φ̃_a += α φ_e, φ̃_b += α φ_e, φ̃_e = (1 − 2α) φ_e, α = 1/5 (for quad8
//! too, where it makes ∫ φ̃_corner > 0), and the dual basis is built on φ̃. The slave part of
//! row i is then (T⁻¹)_ki: +1 at a corner, and 1/(1 − 2α), −α/(1 − 2α), −α/(1 − 2α) at an edge
//! node and its two corners. quad9 slave facets keep the standard dual basis (T = I): every
//! ∫ φᵢ is positive there (corners 1/36, edges 1/9, centre 4/9 of a parallelogram's area; the
//! tensor product of the 1D quadratic dual basis, Wohlmuth, Popp, Gee, Wall 2012, "An abstract
//! framework for a priori estimates for contact problems in 3D with quadratic finite elements",
//! Comput. Mech. 49), so the slave part of each of their rows is +1 at the node alone.
//!
//! **Layout.** This file holds the public API (the facet view, parameters, rows, counters and
//! errors) and the facet geometry shared by the parts: [`Facet`] (a facet with its node
//! coordinates) and [`Plane`] (a slave facet's auxiliary plane). [`clip`] clips and measures the
//! projected polygons, [`dual_basis`] builds the slave facets' dual bases, [`assemble`] searches,
//! integrates the segments and assembles the rows ([`dual_mortar`]). The reference facets (shape
//! functions, quadrature rules) are [`crate::fem::facet`]'s.

use rstar::AABB;
use thiserror::Error;

use crate::fem::facet::{axpy, centre, cross, dot, fine_rule, kind_of, norm, scale, shape, sub, Shape, MAX_NODES};
use crate::mesh::FacetKind;
use clip::sub2;

mod assemble;
mod clip;
mod dual_basis;
#[cfg(test)]
mod tests;

pub use assemble::dual_mortar;

type V2 = [f64; 2];
type V3 = [f64; 3];
type Mat = [[f64; MAX_NODES]; MAX_NODES];

/// α of the modified quadratic slave basis (tri6 and quad8; quad9 keeps the standard one).
const ALPHA: f64 = 0.2;
/// Master entries with |M_ij| at most this fraction of D_ii are round-off and left out.
const PRUNE_FRACTION: f64 = 1e-14;
/// A slave facet whose overlaps miss at most this fraction of its area counts as fully covered.
const FULL_COVER: f64 = 1e-9;
/// Clip polygons with at most this fraction of the slave facet's projected area are slivers.
const SLIVER_FRACTION: f64 = 1e-12;

/// A facet of a surface mesh: node ids into the global coordinate array, ordered so the
/// right-hand rule gives the body's outward normal. tri3: 3 nodes; quad4: 4 (bilinear, may be
/// warped); tri6: corners 0–2, then edge nodes (0,1), (1,2), (2,0); quad8: corners 0–3, then
/// edges (0,1), (1,2), (2,3), (3,0); quad9: as quad8, then the centre.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceFacet<'a> {
    pub nodes: &'a [usize],
}

/// Parameters of the search and of the coverage rule (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MortarParams {
    /// Largest |normal gap| (model length units) at which a master facet is found.
    pub search_distance: f64,
    /// A master facet is used only when −n_m·n₀ exceeds this (0: any opposing facet).
    pub min_opposition: f64,
    /// Drop uncovered slave nodes (counted) instead of failing with [`MortarError::NoMaster`].
    pub allow_uncovered: bool,
    /// A covered node gets a row only when D_ii > min_coverage · ∫ φᵢ dA. A node beyond the
    /// master's edge whose facets are covered over a fraction c (on the far side) has
    /// D_ii/∫ φᵢ dA ≈ c² and master coefficients growing like 1/c, so this bounds the rows
    /// there; the default 10⁻⁸ keeps every row but true slivers.
    pub min_coverage: f64,
    /// The edge of the contact zone: a covered slave node whose normal line misses every master
    /// facet and whose support is less than half covered (it lies beyond the master's edge)
    /// gets no row of its own; its row, unnormalized
    /// (D_ii × the row: D_ii ψᵢ's constraint), is added in equal shares to the rows of its
    /// neighbours on the slave face that keep theirs, as a modified dual basis ψ̃_j = ψ_j +
    /// ψᵢ/k at the boundary of the contact zone. Off: every covered node keeps its row, whose
    /// master coefficients grow as 1/c on a sliver of coverage c.
    pub trim_edge: bool,
}

impl Default for MortarParams {
    fn default() -> Self {
        Self { search_distance: 1e-2, min_opposition: 0.0, allow_uncovered: false, min_coverage: 1e-8, trim_edge: true }
    }
}

/// Counters of one [`dual_mortar`] call.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MortarInfo {
    pub slave_facets: usize,
    pub master_facets: usize,
    /// (slave facet, master facet) pairs returned by the R*-tree.
    pub candidate_pairs: usize,
    /// Pairs with an overlap of positive area that were integrated.
    pub segments: usize,
    /// Covered slave nodes without a row (D_ii ≤ `min_coverage` · ∫ φᵢ dA, or beyond the
    /// master's edge under [`MortarParams::trim_edge`]).
    pub rows_dropped: usize,
    /// Of those, the rows handed on to their neighbours ([`MortarParams::trim_edge`]).
    pub rows_handed_on: usize,
    /// Slave nodes with no overlap at all, dropped under [`MortarParams::allow_uncovered`].
    pub nodes_uncovered: usize,
    /// Wall time of the call.
    pub seconds: f64,
}

/// The mortar rows, one per retained slave node, sorted by node id.
#[derive(Clone, Debug, Default)]
pub struct MortarRows {
    /// The slave node that carries multiplier row i.
    pub node: Vec<usize>,
    /// Averaged unit outward normal of the slave face at the node.
    pub normal: Vec<[f64; 3]>,
    /// D_ii = ∫ ψᵢ dA over the covered part (= ∫ φ̃ᵢ dA for a fully covered node; φ̃ = φ on
    /// linear facets).
    pub area: Vec<f64>,
    /// (node, c_ik): the slave node first (+1; at a quadratic edge node 1/(1 − 2α), then its two
    /// corners with −α/(1 − 2α)), then master nodes by id with −M_ij / D_ii.
    pub coupling: Vec<Vec<(usize, f64)>>,
    /// Normalized weighted gap dᵢ = −Σ_k c_ik (x_k · nᵢ), positive when apart.
    pub gap: Vec<f64>,
    /// The geometric gap at the slave node: the distance along nᵢ from the node to the master
    /// surface, on the master facets' true (quadratic) maps; NaN where the node's normal line
    /// meets none of the master facets its facets overlap (beyond the master's edge). On
    /// quadratic slave facets the weighted gap is the gap transformed by T⁻¹ (1/(1 − 2α) at an
    /// edge node less α/(1 − 2α) at each corner), which on a curved face lies below the
    /// geometric one by about ⅔ of an edge's sagitta.
    pub geometric_gap: Vec<f64>,
    /// The slave nodes with no master facet (ascending), without rows: only under
    /// [`MortarParams::allow_uncovered`].
    pub uncovered: Vec<usize>,
    pub info: MortarInfo,
}

impl MortarRows {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.node.len()
    }

    pub fn is_empty(&self) -> bool {
        self.node.is_empty()
    }

    /// Σ_k c_ik² per row: the diagonal of B Bᵀ for the normal rows (2 for node-to-node).
    #[cfg(test)]
    pub fn row_norms_squared(&self) -> Vec<f64> {
        self.coupling.iter().map(|row| row.iter().map(|(_, c)| c * c).sum()).collect()
    }
}

/// Why the mortar rows could not be built.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum MortarError {
    #[error("{side} facet {facet} has {nodes} nodes; expected 3 (tri3), 4 (quad4), 6 (tri6), 8 (quad8) or 9 (quad9)")]
    FacetNodes { side: &'static str, facet: usize, nodes: usize },
    #[error("{side} facet {facet} names node {node}, beyond the {len} coordinates")]
    NodeOutOfRange { side: &'static str, facet: usize, node: usize, len: usize },
    #[error("{side} facet {facet} is degenerate or not convex")]
    Degenerate { side: &'static str, facet: usize },
    #[error(
        "slave node {node} at {} finds no master facet within the search distance \
         {distance:.1e} ({uncovered} of {nodes} slave nodes uncovered)",
        point(x)
    )]
    NoMaster { node: usize, x: V3, distance: f64, uncovered: usize, nodes: usize },
    #[error("a Gauss point of slave facet {slave} and master facet {master} does not project onto the {side} facet")]
    Projection { slave: usize, master: usize, side: &'static str },
    #[error("the search distance must be finite and positive, got {0}")]
    SearchDistance(f64),
}

fn point(x: &V3) -> String {
    format!("({}, {}, {})", short(x[0]), short(x[1]), short(x[2]))
}

/// Up to 6 significant digits, trailing zeros trimmed.
fn short(v: f64) -> String {
    let s = format!("{:.6}", v);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

// ---------------------------------------------------------------------------------------------
// facets

/// A facet with its node coordinates.
struct Facet {
    kind: FacetKind,
    nodes: [usize; MAX_NODES],
    x: [V3; MAX_NODES],
}

impl Facet {
    fn new(f: &SurfaceFacet, coords: &[V3], side: &'static str, facet: usize) -> Result<Facet, MortarError> {
        let kind = kind_of(f.nodes.len()).ok_or(MortarError::FacetNodes { side, facet, nodes: f.nodes.len() })?;
        let mut out = Facet { kind, nodes: [0; MAX_NODES], x: [[0.0; 3]; MAX_NODES] };
        for (a, &node) in f.nodes.iter().enumerate() {
            let len = coords.len();
            let x = coords.get(node).ok_or(MortarError::NodeOutOfRange { side, facet, node, len })?;
            out.nodes[a] = node;
            out.x[a] = *x;
        }
        Ok(out)
    }

    fn n(&self) -> usize {
        self.kind.len()
    }

    /// The point x(ξ) and the tangents ∂x/∂ξ, ∂x/∂η.
    fn map(&self, s: &Shape) -> (V3, [V3; 2]) {
        let (mut x, mut t) = ([0.0; 3], [[0.0; 3]; 2]);
        for a in 0..self.n() {
            axpy(&mut x, s.phi[a], self.x[a]);
            axpy(&mut t[0], s.dphi[a][0], self.x[a]);
            axpy(&mut t[1], s.dphi[a][1], self.x[a]);
        }
        (x, t)
    }

    /// ∫ |∂x/∂ξ × ∂x/∂η| dξ.
    fn area(&self) -> f64 {
        let rule = fine_rule(self.kind);
        rule.iter().map(|(xi, w)| w * norm(self.jacobian(*xi))).sum()
    }

    /// ∂x/∂ξ × ∂x/∂η at ξ.
    fn jacobian(&self, xi: V2) -> V3 {
        let (_, t) = self.map(&shape(self.kind, xi));
        cross(t[0], t[1])
    }

    /// Unit normal at the facet centre (right-hand rule).
    fn centre_normal(&self) -> Option<V3> {
        let j = self.jacobian(centre(self.kind));
        let l = norm(j);
        (l > 0.0 && l.is_finite()).then(|| scale(j, 1.0 / l))
    }

    /// Bounding box of the corners (straight-sided facets), inflated by `pad`.
    fn aabb(&self, pad: f64) -> AABB<V3> {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for x in &self.x[..self.n()] {
            for k in 0..3 {
                lo[k] = lo[k].min(x[k] - pad);
                hi[k] = hi[k].max(x[k] + pad);
            }
        }
        AABB::from_corners(lo, hi)
    }
}

/// The auxiliary plane of a slave facet: centre, unit normal n₀, tangents with t₀ × t₁ = n₀.
struct Plane {
    c: V3,
    n: V3,
    t: [V3; 2],
}

impl Plane {
    fn of(f: &Facet, n: V3) -> Plane {
        let (c, _) = f.map(&shape(f.kind, centre(f.kind)));
        let e = sub(f.x[1], f.x[0]);
        let e = sub(e, scale(n, dot(e, n)));
        let t0 = scale(e, 1.0 / norm(e));
        Plane { c, n, t: [t0, cross(n, t0)] }
    }

    fn to2d(&self, x: V3) -> V2 {
        let d = sub(x, self.c);
        [dot(d, self.t[0]), dot(d, self.t[1])]
    }

    /// The projected corner polygon of a facet.
    fn polygon(&self, f: &Facet) -> Vec<V2> {
        f.x[..f.kind.corners()].iter().map(|&x| self.to2d(x)).collect()
    }

    /// The parametric coordinates of the point of `f` whose projection is `p` (Newton).
    /// Stops when the step is below 10⁻¹³ or, below 10⁻⁹, stops shrinking (round-off).
    fn invert(&self, f: &Facet, p: V2) -> Option<V2> {
        let (mut xi, mut last) = (centre(f.kind), f64::INFINITY);
        for _ in 0..50 {
            let (x, t) = f.map(&shape(f.kind, xi));
            let r = sub2(self.to2d(x), p);
            let j = [[dot(t[0], self.t[0]), dot(t[1], self.t[0])], [dot(t[0], self.t[1]), dot(t[1], self.t[1])]];
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            if det.abs() < 1e-300 {
                return None;
            }
            let d = [(j[1][1] * r[0] - j[0][1] * r[1]) / det, (j[0][0] * r[1] - j[1][0] * r[0]) / det];
            xi = [xi[0] - d[0], xi[1] - d[1]];
            let step = d[0].abs() + d[1].abs();
            if step < 1e-13 || (step < 1e-9 && step > 0.5 * last) {
                return Some(xi);
            }
            last = step;
        }
        None
    }
}
