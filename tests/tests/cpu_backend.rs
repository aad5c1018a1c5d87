//! What the native CPU backend adds to the difftests' third column: subgroup operations in
//! divergent control flow mean what they mean on a GPU (only the active lanes take part),
//! on every backend; a kernel that panics on the CPU (an index out of bounds) comes back
//! as an error naming the kernel, not as a crash; dispatches are timed.

mod common;

use cohort::prelude::*;
use cohort::runtime::{BackendKind, Device, RuntimeError};
use cohort_tests::kernels::group_pick::{hash, PickParams};

/// Even lanes sum 1 over the subgroup inside the `if` (only they are active there), every
/// lane again after it (all reconverged), and odd lanes count the even lanes below them
/// with an exclusive scan over a ballot-free predicate.
#[kernel(workgroup = 64)]
pub fn divergent_subgroups(
    #[builtin(global_index)] gi: u32,
    #[builtin(subgroup_lane)] lane: u32,
    out: &mut [UVec4],
) {
    let mut inside = 0u32;
    let mut scan = 0u32;
    if lane % 2 == 0 {
        inside = subgroup_add(1u32);
    } else {
        scan = subgroup_exclusive_add(lane);
    }
    let after = subgroup_add(1u32);
    out[gi as usize] = UVec4::new(inside, after, scan, 0);
}

#[test]
fn divergent_subgroup_operations_count_only_active_lanes() {
    for d in common::devices() {
        let size = d.info().subgroup_size;
        let out = d.alloc::<UVec4>(128).unwrap();
        divergent_subgroups::launch(&d, 128u32, &out).unwrap();
        let got = d.read(&out).unwrap();
        for (i, v) in got.iter().enumerate() {
            let lane = i as u32 % size;
            let (inside, scan) = if lane.is_multiple_of(2) {
                (size / 2, 0)
            } else {
                // Odd lanes below this one: 1, 3, ..., lane - 2.
                (0, (1..lane).step_by(2).sum::<u32>())
            };
            assert_eq!(
                *v,
                UVec4::new(inside, size, scan, 0),
                "{:?}, invocation {i} (lane {lane} of {size})",
                d.info().backend
            );
        }
    }
}

#[kernel(workgroup = 64)]
pub fn reads_past_the_end(#[builtin(global_index)] gi: u32, xs: &[u32], out: &mut [u32]) {
    out[gi as usize] = xs[gi as usize + 1000];
}

#[test]
fn a_panicking_invocation_is_an_error_naming_the_kernel() {
    use cohort::runtime::cpu::simd::Forms;
    // The host form panics; the vector form checks each lane's index.
    for forms in [Forms::Host, Forms::Vector] {
        out_of_bounds_is_an_error(Device::cpu_with(forms).unwrap());
    }
}

fn out_of_bounds_is_an_error(d: Device) {
    let xs = d.upload(&[1u32; 64]).unwrap();
    let out = d.alloc::<u32>(64).unwrap();
    let err = reads_past_the_end::launch(&d, 64u32, &xs, &out).unwrap_err();
    let msg = err.to_string();
    assert!(
        matches!(
            err,
            cohort::Error::Runtime(RuntimeError::Dispatch {
                backend: BackendKind::Cpu,
                ..
            })
        ),
        "{msg}"
    );
    assert!(
        msg.contains("reads_past_the_end") && msg.contains("index out of bounds"),
        "{msg}"
    );
    // The device is still usable.
    let ok = d.upload(&[5u32; 2000]).unwrap();
    let stats = reads_past_the_end::launch(&d, 64u32, &ok, &out).unwrap();
    assert_eq!(d.read(&out).unwrap(), vec![5u32; 64]);
    assert!(stats.gpu_time_ns.is_some(), "dispatches are timed");
}

/// An index computed in `i32` that can go below zero.
#[kernel(workgroup = 64)]
pub fn reads_at_a_signed_offset(
    #[builtin(global_index)] gi: u32,
    offsets: &[i32],
    xs: &[u32],
    out: &mut [u32],
) {
    let i = gi as i32 + offsets[gi as usize];
    out[gi as usize] = xs[i as usize];
}

#[test]
fn an_index_below_zero_is_an_error_in_both_forms() {
    use cohort::runtime::cpu::simd::Forms;
    for forms in [Forms::Host, Forms::Vector] {
        let d = Device::cpu_with(forms).unwrap();
        let xs: Vec<u32> = (0..64).map(|i| 100 + i).collect();
        let xs_b = d.upload(&xs).unwrap();
        let out = d.alloc::<u32>(64).unwrap();
        let mut offsets = vec![0i32; 64];
        offsets[5] = -5;
        let offsets_b = d.upload(&offsets).unwrap();
        reads_at_a_signed_offset::launch(&d, 64u32, &offsets_b, &xs_b, &out).unwrap();
        let mut want = xs.clone();
        want[5] = 100;
        assert_eq!(d.read(&out).unwrap(), want, "{forms:?}");
        // Lane 9 reads element -1: four bytes before the buffer, whose end (offset 0) is
        // in bounds.
        offsets[9] = -10;
        let offsets_b = d.upload(&offsets).unwrap();
        let err = reads_at_a_signed_offset::launch(&d, 64u32, &offsets_b, &xs_b, &out).unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("reads_at_a_signed_offset") && msg.contains("index out of bounds"),
            "{forms:?}: {msg}"
        );
    }
}

/// A lane that panics between barriers, while the others of its workgroup wait parked on
/// their own stacks: they are unwound, and the dispatch fails cleanly.
#[kernel(workgroup = 64)]
pub fn panics_between_barriers(
    #[builtin(local_index)] li: u32,
    #[workgroup] shared: &mut [u32; 64],
    xs: &[u32],
    out: &mut [u32],
) {
    shared[li as usize] = xs[li as usize];
    workgroup_barrier();
    let v = shared[(63 - li) as usize];
    let w = if li == 5 { xs[v as usize] } else { v };
    workgroup_barrier();
    out[li as usize] = w;
}

#[test]
fn a_panic_in_a_synchronising_kernel_unwinds_the_parked_lanes() {
    let Some(d) = Device::for_tests(BackendKind::Cpu) else {
        return;
    };
    let mut xs: Vec<u32> = (0..64).collect();
    xs[63 - 5] = 1_000_000;
    let xs = d.upload(&xs).unwrap();
    let out = d.alloc::<u32>(64).unwrap();
    let err = panics_between_barriers::launch(&d, 64u32, &xs, &out).unwrap_err();
    assert!(err.to_string().contains("index out of bounds"), "{err}");
    let fine = d.upload(&(0..64).collect::<Vec<u32>>()).unwrap();
    panics_between_barriers::launch(&d, 64u32, &fine, &out).unwrap();
    assert_eq!(
        d.read(&out).unwrap(),
        (0..64u32).map(|i| 63 - i).collect::<Vec<_>>()
    );
}

#[test]
fn the_cpu_backend_describes_itself() {
    let Some(d) = Device::for_tests(BackendKind::Cpu) else {
        return;
    };
    let info = d.info();
    assert_eq!(info.subgroup_size, cohort::runtime::cpu::SUBGROUP_WIDTH);
    assert!(!info.software_driver);
    assert!(info.timestamps);
    assert!(
        info.adapter_name.starts_with("CPU"),
        "{}",
        info.adapter_name
    );
}

/// A CPU device opened with a block width says it in its driver line, and a width the
/// vector forms do not take is refused with the widths they do.
#[test]
fn a_cpu_device_runs_the_vector_width_it_was_opened_with() {
    use cohort::runtime::cpu::simd::{Forms, WIDTHS};
    if cohort::runtime::cpu::simd::llvm_library().is_ok() {
        for lanes in WIDTHS {
            let d = Device::cpu_with_lanes(Forms::Vector, lanes).unwrap();
            assert!(
                d.info()
                    .driver
                    .contains(&format!("{lanes}-lane vector forms")),
                "{}",
                d.info().driver
            );
        }
    }
    let e = Device::cpu_with_lanes(Forms::Vector, 12)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("12 lanes per block") && e.contains("[8, 16, 32]"),
        "{e}"
    );
}

/// A CPU device counts each kernel's dispatches by the form that ran them (`cohort render`
/// prints them): host forms only under `Forms::Host`; vector forms only under
/// `Forms::Vector`, where libLLVM is there, except for a kernel with subgroup operations,
/// which has no vector form; every dispatch once under the measured choice. The other
/// backends have no forms to count.
#[test]
fn a_cpu_device_counts_the_dispatches_of_each_form() {
    use cohort::runtime::cpu::simd::{FormCount, Forms};
    use cohort_tests::kernels::saxpy::{saxpy, SaxpyParams};
    let run = |d: &Device| {
        let p = SaxpyParams { a: 2.0, n: 200 };
        let x = d.upload(&[1.0f32; 200]).unwrap();
        let y = d.upload(&[0.5f32; 200]).unwrap();
        let out = d.alloc::<UVec4>(128).unwrap();
        for _ in 0..5 {
            saxpy::launch(d, 200u32, &p, &x, &y).unwrap();
            divergent_subgroups::launch(d, 128u32, &out).unwrap();
        }
        assert_eq!(d.read(&y).unwrap()[199], 0.5 + 5.0 * 2.0);
        d.form_counts()
    };
    let named = |counts: &[FormCount], prefix: &str| -> FormCount {
        let c = counts.iter().find(|c| c.kernel.starts_with(prefix));
        c.unwrap_or_else(|| panic!("no count for {prefix}: {counts:?}"))
            .clone()
    };
    let host = run(&Device::cpu_with(Forms::Host).unwrap());
    assert_eq!(host.len(), 2, "{host:?}");
    for k in ["saxpy", "divergent_subgroups"] {
        let c = named(&host, k);
        assert_eq!(
            (c.vector, c.host, c.pending, c.host_only),
            (0, 5, 0, 0),
            "{c:?}"
        );
    }
    let measured = run(&Device::cpu_with(Forms::Measured).unwrap());
    let c = named(&measured, "saxpy");
    assert_eq!(c.vector + c.host + c.pending + c.host_only, 5, "{c:?}");
    if cohort::runtime::cpu::simd::llvm_library().is_ok() {
        let vector = run(&Device::cpu_with(Forms::Vector).unwrap());
        let c = named(&vector, "saxpy");
        assert_eq!(
            (c.vector, c.host, c.pending, c.host_only),
            (5, 0, 0, 0),
            "{c:?}"
        );
        let c = named(&vector, "divergent_subgroups");
        assert_eq!(
            (c.vector, c.host, c.pending, c.host_only),
            (0, 0, 0, 5),
            "{c:?}"
        );
        let c = named(&measured, "divergent_subgroups");
        assert_eq!(c.host_only, 5, "{c:?}");
    }
    for d in common::devices() {
        if d.info().backend != BackendKind::Cpu {
            assert!(d.form_counts().is_empty());
        }
    }
}

/// Which kernels the CPU backend runs as coroutines: those whose invocations wait for each
/// other (barriers, subgroup operations, `group_any` above thread level). `group_share`
/// alone makes none wait at any level, because each invocation computes its group's
/// value; a coherent kernel that only shares values runs as a plain loop.
#[test]
fn only_waiting_operations_make_a_kernel_synchronise() {
    use cohort_tests::kernels::group_pick::group_pick;
    use cohort_tests::kernels::group_vote::group_vote;
    let synchronises = |built: &cohort::ir::BuiltKernel| {
        cohort::emit::emit(built)
            .expect("the kernel builds")
            .compiled
            .synchronises
    };
    for group in [Group::Thread, Group::Warp, Group::Block(256), Group::Grid] {
        let share = cohort::Spec::portable(&group_pick::INFO, group);
        assert!(
            !synchronises(&group_pick::build(&share)),
            "group_share at {group:?}"
        );
        if group != Group::Grid {
            let vote = cohort::Spec::portable(&group_vote::INFO, group);
            assert_eq!(
                synchronises(&group_vote::build(&vote)),
                group != Group::Thread,
                "group_any at {group:?}"
            );
        }
    }
    let barriers = cohort::Spec::portable(&panics_between_barriers::INFO, Group::Thread);
    assert!(synchronises(&panics_between_barriers::build(&barriers)));
    let subgroups = cohort::Spec::portable(&divergent_subgroups::INFO, Group::Thread);
    assert!(synchronises(&divergent_subgroups::build(&subgroups)));
}

/// Two vectors: a struct of eight words, which the vector form moves as rows where the
/// lanes' elements lie apart.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Pair {
    pub a: Vec4,
    pub b: Vec4,
}

/// Reads and writes at `order[gi]` under a divergent condition: where a block's lanes
/// land on consecutive elements the vector form moves them with one wide masked load or
/// store, elsewhere it gathers and scatters; both must touch exactly the elements the
/// host form touches. Scattered `xs[j]` and `out2[j]` (eight words) move as one row per
/// lane, transposed; `xs[j].b` (four) gathers; `xs[j].a.y` reads one member of each
/// element (a sparse wide load); `xs[3]` is one element for every lane.
#[kernel(workgroup = 64)]
pub fn permuted_copies(
    #[builtin(global_index)] gi: u32,
    order: &[u32],
    xs: &[Pair],
    ys: &[u32],
    out2: &mut [Pair],
    out1: &mut [u32],
) {
    let j = order[gi as usize] as usize;
    if j % 3 != 1 {
        let v = xs[j];
        out2[j] = Pair {
            a: v.a * 2.0 + Vec4::splat(ys[j] as f32) + xs[3].a,
            b: xs[j].b - v.a,
        };
        out1[j] = ys[j] + xs[j].a.y.to_bits();
    }
}

/// Four invocations in turn store to one element, a struct moved as rows in the vector
/// form: the element keeps the last one's value, as in the host form, which runs a
/// workgroup's invocations in order (on a GPU the winner is unspecified).
#[kernel(workgroup = 64)]
pub fn shared_stores(#[builtin(global_index)] gi: u32, xs: &[Pair], out2: &mut [Pair]) {
    let v = xs[gi as usize];
    out2[(gi / 4) as usize] = Pair {
        a: v.a + Vec4::splat(gi as f32),
        b: v.b,
    };
}

#[test]
fn lanes_that_store_to_one_element_leave_the_last_ones_value_in_both_forms() {
    use cohort::runtime::cpu::simd::Forms;
    let n = 256u32;
    let xs: Vec<Pair> = (0..n)
        .map(|i| Pair {
            a: Vec4::new(i as f32, 2.0 * i as f32, -(i as f32), 0.5),
            b: Vec4::splat(1.0 + i as f32),
        })
        .collect();
    let want: Vec<Pair> = (0..n / 4)
        .map(|e| {
            let last = 4 * e + 3;
            Pair {
                a: xs[last as usize].a + Vec4::splat(last as f32),
                b: xs[last as usize].b,
            }
        })
        .collect();
    for forms in [Forms::Host, Forms::Vector] {
        let d = Device::cpu_with(forms).unwrap();
        let xs_b = d.upload(&xs).unwrap();
        let out2 = d.alloc::<Pair>((n / 4) as usize).unwrap();
        shared_stores::launch(&d, n, &xs_b, &out2).unwrap();
        assert_eq!(d.read(&out2).unwrap(), want, "{forms:?}");
    }
}

/// The orders `permuted_copies` runs with, over `n` (a multiple of 16) elements: blocks of
/// eight in place, blocks moved to the other half of their sixteen (consecutive, another
/// base), halves swapped within a block (not consecutive), reversed, and a shuffle.
fn orders(n: u32) -> Vec<(&'static str, Vec<u32>)> {
    let mut rng = common::Rng(0x9e37_79b9);
    let mut shuffled: Vec<u32> = (0..n).collect();
    for i in (1..n as usize).rev() {
        let k = rng.next_u32() as usize % (i + 1);
        shuffled.swap(i, k);
    }
    vec![
        ("identity", (0..n).collect()),
        ("blocks moved", (0..n).map(|i| i ^ 8).collect()),
        ("halves swapped", (0..n).map(|i| i ^ 4).collect()),
        ("reversed", (0..n).rev().collect()),
        ("shuffled", shuffled),
    ]
}

#[test]
fn consecutive_and_scattered_accesses_touch_what_the_host_form_touches() {
    let n = 1024u32;
    let xs: Vec<Pair> = (0..n)
        .map(|i| Pair {
            a: Vec4::new(i as f32, -(i as f32), 0.5 * i as f32, 1.0e6 + i as f32),
            b: Vec4::new(3.0 * i as f32, 0.25, -1.5 * i as f32, i as f32 * i as f32),
        })
        .collect();
    let ys: Vec<u32> = (0..n).map(|i| i * 7 + 3).collect();
    let sentinel = Pair {
        a: Vec4::splat(-7.0),
        b: Vec4::splat(-9.0),
    };
    for (what, order) in orders(n) {
        // Untouched elements keep their sentinel: a store must not write masked-off lanes.
        let mut want2 = vec![sentinel; n as usize];
        let mut want1 = vec![0xdead_beefu32; n as usize];
        for &j in &order {
            let j = j as usize;
            if j % 3 != 1 {
                want2[j] = Pair {
                    a: xs[j].a * 2.0 + Vec4::splat(ys[j] as f32) + xs[3].a,
                    b: xs[j].b - xs[j].a,
                };
                want1[j] = ys[j] + xs[j].a.y.to_bits();
            }
        }
        for d in common::devices() {
            let order_b = d.upload(&order).unwrap();
            let xs_b = d.upload(&xs).unwrap();
            let ys_b = d.upload(&ys).unwrap();
            let out2 = d.upload(&vec![sentinel; n as usize]).unwrap();
            let out1 = d.upload(&vec![0xdead_beefu32; n as usize]).unwrap();
            permuted_copies::launch(&d, n, &order_b, &xs_b, &ys_b, &out2, &out1).unwrap();
            let name = d.info().adapter_name.clone();
            assert_eq!(d.read(&out2).unwrap(), want2, "{what}, {name}");
            assert_eq!(d.read(&out1).unwrap(), want1, "{what}, {name}");
        }
    }
}

/// A per-lane index into a vector value.
#[kernel(workgroup = 64)]
pub fn picks_a_component(#[builtin(global_index)] gi: u32, ks: &[u32], out: &mut [f32]) {
    let v = Vec4::new(1.0, 2.0, 3.0, 4.0);
    out[gi as usize] = v[ks[gi as usize] as usize];
}

#[test]
fn a_vector_index_out_of_range_is_an_error_in_both_forms() {
    use cohort::runtime::cpu::simd::Forms;
    for forms in [Forms::Host, Forms::Vector] {
        let d = Device::cpu_with(forms).unwrap();
        let ks: Vec<u32> = (0..64).map(|i| i % 4).collect();
        let ks_b = d.upload(&ks).unwrap();
        let out = d.alloc::<f32>(64).unwrap();
        picks_a_component::launch(&d, 64u32, &ks_b, &out).unwrap();
        let want: Vec<f32> = ks.iter().map(|&k| (k + 1) as f32).collect();
        assert_eq!(d.read(&out).unwrap(), want, "{forms:?}");
        // One lane past the end, in the middle of a block.
        let mut bad = ks.clone();
        bad[13] = 4;
        let bad_b = d.upload(&bad).unwrap();
        let err = picks_a_component::launch(&d, 64u32, &bad_b, &out).unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("picks_a_component") && msg.contains("index out of bounds"),
            "{forms:?}: {msg}"
        );
    }
}

/// A group's shared draw of a direction (trigonometry and a square root, as a coherent
/// sampler's), written with the invocation's index beside it.
#[kernel(workgroup = 64, group = Warp)]
pub fn shared_direction(#[builtin(global_index)] gi: u32, p: &PickParams, out: &mut [Vec4]) {
    let d = group_share(|group| {
        let h = hash(p.seed ^ group);
        let phi = (h >> 8) as f32 * (std::f32::consts::TAU / 16_777_216.0);
        let z = (h & 0xff) as f32 / 127.5 - 1.0;
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    });
    let i = gi as usize;
    if i < p.n as usize {
        out[i] = d.extend(gi as f32);
    }
}

/// At warp and block level the CPU backend's kernels compute each group's shared value in
/// every invocation (`Spec::recompute_group_share`), so they have a vector form, and both
/// CPU forms give the host run's bits: one value per group, the leader's.
#[test]
fn group_shares_run_in_the_vector_form_with_the_leaders_bits() {
    use cohort::runtime::cpu::simd::Forms;
    use cohort::Group;
    let n = 1000u32;
    let p = PickParams { seed: 0x5eed, n };
    for group in [Group::Warp, Group::Block(64), Group::Block(256)] {
        let mut want = vec![Vec4::ZERO; n as usize];
        let wg = match group {
            Group::Block(b) => b,
            _ => 64,
        };
        cohort::host::for_each_invocation(n, wg, group, |inv| {
            shared_direction(inv.global_index, &p, &mut want)
        });
        let groups: std::collections::HashSet<_> = want
            .iter()
            .map(|v| v.truncate().to_array().map(f32::to_bits))
            .collect();
        let per = match group {
            Group::Block(b) => b,
            _ => 32,
        };
        assert_eq!(groups.len(), n.div_ceil(per) as usize, "{group:?}");
        for forms in [Forms::Host, Forms::Vector] {
            let d = Device::cpu_with(forms).unwrap();
            let spec = shared_direction::spec(&d, Some(group));
            assert!(spec.recompute_group_share, "{group:?}");
            if let Err(e) = common::vector_form(&shared_direction::build(&spec), "shared_direction")
            {
                panic!("{group:?}: no vector form: {e}");
            }
            let out = d.upload(&vec![Vec4::splat(-1.0); n as usize]).unwrap();
            shared_direction::launch_spec(&d, &spec, n, &p, &out).unwrap();
            let got = d.read(&out).unwrap();
            assert_eq!(bits(&got), bits(&want), "{group:?}, {forms:?}");
        }
    }
}

/// The argument of invocation `i` of `transcendentals`, from `xs`: its first half the
/// values, its second half their negations. Each value (at `i / 32`) fills four vector
/// blocks of 8 lanes, one of each kind (`i / 8 % 4`): 0, every lane alike (as a group's
/// shared draw is at warp and block level); 1, lanes apart; 2, alike but for lane 7, which
/// has the value negated (so +0 beside -0, and NaN's sign flipped; read from the buffer,
/// so that LLVM cannot move the negation past an odd function); 3, the odd lanes alike and
/// the even lanes apart, where only the odd lanes run (see the kernel).
#[kernel_fn]
pub fn transcendental_arg(i: usize, xs: &[f32]) -> f32 {
    let half = xs.len() / 2;
    let j = i / 32;
    let kind = i / 8 % 4;
    let lane = i % 8;
    let mut x = xs[j];
    if kind == 1 || (kind == 3 && lane % 2 == 0) {
        x = xs[(j * 8 + lane) % half];
    } else if kind == 2 && lane == 7 {
        x = xs[half + j];
    }
    x
}

/// The second argument (of `powf` and `atan2`) of invocation `i`: the next of `xs`, or
/// the one after it for lane 6 of a block of kind 2.
#[kernel_fn]
pub fn transcendental_y(i: usize, xs: &[f32]) -> f32 {
    let mut j = i / 32 + 1;
    if i / 8 % 4 == 2 && i % 8 == 6 {
        j += 1;
    }
    xs[j % (xs.len() / 2)]
}

/// Transcendentals of `transcendental_arg`: the vector form calls each function once for
/// a block whose running lanes pass the same bits, once per lane otherwise. In blocks of
/// kind 3 the even lanes (lane 0 among them) skip the functions, so that the odd lanes
/// alone decide; in blocks of kind 2 lane 6 has its own second argument `y`.
#[kernel(workgroup = 64)]
pub fn transcendentals(
    #[builtin(global_index)] gi: u32,
    xs: &[f32],
    out: &mut [Vec4],
    odd: &mut [Vec4],
) {
    let i = gi as usize;
    let x = transcendental_arg(i, xs);
    let y = transcendental_y(i, xs);
    let mut r = Vec4::splat(-7.0);
    // Odd functions, each alone, so that the sign of a zero result shows.
    let mut o = Vec4::splat(-7.0);
    if i / 8 % 4 != 3 || i % 2 == 1 {
        o = Vec4::new(x.sin(), x.tan(), x.atan(), x.asin());
        let a = x.sin() + x.cos() * 2.0;
        let b = x.exp() + x.exp2() * 0.5 + x.abs().ln() + x.abs().log2() * 0.25;
        let c = x.abs().powf(y) + x.tan() + x.atan() * 0.5 + x.atan2(y);
        let d = x.acos() + x.asin() * 3.0 + (x * 0.5).cos();
        r = Vec4::new(a, b, c, d);
    }
    out[i] = r;
    odd[i] = o;
}

/// Every transcendental the vector form lowers (LLVM's intrinsics and libm calls), over
/// blocks of equal, of distinct and of nearly equal arguments with edge values (NaN, the
/// infinities, -0, subnormals, the extremes, past `exp`'s range), gives the host run's
/// bits in both CPU forms.
#[test]
fn transcendentals_of_uniform_and_varying_arguments_keep_their_bits() {
    use cohort::runtime::cpu::simd::Forms;
    let mut xs = vec![
        0.0f32,
        -0.0,
        1.0,
        -1.0,
        0.5,
        -0.75,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MIN_POSITIVE,
        -f32::MIN_POSITIVE * 0.5,
        f32::MAX,
        f32::MIN,
        88.7,
        -103.9,
        1.0e-20,
        std::f32::consts::PI,
        std::f32::consts::FRAC_PI_2,
        100.0,
        -0.3,
    ];
    let mut rng = common::Rng(0x1234_5678);
    while xs.len() < 256 {
        xs.push((rng.next_u32() as f32 / u32::MAX as f32 - 0.5) * 8.0);
    }
    let n = 32 * xs.len() as u32;
    xs.extend(xs.clone().into_iter().map(|x| -x));
    let mut want = vec![Vec4::ZERO; n as usize];
    let mut want_odd = vec![Vec4::ZERO; n as usize];
    cohort::host::for_each_invocation(n, 64, cohort::Group::Thread, |inv| {
        transcendentals(inv.global_index, &xs, &mut want, &mut want_odd)
    });
    let want: Vec<[Vec4; 2]> = want
        .into_iter()
        .zip(want_odd)
        .map(|(a, b)| [a, b])
        .collect();
    for forms in [Forms::Host, Forms::Vector] {
        let d = Device::cpu_with(forms).unwrap();
        let spec = transcendentals::spec(&d, None);
        if let Err(e) = common::vector_form(&transcendentals::build(&spec), "transcendentals") {
            panic!("no vector form: {e}");
        }
        let xs_b = d.upload(&xs).unwrap();
        let out = d.alloc::<Vec4>(n as usize).unwrap();
        let odd = d.alloc::<Vec4>(n as usize).unwrap();
        transcendentals::launch(&d, n, &xs_b, &out, &odd).unwrap();
        let (got, got_odd) = (d.read(&out).unwrap(), d.read(&odd).unwrap());
        let got: Vec<[Vec4; 2]> = got.into_iter().zip(got_odd).map(|(a, b)| [a, b]).collect();
        if let Some(i) = (0..n as usize).find(|&i| bits(&got[i]) != bits(&want[i])) {
            panic!(
                "{forms:?}: invocation {i} (block kind {}, x = {}, y = {}): {:?} against the host's {:?}",
                i / 8 % 4,
                transcendental_arg(i, &xs),
                transcendental_y(i, &xs),
                got[i],
                want[i]
            );
        }
    }
}

/// Integer quotients and remainders, unsigned and signed, by `bs[gi / 8]` (one divisor for
/// a whole vector block, as `patch / m` in the coherent samplers) and by `bs[gi]`.
#[kernel(workgroup = 64)]
pub fn quotients(#[builtin(global_index)] gi: u32, xs: &[u32], bs: &[u32], out: &mut [UVec4]) {
    let i = gi as usize;
    let a = xs[i];
    let b = if i % 16 < 8 { bs[i / 8] } else { bs[i] };
    let sa = a as i32;
    let sb = b as i32;
    out[i] = UVec4::new(a / b, a % b, (sa / sb) as u32, (sa % sb) as u32);
}

/// The vector form divides in `f64` where the divisor is not a constant; its quotients and
/// remainders are the host's exactly: at the extremes, by 0, `MIN / -1`, and at and around
/// multiples of divisors of every magnitude (where a rounded quotient would show).
#[test]
fn integer_division_in_the_vector_form_is_exact() {
    use cohort::runtime::cpu::simd::Forms;
    let edges = [
        0u32,
        1,
        2,
        3,
        7,
        0x7fff_ffff,
        0x8000_0000,
        0x8000_0001,
        u32::MAX - 1,
        u32::MAX,
    ];
    let (mut xs, mut bs) = (Vec::new(), Vec::new());
    for &a in &edges {
        for &b in &edges {
            xs.push(a);
            bs.push(b);
        }
    }
    let mut rng = common::Rng(0xd1d1);
    while xs.len() < 8192 {
        let b = (rng.next_u32() >> (rng.next_u32() % 32)).max(1);
        let k = rng.next_u32() / b.max(1);
        let m = k.wrapping_mul(b);
        for a in [m, m.wrapping_sub(1), m.wrapping_add(b - 1), rng.next_u32()] {
            xs.push(a);
            bs.push(b);
        }
    }
    let n = xs.len() as u32;
    let mut want = vec![UVec4::ZERO; n as usize];
    cohort::host::for_each_invocation(n, 64, cohort::Group::Thread, |inv| {
        quotients(inv.global_index, &xs, &bs, &mut want)
    });
    let d = Device::cpu_with(Forms::Vector).unwrap();
    let (x, b, out) = (
        d.upload(&xs).unwrap(),
        d.upload(&bs).unwrap(),
        d.alloc::<UVec4>(n as usize).unwrap(),
    );
    quotients::launch(&d, n, &x, &b, &out).unwrap();
    let got = d.read(&out).unwrap();
    if let Some(i) = (0..n as usize).find(|&i| got[i] != want[i]) {
        let b = if i % 16 < 8 { bs[i / 8] } else { bs[i] };
        panic!(
            "invocation {i}, {} by {b}: {} against the host's {}",
            xs[i], got[i], want[i]
        );
    }
}

/// The bits of `v`, a NaN's sign and payload aside (unspecified, docs/LANGUAGE.md section 4).
fn bits(v: &[Vec4]) -> Vec<[u32; 4]> {
    v.iter()
        .map(|x| {
            x.to_array()
                .map(|c| if c.is_nan() { u32::MAX } else { c.to_bits() })
        })
        .collect()
}

/// Atomic adds the vector form makes once per block (every running lane alike: one
/// address, one value) beside those it makes lane by lane (values or addresses apart),
/// each returning the old value.
#[kernel(workgroup = 64)]
pub fn counters(#[builtin(global_index)] gi: u32, counts: &[AtomicU32], olds: &mut [UVec4]) {
    let i = gi as usize;
    if i >= olds.len() {
        return;
    }
    let a = counts[0].fetch_add(3, Ordering::Relaxed);
    let mut b = u32::MAX;
    if i % 3 != 0 {
        b = counts[1].fetch_sub(5, Ordering::Relaxed);
    }
    let c = counts[2].fetch_add(gi % 4, Ordering::Relaxed);
    let d = counts[3 + i % 2].fetch_add(1, Ordering::Relaxed);
    olds[i] = UVec4::new(a, b, c, d);
}

/// Counts whose old values no invocation reads (the vector form adds them once per run
/// of workgroups), beside an atomic load and a read add of counters just added to.
#[kernel(workgroup = 64)]
pub fn tallies(#[builtin(global_index)] gi: u32, counts: &[AtomicU32], seen: &mut [UVec2]) {
    let i = gi as usize;
    if i >= seen.len() {
        return;
    }
    counts[0].fetch_add(1, Ordering::Relaxed);
    if i % 3 != 0 {
        counts[1].fetch_sub(2, Ordering::Relaxed);
    }
    // One address per workgroup: a run's pending sum moves from counter to counter.
    counts[2 + (i / 64) % 3].fetch_add(7, Ordering::Relaxed);
    counts[5].fetch_add(1, Ordering::Relaxed);
    let loaded = counts[5].load(Ordering::Relaxed);
    counts[6].fetch_add(1, Ordering::Relaxed);
    let read = counts[6].fetch_add(0, Ordering::Relaxed);
    seen[i] = UVec2::new(loaded, read);
}

/// Adds whose old values are unread end at the exact sums in both CPU forms, wherever
/// the vector form defers them, and an invocation's atomic load or read add after its own
/// add sees that add.
#[test]
fn deferred_atomic_adds_end_at_the_sums_and_an_invocation_sees_its_own() {
    use cohort::runtime::cpu::simd::Forms;
    for n in [1u32, 63, 1003, 64 * 97 + 5] {
        for forms in [Forms::Host, Forms::Vector] {
            let d = Device::cpu_with(forms).unwrap();
            let spec = tallies::spec(&d, None);
            let ir = common::vector_form(&tallies::build(&spec), "tallies")
                .unwrap_or_else(|e| panic!("no vector form: {e}"));
            assert!(
                ir.contains("cohort_flush"),
                "no deferred adds in the vector form"
            );
            let counts = d.alloc::<u32>(7).unwrap();
            let seen = d.alloc::<UVec2>(n as usize).unwrap();
            tallies::launch(&d, n, &counts, &seen).unwrap();
            let (counts, seen) = (d.read(&counts).unwrap(), d.read(&seen).unwrap());
            let subs = (0..n).filter(|i| i % 3 != 0).count() as u32;
            let per_group = |k: u32| 7 * (0..n).filter(|i| (i / 64) % 3 == k).count() as u32;
            let want = [
                n,
                0u32.wrapping_sub(2 * subs),
                per_group(0),
                per_group(1),
                per_group(2),
                n,
                n,
            ];
            assert_eq!(counts, want, "{forms:?}, {n} invocations");
            if let Some((i, s)) = seen
                .iter()
                .enumerate()
                .find(|(_, s)| s.x == 0 || s.y == 0 || s.x > n || s.y > n)
            {
                panic!("{forms:?}, {n} invocations: invocation {i} saw {s:?}");
            }
        }
    }
}

/// Each counter ends at the sum of what was added, and the old values that the adds
/// returned are each step of it exactly once (so a block that adds once hands its lanes
/// consecutive old values), in both CPU forms, over a dispatch that ends inside a block.
#[test]
fn atomic_adds_return_every_old_value_once() {
    use cohort::runtime::cpu::simd::Forms;
    let n = 1003u32;
    for forms in [Forms::Host, Forms::Vector] {
        let d = Device::cpu_with(forms).unwrap();
        let spec = counters::spec(&d, None);
        if let Err(e) = common::vector_form(&counters::build(&spec), "counters") {
            panic!("no vector form: {e}");
        }
        let counts = d.alloc::<u32>(5).unwrap();
        let olds = d.alloc::<UVec4>(n as usize).unwrap();
        counters::launch(&d, n, &counts, &olds).unwrap();
        let (counts, olds) = (d.read(&counts).unwrap(), d.read(&olds).unwrap());
        let sorted = |f: &dyn Fn(usize, &UVec4) -> Option<u32>| {
            let mut v: Vec<u32> = olds
                .iter()
                .enumerate()
                .filter_map(|(i, o)| f(i, o))
                .collect();
            v.sort_unstable();
            v
        };
        let a = sorted(&|_, o| Some(o.x));
        assert_eq!(
            a,
            (0..n).map(|k| 3 * k).collect::<Vec<_>>(),
            "{forms:?}: alike"
        );
        assert_eq!(counts[0], 3 * n, "{forms:?}");
        let subs = (0..n).filter(|i| i % 3 != 0).count() as u32;
        let mut want_b: Vec<u32> = (0..subs).map(|k| 0u32.wrapping_sub(5 * k)).collect();
        want_b.sort_unstable();
        assert_eq!(
            sorted(&|i, o| (i % 3 != 0).then_some(o.y)),
            want_b,
            "{forms:?}: sub"
        );
        assert!(olds.iter().step_by(3).all(|o| o.y == u32::MAX), "{forms:?}");
        assert_eq!(counts[1], 0u32.wrapping_sub(5 * subs), "{forms:?}");
        assert_eq!(counts[2], (0..n).map(|g| g % 4).sum::<u32>(), "{forms:?}");
        for parity in 0..2 {
            let m = (0..n as usize).filter(|i| i % 2 == parity).count() as u32;
            let got = sorted(&|i, o| (i % 2 == parity).then_some(o.w));
            assert_eq!(got, (0..m).collect::<Vec<_>>(), "{forms:?}: apart");
            assert_eq!(counts[3 + parity], m, "{forms:?}");
        }
    }
}

/// An IR-only kernel (no Rust source, so no host form: the CPU backend runs its vector
/// form) that indexes a buffer with an `i32`, as a naga module from another front end
/// may: `out[gi] = xs[gi as i32 + offsets[gi]]`.
fn signed_index_kernel() -> cohort::runtime::KernelArtifact {
    use cohort::ir::{self, builtin, AsPlace, Buffer};
    use cohort::{Group, KernelInfo, Spec};
    static INFO: KernelInfo = common::ir_kernel_info("signed_index", file!(), line!());
    let built = ir::build_kernel(&INFO, Spec::portable(&INFO, Group::Thread), || {
        let gi = builtin::global_index();
        let offsets = Buffer::<i32>::declare("offsets", false);
        let xs = Buffer::<u32>::declare("xs", false);
        let out = Buffer::<u32>::declare("out", true);
        let i = ir::cast::<i32, u32>(gi) + ir::place_index(offsets.as_place(), gi).get();
        let x = ir::place_index(xs.as_place(), i).get();
        ir::place_index(out.as_place(), gi).set(x);
    });
    cohort::emit::compile(&built, "signed_index".into()).unwrap()
}

/// A signed index is sign-extended to the vector form's 64-bit offsets: one below zero is
/// out of bounds (the bound test `offset + size <= len` would wrap to pass at -1 element,
/// reading the 4 bytes before the buffer), one within bounds reads its element.
#[test]
fn a_signed_index_below_zero_is_out_of_bounds_in_the_vector_form() {
    use cohort::runtime::cpu::simd::Forms;
    use cohort::runtime::{BufferArg, Dispatch};
    let art = signed_index_kernel();
    let d = Device::cpu_with(Forms::Vector).unwrap();
    let xs: Vec<u32> = (0..64).map(|i| 100 + i).collect();
    let xs_b = d.upload(&xs).unwrap();
    let out = d.alloc::<u32>(64).unwrap();
    let run = |offsets: &[i32]| {
        let offsets_b = d.upload(offsets).unwrap();
        let args: Vec<BufferArg> = vec![offsets_b.arg(), xs_b.arg(), out.arg()];
        d.dispatch(&art, &args, Dispatch::Groups([1, 1, 1]))
    };
    // Lane 5 reads element 0, lane 63 element 1: in bounds, through a gather.
    let mut offsets = vec![0i32; 64];
    offsets[5] = -5;
    offsets[63] = -62;
    run(&offsets).unwrap();
    let mut want = xs.clone();
    want[5] = 100;
    want[63] = 101;
    assert_eq!(d.read(&out).unwrap(), want);
    // Element -1 (whose end, byte offset 0, is within the buffer), then far below zero.
    for below in [-10, i32::MIN + 9] {
        offsets[9] = below;
        let err = run(&offsets).expect_err("an index below zero must fail");
        let msg = err.to_string();
        assert!(
            msg.contains("signed_index") && msg.contains("index out of bounds"),
            "{below}: {msg}"
        );
    }
}

/// An `if` whose arm is a few register operations: the vector form runs it under its mask
/// without testing for a lane that takes it (`cpu::simd` `straight`).
#[kernel(workgroup = 64)]
pub fn small_arm(#[builtin(global_index)] gi: u32, xs: &[f32], out: &mut [f32]) {
    let i = gi as usize;
    let x = xs[i];
    let mut y = -x;
    if x > 0.5 {
        y = x * 2.0 + 1.0;
    }
    out[i] = y;
}

/// The same kernel without the `if`.
#[kernel(workgroup = 64)]
pub fn no_arm(#[builtin(global_index)] gi: u32, xs: &[f32], out: &mut [f32]) {
    let i = gi as usize;
    let x = xs[i];
    out[i] = -x;
}

/// Lanes that take no arm (whole blocks of them, and blocks where some do) keep their
/// values when the arm runs without its test, on every device; and the vector form has no
/// more lane tests (mask reductions) than without the `if`.
#[test]
fn small_arms_run_without_a_lane_test() {
    // Blocks of all-small, all-large and mixed values, whatever the block width.
    let xs: Vec<f32> = (0..256)
        .map(|i| match i / 64 {
            0 => 0.25,
            1 => 0.75,
            _ => (i % 3) as f32 * 0.4,
        })
        .collect();
    let want: Vec<f32> = xs
        .iter()
        .map(|&x| if x > 0.5 { x * 2.0 + 1.0 } else { -x })
        .collect();
    for d in common::devices() {
        let xb = d.upload(&xs).unwrap();
        let out = d.alloc::<f32>(xs.len()).unwrap();
        small_arm::launch(&d, xs.len() as u32, &xb, &out).unwrap();
        assert_eq!(d.read(&out).unwrap(), want, "{}", d.info().driver);
    }
    let d = Device::cpu_with(cohort::runtime::cpu::simd::Forms::Vector).unwrap();
    let tests = |ir: String| ir.matches("call i1 @llvm.vector.reduce.or").count();
    let ir = |m, name: &str| common::vector_form(&m, name).unwrap();
    let small = tests(ir(
        small_arm::build(&small_arm::spec(&d, None)),
        "small_arm",
    ));
    let none = tests(ir(no_arm::build(&no_arm::spec(&d, None)), "no_arm"));
    assert_eq!(small, none, "lane tests with the small arm and without it");
}
