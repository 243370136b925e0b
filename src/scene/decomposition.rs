//! `[decomposition]` and `[factorization]`: how the bodies are split into subdomains (TFETI,
//! H-TFETI), glued and held, and how the factors are ordered.

use serde::{Deserialize, Serialize};

use super::{one, yes};

/// How each body is split (TFETI, docs/method.md, "TFETI and H-TFETI"): the `[decomposition]` table.
#[derive(Clone, Debug, Deserialize, Serialize)]
// `rename`: the messages for a malformed table keep saying "expected struct Decomposition"
#[serde(deny_unknown_fields, rename = "Decomposition")]
pub struct DecompositionSettings {
    /// METIS subdomains per body. 1 is the monolithic dual (Dirichlet eliminated, no gluing,
    /// no coarse problem) unless `tfeti = true`. Absent (with `target_dofs`): chosen by cost
    /// (`pipeline::plan`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub subdomains: Option<usize>,
    /// Instead of `subdomains`: as many subdomains per body as give about this many DOFs each.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_dofs: Option<usize>,
    /// TFETI even with one subdomain per body (all floating, Dirichlet as multiplier rows).
    #[serde(default)]
    pub tfeti: bool,
    /// Gluing rows of the interface DOFs.
    #[serde(default)]
    pub gluing: Gluing,
    /// How TFETI holds the Dirichlet conditions: multiplier rows on every copy, or eliminated
    /// inside the subdomains that carry them (hybrid).
    #[serde(default)]
    pub dirichlet: DirichletMode,
    /// How Gλ = e is kept: the oblique projector P̃ (one QP solve) or the orthogonal one with
    /// SMALSE-M's augmented-Lagrangian loop around the QP solver.
    #[serde(default)]
    pub projector: Projector,
    /// SMALSE-M's penalty ϱ as a multiple of σ_max(PFP) (orthogonal projector only).
    #[serde(default = "unit")]
    pub penalty: f64,
    /// A body held by contact alone: TSSN keeps Gλ = e itself on each Newton step's subspace W
    /// (the start closed onto it, the Lagrangian's gradient with the rigid amplitudes α the free
    /// rows fix) instead of SMALSE-M's augmented-Lagrangian loop (a step whose rows cannot hold
    /// the body goes to SMALSE-M). Default true; false: SMALSE-M always.
    #[serde(default = "yes")]
    pub restricted: bool,
    /// The inner CG (TSSN's, plain CG's) runs projected onto Ker G ∩ W, W a Newton step's
    /// subspace, with the orthogonal projector of G = RᵀBᵀ restricted to W (oblique projector
    /// only); the FETI preconditioner acts there. Default true.
    #[serde(default = "yes")]
    pub projected_cg: bool,
    /// H-TFETI: subdomains per cluster (METIS on each body's subdomain graph); a cluster's
    /// subdomains are joined at a few corner nodes inside it and the coarse problem has six
    /// unknowns per cluster. 1 (default): TFETI.
    #[serde(default = "one")]
    pub subdomains_per_cluster: usize,
    /// How the coarse problems C = G_E G_Eᵀ (and SMALSE-M's GGᵀ) are solved: factorized on
    /// every rank, or as the rows of their inverses each rank reads (TSSN's restricted GΠGᵀ
    /// stays factorized).
    #[serde(default)]
    pub coarse_solve: CoarseSolve,
}

fn unit() -> f64 {
    1.0
}

impl Default for DecompositionSettings {
    fn default() -> Self {
        DecompositionSettings {
            subdomains: None,
            target_dofs: None,
            tfeti: false,
            gluing: Default::default(),
            dirichlet: Default::default(),
            projector: Default::default(),
            penalty: 1.0,
            restricted: true,
            projected_cg: true,
            subdomains_per_cluster: 1,
            coarse_solve: CoarseSolve::Factor,
        }
    }
}

impl DecompositionSettings {
    /// Subdomains for a body with `dofs` DOFs.
    pub fn parts(&self, dofs: usize) -> usize {
        match (self.target_dofs, self.subdomains) {
            (Some(t), _) => dofs.div_ceil(t).max(1),
            (None, Some(s)) => s,
            // automatic: fixed by cost before anything is assembled (`pipeline::plan`)
            (None, None) => 1,
        }
    }

    /// Whether bodies of `body_dofs` DOFs are solved by TFETI (else by the monolithic dual).
    pub fn is_tfeti(&self, body_dofs: &[usize]) -> bool {
        self.tfeti || body_dofs.iter().any(|&d| self.parts(d) > 1)
    }
}

/// How the copies of an interface DOF are glued.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Gluing {
    /// `orthonormal` (the default): an orthonormal basis of gluing rows per node.
    #[default]
    Orthonormal,
    /// `chain`: ±1 chains.
    Chain,
}

/// See [`DecompositionSettings::dirichlet`].
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum DirichletMode {
    /// One multiplier row per held DOF of every copy: every subdomain floating (total FETI).
    Multipliers,
    /// Held inside the subdomains that carry them: the held DOFs leave K_s, its kernel keeps
    /// the rigid motions they leave free (a subdomain that holds one only weakly keeps its rows).
    #[default]
    Eliminated,
}

/// See [`DecompositionSettings::projector`].
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Projector {
    /// `oblique` (the default): Gλ = e kept by the oblique projector P̃.
    #[default]
    Oblique,
    /// `orthogonal`: SMALSE-M's augmented Lagrangian with the orthogonal projector (taken
    /// automatically for a body held by contact alone).
    Orthogonal,
}

/// See [`DecompositionSettings::coarse_solve`].
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum CoarseSolve {
    /// Every rank factorizes C and solves with the whole factor (replicated).
    #[default]
    Factor,
    /// Every rank holds the rows of C⁻¹ of its own pieces, computed once from the factor,
    /// which is then dropped: a solve is those dense rows times the reduced G x, and one more
    /// reduction of the result.
    Explicit,
}

/// Fill-reducing ordering of the sparse Cholesky factorizations.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum OrderingKind {
    /// METIS nested dissection of the node graph, expanded to the DOFs.
    #[default]
    Metis,
    /// faer's approximate minimum degree.
    Amd,
}

/// `[factorization]`: the sparse Cholesky factorizations.
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Factorization {
    /// Fill-reducing ordering; default `metis`.
    #[serde(default)]
    pub ordering: OrderingKind,
}
