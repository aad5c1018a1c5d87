//! The table of BSDFs (`cohort_kernels::bsdf`): a scene's shading set builds an `extend`
//! with the BSDFs of its kinds and no other. A BSDF's code in a kernel is found by its
//! `Bsdf::scatters` instance, which every dispatch calls (`Bsdf_scatters_<type>` in the
//! WGSL).

use cohort::{Group, Spec};
use cohort_kernels::bsdf::KINDS;
use cohort_kernels::extend::extend;
use cohort_kernels::integrator::NextEvent;
use cohort_kernels::path_end::EachPath;
use cohort_kernels::sampling::Cosine;
use cohort_kernels::shading::{kind_bit, SHADES_ALL};
use std::collections::BTreeSet;

/// The BSDF types whose code is in `extend` built for shading set `set`.
fn bsdfs_in(set: u32) -> BTreeSet<String> {
    let spec = Spec::portable(&extend::INFO, Group::Thread).with_constants(&[set]);
    let built = extend::build::<Cosine, EachPath, NextEvent>(&spec);
    let wgsl = cohort::emit::emit(&built)
        .unwrap_or_else(|e| panic!("extend for set {set:#x}: {e}"))
        .wgsl;
    wgsl.lines()
        .filter_map(|l| l.strip_prefix("fn Bsdf_scatters_"))
        .map(|rest| rest.split('(').next().unwrap_or_default().to_string())
        .collect()
}

#[test]
fn each_kind_builds_its_bsdf_and_no_other() {
    let all = bsdfs_in(SHADES_ALL);
    assert!(all.len() >= 2, "the every-kind kernel has {all:?}");
    let mut seen = BTreeSet::new();
    for &(kind, name) in KINDS {
        let alone = bsdfs_in(kind_bit(kind));
        assert_eq!(alone.len(), 1, "kind {name} alone builds {alone:?}");
        assert!(all.is_superset(&alone), "{name}: {alone:?} not in {all:?}");
        seen.extend(alone);
    }
    // Every BSDF of the every-kind kernel is some kind's.
    assert_eq!(seen, all);
}

#[test]
fn no_kind_builds_no_bsdf() {
    // A scene of emitters only (or none) shades nothing: the path ends where it hits.
    assert!(bsdfs_in(0).is_empty());
}

#[test]
fn kinds_are_distinct_and_named_once() {
    let kinds: BTreeSet<u32> = KINDS.iter().map(|k| k.0).collect();
    let names: BTreeSet<&str> = KINDS.iter().map(|k| k.1).collect();
    assert_eq!(kinds.len(), KINDS.len());
    assert_eq!(names.len(), KINDS.len());
}
