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
    pub title: String,
    pub ranks: usize,
    /// Name and version of the MPI library.
    pub mpi: String,
    /// What was solved, in words.
    pub problem: String,
    /// The scene's units (length, force, stress), where it names them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub units: Option<UnitsReport>,
    pub tfeti: Option<TfetiReport>,
    /// The fill-reducing ordering of the factorizations.
    pub ordering: String,
    pub mesh: MeshReport,
    pub bodies: Vec<BodyStats>,
    pub results: Results,
    pub contact: Option<ContactReport>,
    pub solver: Option<SolverReport>,
    /// Wall time of each phase (max over the ranks), in the order they ran, and the total.
    pub timings: PhaseTimes,
    pub versions: serde_json::Value,
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

#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct MeshReport {
    pub nodes: usize,
    pub elements: usize,
    /// The cells by type, in words ("1000 hexahedra").
    #[serde(default)]
    pub cells: String,
    pub dofs: usize,
    /// DOFs not held by Dirichlet conditions (of `dofs`, each node once).
    pub free_dofs: usize,
    /// Under TFETI: the subdomains' DOFs summed (interface nodes once per copy, held DOFs
    /// included where they are multiplier rows).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub subdomain_dofs: Option<usize>,
}

#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Results {
    pub max_displacement: f64,
    pub max_displacement_node: usize,
    pub max_displacement_body: Option<String>,
    pub max_von_mises: f64,
}

/// The contact state at the solution.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ContactReport {
    pub pairs: usize,
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
    pub stick: usize,
    pub slip: usize,
    /// Of the `slip` pairs, those with ‖λ̄τ‖ on the slip bound; the others slide an ε-hair
    /// inside it (their slip explains them better than sticking would).
    pub on_slip_bound: usize,
    pub total_force_on_slave: [f64; 3],
}

/// The dual solve: the method, its counters and history ([`qp::Info`]), the KKT residuals.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct SolverReport {
    pub method: String,
    /// Length of the solvers' dual vector (over all ranks).
    pub dual_dim: usize,
    pub eps: f64,
    #[serde(flatten)]
    pub info: qp::Info,
    pub norm_b: f64,
    pub kkt: qp::kkt::Kkt,
    pub kkt_worst: f64,
    /// Where the accuracy guard tightened ε (`pipeline::accuracy`): the result at the scene's ε
    /// missed its checks and the solve went on from there.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub eps_tightened: Vec<super::accuracy::Tightening>,
}

/// What the TFETI path adds.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct TfetiReport {
    pub subdomains_per_body: Vec<usize>,
    pub gluing: Gluing,
    /// How the Dirichlet conditions are held (`decomposition.dirichlet`).
    #[serde(default)]
    pub dirichlet: DirichletMode,
    pub multipliers: Multipliers,
    /// Prescribed DOFs held inside their subdomains (over all copies): no multiplier rows.
    #[serde(default)]
    pub eliminated_dofs: usize,
    /// H-TFETI (`decomposition.subdomains_per_cluster`): clusters, and the rows of their B_c
    /// (face moments, held inside the clusters; as many clusters as subdomains and none without).
    #[serde(default)]
    pub clusters: usize,
    #[serde(default)]
    pub corner_rows: usize,
    pub coarse_dim: usize,
    #[serde(rename = "nnz_C_lower")]
    pub nnz_c: usize,
    /// `decomposition.coarse_solve`, and the bytes of C⁻¹'s (and (GGᵀ)⁻¹'s) rows the rank
    /// holding most holds when explicit.
    #[serde(default)]
    pub coarse_solve: CoarseSolve,
    #[serde(default)]
    pub coarse_explicit_bytes_max_rank: usize,
    /// max over nodes and copies of |u_copy − u_first| / max |u|.
    #[serde(rename = "gluing_jump_relative")]
    pub gluing_jump: f64,
    /// ‖Gλ − e‖/‖e‖ at the solution.
    #[serde(rename = "coarse_feasibility")]
    pub feasibility: f64,
    pub projector: Projector,
    pub smalse: Option<SmalseInfo>,
    pub distribution: DistributionStats,
    pub subdomains: Vec<SubdomainStats>,
}

/// Multipliers by kind.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Multipliers {
    pub contact: usize,
    pub gluing: usize,
    pub dirichlet: usize,
    /// Rows of tied interfaces (`[[tie]]`).
    #[serde(default)]
    pub tie: usize,
}

#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Memory {
    pub peak_rss_bytes_sum_over_ranks: f64,
    pub peak_rss_bytes_max_rank: f64,
    /// The peak so far at the end of each phase (max over the ranks): where the memory grows.
    #[serde(default)]
    pub peak_rss_bytes_max_rank_after_phase: Vec<PhasePeak>,
}

/// [`Memory::peak_rss_bytes_max_rank_after_phase`]'s entries, in the order the phases ran.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct PhasePeak {
    pub phase: String,
    pub bytes: f64,
}

/// Phase times in the order they ran, written as a map with a `total`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhaseTimes(pub Vec<(String, f64)>);

impl PhaseTimes {
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
    pub length: Option<String>,
    pub force: Option<String>,
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
