//! `cohort figures-merge`: combines the CSVs of a sweep's shards (`cohort figures --shard
//! K/N`, on one machine or many) into the figures.csv and the plots that an unsharded run
//! writes, rows in its order. It first checks that the files belong together (the same
//! plan, the same N, every shard once) and that every shard holds exactly its groups'
//! points, and names the file (and line) that does not.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use cohort_render::output;

use super::csv::{merged_csv, read_shard, ReadRow, ShardCsv};
use super::plan::{Group, Plan};
use super::plot::{write_scene_figures, PlotRow};

#[derive(clap::Args)]
pub struct MergeArgs {
    /// The shards' CSVs, as `cohort figures --shard K/N` wrote them
    /// (`figures.shard-K-of-N.csv`): all N of them, in any order.
    #[arg(required = true, value_name = "SHARD_CSV")]
    shards: Vec<PathBuf>,
    /// Where figures.csv and the plots go (created if missing).
    #[arg(long, default_value = "figures")]
    out_dir: PathBuf,
}

pub fn run(a: MergeArgs) -> Result<(), String> {
    let shards: Vec<ShardCsv> = a
        .shards
        .iter()
        .map(|p| read_shard(p))
        .collect::<Result<_, _>>()?;
    check_together(&shards)?;
    warn_about_references(&shards);
    let plan = Plan::from_fingerprint(&shards[0].plan, a.out_dir.clone())
        .map_err(|e| format!("{}: {e}", shards[0].path.display()))?;
    let rows = rows_in_plan_order(&plan, &shards)?;

    std::fs::create_dir_all(&plan.out_dir)
        .map_err(|e| format!("cannot create --out-dir {}: {e}", plan.out_dir.display()))?;
    let csv_path = plan.out_dir.join("figures.csv");
    output::write_text(&csv_path, &merged_csv(rows.iter().map(|r| r.text.as_str())))
        .map_err(|e| e.to_string())?;
    let points: Vec<PlotRow> = rows.iter().map(|r| r.point.clone()).collect();
    let mut written = Vec::new();
    for spec in &plan.scenes {
        written.extend(write_scene_figures(&plan, &spec.label, &points)?);
    }
    println!(
        "wrote {} ({} rows from {} shards)",
        csv_path.display(),
        rows.len(),
        shards.len()
    );
    for p in &written {
        println!("wrote {}", p.display());
    }
    Ok(())
}

/// The same plan and split in every file, every shard of the split exactly once.
fn check_together(shards: &[ShardCsv]) -> Result<(), String> {
    let first = &shards[0];
    let count = first.shard.count;
    let mut owner: BTreeMap<u32, &Path> = BTreeMap::new();
    for s in shards {
        let differences = differences(&first.plan, &s.plan);
        if !differences.is_empty() {
            return Err(format!(
                "{} is not a shard of the sweep of {}: {}",
                s.path.display(),
                first.path.display(),
                differences.join("; ")
            ));
        }
        if s.shard.count != count {
            return Err(format!(
                "{} is shard {} but {} is shard {}: not the same split",
                s.path.display(),
                s.shard,
                first.path.display(),
                first.shard
            ));
        }
        if let Some(other) = owner.insert(s.shard.index, &s.path) {
            return Err(format!(
                "{} and {} are both shard {}: each shard is merged once",
                other.display(),
                s.path.display(),
                s.shard
            ));
        }
    }
    let missing: Vec<String> = (0..count)
        .filter(|k| !owner.contains_key(k))
        .map(|k| format!("{k}/{count}"))
        .collect();
    if !missing.is_empty() {
        return Err(format!(
            "shard {} missing: the sweep is split into {count} shards and the inputs hold {} ({})",
            missing.join(", "),
            owner.len(),
            owner
                .values()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    Ok(())
}

/// The keys whose values differ between two fingerprints, as `key VALUE, not FIRST`.
fn differences(first: &[(String, String)], other: &[(String, String)]) -> Vec<String> {
    let value = |fp: &[(String, String)], key: &str| {
        fp.iter()
            .find(|(k, _)| k == key)
            .map_or("(none)".to_string(), |(_, v)| format!("`{v}`"))
    };
    let mut keys: Vec<&str> = first.iter().map(|(k, _)| k.as_str()).collect();
    for (k, _) in other {
        if !keys.contains(&k.as_str()) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .filter(|k| value(first, k) != value(other, k))
        .map(|k| format!("{k} {}, not {}", value(other, k), value(first, k)))
        .collect()
}

/// Shards of a scene that measured against different references (each rendered its own,
/// e.g. at once in a shared out dir, or in out dirs of their own) still merge: their RMS
/// errors carry different reference noise, which the warning says.
fn warn_about_references(shards: &[ShardCsv]) {
    let mut by_scene: BTreeMap<&str, Vec<(&str, &Path)>> = BTreeMap::new();
    for s in shards {
        for (scene, checksum) in &s.references {
            by_scene.entry(scene).or_default().push((checksum, &s.path));
        }
    }
    for (scene, used) in by_scene {
        if used.iter().any(|u| u.0 != used[0].0) {
            eprintln!(
                "warning: the shards measured scene `{scene}` against different references ({}): their RMS errors carry different reference noise; render the references once before the shards (`cohort figures --references-only`, docs/FIGURES.md)",
                used.iter()
                    .map(|(c, p)| format!("{}: {c}", p.display()))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
}

/// The rows of all shards in the order an unsharded run writes them (group by group in
/// the plan's order, `normal` first in each), after checking that every row is a point of
/// a group of its own shard, that no point is there twice, and that none is missing.
fn rows_in_plan_order<'s>(plan: &Plan, shards: &'s [ShardCsv]) -> Result<Vec<&'s ReadRow>, String> {
    let count = shards[0].shard.count as usize;
    let groups = plan.groups();
    let describe = |g: &Group| {
        format!(
            "group {} (scene `{}`, D {}, column `{}`, N {})",
            g.index, plan.scenes[g.scene].label, g.interleave, g.column.key, g.n
        )
    };
    let group_of: HashMap<(&str, u32, &str, u32), &Group> = groups
        .iter()
        .map(|g| {
            let key = (
                plan.scenes[g.scene].label.as_str(),
                g.interleave,
                g.column.key,
                g.n,
            );
            (key, g)
        })
        .collect();
    let mut found: HashMap<(usize, &str), (&Path, &ReadRow)> = HashMap::new();
    for s in shards {
        for r in &s.rows {
            let p = &r.point;
            let at = format!("{}: line {}", s.path.display(), r.line);
            let key = (p.scene.as_str(), p.interleave, p.column.key, p.group_n);
            let g = group_of.get(&key).ok_or_else(|| {
                format!(
                    "{at}: scene `{}`, D {}, column `{}`, N {} is not a group of the plan",
                    p.scene, p.interleave, p.column.key, p.group_n
                )
            })?;
            if g.index % count != s.shard.index as usize {
                return Err(format!(
                    "{at}: the row is of {}, which shard {}/{count} measures, not shard {}",
                    describe(g),
                    g.index % count,
                    s.shard
                ));
            }
            let algorithm = plan
                .algorithms_of(g)
                .into_iter()
                .find(|a| a.name() == p.config)
                .ok_or_else(|| {
                    format!(
                        "{at}: config `{}` is not measured in {}",
                        p.config,
                        describe(g)
                    )
                })?;
            let n = (algorithm != cohort_render::Algorithm::NORMAL).then_some(g.n);
            if p.n != n {
                return Err(format!(
                    "{at}: `n` is {:?}, but `{}` in {} has {n:?}",
                    p.n,
                    p.config,
                    describe(g)
                ));
            }
            if let Some((other, first)) = found.insert((g.index, &p.config), (&s.path, r)) {
                return Err(format!(
                    "{at}: the same point as {}: line {}",
                    other.display(),
                    first.line
                ));
            }
        }
    }
    let mut ordered = Vec::with_capacity(found.len());
    for g in &groups {
        for algorithm in plan.algorithms_of(g) {
            match found.get(&(g.index, algorithm.name().as_str())) {
                Some((_, r)) => ordered.push(*r),
                None => {
                    let owner = shards
                        .iter()
                        .find(|s| s.shard.index as usize == g.index % count)
                        .map_or(PathBuf::new(), |s| s.path.clone());
                    return Err(format!(
                        "{}: has no row of `{}` in {}: the shard is incomplete (interrupted?), run it again",
                        owner.display(),
                        algorithm.name(),
                        describe(g)
                    ));
                }
            }
        }
    }
    Ok(ordered)
}
