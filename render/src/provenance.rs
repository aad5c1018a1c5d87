//! What a render's EXR header says about how it was made, so that `cohort merge` can
//! tell whether files belong together: the same scene, size, seed, budget, integrator
//! and options (everything that decides a path's random numbers and what it computes),
//! from the same Cohort version, and disjoint shards of one split. The device that
//! rendered a part is recorded but not compared: any device renders the same paths
//! (bit for bit only on the same kind of device).

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;

use crate::{Budget, RenderOptions, Shard};

/// Which shards of a split a file holds: one for a render, several after a merge.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShardSet {
    pub indices: BTreeSet<u32>,
    pub count: u32,
}

impl From<Shard> for ShardSet {
    fn from(s: Shard) -> Self {
        ShardSet {
            indices: [s.index].into(),
            count: s.count,
        }
    }
}

impl ShardSet {
    /// Whether every shard of the split is present.
    pub fn is_complete(&self) -> bool {
        self.indices.len() as u64 == self.count as u64
    }

    /// The shards of the split that are absent.
    pub fn missing(&self) -> ShardSet {
        ShardSet {
            indices: (0..self.count)
                .filter(|k| !self.indices.contains(k))
                .collect(),
            count: self.count,
        }
    }

    /// `0-3,5/8` (ranges of consecutive indices, then the split's count).
    pub fn parse(s: &str) -> Result<ShardSet, String> {
        let bad = |why: &str| format!("shards `{s}`: {why} (expected e.g. 2/8 or 0-3,5/8)");
        let (list, n) = s.rsplit_once('/').ok_or_else(|| bad("no /N"))?;
        let count: u32 = n
            .trim()
            .parse()
            .map_err(|_| bad("N is not a whole number"))?;
        let mut indices = BTreeSet::new();
        for item in list.split(',') {
            let num = |v: &str| {
                v.trim()
                    .parse::<u32>()
                    .map_err(|_| bad("an index is not a whole number"))
            };
            let (a, b) = match item.split_once('-') {
                Some((a, b)) => (num(a)?, num(b)?),
                None => (num(item)?, num(item)?),
            };
            if a > b || b >= count {
                return Err(bad("an index is out of range"));
            }
            indices.extend(a..=b);
        }
        Ok(ShardSet { indices, count })
    }
}

impl fmt::Display for ShardSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut runs: Vec<(u32, u32)> = Vec::new();
        for &k in &self.indices {
            match runs.last_mut() {
                Some((_, end)) if *end + 1 == k => *end = k,
                _ => runs.push((k, k)),
            }
        }
        let list: Vec<String> = runs
            .iter()
            .map(|&(a, b)| {
                if a == b {
                    a.to_string()
                } else {
                    format!("{a}-{b}")
                }
            })
            .collect();
        write!(f, "{}/{}", list.join(","), self.count)
    }
}

/// How a render was made, as its EXR header records it (attributes `cohort.*`).
#[derive(Clone, Debug, PartialEq)]
pub struct Provenance {
    /// The Cohort version that rendered it.
    pub version: String,
    /// The `--scene` argument: an embedded name or an XML file's path.
    pub scene: String,
    /// `WxH`.
    pub size: String,
    pub seed: u32,
    /// `paths=P` or `time=Ts`: the budget that was split, not a shard's share of it.
    pub budget: String,
    /// `nee` or `path`.
    pub integrator: String,
    /// Every other option that changes the image, as `name=value` words (not `reorder`,
    /// which changes only the traversal's order of rays).
    pub options: String,
    /// `exact`: merged shards are the unsplit render's image (per-path sampling under a
    /// paths budget); `statistical`: an unbiased estimate of it.
    pub merge: String,
    pub shards: ShardSet,
    /// The device(s) that rendered it; not compared.
    pub device: String,
}

const PREFIX: &str = "cohort.";

impl Provenance {
    /// The provenance of a render of `scene` at `size` with `opts` on `device`.
    pub fn of(scene: &str, size: (u32, u32), opts: &RenderOptions, device: &str) -> Provenance {
        let o = opts;
        let budget = match o.budget {
            Budget::PathsPerPixel(p) => format!("paths={p}"),
            Budget::KernelTime(t) => format!("time={}s", t.as_secs_f64()),
        };
        let options = format!(
            "algorithm={} in-patch={:?} n={} group-rr={} whole-group-end={} rr-continue={} roulette={} interleave={} coherent-glossy={} \
             compact={} coherent-light={} light-cells={}",
            o.algorithm.name(),
            o.in_patch,
            o.patches_n,
            o.group_rr,
            o.whole_group_end.map(|q| q.to_string()).unwrap_or_else(|| "off".into()),
            o.rr_continue,
            o.roulette.name(),
            o.interleave,
            o.coherent_glossy,
            o.compact,
            o.coherent_light,
            o.light_cells,
        );
        let exact = o.per_path_sampling() && matches!(o.budget, Budget::PathsPerPixel(_));
        Provenance {
            version: env!("CARGO_PKG_VERSION").into(),
            scene: scene.into(),
            size: format!("{}x{}", size.0, size.1),
            seed: o.seed,
            budget,
            integrator: o.integrator.name().into(),
            options,
            merge: if exact { "exact" } else { "statistical" }.into(),
            shards: o.shard.into(),
            device: device.into(),
        }
    }

    /// The header attributes, `cohort.<field>`.
    pub fn to_attributes(&self) -> Vec<(String, String)> {
        self.fields()
            .into_iter()
            .map(|(k, v)| (format!("{PREFIX}{k}"), v))
            .collect()
    }

    /// Reads the attributes `to_attributes` wrote.
    pub fn from_attributes(attrs: &BTreeMap<String, String>) -> Result<Provenance, String> {
        let get = |k: &str| {
            attrs
                .get(&format!("{PREFIX}{k}"))
                .cloned()
                .ok_or_else(|| format!("its header has no {PREFIX}{k} attribute"))
        };
        if !attrs.contains_key("cohort.version") {
            return Err(
                "not rendered by `cohort render` (its header has no cohort.* attributes)".into(),
            );
        }
        Ok(Provenance {
            version: get("version")?,
            scene: get("scene")?,
            size: get("size")?,
            seed: get("seed")?
                .parse()
                .map_err(|_| "its cohort.seed is not a number")?,
            budget: get("budget")?,
            integrator: get("integrator")?,
            options: get("options")?,
            merge: get("merge")?,
            shards: ShardSet::parse(&get("shards")?)?,
            device: get("device")?,
        })
    }

    /// How `other` differs from this in what must agree for a merge (everything except
    /// the shards and the device), one phrase per field: empty when they belong together.
    pub fn differences(&self, other: &Provenance) -> Vec<String> {
        let theirs = other.fields();
        self.fields()
            .into_iter()
            .zip(theirs)
            .filter(|((k, a), (_, b))| !["shards", "device"].contains(k) && a != b)
            .map(|((k, a), (_, b))| format!("{k} `{a}` vs `{b}`"))
            .collect()
    }

    fn fields(&self) -> Vec<(&'static str, String)> {
        vec![
            ("version", self.version.clone()),
            ("scene", self.scene.clone()),
            ("size", self.size.clone()),
            ("seed", self.seed.to_string()),
            ("budget", self.budget.clone()),
            ("integrator", self.integrator.clone()),
            ("options", self.options.clone()),
            ("merge", self.merge.clone()),
            ("shards", self.shards.to_string()),
            ("device", self.device.clone()),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_sets_print_and_parse() {
        let s = ShardSet::parse("0-3,5,7-8/10").unwrap();
        assert_eq!(
            s.indices.iter().copied().collect::<Vec<_>>(),
            vec![0, 1, 2, 3, 5, 7, 8]
        );
        assert_eq!(s.to_string(), "0-3,5,7-8/10");
        assert_eq!(s.missing().to_string(), "4,6,9/10");
        assert!(!s.is_complete());
        assert!(ShardSet::parse("0-9/10").unwrap().is_complete());
        for bad in ["3/3", "2-1/4", "x/4", "1", "1/x"] {
            assert!(ShardSet::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn attributes_round_trip_and_differences_name_the_field() {
        let opts = RenderOptions {
            shard: Shard::new(1, 3).unwrap(),
            ..Default::default()
        };
        let p = Provenance::of("cornell", (32, 32), &opts, "llvmpipe");
        let attrs: BTreeMap<String, String> = p.to_attributes().into_iter().collect();
        let back = Provenance::from_attributes(&attrs).unwrap();
        assert_eq!(back, p);
        assert_eq!(back.merge, "exact");
        let other = Provenance::of(
            "cornell",
            (32, 32),
            &RenderOptions {
                seed: 2,
                shard: Shard::new(2, 3).unwrap(),
                ..opts
            },
            "another GPU",
        );
        assert_eq!(p.differences(&other), vec!["seed `1` vs `2`".to_string()]);
        assert!(Provenance::from_attributes(&BTreeMap::new())
            .unwrap_err()
            .contains("cohort render"));
    }
}
