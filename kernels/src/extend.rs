//! Path extension (the paper's §3, kernel 1) and camera-ray generation.
//!
//! For each live ray: add the emission it reached (implicit path tracing: a path
//! contributes when it hits an emitter or leaves the scene), then either continue the
//! path with a new direction sampled from the BSDF (diffuse bounces through the
//! strategy `S`) or, when it escaped, was absorbed or lost Russian roulette, add its
//! estimate to its pixel and regenerate a fresh camera ray for the same pixel (path
//! regeneration, Novak et al. 2010). `flags[i]` records which, for compaction.

use crate::bsdf::principled::component;
use crate::bsdf::{bsdf_light_sampled, bsdf_shade, hit, Draws};
use crate::environment::{environment_pdf, environment_radiance, environment_sample};
use crate::group_draw::{
    draws_entry, glossy_cell_draw, is_group, light_draw, light_entry, params_entry, patch_key,
    roulette_draw, table_at,
};
use crate::integrator::Integrator;
use crate::layout::*;
use crate::light::{
    area_to_solid_angle, delta_light_arrival, delta_light_direction, mis_power, pick_light,
    triangle_point, triangle_weights,
};
use crate::path_end::PathEnd;
use crate::perturb::{perturb_normal, perturb_weight};
use crate::rng::{stream, uniform};
use crate::sampling::{cell_point, DiffuseSampler};
use crate::scatter::{
    blend_eval, blend_traits, blend_weights, BLEND_LEVELS, BLEND_NONE, BLEND_NOT_PLAIN,
    BLEND_READS_UV,
};
use crate::shading::*;
use crate::texture::{hit_uv, luminance, texture_at_hit};
use cohort::prelude::*;

/// Bins of the reconstruction filter's table across `[-radius, radius]`
/// (`cohort_scenes::film_filter::FILTER_BINS`): two cumulative tables of `FILTER_BINS + 1`
/// values each, of `|f|` and of `f`.
pub const FILTER_BINS: u32 = 62;

/// The cumulative integral of the filter table starting at `base` (its `|f|` half at 0, its
/// signed half at `FILTER_BINS + 1`) at offset `t` from a pixel's centre, `t` clamped to the
/// filter's radius `radius`.
#[kernel_fn]
pub fn filter_cdf(table: &[f32], base: u32, radius: f32, t: f32) -> f32 {
    let x = ((t + radius) * (FILTER_BINS as f32 * 0.5) / radius).clamp(0.0, FILTER_BINS as f32);
    let k = (x as u32).min(FILTER_BINS - 1);
    let c0 = table[(base + k) as usize];
    let c1 = table[(base + k + 1) as usize];
    c0 + (x - k as f32) * (c1 - c0)
}

/// An offset along one axis from a pixel's centre, drawn with density proportional to the
/// filter's `|f|` restricted to `[lo, hi]` (the sampled film area), and its weight: the sign
/// of `f` there times `integral |f| / integral f` over `[lo, hi]`, which is 1 for a filter
/// without negative lobes. The mean of weighted radiance at such offsets is Mitsuba's
/// filtered pixel (`cohort_scenes::film_filter`). Returns (offset, weight).
#[kernel_fn]
pub fn filter_offset(table: &[f32], radius: f32, lo: f32, hi: f32, u: f32) -> Vec2 {
    let a = filter_cdf(table, 0, radius, lo);
    let b = filter_cdf(table, 0, radius, hi);
    let target = a + u * (b - a);
    // The last bin edge at or below `target` (binary search over the edges).
    let mut k0 = 0u32;
    let mut k1 = FILTER_BINS;
    while k1 - k0 > 1 {
        let mid = (k0 + k1) / 2;
        if table[mid as usize] <= target {
            k0 = mid;
        } else {
            k1 = mid;
        }
    }
    let c0 = table[k0 as usize];
    let c1 = table[(k0 + 1) as usize];
    let mut frac = 0.5f32;
    if c1 > c0 {
        frac = ((target - c0) / (c1 - c0)).clamp(0.0, 1.0);
    }
    let h = 2.0 * radius / FILTER_BINS as f32;
    let t = (-radius + (k0 as f32 + frac) * h).max(lo).min(hi);
    let signed = FILTER_BINS + 1;
    let sa = filter_cdf(table, signed, radius, lo);
    let sb = filter_cdf(table, signed, radius, hi);
    let mut w = 1.0f32;
    if sb - sa != b - a {
        w = (b - a) / (sb - sa);
        if table[(signed + k0 + 1) as usize] < table[(signed + k0) as usize] {
            w = -w;
        }
    }
    Vec2::new(t, w)
}

/// A random point for `pixel` on the film, as the offset `(2 sx - 1) right + (1 - 2 sy) up`
/// from the image centre (`sx`, `sy` in [0, 1], y down) in xyz, and its weight in w. With the
/// box filter (`filter_radius` 0) the point is uniform in the pixel and the weight 1; with
/// another reconstruction filter it is drawn from the filter around the pixel's centre over
/// the sampled film area (`filter_offset`).
#[kernel_fn]
pub fn film_sample(f: &Frame, film_filter: &[f32], pixel: u32, key: u32) -> Vec4 {
    let ix = (pixel % f.width) as f32;
    let iy = (pixel / f.width) as f32;
    let mut px = ix + uniform(key, 0);
    let mut py = iy + uniform(key, 1);
    let mut w = 1.0f32;
    if f.filter_radius > 0.0 {
        let r = f.filter_radius;
        let border = f.filter_border as f32;
        let cx = ix + 0.5;
        let cy = iy + 0.5;
        let ox = filter_offset(
            film_filter,
            r,
            (-border - cx).max(-r),
            (f.width as f32 + border - cx).min(r),
            uniform(key, 0),
        );
        let oy = filter_offset(
            film_filter,
            r,
            (-border - cy).max(-r),
            (f.height as f32 + border - cy).min(r),
            uniform(key, 1),
        );
        px = cx + ox.x;
        py = cy + oy.x;
        w = ox.y * oy.y;
    }
    let sx = px / f.width as f32;
    let sy = py / f.height as f32;
    let o = f.cam_right * (2.0 * sx - 1.0) + f.cam_up * (1.0 - 2.0 * sy);
    o.extend(w)
}

/// A uniform point of a thin lens, as an offset from `cam_origin` (zero for a pinhole):
/// uniform in the disk of radius `lens_radius` spanned by the film's axes. It uses the
/// camera vertex's random dimensions 2 and 3 (0 and 1 place the film point).
#[kernel_fn]
pub fn lens_offset(f: &Frame, key: u32) -> Vec3 {
    let mut offset = Vec3::ZERO;
    if f.lens_radius > 0.0 {
        let r = f.lens_radius * uniform(key, 2).sqrt();
        let phi = 2.0 * core::f32::consts::PI * uniform(key, 3);
        offset = f.cam_right.normalize() * (r * phi.cos()) + f.cam_up.normalize() * (r * phi.sin());
    }
    offset
}

/// Direction of the camera ray through film offset `film` (`film_sample`) and lens offset
/// `lens` (`lens_offset`): along the view axis (orthographic), through the film (pinhole),
/// or from the lens point to where the film ray meets the plane of focus (thin lens), as
/// `cohort_scenes::Camera::ray_through_lens`.
#[kernel_fn]
pub fn camera_dir(f: &Frame, film: Vec3, lens: Vec3) -> Vec3 {
    let mut d = f.cam_forward;
    if f.orthographic == 0 {
        d += film;
        if f.lens_radius > 0.0 {
            d = d * f.focus_distance - lens;
        }
    }
    d.normalize()
}

/// Origin of the camera ray through film offset `film` and lens offset `lens`.
#[kernel_fn]
pub fn camera_origin(f: &Frame, film: Vec3, lens: Vec3) -> Vec3 {
    let mut o = f.cam_origin + lens;
    if f.orthographic != 0 {
        o += film;
    }
    o
}

/// Path throughput of a fresh camera ray of film weight `weight` (`film_sample`); w is the
/// BSDF-sampling density of the ray's direction for MIS, 0: a camera ray reaching a light
/// counts in full.
#[kernel_fn]
pub fn camera_beta(weight: f32) -> Vec4 {
    Vec4::new(weight, weight, weight, 0.0)
}

/// Starts every slot: first camera ray, empty estimate, identity order.
#[kernel(workgroup = 64)]
pub fn init_paths(
    #[builtin(global_index)] gi: u32,
    f: &Frame,
    film_filter: &[f32],
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
    // Copy `k` of the pixel starts at its path `first_path + k` (`Frame::copies`).
    let path = f.first_path + gi / (f.slots / f.copies);
    let key = stream(f.seed, pixel, path, 0);
    let fs = film_sample(f, film_filter, pixel, key);
    let film = fs.truncate();
    let lens = lens_offset(f, key);
    let o = camera_origin(f, film, lens);
    let d = camera_dir(f, film, lens);
    idrays[g] = gi;
    // A copy with no path left in the budget (fewer paths than copies) starts done.
    let mut done = 0u32;
    if f.paths_per_pixel != 0 && path - f.first_path >= f.paths_per_pixel {
        done = DONE;
    }
    state[g] = UVec4::new(pixel, path, 0, done);
    ray_o[g] = Vec4::new(o.x, o.y, o.z, 0.0);
    // w: the path's accumulated eta² (1 for a camera ray; see `extend`'s roulette).
    ray_d[g] = Vec4::new(d.x, d.y, d.z, 1.0);
    beta[g] = camera_beta(fs.w);
    radiance[g] = Vec4::ZERO;
    accum[g] = Vec4::ZERO;
}

/// The shading normal at hit `h` (barycentric weights of v1 and v2 in `h.y`, `h.z`) of
/// triangle `original`: its vertex normals interpolated where the scene has them (a
/// degenerate interpolation falls back to the geometric normal `ng`), else `ng`.
#[kernel_fn]
pub fn shading_normal(
    f: &Frame,
    shading_normals: &[Vec4],
    original: u32,
    h: Vec4,
    ng: Vec3,
) -> Vec3 {
    let mut n = ng;
    if f.shading_normals != 0 {
        let k = original as usize * 3;
        let s = shading_normals[k].truncate() * (1.0 - h.y - h.z)
            + shading_normals[k + 1].truncate() * h.y
            + shading_normals[k + 2].truncate() * h.z;
        if s.dot(s) > 1.0e-30 {
            n = s.normalize();
        }
    }
    n
}

/// The radiance emitter material `m` sends from point `h` (barycentric weights of v1 and
/// v2 in `h.y`, `h.z`) of triangle `original`: its texture's value there (Mitsuba's
/// textured `radiance`), else `m.emission`. `shading`: the scene's set (`crate::shading`).
#[kernel_fn]
pub fn emitted(
    shading: u32,
    m: Material,
    textures: &[Vec4],
    tex_coords: &[Vec4],
    original: u32,
    h: Vec4,
) -> Vec3 {
    let mut e = m.emission;
    if shading & SHADES_TEXTURES != 0 && m.emission_texture != 0 {
        let uv = hit_uv(tex_coords, original, h);
        e = texture_at_hit(textures, m.emission_texture - 1, uv, original, h);
    }
    e
}

/// Offset along the normal that keeps a new ray off the surface it leaves, scaled with
/// the hit point's magnitude.
#[kernel_fn]
pub fn offset_origin(p: Vec3, n: Vec3) -> Vec3 {
    let scale = 1e-4 * (1.0 + p.abs().max_element());
    p + n * scale
}

#[kernel(workgroup = 64)]
#[allow(clippy::too_many_arguments)]
pub fn extend<S: DiffuseSampler, E: PathEnd, I: Integrator>(
    #[builtin(global_index)] gi: u32,
    #[specialize] shading: u32,
    f: &Frame,
    count: &[u32],
    idrays: &[u32],
    hits: &[Vec4],
    tris: &[Triangle],
    shading_normals: &[Vec4],
    tex_coords: &[Vec4],
    textures: &[Vec4],
    film_filter: &[f32],
    materials: &[Material],
    lights: &[LightEntry],
    delta_lights: &[DeltaLight],
    state: &mut [UVec4],
    ray_o: &mut [Vec4],
    ray_d: &mut [Vec4],
    beta: &mut [Vec4],
    radiance: &mut [Vec4],
    accum: &mut [Vec4],
    shadow_o: &mut [Vec4],
    shadow_d: &mut [Vec4],
    nee: &mut [Vec4],
    flags: &mut [u32],
    completed: &[AtomicU32],
    group_table: &mut [UVec4],
) {
    // What the scene shades with (`crate::shading`): a test below on a kind or feature
    // that the scene lacks is false when the kernel is built, and its branch is left out.
    let has_blend = shading & SHADES_BLEND != 0;
    let has_mask = shading & SHADES_MASK != 0;
    let has_perturb = shading & SHADES_PERTURB != 0;
    let has_textures = shading & SHADES_TEXTURES != 0;
    let has_delta_lights = shading & SHADES_DELTA_LIGHTS != 0;
    // The group's shared draws come first, in uniform control flow: the patch of
    // coherent sampling and the group's Russian-roulette number. They are keyed by
    // iteration, not by path, so each shard of a render draws them from its own seed.
    // With `SHADES_SLOT_GROUPS` each invocation computes them for the group of the slot
    // it shades instead (`crate::group_draw`): the same numbers while the list holds
    // every slot in order, and still the slot's own once finished slots have left it.
    // With `SHADES_GROUP_TABLE` as well, they read them from `group_table`, where each
    // group's were computed once for this iteration (`crate::group_draw`), and the
    // invocations of the first `ceil(slots / group_slots)` indices compute the next
    // iteration's into its other half (the renderer dispatches at least that many).
    let slot_groups = shading & SHADES_SLOT_GROUPS != 0;
    let tabled = shading & SHADES_GROUP_TABLE != 0;
    let mut slot_group = 0u32;
    if slot_groups && gi < count[0] {
        slot_group = idrays[gi as usize] / f.group_slots;
    }
    if tabled {
        if is_group(f, gi) {
            let next = table_at(f, gi, f.iteration + 1);
            let draws = draws_entry::<S>(f, gi, f.iteration + 1);
            group_table[next] = draws;
            group_table[next + 1] = light_entry(f, gi, f.iteration + 1);
            group_table[next + 2] = params_entry::<S>(f, draws);
        }
    }
    // The patch is drawn only for a sampler that reads it (`DiffuseSampler::GROUP_VALUE`).
    let mut shared_patch = 0u32;
    // With the table, the sampler's parameters of the group's patch too
    // (`DiffuseSampler::group_params`), which each ray would otherwise compute.
    let mut group_params = Vec4::ZERO;
    if S::GROUP_VALUE {
        if tabled {
            let at = table_at(f, slot_group, f.iteration);
            shared_patch = group_table[at].x;
            if S::GROUP_PARAMS {
                let p = group_table[at + 2];
                group_params = Vec4::new(
                    f32::from_bits(p.x),
                    f32::from_bits(p.y),
                    f32::from_bits(p.z),
                    f32::from_bits(p.w),
                );
            }
        } else if slot_groups {
            shared_patch = S::group_value(patch_key(f, slot_group, f.iteration), f.patches_n);
        } else {
            shared_patch =
                group_share(|group| S::group_value(patch_key(f, group, f.iteration), f.patches_n));
        }
    }
    // The configuration's own group draws: the Russian-roulette number of `_rr` and of
    // whole-group ends, the cell of coherent glossy sampling and the light draw of
    // coherent light sampling. The renderer sets `SHADES_GROUP_DRAWS` where a frame flag
    // reads one (`crate::shading::group_draws`), so elsewhere they are left out when the
    // kernel is built: behind the flags alone they cost the CPU backend 16 % of a `normal`
    // render, and warp groups on an H200 3-6 % when tested at run time.
    let mut shared_rr = Vec2::new(0.0, 0.0);
    let mut shared_cell = 0u32;
    let mut shared_light = Vec2::new(0.0, 0.0);
    if E::WHOLE_GROUP || shading & SHADES_GROUP_DRAWS != 0 {
        if tabled {
            let drawn = table_at(f, slot_group, f.iteration);
            let t = group_table[drawn];
            shared_cell = t.y;
            shared_rr = Vec2::new(f32::from_bits(t.z), f32::from_bits(t.w));
            let l = group_table[drawn + 1];
            shared_light = Vec2::new(f32::from_bits(l.x), f32::from_bits(l.y));
        } else if slot_groups {
            shared_rr = roulette_draw(f, slot_group, f.iteration);
            shared_cell = glossy_cell_draw(f, slot_group, f.iteration);
            shared_light = light_draw(f, slot_group, f.iteration);
        } else {
            // x: the group's Russian-roulette number (`_rr`); y: its whole-group-end number.
            shared_rr = group_share(|group| roulette_draw(f, group, f.iteration));
            shared_cell = group_share(|group| glossy_cell_draw(f, group, f.iteration));
            // Coherent light sampling: the group's light pick and stratum.
            shared_light = group_share(|group| light_draw(f, group, f.iteration));
        }
    }
    // Phase 1: shade and decide per path. What phase 2 needs outlives the branch, because
    // the group may vote in between, which every invocation must reach.
    // A material queue's `extend` (`crate::queues`) takes its rays from the queue: its
    // size, start and list length at `count[4 q ..]`, each ray's slot at its place and,
    // the list's length further on, the ray's position in the live list, where its
    // compaction flag goes. Without queues, `q4` is 0 and the branch is left out.
    let queued = shading & SHADES_QUEUE != 0;
    let q4 = 4 * (shading >> QUEUE_SHIFT) as usize;
    let mut i = gi as usize;
    let mut r = 0usize;
    let mut active = false;
    let mut alive = false;
    let mut pixel = 0u32;
    let mut path = 0u32;
    // The bounce of the path's next vertex: one more, except after a camera ray passed
    // through an emitter that `hide_emitters` hides.
    let mut next_bounce = 0u32;
    let mut thr = Vec3::ZERO;
    // The product of eta² over the path's refractions (`ray_d`'s w): refractions scale
    // the throughput by 1 / eta², as Mitsuba's radiance transport does, and Mitsuba's
    // roulette weighs the throughput times this product, so that a path is not ended
    // for the brightness it lost entering glass.
    let mut eta2 = 1.0f32;
    let mut l = Vec3::ZERO;
    let mut new_o = Vec3::ZERO;
    let mut new_d = Vec3::ZERO;
    // Next-event estimation: the BSDF-sampling density of the new direction (0 for a delta
    // BSDF: a light it reaches is counted in full) and the density with which light
    // sampling would have drawn that direction towards the environment.
    let mut bsdf_pdf = 0.0f32;
    let mut env_pdf = 0.0f32;
    // The light sample of this vertex: its contribution if unoccluded, and its shadow ray.
    let mut ld = Vec3::ZERO;
    let mut sh_o = Vec4::ZERO;
    let mut sh_d = Vec3::ZERO;
    if gi < count[q4] {
        if queued {
            let at = count[q4 + 1] as usize + i;
            r = idrays[at] as usize;
            i = idrays[count[q4 + 2] as usize + at] as usize;
        } else {
            r = idrays[i] as usize;
        }
        let st = state[r];
        if st.w & DONE != 0 {
            flags[i] = 0;
            if I::NEE {
                shadow_d[r] = Vec4::new(0.0, 0.0, 0.0, SLOT_IDLE);
            }
        } else {
            active = true;
            pixel = st.x;
            path = st.y;
            let bounce = st.z;
            next_bounce = bounce + 1;
            let key = stream(f.seed, pixel, path, bounce + 1);
            let h = hits[r];
            let tri = h.w.to_bits();
            let d4 = ray_d[r];
            let d = d4.truncate();
            eta2 = d4.w;
            let b4 = beta[r];
            thr = b4.truncate();
            let r4 = radiance[r];
            l = r4.truncate();
            // Camera rays: Mitsuba's `hide_emitters` hides what they reach directly.
            let hidden = f.hide_emitters != 0 && bounce == 0;
            if f.zero_depth != 0 {
                // Mitsuba's max_depth 0: the path ends with nothing (alive stays false).
            } else if tri == MISS {
                // A direction drawn from a non-delta BSDF (pdf in beta.w; 0 after a camera
                // ray or a delta bounce) could also have been drawn by light sampling.
                let mut w = 1.0f32;
                if I::NEE {
                    if b4.w > 0.0 {
                        w = mis_power(b4.w, r4.w);
                    }
                }
                if !hidden {
                    l += thr * environment_radiance(shading, f, textures, d) * w;
                }
            } else {
                let t = tris[tri as usize];
                // Mitsuba `blendbsdf`: one of its BSDFs samples the next direction, the second
                // (`blend`) with probability `blend_weight`; a second BSDF that is a blend
                // itself chooses again. Light samples and MIS densities take the blend's
                // weighted sum (`mixture`, below) where its BSDFs share the surface.
                let root = materials[t.material as usize];
                let mut m = root;
                let mut level = 0u32;
                // The blend level of the BSDF chosen, and the probability of that choice.
                let mut picked = 0u32;
                let mut pick_p = 1.0f32;
                let mut weights = Vec4::ZERO;
                if has_blend && root.blend != 0 {
                    weights = blend_weights(shading, materials, textures, tex_coords, root, t, h);
                }
                if has_blend {
                    while level < BLEND_LEVELS && m.blend != 0 {
                        let weight = component(weights, level);
                        if uniform(key, 10 + level) < weight {
                            m = materials[(m.blend - 1) as usize];
                            level += 1;
                            picked = level;
                            pick_p *= weight;
                        } else {
                            pick_p *= 1.0 - weight;
                            level = BLEND_LEVELS;
                        }
                    }
                }
                // Light samples and MIS densities see the blend's weighted sum
                // (`crate::scatter`), where its BSDFs share the surface.
                let mut traits = 0u32;
                if has_blend && root.blend != 0 {
                    traits = blend_traits(materials, root);
                }
                let plain_blend = has_blend && root.blend != 0 && traits & BLEND_NOT_PLAIN == 0;
                let mixture = I::NEE && plain_blend;
                // A hit on a (numerically) degenerate triangle has no normal: shade it as
                // facing the ray rather than let a NaN normal into the next ray.
                let cr = (t.v1 - t.v0).cross(t.v2 - t.v0);
                let ng = if cr.dot(cr) > 1.0e-30 {
                    cr.normalize()
                } else {
                    -d
                };
                // Shading happens in the frame of the interpolated vertex normal, as in
                // Mitsuba (sidedness included); new rays leave along the geometric normal.
                let ns = shading_normal(f, shading_normals, t.original, h, ng);
                let mut front = ns.dot(d) < 0.0;
                let two_sided = m.flags & TWO_SIDED != 0;
                let mut n = if front { ns } else { -ns };
                // The geometric normal on the side the shading normal faces.
                let ng_n = if ng.dot(n) >= 0.0 { ng } else { -ng };
                let p = ray_o[r].truncate() + d * h.x;
                let pass_through = hidden && m.flags & EMITTER != 0;
                if m.flags & EMITTER != 0 && (front || two_sided) && !hidden {
                    let mut w = 1.0f32;
                    if I::NEE {
                        if b4.w > 0.0 {
                            w = mis_power(b4.w, area_to_solid_angle(t.light_pdf, h.x, ng.dot(d)));
                        }
                    }
                    l += thr * emitted(shading, m, textures, tex_coords, t.original, h) * w;
                }
                let u = Vec2::new(uniform(key, 2), uniform(key, 3));
                // The material's colour (diffuse, plastic base, conductor reflectance), or its
                // texture's here.
                let mut uv = Vec2::ZERO;
                let textured = has_textures
                    && (m.texture != 0
                        || (plain_blend && traits & BLEND_READS_UV != 0)
                        || m.opacity_texture != 0
                        || m.flags & READS_UV != 0);
                if textured || (has_perturb && m.perturb_texture != 0) {
                    uv = hit_uv(tex_coords, t.original, h);
                }
                // Mitsuba `normalmap` / `bumpmap`: the BSDF shades around the perturbed
                // normal `np`; `base` is the shading normal of the side the map applies on,
                // against which each direction is weighed (`perturb_weight`). Emission
                // above stays with the unperturbed surface.
                let perturbed = has_perturb && m.perturb_texture != 0;
                let shadowing = m.flags & NO_SHADOWING == 0;
                let mut base = ns;
                let mut np = ns;
                if perturbed {
                    let pn = perturb_normal(
                        m, textures, tex_coords, t.original, t, uv, ns, ng, -d, front,
                    );
                    np = pn.truncate();
                    base = ns * pn.w;
                    front = np.dot(d) < 0.0;
                    n = if front { np } else { -np };
                }
                let mut albedo = m.color;
                if has_textures && m.texture != 0 {
                    albedo = texture_at_hit(textures, m.texture - 1, uv, t.original, h);
                }
                // Mitsuba `mask`: the BSDF scatters with probability `opacity`, else the path
                // passes through (a null interaction: one more vertex, a delta density).
                let mut opacity = 1.0f32;
                if has_mask && m.flags & MASKED != 0 {
                    opacity = m.opacity;
                    if has_textures && m.opacity_texture != 0 {
                        opacity = luminance(texture_at_hit(
                            textures,
                            m.opacity_texture - 1,
                            uv,
                            t.original,
                            h,
                        ));
                    }
                    opacity = opacity.clamp(0.0, 1.0);
                }
                let masked_through = opacity < 1.0 && uniform(key, 9) >= opacity;
                // Light sampling applies where the material's BSDF has a non-delta lobe
                // that scatters from this side (`crate::bsdf`).
                let at = hit(m, t, h, albedo, uv, d, n, ng, front);
                let light_sampled = bsdf_light_sampled(shading, textures, at);
                // Light sampling at non-delta vertices, if the depth limit allows one
                // more vertex (Mitsuba: an emitter sample makes the path one longer). The
                // light sample: its direction, radiance and density, or a delta light's
                // selection probability (its weight is 1 / selection: BSDF sampling never
                // reaches it, so it has no density to weigh), and the shadow ray's reach.
                let mut light_on = false;
                let mut wi = Vec3::ZERO;
                let mut le = Vec3::ZERO;
                let mut light_pdf = 0.0f32;
                let mut delta_select = 0.0f32;
                let mut tmax = 3.0e38f32;
                let o = offset_origin(p, ng_n);
                if I::NEE {
                    let room = f.max_depth == 0 || bounce + 2 <= f.max_depth;
                    if (light_sampled || mixture)
                        && room
                        && !pass_through
                        && (f.light_count > 0 || f.env_light > 0.0)
                    {
                        let mut ul = uniform(key, 6);
                        let mut up = Vec2::new(uniform(key, 7), uniform(key, 8));
                        if f.coherent_light != 0 {
                            ul = shared_light.x;
                            up = cell_point(shared_light.y.to_bits(), f.light_cells, up);
                        }
                        if ul < f.env_light {
                            let s = environment_sample(shading, f, textures, n, up);
                            wi = s.truncate();
                            light_pdf = f.env_light * s.w;
                            le = environment_radiance(shading, f, textures, wi);
                        } else {
                            let id = pick_light(
                                lights,
                                f.light_count,
                                (ul - f.env_light) / (1.0 - f.env_light),
                            );
                            if has_delta_lights && id & DELTA_LIGHT != 0 {
                                let k = id & !DELTA_LIGHT;
                                let dd = delta_light_direction(delta_lights, k, o);
                                if dd.w > 0.0 {
                                    wi = dd.truncate();
                                    le = delta_light_arrival(delta_lights, textures, k, wi, dd.w);
                                    delta_select = delta_lights[k as usize].select;
                                    tmax = dd.w * (1.0 - 1e-4);
                                }
                            } else {
                                let lt = tris[id as usize];
                                let lm = materials[lt.material as usize];
                                let y = triangle_point(lt.v0, lt.v1, lt.v2, up);
                                let to = y - o;
                                let dist = to.length();
                                if dist > 0.0 {
                                    wi = to / dist;
                                    let lng = (lt.v1 - lt.v0).cross(lt.v2 - lt.v0).normalize();
                                    let cos_l = lng.dot(wi);
                                    if cos_l < 0.0 || lm.flags & TWO_SIDED != 0 {
                                        light_pdf = area_to_solid_angle(lt.light_pdf, dist, cos_l);
                                        le = emitted(
                                            shading,
                                            lm,
                                            textures,
                                            tex_coords,
                                            lt.original,
                                            triangle_weights(up),
                                        );
                                        // Stop short of the light's own surface.
                                        tmax = dist * (1.0 - 1e-4);
                                    }
                                }
                            }
                        }
                        light_on = light_pdf > 0.0 || delta_select > 0.0;
                    }
                }
                // The BSDF, in one dispatch (`crate::bsdf`): its value towards the light
                // sample and the next direction (none where the path passes through). A
                // kernel that shades blends takes every light sample's value from
                // `blend_eval` instead (below), so that each BSDF's `eval` is inlined into it
                // once, not also here (`has_blend` is known when the kernel is built).
                let mut u_glossy = u;
                if f.coherent_glossy != 0 {
                    let cell = shared_cell % (f.patches_n * f.patches_n);
                    u_glossy = cell_point(cell, f.patches_n, u);
                }
                let draws = Draws {
                    u,
                    u_glossy,
                    choice: uniform(key, 4),
                    group_value: shared_patch,
                    patches_n: f.patches_n,
                    // The parameters were read with the group's draw: only for a sampler
                    // that has both.
                    grouped: if tabled && S::GROUP_VALUE && S::GROUP_PARAMS {
                        1
                    } else {
                        0
                    },
                    group_params,
                };
                let shaded = bsdf_shade::<S>(
                    shading,
                    textures,
                    tex_coords,
                    at,
                    wi,
                    !has_blend && I::NEE && light_on,
                    thr,
                    draws,
                    !pass_through && !masked_through,
                );
                // The throughput before this vertex's BSDF weighs it, and the probability
                // with which the BSDF chose the delta lobe it sampled (0: none), for a
                // blend's delta directions (below).
                let thr_in = thr;
                let mut delta_p = 0.0f32;
                if pass_through {
                    // The camera ray goes on behind the hidden emitter, still a camera ray.
                    new_d = d;
                    alive = true;
                    next_bounce = bounce;
                } else if masked_through {
                    // Through the mask: same direction and weight; what it reaches next counts
                    // in full (bsdf_pdf 0, as after a delta bounce).
                    new_d = d;
                    alive = true;
                } else {
                    let s = shaded.next;
                    if s.alive != 0 {
                        new_d = s.dir;
                        thr = s.beta;
                        eta2 *= s.eta2;
                        bsdf_pdf = s.pdf;
                        delta_p = s.delta_p;
                        alive = true;
                        // The environment's light-sampling density of a direction MIS
                        // weighs (one a delta lobe drew is counted in full).
                        if s.pdf > 0.0 {
                            env_pdf = environment_pdf(shading, f, textures, n, new_d);
                        }
                    }
                }
                // A delta direction drawn in a blend takes Mitsuba's weight: the drawing
                // BSDF's delta value and lobe probability, the other BSDFs' value and
                // density there (`crate::scatter`). It stays a delta bounce for MIS.
                // (With or without light sampling: it is the BSDF's weight, not a density.)
                // A blend's non-delta direction, drawn by one of its BSDFs, is weighed
                // against light sampling by the blend's density (a delta lobe's density is
                // 0, so never both).
                let blend_delta = plain_blend && alive && delta_p > 0.0;
                let blend_pdf =
                    mixture && alive && bsdf_pdf > 0.0 && !pass_through && !masked_through;
                // A blend kernel's evaluations, towards the light sample (k = 0: the blend's
                // mixture, or the one BSDF the vertex shades with) and at the drawn direction
                // (k = 1), at one call site: each inlines every BSDF of the scene's set
                // (pipeline creation time grows with the code).
                let mut blend_light = Vec4::ZERO;
                let mut blend_next = Vec4::ZERO;
                if has_blend {
                    let mut k = 0u32;
                    while k < 2 {
                        let towards_light = k == 0;
                        let wanted = if towards_light {
                            I::NEE && light_on
                        } else {
                            blend_delta || blend_pdf
                        };
                        if wanted {
                            let mut dir = new_d;
                            let mut skip = BLEND_NONE;
                            let mut from = root;
                            let mut levels = BLEND_LEVELS;
                            if towards_light {
                                dir = wi;
                                if !mixture {
                                    from = m;
                                    levels = 0;
                                }
                            } else if blend_delta {
                                skip = picked;
                            }
                            let b = blend_eval(
                                shading, materials, textures, tex_coords, from, weights, t, h, uv,
                                d, dir, n, ng, front, skip, levels,
                            );
                            if towards_light {
                                blend_light = b;
                            } else {
                                blend_next = b;
                            }
                        }
                        k += 1;
                    }
                }
                if blend_delta {
                    let own = pick_p * delta_p;
                    thr = (thr * own + thr_in * blend_next.truncate()) / (own + blend_next.w);
                } else if blend_pdf {
                    bsdf_pdf = blend_next.w;
                }
                if I::NEE && light_on {
                    // f·cos and the BSDF-sampling density of `wi`.
                    let e = if has_blend { blend_light } else { shaded.eval };
                    let fc = e.truncate();
                    let pdf_b = e.w;
                    // A normal or bump map weighs the direction (and zeroes its
                    // density where it lies on different sides of the frames).
                    let mut pw = 1.0f32;
                    if perturbed {
                        pw = perturb_weight(base, np, wi, shadowing);
                    }
                    let mut pdf_scatter = pdf_b * opacity;
                    if pw == 0.0 {
                        pdf_scatter = 0.0;
                    }
                    // A mask scatters only its opacity's share, and samples it so.
                    let weight = if delta_select > 0.0 {
                        1.0 / delta_select
                    } else {
                        mis_power(light_pdf, pdf_scatter) / light_pdf
                    };
                    ld = thr_in * fc * le * (weight * opacity * pw);
                    // A transmitting BSDF's light sample leaves from the far side.
                    // Towards a light at a finite distance it aims from there at the
                    // point short of the light where the near side's ray stopped:
                    // parallel to `wi` it could meet the light's own plane first
                    // (seen at a slant, by twice the offset), and the light would
                    // block its own sample.
                    let mut so = o;
                    let mut st = tmax;
                    let mut sd = wi;
                    if wi.dot(ng_n) < 0.0 {
                        so = offset_origin(p, -ng_n);
                        if tmax < 1.0e30 {
                            let to_end = o + wi * tmax - so;
                            st = to_end.length();
                            sd = to_end / st;
                        }
                    }
                    sh_o = so.extend(st);
                    sh_d = sd;
                }
                // A normal or bump map weighs the sampled direction as it weighs light
                // samples (Mitsuba's `sample`: zero on different sides of the frames).
                if perturbed && alive && !pass_through && !masked_through {
                    let pw = perturb_weight(base, np, new_d, shadowing);
                    thr *= pw;
                    if pw == 0.0 {
                        alive = false;
                    }
                }
                // The BSDF densities for MIS are the mask's: its opacity times the nested
                // BSDF's (1 without a mask).
                bsdf_pdf *= opacity;
                env_pdf *= opacity;
                // Anything else absorbs: a black or back-facing one-sided surface (diffuse,
                // plastic), whose BSDF is zero there, as in Mitsuba. The path ends here.
                // A continuing ray starts off the surface on the side it leaves towards
                // (with shading normals that can differ from the side `n` faces).
                if alive {
                    let side = if ng.dot(new_d) >= 0.0 { ng } else { -ng };
                    new_o = offset_origin(p, side);
                }
                if alive && !pass_through && f.max_depth != 0 && bounce + 1 >= f.max_depth {
                    alive = false;
                }
                if alive && !pass_through && bounce + 1 >= f.rr_depth {
                    let mut rr_u = uniform(key, 5);
                    if f.group_rr != 0 {
                        rr_u = shared_rr.x;
                    }
                    // Mitsuba: keep path weights near one; never continue surely, so that
                    // paths trapped by total internal reflection end.
                    let mut q = f.rr_continue;
                    if f.roulette_throughput != 0 {
                        // |throughput|: a reconstruction filter's negative lobes make
                        // it negative (`film_sample`).
                        q = (thr.abs().max_element() * eta2).min(0.95);
                    }
                    if rr_u < q {
                        thr = thr / q;
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
            state[r] = UVec4::new(pixel, path, next_bounce, 0);
            ray_o[r] = new_o.extend(0.0);
            ray_d[r] = new_d.extend(eta2);
            beta[r] = thr.extend(bsdf_pdf);
            radiance[r] = l.extend(env_pdf);
            flags[i] = 1;
        } else {
            // With light sampling the shadow pass adds the estimate to the pixel, after
            // this vertex's light sample.
            if I::NEE {
                radiance[r] = l.extend(0.0);
            } else {
                accum[r] = accum[r] + l.extend(1.0);
                radiance[r] = Vec4::ZERO;
            }
            // One global atomic per ended path, not a per-workgroup count: without its
            // two workgroup barriers the kernel synchronises only where its group level
            // asks, so the CPU backend runs it as a plain loop (1.6-2x its paths/s),
            // while extend's time on an H200 did not change (BENCHMARKS.md, 2026-11-27,
            // 56c20c1).
            completed[0].fetch_add(1, Ordering::Relaxed);
            // The copy's next path: the pixel's other copies trace those in between.
            let next = path + f.copies;
            let mut done = 0u32;
            if f.paths_per_pixel != 0 && next - f.first_path >= f.paths_per_pixel {
                done = DONE;
                completed[1].fetch_add(1, Ordering::Relaxed);
            }
            let key = stream(f.seed, pixel, next, 0);
            let fs = film_sample(f, film_filter, pixel, key);
            let film = fs.truncate();
            let lens = lens_offset(f, key);
            state[r] = UVec4::new(pixel, next, 0, done);
            ray_o[r] = camera_origin(f, film, lens).extend(0.0);
            ray_d[r] = camera_dir(f, film, lens).extend(1.0);
            beta[r] = camera_beta(fs.w);
            flags[i] = 0;
        }
        if I::NEE {
            nee[r] = ld.extend(0.0);
            shadow_o[r] = sh_o;
            shadow_d[r] = sh_d.extend(if alive { SLOT_CONTINUES } else { SLOT_ENDED });
        }
    }
}
