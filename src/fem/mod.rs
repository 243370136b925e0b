//! Finite elements: the hex8, tet4/tet10 and wedge6 kernels (pure functions) and their
//! dispatch by cell and facet type ([`cell`]), the isotropic material, and the sparse assembly
//! of one body's stiffness with Dirichlet elimination.

pub mod assembly;
pub mod cell;
pub mod element;
pub mod material;
pub mod tet;
pub mod wedge;
