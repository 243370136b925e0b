//! Assembly of the mortar rows: the R*-tree search, the overlap of each (slave facet, master
//! facet) pair on the slave's plane, the integration of D and M over the clip polygons, the
//! per-node accumulation, and the coverage rule, normalization, edge trimming and weighted and
//! geometric gaps that turn the accumulated nodes into [`MortarRows`].

use std::collections::BTreeMap;
use std::time::Instant;

use rstar::primitives::{GeomWithData, Rectangle};
use rstar::RTree;

use super::clip::{clip_polygon, cross2, dedup, polygon_area, sub2};
use super::dual_basis::{add_outer, add_scaled, is_modified, SlaveFacet};
use super::{Facet, Mat, MortarError, MortarInfo, MortarParams, MortarRows, Plane, SurfaceFacet, ALPHA, FULL_COVER, PRUNE_FRACTION, SLIVER_FRACTION, V2, V3};
use crate::fem::facet::{axpy, cross, dot, dunavant7, edges, is_tri, norm, scale, shape, sub, MAX_NODES};
use crate::mesh::FacetKind;

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
        for &(e, a, b) in edges(s.f.kind).iter().filter(|_| is_modified(s.f.kind)) {
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
        let (ps, _) = s.f.map(&shape(s.f.kind, xs));
        let (pm, _) = m.map(&shape(m.kind, xm));
        g = g.min(dot(sub(pm, ps), s.plane.n).abs());
    }
    Ok(g)
}

/// Gauss points (plane point, plane weight) of a clip polygon: fan triangles from the
/// vertex centroid, the 7-point rule on each.
pub(super) fn fan_points(poly: &[V2]) -> Vec<(V2, f64)> {
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
        let ss = shape(s.f.kind, xs);
        let psi = s.psi(a, &ss);
        let sm = shape(m.kind, xm);
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
    let inside = |k: FacetKind, xi: V2| {
        let m = 1e-9;
        if is_tri(k) {
            xi[0] >= -m && xi[1] >= -m && xi[0] + xi[1] <= 1.0 + m
        } else {
            xi[0].abs() <= 1.0 + m && xi[1].abs() <= 1.0 + m
        }
    };
    let mut best = f64::NAN;
    for m in masters {
        let Some(xi) = plane.invert(m, [0.0, 0.0]).filter(|&xi| inside(m.kind, xi)) else { continue };
        let (xm, _) = m.map(&shape(m.kind, xi));
        let g = dot(sub(xm, x), n);
        if best.is_nan() || g.abs() < best.abs() {
            best = g;
        }
    }
    best
}
