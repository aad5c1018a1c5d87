//! `cohort figures`: the paper's experiments (PAPER.md §4) as one sweep. For every scene
//! it renders (or reuses) a long `normal` reference, then every configuration × every N
//! × the three columns of Fig. 4/5 (per-path RR with compaction, group RR `_rr` with
//! compaction, `_rr (NO)` without), and the same again with interleaved sampling for
//! Fig. 7, each under a budget of accumulated kernel time. The points of one scene, D,
//! column and N (`normal` and every coherent configuration at that N) are measured
//! together, round-robin in slices, so that the GPU's clock changes fall on all of them
//! alike. It writes `figures.csv` (one row per point) and, per scene, Fig. 4 (paths per
//! pixel vs N), Fig. 5 (RMS % vs N) and Fig. 7 (RMS % vs N with D > 1) as PNG and SVG.
//! docs/FIGURES.md describes the measurement and the outputs.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use cohort::runtime::{BackendKind, Device};
use cohort_render::{
    output, Algorithm, Budget, Image, InPatch, IntegratorKind, RenderOptions, RenderStats, Renderer,
};
use cohort_scenes::embedded;
use glam::Vec3;
use plotters::backend::BitMapBackend;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle as Style, BackendTextStyle, DrawingErrorKind,
};

const DEFAULT_SCENES: &str = "confroom,fairyforest,sponza,stanford";
const DEFAULT_CONFIGS: &str = "normal,warp,block_256,block_512,block_1024,grid";
const DEFAULT_NS: &str = "4,8,16,32,64,100,250,500,1000";
const CONFIG_NAMES: &str = "normal, warp, block_256, block_512, block_1024, grid (or block_N, N a multiple of 32 up to 1024)";

#[derive(clap::Args)]
pub struct FiguresArgs {
    /// Comma-separated scenes: embedded names (see `cohort scenes`) or Mitsuba 3 XML files.
    #[arg(long, default_value = DEFAULT_SCENES)]
    scenes: String,
    /// Comma-separated configurations. `normal` (the baseline, independent of N) is
    /// always run, listed or not.
    #[arg(long, default_value = DEFAULT_CONFIGS)]
    configs: String,
    /// Comma-separated values of N (hemisphere split into N x 4N patches), each in 1..=1000.
    #[arg(long, default_value = DEFAULT_NS)]
    n: String,
    /// Budget of every point: accumulated GPU kernel time (traverse + extend + compact), seconds.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    time: f64,
    /// Kernel-time budget of the `normal` reference images, seconds (default: 20 x --time).
    #[arg(long, allow_negative_numbers = true)]
    reference_time: Option<f64>,
    /// Image width (default: the scene's film).
    #[arg(long, allow_negative_numbers = true)]
    width: Option<u32>,
    /// Image height (default: the scene's film).
    #[arg(long, allow_negative_numbers = true)]
    height: Option<u32>,
    /// `wgpu` (WGSL), `vulkan` (SPIR-V through ash) or `cpu` (the native CPU backend);
    /// default: a real GPU if there is one, else `cpu`.
    #[arg(long)]
    backend: Option<String>,
    /// Seed of every point (the reference uses a different seed derived from it).
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    seed: u32,
    /// Where figures.csv, the plots and the cached references go (created if missing).
    #[arg(long, default_value = "figures")]
    out_dir: PathBuf,
    /// Comma-separated interleave factors D (odd, > 1) for Fig. 7, or `none`.
    #[arg(long, default_value = "5")]
    interleave: String,
    /// Comma-separated columns of the figures: `path` (per-path RR, compaction), `rr`
    /// (group RR), `rr-no` (group RR, no compaction), and beyond the paper `whole` and
    /// `whole-no` (whole-group termination, with and without compaction; `grid` is
    /// skipped there, as it cannot vote).
    #[arg(long, default_value = "path,rr,rr-no")]
    columns: String,
    /// Continuation probability of the whole-group-end roulette (columns `whole`, `whole-no`).
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    end_continue: f32,
    /// Advanced: the points of a group (`normal` and every configuration at one N) take
    /// turns on the GPU in this many slices of --time / SLICES each.
    #[arg(long, default_value_t = 8, allow_negative_numbers = true)]
    slices: u32,
    /// `path`: the paper's implicit path tracing (the default here), or `nee`: next-event
    /// estimation with MIS (does coherence still pay with light sampling?).
    #[arg(long, default_value = "path")]
    integrator: String,
}

/// The columns of the figures: the paper's three (Russian roulette per path or per
/// group, compaction or not) and whole-group termination with and without compaction.
const COLUMNS: [Column; 5] = [
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

#[derive(Clone, Copy, PartialEq)]
struct Column {
    /// Its name in --columns.
    key: &'static str,
    group_rr: bool,
    /// Whole-group termination (`--rr whole`).
    whole: bool,
    compact: bool,
    suffix: &'static str,
    title: &'static str,
}

impl Column {
    /// The CSV's `rr` value.
    fn rr(&self) -> &'static str {
        match (self.whole, self.group_rr) {
            (true, _) => "whole",
            (false, true) => "group",
            (false, false) => "path",
        }
    }
}

struct SceneSpec {
    /// As given: an embedded name or a path.
    arg: String,
    /// Used in file names and the CSV.
    label: String,
}

struct Plan {
    scenes: Vec<SceneSpec>,
    /// Coherent configurations, in the order given (`normal` is always run on its own).
    configs: Vec<Algorithm>,
    ns: Vec<u32>,
    /// Interleave factors: 1 (Fig. 4/5) first, then those of Fig. 7.
    interleaves: Vec<u32>,
    time: Duration,
    reference_time: Duration,
    width: Option<u32>,
    height: Option<u32>,
    seed: u32,
    out_dir: PathBuf,
    slices: u32,
    columns: Vec<Column>,
    end_continue: f32,
    integrator: IntegratorKind,
}

impl Plan {
    /// Measured points and the reference: `normal` is measured again in every group.
    fn points_per_scene(&self) -> u64 {
        let per_group: u64 = self
            .columns
            .iter()
            .map(|c| 1 + self.configs_of(c).len() as u64)
            .sum();
        (self.interleaves.len() * self.ns.len()) as u64 * per_group + 1
    }

    /// The coherent configurations measured in `column` (the grid cannot vote, so it has
    /// no whole-group termination).
    fn configs_of(&self, column: &Column) -> Vec<Algorithm> {
        self.configs
            .iter()
            .copied()
            .filter(|a| !(column.whole && a.group == cohort::Group::Grid))
            .collect()
    }
}

/// One measured point: one row of figures.csv.
struct Row {
    scene: String,
    width: u32,
    height: u32,
    config: String,
    label: String,
    /// `None` for `normal`, which does not depend on N.
    n: Option<u32>,
    /// N of the group the point was measured in (`normal` is measured in every group).
    group_n: u32,
    column: Column,
    interleave: u32,
    stats: RenderStats,
    rms_percent: f64,
    rms_abs: f64,
    ratio_vs_normal: f64,
}

impl Row {
    /// RMS error scaled to one path per pixel (Monte Carlo error falls as 1/sqrt(paths)):
    /// an error per path, which does not depend on how fast the paths were completed, and
    /// so not on the GPU's clocks either.
    fn rms_at_1spp(&self) -> f64 {
        self.rms_percent * self.stats.paths_per_pixel().sqrt()
    }
}

pub fn run(a: FiguresArgs) -> Result<(), String> {
    let plan = parse_plan(&a)?;
    let device = match a.backend.as_deref() {
        None => crate::devices::best()?,
        Some(b) => Device::new(
            BackendKind::parse(b)
                .ok_or_else(|| format!("unknown backend `{b}` (wgpu, vulkan or cpu)"))?,
        )
        .map_err(|e| e.to_string())?,
    };
    let info = device.info().clone();
    let device_name = format!("{} [{}]", info.adapter_name, info.backend.name());
    std::fs::create_dir_all(&plan.out_dir)
        .map_err(|e| format!("cannot create --out-dir {}: {e}", plan.out_dir.display()))?;
    let csv_path = plan.out_dir.join("figures.csv");

    let total = plan.points_per_scene() * plan.scenes.len() as u64;
    let bar = indicatif::ProgressBar::new(total * 1000);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "[{elapsed_precise}] {bar:40} {percent:>3}% eta {eta} {msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let log = |line: String| bar.suspend(|| eprintln!("{line}"));
    log(format!(
        "figures: {} scenes x {} N x 3 columns x D in {:?}, each a group of normal + {} configs measured round-robin in {} slices: \
         {total} points of {:.2} s kernel time (references included) on {device_name}",
        plan.scenes.len(),
        plan.ns.len(),
        plan.interleaves,
        plan.configs.len(),
        plan.slices,
        plan.time.as_secs_f64()
    ));

    let mut rows: Vec<Row> = Vec::new();
    let mut done = 0u64;
    let mut written = Vec::new();
    for spec in &plan.scenes {
        let scene = crate::load_scene(&spec.arg, &Default::default())?;
        // The BVH is built and uploaded once per scene, not once per point.
        let gpu = cohort_render::GpuScene::prepare(&device, &scene)
            .map_err(|e| format!("{}: {e}", spec.label))?;
        let scene: Prepared = (scene, gpu);
        let (w, h) = (
            plan.width.unwrap_or(scene.0.camera.width),
            plan.height.unwrap_or(scene.0.camera.height),
        );
        for &d in &plan.interleaves {
            if gcd(d, w) != 1 || gcd(d, h) != 1 {
                return Err(format!("bad --interleave value `{d}`: it must be coprime with the image size {w}x{h} of scene `{}`", spec.arg));
            }
        }
        let point = |i: u64, msg: String| {
            bar.set_message(format!("[{}/{total}] {msg}", i + 1));
            bar.set_position(i * 1000);
        };

        // Warm-up: one iteration of every configuration, so that a first-use cost of its
        // pipelines (some drivers compile lazily, inside the timed dispatch) is paid here
        // and not inside a measured point.
        for alg in std::iter::once(Algorithm::NORMAL).chain(plan.configs.iter().copied()) {
            bar.set_message(format!(
                "[{}/{total}] {} warm-up {}",
                done + 1,
                spec.label,
                alg.name()
            ));
            let opts = RenderOptions {
                algorithm: alg,
                budget: Budget::KernelTime(Duration::from_nanos(1)),
                size: Some((w, h)),
                integrator: plan.integrator,
                ..Default::default()
            };
            render(&device, &scene, opts, &bar, done)
                .map_err(|e| format!("{} warm-up {}: {e}", spec.label, alg.name()))?;
        }

        // The reference: a long `normal` render, cached in out-dir.
        point(
            done,
            format!(
                "{} reference ({:.1} s)",
                spec.label,
                plan.reference_time.as_secs_f64()
            ),
        );
        let reference = reference_image(&device, &scene, spec, (w, h), &plan, &bar, done, &log)?;
        done += 1;

        // One renderer per place in a group, reconfigured for every group: a new renderer
        // per point cost the host more time than the point's GPU work, and the idle GPU
        // lowered its clocks (docs/FIGURES.md).
        let mut pool: Vec<Renderer> = Vec::new();
        for &d in &plan.interleaves {
            for &column in &plan.columns {
                for &group_n in &plan.ns {
                    let group = measure_group(
                        &device,
                        &scene,
                        &plan,
                        spec,
                        (w, h),
                        d,
                        column,
                        group_n,
                        &bar,
                        done,
                        total,
                        &mut pool,
                    )?;
                    done += group.len() as u64;
                    let normal_pps = group[0].1.paths_per_second();
                    for (point, stats, image) in group {
                        let pps = stats.paths_per_second();
                        let row = Row {
                            scene: spec.label.clone(),
                            width: w,
                            height: h,
                            config: point.algorithm.name(),
                            label: point.label,
                            n: point.n,
                            group_n,
                            column,
                            interleave: d,
                            rms_percent: rms_percent(&image, &reference),
                            rms_abs: image.rms_diff(&reference) as f64,
                            ratio_vs_normal: pps / normal_pps,
                            stats,
                        };
                        log(format!(
                            "{}: {:.2} paths/pixel, {:.3} M paths/s (x{:.3} normal of N={group_n}), RMS {:.3} % ({:.2} % at 1 path/pixel)",
                            point.what,
                            row.stats.paths_per_pixel(),
                            pps / 1e6,
                            row.ratio_vs_normal,
                            row.rms_percent,
                            row.rms_at_1spp()
                        ));
                        rows.push(row);
                    }
                    // Rewritten after every group, so a long sweep that stops keeps what it measured.
                    output::write_text(&csv_path, &csv(&rows, &device_name, &plan))
                        .map_err(|e| e.to_string())?;
                }
            }
        }
        written.extend(write_scene_figures(&plan, &spec.label, &rows)?);
    }
    bar.finish_and_clear();
    println!("wrote {} ({} rows)", csv_path.display(), rows.len());
    for p in &written {
        println!("wrote {}", p.display());
    }
    Ok(())
}

fn parse_plan(a: &FiguresArgs) -> Result<Plan, String> {
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
    for c in list("--configs", &a.configs)? {
        let alg = Algorithm::parse(c).ok_or_else(|| {
            format!("unknown config `{c}` in --configs (available: {CONFIG_NAMES})")
        })?;
        if alg == Algorithm::NORMAL {
            continue;
        }
        if configs.contains(&alg) {
            return Err(format!("config `{c}` is listed twice in --configs"));
        }
        configs.push(alg);
    }
    let mut ns: Vec<u32> = Vec::new();
    for v in list("--n", &a.n)? {
        let n: u32 = v
            .parse()
            .map_err(|_| format!("bad N `{v}` in --n: not a whole number"))?;
        if !(1..=1000).contains(&n) {
            return Err(format!("bad N `{v}` in --n: N must be in 1..=1000"));
        }
        if ns.contains(&n) {
            return Err(format!("N `{v}` is listed twice in --n"));
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
    let seconds = |name: &str, t: f64| {
        if t > 0.0 && t.is_finite() && t < 1e6 {
            Ok(Duration::from_secs_f64(t))
        } else {
            Err(format!("{name} {t} must be a positive number of seconds"))
        }
    };
    let time = seconds("--time", a.time)?;
    let reference_time = seconds(
        "--reference-time",
        a.reference_time.unwrap_or(20.0 * a.time),
    )?;
    for (name, v) in [("--width", a.width), ("--height", a.height)] {
        if v == Some(0) {
            return Err(format!("{name} must be at least 1"));
        }
    }
    if a.slices == 0 {
        return Err("--slices must be at least 1".into());
    }
    let mut columns: Vec<Column> = Vec::new();
    for c in list("--columns", &a.columns)? {
        let col = COLUMNS.iter().find(|k| k.key == c).ok_or_else(|| {
            format!(
                "unknown column `{c}` in --columns (available: {})",
                COLUMNS.iter().map(|k| k.key).collect::<Vec<_>>().join(", ")
            )
        })?;
        if columns.contains(col) {
            return Err(format!("column `{c}` is listed twice in --columns"));
        }
        columns.push(*col);
    }
    if !(a.end_continue > 0.0 && a.end_continue <= 1.0) {
        return Err(format!(
            "--end-continue {} is not in (0, 1]",
            a.end_continue
        ));
    }
    let integrator = IntegratorKind::parse(&a.integrator)
        .ok_or_else(|| format!("unknown --integrator `{}` (path or nee)", a.integrator))?;
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

/// A scene with its BVH already on the device.
type Prepared = (
    cohort_scenes::Scene,
    std::sync::Arc<cohort_render::GpuScene>,
);

/// One render on its own: the warm-ups and the reference, which nothing is compared with
/// for speed.
fn render(
    device: &Device,
    scene: &Prepared,
    opts: RenderOptions,
    bar: &indicatif::ProgressBar,
    index: u64,
) -> Result<(Image, RenderStats), String> {
    let mut renderer =
        Renderer::with_scene(device, &scene.0, scene.1.clone(), opts).map_err(|e| e.to_string())?;
    renderer
        .render(|frac, _| bar.set_position(index * 1000 + (frac * 999.0) as u64))
        .map_err(|e| e.to_string())
}

/// A point of a group, before it is measured.
struct Point {
    algorithm: Algorithm,
    n: Option<u32>,
    label: String,
    /// For messages: scene, label and N.
    what: String,
}

/// Measures one group: `normal` (first) and every coherent configuration at N =
/// `group_n`, for one scene, D and column. All are started, then advanced in turn, in
/// `plan.slices` slices of the budget each, so that they share whatever the GPU's clocks
/// do meanwhile (the driver lowers them when the GPU idles, e.g. while the host computes
/// between points; separate renders one after another were measured at clocks up to 4x
/// apart). `pool` holds the renderers of earlier groups (about 150 MB each at 1024x1024),
/// reconfigured here rather than made anew.
#[allow(clippy::too_many_arguments)]
fn measure_group<'d>(
    device: &'d Device,
    scene: &Prepared,
    plan: &Plan,
    spec: &SceneSpec,
    (w, h): (u32, u32),
    d: u32,
    column: Column,
    group_n: u32,
    bar: &indicatif::ProgressBar,
    first: u64,
    total: u64,
    pool: &mut Vec<Renderer<'d>>,
) -> Result<Vec<(Point, RenderStats, Image)>, String> {
    let points: Vec<Point> = std::iter::once((Algorithm::NORMAL, None))
        .chain(
            plan.configs_of(&column)
                .into_iter()
                .map(|alg| (alg, Some(group_n))),
        )
        .map(|(algorithm, n)| {
            let label = format!(
                "{}{}{}",
                algorithm.name(),
                column.suffix,
                if d > 1 {
                    format!(" D{d}")
                } else {
                    String::new()
                }
            );
            let what = format!(
                "{} {label}{}",
                spec.label,
                n.map(|n| format!(" N={n}"))
                    .unwrap_or_else(|| format!(" (group N={group_n})"))
            );
            Point {
                algorithm,
                n,
                label,
                what,
            }
        })
        .collect();
    for (i, point) in points.iter().enumerate() {
        let opts = RenderOptions {
            algorithm: point.algorithm,
            in_patch: InPatch::Uniform,
            patches_n: point.n.unwrap_or(RenderOptions::default().patches_n),
            group_rr: column.group_rr,
            interleave: d,
            budget: Budget::KernelTime(plan.time),
            seed: plan.seed,
            size: Some((w, h)),
            compact: column.compact,
            whole_group_end: column.whole.then_some(plan.end_continue),
            integrator: plan.integrator,
            ..Default::default()
        };
        if i < pool.len() {
            pool[i]
                .reconfigure(opts)
                .map_err(|e| format!("{}: {e}", point.what))?;
        } else {
            pool.push(
                Renderer::with_scene(device, &scene.0, scene.1.clone(), opts)
                    .map_err(|e| format!("{}: {e}", point.what))?,
            );
        }
        pool[i]
            .start()
            .map_err(|e| format!("{}: {e}", point.what))?;
    }
    let renderers = &mut pool[..points.len()];
    let k = renderers.len();
    let budget = plan.time.as_secs_f64();
    let mut spent = vec![0f64; k];
    let mut stats = vec![RenderStats::default(); k];
    let name = format!(
        "{} {}{} N={group_n}",
        spec.label,
        column.title,
        if d > 1 {
            format!(" D{d}")
        } else {
            String::new()
        }
    );
    for slice in 0..plan.slices {
        let until = Budget::KernelTime(plan.time * (slice + 1) / plan.slices);
        // The first turn of a slice may meet clocks lowered by whatever the host did
        // before it: it rotates, so that no configuration always has it.
        for j in 0..k {
            let i = (slice as usize + j) % k;
            bar.set_message(format!(
                "[{}/{total}] {name}: slice {}/{} {}",
                first + 1,
                slice + 1,
                plan.slices,
                points[i].label
            ));
            stats[i] = renderers[i]
                .advance_with(until, |_, s| {
                    spent[i] = (s.kernel.total().as_secs_f64() / budget).min(1.0);
                    bar.set_position(first * 1000 + (spent.iter().sum::<f64>() * 999.0) as u64);
                })
                .map_err(|e| format!("{}: {e}", points[i].what))?;
        }
    }
    let mut measured = Vec::with_capacity(k);
    for ((point, r), stats) in points.into_iter().zip(renderers.iter()).zip(stats) {
        let image = r.image().map_err(|e| format!("{}: {e}", point.what))?;
        measured.push((point, stats, image));
    }
    Ok(measured)
}

/// The seed of the reference: different from every point's, so that the reference's noise
/// is independent of theirs (with the same seed `normal` would repeat its first paths).
fn reference_seed(seed: u32) -> u32 {
    seed ^ 0x5eed_5eed
}

#[allow(clippy::too_many_arguments)]
fn reference_image(
    device: &Device,
    scene: &Prepared,
    spec: &SceneSpec,
    (w, h): (u32, u32),
    plan: &Plan,
    bar: &indicatif::ProgressBar,
    index: u64,
    log: &dyn Fn(String),
) -> Result<Image, String> {
    let path = plan
        .out_dir
        .join(format!("reference_{}_{w}x{h}.exr", spec.label));
    if path.exists() {
        match read_exr(&path) {
            Ok(img) if (img.width, img.height) == (w, h) => {
                log(format!(
                    "{}: reusing the reference {}",
                    spec.label,
                    path.display()
                ));
                return Ok(img);
            }
            Ok(img) => log(format!(
                "{}: {} is {}x{}, not {w}x{h}: rendering it again",
                spec.label,
                path.display(),
                img.width,
                img.height
            )),
            Err(e) => log(format!(
                "{}: cannot read {} ({e}): rendering it again",
                spec.label,
                path.display()
            )),
        }
    }
    let opts = RenderOptions {
        algorithm: Algorithm::NORMAL,
        budget: Budget::KernelTime(plan.reference_time),
        seed: reference_seed(plan.seed),
        size: Some((w, h)),
        // Both integrators converge to the same image; light sampling gets there sooner.
        integrator: plan.integrator,
        ..Default::default()
    };
    let (image, stats) = render(device, scene, opts, bar, index)
        .map_err(|e| format!("{} reference: {e}", spec.label))?;
    output::write_exr(&path, &image, &[]).map_err(|e| e.to_string())?;
    log(format!(
        "{}: reference {:.1} paths/pixel in {:.2} s kernel time, wrote {}",
        spec.label,
        stats.paths_per_pixel(),
        stats.kernel.total().as_secs_f64(),
        path.display()
    ));
    Ok(image)
}

/// Reads an RGB(A) EXR written by `output::write_exr` (alpha, if any, is ignored).
fn read_exr(path: &Path) -> Result<Image, String> {
    struct Pixels {
        width: usize,
        data: Vec<Vec3>,
    }
    let img = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |size, _| Pixels {
            width: size.width(),
            data: vec![Vec3::ZERO; size.width() * size.height()],
        },
        |p: &mut Pixels, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            p.data[pos.y() * p.width + pos.x()] = Vec3::new(r, g, b)
        },
    )
    .map_err(|e| e.to_string())?;
    let size = img.layer_data.size;
    let pixels = img.layer_data.channel_data.pixels.data;
    Ok(Image {
        width: size.width() as u32,
        height: size.height() as u32,
        paths: vec![0; pixels.len()],
        pixels,
    })
}

/// RMS error in percent: the root mean square of (image - reference) over all pixels and
/// RGB channels, divided by the root mean square of the reference over the same, x 100.
fn rms_percent(img: &Image, reference: &Image) -> f64 {
    let (mut diff, mut norm) = (0f64, 0f64);
    for (a, r) in img.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let (a, r) = (a[c] as f64, r[c] as f64);
            diff += (a - r) * (a - r);
            norm += r * r;
        }
    }
    100.0 * (diff / norm).sqrt()
}

fn gcd(a: u32, b: u32) -> u32 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

const CSV_HEADER: &str = "scene,width,height,device,config,label,n,rr,compaction,interleave,seed,time_budget_s,\
paths_per_pixel,completed_paths,iterations,rays,paths_per_s,rays_per_s,\
kernel_ms_traverse,kernel_ms_extend,kernel_ms_compact,kernel_ms_total,wall_s,rms_percent,rms_abs,paths_per_s_vs_normal,group_n,rms_at_1spp";

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn csv(rows: &[Row], device: &str, plan: &Plan) -> String {
    let mut out = String::from(CSV_HEADER);
    out.push('\n');
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    for r in rows {
        let s = &r.stats;
        let k = s.kernel;
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{:.4},{},{},{},{:.1},{:.1},{:.3},{:.3},{:.3},{:.3},{:.3},{:.5},{:.6},{:.5},{},{:.5}",
            csv_field(&r.scene),
            r.width,
            r.height,
            csv_field(device),
            r.config,
            csv_field(&r.label),
            r.n.map(|n| n.to_string()).unwrap_or_default(),
            r.column.rr(),
            r.column.compact,
            r.interleave,
            plan.seed,
            plan.time.as_secs_f64(),
            s.paths_per_pixel(),
            s.completed_paths,
            s.iterations,
            s.rays,
            s.paths_per_second(),
            s.rays_per_second(),
            ms(k.traverse),
            ms(k.extend),
            ms(k.compact),
            ms(k.total()),
            s.wall.as_secs_f64(),
            r.rms_percent,
            r.rms_abs,
            r.ratio_vs_normal,
            r.group_n,
            r.rms_at_1spp(),
        );
    }
    out
}

// ---------------------------------------------------------------------------------------
// Plots

/// Line colours of the coherent configurations, in the order given (tab10).
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(214, 39, 40),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

struct Panel {
    title: &'static str,
    /// (N of the group, value), sorted by N: `normal` is measured in every group.
    normal: Vec<(f64, f64)>,
    curves: Vec<Curve>,
}

struct Curve {
    name: String,
    color: RGBColor,
    /// (N, value), sorted by N.
    points: Vec<(f64, f64)>,
}

struct Figure {
    title: String,
    y_label: &'static str,
    /// Legend corner: where curves are unlikely to be (paths grow with N, RMS falls).
    legend: SeriesLabelPosition,
    y_from_zero: bool,
    panels: Vec<Panel>,
}

/// Font sizes: larger in the PNG, whose 8x8 bitmap glyphs are wider than the layout
/// estimate of small sizes.
struct Fonts {
    title: u32,
    caption: u32,
    desc: u32,
    label: u32,
}
const SVG_FONTS: Fonts = Fonts {
    title: 24,
    caption: 17,
    desc: 15,
    label: 13,
};
const PNG_FONTS: Fonts = Fonts {
    title: 36,
    caption: 36,
    desc: 18,
    label: 18,
};
/// Size of one panel (one column of the figure).
const PANEL_SIZE: (u32, u32) = (650, 650);

fn write_scene_figures(plan: &Plan, scene: &str, rows: &[Row]) -> Result<Vec<PathBuf>, String> {
    let mut written = Vec::new();
    let mut figs: Vec<(String, Figure)> = Vec::new();
    let fig =
        |d: u32, metric: fn(&Row) -> f64, title: String, y_label, legend, y_from_zero| Figure {
            title,
            y_label,
            legend,
            y_from_zero,
            panels: plan
                .columns
                .iter()
                .map(|col| {
                    let sel = |r: &&Row| r.scene == scene && r.interleave == d && r.column == *col;
                    let mut normal: Vec<(f64, f64)> = rows
                        .iter()
                        .filter(sel)
                        .filter(|r| r.n.is_none())
                        .map(|r| (r.group_n as f64, metric(r)))
                        .collect();
                    normal.sort_by(|a, b| a.0.total_cmp(&b.0));
                    let curves = plan
                        .configs_of(col)
                        .iter()
                        .enumerate()
                        .map(|(i, alg)| {
                            let mut pts: Vec<(f64, f64)> = rows
                                .iter()
                                .filter(sel)
                                .filter(|r| r.config == alg.name())
                                .filter_map(|r| Some((r.n? as f64, metric(r))))
                                .collect();
                            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                            Curve {
                                name: format!("{}{}", alg.name(), col.suffix),
                                color: PALETTE[i % PALETTE.len()],
                                points: pts,
                            }
                        })
                        .collect();
                    Panel {
                        title: col.title,
                        normal,
                        curves,
                    }
                })
                .collect(),
        };
    let budget = format!(
        "{:.3} s kernel time per point, round-robin per N",
        plan.time.as_secs_f64()
    );
    figs.push((
        format!("fig4_{scene}"),
        fig(
            1,
            |r| r.stats.paths_per_pixel(),
            format!("Fig. 4, {scene}: completed paths per pixel vs N ({budget})"),
            "paths per pixel",
            SeriesLabelPosition::UpperLeft,
            true,
        ),
    ));
    figs.push((
        format!("fig5_{scene}"),
        fig(
            1,
            |r| r.rms_percent,
            format!("Fig. 5, {scene}: RMS error vs N ({budget})"),
            "RMS error vs reference (%)",
            SeriesLabelPosition::UpperRight,
            false,
        ),
    ));
    for &d in plan.interleaves.iter().filter(|&&d| d > 1) {
        figs.push((
            format!("fig7_{scene}_d{d}"),
            fig(
                d,
                |r| r.rms_percent,
                format!("Fig. 7, {scene}: RMS error vs N, interleaved D = {d} ({budget})"),
                "RMS error vs reference (%)",
                SeriesLabelPosition::UpperRight,
                false,
            ),
        ));
    }
    for (stem, fig) in &figs {
        let x = x_range(&plan.ns);
        let mut ticks: Vec<f64> = plan.ns.iter().map(|&n| n as f64).collect();
        ticks.sort_by(f64::total_cmp);
        let y = y_range(fig);
        let size = (PANEL_SIZE.0 * fig.panels.len().max(1) as u32, PANEL_SIZE.1);
        let svg_path = plan.out_dir.join(format!("{stem}.svg"));
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
            draw_figure(root, fig, x, &ticks, y, &SVG_FONTS)
                .map_err(|e| format!("cannot draw {}: {e}", svg_path.display()))?;
        }
        output::write_text(&svg_path, &svg).map_err(|e| e.to_string())?;
        written.push(svg_path);

        let png_path = plan.out_dir.join(format!("{stem}.png"));
        let (w, h) = size;
        let mut buf = vec![255u8; (w * h * 3) as usize];
        {
            let root = TextBitmap(BitMapBackend::with_buffer(&mut buf, size)).into_drawing_area();
            draw_figure(root, fig, x, &ticks, y, &PNG_FONTS)
                .map_err(|e| format!("cannot draw {}: {e}", png_path.display()))?;
        }
        write_png_rgb(&png_path, size, &buf)?;
        written.push(png_path);
    }
    Ok(written)
}

fn x_range(ns: &[u32]) -> (f64, f64) {
    let lo = ns.iter().copied().min().unwrap_or(1) as f64;
    let hi = ns.iter().copied().max().unwrap_or(1000) as f64;
    if hi / lo < 2.0 {
        (lo / 1.5, hi * 1.5)
    } else {
        (lo / 1.1, hi * 1.1)
    }
}

fn y_range(fig: &Figure) -> (f64, f64) {
    let values = fig
        .panels
        .iter()
        .flat_map(|p| {
            p.normal
                .iter()
                .chain(p.curves.iter().flat_map(|c| c.points.iter()))
                .map(|v| v.1)
        })
        .filter(|v| v.is_finite());
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let lo = if fig.y_from_zero { 0.0 } else { lo };
    let pad = ((hi - lo) * 0.08).max(hi.abs() * 0.02).max(1e-6);
    ((lo - pad).max(0.0), hi + pad)
}

/// Draws the three panels; the x axis is logarithmic with a tick at every N of the sweep.
fn draw_figure<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    fig: &Figure,
    (x0, x1): (f64, f64),
    ticks: &[f64],
    (y0, y1): (f64, f64),
    fonts: &Fonts,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    // Enough decimals to tell the y ticks apart: 1 for a span of ~10, 0 from ~100.
    let decimals = (1 - (y1 - y0).log10().floor() as i32).clamp(0, 4) as usize;
    root.fill(&WHITE).map_err(e)?;
    let root = root
        .titled(&fig.title, ("sans-serif", fonts.title))
        .map_err(e)?;
    for (area, panel) in root
        .split_evenly((1, fig.panels.len()))
        .iter()
        .zip(&fig.panels)
    {
        let mut chart = ChartBuilder::on(area)
            .caption(panel.title, ("sans-serif", fonts.caption))
            .margin(14)
            .x_label_area_size(fonts.label * 3 + 6)
            .y_label_area_size(fonts.label * 5)
            .build_cartesian_2d((x0..x1).log_scale().with_key_points(ticks.to_vec()), y0..y1)
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc("N (hemisphere split into N x 4N patches, log scale)")
            .y_desc(fig.y_label)
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_label_formatter(&|y| format!("{y:.decimals$}"))
            .label_style(("sans-serif", fonts.label))
            .axis_desc_style(("sans-serif", fonts.desc))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(e)?;
        let normal: Vec<(f64, f64)> = panel
            .normal
            .iter()
            .copied()
            .filter(|p| p.1.is_finite())
            .collect();
        if !normal.is_empty() {
            // `normal` does not depend on N, but it is measured in every group, alongside the
            // configurations it is compared with: its line goes through those values (flat
            // across the panel when the sweep has one N).
            let dashed = if normal.len() == 1 {
                vec![(x0, normal[0].1), (x1, normal[0].1)]
            } else {
                normal.clone()
            };
            chart
                .draw_series(normal.iter().map(|&p| Circle::new(p, 3, BLACK.filled())))
                .map_err(e)?;
            chart
                .draw_series(DashedLineSeries::new(dashed, 10, 6, line(BLACK)))
                .map_err(e)?
                .label("normal")
                .legend(|(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (8, 0)], line(BLACK))
                        + PathElement::new(vec![(13, 0), (20, 0)], line(BLACK))
                });
        }
        for Curve {
            name,
            color,
            points,
        } in &panel.curves
        {
            let color = *color;
            let pts: Vec<(f64, f64)> = points.iter().copied().filter(|p| p.1.is_finite()).collect();
            chart
                .draw_series(LineSeries::new(pts, line(color)).point_size(3))
                .map_err(e)?
                .label(name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], line(color)));
        }
        chart
            .configure_series_labels()
            .position(fig.legend.clone())
            .label_font(("sans-serif", fonts.label))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(e)?;
    }
    root.present().map_err(e)
}

/// A 2-pixel line style (`Color::stroke_width`, named in full: `BackendStyle` has one too).
fn line(color: RGBColor) -> ShapeStyle {
    Color::stroke_width(&color, 2)
}

fn write_png_rgb(path: &Path, (w, h): (u32, u32), rgb: &[u8]) -> Result<(), String> {
    output::write_atomically(path, |tmp| {
        let file = std::fs::File::create(tmp).map_err(|e| e.to_string())?;
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(|e| e.to_string())?;
        writer.write_image_data(rgb).map_err(|e| e.to_string())?;
        writer.finish().map_err(|e| e.to_string())
    })
    .map_err(|e| e.to_string())
}

/// plotters' bitmap backend with text: without its `ttf` feature (fontconfig, system
/// fonts) plotters cannot rasterize text, so this draws it with the public-domain 8x8
/// bitmap font of `font8x8`, scaled by whole pixels, and delegates everything else.
struct TextBitmap<'a>(BitMapBackend<'a>);

type BackendResult<T, E> = Result<T, DrawingErrorKind<E>>;

impl TextBitmap<'_> {
    /// Pixel scale of the 8x8 glyphs for a font size; glyphs advance by 8 x scale.
    fn scale(size: f64) -> i32 {
        ((size * 0.455 / 8.0).floor() as i32).max(1)
    }
}

impl<'a> DrawingBackend for TextBitmap<'a> {
    type ErrorType = <BitMapBackend<'a> as DrawingBackend>::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.0.get_size()
    }
    fn ensure_prepared(&mut self) -> BackendResult<(), Self::ErrorType> {
        self.0.ensure_prepared()
    }
    fn present(&mut self) -> BackendResult<(), Self::ErrorType> {
        self.0.present()
    }
    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> BackendResult<(), Self::ErrorType> {
        self.0.draw_pixel(point, color)
    }
    fn draw_line<S: Style>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> BackendResult<(), Self::ErrorType> {
        self.0.draw_line(from, to, style)
    }
    fn draw_rect<S: Style>(
        &mut self,
        ul: BackendCoord,
        br: BackendCoord,
        style: &S,
        fill: bool,
    ) -> BackendResult<(), Self::ErrorType> {
        self.0.draw_rect(ul, br, style, fill)
    }
    fn draw_path<S: Style, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> BackendResult<(), Self::ErrorType> {
        self.0.draw_path(path, style)
    }
    fn draw_circle<S: Style>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> BackendResult<(), Self::ErrorType> {
        self.0.draw_circle(center, radius, style, fill)
    }
    fn fill_polygon<S: Style, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> BackendResult<(), Self::ErrorType> {
        self.0.fill_polygon(vert, style)
    }
    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> BackendResult<(), Self::ErrorType> {
        self.0.blit_bitmap(pos, size, src)
    }

    fn estimate_text_size<T: BackendTextStyle>(
        &self,
        text: &str,
        style: &T,
    ) -> BackendResult<(u32, u32), Self::ErrorType> {
        let s = Self::scale(style.size()) as u32;
        Ok((8 * s * text.chars().count() as u32, 8 * s))
    }

    fn draw_text<T: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &T,
        pos: BackendCoord,
    ) -> BackendResult<(), Self::ErrorType> {
        let color = style.color();
        if color.alpha == 0.0 {
            return Ok(());
        }
        let s = Self::scale(style.size());
        let (w, h) = (8 * s * text.chars().count() as i32, 8 * s);
        let dx = match style.anchor().h_pos {
            HPos::Left => 0,
            HPos::Right => -w,
            HPos::Center => -w / 2,
        };
        let dy = match style.anchor().v_pos {
            VPos::Top => 0,
            VPos::Center => -h / 2,
            VPos::Bottom => -h,
        };
        let transform = style.transform();
        let (bw, bh) = self.get_size();
        for (i, ch) in text.chars().enumerate() {
            let code = if ch.is_ascii() {
                ch as usize
            } else {
                '?' as usize
            };
            let glyph = font8x8::legacy::BASIC_LEGACY[code];
            for (gy, row) in glyph.iter().enumerate() {
                for gx in 0..8 {
                    if (row >> gx) & 1 == 0 {
                        continue;
                    }
                    for sy in 0..s {
                        for sx in 0..s {
                            let x = i as i32 * 8 * s + gx * s + sx + dx;
                            let y = gy as i32 * s + sy + dy;
                            let (x, y) = transform.transform(x, y);
                            let (x, y) = (pos.0 + x, pos.1 + y);
                            if x >= 0 && y >= 0 && x < bw as i32 && y < bh as i32 {
                                self.0.draw_pixel((x, y), color)?;
                            }
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rms_percent_is_relative_to_the_reference() {
        let img = |v: f32| Image {
            width: 2,
            height: 1,
            pixels: vec![Vec3::splat(v); 2],
            paths: vec![1; 2],
        };
        assert_eq!(rms_percent(&img(1.0), &img(1.0)), 0.0);
        assert!((rms_percent(&img(1.1), &img(1.0)) - 10.0).abs() < 1e-4);
        assert!((rms_percent(&img(0.0), &img(2.0)) - 100.0).abs() < 1e-9);
    }

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
    fn csv_quotes_fields_with_commas() {
        assert_eq!(
            csv_field("llvmpipe (LLVM 15, 256 bits)"),
            "\"llvmpipe (LLVM 15, 256 bits)\""
        );
        assert_eq!(csv_field("warp_rr (NO)"), "warp_rr (NO)");
    }
}
