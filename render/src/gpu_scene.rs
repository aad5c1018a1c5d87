//! The scene on the device: BVH nodes, triangles in leaf order and materials, in the
//! layouts of `cohort_kernels::layout` (byte-identical to `cohort-scenes`' GPU types).

use cohort::runtime::{Device, GpuBuffer, RuntimeError};
use cohort_kernels::layout::{BvhNode, Material, Triangle};
use cohort_scenes::{GpuBvh, Scene};

pub struct GpuScene {
    pub nodes: GpuBuffer<BvhNode>,
    pub triangles: GpuBuffer<Triangle>,
    pub materials: GpuBuffer<Material>,
    pub triangle_count: usize,
}

impl GpuScene {
    /// Builds the BVH of `scene` and uploads everything the kernels read.
    pub fn prepare(device: &Device, scene: &Scene) -> Result<std::sync::Arc<GpuScene>, crate::RenderError> {
        let bvh = GpuBvh::build(scene).map_err(|e| crate::RenderError::Bvh(e.to_string()))?;
        Ok(std::sync::Arc::new(GpuScene::upload(device, scene, &bvh)?))
    }

    pub fn upload(device: &Device, scene: &Scene, bvh: &GpuBvh) -> Result<GpuScene, RuntimeError> {
        let nodes: &[BvhNode] = bytemuck::cast_slice(&bvh.nodes);
        let tris: &[Triangle] = bytemuck::cast_slice(&bvh.triangles);
        let mats = scene.gpu_materials();
        let mats: &[Material] = bytemuck::cast_slice(&mats);
        Ok(GpuScene {
            nodes: device.upload(nodes)?,
            triangles: device.upload(tris)?,
            materials: device.upload(mats)?,
            triangle_count: tris.len(),
        })
    }
}

// The kernels read the scenes crate's bytes through their own types: same sizes, same
// field order (checked field by field in tests/layouts.rs).
const _: () = assert!(std::mem::size_of::<BvhNode>() == std::mem::size_of::<cohort_scenes::GpuBvhNode>());
const _: () = assert!(std::mem::size_of::<Triangle>() == std::mem::size_of::<cohort_scenes::GpuTriangle>());
const _: () = assert!(std::mem::size_of::<Material>() == std::mem::size_of::<cohort_scenes::GpuMaterial>());
