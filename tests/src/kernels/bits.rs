//! Casts and bit operations: `as` between integer and float types, `to_bits` /
//! `from_bits`, shifts, rotations, bit counts, wrapping arithmetic.
use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn bits(#[builtin(global_index)] gi: u32, input: &[u32], out: &mut [UVec4]) {
    let i = gi as usize;
    if i >= input.len() {
        return;
    }
    let x = input[i];
    let signed = x as i32;
    let f = (x >> 8) as f32 * (1.0 / 16777216.0);
    let back = f32::from_bits(f.to_bits() ^ 0x8000_0000);
    let a = x.rotate_left(7) ^ x.rotate_right(3);
    let b = x.count_ones() + x.leading_zeros() * 64 + x.trailing_zeros() * 4096;
    let c = ((signed >> 3) as u32) ^ (!x & 0xffff) | ((signed < 0) as u32);
    let d = ((back * -1000.0) as u32)
        .wrapping_add((-(signed % 1000)) as u32)
        .wrapping_add(x.reverse_bits().wrapping_add(x.wrapping_mul(2654435761)));
    out[i] = UVec4::new(a, b, c, d);
}
