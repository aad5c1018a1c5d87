//! `COHORT_CPU_SIMD_PERF_MAP=1`: each vector form, once linked, is named in
//! `/tmp/perf-PID.map`, the file Linux `perf` reads for code that a JIT made. `perf
//! report` then shows a kernel's samples under its name instead of as bare addresses
//! spread over the JIT's pages. Without it, a profile of a render on the CPU backend says
//! only that about half its time is "[JIT]".

use std::io::Write as _;
use std::sync::OnceLock;

/// Whether the environment asks for the map.
pub fn enabled() -> bool {
    static ON: OnceLock<bool> = OnceLock::new();
    *ON.get_or_init(|| std::env::var("COHORT_CPU_SIMD_PERF_MAP").is_ok_and(|v| v == "1"))
}

/// Appends `addr size name` for a kernel's code: the `.text` section (of `size` bytes,
/// from [`text_size`]) that the JIT placed at `addr`, the entry being its first function.
/// Called under the JIT's linker lock, so lines from different threads never interleave.
pub fn record(name: &str, addr: usize, size: u64) {
    let path = format!("/tmp/perf-{}.map", std::process::id());
    // A profile without names is all that a failure here costs.
    if let Ok(mut f) = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
    {
        let _ = writeln!(f, "{addr:x} {size:x} cohort vector form {name}");
    }
}

/// The size of the `.text` section of a 64-bit little-endian ELF object, or `None` if
/// `object` is not one.
pub fn text_size(object: &[u8]) -> Option<u64> {
    let u16_at = |at: usize| Some(u16::from_le_bytes(object.get(at..at + 2)?.try_into().ok()?));
    let u32_at = |at: usize| Some(u32::from_le_bytes(object.get(at..at + 4)?.try_into().ok()?));
    let u64_at = |at: usize| Some(u64::from_le_bytes(object.get(at..at + 8)?.try_into().ok()?));
    // ELFCLASS64, little-endian.
    if object.get(..6)? != b"\x7fELF\x02\x01" {
        return None;
    }
    let shoff = usize::try_from(u64_at(0x28)?).ok()?;
    let (entsize, count, names) = (
        usize::from(u16_at(0x3a)?),
        usize::from(u16_at(0x3c)?),
        usize::from(u16_at(0x3e)?),
    );
    let header = |i: usize| shoff.checked_add(i.checked_mul(entsize)?);
    let strings = usize::try_from(u64_at(header(names)? + 0x18)?).ok()?;
    (0..count).find_map(|i| {
        let h = header(i)?;
        let name = strings.checked_add(usize::try_from(u32_at(h)?).ok()?)?;
        (object.get(name..name + 6)? == b".text\0").then(|| u64_at(h + 0x20))?
    })
}

#[cfg(test)]
mod tests {
    use super::text_size;

    #[test]
    fn refuses_what_is_not_a_64_bit_elf_object() {
        assert_eq!(text_size(b""), None);
        assert_eq!(text_size(b"\x7fELF\x01\x01 a 32-bit one"), None);
        let mut truncated = b"\x7fELF\x02\x01".to_vec();
        truncated.resize(0x40, 0xff);
        assert_eq!(text_size(&truncated), None);
    }
}
