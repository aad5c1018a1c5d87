//! A naga validation failure means the compiler produced invalid IR from a kernel that
//! type-checked: it must be reported as a compiler bug at the kernel's definition, with
//! naga's message, not as a panic or a bare validation dump. This builds deliberately
//! invalid IR through the builder's escape hatch (`Val::from_handle` vouches for a type
//! it does not have) and checks the report.

use cohort::ir::{self, builtin, AsPlace, Buffer, Val};
use cohort::{Group, KernelInfo, Spec};

static INFO: KernelInfo = KernelInfo {
    name: "broken",
    file: "src/broken.rs",
    line: 42,
    column: 7,
    workgroup_size: 64,
    group: Group::Thread,
    finite_loops: false,
};

#[test]
fn validation_failure_is_reported_at_the_kernel() {
    let built = ir::build_kernel(&INFO, Spec::portable(&INFO, Group::Thread), || {
        let gi = builtin::global_index();
        let out = Buffer::<u32>::declare("out", true);
        // A bool expression passed off as a u32: stored into a u32 buffer.
        let lie: Val<u32> = Val::from_handle(ir::lt(gi, ir::lit(3u32)).handle());
        ir::place_index(out.as_place(), gi).set(lie);
    });
    let err = match cohort::emit::emit(&built) {
        Ok(_) => panic!("invalid IR passed validation"),
        Err(e) => e,
    };
    let msg = err.to_string();
    assert!(
        msg.starts_with("src/broken.rs:42:7: kernel `broken`"),
        "{msg}"
    );
    assert!(msg.contains("compiler bug"), "{msg}");
    assert!(msg.contains("validation"), "{msg}");
    assert_eq!(err.stage, "validate");
}
