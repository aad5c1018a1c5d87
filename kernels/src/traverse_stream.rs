//! The CPU backend's whole-dispatch form of the 8-wide traversals ([`traverse8`] and
//! [`trace_shadow8`], `cohort::runtime::cpu::DispatchForm`): a dispatch's rays traced as
//! one stream instead of one ray per invocation.
//!
//! Why: a CPU traces an incoherent ray one node at a time, and each step waits on branches
//! that differ from ray to ray; the 8-wide traversal took about twice Embree's time per
//! ray (BENCHMARKS.md). A stream turns the work around: at each node, all the rays that
//! entered it are tested against its eight boxes sixteen at a time (one AVX-512 register
//! of rays against one broadcast box, no branch per ray), and the indices of the rays that
//! enter each child are packed into that child's list. A leaf child's triangles are tested
//! against its list the same way, one broadcast triangle against sixteen rays. Inner
//! children are visited depth first with their lists, nearest first in the octant order of
//! the stream's majority direction; a ray's closest hit so far culls it from the boxes
//! behind it, as in `trace8`.
//!
//! The arithmetic is `trace8`'s, operation for operation: the same slab test (`hit4`) and
//! the same watertight triangle test (`traverse::intersect`), so each ray finds the same
//! closest t, and the same triangle except at exact ties in t between two triangles (where
//! the two orders may find a different one first). Any-hit (shadow) results are the same.
//!
//! It needs AVX-512 F; elsewhere the forms decline and the backend runs the kernels'
//! other forms.
//!
//! [`traverse8`]: crate::traverse_wide::traverse8
//! [`trace_shadow8`]: crate::traverse_wide::trace_shadow8

use crate::layout::{Frame, Triangle, DONE, MISS, SLOT_IDLE};
use crate::traverse_wide::WideNode;
use cohort::runtime::cpu::LaneArgs;
use glam::{UVec4, Vec4};
use std::sync::atomic::{AtomicUsize, Ordering};

mod balance;

/// Rays per stream at the least when a dispatch is split over the cores. Shorter streams
/// leave more of a step's sixteen lanes empty deep in the tree (0.51x of `trace8`'s time
/// per ray with 4096 rays, 0.27x with 65536), but a core left idle costs more: with 8192
/// here, the last hundred iterations of a 256x256 render (fewer than 8192 live paths)
/// traced on one core, and 1024 took 0.94-0.98x of the traversals' time.
const MIN_STREAM: usize = 1024;

/// Rays per stream at the most: a stream's lists take up to eight times its length per
/// level of the tree, so a dispatch of a large image's slots is traced as several
/// streams (65536 rays took 0.35x of `trace8`'s time per ray, as fast as any longer one
/// would need to be worth the memory).
const MAX_STREAM: usize = 65536;

/// `traverse8`'s whole-dispatch form: the closest hit of every live ray.
/// Buffers in parameter order: f, count, idrays, state, ray_o, ray_d, nodes, tris, hits.
#[doc(hidden)]
pub fn traverse8_whole(a: &LaneArgs<'_>, invocations: u64) -> bool {
    if !supported() {
        return false;
    }
    // SAFETY: the backend binds traverse8's buffers in parameter order, with their types.
    let (f, count, idrays, state, ray_o, ray_d, nodes, tris, hits) = unsafe {
        (
            a.uniform::<Frame>(0),
            a.storage::<u32>(1),
            a.storage::<u32>(2),
            a.storage::<UVec4>(3),
            a.storage::<Vec4>(4),
            a.storage::<Vec4>(5),
            a.storage::<WideNode>(6),
            a.storage::<Triangle>(7),
            a.storage_mut::<Vec4>(8),
        )
    };
    let n = (count[0] as u64).min(invocations) as usize;
    let hits = Out(hits as *mut Vec4);
    let rays = RaySource {
        org: ray_o,
        dir: ray_d,
        tmin_in_w: true,
        live: f.has_geometry != 0,
        skip: Skip::Done(state),
    };
    trace_slots(&idrays[..n], false, &rays, nodes, tris, |r, part| {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `supported()` checked AVX-512 F; the slots index the buffers, and each
        // slot appears once in the list, so each write is its own.
        unsafe {
            avx512::write_hits(r, part, hits.at(0))
        };
    });
    true
}

/// `trace_shadow8`'s whole-dispatch form: every live slot's shadow ray (any hit), each slot
/// finished (`finish_slot`) by the thread that traced it.
/// Buffers: f, count, idrays, shadow_o, shadow_d, nee, nodes, tris, radiance, accum.
#[doc(hidden)]
pub fn trace_shadow8_whole(a: &LaneArgs<'_>, invocations: u64) -> bool {
    if !supported() {
        return false;
    }
    // SAFETY: the backend binds trace_shadow8's buffers in parameter order, with their
    // types.
    let (f, count, idrays, shadow_o, shadow_d, nee, nodes, tris, radiance, accum) = unsafe {
        (
            a.uniform::<Frame>(0),
            a.storage::<u32>(1),
            a.storage::<u32>(2),
            a.storage::<Vec4>(3),
            a.storage::<Vec4>(4),
            a.storage::<Vec4>(5),
            a.storage::<WideNode>(6),
            a.storage::<Triangle>(7),
            Out(a.storage_mut::<Vec4>(8) as *mut Vec4),
            Out(a.storage_mut::<Vec4>(9) as *mut Vec4),
        )
    };
    let n = (count[0] as u64).min(invocations) as usize;
    let rays = RaySource {
        org: shadow_o,
        dir: shadow_d,
        tmin_in_w: false,
        live: f.has_geometry != 0,
        skip: Skip::Unlit(nee),
    };
    let out = (radiance, accum);
    trace_slots(&idrays[..n], true, &rays, nodes, tris, |r, part| {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `supported()` checked AVX-512 F; the slots index the buffers, and each
        // slot appears once in the list, so each slot's elements are written by one thread.
        unsafe {
            avx512::finish_shadows(r, part, shadow_d, nee, out.0.at(0), out.1.at(0))
        };
    });
    true
}

/// Traces `org`/`dir` (by index; the origin's w as in [`RaySource`]) as one stream on this
/// thread: `trace8`'s result per ray, or `None` where the CPU lacks AVX-512. For tests
/// and the `stream_traversal` example, which compare it with `trace8` ray by ray.
#[doc(hidden)]
pub fn trace_stream(
    org: &[Vec4],
    dir: &[Vec4],
    tmin_in_w: bool,
    any: bool,
    nodes: &[WideNode],
    tris: &[Triangle],
) -> Option<Vec<Vec4>> {
    if !supported() {
        return None;
    }
    let ids: Vec<u32> = (0..org.len() as u32).collect();
    let src = RaySource {
        org,
        dir,
        tmin_in_w,
        live: true,
        skip: Skip::None,
    };
    let mut st = Stream::default();
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `supported()` checked AVX-512 F; the ids index the rays.
    unsafe {
        avx512::setup(&mut st.rays, &src, &ids);
        avx512::trace(&mut st.rays, nodes, tris, any, &mut st.arena, ids.len());
    }
    Some((0..ids.len()).map(|i| st.rays.hit(i)).collect())
}

/// A pointer the tracing threads write through, each at its own indices.
#[derive(Clone, Copy)]
struct Out<T>(*mut T);
unsafe impl<T> Send for Out<T> {}
unsafe impl<T> Sync for Out<T> {}

impl<T> Out<T> {
    /// Element `i` (a method, so that closures capture the whole `Out`, not its pointer).
    fn at(self, i: usize) -> *mut T {
        self.0.wrapping_add(i)
    }
}

fn supported() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        // (Every CPU with AVX-512 has `popcnt`, which counts a step's entering lanes.)
        std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("popcnt")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Where a dispatch's rays are: origins and directions by slot; the origin's w is the ray's
/// tmin (path rays, whose tmax is unbounded) or its tmax (shadow rays, from tmin 0).
struct RaySource<'a> {
    org: &'a [Vec4],
    dir: &'a [Vec4],
    tmin_in_w: bool,
    /// The frame has geometry (`Frame::has_geometry`); else every ray misses.
    live: bool,
    skip: Skip<'a>,
}

/// Which listed slots have no ray to trace: their lanes start done, so that the list
/// need not be filtered first (one pass over it less, on one thread).
enum Skip<'a> {
    /// Path rays whose path is done (`state[s].w & DONE`), which `live_slot` skips.
    Done(&'a [UVec4]),
    /// Shadow rays of idle slots (direction w = `SLOT_IDLE`) or without a light sample
    /// (`nee[s]`'s xyz zero), which `trace_shadow8` does not trace.
    Unlit(&'a [Vec4]),
    /// Every ray is traced.
    None,
}

/// Traces the rays of `slots` in streams spread over the cores and hands each stream's
/// rays, with its slots (ray `i` is slot `part[i]`'s), to `done`. The streams' cuts of
/// the list move with the time their rays took in the last dispatch ([`balance`]).
fn trace_slots(
    slots: &[u32],
    any: bool,
    src: &RaySource<'_>,
    nodes: &[WideNode],
    tris: &[Triangle],
    done: impl Fn(&Rays, &[u32]) + Sync,
) {
    use rayon::prelude::*;
    use std::sync::atomic::AtomicU64;
    if slots.is_empty() {
        return;
    }
    let threads = rayon::current_num_threads().max(1);
    let chunk = slots.len().div_ceil(threads).clamp(MIN_STREAM, MAX_STREAM);
    let streams = slots.len().div_ceil(chunk);
    // Cut at whole steps, so that a list in slot order keeps its steps of consecutive slots.
    let cuts = balance::cuts(any, slots.len(), streams, 16);
    let nanos: Vec<AtomicU64> = (0..streams).map(|_| AtomicU64::new(0)).collect();
    let (started, finished) = (AtomicUsize::new(0), AtomicUsize::new(0));
    (0..streams).into_par_iter().for_each(|k| {
        started.fetch_add(1, Ordering::Relaxed);
        let part = &slots[cuts[k]..cuts[k + 1]];
        if part.is_empty() {
            finished.fetch_add(1, Ordering::Release);
            return;
        }
        let start = std::time::Instant::now();
        STREAM.with(|cell| {
            let st = &mut *cell.borrow_mut();
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `supported()` checked AVX-512 F before any stream was traced.
            unsafe {
                avx512::setup(&mut st.rays, src, part);
                avx512::trace(&mut st.rays, nodes, tris, any, &mut st.arena, part.len())
            };
            done(&st.rays, part);
        });
        nanos[k].store(start.elapsed().as_nanos() as u64, Ordering::Relaxed);
        finished.fetch_add(1, Ordering::Release);
        wait_for_streams(&started, &finished, streams);
    });
    if streams > 1 {
        let seconds: Vec<f64> = nanos
            .iter()
            .map(|n| n.load(Ordering::Relaxed) as f64 * 1e-9)
            .collect();
        balance::record(any, &cuts, slots.len(), &seconds);
    }
}

/// The longest a thread that has finished its stream waits, awake, for the others.
const WAIT_AWAKE: std::time::Duration = std::time::Duration::from_millis(2);

/// Once every stream has started, a thread that finished its own stays awake until the
/// others finish (yielding its core to any other runnable thread), up to [`WAIT_AWAKE`].
/// Returned to the pool, it would fall asleep within microseconds while the dispatch waits
/// on the last stream, and the end of the dispatch would then wait for it to wake: in
/// alternated 256x256 renders on the 2-core virtual machine of BENCHMARKS.md, kernel time
/// without this wait was 1.058x (cornell-box) and 1.015x (stanford-like) of that with it.
fn wait_for_streams(started: &AtomicUsize, finished: &AtomicUsize, streams: usize) {
    let since = std::time::Instant::now();
    while started.load(Ordering::Relaxed) == streams
        && finished.load(Ordering::Acquire) < streams
        && since.elapsed() < WAIT_AWAKE
    {
        std::thread::yield_now();
    }
}

/// One thread's stream: its rays and the index lists of the children being visited.
#[derive(Default)]
struct Stream {
    rays: Rays,
    arena: Arena,
}

/// The index lists of a stream's nodes: regions that compress stores fill from their
/// start. Grown without a zero fill, so that the pages of a region no list reaches are
/// never touched (a fill wrote each level's eight regions of the parent's length whole:
/// a fifth of a render's page faults, in its first dispatches).
#[derive(Default)]
struct Arena(Vec<std::mem::MaybeUninit<u32>>);

impl Arena {
    /// Room for at least `len` entries.
    fn reserve(&mut self, len: usize) {
        if self.0.len() < len {
            self.0.reserve(len - self.0.len());
            // SAFETY: within the capacity just reserved; the elements are `MaybeUninit`.
            unsafe { self.0.set_len(len) };
        }
    }

    fn as_mut_ptr(&mut self) -> *mut u32 {
        self.0.as_mut_ptr() as *mut u32
    }

    /// Entries `from..to`.
    ///
    /// # Safety
    /// Each entry of the range was written.
    unsafe fn list(&self, from: usize, to: usize) -> &[u32] {
        &*(&self.0[from..to] as *const [std::mem::MaybeUninit<u32>] as *const [u32])
    }
}

thread_local! {
    static STREAM: std::cell::RefCell<Stream> = std::cell::RefCell::new(Stream::default());
}

/// A stream's rays: for each of the two tests a record of eight floats (32 bytes) per
/// ray, which a step reads as sixteen 32-byte loads and an 8x16 transpose (a gather
/// fetches one element at a time, and sixteen of them per field took about half of a
/// step's time), and the closest hit so far: t (in the box record, where the box test
/// reads it as its tmax), u, v and the triangle.
#[derive(Default)]
struct Rays {
    /// Both records of each ray, in one cache line.
    recs: Vec<RayRecords>,
    u: Vec<f32>,
    v: Vec<f32>,
    tri: Vec<u32>,
    /// Per step of sixteen rays, the lanes the set-up found with no ray to trace
    /// ([`Skip`]), so that a path ray's slot state is read once per dispatch.
    skipped: Vec<u16>,
    /// Per step of sixteen rays, the lanes whose ray is traced: the root's list holds
    /// only these (the others keep the miss the set-up gave them).
    traced: Vec<u16>,
}

/// A ray's two records side by side in one 64-byte line: a leaf reads the triangle
/// record of rays whose box records its parent node has just read, and the two in one
/// line make that one miss instead of two (the leaves' record loads were a fifth of the
/// traversal's time with the records in two arrays).
#[derive(Clone, Copy, Default)]
#[repr(C, align(64))]
struct RayRecords {
    /// The box test's record: origin, inverse direction, the closest t so far and tmax
    /// (the indices of [`field`]).
    boxr: [f32; 8],
    /// The triangle test's record, as `traverse::intersect` sets a ray up: the rotated
    /// origin, the shear, tmin, and the dominant axis (an i32's bits).
    trir: [f32; 8],
}

/// Records (eight floats each) from one ray's box record to the next ray's: a stride in
/// [`RayRecords`]' layout.
const RECORD_STRIDE: usize = 2;

/// A box-test record's fields, by index: origin, inverse direction, the closest t so far,
/// and tmax (a miss's result).
mod field {
    pub const T: usize = 6;
    pub const TMAX: usize = 7;
}

impl Rays {
    /// Room for `n` rays and the lanes of a last partial step.
    fn resize(&mut self, n: usize) {
        let len = n.next_multiple_of(16);
        self.recs.resize(len, RayRecords::default());
        self.u.resize(len, 0.0);
        self.v.resize(len, 0.0);
        self.tri.resize(len, MISS);
        self.skipped.resize(len / 16, 0);
        self.traced.resize(len / 16, 0);
    }

    /// The box records, [`RECORD_STRIDE`] records apart.
    fn boxr(&mut self) -> *mut [f32; 8] {
        self.recs.as_mut_ptr() as *mut [f32; 8]
    }

    /// The triangle records, [`RECORD_STRIDE`] records apart.
    fn trir(&mut self) -> *mut [f32; 8] {
        // SAFETY: the second half of each record.
        unsafe { self.boxr().add(1) }
    }

    /// Ray `i`'s result as `trace8` returns it: (t, u, v, triangle as bits), or (tmax, 0,
    /// 0, MISS).
    fn hit(&self, i: usize) -> Vec4 {
        let b = &self.recs[i].boxr;
        if self.tri[i] == MISS {
            Vec4::new(b[field::TMAX], 0.0, 0.0, f32::from_bits(MISS))
        } else {
            Vec4::new(
                b[field::T],
                self.u[i],
                self.v[i],
                f32::from_bits(self.tri[i]),
            )
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use super::{
        field, Arena, RaySource, Rays, Skip, Triangle, WideNode, DONE, MISS, RECORD_STRIDE,
        SLOT_IDLE,
    };
    use crate::layout::SLOT_ENDED;

    /// A child slot of a node with fewer than eight children (`cohort_scenes`'
    /// `bvh::wide::EMPTY_SLOT`, whose box no ray enters).
    const EMPTY_SLOT: u32 = u32::MAX;
    use glam::Vec3;
    use std::arch::x86_64::*;

    /// `r` set up with the rays of `slots`, sixteen at a time, as `trace8` sets up one
    /// (its inverse direction, `dominant_axis`, `rotate` and shear, the same operations).
    ///
    /// # Safety
    /// Needs AVX-512 F; the slots index `src`'s arrays.
    #[target_feature(enable = "avx512f,popcnt")]
    pub(super) unsafe fn setup(r: &mut Rays, src: &RaySource<'_>, slots: &[u32]) {
        let n = slots.len();
        r.resize(n);
        let zero = _mm512_setzero_ps();
        let one = _mm512_set1_ps(1.0);
        let mut c = 0;
        while c < n {
            let lm = lanes(n - c);
            let ids = _mm512_maskz_loadu_epi32(lm, slots.as_ptr().add(c) as *const i32);
            let four = _mm512_slli_epi32::<2>(ids);
            let at = slots.as_ptr().add(c);
            let [ox, oy, oz, ow] = load_vec4s(src.org.as_ptr(), at, lm, ids);
            let [dx, dy, dz, dw] = load_vec4s(src.dir.as_ptr(), at, lm, ids);
            let (ax, ay, az) = (_mm512_abs_ps(dx), _mm512_abs_ps(dy), _mm512_abs_ps(dz));
            let k0 =
                _mm512_cmp_ps_mask::<_CMP_GE_OQ>(ax, ay) & _mm512_cmp_ps_mask::<_CMP_GE_OQ>(ax, az);
            let k1 = !k0 & _mm512_cmp_ps_mask::<_CMP_GE_OQ>(ay, az);
            let kz = _mm512_mask_mov_epi32(
                _mm512_mask_mov_epi32(_mm512_set1_epi32(2), k1, _mm512_set1_epi32(1)),
                k0,
                _mm512_setzero_si512(),
            );
            let rot = |x, y, z| {
                (
                    _mm512_mask_blend_ps(k0, _mm512_mask_blend_ps(k1, x, z), y),
                    _mm512_mask_blend_ps(k0, _mm512_mask_blend_ps(k1, y, x), z),
                    _mm512_mask_blend_ps(k0, _mm512_mask_blend_ps(k1, z, y), x),
                )
            };
            let (drx, dry, drz) = rot(dx, dy, dz);
            let (rx, ry, rz) = rot(ox, oy, oz);
            let (tmin, tmax) = if src.tmin_in_w {
                (ow, _mm512_set1_ps(3.0e38))
            } else {
                (zero, ow)
            };
            let dot = |x, y, z| {
                _mm512_add_ps(
                    _mm512_add_ps(_mm512_mul_ps(x, x), _mm512_mul_ps(y, y)),
                    _mm512_mul_ps(z, z),
                )
            };
            let skip = match src.skip {
                Skip::Done(state) => {
                    let w = _mm512_add_epi32(four, _mm512_set1_epi32(3));
                    let w = _mm512_mask_i32gather_epi32::<4>(
                        _mm512_setzero_si512(),
                        lm,
                        w,
                        state.as_ptr() as *const i32,
                    );
                    _mm512_test_epi32_mask(w, _mm512_set1_epi32(DONE as i32))
                }
                Skip::Unlit(nee) => {
                    let idle = _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(dw, _mm512_set1_ps(SLOT_IDLE));
                    let [lx, ly, lz, _] = load_vec4s(nee.as_ptr(), at, lm, ids);
                    // `ld != Vec3::ZERO`: some component unequal to zero (NaN included).
                    let lit = _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(lx, zero)
                        | _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(ly, zero)
                        | _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(lz, zero);
                    idle | !lit
                }
                Skip::None => 0,
            };
            r.skipped[c / 16] = skip;
            let go = if src.live { 0xffff } else { 0 }
                & !skip
                & _mm512_cmp_ps_mask::<_CMP_GT_OQ>(dot(dx, dy, dz), zero)
                & _mm512_cmp_ps_mask::<_CMP_LT_OQ>(dot(ox, oy, oz), _mm512_set1_ps(1.0e36));
            r.traced[c / 16] = go & lm;
            // A ray `trace8` stops before its first node gets a t no box passes.
            let t = _mm512_mask_blend_ps(go, _mm512_set1_ps(-1.0), tmax);
            let (ix, iy, iz) = (
                _mm512_div_ps(one, dx),
                _mm512_div_ps(one, dy),
                _mm512_div_ps(one, dz),
            );
            store_records(
                r.boxr().add(RECORD_STRIDE * c),
                [ox, oy, oz, ix, iy, iz, t, tmax],
            );
            store_records(
                r.trir().add(RECORD_STRIDE * c),
                [
                    rx,
                    ry,
                    rz,
                    _mm512_div_ps(drx, drz),
                    _mm512_div_ps(dry, drz),
                    _mm512_div_ps(one, drz),
                    tmin,
                    _mm512_castsi512_ps(kz),
                ],
            );
            _mm512_storeu_ps(r.u.as_mut_ptr().add(c), zero);
            _mm512_storeu_ps(r.v.as_mut_ptr().add(c), zero);
            _mm512_storeu_si512(
                r.tri.as_mut_ptr().add(c) as *mut __m512i,
                _mm512_set1_epi32(MISS as i32),
            );
            c += 16;
        }
    }

    /// The 8x8 transposes of the two halves of eight registers, each half a row of eight
    /// floats: output `j` holds column `j` of rows 0-3 of the low halves, of rows 0-3 of the
    /// high halves, of rows 4-7 of the low halves, then of rows 4-7 of the high halves (in
    /// that order, four lanes each).
    #[target_feature(enable = "avx512f,popcnt")]
    unsafe fn transpose(z: [__m512; 8]) -> [__m512; 8] {
        let t = [
            _mm512_unpacklo_ps(z[0], z[1]),
            _mm512_unpackhi_ps(z[0], z[1]),
            _mm512_unpacklo_ps(z[2], z[3]),
            _mm512_unpackhi_ps(z[2], z[3]),
            _mm512_unpacklo_ps(z[4], z[5]),
            _mm512_unpackhi_ps(z[4], z[5]),
            _mm512_unpacklo_ps(z[6], z[7]),
            _mm512_unpackhi_ps(z[6], z[7]),
        ];
        // Columns 0/4, 1/5, 2/6 and 3/7 of rows 0-3 (u[0..4]) and 4-7 (u[4..8]).
        let u = [
            _mm512_shuffle_ps::<0x44>(t[0], t[2]),
            _mm512_shuffle_ps::<0xee>(t[0], t[2]),
            _mm512_shuffle_ps::<0x44>(t[1], t[3]),
            _mm512_shuffle_ps::<0xee>(t[1], t[3]),
            _mm512_shuffle_ps::<0x44>(t[4], t[6]),
            _mm512_shuffle_ps::<0xee>(t[4], t[6]),
            _mm512_shuffle_ps::<0x44>(t[5], t[7]),
            _mm512_shuffle_ps::<0xee>(t[5], t[7]),
        ];
        [
            _mm512_shuffle_f32x4::<0x88>(u[0], u[4]),
            _mm512_shuffle_f32x4::<0x88>(u[1], u[5]),
            _mm512_shuffle_f32x4::<0x88>(u[2], u[6]),
            _mm512_shuffle_f32x4::<0x88>(u[3], u[7]),
            _mm512_shuffle_f32x4::<0xdd>(u[0], u[4]),
            _mm512_shuffle_f32x4::<0xdd>(u[1], u[5]),
            _mm512_shuffle_f32x4::<0xdd>(u[2], u[6]),
            _mm512_shuffle_f32x4::<0xdd>(u[3], u[7]),
        ]
    }

    /// The sixteen indices a step reads: `ids` where `lm` is full, else `idx`'s lanes
    /// (zero outside `lm`, so that no lane reads past the arrays) through `part`.
    #[target_feature(enable = "avx512f,popcnt")]
    unsafe fn step_ids(
        ids: *const u32,
        lm: __mmask16,
        idx: __m512i,
        part: &mut [u32; 16],
    ) -> *const u32 {
        if lm == 0xffff {
            ids
        } else {
            _mm512_storeu_si512(part.as_mut_ptr() as *mut __m512i, idx);
            part.as_ptr()
        }
    }

    /// The eight fields of the records of sixteen rays, field `k` in output `k`, ray `j`
    /// in lane `j`: the rays at `ids` (sixteen indices) where `lm` is full, else those of
    /// `idx` (zero in the lanes outside `lm`, which read ray 0's record). Ray `i`'s record
    /// is `recs[RECORD_STRIDE * i]`.
    ///
    /// # Safety
    /// Needs AVX-512 F; every index in `lm`'s lanes is a ray of `recs`, and ray 0 is.
    #[target_feature(enable = "avx512f,popcnt")]
    pub(super) unsafe fn load_records(
        recs: *const [f32; 8],
        ids: *const u32,
        lm: __mmask16,
        idx: __m512i,
    ) -> [__m512; 8] {
        let mut part = [0u32; 16];
        let ids = step_ids(ids, lm, idx, &mut part);
        // Each index read from memory: LLVM otherwise takes them out of `idx` (loaded from
        // the same list) with two extracts each, slower than a load (0.96x of the stream's
        // time in the `stream_traversal` example).
        let rec = |j: usize| {
            let id = ids.add(j).read_volatile() as usize;
            _mm256_loadu_ps(recs.add(RECORD_STRIDE * id) as *const f32)
        };
        // Rays j and j + 4 (j < 4), then j + 4 and j + 8 (4 <= j < 8), so that the
        // transpose's lanes come out in ray order.
        let pair = |lo: usize, hi: usize| {
            // (As doubles: the f32x8 forms need AVX-512 DQ.)
            _mm512_castpd_ps(_mm512_insertf64x4::<1>(
                _mm512_castps_pd(_mm512_castps256_ps512(rec(lo))),
                _mm256_castps_pd(rec(hi)),
            ))
        };
        transpose([
            pair(0, 4),
            pair(1, 5),
            pair(2, 6),
            pair(3, 7),
            pair(8, 12),
            pair(9, 13),
            pair(10, 14),
            pair(11, 15),
        ])
    }

    /// Stores field `k` of sixteen rays (ray `j` in lane `j` of `fields[k]`) as the
    /// records `out[RECORD_STRIDE * j]`.
    ///
    /// # Safety
    /// Needs AVX-512 F; `out` has sixteen rays' records.
    #[target_feature(enable = "avx512f,popcnt")]
    pub(super) unsafe fn store_records(out: *mut [f32; 8], fields: [__m512; 8]) {
        let cols = transpose(fields);
        // Column j holds fields 0-3 of rays j and j + 8, then fields 4-7 of the two.
        let order = _mm512_setr_epi32(0, 1, 2, 3, 8, 9, 10, 11, 4, 5, 6, 7, 12, 13, 14, 15);
        for (j, &col) in cols.iter().enumerate() {
            let both = _mm512_permutexvar_ps(order, col);
            _mm256_storeu_ps(
                out.add(RECORD_STRIDE * j) as *mut f32,
                _mm512_castps512_ps256(both),
            );
            _mm256_storeu_ps(
                out.add(RECORD_STRIDE * (j + 8)) as *mut f32,
                _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(both))),
            );
        }
    }

    /// The x, y, z and w of the `Vec4`s of sixteen slots, ray `j` in lane `j`: the slots
    /// at `ids` where `lm` is full, else those of `idx` (zero outside `lm`: slot 0's, which
    /// then exists). Sixteen 16-byte loads and a 4x4 transpose in each 128-bit lane, or,
    /// where the sixteen slots are consecutive (a list in slot order), four 64-byte loads;
    /// a gather per component fetches one element at a time.
    ///
    /// # Safety
    /// Needs AVX-512 F; every slot in `lm`'s lanes indexes `v`, and so does 0.
    #[target_feature(enable = "avx512f,popcnt")]
    pub(super) unsafe fn load_vec4s(
        v: *const glam::Vec4,
        ids: *const u32,
        lm: __mmask16,
        idx: __m512i,
    ) -> [__m512; 4] {
        let p = v as *const f32;
        let row = |j: u32| _mm_loadu_ps(p.add(4 * j as usize));
        let first = *ids;
        // Every lane's slot is the first's plus the lane (a list need not be sorted).
        let iota = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
        let consecutive = lm == 0xffff
            && _mm512_cmpeq_epi32_mask(
                idx,
                _mm512_add_epi32(_mm512_set1_epi32(first as i32), iota),
            ) == 0xffff;
        let z: [__m512; 4] = if consecutive {
            std::array::from_fn(|q| _mm512_loadu_ps(p.add(4 * (first as usize + 4 * q))))
        } else {
            let mut part = [0u32; 16];
            let ids = step_ids(ids, lm, idx, &mut part);
            // Register q holds slots q, q + 4, q + 8 and q + 12, so that the transpose's
            // lanes come out in slot order.
            std::array::from_fn(|q| {
                // Read from memory, as in `load_records`.
                let r = |k: usize| row(ids.add(q + 4 * k).read_volatile());
                let z = _mm512_castps128_ps512(r(0));
                let z = _mm512_insertf32x4::<1>(z, r(1));
                let z = _mm512_insertf32x4::<2>(z, r(2));
                _mm512_insertf32x4::<3>(z, r(3))
            })
        };
        let mut out = transpose4(z);
        if consecutive {
            // Consecutive rows came out with lane 4k + q holding slot 4q + k: transposed
            // back (the permutation is its own inverse).
            let order = _mm512_setr_epi32(0, 4, 8, 12, 1, 5, 9, 13, 2, 6, 10, 14, 3, 7, 11, 15);
            for o in &mut out {
                *o = _mm512_permutexvar_ps(order, *o);
            }
        }
        out
    }

    /// `traverse8`'s result of each ray of `part` (ray `i` is slot `part[i]`'s) into
    /// `hits`, as [`Rays::hit`] gives it, except where the slot's path is done (the
    /// invocation returns before writing), sixteen at a time.
    ///
    /// # Safety
    /// Needs AVX-512 F; `r` was set up from `part` with `Skip::Done`, the slots index
    /// `hits`, and no other thread writes `part`'s slots.
    #[target_feature(enable = "avx512f,popcnt")]
    pub(super) unsafe fn write_hits(r: &Rays, part: &[u32], hits: *mut glam::Vec4) {
        let zero = _mm512_setzero_ps();
        let n = part.len();
        let recs = r.recs.as_ptr() as *const f32;
        let mut c = 0;
        while c < n {
            let lm = lanes(n - c);
            let at = part.as_ptr().add(c);
            // The slots whose path is done (`Skip::Done`, as the set-up found them).
            let done = r.skipped[c / 16];
            // Rays c.. are consecutive: t and tmax sixteen floats apart.
            let rec = _mm512_slli_epi32::<4>(_mm512_add_epi32(
                _mm512_set1_epi32(c as i32),
                _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15),
            ));
            let t = _mm512_i32gather_ps::<4>(rec, recs.add(field::T));
            let tmax = _mm512_i32gather_ps::<4>(rec, recs.add(field::TMAX));
            let tri = _mm512_loadu_si512(r.tri.as_ptr().add(c) as *const __m512i);
            let miss = _mm512_cmpeq_epi32_mask(tri, _mm512_set1_epi32(MISS as i32));
            let hit = [
                _mm512_mask_blend_ps(miss, t, tmax),
                _mm512_mask_blend_ps(miss, _mm512_loadu_ps(r.u.as_ptr().add(c)), zero),
                _mm512_mask_blend_ps(miss, _mm512_loadu_ps(r.v.as_ptr().add(c)), zero),
                _mm512_castsi512_ps(tri),
            ];
            store_vec4s(hits, at, lm & !done, hit);
            c += 16;
        }
    }

    /// `trace_shadow8`'s end of each slot of `part` (ray `i` is slot `part[i]`'s), sixteen
    /// at a time: a slot whose shadow direction's w is not `SLOT_IDLE` is finished as
    /// `shadow::finish_slot` does, with the light sample visible where it is lit (`nee`'s
    /// xyz not zero) and its ray missed, the same operations on each lane. (A loop over the
    /// slots branched on three random conditions per slot: about a tenth of a cornell-box
    /// render's time.)
    ///
    /// # Safety
    /// Needs AVX-512 F; the slots index the four arrays, which hold at least one element,
    /// and no other thread writes `part`'s slots.
    #[target_feature(enable = "avx512f,popcnt")]
    pub(super) unsafe fn finish_shadows(
        r: &Rays,
        part: &[u32],
        shadow_d: &[glam::Vec4],
        nee: &[glam::Vec4],
        radiance: *mut glam::Vec4,
        accum: *mut glam::Vec4,
    ) {
        let zero = _mm512_setzero_ps();
        let n = part.len();
        let mut c = 0;
        while c < n {
            let lm = lanes(n - c);
            let at = part.as_ptr().add(c);
            let idx = _mm512_maskz_loadu_epi32(lm, at as *const i32);
            let [_, _, _, status] = load_vec4s(shadow_d.as_ptr(), at, lm, idx);
            let [lx, ly, lz, _] = load_vec4s(nee.as_ptr(), at, lm, idx);
            let [rx, ry, rz, rw] = load_vec4s(radiance, at, lm, idx);
            let miss = _mm512_cmpeq_epi32_mask(
                _mm512_loadu_si512(r.tri.as_ptr().add(c) as *const __m512i),
                _mm512_set1_epi32(MISS as i32),
            );
            let active = lm & _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(status, _mm512_set1_ps(SLOT_IDLE));
            // `ld != Vec3::ZERO`: some component unequal to zero (NaN included).
            let lit = _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(lx, zero)
                | _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(ly, zero)
                | _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(lz, zero);
            let visible = lit & miss;
            let l = [
                _mm512_mask_add_ps(rx, visible, rx, lx),
                _mm512_mask_add_ps(ry, visible, ry, ly),
                _mm512_mask_add_ps(rz, visible, rz, lz),
            ];
            let ended =
                active & _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(status, _mm512_set1_ps(SLOT_ENDED));
            let kept = active & !ended;
            if ended != 0 {
                let [ax, ay, az, aw] = load_vec4s(accum, at, lm, idx);
                store_vec4s(
                    accum,
                    at,
                    ended,
                    [
                        _mm512_add_ps(ax, l[0]),
                        _mm512_add_ps(ay, l[1]),
                        _mm512_add_ps(az, l[2]),
                        _mm512_add_ps(aw, _mm512_set1_ps(1.0)),
                    ],
                );
                store_vec4s(radiance, at, ended, [zero; 4]);
            }
            store_vec4s(radiance, at, kept, [l[0], l[1], l[2], rw]);
            c += 16;
        }
    }

    /// Stores the `Vec4` with components lane `j` of `comps` at `v[ids[j]]`, for the lanes
    /// of `mask`: the transpose of [`load_vec4s`]. Where the masked lanes' slots are
    /// consecutive (a live list before retirements, in slot order), as four masked 64-byte
    /// stores; otherwise one 16-byte store per masked lane, the lanes taken from the mask's
    /// set bits (a test of each of the sixteen bits mispredicted on `finish_shadows`' masks
    /// of ended and continuing paths).
    ///
    /// # Safety
    /// Needs AVX-512 F; the slots of `mask`'s lanes index `v` (`ids` is read only there).
    #[target_feature(enable = "avx512f,popcnt")]
    pub(super) unsafe fn store_vec4s(
        v: *mut glam::Vec4,
        ids: *const u32,
        mask: __mmask16,
        comps: [__m512; 4],
    ) {
        if mask == 0 {
            return;
        }
        let idx = _mm512_maskz_loadu_epi32(mask, ids as *const i32);
        let j0 = mask.trailing_zeros();
        // The slot lane 0 would have: where lane 0 is not stored it may be none, even
        // negative (a list need not be sorted: lane 1 may hold slot 0).
        let first = i64::from(*ids.add(j0 as usize)) - i64::from(j0);
        let iota = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
        let expect = _mm512_add_epi32(_mm512_set1_epi32(first as i32), iota);
        if _mm512_mask_cmpeq_epi32_mask(mask, idx, expect) == mask {
            // Lane 4a + b to 4b + a (its own inverse), then the transpose: register q
            // holds the Vec4s of lanes 4q..4q + 4, in order.
            let order = _mm512_setr_epi32(0, 4, 8, 12, 1, 5, 9, 13, 2, 6, 10, 14, 3, 7, 11, 15);
            let rows = transpose4(comps.map(|c| _mm512_permutexvar_ps(order, c)));
            let out = v as *mut f32;
            for (q, row) in rows.iter().enumerate() {
                let lanes4 = (mask >> (4 * q)) & 0xf;
                // Each lane's bit as its Vec4's four floats.
                let floats = (0..4).fold(0u16, |m, b| m | (((lanes4 >> b) & 1) * 0xf) << (4 * b));
                if floats != 0 {
                    // Lanes outside the mask are not written, wherever they would point.
                    let at = out.wrapping_offset(4 * (first as isize + 4 * q as isize));
                    _mm512_mask_storeu_ps(at, floats, *row);
                }
            }
            return;
        }
        // Register q's 128-bit lane k is slot 4k + q's Vec4.
        let rows = transpose4(comps);
        let mut buf = [0f32; 64];
        for (q, row) in rows.iter().enumerate() {
            _mm512_storeu_ps(buf.as_mut_ptr().add(16 * q), *row);
        }
        let mut m = mask;
        while m != 0 {
            let j = m.trailing_zeros() as usize;
            m &= m - 1;
            let from = buf.as_ptr().add(16 * (j % 4) + 4 * (j / 4));
            _mm_storeu_ps(v.add(*ids.add(j) as usize) as *mut f32, _mm_loadu_ps(from));
        }
    }

    /// The 4x4 transposes of four registers' 128-bit lanes: lane k of output e holds
    /// element e of lane k of inputs 0 to 3 (its own inverse).
    #[target_feature(enable = "avx512f,popcnt")]
    unsafe fn transpose4(z: [__m512; 4]) -> [__m512; 4] {
        let t = [
            _mm512_unpacklo_ps(z[0], z[1]),
            _mm512_unpackhi_ps(z[0], z[1]),
            _mm512_unpacklo_ps(z[2], z[3]),
            _mm512_unpackhi_ps(z[2], z[3]),
        ];
        let pd = _mm512_castps_pd;
        [
            _mm512_castpd_ps(_mm512_unpacklo_pd(pd(t[0]), pd(t[2]))),
            _mm512_castpd_ps(_mm512_unpackhi_pd(pd(t[0]), pd(t[2]))),
            _mm512_castpd_ps(_mm512_unpacklo_pd(pd(t[1]), pd(t[3]))),
            _mm512_castpd_ps(_mm512_unpackhi_pd(pd(t[1]), pd(t[3]))),
        ]
    }

    /// Slot `s`'s box of the node (`a` holds slots 0..4, `b` 4..8): lo and hi per axis.
    fn slot_box(a: &WideNode, b: &WideNode, s: usize) -> [f32; 6] {
        let n = if s >= 4 { b } else { a };
        let k = s & 3;
        [
            n.lo_x[k], n.hi_x[k], n.lo_y[k], n.hi_y[k], n.lo_z[k], n.hi_z[k],
        ]
    }

    fn slot_child(a: &WideNode, b: &WideNode, s: usize) -> u32 {
        let n = if s >= 4 { b } else { a };
        n.child[s & 3]
    }

    /// Lanes `0..n` of a step (n <= 16).
    fn lanes(n: usize) -> __mmask16 {
        if n >= 16 {
            0xffff
        } else {
            (1u16 << n) - 1
        }
    }

    /// Traces every ray of `r` through the tree (`any`: stop each at its first hit).
    ///
    /// # Safety
    /// Needs AVX-512 F.
    #[target_feature(enable = "avx512f,popcnt")]
    pub(super) unsafe fn trace(
        r: &mut Rays,
        nodes: &[WideNode],
        tris: &[Triangle],
        any: bool,
        arena: &mut Arena,
        n: usize,
    ) {
        if n == 0 || nodes.is_empty() {
            return;
        }
        // The root's list, then the children's lists of each node on the way down, each
        // in a region of its parent's length plus one step (a step stores sixteen lanes).
        arena.reserve(n + 16);
        // Only the rays the set-up found to trace: a done path's slot (listed until the
        // next retirement, and always with coherent groups, which retire none) or a slot
        // without a shadow ray would otherwise take lanes at every node of the root's level.
        let iota = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
        let mut live = 0;
        for (step, &go) in r.traced[..n.div_ceil(16)].iter().enumerate() {
            let ids = _mm512_add_epi32(_mm512_set1_epi32(16 * step as i32), iota);
            _mm512_storeu_si512(
                arena.as_mut_ptr().add(live) as *mut __m512i,
                _mm512_maskz_compress_epi32(go, ids),
            );
            live += go.count_ones() as usize;
        }
        if live == 0 {
            return;
        }
        // (node, list start, list end, where its children's lists go)
        let mut stack: Vec<(u32, usize, usize, usize)> = vec![(0, 0, live, n + 16)];
        let scale = _mm512_set1_ps(1.0000004);
        let zero = _mm512_setzero_ps();
        while let Some((node, s, e, top)) = stack.pop() {
            let a = &nodes[node as usize];
            let b = &nodes[node as usize + 1];
            let m = e - s;
            let stride = m + 16;
            arena.reserve(top + 8 * stride);
            let base = arena.as_mut_ptr();
            let mut cnt = [0usize; 8];
            // The node's children (a node of fewer than eight has empty slots, which no
            // ray enters: skipped instead of tested).
            let mut slots = [0usize; 8];
            let mut boxes = [[0f32; 6]; 8];
            let mut filled = 0;
            for k in 0..8 {
                if slot_child(a, b, k) != EMPTY_SLOT {
                    slots[filled] = k;
                    boxes[filled] = slot_box(a, b, k);
                    filled += 1;
                }
            }
            let mut negs = [0u32; 3];
            let mut c = s;
            while c < e {
                let lm = lanes(e - c);
                let idx = _mm512_maskz_loadu_epi32(lm, base.add(c) as *const i32);
                let [ox, oy, oz, ix, iy, iz, tmax, _] =
                    load_records(r.boxr(), base.add(c), lm, idx);
                let nx = _mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(lm, ix, zero);
                let ny = _mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(lm, iy, zero);
                let nz = _mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(lm, iz, zero);
                negs[0] += nx.count_ones();
                negs[1] += ny.count_ones();
                negs[2] += nz.count_ones();
                for (&k, bx) in slots[..filled].iter().zip(&boxes[..filled]) {
                    // `hit4`, operation for operation: the near slab is the box's max where
                    // the inverse direction is negative.
                    let (lo_x, hi_x) = (_mm512_set1_ps(bx[0]), _mm512_set1_ps(bx[1]));
                    let (lo_y, hi_y) = (_mm512_set1_ps(bx[2]), _mm512_set1_ps(bx[3]));
                    let (lo_z, hi_z) = (_mm512_set1_ps(bx[4]), _mm512_set1_ps(bx[5]));
                    let ax = _mm512_mask_blend_ps(nx, lo_x, hi_x);
                    let fx = _mm512_mask_blend_ps(nx, hi_x, lo_x);
                    let ay = _mm512_mask_blend_ps(ny, lo_y, hi_y);
                    let fy = _mm512_mask_blend_ps(ny, hi_y, lo_y);
                    let az = _mm512_mask_blend_ps(nz, lo_z, hi_z);
                    let fz = _mm512_mask_blend_ps(nz, hi_z, lo_z);
                    let near = _mm512_max_ps(
                        _mm512_max_ps(
                            _mm512_max_ps(
                                _mm512_mul_ps(_mm512_sub_ps(ax, ox), ix),
                                _mm512_mul_ps(_mm512_sub_ps(ay, oy), iy),
                            ),
                            _mm512_mul_ps(_mm512_sub_ps(az, oz), iz),
                        ),
                        zero,
                    );
                    let far = _mm512_mul_ps(
                        _mm512_min_ps(
                            _mm512_min_ps(
                                _mm512_min_ps(
                                    _mm512_mul_ps(_mm512_sub_ps(fx, ox), ix),
                                    _mm512_mul_ps(_mm512_sub_ps(fy, oy), iy),
                                ),
                                _mm512_mul_ps(_mm512_sub_ps(fz, oz), iz),
                            ),
                            tmax,
                        ),
                        scale,
                    );
                    let hit = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(lm, near, far);
                    // Packed in a register and stored whole: a compress to memory is
                    // microcoded on Zen 4; the region has room for the sixteen lanes.
                    // Stored even where no lane enters: that costs less than the branch,
                    // which mispredicts (the `stream_traversal` example: 0.85-0.97x of the time per ray
                    // with the branch, alternated runs).
                    let dst = base.add(top + k * stride + cnt[k]);
                    _mm512_storeu_si512(dst as *mut __m512i, _mm512_maskz_compress_epi32(hit, idx));
                    cnt[k] += hit.count_ones() as usize;
                }
                c += 16;
            }
            let half = (m as u32).div_ceil(2);
            let oct = (negs[0] > half) as usize
                | ((negs[1] > half) as usize) << 1
                | ((negs[2] > half) as usize) << 2;
            // The leaf bits of octant 0 are in slot order.
            let leaf_bits = (a.meta.x & 0xff) as usize;
            for p in 0..8 {
                let k = p ^ oct;
                if cnt[k] > 0 && leaf_bits & (1 << k) != 0 {
                    let child = slot_child(a, b, k);
                    let first = child & 0x0fff_ffff;
                    let count = ((child >> 28) & 7) + 1;
                    let from = top + k * stride;
                    // SAFETY: the node's step wrote the child's `cnt[k]` entries.
                    leaf(r, tris, arena.list(from, from + cnt[k]), first, count, any);
                }
            }
            // Inner children far first, so that the nearest is visited next.
            let next = top + 8 * stride;
            for p in (0..8).rev() {
                let k = p ^ oct;
                if cnt[k] > 0 && leaf_bits & (1 << k) == 0 {
                    let from = top + k * stride;
                    stack.push((slot_child(a, b, k), from, from + cnt[k], next));
                }
            }
        }
    }

    /// The rays `ids` against triangles `first..first + count`, sixteen rays at a time, as
    /// `traverse::leaf_hits` does for one. With `any`, a ray that hits is done: its t
    /// becomes -1, which no later box or triangle test passes.
    #[target_feature(enable = "avx512f,popcnt")]
    unsafe fn leaf(
        r: &mut Rays,
        tris: &[Triangle],
        ids: &[u32],
        first: u32,
        count: u32,
        any: bool,
    ) {
        let zero = _mm512_setzero_ps();
        let izero = _mm512_setzero_si512();
        let mut c = 0;
        while c < ids.len() {
            let lm = lanes(ids.len() - c);
            let idx = _mm512_maskz_loadu_epi32(lm, ids.as_ptr().add(c) as *const i32);
            let [rx, ry, rz, sx, sy, sz, tmin, kz] =
                load_records(r.trir(), ids.as_ptr().add(c), lm, idx);
            let kz = _mm512_castps_si512(kz);
            // The closest t so far, in the box records.
            let t_at = (r.boxr() as *mut f32).add(field::T);
            let rec = _mm512_slli_epi32::<4>(idx);
            let k0 = _mm512_cmpeq_epi32_mask(kz, izero);
            let k1 = _mm512_cmpeq_epi32_mask(kz, _mm512_set1_epi32(1));
            // The hit so far; only the lanes a triangle hits here are written back, so u, v
            // and the triangle need not be read.
            let mut bt = _mm512_mask_i32gather_ps::<4>(zero, lm, rec, t_at);
            // The closest hit's v, w and det: its u and v are divided out once, after the
            // leaf (the same divisions, of the same values).
            let mut bv = zero;
            let mut bw = zero;
            let mut bdet = _mm512_set1_ps(1.0);
            let mut btri = izero;
            let mut changed: __mmask16 = 0;
            // `rotate(v, kz)` per lane, less the ray's rotated origin: kz 0 -> (y, z, x),
            // 1 -> (z, x, y), 2 -> (x, y, z), as an in-lane permute of the vertex broadcast
            // to each 128-bit lane (two blends per component cost a seventh of the stream's
            // time on closest hits; this moves the same floats).
            let (i0, i1, i2) = (izero, _mm512_set1_epi32(1), _mm512_set1_epi32(2));
            let pick_x = _mm512_mask_mov_epi32(_mm512_mask_mov_epi32(i0, k1, i2), k0, i1);
            let pick_y = _mm512_mask_mov_epi32(_mm512_mask_mov_epi32(i1, k1, i0), k0, i2);
            let pick_z = kz;
            let rel = |v: &Vec3| {
                // A vertex and the four bytes after it (`Triangle` pads each to 16).
                let v = _mm512_broadcast_f32x4(_mm_loadu_ps(v as *const Vec3 as *const f32));
                (
                    _mm512_sub_ps(_mm512_permutevar_ps(v, pick_x), rx),
                    _mm512_sub_ps(_mm512_permutevar_ps(v, pick_y), ry),
                    _mm512_sub_ps(_mm512_permutevar_ps(v, pick_z), rz),
                )
            };
            for k in first..first + count {
                let t = &tris[k as usize];
                // `traverse::intersect`, operation for operation.
                let (a_x, a_y, a_z) = rel(&t.v0);
                let (b_x, b_y, b_z) = rel(&t.v1);
                let (c_x, c_y, c_z) = rel(&t.v2);
                let ax = _mm512_sub_ps(a_x, _mm512_mul_ps(sx, a_z));
                let ay = _mm512_sub_ps(a_y, _mm512_mul_ps(sy, a_z));
                let bx = _mm512_sub_ps(b_x, _mm512_mul_ps(sx, b_z));
                let by = _mm512_sub_ps(b_y, _mm512_mul_ps(sy, b_z));
                let cx = _mm512_sub_ps(c_x, _mm512_mul_ps(sx, c_z));
                let cy = _mm512_sub_ps(c_y, _mm512_mul_ps(sy, c_z));
                let u = _mm512_sub_ps(_mm512_mul_ps(cx, by), _mm512_mul_ps(cy, bx));
                let v = _mm512_sub_ps(_mm512_mul_ps(ax, cy), _mm512_mul_ps(ay, cx));
                let w = _mm512_sub_ps(_mm512_mul_ps(bx, ay), _mm512_mul_ps(by, ax));
                let lt = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(u, zero)
                    | _mm512_cmp_ps_mask::<_CMP_LT_OQ>(v, zero)
                    | _mm512_cmp_ps_mask::<_CMP_LT_OQ>(w, zero);
                let gt = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(u, zero)
                    | _mm512_cmp_ps_mask::<_CMP_GT_OQ>(v, zero)
                    | _mm512_cmp_ps_mask::<_CMP_GT_OQ>(w, zero);
                let det = _mm512_add_ps(_mm512_add_ps(u, v), w);
                let ok = lm & !(lt & gt) & _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(det, zero);
                // No branch on `ok`: whether any of sixteen rays passes a triangle's edges
                // is a coin toss the predictor loses (computed regardless: 0.95x of the
                // closest hits' time in the `stream_traversal` example).
                let szz = |z| _mm512_mul_ps(sz, z);
                let tt = _mm512_div_ps(
                    _mm512_add_ps(
                        _mm512_add_ps(_mm512_mul_ps(u, szz(a_z)), _mm512_mul_ps(v, szz(b_z))),
                        _mm512_mul_ps(w, szz(c_z)),
                    ),
                    det,
                );
                let hit = ok
                    & _mm512_cmp_ps_mask::<_CMP_GT_OQ>(tt, tmin)
                    & _mm512_cmp_ps_mask::<_CMP_LT_OQ>(tt, bt);
                // Blended without a branch on `hit`, which mispredicts.
                bt = _mm512_mask_blend_ps(hit, bt, tt);
                bv = _mm512_mask_blend_ps(hit, bv, v);
                bw = _mm512_mask_blend_ps(hit, bw, w);
                bdet = _mm512_mask_blend_ps(hit, bdet, det);
                btri = _mm512_mask_blend_epi32(hit, btri, _mm512_set1_epi32(k as i32));
                changed |= hit;
            }
            if changed != 0 {
                let bu = _mm512_div_ps(bv, bdet);
                let bv = _mm512_div_ps(bw, bdet);
                if any {
                    // Only whether it hit is wanted (`trace_shadow8`): its t ends the traversal.
                    bt = _mm512_mask_blend_ps(changed, bt, _mm512_set1_ps(-1.0));
                }
                // Lane by lane over the changed lanes (a few of sixteen): four scatters took
                // longer than these scalar stores.
                let mut lane = [[0u32; 16]; 5];
                for (to, from) in lane.iter_mut().zip([
                    idx,
                    _mm512_castps_si512(bt),
                    _mm512_castps_si512(bu),
                    _mm512_castps_si512(bv),
                    btri,
                ]) {
                    _mm512_storeu_si512(to.as_mut_ptr() as *mut __m512i, from);
                }
                let (t_at, u, v, tri) = (
                    t_at as *mut u32,
                    r.u.as_mut_ptr() as *mut u32,
                    r.v.as_mut_ptr() as *mut u32,
                    r.tri.as_mut_ptr(),
                );
                let mut m = changed;
                while m != 0 {
                    let j = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let i = lane[0][j] as usize;
                    *t_at.add(8 * RECORD_STRIDE * i) = lane[1][j];
                    *u.add(i) = lane[2][j];
                    *v.add(i) = lane[3][j];
                    *tri.add(i) = lane[4][j];
                }
            }
            c += 16;
        }
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::avx512::{load_records, load_vec4s, store_records, store_vec4s};
    use super::RECORD_STRIDE;
    use std::arch::x86_64::*;

    /// Records stored from sixteen rays' fields read back, in any order of rays, as the
    /// same fields lane by lane, also for a step of fewer than sixteen rays.
    #[test]
    fn records_round_trip_through_the_transposes() {
        if !super::supported() {
            return;
        }
        let value = |ray: usize, k: usize| (ray * 8 + k) as f32 + 0.5;
        let mut recs = vec![[0f32; 8]; 32 * RECORD_STRIDE];
        // SAFETY: AVX-512 F was checked; the records hold both steps of sixteen rays.
        unsafe {
            for step in 0..2 {
                let fields: [__m512; 8] = std::array::from_fn(|k| {
                    let lane: [f32; 16] = std::array::from_fn(|j| value(step * 16 + j, k));
                    _mm512_loadu_ps(lane.as_ptr())
                });
                store_records(recs.as_mut_ptr().add(RECORD_STRIDE * step * 16), fields);
            }
        }
        for (ray, rec) in recs.iter().step_by(RECORD_STRIDE).enumerate() {
            assert_eq!(*rec, std::array::from_fn(|k| value(ray, k)), "record {ray}");
        }
        let ids: [u32; 16] = [31, 0, 7, 16, 3, 30, 9, 12, 1, 22, 5, 27, 18, 2, 11, 25];
        for n in [16usize, 5] {
            let lm: __mmask16 = if n == 16 { 0xffff } else { (1 << n) - 1 };
            // SAFETY: AVX-512 F was checked; every index is a record.
            let fields = unsafe {
                let idx = _mm512_maskz_loadu_epi32(lm, ids.as_ptr() as *const i32);
                load_records(recs.as_ptr(), ids.as_ptr(), lm, idx)
            };
            for (k, f) in fields.iter().enumerate() {
                let mut lanes = [0f32; 16];
                // SAFETY: sixteen floats.
                unsafe { _mm512_storeu_ps(lanes.as_mut_ptr(), *f) };
                for j in 0..16 {
                    // Lanes outside the step read ray 0's record.
                    let ray = if j < n { ids[j] as usize } else { 0 };
                    assert_eq!(lanes[j], value(ray, k), "n {n}, field {k}, lane {j}");
                }
            }
        }
    }

    /// Slots' `Vec4`s read as components, lane by lane: scattered slots, consecutive
    /// ones (the four-load path), a step of fewer than sixteen, and slots whose first and
    /// last are fifteen apart out of order.
    #[test]
    fn vec4s_of_slots_load_as_components() {
        if !super::supported() {
            return;
        }
        let v: Vec<glam::Vec4> = (0..64)
            .map(|i| glam::Vec4::new(i as f32, i as f32 + 0.25, i as f32 + 0.5, -(i as f32)))
            .collect();
        let scattered: [u32; 16] = [63, 0, 7, 16, 3, 30, 9, 12, 1, 22, 5, 27, 18, 2, 11, 25];
        let consecutive: [u32; 16] = std::array::from_fn(|j| 40 + j as u32);
        // First and last slots fifteen apart, but not in order (a list need not be sorted).
        let mut shuffled = consecutive;
        shuffled.swap(3, 9);
        // Lanes 1.. consecutive from slot 0, lane 0 elsewhere: stored without lane 0, the
        // run starts at slot "-1".
        let from_zero: [u32; 16] = std::array::from_fn(|j| if j == 0 { 50 } else { j as u32 - 1 });
        for (ids, n) in [
            (scattered, 16usize),
            (consecutive, 16),
            (consecutive, 9),
            (shuffled, 16),
            (from_zero, 16),
        ] {
            let lm: __mmask16 = if n == 16 { 0xffff } else { (1 << n) - 1 };
            // SAFETY: AVX-512 F was checked; every slot indexes `v`.
            let comps = unsafe {
                let idx = _mm512_maskz_loadu_epi32(lm, ids.as_ptr() as *const i32);
                load_vec4s(v.as_ptr(), ids.as_ptr(), lm, idx)
            };
            for (k, c) in comps.iter().enumerate() {
                let mut lanes = [0f32; 16];
                // SAFETY: sixteen floats.
                unsafe { _mm512_storeu_ps(lanes.as_mut_ptr(), *c) };
                for (j, &got) in lanes.iter().enumerate().take(n) {
                    assert_eq!(got, v[ids[j] as usize][k], "n {n}, component {k}, lane {j}");
                }
            }
            // Stored back into a zeroed copy under masks of every lane, every other lane
            // (lane 0 stored or not) and a run in the middle: those slots get their
            // Vec4s, the rest stay zero.
            for mask in [0xffff, 0x5555, 0xaaaa, 0x0ff0, 0x8001] {
                let mask: __mmask16 = mask & lm;
                let mut back = vec![glam::Vec4::ZERO; v.len()];
                // SAFETY: AVX-512 F was checked; every slot indexes `back`.
                unsafe { store_vec4s(back.as_mut_ptr(), ids.as_ptr(), mask, comps) };
                for (j, &slot) in ids.iter().enumerate() {
                    let want = if mask & (1 << j) != 0 {
                        v[slot as usize]
                    } else {
                        glam::Vec4::ZERO
                    };
                    assert_eq!(back[slot as usize], want, "n {n}, mask {mask:#x}, lane {j}");
                }
            }
        }
    }
}
