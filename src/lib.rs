//! tresca-feti: a TFETI solver for 3D linear-elastic contact with Tresca friction.
//!
//! Data flows one way, one module per stage:
//! [`scene`] (TOML) → [`model`] ([`mesh`]: boxes, Gmsh) → [`fem`] (hex8 kernels, assembly) →
//! [`linalg`] (METIS ordering, sparse Cholesky) → [`pipeline`] (named, timed phases) →
//! [`output`] (HDF5 + XDMF + JSON). All collective communication goes through [`comm`].

pub mod bench;
pub mod comm;
pub mod contact;
pub mod decomposition;
pub mod dual;
pub mod error;
pub mod feti;
pub mod fem;
pub mod linalg;
pub mod mesh;
pub mod model;
pub mod output;
pub mod pipeline;
pub mod qp;
pub mod recovery;
pub mod scene;
pub mod socp;
pub mod stress;
pub mod table1;
pub mod workprecision;

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
