//! Ray reordering (`RenderOptions::reorder`, `cohort_kernels::reorder`): the sort lists
//! every live ray once, in bin order, and a render with it is the render without it, bit
//! for bit, on every backend.

use cohort::runtime::{BackendKind, Device};
use cohort_kernels::layout::DONE;
use cohort_kernels::reorder::{self, bin_key, BINS};
use cohort_render::{Algorithm, Budget, IntegratorKind, RenderOptions, Renderer};
use glam::{UVec4, Vec3};

const BACKENDS: [BackendKind; 3] = [BackendKind::Cpu, BackendKind::Vulkan, BackendKind::Wgpu];

/// A fixed xorshift sequence in [0, 1).
fn uniform(state: &mut u32) -> f32 {
    *state ^= *state << 13;
    *state ^= *state >> 17;
    *state ^= *state << 5;
    (*state >> 8) as f32 / (1u32 << 24) as f32
}

#[test]
fn the_sort_lists_every_ray_once_in_bin_order() {
    // Slots listed in a scrambled order, a quarter of them done, origins inside and
    // outside the grid, directions with -0 and zero components; more rays than one
    // workgroup and a count below the slots.
    let slots = 5000u32;
    let count = 4321u32;
    let mut s = 12345u32;
    let mut ids: Vec<u32> = (0..slots).collect();
    for i in (1..ids.len()).rev() {
        let j = (uniform(&mut s) * (i + 1) as f32) as usize;
        ids.swap(i, j.min(i));
    }
    let mut o = Vec::new();
    let mut d = Vec::new();
    let mut state = Vec::new();
    for k in 0..slots {
        let p = Vec3::new(uniform(&mut s), uniform(&mut s), uniform(&mut s)) * 14.0 - 2.0;
        o.push(p.extend(0.0));
        let mut dir = Vec3::new(uniform(&mut s), uniform(&mut s), uniform(&mut s)) * 2.0 - 1.0;
        if k % 7 == 0 {
            dir.x = -0.0;
        }
        if k % 11 == 0 {
            dir.y = 0.0;
        }
        d.push(dir.extend(0.0));
        state.push(UVec4::new(0, 0, 0, if k % 4 == 0 { DONE } else { 0 }));
    }
    let grid = reorder::cells(Vec3::ZERO, Vec3::splat(10.0));
    let key = |slot: u32| {
        if state[slot as usize].w & DONE != 0 {
            BINS
        } else {
            bin_key(
                o[slot as usize].truncate(),
                d[slot as usize].truncate(),
                &grid,
            )
        }
    };
    for kind in BACKENDS {
        let Some(dev) = Device::for_tests(kind) else {
            continue;
        };
        let count_b = dev.upload(&[count]).unwrap();
        let ids_b = dev.upload(&ids).unwrap();
        let state_b = dev.upload(&state).unwrap();
        let o_b = dev.upload(&o).unwrap();
        let d_b = dev.upload(&d).unwrap();
        let cells_b = dev.upload(&grid).unwrap();
        let keys_b = dev.alloc::<u32>(slots as usize).unwrap();
        // Stale counts from an earlier sort must be cleared.
        let bins_b = dev.upload(&vec![7u32; reorder::HISTOGRAM_LEN]).unwrap();
        let sorted_b = dev.upload(&vec![u32::MAX; slots as usize]).unwrap();
        let mut b = dev.batch();
        reorder::record(
            &mut b,
            &reorder::specs(&dev),
            slots,
            &count_b,
            &ids_b,
            &state_b,
            &o_b,
            &d_b,
            &reorder::SortBuffers {
                cells: &cells_b,
                keys: &keys_b,
                bins: &bins_b,
                sorted: &sorted_b,
            },
        )
        .unwrap();
        b.submit().unwrap();
        let sorted = dev.read(&sorted_b).unwrap();
        let name = kind.name();
        let mut listed: Vec<u32> = sorted[..count as usize].to_vec();
        let keys: Vec<u32> = listed.iter().map(|&sl| key(sl)).collect();
        assert!(
            keys.windows(2).all(|w| w[0] <= w[1]),
            "{name}: the sorted rays are not in bin order"
        );
        listed.sort_unstable();
        let mut want = ids[..count as usize].to_vec();
        want.sort_unstable();
        assert_eq!(listed, want, "{name}: not a permutation of the listed rays");
        assert!(
            sorted[count as usize..].iter().all(|&x| x == u32::MAX),
            "{name}: wrote past the listed rays"
        );
        // Done slots (a quarter of the slots) come last.
        assert_eq!(*keys.last().unwrap(), BINS, "{name}");
    }
}

fn render(dev: &Device, opts: &RenderOptions) -> Vec<[f32; 3]> {
    let scene = cohort_scenes::embedded::load("cornell").unwrap();
    let mut r = Renderer::new(dev, &scene, opts.clone()).expect("renderer");
    let (img, stats) = r.render(|_, _| {}).expect("render");
    if opts.reorder > 0 {
        assert!(
            !stats.kernel.reorder.is_zero(),
            "the sort's time is not counted"
        );
    }
    img.pixels.iter().map(|p| p.to_array()).collect()
}

#[test]
fn a_reordered_render_is_the_same_image() {
    let base = RenderOptions {
        budget: Budget::PathsPerPixel(6),
        size: Some((32, 32)),
        seed: 3,
        compact: false,
        integrator: IntegratorKind::Nee,
        ..Default::default()
    };
    for kind in BACKENDS {
        let Some(dev) = Device::for_tests(kind) else {
            continue;
        };
        // A coherent configuration with compaction where its compilation is cheap (the
        // software driver takes minutes for a coherent `extend`).
        let mut configs = vec![base.clone()];
        if kind == BackendKind::Cpu {
            configs.push(RenderOptions {
                algorithm: Algorithm::parse("warp").unwrap(),
                compact: true,
                ..base.clone()
            });
        }
        for opts in configs {
            let plain = render(&dev, &opts);
            assert!(plain.iter().any(|p| p[0] > 0.0), "a black image");
            for k in [1, 3] {
                let sorted = render(
                    &dev,
                    &RenderOptions {
                        reorder: k,
                        ..opts.clone()
                    },
                );
                let differ = plain.iter().zip(&sorted).filter(|(a, b)| a != b).count();
                assert_eq!(
                    differ,
                    0,
                    "{}, {}, compaction {}, reorder {k}: {differ} pixels differ",
                    kind.name(),
                    opts.algorithm.name(),
                    opts.compact
                );
            }
        }
    }
}
