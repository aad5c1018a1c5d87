//! Every kernel variant in this crate: each kernel at each specialisation the suites
//! lock (snapshots), validate and time. New kernels are added here once.

use crate::kernels::*;
use cohort::ir::BuiltKernel;
use cohort::{Group, KernelInfo, Spec};

/// One kernel specialisation: a stable name and the function that builds it.
pub struct Variant {
    pub name: String,
    pub spec: Spec,
    pub build: fn(&Spec) -> BuiltKernel,
}

fn v(info: &KernelInfo, label: &str, spec: Spec, build: fn(&Spec) -> BuiltKernel) -> Variant {
    let _ = info;
    Variant {
        name: format!("{label}__{}", spec.suffix()),
        spec,
        build,
    }
}

fn thread(info: &KernelInfo) -> Spec {
    Spec::portable(info, Group::Thread)
}

pub fn all() -> Vec<Variant> {
    let mut out = vec![
        // `#[specialize]`: two values of the constants, each a shader with only its steps.
        v(
            &specialize::specialized_steps::INFO,
            "specialized_steps",
            thread(&specialize::specialized_steps::INFO).with_constants(&[specialize::DOUBLE, 0]),
            specialize::specialized_steps::build,
        ),
        v(
            &specialize::specialized_steps::INFO,
            "specialized_steps",
            thread(&specialize::specialized_steps::INFO)
                .with_constants(&[specialize::ROOT | specialize::NEGATE, 1]),
            specialize::specialized_steps::build,
        ),
        v(
            &saxpy::saxpy::INFO,
            "saxpy",
            thread(&saxpy::saxpy::INFO),
            saxpy::saxpy::build,
        ),
        v(
            &rays::trace_spheres::INFO,
            "trace_spheres",
            thread(&rays::trace_spheres::INFO),
            rays::trace_spheres::build,
        ),
        v(
            &collatz::collatz::INFO,
            "collatz",
            thread(&collatz::collatz::INFO),
            collatz::collatz::build,
        ),
        v(
            &debug_print::debug_print::INFO,
            "debug_print",
            thread(&debug_print::debug_print::INFO),
            debug_print::debug_print::build,
        ),
        v(
            &sort4::sort4::INFO,
            "sort4",
            thread(&sort4::sort4::INFO),
            sort4::sort4::build,
        ),
        v(
            &generic::apply_curve::INFO,
            "apply_curve_square",
            thread(&generic::apply_curve::INFO),
            generic::apply_curve::build::<generic::Square>,
        ),
        v(
            &generic::apply_curve::INFO,
            "apply_curve_tent",
            thread(&generic::apply_curve::INFO),
            generic::apply_curve::build::<generic::Tent>,
        ),
        v(
            &reduce::reduce_sum::INFO,
            "reduce_sum",
            thread(&reduce::reduce_sum::INFO),
            reduce::reduce_sum::build,
        ),
        v(
            &subgroup_scan::subgroup_scan::INFO,
            "subgroup_scan",
            thread(&subgroup_scan::subgroup_scan::INFO),
            subgroup_scan::subgroup_scan::build,
        ),
        v(
            &histogram::histogram::INFO,
            "histogram",
            thread(&histogram::histogram::INFO),
            histogram::histogram::build,
        ),
        v(
            &bits::bits::INFO,
            "bits",
            thread(&bits::bits::INFO),
            bits::bits::build,
        ),
        v(
            &stack_walk::stack_walk::INFO,
            "stack_walk",
            thread(&stack_walk::stack_walk::INFO),
            stack_walk::stack_walk::build,
        ),
        v(
            &mathfns::mathfns::INFO,
            "mathfns",
            thread(&mathfns::mathfns::INFO),
            mathfns::mathfns::build,
        ),
        v(
            &vectors::vectors::INFO,
            "vectors",
            thread(&vectors::vectors::INFO),
            vectors::vectors::build,
        ),
    ];
    let gp = &group_pick::group_pick::INFO;
    let warp_sg = warp_sg_of(gp);
    for spec in [
        Spec::portable(gp, Group::Thread),
        Spec::portable(gp, Group::Warp),
        warp_sg,
        Spec::portable(gp, Group::Block(256)),
        Spec::portable(gp, Group::Block(1024)),
        Spec::portable(gp, Group::Grid),
        recompute_of(gp, Group::Warp),
        recompute_of(gp, Group::Block(256)),
    ] {
        out.push(v(gp, "group_pick", spec, group_pick::group_pick::build));
    }
    let gv = &group_vote::group_vote::INFO;
    for spec in [
        Spec::portable(gv, Group::Thread),
        Spec::portable(gv, Group::Warp),
        warp_sg_of(gv),
        Spec::portable(gv, Group::Block(256)),
    ] {
        out.push(v(gv, "group_vote", spec, group_vote::group_vote::build));
    }
    out
}

/// The CPU backend's specialisation: each invocation computes its group's value.
fn recompute_of(info: &KernelInfo, group: Group) -> Spec {
    let mut s = Spec::portable(info, group);
    s.recompute_group_share = true;
    s
}

fn warp_sg_of(info: &KernelInfo) -> Spec {
    let mut s = Spec::portable(info, Group::Warp);
    s.warp_via_subgroup = true;
    s
}
