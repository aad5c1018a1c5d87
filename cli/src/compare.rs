//! `cohort compare A.exr B.exr`: whether two renders are the same image — e.g. a merge of
//! shards rendered on a cluster and an unsplit run — bit for bit or within a relative
//! tolerance per channel. The default tolerance is that of float summation order for
//! the files' paths budget (`cohort_render::merge::merge_tolerance`), so an exact merge
//! passes and any other difference fails. Exits non-zero when they differ.

use std::path::PathBuf;

use cohort_render::input::read_exr;
use cohort_render::merge::merge_tolerance;

#[derive(clap::Args)]
pub struct CompareArgs {
    /// The first EXR (its header's paths budget sets the default tolerance).
    a: PathBuf,
    /// The second EXR.
    b: PathBuf,
    /// Largest relative difference per channel allowed, 0 or more (default: float
    /// summation order's for the paths budget in A's header, 0 without one).
    #[arg(long, value_parser = crate::choices::non_negative, allow_negative_numbers = true)]
    tolerance: Option<f32>,
}

pub fn run(args: CompareArgs) -> Result<(), String> {
    let a = read_exr(&args.a)?;
    let b = read_exr(&args.b)?;
    let (ia, ib) = (&a.image, &b.image);
    if (ia.width, ia.height) != (ib.width, ib.height) {
        return Err(format!(
            "{} is {}x{} but {} is {}x{}",
            args.a.display(),
            ia.width,
            ia.height,
            args.b.display(),
            ib.width,
            ib.height
        ));
    }
    let budget_paths = a
        .attributes
        .get("cohort.budget")
        .and_then(|b| b.strip_prefix("paths="))
        .and_then(|p| p.parse::<u32>().ok());
    let tol = args
        .tolerance
        .unwrap_or_else(|| budget_paths.map(merge_tolerance).unwrap_or(0.0));
    if a.has_path_counts && b.has_path_counts && ia.paths != ib.paths {
        let i = ia
            .paths
            .iter()
            .zip(&ib.paths)
            .position(|(x, y)| x != y)
            .unwrap_or(0);
        return Err(format!(
            "the path counts differ: pixel {i} has {} paths in {} and {} in {}",
            ia.paths[i],
            args.a.display(),
            ib.paths[i],
            args.b.display()
        ));
    }
    let (mut identical, mut worst, mut worst_at) = (0usize, 0f32, 0usize);
    for (i, (p, q)) in ia.pixels.iter().zip(&ib.pixels).enumerate() {
        for c in 0..3 {
            let (x, y) = (p[c], q[c]);
            if x.to_bits() == y.to_bits() {
                identical += 1;
                continue;
            }
            if x == y {
                // 0.0 and -0.0: the same value.
                continue;
            }
            let rel = (x - y).abs() / x.abs().max(y.abs());
            // NaN compares as the worst difference.
            if rel.is_nan() || rel > worst {
                (worst, worst_at) = (if rel.is_nan() { f32::INFINITY } else { rel }, i);
            }
        }
    }
    let channels = 3 * ia.pixels.len();
    println!("bit-identical  {identical} of {channels} channels");
    println!("largest        relative difference {worst:e} (pixel {worst_at}), tolerance {tol:e}");
    if worst > tol {
        return Err(format!(
            "{} and {} differ: relative difference {worst:e} at pixel {worst_at} exceeds {tol:e}",
            args.a.display(),
            args.b.display()
        ));
    }
    println!("same image");
    Ok(())
}
