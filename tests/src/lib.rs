//! The kernels that Cohort's own test suites compile, snapshot and run on every backend.
//! Each module is one kernel (or one family) covering part of the language subset.

pub mod kernels;
pub mod variants;
