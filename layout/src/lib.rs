//! The path tracer's GPU data layouts, declared once: the scene (BVH nodes, triangles in
//! leaf order, materials with their kind and flag constants), the lights and the per-frame
//! uniform. `cohort-scenes` writes these types and the kernels (`cohort_kernels::layout`
//! re-exports this crate) read them, so the bytes have one definition.

// `#[derive(GpuType)]` names `::cohort::ir` and `::cohort::naga`: here they come from the
// compiler itself, so that the scene builder, which depends on this crate, does not pull
// in the GPU runtime of the `cohort` facade.
extern crate cohort_compiler as cohort;

use cohort_macros::GpuType;
use glam::{UVec4, Vec3, Vec4};

/// Interior BVH2 node holding both children's boxes. Child references: bit 31 set means
/// a leaf (bits 28..30 = count - 1, bits 0..27 = first triangle), else a node index.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct BvhNode {
    pub lmin: Vec3,
    pub left: u32,
    pub lmax: Vec3,
    pub right: u32,
    pub rmin: Vec3,
    pub pad0: u32,
    pub rmax: Vec3,
    pub pad1: u32,
}

/// Four children of an 8-wide node; two records make one node (`cohort_scenes::GpuBvh8`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct WideNode {
    pub lo_x: Vec4,
    pub hi_x: Vec4,
    pub lo_y: Vec4,
    pub hi_y: Vec4,
    pub lo_z: Vec4,
    pub hi_z: Vec4,
    /// Child references (bit 31 set: leaf, as in the BVH2; else the child's first record).
    pub child: UVec4,
    /// First record: leaf-child masks in octant order, one byte per octant (x: 0..3, y: 4..7).
    pub meta: UVec4,
}

/// A compressed 8-wide node (`cohort_scenes::GpuCwBvh`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct CwNode {
    /// Grid origin (f32 bits) in xyz; w: exponents of the grid steps (bytes 0..=2) and the
    /// leaf-slot mask (byte 3).
    pub a: UVec4,
    /// First interior child, first leaf triangle, 4-bit triangle count per slot, interior-slot mask.
    pub b: UVec4,
    /// 8-bit planes: low plane of slots 0..=3, 4..=7, high plane of slots 0..=3, 4..=7.
    pub qx: UVec4,
    pub qy: UVec4,
    pub qz: UVec4,
}

/// A triangle in BVH leaf order: its three vertices, material and original index.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Triangle {
    pub v0: Vec3,
    pub material: u32,
    pub v1: Vec3,
    pub original: u32,
    pub v2: Vec3,
    /// Emitter triangles: the probability that next-event estimation picks this
    /// triangle, divided by its area (a density per unit area); 0 for the others. The
    /// scenes crate leaves it 0 (its `pad`); the renderer fills it with the light table.
    pub light_pdf: f32,
}

/// Material kinds (`Material::kind`).
pub const DIFFUSE: u32 = 0;
pub const CONDUCTOR: u32 = 1;
pub const ROUGH_CONDUCTOR: u32 = 2;
pub const DIELECTRIC: u32 = 3;
/// Mitsuba `plastic`: `color` diffuse, `transmittance` specular reflectance, `param` eta.
pub const PLASTIC: u32 = 4;
/// Mitsuba `roughplastic`: `color` diffuse, `transmittance` specular reflectance, `param`
/// eta, `conductor_k` (alpha, internal reflectance, 0), `table` its transmittance table.
pub const ROUGH_PLASTIC: u32 = 5;
/// Mitsuba `roughdielectric`: `color` specular reflectance, `transmittance` specular
/// transmittance, `param` eta (int/ext), `conductor_k.x` alpha, or `table` its roughness
/// block where that is anisotropic or textured; `BECKMANN` flag.
pub const ROUGH_DIELECTRIC: u32 = 6;
/// Mitsuba `principled`: `color` base colour, `table` index + 1 of its parameter block in
/// the texture array ([`Principled`] as `cohort_kernels::bsdf::principled::params` reads it).
pub const PRINCIPLED: u32 = 7;
/// Mitsuba `principledthin`: as [`PRINCIPLED`].
pub const PRINCIPLED_THIN: u32 = 8;
/// `Material::flags` bits.
pub const TWO_SIDED: u32 = 1;
pub const EMITTER: u32 = 2;
/// Plastic: Mitsuba's `nonlinear` (internal scattering shifts the base's colour).
pub const NONLINEAR: u32 = 4;
/// `Material::flags`: a rough conductor's microfacets follow Beckmann (else GGX).
pub const BECKMANN: u32 = 8;
/// `Material::flags`: Mitsuba `mask` around the BSDF (`Material::opacity`).
pub const MASKED: u32 = 16;
/// `Material::flags`: Mitsuba `normalmap` / `bumpmap` around the BSDF (`perturb_texture`;
/// `cohort_kernels::perturb`), and their options.
pub const NORMAL_MAP: u32 = 32;
pub const BUMP_MAP: u32 = 64;
pub const NO_SHADOWING: u32 = 128;
pub const NO_FLIP: u32 = 256;
pub const PERTURB_PER_SIDE: u32 = 512;
/// `Material::flags`: the BSDF reads textured parameters, or turns with dp/du, at the hit's
/// texture coordinates.
pub const READS_UV: u32 = 1024;

/// A material as the kernels read it, 112 bytes, std430/WGSL compatible (each `Vec3` + 4-byte scalar fills one
/// 16-byte slot):
///
/// | offset | field | meaning |
/// |---|---|---|
/// | 0 | `color: Vec3` | diffuse reflectance (diffuse, plastic), or specular reflectance (conductors, dielectric) |
/// | 12 | `kind: u32` | [`DIFFUSE`] 0, `CONDUCTOR` 1, `ROUGH_CONDUCTOR` 2, `DIELECTRIC` 3, `PLASTIC` 4, `ROUGH_PLASTIC` 5, `ROUGH_DIELECTRIC` 6, `PRINCIPLED` 7, `PRINCIPLED_THIN` 8 |
/// | 16 | `emission: Vec3` | area-light radiance (front side only), zero if none |
/// | 28 | `flags: u32` | bit 0 two-sided, bit 1 emitter, bit 2 nonlinear (plastic), bit 3 Beckmann (rough conductor; else GGX), bit 4 masked, bit 5 normal map, bit 6 bump map, bit 7 no shadowing term, bit 8 no flip of invalid normals, bit 9 perturbation per side (`Perturb`), bit 10 reads the hit's texture coordinates (textured parameters, anisotropy) |
/// | 32 | `transmittance: Vec3` | dielectric specular transmittance, plastic specular reflectance, conductor eta, else zero |
/// | 44 | `param: f32` | microfacet alpha (rough conductor) or relative IOR int/ext (dielectric, plastic) |
/// | 48 | `conductor_k: Vec3` | conductor k (the imaginary part of its index); rough plastic (alpha, internal reflectance, 0); rough dielectric (alpha, 0, 0); else zero |
/// | 60 | `texture: u32` | index + 1 of the header of the texture of `color` (diffuse, plastic) in `Scene::gpu_textures`, 0 for none |
/// | 64 | `opacity: f32` | Mitsuba `mask` (flag bit 4): probability that the surface scatters; 1 without a mask |
/// | 68 | `opacity_texture: u32` | index + 1 of the header of the opacity's texture (its luminance), 0 for none |
/// | 72 | `table: u32` | rough plastic: index + 1 of the header of its transmittance table (a 64 x 1 texture); principled: index + 1 of its parameter block (`Principled::gpu_block`); rough conductor or rough dielectric with anisotropic or textured roughness: index + 1 of its block (`Roughness::gpu_block`); else 0 |
/// | 76 | `blend: u32` | Mitsuba `blendbsdf`: index + 1 of the material that scatters instead with probability `blend_weight`, else 0 |
/// | 80 | `blend_weight: f32` | that probability |
/// | 84 | `perturb_texture: u32` | normal or bump map (flag bit 5 or 6): index + 1 of its texture's header, else 0 |
/// | 88 | `bump_scale: f32` | bump map: Mitsuba's `scale` |
/// | 92 | `blend_texture: u32` | `blendbsdf` with a textured weight: index + 1 of its texture's header (its luminance, clamped, replaces `blend_weight`), else 0 |
/// | 96 | `emission_texture: u32` | index + 1 of the header of the texture that gives an area emitter's radiance per point (`Material::emission_texture`); 0: `emission` everywhere |
/// | 100 | `pad_a`..`pad_c` | |
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Material {
    /// Diffuse reflectance (diffuse, plastic), or specular reflectance.
    pub color: Vec3,
    pub kind: u32,
    pub emission: Vec3,
    pub flags: u32,
    /// Dielectric specular transmittance, plastic specular reflectance, or conductor eta.
    pub transmittance: Vec3,
    /// Microfacet alpha (rough conductor) or int_ior / ext_ior (dielectric, plastic).
    pub param: f32,
    /// Conductor k: the imaginary part of its complex index `transmittance + i k`.
    pub conductor_k: Vec3,
    /// Index + 1 of the header of the texture that replaces `color` (diffuse, plastic,
    /// conductors) in
    /// `extend`'s `textures` (`cohort_kernels::texture`); 0: `color` everywhere.
    pub texture: u32,
    /// Mitsuba `mask` (`MASKED` flag): the probability that the surface scatters (else the
    /// path passes through it), where `opacity_texture` is 0.
    pub opacity: f32,
    /// Index + 1 of the header of the texture whose luminance is the opacity; 0: `opacity`.
    pub opacity_texture: u32,
    /// Rough plastic: index + 1 of the header of its external transmittance table (a 64 x 1
    /// texture over the incident cosine, `cohort_scenes::rough_plastic`); else 0.
    pub table: u32,
    /// Mitsuba `blendbsdf`: index + 1 of the material that scatters instead of this one
    /// with probability `blend_weight` (`extend` picks before shading); 0 for none.
    pub blend: u32,
    pub blend_weight: f32,
    /// Normal or bump map: index + 1 of the header of its texture; else 0.
    pub perturb_texture: u32,
    /// Bump map: Mitsuba's `scale` of the height's gradient.
    pub bump_scale: f32,
    /// Mitsuba `blendbsdf` with a textured weight: index + 1 of the header of the texture
    /// whose luminance (clamped to [0, 1]) replaces `blend_weight`; else 0.
    pub blend_texture: u32,
    /// Area emitter with a textured radiance (Mitsuba's `radiance` texture): index + 1 of
    /// the header of that texture, whose value at a point is the radiance there; else 0.
    pub emission_texture: u32,
    pub pad_a: u32,
    pub pad_b: u32,
    pub pad_c: u32,
}

/// The parameters of a Mitsuba `principled` or `principledthin` BSDF at a hit, named as
/// Mitsuba names them (`cohort_kernels::bsdf::principled`). The sampling rates: `principled`'s
/// main specular, clearcoat and diffuse reflectance in `rate_a`..`rate_c`;
/// `principledthin`'s specular reflectance, specular transmittance, diffuse transmittance
/// and diffuse reflectance in `rate_a`..`rate_d`.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Principled {
    pub base_color: Vec3,
    pub roughness: f32,
    pub anisotropic: f32,
    pub metallic: f32,
    pub spec_trans: f32,
    pub spec_tint: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub clearcoat: f32,
    pub clearcoat_gloss: f32,
    pub flatness: f32,
    /// `principledthin` only, as Mitsuba reads it (0..2).
    pub diff_trans: f32,
    /// `principled`: the relative index (from `eta` or `specular`); `principledthin`: the
    /// film's `eta`.
    pub eta: f32,
    pub rate_a: f32,
    pub rate_b: f32,
    pub rate_c: f32,
    pub rate_d: f32,
    pub pad: u32,
}

/// What every kernel of a frame reads: camera, image, budget and the frame's seed.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Frame {
    pub cam_origin: Vec3,
    pub width: u32,
    pub cam_forward: Vec3,
    pub height: u32,
    pub cam_right: Vec3,
    /// Number of ray slots: `copies` per pixel. Slot `g` is copy `g / (slots / copies)`
    /// of pixel `slot_pixel[g]`.
    pub slots: u32,
    pub cam_up: Vec3,
    pub seed: u32,
    pub environment: Vec3,
    /// Paths per pixel after which a slot stops regenerating, counted from `first_path`
    /// (0 = never stop).
    pub paths_per_pixel: u32,
    /// Paths longer than this many bounces end (0 = no limit; Russian roulette ends them).
    pub max_depth: u32,
    /// Russian roulette starts at this bounce.
    pub rr_depth: u32,
    /// Continuation probability of Russian roulette (the paper: 0.8).
    pub rr_continue: f32,
    /// Whether the scene has any triangle (traversal of an empty scene is a miss).
    pub has_geometry: u32,
    /// Iteration of the wavefront loop (group draws change every iteration).
    pub iteration: u32,
    /// N of the N x 4N hemisphere patches of coherent sampling.
    pub patches_n: u32,
    /// 1: one Russian-roulette draw per coherence group (the paper's `_rr`).
    pub group_rr: u32,
    /// 1: glossy (GGX) bounces also sample coherently: the group shares a cell of a
    /// N x N grid over the VNDF's unit-square domain.
    pub coherent_glossy: u32,
    /// Whole-group termination (`extend::<_, WholeGroup>`): continuation probability of
    /// the roulette a group plays when one of its paths ends.
    pub group_end_continue: f32,
    /// Next-event estimation: entries of the emitter triangles' alias table (0 = no
    /// area light).
    pub light_count: u32,
    /// Next-event estimation: probability of sampling the environment instead of an
    /// emitter triangle (0 without an environment, 1 without area lights).
    pub env_light: f32,
    /// 1: a coherence group shares its light choice and a stratum of the light
    /// (`cohort_kernels::light`), as coherent sampling shares a hemisphere patch.
    pub coherent_light: u32,
    /// K of the K x K strata of a light's sample domain (coherent light sampling).
    pub light_cells: u32,
    /// Index of every pixel's first path: a shard of a render (`--shard K/N`) renders
    /// paths `first_path..first_path + paths_per_pixel`, drawing the same per-path random
    /// numbers as an unsplit run does for those paths.
    pub first_path: u32,
    /// Seed of the group draws (keyed by iteration, not by path): `seed` in an unsplit
    /// run, an independent stream per shard, so that shards do not repeat each other's
    /// group draws.
    pub group_seed: u32,
    /// Pixels sampled beyond each edge of the image with a reconstruction filter (Mitsuba's
    /// `sample_border`; 0: camera rays stay on the image).
    pub filter_border: u32,
    /// 1: Mitsuba's `hide_emitters`: camera rays pass through emitter surfaces and do not
    /// see the environment.
    pub hide_emitters: u32,
    /// 1: Mitsuba's Russian roulette: from bounce `rr_depth` - 1 on, a path continues with
    /// probability min(max component of its throughput, 0.95) (`rr_continue` unused);
    /// 0: the paper's fixed continuation probability `rr_continue`.
    pub roulette_throughput: u32,
    /// 1: Mitsuba's `max_depth` 0: no path contributes anything (`max_depth` above is
    /// 0 = unlimited).
    pub zero_depth: u32,
    /// 1: orthographic camera: camera rays start at `cam_origin` moved across the film by
    /// `cam_right` and `cam_up`, all along `cam_forward` (`cohort_scenes::CameraFrame`).
    pub orthographic: u32,
    /// Thin-lens camera (0: a pinhole): rays start on the disk of this radius around
    /// `cam_origin` (spanned by `cam_right`, `cam_up`) and meet at `focus_distance`.
    pub lens_radius: f32,
    pub focus_distance: f32,
    /// 1: triangles carry per-vertex shading normals (`extend`'s `shading_normals`), which
    /// Mitsuba interpolates for shading; 0: every triangle shades with its face normal.
    pub shading_normals: u32,
    /// Radius in pixels of the reconstruction filter whose table `extend` reads as
    /// `film_filter` (`cohort_scenes::FilmFilter::table`); 0: the box filter, each camera
    /// ray uniform in its own pixel.
    pub filter_radius: f32,
    /// Mitsuba `envmap`: where the map starts in the textures array, plus one
    /// (`cohort_kernels::environment`); 0: the environment is the constant `environment`.
    pub env_map: u32,
    /// Paths of a pixel in flight at once (the wavefront is sized to the device, not to
    /// the image): copy `k` of a pixel traces its paths `first_path + k`, `+ copies`,
    /// `+ 2 copies`, ... below `first_path + paths_per_pixel`, so the n-th path of a
    /// pixel still draws from (seed, pixel, n), whatever the number of copies.
    pub copies: u32,
    /// Invocations per coherence group where `extend` keys the group draws by the slot it
    /// shades (`cohort_kernels::group_draw`: slot `g` is in group `g / group_slots`), so
    /// that finished slots can leave the list; 0: by the invocation's group.
    pub group_slots: u32,
    pub pad2: u32,
}

/// One entry of the alias table over emitter triangles (Walker / Vose): draw entry `j`
/// uniformly, then take `tri` with probability `prob`, else `alias_tri`. Each emitter (an
/// emitting shape or a delta light) is chosen with the same probability, a shape's triangles
/// in proportion to their area (`cohort_render::lights`).
/// The selection probability divided by the area is in the triangle's `light_pdf`, for
/// the MIS weight of paths that hit it by BSDF sampling.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct LightEntry {
    pub tri: u32,
    pub alias_tri: u32,
    pub prob: f32,
    pub pad: u32,
}

/// Bit of a light id (`LightEntry::tri`, `alias_tri`) that marks an entry of the delta-light
/// table rather than a triangle.
pub const DELTA_LIGHT: u32 = 0x8000_0000;
/// `DeltaLight::kind`.
pub const POINT_LIGHT: u32 = 0;
pub const SPOT_LIGHT: u32 = 1;
pub const DIRECTIONAL_LIGHT: u32 = 2;
/// Mitsuba `projector`: `intensity` is its irradiance times `scale` (times `texture` where
/// given), `direction` the unnormalised image axis `to_world` (0, 0, 1).
pub const PROJECTOR_LIGHT: u32 = 3;

/// A light no ray can hit (Mitsuba `point`, `spot`, `directional`, `projector`), reached
/// only by next-event estimation.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct DeltaLight {
    /// Point and spot: where the light is.
    pub position: Vec3,
    pub kind: u32,
    /// Point and spot: radiant intensity (W/sr); directional: irradiance (W/m^2).
    pub intensity: Vec3,
    /// Probability that next-event estimation picks this light.
    pub select: f32,
    /// Spot and projector: rows of the inverse of the linear part of `to_world` (world ->
    /// the light's frame, whose +z is the axis), so that directions are seen as Mitsuba
    /// sees them.
    pub to_local_x: Vec3,
    /// Spot: cosine of the cutoff angle (no light outside it).
    pub cos_cutoff: f32,
    pub to_local_y: Vec3,
    /// Spot: cosine of the beam width (full intensity inside it).
    pub cos_beam: f32,
    pub to_local_z: Vec3,
    /// Spot: the cutoff angle in radians.
    pub cutoff: f32,
    /// Directional: the direction the light travels (unit); projector: `to_world` (0, 0, 1).
    pub direction: Vec3,
    /// Spot: 1 / (cutoff - beam width) in 1/radians (0 for a hard-edged spot).
    pub inv_transition: f32,
    /// Spot and projector: index + 1 of the header of the texture that colours the light
    /// (`cohort_kernels::texture`), 0 for none.
    pub texture: u32,
    /// Spot: tan(cutoff), which maps directions to its texture; projector: tan(fov_x / 2).
    pub uv_factor: f32,
    /// Projector: its image's width / height.
    pub aspect: f32,
    pub pad: u32,
}

/// `state.w` bits of a ray slot.
pub const DONE: u32 = 1;
/// Triangle index of a miss in `hit.w`.
pub const MISS: u32 = 0xffff_ffff;
/// `shadow_d.w` of a slot after `extend` with next-event estimation (as f32): what the
/// shadow pass does with the slot's path.
pub const SLOT_IDLE: f32 = 0.0;
/// The path goes on: add the unoccluded light sample to its radiance.
pub const SLOT_CONTINUES: f32 = 1.0;
/// The path ended at this vertex: add the light sample, then its estimate to the pixel.
pub const SLOT_ENDED: f32 = 2.0;
