//! The studies that run the solver — Table 1, work–precision, the numerical-stability suite, the
//! TFETI benchmark, the coarse problem's cost and the primal SOCP reference (Clarabel) — kept
//! outside the solver core.

pub mod bench;
pub mod coarse_cost;
pub mod socp;
pub mod stability;
pub mod table1;
pub mod work_precision;
