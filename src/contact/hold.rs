//! Whether contact and friction can hold the bodies held by contact alone: before any solve, the
//! equilibrium of their free rigid motions R_f asks for multipliers λ ∈ Λ (λν ≥ 0, the Tresca
//! disc or ellipse, the Coulomb cone) with
//!
//! ```text
//! G_f λ = e_f,   G_f = (B R_f)ᵀ,  e_f = R_fᵀ f,
//! ```
//!
//! the rows of G = RᵀBᵀ that TFETI keeps for such a body. Where no such λ exists the problem
//! has no solution (the body would slide or spin away). One second-order cone problem
//! (Clarabel) decides it: the distance min_{λ ∈ Λ} ‖e_f − G_f λ‖ from the load to what the
//! contact can supply. Where it is not 0, e_f − G_f λ* is the unbalanced part of the load and
//! its direction d the motion it drives; the error names the natural motion (a translation or
//! a rotation about an axis) that carries most of it, the load's component along it, and the
//! limit: the largest load along that motion, the other components as applied, for which a
//! λ ∈ Λ exists (a second cone program).

use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SecondOrderConeT, SolverStatus, SupportedConeT, ZeroConeT};

use super::pairing::{Contact, SlipBound};
use crate::error::{Error, Result};
use crate::mesh::{rigid, Mesh};
use crate::qp::cone::Coefficient;

/// A body held by contact alone, or a group of bodies tied together (`[[tie]]`) that is: its
/// bodies and an orthonormal basis of the rigid motions of the group as one that its Dirichlet
/// conditions leave free ([`rigid::free_modes`]).
pub struct FreeBody {
    pub bodies: Vec<usize>,
    pub modes: Vec<[f64; 6]>,
}

/// What the contact cannot hold: the body (or tied group), the motion, and along the natural
/// motion `natural` (0–2: translation along x, y, z; 3–5: rotation about them) that carries most
/// of the unbalanced load, the applied load (a force, or a moment about the centroid) and the
/// most contact and friction can carry along it with the load's other components as applied
/// (μN for a frictional hold; None: they cannot hold those components either).
#[derive(Clone, Debug, PartialEq)]
pub struct Unheld {
    pub bodies: Vec<usize>,
    pub motion: String,
    pub natural: usize,
    pub load: f64,
    pub supply: Option<f64>,
}

impl Unheld {
    /// The one-line reason, naming the body or the tied group.
    pub fn error(&self, mesh: &Mesh, step: Option<(usize, usize)>) -> Error {
        let at = step.map_or(String::new(), |(k, n)| format!(" at load step {k}/{n}"));
        let load = self.load;
        let axis = ["x", "y", "z"][self.natural % 3];
        let what = if self.natural < 3 { format!("force along {axis}") } else { format!("moment about {axis} (through the centroid)") };
        let carry = match self.supply.map(|h| h.max(0.0)) {
            Some(held) if held > 0.0 => {
                format!("with its other components as applied, contact and friction hold at most {held:.4e} along it, {:.3e} less", load - held)
            }
            Some(_) => "contact and friction hold none of it".into(),
            None => "contact and friction cannot hold its other components either".into(),
        };
        Error::numerical(
            group_name(mesh, &self.bodies),
            format!(
                "no equilibrium exists{at}: along the motion the load drives ({}) the applied {what} is {load:.4e}; {carry}; held by contact alone, {} would slide away",
                self.motion,
                if self.bodies.len() > 1 { "the group" } else { "the body" }
            ),
        )
    }
}

/// `body "a"`, or `bodies "a", "b" (tied)` for a group.
pub fn group_name(mesh: &Mesh, bodies: &[usize]) -> String {
    let names: Vec<String> = bodies.iter().map(|&b| format!("\"{}\"", mesh.bodies[b].name)).collect();
    if names.len() == 1 {
        format!("body {}", names[0])
    } else {
        format!("bodies {} (tied)", names.join(", "))
    }
}

/// The equilibrium rows of the free bodies' motions: G_f (column per multiplier), e_f, and each
/// row's body and mode.
struct Rows {
    g: Vec<Vec<(usize, f64)>>,
    e: Vec<f64>,
    owner: Vec<(Vec<usize>, [f64; 6])>,
}

/// Checks that λ ∈ Λ with G_f λ = e_f exists for the `free` bodies of `mesh` under `loads`
/// (3 per node). Ok(None): it does (or the check could not decide); Ok(Some): what cannot be held.
pub fn check(mesh: &Mesh, contact: &Contact, free: &[FreeBody], loads: &[f64]) -> Result<Option<Unheld>> {
    let friction = contact.has_friction();
    let per = if friction { 3 } else { 1 };
    // the pairs touching a free body, and their multipliers' columns
    let touches = |v: usize| free.iter().any(|fb| fb.bodies.iter().any(|&b| mesh.bodies[b].nodes.contains(&v)));
    let pairs: Vec<usize> = (0..contact.len()).filter(|&i| contact.row(i).iter().any(|&(v, _)| touches(v))).collect();
    let n = per * pairs.len();
    let mut rows = Rows { g: vec![], e: vec![], owner: vec![] };
    for fb in free {
        let frame = rigid::Frame::of(mesh, &fb.bodies);
        let inside = |v: usize| fb.bodies.iter().any(|&b| mesh.bodies[b].nodes.contains(&v));
        for m in &fb.modes {
            let at = |x: [f64; 3], dir: [f64; 3]| frame.row(x, dir).iter().zip(m).map(|(a, b)| a * b).sum::<f64>();
            let mut e = 0.0;
            for v in fb.bodies.iter().flat_map(|&b| mesh.bodies[b].nodes.clone()) {
                for d in 0..3 {
                    let mut dir = [0.0; 3];
                    dir[d] = 1.0;
                    e += loads[3 * v + d] * at(mesh.nodes[v], dir);
                }
            }
            let mut g = Vec::new();
            for (c, &i) in pairs.iter().enumerate() {
                let dirs = [contact.normal[i], contact.t1[i], contact.t2[i]];
                for (k, &dir) in dirs.iter().take(per).enumerate() {
                    // (B r)ᵢ = Σ c·r(node)·dir over the row's nodes (node-to-node: slave − master)
                    let mut x = 0.0;
                    for &(v, coef) in contact.row(i) {
                        if inside(v) {
                            x += coef * at(mesh.nodes[v], dir);
                        }
                    }
                    if x != 0.0 {
                        g.push((per * c + k, x));
                    }
                }
            }
            rows.g.push(g);
            rows.e.push(e);
            rows.owner.push((fb.bodies.clone(), *m));
        }
    }
    let scale = rows.e.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if rows.e.is_empty() || scale == 0.0 || !scale.is_finite() {
        return Ok(None);
    }
    let e: Vec<f64> = rows.e.iter().map(|v| v / scale).collect();
    let cones = Cones::new(contact, &pairs, friction, scale);
    let Some(x) = nearest(&rows.g, &e, n, &cones) else { return Ok(None) };
    // the unbalanced part of the load, e − G λ*
    let gl: Vec<f64> = rows.g.iter().map(|row| row.iter().map(|&(j, v)| v * x[j]).sum()).collect();
    let d: Vec<f64> = e.iter().zip(&gl).map(|(a, b)| a - b).collect();
    let dist = d.iter().map(|v| v * v).sum::<f64>().sqrt();
    let enorm = e.iter().map(|v| v * v).sum::<f64>().sqrt();
    if !(dist > UNBALANCED * enorm) {
        return Ok(None);
    }
    // the body (or group) that moves most along d; its unbalanced, applied and carried
    // generalized forces in the natural modes (force; moment / size), r = e − Gλ*
    let mut share: Vec<Share> = Vec::new();
    for (j, (b, m)) in rows.owner.iter().enumerate() {
        let i = match share.iter().position(|s| s.0 == b.as_slice()) {
            Some(i) => i,
            None => {
                share.push((b, 0.0, [[0.0; 6]; 3]));
                share.len() - 1
            }
        };
        let s = &mut share[i];
        s.1 += d[j] * d[j];
        for (q, mq) in m.iter().enumerate() {
            s.2[0][q] += d[j] * mq;
            s.2[1][q] += e[j] * mq;
            s.2[2][q] += gl[j] * mq;
        }
    }
    let (bodies, _, [r, l, c]) = share.into_iter().fold((&[][..], -1.0, [[0.0; 6]; 3]), |a, s| if s.1 > a.1 { s } else { a });
    // along the natural motion that is the unbalanced part's largest (moments in force × length)
    let q = (0..6).fold(0, |a, q| if r[q].abs() > r[a].abs() { q } else { a });
    let unit = scale * if q < 3 { 1.0 } else { rigid::Frame::of(mesh, bodies).size };
    let sign = if l[q] != 0.0 { l[q].signum() } else { r[q].signum() };
    // the limit: the largest load along the driven motion, the other components as applied —
    // e + t u with u the natural motion's part in this body's rows
    let u: Vec<f64> = rows.owner.iter().map(|(b, m)| if b.as_slice() == bodies { sign * m[q] } else { 0.0 }).collect();
    let uu: f64 = u.iter().map(|v| v * v).sum();
    let limit = if uu > 0.0 { largest(&rows.g, &e, &u, n, &cones) } else { Limit::Unknown };
    let supply = match limit {
        Limit::At(t) => Some((sign * l[q] + t * uu) * unit),
        Limit::Nowhere => None,
        Limit::Unknown => Some(sign * c[q] * unit),
    };
    Ok(Some(Unheld { bodies: bodies.to_vec(), motion: rigid::dominant(&r), natural: q, load: sign * l[q] * unit, supply }))
}

/// The largest t with e + t u = G λ for some λ ∈ Λ.
enum Limit {
    At(f64),
    /// No t: the load's other components cannot be held either.
    Nowhere,
    /// Clarabel did not decide it.
    Unknown,
}

/// max t subject to G λ − t u = e, λ ∈ Λ (one second-order cone program).
fn largest(g: &[Vec<(usize, f64)>], e: &[f64], u: &[f64], n: usize, cones: &Cones) -> Limit {
    let mut rows = Vec::new();
    for (r, row) in g.iter().enumerate() {
        rows.extend(row.iter().map(|&(j, v)| (r, j, v)));
        if u[r] != 0.0 {
            rows.push((r, n, -u[r]));
        }
    }
    let mut q = vec![0.0; n + 1];
    q[n] = -1.0;
    match program(cones, &rows, e.to_vec(), ZeroConeT(g.len()), &q) {
        Some((SolverStatus::Solved | SolverStatus::AlmostSolved, x)) => Limit::At(x[n]),
        Some((SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible, _)) => Limit::Nowhere,
        _ => Limit::Unknown,
    }
}

/// min c·x over x = (λ, t) with λ ∈ Λ (`cones`: s = h − A x, rows first) and `rows` (relative
/// to the cones' rows, right-hand side `h`) in the cone `last`; P = 0. The status and x, or None
/// where Clarabel does not take the problem.
fn program(cones: &Cones, rows: &[(usize, usize, f64)], h: Vec<f64>, last: SupportedConeT<f64>, c: &[f64]) -> Option<(SolverStatus, Vec<f64>)> {
    let r0 = cones.h.len();
    let (mut ai, mut aj, mut av) = (vec![], vec![], vec![]);
    for (r, j, v) in cones.a.iter().copied().chain(rows.iter().map(|&(r, j, v)| (r0 + r, j, v))) {
        ai.push(r);
        aj.push(j);
        av.push(v);
    }
    let nvar = c.len();
    let a = CscMatrix::new_from_triplets(r0 + h.len(), nvar, ai, aj, av);
    let p = CscMatrix::new_from_triplets(nvar, nvar, vec![], vec![], vec![]);
    let h: Vec<f64> = cones.h.iter().copied().chain(h).collect();
    let mut kinds: Vec<SupportedConeT<f64>> = Vec::new();
    if cones.zero > 0 {
        kinds.push(ZeroConeT(cones.zero));
    }
    kinds.push(NonnegativeConeT(cones.nonneg));
    kinds.extend((0..cones.socs).map(|_| SecondOrderConeT(3)));
    kinds.push(last);
    let settings = DefaultSettings { verbose: false, max_iter: 200, max_threads: 1, ..DefaultSettings::default() };
    let mut solver = DefaultSolver::new(&p, c, &a, &h, &kinds, settings).ok()?;
    solver.solve();
    Some((solver.solution.status, solver.solution.x.clone()))
}

/// One body's (or group's) part of the unbalanced load: its bodies, Σ d², and its unbalanced,
/// applied and carried generalized forces in the natural modes.
type Share<'a> = (&'a [usize], f64, [[f64; 6]; 3]);

/// A load the contact cannot meet closer than this (relative to ‖e_f‖) cannot be held.
const UNBALANCED: f64 = 1e-6;

/// Λ of the pairs as Clarabel's cones: rows s = h − A x per cone, after the equality rows.
struct Cones {
    a: Vec<(usize, usize, f64)>,
    h: Vec<f64>,
    zero: usize,
    nonneg: usize,
    socs: usize,
}

impl Cones {
    fn new(contact: &Contact, pairs: &[usize], friction: bool, scale: f64) -> Self {
        let per = if friction { 3 } else { 1 };
        let mut c = Cones { a: vec![], h: vec![], zero: 0, nonneg: 0, socs: 0 };
        // λτ = 0 where a pair has no friction among frictional ones
        let none: Vec<usize> = pairs
            .iter()
            .enumerate()
            .filter(|&(_, &i)| friction && contact.bound[i] == SlipBound::None && contact.coulomb[i] == Coefficient::Fixed)
            .map(|(c, _)| c)
            .collect();
        for &p in &none {
            for k in 1..3 {
                c.a.push((c.h.len(), per * p + k, 1.0));
                c.h.push(0.0);
            }
        }
        c.zero = c.h.len();
        for p in 0..pairs.len() {
            c.a.push((c.h.len(), per * p, -1.0));
            c.h.push(0.0);
        }
        c.nonneg = pairs.len();
        if !friction {
            return c;
        }
        for (p, &i) in pairs.iter().enumerate() {
            let (nu, t1, t2) = (per * p, per * p + 1, per * p + 2);
            let r = c.h.len();
            // s = (s₀, s₁, s₂) ∈ SOC: s₀ ≥ ‖(s₁, s₂)‖
            let (head, a1, a2): (Vec<(usize, f64)>, f64, f64);
            let mut h0 = 0.0;
            match (contact.coulomb[i], contact.bound[i]) {
                (Coefficient::Isotropic(mu), _) => (head, a1, a2) = (vec![(nu, -mu)], 1.0, 1.0),
                // (λ₁/μ₁)² + (λ₂/μ₂)² ≤ λν²  ⇔  ‖(μ₂λ₁, μ₁λ₂)‖ ≤ μ₁μ₂λν
                (Coefficient::Orthotropic(m1, m2), _) => (head, a1, a2) = (vec![(nu, -m1 * m2)], m2, m1),
                (Coefficient::Fixed, SlipBound::Disc(g)) => {
                    h0 = g / scale;
                    (head, a1, a2) = (vec![], 1.0, 1.0);
                }
                (Coefficient::Fixed, SlipBound::Ellipse(g1, g2)) => {
                    h0 = g1 * g2 / (scale * scale);
                    (head, a1, a2) = (vec![], g2 / scale, g1 / scale);
                }
                (Coefficient::Fixed, SlipBound::None) => continue,
            }
            c.a.extend(head.into_iter().map(|(j, v)| (r, j, v)));
            c.h.push(h0);
            c.a.push((r + 1, t1, -a1));
            c.h.push(0.0);
            c.a.push((r + 2, t2, -a2));
            c.h.push(0.0);
            c.socs += 1;
        }
        c
    }
}

/// λ* = argmin over Λ of ‖e − G λ‖ (with t ≥ ‖e − Gλ‖ minimized); None where Clarabel does not
/// solve it.
fn nearest(g: &[Vec<(usize, f64)>], e: &[f64], n: usize, cones: &Cones) -> Option<Vec<f64>> {
    // (t, e − Gλ) ∈ SOC after the cones of Λ
    let mut rows = vec![(0, n, -1.0)];
    for (r, row) in g.iter().enumerate() {
        rows.extend(row.iter().map(|&(j, v)| (1 + r, j, v)));
    }
    let mut q = vec![0.0; n + 1];
    q[n] = 1.0;
    let h: Vec<f64> = std::iter::once(0.0).chain(e.iter().copied()).collect();
    match program(cones, &rows, h, SecondOrderConeT(1 + g.len()), &q)? {
        (SolverStatus::Solved | SolverStatus::AlmostSolved, x) => Some(x),
        _ => None,
    }
}
