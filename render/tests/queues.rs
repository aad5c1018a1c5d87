//! Shading over material queues (`RenderOptions::shading`,
//! `cohort_kernels::queues`): the partition lists every live ray once, stably, in the
//! queue of the kind it hit, with each queue's size and indirect dispatch; and a render
//! over queues is the render without them, bit for bit, on every backend.

use cohort::runtime::{BackendKind, Device};
use cohort_kernels::layout::{Material, Triangle, DONE, MISS};
use cohort_kernels::queues::{self, QueueBuffers, BLEND_ENTRY, MAX_QUEUES, TABLE_LEN};
use cohort_render::{Algorithm, Budget, IntegratorKind, RenderOptions, Renderer, Shading};
use glam::{UVec4, Vec4};

const BACKENDS: [BackendKind; 3] = [BackendKind::Cpu, BackendKind::Vulkan, BackendKind::Wgpu];

/// A fixed xorshift sequence.
fn next(state: &mut u32) -> u32 {
    *state ^= *state << 13;
    *state ^= *state >> 17;
    *state ^= *state << 5;
    *state
}

/// A scene's materials and triangles, the partition's table, and `slots` slots listed in
/// a scrambled order (`count` of them listed), some done, some missed.
struct Inputs {
    materials: Vec<Material>,
    table: [u32; TABLE_LEN],
    tris: Vec<Triangle>,
    slots: u32,
    count: u32,
    ids: Vec<u32>,
    state: Vec<UVec4>,
    hits: Vec<Vec4>,
}

fn inputs(slots: u32, count: u32, seed: u32) -> Inputs {
    // Kinds 0, 3 and 5 have queues 2, 0 and 1, blends queue 3. Materials: one of each
    // kind, a blend (of kind 0, which must not decide its queue), and kind 3 again.
    let kinds = [0u32, 3, 5, 0, 3];
    let materials: Vec<Material> = kinds
        .iter()
        .enumerate()
        .map(|(i, &kind)| Material {
            kind,
            blend: if i == 3 { 1 } else { 0 },
            ..Default::default()
        })
        .collect();
    let mut table = [0u32; TABLE_LEN];
    table[0] = 2;
    table[3] = 0;
    table[5] = 1;
    table[BLEND_ENTRY] = 3;
    table[BLEND_ENTRY + 1] = 4;
    // Workgroups of 64 for the dispatches.
    table[BLEND_ENTRY + 2] = 64;
    table[BLEND_ENTRY + 3] = 65535;
    let tris: Vec<Triangle> = (0..11)
        .map(|t| Triangle {
            material: (t * 7 % 5) as u32,
            ..Default::default()
        })
        .collect();
    let mut s = seed;
    let mut ids: Vec<u32> = (0..slots).collect();
    for i in (1..ids.len()).rev() {
        let j = next(&mut s) as usize % (i + 1);
        ids.swap(i, j);
    }
    let mut state = Vec::new();
    let mut hits = Vec::new();
    for _ in 0..slots {
        let done = next(&mut s).is_multiple_of(5);
        state.push(UVec4::new(0, 0, 0, if done { DONE } else { 0 }));
        let tri = match next(&mut s) % 6 {
            0 => MISS,
            _ => next(&mut s) % tris.len() as u32,
        };
        hits.push(Vec4::new(0.5, 0.25, 0.25, f32::from_bits(tri)));
    }
    Inputs {
        materials,
        table,
        tris,
        slots,
        count,
        ids,
        state,
        hits,
    }
}

/// What the partition of `inp` on `dev` writes: keys, hist, queued, args and out, each
/// buffer starting from stale words.
fn partition(dev: &Device, inp: &Inputs) -> [Vec<u32>; 5] {
    let slots = inp.slots;
    let table_b = dev.upload(&inp.table).unwrap();
    let count_b = dev.upload(&[inp.count]).unwrap();
    let ids_b = dev.upload(&inp.ids).unwrap();
    let state_b = dev.upload(&inp.state).unwrap();
    let hits_b = dev.upload(&inp.hits).unwrap();
    let tris_b = dev.upload(&inp.tris).unwrap();
    let mats_b = dev.upload(&inp.materials).unwrap();
    let keys_b = dev.upload(&vec![5u32; slots.max(1) as usize]).unwrap();
    // Stale counts from an earlier partition must not matter.
    let hist_b = dev.upload(&vec![7u32; queues::hist_len(slots)]).unwrap();
    let queued_b = dev.upload(&[9u32; 4 * MAX_QUEUES as usize]).unwrap();
    let args_b = dev.upload(&[9u32; 3 * MAX_QUEUES as usize]).unwrap();
    let out_b = dev
        .upload(&vec![u32::MAX; 2 * slots.max(1) as usize])
        .unwrap();
    let mut b = dev.batch();
    queues::record(
        &mut b,
        &queues::specs(dev),
        slots,
        &count_b,
        &ids_b,
        &state_b,
        &hits_b,
        &tris_b,
        &mats_b,
        &QueueBuffers {
            table: &table_b,
            keys: &keys_b,
            hist: &hist_b,
            queued: &queued_b,
            args: &args_b,
            out: &out_b,
        },
    )
    .unwrap();
    b.submit().unwrap();
    [&keys_b, &hist_b, &queued_b, &args_b, &out_b].map(|b| dev.read(b).unwrap())
}

#[test]
fn the_queues_partition_the_rays_stably_by_kind() {
    // More rays than one workgroup and a count below the slots.
    let mut inp = inputs(5000, 4321, 2024);
    let Inputs {
        ref materials,
        ref tris,
        count,
        ..
    } = inp;
    let table = inp.table;
    let queue_of_material = |m: usize| {
        if materials[m].blend != 0 {
            3
        } else {
            table[materials[m].kind as usize]
        }
    };
    let key = |slot: u32| {
        let tri = inp.hits[slot as usize].w.to_bits();
        if inp.state[slot as usize].w & DONE != 0 || tri == MISS {
            0
        } else {
            queue_of_material(tris[tri as usize].material as usize)
        }
    };
    // The stable partition: (slot, position in the list) by queue, in list order.
    let mut want: Vec<(u32, u32)> = (0..count).map(|g| (inp.ids[g as usize], g)).collect();
    want.sort_by_key(|&(slot, _)| key(slot));
    let sizes: Vec<u32> = (0..4u32)
        .map(|q| want.iter().filter(|&&(slot, _)| key(slot) == q).count() as u32)
        .collect();
    for kind in BACKENDS {
        let Some(dev) = Device::for_tests(kind) else {
            continue;
        };
        let name = kind.name();
        // At most 3 workgroups in x: dispatches fold into y.
        for max_x in [65535u32, 3] {
            inp.table[BLEND_ENTRY + 3] = max_x;
            let [_, _, queued, args, out] = partition(&dev, &inp);
            let n = count as usize;
            let got: Vec<(u32, u32)> = (0..n).map(|at| (out[at], out[n + at])).collect();
            assert_eq!(got, want, "{name}: not the stable partition by queue");
            assert!(
                out[2 * n..].iter().all(|&x| x == u32::MAX),
                "{name}: wrote past the queues"
            );
            let mut start = 0u32;
            for (q, &size) in sizes.iter().enumerate() {
                assert!(size > 0, "the test leaves queue {q} empty");
                let at = 4 * q;
                assert_eq!(
                    &queued[at..at + 3],
                    &[size, start, count],
                    "{name}: queue {q}"
                );
                let groups = size.div_ceil(64);
                let x = groups.min(max_x);
                let a = 3 * q;
                assert_eq!(
                    &args[a..a + 3],
                    &[x, groups.div_ceil(x), 1],
                    "{name}: dispatch of queue {q}"
                );
                start += size;
            }
        }
    }
}

/// On the CPU backend, the queue kernels' whole-dispatch loops write what their host forms
/// (workgroup arrays and barriers) write: the same keys, block counts, queues, dispatches
/// and lists, word for word, from empty lists to lists of many workgroups, counts below
/// the slots, and dispatches folded into y.
#[test]
fn queues_cpu_whole_dispatches_write_the_host_forms_words() {
    use cohort::runtime::cpu::simd::Forms;
    let whole = Device::cpu_with(Forms::Measured).unwrap();
    let host = Device::cpu_with(Forms::Host).unwrap();
    for (slots, count, max_x) in [
        (0, 0, 65535),
        (1, 1, 65535),
        (1, 0, 65535),
        (256, 256, 65535),
        (257, 257, 2),
        (5000, 4321, 3),
        (9000, 8448, 65535),
    ] {
        let mut inp = inputs(slots, count, 77 + slots);
        inp.table[BLEND_ENTRY + 3] = max_x;
        assert_eq!(
            partition(&whole, &inp),
            partition(&host, &inp),
            "{count} of {slots} slots listed, at most {max_x} workgroups in x"
        );
    }
    let counts = whole.form_counts();
    for k in ["queue_count", "queue_offsets", "queue_scatter"] {
        let c = counts.iter().find(|c| c.kernel.starts_with(k)).expect(k);
        assert!(c.whole > 0 && c.host == 0, "{k} ran {c:?}");
    }
}

fn render(dev: &Device, path: &str, opts: &RenderOptions) -> Vec<[f32; 3]> {
    let scene = cohort_scenes::load_mitsuba(path).expect("scene").scene;
    let mut r = Renderer::new(dev, &scene, opts.clone()).expect("renderer");
    let (img, stats) = r.render(|_, _| {}).expect("render");
    if opts.shading == Shading::Queues {
        assert!(
            !stats.kernel.queue.is_zero(),
            "the partition's time is not counted"
        );
        assert_eq!(stats.queued_iterations, stats.iterations);
    } else {
        // `Auto` measures the designs only on GPUs that are not software drivers.
        assert_eq!(stats.queued_iterations, 0, "{:?}", opts.shading);
        assert!(stats.kernel.queue.is_zero());
    }
    img.pixels.iter().map(|p| p.to_array()).collect()
}

#[test]
fn a_render_over_queues_is_the_same_image() {
    let scenes = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/mitsuba");
    let base = RenderOptions {
        budget: Budget::PathsPerPixel(4),
        size: Some((24, 24)),
        seed: 5,
        integrator: IntegratorKind::Nee,
        shading: Shading::Kernel,
        ..Default::default()
    };
    for kind in BACKENDS {
        let Some(dev) = Device::for_tests(kind) else {
            continue;
        };
        // Blends of several kinds where compilation is cheap; two kinds on the software
        // driver, whose compiler takes long over a blend's kernels.
        let scene = match kind {
            BackendKind::Cpu => "blendbsdf",
            _ => "conductor",
        };
        let path = format!("{scenes}/{scene}.xml");
        let plain = render(&dev, &path, &base);
        assert!(plain.iter().any(|p| p[0] > 0.0), "a black image");
        let auto = RenderOptions {
            shading: Shading::Auto,
            ..base.clone()
        };
        assert_eq!(render(&dev, &path, &auto), plain, "{}: auto", kind.name());
        let queued = RenderOptions {
            shading: Shading::Queues,
            ..base.clone()
        };
        let over_queues = render(&dev, &path, &queued);
        let differ = plain
            .iter()
            .zip(&over_queues)
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(
            differ,
            0,
            "{}, {scene}: {differ} pixels differ",
            kind.name()
        );
        // With coherent groups, the groups form over the queues: the image changes, but
        // the partition is stable, so a second run repeats it.
        if kind == BackendKind::Cpu {
            let warp = RenderOptions {
                algorithm: Algorithm::parse("warp").unwrap(),
                ..queued.clone()
            };
            let first = render(&dev, &path, &warp);
            assert_eq!(
                first,
                render(&dev, &path, &warp),
                "{scene}: warp over queues"
            );
            assert!(first.iter().any(|p| p[0] > 0.0), "a black image");
        }
    }
}
