//! Finite elements: the hex8 kernels and the tet4/tet10 kernels (pure functions), the isotropic
//! material, and the sparse assembly of one body's stiffness with Dirichlet elimination.

pub mod assembly;
pub mod element;
pub mod material;
pub mod tet;
