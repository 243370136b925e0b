//! The TFETI constraint rows B = [B_I; B_E] and their right-hand side c, per subdomain.
//!
//! Multipliers are ordered as in [`Layout`]: the contact rows B_I first (λν, then λτ when there
//! is friction), then λ_E: for every mesh node in ascending order and every component, either
//! its Dirichlet rows or its gluing rows.
//!
//! - **B_I** (contact): the rows N and T of each pair, acting on the *first* copy of each node
//!   of the pair's coupling (slave and master nodes; the other copies follow by gluing);
//!   c = gap for the normal rows.
//!   A prescribed DOF's part of a contact row moves to c (c −= coefficient·value, as on the
//!   monolithic dual) and leaves a zero entry: otherwise a contact row on held DOFs repeats
//!   Dirichlet rows (a tangent along a roller face: B loses rank, F turns singular there).
//! - **Dirichlet**: a prescribed DOF gets one row e_dof on *every* copy of its node (c = the
//!   value) and no gluing rows: each copy is held directly, the rows are orthonormal and
//!   non-redundant. A copy whose subdomain eliminates the DOF (hybrid, [`super::eliminated`])
//!   gets no row: it is held inside K_s.
//! - **Gluing** of a free DOF with k > 1 copies: k − 1 rows. [`Gluing::Orthonormal`] (default)
//!   takes the Helmert basis of the complement of (1, …, 1) — row j = (1, …, 1, −j, 0, …)/√(j(j+1))
//!   on copies 0..=j — so B_E B_Eᵀ = I (non-redundant, orthonormal: B_E adds nothing to the
//!   conditioning of F and C = G_E G_Eᵀ is as well scaled as R). [`Gluing::Chain`] takes the
//!   plain ±1 rows between consecutive copies (non-redundant, not orthogonal at cross points),
//!   kept for comparison. Redundant gluing (all pairs of copies) is not offered: B_E would be
//!   rank-deficient and F singular on Ker B_Eᵀ.
//! - **Ties** (`[[tie]]`): per row of the mortar (or node-to-node) coupling and component,
//!   Σ c·u_node,k = 0 on the first copy of each node, after the gluing and Dirichlet rows.

use crate::contact::pairing::{Contact, Tied};
use crate::feti::decomposition::Decomposition;
use crate::qp::Layout;
use crate::scene::Gluing;

/// B and c: one entry list per subdomain.
#[derive(Clone, Debug)]
pub struct Constraints {
    pub layout: Layout,
    /// c, one value per multiplier.
    pub c: Vec<f64>,
    /// How c depends on the prescribed values (entries of the `dirichlet` list), what a load
    /// step (new values, the same DOFs) needs to give its c without rebuilding B: a contact row
    /// starts from `gap` and loses coef · value for each (row, entry, coef) of `c_moved`, in
    /// order; a Dirichlet row is the value of its entry (`c_held`: row, entry); the others 0.
    pub gap: Vec<f64>,
    pub c_moved: Vec<(usize, usize, f64)>,
    pub c_held: Vec<(usize, usize)>,
    /// Per subdomain: (row, local DOF 3·l + comp, coefficient).
    pub rows: Vec<Vec<(usize, usize, f64)>>,
    pub gluing_rows: usize,
    pub dirichlet_rows: usize,
    /// Rows of tied interfaces (`[[tie]]`), after the gluing and Dirichlet rows.
    pub tie_rows: usize,
}

impl Constraints {
    /// Index of the first λ_E row.
    pub fn e_start(&self) -> usize {
        self.layout.contact_dim()
    }

    /// The multipliers whose rows touch subdomain `s`, ascending.
    pub fn sorted_rows(&self, s: usize) -> Vec<usize> {
        let mut rows: Vec<usize> = self.rows[s].iter().map(|x| x.0).collect();
        rows.sort_unstable();
        rows.dedup();
        rows
    }
}

/// One entry `coef` of `row` on local DOF `dof` of a subdomain (`rows`), for DOF (node, k): a
/// prescribed DOF's part moves to c (c −= coef · value, recorded in `moved`) and the entry stays
/// with coefficient 0, so the row keeps its subdomains.
fn put(
    rows: &mut Vec<(usize, usize, f64)>,
    c: &mut [f64],
    moved: &mut Vec<(usize, usize, f64)>,
    prescribed: &std::collections::HashMap<(usize, usize), (f64, usize)>,
    (row, dof): (usize, usize),
    at: (usize, usize),
    coef: f64,
) {
    match prescribed.get(&at) {
        Some(&(val, entry)) => {
            c[row] -= coef * val;
            moved.push((row, entry, coef));
            rows.push((row, dof, 0.0));
        }
        None => rows.push((row, dof, coef)),
    }
}

/// Builds B and c for the decomposition `d`; `dirichlet` lists (node, component, value), a
/// later entry for the same DOF winning; `contact` the pairs (if contact is on); `eliminated`
/// per subdomain the local DOFs held inside it (sorted; empty: all Dirichlet rows).
pub fn build(
    d: &Decomposition,
    dirichlet: &[(usize, usize, f64)],
    contact: Option<&Contact>,
    ties: &Tied,
    gluing: Gluing,
    eliminated: &[Vec<usize>],
) -> Constraints {
    let (m, friction) = contact.map_or((0, false), |c| (c.len(), c.has_friction()));
    let mut layout = Layout::contact(m, friction);
    let mut rows = vec![Vec::new(); d.subdomains.len()];
    let mut c = vec![0.0; layout.contact_dim()];
    let mut prescribed = std::collections::HashMap::new();
    for (entry, &(v, k, val)) in dirichlet.iter().enumerate() {
        prescribed.insert((v, k), (val, entry));
    }
    let (mut c_moved, mut c_held) = (Vec::new(), Vec::new());
    if let Some(ct) = contact {
        (0..m).for_each(|i| c[layout.normal(i)] = ct.gap[i]);
    }
    let gap = c.clone();
    if let Some(ct) = contact {
        let first = |v: usize| d.copies[v][0];
        for i in 0..m {
            let pair_rows = std::iter::once((layout.normal(i), ct.normal[i]))
                .chain(friction.then(|| [(layout.tangent(i, 0), ct.t1[i]), (layout.tangent(i, 1), ct.t2[i])]).into_iter().flatten());
            for (r, (row, dir)) in pair_rows.enumerate() {
                // a void tangential row keeps its entries at 0 (its subdomains) and c = 0
                let void = r > 0 && ct.is_void(i, r - 1);
                for &(node, sign) in ct.row(i) {
                    let (s, l) = first(node);
                    for k in 0..3 {
                        if dir[k] != 0.0 {
                            // a prescribed DOF's part moves to c (as on the monolithic dual); the
                            // entry stays with coefficient 0 so the row keeps its subdomains
                            let coef = sign * dir[k];
                            if void {
                                rows[s].push((row, 3 * l + k, 0.0));
                                continue;
                            }
                            put(&mut rows[s], &mut c, &mut c_moved, &prescribed, (row, 3 * l + k), (node, k), coef);
                        }
                    }
                }
            }
        }
    }
    let (mut gluing_rows, mut dirichlet_rows) = (0, 0);
    for (v, copies) in d.copies.iter().enumerate() {
        for k in 0..3 {
            if let Some(&(val, entry)) = prescribed.get(&(v, k)) {
                for &(s, l) in copies {
                    if eliminated.get(s).is_some_and(|e| e.binary_search(&(3 * l + k)).is_ok()) {
                        continue;
                    }
                    rows[s].push((c.len(), 3 * l + k, 1.0));
                    c_held.push((c.len(), entry));
                    c.push(val);
                    dirichlet_rows += 1;
                }
                continue;
            }
            for j in 1..copies.len() {
                let row = c.len();
                match gluing {
                    Gluing::Orthonormal => {
                        let h = 1.0 / ((j * (j + 1)) as f64).sqrt();
                        for &(s, l) in &copies[..j] {
                            rows[s].push((row, 3 * l + k, h));
                        }
                        let (s, l) = copies[j];
                        rows[s].push((row, 3 * l + k, -(j as f64) * h));
                    }
                    Gluing::Chain => {
                        let ((s0, l0), (s1, l1)) = (copies[j - 1], copies[j]);
                        rows[s0].push((row, 3 * l0 + k, 1.0));
                        rows[s1].push((row, 3 * l1 + k, -1.0));
                    }
                }
                c.push(0.0);
                gluing_rows += 1;
            }
        }
    }
    // tied interfaces: Σ c·u_node,k = 0 per row and component, on the first copy of each node
    // (a prescribed DOF's part moves to c, as for contact rows); a row with no free DOF left
    // holds nothing and is left out, and so is the component a Dirichlet condition prescribes at
    // the row's slave node: the multiplier space has no function where the slave trace is held
    // (the mortar's Dirichlet boundary), and such rows repeat the Dirichlet rows through the
    // master's held nodes (a quadratic slave edge's 7 rows against a linear master's 5 free
    // nodes left B without full row rank)
    let mut tie_rows = 0;
    for (coupling, &slave) in ties.coupling.iter().zip(&ties.slave) {
        for k in 0..3 {
            if prescribed.contains_key(&(slave, k)) || coupling.iter().all(|&(v, _)| prescribed.contains_key(&(v, k))) {
                continue;
            }
            let row = c.len();
            c.push(0.0);
            for &(node, coef) in coupling {
                let (s, l) = d.copies[node][0];
                put(&mut rows[s], &mut c, &mut c_moved, &prescribed, (row, 3 * l + k), (node, k), coef);
            }
            tie_rows += 1;
        }
    }
    layout.free = gluing_rows + dirichlet_rows + tie_rows;
    Constraints { layout, c, gap, c_moved, c_held, rows, gluing_rows, dirichlet_rows, tie_rows }
}

/// c on this rank's rows at other prescribed values: [`Constraints`]' record of how c depends
/// on them, kept for the local rows of a [`super::distribution::Distribution`].
#[derive(Clone, Debug, Default)]
pub struct LocalRhs {
    /// c on the local rows before the prescribed values: the gaps, 0 elsewhere.
    base: Vec<f64>,
    /// (local row, entry, coefficient) and (local row, entry), in the constraints' order.
    moved: Vec<(usize, usize, f64)>,
    held: Vec<(usize, usize)>,
}

impl LocalRhs {
    /// The part of `cons` on the global rows `rows` (ascending: the local rows, in order).
    pub fn new(cons: &Constraints, rows: &[usize]) -> Self {
        let local = |r: usize| rows.binary_search(&r).ok();
        LocalRhs {
            base: rows.iter().map(|&r| cons.gap.get(r).copied().unwrap_or(0.0)).collect(),
            moved: cons.c_moved.iter().filter_map(|&(r, e, x)| local(r).map(|i| (i, e, x))).collect(),
            held: cons.c_held.iter().filter_map(|&(r, e)| local(r).map(|i| (i, e))).collect(),
        }
    }

    /// c on the local rows for the prescribed values `values` (one per entry of the list the
    /// constraints were built with), computed as [`build`] computes it.
    pub fn at(&self, values: &[f64]) -> Vec<f64> {
        let mut c = self.base.clone();
        for &(i, e, coef) in &self.moved {
            c[i] -= coef * values[e];
        }
        for &(i, e) in &self.held {
            c[i] = values[e];
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::feti::decomposition::decompose;
    use crate::mesh::{boxgen, Mesh};

    #[test]
    fn orthonormal_gluing_rows_and_one_dirichlet_row_per_copy() {
        let mut mesh = Mesh::default();
        mesh.push_body("b", boxgen::generate([0.0; 3], [1.0; 3], [5, 5, 5]));
        let d = decompose(&mesh, 4).unwrap();
        let dirichlet: Vec<_> = (0..5).map(|v| (v, 2, 0.5)).collect();
        for gluing in [Gluing::Orthonormal, Gluing::Chain] {
            let c = build(&d, &dirichlet, None, &Tied::default(), gluing, &[]);
            assert_eq!(c.layout.dim(), c.c.len());
            let n = c.layout.dim();
            // B Bᵀ as a dense matrix
            let mut bbt = vec![0.0; n * n];
            let mut by_dof: std::collections::HashMap<(usize, usize), Vec<(usize, f64)>> = Default::default();
            for (s, r) in c.rows.iter().enumerate() {
                for &(row, dof, v) in r {
                    by_dof.entry((s, dof)).or_default().push((row, v));
                }
            }
            for col in by_dof.values() {
                for &(a, x) in col {
                    for &(b, y) in col {
                        bbt[a * n + b] += x * y;
                    }
                }
            }
            let copies = |v: usize| d.copies[v].len();
            let held = |v: usize, k: usize| dirichlet.iter().any(|&(w, kk, _)| w == v && kk == k);
            let glue: usize = (0..mesh.nodes.len()).map(|v| (0..3).filter(|&k| !held(v, k)).count() * (copies(v) - 1)).sum();
            assert!(glue > 0);
            assert_eq!(c.gluing_rows, glue);
            assert_eq!(c.dirichlet_rows, dirichlet.iter().map(|&(v, _, _)| copies(v)).sum::<usize>());
            assert_eq!(c.gluing_rows + c.dirichlet_rows, n);
            if gluing == Gluing::Orthonormal {
                for a in 0..n {
                    for b in 0..n {
                        assert!((bbt[a * n + b] - if a == b { 1.0 } else { 0.0 }).abs() < 1e-14);
                    }
                }
            }
            // Dirichlet rows carry their value, gluing rows 0
            assert_eq!(c.c.iter().filter(|&&x| x == 0.5).count(), c.dirichlet_rows);
        }
    }
    /// A load step's c from the record of the prescribed values equals c built anew at those
    /// values, bit for bit, on any set of rows: contact rows with prescribed DOFs (the seed's
    /// clamped faces touch the contact face), Dirichlet rows, gluing rows.
    #[test]
    fn local_rhs_gives_the_c_of_other_prescribed_values() {
        let (model, d, cons) = crate::feti::seed_fixture(5, 3);
        assert!(!cons.c_moved.is_empty() && !cons.c_held.is_empty());
        let values: Vec<f64> = (0..model.constraints.len()).map(|i| 1e-3 * ((i * 7919 % 23) as f64 - 11.0)).collect();
        let moved: Vec<(usize, usize, f64)> = model.constraints.iter().zip(&values).map(|(&(v, k, _), &x)| (v, k, x)).collect();
        let again = build(&d, &moved, model.pairs.as_ref(), &model.ties, Gluing::Orthonormal, &[]);
        assert_ne!(again.c, cons.c, "the values move c");
        for rows in [(0..cons.c.len()).collect::<Vec<_>>(), (0..cons.c.len()).step_by(3).collect()] {
            let local = LocalRhs::new(&cons, &rows);
            let want: Vec<u64> = rows.iter().map(|&r| again.c[r].to_bits()).collect();
            assert_eq!(local.at(&values).iter().map(|x| x.to_bits()).collect::<Vec<_>>(), want);
            let at_model: Vec<f64> = model.constraints.iter().map(|c| c.2).collect();
            assert_eq!(local.at(&at_model), rows.iter().map(|&r| cons.c[r]).collect::<Vec<_>>());
        }
    }
}
