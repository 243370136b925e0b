//! `[solver]`: the QP method, the settings every method reads and each method's own, the FETI
//! preconditioner and the products' precision.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::qp;

pub use crate::qp::{CgStop, Method};

/// The FETI preconditioner of the TFETI dual (`solver.preconditioner`; where it applies is
/// decided by `pipeline::preconditioner`).
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Preconditioner {
    /// Dirichlet for the plain CG of a TFETI scene without contact, none elsewhere.
    #[default]
    Auto,
    /// No preconditioner.
    None,
    /// K_s's block on the DOFs the rows touch.
    Lumped,
    /// The diagonal of that block (superlumped).
    Superlumped,
    /// The Schur complement of K_s onto those DOFs, applied through a K_ii solve.
    Dirichlet,
    /// The same Schur complement held as a dense matrix (from a partial factorization).
    DirichletDense,
}

impl Preconditioner {
    /// The name `solver.preconditioner` takes (`"dirichlet-dense"`, …).
    pub fn name(self) -> &'static str {
        match self {
            Preconditioner::Auto => "auto",
            Preconditioner::None => "none",
            Preconditioner::Lumped => "lumped",
            Preconditioner::Superlumped => "superlumped",
            Preconditioner::Dirichlet => "dirichlet",
            Preconditioner::DirichletDense => "dirichlet-dense",
        }
    }
}

/// How the A-products use the factors (`solver.precision`).
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Precision {
    /// A contact solve keeps the factors also in single precision, and its inner CG iterations
    /// use them where their measured error is within what the iteration allows.
    #[default]
    Mixed,
    /// Double precision only.
    Double,
}

impl Precision {
    /// The name `solver.precision` takes (`"mixed"`, `"double"`).
    pub fn name(self) -> &'static str {
        match self {
            Precision::Mixed => "mixed",
            Precision::Double => "double",
        }
    }
}

/// The `[solver]` table: `method`, the settings every method reads ([`qp::Common`]), the
/// method's own ([`qp::MethodParams`]: a key the method does not read is an error) and the
/// FETI preconditioner and the products' precision. Defaults live with the solvers' parameter
/// structs.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverSettings {
    /// The method and its parameters: the settings every method reads and the method's own.
    pub params: qp::Params,
    /// `solver.preconditioner`: the FETI preconditioner (TFETI only); default `auto`.
    pub preconditioner: Preconditioner,
    /// `solver.precision`: how a contact solve's A-products use the factors; default `mixed`.
    pub precision: Precision,
    /// `method` absent (or `"auto"`): the method is chosen for the dual the scene is solved on
    /// (`pipeline::resolve_method`); `params` holds the default method's defaults until then.
    pub auto: bool,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings { params: qp::Params::default(), preconditioner: Preconditioner::Auto, precision: Precision::default(), auto: true }
    }
}

impl SolverSettings {
    /// Reads the `[solver]` table; errors name the key (`solver.<key>`).
    pub fn from_table(mut t: toml::Table) -> Result<Self> {
        fn value<T: serde::de::DeserializeOwned>(key: &str, v: toml::Value) -> Result<T> {
            serde_path_to_error::deserialize(v).map_err(|e| {
                let sub = e.path().to_string();
                let key = if sub == "." { format!("solver.{key}") } else { format!("solver.{sub}") };
                Error::scene(key, e.inner().message().replace('\n', " "))
            })
        }
        let auto = match t.get("method") {
            None => true,
            Some(toml::Value::String(m)) => m == "auto",
            Some(_) => false,
        };
        let method: Method = match t.remove("method") {
            Some(v) if !auto => value("method", v).map_err(|e| match e {
                Error::Scene { key, msg } => Error::Scene { key, msg: format!("{msg}, or `auto` (the default)") },
                e => e,
            })?,
            _ => Method::default(),
        };
        let preconditioner = t.remove("preconditioner").map_or(Ok(Preconditioner::Auto), |v| value("preconditioner", v))?;
        let precision = t.remove("precision").map_or(Ok(Precision::default()), |v| value("precision", v))?;
        let common_keys = Self::common_keys();
        let (common, own): (toml::Table, toml::Table) = t.into_iter().partition(|(k, _)| common_keys.contains(k));
        if let (true, Some(key)) = (auto, own.keys().next()) {
            return Err(Error::scene(
                format!("solver.{key}"),
                format!(
                    "not a setting every method reads ({}); name the method whose setting it is (solver.method), the automatic choice takes its defaults",
                    common_keys.join(", ")
                ),
            ));
        }
        let common: qp::Common = value("", toml::Value::Table(common))?;
        let mut track = serde_path_to_error::Track::new();
        let own = qp::MethodParams::deserialize(method, serde_path_to_error::Deserializer::new(toml::Value::Table(own), &mut track)).map_err(|e| {
            let msg = e.message().replace('\n', " ");
            match msg.strip_prefix("unknown field `").and_then(|r| r.split_once('`')) {
                Some((key, rest)) => {
                    let its = rest.trim_start_matches(", ").replace("expected one of ", "").replace("expected ", "");
                    let its = if its.contains("no fields") { "none".to_string() } else { its };
                    Error::scene(
                        format!("solver.{key}"),
                        format!("not a setting of method \"{}\" (its own: {its}; every method's: {})", method.name(), common_keys.join(", ")),
                    )
                }
                None => Error::scene(format!("solver.{}", track.path()), msg),
            }
        })?;
        let params = qp::Params { common, method: own };
        params.validate().map_err(|e| Error::scene(format!("solver.{}", e.key), e.msg))?;
        Ok(SolverSettings { params, preconditioner, precision, auto })
    }

    /// The keys of [`qp::Common`].
    fn common_keys() -> Vec<String> {
        toml::Table::try_from(qp::Common::default()).map(|t| t.keys().cloned().collect()).unwrap_or_default()
    }

    /// The table as [`SolverSettings::from_table`] reads it.
    pub fn to_table(&self) -> toml::Table {
        let mut t = toml::Table::new();
        t.insert("method".into(), if self.auto { "auto" } else { self.params.method().name() }.into());
        t.extend(toml::Table::try_from(&self.params.common).unwrap_or_default());
        if !self.auto {
            t.extend(toml::Table::try_from(&self.params.method).unwrap_or_default());
        }
        if self.preconditioner != Preconditioner::Auto {
            t.insert("preconditioner".into(), self.preconditioner.name().into());
        }
        if self.precision != Precision::default() {
            t.insert("precision".into(), self.precision.name().into());
        }
        t
    }
}

impl Serialize for SolverSettings {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        self.to_table().serialize(s)
    }
}
