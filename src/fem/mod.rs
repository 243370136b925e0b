//! Finite elements: the hex8, tet4/tet10, wedge6, pyr5 and quadratic hex20/hex27/wedge15 kernels (pure functions) and their
//! dispatch by cell type ([`cell`]), the reference facets (shape functions, quadrature,
//! facet integrals; [`facet`]), the isotropic material, and the sparse assembly
//! of one body's stiffness with Dirichlet elimination.

pub mod assembly;
pub mod cell;
pub mod element;
pub(crate) mod facet;
pub mod material;
pub mod pyramid;
pub mod quadratic;
pub mod tet;
pub mod wedge;
