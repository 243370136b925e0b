//! tresca-feti: a TFETI solver for 3D linear-elastic contact with Tresca friction.
//!
//! Data flows one way (docs/method.md, "Code layout"): [`scene`] (TOML, every settings enum) → [`model`] ([`mesh`]:
//! boxes, Gmsh; [`contact`]: pairs and slip bounds) → [`fem`] (hex8 kernels, assembly) →
//! [`linalg`] → the dual problem ([`dual`]: monolithic; [`feti`]: TFETI) → [`qp`] (the solvers,
//! the floor of the crate: it imports nothing of the rest) → back to the primal solution, the
//! contact state and [`output`] (HDF5 + XDMF + JSON), all run by [`pipeline`] (named, timed
//! phases, one post-solve path, the typed report, the live monitor). All collective
//! communication goes through [`comm`]. The studies that run the solver (Table 1,
//! work–precision, the numerical-stability suite, the TFETI benchmark, the primal SOCP
//! reference) live apart, in [`studies`]; `tests/layout.rs` checks that the module graph has no
//! cycle.

#![warn(missing_docs)]

pub mod comm;
pub mod contact;
pub mod dual;
pub(crate) mod error;
pub mod fem;
pub(crate) mod feti;
pub mod linalg;
pub mod mesh;
pub mod model;
pub mod output;
pub mod pipeline;
pub mod qp;
pub mod scene;
pub mod studies;

pub use error::{Error, Result};

/// Version of this crate and of its main dependencies.
pub fn versions() -> serde_json::Value {
    let (a, b, c) = ::hdf5::library_version();
    serde_json::json!({
        "tresca-feti": env!("CARGO_PKG_VERSION"),
        "dependencies": env!("TRESCA_DEP_VERSIONS"),
        "hdf5": format!("{a}.{b}.{c}"),
    })
}
