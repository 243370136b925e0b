//! The decomposition chosen by cost: when a scene leaves `[decomposition]` open, the monolithic
//! dual and TFETI at a few subdomain counts are priced before anything is assembled — the fill
//! of every factor (METIS nested dissection and the elimination tree, no numeric work), the
//! dual's size and its Dirichlet share, the A-products a solve takes and the time of one — and
//! the cheapest is taken. `tresca-feti check` prints the table, each row marked counted,
//! model or bound ([`Basis`]).
//!
//! Only one TFETI count is partitioned first (the middle one): its B is built and the fill of
//! a sample of its subdomains counted, which fits the power laws nnz(L) = c₁ n^{4/3},
//! Σ (column count)² = c₂ n² and a surface law (gluing rows and duplicated nodes ∝ S^{1/3} − 1)
//! that price the other counts ([`Law`]); the cheapest by the model is partitioned and counted
//! in turn (each count at most once) until the cheapest is counted and at least two counts are,
//! and its partition is kept for the decompose phase (`Model::partition`). Once two counts are
//! counted, the other counts take the power laws through the two nearest counted partitions
//! (constant and exponent: [`Pow`]), which follow the partitions' own fill per subdomain size
//! (a law at the fixed n^{4/3} fitted on one count priced four times the subdomains ~40 % high). The monolithic dual is counted (its orders are kept
//! for the factorization) unless a lower bound from the laws ([`BOUND`]) already loses.
//!
//! Time of a candidate = setup + (nA + σ-estimate products) · t_A with
//! - t_A = [`SECONDS_PER_NNZ`] · nnz(L) of the busiest rank (the forward and backward solves
//!   run at the memory bandwidth) + [`SECONDS_PER_ROW`] · dual rows per rank (the Krylov
//!   vectors, B, the exchange and the coarse projection of TFETI); for the monolithic dual with
//!   contact, whose products use the trailing blocks of factors that order the contact nodes
//!   last, [`SECONDS_PER_DENSE`] · Σ (contact DOFs of a body)² of the busiest rank instead of
//!   the nnz(L) term;
//! - setup = [`SECONDS_PER_FLOP`] · Σ (column count)² + [`SECONDS_PER_DOF`] · DOFs of the
//!   busiest rank (numeric factorization; assembly, ordering, kernels and rows of B);
//! - nA with contact: [`PRODUCTS_PER_DIGIT`] · log10(1/ε) · (m / 100)^[`PAIRS_EXPONENT`] for
//!   the monolithic dual with m contact pairs, [`TFETI_PRODUCTS`] · (1 + [`TFETI_GROWTH`] ·
//!   log2 S) times that for TFETI with S subdomains on the largest body, plus the σ_max
//!   estimate's products; without contact one solve for the monolithic dual,
//!   [`CG_PRODUCTS_PER_DIGIT`] · log10(1/ε) product-equivalents (PCG with the Dirichlet
//!   preconditioner) for TFETI. Where the scene's products cannot be known before solving
//!   ([`Unknown`]: a body held by contact alone, Coulomb friction, a load of prescribed
//!   displacements alone, and the features read off the model: a stiff slave, a soft slave on
//!   a stiff master, ν near ½, a thin body, Tresca bounds small against the load) the count is
//!   a range, each factor's low–high times the law above, and the candidate is priced at the
//!   range's geometric mean.
//!
//! The constants were fitted to the benchmark set on the development machine (docs/method.md,
//! "The default choice"); the ranking, not the seconds, is what the choice uses. The five
//! machine rates are these constants unless `tresca-feti calibrate` cached rates for this CPU
//! ([`super::rates`]).

use super::rates::Rates;
use crate::comm::Comm;
use crate::error::Result;
use crate::fem::assembly::{node_graph, DofMap};
use crate::feti::decomposition::{decompose_shared, Decomposition, DualGraphs};
use crate::feti::{assign_ranks, constraints};
use crate::linalg::ordering::{fill, nested_dissection, Fill};
use crate::model::Model;
use crate::qp::Common;
use crate::scene::DecompositionSettings;

/// Seconds per entry of L per A-product (forward and backward solve).
pub const SECONDS_PER_NNZ: f64 = 1.05e-9;
/// Seconds per (contact DOFs of a body)² per A-product on the monolithic dual with contact: its
/// two dense triangular solves with the factor's trailing block, at the memory bandwidth (blocks
/// that fit in the cache run up to 4× faster).
pub const SECONDS_PER_DENSE: f64 = 1.0e-9;
/// Seconds per dual row per A-product, outside the solves.
pub const SECONDS_PER_ROW: f64 = 0.5e-6;
/// Seconds per unit of Σ (column count)² in the numeric factorization.
pub const SECONDS_PER_FLOP: f64 = 2.5e-11;
/// Seconds per DOF of a rank's pieces before the solve: assembly, ordering, kernels, rows of B.
pub const SECONDS_PER_DOF: f64 = 1.0e-5;
/// A-products per digit of ε of a contact solve on the monolithic dual with 100 contact pairs
/// (fitted on the load-driven Tresca scenes of run/results/cost_model_products.txt) …
pub const PRODUCTS_PER_DIGIT: f64 = 14.0;
/// … growing with the contact pairs m as (m / 100)^this.
pub const PAIRS_EXPONENT: f64 = 0.19;
/// TFETI's A-products with contact as a multiple of the monolithic dual's, at one subdomain …
pub const TFETI_PRODUCTS: f64 = 1.2;
/// … growing by this fraction per doubling of the subdomains of the largest body.
pub const TFETI_GROWTH: f64 = 0.04;
/// Product-equivalents per digit of ε of TFETI's PCG without contact.
pub const CG_PRODUCTS_PER_DIGIT: f64 = 8.0;
/// Candidates with fewer DOFs per subdomain are not priced.
pub const MIN_SUBDOMAIN_DOFS: usize = 1000;
/// Most subdomains whose fill is counted per candidate (the others scaled from them) …
pub const SAMPLED: usize = 16;
/// … and the most nodes they may hold together (at least one subdomain is counted).
pub const SAMPLED_NODES: usize = 20_000;
/// Subdomain counts priced (on the largest body; the others in proportion).
pub const SUBDOMAIN_COUNTS: [usize; 8] = [2, 4, 8, 16, 32, 64, 128, 256];
/// The monolithic dual's lower bound takes the power laws' constants fitted on subdomains times
/// this (a whole body fills at least half as much per n^{4/3} as its subdomains).
pub const BOUND: f64 = 0.5;

/// One priced decomposition.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Candidate {
    /// Subdomains of each body (all 1 for the monolithic dual).
    pub parts: Vec<usize>,
    /// Solved on the TFETI dual (else the monolithic one).
    pub tfeti: bool,
    /// DOFs per subdomain asked for (TFETI).
    pub target_dofs: Option<usize>,
    /// Σ nnz(L) over all factors.
    pub nnz_l: f64,
    /// nnz(L) of the busiest rank.
    pub nnz_l_rank: f64,
    /// Dual rows of the contact constraints.
    pub contact_rows: usize,
    /// Dual rows gluing the subdomains (TFETI).
    pub gluing_rows: usize,
    /// Dual rows of the Dirichlet conditions (TFETI).
    pub dirichlet_rows: usize,
    /// Predicted A-products of the solve.
    pub n_a: f64,
    /// Predicted seconds per A-product.
    pub t_product: f64,
    /// Predicted set-up seconds (assembly to factors).
    pub t_factor: f64,
    /// Predicted total seconds: set-up and products.
    pub time: f64,
    /// The monolithic dual's products through the factors' trailing blocks (contact nodes
    /// ordered last where that costs little fill: [`order_last_if_cheap`]).
    #[serde(default)]
    pub explicit: bool,
    /// Whether the figures were counted, modelled from a counted partition, or a lower bound.
    #[serde(default)]
    pub basis: Basis,
    /// The range (low, high) of the A-products where the scene's count cannot be known before
    /// solving; `n_a` is then its geometric mean.
    #[serde(default)]
    pub n_a_range: Option<(f64, f64)>,
    /// Why the A-products are a range.
    #[serde(default)]
    pub unknowns: Vec<Unknown>,
}

/// What makes a scene's A-products unknown before solving: each widens the law's count by a
/// factor between its low and high (measured on run/results/cost_model_products.txt). The
/// features that carry a number are read off the model before solving.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Unknown {
    /// A body held by contact alone with `decomposition.restricted = false`: SMALSE-M's outer
    /// loop for Gλ = e (measured 0.7–2.3×).
    Floating,
    /// A body held by contact alone: TSSN keeps Gλ = e on each Newton step's subspace
    /// (measured 0.1–0.5×: fewer than a load-driven supported body).
    HeldRestricted,
    /// Coulomb friction: the fixed point on the normal multipliers (measured 0.3–1.0×, its
    /// Newton steps replace the Tresca solve's outer iterations).
    Coulomb,
    /// Loaded by prescribed displacements alone: fewer products, as the contact set is
    /// found in few iterations (measured 0.17–0.9×).
    Displacement,
    /// A stiff slave over a soft master: the slave's E·h (Young's modulus × facet size) this
    /// many times the master's (above [`crate::model::STIFF_SLAVE`], the criterion of the
    /// warning `check` prints). The contact rows are nearly dependent and nodes stay open
    /// (measured 18.9× at E·h ratio 1e6, 2.3× at 302, 3.7× at 4.7 and 15× at 470 on flat punches).
    StiffSlave(f64),
    /// A soft slave over a master with this many times its E·h (above [`CONTRAST`]): F's
    /// spectrum spreads with the contrast (measured 1.38× at 1e6).
    Contrast(f64),
    /// Nearly incompressible: 1/(1 − 2ν) = 1 + λ/μ of the most incompressible body (above
    /// [`INCOMPRESSIBLE`]): K's condition grows with it (measured 1.68× at ν = 0.4999).
    Incompressible(f64),
    /// A thin body: the largest ratio of a body's longest to shortest bounding-box extent
    /// (above [`THIN`]): bending makes K's condition grow with its square, CG's iterations
    /// with its first power (measured 2.3× at 100).
    Thin(f64),
    /// Friction that lets nearly everything slip: the Tresca bounds Σ g·w (the smaller axis of
    /// an ellipse) over the load's resultant |Σ F| (below [`SLIPPING`]): the tangential
    /// multipliers sit on their bounds and the active set is found early (measured 0.48× at
    /// 7e-9, 0.61× at an ellipse's minor axis 6e-4).
    Slipping(f64),
}

/// E·h ratio (master over slave) above which a soft slave's contrast widens the range.
pub const CONTRAST: f64 = 10.0;
/// 1/(1 − 2ν) above which a body is nearly incompressible (ν > 0.45).
pub const INCOMPRESSIBLE: f64 = 10.0;
/// Extent ratio above which a body is thin: below it the widening r/25 < 2 stays within the
/// law's scatter (plane_strain_rollers' and thin_clamped_plate's slabs at 40 measure 0.69× and
/// 1.97×, no trend).
pub const THIN: f64 = 50.0;
/// Ratio of the Tresca bounds to the load's resultant below which nearly everything slips.
pub const SLIPPING: f64 = 0.01;

impl Unknown {
    /// The low and high factor on the law's count.
    pub fn factors(self) -> (f64, f64) {
        match self {
            Unknown::Floating => (0.6, 4.0),
            Unknown::HeldRestricted => (0.1, 1.0),
            Unknown::Coulomb => (0.25, 1.1),
            Unknown::Displacement => (0.15, 1.0),
            Unknown::StiffSlave(r) => (1.0, 5.0 * (1.0 + r.log10())),
            Unknown::Contrast(_) => (1.0, 2.0),
            Unknown::Incompressible(x) => (1.0, 1.0 + 0.25 * x.log10()),
            Unknown::Thin(r) => (1.0, (r / 25.0).max(1.0)),
            Unknown::Slipping(_) => (0.3, 1.0),
        }
    }

    /// The footnote the table prints.
    pub fn why(self) -> String {
        let (lo, hi) = self.factors();
        match self {
            Unknown::Floating => format!("held by contact alone: the outer loop for Gλ = e (SMALSE-M) takes {lo}–{hi}× the law's products"),
            Unknown::HeldRestricted => format!("held by contact alone, Gλ = e kept by each Newton step: {lo}–{hi}× the law's products"),
            Unknown::Coulomb => format!("Coulomb: × the fixed point's outer iterations, {lo}–{hi}× the Tresca law's products"),
            Unknown::Displacement => format!("loaded by prescribed displacements alone: {lo}–{hi}× the load-driven law's products"),
            Unknown::StiffSlave(r) => format!("stiff slave (E·h ratio {r:.3}× the master's): nodes stay open, × {lo}–{hi:.1}"),
            Unknown::Contrast(r) => format!("soft slave on a stiff master (E·h ratio {r:.3}): × {lo}–{hi}"),
            Unknown::Incompressible(x) => format!("nearly incompressible (1/(1 − 2ν) = {x:.3}): × {lo}–{hi:.2}"),
            Unknown::Thin(r) => format!("thin body (extent ratio {r:.0}): × {lo}–{hi:.1}"),
            Unknown::Slipping(q) => format!("nearly all slip (Tresca bounds {q:.1e} × the load): × {lo}–{hi}"),
        }
    }
}

/// The features of `model` known before solving that widen its products' range: the stiffness
/// contrast across each pair, the most incompressible and the thinnest body, and Tresca bounds
/// small against a load. Each is listed once, at its worst.
fn features(model: &Model, contact: &crate::contact::pairing::Contact) -> Vec<Unknown> {
    use crate::contact::pairing::SlipBound;
    let mesh = &model.mesh;
    let young: Vec<f64> = model.lame.iter().map(crate::fem::material::Lame::young).collect();
    let ratios = model.contact.iter().map(|&(s, m)| crate::model::stiffness_size(mesh, &young, s).0 / crate::model::stiffness_size(mesh, &young, m).0);
    let (stiff, soft) = ratios.fold((0.0f64, 0.0f64), |(a, b), r| (a.max(r), b.max(1.0 / r)));
    let incompressible = model.lame.iter().map(|l| 1.0 + l.lambda / l.mu).fold(0.0, f64::max);
    let thin = mesh
        .bodies
        .iter()
        .map(|b| {
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for x in &mesh.nodes[b.nodes.clone()] {
                for k in 0..3 {
                    (lo[k], hi[k]) = (lo[k].min(x[k]), hi[k].max(x[k]));
                }
            }
            let e: Vec<f64> = (0..3).map(|k| hi[k] - lo[k]).collect();
            e.iter().copied().fold(0.0, f64::max) / e.iter().copied().fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max);
    let mut resultant = [0.0; 3];
    for (i, f) in model.loads.iter().enumerate() {
        resultant[i % 3] += f;
    }
    let load = resultant.iter().map(|f| f * f).sum::<f64>().sqrt();
    let tresca = !contact.is_coulomb();
    let bounds: f64 = contact
        .bound
        .iter()
        .map(|b| match *b {
            SlipBound::None => f64::INFINITY,
            SlipBound::Disc(g) => g,
            SlipBound::Ellipse(a, b) => a.min(b),
        })
        .sum();
    let slipping = bounds / load;
    [
        (stiff > crate::model::STIFF_SLAVE, Unknown::StiffSlave(stiff)),
        (soft > CONTRAST, Unknown::Contrast(soft)),
        (incompressible > INCOMPRESSIBLE, Unknown::Incompressible(incompressible)),
        (thin > THIN && thin.is_finite(), Unknown::Thin(thin)),
        (tresca && load > 0.0 && slipping < SLIPPING, Unknown::Slipping(slipping)),
    ]
    .into_iter()
    .filter_map(|(on, u)| on.then_some(u))
    .collect()
}

/// Where a candidate's figures come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Basis {
    /// Counted: its partition made, B built, the fill of its factors (or a sample of them) counted.
    #[default]
    Counted,
    /// Modelled: the fill from the power laws and the rows from the surface law of a counted
    /// partition.
    Modelled,
    /// A lower bound (the monolithic dual's fill from the power laws at half their constant),
    /// which already loses to the cheapest TFETI candidate: not counted.
    Bound,
}

impl Basis {
    /// The word the table prints.
    pub fn word(self) -> &'static str {
        match self {
            Basis::Counted => "counted",
            Basis::Modelled => "model",
            Basis::Bound => "bound",
        }
    }
}

impl Candidate {
    /// `monolithic` or `TFETI p₁/p₂/…` (subdomains per body), as the table prints it.
    pub fn label(&self) -> String {
        if self.tfeti {
            format!("TFETI {}", self.parts.iter().map(|p| p.to_string()).collect::<Vec<_>>().join("/"))
        } else {
            "monolithic".into()
        }
    }

    /// All dual rows: contact, gluing and Dirichlet.
    pub fn dual_rows(&self) -> usize {
        self.contact_rows + self.gluing_rows + self.dirichlet_rows
    }
}

/// Whether the scene leaves the decomposition to the cost model.
pub fn automatic(dec: &DecompositionSettings) -> bool {
    dec.subdomains.is_none() && dec.target_dofs.is_none()
}

/// Prices the monolithic dual (unless `decomposition.tfeti`) and TFETI at the subdomain counts
/// of [`SUBDOMAIN_COUNTS`] for a run on `ranks` ranks with the solver settings `solver`;
/// ordered as priced (the monolithic dual first). Every rank makes the same partitions and
/// the ranks share and sum the counted fills, so every rank gets the same table.
pub fn price<C: Comm>(comm: &C, model: &Model, dec: &DecompositionSettings, solver: &Common, ranks: usize) -> Result<Vec<Candidate>> {
    Ok(price_split(comm, model, dec, solver, ranks, &mut split())?.0)
}

/// The plan's parts, none timed yet.
fn split() -> Split {
    [("plan partition", 0.0), ("plan B", 0.0), ("plan fills", 0.0), ("plan monolithic", 0.0)]
}

/// [`price`], timing its parts into `split`; with the partition of the cheapest counted TFETI
/// candidate.
fn price_split<C: Comm>(
    comm: &C,
    model: &Model,
    dec: &DecompositionSettings,
    solver: &Common,
    ranks: usize,
    split: &mut Split,
) -> Result<(Vec<Candidate>, Option<Partition>)> {
    let pricing = Pricing::new(comm, model, solver, ranks, dec.restricted);
    let specs = pricing.tfeti_specs(dec.tfeti);
    let (tfeti, law, partition) = pricing.tfeti_candidates(dec, specs, split)?;
    let mut out = Vec::new();
    if !dec.tfeti {
        let best = cheapest(&tfeti).map(|c| c.time);
        let clock = std::time::Instant::now();
        // branch and bound: a lower bound of the monolithic dual that loses already is not counted
        let mono = match (law, best) {
            (Some(law), Some(best)) => Some(pricing.monolithic_bound(law)).filter(|m| m.time > best),
            _ => None,
        };
        out.push(match mono {
            Some(m) => m,
            None => pricing.monolithic()?,
        });
        split[3].1 += clock.elapsed().as_secs_f64();
    }
    out.extend(tfeti);
    Ok((out, partition))
}

/// A record of figures that one rank fills in and the ranks sum (every other rank holds zeros
/// there: x + 0 is exact), packed into `LEN` numbers for the sum.
trait Summed: Sized {
    /// The numbers of one record.
    const LEN: usize;
    /// Writes the record's numbers into `out` (`LEN` of them).
    fn pack(&self, out: &mut [f64]);
    /// The record of `LEN` numbers.
    fn unpack(x: &[f64]) -> Self;
}

/// Sums every record over the ranks of `comm`.
fn sum_records<C: Comm, T: Summed>(comm: &C, records: &mut [T]) {
    let mut v = vec![0.0; T::LEN * records.len()];
    for (r, out) in records.iter().zip(v.chunks_mut(T::LEN)) {
        r.pack(out);
    }
    comm.sum_f64(&mut v);
    for (r, x) in records.iter_mut().zip(v.chunks(T::LEN)) {
        *r = T::unpack(x);
    }
}

/// A body's fill, and whether its factor orders the contact nodes last (the monolithic dual's
/// explicit products).
#[derive(Clone, Copy, Debug, Default)]
struct BodyFill {
    fill: Fill,
    last: bool,
}

impl Summed for BodyFill {
    const LEN: usize = 3;
    fn pack(&self, out: &mut [f64]) {
        out.copy_from_slice(&[self.fill.nnz_l, self.fill.flops, if self.last { 1.0 } else { 0.0 }]);
    }
    fn unpack(x: &[f64]) -> Self {
        BodyFill { fill: Fill { nnz_l: x[0], flops: x[1] }, last: x[2] > 0.0 }
    }
}

/// A TFETI candidate to price: the subdomains `s` of the largest body, the DOFs per subdomain
/// asked for, and each body's parts.
struct Spec {
    s: usize,
    target: usize,
    parts: Vec<usize>,
}

/// What every candidate's pricing shares: the model, the ranks, the machine's rates and the
/// solve's figures.
struct Pricing<'a, C: Comm> {
    comm: &'a C,
    rates: Rates,
    model: &'a Model,
    ranks: usize,
    me: usize,
    workers: usize,
    contact: Option<&'a crate::contact::pairing::Contact>,
    contact_rows: usize,
    /// log10(1/ε), at least 1.
    digits: f64,
    /// The σ_max estimate's products (none when σ is given).
    power: f64,
    /// Contact pairs (node pairs or mortar rows).
    pairs: usize,
    /// What makes the products a range.
    unknowns: Vec<Unknown>,
    /// 3 × nodes of each body, and the most of them.
    body_dofs: Vec<usize>,
    largest: usize,
    /// The bodies' element graphs, built by the first partition and partitioned again by the
    /// next counts.
    duals: DualGraphs<'a>,
}

impl<'a, C: Comm> Pricing<'a, C> {
    /// The shared figures of a pricing for `ranks` ranks with the solver settings `solver`.
    /// `restricted`: bodies held by contact alone are solved by TSSN keeping Gλ = e
    /// (`decomposition.restricted`).
    fn new(comm: &'a C, model: &'a Model, solver: &Common, ranks: usize, restricted: bool) -> Self {
        let eps = solver.eps;
        let mesh = &model.mesh;
        let contact = model.pairs.as_ref();
        let body_dofs: Vec<usize> = mesh.bodies.iter().map(|b| 3 * b.nodes.len()).collect();
        let largest = body_dofs.iter().copied().max().unwrap_or(0);
        Pricing {
            comm,
            rates: super::rates::current().rates,
            model,
            ranks: ranks.max(1),
            me: comm.rank(),
            workers: comm.size(),
            contact,
            contact_rows: contact.map_or(0, |c| c.len() * if c.has_friction() { 3 } else { 1 }),
            digits: (1.0 / eps).log10().max(1.0),
            power: if solver.sigma.is_some() { 0.0 } else { solver.power_iterations as f64 },
            pairs: contact.map_or(0, |c| c.len()),
            unknowns: contact.map_or(Vec::new(), |c| {
                let loaded = model.loads.iter().any(|&f| f != 0.0);
                let held = if restricted { Unknown::HeldRestricted } else { Unknown::Floating };
                let mut u: Vec<Unknown> = [(!model.floating.is_empty(), held), (c.is_coulomb(), Unknown::Coulomb), (!loaded, Unknown::Displacement)]
                    .into_iter()
                    .filter_map(|(on, u)| on.then_some(u))
                    .collect();
                u.extend(features(model, c));
                u
            }),
            body_dofs,
            largest,
            duals: DualGraphs::new(mesh),
        }
    }

    /// A candidate from its pieces' fills, ranks and DOFs, its rows of B and its nA.
    #[allow(clippy::too_many_arguments)]
    fn candidate(
        &self,
        parts: Vec<usize>,
        target_dofs: Option<usize>,
        f: &[Fill],
        rank_of: &dyn Fn(usize) -> usize,
        dofs_of: &dyn Fn(usize) -> f64,
        rows: (usize, usize),
        products: Products,
    ) -> Candidate {
        let n_a = products.point;
        let ranks = self.ranks;
        let (mut nnz, mut flops, mut dofs) = (vec![0.0; ranks], vec![0.0; ranks], vec![0.0; ranks]);
        for (i, x) in f.iter().enumerate() {
            let r = rank_of(i);
            (nnz[r], flops[r], dofs[r]) = (nnz[r] + x.nnz_l, flops[r] + x.flops, dofs[r] + dofs_of(i));
        }
        let mut c = Candidate {
            parts,
            tfeti: target_dofs.is_some(),
            target_dofs,
            nnz_l: f.iter().map(|x| x.nnz_l).sum(),
            nnz_l_rank: max(&nnz),
            contact_rows: self.contact_rows,
            gluing_rows: rows.0,
            dirichlet_rows: rows.1,
            n_a,
            t_product: 0.0,
            t_factor: self.rates.flop * max(&flops) + self.rates.dof * max(&dofs),
            time: 0.0,
            explicit: false,
            basis: Basis::Counted,
            n_a_range: products.range,
            unknowns: if products.range.is_some() { self.unknowns.clone() } else { Vec::new() },
        };
        c.t_product = self.rates.nnz * c.nnz_l_rank + self.rates.row * c.dual_rows() as f64 / ranks as f64;
        c.time = c.t_factor + n_a * c.t_product;
        c
    }

    /// The monolithic dual: one factor per body, the contact nodes ordered last with contact.
    fn monolithic(&self) -> Result<Candidate> {
        let (mesh, ranks, contact) = (&self.model.mesh, self.ranks, self.contact);
        let nb = mesh.bodies.len();
        let by_body = crate::model::constraints_by_body(mesh, &self.model.constraints);
        let f = self.body_fills(&by_body)?;
        let fills: Vec<Fill> = f.iter().map(|x| x.fill).collect();
        let products = self.products(None);
        let n_a = products.point;
        let mut mono = self.candidate(vec![1; nb], None, &fills, &|b| super::owner(b, ranks), &|b| self.body_dofs[b] as f64, (0, 0), products);
        if contact.is_some() && f.iter().all(|x| x.last) {
            self.explicit_products(&mut mono, &by_body, n_a);
        }
        Ok(mono)
    }

    /// A lower bound of the monolithic dual from a counted partition's law: each body's fill
    /// from the power laws at [`BOUND`] times their constant, its products the cheaper of the
    /// factor's solves and the explicit ones.
    fn monolithic_bound(&self, law: Law) -> Candidate {
        let (mesh, ranks) = (&self.model.mesh, self.ranks);
        let nb = mesh.bodies.len();
        let low = Law { nnz: BOUND * law.nnz, flops: BOUND * law.flops, pow: None, ..law };
        let fills: Vec<Fill> = mesh.bodies.iter().map(|b| low.fill(b.nodes.len() as f64)).collect();
        let products = self.products(None);
        let n_a = products.point;
        let mut mono = self.candidate(vec![1; nb], None, &fills, &|b| super::owner(b, ranks), &|b| self.body_dofs[b] as f64, (0, 0), products);
        if self.contact.is_some() {
            let mut explicit = mono.clone();
            let by_body = crate::model::constraints_by_body(mesh, &self.model.constraints);
            self.explicit_products(&mut explicit, &by_body, n_a);
            if explicit.time < mono.time {
                mono = explicit;
            }
        }
        mono.basis = Basis::Bound;
        mono
    }

    /// Each body's fill (its node order kept for the factorization), counted by rank
    /// (body % workers) and summed over the ranks.
    fn body_fills(&self, by_body: &[Vec<(usize, usize, f64)>]) -> Result<Vec<BodyFill>> {
        let (model, mesh) = (self.model, &self.model.mesh);
        let n = mesh.bodies.len();
        let mut v = vec![BodyFill::default(); n];
        let mut failed = Ok(());
        for b in (self.me..n).step_by(self.workers) {
            let body = &mesh.bodies[b];
            let graph = || {
                let dofs = DofMap::new(body.nodes.clone(), &by_body[b]);
                let free = (0..body.nodes.len()).map(|l| (0..3).filter(|c| dofs.free[3 * l + c] != crate::fem::assembly::FIXED).count() as u8).collect();
                (node_graph(&mesh.cells, body.elems.clone(), body.nodes.len(), |v| v - body.nodes.start), free)
            };
            // with contact the contact nodes are ordered last (the explicit products); the
            // order is kept for the factorization
            match super::body_order(model, b, self.contact.is_some(), graph) {
                Ok(order) => v[b] = BodyFill { fill: order.fill, last: order.last },
                Err(e) => {
                    failed = Err(e);
                    break;
                }
            }
        }
        // every rank reaches the sum, then all fail together
        sum_records(self.comm, &mut v);
        self.comm.agree(failed)?;
        Ok(v)
    }

    /// Prices the monolithic dual's products through the bodies' trailing blocks: two dense
    /// triangular solves with each body's trailing block per product.
    fn explicit_products(&self, mono: &mut Candidate, by_body: &[Vec<(usize, usize, f64)>], n_a: f64) {
        let (model, mesh, ranks) = (self.model, &self.model.mesh, self.ranks);
        let mut dense = vec![0.0; ranks];
        for b in 0..mesh.bodies.len() {
            let last = super::contact_nodes(model, b);
            let dofs = DofMap::new(mesh.bodies[b].nodes.clone(), &by_body[b]);
            let n = (0..last.len()).filter(|&l| last[l]).map(|l| (0..3).filter(|c| dofs.free[3 * l + c] != crate::fem::assembly::FIXED).count()).sum::<usize>()
                as f64;
            dense[super::owner(b, ranks)] += n * n;
        }
        mono.t_product = self.rates.dense * max(&dense) + self.rates.row * mono.dual_rows() as f64 / ranks as f64;
        mono.time = mono.t_factor + n_a * mono.t_product;
        mono.explicit = true;
    }

    /// The TFETI candidates to price (one subdomain first where `decomposition.tfeti`): the
    /// counts whose subdomains are large enough and no more than each body's elements.
    fn tfeti_specs(&self, with_one: bool) -> Vec<Spec> {
        let mesh = &self.model.mesh;
        let mut counts: Vec<usize> = SUBDOMAIN_COUNTS.to_vec();
        if with_one {
            counts.insert(0, 1);
        }
        counts
            .into_iter()
            .map(|s| (s, self.largest.div_ceil(s)))
            .map(|(s, target)| (s, target, self.body_dofs.iter().map(|&d| d.div_ceil(target).max(1)).collect::<Vec<usize>>()))
            .filter(|(s, target, parts)| !((*s > 1 && *target < MIN_SUBDOMAIN_DOFS) || parts.iter().zip(&mesh.bodies).any(|(&p, b)| p > b.elems.len())))
            .map(|(s, target, parts)| Spec { s, target, parts })
            .collect()
    }

    /// The TFETI candidates: one partition first (the middle count), its sampled fills
    /// calibrating the power laws and its rows the surface law ([`Law`]), every other count
    /// priced from them; then the cheapest by the model is partitioned and counted in turn until
    /// the cheapest is a counted one. Returns the candidates, the law of the last partition and
    /// the cheapest counted candidate's partition (what the decompose phase reuses).
    fn tfeti_candidates(&self, dec: &DecompositionSettings, specs: Vec<Spec>, split: &mut Split) -> Result<(Vec<Candidate>, Option<Law>, Option<Partition>)> {
        if specs.is_empty() {
            return Ok((vec![], None, None));
        }
        let mut counted: Vec<Option<(Candidate, Law)>> = vec![None; specs.len()];
        // two counted partitions fit the exponents of the power laws (where two counts are priced)
        let wanted = specs.len().min(2);
        // the first reference: the middle count with more than one subdomain where there is one
        let many: Vec<usize> = (0..specs.len()).filter(|&j| specs[j].s > 1).collect();
        let mut next = if many.is_empty() { 0 } else { many[many.len() / 2] };
        // the partition of the cheapest counted candidate (its index, the partition)
        let mut keep: Option<(usize, Partition)> = None;
        loop {
            let (c, l, part) = self.tfeti(dec, &specs[next], split)?;
            counted[next] = Some((c, l));
            let priced = self.tfeti_priced(&specs, &counted, l);
            let time = |j: usize| priced[j].time;
            if keep.as_ref().is_none_or(|(k, _)| time(next) < time(*k)) {
                keep = Some((next, part));
            }
            let best = (0..priced.len()).min_by(|&a, &b| time(a).total_cmp(&time(b))).expect("a candidate");
            let open = |j: usize| counted.get(j).is_some_and(|c| c.is_none());
            // done when the cheapest is counted and two counts are (each turn counts another: it
            // ends); with one counted, the cheaper of the cheapest's neighbours next
            if counted[best].is_some() {
                let neighbour = [best.wrapping_sub(1), best + 1].into_iter().filter(|&j| open(j)).min_by(|&a, &b| time(a).total_cmp(&time(b)));
                match neighbour {
                    Some(j) if counted.iter().flatten().count() < wanted => next = j,
                    _ => return Ok((priced, Some(l), keep.map(|k| k.1))),
                }
            } else {
                next = best;
            }
        }
    }

    /// Every candidate: the counted ones as counted, the others from `law` (one counted) or
    /// from the law of the nearest counted partition with the power laws through the two
    /// nearest counted partitions ([`Pow::through`]).
    fn tfeti_priced(&self, specs: &[Spec], counted: &[Option<(Candidate, Law)>], law: Law) -> Vec<Candidate> {
        let done: Vec<usize> = (0..specs.len()).filter(|&j| counted[j].is_some()).collect();
        let law_of = |spec: &Spec| {
            let mut near = done.clone();
            // nearest by the ratio of the counts; the smaller count on a tie
            near.sort_by(|&a, &b| ratio(specs[a].s, spec.s).total_cmp(&ratio(specs[b].s, spec.s)).then(a.cmp(&b)));
            match near[..] {
                [a, b, ..] => {
                    let (la, lb) = (counted[a].as_ref().expect("counted").1, counted[b].as_ref().expect("counted").1);
                    Law { pow: Some(Pow::through(la.per, lb.per)), ..la }
                }
                _ => law,
            }
        };
        specs.iter().zip(counted).map(|(spec, c)| c.as_ref().map_or_else(|| self.modelled(spec, law_of(spec)), |c| c.0.clone())).collect()
    }

    /// The predicted A-products of TFETI with `s` subdomains on the largest body.
    fn tfeti_products(&self, s: usize) -> Products {
        self.products(Some(s))
    }

    /// The predicted A-products: of the monolithic dual (`None`) or of TFETI with `s`
    /// subdomains on the largest body; a range where the scene has [`Unknown`]s.
    fn products(&self, tfeti: Option<usize>) -> Products {
        if self.contact.is_none() {
            let n = if tfeti.is_some() { CG_PRODUCTS_PER_DIGIT * self.digits } else { 1.0 };
            return Products { point: n, range: None };
        }
        let growth = tfeti.map_or(1.0, |s| TFETI_PRODUCTS * (1.0 + TFETI_GROWTH * (s as f64).log2()));
        let law = growth * PRODUCTS_PER_DIGIT * self.digits * (self.pairs.max(1) as f64 / 100.0).powf(PAIRS_EXPONENT);
        if self.unknowns.is_empty() {
            return Products { point: law + self.power, range: None };
        }
        let (lo, hi) = range_factors(&self.unknowns);
        Products { point: (lo * hi).sqrt() * law + self.power, range: Some((lo * law + self.power, hi * law + self.power)) }
    }

    /// A TFETI candidate priced from the law of a counted partition: every subdomain of body b
    /// holds its nodes × (1 + duplication) / parts, its fill from the power laws; the gluing and
    /// Dirichlet rows scaled by the surface law; the ranks balanced by DOFs (LPT).
    fn modelled(&self, spec: &Spec, law: Law) -> Candidate {
        let mesh = &self.model.mesh;
        let surface = law.surface(spec.s);
        let mut nodes = Vec::new();
        for (b, &p) in spec.parts.iter().enumerate() {
            let n = mesh.bodies[b].nodes.len() as f64 * (1.0 + law.duplication * surface) / p as f64;
            nodes.extend(std::iter::repeat_n(n, p));
        }
        let f: Vec<Fill> = nodes.iter().map(|&n| law.fill(n)).collect();
        let owner = balance(&nodes, self.ranks);
        let rows = ((law.gluing * surface).round() as usize, (law.dirichlet * (1.0 + law.duplication * surface)).round() as usize);
        let mut c = self.candidate(spec.parts.clone(), Some(spec.target), &f, &|i| owner[i], &|i| 3.0 * nodes[i], rows, self.tfeti_products(spec.s));
        c.basis = Basis::Modelled;
        c
    }

    /// Partitions and prices one TFETI candidate: its partition, B, the fills of a sample of its
    /// subdomains (shared by the ranks, summed); and the law its figures calibrate.
    fn tfeti(&self, dec: &DecompositionSettings, spec: &Spec, split: &mut Split) -> Result<(Candidate, Law, Partition)> {
        let (model, mesh) = (self.model, &self.model.mesh);
        let clock = std::time::Instant::now();
        let d = decompose_shared(self.comm, &self.duals, &spec.parts)?;
        split[0].1 += clock.elapsed().as_secs_f64();
        let clock = std::time::Instant::now();
        let elim = crate::feti::eliminated(mesh, &d, &model.constraints, dec.dirichlet);
        let cons = constraints::build(&d, &model.constraints, self.contact, &model.ties, dec.gluing, &elim);
        let owner = assign_ranks(&d.subdomains.iter().map(|x| 3 * x.nodes.len()).collect::<Vec<_>>(), &cons, self.ranks);
        split[1].1 += clock.elapsed().as_secs_f64();
        let clock = std::time::Instant::now();
        let total_nodes: usize = mesh.bodies.iter().map(|b| b.nodes.len()).sum();
        let sample = sample_size(d.subdomains.len(), total_nodes as f64 / d.subdomains.len() as f64);
        let (f, fit) = sampled_fills(self.comm, mesh, &d, &elim, sample)?;
        split[2].1 += clock.elapsed().as_secs_f64();
        let rows = (cons.gluing_rows, cons.dirichlet_rows);
        let c = self.candidate(
            spec.parts.clone(),
            Some(spec.target),
            &f,
            &|i| owner[i],
            &|i| 3.0 * d.subdomains[i].nodes.len() as f64,
            rows,
            self.tfeti_products(spec.s),
        );
        let held: usize = d.subdomains.iter().map(|x| x.nodes.len()).sum();
        let surface = Law::surface_of(spec.s);
        let duplication = if surface > 0.0 { (held as f64 / total_nodes as f64 - 1.0) / surface } else { 0.0 };
        let scale = 1.0 + duplication * surface;
        let ns = d.subdomains.len().max(1) as f64;
        let per = Point { nodes: held as f64 / ns, nnz: f.iter().map(|x| x.nnz_l).sum::<f64>() / ns, flops: f.iter().map(|x| x.flops).sum::<f64>() / ns };
        let law = Law {
            nnz: fit.nnz,
            flops: fit.flops,
            duplication,
            gluing: if surface > 0.0 { cons.gluing_rows as f64 / surface } else { 0.0 },
            dirichlet: cons.dirichlet_rows as f64 / scale,
            per,
            pow: None,
        };
        Ok((c, law, (spec.parts.clone(), d)))
    }
}

/// The plan's partition of one count: subdomains per body and the decomposition.
type Partition = (Vec<usize>, Decomposition);

/// Seconds of the plan's parts: partitions, B and ranks, sampled fills, the monolithic fill.
type Split = [(&'static str, f64); 4];

/// A counted partition's figures as laws of the subdomain count: nnz(L) = nnz · n^{4/3} and
/// Σ (column count)² = flops · n² for a piece of n nodes (nested dissection of 3-D pieces), the
/// nodes held by the subdomains (1 + duplication · σ(S)) × the mesh's, the gluing rows gluing ·
/// σ(S), σ(S) = S^{1/3} − 1 (the interfaces of S cubes cut from one: 3 (S^{1/3} − 1) faces of
/// the cube's), and the Dirichlet rows in proportion to the nodes held.
#[derive(Clone, Copy, Debug, Default)]
struct Law {
    nnz: f64,
    flops: f64,
    duplication: f64,
    gluing: f64,
    dirichlet: f64,
    /// The counted partition's mean subdomain: nodes, nnz(L), Σ (column count)².
    per: Point,
    /// The power laws through two counted partitions, where two are (else the fixed exponents).
    pow: Option<Pow>,
}

/// A counted partition's mean subdomain: its nodes and fill.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Point {
    nodes: f64,
    nnz: f64,
    flops: f64,
}

/// Power laws nnz(L) = c_nnz · n^a_nnz and Σ (column count)² = c_flops · n^a_flops through the
/// mean subdomains of two counted partitions.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Pow {
    c_nnz: f64,
    a_nnz: f64,
    c_flops: f64,
    a_flops: f64,
}

impl Pow {
    /// The laws through `p` and `q`: the exponents from the two (nnz(L) within 1 to 2, the work
    /// within 1.5 to 3: nested dissection of 2-D to beyond 3-D pieces), the constants through `p`.
    fn through(p: Point, q: Point) -> Pow {
        let exponent = |a: f64, b: f64, lo: f64, hi: f64, fixed: f64| {
            let e = (a / b).ln() / (p.nodes / q.nodes).ln();
            if e.is_finite() {
                e.clamp(lo, hi)
            } else {
                fixed
            }
        };
        let a_nnz = exponent(p.nnz, q.nnz, 1.0, 2.0, 4.0 / 3.0);
        let a_flops = exponent(p.flops, q.flops, 1.5, 3.0, 2.0);
        Pow { c_nnz: p.nnz / p.nodes.powf(a_nnz), a_nnz, c_flops: p.flops / p.nodes.powf(a_flops), a_flops }
    }
}

/// |ln(a / b)|: how far apart two subdomain counts are.
fn ratio(a: usize, b: usize) -> f64 {
    (a as f64 / b as f64).ln().abs()
}

impl Law {
    /// σ(S) = S^{1/3} − 1.
    fn surface_of(s: usize) -> f64 {
        (s as f64).cbrt() - 1.0
    }

    fn surface(&self, s: usize) -> f64 {
        Self::surface_of(s)
    }

    /// The modelled fill of a piece of `n` nodes.
    fn fill(&self, n: f64) -> Fill {
        match self.pow {
            Some(p) => Fill { nnz_l: p.c_nnz * n.powf(p.a_nnz), flops: p.c_flops * n.powf(p.a_flops) },
            None => Fill { nnz_l: self.nnz * n.powf(4.0 / 3.0), flops: self.flops * n * n },
        }
    }
}

/// The fitted constants of the fill's power laws.
#[derive(Clone, Copy, Debug, Default)]
struct Fit {
    nnz: f64,
    flops: f64,
}

/// Every subdomain's fill, counted on a sample of them (`sample` of them, spread over the
/// subdomains; the ranks share them and sum the counts), the others scaled from it by their node
/// count (nested dissection of 3-D pieces: nnz(L) ~ n^4/3, work ~ n²); and the fitted constants.
fn sampled_fills<C: Comm>(comm: &C, mesh: &crate::mesh::Mesh, d: &Decomposition, elim: &[Vec<usize>], sample: usize) -> Result<(Vec<Fill>, Fit)> {
    let ns = d.subdomains.len();
    let stride = ns.div_ceil(sample.min(ns));
    let sampled: Vec<usize> = (0..ns).step_by(stride).collect();
    let mut counted = vec![FillRecord::default(); sampled.len()];
    let mut failed = Ok(());
    for (i, &s) in sampled.iter().enumerate().filter(|(i, _)| i % comm.size() == comm.rank()) {
        let sd = &d.subdomains[s];
        let (xadj, adj) = node_graph(&mesh.cells, sd.elems.iter().copied(), sd.nodes.len(), |v| sd.local(v).expect("node of the subdomain"));
        // the DOFs held inside the subdomain cost no fill
        let mut free = vec![3u8; sd.nodes.len()];
        elim[s].iter().for_each(|&dof| free[dof / 3] -= 1);
        match nested_dissection(&xadj, &adj) {
            Ok(perm) => counted[i] = FillRecord(fill(&xadj, &adj, &perm, &free)),
            Err(e) => {
                failed = Err(e);
                break;
            }
        }
    }
    // every rank reaches the sum, then all fail together
    sum_records(comm, &mut counted);
    comm.agree(failed)?;
    let nodes = |s: usize| d.subdomains[s].nodes.len() as f64;
    let (mut a, mut b, mut wa, mut wb) = (0.0, 0.0, 0.0, 0.0);
    for (&s, x) in sampled.iter().zip(&counted) {
        (a, b, wa, wb) = (a + x.0.nnz_l, b + x.0.flops, wa + nodes(s).powf(4.0 / 3.0), wb + nodes(s).powi(2));
    }
    let fit = Fit { nnz: a / wa, flops: b / wb };
    let fills = (0..ns)
        .map(|s| match sampled.binary_search(&s) {
            Ok(i) => counted[i].0,
            Err(_) => Fill { nnz_l: fit.nnz * nodes(s).powf(4.0 / 3.0), flops: fit.flops * nodes(s).powi(2) },
        })
        .collect();
    Ok((fills, fit))
}

/// One counted fill, summed over the ranks.
#[derive(Clone, Copy, Debug, Default)]
struct FillRecord(Fill);

impl Summed for FillRecord {
    const LEN: usize = 2;
    fn pack(&self, out: &mut [f64]) {
        out.copy_from_slice(&[self.0.nnz_l, self.0.flops]);
    }
    fn unpack(x: &[f64]) -> Self {
        FillRecord(Fill { nnz_l: x[0], flops: x[1] })
    }
}

/// Subdomains whose fill a candidate counts: a quarter of its `ns`, 2 to [`SAMPLED`], at most
/// [`SAMPLED_NODES`] nodes at `per` nodes each, at least one.
fn sample_size(ns: usize, per: f64) -> usize {
    let by_nodes = ((SAMPLED_NODES as f64 / per) as usize).max(1);
    (ns / 4).clamp(2, SAMPLED).min(by_nodes).min(ns).max(1)
}

/// Jobs of the given work to `workers` ranks, the largest first to the least loaded rank (LPT).
fn balance(work: &[f64], workers: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..work.len()).collect();
    order.sort_by(|&a, &b| work[b].total_cmp(&work[a]).then(a.cmp(&b)));
    let (mut load, mut owner) = (vec![0.0f64; workers.max(1)], vec![0; work.len()]);
    for j in order {
        let r = (0..load.len()).min_by(|&a, &b| load[a].total_cmp(&load[b]).then(a.cmp(&b))).expect("one rank");
        (owner[j], load[r]) = (r, load[r] + work[j]);
    }
    owner
}

fn max(v: &[f64]) -> f64 {
    v.iter().copied().fold(0.0, f64::max)
}

/// A candidate's predicted A-products: the point it is priced at, and the range where unknown.
#[derive(Clone, Copy, Debug)]
struct Products {
    point: f64,
    range: Option<(f64, f64)>,
}

/// The low and high factors of several unknowns: a body held by contact alone and each feature
/// of [`features`] multiply; Coulomb friction and a displacement load, which measure the same
/// few outer iterations, take the wider of their ranges.
fn range_factors(unknowns: &[Unknown]) -> (f64, f64) {
    let (mut lo, mut hi) = (1.0f64, 1.0f64);
    let (mut slo, mut shi) = (f64::INFINITY, 0.0f64);
    for u in unknowns {
        let (l, h) = u.factors();
        if matches!(u, Unknown::Coulomb | Unknown::Displacement) {
            (slo, shi) = (slo.min(l), shi.max(h));
        } else {
            (lo, hi) = (lo * l, hi * h);
        }
    }
    if shi > 0.0 {
        (lo, hi) = (lo * slo, hi * shi);
    }
    (lo, hi)
}

/// The cheapest candidate.
pub fn cheapest(cands: &[Candidate]) -> Option<&Candidate> {
    cands.iter().min_by(|a, b| a.time.total_cmp(&b.time))
}

/// Fixes an automatic decomposition to the cheapest candidate (`subdomains = 1` for the
/// monolithic dual, `target_dofs` for TFETI) and returns the priced table; `None` when the
/// scene set the decomposition itself.
pub fn resolve<C: Comm>(comm: &C, model: &Model, dec: &mut DecompositionSettings, solver: &Common, ranks: usize) -> Result<Option<Vec<Candidate>>> {
    resolve_timed(comm, model, dec, solver, ranks, &mut Vec::new())
}

/// [`resolve`], with the seconds of the plan's parts pushed onto `parts` (the same names on
/// every rank, for `Timings::split`) and the partition of the chosen count kept in the model
/// (`Model::partition`) for the decompose phase.
pub fn resolve_timed<C: Comm>(
    comm: &C,
    model: &Model,
    dec: &mut DecompositionSettings,
    solver: &Common,
    ranks: usize,
    parts: &mut Vec<(&'static str, f64)>,
) -> Result<Option<Vec<Candidate>>> {
    let mut times = split();
    let result = if automatic(dec) {
        let (cands, partition) = price_split(comm, model, dec, solver, ranks, &mut times)?;
        match cheapest(&cands) {
            Some(c) if c.tfeti => {
                dec.target_dofs = c.target_dofs;
                if let Some(p) = partition.filter(|p| p.0 == c.parts) {
                    let _ = model.partition.set(p);
                }
            }
            _ => dec.subdomains = Some(1),
        }
        Some(cands)
    } else {
        None
    };
    parts.extend(times);
    Ok(result)
}

/// The table `check` prints.
pub fn table(cands: &[Candidate], ranks: usize) -> String {
    use std::fmt::Write;
    let best = cheapest(cands).map(Candidate::label);
    let mut s = format!("decomposition by cost ({ranks} rank{}):\n", if ranks == 1 { "" } else { "s" });
    let _ = writeln!(
        s,
        "  {:<16} {:>8} {:>9} {:>11} {:>11} {:>9} {:>6} {:>9} {:>9} {:>9} {:>9}",
        "candidate", "figures", "DOFs/sub", "Σnnz(L)", "nnz(L)/rank", "dual", "Dir %", "nA", "t_A ms", "setup s", "total s"
    );
    let mut unknowns: Vec<Unknown> = Vec::new();
    for c in cands {
        let dual = c.dual_rows();
        let _ = writeln!(
            s,
            "  {:<16} {:>8} {:>9} {:>11.3e} {:>11.3e} {:>9} {:>6.1} {:>9} {:>9.2} {:>9.2} {:>9.2}{}",
            c.label(),
            c.basis.word(),
            c.target_dofs.map_or("-".into(), |t| t.to_string()),
            c.nnz_l,
            c.nnz_l_rank,
            dual,
            100.0 * c.dirichlet_rows as f64 / dual.max(1) as f64,
            c.n_a_range.map_or(format!("{:.0}", c.n_a), |(lo, hi)| format!("{lo:.0}–{hi:.0}")),
            1e3 * c.t_product,
            c.t_factor,
            c.time,
            if Some(c.label()) == best { "  ← chosen" } else { "" }
        );
    }
    for c in cands {
        for u in &c.unknowns {
            if !unknowns.contains(u) {
                unknowns.push(*u);
            }
        }
    }
    if let Some(c) = cands.iter().find(|c| c.n_a_range.is_some()) {
        let _ = writeln!(s, "  nA lo–hi: not known before solving, priced at the geometric mean ({:.0} for {}):", c.n_a, c.label());
    }
    for u in unknowns {
        let _ = writeln!(s, "    {}", u.why());
    }
    let _ = writeln!(s, "  (counted: partitioned, B built, fill counted on sampled subdomains or whole; model: power laws and surface law fitted on a counted partition; bound: a lower bound that loses)");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::comm::SerialComm;
    use crate::feti::decomposition::decompose_each;

    #[test]
    fn the_pricing_is_balanced_and_its_samples_bounded() {
        // LPT: the largest job alone, the others filling the second rank; every job placed once
        assert_eq!(balance(&[1.13, 0.55, 0.70, 0.53, 0.70, 0.55, 0.64], 2), vec![0, 1, 1, 1, 1, 0, 0]);
        assert_eq!(balance(&[3.0, 1.0], 1), vec![0, 0]);
        // a quarter of the subdomains, 2 to SAMPLED, at most SAMPLED_NODES nodes, at least one
        assert_eq!(sample_size(4, 6912.0), 2);
        assert_eq!(sample_size(4, 37_000.0), 1);
        assert_eq!(sample_size(256, 600.0), SAMPLED);
        assert_eq!(sample_size(64, 4_600.0), 4);
        assert_eq!(sample_size(1, 100.0), 1);
    }

    #[test]
    fn the_counted_fill_is_what_the_factors_store() {
        // seed N = 12: the monolithic candidate's count against the factors the solve builds
        let (model, _, _) = crate::feti::seed_fixture(12, 1);
        let dec = DecompositionSettings::default();
        let cands = price(&SerialComm, &model, &dec, &Common::default(), 1).unwrap();
        let mono = &cands[0];
        assert!(!mono.tfeti);
        let bodies = super::super::assemble_and_factorize(&SerialComm, &model, crate::scene::OrderingKind::Metis, true, &mut Default::default()).unwrap();
        let stored: usize = bodies.iter().map(|b| b.chol.nnz_l()).sum();
        let ratio = stored as f64 / mono.nnz_l;
        assert!((1.0..1.5).contains(&ratio), "stored {stored} against counted {}", mono.nnz_l);
        // TFETI candidates: the modelled ones less fill and more gluing with more subdomains;
        // the counted one's rows as the decomposition builds them
        let tfeti: Vec<&Candidate> = cands.iter().filter(|c| c.tfeti).collect();
        let modelled: Vec<&&Candidate> = tfeti.iter().filter(|c| c.basis == Basis::Modelled).collect();
        for w in modelled.windows(2) {
            assert!(w[1].parts[0] > w[0].parts[0] && w[1].nnz_l < w[0].nnz_l && w[1].gluing_rows > w[0].gluing_rows);
        }
        let counted = tfeti.iter().find(|c| c.basis == Basis::Counted).expect("one counted partition");
        let (_, d, _) = crate::feti::seed_fixture(12, counted.parts[0]);
        let elim = crate::feti::eliminated(&model.mesh, &d, &model.constraints, dec.dirichlet);
        let cons = constraints::build(&d, &model.constraints, model.pairs.as_ref(), &model.ties, dec.gluing, &elim);
        assert_eq!((counted.gluing_rows, counted.dirichlet_rows), (cons.gluing_rows, cons.dirichlet_rows));
        assert_eq!(d.subdomains.len(), 2 * counted.parts[0]);
    }

    #[test]
    fn the_plans_partition_is_a_fresh_partition_of_the_chosen_count() {
        // TFETI only: the chosen count's partition is kept for the decompose phase
        let (model, _, _) = crate::feti::seed_fixture(12, 1);
        let mut dec = DecompositionSettings { tfeti: true, ..Default::default() };
        let cands = resolve(&SerialComm, &model, &mut dec, &Common::default(), 2).unwrap().expect("automatic");
        let best = cheapest(&cands).unwrap();
        let (parts, kept) = model.partition.get().expect("the chosen count's partition kept");
        assert_eq!(*parts, best.parts);
        assert_eq!(parts, &model.mesh.bodies.iter().map(|b| dec.parts(3 * b.nodes.len())).collect::<Vec<_>>());
        let fresh = decompose_each(&model.mesh, parts).unwrap();
        assert_eq!(kept.subdomains, fresh.subdomains);
        assert_eq!(kept.copies, fresh.copies);
    }

    #[test]
    fn two_counted_partitions_fit_the_exponents() {
        // points on nnz = 3 n^1.5, work = 0.5 n^2.4: the law through them gives the law back
        let at = |n: f64| Point { nodes: n, nnz: 3.0 * n.powf(1.5), flops: 0.5 * n.powf(2.4) };
        let p = Pow::through(at(2000.0), at(9000.0));
        assert!((p.a_nnz - 1.5).abs() < 1e-12 && (p.a_flops - 2.4).abs() < 1e-12, "{p:?}");
        let law = Law { pow: Some(p), ..Default::default() };
        let f = law.fill(500.0);
        assert!((f.nnz_l / (3.0 * 500f64.powf(1.5)) - 1.0).abs() < 1e-12 && (f.flops / (0.5 * 500f64.powf(2.4)) - 1.0).abs() < 1e-12);
        // exponents outside nested dissection's range are clamped, equal sizes keep the fixed ones
        assert_eq!(Pow::through(at(1000.0), Point { nnz: 1.0, ..at(2000.0) }).a_nnz, 1.0);
        assert_eq!(Pow::through(at(1000.0), at(1000.0)).a_nnz, 4.0 / 3.0);
        // the plan counts two partitions, the cheapest among them, and models the others
        let (model, _, _) = crate::feti::seed_fixture(12, 1);
        let dec = DecompositionSettings { tfeti: true, ..Default::default() };
        let cands = price(&SerialComm, &model, &dec, &Common::default(), 2).unwrap();
        let counted = cands.iter().filter(|c| c.basis == Basis::Counted).count();
        assert!(cands.len() < 2 || counted >= 2, "{}", table(&cands, 2));
        assert_eq!(cheapest(&cands).unwrap().basis, Basis::Counted);
    }

    #[test]
    fn an_automatic_decomposition_is_fixed_to_the_cheapest() {
        let (model, _, _) = crate::feti::seed_fixture(8, 1);
        let mut dec = DecompositionSettings::default();
        let cands = resolve(&SerialComm, &model, &mut dec, &Common::default(), 1).unwrap().expect("automatic");
        let best = cheapest(&cands).unwrap();
        assert!(cands.iter().all(|c| c.time >= best.time));
        assert_eq!((dec.subdomains, dec.target_dofs), if best.tfeti { (None, best.target_dofs) } else { (Some(1), None) });
        // a scene that sets the decomposition is left alone
        let mut set = DecompositionSettings { subdomains: Some(4), ..Default::default() };
        assert!(resolve(&SerialComm, &model, &mut set, &Common::default(), 1).unwrap().is_none());
        assert_eq!(set.subdomains, Some(4));
    }
}
