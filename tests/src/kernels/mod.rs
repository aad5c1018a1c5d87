//! One module per kernel (or kernel family); each doc comment says which part of the
//! language subset it covers.
// Test kernels are written as a new user writes kernels (index loops over buffers, the
// operations a test exercises, e.g. max-then-min, which differs from clamp on NaN).
#![allow(clippy::needless_range_loop, clippy::manual_clamp)]

pub mod bits;
pub mod collatz;
pub mod debug_print;
pub mod generic;
pub mod group_pick;
pub mod group_vote;
pub mod histogram;
pub mod mathfns;
pub mod numeric;
pub mod rays;
pub mod reduce;
pub mod saxpy;
pub mod sort4;
pub mod specialize;
pub mod stack_walk;
pub mod subgroup_scan;
pub mod vectors;
