//! The scene on the device: BVH nodes, triangles in leaf order and materials, in the
//! layouts of `cohort_kernels::layout` (byte-identical to `cohort-scenes`' GPU types).

use cohort::runtime::{Device, GpuBuffer, RuntimeError};
use cohort_kernels::layout::{BvhNode, LightEntry, Material, Triangle};
use cohort_kernels::traverse_wide::WideNode;
use cohort_scenes::{GpuBvh, GpuBvh8, Scene};

pub struct GpuScene {
    pub nodes: GpuBuffer<BvhNode>,
    pub triangles: GpuBuffer<Triangle>,
    pub materials: GpuBuffer<Material>,
    pub triangle_count: usize,
    /// Next-event estimation's alias table over the emitter triangles (`crate::lights`).
    pub lights: GpuBuffer<LightEntry>,
    /// Entries of `lights` in use (0: no area light).
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
}

impl GpuScene {
    /// Builds the BVH of `scene` and uploads everything the kernels read.
    pub fn prepare(
        device: &Device,
        scene: &Scene,
    ) -> Result<std::sync::Arc<GpuScene>, crate::RenderError> {
        // Leaves of at most 4 triangles (see `cohort_scenes::bvh::wide::WIDE_MAX_LEAF`): faster
        // for the 8-wide kernel and for the BVH2 kernel alike.
        let (bvh, wide) =
            GpuBvh8::build_scene(scene).map_err(|e| crate::RenderError::Bvh(e.to_string()))?;
        Ok(std::sync::Arc::new(GpuScene::upload_with(
            device,
            scene,
            &bvh,
            wide.as_ref(),
        )?))
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
        let nodes: &[BvhNode] = bytemuck::cast_slice(&bvh.nodes);
        let started = std::time::Instant::now();
        let mut tris: Vec<Triangle> = bytemuck::cast_slice(&bvh.triangles).to_vec();
        let lights = crate::lights::build(scene, &mut tris);
        let mats = scene.gpu_materials();
        let mats: &[Material] = bytemuck::cast_slice(&mats);
        Ok(GpuScene {
            nodes: device.upload(nodes)?,
            triangles: device.upload(&tris)?,
            materials: device.upload(mats)?,
            triangle_count: tris.len(),
            lights: device.upload(&lights.entries)?,
            light_count: lights.count,
            env_light: lights.env_light,
            bvh_build: std::time::Duration::ZERO,
            upload: started.elapsed(),
            nodes8: match wide {
                Some(w) => Some(device.upload::<WideNode>(bytemuck::cast_slice(&w.nodes))?),
                None => None,
            },
        })
    }
}

// The kernels read the scenes crate's bytes through their own types: same sizes, same
// field order (checked field by field in tests/layouts.rs).
const _: () =
    assert!(std::mem::size_of::<BvhNode>() == std::mem::size_of::<cohort_scenes::GpuBvhNode>());
const _: () =
    assert!(std::mem::size_of::<Triangle>() == std::mem::size_of::<cohort_scenes::GpuTriangle>());
const _: () =
    assert!(std::mem::size_of::<Material>() == std::mem::size_of::<cohort_scenes::GpuMaterial>());
const _: () =
    assert!(std::mem::size_of::<WideNode>() == std::mem::size_of::<cohort_scenes::GpuWideNode>());
