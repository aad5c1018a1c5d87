//! The sweep's plan: the options of `cohort figures`, checked before anything is rendered;
//! the columns of the figures; the groups of points the sweep measures, in the fixed order
//! that shards split and the merge restores; and the plan's fingerprint, which a shard's
//! CSV carries so that the merge can tell shards of one sweep from others and rebuild the
//! plan without the scene files.

use std::path::{Path, PathBuf};
use std::time::Duration;

use cohort_render::{Algorithm, IntegratorKind};
use cohort_scenes::embedded;

use super::FiguresArgs;
use crate::choices;

pub const DEFAULT_SCENES: &str = "confroom,fairyforest,sponza,stanford";
pub const DEFAULT_CONFIGS: &str = "normal,warp,block_256,block_512,block_1024,grid";
pub const DEFAULT_NS: &str = "4,8,16,32,64,100,250,500,1000";

/// The columns of the figures: the paper's three (Russian roulette per path or per
/// group, compaction or not) and whole-group termination with and without compaction.
pub const COLUMNS: [Column; 5] = [
    Column {
        key: "path",
        group_rr: false,
        whole: false,
        compact: true,
        suffix: "",
        title: "per-path RR, compaction",
    },
    Column {
        key: "rr",
        group_rr: true,
        whole: false,
        compact: true,
        suffix: "_rr",
        title: "_rr: group RR, compaction",
    },
    Column {
        key: "rr-no",
        group_rr: true,
        whole: false,
        compact: false,
        suffix: "_rr (NO)",
        title: "_rr (NO): group RR, no compaction",
    },
    Column {
        key: "whole",
        group_rr: true,
        whole: true,
        compact: true,
        suffix: "_whole",
        title: "_whole: whole-group end, compaction",
    },
    Column {
        key: "whole-no",
        group_rr: true,
        whole: true,
        compact: false,
        suffix: "_whole (NO)",
        title: "_whole (NO): whole-group end, no compaction",
    },
];

#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Column {
    /// Its name in --columns.
    pub key: &'static str,
    pub group_rr: bool,
    /// Whole-group termination (`--rr whole`).
    pub whole: bool,
    pub compact: bool,
    pub suffix: &'static str,
    pub title: &'static str,
}

impl Column {
    /// The CSV's `rr` value.
    pub fn rr(&self) -> &'static str {
        match (self.whole, self.group_rr) {
            (true, _) => "whole",
            (false, true) => "group",
            (false, false) => "path",
        }
    }

    /// The column of a CSV row, from its `rr` and `compaction` fields.
    pub fn from_csv(rr: &str, compaction: &str) -> Option<Column> {
        COLUMNS
            .into_iter()
            .find(|c| c.rr() == rr && c.compact.to_string() == compaction)
    }
}

pub struct SceneSpec {
    /// As given: an embedded name or a path.
    pub arg: String,
    /// Used in file names and the CSV.
    pub label: String,
}

pub struct Plan {
    pub scenes: Vec<SceneSpec>,
    /// Coherent configurations, in the order given (`normal` is always run on its own).
    pub configs: Vec<Algorithm>,
    pub ns: Vec<u32>,
    /// Interleave factors: 1 (Fig. 4/5) first, then those of Fig. 7.
    pub interleaves: Vec<u32>,
    pub time: Duration,
    pub reference_time: Duration,
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub seed: u32,
    pub out_dir: PathBuf,
    pub slices: u32,
    pub columns: Vec<Column>,
    pub end_continue: f32,
    pub integrator: IntegratorKind,
}

/// One group of points, measured together round-robin: `normal` and every coherent
/// configuration of its column, for one scene, D, column and N.
pub struct Group {
    /// Its place in the plan's order (`Plan::groups`): shard K of N measures the groups
    /// whose index is K modulo N.
    pub index: usize,
    /// Index into `Plan::scenes`.
    pub scene: usize,
    pub interleave: u32,
    pub column: Column,
    pub n: u32,
}

impl Plan {
    /// The coherent configurations measured in `column` (the grid cannot vote, so it has
    /// no whole-group termination).
    pub fn configs_of(&self, column: &Column) -> Vec<Algorithm> {
        self.configs
            .iter()
            .copied()
            .filter(|a| !(column.whole && a.group == cohort::Group::Grid))
            .collect()
    }

    /// The points of a group, `normal` first, in the order they are measured and written.
    pub fn algorithms_of(&self, group: &Group) -> Vec<Algorithm> {
        std::iter::once(Algorithm::NORMAL)
            .chain(self.configs_of(&group.column))
            .collect()
    }

    /// Every group of the sweep, in the order an unsharded run measures them: scene by
    /// scene, then D, column and N. This order is what `--shard K/N` deals out and what
    /// the merge restores, so it must not depend on anything but the plan.
    pub fn groups(&self) -> Vec<Group> {
        let mut groups = Vec::new();
        for scene in 0..self.scenes.len() {
            for &interleave in &self.interleaves {
                for &column in &self.columns {
                    for &n in &self.ns {
                        groups.push(Group {
                            index: groups.len(),
                            scene,
                            interleave,
                            column,
                            n,
                        });
                    }
                }
            }
        }
        groups
    }

    /// What makes two runs parts of one sweep, as `key=value` pairs: every option that
    /// changes which points are measured or how (the scenes by label, as the CSV names
    /// them), and Cohort's version. Not the backend or device: shards may run anywhere,
    /// and each row names its device.
    pub fn fingerprint(&self) -> Vec<(&'static str, String)> {
        let join = |v: Vec<String>| v.join(",");
        let size = |v: Option<u32>| v.map_or("film".to_string(), |v| v.to_string());
        vec![
            ("version", env!("CARGO_PKG_VERSION").to_string()),
            (
                "scenes",
                join(self.scenes.iter().map(|s| s.label.clone()).collect()),
            ),
            (
                "configs",
                join(self.configs.iter().map(|a| a.name()).collect()),
            ),
            ("n", join(self.ns.iter().map(u32::to_string).collect())),
            (
                "interleave",
                join(self.interleaves.iter().map(u32::to_string).collect()),
            ),
            (
                "columns",
                join(self.columns.iter().map(|c| c.key.to_string()).collect()),
            ),
            ("time_s", self.time.as_secs_f64().to_string()),
            (
                "reference_time_s",
                self.reference_time.as_secs_f64().to_string(),
            ),
            ("width", size(self.width)),
            ("height", size(self.height)),
            ("seed", self.seed.to_string()),
            ("slices", self.slices.to_string()),
            ("end_continue", self.end_continue.to_string()),
            ("integrator", self.integrator.name().to_string()),
        ]
    }

    /// The plan a fingerprint describes (for the merge, which has only the shards' CSVs:
    /// scenes are known by their labels, which is all the CSV and the plots need).
    pub fn from_fingerprint(fp: &[(String, String)], out_dir: PathBuf) -> Result<Plan, String> {
        let get = |key: &str| {
            fp.iter()
                .find(|(k, _)| k == key)
                .map(|(_, v)| v.as_str())
                .ok_or_else(|| format!("the plan has no `{key}`"))
        };
        let bad = |key: &str| format!("the plan's `{key}={}` is malformed", get(key).unwrap_or(""));
        let items = |key: &str| -> Result<Vec<String>, String> {
            Ok(get(key)?.split(',').map(str::to_string).collect())
        };
        let number = |key: &str, v: &str| v.parse::<u32>().map_err(|_| bad(key));
        let numbers = |key: &str| -> Result<Vec<u32>, String> {
            items(key)?.iter().map(|v| number(key, v)).collect()
        };
        let size = |key: &str| match get(key)? {
            "film" => Ok(None),
            v => number(key, v).map(Some),
        };
        let seconds = |key: &str| {
            get(key)?
                .parse::<f64>()
                .ok()
                .and_then(|t| Duration::try_from_secs_f64(t).ok())
                .ok_or_else(|| bad(key))
        };
        Ok(Plan {
            scenes: items("scenes")?
                .into_iter()
                .map(|label| SceneSpec {
                    arg: label.clone(),
                    label,
                })
                .collect(),
            configs: items("configs")?
                .iter()
                .map(|c| Algorithm::parse(c).ok_or_else(|| bad("configs")))
                .collect::<Result<_, _>>()?,
            ns: numbers("n")?,
            interleaves: numbers("interleave")?,
            time: seconds("time_s")?,
            reference_time: seconds("reference_time_s")?,
            width: size("width")?,
            height: size("height")?,
            seed: number("seed", get("seed")?)?,
            out_dir,
            slices: number("slices", get("slices")?)?,
            columns: items("columns")?
                .iter()
                .map(|c| {
                    COLUMNS
                        .into_iter()
                        .find(|k| k.key == c)
                        .ok_or_else(|| bad("columns"))
                })
                .collect::<Result<_, _>>()?,
            end_continue: get("end_continue")?
                .parse()
                .map_err(|_| bad("end_continue"))?,
            integrator: IntegratorKind::parse(get("integrator")?)
                .ok_or_else(|| bad("integrator"))?,
        })
    }
}

/// Checks and parses the options of `cohort figures` into a plan; every bad value is an
/// error naming it, before anything is rendered.
pub fn parse(a: &FiguresArgs) -> Result<Plan, String> {
    let mut scenes: Vec<SceneSpec> = Vec::new();
    for s in list("--scenes", &a.scenes)? {
        if !(embedded::names().contains(&s) || Path::new(s).is_file()) {
            return Err(format!(
                "unknown scene `{s}` in --scenes: not an embedded scene ({}) nor an XML file",
                embedded::names().join(", ")
            ));
        }
        let label = if embedded::names().contains(&s) {
            s.to_string()
        } else {
            file_label(s)
        };
        if scenes.iter().any(|o| o.label == label) {
            return Err(format!("scene `{s}` is listed twice in --scenes (or shares the name `{label}` with another)"));
        }
        scenes.push(SceneSpec {
            arg: s.to_string(),
            label,
        });
    }
    let mut configs: Vec<Algorithm> = Vec::new();
    for c in &a.configs {
        let alg = c.0;
        if alg == Algorithm::NORMAL {
            continue;
        }
        if configs.contains(&alg) {
            return Err(format!(
                "config `{}` is listed twice in --configs",
                alg.name()
            ));
        }
        configs.push(alg);
    }
    let mut ns: Vec<u32> = Vec::new();
    for &n in &a.n {
        if ns.contains(&n) {
            return Err(format!("N `{n}` is listed twice in --n"));
        }
        ns.push(n);
    }
    let mut interleaves = vec![1];
    if a.interleave.trim() != "none" {
        for v in list("--interleave", &a.interleave)? {
            let d: u32 = v
                .parse()
                .map_err(|_| format!("bad --interleave value `{v}`: not a whole number"))?;
            if d < 3 || d & 1 == 0 {
                return Err(format!("bad --interleave value `{v}`: D must be odd and at least 3 (use `none` for no Fig. 7)"));
            }
            if interleaves.contains(&d) {
                return Err(format!("--interleave value `{v}` is listed twice"));
            }
            interleaves.push(d);
        }
    }
    // Both parsed in (0, 1e6] seconds; the default reference time is at most 20 times that.
    let time = Duration::from_secs_f64(a.time);
    let reference_time = Duration::from_secs_f64(a.reference_time.unwrap_or(20.0 * a.time));
    let mut columns: Vec<Column> = Vec::new();
    for c in &a.columns {
        let key = choices::name(c);
        let col = COLUMNS
            .iter()
            .find(|k| k.key == key)
            .expect("every --columns choice is a column");
        if columns.contains(col) {
            return Err(format!("column `{key}` is listed twice in --columns"));
        }
        columns.push(*col);
    }
    let integrator = a.integrator.to_render();
    Ok(Plan {
        columns,
        end_continue: a.end_continue,
        integrator,
        scenes,
        configs,
        ns,
        interleaves,
        time,
        reference_time,
        width: a.width,
        height: a.height,
        seed: a.seed,
        out_dir: a.out_dir.clone(),
        slices: a.slices,
    })
}

/// Splits a comma-separated option; an empty list or an empty item is an error.
fn list<'s>(option: &str, s: &'s str) -> Result<Vec<&'s str>, String> {
    let items: Vec<&str> = s.split(',').map(str::trim).collect();
    if items.iter().any(|i| i.is_empty()) {
        return Err(format!(
            "{option} `{s}` has an empty item (expected a comma-separated list)"
        ));
    }
    Ok(items)
}

/// A file-name-safe label for a scene file: its stem, or its folder's name when the stem
/// is the generic `scene` (`cornell-box/scene.xml` → `cornell-box`).
fn file_label(path: &str) -> String {
    let p = Path::new(path);
    let stem = p
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let raw = if stem == "scene" {
        p.parent()
            .and_then(|d| d.file_name())
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or(stem)
    } else {
        stem
    };
    raw.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_reject_empty_items() {
        assert_eq!(list("--n", "4, 8").unwrap(), vec!["4", "8"]);
        assert!(list("--n", "4,,8").unwrap_err().contains("4,,8"));
        assert!(list("--n", "").is_err());
    }

    #[test]
    fn file_labels_are_safe_names() {
        assert_eq!(
            file_label("../shared/scenes/cornell-box/scene.xml"),
            "cornell-box"
        );
        assert_eq!(file_label("a b/my scene.xml"), "my_scene");
    }

    #[test]
    fn csv_fields_give_back_the_column() {
        for c in COLUMNS {
            assert_eq!(
                Column::from_csv(c.rr(), &c.compact.to_string()),
                Some(c),
                "{}",
                c.key
            );
        }
        assert_eq!(Column::from_csv("path", "false"), None);
    }

    #[test]
    fn the_fingerprint_gives_back_the_plan() {
        let plan = Plan {
            scenes: vec![SceneSpec {
                arg: "x/cornell-box/scene.xml".into(),
                label: "cornell-box".into(),
            }],
            configs: vec![
                Algorithm::parse("warp").unwrap(),
                Algorithm::parse("grid").unwrap(),
            ],
            ns: vec![4, 250],
            interleaves: vec![1, 5],
            time: Duration::from_secs_f64(0.05),
            reference_time: Duration::from_secs_f64(1.5),
            width: Some(32),
            height: None,
            seed: 7,
            out_dir: "a".into(),
            slices: 3,
            columns: vec![COLUMNS[1], COLUMNS[4]],
            end_continue: 0.4,
            integrator: IntegratorKind::parse("nee").unwrap(),
        };
        let fp: Vec<(String, String)> = plan
            .fingerprint()
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect();
        let back = Plan::from_fingerprint(&fp, "b".into()).unwrap();
        assert_eq!(back.fingerprint(), plan.fingerprint());
        assert_eq!(back.groups().len(), plan.groups().len());
        assert_eq!(back.scenes[0].label, "cornell-box");
        let mut broken = fp.clone();
        broken.retain(|(k, _)| k != "seed");
        assert!(Plan::from_fingerprint(&broken, "b".into())
            .map(|_| ())
            .unwrap_err()
            .contains("seed"));
    }
}
