//! Stream compaction on the GPU (both backends) against a host stable partition: sizes
//! around the block and word boundaries, several flag densities (all 0, all 1, sparse,
//! dense, half), `count[0]` below the launched size, and nothing written past the end.

use cohort::runtime::{BackendKind, Device};
use cohort_kernels::compact::{record, scratch_len, specs, BLOCK, DISPATCHES};

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
    (got[..n].to_vec(), total)
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
    for (n, launched, density) in cases {
        let len = launched as usize;
        let flags: Vec<u32> = (0..len)
            .map(|_| ((rng.next() % 1000) < density) as u32)
            .collect();
        // Distinct ids that are not the identity, so misplaced ids are caught.
        let ids: Vec<u32> = (0..len as u32)
            .map(|i| i.wrapping_mul(2_654_435_761) ^ 0x5555)
            .collect();
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

#[test]
fn compaction_wgpu() {
    check(BackendKind::Wgpu);
}

#[test]
fn compaction_vulkan() {
    check(BackendKind::Vulkan);
}

/// The native CPU backend runs the same kernels (subgroup scans, barriers and workgroup
/// memory included) with its 32-wide subgroups.
#[test]
fn compaction_cpu() {
    check(BackendKind::Cpu);
}
