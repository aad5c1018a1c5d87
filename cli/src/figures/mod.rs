//! `cohort figures`: the paper's experiments (§4) as one sweep. For every scene
//! it renders (or reuses) a long `normal` reference, then every configuration × every N
//! × the three columns of Fig. 4/5 (per-path RR with compaction, group RR `_rr` with
//! compaction, `_rr (NO)` without), and the same again with interleaved sampling for
//! Fig. 7, each under a budget of accumulated kernel time. The points of one scene, D,
//! column and N (`normal` and every coherent configuration at that N) are measured
//! together, round-robin in slices, so that the GPU's clock changes fall on all of them
//! alike. It writes `figures.csv` (one row per point) and, per scene, Fig. 4 (paths per
//! pixel vs N), Fig. 5 (RMS % vs N) and Fig. 7 (RMS % vs N with D > 1) as PNG and SVG.
//! With `--shard K/N` it measures only every N-th group from the K-th, whole, and writes
//! them to `figures.shard-K-of-N.csv`, which `cohort figures-merge` combines ([`merge`]).
//! docs/FIGURES.md describes the measurement and the outputs.
//!
//! `plan` checks the options and orders the groups, `measure` renders, `reference` keeps
//! the references, `csv` writes and reads the rows, `plot` and `text_bitmap` draw.

use std::path::PathBuf;

use cohort_render::{output, Image, Shard};

use crate::choices::{
    self, AlgorithmChoice, AlgorithmParser, Backend, ColumnChoice, IntegratorChoice,
};

mod csv;
mod measure;
pub mod merge;
mod plan;
mod plot;
mod reference;
mod text_bitmap;

use csv::Row;
use measure::{LoadedScene, Sweep};
use plan::{Group, Plan, DEFAULT_CONFIGS, DEFAULT_NS, DEFAULT_SCENES};
use plot::PlotRow;

#[derive(clap::Args)]
pub struct FiguresArgs {
    /// Comma-separated scenes: embedded names (see `cohort scenes`) or Mitsuba 3 XML files.
    #[arg(long, default_value = DEFAULT_SCENES)]
    scenes: String,
    /// Comma-separated configurations, as `cohort render --algorithm` names them
    /// (`block_N` too, N a multiple of 32 up to 1024). `normal` (the baseline, independent
    /// of N) is always run, listed or not.
    #[arg(long, default_value = DEFAULT_CONFIGS, value_delimiter = ',', value_parser = AlgorithmParser)]
    configs: Vec<AlgorithmChoice>,
    /// Comma-separated values of N (hemisphere split into N x 4N patches), each in 1..=1000.
    #[arg(long, default_value = DEFAULT_NS, value_delimiter = ',', value_parser = choices::patches_n(), allow_negative_numbers = true)]
    n: Vec<u32>,
    /// Budget of every point: accumulated GPU kernel time (traverse + extend + compact),
    /// seconds (positive, at most 1e6).
    #[arg(long, default_value_t = 1.0, value_parser = choices::seconds, allow_negative_numbers = true)]
    time: f64,
    /// Kernel-time budget of the `normal` reference images, seconds (default: 20 x --time).
    #[arg(long, value_parser = choices::seconds, allow_negative_numbers = true)]
    reference_time: Option<f64>,
    /// Image width, at least 1 (default: the scene's film).
    #[arg(long, value_parser = choices::at_least_one(), allow_negative_numbers = true)]
    width: Option<u32>,
    /// Image height, at least 1 (default: the scene's film).
    #[arg(long, value_parser = choices::at_least_one(), allow_negative_numbers = true)]
    height: Option<u32>,
    /// Which backend runs the kernels (default: a real GPU if there is one, else `cpu`).
    #[arg(long, value_enum)]
    backend: Option<Backend>,
    /// Seed of every point (the reference uses a different seed derived from it).
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    seed: u32,
    /// Where figures.csv, the plots and the cached references go (created if missing).
    #[arg(long, default_value = "figures")]
    out_dir: PathBuf,
    /// Comma-separated interleave factors D (odd, > 1) for Fig. 7, or `none`.
    #[arg(long, default_value = "5")]
    interleave: String,
    /// Comma-separated columns of the figures: which roulette, and compaction or not
    /// (`path` here is the paper's first column, per-path roulette with compaction).
    #[arg(
        long,
        default_value = "path,rr,rr-no",
        value_delimiter = ',',
        value_enum
    )]
    columns: Vec<ColumnChoice>,
    /// Continuation probability of the whole-group-end roulette (columns `whole`,
    /// `whole-no`), in (0, 1].
    #[arg(long, default_value_t = 0.5, value_parser = choices::probability, allow_negative_numbers = true)]
    end_continue: f32,
    /// Advanced: the points of a group (`normal` and every configuration at one N) take
    /// turns on the GPU in this many slices of --time / SLICES each (at least 1).
    #[arg(long, default_value_t = 8, value_parser = choices::at_least_one(), allow_negative_numbers = true)]
    slices: u32,
    /// The light transport estimator. The default here is `path`, the paper's implicit
    /// path tracing, unlike `cohort render`'s `nee` (does coherence still pay with light
    /// sampling? `--integrator nee`).
    #[arg(long, value_enum, default_value_t = IntegratorChoice::Path)]
    integrator: IntegratorChoice,
    /// Measure only shard K of N of the sweep (0 <= K < N): the groups (one scene, D,
    /// column and N, measured together) whose place in the plan's order is K modulo N,
    /// whole, so ratios stay clock-fair. Writes figures.shard-K-of-N.csv and no plots;
    /// `cohort figures-merge` combines the N shards' CSVs.
    #[arg(long, value_name = "K/N", value_parser = Shard::parse)]
    shard: Option<Shard>,
    /// Render (or reuse) the references of the sweep's scenes (of the shard's, with
    /// --shard) and stop: run it once before the shards, so that all of them measure
    /// against the same reference files in the shared --out-dir.
    #[arg(long)]
    references_only: bool,
}

pub fn run(a: FiguresArgs) -> Result<(), String> {
    let plan = plan::parse(&a)?;
    let shard = a.shard;
    let groups = groups_of(&plan, shard);
    let device = crate::devices::one(a.backend.map(Backend::kind))?;
    std::fs::create_dir_all(&plan.out_dir)
        .map_err(|e| format!("cannot create --out-dir {}: {e}", plan.out_dir.display()))?;
    let total = points_of(&plan, &groups, a.references_only);
    let mut sweep = Sweep::new(&device, &plan, total);
    sweep.log(summary(&sweep, shard, &groups, a.references_only));
    let mut results = Results::new(&plan, shard, a.references_only, &sweep.device_name);
    for scene_groups in groups.chunk_by(|a, b| a.scene == b.scene) {
        let scene = sweep.load(&plan.scenes[scene_groups[0].scene])?;
        sweep.warm_up(&scene)?;
        let reference = sweep.reference(&scene)?;
        results.add_reference(&scene, &reference);
        if a.references_only {
            continue;
        }
        // One renderer per place in a group, reconfigured for every group.
        let mut pool = Vec::new();
        for group in scene_groups {
            results.add_group(sweep.measure(&scene, &reference, group, &mut pool)?)?;
        }
        results.scene_done(&scene.spec.label)?;
    }
    sweep.finish();
    results.finish()
}

/// What a run writes: its CSV, and unsharded each scene's plots, or with
/// --references-only nothing but the references.
struct Results<'a> {
    plan: &'a Plan,
    shard: Option<Shard>,
    references_only: bool,
    device_name: String,
    csv_path: PathBuf,
    rows: Vec<Row>,
    /// (scene, checksum) of the references measured against, for the merge to compare.
    references: Vec<(String, String)>,
    /// Plots (or references) written, reported at the end.
    written: Vec<PathBuf>,
}

impl<'a> Results<'a> {
    fn new(plan: &'a Plan, shard: Option<Shard>, references_only: bool, device_name: &str) -> Self {
        let csv_path = plan.out_dir.join(match shard {
            Some(s) => csv::shard_file_name(s),
            None => "figures.csv".into(),
        });
        Results {
            plan,
            shard,
            references_only,
            device_name: device_name.to_string(),
            csv_path,
            rows: Vec::new(),
            references: Vec::new(),
            written: Vec::new(),
        }
    }

    fn add_reference(&mut self, scene: &LoadedScene, reference: &Image) {
        let label = &scene.spec.label;
        if self.references_only {
            let path = reference::reference_path(&self.plan.out_dir, label, scene.size);
            self.written.push(path);
        } else {
            let checksum = reference::checksum(reference);
            self.references.push((label.clone(), checksum));
        }
    }

    /// Rewrites the CSV after every group, so that a long sweep that stops keeps what it
    /// measured.
    fn add_group(&mut self, rows: Vec<Row>) -> Result<(), String> {
        self.rows.extend(rows);
        self.write_csv()
    }

    /// The plots of a scene, once its groups are done; a shard has no plots, the merge
    /// draws them.
    fn scene_done(&mut self, label: &str) -> Result<(), String> {
        if self.shard.is_none() {
            let points: Vec<PlotRow> = self.rows.iter().map(Row::plot_row).collect();
            let plots = plot::write_scene_figures(self.plan, label, &points)?;
            self.written.extend(plots);
        }
        Ok(())
    }

    fn finish(self) -> Result<(), String> {
        if !self.references_only {
            // Once more, so that a shard without groups (N above the number of groups)
            // still writes the file the merge expects.
            self.write_csv()?;
            println!(
                "wrote {} ({} rows)",
                self.csv_path.display(),
                self.rows.len()
            );
        }
        for p in &self.written {
            println!("wrote {}", p.display());
        }
        Ok(())
    }

    fn write_csv(&self) -> Result<(), String> {
        let (rows, device, plan) = (&self.rows, &self.device_name, self.plan);
        let text = match self.shard {
            Some(s) => csv::shard_csv(rows, device, plan, s, &self.references),
            None => csv::figures_csv(rows, device, plan),
        };
        output::write_text(&self.csv_path, &text).map_err(|e| e.to_string())
    }
}

/// The groups this run measures, in the plan's order: all, or those of its shard.
fn groups_of(plan: &Plan, shard: Option<Shard>) -> Vec<Group> {
    plan.groups()
        .into_iter()
        .filter(|g| shard.is_none_or(|s| g.index % s.count as usize == s.index as usize))
        .collect()
}

/// Points this run measures, counting each scene's reference as one.
fn points_of(plan: &Plan, groups: &[Group], references_only: bool) -> u64 {
    let references = groups.chunk_by(|a, b| a.scene == b.scene).count() as u64;
    if references_only {
        return references;
    }
    let points: usize = groups.iter().map(|g| plan.algorithms_of(g).len()).sum();
    references + points as u64
}

/// The first line on stderr: what the run measures, and where.
fn summary(sweep: &Sweep, shard: Option<Shard>, groups: &[Group], references_only: bool) -> String {
    let plan = sweep.plan;
    let shard = match shard {
        Some(s) => format!(
            ", shard {s}: {} of the sweep's {} groups",
            groups.len(),
            plan.groups().len()
        ),
        None => String::new(),
    };
    let work = if references_only {
        format!(
            "references only: {} of {:.2} s kernel time",
            sweep.total(),
            plan.reference_time.as_secs_f64()
        )
    } else {
        format!(
            "{} points of {:.2} s kernel time (references included)",
            sweep.total(),
            plan.time.as_secs_f64()
        )
    };
    format!(
        "figures: {} scenes x {} N x {} columns x D in {:?}, each a group of normal + {} configs \
         measured round-robin in {} slices{shard}: {work} on {}",
        plan.scenes.len(),
        plan.ns.len(),
        plan.columns.len(),
        plan.interleaves,
        plan.configs.len(),
        plan.slices,
        sweep.device_name
    )
}
