//! Deterministic random numbers: a function of (pixel, path index, bounce, dimension,
//! frame seed) only, so runs are reproducible and both backends (and the host) draw the
//! same numbers.

use cohort::prelude::*;

/// lowbias32, a 32-bit integer hash with good avalanche.
#[kernel_fn]
pub fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846ca68b);
    x ^= x >> 16;
    x
}

/// The random stream key of one path vertex.
#[kernel_fn]
pub fn stream(seed: u32, pixel: u32, path: u32, bounce: u32) -> u32 {
    hash(
        seed ^ hash(
            pixel ^ hash(path.wrapping_mul(0x9e3779b9) ^ hash(bounce.wrapping_add(0x632be5ab))),
        ),
    )
}

/// Uniform number in [0, 1) for dimension `dim` of a stream.
#[kernel_fn]
pub fn uniform(key: u32, dim: u32) -> f32 {
    (hash(key ^ dim.wrapping_mul(0x68e31da4)) >> 8) as f32 * (1.0 / 16777216.0)
}
