//! `cohort`: the command-line front of the path tracer. Parses options (clap), loads
//! an embedded or Mitsuba XML scene (`cohort-scenes`), renders it (`cohort-render`)
//! with a progress bar (indicatif) and writes the outputs atomically.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use choices::{
    AlgorithmChoice, Backend, DeviceList, InPatchChoice, IntegratorChoice, RouletteChoice,
    RrChoice, ShadingChoice,
};
use clap::{Parser, Subcommand};
use cohort_render::multi_device::{combined_stats, render_on_devices};
use cohort_render::provenance::Provenance;
use cohort_render::{
    output, Budget, GpuScene, PreparedScene, RenderOptions, Renderer, SceneBvh, Shard,
};
use cohort_scenes::embedded;
use options::Config;

mod check;
mod choices;
mod compare;
mod devices;
mod figures;
mod forms;
mod merge;
mod options;
mod view;

#[derive(Parser)]
#[command(
    name = "cohort",
    version,
    about = "Coherent-ray wavefront path tracer written in the Cohort GPU kernel language"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene.
    Render(RenderArgs),
    /// List the embedded scenes.
    Scenes,
    /// Run the paper's experiments (Figs. 4, 5, 7): a CSV and plots (docs/FIGURES.md).
    Figures(figures::FiguresArgs),
    /// Merge the CSVs of a sweep's shards (`figures --shard K/N`) into figures.csv and the plots.
    FiguresMerge(figures::merge::MergeArgs),
    /// Merge the EXRs of a render's shards (`render --shard K/N`) into one image.
    Merge(merge::MergeArgs),
    /// Compare two EXRs: the same image, bit for bit or within float summation order?
    Compare(compare::CompareArgs),
    /// Statistical tests of every built-in sampling strategy and BSDF (docs/VALIDATION.md).
    Check(check::CheckArgs),
    /// List the usable devices of each backend, by the index `--devices` takes.
    Devices,
    /// Watch a scene render progressively in a window: move the camera, switch the
    /// configuration live, compare two side by side (README, "The viewer").
    View(view::ViewArgs),
}

/// The paths per pixel of an embedded scene without --paths or --time.
const EMBEDDED_PATHS: u32 = 64;

#[derive(clap::Args)]
struct RenderArgs {
    /// Embedded scene name (see `cohort scenes`) or a Mitsuba 3 XML file.
    #[arg(long, default_value = embedded::DEFAULT)]
    scene: String,
    /// Which backend runs the kernels (default: a real GPU if there is one, else `cpu`).
    #[arg(long, value_enum)]
    backend: Option<Backend>,
    /// Diffuse sampling: `normal` (independent cosine sampling), or coherent sampling shared
    /// by a group of paths; besides the listed groups, `block_N` with N a multiple of 32 up
    /// to 1024.
    #[arg(long, default_value = "normal", value_parser = choices::AlgorithmParser)]
    algorithm: AlgorithmChoice,
    /// N: the hemisphere is split into N x 4N patches for coherent sampling (1..=1000).
    #[arg(long, default_value_t = 64, value_parser = choices::patches_n(), allow_negative_numbers = true)]
    n: u32,
    /// How a ray samples inside its group's patch (coherent algorithms).
    #[arg(long, value_enum, default_value_t = InPatchChoice::Uniform)]
    in_patch: InPatchChoice,
    /// Who draws the Russian roulette that ends paths: each path (`path`: per-path
    /// roulette, whatever --integrator is), each group or the whole group. --roulette
    /// chooses the continuation probability.
    #[arg(long, value_enum, default_value_t = RrChoice::Path)]
    rr: RrChoice,
    /// The continuation probability of the Russian roulette that --rr draws.
    #[arg(long, value_enum, default_value_t = RouletteChoice::Auto)]
    roulette: RouletteChoice,
    /// Continuation probability of the whole-group-end roulette (`--rr whole`), in (0, 1].
    #[arg(long, default_value_t = 0.5, value_parser = choices::probability, allow_negative_numbers = true)]
    end_continue: f32,
    /// Interleaved sampling factor D (odd, and coprime with the image size): pixel
    /// coordinates are multiplied by D; 1 for none.
    #[arg(long, default_value_t = 1, value_parser = choices::odd, allow_negative_numbers = true)]
    interleave: u32,
    /// Glossy (GGX) bounces also sample coherently, sharing a cell of the VNDF domain.
    #[arg(long)]
    coherent_glossy: bool,
    /// Image width, at least 1 (default: the scene's film).
    #[arg(long, value_parser = choices::at_least_one(), allow_negative_numbers = true)]
    width: Option<u32>,
    /// Image height, at least 1 (default: the scene's film).
    #[arg(long, value_parser = choices::at_least_one(), allow_negative_numbers = true)]
    height: Option<u32>,
    /// Completed paths per pixel, at least 1 (default: the sample_count of a Mitsuba
    /// scene's sampler, or 64).
    #[arg(long, conflicts_with = "time", value_parser = choices::at_least_one(), allow_negative_numbers = true)]
    paths: Option<u32>,
    /// Budget of accumulated GPU kernel time (traverse + extend + compact), in seconds
    /// (positive, at most 1e6).
    #[arg(long, value_parser = choices::seconds, allow_negative_numbers = true)]
    time: Option<f64>,
    /// Seed of the random numbers (0..=4294967295): the same seed, options and budget
    /// give the same image.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    seed: u32,
    /// Linear EXR output.
    #[arg(long, default_value = "render.exr")]
    out: PathBuf,
    /// Tone-mapped sRGB PNG output (default: beside the EXR, its name with `.png`: so
    /// renders with different --out, shards among them, do not overwrite one PNG).
    #[arg(long)]
    png: Option<PathBuf>,
    /// Exposure of the PNG, in stops (negative: darker).
    #[arg(long, default_value_t = 0.0, value_parser = choices::finite, allow_negative_numbers = true)]
    exposure: f32,
    /// Statistics as JSON.
    #[arg(long)]
    stats: Option<PathBuf>,
    /// Run stream compaction between iterations (the paper's renderer; its `(NO)`
    /// variants are without). Off by default: with light sampling, the path state stays
    /// coalesced without it and renders reach a given error about twice as fast on an H100
    /// (BENCHMARKS.md, equal-time table).
    #[arg(long)]
    compact: bool,
    /// Keep finished slots in the live list. By default, once a quarter of the listed
    /// slots have finished their pixel's paths, the list is cut to the others, where the
    /// image does not depend on which invocation takes a slot; it is the same image either
    /// way, so this is for comparisons of speed.
    #[arg(long)]
    no_retire: bool,
    /// Sort the rays by direction octant and origin cell before the traversal, every K
    /// iterations (0: never, the default). The image is the same; it changes only the
    /// order in which the traversal takes the rays (BENCHMARKS.md: it does not pay).
    #[arg(
        long,
        value_name = "K",
        default_value_t = 0,
        allow_negative_numbers = true
    )]
    reorder: u32,
    /// How shading is organised: one kernel built with the scene's BSDF kinds, material
    /// queues (one kernel per kind over the rays that hit it), or `auto`, the default:
    /// on a GPU, both measured on the render and the faster kept (BENCHMARKS.md: each wins
    /// on some scenes); on the CPU backend and the software driver, one kernel. The image
    /// is the same either way, except with coherent groups, which form over the queues
    /// (and where `auto` keeps one kernel).
    #[arg(long, value_enum, default_value_t = ShadingChoice::Auto)]
    shading: ShadingChoice,
    /// Ray slots in flight: paths traced at once. Rounded up to whole copies of the image
    /// (several paths of each pixel at once), at most one copy per path of the budget.
    /// Default: chosen from the device (about a million on a GPU, 16384 on the CPU
    /// backend and software drivers). The image does not depend on it beyond the order
    /// of float sums.
    #[arg(long, value_name = "SLOTS", value_parser = clap::value_parser!(u32).range(1..))]
    wavefront: Option<u32>,
    /// The light transport estimator. The default here is `nee`; `cohort figures`
    /// defaults to `path`, the paper's.
    #[arg(long, value_enum, default_value_t = IntegratorChoice::Nee)]
    integrator: IntegratorChoice,
    /// Coherent light sampling (with `--integrator nee`): a group shares its light pick
    /// and one of K x K strata of the light.
    #[arg(long)]
    coherent_light: bool,
    /// K of the K x K light strata of `--coherent-light` (1..=64).
    #[arg(long, default_value_t = 4, value_parser = choices::light_cells(), allow_negative_numbers = true)]
    light_cells: u32,
    /// Mitsuba scenes: render even with plugins, elements or parameters that Mitsuba rejects or
    /// the renderer does not implement; each becomes a warning and the object is skipped or
    /// replaced by the nearest supported one (default: an error naming file and line).
    #[arg(long)]
    lenient: bool,
    /// Mitsuba scenes: set the scene parameter `$NAME` (overrides its `<default>`), as
    /// `mitsuba -D NAME=VALUE`. Repeatable.
    #[arg(short = 'D', value_name = "NAME=VALUE", value_parser = parse_define)]
    define: Vec<(String, String)>,
    /// Render only shard K of N of the budget (0 <= K < N): with --paths P, paths
    /// K*P/N..(K+1)*P/N of every pixel. `cohort merge` combines the shards' EXRs.
    #[arg(long, value_name = "K/N", value_parser = Shard::parse)]
    shard: Option<Shard>,
    /// Render on several devices at once, one thread each, splitting the paths between
    /// them: `all`, or device indices such as `0,1` (`cohort devices` lists them).
    #[arg(long, value_parser = choices::device_list)]
    devices: Option<DeviceList>,
}

/// `NAME=VALUE` of `-D`.
fn parse_define(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((k, v)) if !k.is_empty() => Ok((k.to_string(), v.to_string())),
        _ => Err(format!("expected NAME=VALUE, got '{s}'")),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Scenes => {
            for name in embedded::names() {
                println!("{name:<12} {}", embedded::description(name).unwrap_or(""));
            }
            Ok(())
        }
        Command::Render(a) => render(a),
        Command::Figures(a) => figures::run(a),
        Command::FiguresMerge(a) => figures::merge::run(a),
        Command::Merge(a) => merge::run(a),
        Command::Compare(a) => compare::run(a),
        Command::Check(a) => check::run(a),
        Command::Devices => devices::list(),
        Command::View(a) => view::run(a),
    };
    // Before exit destroys LLVM's static objects, which a background compile may use.
    cohort::runtime::stop_background_compiles();
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn load_scene(
    name: &str,
    options: &cohort_scenes::LoadOptions,
) -> Result<cohort_scenes::Scene, String> {
    if let Some(s) = embedded::load(name) {
        if !options.params.is_empty() {
            return Err(format!(
                "-D sets parameters of Mitsuba XML scenes; `{name}` is an embedded scene"
            ));
        }
        return Ok(s);
    }
    if name.ends_with(".xml") || std::path::Path::new(name).exists() {
        let loaded = cohort_scenes::load_mitsuba_with(name, options).map_err(|e| e.to_string())?;
        for w in &loaded.warnings {
            eprintln!("warning: {w}");
        }
        return Ok(loaded.scene);
    }
    Err(format!(
        "unknown scene `{name}`: not an embedded scene ({}) nor an XML file",
        embedded::names().join(", ")
    ))
}

impl RenderArgs {
    /// Where the PNG goes: --png, else the EXR's path with the extension `.png`.
    fn png_path(&self) -> Result<PathBuf, String> {
        let png = self
            .png
            .clone()
            .unwrap_or_else(|| self.out.with_extension("png"));
        if png == self.out {
            return Err(format!(
                "--out and the PNG would both be written to {}: name the PNG with --png",
                png.display()
            ));
        }
        Ok(png)
    }

    /// The configuration options, by name (shared with `cohort view`).
    fn config(&self) -> Config {
        Config {
            algorithm: self.algorithm,
            n: self.n,
            in_patch: self.in_patch,
            rr: self.rr,
            roulette: self.roulette,
            end_continue: self.end_continue,
            interleave: self.interleave,
            coherent_glossy: self.coherent_glossy,
            compact: self.compact,
            retire: !self.no_retire,
            reorder: self.reorder,
            shading: self.shading,
            integrator: self.integrator,
            coherent_light: self.coherent_light,
            light_cells: self.light_cells,
            seed: self.seed,
            wavefront: self.wavefront,
        }
    }

    /// The budget the options ask for (`None`: the scene's default). The parser has
    /// checked both numbers.
    fn budget(&self) -> Option<Budget> {
        match (self.paths, self.time) {
            (_, Some(t)) => Some(Budget::KernelTime(Duration::from_secs_f64(t))),
            (Some(p), None) => Some(Budget::PathsPerPixel(p)),
            (None, None) => None,
        }
    }

    /// The budget known before the scene is read: the options', or an embedded scene's
    /// default.
    fn known_budget(&self) -> Option<Budget> {
        self.budget().or(self
            .is_embedded_scene()
            .then_some(Budget::PathsPerPixel(EMBEDDED_PATHS)))
    }

    /// Checks `options` as far as they can be without the scene, so that a combination the
    /// renderer refuses (`--rr whole` with `grid`, `--coherent-light` with `--integrator
    /// path`, a shard without paths, an interleave factor that does not permute the given
    /// width or height) fails before any scene is read or device opened. Sides of the
    /// image taken from the scene's film are checked once it is read.
    fn check_before_scene(&self, options: &RenderOptions) -> Result<(), String> {
        let options = RenderOptions {
            // Unknown until the scene is read: a time budget, which every shard has.
            budget: self
                .known_budget()
                .unwrap_or(Budget::KernelTime(Duration::ZERO)),
            ..options.clone()
        };
        options
            .check(self.width.unwrap_or(1), self.height.unwrap_or(1))
            .map_err(|e| e.to_string())
    }

    fn is_embedded_scene(&self) -> bool {
        embedded::names().contains(&self.scene.as_str())
    }

    /// The scene the options name, loaded with their `-D` and `--lenient`.
    fn load_scene(&self) -> Result<cohort_scenes::Scene, String> {
        load_scene(
            &self.scene,
            &cohort_scenes::LoadOptions {
                params: self.define.clone(),
                lenient: self.lenient,
            },
        )
    }

    /// `--width` / `--height` (one alone keeps the scene's other side).
    fn size(&self, scene: &cohort_scenes::Scene) -> Option<(u32, u32)> {
        match (self.width, self.height) {
            (None, None) => None,
            (w, h) => Some((
                w.unwrap_or(scene.camera.width),
                h.unwrap_or(scene.camera.height),
            )),
        }
    }
}

/// When the scene had loaded, the device had opened (on its own thread) and the BVH had
/// been built, from the start of `render`.
struct Opened {
    scene_loaded: std::time::Duration,
    device_opened: std::time::Duration,
    bvh_built: std::time::Duration,
}

fn render(a: RenderArgs) -> Result<(), String> {
    let process_start = std::time::Instant::now();
    let config = a.config();
    let shard = a.shard.unwrap_or(Shard::WHOLE);
    let configured = RenderOptions {
        shard,
        ..config.options(a.is_embedded_scene())
    };
    // Every option is checked before anything is loaded or rendered, and so is where the
    // outputs go.
    a.check_before_scene(&configured)?;
    let png_path = a.png_path()?;
    for path in [Some(&a.out), Some(&png_path), a.stats.as_ref()]
        .into_iter()
        .flatten()
    {
        output::check_destination(path).map_err(|e| e.to_string())?;
    }
    // The device opens on its own thread while the scene loads and (for one device) its
    // BVH is built (or read from the cache) and its arrays laid out: neither needs the
    // other. The devices come back over a channel, and the thread then sleeps until the
    // process ends: on the H200's driver, a thread that opened a Vulkan device works for
    // 11-13 ms more when it exits, and holds the driver meanwhile. Joined, it delayed the
    // first iteration by that much; left to exit on its own, it delayed the upload.
    let (opened_tx, opened_rx) = std::sync::mpsc::channel();
    let (backend, device_list) = (a.backend.map(Backend::kind), a.devices.clone());
    std::thread::spawn(move || {
        let devices = devices::open(backend, device_list.as_ref());
        let _ = opened_tx.send((devices, process_start.elapsed()));
        // `park` may return spuriously.
        loop {
            std::thread::park();
        }
    });
    let (scene, built, devices, opts, times) = {
        let loaded = (|| {
            let scene = a.load_scene()?;
            let scene_loaded = process_start.elapsed();
            // A Mitsuba scene renders its sampler's sample count, as Mitsuba would.
            let budget = a
                .known_budget()
                .unwrap_or(Budget::PathsPerPixel(scene.sample_count.max(1)));
            let size = a.size(&scene);
            let (w, h) = size.unwrap_or((scene.camera.width, scene.camera.height));
            let opts = RenderOptions {
                budget,
                size,
                ..configured
            };
            // With the scene's size and budget, before anything is uploaded.
            opts.check(w, h).map_err(|e| e.to_string())?;
            // Several devices: each renderer builds and uploads its own.
            let built = match a.devices {
                None => {
                    let built = SceneBvh::cached(&scene).map_err(|e| e.to_string())?;
                    Some(PreparedScene::new(&scene, built))
                }
                Some(_) => None,
            };
            Ok::<_, String>((scene, scene_loaded, opts, built))
        })();
        let (devices, device_opened) = opened_rx
            .recv()
            .map_err(|_| "the device thread panicked".to_string())?;
        let (scene, scene_loaded, opts, built) = loaded?;
        let times = Opened {
            scene_loaded,
            device_opened,
            bvh_built: process_start.elapsed(),
        };
        (scene, built, devices?, opts, times)
    };
    let (w, h) = opts
        .size
        .unwrap_or((scene.camera.width, scene.camera.height));
    let RenderOptions {
        algorithm,
        group_rr,
        whole_group_end,
        integrator,
        budget,
        ..
    } = opts;
    let info = devices[0].info().clone();
    for w in cohort_render::roulette::warnings(&scene, &opts) {
        eprintln!("warning: {w}");
    }
    let device_names: Vec<String> = devices
        .iter()
        .map(|d| d.info().adapter_name.clone())
        .collect();
    // One device: the renderer is made here, so that its startup (BVH build, upload,
    // pipelines) is reported apart from the render. Several: one thread per device.
    let bvh_cached = built.as_ref().is_some_and(|b| b.built.cached);
    let arrays_time = built.as_ref().map_or(Duration::ZERO, |b| b.time);
    let mut single = match (devices.as_slice(), &built) {
        ([device], Some(built)) => {
            let gpu = GpuScene::upload_prepared(device, built).map_err(|e| e.to_string())?;
            Some(
                Renderer::with_scene(device, &scene, gpu, opts.clone())
                    .map_err(|e| e.to_string())?,
            )
        }
        ([device], None) => {
            Some(Renderer::new(device, &scene, opts.clone()).map_err(|e| e.to_string())?)
        }
        _ => None,
    };
    // Everything before the first iteration: the render starts right after this.
    let ready = process_start.elapsed();
    // A BVH built for the cache is written while the scene renders (waited for on return).
    let _saving = built.map(PreparedScene::save_beside);
    let startup = single.as_ref().map(|r| r.startup()).unwrap_or_default();
    eprintln!(
        "{} ({w}x{h}, {} triangles) on {} [{}], algorithm {}{}",
        a.scene,
        scene.triangles.len(),
        device_names.join(" + "),
        info.backend.name(),
        algorithm.name(),
        if shard == Shard::WHOLE {
            String::new()
        } else {
            format!(", shard {shard}")
        }
    );
    let bar = indicatif::ProgressBar::new(1000);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {percent:>3}% {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    // Each device's thread reports its own fraction and statistics; the bar shows them
    // together.
    let progress = std::sync::Mutex::new(vec![
        (0.0, cohort_render::RenderStats::default());
        devices.len()
    ]);
    let report = |i: usize, frac: f64, s: &cohort_render::RenderStats| {
        let mut all = progress.lock().unwrap_or_else(|p| p.into_inner());
        all[i] = (frac, s.clone());
        let frac = all.iter().map(|p| p.0).sum::<f64>() / all.len() as f64;
        let s = combined_stats(&all.iter().map(|p| p.1.clone()).collect::<Vec<_>>());
        bar.set_position((frac * 1000.0) as u64);
        bar.set_message(format!(
            "{:.2} paths/pixel, {} iterations",
            s.paths_per_pixel(),
            s.iterations
        ));
    };
    let (image, per_device) = match single.as_mut() {
        Some(renderer) => {
            let (image, s) = renderer
                .render(|frac, s| report(0, frac, s))
                .map_err(|e| e.to_string())?;
            (image, vec![s])
        }
        None => render_on_devices(&devices, &scene, &opts, &report).map_err(|e| e.to_string())?,
    };
    let stats = combined_stats(&per_device);
    bar.finish_and_clear();
    let provenance = Provenance::of(&a.scene, (w, h), &opts, &device_names.join("; "));
    // The two files are encoded at once, on two threads: at 1024x1024 each takes a tenth
    // of a second or more, as long as a short render itself (BENCHMARKS.md, 2026-11-27,
    // ab1bebc).
    let attributes = provenance.to_attributes();
    let writing = std::time::Instant::now();
    // Both are written to temporary files first and put in place only when both were
    // written: a failure leaves both existing files as they were.
    let (exr, png) = std::thread::scope(|threads| {
        let png = threads.spawn(|| output::stage_png(&png_path, &image, a.exposure));
        let exr = output::stage_exr(&a.out, &image, &attributes);
        (exr, png.join().expect("the PNG writer panicked"))
    });
    let (exr, png) = (
        exr.map_err(|e| e.to_string())?,
        png.map_err(|e| e.to_string())?,
    );
    exr.commit().map_err(|e| e.to_string())?;
    png.commit().map_err(|e| e.to_string())?;
    let written = writing.elapsed();
    let k = stats.kernel;
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    println!(
        "scene          {} ({w}x{h}, {} triangles)",
        a.scene,
        scene.triangles.len()
    );
    for (i, d) in devices.iter().enumerate() {
        let info = d.info();
        let label = if devices.len() > 1 {
            format!("device {i}")
        } else {
            "device".into()
        };
        println!(
            "{label:<14} {} [{}], subgroup {}",
            info.adapter_name,
            info.backend.name(),
            info.subgroup_size
        );
    }
    if shard != Shard::WHOLE {
        let paths = match budget {
            Budget::PathsPerPixel(p) => {
                let r = shard.paths(p);
                format!("paths {}..{} of {p} per pixel", r.start, r.end)
            }
            Budget::KernelTime(_) => format!(
                "paths from {} on, for the time budget",
                shard.time_first_path()
            ),
        };
        println!(
            "shard          {shard}: {paths} ({} merge)",
            provenance.merge
        );
    }
    println!("algorithm      {}", config.label());
    println!(
        "paths/pixel    {:.2} ({} paths, {} iterations, {} slots in flight)",
        stats.paths_per_pixel(),
        stats.completed_paths,
        stats.iterations,
        stats.slots
    );
    println!(
        "kernel time    {:.1} ms: reorder {:.1}, traverse {:.1}, queue {:.1}, extend {:.1}, shadow {:.1}, compact {:.1}",
        ms(k.total()),
        ms(k.reorder),
        ms(k.traverse),
        ms(k.queue),
        ms(k.extend),
        ms(k.shadow),
        ms(k.compact)
    );
    println!(
        "shading        {} ({} of {} iterations over material queues)",
        choices::name(&a.shading),
        stats.queued_iterations,
        stats.iterations
    );
    println!(
        "paths/s        {:.3} M (per kernel second)",
        stats.paths_per_second() / 1e6
    );
    println!(
        "rays/s         {:.3} M (traversal)",
        stats.rays_per_second() / 1e6
    );
    if devices.len() == 1 {
        println!(
            "wall           {:.2} s (render; {:.0} % over kernel time)",
            stats.wall.as_secs_f64(),
            100.0 * (stats.wall.as_secs_f64() / k.total().as_secs_f64().max(1e-9) - 1.0)
        );
        println!(
            "host           {} batches: record {:.1} ms, submit {:.1} ms, wait {:.1} ms",
            stats.host.batches,
            ms(stats.host.record),
            ms(stats.host.submit),
            ms(stats.host.wait)
        );
        // Every millisecond to the first iteration: the scene and its BVH on this thread
        // while the device opens on another, then upload and pipelines, and whatever the
        // renderer's set-up took besides (buffers, the frame).
        let parallel = times.bvh_built.max(times.device_opened);
        let beside = startup.path_state.max(startup.pipelines);
        let other = ready.saturating_sub(parallel + startup.upload + beside);
        println!(
            "startup        {:.3} s to the first iteration: scene load {:.3} + BVH {} {:.3} + arrays {:.3} beside device {:.3}, then upload {:.3}, then path state {:.3} beside pipelines {:.3}{}, other {:.3} (shading {})",
            ready.as_secs_f64(),
            times.scene_loaded.as_secs_f64(),
            if bvh_cached { "read from the cache" } else { "build" },
            startup.bvh_build.as_secs_f64(),
            arrays_time.as_secs_f64(),
            times.device_opened.as_secs_f64(),
            startup.upload.as_secs_f64(),
            startup.path_state.as_secs_f64(),
            startup.pipelines.as_secs_f64(),
            // The pipeline thread the others waited for, named without the type
            // parameters that follow `___` (`--stats` has them).
            startup.kernels.first().map_or(String::new(), |(name, t)| format!(
                " (longest {} {:.3})",
                name.split("___").next().unwrap_or(name),
                t.as_secs_f64()
            )),
            other.as_secs_f64(),
            cohort_render::shading::label(startup.shading)
        );
    } else {
        // Kernel times are summed over devices; the wall time is the slowest device's.
        println!(
            "wall           {:.2} s (render on {} devices, the slowest; kernel time is their sum)",
            stats.wall.as_secs_f64(),
            devices.len()
        );
    }
    let form_counts = forms::counts(&devices);
    if !form_counts.is_empty() {
        println!("cpu forms      {}", forms::line(&form_counts));
    }
    println!(
        "mean radiance  {:.4} {:.4} {:.4}",
        image.mean().x,
        image.mean().y,
        image.mean().z
    );
    println!(
        "wrote          {} and {} in {:.3} s",
        a.out.display(),
        png_path.display(),
        written.as_secs_f64()
    );
    if let Some(path) = &a.stats {
        // Each pipeline thread's time, by its kernels' names.
        let kernels: serde_json::Map<String, serde_json::Value> = startup
            .kernels
            .iter()
            .map(|(name, t)| (name.clone(), t.as_secs_f64().into()))
            .collect();
        let startup_json = serde_json::json!({ "to_first_iteration": ready.as_secs_f64(), "scene_load": times.scene_loaded.as_secs_f64(), "device": times.device_opened.as_secs_f64(),
            "bvh_build": startup.bvh_build.as_secs_f64(), "bvh_cached": bvh_cached, "arrays": arrays_time.as_secs_f64(), "upload": startup.upload.as_secs_f64(), "path_state": startup.path_state.as_secs_f64(), "pipelines": startup.pipelines.as_secs_f64(),
            "kernels": kernels });
        let json = serde_json::json!({
            "scene": a.scene, "width": w, "height": h, "triangles": scene.triangles.len(),
            "device": info.adapter_name, "backend": info.backend.name(), "algorithm": algorithm.name(),
            "patches_n": a.n, "in_patch": choices::name(&a.in_patch), "group_rr": group_rr, "whole_group_end": whole_group_end, "interleave": a.interleave,
            "compaction": a.compact, "reorder": a.reorder, "shading_design": choices::name(&a.shading), "queued_iterations": stats.queued_iterations, "seed": a.seed, "integrator": integrator.name(), "coherent_light": a.coherent_light, "light_cells": a.light_cells,
            "shard": shard.to_string(), "devices": device_names,
            "paths_per_pixel": stats.paths_per_pixel(), "completed_paths": stats.completed_paths,
            "iterations": stats.iterations, "rays": stats.rays, "slots": stats.slots,
            "kernel_ms": { "traverse": ms(k.traverse), "extend": ms(k.extend), "shadow": ms(k.shadow), "compact": ms(k.compact), "reorder": ms(k.reorder), "queue": ms(k.queue), "total": ms(k.total()) },
            "paths_per_second": stats.paths_per_second(), "rays_per_second": stats.rays_per_second(),
            "wall_s": stats.wall.as_secs_f64(), "outputs_s": written.as_secs_f64(),
            "host_ms": { "batches": stats.host.batches, "record": ms(stats.host.record), "submit": ms(stats.host.submit), "wait": ms(stats.host.wait) },
            "startup_s": startup_json,
            "cpu_forms": forms::json(&form_counts),
            "shading": cohort_render::shading::label(startup.shading),
            "scene_integrator": {
                "max_depth": scene.integrator.max_depth, "rr_depth": scene.integrator.rr_depth,
                "hide_emitters": scene.integrator.hide_emitters,
            },
        });
        output::write_text(path, &serde_json::to_string_pretty(&json).unwrap())
            .map_err(|e| e.to_string())?;
        println!("stats          {}", path.display());
    }
    Ok(())
}
