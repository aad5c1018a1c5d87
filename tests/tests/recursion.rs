//! Recursion through several helpers (which no single `#[kernel_fn]` can see) is a build
//! error of the kernel naming the chain of calls, reported by `launch` as the user's error,
//! never a panic or a stack overflow; for helpers taking values (naga functions) and helpers
//! taking buffers (inlined). Direct recursion is a compile error:
//! `tests/compile_fail/recursive_helper.rs`.

mod common;

use cohort::prelude::*;

#[kernel_fn]
pub fn even(n: u32) -> u32 {
    if n == 0 {
        1
    } else {
        odd(n - 1)
    }
}

#[kernel_fn]
pub fn odd(n: u32) -> u32 {
    if n == 0 {
        0
    } else {
        even(n - 1)
    }
}

#[kernel(workgroup = 64)]
pub fn parity(#[builtin(global_index)] i: u32, out: &mut [u32]) {
    if (i as usize) < out.len() {
        out[i as usize] = even(i);
    }
}

#[kernel_fn]
pub fn walk_a(xs: &[u32], i: u32) -> u32 {
    if i == 0 {
        xs[0]
    } else {
        walk_b(xs, i - 1)
    }
}

#[kernel_fn]
pub fn walk_b(xs: &[u32], i: u32) -> u32 {
    walk_a(xs, i)
}

#[kernel(workgroup = 64)]
pub fn walker(#[builtin(global_index)] i: u32, xs: &[u32], out: &mut [u32]) {
    out[i as usize] = walk_a(xs, i);
}

fn expect_cycle(err: cohort::Error, chain: &str) {
    let msg = err.to_string();
    assert!(matches!(&err, cohort::Error::Compile(e) if e.stage == "build"), "{msg}");
    assert!(msg.contains(chain), "expected `{chain}` in: {msg}");
    assert!(msg.contains("cannot recurse"), "{msg}");
    assert!(!msg.contains("compiler bug"), "a user's recursion is not a compiler bug: {msg}");
}

#[test]
fn mutual_recursion_is_a_build_error_with_the_chain() {
    // The host form is plain Rust and recurses as Rust does.
    assert_eq!(even(10), 1);
    assert_eq!(walk_a(&[7], 3), 7);
    for d in common::devices() {
        let out = d.alloc::<u32>(64).unwrap();
        expect_cycle(parity::launch(&d, 64u32, &out).unwrap_err(), "even -> odd -> even");
        let xs = d.upload(&[1u32; 64]).unwrap();
        expect_cycle(walker::launch(&d, 64u32, &xs, &out).unwrap_err(), "walk_a -> walk_b -> walk_a");
    }
}
