//! Unit tests of the mortar rows: the dual basis (tri3, warped quad4, quadratic), matching and
//! non-matching patches (linear gap reproduction, rotations), row norms, curved surfaces, the
//! search and coverage rules, and partly covered facets.

use super::dual_basis::{add_outer, dual_coefficients, mat_vec, transformation, SlaveFacet};
use super::*;
use crate::fem::facet::{fine_rule, shape};
use std::collections::BTreeMap;

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
    for (xi, w) in fine_rule(s.f.kind) {
        let sh = shape(s.f.kind, xi);
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
        let t = transformation(s.f.kind);
        let mut g = [[0.0; MAX_NODES]; MAX_NODES];
        for (xi, w) in fine_rule(s.f.kind) {
            let sh = shape(s.f.kind, xi);
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

/// [`patch2`]'s quad8 patch with each cell's centre as a ninth node (quad9).
fn patch9(coords: &mut Vec<V3>, nx: usize, ny: usize, up: bool, map: &dyn Fn(f64, f64) -> V3) -> Patch {
    let mut p = patch2(coords, nx, ny, false, up, map);
    // the centre lies midway in the lattice between the facet's edge nodes 4 and 6
    for f in &mut p.facets {
        let c = (f[4] + f[6]) / 2;
        f.push(c);
    }
    let ids = p.facets.iter().flatten().copied().collect::<std::collections::BTreeSet<_>>();
    Patch { ids: ids.into_iter().collect(), facets: p.facets }
}

/// quad9 keeps the standard dual basis (T = I): D = ∫ φᵢ dA, 1/36 of the area at the corners,
/// 1/9 at the edge nodes, 4/9 at the centre, and ∫ ψᵢ φ_k dA = δ_ik D_kk on a parallelogram.
#[test]
fn quad9_standard_dual_basis() {
    let mut coords = Vec::new();
    let p = patch9(&mut coords, 1, 1, true, &|u, v| [2.0 * u + 0.3 * v, 1.5 * v, 0.1 * u]);
    let f = Facet::new(&SurfaceFacet { nodes: &p.facets[0] }, &coords, "slave", 0).unwrap();
    let s = SlaveFacet::new(f, 0).unwrap();
    let (n, area) = (s.f.n(), s.f.area());
    assert_eq!(n, 9);
    let t = transformation(s.f.kind);
    for (i, row) in t.iter().enumerate().take(n) {
        for (k, tik) in row.iter().enumerate().take(n) {
            assert_eq!(*tik, if i == k { 1.0 } else { 0.0 });
        }
    }
    for k in 0..n {
        let want = [1.0 / 36.0, 1.0 / 9.0, 4.0 / 9.0][usize::from(k >= 4) + usize::from(k == 8)];
        assert!((s.d[k] / area - want).abs() < 1e-14, "D_{k}/A = {}", s.d[k] / area);
    }
    let mut g = [[0.0; MAX_NODES]; MAX_NODES];
    for (xi, w) in fine_rule(s.f.kind) {
        let sh = shape(s.f.kind, xi);
        let (psi, wj) = (s.psi(&s.a, &sh), w * norm(s.f.jacobian(xi)));
        add_outer(&mut g, wj, &psi[..n], &sh.phi[..n]);
    }
    for (i, row) in g.iter().enumerate().take(n) {
        for (k, gik) in row.iter().enumerate().take(n) {
            let want = if i == k { s.d[k] } else { 0.0 };
            assert!((gik - want).abs() < 1e-13, "∫ψ{i}φ{k} = {gik}");
        }
    }
}

/// ∫ φ_j dA of every node of a patch, by the facets' fine rule.
fn primal_areas(coords: &[V3], p: &Patch) -> BTreeMap<usize, f64> {
    let mut out = BTreeMap::new();
    for (k, nodes) in p.facets.iter().enumerate() {
        let f = Facet::new(&SurfaceFacet { nodes }, coords, "master", k).unwrap();
        for (xi, w) in fine_rule(f.kind) {
            let sh = shape(f.kind, xi);
            let wj = w * norm(f.jacobian(xi));
            for (a, &v) in nodes.iter().enumerate() {
                *out.entry(v).or_insert(0.0) += wj * sh.phi[a];
            }
        }
    }
    out
}

/// Non-matching quad9 faces: a 3 × 3 quad9 slave on a 4 × 4 quad9 master at z = f_lin and on a
/// wobbly quad4 master (7 × 7): every row is +1 at its slave node alone, its master part sums to
/// −1 and its gap is f_lin at the node. On a flat parallel 4 × 4 quad9 master (gap 0.01) the
/// uniform slave pressure 1 (λᵢ = D_ii) puts the force ∫ φ_j dA on every master node j: a
/// constant pressure is transferred exactly.
#[test]
fn quad9_faces_reproduce_linear_gap_and_transfer_a_constant_pressure() {
    for master in ["quad9", "quad4", "flat"] {
        let mut coords = Vec::new();
        let s = patch9(&mut coords, 3, 3, true, &flat(0.0));
        let m = match master {
            "quad9" => patch9(&mut coords, 4, 4, false, &|u, v| [u, v, f_lin(u, v)]),
            "quad4" => patch(&mut coords, 7, 7, false, false, &wobbly(0.2 / 7.0, f_lin)),
            _ => patch9(&mut coords, 4, 4, false, &flat(0.01)),
        };
        let rows = run(&coords, &s, &m, &params(0.05)).unwrap();
        assert_eq!(rows.len(), s.ids.len(), "{master}");
        let total: f64 = rows.area.iter().sum();
        assert!((total - 1.0).abs() < 1e-13, "{master}: Σ D_ii = {total}");
        let mut force: BTreeMap<usize, f64> = BTreeMap::new();
        for r in 0..rows.len() {
            let row = &rows.coupling[r];
            assert_eq!(row[0], (rows.node[r], 1.0), "{master}, row {r}");
            assert!(row[1..].iter().all(|(k, _)| !s.ids.contains(k)), "{master}, row {r}: a second slave node");
            let cm: f64 = row[1..].iter().map(|e| e.1).sum();
            assert!((cm + 1.0).abs() < 1e-12, "{master}, row {r}: master part {cm}");
            let x = coords[rows.node[r]];
            let want = if master == "flat" { 0.01 } else { f_lin(x[0], x[1]) };
            assert!((rows.gap[r] - want).abs() < 1e-12, "{master}, row {r} at {x:?}: gap {}", rows.gap[r]);
            for &(k, c) in &row[1..] {
                *force.entry(k).or_insert(0.0) -= rows.area[r] * c;
            }
        }
        if master == "flat" {
            for (j, a) in primal_areas(&coords, &m) {
                let f = force.get(&j).copied().unwrap_or(0.0);
                assert!((f - a).abs() < 1e-13, "master node {j} at {:?}: force {f}, ∫φ dA {a}", coords[j]);
            }
        }
    }
}
