//! The native CPU backend: buffers in host memory, and dispatches that run, for every
//! invocation, the kernel's own Rust function (`KernelArtifact::host`, `cpu::lanes` runs one
//! workgroup) or its vector form (`cpu::simd`, a block of lanes per call), whichever
//! `cpu::simd::Chooser` measures faster; workgroups are spread over all cores by rayon.
//! Submissions run when they are made, so a `Submission` is already complete; timestamps
//! are wall time.

use std::cell::{RefCell, UnsafeCell};
use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use rayon::prelude::*;

use crate::backend::{
    resolve, Arg, Backend, Finished, Groups, InFlight, Recorded, Recording, Records,
};
use crate::buffer::RawBuffer;
use crate::cpu::{self, HostBuf, HostKernel};
use crate::device::{DeviceInfo, Dispatch, DispatchStats, Limits};
use crate::{BackendKind, BufferArg, KernelArtifact, KernelCode, Result, RuntimeError};

/// Host memory of one buffer, 16-byte aligned and zero-filled.
pub(crate) struct CpuBuffer {
    mem: Box<[UnsafeCell<u128>]>,
}
// Dispatches write buffers from several threads at once, as GPU invocations do.
unsafe impl Send for CpuBuffer {}
unsafe impl Sync for CpuBuffer {}

impl CpuBuffer {
    fn new(bytes: u64, init: &[u8]) -> Result<CpuBuffer> {
        let words = usize::try_from(bytes.div_ceil(16)).map_err(|_| RuntimeError::Allocation {
            backend: BackendKind::Cpu,
            bytes,
            detail: "larger than the address space".into(),
        })?;
        let mut v = Vec::new();
        v.try_reserve_exact(words)
            .map_err(|e| RuntimeError::Allocation {
                backend: BackendKind::Cpu,
                bytes,
                detail: e.to_string(),
            })?;
        v.resize_with(words, || UnsafeCell::new(0));
        let buf = CpuBuffer {
            mem: v.into_boxed_slice(),
        };
        // SAFETY: fresh allocation of at least `init.len()` bytes.
        unsafe { std::ptr::copy_nonoverlapping(init.as_ptr(), buf.ptr(), init.len()) };
        Ok(buf)
    }

    fn ptr(&self) -> *mut u8 {
        UnsafeCell::raw_get(self.mem.as_ptr()) as *mut u8
    }

    fn bytes(&self) -> usize {
        self.mem.len() * 16
    }
}

/// One recorded dispatch.
pub(crate) struct Cmd {
    name: String,
    /// The compiled kernel, for its vector form.
    code: Option<Arc<cohort_compiler::CompiledKernel>>,
    host: Option<HostKernel>,
    workgroup_size: u32,
    /// The kept buffers (alive until the dispatch ran) and their logical sizes.
    args: Vec<Arg<Arc<CpuBuffer>>>,
    groups: Groups<Arc<CpuBuffer>>,
}

pub(crate) struct CpuDevice {
    pub(crate) info: DeviceInfo,
    pub(crate) limits: Limits,
    forms: cpu::simd::Forms,
    /// Invocations per block of the vector forms (one of `cpu::simd::WIDTHS`).
    lanes: u32,
    chooser: cpu::simd::Chooser,
    ran: cpu::simd::FormCounts,
}

thread_local! {
    static SCRATCH: RefCell<cpu::Scratch> = RefCell::new(cpu::Scratch::new());
}

impl CpuDevice {
    /// The CPU device, running kernels in `forms`, vector forms in blocks of `lanes`
    /// (`cpu::simd::default_lanes` when `None`).
    pub(crate) fn new(
        which: Option<usize>,
        forms: cpu::simd::Forms,
        lanes: Option<u32>,
    ) -> Result<CpuDevice> {
        use cpu::simd::Forms;
        let lanes = lanes.unwrap_or_else(cpu::simd::default_lanes);
        if let Some(index) = which.filter(|&i| i > 0) {
            return Err(RuntimeError::NoSuchDevice {
                backend: BackendKind::Cpu,
                index,
                available: vec![cpu_name()],
            });
        }
        Ok(CpuDevice {
            info: DeviceInfo {
                backend: BackendKind::Cpu,
                adapter_name: cpu_name(),
                driver: format!(
                    "cohort native, {} threads, {}",
                    rayon::current_num_threads(),
                    match (forms, cpu::simd::llvm_library()) {
                        (Forms::Host, _) => "host forms".to_string(),
                        // The reason, so that a user who named a libLLVM learns why
                        // it was refused.
                        (_, Err(why)) => format!("host forms ({why})"),
                        (Forms::Vector, Ok(lib)) => format!("{lanes}-lane vector forms ({lib})"),
                        (Forms::Measured, Ok(lib)) =>
                            format!("the faster of host and {lanes}-lane vector forms ({lib})"),
                    }
                ),
                software_driver: false,
                subgroup_size_min: cpu::SUBGROUP_WIDTH,
                subgroup_size_max: cpu::SUBGROUP_WIDTH,
                subgroup_size: cpu::SUBGROUP_WIDTH,
                supports_required_subgroup_size: true,
                timestamps: true,
                max_workgroups_per_dim: 65535,
                max_storage_buffer_binding_size: u32::MAX as u64,
                // Rust's f32 arithmetic on x86-64 and AArch64 is IEEE without flushing.
                f32_subnormals: true,
                f32_nan_inf: true,
                uniforms_as_storage: false,
            },
            limits: Limits {
                max_workgroups: [65535; 3],
                max_workgroup_size: [1024, 1, 1],
                max_invocations: 1024,
                max_storage_binding: u32::MAX as u64,
                max_uniform_binding: 1 << 16,
                subgroups: true,
                // The H100's default: a kernel that fits here fits on the GPUs people
                // move it to (the CPU itself would take far more).
                max_workgroup_memory: 48 * 1024,
            },
            forms,
            lanes,
            chooser: Default::default(),
            ran: Default::default(),
        })
    }

    /// Whether a compiled kernel's vector form is ready for this device (see
    /// `cpu::simd::compiled`: a kernel with a host form runs that until its vector form is
    /// ready; others wait for it).
    fn simd_form(
        &self,
        code: &Option<Arc<cohort_compiler::CompiledKernel>>,
        has_host: bool,
    ) -> cpu::simd::Ready {
        match code {
            Some(k) if self.forms != cpu::simd::Forms::Host => {
                let wait = self.forms == cpu::simd::Forms::Vector || !has_host;
                cpu::simd::compiled(k, self.lanes, wait)
            }
            _ => cpu::simd::Ready::Never,
        }
    }

    fn own(&self, raw: &RawBuffer, op: &'static str) -> Result<Arc<CpuBuffer>> {
        raw.get::<CpuBuffer>()
            .ok_or(RuntimeError::BufferNotOnDevice { op })
    }

    /// Runs the dispatches in order, then copies the read-backs.
    pub(crate) fn submit(
        &self,
        cmds: Vec<Cmd>,
        reads: Vec<(Arc<CpuBuffer>, u64)>,
    ) -> Result<(Vec<DispatchStats>, Vec<Vec<u8>>)> {
        // The dispatches run in order on a thread of rayon's pool (`rayon::scope` from a
        // thread outside it runs its body there), not on the submitting thread: from
        // outside, each dispatch's parallel loop would put this thread to sleep until the
        // pool finished it and then wake it, and wake the pool's idle threads for the next
        // one, a futex round trip per dispatch that kept the cores 7 % idle in a render.
        let awake = &Awake::default();
        let stats = rayon::scope(|s| {
            let _done = awake.until_dropped();
            let submitter = rayon::current_thread_index();
            for _ in 1..rayon::current_num_threads() {
                s.spawn(move |_| awake.keep(submitter));
            }
            let mut stats = Vec::with_capacity(cmds.len());
            for cmd in &cmds {
                let start = Instant::now();
                self.run(cmd)?;
                stats.push(DispatchStats {
                    gpu_time_ns: Some(start.elapsed().as_nanos() as u64),
                });
            }
            Ok::<_, RuntimeError>(stats)
        })?;
        let reads = reads
            .into_iter()
            .map(|(b, bytes)| {
                let mut out = vec![0u8; bytes as usize];
                read_prefix(&b, &mut out);
                out
            })
            .collect();
        Ok((stats, reads))
    }
}

/// The pool's other threads kept awake for a submission. Between two dispatches, and
/// inside one whose parallel loop has fewer pieces than threads, a thread that finds no
/// work goes to sleep within microseconds, and the next dispatch waits for it to wake: on
/// the 2-core virtual machine of BENCHMARKS.md the second thread began a traversal's
/// second stream 10-60 us after the first (a dispatch of a 256x256 iteration takes
/// 0.5-1.3 ms). So each other thread runs [`Awake::keep`] for the submission's length,
/// taking the dispatches' work as it comes (and giving its core to any other runnable
/// thread while there is none).
#[derive(Default)]
struct Awake(AtomicBool);

/// A thread in [`Awake::keep`] that has found no work for this long goes back to the
/// pool. A submission's dispatches follow each other within microseconds, so this ends
/// only waits that were not worth keeping: and it ends any wait that blocks others (a
/// thread can pick up a `keep` while it waits inside a job of another submission, which
/// could then wait on this one).
const AWAKE_IDLE: Duration = Duration::from_millis(1);

/// Ends the submission's [`Awake::keep`] loops when dropped, on return or unwind.
struct AwakeUntil<'a>(&'a Awake);

impl Drop for AwakeUntil<'_> {
    fn drop(&mut self) {
        self.0 .0.store(true, Ordering::Release);
    }
}

impl Awake {
    fn until_dropped(&self) -> AwakeUntil<'_> {
        AwakeUntil(self)
    }

    /// Runs the pool's work until the submission ends or none comes for [`AWAKE_IDLE`].
    /// Not on the submitting thread (`submitter`), which can pick this job up while it
    /// waits inside a dispatch.
    fn keep(&self, submitter: Option<usize>) {
        if rayon::current_thread_index() == submitter {
            return;
        }
        let mut worked = Instant::now();
        while !self.0.load(Ordering::Acquire) {
            if rayon::yield_now() == Some(rayon::Yield::Executed) {
                worked = Instant::now();
            } else if worked.elapsed() > AWAKE_IDLE {
                return;
            } else {
                std::thread::yield_now();
            }
        }
    }
}

/// The compiled kernel behind an artifact (none for shaders written by hand).
fn compiled_code(kernel: &KernelArtifact) -> Option<Arc<cohort_compiler::CompiledKernel>> {
    match &kernel.code {
        KernelCode::Compiled(k) => Some(Arc::clone(k)),
        KernelCode::Shaders { .. } => None,
    }
}

/// Copies the first `dst.len()` bytes of `b`.
fn read_prefix(b: &CpuBuffer, dst: &mut [u8]) {
    assert!(dst.len() <= b.bytes());
    // SAFETY: in range; no dispatch is running (submissions complete before they return).
    unsafe { std::ptr::copy_nonoverlapping(b.ptr(), dst.as_mut_ptr(), dst.len()) };
}

fn cpu_name() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    format!("CPU: {model}")
}

impl CpuDevice {
    /// Runs one dispatch in the kernel's vector form or its host form (`choice`).
    fn run(&self, cmd: &Cmd) -> Result<()> {
        let groups = match &cmd.groups {
            Groups::Direct(g) => *g,
            Groups::Indirect(b, at) => {
                let mut words = [0u8; 12];
                let start = *at as usize;
                // SAFETY: `check_call` checked that three words follow `at`.
                unsafe {
                    std::ptr::copy_nonoverlapping(b.ptr().add(start), words.as_mut_ptr(), 12)
                };
                let w = |i: usize| u32::from_le_bytes(words[i * 4..i * 4 + 4].try_into().unwrap());
                [w(0), w(1), w(2)]
            }
        };
        let total = groups.iter().map(|&g| g as u64).product::<u64>();
        if total == 0 {
            return Ok(());
        }
        let invocations = total * u64::from(cmd.workgroup_size);
        if let Some((whole, host)) = cmd.host.and_then(|h| Some((h.dispatch?, h))) {
            if self.forms == cpu::simd::Forms::Measured
                && run_whole(cmd, whole, &host, invocations)?
            {
                self.ran.add(&cmd.name, cpu::simd::Ran::Whole);
                return Ok(());
            }
        }
        let ready = self.simd_form(&cmd.code, cmd.host.is_some());
        let simd = match ready {
            cpu::simd::Ready::Vector(k) => Some(k),
            _ => None,
        };
        let vector = match (simd, cmd.host) {
            (Some(_), None) => true,
            (Some(_), Some(_)) => {
                self.forms == cpu::simd::Forms::Vector
                    || self.chooser.vector_next(&cmd.name, simd.map(|k| k.key))
            }
            _ => false,
        };
        let start = Instant::now();
        let ran = match (vector, simd, cmd.host) {
            (true, Some(k), _) => run_simd(cmd, k, groups, total as u32),
            (_, _, Some(h)) => run_host(cmd, h, groups, total),
            _ => unreachable!("record_cmd keeps a command only with a form to run"),
        };
        if ran.is_ok() {
            self.ran.add(
                &cmd.name,
                match (vector, ready) {
                    (true, _) => cpu::simd::Ran::Vector,
                    (false, cpu::simd::Ready::Vector(_)) => cpu::simd::Ran::Host,
                    (false, cpu::simd::Ready::NotYet) => cpu::simd::Ran::Pending,
                    (false, cpu::simd::Ready::Never) if self.forms == cpu::simd::Forms::Host => {
                        cpu::simd::Ran::Host
                    }
                    (false, cpu::simd::Ready::Never) => cpu::simd::Ran::HostOnly,
                },
            );
            let ns = start.elapsed().as_nanos() as u64;
            match (ready, &cmd.code) {
                (cpu::simd::Ready::Vector(k), _) if cmd.host.is_some() => {
                    self.chooser
                        .record(&cmd.name, Some(k.key), vector, ns, invocations)
                }
                (cpu::simd::Ready::NotYet, Some(k)) => cpu::simd::ran_host(k, self.lanes, ns),
                _ => {}
            }
        }
        ran
    }
}

/// The dispatch's buffers as the host forms see them.
fn host_bufs(cmd: &Cmd) -> Vec<HostBuf> {
    cmd.args
        .iter()
        .map(|arg| HostBuf {
            ptr: arg.buffer.ptr(),
            bytes: arg.size_bytes as usize,
        })
        .collect()
}

/// The error of a dispatch whose code panicked.
fn panicked(cmd: &Cmd, payload: Box<dyn std::any::Any + Send>) -> RuntimeError {
    let message = payload
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "a panic without a message".into());
    RuntimeError::Dispatch {
        kernel: cmd.name.clone(),
        backend: BackendKind::Cpu,
        detail: format!("an invocation panicked: {message}"),
    }
}

/// A dispatch of a kernel's host form.
fn run_host(cmd: &Cmd, host: HostKernel, groups: [u32; 3], total: u64) -> Result<()> {
    let bufs = host_bufs(cmd);
    let launch = cpu::Launch::new(&host, &bufs, cmd.workgroup_size, groups);
    std::panic::catch_unwind(AssertUnwindSafe(|| {
        (0..total as u32)
            .into_par_iter()
            .for_each(|wg| SCRATCH.with(|s| cpu::run_workgroup(&launch, wg, &mut s.borrow_mut())))
    }))
    .map_err(|payload| panicked(cmd, payload))
}

/// A dispatch of a kernel's whole-dispatch form: whether it ran (`cpu::DispatchForm`).
fn run_whole(
    cmd: &Cmd,
    whole: cpu::DispatchForm,
    host: &HostKernel,
    invocations: u64,
) -> Result<bool> {
    let bufs = host_bufs(cmd);
    let args = cpu::LaneArgs {
        bufs: &bufs,
        workgroup: &[],
        constants: &host.constants,
    };
    std::panic::catch_unwind(AssertUnwindSafe(|| whole(&args, invocations)))
        .map_err(|payload| panicked(cmd, payload))
}

/// A dispatch of a kernel's vector form: workgroups spread over the cores as for host
/// forms, each run as blocks of as many invocations as its lowering chose.
fn run_simd(cmd: &Cmd, k: cpu::simd::SimdKernel, groups: [u32; 3], total: u32) -> Result<()> {
    let env: Vec<cpu::simd::EnvEntry> = cmd
        .args
        .iter()
        .map(|arg| cpu::simd::EnvEntry {
            ptr: arg.buffer.ptr(),
            bytes: arg.size_bytes,
        })
        .collect();
    struct Env(Vec<cpu::simd::EnvEntry>);
    // The entries point at buffers the dispatch's invocations share, as on a GPU.
    unsafe impl Sync for Env {}
    let env = Env(env);
    let env = &env;
    let ok = (0..total).into_par_iter().all(|wg| {
        // SAFETY: the entries are the dispatch's bindings in binding order, at their sizes.
        unsafe { k.run(&env.0, wg, wg + 1, groups) }
    });
    if ok {
        Ok(())
    } else {
        Err(RuntimeError::Dispatch {
            kernel: cmd.name.clone(),
            backend: BackendKind::Cpu,
            detail: "index out of bounds: an invocation read or wrote past the end of a buffer or local array".into(),
        })
    }
}

impl Backend for CpuDevice {
    fn info(&self) -> &DeviceInfo {
        &self.info
    }

    fn limits(&self) -> &Limits {
        &self.limits
    }

    fn create_buffer(&self, bytes: u64, init: &[u8]) -> Result<RawBuffer> {
        Ok(RawBuffer::new(CpuBuffer::new(bytes, init)?))
    }

    fn write(&self, raw: &RawBuffer, offset: u64, bytes: &[u8]) -> Result<()> {
        let b = self.own(raw, "write")?;
        assert!(offset as usize + bytes.len() <= b.bytes());
        // SAFETY: in range (checked by the caller against the logical length); no dispatch
        // runs while the host writes (submissions complete before they return).
        unsafe {
            std::ptr::copy_nonoverlapping(bytes.as_ptr(), b.ptr().add(offset as usize), bytes.len())
        };
        Ok(())
    }

    fn read(&self, raw: &RawBuffer, dst: &mut [u8]) -> Result<()> {
        read_prefix(&*self.own(raw, "read")?, dst);
        Ok(())
    }

    /// Starts compiling the kernel's vector form (the host form is part of the program).
    fn prepare(&self, kernel: &KernelArtifact) -> Result<()> {
        self.simd_form(&compiled_code(kernel), kernel.host.is_some());
        Ok(())
    }

    fn form_counts(&self) -> Vec<cpu::simd::FormCount> {
        self.ran.get()
    }

    /// The lanes' `println!` prints directly, so the print buffer stays empty.
    fn print_buffer_words(&self) -> usize {
        crate::print::HEADER_WORDS + 1
    }

    fn begin(&self) -> Box<dyn Recording<'_> + '_> {
        Recorded::start(self)
    }
}

impl Records for CpuDevice {
    type Cmd = Cmd;
    type ReadBuffer = Arc<CpuBuffer>;

    fn record_cmd(
        &self,
        kernel: &KernelArtifact,
        args: &[BufferArg<'_>],
        dispatch: &Dispatch<'_>,
    ) -> Result<Cmd> {
        let code = compiled_code(kernel);
        if kernel.host.is_none()
            && !matches!(self.simd_form(&code, false), cpu::simd::Ready::Vector(_))
        {
            return Err(RuntimeError::MissingFeature {
                kernel: kernel.name.clone(),
                backend: BackendKind::Cpu,
                feature:
                    "a host form (kernels built from WGSL or SPIR-V alone cannot run on the CPU)",
            });
        }
        // Host memory is one: a buffer of any CPU device binds on every CPU device.
        let (args, groups) = resolve(kernel, args, dispatch, |raw| raw.get::<CpuBuffer>())?;
        Ok(Cmd {
            name: kernel.name.clone(),
            code,
            host: kernel.host,
            workgroup_size: kernel.workgroup_size[0],
            args,
            groups,
        })
    }

    fn read_buffer(&self, raw: &RawBuffer) -> Result<Arc<CpuBuffer>> {
        self.own(raw, "read_back")
    }

    /// Runs the batch at once: a CPU has nothing to overlap it with.
    fn submit_cmds<'d>(
        &'d self,
        cmds: Vec<Cmd>,
        reads: Vec<(Arc<CpuBuffer>, u64)>,
    ) -> Result<Box<dyn InFlight + 'd>> {
        let (stats, reads) = self.submit(cmds, reads)?;
        Ok(Box::new(Finished(stats, reads)))
    }
}
