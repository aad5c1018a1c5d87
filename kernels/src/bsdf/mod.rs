//! The BSDFs the renderer shades with: one [`Bsdf`] impl per BSDF, each in its own file,
//! and one table (the `bsdfs!` invocation at the end) that lists them. The table is the only place a BSDF is
//! named: it generates the material kinds' names ([`KINDS`], used for labels, `--stats`
//! and the scene-set bits of `crate::shading`), and the three dispatches `extend` and
//! [`crate::scatter`] call on a material — [`bsdf_light_sampled`], [`bsdf_shade`] and
//! [`bsdf_eval`] — each a chain over the table in which the BSDFs outside the scene's
//! shading set (a `#[specialize]` value of `extend`) are false when the kernel is built
//! and left out. Adding a BSDF is one file with its impl and one line of the table (plus
//! its kind constant in `cohort_layout` and its parameters in the scene loader).
//!
//! `blendbsdf`, `mask` and normal or bump maps are not kinds: they compose the BSDFs of
//! the table at run time (a blend nests materials, a mask or a map wraps any kind), so
//! `extend` applies them around these dispatches (`crate::scatter`, `crate::perturb`).
//!
//! Every dispatch takes the texture buffer, so that the macro inlines it into its caller
//! (helpers taking buffers are inlined) where `shading` is a constant.

pub mod conductor;
pub mod dielectric;
pub mod diffuse;
pub mod plastic;
pub mod principled;
pub mod rough_conductor;
pub mod rough_dielectric;
pub mod rough_plastic;

use crate::layout::*;
use crate::sampling::DiffuseSampler;
use cohort::prelude::*;

/// What a BSDF's `sample` draws from: the vertex's random numbers and the strategy's
/// group value for cosine-weighted lobes.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Draws {
    /// The direction's two numbers (`extend`'s dimensions 2 and 3).
    pub u: Vec2,
    /// `u` placed in the group's shared cell where coherent glossy sampling is on (else
    /// `u`): glossy lobes sampled by a measure-preserving warp draw from it.
    pub u_glossy: Vec2,
    /// The number that picks a lobe (dimension 4).
    pub choice: f32,
    /// The group's draw of the diffuse strategy `S` (`DiffuseSampler::group_value`).
    pub group_value: u32,
    /// N of the strategy's N x 4N patches.
    pub patches_n: u32,
    /// 1: `group_params` holds `S::group_params(group_value, patches_n)`, read from the
    /// group table, and the strategy samples with it ([`diffuse_direction`]); 0: it is
    /// unset.
    pub grouped: u32,
    /// The strategy's values of the group (`DiffuseSampler::group_params`) where `grouped`.
    pub group_params: Vec4,
}

/// The diffuse strategy `S`'s direction and weight for a bounce at normal `n`
/// (`DiffuseSampler::sample`), from the group's parameters where the group table holds
/// them.
#[kernel_fn]
pub fn diffuse_direction<S: DiffuseSampler>(n: Vec3, r: Draws) -> Vec4 {
    if S::GROUP_PARAMS && r.grouped != 0 {
        S::sample_grouped(n, r.u, r.group_value, r.group_params, r.patches_n)
    } else {
        S::sample(n, r.u, r.group_value, r.patches_n)
    }
}

/// A direction a BSDF drew ([`Bsdf::sample`]) and how the path carries on.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Scattered {
    /// The new direction (world space, unit).
    pub dir: Vec3,
    /// Its BSDF-sampling density for MIS; 0 for a delta lobe (a light it reaches counts in
    /// full).
    pub pdf: f32,
    /// The path throughput after the bounce (the incoming one times f·cos / density).
    pub beta: Vec3,
    /// The probability with which the BSDF chose the delta lobe it drew (0: none): a
    /// blend weighs a delta direction with it (`crate::scatter`).
    pub delta_p: f32,
    /// The factor of the path's eta² (a refraction's eta², else 1): Mitsuba's roulette
    /// weighs the throughput times the product.
    pub eta2: f32,
    /// 1: the path goes on; 0: the BSDF drew nothing (absorbed).
    pub alive: u32,
    pub pad_a: u32,
    pub pad_b: u32,
}

/// What [`Bsdf::shade`] returns: the BSDF at the light sample's direction and the
/// direction it drew.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Shaded {
    /// `f · cos` (xyz) and the BSDF-sampling density (w) towards the light sample (zero
    /// where it was not asked for).
    pub eval: Vec4,
    /// The next direction ([`absorbed`] where it was not asked for).
    pub next: Scattered,
}

/// A surface point as a BSDF sees it ([`hit`] makes one). Directions are world-space.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Hit {
    /// The material: one BSDF (a blend's chosen one, or each of a blend's in turn).
    pub m: Material,
    pub t: Triangle,
    /// The hit: distance, barycentric weights of v1 and v2, the triangle (bits).
    pub h: Vec4,
    /// The material's colour, its texture already looked up.
    pub albedo: Vec3,
    /// 1: the ray meets the surface's front side.
    pub front: u32,
    /// The texture coordinates where the material reads them (else zero).
    pub uv: Vec2,
    pub pad_uv: Vec2,
    /// The ray's direction (towards the surface).
    pub d: Vec3,
    pub pad_d: u32,
    /// The shading normal on the side the ray arrives from (a normal or bump map's).
    pub n: Vec3,
    pub pad_n: u32,
    /// The geometric normal.
    pub ng: Vec3,
    pub pad_ng: u32,
}

/// The [`Hit`] of these values.
#[kernel_fn]
pub fn hit(
    m: Material,
    t: Triangle,
    h: Vec4,
    albedo: Vec3,
    uv: Vec2,
    d: Vec3,
    n: Vec3,
    ng: Vec3,
    front: bool,
) -> Hit {
    Hit {
        m,
        t,
        h,
        albedo,
        front: if front { 1 } else { 0 },
        uv,
        pad_uv: Vec2::ZERO,
        d,
        pad_d: 0,
        n,
        pad_n: 0,
        ng,
        pad_ng: 0,
    }
}

/// A BSDF as the kernels shade it.
#[kernel_trait]
pub trait Bsdf {
    /// The material kinds it shades, one bit each (`1 << Material::kind`).
    const KINDS: u32;
    /// It has a non-delta lobe: light sampling at its vertices meets it ([`Bsdf::eval`]
    /// is not zero), and the directions it draws there carry densities for MIS.
    const NON_DELTA: bool;

    /// Whether the material scatters at all from the side the ray arrives from: by
    /// default only a `twosided` material scatters from the back, as in Mitsuba, whose
    /// one-sided BSDFs are black there.
    fn scatters(at: Hit) -> bool {
        at.front != 0 || at.m.flags & TWO_SIDED != 0
    }

    /// Draws the next direction with the numbers `r`, the diffuse lobes through strategy
    /// `S`, for a path of throughput `beta` (only called where [`Bsdf::scatters`]).
    fn sample<S: DiffuseSampler>(
        textures: &[Vec4],
        tex_coords: &[Vec4],
        at: Hit,
        beta: Vec3,
        r: Draws,
    ) -> Scattered;

    /// `f · cos` (xyz) and the BSDF-sampling density (w) for light arriving from `wi`
    /// (only called where [`Bsdf::scatters`]; zero for a BSDF without a non-delta lobe).
    fn eval(textures: &[Vec4], tex_coords: &[Vec4], at: Hit, wi: Vec3) -> Vec4;

    /// A vertex's whole use of the BSDF, as `extend` makes it: [`Bsdf::eval`] towards the
    /// light sample `wi` where `evaluate`, and [`Bsdf::sample`] where `draw`. One call
    /// site in the kernel instead of two: a BSDF whose parameters cost texture reads (a
    /// principled BSDF's dozen) overrides it to read them once, which halves its share
    /// of the kernel's code (pipeline creation time grows with it).
    fn shade<S: DiffuseSampler>(
        textures: &[Vec4],
        tex_coords: &[Vec4],
        at: Hit,
        wi: Vec3,
        evaluate: bool,
        beta: Vec3,
        r: Draws,
        draw: bool,
    ) -> Shaded {
        let mut eval = Vec4::ZERO;
        if Self::NON_DELTA && evaluate {
            eval = Self::eval(textures, tex_coords, at, wi);
        }
        let mut next = absorbed();
        if draw {
            next = Self::sample::<S>(textures, tex_coords, at, beta, r);
        }
        Shaded { eval, next }
    }
}

/// The [`Scattered`] of a path the BSDF ends (nothing drawn).
#[kernel_fn]
pub fn absorbed() -> Scattered {
    Scattered {
        dir: Vec3::ZERO,
        pdf: 0.0,
        beta: Vec3::ZERO,
        delta_p: 0.0,
        eta2: 1.0,
        alive: 0,
        pad_a: 0,
        pad_b: 0,
    }
}

/// The [`Scattered`] of a path that goes on along `dir`.
#[kernel_fn]
pub fn scattered(dir: Vec3, pdf: f32, beta: Vec3, delta_p: f32, eta2: f32) -> Scattered {
    Scattered {
        dir,
        pdf,
        beta,
        delta_p,
        eta2,
        alive: 1,
        pad_a: 0,
        pad_b: 0,
    }
}

/// Generates, from the table of BSDFs (`Type: [KIND "name", ..]`, one line per BSDF),
/// [`KINDS`] and the dispatches over it.
macro_rules! bsdfs {
    ($($ty:ident: [$($kind:ident $name:literal),+],)+) => {
        /// Every material kind and its name in labels and `--stats` (Mitsuba's plugin
        /// name), in table order.
        pub const KINDS: &[(u32, &str)] = &[$($(($kind, $name)),+),+];

        /// Whether light sampling applies at `at`: its BSDF scatters from this side and has
        /// a non-delta lobe. Only the kinds in `shading` are built.
        #[kernel_fn]
        pub fn bsdf_light_sampled(shading: u32, _textures: &[Vec4], at: Hit) -> bool {
            let bit = 1u32 << at.m.kind;
            let mut lit = false;
            $(
                if shading & <$ty as Bsdf>::KINDS != 0 && bit & <$ty as Bsdf>::KINDS != 0 {
                    lit = <$ty as Bsdf>::NON_DELTA && <$ty as Bsdf>::scatters(at);
                }
            )+
            lit
        }

        /// [`Bsdf::shade`] of the BSDF at `at`: its value towards `wi` where `evaluate`
        /// and it has a non-delta lobe, the next direction where `draw`; zero and
        /// [`absorbed`] where it does not scatter (a one-sided BSDF seen from the back, a
        /// black diffuse surface, a kind outside `shading`).
        #[kernel_fn]
        pub fn bsdf_shade<S: DiffuseSampler>(
            shading: u32,
            textures: &[Vec4],
            tex_coords: &[Vec4],
            at: Hit,
            wi: Vec3,
            evaluate: bool,
            beta: Vec3,
            r: Draws,
            draw: bool,
        ) -> Shaded {
            let bit = 1u32 << at.m.kind;
            let mut out = Shaded {
                eval: Vec4::ZERO,
                next: absorbed(),
            };
            $(
                if shading & <$ty as Bsdf>::KINDS != 0
                    && bit & <$ty as Bsdf>::KINDS != 0
                    && <$ty as Bsdf>::scatters(at)
                {
                    out = <$ty as Bsdf>::shade::<S>(
                        textures, tex_coords, at, wi, evaluate, beta, r, draw,
                    );
                }
            )+
            out
        }

        /// [`Bsdf::eval`] of the BSDF at `at`: `f · cos` (xyz) and the BSDF-sampling
        /// density (w) for light arriving from `wi`; zero where it does not scatter.
        #[kernel_fn]
        pub fn bsdf_eval(
            shading: u32,
            textures: &[Vec4],
            tex_coords: &[Vec4],
            at: Hit,
            wi: Vec3,
        ) -> Vec4 {
            let bit = 1u32 << at.m.kind;
            let mut out = Vec4::ZERO;
            $(
                if shading & <$ty as Bsdf>::KINDS != 0
                    && <$ty as Bsdf>::NON_DELTA
                    && bit & <$ty as Bsdf>::KINDS != 0
                    && <$ty as Bsdf>::scatters(at)
                {
                    out = <$ty as Bsdf>::eval(textures, tex_coords, at, wi);
                }
            )+
            out
        }
    };
}

use conductor::Conductor;
use dielectric::Dielectric;
use diffuse::Diffuse;
use plastic::Plastic;
use principled::PrincipledBsdf;
use rough_conductor::RoughConductor;
use rough_dielectric::RoughDielectric;
use rough_plastic::RoughPlastic;

// The table: each BSDF and the kinds (`cohort_layout` constants) with their names.
bsdfs! {
    Diffuse: [DIFFUSE "diffuse"],
    Conductor: [CONDUCTOR "conductor"],
    RoughConductor: [ROUGH_CONDUCTOR "roughconductor"],
    Dielectric: [DIELECTRIC "dielectric"],
    Plastic: [PLASTIC "plastic"],
    RoughPlastic: [ROUGH_PLASTIC "roughplastic"],
    RoughDielectric: [ROUGH_DIELECTRIC "roughdielectric"],
    PrincipledBsdf: [PRINCIPLED "principled", PRINCIPLED_THIN "principledthin"],
}
