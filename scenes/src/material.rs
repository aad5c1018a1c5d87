//! Surface materials of a [`crate::Scene`] (the Mitsuba BSDF subset the renderer implements) and
//! their packed GPU form, uploaded next to the BVH arrays and indexed by each triangle's material.

use crate::layout;
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
    /// `table` of the scene: a `TABLE_SIZE` x 1 bilinear bitmap with clamped wrapping and
    /// the identity `to_uv`, the form the kernels read it in (as the Mitsuba loader writes
    /// it).
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
    /// `Material::param` of the GPU layout and need no parameter block.
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

    pub fn to_gpu(&self) -> layout::Material {
        let mut flags = 0;
        let mut conductor_k = Vec3::ZERO;
        let (kind, color, transmittance, param) = match self.bsdf {
            Bsdf::Diffuse { reflectance } => (layout::DIFFUSE, reflectance, Vec3::ZERO, 0.0),
            Bsdf::Conductor {
                specular_reflectance,
                eta,
                k,
            } => {
                conductor_k = k;
                (layout::CONDUCTOR, specular_reflectance, eta, 0.0)
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
                    flags |= layout::BECKMANN;
                }
                (layout::ROUGH_CONDUCTOR, specular_reflectance, eta, alpha.u)
            }
            Bsdf::Dielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => (
                layout::DIELECTRIC,
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
                    flags |= layout::NONLINEAR;
                }
                (
                    layout::PLASTIC,
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
                    flags |= layout::BECKMANN;
                }
                conductor_k = Vec3::new(alpha.u, 0.0, 0.0);
                (
                    layout::ROUGH_DIELECTRIC,
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
                    flags |= layout::NONLINEAR;
                }
                if distribution == Microfacet::Beckmann {
                    flags |= layout::BECKMANN;
                }
                conductor_k = Vec3::new(alpha, internal_reflectance, 0.0);
                (
                    layout::ROUGH_PLASTIC,
                    diffuse_reflectance,
                    specular_reflectance,
                    eta,
                )
            }
            Bsdf::Principled(params) => {
                let kind = if params.thin {
                    layout::PRINCIPLED_THIN
                } else {
                    layout::PRINCIPLED
                };
                (kind, params.base_color, Vec3::ZERO, params.eta)
            }
        };
        if self.two_sided {
            flags |= layout::TWO_SIDED;
        }
        if self.emission.is_some() {
            flags |= layout::EMITTER;
        }
        if self.mask.is_some() {
            flags |= layout::MASKED;
        }
        let mut bump_scale = 0.0;
        if let Some(p) = self.perturb {
            flags |= match p.kind {
                PerturbKind::Normal => layout::NORMAL_MAP,
                PerturbKind::Bump { scale } => {
                    bump_scale = scale;
                    layout::BUMP_MAP
                }
            };
            if !p.shadowing {
                flags |= layout::NO_SHADOWING;
            }
            if !p.flip_invalid {
                flags |= layout::NO_FLIP;
            }
            if p.per_side {
                flags |= layout::PERTURB_PER_SIDE;
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
            flags |= layout::READS_UV;
        }
        layout::Material {
            color,
            kind,
            emission: self.emission.unwrap_or(Vec3::ZERO),
            flags,
            transmittance,
            param,
            conductor_k,
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
            pad_a: 0,
            pad_b: 0,
            pad_c: 0,
            // Set by `Scene::gpu_materials`.
            perturb_texture: 0,
            bump_scale,
        }
    }
}
