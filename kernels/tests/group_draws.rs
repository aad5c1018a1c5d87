//! The group draws of `extend` beyond the sampler's (the Russian-roulette number of `_rr`
//! and whole-group ends, coherent glossy and light sampling) are in the kernel only where
//! the set has `SHADES_GROUP_DRAWS` or paths end as whole groups; the sampler's patch only
//! for a sampler that reads it. Each draw is found by the helper it calls
//! (`fn shared_light_draw`, `fn cosine_patch` in the WGSL).

use cohort::{Group, Spec};
use cohort_kernels::extend::extend;
use cohort_kernels::integrator::NextEvent;
use cohort_kernels::layout::{Frame, DIFFUSE};
use cohort_kernels::path_end::{EachPath, WholeGroup};
use cohort_kernels::sampling::{CoherentCosine, Cosine};
use cohort_kernels::shading::{group_draws, kind_bit, SHADES_GROUP_DRAWS};

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
}
