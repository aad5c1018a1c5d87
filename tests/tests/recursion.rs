//! Recursion that the compile-time checks cannot see (helpers reached through generic or
//! trait dispatch; here built directly through the IR builder, as generated code does) is
//! the kernel's build error naming the chain of calls, reported as the user's error, never
//! a panic or a stack overflow. Direct and mutual recursion of `#[kernel_fn]` helpers are
//! compile errors: `tests/compile_fail/recursive_helper.rs`, `mutual_recursion.rs`.

use cohort::ir::{self, builtin, AsPlace, Buffer, Val};
use cohort::{Group, KernelInfo, Spec};

static INFO: KernelInfo = KernelInfo {
    name: "ping_pong",
    file: "src/ping.rs",
    line: 3,
    column: 1,
    workgroup_size: 64,
    group: Group::Thread,
    finite_loops: false,
};

struct Ping;
struct Pong;

fn ping(n: Val<u32>) -> Val<u32> {
    ir::function::<Ping, _, _>("ping", &["n"], (n,), |(n,)| pong(n))
}

fn pong(n: Val<u32>) -> Val<u32> {
    ir::function::<Pong, _, _>("pong", &["n"], (n,), |(n,)| ping(n))
}

#[test]
fn recursion_through_helpers_is_a_build_error_with_the_chain() {
    let built = ir::build_kernel(&INFO, Spec::portable(&INFO, Group::Thread), || {
        let gi = builtin::global_index();
        let out = Buffer::<u32>::declare("out", true);
        ir::place_index(out.as_place(), gi).set(ping(gi));
    });
    let Err(err) = cohort::emit::emit(&built) else {
        panic!("a recursive kernel must not build");
    };
    let msg = err.to_string();
    assert_eq!(err.stage, "build", "{msg}");
    assert!(
        msg.starts_with("src/ping.rs:3:1: kernel `ping_pong`"),
        "{msg}"
    );
    assert!(
        msg.contains("ping -> pong -> ping") && msg.contains("cannot recurse"),
        "{msg}"
    );
    assert!(
        !msg.contains("compiler bug"),
        "a user's recursion is not a compiler bug: {msg}"
    );
}
