//! H-TFETI clusters (docs/method.md, "Scale-out: H-TFETI"): groups of subdomains of one body that the outer dual treats
//! as one floating piece. Inside a cluster the subdomains are joined by the gluing rows of a few
//! **corner nodes** per adjacent pair (B_c), enforced exactly by every application of the
//! cluster's generalized inverse — a small saddle-point problem per cluster — so the cluster's
//! kernel is R_c = R N, N an orthonormal basis of Ker B_c R (six columns for a floating cluster,
//! fewer where held DOFs are eliminated), and the global coarse problem has k_c unknowns per
//! cluster instead of k_s per subdomain. The other rows of B (the interface inside the cluster
//! included) stay the outer dual's.
//!
//! **K_c⁺** (the symmetric generalized inverse E(EᵀKE)⁺Eᵀ of the cluster's operator, E an
//! orthonormal basis of Ker B_c): x̃ = x − R_c R_cᵀ x (the part in the range), z = K⁺x̃, then
//! the corner forces μ and the member amplitudes β from
//!
//! ```text
//! [ F_c   −G_cᵀ ] [μ]   [ B_c z ]          F_c = B_c K⁺ B_cᵀ,  G_c = Rᵀ B_cᵀ,
//! [ −G_c    0   ] [β] = [ −Rᵀx̃ ],          u = z − K⁺B_cᵀ μ + R β,
//! ```
//!
//! made regular by N Nᵀ on the β block (the consistent right-hand side keeps Nᵀβ = 0) and
//! inverted densely once, and u ← u − R_c R_cᵀ u; K⁺B_cᵀ is kept per subdomain (one K_s⁺ solve
//! per product, as in TFETI). Clusters are fixed by the decomposition alone (METIS on each body's subdomain graph),
//! never by the rank count; a cluster of one subdomain is that subdomain, bit for bit.

use super::constraints::Constraints;
use super::decomposition::Decomposition;
use super::subdomain::{held_kernel, SubdomainSystem, NR};
use crate::error::{Error, Result};
use crate::linalg::sparse::SymCsc;
use crate::mesh::Mesh;

/// Most unknowns of a cluster's corner problem (corner rows + the members' kernel columns): it
/// is inverted densely once (≈ 128 MB and a few tens of seconds at this size).
pub const MAX_CORNER_SYSTEM: usize = 4000;
/// Share of the largest eigenvalue of (B_c R)ᵀ(B_c R) at or below which a direction is a rigid
/// motion of the whole cluster.
const KERNEL_SHARE: f64 = 1e-10;

/// B_c of one cluster, one entry list per member: (corner row, local DOF, coefficient).
pub type CornerEntries = Vec<Vec<(usize, usize, f64)>>;
/// The gluing rows of one node and component: row → its entries (subdomain, local DOF,
/// coefficient).
type NodeRows = std::collections::BTreeMap<usize, Vec<(usize, usize, f64)>>;

/// The clusters of a decomposition and the rows of B that join their subdomains.
#[derive(Clone, Debug)]
pub struct Clustering {
    /// Per cluster: its subdomains, ascending. Clusters ordered by body.
    pub members: Vec<Vec<usize>>,
    /// Per subdomain: its cluster and the first of its DOFs in the cluster's numbering.
    pub cluster_of: Vec<usize>,
    pub offset: Vec<usize>,
    /// Per cluster: B_c, one entry list per member (corner row, local DOF, coefficient), and
    /// its number of rows.
    pub bc: Vec<(CornerEntries, usize)>,
    /// The null space of F = B K_c⁺ Bᵀ: per corner row, the combination w of B's gluing rows
    /// with Bᵀw = B_cᵀe_j, (row, value), unit, rows ascending; together orthonormal.
    pub null: Vec<Vec<(usize, f64)>>,
}

impl Clustering {
    /// Every subdomain its own cluster: TFETI.
    pub fn singletons(d: &Decomposition) -> Self {
        let ns = d.subdomains.len();
        Clustering {
            members: (0..ns).map(|s| vec![s]).collect(),
            cluster_of: (0..ns).collect(),
            offset: vec![0; ns],
            bc: vec![(vec![vec![]], 0); ns],
            null: vec![],
        }
    }

    /// Clusters of about `per_cluster` subdomains of each body (a METIS k-way partition of the
    /// body's subdomain graph, contiguous parts) and their corner rows: the gluing rows of up to
    /// [`CORNERS_PER_PAIR`] spread nodes shared by each pair of adjacent members (nodes whose
    /// copies all lie in the cluster).
    pub fn new(mesh: &Mesh, d: &Decomposition, cons: &Constraints, per_cluster: usize) -> Result<Self> {
        if per_cluster <= 1 {
            return Ok(Self::singletons(d));
        }
        let ns = d.subdomains.len();
        let dofs: Vec<usize> = d.subdomains.iter().map(|s| 3 * s.nodes.len()).collect();
        // subdomain pairs sharing nodes, weighted by their count
        let mut weight: std::collections::BTreeMap<(usize, usize), usize> = Default::default();
        for copies in d.copies.iter().filter(|c| c.len() > 1) {
            for (i, &(a, _)) in copies.iter().enumerate() {
                for &(b, _) in &copies[i + 1..] {
                    *weight.entry((a.min(b), a.max(b))).or_default() += 1;
                }
            }
        }
        let mut cluster_of = vec![0; ns];
        let mut members: Vec<Vec<usize>> = Vec::new();
        let mut first = 0;
        while first < ns {
            let body = d.subdomains[first].body;
            let last = (first..ns).find(|&s| d.subdomains[s].body != body).unwrap_or(ns);
            let nb = last - first;
            let parts = nb.div_ceil(per_cluster);
            let part = if parts <= 1 {
                vec![0; nb]
            } else {
                body_parts(first, last, &weight, &dofs, parts).ok_or_else(|| {
                    Error::numerical(
                        format!("METIS clusters of body \"{}\"", mesh.bodies[body].name),
                        "the partition of the subdomain graph failed; try another decomposition.subdomains_per_cluster",
                    )
                })?
            };
            let base = members.len();
            let mut groups = vec![Vec::new(); parts.max(1)];
            for (k, &p) in part.iter().enumerate() {
                groups[p].push(first + k);
            }
            for g in groups.into_iter().filter(|g| !g.is_empty()) {
                let c = members.len();
                g.iter().for_each(|&s| cluster_of[s] = c);
                members.push(g);
            }
            debug_assert!(members.len() > base);
            first = last;
        }
        let mut offset = vec![0; ns];
        for m in &members {
            let mut o = 0;
            for &s in m {
                offset[s] = o;
                o += dofs[s];
            }
        }
        // the gluing row of every free component of the face nodes (two copies, both in one
        // cluster): (node, component) → rows with their entries (subdomain, local DOF, coefficient)
        let e_start = cons.e_start();
        let mut count = vec![0u32; cons.layout.dim()];
        cons.rows.iter().flatten().for_each(|&(r, _, _)| count[r] += 1);
        let face_node = |v: usize| d.copies[v].len() == 2 && cluster_of[d.copies[v][0].0] == cluster_of[d.copies[v][1].0];
        let mut glue: std::collections::BTreeMap<(usize, usize), NodeRows> = Default::default();
        for (s, rows) in cons.rows.iter().enumerate() {
            // gluing rows: E rows with two entries or more (a Dirichlet row has one)
            for &(r, dof, coef) in rows.iter().filter(|x| x.0 >= e_start && count[x.0] >= 2) {
                let v = d.subdomains[s].nodes[dof / 3];
                if face_node(v) {
                    glue.entry((v, dof % 3)).or_default().entry(r).or_default().push((s, dof, coef));
                }
            }
        }
        // per pair of members: their face nodes (copies ascending by subdomain)
        let mut face: std::collections::BTreeMap<(usize, usize), Vec<usize>> = Default::default();
        for v in (0..d.copies.len()).filter(|&v| face_node(v)) {
            face.entry((d.copies[v][0].0, d.copies[v][1].0)).or_default().push(v);
        }
        // W: per face, the moments of the jump u_a − u_b against the face's rigid motions as
        // combinations of the gluing rows (per node and component, λ with Σ λ_r B_r = e_a − e_b),
        // orthonormalized per cluster (dependent ones dropped)
        let mut raw: Vec<Vec<Vec<(usize, f64)>>> = vec![Vec::new(); members.len()];
        for (&(a, b), nodes) in &face {
            let dofs: Vec<(usize, usize)> = nodes.iter().flat_map(|&v| (0..3).map(move |k| (v, k))).filter(|x| glue.contains_key(x)).collect();
            let jumps: Vec<Vec<(usize, f64)>> = dofs.iter().map(|&(v, k)| jump_rows(&glue[&(v, k)], a, b)).collect();
            for q in face_modes(&dofs, &mesh.nodes) {
                let mut w: std::collections::BTreeMap<usize, f64> = Default::default();
                for (jr, &x) in jumps.iter().zip(&q) {
                    jr.iter().for_each(|&(r, l)| *w.entry(r).or_default() += x * l);
                }
                raw[cluster_of[a]].push(w.into_iter().collect());
            }
        }
        // B_c = Wᵀ B on the cluster's subdomains
        let mut bc: Vec<(CornerEntries, usize)> = members.iter().map(|m| (vec![Vec::new(); m.len()], 0)).collect();
        let mut entries_of: std::collections::HashMap<usize, &Vec<(usize, usize, f64)>> = Default::default();
        for rows in glue.values() {
            for (&r, list) in rows {
                entries_of.insert(r, list);
            }
        }
        let mut null = Vec::new();
        for (c, ws) in raw.into_iter().enumerate() {
            let (lists, nc) = &mut bc[c];
            for w in orthonormalize(ws) {
                let mut row: std::collections::BTreeMap<(usize, usize), f64> = Default::default();
                for &(r, x) in &w {
                    for &(s, dof, coef) in entries_of[&r] {
                        *row.entry((s, dof)).or_default() += x * coef;
                    }
                }
                for ((s, dof), v) in row {
                    let p = members[c].binary_search(&s).expect("a member");
                    lists[p].push((*nc, dof, v));
                }
                *nc += 1;
                null.push(w);
            }
        }
        // the corner problem is solved densely: refuse one too large to hold and invert
        for (c, (_, nc)) in bc.iter().enumerate() {
            let n2 = nc + NR * members[c].len();
            if n2 > MAX_CORNER_SYSTEM {
                return Err(Error::scene(
                    "decomposition.subdomains_per_cluster",
                    format!(
                        "cluster {c} of {} subdomains has a corner problem of {n2} unknowns (at most {MAX_CORNER_SYSTEM}, held dense); use smaller clusters",
                        members[c].len()
                    ),
                ));
            }
        }
        Ok(Clustering { members, cluster_of, offset, bc, null })
    }

    /// Number of clusters.
    pub fn len(&self) -> usize {
        self.members.len()
    }

    pub fn is_empty(&self) -> bool {
        self.members.is_empty()
    }

    /// Rows of all the B_c.
    pub fn corner_rows(&self) -> usize {
        self.bc.iter().map(|x| x.1).sum()
    }

    /// Whether cluster `c` is a subdomain on its own (no corners): TFETI's piece.
    pub fn is_single(&self, c: usize) -> bool {
        self.members[c].len() == 1 && self.bc[c].1 == 0
    }

    /// The outer dual's constraints: B's rows (all of them: B_c's rows are combinations of its
    /// gluing rows, [`Clustering::null`]), one entry list per cluster over the cluster's DOFs
    /// (member s's local DOF j is `offset[s] + j`). Clusters of one subdomain each (TFETI) take
    /// `cons` as it is: no second copy of B.
    pub fn outer(&self, cons: Constraints) -> Constraints {
        if (0..self.len()).all(|c| self.members[c] == [c] && self.offset[c] == 0) {
            return cons;
        }
        let rows =
            self.members.iter().map(|m| m.iter().flat_map(|&s| cons.rows[s].iter().map(move |&(r, j, v)| (r, self.offset[s] + j, v))).collect()).collect();
        Constraints { rows, ..cons }
    }

    /// Per cluster: its members' vectors one after the other (`per_sub[s]` for subdomain s).
    pub fn concat(&self, per_sub: &[Vec<f64>]) -> Vec<Vec<f64>> {
        self.members.iter().map(|m| m.iter().flat_map(|&s| per_sub[s].iter().copied()).collect()).collect()
    }

    /// R_c of every cluster (column-major, the cluster's DOFs × k_c) from the members' kernels
    /// with their held DOFs `eliminated`.
    pub fn kernels(&self, mesh: &Mesh, d: &Decomposition, eliminated: &[Vec<usize>]) -> Vec<(Vec<f64>, usize)> {
        let part = |s: usize| (d.subdomains[s].nodes.iter().map(|&v| mesh.nodes[v]).collect(), eliminated[s].as_slice());
        (0..self.len()).map(|c| self.kernel(c, &part)).collect()
    }

    /// R_c of the clusters `pieces` only (None for the others), from each member's node
    /// coordinates and held DOFs (`part(s)`): what a rank's blocks of G need.
    pub fn kernels_of<'a>(&self, pieces: &[usize], part: impl Fn(usize) -> (Vec<[f64; 3]>, &'a [usize])) -> Vec<Option<(Vec<f64>, usize)>> {
        let mut out = vec![None; self.len()];
        pieces.iter().for_each(|&c| out[c] = Some(self.kernel(c, &part)));
        out
    }

    /// R_c of cluster `c` (see [`Clustering::kernels`]).
    fn kernel<'a>(&self, c: usize, part: &impl Fn(usize) -> (Vec<[f64; 3]>, &'a [usize])) -> (Vec<f64>, usize) {
        let rs: Vec<(Vec<f64>, usize, usize)> = self.members[c]
            .iter()
            .map(|&s| {
                let (coords, held) = part(s);
                let (r, k) = held_kernel(&coords, held).expect("eliminated only where the held DOFs leave an exact kernel");
                (r, k, 3 * coords.len())
            })
            .collect();
        if self.is_single(c) {
            return rs.into_iter().next().map(|(r, k, _)| (r, k)).expect("one member");
        }
        let members: Vec<(&[f64], usize, usize)> = rs.iter().map(|(r, k, nd)| (r.as_slice(), *k, *nd)).collect();
        let (_, _, n, kc) = kernel_basis(&members, &self.bc[c].0, self.bc[c].1);
        (expand(&members, &n, kc), kc)
    }
}

/// METIS k-way parts of the subdomains `first..last` (one body) on their graph; `None` if METIS fails.
fn body_parts(first: usize, last: usize, weight: &std::collections::BTreeMap<(usize, usize), usize>, dofs: &[usize], parts: usize) -> Option<Vec<usize>> {
    let nb = last - first;
    let mut adj: Vec<Vec<(usize, usize)>> = vec![Vec::new(); nb];
    for (&(a, b), &w) in weight.range((first, 0)..(last, 0)) {
        if b < last {
            adj[a - first].push((b - first, w));
            adj[b - first].push((a - first, w));
        }
    }
    super::kway(adj, &dofs[first..last], parts, true)
}

/// The rigid motions of a face (translations, rotations about its centroid) on its DOFs
/// `dofs` (node, component), orthonormalized (modified Gram–Schmidt, twice; a motion that
/// vanishes there — collinear nodes — dropped).
fn face_modes(dofs: &[(usize, usize)], coords: &[[f64; 3]]) -> Vec<Vec<f64>> {
    if dofs.is_empty() {
        return vec![];
    }
    let n = dofs.len() as f64;
    let mut c = [0.0; 3];
    dofs.iter().for_each(|&(v, _)| (0..3).for_each(|d| c[d] += coords[v][d] / n));
    let mode = |j: usize, (v, k): (usize, usize)| -> f64 {
        let x = [0, 1, 2].map(|d| coords[v][d] - c[d]);
        match j {
            0..=2 => f64::from(u8::from(k == j)),
            // (e_{j−3} × x)_k
            _ => [[0.0, -x[2], x[1]], [x[2], 0.0, -x[0]], [-x[1], x[0], 0.0]][j - 3][k],
        }
    };
    let mut out: Vec<Vec<f64>> = Vec::new();
    for j in 0..NR {
        let mut x: Vec<f64> = dofs.iter().map(|&d| mode(j, d)).collect();
        let before = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        for _ in 0..2 {
            for q in &out {
                let h: f64 = q.iter().zip(&x).map(|(a, b)| a * b).sum();
                x.iter_mut().zip(q).for_each(|(a, b)| *a -= h * b);
            }
        }
        let nrm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        if nrm > 1e-6 * before {
            x.iter_mut().for_each(|v| *v /= nrm);
            out.push(x);
        }
    }
    out
}

/// λ on the gluing rows `rows` of one node and component (row → its entries (subdomain, DOF,
/// coefficient)) with Σ_r λ_r B_r = e_a − e_b on the node's copies: (HHᵀ)λ = H(e_a − e_b), H
/// the rows on the copies (a basis of the complement of (1, …, 1)).
fn jump_rows(rows: &NodeRows, a: usize, b: usize) -> Vec<(usize, f64)> {
    let ids: Vec<usize> = rows.keys().copied().collect();
    let coef = |r: usize, s: usize| rows[&r].iter().find(|x| x.0 == s).map_or(0.0, |x| x.2);
    let copies: std::collections::BTreeSet<usize> = rows.values().flatten().map(|x| x.0).collect();
    let m = ids.len();
    let hh = faer::Mat::<f64>::from_fn(m, m, |i, j| copies.iter().map(|&s| coef(ids[i], s) * coef(ids[j], s)).sum());
    let rhs = faer::Mat::<f64>::from_fn(m, 1, |i, _| coef(ids[i], a) - coef(ids[i], b));
    use faer::linalg::solvers::Solve;
    let lam = hh.llt(faer::Side::Lower).expect("gluing rows of a node are independent").solve(&rhs);
    ids.iter().enumerate().map(|(i, &r)| (r, lam[(i, 0)] * std::f64::consts::FRAC_1_SQRT_2)).collect()
}

/// Modified Gram–Schmidt (twice) on sparse vectors (row, value), sorted; a vector that keeps
/// less than 1e-8 of its norm is dropped.
fn orthonormalize(ws: Vec<Vec<(usize, f64)>>) -> Vec<Vec<(usize, f64)>> {
    let mut out: Vec<Vec<(usize, f64)>> = Vec::new();
    let mut by_row: std::collections::HashMap<usize, Vec<usize>> = Default::default();
    for w in ws {
        let mut x: std::collections::BTreeMap<usize, f64> = w.into_iter().collect();
        let before = x.values().map(|v| v * v).sum::<f64>().sqrt();
        for _ in 0..2 {
            let mut near: Vec<usize> = x.keys().filter_map(|r| by_row.get(r)).flatten().copied().collect();
            near.sort_unstable();
            near.dedup();
            for &j in &near {
                let h: f64 = out[j].iter().map(|&(r, q)| q * x.get(&r).copied().unwrap_or(0.0)).sum();
                out[j].iter().for_each(|&(r, q)| *x.entry(r).or_default() -= h * q);
            }
        }
        let nrm = x.values().map(|v| v * v).sum::<f64>().sqrt();
        if nrm > 1e-8 * before {
            let j = out.len();
            let v: Vec<(usize, f64)> = x.into_iter().filter(|x| x.1 != 0.0).map(|(r, v)| (r, v / nrm)).collect();
            v.iter().for_each(|&(r, _)| by_row.entry(r).or_default().push(j));
            out.push(v);
        }
    }
    out
}

/// G_c = Rᵀ B_cᵀ (Σk × n_c, row-major), its row offsets per member, and N, an orthonormal basis
/// of Ker B_c R (Σk × k_c, column-major), with k_c. `members`: (R_s column-major, k_s, DOFs).
fn kernel_basis(members: &[(&[f64], usize, usize)], corners: &[Vec<(usize, usize, f64)>], nc: usize) -> (Vec<f64>, Vec<usize>, Vec<f64>, usize) {
    let mut roff = vec![0];
    members.iter().for_each(|m| roff.push(roff.last().unwrap() + m.1));
    let sk = *roff.last().unwrap();
    let mut g = vec![0.0; sk * nc];
    for (&(r, k, nd), (entries, &o)) in members.iter().zip(corners.iter().zip(&roff)) {
        for &(i, dof, v) in entries {
            for jj in 0..k {
                g[(o + jj) * nc + i] += v * r[jj * nd + dof];
            }
        }
    }
    let gg = faer::Mat::<f64>::from_fn(sk, sk, |a, b| (0..nc).map(|i| g[a * nc + i] * g[b * nc + i]).sum());
    let eig = gg.self_adjoint_eigen(faer::Side::Lower).expect("eigenvalues of a small symmetric matrix");
    let (mu, q) = (eig.S(), eig.U());
    let top = (0..sk).map(|i| mu[i]).fold(0.0, f64::max);
    let ker: Vec<usize> = (0..sk).filter(|&i| mu[i] <= KERNEL_SHARE * top).collect();
    let n: Vec<f64> = ker.iter().flat_map(|&i| (0..sk).map(move |a| q[(a, i)])).collect();
    (g, roff, n, ker.len())
}

/// R N: the members' kernels (block-diagonal) times N (Σk × k_c), column-major over the
/// cluster's DOFs.
fn expand(members: &[(&[f64], usize, usize)], n: &[f64], kc: usize) -> Vec<f64> {
    let ndc: usize = members.iter().map(|m| m.2).sum();
    let sk: usize = members.iter().map(|m| m.1).sum();
    let mut out = vec![0.0; ndc * kc];
    for j in 0..kc {
        let (mut off, mut ro) = (0, 0);
        for &(r, k, nd) in members {
            let col = &mut out[j * ndc + off..j * ndc + off + nd];
            for jj in 0..k {
                let w = n[j * sk + ro + jj];
                col.iter_mut().zip(&r[jj * nd..(jj + 1) * nd]).for_each(|(o, x)| *o += w * x);
            }
            off += nd;
            ro += k;
        }
    }
    out
}

/// y = A x (or y + A x with `add`; Aᵀx with `transpose`) times `alpha`, A column-major with
/// `m` rows: faer's product, sequential.
fn gemv(y: &mut [f64], a: &[f64], m: usize, x: &[f64], alpha: f64, add: bool, transpose: bool) {
    use faer::{linalg::matmul::matmul, Accum, MatMut, MatRef, Par};
    let n = a.len().checked_div(m).unwrap_or(0);
    let a = MatRef::from_column_major_slice(a, m, n);
    let accum = if add { Accum::Add } else { Accum::Replace };
    let (x, y) = (MatRef::from_column_major_slice(x, x.len(), 1), MatMut::from_column_major_slice_mut(y, y.len(), 1));
    if transpose {
        matmul(y, accum, a.transpose(), x, alpha, Par::Seq);
    } else {
        matmul(y, accum, a, x, alpha, Par::Seq);
    }
}

/// A cluster assembled and factorized: its subdomains and, with corners, the local saddle-point
/// problem of its generalized inverse.
pub struct ClusterSystem {
    /// Index among the clusters.
    pub index: usize,
    pub subs: Vec<SubdomainSystem>,
    /// First DOF of each member in the cluster's numbering; the cluster's DOF count last.
    pub off: Vec<usize>,
    /// f̂ of the members one after the other.
    pub f: Vec<f64>,
    hybrid: Option<Hybrid>,
    /// Seconds in K_c⁺ outside the members' K_s⁺ solves (the corner problem).
    pub corner_s: std::cell::Cell<f64>,
}

/// The corner coupling of a cluster of several subdomains.
struct Hybrid {
    /// R_c (column-major, the cluster's DOFs × k) and k.
    r: Vec<f64>,
    k: usize,
    nc: usize,
    /// Per member: B_c entries (corner index, local DOF, coefficient), the corner indices of
    /// its columns of K⁺B_cᵀ, and those columns (column-major).
    entries: CornerEntries,
    cols: Vec<Vec<usize>>,
    z: Vec<Vec<f64>>,
    /// Per member: first of its amplitudes β_s; Σk last.
    roff: Vec<usize>,
    /// β's scale in the saddle-point system (β = t β').
    t: f64,
    /// The inverse of the regularized, scaled saddle-point matrix, column-major.
    sinv: Vec<f64>,
}

impl ClusterSystem {
    /// Cluster `index` of the factorized subdomains `subs` (ascending) joined by the corner
    /// entries `corners` (per member, as [`Clustering::corner_entries`]) of `nc` corner rows.
    pub fn new(index: usize, subs: Vec<SubdomainSystem>, corners: CornerEntries, nc: usize) -> Result<Self> {
        let mut off = vec![0];
        subs.iter().for_each(|s| off.push(off.last().unwrap() + s.ndof()));
        let f = subs.iter().flat_map(|s| s.f.iter().copied()).collect();
        let hybrid = (subs.len() > 1 || nc > 0).then(|| Hybrid::new(index, &subs, corners, nc)).transpose()?;
        Ok(ClusterSystem { index, subs, off, f, hybrid, corner_s: Default::default() })
    }

    pub fn ndof(&self) -> usize {
        *self.off.last().unwrap()
    }

    /// Stored entries of the members' Cholesky factors.
    pub fn nnz_l(&self) -> usize {
        self.subs.iter().map(|s| s.nnz_l()).sum()
    }

    /// The kernel R_c (column-major) and its column count.
    pub fn kernel(&self) -> (&[f64], usize) {
        match &self.hybrid {
            Some(h) => (&h.r, h.k),
            None => (&self.subs[0].r, self.subs[0].kdim),
        }
    }

    /// Member `m`'s part of a cluster vector.
    pub fn part<'a>(&self, x: &'a [f64], m: usize) -> &'a [f64] {
        &x[self.off[m]..self.off[m + 1]]
    }

    /// A new load per member: (f_s, g_s).
    pub fn set_load(&mut self, loads: Vec<(Vec<f64>, Vec<f64>)>) {
        for (s, (f, g)) in self.subs.iter_mut().zip(loads) {
            s.set_load(f, g);
        }
        self.f = self.subs.iter().flat_map(|s| s.f.iter().copied()).collect();
    }

    /// x ← K_c⁺ x.
    pub fn pinv_in_place(&self, x: &mut [f64]) {
        self.pinv_corners(x);
    }

    /// x ← K_c⁺ x, the members' solves in single precision when `single` (and their factors
    /// keep a copy): [`ClusterSystem::keep_single`].
    pub fn pinv_in_place_as(&self, x: &mut [f64], single: bool) {
        self.pinv_corners_as(x, single);
    }

    /// Keeps single-precision copies of the members' factors; returns their bytes.
    pub fn keep_single(&mut self) -> usize {
        self.subs.iter_mut().map(|s| s.keep_single()).sum()
    }

    /// x ← K_c⁺ x; returns the corner forces μ (empty without corners). The time outside the
    /// members' K_s⁺ solves adds to [`ClusterSystem::corner_s`].
    pub fn pinv_corners(&self, x: &mut [f64]) -> Vec<f64> {
        self.pinv_corners_as(x, false)
    }

    fn pinv_corners_as(&self, x: &mut [f64], single: bool) -> Vec<f64> {
        let Some(h) = &self.hybrid else {
            self.subs[0].pinv_in_place_as(x, single);
            return vec![];
        };
        let t0 = std::time::Instant::now();
        let mut solves = 0.0;
        let nd = self.ndof();
        // x̃ = x − R_c R_cᵀ x
        let mut gamma = vec![0.0; h.k];
        gemv(&mut gamma, &h.r, nd, x, 1.0, false, true);
        gemv(x, &h.r, nd, &gamma, -1.0, true, false);
        let sk = *h.roff.last().unwrap();
        let mut rhs = vec![0.0; h.nc + sk];
        for (m, s) in self.subs.iter().enumerate() {
            let xs = &mut x[self.off[m]..self.off[m + 1]];
            let nds = xs.len();
            gemv(&mut rhs[h.nc + h.roff[m]..h.nc + h.roff[m + 1]], &s.r[..nds * s.kdim], nds, xs, -h.t, false, true);
            let t1 = std::time::Instant::now();
            s.pinv_in_place_as(xs, single);
            solves += t1.elapsed().as_secs_f64();
            for &(i, dof, v) in &h.entries[m] {
                rhs[i] += v * xs[dof];
            }
        }
        let mut sol = vec![0.0; rhs.len()];
        gemv(&mut sol, &h.sinv, rhs.len(), &rhs, 1.0, false, false);
        let mu = sol[..h.nc].to_vec();
        for (m, s) in self.subs.iter().enumerate() {
            let xs = &mut x[self.off[m]..self.off[m + 1]];
            let nds = xs.len();
            let mu_m: Vec<f64> = h.cols[m].iter().map(|&i| mu[i]).collect();
            gemv(xs, &h.z[m], nds, &mu_m, -1.0, true, false);
            gemv(xs, &s.r[..nds * s.kdim], nds, &sol[h.nc + h.roff[m]..h.nc + h.roff[m + 1]], h.t, true, false);
        }
        // u ← u − R_c R_cᵀ u: with the projection of x, K_c⁺ = E(EᵀKE)⁺Eᵀ (E an orthonormal
        // basis of Ker B_c), symmetric
        gemv(&mut gamma, &h.r, nd, x, 1.0, false, true);
        gemv(x, &h.r, nd, &gamma, -1.0, true, false);
        self.corner_s.set(self.corner_s.get() + t0.elapsed().as_secs_f64() - solves);
        mu
    }

    /// rhs −= B_cᵀ μ: the corner forces on the members.
    pub fn sub_corner_forces(&self, mu: &[f64], rhs: &mut [f64]) {
        if let Some(h) = &self.hybrid {
            for (m, entries) in h.entries.iter().enumerate() {
                for &(i, dof, v) in entries {
                    rhs[self.off[m] + dof] -= v * mu[i];
                }
            }
        }
    }

    /// x += R_c α.
    pub fn add_r_mul(&self, alpha: &[f64], x: &mut [f64]) {
        let (r, k) = self.kernel();
        let nd = self.ndof();
        for (j, &a) in alpha.iter().enumerate().take(k) {
            x.iter_mut().zip(&r[j * nd..(j + 1) * nd]).for_each(|(xi, ri)| *xi += a * ri);
        }
    }

    /// x_D ← g on every member's held DOFs.
    pub fn set_held(&self, x: &mut [f64]) {
        for (m, s) in self.subs.iter().enumerate() {
            s.set_held(&mut x[self.off[m]..self.off[m + 1]]);
        }
    }

    /// The members' K_free, block-diagonal over the cluster's DOFs.
    pub fn k_free(&self) -> std::borrow::Cow<'_, SymCsc> {
        if self.subs.len() == 1 {
            return self.subs[0].k_free();
        }
        let mut out = SymCsc { n: self.ndof(), col_ptr: vec![0], row_idx: vec![], values: vec![] };
        for (s, &o) in self.subs.iter().zip(&self.off) {
            let k = s.k_free();
            for j in 0..k.n {
                for p in k.col_ptr[j]..k.col_ptr[j + 1] {
                    out.row_idx.push(o + k.row_idx[p]);
                    out.values.push(k.values[p]);
                }
                out.col_ptr.push(out.row_idx.len());
            }
        }
        std::borrow::Cow::Owned(out)
    }
}

impl Hybrid {
    fn new(index: usize, subs: &[SubdomainSystem], entries: CornerEntries, nc: usize) -> Result<Self> {
        let members: Vec<(&[f64], usize, usize)> = subs.iter().map(|s| (s.r.as_slice(), s.kdim, s.ndof())).collect();
        let (g, roff, n, k) = kernel_basis(&members, &entries, nc);
        let r = expand(&members, &n, k);
        let sk = *roff.last().unwrap();
        // K_s⁺ B_c,sᵀ on each member's corner columns
        let mut cols = Vec::with_capacity(subs.len());
        let mut z = Vec::with_capacity(subs.len());
        for (s, ent) in subs.iter().zip(&entries) {
            let mut c: Vec<usize> = ent.iter().map(|x| x.0).collect();
            c.sort_unstable();
            c.dedup();
            let nd = s.ndof();
            let mut zs = vec![0.0; nd * c.len()];
            for &(i, dof, v) in ent {
                let p = c.binary_search(&i).expect("listed");
                zs[p * nd + dof] += v;
            }
            s.pinv_many_in_place(&mut zs, c.len());
            cols.push(c);
            z.push(zs);
        }
        // F_c = B_c K⁺ B_cᵀ
        let mut fc = vec![0.0; nc * nc];
        for (((ent, c), zs), s) in entries.iter().zip(&cols).zip(&z).zip(subs) {
            let nd = s.ndof();
            for &(i, dof, v) in ent {
                for (p, &j) in c.iter().enumerate() {
                    fc[i * nc + j] += v * zs[p * nd + dof];
                }
            }
        }
        let fmax = fc.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let gmax = g.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let t = if fmax > 0.0 && gmax > 0.0 { fmax / gmax } else { 1.0 };
        let diag = if fmax > 0.0 { fmax } else { 1.0 };
        let n2 = nc + sk;
        let a = faer::Mat::<f64>::from_fn(n2, n2, |i, j| match (i < nc, j < nc) {
            (true, true) => fc[i * nc + j],
            (true, false) => -t * g[(j - nc) * nc + i],
            (false, true) => -t * g[(i - nc) * nc + j],
            (false, false) => diag * (0..k).map(|c| n[c * sk + i - nc] * n[c * sk + j - nc]).sum::<f64>(),
        });
        use faer::linalg::solvers::DenseSolveCore;
        let inv = a.full_piv_lu().inverse();
        let sinv: Vec<f64> = (0..n2 * n2).map(|p| inv[(p % n2, p / n2)]).collect();
        if sinv.iter().any(|v| !v.is_finite()) {
            return Err(Error::numerical(format!("cluster {index}"), "its corner problem is singular: the corner rows are redundant"));
        }
        Ok(Hybrid { r, k, nc, entries, cols, z, roff, t, sinv })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::feti::subdomain::tests::{lcg, norm};
    use crate::scene::OrderingKind;

    /// The seed at N = 6, 4 subdomains per body in one cluster per body (nothing eliminated): a
    /// cluster floats with six rigid motions (K_s R_c = 0 on every member, B_c R_c = 0, R_cᵀR_c =
    /// I), and u = K_c⁺x with its corner forces μ solves the corner problem — B_c u = 0,
    /// K_s u_s = x̃_s − B_c,sᵀμ on every member, x̃ = x − R_cR_cᵀx — and K_c⁺ is symmetric.
    #[test]
    fn a_cluster_floats_as_one_body_and_its_inverse_solves_the_corner_problem() {
        let (model, d, cons) = crate::feti::seed_fixture(6, 4);
        let cl = Clustering::new(&model.mesh, &d, &cons, 4).unwrap();
        assert_eq!(cl.members, vec![vec![0, 1, 2, 3], vec![4, 5, 6, 7]]);
        assert!(cl.bc.iter().all(|b| b.1 >= 6), "each cluster has corner rows: {:?}", cl.bc.iter().map(|b| b.1).collect::<Vec<_>>());
        // the outer rows are B's; the B_c rows are combinations w of them (Bᵀw = B_cᵀe_j),
        // orthonormal
        let outer = cl.outer(cons.clone());
        assert_eq!((outer.c.len(), outer.rows.iter().map(Vec::len).sum::<usize>()), (cons.c.len(), cons.rows.iter().map(Vec::len).sum::<usize>()));
        assert_eq!(cl.null.len(), cl.corner_rows());
        let dense = |w: &[(usize, f64)]| {
            let mut v = vec![0.0; cons.layout.dim()];
            w.iter().for_each(|&(r, x)| v[r] = x);
            v
        };
        for (i, wi) in cl.null.iter().enumerate() {
            for (j, wj) in cl.null.iter().enumerate() {
                let dot: f64 = dense(wi).iter().zip(dense(wj)).map(|(a, b)| a * b).sum();
                assert!((dot - f64::from(u8::from(i == j))).abs() < 1e-12);
            }
        }
        // Bᵀw_j = B_cᵀe_j (the clusters' subdomains are contiguous here: W in the order of the
        // clusters' corner rows)
        let mut j = 0;
        for (c, (lists, nc)) in cl.bc.iter().enumerate() {
            for row in 0..*nc {
                let w = dense(&cl.null[j]);
                for (m, &s) in cl.members[c].iter().enumerate() {
                    let mut btw = vec![0.0; 3 * d.subdomains[s].nodes.len()];
                    cons.rows[s].iter().for_each(|&(r, dof, v)| btw[dof] += v * w[r]);
                    lists[m].iter().filter(|x| x.0 == row).for_each(|&(_, dof, v)| btw[dof] -= v);
                    assert!(norm(&btw) < 1e-12, "cluster {c}, corner row {row}, member {m}");
                }
                j += 1;
            }
        }
        let kernels = cl.kernels(&model.mesh, &d, &vec![vec![]; d.subdomains.len()]);
        let mut seed = 3u64;
        for (c, (r, k)) in kernels.iter().enumerate() {
            assert_eq!(*k, NR, "cluster {c}");
            let subs: Vec<SubdomainSystem> = cl.members[c]
                .iter()
                .map(|&s| {
                    let sd = &d.subdomains[s];
                    SubdomainSystem::new(&model.mesh, sd, s, model.lame[sd.body], OrderingKind::Metis, vec![0.0; 3 * sd.nodes.len()], vec![], vec![]).unwrap()
                })
                .collect();
            let sys = ClusterSystem::new(c, subs, cl.bc[c].0.clone(), cl.bc[c].1).unwrap();
            let nd = sys.ndof();
            assert_eq!(sys.kernel(), (r.as_slice(), NR), "the same R_c on every rank");
            let bc_mul = |u: &[f64]| {
                let mut out = vec![0.0; cl.bc[c].1];
                for (m, entries) in cl.bc[c].0.iter().enumerate() {
                    entries.iter().for_each(|&(i, dof, v)| out[i] += v * u[sys.off[m] + dof]);
                }
                out
            };
            let kmax = sys.subs.iter().flat_map(|s| s.k.values.iter()).fold(0.0f64, |a, v| a.max(v.abs()));
            for j in 0..NR {
                let col = &r[j * nd..(j + 1) * nd];
                for i in 0..NR {
                    let dot: f64 = col.iter().zip(&r[i * nd..(i + 1) * nd]).map(|(a, b)| a * b).sum();
                    assert!((dot - f64::from(u8::from(i == j))).abs() < 1e-12);
                }
                assert!(norm(&bc_mul(col)) < 1e-12, "B_c r_{j}");
                for (m, s) in sys.subs.iter().enumerate() {
                    assert!(norm(&s.k.mul(sys.part(col, m))) < 1e-10 * kmax, "K_s r_{j} on member {m}");
                }
            }
            let rand = |seed: &mut u64| (0..nd).map(|_| lcg(seed)).collect::<Vec<f64>>();
            let (x, y) = (rand(&mut seed), rand(&mut seed));
            let mut u = x.clone();
            let mu = sys.pinv_corners(&mut u);
            assert!(norm(&bc_mul(&u)) < 1e-10 * norm(&u), "B_c u = {:.2e}", norm(&bc_mul(&u)));
            let mut xt = x.clone();
            for j in 0..NR {
                let col = &r[j * nd..(j + 1) * nd];
                let g: f64 = col.iter().zip(&x).map(|(a, b)| a * b).sum();
                xt.iter_mut().zip(col).for_each(|(a, b)| *a -= g * b);
            }
            sys.sub_corner_forces(&mu, &mut xt);
            for (m, s) in sys.subs.iter().enumerate() {
                let ku = s.k.mul(sys.part(&u, m));
                let res: Vec<f64> = ku.iter().zip(sys.part(&xt, m)).map(|(a, b)| a - b).collect();
                assert!(norm(&res) < 1e-9 * norm(sys.part(&xt, m)), "member {m}: ‖K u − x̃ + B_cᵀμ‖ = {:.2e}", norm(&res));
            }
            let mut v = y.clone();
            sys.pinv_in_place(&mut v);
            let (xv, yu): (f64, f64) = (x.iter().zip(&v).map(|(a, b)| a * b).sum(), y.iter().zip(&u).map(|(a, b)| a * b).sum());
            assert!((xv - yu).abs() < 1e-10 * xv.abs().max(yu.abs()), "xᵀK⁺y = {xv:e}, yᵀK⁺x = {yu:e}");
        }
    }

    /// One subdomain per cluster is TFETI: no corners, the subdomain's own kernel.
    #[test]
    fn clusters_of_one_are_the_subdomains() {
        let (model, d, cons) = crate::feti::seed_fixture(5, 3);
        let cl = Clustering::new(&model.mesh, &d, &cons, 1).unwrap();
        assert_eq!(cl.len(), d.subdomains.len());
        assert!((0..cl.len()).all(|c| cl.is_single(c)));
        let outer = cl.outer(cons.clone());
        assert_eq!(outer.rows, cons.rows);
        // clusters of 2 and 3 of the 3 subdomains per body: every subdomain in one cluster of its body
        for per in [2, 3] {
            let cl = Clustering::new(&model.mesh, &d, &cons, per).unwrap();
            let mut seen = vec![0; d.subdomains.len()];
            for m in &cl.members {
                assert!(m.iter().all(|&s| d.subdomains[s].body == d.subdomains[m[0]].body));
                m.iter().for_each(|&s| seen[s] += 1);
            }
            assert!(seen.iter().all(|&k| k == 1));
            assert_eq!(cl.len(), 2 * 3usize.div_ceil(per));
        }
    }
}
