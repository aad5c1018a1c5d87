//! Where a dispatch's list of rays is cut into its streams, one per core.
//!
//! A slot keeps its pixel for the whole render, so a dispatch's list runs over the image in
//! order, and equal cuts give one core the image's top (ceiling and light, quickly traced)
//! and the other its bottom (the objects): the slower stream took 1.13x the mean stream's
//! time over a stanford-like render, its core idle in between. Dealing the slots out in
//! interleaved blocks evened the streams but made the stages after them slower (each
//! core then read slots that the other had written: `extend` 1.04-1.08x). So the cuts stay
//! contiguous and move instead: each dispatch's cuts follow the time per ray that each
//! stream took in the dispatch before (of the same query), which changes slowly over a
//! render.

use std::sync::Mutex;

/// The cuts of the last dispatch of each query (closest hit, any hit), as fractions of the
/// list: `0 = c[0] < c[1] < ... < c[streams] = 1`.
static CUTS: [Mutex<Vec<f64>>; 2] = [Mutex::new(Vec::new()), Mutex::new(Vec::new())];

/// How far the cuts move towards the balance the last dispatch measured: halfway, so that
/// one noisy timing does not swing them.
const STEP: f64 = 0.5;

/// A stream's share of the list stays within this factor of an equal cut's.
const MIN_SHARE: f64 = 0.25;

/// The cuts for a list of `n` rays in `streams` streams: positions in the list, multiples
/// of `align` (but the last, `n`), from the last dispatch's of the query `any`.
pub(super) fn cuts(any: bool, n: usize, streams: usize, align: usize) -> Vec<usize> {
    let fractions = {
        let last = CUTS[any as usize].lock().unwrap_or_else(|e| e.into_inner());
        if last.len() == streams + 1 {
            last.clone()
        } else {
            equal(streams)
        }
    };
    positions(&fractions, n, align)
}

/// Records the time each stream took with `cuts` (positions in a list of `n` rays), for
/// the next dispatch of the query `any`.
pub(super) fn record(any: bool, cuts: &[usize], n: usize, seconds: &[f64]) {
    let fractions: Vec<f64> = cuts.iter().map(|&c| c as f64 / n as f64).collect();
    let next = rebalanced(&fractions, seconds);
    *CUTS[any as usize].lock().unwrap_or_else(|e| e.into_inner()) = next;
}

fn equal(streams: usize) -> Vec<f64> {
    (0..=streams).map(|k| k as f64 / streams as f64).collect()
}

/// Fractions as positions in a list of `n`, rounded to multiples of `align`, increasing.
fn positions(fractions: &[f64], n: usize, align: usize) -> Vec<usize> {
    let last = fractions.len() - 1;
    let mut out: Vec<usize> = fractions
        .iter()
        .enumerate()
        .map(|(k, f)| {
            if k == last {
                n
            } else {
                ((f * n as f64 / align as f64).round() as usize * align).min(n)
            }
        })
        .collect();
    for k in 1..out.len() {
        out[k] = out[k].max(out[k - 1]);
    }
    out
}

/// The cuts that would have given each stream the same time, had each stream's rays cost
/// what they did (its time spread evenly over its share), moved [`STEP`] of the way there
/// from `cuts`, each share kept within [`MIN_SHARE`] of an equal one.
fn rebalanced(cuts: &[f64], seconds: &[f64]) -> Vec<f64> {
    let streams = seconds.len();
    let total: f64 = seconds.iter().sum();
    // (NaN compares false: a NaN total falls back too.)
    if streams < 2
        || total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        || cuts.len() != streams + 1
    {
        return equal(streams.max(1));
    }
    // The cumulative time as a piecewise linear function of the position in the list, cut
    // into equal parts.
    let mut target = vec![0.0; streams + 1];
    let mut k = 0;
    let mut before = 0.0;
    for (j, t) in target.iter_mut().enumerate().take(streams).skip(1) {
        let want = total * j as f64 / streams as f64;
        while k < streams - 1 && before + seconds[k] < want {
            before += seconds[k];
            k += 1;
        }
        let within = if seconds[k] > 0.0 {
            ((want - before) / seconds[k]).clamp(0.0, 1.0)
        } else {
            0.0
        };
        *t = cuts[k] + within * (cuts[k + 1] - cuts[k]);
    }
    target[streams] = 1.0;
    let min = MIN_SHARE / streams as f64;
    let mut next: Vec<f64> = cuts
        .iter()
        .zip(&target)
        .map(|(c, t)| c + STEP * (t - c))
        .collect();
    next[0] = 0.0;
    next[streams] = 1.0;
    for j in 1..streams {
        let lo = next[j - 1] + min;
        let hi = 1.0 - min * (streams - j) as f64;
        next[j] = next[j].clamp(lo, hi.max(lo));
    }
    next
}

#[cfg(test)]
mod tests {
    use super::{positions, rebalanced, MIN_SHARE, STEP};

    /// Streams that took equal times keep their cuts.
    #[test]
    fn equal_times_keep_the_cuts() {
        let cuts = [0.0, 0.3, 0.7, 1.0];
        let next = rebalanced(&cuts, &[2.0, 2.0, 2.0]);
        for (a, b) in cuts.iter().zip(&next) {
            assert!((a - b).abs() < 1e-12, "{cuts:?} -> {next:?}");
        }
    }

    /// A stream whose rays cost three times the other's gets a smaller share: with the
    /// halves' times at 3 : 1, each spread evenly over its half, half the time has passed
    /// at 1/3 of the list, and the cut moves `STEP` of the way from 1/2 to there.
    #[test]
    fn a_slow_stream_gives_up_rays() {
        let next = rebalanced(&[0.0, 0.5, 1.0], &[3.0, 1.0]);
        let want = 0.5 + STEP * ((0.5 * 2.0 / 3.0) - 0.5);
        assert!((next[1] - want).abs() < 1e-12, "{next:?}, want {want}");
        // Repeated with rays that cost 3 : 1 wherever the cut is, it settles at 1/4, where
        // the times are equal.
        let mut cuts = vec![0.0, 0.5, 1.0];
        for _ in 0..60 {
            let (a, b) = (cuts[1] * 3.0, (1.0 - cuts[1]) * 1.0);
            cuts = rebalanced(&cuts, &[a, b]);
        }
        assert!((cuts[1] - 0.25).abs() < 1e-6, "{cuts:?}");
    }

    /// No share shrinks below `MIN_SHARE` of an equal one, however lopsided the times.
    #[test]
    fn shares_keep_a_floor() {
        let mut cuts = vec![0.0, 0.5, 1.0];
        for _ in 0..20 {
            cuts = rebalanced(&cuts, &[1.0e6, 1.0]);
        }
        assert!(cuts[1] >= MIN_SHARE / 2.0 - 1e-12, "{cuts:?}");
        // Timings of nothing (a zero or NaN total) fall back to equal cuts.
        assert_eq!(rebalanced(&cuts, &[0.0, 0.0]), vec![0.0, 0.5, 1.0]);
        assert_eq!(rebalanced(&cuts, &[f64::NAN, 1.0]), vec![0.0, 0.5, 1.0]);
    }

    /// Positions are multiples of the alignment, increasing, and end at the list's length.
    #[test]
    fn positions_are_aligned_and_end_at_the_length() {
        let p = positions(&[0.0, 0.3, 0.34, 1.0], 1000, 16);
        assert_eq!(p, vec![0, 304, 336, 1000]);
        // Cuts that round to the same multiple leave a stream empty.
        let p = positions(&[0.0, 0.33, 0.34, 1.0], 1000, 16);
        assert_eq!(p, vec![0, 336, 336, 1000]);
        let p = positions(&[0.0, 0.5, 1.0], 10, 16);
        assert_eq!(p, vec![0, 0, 10]);
    }
}
