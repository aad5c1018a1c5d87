//! The group draws of `extend` beyond the sampler's (the Russian-roulette number of `_rr`
//! and whole-group ends, coherent glossy and light sampling) are in the kernel only where
//! the set has `SHADES_GROUP_DRAWS` or paths end as whole groups; the sampler's patch only
//! for a sampler that reads it. Each draw is found by the helper it calls
//! (`fn shared_light_draw`, `fn cosine_patch` in the WGSL).
//!
//! The group table (`draw_groups`) holds, for every group of slots, the draws its
//! invocations would compute themselves, on every backend, and nothing past its end.

use cohort::runtime::{BackendKind, Device};
use cohort::{Group, Spec};
use cohort_kernels::extend::extend;
use cohort_kernels::group_draw::{
    draw_groups, draws_entry, groups, light_entry, params_entry, patch_key, table_at, table_len,
    TABLE_STRIDE,
};
use cohort_kernels::integrator::NextEvent;
use cohort_kernels::layout::{Frame, DIFFUSE};
use cohort_kernels::path_end::{EachPath, WholeGroup};
use cohort_kernels::rng::uniform;
use cohort_kernels::sampling::{CoherentCosine, CoherentEqualArea, Cosine, DiffuseSampler};
use cohort_kernels::shading::{
    group_draws, kind_bit, SHADES_GROUP_DRAWS, SHADES_GROUP_TABLE, SHADES_SLOT_GROUPS,
};
use glam::UVec4;

fn has(wgsl: &str, helper: &str) -> bool {
    wgsl.lines()
        .any(|l| l.starts_with(&format!("fn {helper}(")))
}

fn wgsl(group: Group, set: u32, build: fn(&Spec) -> cohort::ir::BuiltKernel) -> String {
    let spec = Spec::portable(&extend::INFO, group).with_constants(&[set]);
    cohort::emit::emit(&build(&spec))
        .unwrap_or_else(|e| panic!("extend for set {set:#x}: {e}"))
        .wgsl
}

#[test]
fn group_draws_are_built_only_where_read() {
    let diffuse = kind_bit(DIFFUSE);
    let normal = extend::build::<Cosine, EachPath, NextEvent>;
    let coherent = extend::build::<CoherentCosine, EachPath, NextEvent>;
    let whole = extend::build::<CoherentCosine, WholeGroup, NextEvent>;
    for group in [Group::Thread, Group::Warp] {
        let plain = wgsl(group, diffuse, normal);
        assert!(!has(&plain, "shared_light_draw"), "{group:?}");
        assert!(
            !has(&plain, "cosine_patch"),
            "{group:?}: Cosine reads no patch"
        );
        let drawn = wgsl(group, diffuse | SHADES_GROUP_DRAWS, normal);
        assert!(has(&drawn, "shared_light_draw"), "{group:?}");
        let patch = wgsl(group, diffuse, coherent);
        assert!(has(&patch, "cosine_patch"), "{group:?}");
        assert!(!has(&patch, "shared_light_draw"), "{group:?}");
        assert!(
            has(&wgsl(group, diffuse, whole), "shared_light_draw"),
            "{group:?}"
        );
    }
}

#[test]
fn the_frame_flags_that_read_group_draws_set_the_bit() {
    assert_eq!(group_draws(&Frame::default()), 0);
    for set in [
        |f: &mut Frame| f.group_rr = 1,
        |f: &mut Frame| f.coherent_glossy = 1,
        |f: &mut Frame| f.coherent_light = 1,
    ] {
        let mut f = Frame::default();
        set(&mut f);
        assert_eq!(group_draws(&f), SHADES_GROUP_DRAWS);
    }
    // Keyed by slot: one slot a group computes its own draws; larger groups read the table.
    let mut f = Frame {
        group_slots: 1,
        ..Default::default()
    };
    assert_eq!(group_draws(&f), SHADES_SLOT_GROUPS);
    f.group_slots = 32;
    assert_eq!(group_draws(&f), SHADES_SLOT_GROUPS | SHADES_GROUP_TABLE);
}

/// With the group table, `extend` reads its group's draws from the table and writes the
/// next iteration's there; without it, the table is not in the kernel at all.
#[test]
fn a_tabled_extend_reads_and_writes_the_table() {
    let set = kind_bit(DIFFUSE) | SHADES_GROUP_DRAWS | SHADES_SLOT_GROUPS;
    let coherent = extend::build::<CoherentCosine, EachPath, NextEvent>;
    let own = wgsl(Group::Warp, set, coherent);
    assert!(!own.contains("group_table"));
    let tabled = wgsl(Group::Warp, set | SHADES_GROUP_TABLE, coherent);
    let reads = tabled
        .lines()
        .filter(|l| l.contains("= group_table["))
        .count();
    let writes = tabled
        .lines()
        .filter(|l| l.trim_start().starts_with("group_table["))
        .count();
    assert!(reads >= 4 && writes == 3, "{reads} reads, {writes} writes");
    assert!(tabled.contains("var<storage, read_write> group_table"));
}

const SENTINEL: u32 = 0xDEAD_BEEF;

/// How far a GPU's sampler parameters (cosines of band edges, the band's width) may be
/// from the host's, relative to their size (at least 1): lavapipe's and NVIDIA's `cos`
/// are within it, and the cosine of a neighbouring band's edge is at least
/// 1 - cos(pi / 32) = 4.8e-3 away for the N of these tests (at most 8).
const PARAMS_TOLERANCE: f32 = 1e-4;

/// The table that `draw_groups::<S>` writes for frame `f` on `d`, `slack` entries past
/// its length left at [`SENTINEL`].
fn table<S: DiffuseSampler>(d: &Device, f: &Frame, slack: usize) -> Vec<UVec4> {
    let len = table_len(groups(f));
    let buf = d
        .upload(&vec![UVec4::splat(SENTINEL); len + slack])
        .unwrap();
    draw_groups::launch::<S>(d, groups(f), f, &buf).unwrap();
    d.read(&buf).unwrap()
}

/// What `extend` computes for group `g` itself at the frame's iteration, as the table
/// holds it: the kernel functions, run on the host.
fn host_entries<S: DiffuseSampler>(f: &Frame, g: u32) -> [UVec4; 3] {
    let draws = draws_entry::<S>(f, g, f.iteration);
    [
        draws,
        light_entry(f, g, f.iteration),
        params_entry::<S>(f, draws),
    ]
}

/// Whether the sampler's parameters `got` from a device are the host's `want` as floats
/// within `tolerance` of their size (at least 1): a GPU's `cos` and division are not the
/// host's to the bit.
fn params_near(got: UVec4, want: UVec4, tolerance: f32) -> bool {
    (0..4).all(|i| {
        let (g, w) = (f32::from_bits(got[i]), f32::from_bits(want[i]));
        (g - w).abs() <= tolerance * w.abs().max(1.0)
    })
}

/// The polar band of `cosine_patch`'s draw for group `g` on the host, and how far (in
/// bands) its angle is from the nearest band edge.
fn polar_band(f: &Frame, g: u32) -> (u32, f32) {
    let u1 = uniform(patch_key(f, g, f.iteration), 0);
    let theta = (1.0 - u1).max(0.0).sqrt().min(1.0).acos();
    let t = theta / (std::f32::consts::FRAC_PI_2 / f.patches_n as f32);
    ((t as u32).min(f.patches_n - 1), (t - t.round()).abs())
}

/// `exact_acos`: the backend's acos is the host's (the CPU backend), so a patch from
/// `cosine_patch` must be the host's too; elsewhere it may be a neighbour
/// ([`polar_band`]).
fn check_table<S: DiffuseSampler>(d: &Device, name: &str, exact_acos: bool) {
    // Slot counts that are and are not multiples of the group, one group, and group
    // sizes from two slots to a block; iterations of both parities (the table's halves),
    // seeds, patch and light grids vary.
    for (slots, group_slots) in [
        (1, 32),
        (31, 32),
        (1000, 32),
        (65536, 32),
        (777, 2),
        (4096, 256),
    ] {
        for (iteration, group_seed, patches_n, light_cells) in [
            (0, 0, 4, 1),
            (7, 0x1234_5678, 8, 3),
            (u32::MAX - 1, u32::MAX, 1, 16),
        ] {
            let f = Frame {
                slots,
                group_slots,
                iteration,
                group_seed,
                patches_n,
                light_cells,
                ..Default::default()
            };
            let got = table::<S>(d, &f, 8);
            let len = table_len(groups(&f));
            // Counted apart from `groups(&f)`, which the table's layout uses.
            let n = slots.div_ceil(group_slots);
            assert_eq!(groups(&f), n);
            let what =
                format!("{name}: {slots} slots in groups of {group_slots}, iteration {iteration}");
            for g in 0..n {
                let at = table_at(&f, g, iteration);
                assert_eq!(at, (TABLE_STRIDE * ((iteration % 2) * n + g)) as usize);
                let mut want = host_entries::<S>(&f, g);
                if exact_acos || want[0].x == got[at].x {
                    assert_eq!(got[at..at + 2], want[..2], "{what}, group {g}");
                    let tolerance = if exact_acos { 0.0 } else { PARAMS_TOLERANCE };
                    assert!(
                        params_near(got[at + 2], want[2], tolerance),
                        "{what}, group {g}: parameters {:?}, the host's {:?}",
                        got[at + 2],
                        want[2]
                    );
                    continue;
                }
                // A GPU's acos is not the host's: `cosine_patch` may pick the
                // neighbouring polar band where the angle is within its error of an edge.
                let (band, edge) = polar_band(&f, g);
                let (m, p) = (4 * patches_n, got[at].x);
                assert!(
                    p % m == want[0].x % m && (p / m).abs_diff(band) == 1 && edge < 1e-4,
                    "{what}, group {g}: patch {p}, the host's {} ({edge} from an edge)",
                    want[0].x
                );
                want[0].x = p;
                want[2] = params_entry::<S>(&f, want[0]);
                assert_eq!(got[at..at + 2], want[..2], "{what}, group {g}");
                assert!(
                    params_near(got[at + 2], want[2], PARAMS_TOLERANCE),
                    "{what}, group {g}: parameters of the neighbouring band"
                );
            }
            // The other iteration parity's half, and past the table, stay untouched.
            let other = table_at(&f, 0, iteration + 1);
            let half = (TABLE_STRIDE * n) as usize;
            assert!(
                got[other..other + half]
                    .iter()
                    .all(|&e| e == UVec4::splat(SENTINEL)),
                "{what}: written into the other half"
            );
            assert!(
                got[len..].iter().all(|&e| e == UVec4::splat(SENTINEL)),
                "{what}: written past the table"
            );
        }
    }
}

/// `draw_groups` writes, on every backend, the draws each group's invocations would
/// compute themselves, for samplers with and without a patch: bit for bit against the
/// host, except that a GPU's acos may put `cosine_patch`'s angle in the neighbouring
/// polar band where it lies within 1e-4 of a band's width from the edge.
#[test]
fn the_group_table_holds_the_draws_of_each_group() {
    for kind in [BackendKind::Cpu, BackendKind::Vulkan, BackendKind::Wgpu] {
        let Some(d) = Device::for_tests(kind) else {
            continue;
        };
        let exact = kind == BackendKind::Cpu;
        check_table::<CoherentCosine>(&d, kind.name(), exact);
        // Equal-area patches and `Cosine`'s lack of one are integers: exact everywhere.
        check_table::<CoherentEqualArea>(&d, kind.name(), true);
        check_table::<Cosine>(&d, kind.name(), true);
    }
}
