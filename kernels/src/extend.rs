//! Path extension (PAPER.md §3 kernel 1) and camera-ray generation.
//!
//! For each live ray: add the emission it reached (implicit path tracing: a path
//! contributes when it hits an emitter or leaves the scene), then either continue the
//! path with a new direction sampled from the BSDF (diffuse bounces through the
//! strategy `S`) or, when it escaped, was absorbed or lost Russian roulette, add its
//! estimate to its pixel and regenerate a fresh camera ray for the same pixel (path
//! regeneration, Novak et al. 2010). `flags[i]` records which, for compaction.

use crate::layout::*;
use crate::path_end::PathEnd;
use crate::rng::{hash, stream, uniform};
use crate::sampling::{cell_point, fresnel_dielectric, ggx_vndf, smith_g1, DiffuseSampler};
use cohort::prelude::*;

/// Camera ray through a random point of `pixel`: origin in xyz (w = tmin), direction.
#[kernel_fn]
pub fn camera_dir(f: &Frame, pixel: u32, key: u32) -> Vec3 {
    let px = (pixel % f.width) as f32 + uniform(key, 0);
    let py = (pixel / f.width) as f32 + uniform(key, 1);
    let sx = px / f.width as f32;
    let sy = py / f.height as f32;
    (f.cam_forward + f.cam_right * (2.0 * sx - 1.0) + f.cam_up * (1.0 - 2.0 * sy)).normalize()
}

/// Starts every slot: first camera ray, empty estimate, identity order.
#[kernel(workgroup = 64)]
pub fn init_paths(
    #[builtin(global_index)] gi: u32,
    f: &Frame,
    slot_pixel: &[u32],
    idrays: &mut [u32],
    state: &mut [UVec4],
    ray_o: &mut [Vec4],
    ray_d: &mut [Vec4],
    beta: &mut [Vec4],
    radiance: &mut [Vec4],
    accum: &mut [Vec4],
) {
    let g = gi as usize;
    if gi >= f.slots {
        return;
    }
    let pixel = slot_pixel[g];
    let d = camera_dir(f, pixel, stream(f.seed, pixel, 0, 0));
    idrays[g] = gi;
    state[g] = UVec4::new(pixel, 0, 0, 0);
    ray_o[g] = Vec4::new(f.cam_origin.x, f.cam_origin.y, f.cam_origin.z, 0.0);
    ray_d[g] = Vec4::new(d.x, d.y, d.z, 0.0);
    beta[g] = Vec4::ONE;
    radiance[g] = Vec4::ZERO;
    accum[g] = Vec4::ZERO;
}

/// Offset along the normal that keeps a new ray off the surface it leaves, scaled with
/// the hit point's magnitude.
#[kernel_fn]
pub fn offset_origin(p: Vec3, n: Vec3) -> Vec3 {
    let scale = 1e-4 * (1.0 + p.abs().max_element());
    p + n * scale
}

#[kernel(workgroup = 64)]
pub fn extend<S: DiffuseSampler, E: PathEnd>(
    #[builtin(global_index)] gi: u32,
    #[builtin(local_index)] li: u32,
    #[workgroup] wg_done: &mut [AtomicU32; 2],
    f: &Frame,
    count: &[u32],
    idrays: &[u32],
    hits: &[Vec4],
    tris: &[Triangle],
    materials: &[Material],
    state: &mut [UVec4],
    ray_o: &mut [Vec4],
    ray_d: &mut [Vec4],
    beta: &mut [Vec4],
    radiance: &mut [Vec4],
    accum: &mut [Vec4],
    flags: &mut [u32],
    completed: &[AtomicU32],
) {
    // The group's shared draws come first, in uniform control flow: the patch of
    // coherent sampling and the group's Russian-roulette number.
    let shared_patch = group_share(|group| S::group_value(stream(f.seed, group, f.iteration, 0x5eed), f.patches_n));
    // x: the group's Russian-roulette number (`_rr`); y: its whole-group-end number.
    let shared_rr = group_share(|group| {
        let k = stream(f.seed ^ 0x2b5e, group, f.iteration, 0x7a11);
        Vec2::new(uniform(k, 0), uniform(k, 1))
    });
    let shared_cell = group_share(|group| hash(stream(f.seed ^ 0x61c8, group, f.iteration, 0x9e37)));
    // Completed paths are counted per workgroup and added to the global counters once
    // per workgroup: one global atomic per path serialised on a single address.
    if li == 0 {
        wg_done[0].store(0, Ordering::Relaxed);
        wg_done[1].store(0, Ordering::Relaxed);
    }
    workgroup_barrier();
    // Phase 1: shade and decide per path. What phase 2 needs outlives the branch, because
    // the group may vote in between, which every invocation must reach.
    let i = gi as usize;
    let mut r = 0usize;
    let mut active = false;
    let mut alive = false;
    let mut pixel = 0u32;
    let mut path = 0u32;
    let mut bounce = 0u32;
    let mut thr = Vec3::ZERO;
    let mut l = Vec3::ZERO;
    let mut new_o = Vec3::ZERO;
    let mut new_d = Vec3::ZERO;
    if gi < count[0] {
        r = idrays[i] as usize;
        let st = state[r];
        if st.w & DONE != 0 {
            flags[i] = 0;
        } else {
            active = true;
            pixel = st.x;
            path = st.y;
            bounce = st.z;
            let key = stream(f.seed, pixel, path, bounce + 1);
            let h = hits[r];
            let tri = h.w.to_bits();
            let d = ray_d[r].truncate();
            thr = beta[r].truncate();
            l = radiance[r].truncate();
            if tri == MISS {
                l += thr * f.environment;
            } else {
                let t = tris[tri as usize];
                let m = materials[t.material as usize];
                let ng = (t.v1 - t.v0).cross(t.v2 - t.v0).normalize();
                let front = ng.dot(d) < 0.0;
                let two_sided = m.flags & TWO_SIDED != 0;
                let n = if front { ng } else { -ng };
                let p = ray_o[r].truncate() + d * h.x;
                if m.flags & EMITTER != 0 && (front || two_sided) {
                    l += thr * m.emission;
                }
                let u = Vec2::new(uniform(key, 2), uniform(key, 3));
                if m.kind == DIFFUSE {
                    if (front || two_sided) && m.color.max_element() > 0.0 {
                        let s = S::sample(n, u, shared_patch, f.patches_n);
                        new_d = s.truncate();
                        thr = thr * m.color * s.w;
                        new_o = offset_origin(p, n);
                        alive = true;
                    }
                } else if m.kind == CONDUCTOR {
                    new_d = d - n * (2.0 * d.dot(n));
                    thr = thr * m.color;
                    new_o = offset_origin(p, n);
                    alive = true;
                } else if m.kind == ROUGH_CONDUCTOR {
                    let fr = crate::sampling::frame(n);
                    let wo = fr.transpose() * -d;
                    // VNDF sampling maps the unit square onto the visible normals preserving
                    // measure, so a shared cell of the square keeps each ray's pdf unchanged.
                    let mut ug = u;
                    if f.coherent_glossy != 0 {
                        ug = cell_point(shared_cell % (f.patches_n * f.patches_n), f.patches_n, u);
                    }
                    let mn = ggx_vndf(wo, m.param, ug);
                    let wi = mn * (2.0 * wo.dot(mn)) - wo;
                    if wi.z > 0.0 {
                        new_d = fr * wi;
                        thr = thr * m.color * smith_g1(wi.z, m.param);
                        new_o = offset_origin(p, n);
                        alive = true;
                    }
                } else {
                    // Dielectric: `param` is int_ior / ext_ior; entering through the front face.
                    let eta = if front { m.param } else { 1.0 / m.param };
                    let cos_i = -d.dot(n);
                    let fr = fresnel_dielectric(cos_i, eta);
                    if uniform(key, 4) < fr {
                        new_d = d + n * (2.0 * cos_i);
                        thr = thr * m.color;
                        new_o = offset_origin(p, n);
                    } else {
                        let inv = 1.0 / eta;
                        let cos_t = (1.0 - inv * inv * (1.0 - cos_i * cos_i)).max(0.0).sqrt();
                        new_d = (d * inv + n * (inv * cos_i - cos_t)).normalize();
                        thr = thr * m.transmittance;
                        new_o = offset_origin(p, -n);
                    }
                    alive = true;
                }
                if alive && f.max_depth != 0 && bounce + 1 >= f.max_depth {
                    alive = false;
                }
                if alive && bounce + 1 >= f.rr_depth {
                    let mut rr_u = uniform(key, 5);
                    if f.group_rr != 0 {
                        rr_u = shared_rr.x;
                    }
                    if rr_u < f.rr_continue {
                        thr = thr / f.rr_continue;
                    } else {
                        alive = false;
                    }
                }
            }
        }
    }
    // Whole-group termination: a path that ended makes its group play a shared roulette.
    let mut group_ended = false;
    if E::WHOLE_GROUP {
        group_ended = group_any(active && !alive);
    }
    // Phase 2: continue the path, or add its estimate and regenerate a camera ray.
    if active {
        if alive && group_ended {
            if shared_rr.y < f.group_end_continue {
                thr = thr / f.group_end_continue;
            } else {
                alive = false;
            }
        }
        if alive {
            state[r] = UVec4::new(pixel, path, bounce + 1, 0);
            ray_o[r] = new_o.extend(0.0);
            ray_d[r] = new_d.extend(0.0);
            beta[r] = thr.extend(0.0);
            radiance[r] = l.extend(0.0);
            flags[i] = 1;
        } else {
            accum[r] = accum[r] + l.extend(1.0);
            wg_done[0].fetch_add(1, Ordering::Relaxed);
            let next = path + 1;
            let mut done = 0u32;
            if f.paths_per_pixel != 0 && next >= f.paths_per_pixel {
                done = DONE;
                wg_done[1].fetch_add(1, Ordering::Relaxed);
            }
            let cd = camera_dir(f, pixel, stream(f.seed, pixel, next, 0));
            state[r] = UVec4::new(pixel, next, 0, done);
            ray_o[r] = f.cam_origin.extend(0.0);
            ray_d[r] = cd.extend(0.0);
            beta[r] = Vec4::ONE;
            radiance[r] = Vec4::ZERO;
            flags[i] = 0;
        }
    }
    workgroup_barrier();
    if li == 0 {
        let c = wg_done[0].load(Ordering::Relaxed);
        if c > 0 {
            completed[0].fetch_add(c, Ordering::Relaxed);
        }
        let c1 = wg_done[1].load(Ordering::Relaxed);
        if c1 > 0 {
            completed[1].fetch_add(c1, Ordering::Relaxed);
        }
    }
}
