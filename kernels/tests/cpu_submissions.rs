//! Submissions to the CPU backend from several threads at once, on a pool of more threads
//! than they are: each submission keeps the pool's other threads awake while it runs
//! (`cpu_backend`'s `Awake`), and a thread may pick up one submission's wait while it
//! waits inside another's dispatch (a wait that finds no work ends within a millisecond,
//! so no two such waits can hold each other). Every submission must still finish, with the results
//! it gets alone. Its own test binary, so that it sizes rayon's global pool.

use cohort::runtime::cpu::simd::Forms;
use cohort::runtime::Device;
use cohort_kernels::compact::{record, scratch_len, specs};

/// Rayon's pool: more threads than the submitting threads, so that some run only other
/// submissions' work and waits.
const POOL: usize = 8;
const SUBMITTERS: u32 = 6;
const ROUNDS: u32 = 12;

/// The compaction of `flags` (ids 0..n) on `d`: the partition and the count of ones.
fn compact(d: &Device, flags: &[u32]) -> (Vec<u32>, u32) {
    let n = flags.len();
    let ids: Vec<u32> = (0..n as u32).collect();
    let flags_buf = d.upload(flags).unwrap();
    let ids_buf = d.upload(&ids).unwrap();
    let count = d.upload(&[n as u32]).unwrap();
    let scratch = d.upload(&vec![0u32; scratch_len(n)]).unwrap();
    let total = d.upload(&[0u32]).unwrap();
    let out = d.upload(&vec![0u32; n]).unwrap();
    let sp = specs(d);
    let mut b = d.batch();
    record(
        &mut b, &sp, n as u32, &count, &flags_buf, &scratch, &total, &ids_buf, &out,
    )
    .unwrap();
    b.submit().unwrap();
    (d.read(&out).unwrap(), d.read(&total).unwrap()[0])
}

/// The host's stable partition: ids with flag 1, then the others.
fn partition(flags: &[u32]) -> (Vec<u32>, u32) {
    let ones = (0..flags.len() as u32).filter(|&i| flags[i as usize] != 0);
    let zeros = (0..flags.len() as u32).filter(|&i| flags[i as usize] == 0);
    let total = ones.clone().count() as u32;
    (ones.chain(zeros).collect(), total)
}

#[test]
fn concurrent_submissions_on_a_larger_pool_all_finish_with_their_own_results() {
    rayon::ThreadPoolBuilder::new()
        .num_threads(POOL)
        .build_global()
        .expect("the global pool, before any other use of it in this binary");
    // Host forms run each workgroup as a pool job (many small jobs to steal); measured
    // forms run the compaction's whole-dispatch forms (one job per dispatch).
    for forms in [Forms::Host, Forms::Measured] {
        let d = Device::cpu_with(forms).unwrap();
        std::thread::scope(|t| {
            for k in 0..SUBMITTERS {
                let d = &d;
                t.spawn(move || {
                    for round in 0..ROUNDS {
                        let n = 20_000 + 1_237 * (k * ROUNDS + round) as usize;
                        let flags: Vec<u32> = (0..n as u32)
                            .map(|i| {
                                u32::from(
                                    (i ^ (k << 7) ^ round).wrapping_mul(2_654_435_761) >> 31 == 1,
                                )
                            })
                            .collect();
                        assert_eq!(
                            compact(d, &flags),
                            partition(&flags),
                            "{forms:?}, submitter {k}, round {round}, {n} flags"
                        );
                    }
                });
            }
        });
    }
}
