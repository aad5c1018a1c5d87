//! Surface materials of a [`crate::Scene`] (the Mitsuba BSDF subset the renderer implements) and
//! their packed GPU form, uploaded next to the BVH arrays and indexed by each triangle's material.

use glam::Vec3;

/// The scattering part of a material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    /// Lambertian. One-sided, like Mitsuba: a hit on the back reflects nothing unless the material
    /// is [`Material::two_sided`].
    Diffuse { reflectance: Vec3 },
    /// Smooth conductor (Mitsuba `conductor`): mirror reflection weighted by the conductor
    /// Fresnel factor of the complex index `eta + i k` (Mitsuba's default `material` = none
    /// is eta 0, k 1: a factor of 1) times `specular_reflectance`.
    Conductor {
        specular_reflectance: Vec3,
        eta: Vec3,
        k: Vec3,
    },
    /// Microfacet conductor (Mitsuba `roughconductor`), GGX or Beckmann, isotropic or
    /// anisotropic, with the same Fresnel factor as [`Bsdf::Conductor`].
    RoughConductor {
        alpha: Roughness,
        distribution: Microfacet,
        specular_reflectance: Vec3,
        eta: Vec3,
        k: Vec3,
    },
    /// Smooth glass. Inside is the side the face normal points away from.
    Dielectric {
        int_ior: f32,
        ext_ior: f32,
        /// Mitsuba's optional factors; the stanford-like scene sets them to 0.8 ("all albedos 0.8").
        specular_reflectance: Vec3,
        specular_transmittance: Vec3,
    },
    /// Mitsuba `plastic`: a diffuse base under a smooth dielectric coating of relative index
    /// `eta` (int/ext); light reflects off the coating (Fresnel, times
    /// `specular_reflectance`) or enters, scatters in the base and leaves, with the internal
    /// reflections Mitsuba accounts for (`nonlinear`: also the base's colour shift). One-sided.
    Plastic {
        eta: f32,
        diffuse_reflectance: Vec3,
        specular_reflectance: Vec3,
        nonlinear: bool,
    },
    /// Mitsuba `roughdielectric`: a rough glass interface (GGX or Beckmann, anisotropic and
    /// textured roughness as `roughconductor`'s) of relative index `eta` (int/ext) that
    /// reflects or refracts off sampled microfacets.
    RoughDielectric {
        eta: f32,
        alpha: Roughness,
        distribution: Microfacet,
        specular_reflectance: Vec3,
        specular_transmittance: Vec3,
    },
    /// Mitsuba `roughplastic`: [`Bsdf::Plastic`] with a rough (microfacet) coating: its
    /// glossy reflection, and the base's light through the rough interface, weighted by
    /// the precomputed transmittance table ([`crate::rough_plastic`]) stored as texture
    /// `table` of the scene.
    RoughPlastic {
        eta: f32,
        alpha: f32,
        distribution: Microfacet,
        diffuse_reflectance: Vec3,
        specular_reflectance: Vec3,
        nonlinear: bool,
        internal_reflectance: f32,
        table: u32,
    },
    /// Mitsuba `principled` or `principledthin` (`cohort_kernels::principled`). Its
    /// parameters reach the kernels as a block of the scene's texture array
    /// ([`Principled::gpu_block`], placed by `Scene::gpu_textures`).
    Principled(Principled),
}

/// Microfacet roughness as Mitsuba's `roughconductor` reads it: alpha along the shading
/// frame's s (dp/du) and t, each a number or the texture (index into
/// [`crate::Scene::textures`]) whose luminance it is per hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roughness {
    pub u: f32,
    pub v: f32,
    pub u_texture: Option<u32>,
    pub v_texture: Option<u32>,
}

impl Roughness {
    pub fn isotropic(alpha: f32) -> Self {
        Roughness {
            u: alpha,
            v: alpha,
            u_texture: None,
            v_texture: None,
        }
    }

    /// One number everywhere and in every direction: the kernels read it from
    /// `GpuMaterial::param` and need no parameter block.
    pub fn is_constant_isotropic(&self) -> bool {
        self.u == self.v && self.u_texture.is_none() && self.v_texture.is_none()
    }

    /// The parameter block the kernels read where it is not
    /// [`is_constant_isotropic`](Self::is_constant_isotropic)
    /// (`cohort_kernels::rough_conductor::alpha`): alpha_u, alpha_v and the headers + 1 of
    /// their textures in `starts` (0: none).
    pub fn gpu_block(&self, starts: &[u32]) -> [f32; 4] {
        let header = |t: Option<u32>| f32::from_bits(t.map_or(0, |t| starts[t as usize] + 1));
        [
            self.u,
            self.v,
            header(self.u_texture),
            header(self.v_texture),
        ]
    }
}

/// The parameters of a Mitsuba `principled` / `principledthin` BSDF, as Mitsuba reads
/// them (`eta` already derived from `specular` where that was given).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Principled {
    pub thin: bool,
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
    pub diff_trans: f32,
    pub eta: f32,
    /// `principled`: main specular, clearcoat, diffuse reflectance, unused;
    /// `principledthin`: specular reflectance, specular transmittance, diffuse
    /// transmittance, diffuse reflectance.
    pub sampling_rates: [f32; 4],
    /// The textures (indices into [`crate::Scene::textures`]) whose luminance replaces a
    /// number per hit, in [`Principled::TEXTURED`]'s order (Mitsuba reads every one of
    /// them with `eval_1`).
    pub textures: [Option<u32>; 11],
}

impl Principled {
    /// The parameters that may be textures, in the order of [`Principled::textures`].
    pub const TEXTURED: [&'static str; 11] = [
        "roughness",
        "anisotropic",
        "metallic",
        "spec_trans",
        "spec_tint",
        "sheen",
        "sheen_tint",
        "clearcoat",
        "clearcoat_gloss",
        "flatness",
        "diff_trans",
    ];

    /// The parameter block the kernels read (`cohort_kernels::principled::params`):
    /// [`Principled::GPU_BLOCK`] entries of the texture array: the numbers, the sampling
    /// rates, then the headers + 1 of the parameters' textures in `starts` (0: a number).
    /// A textured anisotropy is marked 1 in the numbers, so that the kernels turn the
    /// frame with dp/du.
    pub fn gpu_block(&self, starts: &[u32]) -> [[f32; 4]; Principled::GPU_BLOCK] {
        let r = self.sampling_rates;
        let anisotropic = if self.textures[1].is_some() {
            1.0
        } else {
            self.anisotropic
        };
        let t = |k: usize| {
            f32::from_bits(
                self.textures
                    .get(k)
                    .copied()
                    .flatten()
                    .map_or(0, |t| starts[t as usize] + 1),
            )
        };
        [
            [self.roughness, anisotropic, self.metallic, self.spec_trans],
            [self.spec_tint, self.sheen, self.sheen_tint, self.clearcoat],
            [
                self.clearcoat_gloss,
                self.flatness,
                self.diff_trans,
                self.eta,
            ],
            [r[0], r[1], r[2], r[3]],
            [t(0), t(1), t(2), t(3)],
            [t(4), t(5), t(6), t(7)],
            [t(8), t(9), t(10), t(11)],
        ]
    }

    /// Whether a parameter is a texture (or the frame turns with dp/du): the kernels then
    /// need the hit's texture coordinates.
    pub fn reads_tex_coords(&self) -> bool {
        self.anisotropic != 0.0 || self.textures.iter().any(Option::is_some)
    }

    pub const GPU_BLOCK: usize = 7;
}

/// A microfacet normal distribution (Mitsuba's `distribution`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Microfacet {
    Ggx,
    /// Mitsuba's default.
    Beckmann,
}

/// Mitsuba's conductor `material` = none: eta 0, k 1, a Fresnel factor of 1.
pub const PERFECT_CONDUCTOR: (Vec3, Vec3) = (Vec3::ZERO, Vec3::ONE);

/// A BSDF plus, optionally, an area emitter on the same surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub bsdf: Bsdf,
    /// Mitsuba `twosided`: the back side scatters like the front. Meaningless for dielectrics.
    pub two_sided: bool,
    /// Radiance of a Mitsuba `area` emitter: emitted only on the front (face-normal) side.
    pub emission: Option<Vec3>,
    /// Index into [`crate::Scene::textures`] of the texture that gives an `area` emitter's
    /// radiance per point (Mitsuba's textured `radiance`); `emission` is then its mean.
    pub emission_texture: Option<u32>,
    /// Index into [`crate::Scene::textures`] of the texture that gives the BSDF's colour
    /// (diffuse `reflectance`, plastic `diffuse_reflectance`, conductor
    /// `specular_reflectance`) where it is not a constant.
    pub texture: Option<u32>,
    /// Mitsuba `mask` around the BSDF: where it is not opaque, paths pass through.
    pub mask: Option<Mask>,
    /// Mitsuba `blendbsdf`: with probability `weight` the material [`Blend::other`] scatters
    /// instead of this one (which is the blend's first BSDF).
    pub blend: Option<Blend>,
    /// Mitsuba `normalmap` or `bumpmap` around the BSDF.
    pub perturb: Option<Perturb>,
}

/// Mitsuba `normalmap` / `bumpmap`: the BSDF shades in a frame whose normal a texture
/// perturbs (`cohort_kernels::perturb`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Perturb {
    pub kind: PerturbKind,
    /// Index into [`crate::Scene::textures`]: the normal map (RGB = (n + 1) / 2 in the
    /// shading frame), or the height whose luminance's gradient bumps the surface.
    pub texture: u32,
    /// Mitsuba's `use_shadowing_function` (default true): Estevez et al.'s shadowing term.
    pub shadowing: bool,
    /// Mitsuba's `flip_invalid_normals` (default true): a perturbed normal facing away from
    /// the viewer is mirrored about the shading normal.
    pub flip_invalid: bool,
    /// A `twosided` around the map: on the back side the map applies in the shading frame
    /// mirrored to that side, as Mitsuba's `twosided` evaluates its nested BSDF.
    pub per_side: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PerturbKind {
    Normal,
    /// Mitsuba's `scale` multiplies the height's gradient.
    Bump {
        scale: f32,
    },
}

/// The second BSDF of a Mitsuba `blendbsdf` and its weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blend {
    pub weight: f32,
    /// Index into [`crate::Scene::textures`] of the texture whose luminance (clamped to
    /// [0, 1]) is the weight per hit, in place of `weight`.
    pub texture: Option<u32>,
    /// Index into [`crate::Scene::materials`] of the second BSDF's material (which carries
    /// the blend's emission, sidedness and mask too).
    pub other: u32,
}

/// Mitsuba `mask`: the surface scatters with probability `opacity` (the luminance of the
/// texture `texture` where given), else the path passes through it unchanged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mask {
    pub opacity: f32,
    /// Index into [`crate::Scene::textures`].
    pub texture: Option<u32>,
}

impl Material {
    pub fn diffuse(reflectance: Vec3) -> Self {
        Material {
            bsdf: Bsdf::Diffuse { reflectance },
            two_sided: false,
            emission: None,
            texture: None,
            mask: None,
            blend: None,
            perturb: None,
            emission_texture: None,
        }
    }

    pub fn diffuse_two_sided(reflectance: Vec3) -> Self {
        Material {
            two_sided: true,
            ..Material::diffuse(reflectance)
        }
    }

    pub fn mirror(specular_reflectance: Vec3) -> Self {
        Material {
            bsdf: Bsdf::Conductor {
                specular_reflectance,
                eta: PERFECT_CONDUCTOR.0,
                k: PERFECT_CONDUCTOR.1,
            },
            two_sided: false,
            emission: None,
            texture: None,
            mask: None,
            blend: None,
            perturb: None,
            emission_texture: None,
        }
    }

    /// A GGX rough conductor without Fresnel (`material` = none).
    pub fn rough_conductor(alpha: f32, specular_reflectance: Vec3) -> Self {
        Material {
            bsdf: Bsdf::RoughConductor {
                alpha: Roughness::isotropic(alpha),
                distribution: Microfacet::Ggx,
                specular_reflectance,
                eta: PERFECT_CONDUCTOR.0,
                k: PERFECT_CONDUCTOR.1,
            },
            two_sided: false,
            emission: None,
            texture: None,
            mask: None,
            blend: None,
            perturb: None,
            emission_texture: None,
        }
    }

    pub fn glass(int_ior: f32, ext_ior: f32, factor: Vec3) -> Self {
        Material {
            bsdf: Bsdf::Dielectric {
                int_ior,
                ext_ior,
                specular_reflectance: factor,
                specular_transmittance: factor,
            },
            two_sided: false,
            emission: None,
            texture: None,
            mask: None,
            blend: None,
            perturb: None,
            emission_texture: None,
        }
    }

    /// A one-sided area light with a black diffuse BSDF, so a path that hits it ends there (the
    /// convention of the reference scenes).
    pub fn emitter(radiance: Vec3) -> Self {
        Material {
            emission: Some(radiance),
            ..Material::diffuse(Vec3::ZERO)
        }
    }

    pub fn is_diffuse(&self) -> bool {
        matches!(self.bsdf, Bsdf::Diffuse { .. })
    }

    pub fn to_gpu(&self) -> GpuMaterial {
        let mut flags = 0;
        let mut conductor_k = Vec3::ZERO;
        let (kind, color, transmittance, param) = match self.bsdf {
            Bsdf::Diffuse { reflectance } => (GpuMaterial::DIFFUSE, reflectance, Vec3::ZERO, 0.0),
            Bsdf::Conductor {
                specular_reflectance,
                eta,
                k,
            } => {
                conductor_k = k;
                (GpuMaterial::CONDUCTOR, specular_reflectance, eta, 0.0)
            }
            Bsdf::RoughConductor {
                alpha,
                distribution,
                specular_reflectance,
                eta,
                k,
            } => {
                conductor_k = k;
                if distribution == Microfacet::Beckmann {
                    flags |= GpuMaterial::FLAG_BECKMANN;
                }
                (
                    GpuMaterial::ROUGH_CONDUCTOR,
                    specular_reflectance,
                    eta,
                    alpha.u,
                )
            }
            Bsdf::Dielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => (
                GpuMaterial::DIELECTRIC,
                specular_reflectance,
                specular_transmittance,
                int_ior / ext_ior,
            ),
            Bsdf::Plastic {
                eta,
                diffuse_reflectance,
                specular_reflectance,
                nonlinear,
            } => {
                if nonlinear {
                    flags |= GpuMaterial::FLAG_NONLINEAR;
                }
                (
                    GpuMaterial::PLASTIC,
                    diffuse_reflectance,
                    specular_reflectance,
                    eta,
                )
            }
            Bsdf::RoughDielectric {
                eta,
                alpha,
                distribution,
                specular_reflectance,
                specular_transmittance,
            } => {
                if distribution == Microfacet::Beckmann {
                    flags |= GpuMaterial::FLAG_BECKMANN;
                }
                conductor_k = Vec3::new(alpha.u, 0.0, 0.0);
                (
                    GpuMaterial::ROUGH_DIELECTRIC,
                    specular_reflectance,
                    specular_transmittance,
                    eta,
                )
            }
            Bsdf::RoughPlastic {
                eta,
                alpha,
                distribution,
                diffuse_reflectance,
                specular_reflectance,
                nonlinear,
                internal_reflectance,
                table: _,
            } => {
                if nonlinear {
                    flags |= GpuMaterial::FLAG_NONLINEAR;
                }
                if distribution == Microfacet::Beckmann {
                    flags |= GpuMaterial::FLAG_BECKMANN;
                }
                conductor_k = Vec3::new(alpha, internal_reflectance, 0.0);
                (
                    GpuMaterial::ROUGH_PLASTIC,
                    diffuse_reflectance,
                    specular_reflectance,
                    eta,
                )
            }
            Bsdf::Principled(params) => {
                let kind = if params.thin {
                    GpuMaterial::PRINCIPLED_THIN
                } else {
                    GpuMaterial::PRINCIPLED
                };
                (kind, params.base_color, Vec3::ZERO, params.eta)
            }
        };
        if self.two_sided {
            flags |= GpuMaterial::FLAG_TWO_SIDED;
        }
        if self.emission.is_some() {
            flags |= GpuMaterial::FLAG_EMITTER;
        }
        if self.mask.is_some() {
            flags |= GpuMaterial::FLAG_MASKED;
        }
        let mut bump_scale = 0.0;
        if let Some(p) = self.perturb {
            flags |= match p.kind {
                PerturbKind::Normal => GpuMaterial::FLAG_NORMAL_MAP,
                PerturbKind::Bump { scale } => {
                    bump_scale = scale;
                    GpuMaterial::FLAG_BUMP_MAP
                }
            };
            if !p.shadowing {
                flags |= GpuMaterial::FLAG_NO_SHADOWING;
            }
            if !p.flip_invalid {
                flags |= GpuMaterial::FLAG_NO_FLIP;
            }
            if p.per_side {
                flags |= GpuMaterial::FLAG_PERTURB_PER_SIDE;
            }
        }
        let reads_uv = match self.bsdf {
            Bsdf::Principled(p) => p.textures.iter().any(Option::is_some),
            Bsdf::RoughConductor { alpha, .. } | Bsdf::RoughDielectric { alpha, .. } => {
                !alpha.is_constant_isotropic()
            }
            _ => false,
        };
        if reads_uv {
            flags |= GpuMaterial::FLAG_READS_UV;
        }
        GpuMaterial {
            color: color.to_array(),
            kind,
            emission: self.emission.unwrap_or(Vec3::ZERO).to_array(),
            flags,
            transmittance: transmittance.to_array(),
            param,
            conductor_k: conductor_k.to_array(),
            // Set by `Scene::gpu_materials`, which knows where the textures go.
            texture: 0,
            opacity: self.mask.map_or(1.0, |m| m.opacity),
            opacity_texture: 0,
            table: 0,
            // Set by `Scene::gpu_materials`, which knows where the other materials are.
            blend: 0,
            blend_weight: 0.0,
            blend_texture: 0,
            emission_texture: 0,
            pad: [0; 3],
            // Set by `Scene::gpu_materials`.
            perturb_texture: 0,
            bump_scale,
        }
    }
}

/// Packed material, 96 bytes, std430/WGSL compatible (each `[f32; 3]` + 4-byte scalar fills one
/// 16-byte slot):
///
/// | offset | field | meaning |
/// |---|---|---|
/// | 0 | `color: [f32;3]` | diffuse reflectance (diffuse, plastic), or specular reflectance (conductors, dielectric) |
/// | 12 | `kind: u32` | `DIFFUSE` 0, `CONDUCTOR` 1, `ROUGH_CONDUCTOR` 2, `DIELECTRIC` 3, `PLASTIC` 4, `ROUGH_PLASTIC` 5, `ROUGH_DIELECTRIC` 6, `PRINCIPLED` 7, `PRINCIPLED_THIN` 8 |
/// | 16 | `emission: [f32;3]` | area-light radiance (front side only), zero if none |
/// | 28 | `flags: u32` | bit 0 two-sided, bit 1 emitter, bit 2 nonlinear (plastic), bit 3 Beckmann (rough conductor; else GGX), bit 4 masked, bit 5 normal map, bit 6 bump map, bit 7 no shadowing term, bit 8 no flip of invalid normals, bit 9 perturbation per side (`Perturb`), bit 10 reads the hit's texture coordinates (textured parameters, anisotropy) |
/// | 32 | `transmittance: [f32;3]` | dielectric specular transmittance, plastic specular reflectance, conductor eta, else zero |
/// | 44 | `param: f32` | microfacet alpha (rough conductor) or relative IOR int/ext (dielectric, plastic) |
/// | 48 | `conductor_k: [f32;3]` | conductor k (the imaginary part of its index); rough plastic (alpha, internal reflectance, 0); rough dielectric (alpha, 0, 0); else zero |
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
/// | 100 | `pad: [u32; 3]` | |
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuMaterial {
    pub color: [f32; 3],
    pub kind: u32,
    pub emission: [f32; 3],
    pub flags: u32,
    pub transmittance: [f32; 3],
    pub param: f32,
    pub conductor_k: [f32; 3],
    pub texture: u32,
    pub opacity: f32,
    pub opacity_texture: u32,
    pub table: u32,
    pub blend: u32,
    pub blend_weight: f32,
    pub perturb_texture: u32,
    pub bump_scale: f32,
    pub blend_texture: u32,
    pub emission_texture: u32,
    pub pad: [u32; 3],
}

impl GpuMaterial {
    pub const DIFFUSE: u32 = 0;
    pub const CONDUCTOR: u32 = 1;
    pub const ROUGH_CONDUCTOR: u32 = 2;
    pub const DIELECTRIC: u32 = 3;
    pub const PLASTIC: u32 = 4;
    pub const ROUGH_PLASTIC: u32 = 5;
    pub const ROUGH_DIELECTRIC: u32 = 6;
    pub const PRINCIPLED: u32 = 7;
    pub const PRINCIPLED_THIN: u32 = 8;
    pub const FLAG_TWO_SIDED: u32 = 1;
    pub const FLAG_EMITTER: u32 = 2;
    pub const FLAG_NONLINEAR: u32 = 4;
    pub const FLAG_BECKMANN: u32 = 8;
    pub const FLAG_MASKED: u32 = 16;
    pub const FLAG_NORMAL_MAP: u32 = 32;
    pub const FLAG_BUMP_MAP: u32 = 64;
    pub const FLAG_NO_SHADOWING: u32 = 128;
    pub const FLAG_NO_FLIP: u32 = 256;
    pub const FLAG_PERTURB_PER_SIDE: u32 = 512;
    /// The BSDF reads parameters (textures) or turns with dp/du at the hit's texture
    /// coordinates.
    pub const FLAG_READS_UV: u32 = 1024;
}

const _: () = assert!(std::mem::size_of::<GpuMaterial>() == 112);
