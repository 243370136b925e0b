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
//! **Facets.** tri3, quad4 (bilinear, may be warped), tri6 and quad8 (serendipity), each with a
//! convex projected corner polygon; the clipping uses the corner polygons (exact for
//! straight-edged facets), the integration the true facet maps. Quadratic slave facets use the
//! modified basis φ̃ = T φ of Popp, Wohlmuth, Gee, Wall 2012 ("Dual quadratic mortar finite
//! element methods for 3D finite deformation contact", SIAM J. Sci. Comput. 34): per edge node
//! e between corners a, b, φ̃_a += α φ_e, φ̃_b += α φ_e, φ̃_e = (1 − 2α) φ_e, α = 1/5 (for quad8
//! too, where it makes ∫ φ̃_corner > 0), and the dual basis is built on φ̃. The slave part of
//! row i is then (T⁻¹)_ki: +1 at a corner, and 1/(1 − 2α), −α/(1 − 2α), −α/(1 − 2α) at an edge
//! node and its two corners.

use std::collections::BTreeMap;
use std::time::Instant;

use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};
use thiserror::Error;

type V2 = [f64; 2];
type V3 = [f64; 3];
type Mat = [[f64; MAX_NODES]; MAX_NODES];

/// Largest number of nodes of a facet.
const MAX_NODES: usize = 8;
/// α of the modified quadratic slave basis (tri6 and quad8).
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
/// edges (0,1), (1,2), (2,3), (3,0).
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
    pub fn row_norms_squared(&self) -> Vec<f64> {
        self.coupling.iter().map(|row| row.iter().map(|(_, c)| c * c).sum()).collect()
    }
}

/// Why the mortar rows could not be built.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum MortarError {
    #[error("{side} facet {facet} has {nodes} nodes; expected 3 (tri3), 4 (quad4), 6 (tri6) or 8 (quad8)")]
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
// small vector algebra

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}

fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

fn axpy(y: &mut V3, s: f64, x: V3) {
    for k in 0..3 {
        y[k] += s * x[k];
    }
}

fn cross2(a: V2, b: V2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn sub2(a: V2, b: V2) -> V2 {
    [a[0] - b[0], a[1] - b[1]]
}

// ---------------------------------------------------------------------------------------------
// reference elements and quadrature

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Tri3,
    Quad4,
    Tri6,
    Quad8,
}

/// Shape function values φ_a and reference derivatives [∂φ_a/∂ξ, ∂φ_a/∂η] at one point.
struct Shape {
    phi: [f64; MAX_NODES],
    dphi: [V2; MAX_NODES],
}

/// quad4/quad8 corners, counter-clockwise from (−1, −1).
const QUAD: [V2; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

impl Kind {
    fn of(nodes: usize) -> Option<Kind> {
        match nodes {
            3 => Some(Kind::Tri3),
            4 => Some(Kind::Quad4),
            6 => Some(Kind::Tri6),
            8 => Some(Kind::Quad8),
            _ => None,
        }
    }

    fn len(self) -> usize {
        match self {
            Kind::Tri3 => 3,
            Kind::Quad4 => 4,
            Kind::Tri6 => 6,
            Kind::Quad8 => 8,
        }
    }

    fn is_tri(self) -> bool {
        matches!(self, Kind::Tri3 | Kind::Tri6)
    }

    /// The number of corner nodes (the polygon of the facet).
    fn corners(self) -> usize {
        if self.is_tri() {
            3
        } else {
            4
        }
    }

    /// (edge node, its two corners) of a quadratic facet; empty for linear ones.
    fn edges(self) -> &'static [(usize, usize, usize)] {
        match self {
            Kind::Tri3 | Kind::Quad4 => &[],
            Kind::Tri6 => &[(3, 0, 1), (4, 1, 2), (5, 2, 0)],
            Kind::Quad8 => &[(4, 0, 1), (5, 1, 2), (6, 2, 3), (7, 3, 0)],
        }
    }

    fn centre(self) -> V2 {
        if self.is_tri() {
            [1.0 / 3.0, 1.0 / 3.0]
        } else {
            [0.0, 0.0]
        }
    }

    /// Triangles on (0,0),(1,0),(0,1); quads on [−1, 1]² (corners as [`QUAD`], then the edge
    /// midpoints in the order of [`Kind::edges`]).
    fn shape(self, xi: V2) -> Shape {
        let mut s = Shape { phi: [0.0; MAX_NODES], dphi: [[0.0; 2]; MAX_NODES] };
        match self {
            Kind::Tri3 | Kind::Tri6 => tri_shape(self, xi, &mut s),
            Kind::Quad4 => quad4_shape(xi, &mut s),
            Kind::Quad8 => quad8_shape(xi, &mut s),
        }
        s
    }

    /// Quadrature on the reference element: triangles 7-point degree 5, quads 4×4 Gauss
    /// (degree 7).
    fn rule(self) -> Vec<(V2, f64)> {
        if self.is_tri() {
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

    /// The modified slave basis φ̃ = T φ of Popp et al. (2012): per edge node e between corners
    /// a, b: φ̃_a += α φ_e, φ̃_b += α φ_e, φ̃_e = (1 − 2α) φ_e; identity for linear facets.
    fn transformation(self) -> Mat {
        let mut t = [[0.0; MAX_NODES]; MAX_NODES];
        for (i, row) in t.iter_mut().enumerate().take(self.len()) {
            row[i] = 1.0;
        }
        for &(e, a, b) in self.edges() {
            t[a][e] += ALPHA;
            t[b][e] += ALPHA;
            t[e][e] = 1.0 - 2.0 * ALPHA;
        }
        t
    }
}

/// tri3 (λ) and tri6 (corners λ(2λ − 1), edges 4λ_aλ_b) with λ = (1 − ξ − η, ξ, η).
fn tri_shape(kind: Kind, [r, t]: V2, s: &mut Shape) {
    let l = [1.0 - r - t, r, t];
    let dl: [V2; 3] = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
    if kind == Kind::Tri3 {
        s.phi[..3].copy_from_slice(&l);
        s.dphi[..3].copy_from_slice(&dl);
        return;
    }
    for a in 0..3 {
        s.phi[a] = l[a] * (2.0 * l[a] - 1.0);
        s.dphi[a] = [(4.0 * l[a] - 1.0) * dl[a][0], (4.0 * l[a] - 1.0) * dl[a][1]];
    }
    for &(e, a, b) in kind.edges() {
        s.phi[e] = 4.0 * l[a] * l[b];
        s.dphi[e] = [4.0 * (l[a] * dl[b][0] + l[b] * dl[a][0]), 4.0 * (l[a] * dl[b][1] + l[b] * dl[a][1])];
    }
}

fn quad4_shape([r, t]: V2, s: &mut Shape) {
    for (a, [ra, ta]) in QUAD.into_iter().enumerate() {
        s.phi[a] = 0.25 * (1.0 + ra * r) * (1.0 + ta * t);
        s.dphi[a] = [0.25 * ra * (1.0 + ta * t), 0.25 * ta * (1.0 + ra * r)];
    }
}

/// The 8-node serendipity quad.
fn quad8_shape([r, t]: V2, s: &mut Shape) {
    for (a, [ra, ta]) in QUAD.into_iter().enumerate() {
        let (p, q) = (1.0 + ra * r, 1.0 + ta * t);
        s.phi[a] = 0.25 * p * q * (ra * r + ta * t - 1.0);
        s.dphi[a] = [0.25 * ra * q * (2.0 * ra * r + ta * t), 0.25 * ta * p * (ra * r + 2.0 * ta * t)];
    }
    for &(e, a, b) in Kind::Quad8.edges() {
        let [re, te] = [0.5 * (QUAD[a][0] + QUAD[b][0]), 0.5 * (QUAD[a][1] + QUAD[b][1])];
        if re == 0.0 {
            s.phi[e] = 0.5 * (1.0 - r * r) * (1.0 + te * t);
            s.dphi[e] = [-r * (1.0 + te * t), 0.5 * (1.0 - r * r) * te];
        } else {
            s.phi[e] = 0.5 * (1.0 + re * r) * (1.0 - t * t);
            s.dphi[e] = [0.5 * re * (1.0 - t * t), -t * (1.0 + re * r)];
        }
    }
}

/// The 7-point degree-5 triangle rule (Radon; Dunavant 1985): barycentric points, weights
/// summing to 1.
fn dunavant7() -> [([f64; 3], f64); 7] {
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
fn gauss4() -> [(f64, f64); 4] {
    let (p, q) = (0.339_981_043_584_856_3, 0.861_136_311_594_052_6);
    let (wp, wq) = (0.652_145_154_862_546_1, 0.347_854_845_137_453_9);
    [(-q, wq), (-p, wp), (p, wp), (q, wq)]
}

// ---------------------------------------------------------------------------------------------
// facets

/// A facet with its node coordinates.
struct Facet {
    kind: Kind,
    nodes: [usize; MAX_NODES],
    x: [V3; MAX_NODES],
}

impl Facet {
    fn new(f: &SurfaceFacet, coords: &[V3], side: &'static str, facet: usize) -> Result<Facet, MortarError> {
        let kind = Kind::of(f.nodes.len()).ok_or(MortarError::FacetNodes { side, facet, nodes: f.nodes.len() })?;
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
        let rule = self.kind.rule();
        rule.iter().map(|(xi, w)| w * norm(self.jacobian(*xi))).sum()
    }

    /// ∂x/∂ξ × ∂x/∂η at ξ.
    fn jacobian(&self, xi: V2) -> V3 {
        let (_, t) = self.map(&self.kind.shape(xi));
        cross(t[0], t[1])
    }

    /// Unit normal at the facet centre (right-hand rule).
    fn centre_normal(&self) -> Option<V3> {
        let j = self.jacobian(self.kind.centre());
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
        let (c, _) = f.map(&f.kind.shape(f.kind.centre()));
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
        let (mut xi, mut last) = (f.kind.centre(), f64::INFINITY);
        for _ in 0..50 {
            let (x, t) = f.map(&f.kind.shape(xi));
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

/// A slave facet with its auxiliary plane and dual basis.
struct SlaveFacet {
    f: Facet,
    plane: Plane,
    /// Dual coefficients of the whole facet: ψᵢ = Σ_j a[i][j] φ_j.
    a: Mat,
    /// ∫_e φ̃_j dA (φ̃ = φ for linear facets).
    d: [f64; MAX_NODES],
    /// Unit normal at the centre, times the facet area.
    weighted_normal: V3,
    /// Area of the projected corner polygon.
    plane_area: f64,
}

impl SlaveFacet {
    fn new(f: Facet, facet: usize) -> Result<SlaveFacet, MortarError> {
        let bad = MortarError::Degenerate { side: "slave", facet };
        let n0 = f.centre_normal().ok_or(bad.clone())?;
        let plane = Plane::of(&f, n0);
        let poly = plane.polygon(&f);
        if !is_convex(&poly) {
            return Err(bad);
        }
        let (a, d) = dual_coefficients(&f).ok_or(bad)?;
        let weighted_normal = scale(n0, f.area());
        Ok(SlaveFacet { plane_area: polygon_area(&poly), f, plane, a, d, weighted_normal })
    }

    /// ψᵢ = Σ_j a_ij φ_j at a point, from the shape functions there.
    fn psi(&self, a: &Mat, s: &Shape) -> [f64; MAX_NODES] {
        let mut psi = [0.0; MAX_NODES];
        let n = self.f.n();
        for (i, p) in psi.iter_mut().enumerate().take(n) {
            *p = (0..n).map(|j| a[i][j] * s.phi[j]).sum();
        }
        psi
    }

    /// Slave area per plane area at a point: |x_ξ × x_η| / |(x_ξ × x_η)·n₀|.
    fn jacobian_ratio(&self, s: &Shape) -> f64 {
        let (_, t) = self.f.map(s);
        let j = cross(t[0], t[1]);
        norm(j) / dot(j, self.plane.n).abs()
    }

    /// The dual coefficients for the covered part `segs` of a partly covered facet:
    /// A = D̂ M̂⁻¹ with D̂, M̂ integrated over the segments only, or None when M̂ is singular.
    fn partial_dual(&self, segs: &[(usize, Vec<V2>)], id: usize) -> Result<Option<Mat>, MortarError> {
        let mut samples = Vec::new();
        for (master, poly) in segs {
            for (p, w) in fan_points(poly) {
                let fail = MortarError::Projection { slave: id, master: *master, side: "slave" };
                let sh = self.f.kind.shape(self.plane.invert(&self.f, p).ok_or(fail)?);
                let wj = w * self.jacobian_ratio(&sh);
                samples.push((sh, wj));
            }
        }
        let t = self.f.kind.transformation();
        Ok(dual_from(&samples, &t, self.f.n()).map(|(a, _)| a))
    }
}

/// The dual coefficients of a whole facet (in the standard basis, see [`dual_from`]) and
/// D_e = (∫_e φ̃_j dA), or None when M_e is singular.
fn dual_coefficients(f: &Facet) -> Option<(Mat, [f64; MAX_NODES])> {
    let samples: Vec<(Shape, f64)> = f.kind.rule().into_iter().map(|(xi, w)| (f.kind.shape(xi), w * norm(f.jacobian(xi)))).collect();
    dual_from(&samples, &f.kind.transformation(), f.n())
}

/// From (shape functions, weight) samples of a region: D = diag(∫ φ̃), M = (∫ φ̃ᵢ φ̃_j) with
/// φ̃ = T φ, A = D M⁻¹, so ψᵢ = Σ_j (A T)_ij φ_j; returns A T and the diagonal of D.
fn dual_from(samples: &[(Shape, f64)], t: &Mat, n: usize) -> Option<(Mat, [f64; MAX_NODES])> {
    let (mut m, mut d) = ([[0.0; MAX_NODES]; MAX_NODES], [0.0; MAX_NODES]);
    for (s, w) in samples {
        let b = mat_vec(t, &s.phi, n);
        add_scaled(&mut d, *w, &b[..n]);
        add_outer(&mut m, *w, &b[..n], &b[..n]);
    }
    let a = scale_rows(&invert(m, n)?, &d, n);
    Some((mat_mul(&a, t, n), d))
}

/// T v on the leading n entries.
fn mat_vec(t: &Mat, v: &[f64; MAX_NODES], n: usize) -> [f64; MAX_NODES] {
    let mut out = [0.0; MAX_NODES];
    for (o, row) in out.iter_mut().zip(t).take(n) {
        *o = row[..n].iter().zip(&v[..n]).map(|(a, b)| a * b).sum();
    }
    out
}

/// A B on the leading n×n blocks.
fn mat_mul(a: &Mat, b: &Mat, n: usize) -> Mat {
    let mut out = [[0.0; MAX_NODES]; MAX_NODES];
    for (o, arow) in out.iter_mut().zip(a).take(n) {
        for (k, &aik) in arow[..n].iter().enumerate() {
            add_scaled(&mut o[..n], aik, &b[k][..n]);
        }
    }
    out
}

/// d_i += w a_i.
fn add_scaled(d: &mut [f64], w: f64, a: &[f64]) {
    for (di, ai) in d.iter_mut().zip(a) {
        *di += w * ai;
    }
}

/// m_ij += w a_i b_j.
fn add_outer(m: &mut Mat, w: f64, a: &[f64], b: &[f64]) {
    for (row, ai) in m.iter_mut().zip(a) {
        for (mij, bj) in row.iter_mut().zip(b) {
            *mij += w * ai * bj;
        }
    }
}

/// diag(d) · m on the leading n×n block.
fn scale_rows(m: &Mat, d: &[f64; MAX_NODES], n: usize) -> Mat {
    let mut a = [[0.0; MAX_NODES]; MAX_NODES];
    for i in 0..n {
        for j in 0..n {
            a[i][j] = d[i] * m[i][j];
        }
    }
    a
}

/// Inverse of the leading n×n block (Gauss–Jordan, partial pivoting).
fn invert(mut m: [[f64; MAX_NODES]; MAX_NODES], n: usize) -> Option<[[f64; MAX_NODES]; MAX_NODES]> {
    let mut inv = [[0.0; MAX_NODES]; MAX_NODES];
    for (i, row) in inv.iter_mut().enumerate().take(n) {
        row[i] = 1.0;
    }
    let size = (0..n).map(|i| m[i][i].abs()).fold(0.0, f64::max);
    for c in 0..n {
        let p = (c..n).max_by(|&a, &b| m[a][c].abs().total_cmp(&m[b][c].abs()))?;
        let pivot_ok = m[p][c].abs() > 1e-12 * size;
        if !pivot_ok {
            return None;
        }
        m.swap(c, p);
        inv.swap(c, p);
        let piv = m[c][c];
        for k in 0..n {
            m[c][k] /= piv;
            inv[c][k] /= piv;
        }
        for r in (0..n).filter(|&r| r != c) {
            let f = m[r][c];
            for k in 0..n {
                m[r][k] -= f * m[c][k];
                inv[r][k] -= f * inv[c][k];
            }
        }
    }
    Some(inv)
}

// ---------------------------------------------------------------------------------------------
// polygons

fn polygon_area(p: &[V2]) -> f64 {
    let n = p.len();
    0.5 * (0..n).map(|i| cross2(p[i], p[(i + 1) % n])).sum::<f64>()
}

/// Counter-clockwise and convex (every turn to the left).
fn is_convex(p: &[V2]) -> bool {
    let n = p.len();
    let a = polygon_area(p);
    a > 0.0
        && (0..n).all(|i| {
            let (u, v) = (sub2(p[(i + 1) % n], p[i]), sub2(p[(i + 2) % n], p[(i + 1) % n]));
            cross2(u, v) > 1e-12 * a
        })
}

/// Sutherland–Hodgman: `subject` clipped by the convex counter-clockwise polygon `clip`.
fn clip_polygon(subject: &[V2], clip: &[V2]) -> Vec<V2> {
    let mut out = subject.to_vec();
    for i in 0..clip.len() {
        if out.is_empty() {
            break;
        }
        let (a, b) = (clip[i], clip[(i + 1) % clip.len()]);
        let e = sub2(b, a);
        let tol = 1e-14 * (e[0] * e[0] + e[1] * e[1]);
        let side = |p: V2| cross2(e, sub2(p, a));
        let input = std::mem::take(&mut out);
        for k in 0..input.len() {
            let (s, q) = (input[k], input[(k + 1) % input.len()]);
            let (ds, dq) = (side(s), side(q));
            if ds >= -tol {
                out.push(s);
            }
            if (ds >= -tol) != (dq >= -tol) {
                let t = ds / (ds - dq);
                out.push([s[0] + t * (q[0] - s[0]), s[1] + t * (q[1] - s[1])]);
            }
        }
    }
    out
}

/// The polygon without (nearly) repeated consecutive vertices.
fn dedup(p: Vec<V2>, tol: f64) -> Vec<V2> {
    let mut out: Vec<V2> = Vec::with_capacity(p.len());
    for v in p {
        if out.last().is_none_or(|l| (v[0] - l[0]).abs() + (v[1] - l[1]).abs() > tol) {
            out.push(v);
        }
    }
    while out.len() > 1 {
        let (f, l) = (out[0], out[out.len() - 1]);
        if (f[0] - l[0]).abs() + (f[1] - l[1]).abs() > tol {
            break;
        }
        out.pop();
    }
    out
}

// ---------------------------------------------------------------------------------------------
// assembly

/// What one slave node gathers over its facets.
#[derive(Default)]
struct NodeAcc {
    /// D_ii over the covered segments.
    d: f64,
    /// ∫ φ̃ᵢ dA over the whole slave face.
    nominal: f64,
    /// The two corners of a quadratic facet's edge node.
    edge: Option<(usize, usize)>,
    /// Σ facet area × facet unit normal.
    normal: V3,
    /// M_ij by master node j.
    m: BTreeMap<usize, f64>,
    /// The master facets its facets overlap (for the geometric gap).
    masters: Vec<usize>,
    covered: bool,
    /// The other nodes of its slave facets.
    neighbours: Vec<usize>,
}

/// The integrals of one (slave facet, master facet) segment: D_ii and M_ij in local numbering.
struct Segment {
    d: [f64; MAX_NODES],
    m: [[f64; MAX_NODES]; MAX_NODES],
}

/// Build the dual mortar rows of `slave` against `master` (see the module doc).
pub fn dual_mortar(coords: &[[f64; 3]], slave: &[SurfaceFacet], master: &[SurfaceFacet], params: &MortarParams) -> Result<MortarRows, MortarError> {
    let start = Instant::now();
    let sd = params.search_distance;
    if !(sd.is_finite() && sd > 0.0) {
        return Err(MortarError::SearchDistance(sd));
    }
    let slaves = slave_facets(coords, slave)?;
    let masters = master_facets(coords, master)?;
    let tree = RTree::bulk_load(masters.iter().enumerate().map(|(k, (m, _))| GeomWithData::new(Rectangle::from_aabb(m.aabb(sd)), k)).collect());
    let mut acc = node_accumulators(&slaves);
    let mut info = MortarInfo { slave_facets: slaves.len(), master_facets: masters.len(), ..Default::default() };
    for (si, s) in slaves.iter().enumerate() {
        let mut segs = Vec::new();
        for hit in tree.locate_in_envelope_intersecting(s.f.aabb(0.0)) {
            info.candidate_pairs += 1;
            let (m, nm) = &masters[hit.data];
            if let Some(poly) = overlap(s, m, *nm, params, (si, hit.data))? {
                segs.push((hit.data, poly));
            }
        }
        info.segments += segs.len();
        let a = facet_dual(s, &segs, si)?;
        for (mi, poly) in &segs {
            let seg = integrate(s, &a, &masters[*mi].0, poly, (si, *mi))?;
            add_segment(&mut acc, s, &masters[*mi].0, *mi, &seg);
        }
    }
    let mut rows = finish(coords, acc, &masters, params, &mut info)?;
    info.seconds = start.elapsed().as_secs_f64();
    rows.info = info;
    Ok(rows)
}

fn slave_facets(coords: &[V3], slave: &[SurfaceFacet]) -> Result<Vec<SlaveFacet>, MortarError> {
    slave.iter().enumerate().map(|(k, f)| SlaveFacet::new(Facet::new(f, coords, "slave", k)?, k)).collect()
}

/// Master facets with their unit normals (at the centre).
fn master_facets(coords: &[V3], master: &[SurfaceFacet]) -> Result<Vec<(Facet, V3)>, MortarError> {
    let one = |(k, f): (usize, &SurfaceFacet)| {
        let m = Facet::new(f, coords, "master", k)?;
        let n = m.centre_normal().ok_or(MortarError::Degenerate { side: "master", facet: k })?;
        Ok((m, n))
    };
    master.iter().enumerate().map(one).collect()
}

/// One accumulator per slave node, with ∫ φᵢ dA and the area-weighted normal.
fn node_accumulators(slaves: &[SlaveFacet]) -> BTreeMap<usize, NodeAcc> {
    let mut acc: BTreeMap<usize, NodeAcc> = BTreeMap::new();
    for s in slaves {
        for a in 0..s.f.n() {
            let node = acc.entry(s.f.nodes[a]).or_default();
            node.nominal += s.d[a];
            axpy(&mut node.normal, 1.0, s.weighted_normal);
            node.neighbours.extend(s.f.nodes[..s.f.n()].iter().filter(|&&v| v != s.f.nodes[a]));
        }
        for &(e, a, b) in s.f.kind.edges() {
            let edge = Some((s.f.nodes[a].min(s.f.nodes[b]), s.f.nodes[a].max(s.f.nodes[b])));
            acc.get_mut(&s.f.nodes[e]).expect("slave node accumulator").edge = edge;
        }
    }
    acc
}

/// The slave part of row i, (T⁻¹)_ki: +1 at a corner (or a linear facet's node); at the edge
/// node of corners a, b: 1/(1 − 2α) there and −α/(1 − 2α) at a and b.
fn slave_part(node: usize, edge: Option<(usize, usize)>) -> Vec<(usize, f64)> {
    match edge {
        None => vec![(node, 1.0)],
        Some((a, b)) => {
            let s = 1.0 / (1.0 - 2.0 * ALPHA);
            vec![(node, s), (a, -ALPHA * s), (b, -ALPHA * s)]
        }
    }
}

/// The dual coefficients of a slave facet: its own when fully covered by `segs`, else those of
/// the covered part (Cichosz & Bischoff 2011; Popp et al. 2013), falling back to its own when
/// the covered part is too thin for M̂ to be inverted.
fn facet_dual(s: &SlaveFacet, segs: &[(usize, Vec<V2>)], id: usize) -> Result<Mat, MortarError> {
    let covered: f64 = segs.iter().map(|(_, p)| polygon_area(p).abs()).sum();
    if segs.is_empty() || covered >= (1.0 - FULL_COVER) * s.plane_area {
        return Ok(s.a);
    }
    Ok(s.partial_dual(segs, id)?.unwrap_or(s.a))
}

/// The clip polygon of a slave and a master facet on the slave's plane, or None when they do
/// not face each other, do not overlap, or are farther apart than the search distance.
fn overlap(s: &SlaveFacet, m: &Facet, nm: V3, params: &MortarParams, ids: (usize, usize)) -> Result<Option<Vec<V2>>, MortarError> {
    if -dot(nm, s.plane.n) <= params.min_opposition {
        return Ok(None);
    }
    let sp = s.plane.polygon(&s.f);
    let scale2 = s.plane_area.sqrt();
    let poly = dedup(clip_polygon(&s.plane.polygon(m), &sp), 1e-13 * scale2);
    if poly.len() < 3 || polygon_area(&poly).abs() <= SLIVER_FRACTION * s.plane_area {
        return Ok(None);
    }
    if min_gap(s, m, &poly, ids)? > params.search_distance {
        return Ok(None);
    }
    Ok(Some(poly))
}

/// Slave and master parametric coordinates of the plane point p.
fn project(s: &SlaveFacet, m: &Facet, p: V2, ids: (usize, usize)) -> Result<(V2, V2), MortarError> {
    let fail = |side| MortarError::Projection { slave: ids.0, master: ids.1, side };
    let xs = s.plane.invert(&s.f, p).ok_or(fail("slave"))?;
    let xm = s.plane.invert(m, p).ok_or(fail("master"))?;
    Ok((xs, xm))
}

/// The smallest |(x_m − x_s)·n₀| over the vertices of the clip polygon.
fn min_gap(s: &SlaveFacet, m: &Facet, poly: &[V2], ids: (usize, usize)) -> Result<f64, MortarError> {
    let mut g = f64::INFINITY;
    for &p in poly {
        let (xs, xm) = project(s, m, p, ids)?;
        let (ps, _) = s.f.map(&s.f.kind.shape(xs));
        let (pm, _) = m.map(&m.kind.shape(xm));
        g = g.min(dot(sub(pm, ps), s.plane.n).abs());
    }
    Ok(g)
}

/// Gauss points (plane point, plane weight) of a clip polygon: fan triangles from the
/// vertex centroid, the 7-point rule on each.
fn fan_points(poly: &[V2]) -> Vec<(V2, f64)> {
    let k = poly.len() as f64;
    let c = [poly.iter().map(|p| p[0]).sum::<f64>() / k, poly.iter().map(|p| p[1]).sum::<f64>() / k];
    let mut out = Vec::with_capacity(7 * poly.len());
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let area = 0.5 * cross2(sub2(a, c), sub2(b, c)).abs();
        for (l, w) in dunavant7() {
            let p = [l[0] * c[0] + l[1] * a[0] + l[2] * b[0], l[0] * c[1] + l[1] * a[1] + l[2] * b[1]];
            out.push((p, w * area));
        }
    }
    out
}

/// D_ii = ∫ ψᵢ and M_ij = ∫ ψᵢ φ_j over a clip polygon, with ψ from the coefficients `a`.
fn integrate(s: &SlaveFacet, a: &Mat, m: &Facet, poly: &[V2], ids: (usize, usize)) -> Result<Segment, MortarError> {
    let mut seg = Segment { d: [0.0; MAX_NODES], m: [[0.0; MAX_NODES]; MAX_NODES] };
    for (p, w) in fan_points(poly) {
        let (xs, xm) = project(s, m, p, ids)?;
        let ss = s.f.kind.shape(xs);
        let psi = s.psi(a, &ss);
        let sm = m.kind.shape(xm);
        let wj = w * s.jacobian_ratio(&ss);
        let psi = &psi[..s.f.n()];
        add_scaled(&mut seg.d, wj, psi);
        add_outer(&mut seg.m, wj, psi, &sm.phi[..m.n()]);
    }
    Ok(seg)
}

fn add_segment(acc: &mut BTreeMap<usize, NodeAcc>, s: &SlaveFacet, m: &Facet, mi: usize, seg: &Segment) {
    for i in 0..s.f.n() {
        let node = acc.get_mut(&s.f.nodes[i]).expect("slave node accumulator");
        node.covered = true;
        if !node.masters.contains(&mi) {
            node.masters.push(mi);
        }
        node.d += seg.d[i];
        for j in 0..m.n() {
            *node.m.entry(m.nodes[j]).or_default() += seg.m[i][j];
        }
    }
}

/// Rows from the accumulated nodes: the coverage rule, normalization and weighted gaps.
fn finish(
    coords: &[V3],
    acc: BTreeMap<usize, NodeAcc>,
    masters: &[(Facet, V3)],
    params: &MortarParams,
    info: &mut MortarInfo,
) -> Result<MortarRows, MortarError> {
    let uncovered: Vec<usize> = acc.iter().filter(|(_, a)| !a.covered).map(|(&k, _)| k).collect();
    if let (Some(&node), false) = (uncovered.first(), params.allow_uncovered) {
        let (distance, nodes) = (params.search_distance, acc.len());
        return Err(MortarError::NoMaster { node, x: coords[node], distance, uncovered: uncovered.len(), nodes });
    }
    info.nodes_uncovered = uncovered.len();
    let mut rows = MortarRows { uncovered, ..Default::default() };
    // each covered node's row, its normal and geometric gap, and what neighbours beyond the
    // master's edge handed on to it (ΣD, and Σ D × their rows)
    struct Raw {
        d: f64,
        row: Vec<(usize, f64)>,
        n: V3,
        geometric: f64,
        handed: Option<(f64, BTreeMap<usize, f64>)>,
    }
    let mut raw: BTreeMap<usize, Raw> = BTreeMap::new();
    let mut beyond = Vec::new();
    for (node, a) in acc.iter().filter(|(_, a)| a.covered) {
        if a.d <= params.min_coverage * a.nominal {
            info.rows_dropped += 1;
            continue;
        }
        let n = scale(a.normal, 1.0 / norm(a.normal));
        let mut row = slave_part(*node, a.edge);
        row.extend(a.m.iter().filter(|(_, m)| m.abs() > PRUNE_FRACTION * a.d).map(|(&j, m)| (j, -m / a.d)));
        let geometric = geometric_gap(coords[*node], n, a.masters.iter().map(|&k| &masters[k].0));
        if params.trim_edge && geometric.is_nan() && a.d < 0.5 * a.nominal {
            beyond.push(*node);
        }
        raw.insert(*node, Raw { d: a.d, row, n, geometric, handed: None });
    }
    // the edge of the contact zone: a node beyond the master's edge hands its row, times its
    // D_ii, to its neighbours that keep theirs, in equal shares
    for i in beyond {
        let Some(r) = raw.remove(&i) else { continue };
        let takers: Vec<usize> = acc[&i].neighbours.iter().copied().filter(|j| raw.get(j).is_some_and(|x| !x.geometric.is_nan())).collect();
        info.rows_dropped += 1;
        info.rows_handed_on += usize::from(!takers.is_empty());
        let share = r.d / takers.len().max(1) as f64;
        for j in takers {
            let (d, sum) = raw.get_mut(&j).expect("a taker keeps its row").handed.get_or_insert_with(Default::default);
            *d += share;
            for &(k, c) in &r.row {
                *sum.entry(k).or_default() += share * c;
            }
        }
    }
    for (node, mut r) in raw {
        if let Some((extra, mut sum)) = r.handed.take() {
            // (D_jj row_j + Σ shares) / (D_jj + Σ D shares), the row's own entries first
            let d = r.d + extra;
            let mut row: Vec<(usize, f64)> = r.row.iter().map(|&(k, c)| (k, (r.d * c + sum.remove(&k).unwrap_or(0.0)) / d)).collect();
            row.extend(sum.into_iter().map(|(k, c)| (k, c / d)));
            row.retain(|(_, c)| c.abs() > PRUNE_FRACTION);
            (r.row, r.d) = (row, d);
        }
        let gap = -r.row.iter().map(|&(k, c)| c * dot(coords[k], r.n)).sum::<f64>();
        rows.geometric_gap.push(r.geometric);
        rows.node.push(node);
        rows.normal.push(r.n);
        rows.area.push(r.d);
        rows.coupling.push(r.row);
        rows.gap.push(gap);
    }
    Ok(rows)
}

/// The distance along the unit normal `n` from `x` to the nearest of the `masters` facets that
/// its normal line meets (on their true maps, by Newton on the plane through `x` normal to n);
/// NaN where it meets none.
fn geometric_gap<'a>(x: V3, n: V3, masters: impl Iterator<Item = &'a Facet>) -> f64 {
    let e = if n[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
    let t0 = sub(e, scale(n, dot(e, n)));
    let t0 = scale(t0, 1.0 / norm(t0));
    let plane = Plane { c: x, n, t: [t0, cross(n, t0)] };
    // inside the reference facet, with a margin of round-off
    let inside = |k: Kind, xi: V2| {
        let m = 1e-9;
        if k.is_tri() {
            xi[0] >= -m && xi[1] >= -m && xi[0] + xi[1] <= 1.0 + m
        } else {
            xi[0].abs() <= 1.0 + m && xi[1].abs() <= 1.0 + m
        }
    };
    let mut best = f64::NAN;
    for m in masters {
        let Some(xi) = plane.invert(m, [0.0, 0.0]).filter(|&xi| inside(m.kind, xi)) else { continue };
        let (xm, _) = m.map(&m.kind.shape(xi));
        let g = dot(sub(xm, x), n);
        if best.is_nan() || g.abs() < best.abs() {
            best = g;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A structured patch over (u, v) ∈ [0, 1]² with nx × ny cells mapped by `map`; tri3 splits
    /// each cell in two. `up`: facets ordered counter-clockwise in (u, v), else reversed.
    struct Patch {
        /// Node id of grid point (i, j) at index j (nx + 1) + i.
        ids: Vec<usize>,
        facets: Vec<Vec<usize>>,
    }

    fn patch(coords: &mut Vec<V3>, nx: usize, ny: usize, tri: bool, up: bool, map: &dyn Fn(f64, f64) -> V3) -> Patch {
        let mut ids = Vec::new();
        for j in 0..=ny {
            for i in 0..=nx {
                ids.push(coords.len());
                coords.push(map(i as f64 / nx as f64, j as f64 / ny as f64));
            }
        }
        let id = |i: usize, j: usize| ids[j * (nx + 1) + i];
        let mut facets = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let q = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                let mut fs = if tri { vec![vec![q[0], q[1], q[2]], vec![q[0], q[2], q[3]]] } else { vec![q.to_vec()] };
                if !up {
                    fs.iter_mut().for_each(|f| f.reverse());
                }
                facets.extend(fs);
            }
        }
        Patch { ids, facets }
    }

    fn views(p: &Patch) -> Vec<SurfaceFacet<'_>> {
        p.facets.iter().map(|f| SurfaceFacet { nodes: f }).collect()
    }

    fn run(coords: &[V3], s: &Patch, m: &Patch, params: &MortarParams) -> Result<MortarRows, MortarError> {
        dual_mortar(coords, &views(s), &views(m), params)
    }

    fn params(sd: f64) -> MortarParams {
        MortarParams { search_distance: sd, ..Default::default() }
    }

    /// ∫ φᵢ dA of flat straight-sided tri3 / parallelogram quad4 facets: facet area / nodes.
    fn nodal_areas(coords: &[V3], p: &Patch) -> BTreeMap<usize, f64> {
        let mut out = BTreeMap::new();
        for f in &p.facets {
            let area = match f.len() {
                3 => 0.5 * norm(cross(sub(coords[f[1]], coords[f[0]]), sub(coords[f[2]], coords[f[0]]))),
                _ => norm(cross(sub(coords[f[1]], coords[f[0]]), sub(coords[f[3]], coords[f[0]]))),
            };
            for &n in f {
                *out.entry(n).or_insert(0.0) += area / f.len() as f64;
            }
        }
        out
    }

    fn flat(z: f64) -> impl Fn(f64, f64) -> V3 {
        move |u, v| [u, v, z]
    }

    /// Interior nodes shifted in-plane by up to `amp` (deterministic), boundary kept.
    fn wobbly(amp: f64, z: impl Fn(f64, f64) -> f64) -> impl Fn(f64, f64) -> V3 {
        move |u: f64, v: f64| {
            let inner = |t: f64| t > 1e-9 && t < 1.0 - 1e-9;
            let (du, dv) = if inner(u) && inner(v) { (amp * (17.0 * u + 5.0 * v).sin(), amp * (3.0 * u - 11.0 * v).cos()) } else { (0.0, 0.0) };
            let (x, y) = (u + du, v + dv);
            [x, y, z(x, y)]
        }
    }

    fn coefficient(row: &[(usize, f64)], node: usize) -> f64 {
        row.iter().find(|(k, _)| *k == node).map_or(0.0, |(_, c)| *c)
    }

    #[test]
    fn tri3_dual_basis_is_4_lambda_minus_1() {
        let coords = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.3, 1.5, 0.2]];
        let f = Facet::new(&SurfaceFacet { nodes: &[0, 1, 2] }, &coords, "slave", 0).unwrap();
        let (a, d) = dual_coefficients(&f).unwrap();
        let area = f.area();
        for (i, row) in a.iter().enumerate().take(3) {
            assert!((d[i] - area / 3.0).abs() < 1e-14 * area);
            for (j, aij) in row.iter().enumerate().take(3) {
                let want = if i == j { 3.0 } else { -1.0 };
                assert!((aij - want).abs() < 1e-12, "a[{i}][{j}] = {aij}");
            }
        }
    }

    #[test]
    fn warped_quad_dual_basis_is_biorthogonal() {
        let coords = [[0.0, 0.0, 0.0], [1.2, 0.1, 0.15], [1.0, 0.9, -0.1], [-0.1, 1.1, 0.2]];
        let f = Facet::new(&SurfaceFacet { nodes: &[0, 1, 2, 3] }, &coords, "slave", 0).unwrap();
        let s = SlaveFacet::new(f, 0).unwrap();
        let mut g = [[0.0; MAX_NODES]; MAX_NODES];
        for (xi, w) in s.f.kind.rule() {
            let sh = s.f.kind.shape(xi);
            let (psi, wj) = (s.psi(&s.a, &sh), w * norm(s.f.jacobian(xi)));
            add_outer(&mut g, wj, &psi[..4], &sh.phi[..4]);
        }
        for (i, row) in g.iter().enumerate().take(4) {
            for (k, gik) in row.iter().enumerate().take(4) {
                let want = if i == k { s.d[k] } else { 0.0 };
                assert!((gik - want).abs() < 1e-14, "∫ψ{i}φ{k} = {gik} (want {want})");
            }
        }
    }

    /// Matching flat grids, master offset by a smooth non-linear field g: node-to-node exactly.
    fn check_matching(tri: bool) {
        let g = |u: f64, v: f64| 0.02 + 0.01 * (3.0 * u).sin() * v * v;
        let mut coords = Vec::new();
        let s = patch(&mut coords, 4, 3, tri, true, &flat(0.0));
        let m = patch(&mut coords, 4, 3, tri, false, &|u, v| [u, v, g(u, v)]);
        let rows = run(&coords, &s, &m, &params(0.05)).unwrap();
        let areas = nodal_areas(&coords, &s);
        assert_eq!(rows.len(), s.ids.len());
        assert_eq!(rows.info.rows_dropped + rows.info.nodes_uncovered, 0);
        for (r, (&sn, &mn)) in s.ids.iter().zip(&m.ids).enumerate() {
            assert_eq!(rows.node[r], sn);
            assert_eq!(rows.coupling[r].len(), 2, "row {r}: {:?}", rows.coupling[r]);
            assert!((coefficient(&rows.coupling[r], sn) - 1.0).abs() < 1e-13);
            assert!((coefficient(&rows.coupling[r], mn) + 1.0).abs() < 1e-13);
            assert!((rows.area[r] - areas[&sn]).abs() < 1e-14, "area {} vs {}", rows.area[r], areas[&sn]);
            let x = coords[sn];
            assert!((rows.gap[r] - g(x[0], x[1])).abs() < 1e-14, "gap {} vs {}", rows.gap[r], g(x[0], x[1]));
            assert!((rows.normal[r][2] - 1.0).abs() < 1e-15);
            assert!((rows.row_norms_squared()[r] - 2.0).abs() < 1e-13);
        }
    }

    #[test]
    fn matching_quad4_is_node_to_node() {
        check_matching(false);
    }

    #[test]
    fn matching_tri3_is_node_to_node() {
        check_matching(true);
    }

    /// Linear normal offset of the master.
    fn f_lin(x: f64, y: f64) -> f64 {
        0.03 + 0.01 * x - 0.007 * y
    }

    /// Slave (tri or quad, ns cells) on a wobbly master (tri or quad, nm cells) over the unit
    /// square, master at z = f_lin; the whole pair mapped by `rot` (a rigid motion).
    fn nonmatching(stri: bool, ns: usize, mtri: bool, nm: usize, rot: &dyn Fn(V3) -> V3) -> (Vec<V3>, Patch, MortarRows) {
        let mut coords = Vec::new();
        let s = patch(&mut coords, ns, ns, stri, true, &|u, v| rot([u, v, 0.0]));
        let w = wobbly(0.2 / nm as f64, f_lin);
        let m = patch(&mut coords, nm, nm, mtri, false, &|u, v| rot(w(u, v)));
        let rows = run(&coords, &s, &m, &params(0.05)).unwrap();
        (coords, s, rows)
    }

    /// Test 2's checks, in the frame given by `rot` (slave nodes are rot([x, y, 0])).
    fn check_nonmatching(s: &Patch, rows: &MortarRows, ns: usize, rot: &dyn Fn(V3) -> V3) {
        assert_eq!(rows.len(), s.ids.len());
        assert_eq!(rows.info.rows_dropped + rows.info.nodes_uncovered, 0);
        let total: f64 = rows.area.iter().sum();
        assert!((total - 1.0).abs() < 1e-13, "Σ D_ii = {total}");
        let n = rot([0.0, 0.0, 1.0]);
        let o = rot([0.0; 3]);
        let n = sub(n, o);
        for r in 0..rows.len() {
            let masters: f64 = rows.coupling[r][1..].iter().map(|(_, c)| -c).sum();
            assert!((masters - 1.0).abs() < 1e-12, "row {r}: Σ M_ij/D_ii = {masters}");
            let (i, j) = (r % (ns + 1), r / (ns + 1));
            let (x, y) = (i as f64 / ns as f64, j as f64 / ns as f64);
            assert!((rows.gap[r] - f_lin(x, y)).abs() < 1e-12, "row {r} at ({x}, {y}): gap {} vs {}", rows.gap[r], f_lin(x, y));
            assert!(norm(sub(rows.normal[r], n)) < 1e-14);
            let q = rows.row_norms_squared()[r];
            assert!(q > 1.0, "row {r}: ‖row‖² = {q}");
        }
    }

    #[test]
    fn nonmatching_quad4_on_finer_quad4_reproduces_linear_gap() {
        let id = |x: V3| x;
        let (_, s, rows) = nonmatching(false, 4, false, 7, &id);
        check_nonmatching(&s, &rows, 4, &id);
        assert!(rows.coupling.iter().all(|r| r.len() > 2));
    }

    #[test]
    fn nonmatching_tri3_on_quad4_and_quad4_on_tri3_reproduce_linear_gap() {
        let id = |x: V3| x;
        let (_, s, rows) = nonmatching(true, 4, false, 7, &id);
        check_nonmatching(&s, &rows, 4, &id);
        let (_, s, rows) = nonmatching(false, 5, true, 3, &id);
        check_nonmatching(&s, &rows, 5, &id);
    }

    /// A fixed "random" rotation (axis (1, −2, 3), angle 0.83) and a translation.
    fn rotation(x: V3) -> V3 {
        let k = scale([1.0, -2.0, 3.0], 1.0 / 14f64.sqrt());
        let (c, s) = (0.83f64.cos(), 0.83f64.sin());
        let mut y = scale(x, c);
        axpy(&mut y, s, cross(k, x));
        axpy(&mut y, dot(k, x) * (1.0 - c), k);
        [y[0] + 0.4, y[1] - 1.3, y[2] + 2.1]
    }

    #[test]
    fn rotated_nonmatching_pair_gives_the_same_rows() {
        let id = |x: V3| x;
        for (stri, ns, mtri, nm) in [(false, 4, false, 7), (true, 4, false, 7), (false, 5, true, 3)] {
            let (_, s, rows) = nonmatching(stri, ns, mtri, nm, &rotation);
            check_nonmatching(&s, &rows, ns, &rotation);
            let (_, _, flat) = nonmatching(stri, ns, mtri, nm, &id);
            for r in 0..rows.len() {
                assert!((rows.area[r] - flat.area[r]).abs() < 1e-14);
                assert_eq!(rows.coupling[r].len(), flat.coupling[r].len());
                for (a, b) in rows.coupling[r].iter().zip(&flat.coupling[r]) {
                    assert!(a.0 == b.0 && (a.1 - b.1).abs() < 1e-12, "{a:?} vs {b:?}");
                }
            }
        }
    }

    fn norms_range(rows: &MortarRows) -> (f64, f64) {
        let q = rows.row_norms_squared();
        (q.iter().copied().fold(f64::INFINITY, f64::min), q.iter().copied().fold(0.0, f64::max))
    }

    /// Master finer than the slave: every ‖row‖² = 1 + Σ_j (M_ij/D_ii)² lies in (1, 2), below
    /// the node-to-node value 2.
    #[test]
    fn row_norms_squared_between_1_and_2_on_a_finer_master() {
        let id = |x: V3| x;
        for (stri, ns, mtri, nm) in [(false, 4, false, 7), (true, 4, false, 7), (false, 3, true, 8), (false, 4, false, 13)] {
            let (_, _, rows) = nonmatching(stri, ns, mtri, nm, &id);
            let (lo, hi) = norms_range(&rows);
            assert!(lo > 1.0 && hi < 2.0, "{ns} on {nm}: ‖row‖² in [{lo}, {hi}]");
        }
    }

    /// Master coarser than the slave: at the face's corners the dual weights extrapolate the
    /// master (negative M_ij) and ‖row‖² exceeds 2 (2.16 for a 5×5 quad4 slave on a 3×3 tri3
    /// master); interior rows stay below 2.
    #[test]
    fn row_norms_squared_exceed_2_at_corners_on_a_coarser_master() {
        let id = |x: V3| x;
        let (_, s, rows) = nonmatching(false, 5, true, 3, &id);
        let (lo, hi) = norms_range(&rows);
        assert!(lo > 1.0 && hi > 2.0 && hi < 2.3, "‖row‖² in [{lo}, {hi}]");
        let q = rows.row_norms_squared();
        assert!(q[0] > 2.0, "corner row: {}", q[0]);
        for (r, &node) in rows.node.iter().enumerate() {
            let k = s.ids.iter().position(|&n| n == node).unwrap();
            let (i, j) = (k % 6, k / 6);
            if (1..5).contains(&i) && (1..5).contains(&j) {
                assert!(q[r] < 2.0, "interior row {r}: {}", q[r]);
            }
        }
    }

    /// Slave on the cylinder r = 1 (θ ∈ [−0.3, 0.3], y ∈ [0, 0.6], n × n cells), master on
    /// r = 1 + δ over a larger patch with a finer, non-nested grid: the largest |dᵢ − δ|.
    fn cylinder_gap_error(n: usize, tri: bool, delta: f64) -> f64 {
        let cyl = |r: f64, t0: f64, t1: f64, y0: f64, y1: f64| {
            move |u: f64, v: f64| {
                let t = t0 + u * (t1 - t0);
                [r * t.sin(), y0 + v * (y1 - y0), r * t.cos()]
            }
        };
        let mut coords = Vec::new();
        let s = patch(&mut coords, n, n, tri, true, &cyl(1.0, -0.3, 0.3, 0.0, 0.6));
        let nm = (2.3 * n as f64) as usize;
        let m = patch(&mut coords, nm, nm, !tri, false, &cyl(1.0 + delta, -0.35, 0.35, -0.05, 0.65));
        let rows = run(&coords, &s, &m, &params(0.05)).unwrap();
        assert_eq!(rows.len(), s.ids.len());
        rows.gap.iter().map(|g| (g - delta).abs()).fold(0.0, f64::max)
    }

    /// |dᵢ − δ| ≤ 0.1 h² (R = 1), and halving h divides it by about 4 (quad4 slave on a tri3
    /// master and tri3 on quad4).
    #[test]
    fn curved_cylinder_gap_is_delta_to_second_order() {
        for tri in [false, true] {
            let e: Vec<f64> = [4, 8, 16].iter().map(|&n| cylinder_gap_error(n, tri, 0.01)).collect();
            for (k, n) in [4.0, 8.0, 16.0].into_iter().enumerate() {
                let h = 0.6 / n;
                assert!(e[k] < 0.1 * h * h, "tri {tri}, h = {h}: |d − δ| = {}", e[k]);
            }
            for k in 0..2 {
                let ratio = e[k] / e[k + 1];
                assert!(ratio > 3.0 && ratio < 5.5, "tri {tri}: halving h divides the error by {ratio}");
            }
        }
    }

    #[test]
    fn master_beyond_the_search_distance_is_an_error_naming_a_slave_node() {
        let mut coords = Vec::new();
        let s = patch(&mut coords, 3, 3, false, true, &flat(0.0));
        let m = patch(&mut coords, 5, 5, false, false, &flat(0.2));
        let err = run(&coords, &s, &m, &params(0.1)).unwrap_err();
        assert_eq!(
            err.to_string(),
            "slave node 0 at (0, 0, 0) finds no master facet within the search distance 1.0e-1 \
             (16 of 16 slave nodes uncovered)"
        );
        assert!(run(&coords, &s, &m, &params(0.25)).is_ok());
        // Within reach of the boxes but beside the slave face (no overlap): the same error.
        let mut coords = Vec::new();
        let s = patch(&mut coords, 3, 3, false, true, &flat(0.0));
        let m = patch(&mut coords, 3, 3, false, false, &|u, v| [u + 1.05, v, 0.01]);
        let err = run(&coords, &s, &m, &params(0.1)).unwrap_err();
        assert!(matches!(err, MortarError::NoMaster { node: 0, uncovered: 16, .. }), "{err}");
    }

    #[test]
    fn master_facing_the_same_way_is_not_found() {
        let mut coords = Vec::new();
        let s = patch(&mut coords, 2, 2, false, true, &flat(0.0));
        let m = patch(&mut coords, 3, 3, false, true, &flat(0.01));
        let err = run(&coords, &s, &m, &params(0.1)).unwrap_err();
        assert!(matches!(err, MortarError::NoMaster { uncovered: 9, .. }), "{err}");
    }

    /// Slave [0, 1.5] × [0, 1] (6 × 4 quads, h = 0.25) on master [0, 1]²: the nodes at
    /// x ≥ 1.25 overlap no master facet. Default: an error naming the first of them;
    /// `allow_uncovered`: those 10 nodes are dropped and counted, the rest keep exact rows.
    #[test]
    fn slave_face_larger_than_the_master() {
        let mut coords = Vec::new();
        let s = patch(&mut coords, 6, 4, false, true, &|u, v| [1.5 * u, v, 0.0]);
        let m = patch(&mut coords, 7, 7, false, false, &wobbly(0.2 / 7.0, f_lin));
        let err = run(&coords, &s, &m, &params(0.05)).unwrap_err();
        assert!(err.to_string().starts_with("slave node 5 at (1.25, 0, 0) finds no master facet"), "{err}");
        assert!(matches!(err, MortarError::NoMaster { node: 5, uncovered: 10, nodes: 35, .. }));
        let p = MortarParams { allow_uncovered: true, ..params(0.05) };
        let rows = run(&coords, &s, &m, &p).unwrap();
        assert_eq!((rows.info.nodes_uncovered, rows.info.rows_dropped, rows.len()), (10, 0, 25));
        let areas = nodal_areas(&coords, &s);
        for r in 0..rows.len() {
            let x = coords[rows.node[r]];
            assert!(x[0] < 1.0 + 1e-12);
            let masters: f64 = rows.coupling[r][1..].iter().map(|(_, c)| -c).sum();
            assert!((masters - 1.0).abs() < 1e-12, "row {r}: Σ M_ij/D_ii = {masters}");
            // Nodes on x = 1 have only their left facets covered: D_ii = half the nodal area.
            let want = if x[0] > 1.0 - 1e-12 { 0.5 * areas[&rows.node[r]] } else { areas[&rows.node[r]] };
            assert!((rows.area[r] - want).abs() < 1e-14, "row {r}: D_ii = {} vs {want}", rows.area[r]);
            if x[0] < 0.75 + 1e-12 {
                assert!((rows.gap[r] - f_lin(x[0], x[1])).abs() < 1e-12);
            }
        }
    }

    /// Slave [0, 1.25] × [0, 1] (5 × 4 quads, h = 0.25) on master [0, 1.1] × [0, 1] at
    /// z = f_lin: the facets at x ≥ 1 are 40 % covered, on the side away from the nodes at
    /// x = 1.25. With the dual basis of the covered part every node keeps a row that
    /// reproduces the linear gap exactly, with D_ii = ∫_covered φᵢ dA (0.16 of the nodal area
    /// at x = 1.25); min_coverage = 0.2 drops those 5 rows.
    #[test]
    fn partly_covered_facets_use_the_dual_basis_of_the_covered_part() {
        let mut coords = Vec::new();
        let s = patch(&mut coords, 5, 4, false, true, &|u, v| [1.25 * u, v, 0.0]);
        let m = patch(&mut coords, 9, 7, false, false, &|u, v| [1.1 * u, v, f_lin(1.1 * u, v)]);
        let rows = run(&coords, &s, &m, &MortarParams { trim_edge: false, ..params(0.05) }).unwrap();
        assert_eq!((rows.len(), rows.info.rows_dropped), (30, 0));
        let areas = nodal_areas(&coords, &s);
        let total: f64 = rows.area.iter().sum();
        assert!((total - 1.1).abs() < 1e-13, "Σ D_ii = {total}");
        let q = rows.row_norms_squared();
        for r in 0..rows.len() {
            let x = coords[rows.node[r]];
            let masters: f64 = rows.coupling[r][1..].iter().map(|(_, c)| -c).sum();
            assert!((masters - 1.0).abs() < 1e-12, "row {r}: Σ M_ij/D_ii = {masters}");
            let err = rows.gap[r] - f_lin(x[0], x[1]);
            assert!(err.abs() < 1e-12, "row {r} at {x:?}: gap error {err}");
            if x[0] > 1.2 {
                let ratio = rows.area[r] / areas[&rows.node[r]];
                assert!((ratio - 0.16).abs() < 1e-12, "row {r}: D_ii/∫φᵢ = {ratio}");
                assert!(q[r] > 2.0, "row {r}: ‖row‖² = {}", q[r]);
            }
        }
        let p = MortarParams { min_coverage: 0.2, trim_edge: false, ..params(0.05) };
        let rows = run(&coords, &s, &m, &p).unwrap();
        assert_eq!((rows.len(), rows.info.rows_dropped), (25, 5));
        assert!(rows.node.iter().all(|&n| coords[n][0] < 1.2));
        // by default the 5 nodes beyond the master's edge (x = 1.25 > 1.1) hand their rows to
        // the nodes at x = 1: Σ D_ii stays the covered area, every row still sums to 0 (a rigid
        // translation of the master moves no gap), and the rows at x ≤ 0.75 are untouched
        let rows = run(&coords, &s, &m, &params(0.05)).unwrap();
        assert_eq!((rows.len(), rows.info.rows_dropped, rows.info.rows_handed_on), (25, 5, 5));
        let total: f64 = rows.area.iter().sum();
        assert!((total - 1.1).abs() < 1e-13, "Σ D_ii = {total}");
        for r in 0..rows.len() {
            let x = coords[rows.node[r]];
            let sum: f64 = rows.coupling[r].iter().map(|(_, c)| c).sum();
            assert!(sum.abs() < 1e-12 && rows.coupling[r][0] == (rows.node[r], rows.coupling[r][0].1), "row {r}: Σ c = {sum}");
            if x[0] < 0.75 + 1e-12 {
                assert!((rows.gap[r] - f_lin(x[0], x[1])).abs() < 1e-12);
            }
            if x[0] > 1.0 - 1e-12 {
                assert!(rows.coupling[r].iter().any(|&(k, _)| coords[k][0] > 1.2), "row {r} took its neighbour's");
            }
        }
    }

    /// A quadratic structured patch (tri6 or quad8) on the (2nx + 1) × (2ny + 1) lattice of
    /// (u, v) ∈ [0, 1]² mapped by `map` (quad8 leaves the cell centres unused).
    fn patch2(coords: &mut Vec<V3>, nx: usize, ny: usize, tri: bool, up: bool, map: &dyn Fn(f64, f64) -> V3) -> Patch {
        let base = coords.len();
        for j in 0..=2 * ny {
            for i in 0..=2 * nx {
                coords.push(map(i as f64 / (2 * nx) as f64, j as f64 / (2 * ny) as f64));
            }
        }
        let l = |i: usize, j: usize| base + j * (2 * nx + 1) + i;
        let mut facets = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let (a, b) = (2 * i, 2 * j);
                let q = [l(a, b), l(a + 2, b), l(a + 2, b + 2), l(a, b + 2)];
                let mid = l(a + 1, b + 1);
                let e = [l(a + 1, b), l(a + 2, b + 1), l(a + 1, b + 2), l(a, b + 1)];
                let mut fs = if tri {
                    vec![vec![q[0], q[1], q[2], e[0], e[1], mid], vec![q[0], q[2], q[3], mid, e[2], e[3]]]
                } else {
                    vec![vec![q[0], q[1], q[2], q[3], e[0], e[1], e[2], e[3]]]
                };
                if !up {
                    for f in &mut fs {
                        let c = f.len() / 2;
                        f[1..c].reverse();
                        f[c..].reverse();
                    }
                }
                facets.extend(fs);
            }
        }
        let ids = facets.iter().flatten().copied().collect::<std::collections::BTreeSet<_>>();
        Patch { ids: ids.into_iter().collect(), facets }
    }

    /// The modified quadratic dual basis is biorthogonal to φ̃ and has positive D̃: corners
    /// 2/15 (tri6) or 1/20 (quad8) of the area, edge nodes 1/5.
    #[test]
    fn quadratic_modified_dual_basis() {
        let mut coords = Vec::new();
        for (tri, corner) in [(true, 2.0 / 15.0), (false, 1.0 / 20.0)] {
            let p = patch2(&mut coords, 1, 1, tri, true, &|u, v| [2.0 * u, 1.5 * v, 0.0]);
            let f = Facet::new(&SurfaceFacet { nodes: &p.facets[0] }, &coords, "slave", 0).unwrap();
            let s = SlaveFacet::new(f, 0).unwrap();
            let (n, c, area) = (s.f.n(), s.f.kind.corners(), s.f.area());
            for k in 0..n {
                let want = if k < c { corner } else { 0.2 };
                assert!((s.d[k] / area - want).abs() < 1e-14, "tri {tri}: D̃_{k}/A = {}", s.d[k] / area);
            }
            let t = s.f.kind.transformation();
            let mut g = [[0.0; MAX_NODES]; MAX_NODES];
            for (xi, w) in s.f.kind.rule() {
                let sh = s.f.kind.shape(xi);
                let (psi, wj) = (s.psi(&s.a, &sh), w * norm(s.f.jacobian(xi)));
                add_outer(&mut g, wj, &psi[..n], &mat_vec(&t, &sh.phi, n)[..n]);
            }
            for (i, row) in g.iter().enumerate().take(n) {
                for (k, gik) in row.iter().enumerate().take(n) {
                    let want = if i == k { s.d[k] } else { 0.0 };
                    assert!((gik - want).abs() < 1e-13, "tri {tri}: ∫ψ{i}φ̃{k} = {gik}");
                }
            }
        }
    }

    /// Quadratic slaves (tri6, quad8; 3 × 3 cells) on a wobbly quad4 master (7 × 7) and on a
    /// quad8 master (5 × 5) at z = f_lin: the slave and master parts of every row each sum to
    /// ±1, Σ D̃_ii = 1, and the gap equals f_lin at the node (linear fields reproduced).
    #[test]
    fn quadratic_slaves_reproduce_linear_gap() {
        for (stri, mquad8) in [(true, false), (false, false), (true, true), (false, true)] {
            let mut coords = Vec::new();
            let s = patch2(&mut coords, 3, 3, stri, true, &flat(0.0));
            let m = if mquad8 {
                patch2(&mut coords, 5, 5, false, false, &|u, v| [u, v, f_lin(u, v)])
            } else {
                patch(&mut coords, 7, 7, false, false, &wobbly(0.2 / 7.0, f_lin))
            };
            let rows = run(&coords, &s, &m, &params(0.05)).unwrap();
            let case = format!("slave tri {stri}, master quad8 {mquad8}");
            assert_eq!(rows.len(), s.ids.len(), "{case}");
            let total: f64 = rows.area.iter().sum();
            assert!((total - 1.0).abs() < 1e-13, "{case}: Σ D_ii = {total}");
            assert!(rows.area.iter().all(|&d| d > 0.0));
            for r in 0..rows.len() {
                let (mut cs, mut cm) = (0.0, 0.0);
                for &(k, c) in &rows.coupling[r] {
                    if s.ids.contains(&k) {
                        cs += c
                    } else {
                        cm += c
                    }
                }
                assert!((cs - 1.0).abs() < 1e-13 && (cm + 1.0).abs() < 1e-12, "{case}, row {r}: {cs} {cm}");
                let x = coords[rows.node[r]];
                let err = rows.gap[r] - f_lin(x[0], x[1]);
                assert!(err.abs() < 1e-12, "{case}, row {r} at {x:?}: gap error {err}");
            }
            let edge_rows = rows.coupling.iter().filter(|row| (row[0].1 - 5.0 / 3.0).abs() < 1e-15).count();
            assert_eq!(edge_rows, if stri { 33 } else { 24 }, "{case}");
        }
    }
}
