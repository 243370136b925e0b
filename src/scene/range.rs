//! The magnitudes double precision carries through the whole computation: Young's modulus
//! (MPa), lengths (m: coordinates, element edges, radii), tractions, prescribed displacements
//! and slip bounds must lie in `[MIN, MAX]` = 1e-30 … 1e30 (0 where 0 means "none").
//!
//! Why this range: the arithmetic multiplies these inputs several deep. A stiffness entry is
//! ~ E·h (≤ 1e60 when E and h are), an element volume ~ h³ (≤ 1e90), a nodal load ~ p·h²
//! (≤ 1e90), a displacement ~ p·h/E, a dual operator entry ~ 1/(E·h); the Cholesky
//! factorization and every squared norm (‖b‖², ‖Ku − f‖², the Gram matrices) multiply two of
//! them and sum up to ~1e10 terms: ≤ 1e190 at the extremes, inside the 1e±308 of a double
//! (and far above its subnormal range 1e-308, so no residual or stopping test underflows to 0).
//! With E = 1e200 instead, E² already overflows and the solver stops at once with u = 0. The
//! range is still 30 orders of magnitude either side of SI or mm/MPa units.

/// The smallest magnitude allowed (other than 0 where 0 means "none").
pub const MIN: f64 = 1e-30;
/// The largest magnitude allowed.
pub const MAX: f64 = 1e30;
/// The smallest 1 − 2ν (and 1 + ν) allowed: λ = Eν/((1+ν)(1−2ν)) is then at most ~1e8·E
/// (≤ 1e38), and the stiffness's condition number grows by at most ~1e8 over a compressible
/// material's, which leaves digits to solve at ε = 1e-8 on the meshes this code runs; ν
/// nearer 1/2 gives a K that double precision cannot factorize meaningfully (at
/// 1 − 2ν ~ 1e-16 not even 1 − 2ν itself has a correct digit). ν = 0.4999 (the stability
/// suite's `run/stress/nu_04999.toml`) has 1 − 2ν = 2e-4.
pub const POISSON_MARGIN: f64 = 1e-8;
/// The largest ratio of an element's longest edge to its shortest: the stiffness's
/// condition number grows with its square (1e14 here, two digits left to solve at
/// ε = 1e-8). Measured on the seed's upper block thinned to t with 4 × 4 × 4 nodes (edges
/// 0.67 and t/3): ratios 2e6 and 2e7 solve, 2e8 fails in the Cholesky factorization.
pub const MAX_ASPECT: f64 = 1e7;

/// Whether `v` lies in [MIN, MAX] (or is 0, when `zero_ok`).
pub fn carries(v: f64, zero_ok: bool) -> bool {
    (zero_ok && v == 0.0) || (MIN..=MAX).contains(&v.abs())
}
