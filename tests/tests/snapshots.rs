//! Locks the generated shaders: for every kernel variant, the WGSL and the SPIR-V
//! disassembly (after `naga::compact`, so names are stable) are insta snapshots. Every
//! snapshot is also checked: the SPIR-V passes `spirv-val` and the WGSL re-parses and
//! re-validates through naga's own front end. (Executing them is the difftests' job; the
//! renderer's kernels, locked here too, run in `cohort-render`'s tests.)

mod common;

use cohort_tests::variants;
use std::process::Command;

fn disassemble(words: &[u32]) -> String {
    use rspirv::binary::Disassemble;
    let module = rspirv::dr::load_words(words).expect("naga wrote SPIR-V that rspirv cannot load");
    module.disassemble()
}

fn spirv_val(name: &str, words: &[u32]) {
    let dir = std::env::temp_dir().join(format!("cohort-spv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.spv"));
    std::fs::write(&path, bytemuck::cast_slice::<u32, u8>(words)).unwrap();
    match Command::new("spirv-val")
        .arg("--target-env")
        .arg("vulkan1.1")
        .arg(&path)
        .output()
    {
        Ok(out) => assert!(
            out.status.success(),
            "spirv-val rejects {name}:\n{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        ),
        Err(e) => {
            assert!(
                std::env::var("CI").as_deref() != Ok("true"),
                "spirv-val not found ({e}); install spirv-tools"
            );
            eprintln!("skipping spirv-val for {name}: {e} (install spirv-tools)");
        }
    }
}

fn reparse_wgsl(name: &str, wgsl: &str) {
    let module = naga::front::wgsl::parse_str(wgsl)
        .unwrap_or_else(|e| panic!("{name}: WGSL does not re-parse: {}", e.emit_to_string(wgsl)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|e| {
        panic!(
            "{name}: re-parsed WGSL does not validate: {:?}",
            e.into_inner()
        )
    });
}

#[test]
fn every_variant_is_locked_and_valid() {
    let variants = variants::all();
    assert!(variants.len() >= 18);
    let mut names = std::collections::HashSet::new();
    for v in variants {
        assert!(
            names.insert(v.name.clone()),
            "duplicate variant name {}",
            v.name
        );
        let built = (v.build)(&v.spec);
        let e = cohort::emit::emit(&built).unwrap_or_else(|e| panic!("{e}"));
        reparse_wgsl(&v.name, &e.wgsl);
        spirv_val(&v.name, &e.spirv);
        insta::assert_snapshot!(format!("{}.wgsl", v.name), e.wgsl);
        insta::assert_snapshot!(format!("{}.spvasm", v.name), disassemble(&e.spirv));
    }
}

/// The renderer's own kernels (`cohort-kernels`), at the specialisations it dispatches:
/// a change to the path tracer's generated code shows up in review like any other.
fn renderer_variants() -> Vec<variants::Variant> {
    use cohort::{Group, KernelInfo, Spec};
    use cohort_kernels::compact::{compact_count, compact_offsets, compact_scatter};
    use cohort_kernels::display::display;
    use cohort_kernels::extend::{extend, init_paths};
    use cohort_kernels::group_draw::draw_groups;
    use cohort_kernels::integrator::{Implicit, NextEvent};
    use cohort_kernels::layout::DIFFUSE;
    use cohort_kernels::path_end::{EachPath, WholeGroup};
    use cohort_kernels::queues::{queue_count, queue_offsets, queue_scatter};
    use cohort_kernels::reorder::{bin_clear, bin_count, bin_offsets, bin_scatter};
    use cohort_kernels::retire::mark_live;
    use cohort_kernels::sampling::{CoherentCosine, Cosine};
    use cohort_kernels::shading::{
        kind_bit, queue_set, SHADES_ALL, SHADES_GROUP_TABLE, SHADES_SLOT_GROUPS,
    };
    use cohort_kernels::traverse::{trace_shadow, traverse};
    use cohort_kernels::traverse_wide::{trace_shadow8, traverse8};
    fn variant(
        label: &str,
        info: &KernelInfo,
        group: Group,
        build: fn(&Spec) -> cohort::ir::BuiltKernel,
    ) -> variants::Variant {
        specialized(label, info, group, &[], build)
    }
    // A kernel with `#[specialize]` parameters, at the values in `constants`.
    fn specialized(
        label: &str,
        info: &KernelInfo,
        group: Group,
        constants: &[u32],
        build: fn(&Spec) -> cohort::ir::BuiltKernel,
    ) -> variants::Variant {
        let spec = Spec::portable(info, group).with_constants(constants);
        variants::Variant {
            name: format!("renderer_{label}__{}", spec.suffix()),
            spec,
            build,
        }
    }
    vec![
        variant(
            "init_paths",
            &init_paths::INFO,
            Group::Thread,
            init_paths::build,
        ),
        variant("traverse", &traverse::INFO, Group::Thread, traverse::build),
        variant(
            "traverse8",
            &traverse8::INFO,
            Group::Thread,
            traverse8::build,
        ),
        variant(
            "trace_shadow",
            &trace_shadow::INFO,
            Group::Thread,
            trace_shadow::build,
        ),
        variant(
            "trace_shadow8",
            &trace_shadow8::INFO,
            Group::Thread,
            trace_shadow8::build,
        ),
        variant(
            "compact_count",
            &compact_count::INFO,
            Group::Thread,
            compact_count::build,
        ),
        variant(
            "compact_offsets",
            &compact_offsets::INFO,
            Group::Thread,
            compact_offsets::build,
        ),
        variant(
            "compact_scatter",
            &compact_scatter::INFO,
            Group::Thread,
            compact_scatter::build,
        ),
        // Retiring finished slots from the live list.
        variant(
            "mark_live",
            &mark_live::INFO,
            Group::Thread,
            mark_live::build,
        ),
        // Ray reordering (`cohort render --reorder K`).
        variant(
            "bin_clear",
            &bin_clear::INFO,
            Group::Thread,
            bin_clear::build,
        ),
        variant(
            "bin_count",
            &bin_count::INFO,
            Group::Thread,
            bin_count::build,
        ),
        variant(
            "bin_offsets",
            &bin_offsets::INFO,
            Group::Thread,
            bin_offsets::build,
        ),
        variant(
            "bin_scatter",
            &bin_scatter::INFO,
            Group::Thread,
            bin_scatter::build,
        ),
        // Material queues (`cohort render --shading-queues`).
        variant(
            "queue_count",
            &queue_count::INFO,
            Group::Thread,
            queue_count::build,
        ),
        variant(
            "queue_offsets",
            &queue_offsets::INFO,
            Group::Thread,
            queue_offsets::build,
        ),
        variant(
            "queue_scatter",
            &queue_scatter::INFO,
            Group::Thread,
            queue_scatter::build,
        ),
        // The viewer's tone mapping (`cohort view`).
        variant("display", &display::INFO, Group::Thread, display::build),
        // The default render (independent cosine sampling, light sampling) and the paper's
        // coherent sampling with a whole-warp end, implicit paths: for a scene of every
        // BSDF kind and shading feature, and for the Cornell box (diffuse only), whose
        // kernel has no other BSDF.
        specialized(
            "extend_cosine_nee",
            &extend::INFO,
            Group::Thread,
            &[SHADES_ALL],
            extend::build::<Cosine, EachPath, NextEvent>,
        ),
        specialized(
            "extend_cosine_nee_diffuse",
            &extend::INFO,
            Group::Thread,
            &[kind_bit(DIFFUSE)],
            extend::build::<Cosine, EachPath, NextEvent>,
        ),
        // The diffuse queue's `extend` (`--shading-queues`): the same kernel, reading its
        // rays from queue 1.
        specialized(
            "extend_cosine_nee_diffuse_queue",
            &extend::INFO,
            Group::Thread,
            &[queue_set(kind_bit(DIFFUSE), 1)],
            extend::build::<Cosine, EachPath, NextEvent>,
        ),
        specialized(
            "extend_coherent_wholegroup_path",
            &extend::INFO,
            Group::Warp,
            &[SHADES_ALL],
            extend::build::<CoherentCosine, WholeGroup, Implicit>,
        ),
        // Coherent warps as the CPU backend renders them: each group's draws computed
        // once an iteration into the group table, which `extend` reads by slot.
        variant(
            "draw_groups_coherent",
            &draw_groups::INFO,
            Group::Thread,
            draw_groups::build::<CoherentCosine>,
        ),
        specialized(
            "extend_coherent_nee_diffuse_tabled",
            &extend::INFO,
            Group::Warp,
            &[kind_bit(DIFFUSE) | SHADES_SLOT_GROUPS | SHADES_GROUP_TABLE],
            extend::build::<CoherentCosine, EachPath, NextEvent>,
        ),
    ]
}

#[test]
fn renderer_kernels_are_locked_and_valid() {
    for v in renderer_variants() {
        let built = (v.build)(&v.spec);
        let e = cohort::emit::emit(&built).unwrap_or_else(|e| panic!("{}: {e}", v.name));
        reparse_wgsl(&v.name, &e.wgsl);
        spirv_val(&v.name, &e.spirv);
        insta::assert_snapshot!(format!("{}.wgsl", v.name), e.wgsl);
        insta::assert_snapshot!(format!("{}.spvasm", v.name), disassemble(&e.spirv));
    }
}

/// Building the same variant twice gives byte-identical output (no hash-map order or
/// handle leaks into names).
#[test]
fn emission_is_deterministic() {
    for v in variants::all() {
        let a = cohort::emit::emit(&(v.build)(&v.spec)).unwrap();
        let b = cohort::emit::emit(&(v.build)(&v.spec)).unwrap();
        assert_eq!(a.wgsl, b.wgsl, "{}", v.name);
        assert_eq!(a.spirv, b.spirv, "{}", v.name);
    }
}

/// The CPU backend's vector form covers every renderer kernel except those that wait for
/// each other or share workgroup memory (which keep their host forms): a construct the
/// lowering does not know would silently cost the renderer its vector speed.
#[test]
fn renderer_kernels_have_a_vector_form() {
    let excluded = ["barriers or subgroup operations", "workgroup memory"];
    let mut lowered = 0;
    for v in renderer_variants() {
        match common::vector_form(&(v.build)(&v.spec), &v.name) {
            Ok(ir) => {
                assert!(ir.contains("define void @cohort_run("), "{}", v.name);
                lowered += 1;
            }
            Err(e) => assert!(
                excluded.contains(&e.as_str()),
                "{}: no vector form: {e}",
                v.name
            ),
        }
    }
    assert!(lowered >= 8, "only {lowered} renderer kernels lowered");
}

/// The paper's coherent configurations (warp and block groups, group draws, per-path or
/// group roulette) shade in the vector form too: at the CPU backend's specialisation each
/// invocation computes its group's draws, so `extend` keeps no barrier. Whole-group ends
/// (`group_any`) still wait for each other, and keep the host form.
#[test]
fn coherent_shading_has_a_vector_form_on_the_cpu() {
    use cohort::Group;
    use cohort_kernels::extend::extend;
    use cohort_kernels::integrator::NextEvent;
    use cohort_kernels::path_end::EachPath;
    use cohort_kernels::sampling::CoherentCosine;
    use cohort_kernels::shading::{SHADES_ALL, SHADES_GROUP_DRAWS};
    let cpu = cohort::runtime::Device::cpu_with(cohort::runtime::cpu::simd::Forms::Host).unwrap();
    for group in [Group::Warp, Group::Block(256)] {
        let spec =
            extend::spec(&cpu, Some(group)).with_constants(&[SHADES_ALL | SHADES_GROUP_DRAWS]);
        assert!(spec.recompute_group_share, "{group:?}");
        let built = extend::build::<CoherentCosine, EachPath, NextEvent>(&spec);
        if let Err(e) = common::vector_form(&built, &format!("extend {group:?}")) {
            panic!("{group:?}: no vector form: {e}");
        }
    }
}
