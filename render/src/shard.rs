//! Splitting one render over processes, machines or devices: shard K of N renders the
//! K-th of N parts of every pixel's paths, and the parts merge into the whole
//! ([`crate::merge`]).
//!
//! A pixel's n-th path draws its random numbers from `stream(seed, pixel, n, bounce)`
//! (`cohort_kernels::rng`), whatever else runs beside it, so under a budget of P paths
//! per pixel shard K renders exactly paths `K*P/N .. (K+1)*P/N` of the unsplit run. With
//! per-path sampling (`normal`, per-path roulette, independent light samples) the merged
//! shards are that run's image up to the order of the float sums. Coherent
//! configurations also share draws within a group, keyed by the iteration of the
//! wavefront loop rather than by path; each shard takes those from its own seed
//! ([`Shard::group_seed`]), so shards are independent and their merge is an unbiased
//! estimate, not the unsplit run's image.

use std::fmt;
use std::ops::Range;

use cohort_kernels::rng::hash;

/// Shard `index` of `count` (`0/1` is the whole render).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Default for Shard {
    fn default() -> Self {
        Shard::WHOLE
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// The whole render, unsplit.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    pub fn new(index: u32, count: u32) -> Result<Shard, String> {
        if count == 0 || index >= count {
            return Err(format!(
                "shard {index}/{count}: K/N needs N >= 1 and 0 <= K < N"
            ));
        }
        Ok(Shard { index, count })
    }

    /// `K/N`, as `--shard` and Slurm's `$SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT` give it.
    pub fn parse(s: &str) -> Result<Shard, String> {
        let (k, n) = s
            .split_once('/')
            .ok_or_else(|| format!("shard `{s}` is not of the form K/N (e.g. 0/4)"))?;
        let num = |v: &str| {
            v.trim().parse::<u32>().map_err(|_| {
                format!("shard `{s}` is not of the form K/N: `{v}` is not a whole number")
            })
        };
        Shard::new(num(k)?, num(n)?)
    }

    /// The paths of every pixel this shard renders under a budget of `paths` per pixel.
    /// Consecutive shards' ranges tile `0..paths`; a range is empty when N > P.
    pub fn paths(self, paths: u32) -> Range<u32> {
        let at = |k: u32| (k as u64 * paths as u64 / self.count as u64) as u32;
        at(self.index)..at(self.index + 1)
    }

    /// The first path index under a time budget, where the number of paths is not known
    /// in advance: shards start 2^32 / N paths apart, so they never render the same path
    /// (unless one renders more than 2^32 / N paths per pixel).
    pub fn time_first_path(self) -> u32 {
        ((self.index as u64) << 32).div_euclid(self.count as u64) as u32
    }

    /// The shard split into `parts` (one per device): part d is shard K*parts + d of
    /// N*parts, and together they render exactly this shard's paths, since
    /// (K*parts)*P / (N*parts) = K*P/N.
    pub fn split(self, parts: u32) -> Result<Vec<Shard>, String> {
        let count = self
            .count
            .checked_mul(parts)
            .filter(|_| parts > 0)
            .ok_or_else(|| format!("cannot split shard {self} into {parts} parts"))?;
        Ok((0..parts)
            .map(|d| Shard {
                index: self.index * parts + d,
                count,
            })
            .collect())
    }

    /// The seed of the group draws: `seed` itself for the whole render (so an unsplit run
    /// draws what it always did), otherwise hashed with the shard's index and count, so
    /// that no two shards of a render, nor a part of one device and a shard of another
    /// split, share group draws.
    pub fn group_seed(self, seed: u32) -> u32 {
        if self == Shard::WHOLE {
            seed
        } else {
            hash(seed ^ hash(self.index ^ hash(self.count.wrapping_add(0x51a4d))))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_rejects() {
        assert_eq!(Shard::parse("2/7").unwrap(), Shard { index: 2, count: 7 });
        for bad in ["7/7", "1/0", "a/3", "3", "-1/4", "1/2/3"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
        assert_eq!(Shard::parse("3/4").unwrap().to_string(), "3/4");
    }

    #[test]
    fn ranges_tile_the_budget() {
        for n in 1..=9 {
            for p in [1, 2, 3, 7, 64, 1000] {
                let mut next = 0;
                for k in 0..n {
                    let r = Shard::new(k, n).unwrap().paths(p);
                    assert_eq!(r.start, next, "{k}/{n} of {p}");
                    next = r.end;
                }
                assert_eq!(next, p);
            }
        }
    }

    #[test]
    fn a_split_shard_renders_the_same_paths() {
        for (s, parts, p) in [
            (Shard::new(1, 3).unwrap(), 2, 64),
            (Shard::new(4, 7).unwrap(), 3, 10),
        ] {
            let split = s.split(parts).unwrap();
            assert_eq!(split.first().unwrap().paths(p).start, s.paths(p).start);
            assert_eq!(split.last().unwrap().paths(p).end, s.paths(p).end);
            for w in split.windows(2) {
                assert_eq!(w[0].paths(p).end, w[1].paths(p).start);
            }
        }
    }

    #[test]
    fn time_shards_start_apart_and_group_seeds_differ() {
        assert_eq!(Shard::WHOLE.time_first_path(), 0);
        assert_eq!(Shard::new(1, 2).unwrap().time_first_path(), 1 << 31);
        assert_eq!(Shard::new(3, 4).unwrap().time_first_path(), 3 << 30);
        assert_eq!(Shard::WHOLE.group_seed(5), 5);
        let seeds: std::collections::HashSet<u32> = [(0, 2), (1, 2), (0, 4), (1, 4), (2, 4)]
            .iter()
            .map(|&(k, n)| Shard::new(k, n).unwrap().group_seed(5))
            .collect();
        assert_eq!(seeds.len(), 5);
    }
}
