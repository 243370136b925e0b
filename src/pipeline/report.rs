//! The typed report of a solve: what `solve` writes to the JSON file and to the HDF5 file's
//! `report` attribute, and what the studies and the summary read (fields, not strings).

use serde::{Deserialize, Serialize};

use super::tfeti::{DistributionStats, SubdomainStats};
use super::BodyStats;
use crate::feti::smalse::SmalseInfo;
use crate::qp;
use crate::scene::{CoarseSolve, DirichletMode, Gluing, Projector};

/// Everything a solve reports.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Report {
    /// The scene file.
    pub scene: String,
    /// The scene's `title`.
    pub title: String,
    /// MPI ranks the solve ran on.
    pub ranks: usize,
    /// Name and version of the MPI library.
    pub mpi: String,
    /// What was solved, in words.
    pub problem: String,
    /// The scene's units (length, force, stress), where it names them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub units: Option<UnitsReport>,
    /// What the TFETI path adds (none on the monolithic dual).
    pub tfeti: Option<TfetiReport>,
    /// The fill-reducing ordering of the factorizations.
    pub ordering: String,
    /// Size of the whole mesh.
    pub mesh: MeshReport,
    /// Figures of each body's linear solve.
    pub bodies: Vec<BodyStats>,
    /// Maxima of the displacement and the von Mises stress.
    pub results: Results,
    /// The contact state at the solution (none without contact).
    pub contact: Option<ContactReport>,
    /// The dual solve (none without contact on the monolithic dual).
    pub solver: Option<SolverReport>,
    /// Wall time of each phase (max over the ranks), in the order they ran, and the total.
    pub timings: PhaseTimes,
    /// Version of this crate and of its main dependencies ([`crate::versions`]).
    pub versions: serde_json::Value,
    /// Peak resident memory (VmHWM) of the ranks.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub memory: Option<Memory>,
    /// The priced decompositions when the scene left `[decomposition]` to the cost model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decomposition_plan: Option<Vec<super::plan::Candidate>>,
    /// Every step of a load path (`[load] steps` > 1); `solver` and `contact` are the last's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load_path: Option<Vec<super::path::StepReport>>,
    /// A load path cut short: the step without equilibrium and why (the steps before it are
    /// `load_path`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path_stopped: Option<String>,
    /// Values read back and checked (`output.verify`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output_verified_values: Option<u64>,
    /// `solver.precision = "mixed"`: η, the relative error of the dual operator's product with
    /// the single-precision factors (measured once on a probe vector).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub single_precision_error: Option<f64>,
    /// The monolithic dual's products through the factors' trailing blocks (contact nodes
    /// ordered last): the contact DOFs of all blocks.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub explicit_products: Option<usize>,
}

/// Size of the whole mesh.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct MeshReport {
    /// Nodes of the mesh.
    pub nodes: usize,
    /// Elements of the mesh.
    pub elements: usize,
    /// The cells by type, in words ("1000 hexahedra").
    #[serde(default)]
    pub cells: String,
    /// DOFs of the mesh: 3 per node.
    pub dofs: usize,
    /// DOFs not held by Dirichlet conditions (of `dofs`, each node once).
    pub free_dofs: usize,
    /// Under TFETI: the subdomains' DOFs summed (interface nodes once per copy, held DOFs
    /// included where they are multiplier rows).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub subdomain_dofs: Option<usize>,
}

/// Maxima of the computed fields over the whole mesh.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Results {
    /// Largest displacement magnitude ‖u‖ over the nodes.
    pub max_displacement: f64,
    /// Node (global index) where ‖u‖ is largest.
    pub max_displacement_node: usize,
    /// Body holding that node.
    pub max_displacement_body: Option<String>,
    /// Largest von Mises stress over the elements.
    pub max_von_mises: f64,
}

/// The contact state at the solution.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ContactReport {
    /// Contact pairs (slave nodes with a master facet).
    pub pairs: usize,
    /// Open pairs.
    pub open: usize,
    /// Closed pairs without friction (neither stick nor slip).
    #[serde(default)]
    pub contact: usize,
    /// Slave nodes outside the contact zone (no master facet within reach: no pair).
    #[serde(default)]
    pub outside: usize,
    /// The lines that name them, and the warnings about them ([`super::outside_lines`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    /// Sticking pairs.
    pub stick: usize,
    /// Slipping pairs.
    pub slip: usize,
    /// Of the `slip` pairs, those with ‖λ̄τ‖ on the slip bound; the others slide an ε-hair
    /// inside it (their slip explains them better than sticking would).
    pub on_slip_bound: usize,
    /// Total force the contact exerts on the slave bodies (global x, y, z).
    pub total_force_on_slave: [f64; 3],
}

/// The dual solve: the method, its counters and history ([`qp::Info`]), the KKT residuals.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct SolverReport {
    /// The dual method that ran (`coulomb-newton`, `coulomb-lagged` for Coulomb solves, `cg` for TFETI without contact).
    pub method: String,
    /// Length of the solvers' dual vector (over all ranks).
    pub dual_dim: usize,
    /// The stopping tolerance ε (`solver.eps`).
    pub eps: f64,
    /// The solver's counters and history.
    #[serde(flatten)]
    pub info: qp::Info,
    /// ‖b‖ of the dual right-hand side.
    pub norm_b: f64,
    /// The KKT residuals at the solution.
    pub kkt: qp::kkt::Kkt,
    /// The largest of the KKT residuals ([`qp::kkt::Kkt::worst`]; 0 without contact).
    pub kkt_worst: f64,
    /// Where the accuracy guard tightened ε (`pipeline::accuracy`): the result at the scene's ε
    /// missed its checks and the solve went on from there.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub eps_tightened: Vec<super::accuracy::Tightening>,
}

/// What the TFETI path adds.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct TfetiReport {
    /// Subdomains of each body, in body order.
    pub subdomains_per_body: Vec<usize>,
    /// How the subdomains' interface copies are glued (`decomposition.gluing`).
    pub gluing: Gluing,
    /// How the Dirichlet conditions are held (`decomposition.dirichlet`).
    #[serde(default)]
    pub dirichlet: DirichletMode,
    /// Rows of B by kind.
    pub multipliers: Multipliers,
    /// Prescribed DOFs held inside their subdomains (over all copies): no multiplier rows.
    #[serde(default)]
    pub eliminated_dofs: usize,
    /// H-TFETI (`decomposition.subdomains_per_cluster`): clusters, and the rows of their B_c
    /// (face moments, held inside the clusters; as many clusters as subdomains and none without).
    #[serde(default)]
    pub clusters: usize,
    /// H-TFETI: gluing rows of the clusters' corner nodes (held inside the clusters).
    #[serde(default)]
    pub corner_rows: usize,
    /// Size of the coarse problem: the rows of G (k_s per subdomain).
    pub coarse_dim: usize,
    /// Nonzeros of the lower triangle of the coarse matrix C.
    #[serde(rename = "nnz_C_lower")]
    pub nnz_c: usize,
    /// `decomposition.coarse_solve`, and the bytes of C⁻¹'s (and (GGᵀ)⁻¹'s) rows the rank
    /// holding most holds when explicit.
    #[serde(default)]
    pub coarse_solve: CoarseSolve,
    /// Bytes of explicit coarse-inverse rows on the rank holding most (0 with the factor).
    #[serde(default)]
    pub coarse_explicit_bytes_max_rank: usize,
    /// max over nodes and copies of |u_copy − u_first| / max |u|.
    #[serde(rename = "gluing_jump_relative")]
    pub gluing_jump: f64,
    /// ‖Gλ − e‖/‖e‖ at the solution.
    #[serde(rename = "coarse_feasibility")]
    pub feasibility: f64,
    /// The projector onto Ker G (`decomposition.projector`).
    pub projector: Projector,
    /// SMALSE-M's outer loop (orthogonal projector only).
    pub smalse: Option<SmalseInfo>,
    /// How the dual vectors and the A-products' work are spread over the ranks.
    pub distribution: DistributionStats,
    /// Figures of each subdomain.
    pub subdomains: Vec<SubdomainStats>,
}

/// Multipliers by kind.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Multipliers {
    /// Contact rows of B.
    pub contact: usize,
    /// Gluing rows between subdomains.
    pub gluing: usize,
    /// Dirichlet rows (prescribed DOFs held by multipliers).
    pub dirichlet: usize,
    /// Rows of tied interfaces (`[[tie]]`).
    #[serde(default)]
    pub tie: usize,
}

/// Peak resident memory (VmHWM), in bytes.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Memory {
    /// Sum over the ranks of each rank's peak.
    pub peak_rss_bytes_sum_over_ranks: f64,
    /// The largest peak of a rank.
    pub peak_rss_bytes_max_rank: f64,
    /// The peak so far at the end of each phase (max over the ranks): where the memory grows.
    #[serde(default)]
    pub peak_rss_bytes_max_rank_after_phase: Vec<PhasePeak>,
}

/// [`Memory::peak_rss_bytes_max_rank_after_phase`]'s entries, in the order the phases ran.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct PhasePeak {
    /// Name of the phase.
    pub phase: String,
    /// Peak resident memory at its end (max over the ranks), in bytes.
    pub bytes: f64,
}

/// Phase times in the order they ran, written as a map with a `total`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhaseTimes(pub Vec<(String, f64)>);

impl PhaseTimes {
    /// Sum of the phase times, in seconds.
    pub fn total(&self) -> f64 {
        self.0.iter().map(|p| p.1).sum()
    }

    /// The time of phase `name` (0 when it did not run).
    pub fn get(&self, name: &str) -> f64 {
        self.0.iter().filter(|p| p.0 == name).map(|p| p.1).sum()
    }
}

impl Serialize for PhaseTimes {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(self.0.len() + 1))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.serialize_entry("total", &self.total())?;
        m.end()
    }
}

impl<'de> Deserialize<'de> for PhaseTimes {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let m = serde_json::Map::<String, serde_json::Value>::deserialize(d)?;
        Ok(PhaseTimes(m.into_iter().filter(|(k, _)| k != "total").map(|(k, v)| (k, v.as_f64().unwrap_or(0.0))).collect()))
    }
}

/// The pairs' states in words: "3 open, 20 stick, 2 slip", "3 open, 22 in contact" (no
/// friction), "3 open, 10 in contact, 8 stick, 4 slip" (both kinds of pairs).
pub fn counts(open: usize, contact: usize, stick: usize, slip: usize) -> String {
    let mut s = format!("{open} open");
    if contact > 0 {
        s += &format!(", {contact} in contact");
    }
    if contact == 0 || stick + slip > 0 {
        s += &format!(", {stick} stick, {slip} slip");
    }
    s
}

/// The units results are printed in: the scene's `units`, and the stress unit they make.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct UnitsReport {
    /// Unit of length.
    pub length: Option<String>,
    /// Unit of force.
    pub force: Option<String>,
    /// Unit of stress the length and force units make.
    pub stress: Option<String>,
}

impl UnitsReport {
    /// The scene's `units`, none where it names neither.
    pub fn of(units: &crate::scene::Units) -> Option<UnitsReport> {
        (!units.is_empty()).then(|| UnitsReport { length: units.length.clone(), force: units.force.clone(), stress: units.stress() })
    }

    /// " mm" after a length, "" where the scene names no length unit (`which`: 0 length,
    /// 1 force, 2 stress, 3 area).
    pub fn suffix(units: Option<&UnitsReport>, which: usize) -> String {
        let u = units.and_then(|u| match which {
            3 => u.length.as_ref().map(|l| format!("{l}²")),
            _ => [&u.length, &u.force, &u.stress][which].clone(),
        });
        u.map_or(String::new(), |u| format!(" {u}"))
    }
}

/// The contact problem in words from each pair entry's law ([`crate::contact::pairing::Contact::laws`]):
/// "frictionless contact", "contact with Coulomb friction", or each entry's where they differ.
pub fn contact_phrase(laws: &[(usize, &str)]) -> String {
    match laws.first() {
        Some(&(_, first)) if laws.iter().all(|l| l.1 == first) => {
            if first == "frictionless" {
                "frictionless contact".into()
            } else {
                format!("contact with {first} friction")
            }
        }
        _ => format!("contact: {}", laws.iter().map(|(e, l)| format!("pair {e} {l}")).collect::<Vec<_>>().join(", ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_contact_phrase_names_each_law() {
        assert_eq!(contact_phrase(&[(0, "frictionless")]), "frictionless contact");
        assert_eq!(contact_phrase(&[(0, "Tresca"), (1, "Tresca")]), "contact with Tresca friction");
        assert_eq!(contact_phrase(&[(0, "Coulomb"), (1, "frictionless")]), "contact: pair 0 Coulomb, pair 1 frictionless");
        assert_eq!(counts(3, 22, 0, 0), "3 open, 22 in contact");
        assert_eq!(counts(3, 0, 20, 2), "3 open, 20 stick, 2 slip");
        assert_eq!(counts(1, 2, 3, 4), "1 open, 2 in contact, 3 stick, 4 slip");
    }
}
