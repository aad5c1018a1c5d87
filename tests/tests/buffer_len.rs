//! `len()` of a storage buffer is its element count on every backend and on the host,
//! also for an empty buffer (bound to a small stand-in whose size the GPU would otherwise
//! report: 4 for `&[u32]`, 1 for `&[Vec4]`) and for lengths that are not a multiple of
//! anything (docs/LANGUAGE.md, section 2).

mod common;

use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn lengths(#[builtin(global_index)] gi: u32, words: &[u32], vectors: &[Vec4], out: &mut [u32]) {
    if gi == 0 {
        out[0] = words.len() as u32;
        out[1] = vectors.len() as u32;
        out[2] = words.is_empty() as u32;
        out[3] = out.len() as u32;
    }
}

#[test]
fn len_is_the_element_count_even_when_empty() {
    for d in common::devices() {
        for (nw, nv) in [(0usize, 0usize), (0, 3), (5, 0), (7, 1), (1000, 333)] {
            let words = d.upload(&vec![1u32; nw]).unwrap();
            let vectors = d.upload(&vec![glam::Vec4::ONE; nv]).unwrap();
            let out = d.alloc::<u32>(4).unwrap();
            lengths::launch(&d, 1u32, &words, &vectors, &out).unwrap();
            let got = d.read(&out).unwrap();
            assert_eq!(
                got,
                vec![nw as u32, nv as u32, (nw == 0) as u32, 4],
                "{:?}: {nw} words, {nv} vectors",
                d.info().backend
            );
        }
    }
}

#[test]
fn len_on_the_host_is_the_slice_length() {
    let mut out = [0u32; 4];
    lengths(0, &[], &[glam::Vec4::ONE; 3], &mut out);
    assert_eq!(out, [0, 3, 1, 4]);
}
