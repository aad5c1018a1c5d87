//! The public face of the runtime: `Device`, its buffers and dispatches, and `Batch`.
//!
//! A call goes: `Device::dispatch` / `Batch::dispatch` → `check_call` (argument count,
//! binding sizes, workgroup counts; backend independent, so every backend rejects the same
//! mistakes with the same messages) → the backend's `record` (cached pipeline + resolved
//! buffer handles, no GPU work yet) → the backend's `submit` (one command buffer, one
//! queue submission, wait, timestamps). `Device::dispatch` is a batch of one. The backend
//! is one `Arc<dyn Backend>` (`backend.rs`).

use std::sync::Arc;

use crate::backend::{Backend, InFlight, Recording};
use crate::buffer::{alloc_size, storage_binding_size, uniform_binding_size};
use crate::print::{self, PrintSite};
use crate::{
    cpu_backend, vulkan_backend, wgpu_backend, BackendKind, BindingKind, BufferArg, GpuBuffer,
    KernelArtifact, Result, RuntimeError,
};

/// What a device offers, as kernels and their launchers need to know it.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub backend: BackendKind,
    pub adapter_name: String,
    pub driver: String,
    /// Whether the adapter is a GPU API implemented in software on the CPU (Mesa's
    /// llvmpipe / lavapipe), which `Device::best` passes over for the CPU backend.
    pub software_driver: bool,
    pub subgroup_size_min: u32,
    pub subgroup_size_max: u32,
    /// The subgroup size a compute pipeline gets when the kernel does not require one.
    pub subgroup_size: u32,
    /// Whether `KernelFeatures::required_subgroup_size` can pick a size in
    /// `[subgroup_size_min, subgroup_size_max]` (Vulkan subgroup size control).
    pub supports_required_subgroup_size: bool,
    /// Whether dispatches report `DispatchStats::gpu_time_ns`.
    pub timestamps: bool,
    /// The largest workgroup count valid in every dimension (some drivers allow more in x).
    pub max_workgroups_per_dim: u32,
    pub max_storage_buffer_binding_size: u64,
    /// Whether kernels keep f32 subnormals (not flushed to zero): the Vulkan backend on
    /// devices with `shaderDenormPreserveFloat32` (docs/LANGUAGE.md, section 4).
    pub f32_subnormals: bool,
    /// Whether kernels keep f32 NaN, infinities and signed zeros as IEEE defines them
    /// (not folded away, e.g. a NaN-propagating select turned into `fmax`): the Vulkan
    /// backend on devices with `shaderSignedZeroInfNanPreserveFloat32`.
    pub f32_nan_inf: bool,
    /// Whether kernels specialised for this device read their uniform parameters from
    /// read-only storage buffers (`Spec::uniforms_as_storage`). The software driver
    /// (Mesa's llvmpipe, 22.x) specialises a kernel on the values of a bound uniform
    /// buffer whose words steer its branches, anew at every bind, and keeps each copy
    /// until the pipeline is destroyed: the path tracer's `extend` grew the process by
    /// about 0.5 MB per dispatch (the Mitsuba-scene work, `render/tests/memory.rs`).
    pub uniforms_as_storage: bool,
}

impl DeviceInfo {
    /// What the compiler may assume about this device when it picks a specialisation.
    pub fn target(&self) -> cohort_compiler::Target {
        cohort_compiler::Target {
            subgroup_size: self.subgroup_size,
            subgroup_size_min: self.subgroup_size_min,
            subgroup_size_max: self.subgroup_size_max,
            supports_required_subgroup_size: self.supports_required_subgroup_size,
            uniforms_as_storage: self.uniforms_as_storage,
            // The CPU backend's vector form runs a group's invocations as SIMD blocks,
            // without barriers (docs/LANGUAGE.md, section 13).
            recompute_group_share: self.backend == BackendKind::Cpu,
        }
    }
}

/// `DeviceInfo::uniforms_as_storage` for a device whose driver would have it `software`:
/// `COHORT_UNIFORMS_AS_STORAGE=0` or `=1` overrides the choice (for comparisons, and for
/// drivers this default does not know).
pub(crate) fn uniforms_as_storage(software: bool) -> bool {
    match std::env::var("COHORT_UNIFORMS_AS_STORAGE").as_deref() {
        Ok("0") => false,
        Ok("1") => true,
        _ => software,
    }
}

/// Device limits the host-side checks need; filled by each backend from its own API.
#[derive(Clone, Debug)]
pub(crate) struct Limits {
    pub max_workgroups: [u32; 3],
    pub max_workgroup_size: [u32; 3],
    pub max_invocations: u32,
    pub max_storage_binding: u64,
    pub max_uniform_binding: u64,
    pub subgroups: bool,
    /// Bytes of workgroup memory one workgroup may use.
    pub max_workgroup_memory: u64,
}

/// How many workgroups to launch.
#[derive(Clone, Copy, Debug)]
pub enum Dispatch<'a> {
    Groups([u32; 3]),
    /// Workgroup counts read by the GPU from `args[offset_elems..offset_elems + 3]`, so a
    /// previous dispatch can size this one. The counts are not checked against the limits.
    Indirect {
        args: &'a GpuBuffer<u32>,
        offset_elems: usize,
    },
}

#[derive(Clone, Copy, Debug, Default)]
pub struct DispatchStats {
    /// Time between GPU timestamps written before and after the dispatch, when the device
    /// supports timestamps on its compute queue.
    pub gpu_time_ns: Option<u64>,
}

/// A GPU device on one backend. Cloning is cheap and shares the device.
#[derive(Clone)]
pub struct Device {
    backend: Arc<dyn Backend>,
}

impl std::fmt::Debug for Device {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let info = self.info();
        write!(
            f,
            "Device({}: {} / {})",
            info.backend.name(),
            info.adapter_name,
            info.driver
        )
    }
}

impl Device {
    /// The best device of the backend: a discrete GPU if there is one.
    pub fn new(kind: BackendKind) -> Result<Device> {
        Device::open(kind, None)
    }

    /// Device number `index` of the backend, in the order it lists its usable devices
    /// (for Vulkan, the loader's order of the devices with Vulkan 1.1 and a compute
    /// queue). An index past the last is `RuntimeError::NoSuchDevice`, which names the
    /// devices there are.
    pub fn new_index(kind: BackendKind, index: usize) -> Result<Device> {
        Device::open(kind, Some(index))
    }

    /// Every usable device of the backend, each opened on its own (so one thread per
    /// device can drive them at once), in index order.
    pub fn all(kind: BackendKind) -> Result<Vec<Device>> {
        let mut devices = Vec::new();
        loop {
            match Device::new_index(kind, devices.len()) {
                Ok(d) => devices.push(d),
                Err(RuntimeError::NoSuchDevice { .. }) if !devices.is_empty() => {
                    return Ok(devices)
                }
                Err(e) => return Err(e),
            }
        }
    }

    fn open(kind: BackendKind, which: Option<usize>) -> Result<Device> {
        // A crash in a driver or a vector form says where it happened.
        crate::crash_report::install();
        let backend: Arc<dyn Backend> = match kind {
            BackendKind::Wgpu => Arc::new(wgpu_backend::WgpuDevice::new(which)?),
            BackendKind::Vulkan => Arc::new(vulkan_backend::VkDevice::new(which)?),
            BackendKind::Cpu => Arc::new(cpu_backend::CpuDevice::new(
                which,
                crate::cpu::simd::Forms::from_env(),
                None,
            )?),
        };
        Ok(Device { backend })
    }

    /// The CPU backend with kernels in the given forms, whatever `COHORT_CPU_SIMD` says
    /// (`Forms::Host` is the reference the vector forms are compared with).
    pub fn cpu_with(forms: crate::cpu::simd::Forms) -> Result<Device> {
        Ok(Device {
            backend: Arc::new(cpu_backend::CpuDevice::new(None, forms, None)?),
        })
    }

    /// [`cpu_with`](Self::cpu_with), with vector forms that run `lanes` invocations per
    /// block (8, 16 or 32: [`crate::cpu::simd::WIDTHS`]) instead of one vector register's
    /// worth ([`crate::cpu::simd::default_lanes`]). Every width computes the same bits.
    pub fn cpu_with_lanes(forms: crate::cpu::simd::Forms, lanes: u32) -> Result<Device> {
        if !crate::cpu::simd::WIDTHS.contains(&lanes) {
            return Err(RuntimeError::DeviceCreation {
                backend: BackendKind::Cpu,
                detail: format!(
                    "{lanes} lanes per block: the vector forms take {:?}",
                    crate::cpu::simd::WIDTHS
                ),
            });
        }
        Ok(Device {
            backend: Arc::new(cpu_backend::CpuDevice::new(None, forms, Some(lanes))?),
        })
    }

    /// A real GPU if there is one: raw Vulkan first (required subgroup sizes, no WGSL
    /// limits), then wgpu. Without one, the CPU backend: on the same cores it renders
    /// faster than the software Vulkan driver (BENCHMARKS.md, "CPU backend").
    pub fn best() -> Result<Device> {
        Device::best_explained().map(|(d, _)| d)
    }

    /// [`best`](Self::best), and when it chose the CPU backend, why (for a note to the user).
    pub fn best_explained() -> Result<(Device, Option<String>)> {
        let software = |name: &str| {
            format!("the only GPU device is {name}, a software driver, slower on the same cores")
        };
        // Where Vulkan's best device is the software driver, its instance tells so, and the
        // CPU backend is taken without creating that device (creating it cost such a
        // render 0.01-0.02 s of its startup on idle cores, more on busy ones: BENCHMARKS.md,
        // "the CPU backend's startup").
        let why = match vulkan_backend::VkDevice::new_unless_software() {
            Ok(Ok(vk)) => {
                return Ok((
                    Device {
                        backend: Arc::new(vk),
                    },
                    None,
                ))
            }
            Ok(Err(name)) => software(&name),
            // No Vulkan device: wgpu's, as `best_gpu` tries them.
            Err(_) => match Device::best_gpu() {
                Ok(d) if !d.info().software_driver => return Ok((d, None)),
                Ok(d) => software(&d.info().adapter_name),
                Err(e) => format!("no GPU device ({e})"),
            },
        };
        Ok((Device::new(BackendKind::Cpu)?, Some(why)))
    }

    /// [`best`](Self::best) among the GPU backends only (the software driver included):
    /// for what only a GPU API can do, such as comparing the WGSL and SPIR-V paths.
    pub fn best_gpu() -> Result<Device> {
        Device::new(BackendKind::Vulkan).or_else(|vk_err| {
            Device::new(BackendKind::Wgpu).map_err(|wgpu_err| match (vk_err, wgpu_err) {
                (
                    RuntimeError::NoAdapter { detail: vk, .. },
                    RuntimeError::NoAdapter { detail: wg, .. },
                ) => RuntimeError::NoAdapter {
                    backend: BackendKind::Vulkan,
                    detail: format!("{vk}; the wgpu backend found none either: {wg}"),
                },
                (vk_err, _) => vk_err,
            })
        })
    }

    /// A device for a test, or `None` (with a "skipping: ..." line) when the machine has no
    /// adapter for `kind`. With `CI=true` a missing adapter panics instead: CI must fail
    /// rather than silently skip every GPU test. Errors other than a missing adapter always
    /// panic, since they are bugs rather than an absent driver.
    pub fn for_tests(kind: BackendKind) -> Option<Device> {
        match Device::new(kind) {
            Ok(device) => Some(device),
            Err(err @ RuntimeError::NoAdapter { .. }) => {
                if std::env::var("CI").as_deref() == Ok("true") {
                    panic!(
                        "CI=true and the {} backend has no adapter: {err}",
                        kind.name()
                    );
                }
                println!("skipping: {err}");
                None
            }
            Err(err) => panic!("could not create a {} device: {err}", kind.name()),
        }
    }

    pub fn info(&self) -> &DeviceInfo {
        self.backend.info()
    }

    /// A zero-filled buffer of `len` elements.
    pub fn alloc<T: bytemuck::Pod>(&self, len: usize) -> Result<GpuBuffer<T>> {
        let bytes = alloc_size(elem_bytes::<T>(len));
        let raw = self.backend.create_buffer(bytes, &[])?;
        Ok(GpuBuffer::new(raw, len))
    }

    pub fn upload<T: bytemuck::Pod>(&self, data: &[T]) -> Result<GpuBuffer<T>> {
        let init: &[u8] = bytemuck::cast_slice(data);
        let bytes = alloc_size(init.len() as u64);
        let raw = self.backend.create_buffer(bytes, init)?;
        Ok(GpuBuffer::new(raw, data.len()))
    }

    /// A small buffer holding `value`, for a kernel's uniform argument. Unlike
    /// [`upload`](Self::upload) it puts no work on the queue (host-visible memory, written
    /// through its mapping), so recording a batch never waits for submissions in flight.
    pub fn upload_uniform<T: bytemuck::Pod>(&self, value: &T) -> Result<GpuBuffer<T>> {
        let init: &[u8] = bytemuck::bytes_of(value);
        let bytes = alloc_size(init.len() as u64);
        let raw = self.backend.create_uniform_buffer(bytes, init)?;
        Ok(GpuBuffer::new(raw, 1))
    }

    /// Overwrites `buf[first..first + data.len()]`. Ordered before any later dispatch or read.
    pub fn write<T: bytemuck::Pod>(
        &self,
        buf: &GpuBuffer<T>,
        first: usize,
        data: &[T],
    ) -> Result<()> {
        if first
            .checked_add(data.len())
            .is_none_or(|end| end > buf.len())
        {
            return Err(RuntimeError::WriteOutOfRange {
                first,
                count: data.len(),
                len: buf.len(),
            });
        }
        if data.is_empty() {
            return Ok(());
        }
        let offset = elem_bytes::<T>(first);
        let bytes: &[u8] = bytemuck::cast_slice(data);
        self.backend.write(&buf.raw, offset, bytes)
    }

    /// Copies the whole buffer back to the host, after all previously submitted work.
    pub fn read<T: bytemuck::Pod>(&self, buf: &GpuBuffer<T>) -> Result<Vec<T>> {
        let mut out = vec![T::zeroed(); buf.len()];
        let dst: &mut [u8] = bytemuck::cast_slice_mut(&mut out);
        self.backend.read(&buf.raw, dst)?;
        Ok(out)
    }

    /// Runs one kernel and waits for it.
    pub fn dispatch(
        &self,
        kernel: &KernelArtifact,
        args: &[BufferArg<'_>],
        dispatch: Dispatch<'_>,
    ) -> Result<DispatchStats> {
        let mut batch = self.batch();
        batch.dispatch(kernel, args, dispatch)?;
        Ok(batch.submit()?.pop().unwrap_or_default())
    }

    /// Starts recording dispatches that are submitted together, in order, each seeing the
    /// writes of the ones before it.
    pub fn batch(&self) -> Batch<'_> {
        Batch {
            recording: self.backend.begin(),
            reads: 0,
            device: self,
            prints: Vec::new(),
        }
    }

    /// Vulkan validation-layer errors and warnings collected since the last call (wgpu:
    /// errors wgpu reported outside any operation of this crate).
    pub fn take_validation_messages(&self) -> Vec<String> {
        self.backend.take_messages()
    }

    /// Compiles the pipeline of `kernel` now (or finds it cached), so that the first
    /// dispatch does not pay for it: a renderer prepares its kernels before it is timed.
    pub fn prepare(&self, kernel: &KernelArtifact) -> Result<()> {
        self.backend.prepare(kernel)
    }

    /// How many pipelines this device has compiled and cached.
    pub fn cached_pipeline_count(&self) -> usize {
        self.backend.cached_pipeline_count()
    }

    /// On the CPU backend, how many of each kernel's dispatches so far ran its vector
    /// form and how many its host form, and why (empty on the other backends).
    pub fn form_counts(&self) -> Vec<crate::cpu::simd::FormCount> {
        self.backend.form_counts()
    }
}

fn elem_bytes<T>(len: usize) -> u64 {
    (len as u64) * std::mem::size_of::<T>() as u64
}

/// Dispatches recorded for one submission. Nothing reaches the GPU before `submit` or
/// `submit_async`.
pub struct Batch<'d> {
    recording: Box<dyn Recording<'d> + 'd>,
    /// Read-backs asked for so far.
    reads: usize,
    device: &'d Device,
    /// The print buffers of the printing dispatches recorded so far.
    prints: Vec<PendingPrint>,
}

/// A printing dispatch's buffer, read back with the batch and printed when it is waited for.
struct PendingPrint {
    kernel: String,
    sites: Vec<PrintSite>,
    read: ReadBack<u32>,
}

/// A buffer's contents as a batch copies them back after its dispatches: the handle
/// returned by [`Batch::read_back`], redeemed with [`Completed::read`].
#[derive(Clone, Copy, Debug)]
pub struct ReadBack<T> {
    index: usize,
    len: usize,
    _t: std::marker::PhantomData<fn() -> T>,
}

/// What a finished submission gives back: one `DispatchStats` per dispatch, in recording
/// order, and the read-backs.
pub struct Completed {
    pub stats: Vec<DispatchStats>,
    reads: Vec<Vec<u8>>,
}

impl Completed {
    /// The contents of a buffer read back by this submission's batch.
    pub fn read<T: bytemuck::Pod>(&self, r: ReadBack<T>) -> Vec<T> {
        let bytes = &self.reads[r.index];
        let mut out = vec![T::zeroed(); r.len];
        bytemuck::cast_slice_mut::<T, u8>(&mut out)
            .copy_from_slice(&bytes[..r.len * std::mem::size_of::<T>()]);
        out
    }
}

/// A batch on the GPU. The host goes on (e.g. records the next batch) until it calls
/// [`wait`](Submission::wait); submissions run in the order they were made. Dropping one
/// without waiting waits for it.
pub struct Submission<'d> {
    inner: Box<dyn InFlight + 'd>,
    prints: Vec<PendingPrint>,
}

impl Submission<'_> {
    /// Waits until the GPU has run the batch, then writes what its kernels printed to
    /// stdout and stderr (a submission dropped without waiting prints nothing).
    pub fn wait(self) -> Result<Completed> {
        let (stats, reads) = self.inner.wait()?;
        let completed = Completed { stats, reads };
        for p in &self.prints {
            print::emit(&p.kernel, &print::decode(&p.sites, &completed.read(p.read)));
        }
        Ok(completed)
    }
}

impl<'d> Batch<'d> {
    /// The device the batch records for (to allocate buffers its dispatches use).
    pub fn device(&self) -> &'d Device {
        self.device
    }

    pub fn dispatch(
        &mut self,
        kernel: &KernelArtifact,
        args: &[BufferArg<'_>],
        dispatch: Dispatch<'_>,
    ) -> Result<()> {
        // A printing kernel gets a zeroed print buffer at its print binding (launches do
        // not pass one); the CPU backend's lanes print directly, so it gets a small one.
        let print_at = kernel
            .bindings
            .iter()
            .position(|b| b.name == print::PRINT_BINDING);
        let print_buffer = match print_at {
            Some(at) if args.len() + 1 == kernel.bindings.len() && at <= args.len() => {
                let words = self.device.backend.print_buffer_words();
                Some((at, self.device.alloc::<u32>(words)?))
            }
            _ => None,
        };
        let Some((at, buffer)) = &print_buffer else {
            return self.record(kernel, args, dispatch);
        };
        let mut with_print = args.to_vec();
        with_print.insert(*at, buffer.arg());
        self.record(kernel, &with_print, dispatch)?;
        let read = self.read_back(buffer)?;
        self.prints.push(PendingPrint {
            kernel: kernel.name.clone(),
            sites: kernel.prints.clone(),
            read,
        });
        Ok(())
    }

    fn record(
        &mut self,
        kernel: &KernelArtifact,
        args: &[BufferArg<'_>],
        dispatch: Dispatch<'_>,
    ) -> Result<()> {
        let backend = &self.device.backend;
        check_call(backend.info(), backend.limits(), kernel, args, &dispatch)?;
        self.recording.record(kernel, args, &dispatch)
    }

    /// Copies `buf` back to the host after all of the batch's dispatches, in the same
    /// submission: its contents arrive with the submission's [`Completed`] without a
    /// separate, blocking read.
    pub fn read_back<T: bytemuck::Pod>(&mut self, buf: &GpuBuffer<T>) -> Result<ReadBack<T>> {
        let bytes = elem_bytes::<T>(buf.len());
        self.recording.read_back(&buf.raw, bytes)?;
        self.reads += 1;
        Ok(ReadBack {
            index: self.reads - 1,
            len: buf.len(),
            _t: std::marker::PhantomData,
        })
    }

    /// Dispatches recorded so far.
    pub fn len(&self) -> usize {
        self.recording.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Submits everything as one command buffer and waits; one `DispatchStats` per dispatch.
    pub fn submit(self) -> Result<Vec<DispatchStats>> {
        Ok(self.submit_async()?.wait()?.stats)
    }

    /// Submits everything as one command buffer and returns at once.
    pub fn submit_async(self) -> Result<Submission<'d>> {
        let prints = self.prints;
        let inner = self.recording.submit()?;
        Ok(Submission { inner, prints })
    }
}

/// Host-side checks shared by every backend, done before any GPU object is touched.
fn check_call(
    info: &DeviceInfo,
    limits: &Limits,
    kernel: &KernelArtifact,
    args: &[BufferArg<'_>],
    dispatch: &Dispatch<'_>,
) -> Result<()> {
    let name = || kernel.name.clone();
    if args.len() != kernel.bindings.len() {
        // The print binding is the runtime's to pass, not the caller's.
        let params: Vec<&str> = kernel
            .bindings
            .iter()
            .map(|b| b.name.as_str())
            .filter(|n| *n != print::PRINT_BINDING)
            .collect();
        return Err(RuntimeError::ArgumentCount {
            kernel: name(),
            expected: params.len(),
            got: args.len(),
            params: params.join(", "),
        });
    }
    for (binding, arg) in kernel.bindings.iter().zip(args) {
        let (kind, size, max) = match binding.kind {
            BindingKind::Uniform => (
                "uniform",
                uniform_binding_size(arg.size_bytes),
                limits.max_uniform_binding,
            ),
            BindingKind::StorageRead | BindingKind::StorageReadWrite => (
                "storage",
                storage_binding_size(arg.size_bytes),
                limits.max_storage_binding,
            ),
        };
        if size > max {
            return Err(RuntimeError::BindingTooLarge {
                kernel: name(),
                param: binding.name.clone(),
                kind,
                size,
                max,
            });
        }
    }
    for (i, (bi, ai)) in kernel.bindings.iter().zip(args).enumerate() {
        for (bj, aj) in kernel.bindings.iter().zip(args).skip(i + 1) {
            let writable = bi.kind == BindingKind::StorageReadWrite
                || bj.kind == BindingKind::StorageReadWrite;
            if writable && ai.raw.same(aj.raw) {
                return Err(RuntimeError::AliasedArguments {
                    kernel: name(),
                    first: bi.name.clone(),
                    second: bj.name.clone(),
                });
            }
        }
    }
    if kernel.features.subgroups && !limits.subgroups {
        return Err(RuntimeError::MissingFeature {
            kernel: name(),
            backend: info.backend,
            feature: "subgroup operations",
        });
    }
    if kernel.features.workgroup_memory_bytes > limits.max_workgroup_memory {
        return Err(RuntimeError::WorkgroupMemoryTooLarge {
            kernel: name(),
            bytes: kernel.features.workgroup_memory_bytes,
            max: limits.max_workgroup_memory,
        });
    }
    let wg = kernel.workgroup_size;
    let invocations = wg.iter().map(|&d| d as u64).product::<u64>();
    if (0..3).any(|d| wg[d] > limits.max_workgroup_size[d])
        || invocations > limits.max_invocations as u64
    {
        return Err(RuntimeError::WorkgroupTooLarge {
            kernel: name(),
            size: wg,
            max_size: limits.max_workgroup_size,
            max_invocations: limits.max_invocations,
        });
    }
    match dispatch {
        Dispatch::Groups(groups) => {
            if (0..3).any(|d| groups[d] > limits.max_workgroups[d]) {
                return Err(RuntimeError::TooManyWorkgroups {
                    kernel: name(),
                    groups: *groups,
                    max: limits.max_workgroups,
                });
            }
        }
        Dispatch::Indirect { args, offset_elems } => {
            if offset_elems
                .checked_add(3)
                .is_none_or(|end| end > args.len())
            {
                return Err(RuntimeError::IndirectOutOfRange {
                    kernel: name(),
                    offset_elems: *offset_elems,
                    len: args.len(),
                });
            }
        }
    }
    Ok(())
}
