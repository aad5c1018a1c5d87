//! GPU timestamps → `DispatchStats`. Both backends write a begin/end timestamp pair around
//! every dispatch into one query pool per submission, read the raw ticks back after the
//! wait, and turn each pair into nanoseconds here.

use crate::DispatchStats;

/// `ticks` holds `[begin0, end0, begin1, end1, ...]`. `valid_bits` is the queue family's
/// timestampValidBits: counters narrower than 64 bits wrap, so the difference is taken
/// modulo 2^valid_bits. `period_ns` is nanoseconds per tick.
pub(crate) fn stats_from_ticks(
    ticks: &[u64],
    valid_bits: u32,
    period_ns: f64,
) -> Vec<DispatchStats> {
    let mask = if valid_bits >= 64 {
        u64::MAX
    } else {
        (1u64 << valid_bits) - 1
    };
    ticks
        .chunks_exact(2)
        .map(|pair| {
            let delta = pair[1].wrapping_sub(pair[0]) & mask;
            DispatchStats {
                gpu_time_ns: Some((delta as f64 * period_ns).round() as u64),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wraps_narrow_counters_and_scales_by_period() {
        let s = stats_from_ticks(&[10, 30, (1 << 36) - 5, 5], 36, 2.5);
        assert_eq!(s[0].gpu_time_ns, Some(50));
        assert_eq!(s[1].gpu_time_ns, Some(25));
    }
}
