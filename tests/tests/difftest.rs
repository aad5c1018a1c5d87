//! Cross-backend difftests: each kernel runs on wgpu (WGSL), on raw Vulkan (SPIR-V
//! through ash) and on the native CPU backend with the same inputs. The GPU backends must
//! agree with each other and, where the kernel has no cross-invocation communication,
//! with the host run of the same Rust function; the CPU backend runs that function, so
//! it must equal the host run exactly. Integer results are compared exactly; float results exactly
//! between backends unless stated, and within a bound stated at each comparison against
//! the host (GPU drivers may contract `a*b+c` into an FMA and use their own
//! transcendentals). The suite passes on lavapipe and on an NVIDIA H200 (BENCHMARKS.md).

mod common;
use cohort::host::for_each_invocation;
use cohort::runtime::Device;
use cohort::Group;
use common::*;
use glam::{UVec2, UVec4, Vec3, Vec4};
use std::sync::atomic::{AtomicU32, Ordering};

fn run_all<T: PartialEq + std::fmt::Debug>(name: &str, f: impl Fn(&Device) -> T) -> Vec<T> {
    let devs = devices();
    let outs: Vec<T> = devs.iter().map(&f).collect();
    for w in gpu_outputs(&devs, &outs).windows(2) {
        assert_eq!(w[0], w[1], "{name}: wgpu and Vulkan disagree");
    }
    outs
}

#[test]
fn saxpy_matches_host() {
    use cohort_tests::kernels::saxpy::*;
    let n = 1000u32;
    let mut rng = Rng(1);
    let x: Vec<f32> = (0..n).map(|_| rng.f32(-10.0, 10.0)).collect();
    let y0: Vec<f32> = (0..n).map(|_| rng.f32(-10.0, 10.0)).collect();
    let p = SaxpyParams { a: 1.5, n: n - 3 };
    let outs = run_all("saxpy", |d| {
        let xb = d.upload(&x).unwrap();
        let yb = d.upload(&y0).unwrap();
        saxpy::launch(d, n, &p, &xb, &yb).unwrap();
        d.read(&yb)
            .unwrap()
            .iter()
            .map(|v| v.to_bits())
            .collect::<Vec<_>>()
    });
    let mut host = y0.clone();
    for_each_invocation(n, saxpy::INFO.workgroup_size, Group::Thread, |inv| {
        if inv.global_index < n {
            saxpy(inv.global_index, &p, &x, &mut host)
        }
    });
    for o in outs {
        let o: Vec<f32> = o.into_iter().map(f32::from_bits).collect();
        // A driver may fuse a*x + y into one FMA (NVIDIA does): the product is then not
        // rounded, so results differ by up to one rounding of the terms, 2^-24 (|a x| + |y|),
        // which is many ulps of a result that cancels. Bound: twice that.
        for k in 0..n as usize {
            let bound = 2.0 * f32::EPSILON * (p.a * x[k]).abs().max(y0[k].abs());
            assert!(
                (o[k] - host[k]).abs() <= bound,
                "saxpy element {k}: {} vs {} (bound {bound})",
                o[k],
                host[k]
            );
        }
        assert_eq!(
            o[n as usize - 1],
            y0[n as usize - 1],
            "bounds check must leave the tail alone"
        );
    }
}

#[test]
fn structs_trace_spheres() {
    use cohort_tests::kernels::rays::*;
    let mut rng = Rng(7);
    let spheres: Vec<Sphere> = (0..8)
        .map(|_| Sphere {
            center: Vec3::new(rng.f32(-4.0, 4.0), rng.f32(-4.0, 4.0), rng.f32(5.0, 15.0)),
            radius: rng.f32(0.5, 2.0),
        })
        .collect();
    let rays_in: Vec<Ray> = (0..500)
        .map(|_| Ray {
            origin: Vec3::ZERO,
            tmin: 1e-3,
            dir: Vec3::new(rng.f32(-0.4, 0.4), rng.f32(-0.4, 0.4), 1.0).normalize(),
            tmax: 1e30,
        })
        .collect();
    let outs = run_all("trace_spheres", |d| {
        let r = d.upload(&rays_in).unwrap();
        let s = d.upload(&spheres).unwrap();
        let h = d.alloc::<Hit>(rays_in.len()).unwrap();
        trace_spheres::launch(d, rays_in.len() as u32, &r, &s, &h).unwrap();
        d.read(&h).unwrap()
    });
    let mut host = vec![Hit::default(); rays_in.len()];
    for_each_invocation(rays_in.len() as u32, 64, Group::Thread, |inv| {
        trace_spheres(inv.global_index, &rays_in, &spheres, &mut host)
    });
    let hits = host.iter().filter(|h| h.hit == 1).count();
    assert!(
        hits > 20 && hits < 490,
        "test scene should mix hits and misses, got {hits}"
    );
    for o in outs {
        for (g, h) in o.iter().zip(&host) {
            assert_eq!((g.hit, g.sphere), (h.hit, h.sphere));
            // The hit distance comes from b^2 - c, which cancels near grazing hits, and
            // drivers may contract it into FMAs: t agrees to 1e-4 relative, and the normal
            // built from it to 1e-3.
            assert!(
                (g.t - h.t).abs() <= 1e-4 * h.t.abs().max(1.0),
                "t: {} vs {}",
                g.t,
                h.t
            );
            assert_close(
                "normal",
                &g.normal.to_array(),
                &h.normal.to_array(),
                64,
                1e-3,
            );
        }
    }
}

#[test]
fn loops_collatz() {
    use cohort_tests::kernels::collatz::*;
    let seeds: Vec<u32> = (0..777u32).map(|i| i * 37 + 1).collect();
    let outs = run_all("collatz", |d| {
        let s = d.upload(&seeds).unwrap();
        let a = d.alloc::<u32>(seeds.len()).unwrap();
        let b = d.alloc::<u32>(seeds.len()).unwrap();
        collatz::launch(d, seeds.len() as u32, &s, &a, &b).unwrap();
        (d.read(&a).unwrap(), d.read(&b).unwrap())
    });
    let (mut ha, mut hb) = (vec![0u32; seeds.len()], vec![0u32; seeds.len()]);
    for_each_invocation(seeds.len() as u32, 64, Group::Thread, |inv| {
        collatz(inv.global_index, &seeds, &mut ha, &mut hb)
    });
    assert_eq!(ha[26 / 37], 0, "seed 1 takes no steps");
    for o in outs {
        assert_eq!(o, (ha.clone(), hb.clone()));
    }
}

#[test]
fn mut_helpers_sort4() {
    use cohort_tests::kernels::sort4::*;
    let mut rng = Rng(3);
    let v: Vec<Vec4> = (0..300)
        .map(|_| {
            Vec4::new(
                rng.f32(-200.0, 200.0),
                rng.f32(-9.0, 9.0),
                rng.f32(-9.0, 9.0),
                rng.f32(-200.0, 200.0),
            )
        })
        .collect();
    let outs = run_all("sort4", |d| {
        let b = d.upload(&v).unwrap();
        sort4::launch(d, v.len() as u32, &b).unwrap();
        d.read(&b).unwrap()
    });
    let mut host = v.clone();
    for_each_invocation(v.len() as u32, 32, Group::Thread, |inv| {
        sort4(inv.global_index, &mut host)
    });
    for x in &host {
        assert!(x.x <= x.y && x.y <= x.z, "not sorted: {x}");
    }
    for o in outs {
        assert_eq!(o, host);
    }
    let d = Device::cpu_with(cohort::runtime::cpu::simd::Forms::Vector).unwrap();
    has_vector_form(sort4::build(&sort4::spec(&d, None)), "sort4");
}

/// `&mut` helpers over a local array and its depth, each lane at its own depth: the same
/// digits on every device, and a vector form on the CPU backend (the helpers' pointers are
/// the caller's per-lane slots).
#[test]
fn mut_helpers_bit_stack() {
    use cohort_tests::kernels::sort4::*;
    let mut rng = Rng(5);
    let mut xs: Vec<u32> = (0..517).map(|_| rng.next_u32()).collect();
    xs.extend([0, 1, 0x80, 0xff, u32::MAX]);
    let outs = run_all("bit_stack", |d| {
        let xb = d.upload(&xs).unwrap();
        let out = d.alloc::<u32>(xs.len()).unwrap();
        bit_stack::launch(d, xs.len() as u32, &xb, &out).unwrap();
        d.read(&out).unwrap()
    });
    let mut host = vec![0u32; xs.len()];
    for_each_invocation(xs.len() as u32, 32, Group::Thread, |inv| {
        bit_stack(inv.global_index, &xs, &mut host)
    });
    let want = |x: u32| {
        (0..8)
            .rev()
            .filter(|b| (x >> b) & 1 != 0)
            .fold(1u32, |r, b| r * 8 + b)
    };
    for (i, &x) in xs.iter().enumerate() {
        assert_eq!(host[i], want(x), "host, x = {x:#x}");
    }
    for o in outs {
        assert_eq!(o, host);
    }
    let d = Device::cpu_with(cohort::runtime::cpu::simd::Forms::Vector).unwrap();
    has_vector_form(bit_stack::build(&bit_stack::spec(&d, None)), "bit_stack");
}

/// Panics unless the CPU backend lowers `module` to a vector form.
fn has_vector_form(module: cohort::compiler::ir::BuiltKernel, name: &str) {
    if let Err(e) = vector_form(&module, name) {
        panic!("{name}: no vector form: {e}");
    }
}

#[test]
fn generic_over_trait() {
    use cohort_tests::kernels::generic::*;
    let xs: Vec<f32> = (0..256).map(|i| i as f32 * 0.37 - 20.0).collect();
    fn run<C: Curve>(xs: &[f32]) -> Vec<Vec<f32>> {
        let outs = run_all("apply_curve", |d| {
            let x = d.upload(xs).unwrap();
            let y = d.alloc::<f32>(xs.len()).unwrap();
            apply_curve::launch::<C>(d, xs.len() as u32, &x, &y).unwrap();
            d.read(&y)
                .unwrap()
                .iter()
                .map(|v| v.to_bits())
                .collect::<Vec<_>>()
        });
        let mut host = vec![0f32; xs.len()];
        for_each_invocation(xs.len() as u32, 64, Group::Thread, |inv| {
            apply_curve::<C>(inv.global_index, xs, &mut host)
        });
        for o in &outs {
            let o: Vec<f32> = o.iter().map(|b| f32::from_bits(*b)).collect();
            assert_close("curve", &o, &host, 2, 1e-6);
        }
        vec![host]
    }
    let sq = run::<Square>(&xs);
    let tent = run::<Tent>(&xs);
    assert_ne!(sq, tent, "two strategies must give two kernels");
    let spec = cohort::Spec::portable(&apply_curve::INFO, Group::Thread);
    let a = cohort::emit::emit(&apply_curve::build::<Square>(&spec)).unwrap();
    let b = cohort::emit::emit(&apply_curve::build::<Tent>(&spec)).unwrap();
    assert_ne!(a.wgsl, b.wgsl);
}

/// A trait method generic over another strategy, called with two type arguments in one
/// kernel: two functions, not one reused (the device agrees with the host).
#[test]
fn generic_method_instances_are_distinct() {
    use cohort_tests::kernels::generic::*;
    let xs: Vec<f32> = (0..256).map(|i| i as f32 * 0.37 - 20.0).collect();
    let outs = run_all("apply_both", |d| {
        let x = d.upload(&xs).unwrap();
        let y = d.alloc::<f32>(xs.len()).unwrap();
        apply_both::launch::<Twice>(d, xs.len() as u32, &x, &y).unwrap();
        d.read(&y).unwrap()
    });
    let mut host = vec![0f32; xs.len()];
    for_each_invocation(xs.len() as u32, 64, Group::Thread, |inv| {
        apply_both::<Twice>(inv.global_index, &xs, &mut host)
    });
    // Square after square minus tent after tent: not zero, as one function reused for
    // both calls would make it.
    assert!(host.iter().any(|&v| v != 0.0));
    for o in &outs {
        assert_close("apply_both", o, &host, 2, 1e-6);
    }
}

#[test]
fn workgroup_reduction() {
    use cohort_tests::kernels::reduce::*;
    let input: Vec<u32> = (0..5000u32)
        .map(|i| i.wrapping_mul(2654435761) >> 20)
        .collect();
    let groups = input.len().div_ceil(256);
    let outs = run_all("reduce_sum", |d| {
        let i = d.upload(&input).unwrap();
        let s = d.alloc::<u32>(groups).unwrap();
        reduce_sum::launch(d, input.len() as u32, &i, &s).unwrap();
        d.read(&s).unwrap()
    });
    let expect: Vec<u32> = input.chunks(256).map(|c| c.iter().sum()).collect();
    for o in outs {
        assert_eq!(o, expect);
    }
}

#[test]
fn subgroup_ballot_and_scan() {
    use cohort_tests::kernels::subgroup_scan::*;
    let flags: Vec<u32> = (0..200u32).map(|i| ((i * 7 + 3) % 5 < 2) as u32).collect();
    for d in devices() {
        let sg = d.info().subgroup_size;
        let f = d.upload(&flags).unwrap();
        let (e, i, v) = (
            d.alloc::<u32>(200).unwrap(),
            d.alloc::<u32>(200).unwrap(),
            d.alloc::<u32>(200).unwrap(),
        );
        subgroup_scan::launch(&d, 200u32, &f, &e, &i, &v).unwrap();
        let (e, i, v) = (
            d.read(&e).unwrap(),
            d.read(&i).unwrap(),
            d.read(&v).unwrap(),
        );
        for (k, chunk) in flags.chunks(sg as usize).enumerate() {
            let base = k * sg as usize;
            let mut acc = 0;
            for (j, f) in chunk.iter().enumerate() {
                assert_eq!(e[base + j], acc, "exclusive at {}", base + j);
                acc += f;
                assert_eq!(i[base + j], acc, "inclusive at {}", base + j);
                let below: u32 = chunk[..j].iter().sum();
                let total: u32 = chunk.iter().sum();
                let full = chunk.len() == sg as usize;
                let expect = below
                    + (chunk[0] << 8)
                    + ((total > 0) as u32) * (1 << 16)
                    + ((total == sg) as u32 * (1 << 17))
                    + (total << 20)
                    + (sg << 26);
                if full {
                    assert_eq!(v[base + j], expect, "votes at {}", base + j);
                }
            }
        }
    }
}

#[test]
fn atomic_histogram() {
    use cohort_tests::kernels::histogram::*;
    let values: Vec<u32> = (0..4096u32)
        .map(|i| i.wrapping_mul(2654435761u32.wrapping_add(i)) % 1000 + 5)
        .collect();
    let outs = run_all("histogram", |d| {
        let v = d.upload(&values).unwrap();
        let bins = d.alloc::<u32>(16).unwrap();
        let stats = d.upload(&[0u32, u32::MAX, 0, 0]).unwrap();
        histogram::launch(d, values.len() as u32, &v, &bins, &stats).unwrap();
        (d.read(&bins).unwrap(), d.read(&stats).unwrap())
    });
    let bins: Vec<AtomicU32> = (0..16).map(|_| AtomicU32::new(0)).collect();
    let stats: Vec<AtomicU32> = [0, u32::MAX, 0, 0]
        .into_iter()
        .map(AtomicU32::new)
        .collect();
    for_each_invocation(values.len() as u32, 128, Group::Thread, |inv| {
        histogram(inv.global_index, &values, &bins, &stats)
    });
    let hb: Vec<u32> = bins.iter().map(|b| b.load(Ordering::Relaxed)).collect();
    let hs: Vec<u32> = stats.iter().map(|b| b.load(Ordering::Relaxed)).collect();
    assert_eq!(hb.iter().sum::<u32>(), values.len() as u32);
    for o in outs {
        assert_eq!(o, (hb.clone(), hs.clone()));
    }
}

/// Every group level from one source: each invocation gets its group leader's draw.
#[test]
fn group_levels_share_leader_value() {
    use cohort_tests::kernels::group_pick::*;
    let n = 1000u32;
    let p = PickParams { seed: 0xC0FFEE, n };
    for d in devices() {
        for group in [Group::Thread, Group::Warp, Group::Block(256), Group::Grid] {
            let out = d.alloc::<u32>(n as usize).unwrap();
            let spec = group_pick::spec(&d, Some(group));
            group_pick::launch_spec(&d, &spec, n, &p, &out).unwrap();
            let gpu = d.read(&out).unwrap();
            let mut host = vec![0u32; n as usize];
            for_each_invocation(n, spec.workgroup_size, group, |inv| {
                group_pick(inv.global_index, &p, &mut host)
            });
            assert_eq!(
                gpu,
                host,
                "{group:?} on {:?} ({})",
                d.info().backend,
                spec.suffix()
            );
            let distinct: std::collections::HashSet<_> = gpu.iter().collect();
            let expected = match group {
                Group::Thread => n as usize,
                Group::Warp => (n as usize).div_ceil(32),
                Group::Block(b) => (n as usize).div_ceil(b as usize),
                Group::Grid => 1,
            };
            assert_eq!(distinct.len(), expected, "{group:?}: one value per group");
        }
        // Both warp lowerings (subgroup broadcast where subgroups are 32 wide, workgroup
        // memory elsewhere) give the same result where the device supports them.
        let portable = cohort::Spec::portable(&group_pick::INFO, Group::Warp);
        let out = d.alloc::<u32>(n as usize).unwrap();
        group_pick::launch_spec(&d, &portable, n, &p, &out).unwrap();
        let mut host = vec![0u32; n as usize];
        for_each_invocation(n, 256, Group::Warp, |inv| {
            group_pick(inv.global_index, &p, &mut host)
        });
        assert_eq!(d.read(&out).unwrap(), host);
    }
}

/// `group_any` at every group level that can lower it: each invocation learns whether any
/// member of its group voted, the flag is fresh at every call, and both warp lowerings
/// agree. At grid level the kernel does not build, with an error naming it.
#[test]
fn group_any_is_per_group() {
    use cohort_tests::kernels::group_vote::*;
    let n = 4000u32;
    let mut rng = Rng(7);
    let values: Vec<u32> = (0..n).map(|_| rng.next_u32()).collect();
    // About one voter per 400 invocations: most warps have none, most blocks of 256 some.
    let p = VoteParams {
        threshold: u32::MAX / 400,
        n,
    };
    let expected = |group_of: &dyn Fn(u32) -> u32| -> Vec<u32> {
        let mut any = std::collections::HashMap::new();
        for i in 0..n {
            *any.entry(group_of(i)).or_insert(false) |= values[i as usize] < p.threshold;
        }
        (0..n)
            .map(|i| if any[&group_of(i)] { 0b101 } else { 0 })
            .collect()
    };
    for d in devices() {
        let vals = d.upload(&values).unwrap();
        let mut specs = vec![(Group::Thread, group_vote::spec(&d, Some(Group::Thread)))];
        specs.push((
            Group::Warp,
            cohort::Spec::portable(&group_vote::INFO, Group::Warp),
        ));
        specs.push((Group::Warp, group_vote::spec(&d, Some(Group::Warp))));
        specs.push((
            Group::Block(256),
            group_vote::spec(&d, Some(Group::Block(256))),
        ));
        specs.push((
            Group::Block(64),
            group_vote::spec(&d, Some(Group::Block(64))),
        ));
        for (group, spec) in specs {
            let out = d.alloc::<u32>(n as usize).unwrap();
            group_vote::launch_spec(&d, &spec, n, &p, &vals, &out).unwrap();
            let gpu = d.read(&out).unwrap();
            let want = match group {
                Group::Thread => expected(&|i| i),
                Group::Warp => expected(&|i| i / 32),
                Group::Block(b) => expected(&|i| i / b),
                Group::Grid => unreachable!(),
            };
            assert!(
                want.iter().any(|&w| w != 0) && want.contains(&0),
                "{group:?}: the inputs must give both outcomes"
            );
            assert_eq!(
                gpu,
                want,
                "{group:?} on {:?} ({})",
                d.info().backend,
                spec.suffix()
            );
        }
    }
    // On the host every invocation is its own group.
    let mut host = vec![0u32; n as usize];
    for_each_invocation(n, 256, Group::Thread, |inv| {
        group_vote(inv.global_index, &p, &values, &mut host)
    });
    let own: Vec<u32> = values
        .iter()
        .map(|&v| if v < p.threshold { 0b101 } else { 0 })
        .collect();
    assert_eq!(host, own);
    let err = match cohort::emit::emit(&group_vote::build(&cohort::Spec::portable(
        &group_vote::INFO,
        Group::Grid,
    ))) {
        Ok(_) => panic!("group_any built at grid level"),
        Err(e) => e,
    };
    let msg = err.to_string();
    assert_eq!(err.stage, "build");
    assert!(
        msg.contains("group_vote.rs")
            && msg.contains("kernel `group_vote`")
            && msg.contains("group_any"),
        "{msg}"
    );
    assert!(!msg.contains("compiler bug"), "{msg}");
}

#[test]
fn casts_and_bits() {
    use cohort_tests::kernels::bits::*;
    let mut rng = Rng(99);
    let input: Vec<u32> = (0..1000)
        .map(|_| rng.next_u32())
        .chain([0, 1, u32::MAX, 0x8000_0000])
        .collect();
    let outs = run_all("bits", |d| {
        let i = d.upload(&input).unwrap();
        let o = d.alloc::<UVec4>(input.len()).unwrap();
        bits::launch(d, input.len() as u32, &i, &o).unwrap();
        d.read(&o).unwrap()
    });
    let mut host = vec![UVec4::ZERO; input.len()];
    for_each_invocation(input.len() as u32, 64, Group::Thread, |inv| {
        bits(inv.global_index, &input, &mut host)
    });
    for o in outs {
        assert_eq!(o, host);
    }
}

#[test]
fn local_array_stack() {
    use cohort_tests::kernels::stack_walk::*;
    let mut rng = Rng(5);
    let qs: Vec<UVec2> = (0..400)
        .map(|_| {
            let a = rng.next_u32() % 1024;
            let b = rng.next_u32() % 1024;
            UVec2::new(a.min(b), a.max(b) + 1)
        })
        .collect();
    let outs = run_all("stack_walk", |d| {
        let q = d.upload(&qs).unwrap();
        let o = d.alloc::<u32>(qs.len()).unwrap();
        stack_walk::launch(d, qs.len() as u32, &q, &o).unwrap();
        d.read(&o).unwrap()
    });
    let mut host = vec![0u32; qs.len()];
    for_each_invocation(qs.len() as u32, 64, Group::Thread, |inv| {
        stack_walk(inv.global_index, &qs, &mut host)
    });
    for (q, h) in qs.iter().zip(&host) {
        let sum: u32 = (q.x..q.y).sum();
        assert_eq!(h & 0xfffff, sum & 0xfffff);
    }
    for o in outs {
        assert_eq!(o, host);
    }
}

/// Transcendentals: the backends run the same driver here, so they agree closely; the
/// host's libm differs by a few ulps (bound: 64 ulps, or 1e-5 absolute near zero).
#[test]
fn transcendental_math() {
    use cohort_tests::kernels::mathfns::*;
    let xs: Vec<f32> = (0..512).map(|i| (i as f32 - 256.0) * 0.03125).collect();
    let devs = devices();
    let outs: Vec<Vec<Vec4>> = devs
        .iter()
        .map(|d| {
            let x = d.upload(&xs).unwrap();
            let o = d.alloc::<Vec4>(xs.len()).unwrap();
            mathfns::launch(d, xs.len() as u32, &x, &o).unwrap();
            d.read(&o).unwrap()
        })
        .collect();
    let mut host = vec![Vec4::ZERO; xs.len()];
    for_each_invocation(xs.len() as u32, 64, Group::Thread, |inv| {
        mathfns(inv.global_index, &xs, &mut host)
    });
    assert_cpu_is_host("mathfns", &devs, &outs, &host);
    for w in gpu_outputs(&devs, &outs).windows(2) {
        assert_close(
            "mathfns wgpu vs vulkan",
            &flatten_vec4(w[0]),
            &flatten_vec4(w[1]),
            4,
            1e-6,
        );
    }
    for o in &outs {
        assert_close(
            "mathfns gpu vs host",
            &flatten_vec4(o),
            &flatten_vec4(&host),
            64,
            1e-5,
        );
    }
}

/// `sin` and `cos` on the CPU backend's forms, bit for bit against the host run (NaNs: both
/// NaN): the edges
/// of the ranges where the vector form computes them itself (|x| < 2^-12, < 0.75, < 120) and
/// where it calls the C library (|x| >= 120, infinities, NaN), quadrant boundaries, and
/// random bit patterns. The GPUs' sines are bounded by `transcendental_math`.
#[test]
fn sines_match_the_host_exactly() {
    use cohort_tests::kernels::mathfns::*;
    let mut xs = vec![
        0.0f32,
        f32::MIN_POSITIVE,
        1.0e-40,
        f32::INFINITY,
        f32::NAN,
        f32::MAX,
        1.0e30,
        1.0e6,
        120.0,
        0.75,
        2.0f32.powi(-12),
    ];
    for x in xs.clone() {
        xs.extend([
            f32::from_bits(x.to_bits().wrapping_sub(1)),
            f32::from_bits(x.to_bits() + 1),
        ]);
    }
    for k in 0..80 {
        let q = k as f32 * std::f32::consts::FRAC_PI_2;
        xs.extend((0..7).map(|d| f32::from_bits((q.to_bits() + d).wrapping_sub(3))));
    }
    let mut rng = Rng(7);
    xs.extend((0..2000).map(|_| f32::from_bits(rng.next_u32())));
    xs.extend((0..2000).map(|_| rng.f32(-130.0, 130.0)));
    xs.extend(xs.clone().iter().map(|x| -x));
    xs.push(1.5);
    let devs = devices();
    let outs: Vec<Vec<u32>> = devs
        .iter()
        .map(|d| {
            let x = d.upload(&xs).unwrap();
            let o = d.alloc::<Vec4>(xs.len()).unwrap();
            sines::launch(d, xs.len() as u32, &x, &o).unwrap();
            flatten_vec4(&d.read(&o).unwrap())
                .iter()
                .map(|v| v.to_bits())
                .collect()
        })
        .collect();
    let mut host = vec![Vec4::ZERO; xs.len()];
    for_each_invocation(xs.len() as u32, 64, Group::Thread, |inv| {
        sines(inv.global_index, &xs, &mut host)
    });
    let host: Vec<u32> = flatten_vec4(&host).iter().map(|v| v.to_bits()).collect();
    // NaNs compare as both NaN: their sign and payload are not specified (LANGUAGE.md
    // section 4), and the vector forms' differ from the C library's.
    let nan = |b: u32| f32::from_bits(b).is_nan();
    let mut cpus = 0;
    for (d, o) in devs.iter().zip(&outs) {
        if is_cpu(d) {
            cpus += 1;
            for (k, (&a, &b)) in o.iter().zip(&host).enumerate() {
                assert!(
                    a == b || (nan(a) && nan(b)),
                    "output {} of {:e} ({:#x}) on a CPU form: {a:#x}, host {b:#x}",
                    k % 4,
                    xs[k / 4],
                    xs[k / 4].to_bits()
                );
            }
        }
    }
    assert!(cpus >= 2, "the host form and at least one vector form");
}

/// `acos` on the CPU backend's forms, bit for bit against the host run (NaNs: both NaN):
/// the edges of the ranges where the vector form computes it itself (|x| <= 2^-26, < 0.5,
/// up to 1, each sign) and where it calls the C library (|x| > 1, infinities, NaN), and
/// random values. The GPUs' are bounded by `transcendental_math`.
#[test]
fn arccosines_match_the_host_exactly() {
    use cohort_tests::kernels::mathfns::*;
    let mut xs = vec![
        0.0f32,
        2.0f32.powi(-26),
        0.5,
        1.0,
        f32::INFINITY,
        f32::NAN,
        2.0,
    ];
    for x in xs.clone() {
        xs.extend([
            f32::from_bits(x.to_bits().wrapping_sub(1)),
            f32::from_bits(x.to_bits() + 1),
        ]);
    }
    let mut rng = Rng(13);
    xs.extend((0..3000).map(|_| rng.f32(-1.0, 1.0)));
    xs.extend((0..1000).map(|_| f32::from_bits(rng.next_u32())));
    xs.extend(xs.clone().iter().map(|x| -x));
    let mut host = vec![0.0f32; xs.len()];
    for_each_invocation(xs.len() as u32, 64, Group::Thread, |inv| {
        arccosines(inv.global_index, &xs, &mut host)
    });
    let mut cpus = 0;
    for d in devices().iter().filter(|d| is_cpu(d)) {
        let x = d.upload(&xs).unwrap();
        let o = d.alloc::<f32>(xs.len()).unwrap();
        arccosines::launch(d, xs.len() as u32, &x, &o).unwrap();
        for (k, (a, b)) in d.read(&o).unwrap().iter().zip(&host).enumerate() {
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "acos {:e} ({:#x}) on a CPU form: {a:e}, host {b:e}",
                xs[k],
                xs[k].to_bits()
            );
        }
        cpus += 1;
    }
    assert!(cpus >= 2, "the host form and at least one vector form");
}

#[test]
fn vector_and_matrix_math() {
    use cohort_tests::kernels::vectors::*;
    let mut rng = Rng(11);
    let input: Vec<Vec4> = (0..300)
        .map(|_| {
            Vec4::new(
                rng.f32(-3.0, 3.0),
                rng.f32(-3.0, 3.0),
                rng.f32(0.1, 3.0),
                rng.f32(0.0, 2.0),
            )
        })
        .collect();
    let devs = devices();
    let outs: Vec<Vec<Vec4>> = devs
        .iter()
        .map(|d| {
            let i = d.upload(&input).unwrap();
            let o = d.alloc::<Vec4>(input.len()).unwrap();
            vectors::launch(d, input.len() as u32, &i, &o).unwrap();
            d.read(&o).unwrap()
        })
        .collect();
    let mut host = vec![Vec4::ZERO; input.len()];
    for_each_invocation(input.len() as u32, 64, Group::Thread, |inv| {
        vectors(inv.global_index, &input, &mut host)
    });
    assert_cpu_is_host("vectors", &devs, &outs, &host);
    for o in &outs {
        assert_close(
            "vectors gpu vs host",
            &flatten_vec4(o),
            &flatten_vec4(&host),
            64,
            1e-4,
        );
    }
}

/// `#[specialize]` parameters: every combination of the constants, on every backend and on
/// the host, over edge values (NaN, infinities, -0, the extremes, an empty buffer). The
/// operations are exact on the host and the CPU backend (doubling, sqrt, negation,
/// min/max), so those match bit for bit; a GPU's `sqrt` need not be correctly rounded
/// (LANGUAGE.md: Vulkan allows about 3 ulp; NVIDIA's, through wgpu, is 1 ulp off for 7.5),
/// so where the root is taken GPU results are within 3 ulp.
#[test]
fn specialize_constants_match_host() {
    use cohort_tests::kernels::specialize::*;
    let mut x = vec![
        0.0f32,
        -0.0,
        1.0,
        -1.0,
        0.25,
        -7.5,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MAX,
        f32::MIN,
        f32::MIN_POSITIVE,
    ];
    let mut rng = Rng(5);
    x.extend((0..100).map(|_| rng.f32(-100.0, 100.0)));
    let devs = devices();
    for mode in 0..8u32 {
        for clamp in [false, true] {
            for n in [0usize, x.len()] {
                let x = &x[..n];
                let outs: Vec<Vec<u32>> = devs
                    .iter()
                    .map(|d| {
                        let xb = d.upload(x).unwrap();
                        let yb = d.upload(&vec![3.0f32; n]).unwrap();
                        specialized_steps::launch(d, n, mode, clamp, &xb, &yb).unwrap();
                        d.read(&yb).unwrap().iter().map(|v| v.to_bits()).collect()
                    })
                    .collect();
                let mut host = vec![3.0f32; n];
                for_each_invocation(n.max(1) as u32, 64, Group::Thread, |inv| {
                    specialized_steps(inv.global_index, mode, clamp, x, &mut host)
                });
                let host: Vec<u32> = host.iter().map(|v| v.to_bits()).collect();
                for (d, o) in devs.iter().zip(&outs) {
                    let gpu = d.info().backend != cohort::runtime::BackendKind::Cpu;
                    let bound = if gpu && mode & ROOT != 0 { 3 } else { 0 };
                    // NaN's payload and sign may differ through sqrt and negation on a GPU.
                    for (k, (a, b)) in o.iter().zip(&host).enumerate() {
                        let (fa, fb) = (f32::from_bits(*a), f32::from_bits(*b));
                        assert!(
                            a == b || (fa.is_nan() && fb.is_nan()) || ulps(fa, fb) <= bound,
                            "{:?}, mode {mode}, clamp {clamp}, element {k}: {fa} vs host {fb}",
                            d.info().backend
                        );
                    }
                }
            }
        }
    }
}

/// The specialisations differ only in what they build: a branch on a constant that is
/// false is not in the shader, and each value is its own cached artifact.
#[test]
fn specialize_leaves_other_branches_out() {
    use cohort::Spec;
    use cohort_tests::kernels::specialize::*;
    let base = Spec::portable(&specialized_steps::INFO, Group::Thread);
    let wgsl = |mode: u32, clamp: bool| {
        let spec = specialized_steps::specialized(&base, mode, clamp);
        cohort::emit::emit(&specialized_steps::build(&spec))
            .unwrap()
            .wgsl
    };
    let none = wgsl(0, false);
    let all = wgsl(DOUBLE | ROOT | NEGATE, true);
    assert!(!none.contains("sqrt") && !none.contains("-1f"), "{none}");
    assert!(all.contains("sqrt") && all.contains("-1f"), "{all}");
    assert!(!none.contains("mode") && !none.contains("clamp"), "{none}");
    let a = specialized_steps::artifact(&specialized_steps::specialized(&base, 1, false)).unwrap();
    let b = specialized_steps::artifact(&specialized_steps::specialized(&base, 2, false)).unwrap();
    assert_ne!(a.name, b.name);
}
