//! One fast, stable 64-bit hash of bytes, for the caches' keys and checksums.

/// A multiply-xor fold over 8-byte words, seeded with `seed`: the same bytes give the same
/// hash on every run and machine. Every dispatch looks its pipeline up by such a hash, so it
/// must be cheap for tens of kilobytes of code (SipHash measured tens of microseconds per
/// dispatch of the path tracer's kernels). Each step is a bijection of the state, so a
/// changed word always changes the hash of otherwise equal input, which is what a checksum
/// for torn or damaged files needs. Not for adversarial input.
pub fn hash64(seed: u64, bytes: &[u8]) -> u64 {
    const K: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut h = seed ^ bytes.len() as u64;
    let mut chunks = bytes.chunks_exact(8);
    for c in &mut chunks {
        let w = u64::from_le_bytes(c.try_into().expect("8 bytes"));
        h = (h ^ w).wrapping_mul(K).rotate_left(29);
    }
    for &b in chunks.remainder() {
        h = (h ^ b as u64).wrapping_mul(K);
    }
    h
}

#[cfg(test)]
mod tests {
    use super::hash64;

    #[test]
    fn any_changed_byte_changes_the_hash() {
        let data: Vec<u8> = (0..37u8).collect();
        let h = hash64(5, &data);
        assert_eq!(h, hash64(5, &data), "stable");
        assert_ne!(h, hash64(6, &data), "seeded");
        assert_ne!(h, hash64(5, &data[..36]), "length counts");
        for i in 0..data.len() {
            let mut d = data.clone();
            d[i] ^= 0x10;
            assert_ne!(h, hash64(5, &d), "byte {i}");
        }
    }
}
