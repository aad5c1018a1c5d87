//! The scene on the device: BVH nodes, triangles in leaf order and materials, in the
//! layouts of `cohort-layout`, which the scene builder writes and the kernels read.

use cohort::runtime::{Device, GpuBuffer, RuntimeError};
use cohort_kernels::layout::{BvhNode, DeltaLight, LightEntry, Material, Triangle};
use cohort_kernels::traverse_wide::WideNode;
use cohort_scenes::{GpuBvh, GpuBvh8, Scene};

pub struct GpuScene {
    pub nodes: GpuBuffer<BvhNode>,
    pub triangles: GpuBuffer<Triangle>,
    pub materials: GpuBuffer<Material>,
    /// Per-vertex shading normals, 3 per triangle in the scene's order (`Triangle::original`),
    /// or one zero element when every triangle shades with its face normal.
    pub shading_normals: GpuBuffer<glam::Vec4>,
    /// Whether `shading_normals` holds the scene's normals.
    pub has_shading_normals: bool,
    /// Texture coordinates, 2 per triangle in the scene's order ((u0, v0, u1, v1), (u2, v2)),
    /// where a material is textured; else one zero element.
    pub tex_coords: GpuBuffer<glam::Vec4>,
    /// Every texture (`cohort_scenes::Scene::gpu_textures`), or one zero element.
    pub textures: GpuBuffer<glam::Vec4>,
    /// Where the environment map starts in `textures`, plus one (0: none).
    pub env_map: u32,
    pub triangle_count: usize,
    /// Next-event estimation's alias table over the emitter triangles (`crate::lights`).
    pub lights: GpuBuffer<LightEntry>,
    /// The point, spot and directional lights that entries of `lights` refer to.
    pub delta_lights: GpuBuffer<DeltaLight>,
    /// Entries of `lights` in use (0: no area or delta light).
    pub light_count: u32,
    /// Probability that a light sample goes to the environment.
    pub env_light: f32,
    /// Host time spent building the BVHs (zero when built elsewhere) and uploading.
    pub bvh_build: std::time::Duration,
    pub upload: std::time::Duration,
    /// The same tree as `nodes` collapsed to 8-wide nodes (`cohort_scenes::GpuBvh8`), over the
    /// same `triangles`, for `traverse_wide::traverse8`; `None` where the tree may need more
    /// stack than that kernel has (then use `traverse::traverse`).
    pub nodes8: Option<GpuBuffer<WideNode>>,
    /// The scene's bounding box (the BVH root's), for ray reordering's grid of origin cells.
    pub bounds: [glam::Vec3; 2],
    /// The BSDF kinds and shading features the scene uses (`cohort_kernels::shading`):
    /// `extend` is built with these alone.
    pub shading: u32,
}

/// A scene's BVH as the renderer traverses it, built on the host, and how long that took.
pub struct SceneBvh {
    pub bvh: GpuBvh,
    /// Its 8-wide form, where the traversal's stack holds the tree.
    pub wide: Option<GpuBvh8>,
    pub time: std::time::Duration,
    /// Whether the tree came from Cohort's cache folder ([`crate::bvh_cache`]).
    pub cached: bool,
    /// Where [`SceneBvh::save`] keeps a tree that was built, not read, when caching is on.
    pub save_to: Option<std::path::PathBuf>,
}

impl SceneBvh {
    pub fn build(scene: &Scene) -> Result<SceneBvh, crate::RenderError> {
        let started = std::time::Instant::now();
        // Leaves of at most 4 triangles (see `cohort_scenes::bvh::wide::WIDE_MAX_LEAF`): faster
        // for the 8-wide kernel and for the BVH2 kernel alike.
        let (bvh, wide) =
            GpuBvh8::build_scene(scene).map_err(|e| crate::RenderError::Bvh(e.to_string()))?;
        Ok(SceneBvh {
            bvh,
            wide,
            time: started.elapsed(),
            cached: false,
            save_to: None,
        })
    }

    /// [`SceneBvh::build`] through Cohort's cache folder ([`crate::bvh_cache`]): a large
    /// scene's tree is read back from there when a run has built it before. A tree built
    /// here is not written yet: [`SceneBvh::save`] does that, off the path to the first
    /// iteration (a large tree takes tens of milliseconds to write). The tree is the same
    /// either way.
    pub fn cached(scene: &Scene) -> Result<SceneBvh, crate::RenderError> {
        let started = std::time::Instant::now();
        let Some(file) = crate::bvh_cache::file_for(scene) else {
            return SceneBvh::build(scene);
        };
        if let Some((bvh, wide)) = crate::bvh_cache::load(&file, scene) {
            return Ok(SceneBvh {
                bvh,
                wide,
                time: started.elapsed(),
                cached: true,
                save_to: None,
            });
        }
        Ok(SceneBvh {
            save_to: Some(file),
            ..SceneBvh::build(scene)?
        })
    }

    /// Writes a tree [`SceneBvh::cached`] built into the cache folder (nothing for one it
    /// read, or when caching is off).
    pub fn save(&self) {
        if let Some(file) = &self.save_to {
            crate::bvh_cache::save(file, &self.bvh, self.wide.as_ref());
        }
    }
}

impl GpuScene {
    /// Builds the BVH of `scene` and uploads everything the kernels read.
    pub fn prepare(
        device: &Device,
        scene: &Scene,
    ) -> Result<std::sync::Arc<GpuScene>, crate::RenderError> {
        let built = SceneBvh::build(scene)?;
        GpuScene::upload_prepared(device, &PreparedScene::new(scene, built))
    }

    /// Uploads `bvh` and its 8-wide form (built here).
    pub fn upload(device: &Device, scene: &Scene, bvh: &GpuBvh) -> Result<GpuScene, RuntimeError> {
        GpuScene::upload_with(device, scene, bvh, GpuBvh8::build(bvh).ok().as_ref())
    }

    /// Uploads `bvh` and `wide`, which must have been built from `bvh`.
    pub fn upload_with(
        device: &Device,
        scene: &Scene,
        bvh: &GpuBvh,
        wide: Option<&GpuBvh8>,
    ) -> Result<GpuScene, RuntimeError> {
        let started = std::time::Instant::now();
        let arrays = SceneArrays::prepare(scene, bvh);
        let mut gpu = GpuScene::upload_arrays(device, &arrays, bvh, wide)?;
        gpu.upload = started.elapsed();
        Ok(gpu)
    }

    /// Uploads a scene laid out already ([`PreparedScene`], made on the host without a
    /// device: a caller can make it while the device opens).
    pub fn upload_prepared(
        device: &Device,
        prepared: &PreparedScene,
    ) -> Result<std::sync::Arc<GpuScene>, crate::RenderError> {
        let PreparedScene { built, arrays, .. } = prepared;
        let started = std::time::Instant::now();
        let mut gpu = GpuScene::upload_arrays(device, arrays, &built.bvh, built.wide.as_ref())?;
        gpu.upload = started.elapsed();
        gpu.bvh_build = built.time;
        Ok(std::sync::Arc::new(gpu))
    }

    /// Uploads the arrays, the large ones each on a thread of its own: copying into
    /// staging memory and allocating run side by side, and only the copy commands queue
    /// one after another.
    fn upload_arrays(
        device: &Device,
        a: &SceneArrays,
        bvh: &GpuBvh,
        wide: Option<&GpuBvh8>,
    ) -> Result<GpuScene, RuntimeError> {
        std::thread::scope(|t| {
            let triangles = t.spawn(|| upload(device, &a.triangles));
            let normals = t.spawn(|| upload(device, &a.normals));
            let nodes = t.spawn(|| upload(device, &bvh.nodes));
            let nodes8 = t.spawn(|| {
                wide.map(|w| upload::<WideNode>(device, &w.nodes))
                    .transpose()
            });
            let tex_coords = t.spawn(|| upload(device, &a.tex_coords));
            let textures = t.spawn(|| upload(device, &a.textures));
            let materials = upload(device, &a.materials)?;
            let lights = upload(device, &a.lights.entries)?;
            let delta_lights = upload(device, &a.lights.delta)?;
            Ok(GpuScene {
                shading: a.shading,
                tex_coords: joined(tex_coords)?,
                textures: joined(textures)?,
                env_map: a.env_map,
                nodes: joined(nodes)?,
                triangles: joined(triangles)?,
                materials,
                has_shading_normals: !a.normals.is_empty(),
                shading_normals: joined(normals)?,
                triangle_count: a.triangles.len(),
                lights,
                delta_lights,
                light_count: a.lights.count,
                env_light: a.lights.env_light,
                bvh_build: std::time::Duration::ZERO,
                upload: std::time::Duration::ZERO,
                bounds: [bvh.bounds_min, bvh.bounds_max],
                nodes8: joined(nodes8)?,
            })
        })
    }
}

/// A scene's BVH with every other array the kernels read, laid out on the host: all of
/// [`GpuScene`]'s work that needs no device.
pub struct PreparedScene {
    pub built: SceneBvh,
    arrays: SceneArrays,
    /// Host time spent laying out the arrays besides the trees.
    pub time: std::time::Duration,
}

impl PreparedScene {
    pub fn new(scene: &Scene, built: SceneBvh) -> PreparedScene {
        let started = std::time::Instant::now();
        let arrays = SceneArrays::prepare(scene, &built.bvh);
        PreparedScene {
            built,
            arrays,
            time: started.elapsed(),
        }
    }
}

impl PreparedScene {
    /// Writes a tree that was built for the cache ([`SceneBvh::save`]) on a thread of its
    /// own, once the scene is on the device; the returned guard waits for it when dropped,
    /// so that a run ends with the file whole.
    pub fn save_beside(self) -> Saving {
        Saving(
            (self.built.save_to.is_some()).then(|| std::thread::spawn(move || self.built.save())),
        )
    }
}

/// A BVH being written to the cache ([`PreparedScene::save_beside`]); dropping it waits.
pub struct Saving(Option<std::thread::JoinHandle<()>>);

impl Drop for Saving {
    fn drop(&mut self) {
        if let Some(h) = self.0.take() {
            let _ = h.join();
        }
    }
}

/// The arrays of [`GpuScene`] besides the trees, in the kernels' layouts.
struct SceneArrays {
    /// The BVH's triangles with their light densities (`crate::lights`).
    triangles: Vec<Triangle>,
    lights: crate::lights::LightTable,
    materials: Vec<Material>,
    normals: Vec<glam::Vec4>,
    tex_coords: Vec<glam::Vec4>,
    textures: Vec<glam::Vec4>,
    env_map: u32,
    shading: u32,
}

impl SceneArrays {
    fn prepare(scene: &Scene, bvh: &GpuBvh) -> SceneArrays {
        let mut tris: Vec<Triangle> = bvh.triangles.clone();
        let lights = crate::lights::build(scene, &mut tris);
        let mats = scene.gpu_materials();
        let normals: Vec<glam::Vec4> = scene
            .triangles
            .normals
            .iter()
            .flatten()
            .map(|n| n.extend(0.0))
            .collect();
        // Texture coordinates only matter where a material reads a texture.
        let textured = scene.materials.iter().any(|m| {
            m.texture.is_some()
                || m.emission_texture.is_some()
                || m.mask.is_some_and(|k| k.texture.is_some())
                || m.perturb.is_some()
                || m.blend.is_some_and(|b| b.texture.is_some())
                // An anisotropic principled BSDF turns with dp/du; textured parameters are
                // read at (u, v).
                || matches!(m.bsdf, cohort_scenes::Bsdf::Principled(p) if p.reads_tex_coords())
                // The same for a rough conductor's or rough dielectric's roughness.
                || matches!(m.bsdf, cohort_scenes::Bsdf::RoughConductor { alpha, .. } | cohort_scenes::Bsdf::RoughDielectric { alpha, .. } if !alpha.is_constant_isotropic())
        });
        let tex_coords: Vec<glam::Vec4> = match (&scene.triangles.uvs, textured) {
            (Some(uvs), true) => uvs
                .chunks_exact(3)
                .flat_map(|c| {
                    [
                        glam::Vec4::new(c[0].x, c[0].y, c[1].x, c[1].y),
                        glam::Vec4::new(c[2].x, c[2].y, 0.0, 0.0),
                    ]
                })
                .collect(),
            // Textured meshes without coordinates: Mitsuba's barycentric (u, v).
            (None, true) => (0..scene.triangles.len())
                .flat_map(|_| {
                    [
                        glam::Vec4::new(0.0, 0.0, 1.0, 0.0),
                        glam::Vec4::new(0.0, 1.0, 0.0, 0.0),
                    ]
                })
                .collect(),
            (_, false) => Vec::new(),
        };
        let textures: Vec<glam::Vec4> = scene
            .gpu_textures()
            .into_iter()
            .map(glam::Vec4::from_array)
            .collect();
        let env_map = scene.gpu_environment_map();
        // The kernels reach a delta light only through an alias-table entry naming it
        // (`lights.delta` is never empty: it holds a stand-in where there is none).
        let delta = cohort_kernels::layout::DELTA_LIGHT;
        let has_delta = (lights.entries.iter().take(lights.count as usize))
            .any(|e| e.tri & delta != 0 || e.alias_tri & delta != 0);
        let shading = cohort_kernels::shading::shading_set(&mats, has_delta, env_map != 0);
        SceneArrays {
            triangles: tris,
            lights,
            materials: mats,
            normals,
            tex_coords,
            textures,
            env_map,
            shading,
        }
    }
}

/// The result of an upload thread.
fn joined<T>(h: std::thread::ScopedJoinHandle<'_, T>) -> T {
    h.join().expect("an upload thread panicked")
}

/// `Device::upload`, with one zeroed element in place of an empty array: a kernel's binding must
/// hold at least one element (wgpu checks it), and the kernels never read these arrays of an
/// empty scene (`has_geometry` = 0, no lights).
fn upload<T: bytemuck::Pod>(device: &Device, data: &[T]) -> Result<GpuBuffer<T>, RuntimeError> {
    if data.is_empty() {
        device.upload(&[T::zeroed()])
    } else {
        device.upload(data)
    }
}
