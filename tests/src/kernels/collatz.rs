//! Loops: `while`, `loop` with `break` and `continue`, `for` over inclusive, exclusive
//! and reversed ranges, compound assignment.
use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn collatz(
    #[builtin(global_index)] i: u32,
    seeds: &[u32],
    steps: &mut [u32],
    odd_digits: &mut [u32],
) {
    let i = i as usize;
    if i >= seeds.len() {
        return;
    }
    let mut n = seeds[i];
    let mut count = 0u32;
    while n != 1 && n != 0 {
        if n % 2 == 0 {
            n /= 2;
        } else {
            n = 3 * n + 1;
        }
        count += 1;
    }
    steps[i] = count;

    // Sum the odd decimal digits of the seed, skipping zeros, counting down a range.
    let mut m = seeds[i];
    let mut sum = 0u32;
    loop {
        if m == 0 {
            break;
        }
        let d = m % 10;
        m /= 10;
        if d % 2 == 0 {
            continue;
        }
        sum += d;
    }
    for k in 1..=3u32 {
        sum += k;
    }
    for k in (0..4u32).rev() {
        sum = sum * 2 + k;
    }
    odd_digits[i] = sum;
}
