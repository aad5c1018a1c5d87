//! The path state on the device: one entry per ray slot of the wavefront ([`Paths`]),
//! and ray reordering's buffers ([`SortState`]).

use cohort::runtime::{Device, GpuBuffer};
use cohort_kernels::{compact, group_draw, reorder};
use cohort_scenes::Camera;
use glam::{UVec4, Vec4};

use crate::queues::QueueState;
use crate::{GpuScene, RenderError};

/// Path state, structure of arrays, one entry per ray slot.
pub(crate) struct Paths {
    pub(crate) slot_pixel: GpuBuffer<u32>,
    /// The camera's reconstruction filter as `extend::film_sample` reads it
    /// (`cohort_scenes::FilmFilter::table`; one unused zero for the box).
    pub(crate) film_filter: GpuBuffer<f32>,
    pub(crate) idrays: [GpuBuffer<u32>; 2],
    pub(crate) state: GpuBuffer<UVec4>,
    pub(crate) ray_o: GpuBuffer<Vec4>,
    pub(crate) ray_d: GpuBuffer<Vec4>,
    pub(crate) beta: GpuBuffer<Vec4>,
    pub(crate) radiance: GpuBuffer<Vec4>,
    pub(crate) hits: GpuBuffer<Vec4>,
    pub(crate) accum: GpuBuffer<Vec4>,
    /// Next-event estimation: each slot's shadow ray (origin, tmax), (direction, status)
    /// and unoccluded light-sample contribution.
    pub(crate) shadow_o: GpuBuffer<Vec4>,
    pub(crate) shadow_d: GpuBuffer<Vec4>,
    pub(crate) nee: GpuBuffer<Vec4>,
    pub(crate) flags: GpuBuffer<u32>,
    /// Ray reordering's buffers, allocated by the first run that sorts.
    pub(crate) sort: Option<SortState>,
    /// Material queues' buffers, allocated by the first run that shades over queues.
    pub(crate) queues: Option<QueueState>,
    /// The number of entries of each `idrays` list: the slots, until finished slots are
    /// retired from a list (`cohort_kernels::retire`).
    pub(crate) counts: [GpuBuffer<u32>; 2],
    pub(crate) block_sums: GpuBuffer<u32>,
    pub(crate) total: GpuBuffer<u32>,
    /// [completed paths, slots done]
    pub(crate) counters: GpuBuffer<u32>,
    /// Each slot group's draws of the iteration and the next (`cohort_kernels::group_draw`),
    /// sized by the first run whose `extend` reads them (`SHADES_GROUP_TABLE`); one
    /// unread group before, which `extend` binds all the same.
    pub(crate) group_table: GpuBuffer<UVec4>,
}

impl Paths {
    /// The path state of `slot_to_pixel.len()` slots (their pixels), for `camera`'s
    /// reconstruction filter.
    pub(crate) fn alloc(
        device: &Device,
        slot_to_pixel: &[u32],
        camera: &Camera,
    ) -> Result<Paths, RenderError> {
        let n = slot_to_pixel.len();
        let blocks = compact::scratch_len(n);
        Ok(Paths {
            slot_pixel: device.upload(slot_to_pixel)?,
            film_filter: match &camera.filter {
                Some(filter) => device.upload(&filter.table())?,
                None => device.upload(&[0.0f32])?,
            },
            idrays: [device.alloc(n)?, device.alloc(n)?],
            state: device.alloc(n)?,
            ray_o: device.alloc(n)?,
            ray_d: device.alloc(n)?,
            beta: device.alloc(n)?,
            radiance: device.alloc(n)?,
            hits: device.alloc(n)?,
            accum: device.alloc(n)?,
            shadow_o: device.alloc(n)?,
            shadow_d: device.alloc(n)?,
            nee: device.alloc(n)?,
            flags: device.alloc(n)?,
            sort: None,
            queues: None,
            counts: [device.upload(&[n as u32])?, device.upload(&[n as u32])?],
            block_sums: device.alloc(blocks)?,
            total: device.alloc(1)?,
            counters: device.alloc(2)?,
            group_table: device.alloc(group_draw::table_len(1))?,
        })
    }
}

/// Ray reordering's buffers (`cohort_kernels::reorder::SortBuffers`): the grid of origin
/// cells over the scene's bounds, each listed ray's bin, the histogram, and the live slots
/// in bin order (what the traversal reads instead of `idrays` on a sorting iteration).
pub(crate) struct SortState {
    cells: GpuBuffer<Vec4>,
    keys: GpuBuffer<u32>,
    bins: GpuBuffer<u32>,
    pub(crate) sorted: GpuBuffer<u32>,
}

impl SortState {
    pub(crate) fn new(d: &Device, slots: u32, scene: &GpuScene) -> Result<SortState, RenderError> {
        Ok(SortState {
            cells: d.upload(&reorder::cells(scene.bounds[0], scene.bounds[1]))?,
            keys: d.alloc(slots as usize)?,
            bins: d.alloc(reorder::HISTOGRAM_LEN)?,
            sorted: d.alloc(slots as usize)?,
        })
    }

    pub(crate) fn buffers(&self) -> reorder::SortBuffers<'_> {
        reorder::SortBuffers {
            cells: &self.cells,
            keys: &self.keys,
            bins: &self.bins,
            sorted: &self.sorted,
        }
    }
}
