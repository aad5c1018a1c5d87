//! The scene as plain data: what every source (Mitsuba XML loader, embedded generators) produces
//! and what the BVH builder and the renderer's upload code consume. Geometry is a flat
//! structure-of-arrays triangle soup in world space, because the GPU wants exactly that after the
//! BVH has reordered it; nothing here knows about files or GPUs.

use glam::{Mat4, Vec3};
use std::ops::Range;

use crate::camera::Camera;
use crate::material::Material;

/// World-space triangles, structure-of-arrays, NOT indexed: vertex `k` of triangle `i` is
/// `positions[3 * i + k]`.
///
/// Non-indexed because the BVH reorders triangles into leaf order and the traversal kernel then
/// reads three consecutive vertices; an index buffer would add one dependent load per hit test and
/// save memory only on meshes we never render large enough for it to matter.
///
/// The geometric (face) normal is always `normalize(cross(v1 - v0, v2 - v0))` (Mitsuba's rule, after
/// `to_world`); counter-clockwise winding is the front. Where the triangles carry shading normals,
/// the renderer shades in the frame of the interpolated one, as Mitsuba does: it decides
/// one-sidedness (diffuse/conductor back faces are black, area lights emit only on its side) and
/// inside/outside for dielectrics; new rays leave along the geometric normal.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Triangles {
    /// 3 per triangle.
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, 3 per triangle, or `None` when every triangle shades with its face
    /// normal. When only some meshes are smooth, the flat ones carry their face normal three times,
    /// so the renderer never needs a per-triangle branch.
    pub normals: Option<Vec<Vec3>>,
    /// Texture coordinates, 3 per triangle, or `None` when no mesh has any. Triangles of meshes
    /// without them carry (0, 0), (1, 0), (0, 1): their barycentric coordinates, as Mitsuba.
    pub uvs: Option<Vec<glam::Vec2>>,
    /// Mitsuba's mesh attributes by name (`vertex_color`, `face_color`, ...): the value at
    /// each triangle corner, 3 per triangle (a per-face value three times, a number as grey);
    /// zero for the triangles of meshes without it.
    pub attributes: Vec<(String, Vec<Vec3>)>,
    /// Index into [`Scene::materials`], 1 per triangle.
    pub materials: Vec<u32>,
}

impl Triangles {
    pub fn len(&self) -> usize {
        self.materials.len()
    }

    pub fn is_empty(&self) -> bool {
        self.materials.is_empty()
    }

    pub fn vertices(&self, i: usize) -> [Vec3; 3] {
        [
            self.positions[3 * i],
            self.positions[3 * i + 1],
            self.positions[3 * i + 2],
        ]
    }

    /// Unit face normal (front side), Mitsuba's convention.
    pub fn face_normal(&self, i: usize) -> Vec3 {
        let [a, b, c] = self.vertices(i);
        (b - a).cross(c - a).normalize()
    }

    pub fn area(&self, i: usize) -> f32 {
        let [a, b, c] = self.vertices(i);
        0.5 * (b - a).cross(c - a).length()
    }
}

/// One shape of the source (a `<shape>` element, or a part of a generated scene): a contiguous run
/// of triangles with one material. Kept for statistics, debugging and light bookkeeping; the
/// renderer itself only needs the per-triangle material index.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    pub name: String,
    pub triangles: Range<u32>,
    pub material: u32,
}

/// Integrator settings read from the scene (Mitsuba `path`, or the `path` nested in `aov` /
/// `moment`). The renderer honours `max_depth` and `hide_emitters` always, and `rr_depth` when
/// asked for Mitsuba's throughput-based roulette (`cohort_render::Roulette::Mitsuba`); the
/// paper's configurations keep their fixed continuation probability (the paper).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Integrator {
    /// Longest path, in vertices after the camera (1: only emitters seen directly; 0: nothing);
    /// -1 = unlimited (Mitsuba's convention).
    pub max_depth: i32,
    /// Depth from which Mitsuba starts Russian roulette (>= 1).
    pub rr_depth: i32,
    /// Mitsuba `hide_emitters`: emitters seen directly from the camera (and through
    /// index-matched surfaces) are black.
    pub hide_emitters: bool,
}

impl Default for Integrator {
    fn default() -> Self {
        // Mitsuba 3's `path` defaults.
        Integrator {
            max_depth: -1,
            rr_depth: 5,
            hide_emitters: false,
        }
    }
}

/// A light that is not a surface (Mitsuba `point`, `spot`, `directional`), in world space.
/// None of them can be hit by a ray: next-event estimation is the only way to reach them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Radiant intensity `intensity` (W/sr) in every direction from `position`.
    Point { position: Vec3, intensity: Vec3 },
    /// Mitsuba `spot`: at the origin of `to_world` pointing along its +z, radiant intensity
    /// `intensity` inside `beam_width`, falling off linearly in angle to 0 at `cutoff_angle`
    /// (both in radians, half-angles from the axis).
    Spot {
        to_world: Mat4,
        intensity: Vec3,
        cutoff_angle: f32,
        beam_width: f32,
        /// Mitsuba's `texture`: index into [`Scene::textures`] of the image that colours the
        /// beam (at u, v = 0.5 + 0.5 (x, y) / (z tan cutoff) of the spot's frame).
        texture: Option<u32>,
    },
    /// Mitsuba `projector`: a pinhole projecting `irradiance` (or, where given, the texture
    /// `texture` times `scale`) along its +z: the irradiance at distance 1 on the axis is the
    /// image value times pi `scale`, as Mitsuba defines it.
    Projector {
        to_world: Mat4,
        /// Constant irradiance times `scale` (with a texture: `scale` in every channel).
        irradiance: Vec3,
        texture: Option<u32>,
        /// tan(fov_x / 2) of the projected image, and its width / height.
        tan_half_fov: f32,
        aspect: f32,
    },
    /// Parallel light travelling along `direction` (unit) with `irradiance` (W/m^2) on a
    /// surface facing it.
    Directional { direction: Vec3, irradiance: Vec3 },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub camera: Camera,
    pub triangles: Triangles,
    pub materials: Vec<Material>,
    pub objects: Vec<Object>,
    /// Radiance of rays that leave the scene (Mitsuba `constant` emitter); black when absent.
    pub environment: Vec3,
    /// Mitsuba `envmap`: radiance of rays that leave the scene by direction (in place of
    /// `environment`, which is then black).
    pub environment_map: Option<crate::EnvironmentMap>,
    /// Point, spot and directional lights (Mitsuba emitters that are not shapes).
    pub lights: Vec<Light>,
    pub integrator: Integrator,
    /// The sampler's sample count from the file; a placeholder the renderer may override.
    pub sample_count: u32,
    /// Textures that materials refer to (`Material::texture`).
    pub textures: Vec<crate::texture::Texture>,
}

/// Summary numbers, for logs and tests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneStats {
    pub triangles: usize,
    pub materials: usize,
    pub objects: usize,
    /// Objects whose material emits.
    pub emitters: usize,
    pub emissive_triangles: usize,
    /// Summed area of the emissive triangles.
    pub emissive_area: f32,
    pub has_environment: bool,
    pub has_vertex_normals: bool,
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
}

impl Scene {
    /// An empty scene with the given camera; sources fill it through [`crate::SceneBuilder`].
    pub fn new(camera: Camera) -> Self {
        Scene {
            camera,
            triangles: Triangles::default(),
            materials: Vec::new(),
            objects: Vec::new(),
            environment: Vec3::ZERO,
            environment_map: None,
            lights: Vec::new(),
            integrator: Integrator::default(),
            sample_count: 1,
            textures: Vec::new(),
        }
    }

    /// Packed material table, indexed by [`crate::layout::Triangle::material`].
    /// The materials in the kernels' layout; a textured one refers to its texture's header in
    /// [`Scene::gpu_textures`] (`texture` = header index + 1, 0 without a texture).
    pub fn gpu_materials(&self) -> Vec<crate::layout::Material> {
        let starts = crate::texture::gpu_texture_starts(&self.textures);
        let mut block_at = self.gpu_blocks_start();
        self.materials
            .iter()
            .map(|m| {
                let mut g = m.to_gpu();
                if let Some(t) = m.texture {
                    g.texture = starts[t as usize] + 1;
                }
                if let Some(t) = m.mask.and_then(|m| m.texture) {
                    g.opacity_texture = starts[t as usize] + 1;
                }
                if let Some(p) = m.perturb {
                    g.perturb_texture = starts[p.texture as usize] + 1;
                }
                if let Some(t) = m.emission_texture {
                    g.emission_texture = starts[t as usize] + 1;
                }
                if let crate::Bsdf::RoughPlastic { table, .. } = m.bsdf {
                    g.table = starts[table as usize] + 1;
                }
                let block = Self::gpu_block(m, &starts);
                if !block.is_empty() {
                    g.table = block_at + 1;
                    block_at += block.len() as u32;
                }
                if let Some(b) = m.blend {
                    g.blend = b.other + 1;
                    g.blend_weight = b.weight;
                    if let Some(t) = b.texture {
                        g.blend_texture = starts[t as usize] + 1;
                    }
                }
                g
            })
            .collect()
    }

    /// Every texture in the kernels' layout (`cohort_scenes::texture::gpu_textures`), then
    /// the mesh attributes that textures read, the materials' parameter blocks (in material
    /// order: [`Scene::gpu_block`]), and the environment map's
    /// (`EnvironmentMap::gpu_layout`), if any.
    pub fn gpu_textures(&self) -> Vec<[f32; 4]> {
        let mut data = crate::texture::gpu_textures(&self.textures, self.triangles.len()).0;
        for name in crate::texture::attributes_read(&self.textures) {
            data.extend(self.gpu_attribute(&name));
        }
        let starts = crate::texture::gpu_texture_starts(&self.textures);
        for m in &self.materials {
            data.extend(Self::gpu_block(m, &starts));
        }
        if let Some(map) = &self.environment_map {
            data.extend(map.gpu_layout());
        }
        data
    }

    /// Material `m`'s parameter block in [`Scene::gpu_textures`] (`layout::table` =
    /// its start + 1), if it has one: a principled BSDF's (`Principled::gpu_block`), or a
    /// rough conductor's or rough dielectric's roughness where that is not one constant
    /// (`Roughness::gpu_block`).
    /// `starts`: where each texture's header starts.
    fn gpu_block(m: &crate::Material, starts: &[u32]) -> Vec<[f32; 4]> {
        match m.bsdf {
            crate::Bsdf::Principled(p) => p.gpu_block(starts).to_vec(),
            crate::Bsdf::RoughConductor { alpha, .. }
            | crate::Bsdf::RoughDielectric { alpha, .. }
                if !alpha.is_constant_isotropic() =>
            {
                vec![alpha.gpu_block(starts)]
            }
            _ => Vec::new(),
        }
    }

    /// Where the materials' parameter blocks start in [`Scene::gpu_textures`].
    fn gpu_blocks_start(&self) -> u32 {
        let attributes = crate::texture::attributes_read(&self.textures).len();
        crate::texture::gpu_textures_len(&self.textures)
            + (attributes * 3 * self.triangles.len()) as u32
    }

    /// Where the environment map starts in [`Scene::gpu_textures`], plus one (0: no map).
    pub fn gpu_environment_map(&self) -> u32 {
        match &self.environment_map {
            Some(_) => {
                let starts = crate::texture::gpu_texture_starts(&self.textures);
                let blocks: usize = self
                    .materials
                    .iter()
                    .map(|m| Self::gpu_block(m, &starts).len())
                    .sum();
                self.gpu_blocks_start() + blocks as u32 + 1
            }
            None => 0,
        }
    }

    /// Mesh attribute `name` at the triangles' corners (3 per triangle in the scene's order;
    /// zero where a mesh has none), as a `mesh_attribute` texture reads it after the textures.
    fn gpu_attribute(&self, name: &str) -> Vec<[f32; 4]> {
        match self.triangles.attributes.iter().find(|(n, _)| n == name) {
            Some((_, c)) => c.iter().map(|c| c.extend(0.0).to_array()).collect(),
            None => vec![[0.0; 4]; 3 * self.triangles.len()],
        }
    }

    pub fn material_of(&self, triangle: usize) -> &Material {
        &self.materials[self.triangles.materials[triangle] as usize]
    }

    pub fn stats(&self) -> SceneStats {
        let mut emissive_triangles = 0;
        let mut emissive_area = 0.0;
        for i in 0..self.triangles.len() {
            if self.material_of(i).emission.is_some() {
                emissive_triangles += 1;
                emissive_area += self.triangles.area(i);
            }
        }
        let (bounds_min, bounds_max) = self.triangles.positions.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        SceneStats {
            triangles: self.triangles.len(),
            materials: self.materials.len(),
            objects: self.objects.len(),
            emitters: self
                .objects
                .iter()
                .filter(|o| self.materials[o.material as usize].emission.is_some())
                .count(),
            emissive_triangles,
            emissive_area,
            has_environment: self.environment != Vec3::ZERO || self.environment_map.is_some(),
            has_vertex_normals: self.triangles.normals.is_some(),
            bounds_min,
            bounds_max,
        }
    }
}

impl std::fmt::Display for SceneStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} triangles, {} materials, {} objects, {} emitters ({} emissive triangles, area {:.3}), \
             environment {}, vertex normals {}, bounds [{:.3}, {:.3}, {:.3}]..[{:.3}, {:.3}, {:.3}]",
            self.triangles,
            self.materials,
            self.objects,
            self.emitters,
            self.emissive_triangles,
            self.emissive_area,
            if self.has_environment { "yes" } else { "no" },
            if self.has_vertex_normals { "yes" } else { "no" },
            self.bounds_min.x,
            self.bounds_min.y,
            self.bounds_min.z,
            self.bounds_max.x,
            self.bounds_max.y,
            self.bounds_max.z,
        )
    }
}
