//! The one trait every backend implements. A [`Device`](crate::Device) holds its backend
//! as an `Arc<dyn Backend>` and does everything backend-independent itself (argument and
//! limit checks, print buffers, typed buffers); a backend owns its buffers, lowers and
//! caches its pipelines, records dispatches and submits them. Adding a backend is one file
//! with an impl of [`Backend`] and of [`Records`] (how it records and submits a batch),
//! plus its arm in `Device::open`.

use std::any::Any;
use std::sync::Arc;

use crate::buffer::{storage_binding_size, uniform_binding_size};
use crate::device::Limits;
use crate::{
    BindingKind, BufferArg, DeviceInfo, Dispatch, DispatchStats, KernelArtifact, Result,
    RuntimeError,
};

/// One backend's device.
pub(crate) trait Backend: Send + Sync {
    fn info(&self) -> &DeviceInfo;

    fn limits(&self) -> &Limits;

    /// A buffer of `bytes` (already rounded to the allocation granule), holding `init`
    /// followed by zeros.
    fn create_buffer(&self, bytes: u64, init: &[u8]) -> Result<RawBuffer>;

    /// A small buffer the host writes once per launch (a uniform argument): where it
    /// matters, in host-visible memory, so that creating it never waits for the queue.
    fn create_uniform_buffer(&self, bytes: u64, init: &[u8]) -> Result<RawBuffer> {
        self.create_buffer(bytes, init)
    }

    /// Overwrites `bytes.len()` bytes at `offset`, ordered before later dispatches and reads.
    fn write(&self, raw: &RawBuffer, offset: u64, bytes: &[u8]) -> Result<()>;

    /// Copies the start of the buffer into `dst`, after all submitted work.
    fn read(&self, raw: &RawBuffer, dst: &mut [u8]) -> Result<()>;

    /// Builds (or finds cached) what dispatching `kernel` needs, without dispatching it.
    fn prepare(&self, kernel: &KernelArtifact) -> Result<()>;

    /// Diagnostics the driver or API reported outside any operation (validation layers).
    fn take_messages(&self) -> Vec<String> {
        Vec::new()
    }

    /// How many pipelines the backend has built and cached.
    fn cached_pipeline_count(&self) -> usize {
        0
    }

    /// How many dispatches of each kernel ran in each form: the CPU backend's; no other
    /// backend has forms.
    fn form_counts(&self) -> Vec<crate::cpu::simd::FormCount> {
        Vec::new()
    }

    /// Words of the print buffer a printing dispatch gets.
    fn print_buffer_words(&self) -> usize {
        crate::print::buffer_words()
    }

    /// Starts recording a batch of dispatches (backends return `Recorded::start(self)`).
    fn begin(&self) -> Box<dyn Recording<'_> + '_>;
}

/// Dispatches and read-backs recorded for one submission of a backend. `Device` has
/// checked each call against the kernel's bindings and the device's limits first.
pub(crate) trait Recording<'d> {
    fn record(
        &mut self,
        kernel: &KernelArtifact,
        args: &[BufferArg<'_>],
        dispatch: &Dispatch<'_>,
    ) -> Result<()>;

    /// Copies `bytes` of `raw` back after the batch's dispatches; read-backs come back in
    /// the order they were asked for.
    fn read_back(&mut self, raw: &RawBuffer, bytes: u64) -> Result<()>;

    /// Dispatches recorded so far.
    fn len(&self) -> usize;

    /// Hands the batch to the device; the host goes on until it waits.
    fn submit(self: Box<Self>) -> Result<Box<dyn InFlight + 'd>>;
}

/// How a backend records one dispatch, holds on to a buffer to read back, and submits.
pub(crate) trait Records: Sync {
    /// One recorded dispatch: its pipeline, bound buffers and workgroup counts.
    type Cmd;
    /// A buffer to copy back after the dispatches, kept alive until then.
    type ReadBuffer;

    fn record_cmd(
        &self,
        kernel: &KernelArtifact,
        args: &[BufferArg<'_>],
        dispatch: &Dispatch<'_>,
    ) -> Result<Self::Cmd>;

    fn read_buffer(&self, raw: &RawBuffer) -> Result<Self::ReadBuffer>;

    fn submit_cmds<'d>(
        &'d self,
        cmds: Vec<Self::Cmd>,
        reads: Vec<(Self::ReadBuffer, u64)>,
    ) -> Result<Box<dyn InFlight + 'd>>;
}

/// A batch being recorded on backend `D`.
pub(crate) struct Recorded<'d, D: Records> {
    device: &'d D,
    cmds: Vec<D::Cmd>,
    reads: Vec<(D::ReadBuffer, u64)>,
}

impl<'d, D: Records> Recorded<'d, D> {
    pub(crate) fn start(device: &'d D) -> Box<Self> {
        Box::new(Recorded {
            device,
            cmds: Vec::new(),
            reads: Vec::new(),
        })
    }
}

impl<'d, D: Records> Recording<'d> for Recorded<'d, D> {
    fn record(
        &mut self,
        kernel: &KernelArtifact,
        args: &[BufferArg<'_>],
        dispatch: &Dispatch<'_>,
    ) -> Result<()> {
        self.cmds
            .push(self.device.record_cmd(kernel, args, dispatch)?);
        Ok(())
    }

    fn read_back(&mut self, raw: &RawBuffer, bytes: u64) -> Result<()> {
        self.reads.push((self.device.read_buffer(raw)?, bytes));
        Ok(())
    }

    fn len(&self) -> usize {
        self.cmds.len()
    }

    fn submit(self: Box<Self>) -> Result<Box<dyn InFlight + 'd>> {
        let Recorded {
            device,
            cmds,
            reads,
        } = *self;
        device.submit_cmds(cmds, reads)
    }
}

/// A submitted batch.
pub(crate) trait InFlight {
    /// Waits for it: one `DispatchStats` per dispatch, and the read-backs' bytes.
    fn wait(self: Box<Self>) -> Result<(Vec<DispatchStats>, Vec<Vec<u8>>)>;
}

/// A batch that has already run (backends that execute at submission).
pub(crate) struct Finished(pub Vec<DispatchStats>, pub Vec<Vec<u8>>);

impl InFlight for Finished {
    fn wait(self: Box<Self>) -> Result<(Vec<DispatchStats>, Vec<Vec<u8>>)> {
        Ok((self.0, self.1))
    }
}

/// A backend's handle of one allocation, type-erased: each backend puts its own buffer
/// type in and takes it out again with [`RawBuffer::get`]. Cloning shares the allocation:
/// a recorded batch holds clones so a buffer dropped before `Batch::submit` stays alive
/// until the device is done with it.
#[derive(Clone)]
pub(crate) struct RawBuffer(Arc<dyn Any + Send + Sync>);

impl RawBuffer {
    pub(crate) fn new<B: Any + Send + Sync>(buffer: B) -> Self {
        RawBuffer(Arc::new(buffer))
    }

    /// A handle to a buffer the backend also holds elsewhere.
    pub(crate) fn from_arc<B: Any + Send + Sync>(buffer: Arc<B>) -> Self {
        RawBuffer(buffer)
    }

    /// The backend's buffer, if this handle holds one of type `B`.
    pub(crate) fn get<B: Any + Send + Sync>(&self) -> Option<Arc<B>> {
        self.0.clone().downcast::<B>().ok()
    }

    /// The backend's buffer, borrowed, if this handle holds one of type `B`.
    pub(crate) fn get_ref<B: Any + Send + Sync>(&self) -> Option<&B> {
        self.0.downcast_ref::<B>()
    }

    /// Whether both handles name the same allocation.
    pub(crate) fn same(&self, other: &RawBuffer) -> bool {
        std::ptr::addr_eq(Arc::as_ptr(&self.0), Arc::as_ptr(&other.0))
    }
}

/// A kernel argument as a backend binds it.
pub(crate) struct Arg<B> {
    pub binding: u32,
    pub kind: BindingKind,
    /// The backend's buffer.
    pub buffer: B,
    /// The argument's logical size (what `len()` in the kernel counts).
    pub size_bytes: u64,
}

impl<B> Arg<B> {
    /// Bytes a GPU API's binding covers (`buffer.rs` says why they differ).
    pub(crate) fn binding_size(&self) -> u64 {
        match self.kind {
            BindingKind::Uniform => uniform_binding_size(self.size_bytes),
            BindingKind::StorageRead | BindingKind::StorageReadWrite => {
                storage_binding_size(self.size_bytes)
            }
        }
    }
}

/// How many workgroups a recorded dispatch runs: given, or read by the device from three
/// `u32` in a buffer at a byte offset.
pub(crate) enum Groups<B> {
    Direct([u32; 3]),
    Indirect(B, u64),
}

/// A dispatch's arguments and workgroup counts in backend buffers, which `own` finds in a
/// handle (`None`: the buffer belongs to another device or backend, an error naming the
/// parameter).
pub(crate) fn resolve<B>(
    kernel: &KernelArtifact,
    args: &[BufferArg<'_>],
    dispatch: &Dispatch<'_>,
    own: impl Fn(&RawBuffer) -> Option<B>,
) -> Result<(Vec<Arg<B>>, Groups<B>)> {
    let foreign = |param: &str| RuntimeError::ForeignBuffer {
        kernel: kernel.name.clone(),
        param: param.to_string(),
    };
    let bound = kernel
        .bindings
        .iter()
        .zip(args)
        .map(|(b, arg)| {
            Ok(Arg {
                binding: b.binding,
                kind: b.kind,
                buffer: own(arg.raw).ok_or_else(|| foreign(&b.name))?,
                size_bytes: arg.size_bytes,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let groups = match dispatch {
        Dispatch::Groups(g) => Groups::Direct(*g),
        Dispatch::Indirect { args, offset_elems } => Groups::Indirect(
            own(&args.raw).ok_or_else(|| foreign("indirect arguments"))?,
            (*offset_elems as u64) * 4,
        ),
    };
    Ok((bound, groups))
}
