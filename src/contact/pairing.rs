//! Contact rows of each `[[contact.pair]]` (and the equality rows of each `[[tie]]`): node to
//! node where the faces match, dual mortar ([`super::mortar`]) otherwise or when asked; each
//! row is a coupling list Σ c·u_node (node to node: [(slave, 1), (master, −1)]) with the frame,
//! area, gap and slip bound of its slave node.
//!
//! Node to node: every node of the slave face is matched with the master node that
//! has the same position in the contact plane (distance measured after projecting out the slave
//! normal, within `tolerance`; failing that, the master node whose normal line passes through
//! the slave node, so a curved slave face pairs with a flat master); the distance along the
//! normal is the initial gap dᵢ ≥ 0. The frame of pair i is the slave face's outward unit normal
//! nᵢ (averaged over the quads around the node, area-weighted; exact for planar faces), or minus
//! the master's where the master's normal line made the match; tangents t₁ᵢ (the orthotropic `direction`,
//! else the global x axis — y if x is nearly normal — projected into the plane), t₂ᵢ = t₁ᵢ × nᵢ.
//! With u_s, u_m the displacements of the slave and master node, pair i contributes
//!
//! ```text
//! (N u)ᵢ = (u_s − u_m)·nᵢ ≤ dᵢ      (non-penetration)
//! (T u)ᵢ = ((u_s − u_m)·t₁ᵢ, (u_s − u_m)·t₂ᵢ)   (relative tangential displacement)
//! ```
//!
//! which for the seed scene (slave = upper face z = 1, n = −z) is exactly the paper's (docs/validation.md, "The paper's benchmark")
//! `Nᵢu = u_z(lower) − u_z(upper)` and `Tᵢu = (u_x, u_y)(upper) − (u_x, u_y)(lower)`.
//! The nodal area wᵢ = ∫ φᵢ dA over the slave face (2×2 Gauss; a quarter of a quad at corners
//! of a uniform grid), and the slip bound gᵢ = g·wᵢ (orthotropic: g₁wᵢ along t₁, g₂wᵢ along t₂).

use std::collections::HashMap;

use crate::error::{Error, Result};
use crate::fem::facet::{cross, dot, edges, facet_nodal_areas, facet_normal_area, sub};
use crate::mesh::FacetKind;
use crate::mesh::{Face, Mesh};
use crate::qp::cone::Coefficient;
use crate::qp::sets::{Disc, Ellipse, TangentSet};
use crate::qp::Lambda;
use crate::scene::{default_search_distance, ContactPair, Discretization, Friction, Tie};

/// A tangent whose part along the slave node's free DOFs is at most this (of 1) is held by the
/// Dirichlet conditions: its row is left empty ([`Contact::void_held_tangents`]).
pub const VOID_FREE_PART: f64 = 0.05;

/// On a slave node on rollers (a symmetry plane), a tangent within about 11° of the plane's
/// normal (its free part at most this) is the plane's normal direction: the averaged normal of
/// an unstructured face tilts there by a few degrees.
pub const VOID_ROLLER_PART: f64 = 0.2;

/// Slip bound of one pair, as a nodal force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SlipBound {
    /// Frictionless: no tangential multipliers.
    None,
    /// Isotropic Tresca: ‖λ̄τ,ᵢ‖ ≤ g.
    Disc(f64),
    /// Orthotropic Tresca: (λ₁/g₁)² + (λ₂/g₂)² ≤ 1 in the pair's frame (t₁, t₂).
    Ellipse(f64, f64),
}

/// All contact pairs of a scene, in the order of the scene's pair entries and slave nodes.
#[derive(Clone, Debug, Default)]
pub struct Contact {
    /// The slave node that carries row i's multipliers (where its frame, area and result
    /// fields live).
    pub slave: Vec<usize>,
    /// Row i's nodes and coefficients: (N u)ᵢ = Σ c·(u_node · nᵢ), the tangential rows alike.
    /// Node-to-node [(slave, 1), (master, −1)]; mortar the slave's row of D⁻¹[D  −M]
    /// ([`crate::contact::mortar`]).
    pub coupling: Vec<Vec<(usize, f64)>>,
    pub normal: Vec<[f64; 3]>,
    pub t1: Vec<[f64; 3]>,
    pub t2: Vec<[f64; 3]>,
    /// Nodal area wᵢ of the slave node.
    pub area: Vec<f64>,
    /// Initial gap dᵢ (< 0: an initial interference, removed by the solution).
    pub gap: Vec<f64>,
    pub bound: Vec<SlipBound>,
    /// Index of the scene's `[[contact.pair]]` entry each pair comes from.
    pub entry: Vec<usize>,
    /// The Coulomb coefficient of each pair ([`Coefficient::Fixed`]: its bound is `bound`).
    pub coulomb: Vec<Coefficient>,
    /// How each `[[contact.pair]]` entry was discretized.
    pub discretization: Vec<Discretization>,
    /// Each entry's slave nodes outside the contact zone (no master facet within reach).
    pub outside: Vec<Outside>,
    /// Each entry's initial interference.
    pub interference: Vec<Interference>,
    /// Tangential rows left empty (per pair, t₁ and t₂): the slave node's DOFs along that
    /// tangent are all prescribed (a symmetry plane's rollers), so friction along it means
    /// nothing there ([`Contact::void_held_tangents`]). Empty: none.
    pub void: Vec<[bool; 2]>,
    /// The smoothed pressure of each row's slave node as weights on the rows of its entry:
    /// p̄ᵢ = Σ_j w_ij p_j, the area-weighted average over the node's slave facets of each
    /// facet's mean nodal pressure ([`Contact::smooth`]); on quadratic mortar faces the corner
    /// hats' moments instead, edge nodes the mean of their corners (`vertex_weights`).
    pub smoothing: Vec<Vec<(usize, f64)>>,
}

impl Contact {
    /// Number of pairs, the paper's m.
    pub fn len(&self) -> usize {
        self.slave.len()
    }

    pub fn is_empty(&self) -> bool {
        self.slave.is_empty()
    }

    /// Row i's (node, coefficient) couples.
    pub fn row(&self, i: usize) -> &[(usize, f64)] {
        &self.coupling[i]
    }

    /// Whether tangential row `j` (0: t₁, 1: t₂) of pair `i` is left empty.
    pub fn is_void(&self, i: usize, j: usize) -> bool {
        self.void.get(i).is_some_and(|v| v[j])
    }

    /// Marks the tangential rows held on both sides (`held(node, component)`): the slave
    /// node's DOFs along the tangent up to a part of [`VOID_FREE_PART`], and most of the master
    /// side (the free part of Σ|c|·t over the master nodes at most half of Σ|c|) — a symmetry
    /// plane's rollers, where friction along the plane's normal is zero by symmetry. Node to
    /// node such a row is zero anyway; a mortar row keeps small coefficients on master nodes off
    /// the plane, and neighbouring rows that reach the same few master DOFs make B
    /// rank-deficient. A slave node on rollers (held at 0 along the tangent, free in another
    /// component; `still`: held at 0 at every step) is on a symmetry plane: its row is void whatever the master side (on an
    /// unstructured mesh the master part is mostly free, and the row nearly a combination of
    /// the rollers' Dirichlet rows: TFETI's BΔBᵀ nearly singular). A clamped slave node (all
    /// three held) over a free master node (a clamped face's edge on the contact) keeps its
    /// rows: friction acts on the master there.
    pub fn void_held_tangents(&mut self, held: impl Fn(usize, usize) -> bool, still: impl Fn(usize, usize) -> bool) {
        if !self.has_friction() {
            return;
        }
        self.void = (0..self.len())
            .map(|i| {
                // the tangent's part along the free DOFs: under 5 % of it (a unit vector) is the
                // averaged normal's tilt at a symmetry plane, not a direction of its own
                let free = |v: usize, t: [f64; 3]| (0..3).filter(|&k| !held(v, k)).map(|k| t[k] * t[k]).sum::<f64>().sqrt();
                [self.t1[i], self.t2[i]].map(|t| {
                    let master = self.coupling[i].iter().filter(|e| e.0 != self.slave[i]);
                    let (total, loose) = master.fold((0.0, 0.0), |(a, b), &(v, c)| (a + c.abs(), b + c.abs() * free(v, t)));
                    // a slave node on rollers (some component free) lies on a symmetry plane:
                    // friction along the plane's normal is zero there whatever the master side
                    let v = self.slave[i];
                    let roller = (0..3).any(|k| !held(v, k)) && (0..3).all(|k| !held(v, k) || still(v, k));
                    if roller {
                        free(self.slave[i], t) <= VOID_ROLLER_PART
                    } else {
                        free(self.slave[i], t) <= VOID_FREE_PART && loose <= 0.5 * total
                    }
                })
            })
            .collect();
    }

    /// Whether any pair carries friction (i.e. tangential multipliers exist).
    pub fn has_friction(&self) -> bool {
        self.bound.iter().any(|b| *b != SlipBound::None) || self.is_coulomb()
    }

    /// Whether pair `i` carries friction (a slip bound, or a Coulomb coefficient).
    pub fn has_friction_at(&self, i: usize) -> bool {
        self.bound[i] != SlipBound::None || self.coulomb[i] != Coefficient::Fixed
    }

    /// The friction law of each `[[contact.pair]]` entry that has pairs ("frictionless",
    /// "Tresca", "orthotropic Tresca", "Coulomb", "orthotropic Coulomb"), in entry order.
    pub fn laws(&self) -> Vec<(usize, &'static str)> {
        let mut out: Vec<(usize, &'static str)> = Vec::new();
        for i in 0..self.len() {
            if out.last().is_some_and(|l| l.0 == self.entry[i]) {
                continue;
            }
            let law = match (self.coulomb[i], self.bound[i]) {
                (Coefficient::Isotropic(_), _) => "Coulomb",
                (Coefficient::Orthotropic(..), _) => "orthotropic Coulomb",
                (Coefficient::Fixed, SlipBound::None) => "frictionless",
                (Coefficient::Fixed, SlipBound::Disc(_)) => "Tresca",
                (Coefficient::Fixed, SlipBound::Ellipse(..)) => "orthotropic Tresca",
            };
            out.push((self.entry[i], law));
        }
        out
    }

    /// Whether any pair follows Coulomb's law (the slip bounds depend on λν).
    pub fn is_coulomb(&self) -> bool {
        self.coulomb.iter().any(|c| *c != Coefficient::Fixed)
    }

    /// The Coulomb coefficients of the pairs `pairs` (a rank's part).
    pub fn coefficients(&self, pairs: &[usize]) -> Vec<Coefficient> {
        pairs.iter().map(|&i| self.coulomb[i]).collect()
    }

    /// Λ of these pairs: a half-line per normal multiplier and, with friction, the slip bound's
    /// disc or ellipse per tangential pair (a frictionless pair among frictional ones: the
    /// point {0}).
    pub fn constraint_set(&self) -> Lambda {
        let tangent = self.has_friction().then(|| {
            self.bound
                .iter()
                .map(|b| match *b {
                    SlipBound::None => TangentSet::Disc(Disc::new(0.0)),
                    SlipBound::Disc(g) => TangentSet::Disc(Disc::new(g)),
                    SlipBound::Ellipse(a, b) => TangentSet::Ellipse(Ellipse::new(a, b)),
                })
                .collect()
        });
        Lambda::new(self.len(), tangent)
    }
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    a.map(|v| v / n)
}

/// Area-weighted outward normals at the nodes of a face (sum of the facets' area vectors).
fn node_normals(mesh: &Mesh, face: &Face) -> HashMap<usize, [f64; 3]> {
    let mut out: HashMap<usize, [f64; 3]> = HashMap::new();
    for q in &face.facets {
        let x = mesh.facet_coords(q);
        // twice the area vector: for a (warped) quad4 the cross product of the diagonals, for a
        // tri3 that of two edges
        let n = match q.kind {
            FacetKind::Quad4 => cross(sub(x[2], x[0]), sub(x[3], x[1])),
            FacetKind::Tri3 => cross(sub(x[1], x[0]), sub(x[2], x[0])),
            k => facet_normal_area(k, &x).map(|v| 2.0 * v),
        };
        for &v in q.nodes() {
            let e = out.entry(v).or_insert([0.0; 3]);
            for d in 0..3 {
                e[d] += n[d];
            }
        }
    }
    out.into_iter().map(|(v, n)| (v, unit(n))).collect()
}

/// The curvature of a face at each node, from its averaged normals: the largest angle between
/// the normals of two nodes of a facet around it over their distance (0 on a flat face).
fn node_curvatures(mesh: &Mesh, face: &Face, normals: &HashMap<usize, [f64; 3]>) -> HashMap<usize, f64> {
    let mut out: HashMap<usize, f64> = HashMap::new();
    for q in &face.facets {
        let v = q.nodes();
        let mut k = 0.0f64;
        for a in 0..v.len() {
            for b in a + 1..v.len() {
                let (na, nb) = (normals[&v[a]], normals[&v[b]]);
                let c = cross(na, nb);
                let angle = dot(c, c).sqrt().atan2(dot(na, nb));
                let d = sub(mesh.nodes[v[a]], mesh.nodes[v[b]]);
                let len = dot(d, d).sqrt();
                if len > 0.0 {
                    k = k.max(angle / len);
                }
            }
        }
        for &n in v {
            let e = out.entry(n).or_insert(0.0);
            *e = e.max(k);
        }
    }
    out
}

/// The contact frame's normal at a row: the two faces' normals (the slave's `ns` at its node,
/// the master's `nm` where the row couples, by the coefficients' weights) averaged with the
/// weights of their radii of curvature, n ∝ κ_m n_s − κ_s n_m — the common normal of the
/// surfaces that the bodies approach along (Hertz: the load axis for either side as slave; the
/// flat face's normal against a curved one; the bisector of equal spheres). The slave's where
/// both faces are flat. The slave's own normal would tilt the frame by r/R on a curved slave,
/// so that the gap closing under pressing would read as a tangential slip of about (r²/2R)·(r/R).
fn frame_normal(row: &RowGeom, sn: &HashMap<usize, [f64; 3]>, sk: &HashMap<usize, f64>, mn: &HashMap<usize, [f64; 3]>, mk: &HashMap<usize, f64>) -> [f64; 3] {
    let ns = row.normal;
    let ks = sk.get(&row.slave).copied().unwrap_or(0.0);
    let (mut nm, mut km, mut w) = ([0.0; 3], 0.0, 0.0);
    for &(v, c) in &row.coupling {
        if let (Some(n), Some(&k)) = (mn.get(&v), mk.get(&v)) {
            if sn.contains_key(&v) {
                continue;
            }
            (0..3).for_each(|d| nm[d] += c.abs() * n[d]);
            km += c.abs() * k;
            w += c.abs();
        }
    }
    if w == 0.0 || (ks == 0.0 && km == 0.0) {
        return ns;
    }
    let km = km / w;
    let nm = unit(nm);
    let n: [f64; 3] = std::array::from_fn(|d| km * ns[d] - ks * nm[d]);
    let l = dot(n, n).sqrt();
    // faces that do not face each other keep the slave's normal (the pairing refuses them)
    if l.is_nan() || l <= 0.0 || dot(ns, nm) > 0.0 {
        ns
    } else {
        n.map(|v| v / l)
    }
}

/// Consistent nodal areas ∫ φᵢ dA of a face.
fn node_areas(mesh: &Mesh, face: &Face) -> HashMap<usize, f64> {
    let mut out = HashMap::new();
    for q in &face.facets {
        let w = facet_nodal_areas(q.kind, &mesh.facet_coords(q));
        for (a, &v) in q.nodes().iter().enumerate() {
            *out.entry(v).or_insert(0.0) += w[a];
        }
    }
    out
}

/// First tangent: `dir` projected into the plane ⟂ n, normalized.
fn tangent(n: [f64; 3], dir: [f64; 3]) -> Option<[f64; 3]> {
    // a direction whose squared length under- or overflows is scaled first
    let d = if dot(dir, dir).is_normal() {
        unit(dir)
    } else {
        let s = dir.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        unit(dir.map(|v| v / s))
    };
    let p = sub(d, n.map(|v| v * dot(d, n)));
    (dot(p, p).sqrt() > 1e-6).then(|| unit(p))
}

/// One row's geometry before its frame and bound: the slave node, its coupling, normal, area
/// and initial gap.
struct RowGeom {
    slave: usize,
    coupling: Vec<(usize, f64)>,
    normal: [f64; 3],
    area: f64,
    /// The weighted gap dᵢ (node-to-node: the gap).
    gap: f64,
    /// The gap on the faces' true geometry ([`crate::contact::mortar::MortarRows::geometric_gap`];
    /// NaN: not known, beyond the master's edge).
    geometric: f64,
}

/// Why node-to-node pairing did not apply.
enum NodeToNode {
    /// The faces do not match node for node (the message says where): mortar applies.
    Mismatch(String),
    /// Anything else (the error as is).
    Fail(Error),
}

/// The bounding-box diagonal of `points` (0 for none).
fn diagonal<'a>(points: impl Iterator<Item = &'a [f64; 3]>) -> f64 {
    let (lo, hi) = points
        .fold(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]), |(lo, hi), p| (std::array::from_fn(|d| lo[d].min(p[d])), std::array::from_fn(|d| hi[d].max(p[d]))));
    if lo[0] > hi[0] {
        0.0
    } else {
        dot(sub(hi, lo), sub(hi, lo)).sqrt()
    }
}

/// Node-to-node rows of one pair entry: every slave node with the master node at its place.
fn node_to_node(mesh: &Mesh, key: &str, slave: &Face, master: &Face, tol: f64) -> std::result::Result<Vec<RowGeom>, NodeToNode> {
    let normals = node_normals(mesh, slave);
    let mnormals = node_normals(mesh, master);
    let areas = node_areas(mesh, slave);
    let snodes = slave.nodes();
    let mnodes = master.nodes();
    if snodes.len() != mnodes.len() {
        return Err(NodeToNode::Mismatch(format!("slave face {} has {} nodes but master face {} has {}", slave.name, snodes.len(), master.name, mnodes.len())));
    }
    // master nodes hashed by their position in the contact plane of the slave face's mean
    // normal, in cells of size tol: a match lies in one of the 27 neighbouring cells
    let mean = unit(normals.values().fold([0.0; 3], |a, n| [a[0] + n[0], a[1] + n[1], a[2] + n[2]]));
    let inplane = |x: [f64; 3]| sub(x, mean.map(|v| v * dot(x, mean)));
    let cell = |x: [f64; 3]| inplane(x).map(|v| (v / tol).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for &v in &mnodes {
        grid.entry(cell(mesh.nodes[v])).or_default().push(v);
    }
    let mut used = HashMap::new();
    // off the line along `dir` through x, the distance of y
    let off = |x: [f64; 3], y: [f64; 3], dir: [f64; 3]| {
        let d = sub(y, x);
        let t = sub(d, dir.map(|v| v * dot(d, dir)));
        dot(t, t).sqrt()
    };
    let mut rows = Vec::with_capacity(snodes.len());
    for &s in &snodes {
        let xs = mesh.nodes[s];
        let cs = cell(xs);
        // the master node on the slave node's normal line; failing that, the master node
        // whose normal line passes through the slave node (a curved slave face against a
        // flatter master: the frame then follows the master face)
        let mut best: [Option<(f64, usize)>; 2] = [None, None];
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    for &m in grid.get(&[cs[0] + dx, cs[1] + dy, cs[2] + dz]).into_iter().flatten() {
                        for (b, dist) in best.iter_mut().zip([off(xs, mesh.nodes[m], normals[&s]), off(mesh.nodes[m], xs, mnormals[&m])]) {
                            if dist <= tol && b.is_none_or(|b| dist < b.0) {
                                *b = Some((dist, m));
                            }
                        }
                    }
                }
            }
        }
        let (n, best) = match best {
            [Some(b), _] => (normals[&s], Some(b)),
            [None, Some(b)] => (mnormals[&b.1].map(|v| -v), Some(b)),
            _ => (normals[&s], None),
        };
        let Some((_, m)) = best else {
            return Err(NodeToNode::Mismatch(format!(
                "faces {} and {} do not match node to node: no master node within {tol:.1e} of the slave node at ({:.6}, {:.6}, {:.6})",
                slave.name, master.name, xs[0], xs[1], xs[2]
            )));
        };
        if let Some(prev) = used.insert(m, s) {
            return Err(NodeToNode::Fail(Error::scene(key, format!("master node {m} of {} is matched by two slave nodes ({prev} and {s})", master.name))));
        }
        if dot(n, mnormals[&m]) > -0.5 {
            return Err(NodeToNode::Fail(Error::scene(
                key,
                format!("faces {} and {} do not face each other (their outward normals are not opposite)", slave.name, master.name),
            )));
        }
        let gap = dot(sub(mesh.nodes[m], xs), n);
        rows.push(RowGeom { slave: s, coupling: vec![(s, 1.0), (m, -1.0)], normal: n, area: areas[&s], gap, geometric: gap });
    }
    Ok(rows)
}

/// The rows of one interface, how it was discretized, and its slave nodes that found no master
/// facet within the search distance (ascending; rows for none of them).
struct Interface {
    rows: Vec<RowGeom>,
    how: Discretization,
    outside: Vec<usize>,
    search: f64,
}

/// Dual mortar rows of one interface ([`crate::contact::mortar`]); `search` the search
/// distance; `outside`: slave nodes without a master facet are left out (a contact zone), not
/// an error (a tie).
fn mortar_rows(mesh: &Mesh, key: &str, slave: &Face, master: &Face, search: f64, outside: bool) -> Result<Interface> {
    use crate::contact::mortar::{dual_mortar, MortarParams, SurfaceFacet};
    fn facets(f: &Face) -> Vec<SurfaceFacet<'_>> {
        f.facets.iter().map(|q| SurfaceFacet { nodes: q.nodes() }).collect()
    }
    let params = MortarParams { search_distance: search, allow_uncovered: outside, ..Default::default() };
    let r = dual_mortar(&mesh.nodes, &facets(slave), &facets(master), &params)
        .map_err(|e| Error::scene(key, format!("mortar of {} on {}: {e}", slave.name, master.name)))?;
    if r.is_empty() {
        return Err(Error::scene(
            key,
            format!(
                "no slave node of {} finds a master facet of {} within the search distance {search:.3e} (do the faces face each other? is it the right face?)",
                slave.name, master.name
            ),
        ));
    }
    let rows = (0..r.len())
        .map(|i| RowGeom {
            slave: r.node[i],
            coupling: r.coupling[i].clone(),
            normal: r.normal[i],
            area: r.area[i],
            gap: r.gap[i],
            geometric: r.geometric_gap[i],
        })
        .collect();
    Ok(Interface { rows, how: Discretization::Mortar, outside: r.uncovered, search })
}

/// The rows of interface `slave`–`master` under `discretization` (None: node-to-node where the
/// faces match, mortar otherwise); `outside` as for [`mortar_rows`].
#[allow(clippy::too_many_arguments)]
fn interface_rows(
    mesh: &Mesh,
    key: &str,
    slave: &Face,
    master: &Face,
    tol: f64,
    discretization: Option<Discretization>,
    search: Option<f64>,
    outside: bool,
) -> Result<Interface> {
    let search = search.unwrap_or_else(|| default_search_distance(diagonal(slave.nodes().iter().map(|&v| &mesh.nodes[v]))));
    let mortar = || mortar_rows(mesh, key, slave, master, search, outside);
    let nodal = |rows| Ok(Interface { rows, how: Discretization::NodeToNode, outside: vec![], search });
    // a quadratic facet's corner nodes carry no area (∫ N dA = 0 on a tri6's corners): nodal
    // pairs there would hold no force; the mortar's modified dual basis gives every node one (quad9:
    // mortar too, for the weighted gap on the true geometry and the vertex-recovered pressure)
    let quadratic = slave.facets.iter().any(|q| is_quadratic(q.kind));
    if quadratic && discretization == Some(Discretization::NodeToNode) {
        return Err(Error::scene(
            key,
            format!(
                "face {} has quadratic facets ({}): node-to-node cannot use them (discretization = \"mortar\" can)",
                slave.name,
                if slave.facets.iter().any(|q| q.kind == FacetKind::Quad9) {
                    "9-node quadrilaterals: nodal pairs would ignore the curved geometry between the nodes"
                } else {
                    "their corner nodes carry no area, so nodal pairs there would hold no force"
                }
            ),
        ));
    }
    if quadratic {
        return mortar();
    }
    match discretization {
        Some(Discretization::Mortar) => mortar(),
        Some(Discretization::NodeToNode) => match node_to_node(mesh, key, slave, master, tol) {
            Ok(rows) => nodal(rows),
            Err(NodeToNode::Mismatch(m)) => Err(Error::scene(key, format!("{m}: node-to-node needs matching meshes (discretization = \"mortar\" takes any)"))),
            Err(NodeToNode::Fail(e)) => Err(e),
        },
        None => match node_to_node(mesh, key, slave, master, tol) {
            Ok(rows) => nodal(rows),
            Err(NodeToNode::Mismatch(_)) => mortar(),
            Err(NodeToNode::Fail(e)) => Err(e),
        },
    }
}

/// Whether a slave facet is quadratic (tri6, quad8, quad9): it is paired by mortar only, its
/// weighted gap is taken on the true geometry and its smoothed pressure from its vertices.
fn is_quadratic(kind: FacetKind) -> bool {
    matches!(kind, FacetKind::Tri6 | FacetKind::Quad8 | FacetKind::Quad9)
}

/// The gaps within this fraction of the model's extent (its diagonal, or its farthest
/// coordinate) are round-off of the coordinates and taken as 0: the mortar patch test on
/// touching faces computed gaps of ±1e-15 on a model of extent 3, which at E = 1e16
/// (displacements ~1e-16) put 7 of 20 slave nodes open and the stress 71 % off.
pub const ROUNDOFF_GAP: f64 = 64.0 * f64::EPSILON;

/// Pairs the faces of every contact entry of the scene. `faces[k]` = (slave, master) indices into
/// `mesh.faces` for `pairs[k]`.
pub fn pair(mesh: &Mesh, pairs: &[ContactPair], faces: &[(usize, usize)]) -> Result<Contact> {
    let size = diagonal(mesh.nodes.iter()).max(f64::MIN_POSITIVE);
    // a gap of this size is the round-off of the coordinates it is computed from (both signs):
    // touching faces, gap 0, whatever the scale of the displacements
    let far = mesh.nodes.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    let roundoff = ROUNDOFF_GAP * size.max(far);
    let mut c = Contact::default();
    // (slave, master) node couples, unordered, and the entry that made each
    let mut couples: HashMap<(usize, usize), usize> = HashMap::new();
    for (k, (p, &(sf, mf))) in pairs.iter().zip(faces).enumerate() {
        let key = format!("contact.pair[{k}]");
        let (slave, master) = (&mesh.faces[sf], &mesh.faces[mf]);
        let tol = p.tolerance.unwrap_or(1e-8 * size);
        let Interface { rows, how, outside, search } = interface_rows(mesh, &key, slave, master, tol, p.discretization, p.search_distance, true)?;
        c.discretization.push(how);
        c.outside.push(Outside::new(mesh, slave, master, outside, search));
        // on quadratic slave facets the weighted gap is T⁻¹ of the nodal gaps, below the true
        // one on a curved face: the constraint takes the gap on the true geometry there
        let quadratic = slave.facets.iter().any(|q| is_quadratic(q.kind));
        let fraction = p.max_overlap.unwrap_or(crate::scene::DEFAULT_MAX_OVERLAP);
        let mut fit = Interference::default();
        let first_row = c.len();
        let (sn, mn) = (node_normals(mesh, slave), node_normals(mesh, master));
        let (sk, mk) = (node_curvatures(mesh, slave, &sn), node_curvatures(mesh, master, &mn));
        for row in rows {
            // the frame between the faces' normals, and the weighted gap along it
            let n = frame_normal(&row, &sn, &sk, &mn, &mk);
            let row = if n == row.normal {
                row
            } else {
                RowGeom { gap: -row.coupling.iter().map(|&(k, c)| c * dot(mesh.nodes[k], n)).sum::<f64>(), normal: n, ..row }
            };
            let (s, n, xs) = (row.slave, row.normal, mesh.nodes[row.slave]);
            for &(m, _) in row.coupling.iter().skip(1) {
                if let Some(prev) = couples.insert((s.min(m), s.max(m)), k).filter(|&prev| prev != k) {
                    return Err(Error::scene(
                        &key,
                        format!(
                            "the slave node at ({:.6}, {:.6}, {:.6}) of {} and its master node are already a pair of contact.pair[{prev}]: give each interface once",
                            xs[0], xs[1], xs[2], slave.name
                        ),
                    ));
                }
            }
            let measured = if row.geometric.is_finite() { row.geometric } else { row.gap };
            // an overlap within the matching tolerance, or a gap of round-off, is touching: gap 0
            let gap = if quadratic { measured } else { row.gap };
            let gap = if (gap < 0.0 && gap >= -tol) || gap.abs() <= roundoff { 0.0 } else { gap };
            // a stated interference replaces the meshed gap
            let gap = if let crate::scene::Fit::Stated(delta) = p.interference { -delta } else { gap };
            let h = row.area.max(0.0).sqrt();
            if measured < -tol.max(fraction * h) && !p.interference.allows_overlap() {
                return Err(Error::scene(
                    &key,
                    format!(
                        "bodies overlap: the slave node at ({:.6}, {:.6}, {:.6}) of {} lies {:.3e} inside {}, more than max_overlap = {fraction:.0e} of its element size {h:.3e} (a press fit: set interference = true, or state it as a length, interference = δ)",
                        xs[0],
                        xs[1],
                        xs[2],
                        slave.name,
                        -measured,
                        master.name
                    ),
                ));
            }
            if gap < 0.0 {
                fit.nodes += 1;
                fit.depth = fit.depth.max(-gap);
            }
            let dir = p.friction.direction().unwrap_or([1.0, 0.0, 0.0]);
            let t1 = match (tangent(n, dir), p.friction.direction()) {
                (Some(t), _) => t,
                (None, Some(_)) => {
                    return Err(Error::scene(format!("{key}.friction.direction"), format!("is normal to the contact face {}", slave.name)));
                }
                (None, _) => tangent(n, [0.0, 1.0, 0.0]).expect("x and y cannot both be normal"),
            };
            let w = row.area;
            c.slave.push(s);
            c.coupling.push(row.coupling);
            c.normal.push(n);
            c.t1.push(t1);
            c.t2.push(cross(t1, n));
            c.area.push(w);
            c.gap.push(gap);
            c.bound.push(match p.friction {
                Friction::None => SlipBound::None,
                Friction::Tresca { g } => SlipBound::Disc(g * w),
                Friction::Orthotropic { g1, g2, .. } => SlipBound::Ellipse(g1 * w, g2 * w),
                // the bound follows λν: zero until the fixed point sets it
                Friction::Coulomb { mu1: Some(_), .. } => SlipBound::Ellipse(0.0, 0.0),
                Friction::Coulomb { .. } => SlipBound::Disc(0.0),
            });
            c.coulomb.push(match p.friction {
                Friction::Coulomb { mu: Some(m), .. } => Coefficient::Isotropic(m),
                Friction::Coulomb { mu1: Some(a), mu2: Some(b), .. } => Coefficient::Orthotropic(a, b),
                _ => Coefficient::Fixed,
            });
            c.entry.push(k);
        }
        c.interference.push(fit);
        let quadratic_mortar = c.discretization.last() == Some(&Discretization::Mortar) && slave.facets.iter().all(|q| is_quadratic(q.kind));
        if quadratic_mortar {
            vertex_weights(mesh, slave, first_row, &mut c);
        } else {
            smoothing_weights(mesh, slave, first_row, &mut c);
        }
    }
    Ok(c)
}

/// The weights of [`Contact::smoothing`] for the rows `first..` (one entry, slave face `slave`):
/// each slave facet spreads its area over its nodes' rows (a node without a row, outside the
/// contact zone, counts as pressure 0).
fn smoothing_weights(mesh: &Mesh, slave: &Face, first: usize, c: &mut Contact) {
    let row_of: HashMap<usize, usize> = (first..c.len()).map(|i| (c.slave[i], i)).collect();
    let mut acc: Vec<(f64, HashMap<usize, f64>)> = vec![(0.0, HashMap::new()); c.len() - first];
    for q in &slave.facets {
        let x: Vec<[f64; 3]> = q.nodes().iter().map(|&v| mesh.nodes[v]).collect();
        let a = facet_nodal_areas(q.kind, &x).iter().sum::<f64>().abs();
        let share = a / q.nodes().len() as f64;
        for v in q.nodes() {
            let Some(&i) = row_of.get(v) else { continue };
            let (total, w) = &mut acc[i - first];
            *total += a;
            for u in q.nodes() {
                if let Some(&j) = row_of.get(u) {
                    *w.entry(j).or_default() += share;
                }
            }
        }
    }
    for (total, w) in acc {
        let mut w: Vec<(usize, f64)> = w.into_iter().map(|(j, x)| (j, x / total)).collect();
        w.sort_unstable_by_key(|e| e.0);
        c.smoothing.push(w);
    }
}

/// The weights of [`Contact::smoothing`] for the rows `first..` of an entry whose slave facets are
/// all quadratic (tri6, quad8, quad9) and mortar: the multipliers λ = p w are the moments ∫ φ̃ p of
/// the slave basis φ̃ (= T φ on tri6 and quad8, φ on quad9), so a corner c's linear hat
/// N¹_c = N_c + ½ Σ_e N_e (+ ¼ N_m of a quad9's centre m) carries ∫ N¹_c p = λ_c + ½ Σ_e λ_e
/// (+ ¼ λ_m) whatever α; p̄_c is that over ∫ N¹_c, and an edge node (a quad9's centre) gets the
/// mean of its two (four) corners. A node without a row counts as pressure 0.
fn vertex_weights(mesh: &Mesh, slave: &Face, first: usize, c: &mut Contact) {
    let row_of: HashMap<usize, usize> = (first..c.len()).map(|i| (c.slave[i], i)).collect();
    // per corner node: ∫ N¹ over its facets, and its higher-order nodes with their shares (each once)
    let mut hat: HashMap<usize, (f64, Vec<(usize, f64)>)> = HashMap::new();
    let mut corners_of: HashMap<usize, Vec<usize>> = HashMap::new();
    let share = |hat: &mut HashMap<usize, (f64, Vec<(usize, f64)>)>, k: usize, e: usize, s: f64, a: f64| {
        let h = hat.entry(k).or_default();
        h.0 += s * a;
        if !h.1.iter().any(|x| x.0 == e) {
            h.1.push((e, s));
        }
    };
    for q in &slave.facets {
        let v = q.nodes();
        let x: Vec<[f64; 3]> = v.iter().map(|&k| mesh.nodes[k]).collect();
        let raw = facet_nodal_areas(q.kind, &x);
        let sign = raw.iter().sum::<f64>().signum();
        let na: Vec<f64> = raw.iter().map(|a| sign * a).collect();
        for k in 0..q.kind.corners() {
            hat.entry(v[k]).or_default().0 += na[k];
        }
        for &(e, a, b) in edges(q.kind) {
            for k in [a, b] {
                share(&mut hat, v[k], v[e], 0.5, na[e]);
            }
            corners_of.insert(v[e], vec![v[a], v[b]]);
        }
        if q.kind == FacetKind::Quad9 {
            for k in 0..4 {
                share(&mut hat, v[k], v[8], 0.25, na[8]);
            }
            corners_of.insert(v[8], v[..4].to_vec());
        }
    }
    let corner = |node: usize| -> HashMap<usize, f64> {
        let mut w = HashMap::new();
        let (Some(&i), Some((n1, es))) = (row_of.get(&node), hat.get(&node)) else { return w };
        w.insert(i, c.area[i] / n1);
        for &(e, s) in es {
            if let Some(&j) = row_of.get(&e) {
                *w.entry(j).or_default() += s * c.area[j] / n1;
            }
        }
        w
    };
    for i in first..c.len() {
        let node = c.slave[i];
        let w = match corners_of.get(&node) {
            Some(cs) => {
                let mut w = corner(cs[0]);
                for &b in &cs[1..] {
                    for (j, x) in corner(b) {
                        *w.entry(j).or_default() += x;
                    }
                }
                let mean = 1.0 / cs.len() as f64;
                w.into_iter().map(|(j, x)| (j, mean * x)).collect()
            }
            None => corner(node),
        };
        let mut w: Vec<(usize, f64)> = w.into_iter().collect();
        w.sort_unstable_by_key(|e| e.0);
        c.smoothing.push(w);
    }
}

impl Contact {
    /// The smoothed value of a nodal field given per row (`values[i]` of row i).
    pub fn smooth<const K: usize>(&self, values: &[[f64; K]]) -> Vec<[f64; K]> {
        self.smoothing.iter().map(|w| std::array::from_fn(|k| w.iter().map(|&(j, x)| x * values[j][k]).sum())).collect()
    }
}

/// The initial interference of one contact entry: its slave nodes that start inside the master
/// (gap < 0 in the constraint, which the solution removes) and the deepest overlap.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Interference {
    pub nodes: usize,
    pub depth: f64,
}

/// The equality rows of a tied interface: as contact rows, in all three directions.
#[derive(Clone, Debug, Default)]
pub struct Tied {
    /// The slave node of each row.
    pub slave: Vec<usize>,
    /// (node, coefficient) of each row: Σ c·u_node,k = 0 for k = x, y, z.
    pub coupling: Vec<Vec<(usize, f64)>>,
    /// The `[[tie]]` entry of each row.
    pub entry: Vec<usize>,
}

impl Tied {
    pub fn len(&self) -> usize {
        self.slave.len()
    }

    pub fn is_empty(&self) -> bool {
        self.slave.is_empty()
    }
}

/// The rows of every `[[tie]]` (mortar on any meshes; node-to-node where the faces match).
pub fn tie(mesh: &Mesh, ties: &[Tie], faces: &[(usize, usize)]) -> Result<Tied> {
    let size = diagonal(mesh.nodes.iter()).max(f64::MIN_POSITIVE);
    let mut t = Tied::default();
    for (k, (p, &(sf, mf))) in ties.iter().zip(faces).enumerate() {
        let key = format!("tie[{k}]");
        let (slave, master) = (&mesh.faces[sf], &mesh.faces[mf]);
        for row in interface_rows(mesh, &key, slave, master, 1e-8 * size, None, p.search_distance, false)?.rows {
            t.slave.push(row.slave);
            t.coupling.push(row.coupling);
            t.entry.push(k);
        }
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::boxgen;

    /// Two stacked boxes (upper on lower) with n nodes per edge; `shift` moves the upper one,
    /// `rot` rotates everything.
    fn blocks(n_up: usize, n_low: usize, shift: [f64; 3], rot: [[f64; 3]; 3]) -> Mesh {
        let mut m = Mesh::default();
        let mut up = boxgen::generate([0.0, 0.0, 1.0], [2.0, 1.0, 2.0], [n_up; 3]);
        for p in &mut up.nodes {
            *p = std::array::from_fn(|d| p[d] + shift[d]);
        }
        m.push_body("upper", up);
        m.push_body("lower", boxgen::generate([0.0; 3], [2.0, 1.0, 1.0], [n_low; 3]));
        for p in &mut m.nodes {
            *p = std::array::from_fn(|i| (0..3).map(|j| rot[i][j] * p[j]).sum());
        }
        m
    }

    const I: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    fn rotation() -> [[f64; 3]; 3] {
        // rotation by 0.7 rad about the axis (1, 2, 2)/3
        let k = [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
        let (s, c) = 0.7f64.sin_cos();
        std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                let kk = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
                let kk2: f64 = (0..3).map(|l| kk[i][l] * kk[l][j]).sum();
                I[i][j] + s * kk[i][j] + (1.0 - c) * kk2
            })
        })
    }

    /// The slave nodes "over" the master (the warning's candidates) are those inside the master's
    /// outline, not its bounding box: an L-shaped master leaves its missing quadrant out, and a
    /// hole in it stays inside. Before: every node within the bounding box.
    #[test]
    fn over_the_master_means_inside_its_outline() {
        let m = blocks(9, 9, [0.0; 3], I);
        let face = |n: &str| m.faces.iter().find(|f| f.name == n).unwrap();
        let (slave, full) = (face("upper.zmin"), face("lower.zmax"));
        let centre = |q: &crate::mesh::Facet| {
            let x = m.facet_coords(q);
            [0.25 * x.iter().map(|p| p[0]).sum::<f64>(), 0.25 * x.iter().map(|p| p[1]).sum::<f64>()]
        };
        // the 2 × 1 face (facets 0.25 × 0.125) less its quadrant x > 1, y > 0.5, and for the
        // second master less the four facets about (0.5, 0.25) too
        let l_shape = |hole: bool| Face {
            name: "lower.l".into(),
            body: 1,
            facets: full
                .facets
                .iter()
                .filter(|q| {
                    let c = centre(q);
                    (c[0] < 1.0 || c[1] < 0.5) && !(hole && (c[0] - 0.5).abs() < 0.25 && (c[1] - 0.25).abs() < 0.125)
                })
                .copied()
                .collect(),
        };
        let at = |x: f64, y: f64| slave.nodes().into_iter().find(|&v| (m.nodes[v][0] - x).abs() < 1e-9 && (m.nodes[v][1] - y).abs() < 1e-9).unwrap();
        let (quadrant, over) = (at(1.5, 0.75), at(0.5, 0.25));
        for hole in [false, true] {
            let o = Outside::new(&m, slave, &l_shape(hole), vec![quadrant, over], 0.2);
            assert_eq!(o.over, vec![over], "hole {hole}");
        }
    }

    fn seed_pair(friction: Friction) -> ContactPair {
        ContactPair {
            slave: "upper.zmin".into(),
            master: "lower.zmax".into(),
            friction,
            tolerance: None,
            discretization: None,
            search_distance: None,
            max_overlap: None,
            interference: crate::scene::Fit::None,
            faces: None,
        }
    }

    fn faces(m: &Mesh, s: &str, ma: &str) -> Vec<(usize, usize)> {
        let f = |n: &str| m.faces.iter().position(|f| f.name == n).unwrap();
        vec![(f(s), f(ma))]
    }

    #[test]
    fn seed_pairs_frames_areas() {
        let m = blocks(8, 8, [0.0; 3], I);
        let c = pair(&m, &[seed_pair(Friction::Tresca { g: 0.09 })], &faces(&m, "upper.zmin", "lower.zmax")).unwrap();
        assert_eq!(c.len(), 64);
        let total: f64 = c.area.iter().sum();
        assert!((total - 2.0).abs() < 1e-13);
        let h = (2.0 / 7.0) * (1.0 / 7.0);
        for i in 0..c.len() {
            assert_eq!(c.normal[i], [0.0, 0.0, -1.0]);
            assert_eq!(c.t1[i], [1.0, 0.0, 0.0]);
            assert_eq!(c.t2[i], [0.0, 1.0, 0.0]);
            assert_eq!(c.gap[i], 0.0);
            let master = c.row(i)[1].0;
            let (xs, xm) = (m.nodes[c.slave[i]], m.nodes[master]);
            assert!(sub(xs, xm).iter().all(|v| v.abs() < 1e-14));
            assert!(m.bodies[0].nodes.contains(&c.slave[i]) && m.bodies[1].nodes.contains(&master));
            // lumped areas: quarter at corners, half on edges, full inside
            let on = |v: f64, a: f64| (v - a).abs() < 1e-12;
            let edges = [on(xs[0], 0.0) || on(xs[0], 2.0), on(xs[1], 0.0) || on(xs[1], 1.0)].iter().filter(|&&b| b).count();
            assert!((c.area[i] - h / f64::from(1 << edges)).abs() < 1e-14);
            assert_eq!(c.bound[i], SlipBound::Disc(0.09 * c.area[i]));
        }
    }

    /// Slave nodes without a master facet are outside the contact zone, not an error; those
    /// over a hole in the master face are flagged; no slave node at all finding one is an error.
    #[test]
    fn slave_nodes_without_a_master_are_outside_and_a_hole_is_flagged() {
        let mut m = blocks(5, 5, [0.0; 3], I);
        let lower = m.faces.iter().position(|f| f.name == "lower.zmax").unwrap();
        let inner = |v: usize| (0.49..=1.51).contains(&m.nodes[v][0]) && (0.24..=0.76).contains(&m.nodes[v][1]);
        let keep: Vec<_> = m.faces[lower].facets.iter().filter(|q| !q.nodes().iter().all(|&v| inner(v))).cloned().collect();
        assert_eq!(keep.len(), 16 - 4, "the central 2 × 2 master facets are cut out");
        m.faces[lower].facets = keep;
        let c = pair(&m, &[seed_pair(Friction::None)], &faces(&m, "upper.zmin", "lower.zmax")).unwrap();
        let o = &c.outside[0];
        assert_eq!(c.len(), 24);
        assert_eq!(o.nodes.len(), 1);
        assert_eq!(m.nodes[o.nodes[0]], [1.0, 0.5, 1.0]);
        assert_eq!(o.over, o.nodes, "the node over the hole is flagged");
        // the slave face larger than the master: its nodes beyond the master are outside, not flagged
        let mut m = blocks(5, 5, [0.0; 3], I);
        let upper = m.faces.iter().position(|f| f.name == "upper.zmin").unwrap();
        let lower = m.faces.iter().position(|f| f.name == "lower.zmax").unwrap();
        let half: Vec<_> = m.faces[lower].facets.iter().filter(|q| q.nodes().iter().all(|&v| m.nodes[v][0] <= 1.0 + 1e-12)).cloned().collect();
        m.faces[lower].facets = half;
        let c = pair(&m, &[seed_pair(Friction::None)], &faces(&m, "upper.zmin", "lower.zmax")).unwrap();
        assert_eq!(c.outside[0].nodes.len(), 2 * 5, "the slave nodes at x = 1.5 and 2 (their facets touch the master along x = 1 only)");
        assert!(c.outside[0].over.is_empty());
        // no slave node finds a master (the master faces away): an error naming both faces
        let away = m.faces.iter().position(|f| f.name == "lower.zmin").unwrap();
        let mortar = ContactPair { discretization: Some(Discretization::Mortar), ..seed_pair(Friction::None) };
        let e = pair(&m, &[mortar], &[(upper, away)]).unwrap_err().to_string();
        assert!(e.contains("contact.pair[0]") && e.contains("no slave node of upper.zmin finds a master facet of lower.zmin"), "{e}");
    }

    #[test]
    fn rotated_faces_with_a_gap() {
        let r = rotation();
        let m = blocks(5, 5, [0.0, 0.0, 0.01], r);
        let c = pair(&m, &[seed_pair(Friction::None)], &faces(&m, "upper.zmin", "lower.zmax")).unwrap();
        assert_eq!(c.len(), 25);
        let n: [f64; 3] = std::array::from_fn(|i| -r[i][2]);
        for i in 0..c.len() {
            assert!(sub(c.normal[i], n).iter().all(|v| v.abs() < 1e-13), "{:?} vs {n:?}", c.normal[i]);
            assert!((c.gap[i] - 0.01).abs() < 1e-13);
            assert!(dot(c.t1[i], c.normal[i]).abs() < 1e-14 && dot(c.t2[i], c.normal[i]).abs() < 1e-14);
            assert!(dot(c.t1[i], c.t2[i]).abs() < 1e-14 && (dot(c.t2[i], c.t2[i]) - 1.0).abs() < 1e-14);
            assert_eq!(c.bound[i], SlipBound::None);
        }
        assert!(!c.has_friction());
        assert!((c.area.iter().sum::<f64>() - 2.0).abs() < 1e-13);
    }

    #[test]
    fn orthotropic_frame_follows_the_direction() {
        let m = blocks(4, 4, [0.0; 3], I);
        let p = seed_pair(Friction::Orthotropic { g1: 0.1, g2: 0.05, direction: [1.0, 1.0, 0.5] });
        let c = pair(&m, &[p], &faces(&m, "upper.zmin", "lower.zmax")).unwrap();
        let s = 0.5f64.sqrt();
        for i in 0..c.len() {
            assert!(sub(c.t1[i], [s, s, 0.0]).iter().all(|v| v.abs() < 1e-14));
            assert_eq!(c.bound[i], SlipBound::Ellipse(0.1 * c.area[i], 0.05 * c.area[i]));
        }
        // a direction whose squared length overflows or underflows is still (1, 1, 0)/√2 in the plane
        for scale in [1e300, 1e-300] {
            let p = seed_pair(Friction::Orthotropic { g1: 0.1, g2: 0.05, direction: [scale, scale, 0.5 * scale] });
            let c = pair(&m, &[p], &faces(&m, "upper.zmin", "lower.zmax")).unwrap();
            assert!(sub(c.t1[0], [s, s, 0.0]).iter().all(|v| v.abs() < 1e-14), "{scale}: {:?}", c.t1[0]);
        }
        let p = seed_pair(Friction::Orthotropic { g1: 0.1, g2: 0.05, direction: [0.0, 0.0, 1.0] });
        let e = pair(&m, &[p], &faces(&m, "upper.zmin", "lower.zmax")).unwrap_err().to_string();
        assert!(e.contains("direction") && e.contains("normal"), "{e}");
    }

    #[test]
    fn bad_pairs_are_named() {
        // non-matching faces: refused by node-to-node, naming both faces; mortar (the default
        // there) gives a row per slave node, covering the face
        let n2n = |f| ContactPair { discretization: Some(Discretization::NodeToNode), ..seed_pair(f) };
        let m = blocks(5, 4, [0.0; 3], I);
        let e = pair(&m, &[n2n(Friction::None)], &faces(&m, "upper.zmin", "lower.zmax")).unwrap_err().to_string();
        assert!(e.contains("contact.pair[0]") && e.contains("upper.zmin") && e.contains("lower.zmax") && e.contains("mortar"), "{e}");
        let c = pair(&m, &[seed_pair(Friction::None)], &faces(&m, "upper.zmin", "lower.zmax")).unwrap();
        assert_eq!(c.len(), 25);
        assert!((c.area.iter().sum::<f64>() - 2.0).abs() < 1e-12);
        assert!(c.coupling.iter().all(|r| r.len() > 2 || r.len() == 2));
        let m = blocks(4, 4, [0.0; 3], I);
        let e = pair(&m, &[seed_pair(Friction::None)], &faces(&m, "upper.zmin", "lower.zmin")).unwrap_err().to_string();
        assert!(e.contains("do not face each other"), "{e}");
        let m = blocks(4, 4, [0.0, 0.0, -0.1], I);
        let e = pair(&m, &[seed_pair(Friction::None)], &faces(&m, "upper.zmin", "lower.zmax")).unwrap_err().to_string();
        assert!(e.contains("overlap"), "{e}");
        let m = blocks(4, 4, [0.05, 0.0, 0.0], I);
        let e = pair(&m, &[n2n(Friction::None)], &faces(&m, "upper.zmin", "lower.zmax")).unwrap_err().to_string();
        assert!(e.contains("do not match node to node"), "{e}");
        // far apart: no master facet within the search distance, the slave node named
        let m = blocks(4, 4, [0.0, 0.0, 0.5], I);
        let e = pair(&m, &[ContactPair { discretization: Some(Discretization::Mortar), ..seed_pair(Friction::None) }], &faces(&m, "upper.zmin", "lower.zmax"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("contact.pair[0]") && e.contains("slave node") && e.contains("search distance"), "{e}");
        // one interface given twice, or from both sides
        let m = blocks(4, 4, [0.0; 3], I);
        let twice = [faces(&m, "upper.zmin", "lower.zmax"), faces(&m, "upper.zmin", "lower.zmax")].concat();
        let e = pair(&m, &[seed_pair(Friction::None), seed_pair(Friction::None)], &twice).unwrap_err().to_string();
        assert!(e.contains("contact.pair[1]") && e.contains("already a pair of contact.pair[0]"), "{e}");
        let swapped = ContactPair { slave: "lower.zmax".into(), master: "upper.zmin".into(), ..seed_pair(Friction::None) };
        let both = [faces(&m, "upper.zmin", "lower.zmax"), faces(&m, "lower.zmax", "upper.zmin")].concat();
        let e = pair(&m, &[seed_pair(Friction::None), swapped], &both).unwrap_err().to_string();
        assert!(e.contains("contact.pair[1]") && e.contains("already a pair of contact.pair[0]"), "{e}");
    }
}

/// The slave nodes of one contact entry outside its contact zone: no master facet within the
/// search distance `search`, so no row (inactive). `over` are those of them over the master
/// face — inside its outline seen along its mean normal, facing it, and within half the search
/// distance of its level — a region that looks as if it should touch but found no master (a
/// hole in the master face, facets facing away): a warning, not an error.
#[derive(Clone, Debug, Default)]
pub struct Outside {
    pub nodes: Vec<usize>,
    pub over: Vec<usize>,
    pub search: f64,
    /// Where the first of `nodes` and of `over` are (kept when the mesh is released).
    pub first: [Option<[f64; 3]>; 2],
}

/// The outer boundary of a face seen along a direction (`project` maps a point to the plane
/// normal to it): its boundary edges (those of one facet only; through the edge nodes of
/// quadratic facets) chained into loops, the loop of the largest projected area. Holes are
/// inner loops, so a point over a hole lies inside the outline.
fn outline(mesh: &Mesh, face: &Face, project: impl Fn([f64; 3]) -> [f64; 2]) -> Vec<[f64; 2]> {
    // each facet edge as (corner a, corner b, edge node), a → b along the facet
    let mut edges: HashMap<(usize, usize), (usize, Option<usize>, usize)> = HashMap::new();
    for q in &face.facets {
        let (nodes, c) = (q.nodes(), q.corners().len());
        for i in 0..c {
            let (a, b) = (nodes[i], nodes[(i + 1) % c]);
            let mid = (nodes.len() > c).then(|| nodes[c + i]);
            edges.entry((a.min(b), a.max(b))).and_modify(|e| e.2 += 1).or_insert((a, mid, 1));
        }
    }
    let mut next: HashMap<usize, Vec<(usize, Option<usize>)>> = HashMap::new();
    for (&(lo, hi), &(a, mid, count)) in &edges {
        if count == 1 {
            let b = if a == lo { hi } else { lo };
            next.entry(a).or_default().push((b, mid));
        }
    }
    let mut starts: Vec<usize> = next.keys().copied().collect();
    starts.sort_unstable();
    let (mut best, mut best_area) = (Vec::new(), 0.0f64);
    for start in starts {
        let mut polygon = Vec::new();
        let mut at = start;
        while let Some((b, mid)) = next.get_mut(&at).and_then(Vec::pop) {
            polygon.push(project(mesh.nodes[at]));
            if let Some(m) = mid {
                polygon.push(project(mesh.nodes[m]));
            }
            at = b;
            if at == start {
                break;
            }
        }
        let n = polygon.len();
        let area = 0.5 * (0..n).map(|i| polygon[i][0] * polygon[(i + 1) % n][1] - polygon[(i + 1) % n][0] * polygon[i][1]).sum::<f64>().abs();
        if area > best_area {
            (best, best_area) = (polygon, area);
        }
    }
    best
}

/// Whether `p` lies strictly inside the polygon (crossings of a ray along +x).
fn inside_polygon(polygon: &[[f64; 2]], p: [f64; 2]) -> bool {
    let n = polygon.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (polygon[i], polygon[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) && p[0] < a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]) {
            inside = !inside;
        }
    }
    inside
}

impl Outside {
    fn new(mesh: &Mesh, slave: &Face, master: &Face, nodes: Vec<usize>, search: f64) -> Self {
        let first = nodes.first().map(|&v| mesh.nodes[v]);
        let mut out = Outside { nodes, over: vec![], search, first: [first, None] };
        let normal_area = |f: &crate::mesh::Facet| facet_normal_area(f.kind, &f.nodes().iter().map(|&v| mesh.nodes[v]).collect::<Vec<_>>());
        let areas: Vec<[f64; 3]> = master.facets.iter().map(normal_area).collect();
        let mean = areas.iter().fold([0.0; 3], |a, n| std::array::from_fn(|d| a[d] + n[d]));
        let total: f64 = areas.iter().map(|&n| dot(n, n).sqrt()).sum();
        let len = dot(mean, mean).sqrt();
        // a closed or strongly curved master has no outline along one direction
        if out.nodes.is_empty() || len < 0.5 * total {
            return out;
        }
        let nm = mean.map(|v| v / len);
        let e1 = tangent(nm, [1.0, 0.0, 0.0]).or_else(|| tangent(nm, [0.0, 1.0, 0.0])).expect("x and y cannot both be normal");
        let e2 = cross(nm, e1);
        let mut level = [f64::INFINITY, f64::NEG_INFINITY];
        for v in master.nodes() {
            let h = dot(mesh.nodes[v], nm);
            level = [level[0].min(h), level[1].max(h)];
        }
        let outline = outline(mesh, master, |x| [dot(x, e1), dot(x, e2)]);
        // the outside nodes' normals, area-weighted over their slave facets
        let mut normals: HashMap<usize, [f64; 3]> = out.nodes.iter().map(|&v| (v, [0.0; 3])).collect();
        for f in &slave.facets {
            let n = normal_area(f);
            for v in f.nodes() {
                if let Some(s) = normals.get_mut(v) {
                    (0..3).for_each(|d| s[d] += n[d]);
                }
            }
        }
        out.over = out
            .nodes
            .iter()
            .copied()
            .filter(|v| {
                let (x, n) = (mesh.nodes[*v], normals[v]);
                let inside = inside_polygon(&outline, [dot(x, e1), dot(x, e2)]);
                let h = dot(x, nm);
                // well within reach (a node near the search distance may miss it along its
                // facets' slanted normals)
                let near = h >= level[0] - 0.5 * search && h <= level[1] + 0.5 * search;
                inside && near && dot(n, nm) < -0.5 * dot(n, n).sqrt()
            })
            .collect();
        out.first[1] = out.over.first().map(|&v| mesh.nodes[v]);
        out
    }
}
