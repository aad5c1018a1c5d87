//! A post-pass over the SPIR-V naga writes for the Vulkan backend: function-local arrays
//! lose the zero initializer naga gives every local variable.
//!
//! Why: naga initialises each `Function` variable with `OpConstantNull` (WGSL zero-fills
//! variables). A kernel's locals never need it: every `let` is assigned before it is read
//! (rustc's definite-initialisation check on the kernel's host form), with one exception
//! by design, `let mut x: [T; N] = uninit();` (docs/LANGUAGE.md, "Uninitialised locals"),
//! whose elements are unspecified until written. A null initializer on a 64-entry
//! traversal stack is 256 bytes of local-memory stores per invocation that are never read:
//! removing it with the stack's explicit zero fill measured 1.12x renderer paths/s on
//! confroom (H200, BENCHMARKS.md, 2026-11-27, d2bc83f and 807cf8c). Only arrays are
//! touched: scalars, vectors and structs live in registers, where the initializer costs
//! nothing.

use std::collections::HashSet;

const OP_TYPE_ARRAY: u32 = 28;
const OP_TYPE_POINTER: u32 = 32;
const OP_VARIABLE: u32 = 59;
const STORAGE_FUNCTION: u32 = 7;
const HEADER_WORDS: usize = 5;

/// Removes the initializer of every `Function`-class `OpVariable` of array type; returns
/// how many it removed. A module it cannot parse (a truncated instruction) is left as it
/// was.
pub fn drop_array_local_initializers(words: &mut Vec<u32>) -> usize {
    let Some(insts) = instructions(words) else {
        return 0;
    };
    let mut arrays = HashSet::new();
    let mut array_pointers = HashSet::new();
    for &(at, len) in &insts {
        let op = words[at] & 0xffff;
        if op == OP_TYPE_ARRAY && len >= 2 {
            arrays.insert(words[at + 1]);
        } else if op == OP_TYPE_POINTER
            && len >= 4
            && words[at + 2] == STORAGE_FUNCTION
            && arrays.contains(&words[at + 3])
        {
            array_pointers.insert(words[at + 1]);
        }
    }
    let mut out = Vec::with_capacity(words.len());
    out.extend_from_slice(&words[..HEADER_WORDS]);
    let mut dropped = 0;
    for &(at, len) in &insts {
        let inst = &words[at..at + len];
        // OpVariable: result type, result id, storage class, [initializer].
        if inst[0] & 0xffff == OP_VARIABLE
            && len == 5
            && inst[3] == STORAGE_FUNCTION
            && array_pointers.contains(&inst[1])
        {
            out.push((4 << 16) | OP_VARIABLE);
            out.extend_from_slice(&inst[1..4]);
            dropped += 1;
        } else {
            out.extend_from_slice(inst);
        }
    }
    *words = out;
    dropped
}

/// (offset, word count) of each instruction after the header.
fn instructions(words: &[u32]) -> Option<Vec<(usize, usize)>> {
    let mut at = HEADER_WORDS;
    let mut insts = Vec::new();
    while at < words.len() {
        let len = (words[at] >> 16) as usize;
        if len == 0 || at + len > words.len() {
            return None;
        }
        insts.push((at, len));
        at += len;
    }
    Some(insts)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inst(op: u32, operands: &[u32]) -> Vec<u32> {
        let mut v = vec![((operands.len() as u32 + 1) << 16) | op];
        v.extend_from_slice(operands);
        v
    }

    #[test]
    fn only_function_arrays_lose_their_initializer() {
        let mut w = vec![0x0723_0203, 0x0001_0300, 0, 100, 0];
        w.extend(inst(21, &[1, 32, 0])); // %1 = OpTypeInt 32 0
        w.extend(inst(28, &[2, 1, 3])); // %2 = OpTypeArray %1 %3
        w.extend(inst(32, &[4, 7, 2])); // %4 = OpTypePointer Function %2
        w.extend(inst(32, &[5, 7, 1])); // %5 = OpTypePointer Function %1
        w.extend(inst(32, &[6, 4, 2])); // %6 = OpTypePointer Workgroup %2
        w.extend(inst(46, &[2, 7])); // %7 = OpConstantNull %2
        w.extend(inst(59, &[4, 8, 7, 7])); // %8 = OpVariable %4 Function %7
        w.extend(inst(59, &[5, 9, 7, 10])); // %9 = OpVariable %5 Function %10
        w.extend(inst(59, &[6, 11, 4])); // %11 = OpVariable %6 Workgroup
        let before = w.clone();
        assert_eq!(drop_array_local_initializers(&mut w), 1);
        assert_eq!(w.len(), before.len() - 1);
        let mut expect = before[..before.len() - 14].to_vec();
        expect.extend(inst(59, &[4, 8, 7]));
        expect.extend(inst(59, &[5, 9, 7, 10]));
        expect.extend(inst(59, &[6, 11, 4]));
        assert_eq!(w, expect);
    }

    #[test]
    fn a_truncated_module_is_left_alone() {
        let mut w = vec![0x0723_0203, 0x0001_0300, 0, 100, 0, (9 << 16) | 59, 1];
        let before = w.clone();
        assert_eq!(drop_array_local_initializers(&mut w), 0);
        assert_eq!(w, before);
    }
}
