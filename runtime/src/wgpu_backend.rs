//! The wgpu backend: lowers compiled kernels to WGSL ([`lower`]). One wgpu device on the Vulkan API (the
//! only API this project targets), buffers as plain `wgpu::Buffer`s, one compute pass per
//! dispatch so that each pass can carry its own timestamp writes.
//!
//! wgpu reports most failures asynchronously through error scopes rather than return
//! values, so every operation that can fail on user input (shader compilation, binding,
//! submission) runs inside a validation + internal error scope that is popped into a
//! `RuntimeError`. Anything that escapes the scopes goes to the uncaptured-error handler,
//! which collects it (wgpu's default handler would panic).

use std::borrow::Cow;
use std::mem::ManuallyDrop;
use std::num::NonZeroU64;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};

use crate::backend::{resolve, Arg, Backend, Groups, InFlight, Recorded, Recording, Records};
use crate::buffer::{round_up, RawBuffer};
use crate::device::Limits;
use crate::pipeline_cache::{Code, PipelineCache};
use crate::{
    BackendKind, BindingKind, BufferArg, CompiledKernel, DeviceInfo, Dispatch, DispatchStats,
    KernelArtifact, KernelCode, Result, RuntimeError,
};

const BACKEND: BackendKind = BackendKind::Wgpu;

/// Distinguishes devices so a buffer from one device is never bound on another.
static NEXT_DEVICE_ID: AtomicU64 = AtomicU64::new(1);

#[derive(Clone)]
pub(crate) struct Buffer {
    pub(crate) device_id: u64,
    pub(crate) buffer: wgpu::Buffer,
}

pub(crate) struct Pipeline {
    pipeline: wgpu::ComputePipeline,
    bind_group_layout: wgpu::BindGroupLayout,
}

/// One recorded dispatch, holding everything it binds so it outlives the caller's borrows.
pub(crate) struct Cmd {
    kernel: String,
    pipeline: Arc<Pipeline>,
    bindings: Vec<Arg<wgpu::Buffer>>,
    groups: Groups<wgpu::Buffer>,
}

pub(crate) struct WgpuDevice {
    id: u64,
    pub(crate) info: DeviceInfo,
    pub(crate) limits: Limits,
    pub(crate) pipelines: PipelineCache<Pipeline>,
    /// Dropped under `vulkan_init::lifecycle`, as the Vulkan backend's devices are.
    device: ManuallyDrop<wgpu::Device>,
    queue: ManuallyDrop<wgpu::Queue>,
    max_buffer_size: u64,
    timestamp_period_ns: f64,
    messages: Arc<Mutex<Vec<String>>>,
    /// Held by every [`Scope`]: wgpu's error scopes (which catch its validation errors)
    /// are one stack per device in this build (its `std` feature, which makes them per
    /// thread, is off), so threads that create pipelines or buffers or record batches on
    /// one device take turns from push to pop.
    scopes: Mutex<()>,
}

const BUFFER_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::UNIFORM)
    .union(wgpu::BufferUsages::INDIRECT)
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

/// Features used when the adapter has them. TIMESTAMP_QUERY alone covers compute-pass
/// timestamp writes; the *_INSIDE_PASSES/ENCODERS features are only for `write_timestamp`.
const WANTED_FEATURES: wgpu::Features = wgpu::Features::SUBGROUP
    .union(wgpu::Features::SUBGROUP_BARRIER)
    .union(wgpu::Features::TIMESTAMP_QUERY)
    .union(wgpu::Features::SHADER_INT64)
    .union(wgpu::Features::SHADER_FLOAT32_ATOMIC);

fn adapter_rank(t: wgpu::DeviceType) -> u32 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    }
}

/// The process's one wgpu instance. A new instance per device made the NVIDIA driver report
/// no adapter after about 17 devices in one process (the Mitsuba render test on an H100);
/// wgpu expects one instance per process anyway.
fn instance() -> &'static wgpu::Instance {
    static INSTANCE: std::sync::OnceLock<wgpu::Instance> = std::sync::OnceLock::new();
    INSTANCE.get_or_init(|| {
        wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::VULKAN,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        })
    })
}

impl Drop for WgpuDevice {
    fn drop(&mut self) {
        let _lifecycle = crate::vulkan_init::lifecycle();
        // The pipelines hold the device too: all go while the lock is held.
        drop(self.pipelines.drain());
        // SAFETY: dropped once, here; no method runs after `drop`.
        unsafe {
            ManuallyDrop::drop(&mut self.queue);
            ManuallyDrop::drop(&mut self.device);
        }
    }
}

impl WgpuDevice {
    /// The best adapter, or adapter number `which` in wgpu's order.
    pub(crate) fn new(which: Option<usize>) -> Result<Self> {
        let mut adapters =
            pollster::block_on(instance().enumerate_adapters(wgpu::Backends::VULKAN));
        if let Some(index) = which {
            if index >= adapters.len() {
                return Err(RuntimeError::NoSuchDevice {
                    backend: BACKEND,
                    index,
                    available: adapters.iter().map(|a| a.get_info().name).collect(),
                });
            }
            adapters = vec![adapters.swap_remove(index)];
        }
        let adapter = adapters
            .into_iter()
            .min_by_key(|a| adapter_rank(a.get_info().device_type))
            .ok_or_else(|| RuntimeError::NoAdapter {
                backend: BACKEND,
                detail: "wgpu enumerated no Vulkan adapter (is libvulkan.so.1 with a driver \
                         ICD installed?)"
                    .into(),
            })?;
        let adapter_info = adapter.get_info();
        let features = adapter.features() & WANTED_FEATURES;
        let lifecycle = crate::vulkan_init::lifecycle();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("cohort"),
            required_features: features,
            // The adapter's own limits, not WebGPU defaults, so large buffers work.
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| RuntimeError::DeviceCreation {
            backend: BACKEND,
            detail: e.to_string(),
        })?;
        drop(lifecycle);

        let messages = Arc::new(Mutex::new(Vec::new()));
        let sink = messages.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            let msg = format!("wgpu: {e}");
            eprintln!("{msg}");
            sink.lock().unwrap_or_else(|p| p.into_inner()).push(msg);
        }));

        let l = device.limits();
        let (sg_min, sg_max) = (
            adapter_info.subgroup_min_size,
            adapter_info.subgroup_max_size,
        );
        let subgroup_size = if sg_min == sg_max {
            sg_min
        } else {
            vulkan_default_subgroup_size(&adapter)
                .filter(|s| (sg_min..=sg_max).contains(s))
                .unwrap_or(sg_max)
        };
        let timestamps = features.contains(wgpu::Features::TIMESTAMP_QUERY)
            && queue.get_timestamp_period() > 0.0;
        // The software driver under wgpu, as under the Vulkan backend.
        let software = adapter_info.device_type == wgpu::DeviceType::Cpu
            && adapter_info
                .driver
                .to_ascii_lowercase()
                .contains("llvmpipe");
        let info = DeviceInfo {
            backend: BACKEND,
            adapter_name: adapter_info.name.clone(),
            driver: format!("{} {}", adapter_info.driver, adapter_info.driver_info)
                .trim()
                .to_string(),
            software_driver: software,
            subgroup_size_min: sg_min,
            subgroup_size_max: sg_max,
            subgroup_size,
            // wgpu 30 has no way to request a subgroup size for a pipeline.
            supports_required_subgroup_size: false,
            timestamps,
            max_workgroups_per_dim: l.max_compute_workgroups_per_dimension,
            max_storage_buffer_binding_size: l.max_storage_buffer_binding_size,
            // wgpu compiles WGSL itself and cannot request float controls: the driver's
            // defaults apply (lavapipe keeps IEEE behaviour; NVIDIA flushes subnormals).
            f32_subnormals: false,
            f32_nan_inf: false,
            uniforms_as_storage: crate::device::uniforms_as_storage(software),
        };
        let limits = Limits {
            max_workgroups: [l.max_compute_workgroups_per_dimension; 3],
            max_workgroup_size: [
                l.max_compute_workgroup_size_x,
                l.max_compute_workgroup_size_y,
                l.max_compute_workgroup_size_z,
            ],
            max_invocations: l.max_compute_invocations_per_workgroup,
            max_storage_binding: l.max_storage_buffer_binding_size,
            max_workgroup_memory: l.max_compute_workgroup_storage_size as u64,
            max_uniform_binding: l.max_uniform_buffer_binding_size,
            subgroups: features.contains(wgpu::Features::SUBGROUP),
        };
        Ok(WgpuDevice {
            id: NEXT_DEVICE_ID.fetch_add(1, Ordering::Relaxed),
            info,
            limits,
            pipelines: PipelineCache::new(Code::Wgsl),
            max_buffer_size: l.max_buffer_size,
            timestamp_period_ns: queue.get_timestamp_period() as f64,
            device: ManuallyDrop::new(device),
            queue: ManuallyDrop::new(queue),
            messages,
            scopes: Mutex::new(()),
        })
    }

    fn own<'a>(&self, raw: &'a RawBuffer) -> Option<&'a wgpu::Buffer> {
        raw.get_ref::<Buffer>()
            .filter(|b| b.device_id == self.id)
            .map(|b| &b.buffer)
    }

    fn create_pipeline(&self, kernel: &KernelArtifact) -> Result<Pipeline> {
        let fail = |detail: String| RuntimeError::ShaderCompilation {
            kernel: kernel.name.clone(),
            backend: BACKEND,
            detail,
        };
        let lowered;
        let (wgsl, entry_point) = match &kernel.code {
            KernelCode::Compiled(k) => {
                lowered = lower(k)?;
                (&lowered.code, &lowered.entry_point)
            }
            KernelCode::Shaders {
                wgsl, entry_point, ..
            } => (wgsl, entry_point),
        };
        if wgsl.trim().is_empty() {
            return Err(fail("the artifact has no WGSL code".into()));
        }
        let scope = Scope::push(self);
        let desc = wgpu::ShaderModuleDescriptor {
            label: Some(&kernel.name),
            source: wgpu::ShaderSource::Wgsl(strip_subgroups_enable(wgsl)),
        };
        let module = match &kernel.code {
            // A `loops = finite` kernel: no loop-bound counters (as on the Vulkan backend);
            // bounds checks stay as wgpu's default.
            KernelCode::Compiled(k) if k.finite_loops => {
                let checks = wgpu::ShaderRuntimeChecks {
                    force_loop_bounding: false,
                    ..wgpu::ShaderRuntimeChecks::checked()
                };
                // SAFETY: the kernel's author promises that all its loops end
                // (`KernelInfo::finite_loops`); only loop bounding is turned off.
                unsafe { self.device.create_shader_module_trusted(desc, checks) }
            }
            _ => self.device.create_shader_module(desc),
        };
        let entries: Vec<wgpu::BindGroupLayoutEntry> = kernel
            .bindings
            .iter()
            .map(|b| wgpu::BindGroupLayoutEntry {
                binding: b.binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: match b.kind {
                        BindingKind::StorageRead => {
                            wgpu::BufferBindingType::Storage { read_only: true }
                        }
                        BindingKind::StorageReadWrite => {
                            wgpu::BufferBindingType::Storage { read_only: false }
                        }
                        BindingKind::Uniform => wgpu::BufferBindingType::Uniform,
                    },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            })
            .collect();
        let bind_group_layout =
            self.device
                .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(&kernel.name),
                    entries: &entries,
                });
        let layout = self
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(&kernel.name),
                bind_group_layouts: &[Some(&bind_group_layout)],
                immediate_size: 0,
            });
        let pipeline = self
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(&kernel.name),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry_point),
                compilation_options: Default::default(),
                cache: None,
            });
        scope.pop().map_err(fail)?;
        Ok(Pipeline {
            pipeline,
            bind_group_layout,
        })
    }

    /// Submits `cmds`, then copies of `reads` (buffer, bytes) into mappable buffers, and
    /// returns without waiting (wgpu queues submissions in order).
    pub(crate) fn submit_async(
        &self,
        cmds: Vec<Cmd>,
        reads: Vec<(wgpu::Buffer, u64)>,
    ) -> Result<WgpuInFlight> {
        let mut names: Vec<&str> = cmds.iter().map(|c| c.kernel.as_str()).collect();
        names.dedup();
        let names = names.join(", ");
        let fail = |detail: String| RuntimeError::Dispatch {
            kernel: names.clone(),
            backend: BACKEND,
            detail,
        };
        let n = cmds.len() as u32;
        let scope = Scope::push(self);
        let queries = (self.info.timestamps && n > 0).then(|| {
            self.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("cohort timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * n,
            })
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        for (i, cmd) in cmds.iter().enumerate() {
            let entries: Vec<wgpu::BindGroupEntry> = cmd
                .bindings
                .iter()
                .map(|arg| wgpu::BindGroupEntry {
                    binding: arg.binding,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &arg.buffer,
                        offset: 0,
                        size: NonZeroU64::new(arg.binding_size()),
                    }),
                })
                .collect();
            let bind_group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(&cmd.kernel),
                layout: &cmd.pipeline.bind_group_layout,
                entries: &entries,
            });
            let timestamp_writes = queries.as_ref().map(|q| wgpu::ComputePassTimestampWrites {
                query_set: q,
                beginning_of_pass_write_index: Some(2 * i as u32),
                end_of_pass_write_index: Some(2 * i as u32 + 1),
            });
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&cmd.kernel),
                timestamp_writes,
            });
            pass.set_pipeline(&cmd.pipeline.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            match &cmd.groups {
                Groups::Direct([x, y, z]) => pass.dispatch_workgroups(*x, *y, *z),
                Groups::Indirect(buffer, offset) => {
                    pass.dispatch_workgroups_indirect(buffer, *offset)
                }
            }
        }
        let timestamps = queries.as_ref().map(|q| {
            let bytes = 16 * n as u64;
            let resolve = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("cohort timestamp resolve"),
                size: bytes,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let readback = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("cohort timestamp readback"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            enc.resolve_query_set(q, 0..2 * n, &resolve, 0);
            enc.copy_buffer_to_buffer(&resolve, 0, &readback, 0, bytes);
            readback
        });
        let mut read_buffers = Vec::with_capacity(reads.len());
        for (src, bytes) in &reads {
            // Allocations are multiples of 16 bytes, so the rounded copy stays inside.
            let size = round_up((*bytes).max(4), wgpu::COPY_BUFFER_ALIGNMENT);
            let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("cohort batch readback"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            enc.copy_buffer_to_buffer(src, 0, &staging, 0, size);
            read_buffers.push((staging, *bytes));
        }
        let command_buffer = enc.finish();
        // Encoding errors (bad bindings, ...) surface here; submitting an invalid command
        // buffer would only add a second, less helpful error.
        scope.pop().map_err(fail)?;

        let scope = Scope::push(self);
        let index = self.queue.submit([command_buffer]);
        scope.pop().map_err(fail)?;
        // Mapping requests complete once the device is polled past this submission.
        let timestamps = timestamps.map(|b| {
            let rx = map_read(&b);
            (b, rx)
        });
        let reads = read_buffers
            .into_iter()
            .map(|(b, bytes)| {
                let rx = map_read(&b);
                (b, bytes, rx)
            })
            .collect();
        Ok(WgpuInFlight {
            index,
            names,
            dispatches: cmds.len(),
            timestamps,
            reads,
        })
    }

    /// Waits for a submission; its dispatches' timings and the read-back bytes.
    pub(crate) fn wait_for(&self, f: WgpuInFlight) -> Result<(Vec<DispatchStats>, Vec<Vec<u8>>)> {
        let fail = |e: RuntimeError| RuntimeError::Dispatch {
            kernel: f.names.clone(),
            backend: BACKEND,
            detail: e.to_string(),
        };
        self.wait(f.index.clone()).map_err(fail)?;
        let stats = match f.timestamps {
            None => vec![DispatchStats::default(); f.dispatches],
            Some((readback, rx)) => {
                receive_map(rx).map_err(fail)?;
                let view =
                    readback
                        .slice(..)
                        .get_mapped_range()
                        .map_err(|e| RuntimeError::Wgpu {
                            context: "timestamp mapping",
                            detail: e.to_string(),
                        })?;
                let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(&view[..]);
                // wgpu hands back raw 64-bit ticks; the Vulkan layer below already masked them.
                crate::timing::stats_from_ticks(&ticks, 64, self.timestamp_period_ns)
            }
        };
        let mut reads = Vec::with_capacity(f.reads.len());
        for (buffer, bytes, rx) in f.reads {
            receive_map(rx).map_err(fail)?;
            let view = buffer
                .slice(..)
                .get_mapped_range()
                .map_err(|e| RuntimeError::Wgpu {
                    context: "read-back mapping",
                    detail: e.to_string(),
                })?;
            reads.push(view[..bytes as usize].to_vec());
        }
        Ok((stats, reads))
    }

    fn wait(&self, index: wgpu::SubmissionIndex) -> Result<()> {
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map(|_| ())
            .map_err(|e| RuntimeError::Wgpu {
                context: "device poll",
                detail: e.to_string(),
            })
    }
}

/// A submission on the queue: `WgpuDevice::wait_for` gives its timings and read-backs.
/// (wgpu keeps what a submitted command buffer uses alive by itself.)
pub(crate) struct WgpuInFlight {
    index: wgpu::SubmissionIndex,
    names: String,
    dispatches: usize,
    timestamps: Option<(wgpu::Buffer, MapReceiver)>,
    reads: Vec<(wgpu::Buffer, u64, MapReceiver)>,
}

type MapReceiver = mpsc::Receiver<std::result::Result<(), wgpu::BufferAsyncError>>;

/// Starts mapping `buffer` for reading; the result arrives once the device is polled.
fn map_read(
    buffer: &wgpu::Buffer,
) -> mpsc::Receiver<std::result::Result<(), wgpu::BufferAsyncError>> {
    let (tx, rx) = mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    rx
}

fn receive_map(rx: mpsc::Receiver<std::result::Result<(), wgpu::BufferAsyncError>>) -> Result<()> {
    match rx.recv() {
        Ok(Ok(())) => Ok(()),
        Ok(Err(e)) => Err(RuntimeError::Wgpu {
            context: "map_async",
            detail: e.to_string(),
        }),
        Err(_) => Err(RuntimeError::Wgpu {
            context: "map_async",
            detail: "the mapping callback never ran".into(),
        }),
    }
}

/// naga 30's WGSL front end knows `enable subgroups;` but rejects it as "not yet
/// implemented", while accepting subgroup builtins without it (gated on the device's
/// SUBGROUP feature instead). Standard WGSL requires the directive, so code written for
/// other implementations carries it; drop it here rather than fail.
fn strip_subgroups_enable(wgsl: &str) -> Cow<'_, str> {
    let is_directive = |line: &str| {
        let compact: String = line.chars().filter(|c| !c.is_whitespace()).collect();
        compact == "enablesubgroups;"
    };
    if !wgsl.lines().any(is_directive) {
        return Cow::Borrowed(wgsl);
    }
    let kept: Vec<&str> = wgsl
        .lines()
        .map(|l| if is_directive(l) { "" } else { l })
        .collect();
    Cow::Owned(kept.join("\n"))
}

/// The subgroup size Vulkan gives a pipeline by default, read through wgpu's Vulkan HAL
/// (wgpu itself only reports the min/max range).
fn vulkan_default_subgroup_size(adapter: &wgpu::Adapter) -> Option<u32> {
    // SAFETY: only queries properties through the adapter's live instance and device.
    let hal = unsafe { adapter.as_hal::<wgpu::hal::api::Vulkan>() }?;
    let instance = hal.shared_instance().raw_instance();
    let mut subgroup = ash::vk::PhysicalDeviceSubgroupProperties::default();
    let mut props = ash::vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
    unsafe { instance.get_physical_device_properties2(hal.raw_physical_device(), &mut props) };
    Some(subgroup.subgroup_size).filter(|&s| s > 0)
}

/// A validation scope nested in an internal-error scope, popped together: the first error
/// either caught (validation first, as it is the one user code triggers) as its message.
/// It holds the device's `scopes` lock from push to pop.
struct Scope<'a> {
    internal: wgpu::ErrorScopeGuard,
    validation: wgpu::ErrorScopeGuard,
    _one_at_a_time: std::sync::MutexGuard<'a, ()>,
}

impl<'a> Scope<'a> {
    fn push(d: &'a WgpuDevice) -> Self {
        let one_at_a_time = d.scopes.lock().unwrap_or_else(|e| e.into_inner());
        let internal = d.device.push_error_scope(wgpu::ErrorFilter::Internal);
        let validation = d.device.push_error_scope(wgpu::ErrorFilter::Validation);
        Scope {
            internal,
            validation,
            _one_at_a_time: one_at_a_time,
        }
    }

    fn pop(self) -> std::result::Result<(), String> {
        let validation = pollster::block_on(self.validation.pop());
        let internal = pollster::block_on(self.internal.pop());
        match validation.or(internal) {
            None => Ok(()),
            Some(e) => Err(error_text(&e)),
        }
    }
}

/// wgpu's `Display` for an error is only the top line; the cause chain holds the details
/// (e.g. the WGSL parse error with its source location).
fn error_text(e: &wgpu::Error) -> String {
    let mut text = e.to_string();
    let mut source = std::error::Error::source(e);
    while let Some(s) = source {
        let line = s.to_string();
        if !text.contains(&line) {
            text.push_str(": ");
            text.push_str(&line);
        }
        source = s.source();
    }
    text
}

impl Backend for WgpuDevice {
    fn info(&self) -> &DeviceInfo {
        &self.info
    }

    fn limits(&self) -> &Limits {
        &self.limits
    }

    /// `bytes` is already the padded allocation size; `init` (possibly empty) fills its
    /// start. wgpu zero-initialises the rest.
    fn create_buffer(&self, bytes: u64, init: &[u8]) -> Result<RawBuffer> {
        if bytes > self.max_buffer_size {
            return Err(RuntimeError::Allocation {
                backend: BACKEND,
                bytes,
                detail: format!("the device's max_buffer_size is {}", self.max_buffer_size),
            });
        }
        let scope = Scope::push(self);
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: bytes,
            usage: BUFFER_USAGE,
            mapped_at_creation: !init.is_empty(),
        });
        if !init.is_empty() {
            // Mapping at creation writes straight into the allocation: no staging copy.
            let mut view =
                buffer
                    .slice(..)
                    .get_mapped_range_mut()
                    .map_err(|e| RuntimeError::Wgpu {
                        context: "buffer mapping",
                        detail: e.to_string(),
                    })?;
            view.slice(..init.len()).copy_from_slice(init);
            drop(view);
            buffer.unmap();
        }
        scope.pop().map_err(|detail| RuntimeError::Allocation {
            backend: BACKEND,
            bytes,
            detail,
        })?;
        Ok(RawBuffer::new(Buffer {
            device_id: self.id,
            buffer,
        }))
    }

    fn write(&self, raw: &RawBuffer, offset: u64, bytes: &[u8]) -> Result<()> {
        let buffer = self
            .own(raw)
            .ok_or(RuntimeError::BufferNotOnDevice { op: "write" })?;
        let align = wgpu::COPY_BUFFER_ALIGNMENT;
        if offset % align != 0 {
            return Err(RuntimeError::Unaligned {
                what: "a write offset",
                bytes: offset,
            });
        }
        if bytes.len() as u64 % align != 0 {
            return Err(RuntimeError::Unaligned {
                what: "a write",
                bytes: bytes.len() as u64,
            });
        }
        let scope = Scope::push(self);
        // Staged by wgpu and executed before the next submission, which keeps it ordered
        // before any later dispatch or read.
        self.queue.write_buffer(buffer, offset, bytes);
        scope.pop().map_err(|detail| RuntimeError::Wgpu {
            context: "write_buffer",
            detail,
        })
    }

    fn read(&self, raw: &RawBuffer, dst: &mut [u8]) -> Result<()> {
        let buffer = self
            .own(raw)
            .ok_or(RuntimeError::BufferNotOnDevice { op: "read" })?;
        if dst.is_empty() {
            return Ok(());
        }
        // Allocations are multiples of 16 bytes, so the rounded copy stays inside.
        let size = round_up(dst.len() as u64, wgpu::COPY_BUFFER_ALIGNMENT);
        let scope = Scope::push(self);
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("cohort readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
        let index = self.queue.submit([enc.finish()]);
        let mapped = map_read(&staging);
        self.wait(index)?;
        scope.pop().map_err(|detail| RuntimeError::Wgpu {
            context: "read",
            detail,
        })?;
        receive_map(mapped)?;
        let view = staging
            .slice(..)
            .get_mapped_range()
            .map_err(|e| RuntimeError::Wgpu {
                context: "buffer mapping",
                detail: e.to_string(),
            })?;
        dst.copy_from_slice(&view[..dst.len()]);
        Ok(())
    }

    /// Compiles (or finds in the cache) the pipeline of `kernel` without dispatching it.
    fn prepare(&self, kernel: &KernelArtifact) -> Result<()> {
        self.pipelines
            .get_or_create(kernel, || self.create_pipeline(kernel))
            .map(|_| ())
    }

    fn take_messages(&self) -> Vec<String> {
        std::mem::take(&mut *self.messages.lock().unwrap_or_else(|p| p.into_inner()))
    }

    fn cached_pipeline_count(&self) -> usize {
        self.pipelines.len()
    }

    fn begin(&self) -> Box<dyn Recording<'_> + '_> {
        Recorded::start(self)
    }
}

impl Records for WgpuDevice {
    type Cmd = Cmd;
    type ReadBuffer = wgpu::Buffer;

    fn record_cmd(
        &self,
        kernel: &KernelArtifact,
        args: &[BufferArg<'_>],
        dispatch: &Dispatch<'_>,
    ) -> Result<Cmd> {
        if let Some(n) = kernel.features.required_subgroup_size {
            let (min, max) = (self.info.subgroup_size_min, self.info.subgroup_size_max);
            if !(min == max && n == min) {
                return Err(RuntimeError::SubgroupSize {
                    kernel: kernel.name.clone(),
                    backend: BACKEND,
                    required: n,
                    detail: format!(
                        "wgpu cannot pin a pipeline's subgroup size and this adapter's sizes \
                         range over [{min}, {max}]; use the vulkan backend"
                    ),
                });
            }
        }
        let pipeline = self
            .pipelines
            .get_or_create(kernel, || self.create_pipeline(kernel))?;
        let (bindings, groups) = resolve(kernel, args, dispatch, |raw| self.own(raw).cloned())?;
        Ok(Cmd {
            kernel: kernel.name.clone(),
            pipeline,
            bindings,
            groups,
        })
    }

    /// The buffer behind `raw`, for a read-back recorded in a batch.
    fn read_buffer(&self, raw: &RawBuffer) -> Result<wgpu::Buffer> {
        self.own(raw)
            .cloned()
            .ok_or(RuntimeError::BufferNotOnDevice { op: "read back" })
    }

    fn submit_cmds<'d>(
        &'d self,
        cmds: Vec<Cmd>,
        reads: Vec<(wgpu::Buffer, u64)>,
    ) -> Result<Box<dyn InFlight + 'd>> {
        let submitted = self.submit_async(cmds, reads)?;
        Ok(Box::new(Submitted {
            device: self,
            submitted,
        }))
    }
}

/// A submission and the device that waits for it.
struct Submitted<'d> {
    device: &'d WgpuDevice,
    submitted: WgpuInFlight,
}

impl InFlight for Submitted<'_> {
    fn wait(self: Box<Self>) -> Result<(Vec<DispatchStats>, Vec<Vec<u8>>)> {
        self.device.wait_for(self.submitted)
    }
}

/// A compiled kernel as WGSL: what this backend hands wgpu.
#[derive(Clone, Debug)]
pub struct Wgsl {
    pub code: String,
    /// The entry point's name in `code` (naga's namer may change a kernel's name).
    pub entry_point: String,
}

/// WGSL of a compiled kernel. A failure is a compiler bug (the module was validated),
/// reported at the kernel's definition.
#[doc(alias = "naga::back::wgsl::write_string")]
pub fn lower(kernel: &CompiledKernel) -> Result<Wgsl> {
    let code = naga::back::wgsl::write_string(
        &kernel.module,
        &kernel.info,
        naga::back::wgsl::WriterFlags::empty(),
    )
    .map_err(|e| RuntimeError::Lowering {
        kernel: kernel.name.clone(),
        location: kernel.location.clone(),
        target: "WGSL",
        detail: e.to_string(),
    })?;
    let entry_point = wgsl_entry_point(&code).unwrap_or_else(|| kernel.entry_point.clone());
    Ok(Wgsl { code, entry_point })
}

/// The name of the `@compute` function in `wgsl`.
fn wgsl_entry_point(wgsl: &str) -> Option<String> {
    let at = wgsl.find("@compute")?;
    let rest = &wgsl[at..];
    let f = rest.find("fn ")? + 3;
    let name: String = rest[f..]
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect();
    (!name.is_empty()).then_some(name)
}
