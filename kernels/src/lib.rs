//! The wavefront path tracer's kernels (the paper's §3), written in the Cohort language so
//! that each is one Rust source that also runs on the host.
//!
//! Data flow of one iteration (driven by the `cohort-render` crate):
//! `traverse` (closest hit of every live ray) → `extend::<S, E>` (shade, sample the next
//! direction with strategy `S`, or finish the path, as policy `E` says, and regenerate a
//! camera ray) →
//! with next-event estimation `trace_shadow*` (occlusion of each vertex's light sample;
//! adds it, and the estimate of each ended path to its pixel) →
//! `compact_*` (stable partition of `idrays`: extended rays first, regenerated last).
//! With ray reordering, `bin_*` (`reorder`) first sort the live rays by direction octant
//! and origin cell into the list the traversal alone reads.
//! A viewer (`cohort view`) runs `display` between iterations: the accumulation, tone-mapped.
//! Path state lives in structure-of-arrays buffers indexed by ray slot; slot `g` belongs
//! to pixel `slot_pixel[g]` (Morton order), and only `idrays` is ever reordered.
// Kernel source is Rust the macro lowers to shaders: a kernel's parameters are its bindings
// (many by design); an `if` on a compile-time constant (`I::NEE`) is resolved when the
// kernel is built and cannot be merged into a condition on GPU values.
#![allow(clippy::too_many_arguments, clippy::collapsible_if)]

pub mod bsdf;
pub mod compact;
pub mod copy;
pub mod display;
pub mod environment;
pub mod extend;
pub mod group_draw;
pub mod integrator;
pub mod layout;
pub mod light;
pub mod microfacet;
pub mod path_end;
pub mod perturb;
pub mod queues;
pub mod reorder;
pub mod retire;
pub mod rng;
pub mod sampling;
pub mod scatter;
pub mod shading;
pub mod shadow;
pub mod texture;
pub mod traverse;
pub mod traverse_cw;
pub mod traverse_stream;
pub mod traverse_wide;
pub mod validate;
mod words;
