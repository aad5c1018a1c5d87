//! The end of an iteration with next-event estimation: after `extend` has shaded a vertex
//! and drawn a light sample, the shadow pass (`trace_shadow8`, or `trace_shadow` over the
//! BVH2) tests the sample's shadow ray and finishes the slot here: the unoccluded sample
//! joins the path's radiance, and a path that ended at this vertex adds its estimate to
//! its pixel. Accumulating only here keeps every path's light samples in its own estimate,
//! so a pixel's mean is over whole paths, whenever the run stops.

use crate::layout::*;
use cohort::prelude::*;

/// Finishes slot `r` after its shadow ray: `status` is `SLOT_CONTINUES` or `SLOT_ENDED`,
/// `ld` the light sample's contribution, counted when `visible`.
#[kernel_fn]
pub fn finish_slot(
    r: u32,
    status: f32,
    ld: Vec3,
    visible: bool,
    radiance: &mut [Vec4],
    accum: &mut [Vec4],
) {
    let ri = r as usize;
    let r4 = radiance[ri];
    let mut l = r4.truncate();
    if visible {
        l += ld;
    }
    if status == SLOT_ENDED {
        accum[ri] = accum[ri] + l.extend(1.0);
        radiance[ri] = Vec4::ZERO;
    } else {
        radiance[ri] = l.extend(r4.w);
    }
}
