//! Stream compaction on the GPU (both backends) against a host stable partition: sizes
//! around the block and word boundaries, several flag densities (all 0, all 1, sparse,
//! dense, half), `count[0]` below the launched size, and nothing written past the end.
//!
//! Retiring finished slots (`cohort_kernels::retire`, the compaction over flags of slots
//! not done) against a host filter: the new list is the listed slots whose state is not
//! done, in list order, then the done ones; the new count is the number not done. Lists
//! shorter than the launched size, lists that are a permutation of a subset of the slots,
//! all done and none done, and state words whose other bits are set.

use cohort::runtime::{BackendKind, Device};
use cohort_kernels::compact::{record, scratch_len, specs, BLOCK, DISPATCHES};
use cohort_kernels::layout::DONE;
use cohort_kernels::retire;
use glam::UVec4;

const SIZES: &[u32] = &[0, 1, 31, 255, 256, 257, 1000, 4097, 100_003, 1 << 20];
/// Probability of flag 1, in 1/1000.
const DENSITIES: &[u32] = &[0, 1000, 500, 30, 970];
const SENTINEL: u32 = 0xDEAD_BEEF;
/// Slack after the end of `out` that must stay untouched.
const SLACK: usize = 64;

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u32 {
        // xorshift64*
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 32) as u32
    }
}

/// Host reference: flag-1 ids first, then flag-0 ids, both in order.
fn partition(flags: &[u32], ids: &[u32]) -> (Vec<u32>, u32) {
    let ones: Vec<u32> = ids
        .iter()
        .zip(flags)
        .filter(|(_, &f)| f != 0)
        .map(|(&i, _)| i)
        .collect();
    let total = ones.len() as u32;
    let mut out = ones;
    out.extend(
        ids.iter()
            .zip(flags)
            .filter(|(_, &f)| f == 0)
            .map(|(&i, _)| i),
    );
    (out, total)
}

/// Compacts the first `n` of `flags`/`ids` with kernels launched for `launched >= n` rays.
fn run(d: &Device, flags: &[u32], ids: &[u32], n: u32, launched: u32) -> (Vec<u32>, u32) {
    let (out, total, _) = run_words(d, flags, ids, n, launched);
    (out, total)
}

/// [`run`], and every word of the scratch buffer after it.
fn run_words(
    d: &Device,
    flags: &[u32],
    ids: &[u32],
    n: u32,
    launched: u32,
) -> (Vec<u32>, u32, Vec<u32>) {
    let len = launched as usize;
    let flags_buf = d.upload(&flags[..len]).unwrap();
    let ids_buf = d.upload(&ids[..len]).unwrap();
    let count = d.upload(&[n]).unwrap();
    // Stale scratch and total from an earlier run must not matter.
    let scratch = d.upload(&vec![SENTINEL; scratch_len(len)]).unwrap();
    let total = d.upload(&[SENTINEL]).unwrap();
    let out = d.upload(&vec![SENTINEL; len + SLACK]).unwrap();
    let sp = specs(d);
    let mut b = d.batch();
    record(
        &mut b, &sp, launched, &count, &flags_buf, &scratch, &total, &ids_buf, &out,
    )
    .unwrap();
    let stats = b.submit().unwrap();
    assert_eq!(stats.len(), DISPATCHES);
    let got = d.read(&out).unwrap();
    let total = d.read(&total).unwrap()[0];
    let n = n as usize;
    assert!(
        got[n..].iter().all(|&v| v == SENTINEL),
        "n = {n} (launched {launched}): something was written past element {n}"
    );
    (got[..n].to_vec(), total, d.read(&scratch).unwrap())
}

/// The cases of [`check`]: (rays, launched size, density of flag 1 in 1/1000).
fn cases() -> Vec<(u32, u32, u32)> {
    let mut cases = Vec::new();
    for &n in SIZES {
        for &density in DENSITIES {
            cases.push((n, n, density));
        }
    }
    // `count[0]` smaller than the launched size (the renderer's buffers are sized for
    // the maximum): the tail must be ignored.
    cases.push((4097, 5000, 500));
    cases.push((1, BLOCK * 3 + 5, 500));
    cases.push((BLOCK * 2, BLOCK * 2 + 1, 700));
    cases
}

/// Flags of density `density`/1000 and distinct ids that are not the identity (so that
/// misplaced ids are caught), `len` of each.
fn inputs(rng: &mut Rng, len: usize, density: u32) -> (Vec<u32>, Vec<u32>) {
    let flags = (0..len)
        .map(|_| ((rng.next() % 1000) < density) as u32)
        .collect();
    let ids = (0..len as u32)
        .map(|i| i.wrapping_mul(2_654_435_761) ^ 0x5555)
        .collect();
    (flags, ids)
}

fn check(kind: BackendKind) {
    let Some(d) = Device::for_tests(kind) else {
        return;
    };
    println!(
        "{}: subgroup size {}",
        d.info().adapter_name,
        d.info().subgroup_size
    );
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for (n, launched, density) in cases() {
        let (flags, ids) = inputs(&mut rng, launched as usize, density);
        let (want, want_total) = partition(&flags[..n as usize], &ids[..n as usize]);
        let (got, total) = run(&d, &flags, &ids, n, launched);
        assert_eq!(
            total, want_total,
            "{kind:?}: n = {n}, density {density}/1000: wrong total"
        );
        if got != want {
            let first = got.iter().zip(&want).position(|(a, b)| a != b).unwrap();
            panic!(
                "{kind:?}: n = {n} (launched {launched}), density {density}/1000: first difference at {first}: got {:#x}, want {:#x}",
                got[first], want[first]
            );
        }
    }
}

/// One case: `slots` slots, `n` of them listed (in a shuffled order), the list launched
/// over `launched >= n` entries, each slot done with probability `done`/1000.
fn retire_case(d: &Device, rng: &mut Rng, slots: u32, n: u32, launched: u32, done: u32) {
    let state: Vec<UVec4> = (0..slots)
        .map(|_| {
            let flags = if rng.next() % 1000 < done { DONE } else { 0 };
            // Other bits of w (a path's status flags) must not count as done.
            UVec4::new(
                rng.next(),
                rng.next(),
                rng.next(),
                flags | (rng.next() & !DONE),
            )
        })
        .collect();
    let mut ids: Vec<u32> = (0..slots).collect();
    for i in (1..ids.len()).rev() {
        ids.swap(i, rng.next() as usize % (i + 1));
    }
    ids.resize(launched as usize, SENTINEL);
    let listed = &ids[..n as usize];
    let live = |s: &&u32| state[**s as usize].w & DONE == 0;
    let mut want: Vec<u32> = listed.iter().filter(live).copied().collect();
    let want_count = want.len() as u32;
    want.extend(listed.iter().filter(|s| !live(s)));

    let len = launched as usize;
    let count = d.upload(&[n]).unwrap();
    let ids_buf = d.upload(&ids).unwrap();
    let state_buf = d.upload(&state).unwrap();
    // Stale flags, scratch and count must not matter.
    let flags = d.upload(&vec![SENTINEL; len]).unwrap();
    let scratch = d.upload(&vec![SENTINEL; scratch_len(len)]).unwrap();
    let out_count = d.upload(&[SENTINEL]).unwrap();
    let out = d.upload(&vec![SENTINEL; len]).unwrap();
    let mut b = d.batch();
    retire::record(
        &mut b,
        &retire::spec(d),
        &specs(d),
        launched,
        &count,
        &ids_buf,
        &state_buf,
        &flags,
        &scratch,
        &out_count,
        &out,
    )
    .unwrap();
    assert_eq!(b.submit().unwrap().len(), retire::DISPATCHES);
    let got = d.read(&out).unwrap();
    let got_count = d.read(&out_count).unwrap()[0];
    let what = format!(
        "{}: {slots} slots, {n} listed (launched {launched}), {done}/1000 done",
        d.info().adapter_name
    );
    assert_eq!(got_count, want_count, "{what}: wrong count");
    assert_eq!(&got[..n as usize], &want[..], "{what}: wrong list");
    assert!(
        got[n as usize..].iter().all(|&v| v == SENTINEL),
        "{what}: written past the list"
    );
    // The list the renderer reads next is exactly the live slots.
    assert!(got[..got_count as usize]
        .iter()
        .all(|&s| state[s as usize].w & DONE == 0));
}

fn check_retire(kind: BackendKind) {
    let Some(d) = Device::for_tests(kind) else {
        return;
    };
    let mut rng = Rng(0x51ED_2701_A3C4_9B17);
    for (slots, n, launched) in [
        (0, 0, 0),
        (1, 1, 1),
        (300, 300, 300),
        (5000, 4097, 4097),
        (5000, 1000, 4097),
        (70_000, 65_536, 65_536),
    ] {
        for done in [0, 1000, 500, 30, 970] {
            retire_case(&d, &mut rng, slots, n, launched, done);
        }
    }
}

#[test]
fn compaction_wgpu() {
    check(BackendKind::Wgpu);
    check_retire(BackendKind::Wgpu);
}

#[test]
fn compaction_vulkan() {
    check(BackendKind::Vulkan);
    check_retire(BackendKind::Vulkan);
}

/// The native CPU backend runs the kernels as whole-dispatch loops by default.
#[test]
fn compaction_cpu() {
    check(BackendKind::Cpu);
    check_retire(BackendKind::Cpu);
}

/// On the CPU backend, the kernels' whole-dispatch loops write what their host forms
/// (subgroup scans, barriers and workgroup memory, 32-wide subgroups) write: the same
/// partition, total and scratch words, in every case of [`check`].
#[test]
fn compaction_cpu_whole_dispatches_write_the_host_forms_words() {
    use cohort::runtime::cpu::simd::Forms;
    let whole = Device::cpu_with(Forms::Measured).unwrap();
    let host = Device::cpu_with(Forms::Host).unwrap();
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    for (n, launched, density) in cases() {
        let (flags, ids) = inputs(&mut rng, launched as usize, density);
        let a = run_words(&whole, &flags, &ids, n, launched);
        let b = run_words(&host, &flags, &ids, n, launched);
        assert_eq!(
            a, b,
            "n = {n} (launched {launched}), density {density}/1000"
        );
    }
    let counts = whole.form_counts();
    for k in ["compact_count", "compact_offsets", "compact_scatter"] {
        let c = counts.iter().find(|c| c.kernel.starts_with(k)).expect(k);
        assert!(c.whole > 0 && c.host == 0, "{k} ran {c:?}");
    }
}
