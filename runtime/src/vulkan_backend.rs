//! The raw Vulkan backend (through `ash`): lowers compiled kernels to SPIR-V ([`lower`]). It exists next
//! to wgpu for what wgpu cannot do: pin a pipeline's subgroup size, and run SPIR-V as the
//! compiler emitted it.
//!
//! Ownership: `Shared` (see `vulkan_init`, which opens the device) holds the instance, the
//! logical device and the memory allocator and is destroyed last; every `Buffer` holds an
//! `Arc<Shared>`, so buffers may outlive the `VkDevice` that made them. `VkDevice` adds the
//! queue, the command pool and the pipeline cache. Transfers go through `VkDevice::run`:
//! one command buffer, one submission, wait on a fence, reset the pool; dispatches through
//! `submit_async`. Device-local memory is only touched by copy commands from/to
//! host-visible staging buffers, so there is one upload path on every GPU. A new buffer's
//! zero fill or upload copy waits in [`pending`] for the next submission of either kind.

use std::borrow::Cow;
use std::ffi::CString;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

use crate::backend::{resolve, Arg, Backend, Groups, InFlight, Recorded, Recording, Records};
use crate::buffer::RawBuffer;
use crate::device::Limits;
use crate::error::VkContext;
use crate::pipeline_cache::{Code, PipelineCache};
use crate::vulkan_init::{self, lock, Opened, Shared, SubgroupControl};
use crate::{
    BackendKind, BindingKind, BufferArg, CompiledKernel, DeviceInfo, Dispatch, DispatchStats,
    KernelArtifact, KernelCode, Result, RuntimeError,
};

mod pending;

const BACKEND: BackendKind = BackendKind::Vulkan;

/// Distinguishes devices so a buffer from one device is never bound on another.
static NEXT_DEVICE_ID: AtomicU64 = AtomicU64::new(1);

const BUFFER_USAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::STORAGE_BUFFER.as_raw()
        | vk::BufferUsageFlags::UNIFORM_BUFFER.as_raw()
        | vk::BufferUsageFlags::INDIRECT_BUFFER.as_raw()
        | vk::BufferUsageFlags::TRANSFER_SRC.as_raw()
        | vk::BufferUsageFlags::TRANSFER_DST.as_raw(),
);

pub(crate) struct Buffer {
    device_id: u64,
    shared: Arc<Shared>,
    raw: vk::Buffer,
    allocation: Option<Allocation>,
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(allocation) = self.allocation.take() {
            let _ = lock(&self.shared.allocator).free(allocation);
        }
        unsafe { self.shared.device.destroy_buffer(self.raw, None) };
    }
}

pub(crate) struct Pipeline {
    pipeline: vk::Pipeline,
    layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
}

/// One recorded dispatch, holding everything it binds so it outlives the caller's borrows.
pub(crate) struct Cmd {
    kernel: String,
    pipeline: Arc<Pipeline>,
    bindings: Vec<Arg<Arc<Buffer>>>,
    groups: Groups<Arc<Buffer>>,
}

/// The descriptor type a binding of `kind` is.
fn descriptor_type(kind: BindingKind) -> vk::DescriptorType {
    match kind {
        BindingKind::Uniform => vk::DescriptorType::UNIFORM_BUFFER,
        BindingKind::StorageRead | BindingKind::StorageReadWrite => {
            vk::DescriptorType::STORAGE_BUFFER
        }
    }
}

/// Serialises queue access (Vulkan requires external synchronisation of queues and
/// command pools); one submission is in flight at a time.
struct Submitter {
    queue: vk::Queue,
    pool: vk::CommandPool,
    fence: vk::Fence,
}

impl Submitter {
    fn new(device: &ash::Device, queue_family: u32) -> Result<Self> {
        unsafe {
            let queue = device.get_device_queue(queue_family, 0);
            let pool = device
                .create_command_pool(
                    &vk::CommandPoolCreateInfo::default()
                        .flags(vk::CommandPoolCreateFlags::TRANSIENT)
                        .queue_family_index(queue_family),
                    None,
                )
                .vk("vkCreateCommandPool")?;
            match device.create_fence(&vk::FenceCreateInfo::default(), None) {
                Ok(fence) => Ok(Submitter { queue, pool, fence }),
                Err(e) => {
                    device.destroy_command_pool(pool, None);
                    Err(RuntimeError::Vulkan {
                        call: "vkCreateFence",
                        result: e,
                    })
                }
            }
        }
    }
}

pub(crate) struct VkDevice {
    id: u64,
    pub(crate) info: DeviceInfo,
    pub(crate) limits: Limits,
    pub(crate) pipelines: PipelineCache<Pipeline>,
    shared: Arc<Shared>,
    submitter: Mutex<Submitter>,
    /// New buffers' fills and copies, recorded by the next submission. Locked after
    /// `submitter` where both are held.
    pending: Mutex<pending::Pending>,
    queue_family: u32,
    /// The driver's pipeline cache, loaded from and saved to `cache_file` (`disk_cache`).
    vk_cache: vk::PipelineCache,
    cache_file: Option<std::path::PathBuf>,
    /// Whether a pipeline was created since the cache was loaded (then it is saved on drop).
    cache_dirty: std::sync::atomic::AtomicBool,
    subgroup_control: SubgroupControl,
    timestamp_valid_bits: u32,
    timestamp_period_ns: f64,
}

impl Drop for VkDevice {
    fn drop(&mut self) {
        let device = &self.shared.device;
        let s = lock(&self.submitter);
        unsafe {
            let _ = device.device_wait_idle();
            // No batch can outlive its `&Device`, so these are the last references.
            for p in self.pipelines.drain() {
                device.destroy_pipeline(p.pipeline, None);
                device.destroy_pipeline_layout(p.layout, None);
                device.destroy_descriptor_set_layout(p.set_layout, None);
            }
            device.destroy_command_pool(s.pool, None);
            device.destroy_fence(s.fence, None);
            if self.cache_dirty.load(Ordering::Relaxed) {
                if let Ok(data) = device.get_pipeline_cache_data(self.vk_cache) {
                    crate::disk_cache::save(&self.cache_file, &data);
                }
            }
            device.destroy_pipeline_cache(self.vk_cache, None);
        }
    }
}

impl VkDevice {
    /// The best device, or, where that is Mesa's software driver, its name (and no device
    /// created: `vulkan_init::open_unless_software`).
    pub(crate) fn new_unless_software() -> Result<std::result::Result<Self, String>> {
        match vulkan_init::open_unless_software()? {
            vulkan_init::Found::Opened(opened) => Self::from_opened(*opened).map(Ok),
            vulkan_init::Found::Software(name) => Ok(Err(name)),
        }
    }

    /// The best device, or the usable device number `which` (`vulkan_init::open`).
    pub(crate) fn new(which: Option<usize>) -> Result<Self> {
        Self::from_opened(vulkan_init::open(which)?)
    }

    fn from_opened(opened: Opened) -> Result<Self> {
        let Opened { shared, desc } = opened;
        // From here, dropping `shared` on an error path destroys the device and instance.
        let shared = Arc::new(shared);
        let submitter = Submitter::new(&shared.device, desc.queue_family)?;
        let cache_file = crate::disk_cache::file_for(&desc.info.adapter_name);
        let initial = crate::disk_cache::load(&cache_file);
        let create = |data: &[u8]| unsafe {
            shared.device.create_pipeline_cache(
                &vk::PipelineCacheCreateInfo::default().initial_data(data),
                None,
            )
        };
        // A blob the driver rejects outright is dropped rather than failing the device.
        let vk_cache = create(&initial)
            .or_else(|_| create(&[]))
            .vk("vkCreatePipelineCache")?;
        Ok(VkDevice {
            id: NEXT_DEVICE_ID.fetch_add(1, Ordering::Relaxed),
            info: desc.info,
            limits: desc.limits,
            pipelines: PipelineCache::new(Code::Spirv),
            shared,
            submitter: Mutex::new(submitter),
            pending: Mutex::default(),
            queue_family: desc.queue_family,
            vk_cache,
            cache_file,
            cache_dirty: std::sync::atomic::AtomicBool::new(false),
            subgroup_control: desc.subgroup_control,
            timestamp_valid_bits: desc.timestamp_valid_bits,
            timestamp_period_ns: desc.timestamp_period_ns,
        })
    }

    /// Validation messages logged since `mark` (a length of the list), without draining
    /// them, to attach to an error.
    fn messages_since(&self, mark: usize) -> Vec<String> {
        lock(&self.shared.messages)
            .iter()
            .skip(mark)
            .cloned()
            .collect()
    }

    fn message_count(&self) -> usize {
        lock(&self.shared.messages).len()
    }

    fn own(&self, raw: &RawBuffer) -> Option<Arc<Buffer>> {
        raw.get::<Buffer>().filter(|b| b.device_id == self.id)
    }

    fn new_buffer(
        &self,
        bytes: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Buffer> {
        let device = &self.shared.device;
        let alloc_err = |detail: String| RuntimeError::Allocation {
            backend: BACKEND,
            bytes,
            detail,
        };
        let info = vk::BufferCreateInfo::default()
            .size(bytes)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        let raw = unsafe { device.create_buffer(&info, None) }
            .map_err(|e| alloc_err(format!("vkCreateBuffer failed: {e}")))?;
        let requirements = unsafe { device.get_buffer_memory_requirements(raw) };
        let allocation = lock(&self.shared.allocator).allocate(&AllocationCreateDesc {
            name: "cohort buffer",
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        // From here the buffer owns `raw`, so every early return frees it.
        let mut buffer = Buffer {
            device_id: self.id,
            shared: self.shared.clone(),
            raw,
            allocation: None,
        };
        let allocation = allocation.map_err(|e| alloc_err(e.to_string()))?;
        let bound =
            unsafe { device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) };
        buffer.allocation = Some(allocation);
        bound.map_err(|e| alloc_err(format!("vkBindBufferMemory failed: {e}")))?;
        Ok(buffer)
    }

    fn staging(&self, bytes: u64, location: MemoryLocation) -> Result<Buffer> {
        let usage = vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
        self.new_buffer(bytes, usage, location)
    }

    /// Records `record` into a fresh command buffer between full memory barriers, submits
    /// it and waits. The leading barrier makes earlier submissions' writes visible; the
    /// trailing one makes this submission's writes visible to the host (staging reads).
    fn run(&self, record: impl FnOnce(&ash::Device, vk::CommandBuffer)) -> Result<()> {
        let device = &self.shared.device;
        let s = lock(&self.submitter);
        // Dropped after the wait below: the fills' and copies' buffers outlive them.
        let pending = std::mem::take(&mut *lock(&self.pending));
        let mut allocated = None;
        let result = (|| unsafe {
            let cb = begin_one_time(device, s.pool)?;
            allocated = Some(cb);
            pending.record(device, cb);
            let all = vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE;
            barrier(
                device,
                cb,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::AccessFlags::MEMORY_WRITE,
                vk::PipelineStageFlags::ALL_COMMANDS,
                all,
            );
            record(device, cb);
            barrier(
                device,
                cb,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::AccessFlags::MEMORY_WRITE,
                vk::PipelineStageFlags::HOST,
                vk::AccessFlags::HOST_READ,
            );
            device.end_command_buffer(cb).vk("vkEndCommandBuffer")?;
            let cbs = [cb];
            let submit = vk::SubmitInfo::default().command_buffers(&cbs);
            device
                .queue_submit(s.queue, &[submit], s.fence)
                .vk("vkQueueSubmit")?;
            device
                .wait_for_fences(&[s.fence], true, u64::MAX)
                .vk("vkWaitForFences")?;
            Ok(())
        })();
        unsafe {
            let _ = device.reset_fences(&[s.fence]);
            // Resetting the pool only resets its command buffers; without freeing, every
            // call would leave one more allocated in the pool (the Mitsuba-scene work: memory
            // grew by about 8 KB per upload, write and read on the software driver).
            if let Some(cb) = allocated {
                device.free_command_buffers(s.pool, &[cb]);
            }
            let _ = device.reset_command_pool(s.pool, vk::CommandPoolResetFlags::empty());
        }
        result
    }

    /// The subgroup size chained into the pipeline, after checking the device can do it.
    fn required_subgroup_size(&self, kernel: &KernelArtifact) -> Result<Option<u32>> {
        let Some(n) = kernel.features.required_subgroup_size else {
            return Ok(None);
        };
        let sc = &self.subgroup_control;
        let problem = if !sc.enabled {
            Some(
                "the device does not support subgroup size control for compute shaders".to_string(),
            )
        } else if !n.is_power_of_two() || n < sc.min || n > sc.max {
            Some(format!(
                "the device supports sizes {}..={} (powers of two)",
                sc.min, sc.max
            ))
        } else {
            None
        };
        match problem {
            Some(detail) => Err(RuntimeError::SubgroupSize {
                kernel: kernel.name.clone(),
                backend: BACKEND,
                required: n,
                detail,
            }),
            None => Ok(Some(n)),
        }
    }

    fn create_pipeline(&self, kernel: &KernelArtifact) -> Result<Pipeline> {
        let device = &self.shared.device;
        let mark = self.message_count();
        let fail = |what: String| {
            let mut detail = what;
            for m in self.messages_since(mark) {
                detail.push_str("\n  ");
                detail.push_str(&m);
            }
            RuntimeError::ShaderCompilation {
                kernel: kernel.name.clone(),
                backend: BACKEND,
                detail,
            }
        };
        let (spirv, entry_point) = match &kernel.code {
            KernelCode::Compiled(k) => (Cow::Owned(lower(k)?), k.entry_point.as_str()),
            KernelCode::Shaders {
                spirv, entry_point, ..
            } => (Cow::Borrowed(spirv.as_slice()), entry_point.as_str()),
        };
        if spirv.first() != Some(&0x0723_0203) {
            return Err(fail(
                "the artifact has no SPIR-V code (missing magic number)".into(),
            ));
        }
        // Subnormals, NaN, infinities and signed zeros kept as IEEE (and Rust) define them,
        // where the device can: the driver may otherwise flush and fold them.
        let code = crate::float_controls::preserve_f32(
            &spirv,
            self.info.f32_subnormals,
            self.info.f32_nan_inf,
        );
        let entry = CString::new(entry_point)
            .map_err(|_| fail("the entry point name contains a NUL byte".into()))?;
        let required = self.required_subgroup_size(kernel)?;

        let layout_bindings: Vec<vk::DescriptorSetLayoutBinding> = kernel
            .bindings
            .iter()
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b.binding)
                    .descriptor_type(descriptor_type(b.kind))
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();

        // Handles created so far, destroyed if a later step fails.
        let mut module = vk::ShaderModule::null();
        let mut set_layout = vk::DescriptorSetLayout::null();
        let mut layout = vk::PipelineLayout::null();
        let result = (|| unsafe {
            module = device
                .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&code), None)
                .map_err(|e| fail(format!("vkCreateShaderModule failed: {e}")))?;
            set_layout = device
                .create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings),
                    None,
                )
                .map_err(|e| fail(format!("vkCreateDescriptorSetLayout failed: {e}")))?;
            let set_layouts = [set_layout];
            layout = device
                .create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts),
                    None,
                )
                .map_err(|e| fail(format!("vkCreatePipelineLayout failed: {e}")))?;
            let mut required_info =
                vk::PipelineShaderStageRequiredSubgroupSizeCreateInfo::default();
            let mut stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module)
                .name(&entry);
            if let Some(n) = required {
                required_info = required_info.required_subgroup_size(n);
                stage = stage.push_next(&mut required_info);
                // Full subgroups make "every subgroup has n lanes" true for kernels whose
                // workgroup width is a multiple of n, which is what pinning the size is for.
                let sc = &self.subgroup_control;
                let invocations: u64 = kernel.workgroup_size.iter().map(|&d| d as u64).product();
                if sc.full_subgroups
                    && kernel.workgroup_size[0] % n == 0
                    && invocations <= n as u64 * sc.max_workgroup_subgroups as u64
                {
                    stage = stage.flags(vk::PipelineShaderStageCreateFlags::REQUIRE_FULL_SUBGROUPS);
                }
            }
            let info = vk::ComputePipelineCreateInfo::default()
                .stage(stage)
                .layout(layout);
            let pipeline = device
                .create_compute_pipelines(self.vk_cache, &[info], None)
                .map_err(|(_, e)| fail(format!("vkCreateComputePipelines failed: {e}")))?[0];
            Ok(pipeline)
        })();
        unsafe {
            if module != vk::ShaderModule::null() {
                device.destroy_shader_module(module, None);
            }
        }
        match result {
            Ok(pipeline) => {
                self.cache_dirty.store(true, Ordering::Relaxed);
                Ok(Pipeline {
                    pipeline,
                    layout,
                    set_layout,
                })
            }
            Err(e) => {
                unsafe {
                    if layout != vk::PipelineLayout::null() {
                        device.destroy_pipeline_layout(layout, None);
                    }
                    if set_layout != vk::DescriptorSetLayout::null() {
                        device.destroy_descriptor_set_layout(set_layout, None);
                    }
                }
                Err(e)
            }
        }
    }

    /// A host-visible buffer holding `init` (zero-padded to `bytes`), written through its
    /// mapping: no queue work, so it never waits for submissions in flight (the uniform
    /// arguments that batches record).
    pub(crate) fn create_host_buffer(&self, bytes: u64, init: &[u8]) -> Result<RawBuffer> {
        let mut buffer = self.new_buffer(bytes, BUFFER_USAGE, MemoryLocation::CpuToGpu)?;
        let mapped = mapped_bytes(&mut buffer)?;
        mapped[..init.len()].copy_from_slice(init);
        mapped[init.len()..bytes as usize].fill(0);
        Ok(RawBuffer::new(buffer))
    }

    /// Submits `cmds`, then copies of `reads` (buffer, bytes) to host memory, and returns
    /// without waiting. Each submission has its own command pool, fence, descriptor and
    /// query pools, so several can be in flight; the queue orders them.
    pub(crate) fn submit_async(
        &self,
        cmds: Vec<Cmd>,
        reads: Vec<(Arc<Buffer>, u64)>,
    ) -> Result<VkInFlight> {
        let device = &self.shared.device;
        let n = cmds.len() as u32;
        let names = {
            let mut names: Vec<&str> = cmds.iter().map(|c| c.kernel.as_str()).collect();
            names.dedup();
            names.join(", ")
        };
        let fail = |e: RuntimeError| RuntimeError::Dispatch {
            kernel: names.clone(),
            backend: BACKEND,
            detail: e.to_string(),
        };
        let count = |ty| {
            cmds.iter()
                .flat_map(|c| &c.bindings)
                .filter(|b| descriptor_type(b.kind) == ty)
                .count() as u32
        };
        let mut f = VkInFlight {
            shared: self.shared.clone(),
            pool: vk::CommandPool::null(),
            fence: vk::Fence::null(),
            descriptor_pool: vk::DescriptorPool::null(),
            query_pool: None,
            submitted: false,
            dispatches: cmds.len(),
            timestamp_valid_bits: self.timestamp_valid_bits,
            timestamp_period_ns: self.timestamp_period_ns,
            staging: Vec::new(),
            init: pending::Pending::default(),
            cmds: Vec::new(),
            reads: Vec::new(),
        };
        // Every object is owned by `f` as soon as it exists: an error drops `f`, which
        // destroys what was made.
        let result = (|| -> Result<()> {
            unsafe {
                f.pool = device
                    .create_command_pool(
                        &vk::CommandPoolCreateInfo::default()
                            .flags(vk::CommandPoolCreateFlags::TRANSIENT)
                            .queue_family_index(self.queue_family),
                        None,
                    )
                    .vk("vkCreateCommandPool")?;
                f.fence = device
                    .create_fence(&vk::FenceCreateInfo::default(), None)
                    .vk("vkCreateFence")?;
                let pool_sizes = [
                    vk::DescriptorPoolSize {
                        ty: vk::DescriptorType::STORAGE_BUFFER,
                        descriptor_count: count(vk::DescriptorType::STORAGE_BUFFER).max(1),
                    },
                    vk::DescriptorPoolSize {
                        ty: vk::DescriptorType::UNIFORM_BUFFER,
                        descriptor_count: count(vk::DescriptorType::UNIFORM_BUFFER).max(1),
                    },
                ];
                f.descriptor_pool = device
                    .create_descriptor_pool(
                        &vk::DescriptorPoolCreateInfo::default()
                            .max_sets(n.max(1))
                            .pool_sizes(&pool_sizes),
                        None,
                    )
                    .vk("vkCreateDescriptorPool")?;
                if self.info.timestamps && n > 0 {
                    f.query_pool = Some(
                        device
                            .create_query_pool(
                                &vk::QueryPoolCreateInfo::default()
                                    .query_type(vk::QueryType::TIMESTAMP)
                                    .query_count(2 * n),
                                None,
                            )
                            .vk("vkCreateQueryPool")?,
                    );
                }
            }
            for (_, bytes) in &reads {
                f.staging
                    .push(self.staging((*bytes).max(4), MemoryLocation::GpuToCpu)?);
            }
            let sets = if n == 0 {
                Vec::new()
            } else {
                let set_layouts: Vec<vk::DescriptorSetLayout> =
                    cmds.iter().map(|c| c.pipeline.set_layout).collect();
                unsafe {
                    device.allocate_descriptor_sets(
                        &vk::DescriptorSetAllocateInfo::default()
                            .descriptor_pool(f.descriptor_pool)
                            .set_layouts(&set_layouts),
                    )
                }
                .vk("vkAllocateDescriptorSets")?
            };
            let buffer_infos: Vec<Vec<vk::DescriptorBufferInfo>> = cmds
                .iter()
                .map(|c| {
                    c.bindings
                        .iter()
                        .map(|arg| vk::DescriptorBufferInfo {
                            buffer: arg.buffer.raw,
                            offset: 0,
                            range: arg.binding_size(),
                        })
                        .collect()
                })
                .collect();
            let writes: Vec<vk::WriteDescriptorSet> = cmds
                .iter()
                .zip(&sets)
                .zip(&buffer_infos)
                .flat_map(|((c, &set), infos)| {
                    c.bindings.iter().zip(infos).map(move |(arg, info)| {
                        vk::WriteDescriptorSet::default()
                            .dst_set(set)
                            .dst_binding(arg.binding)
                            .descriptor_type(descriptor_type(arg.kind))
                            .buffer_info(std::slice::from_ref(info))
                    })
                })
                .collect();
            unsafe { device.update_descriptor_sets(&writes, &[]) };

            let query_pool = f.query_pool;
            unsafe {
                let cb = begin_one_time(device, f.pool)?;
                // Earlier submissions' writes (and host writes) are visible to this one.
                let all = vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE;
                barrier(
                    device,
                    cb,
                    vk::PipelineStageFlags::ALL_COMMANDS,
                    vk::AccessFlags::MEMORY_WRITE,
                    vk::PipelineStageFlags::ALL_COMMANDS,
                    all,
                );
                if let Some(q) = query_pool {
                    device.cmd_reset_query_pool(cb, q, 0, 2 * n);
                }
                for (i, (cmd, &set)) in cmds.iter().zip(&sets).enumerate() {
                    if i > 0 {
                        // Each dispatch sees the previous ones' writes, including
                        // indirect arguments they computed.
                        barrier(
                            device,
                            cb,
                            vk::PipelineStageFlags::COMPUTE_SHADER,
                            vk::AccessFlags::SHADER_WRITE,
                            vk::PipelineStageFlags::COMPUTE_SHADER
                                | vk::PipelineStageFlags::DRAW_INDIRECT,
                            vk::AccessFlags::SHADER_READ
                                | vk::AccessFlags::SHADER_WRITE
                                | vk::AccessFlags::INDIRECT_COMMAND_READ,
                        );
                    }
                    device.cmd_bind_pipeline(
                        cb,
                        vk::PipelineBindPoint::COMPUTE,
                        cmd.pipeline.pipeline,
                    );
                    device.cmd_bind_descriptor_sets(
                        cb,
                        vk::PipelineBindPoint::COMPUTE,
                        cmd.pipeline.layout,
                        0,
                        &[set],
                        &[],
                    );
                    // COMPUTE_SHADER rather than TOP_OF_PIPE: the begin stamp waits for the
                    // previous dispatch, so consecutive timings do not overlap.
                    if let Some(q) = query_pool {
                        device.cmd_write_timestamp(
                            cb,
                            vk::PipelineStageFlags::COMPUTE_SHADER,
                            q,
                            2 * i as u32,
                        );
                    }
                    match &cmd.groups {
                        Groups::Direct([x, y, z]) => device.cmd_dispatch(cb, *x, *y, *z),
                        Groups::Indirect(buffer, offset) => {
                            device.cmd_dispatch_indirect(cb, buffer.raw, *offset)
                        }
                    }
                    if let Some(q) = query_pool {
                        device.cmd_write_timestamp(
                            cb,
                            vk::PipelineStageFlags::COMPUTE_SHADER,
                            q,
                            2 * i as u32 + 1,
                        );
                    }
                }
                if !reads.is_empty() {
                    barrier(
                        device,
                        cb,
                        vk::PipelineStageFlags::ALL_COMMANDS,
                        vk::AccessFlags::MEMORY_WRITE,
                        vk::PipelineStageFlags::TRANSFER,
                        vk::AccessFlags::TRANSFER_READ,
                    );
                    for ((src, bytes), dst) in reads.iter().zip(&f.staging) {
                        let region = vk::BufferCopy {
                            src_offset: 0,
                            dst_offset: 0,
                            size: *bytes,
                        };
                        if *bytes > 0 {
                            device.cmd_copy_buffer(cb, src.raw, dst.raw, &[region]);
                        }
                    }
                }
                // This submission's writes are visible to the host once its fence signals.
                barrier(
                    device,
                    cb,
                    vk::PipelineStageFlags::ALL_COMMANDS,
                    vk::AccessFlags::MEMORY_WRITE,
                    vk::PipelineStageFlags::HOST,
                    vk::AccessFlags::HOST_READ,
                );
                device.end_command_buffer(cb).vk("vkEndCommandBuffer")?;
                // The queue needs external synchronisation; the submitter's lock gives it.
                let s = lock(&self.submitter);
                // New buffers' fills and copies go first, in a command buffer of their own
                // recorded under the lock, so that no submission overtakes them; `cb`'s
                // leading barrier makes their writes visible.
                f.init = std::mem::take(&mut *lock(&self.pending));
                let mut cbs = Vec::with_capacity(2);
                if !f.init.is_empty() {
                    let init = begin_one_time(device, f.pool)?;
                    f.init.record(device, init);
                    device.end_command_buffer(init).vk("vkEndCommandBuffer")?;
                    cbs.push(init);
                }
                cbs.push(cb);
                let submit = vk::SubmitInfo::default().command_buffers(&cbs);
                device
                    .queue_submit(s.queue, &[submit], f.fence)
                    .vk("vkQueueSubmit")?;
                f.submitted = true;
            }
            Ok(())
        })();
        result.map_err(fail)?;
        f.cmds = cmds;
        f.reads = reads;
        Ok(f)
    }
}

/// A submission on the GPU: `wait` for its timings and read-backs. Dropping it without
/// waiting still waits, so nothing it uses is freed while the GPU runs it.
pub(crate) struct VkInFlight {
    shared: Arc<Shared>,
    pool: vk::CommandPool,
    fence: vk::Fence,
    descriptor_pool: vk::DescriptorPool,
    query_pool: Option<vk::QueryPool>,
    submitted: bool,
    dispatches: usize,
    timestamp_valid_bits: u32,
    timestamp_period_ns: f64,
    staging: Vec<Buffer>,
    /// New buffers' fills and copies this submission runs first.
    init: pending::Pending,
    /// Keeps every bound buffer alive until the GPU is done.
    cmds: Vec<Cmd>,
    /// The buffers copied back, and how many bytes of each.
    reads: Vec<(Arc<Buffer>, u64)>,
}

impl VkInFlight {
    /// Waits for the submission; its dispatches' timings and the read-back bytes.
    pub(crate) fn wait(mut self) -> Result<(Vec<DispatchStats>, Vec<Vec<u8>>)> {
        let device = &self.shared.device;
        let fail = |e: RuntimeError| {
            let mut names: Vec<&str> = self.cmds.iter().map(|c| c.kernel.as_str()).collect();
            names.dedup();
            RuntimeError::Dispatch {
                kernel: names.join(", "),
                backend: BACKEND,
                detail: e.to_string(),
            }
        };
        unsafe { device.wait_for_fences(&[self.fence], true, u64::MAX) }
            .vk("vkWaitForFences")
            .map_err(fail)?;
        self.submitted = false;
        let stats = match self.query_pool {
            None => vec![DispatchStats::default(); self.dispatches],
            Some(q) => {
                let mut ticks = vec![0u64; 2 * self.dispatches];
                unsafe {
                    device.get_query_pool_results(
                        q,
                        0,
                        &mut ticks,
                        vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                    )
                }
                .vk("vkGetQueryPoolResults")
                .map_err(fail)?;
                crate::timing::stats_from_ticks(
                    &ticks,
                    self.timestamp_valid_bits,
                    self.timestamp_period_ns,
                )
            }
        };
        let mut reads = Vec::with_capacity(self.staging.len());
        let sizes: Vec<u64> = self.reads.iter().map(|r| r.1).collect();
        for (staging, size) in self.staging.iter_mut().zip(sizes) {
            let bytes = mapped_bytes(staging).map_err(fail)?;
            reads.push(bytes[..size as usize].to_vec());
        }
        Ok((stats, reads))
    }
}

impl Drop for VkInFlight {
    fn drop(&mut self) {
        let device = &self.shared.device;
        unsafe {
            if self.submitted {
                let _ = device.wait_for_fences(&[self.fence], true, u64::MAX);
            }
            if let Some(q) = self.query_pool {
                device.destroy_query_pool(q, None);
            }
            if self.descriptor_pool != vk::DescriptorPool::null() {
                device.destroy_descriptor_pool(self.descriptor_pool, None);
            }
            if self.fence != vk::Fence::null() {
                device.destroy_fence(self.fence, None);
            }
            if self.pool != vk::CommandPool::null() {
                device.destroy_command_pool(self.pool, None);
            }
        }
    }
}

fn mapped_bytes(buffer: &mut Buffer) -> Result<&mut [u8]> {
    buffer
        .allocation
        .as_mut()
        .and_then(|a| a.mapped_slice_mut())
        .ok_or(RuntimeError::Allocation {
            backend: BACKEND,
            bytes: 0,
            detail: "staging memory is not host-mapped".into(),
        })
}

/// A primary command buffer from `pool`, begun for one submission.
///
/// # Safety
/// `pool` belongs to `device`, and no other thread uses it meanwhile.
unsafe fn begin_one_time(device: &ash::Device, pool: vk::CommandPool) -> Result<vk::CommandBuffer> {
    let cb = unsafe {
        device.allocate_command_buffers(
            &vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1),
        )
    }
    .vk("vkAllocateCommandBuffers")?[0];
    let begun = unsafe {
        device.begin_command_buffer(
            cb,
            &vk::CommandBufferBeginInfo::default()
                .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
        )
    };
    if begun.is_err() {
        unsafe { device.free_command_buffers(pool, &[cb]) };
    }
    begun.vk("vkBeginCommandBuffer")?;
    Ok(cb)
}

unsafe fn barrier(
    device: &ash::Device,
    cb: vk::CommandBuffer,
    src_stage: vk::PipelineStageFlags,
    src_access: vk::AccessFlags,
    dst_stage: vk::PipelineStageFlags,
    dst_access: vk::AccessFlags,
) {
    let mb = vk::MemoryBarrier::default()
        .src_access_mask(src_access)
        .dst_access_mask(dst_access);
    unsafe {
        device.cmd_pipeline_barrier(
            cb,
            src_stage,
            dst_stage,
            vk::DependencyFlags::empty(),
            &[mb],
            &[],
            &[],
        )
    };
}

impl Backend for VkDevice {
    fn info(&self) -> &DeviceInfo {
        &self.info
    }

    fn limits(&self) -> &Limits {
        &self.limits
    }

    /// `bytes` is already the padded allocation size; `init` (possibly empty) fills its
    /// start and the rest is zeroed, by a fill or copy that waits for the next submission
    /// (`pending`).
    fn create_buffer(&self, bytes: u64, init: &[u8]) -> Result<RawBuffer> {
        let buffer = Arc::new(self.new_buffer(bytes, BUFFER_USAGE, MemoryLocation::GpuOnly)?);
        if init.is_empty() {
            lock(&self.pending).zero(buffer.clone());
        } else {
            let mut staging = self.staging(bytes, MemoryLocation::CpuToGpu)?;
            let mapped = mapped_bytes(&mut staging)?;
            mapped[..init.len()].copy_from_slice(init);
            mapped[init.len()..bytes as usize].fill(0);
            let submit_now = lock(&self.pending).copy(staging, buffer.clone(), bytes);
            if submit_now {
                self.run(|_, _| {})?;
            }
        }
        Ok(RawBuffer::from_arc(buffer))
    }

    fn create_uniform_buffer(&self, bytes: u64, init: &[u8]) -> Result<RawBuffer> {
        self.create_host_buffer(bytes, init)
    }

    fn write(&self, raw: &RawBuffer, offset: u64, bytes: &[u8]) -> Result<()> {
        let buffer = self
            .own(raw)
            .ok_or(RuntimeError::BufferNotOnDevice { op: "write" })?;
        let mut staging = self.staging(bytes.len() as u64, MemoryLocation::CpuToGpu)?;
        mapped_bytes(&mut staging)?[..bytes.len()].copy_from_slice(bytes);
        let region = vk::BufferCopy {
            src_offset: 0,
            dst_offset: offset,
            size: bytes.len() as u64,
        };
        self.run(|d, cb| unsafe { d.cmd_copy_buffer(cb, staging.raw, buffer.raw, &[region]) })
    }

    fn read(&self, raw: &RawBuffer, dst: &mut [u8]) -> Result<()> {
        let buffer = self
            .own(raw)
            .ok_or(RuntimeError::BufferNotOnDevice { op: "read" })?;
        if dst.is_empty() {
            return Ok(());
        }
        let mut staging = self.staging(dst.len() as u64, MemoryLocation::GpuToCpu)?;
        let region = vk::BufferCopy {
            src_offset: 0,
            dst_offset: 0,
            size: dst.len() as u64,
        };
        self.run(|d, cb| unsafe { d.cmd_copy_buffer(cb, buffer.raw, staging.raw, &[region]) })?;
        let n = dst.len();
        dst.copy_from_slice(&mapped_bytes(&mut staging)?[..n]);
        Ok(())
    }

    /// Compiles (or finds in the cache) the pipeline of `kernel` without dispatching it.
    fn prepare(&self, kernel: &KernelArtifact) -> Result<()> {
        self.pipelines
            .get_or_create(kernel, || self.create_pipeline(kernel))
            .map(|_| ())
    }

    fn take_messages(&self) -> Vec<String> {
        std::mem::take(&mut *lock(&self.shared.messages))
    }

    fn cached_pipeline_count(&self) -> usize {
        self.pipelines.len()
    }

    fn begin(&self) -> Box<dyn Recording<'_> + '_> {
        Recorded::start(self)
    }
}

impl Records for VkDevice {
    type Cmd = Cmd;
    type ReadBuffer = Arc<Buffer>;

    fn record_cmd(
        &self,
        kernel: &KernelArtifact,
        args: &[BufferArg<'_>],
        dispatch: &Dispatch<'_>,
    ) -> Result<Cmd> {
        let pipeline = self
            .pipelines
            .get_or_create(kernel, || self.create_pipeline(kernel))?;
        let (bindings, groups) = resolve(kernel, args, dispatch, |raw| self.own(raw))?;
        Ok(Cmd {
            kernel: kernel.name.clone(),
            pipeline,
            bindings,
            groups,
        })
    }

    /// The buffer behind `raw`, for a read-back recorded in a batch.
    fn read_buffer(&self, raw: &RawBuffer) -> Result<Arc<Buffer>> {
        self.own(raw)
            .ok_or(RuntimeError::BufferNotOnDevice { op: "read back" })
    }

    fn submit_cmds<'d>(
        &'d self,
        cmds: Vec<Cmd>,
        reads: Vec<(Arc<Buffer>, u64)>,
    ) -> Result<Box<dyn InFlight + 'd>> {
        Ok(Box::new(self.submit_async(cmds, reads)?))
    }
}

impl InFlight for VkInFlight {
    fn wait(self: Box<Self>) -> Result<(Vec<DispatchStats>, Vec<Vec<u8>>)> {
        VkInFlight::wait(*self)
    }
}

/// SPIR-V 1.3 of a compiled kernel: what this backend hands the driver. A failure is a
/// compiler bug (the module was validated), reported at the kernel's definition.
#[doc(alias = "naga::back::spv::write_vec")]
pub fn lower(kernel: &CompiledKernel) -> Result<Vec<u32>> {
    let options = naga::back::spv::Options {
        // Subgroup operations need SPIR-V 1.3; 1.0 would silently declare capabilities
        // that spirv-val rejects.
        lang_version: (1, 3),
        flags: naga::back::spv::WriterFlags::empty(),
        // Workgroup memory is zeroed by the driver (Vulkan 1.3 / the zero-initialize
        // extension, which the runtime enables), as WGSL promises, instead of naga's
        // polyfill: a store of every array by invocation 0 plus a barrier in every
        // kernel, which made a 16 KiB workgroup array cost seconds on lavapipe.
        zero_initialize_workgroup_memory:
            naga::back::spv::ZeroInitializeWorkgroupMemoryMode::Native,
        // naga guards every loop with a 64-bit iteration counter, so that a driver cannot
        // assume an endless loop away. A kernel that promises `loops = finite` does
        // without: on confroom's traversal the counters cost 8 % of the renderer's paths/s
        // (H200, BENCHMARKS.md, 2026-11-27, d2bc83f and 807cf8c).
        force_loop_bounding: !kernel.finite_loops,
        ..Default::default()
    };
    let pipeline = naga::back::spv::PipelineOptions {
        shader_stage: naga::ShaderStage::Compute,
        entry_point: kernel.entry_point.clone(),
    };
    let mut words =
        naga::back::spv::write_vec(&kernel.module, &kernel.info, &options, Some(&pipeline))
            .map_err(|e| RuntimeError::Lowering {
                kernel: kernel.name.clone(),
                location: kernel.location.clone(),
                target: "SPIR-V",
                detail: e.to_string(),
            })?;
    crate::spirv_locals::drop_array_local_initializers(&mut words);
    Ok(words)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The messenger really collects: provoke one invalid call through the raw device.
    #[test]
    fn validation_messages_are_collected() {
        let Ok(dev) = VkDevice::new(None) else { return };
        if dev.shared.debug.is_none() {
            println!("skipping: validation layer not active");
            return;
        }
        assert!(dev.take_messages().is_empty());
        let info = vk::BufferCreateInfo::default()
            .size(0) // VUID-VkBufferCreateInfo-size-00912
            .usage(vk::BufferUsageFlags::STORAGE_BUFFER);
        unsafe {
            if let Ok(b) = dev.shared.device.create_buffer(&info, None) {
                dev.shared.device.destroy_buffer(b, None);
            }
        }
        let msgs = dev.take_messages();
        assert!(msgs.iter().any(|m| m.contains("00912")), "{msgs:?}");
        assert!(dev.take_messages().is_empty(), "take drains");
    }
}
