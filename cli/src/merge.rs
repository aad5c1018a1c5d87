//! `cohort merge`: combines the EXRs of shards of one render (`cohort render --shard
//! K/N`, on one machine or many) into one image, weighting every pixel by its path
//! counts. It first checks that the files belong together — the same scene, size, seed,
//! budget, integrator, options and Cohort version, disjoint shards of the same split —
//! and names the file that does not. A subset of the shards merges with a warning.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use cohort_render::input::read_exr;
use cohort_render::merge::merge;
use cohort_render::provenance::{Provenance, ShardSet};
use cohort_render::{output, Image, Shard};

#[derive(clap::Args)]
pub struct MergeArgs {
    /// The shards' EXRs, as `cohort render --shard K/N --out` wrote them (or earlier merges).
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// The merged linear EXR (mergeable again, like a shard).
    #[arg(long)]
    out: PathBuf,
    /// Tone-mapped sRGB PNG of the merged image.
    #[arg(long)]
    png: Option<PathBuf>,
    /// Exposure of the PNG, in stops (negative: darker).
    #[arg(long, default_value_t = 0.0, value_parser = crate::choices::finite, allow_negative_numbers = true)]
    exposure: f32,
    /// Fail, rather than warn, when shards of the split are missing (for pipelines).
    #[arg(long)]
    require_all: bool,
}

/// A file to merge: its image and what its header says.
struct Part {
    path: PathBuf,
    image: Image,
    provenance: Provenance,
}

pub fn run(a: MergeArgs) -> Result<(), String> {
    let parts: Vec<Part> = a
        .inputs
        .iter()
        .map(|p| read_part(p))
        .collect::<Result<_, _>>()?;
    let first = &parts[0];
    let mut owner: BTreeMap<u32, &Path> = BTreeMap::new();
    for part in &parts {
        let (p, f) = (&part.provenance, &first.provenance);
        let differences = f.differences(p);
        if !differences.is_empty() {
            return Err(format!(
                "{} does not belong with {}: {}",
                part.path.display(),
                first.path.display(),
                differences.join("; ")
            ));
        }
        if p.shards.count != f.shards.count {
            return Err(format!(
                "{} holds shards {} but {} holds {}: not the same split",
                part.path.display(),
                p.shards,
                first.path.display(),
                f.shards
            ));
        }
        for &k in &p.shards.indices {
            if let Some(other) = owner.insert(k, &part.path) {
                return Err(format!(
                    "{} and {} both hold shard {k}/{}: merging them would count the same paths twice",
                    other.display(),
                    part.path.display(),
                    p.shards.count
                ));
            }
        }
    }
    let shards = ShardSet {
        indices: owner.keys().copied().collect(),
        count: first.provenance.shards.count,
    };
    if !shards.is_complete() && a.require_all {
        return Err(format!(
            "shards {} are missing (the inputs hold {shards}) and --require-all is given",
            shards.missing()
        ));
    }
    if !shards.is_complete() {
        eprintln!(
            "warning: merging shards {shards} without {}: the image has only the paths of the shards present{}",
            shards.missing(),
            if first.provenance.merge == "exact" { ", so it is not the unsplit render's image" } else { "" }
        );
    }
    let images: Vec<Image> = parts.iter().map(|p| p.image.clone()).collect();
    let merged = merge(&images)?;
    let mut devices: Vec<&str> = Vec::new();
    for p in &parts {
        for d in p.provenance.device.split("; ") {
            if !devices.contains(&d) {
                devices.push(d);
            }
        }
    }
    let provenance = Provenance {
        shards: shards.clone(),
        device: devices.join("; "),
        ..first.provenance.clone()
    };
    output::write_exr(&a.out, &merged, &provenance.to_attributes()).map_err(|e| e.to_string())?;
    if let Some(png) = &a.png {
        output::write_png(png, &merged, a.exposure).map_err(|e| e.to_string())?;
    }
    let (lo, hi) = merged
        .paths
        .iter()
        .fold((u32::MAX, 0), |(lo, hi), &c| (lo.min(c), hi.max(c)));
    let m = merged.mean();
    println!(
        "merged         {} files: shards {shards} ({} merge)",
        parts.len(),
        first.provenance.merge
    );
    println!("paths/pixel    {lo}..={hi}");
    println!("mean radiance  {:.4} {:.4} {:.4}", m.x, m.y, m.z);
    println!(
        "wrote          {}{}",
        a.out.display(),
        a.png
            .as_ref()
            .map(|p| format!(" and {}", p.display()))
            .unwrap_or_default()
    );
    Ok(())
}

/// Reads one input and checks it on its own: a Cohort render with path counts, and
/// under a paths budget exactly its shards' paths in every pixel (a cut-short render
/// would otherwise merge silently).
fn read_part(path: &Path) -> Result<Part, String> {
    let exr = read_exr(path)?;
    let name = path.display();
    let provenance =
        Provenance::from_attributes(&exr.attributes).map_err(|e| format!("{name}: {e}"))?;
    if !exr.has_path_counts {
        return Err(format!(
            "{name}: has no `paths` channel, so it cannot be weighted by its path counts"
        ));
    }
    let size = format!("{}x{}", exr.image.width, exr.image.height);
    if size != provenance.size {
        return Err(format!(
            "{name}: its image is {size} but its header says {}",
            provenance.size
        ));
    }
    if let Some(p) = provenance
        .budget
        .strip_prefix("paths=")
        .and_then(|p| p.parse::<u32>().ok())
    {
        let s = &provenance.shards;
        let expected: u32 = s
            .indices
            .iter()
            .map(|&k| {
                Shard {
                    index: k,
                    count: s.count,
                }
                .paths(p)
                .len() as u32
            })
            .sum();
        if let Some(i) = exr.image.paths.iter().position(|&c| c != expected) {
            return Err(format!(
                "{name}: pixel {i} has {} paths, but shards {s} of {p} paths per pixel have {expected}: the render is incomplete",
                exr.image.paths[i]
            ));
        }
    }
    Ok(Part {
        path: path.to_path_buf(),
        image: exr.image,
        provenance,
    })
}
