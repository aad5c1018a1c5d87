//! A stack in a function-local array indexed at run time, driven by a loop: a
//! depth-first walk of an implicit binary tree, as a BVH traversal does. One stack starts
//! as `uninit()` (every entry is pushed before it is popped), the other zero-filled.
use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn stack_walk(#[builtin(global_index)] gi: u32, queries: &[UVec2], out: &mut [u32]) {
    let i = gi as usize;
    if i >= queries.len() {
        return;
    }
    // Leaves of the implicit tree over [0, 1024) are 1-wide; a query sums the leaf
    // indices in [lo, hi) and counts visited nodes.
    let q = queries[i];
    let mut stack: [u32; 32] = uninit();
    let mut lo_stack = [0u32; 32];
    let mut sp = 1usize;
    stack[0] = 1024;
    lo_stack[0] = 0;
    let mut sum = 0u32;
    let mut visited = 0u32;
    while sp > 0 {
        sp -= 1;
        let width = stack[sp];
        let lo = lo_stack[sp];
        visited += 1;
        if lo >= q.y || lo + width <= q.x {
            continue;
        }
        if width == 1 {
            sum += lo;
            continue;
        }
        let half = width / 2;
        stack[sp] = half;
        lo_stack[sp] = lo + half;
        stack[sp + 1] = half;
        lo_stack[sp + 1] = lo;
        sp += 2;
    }
    out[i] = sum ^ (visited << 20);
}
