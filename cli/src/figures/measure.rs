//! Measuring: the device and the progress of a run (`Sweep`), a scene loaded and uploaded
//! once, the warm-up, and one group of points measured together round-robin, which gives
//! the rows of the CSV.

use std::sync::Arc;
use std::time::Duration;

use cohort::runtime::Device;
use cohort_render::{
    Algorithm, Budget, GpuScene, Image, InPatch, RenderOptions, RenderStats, Renderer,
};

use super::csv::Row;
use super::plan::{Group, Plan, SceneSpec};
use super::reference::{reference_image, rms_percent};

/// A run of the sweep on one device, with its progress bar: `total` points (references
/// included), of which `done` are measured.
pub struct Sweep<'a> {
    pub device: &'a Device,
    /// Adapter and backend, as the CSV names them.
    pub device_name: String,
    pub plan: &'a Plan,
    bar: indicatif::ProgressBar,
    total: u64,
    done: u64,
}

/// A scene of the sweep, loaded, with its BVH on the device and its image size.
pub struct LoadedScene<'p> {
    pub spec: &'p SceneSpec,
    scene: cohort_scenes::Scene,
    gpu: Arc<GpuScene>,
    pub size: (u32, u32),
}

/// A point of a group, before it is measured.
struct Point {
    algorithm: Algorithm,
    n: Option<u32>,
    label: String,
    /// For messages: scene, label and N.
    what: String,
}

impl<'a> Sweep<'a> {
    pub fn new(device: &'a Device, plan: &'a Plan, total: u64) -> Sweep<'a> {
        let info = device.info();
        let bar = indicatif::ProgressBar::new(total * 1000);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "[{elapsed_precise}] {bar:40} {percent:>3}% eta {eta} {msg}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Sweep {
            device,
            device_name: format!("{} [{}]", info.adapter_name, info.backend.name()),
            plan,
            bar,
            total,
            done: 0,
        }
    }

    /// A line on stderr, above the progress bar.
    pub fn log(&self, line: String) {
        self.bar.suspend(|| eprintln!("{line}"))
    }

    pub fn total(&self) -> u64 {
        self.total
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }

    /// Loads the scene and uploads its BVH, once for all its points, and checks that every
    /// interleave factor suits its image size.
    pub fn load<'p>(&self, spec: &'p SceneSpec) -> Result<LoadedScene<'p>, String> {
        let scene = crate::load_scene(&spec.arg, &Default::default())?;
        // The BVH is built and uploaded once per scene, not once per point.
        let gpu =
            GpuScene::prepare(self.device, &scene).map_err(|e| format!("{}: {e}", spec.label))?;
        let (w, h) = (
            self.plan.width.unwrap_or(scene.camera.width),
            self.plan.height.unwrap_or(scene.camera.height),
        );
        for &d in &self.plan.interleaves {
            if !cohort_render::renderer::interleave_permutes(d, w, h) {
                return Err(format!("bad --interleave value `{d}`: it must be odd and coprime with the image size {w}x{h} of scene `{}`", spec.arg));
            }
        }
        Ok(LoadedScene {
            spec,
            scene,
            gpu,
            size: (w, h),
        })
    }

    /// Warm-up: one iteration of every configuration in every column, with the options
    /// its measured points use (`point_options`: the sampler, the roulette, whole-group
    /// ends and compaction each choose other kernels), so that a first-use cost of its
    /// pipelines (some drivers compile lazily, inside the timed dispatch) is paid here
    /// and not inside a measured point.
    pub fn warm_up(&self, scene: &LoadedScene) -> Result<(), String> {
        let plan = self.plan;
        for column in &plan.columns {
            let group = Group {
                index: 0,
                scene: 0,
                interleave: 1,
                column: *column,
                n: plan
                    .ns
                    .first()
                    .copied()
                    .unwrap_or(RenderOptions::default().patches_n),
            };
            for alg in plan.algorithms_of(&group) {
                self.bar.set_message(format!(
                    "[{}/{}] {} warm-up {}{}",
                    self.done + 1,
                    self.total,
                    scene.spec.label,
                    alg.name(),
                    column.suffix
                ));
                let opts = RenderOptions {
                    budget: Budget::KernelTime(Duration::from_nanos(1)),
                    ..point_options(plan, alg, &group, scene.size)
                };
                self.render(scene, opts).map_err(|e| {
                    format!(
                        "{} warm-up {}{}: {e}",
                        scene.spec.label,
                        alg.name(),
                        column.suffix
                    )
                })?;
            }
        }
        Ok(())
    }

    /// The reference: a long `normal` render, cached in out-dir. One point of the progress.
    pub fn reference(&mut self, scene: &LoadedScene) -> Result<Image, String> {
        self.bar.set_message(format!(
            "[{}/{}] {} reference ({:.1} s)",
            self.done + 1,
            self.total,
            scene.spec.label,
            self.plan.reference_time.as_secs_f64()
        ));
        self.bar.set_position(self.done * 1000);
        let reference = reference_image(self, scene)?;
        self.done += 1;
        Ok(reference)
    }

    /// One render on its own: the warm-ups and the reference, which nothing is compared
    /// with for speed.
    pub fn render(
        &self,
        scene: &LoadedScene,
        opts: RenderOptions,
    ) -> Result<(Image, RenderStats), String> {
        let mut renderer = Renderer::with_scene(self.device, &scene.scene, scene.gpu.clone(), opts)
            .map_err(|e| e.to_string())?;
        let index = self.done;
        renderer
            .render(|frac, _| self.bar.set_position(index * 1000 + (frac * 999.0) as u64))
            .map_err(|e| e.to_string())
    }

    /// Measures a group (`measure_group`) and makes its rows: RMS against `reference`,
    /// speed against the group's own `normal`. One line per point goes to stderr.
    pub fn measure(
        &mut self,
        scene: &LoadedScene,
        reference: &Image,
        group: &Group,
        pool: &mut Vec<Renderer<'a>>,
    ) -> Result<Vec<Row>, String> {
        let measured = self.measure_group(scene, group, pool)?;
        self.done += measured.len() as u64;
        let normal_pps = measured[0].1.paths_per_second();
        let mut rows = Vec::with_capacity(measured.len());
        for (point, stats, image) in measured {
            let pps = stats.paths_per_second();
            let row = Row {
                scene: scene.spec.label.clone(),
                width: scene.size.0,
                height: scene.size.1,
                config: point.algorithm.name(),
                label: point.label,
                n: point.n,
                group_n: group.n,
                column: group.column,
                interleave: group.interleave,
                rms_percent: rms_percent(&image, reference),
                rms_abs: image.rms_diff(reference) as f64,
                ratio_vs_normal: pps / normal_pps,
                stats,
            };
            self.log(format!(
                "{}: {:.2} paths/pixel, {:.3} M paths/s (x{:.3} normal of N={}), RMS {:.3} % ({:.2} % at 1 path/pixel)",
                point.what,
                row.stats.paths_per_pixel(),
                pps / 1e6,
                row.ratio_vs_normal,
                group.n,
                row.rms_percent,
                row.rms_at_1spp()
            ));
            rows.push(row);
        }
        Ok(rows)
    }

    /// Measures one group: `normal` (first) and every coherent configuration at N =
    /// `group.n`, for one scene, D and column. All are started, then advanced in turn, in
    /// `plan.slices` slices of the budget each, so that they share whatever the GPU's
    /// clocks do meanwhile (the driver lowers them when the GPU idles, e.g. while the host
    /// computes between points; separate renders one after another were measured at clocks
    /// up to 4x apart). `pool` holds the renderers of earlier groups (about 150 MB each at
    /// 1024x1024), reconfigured here rather than made anew: a new renderer per point cost
    /// the host more time than the point's GPU work, and the idle GPU lowered its clocks
    /// (docs/FIGURES.md).
    fn measure_group(
        &self,
        scene: &LoadedScene,
        group: &Group,
        pool: &mut Vec<Renderer<'a>>,
    ) -> Result<Vec<(Point, RenderStats, Image)>, String> {
        let (plan, spec, (w, h)) = (self.plan, scene.spec, scene.size);
        let (d, column, group_n) = (group.interleave, group.column, group.n);
        let (bar, first, total) = (&self.bar, self.done, self.total);
        let points: Vec<Point> = plan
            .algorithms_of(group)
            .into_iter()
            .map(|algorithm| {
                let n = (algorithm != Algorithm::NORMAL).then_some(group_n);
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
            let opts = point_options(plan, point.algorithm, group, (w, h));
            if i < pool.len() {
                pool[i]
                    .reconfigure(opts)
                    .map_err(|e| format!("{}: {e}", point.what))?;
            } else {
                pool.push(
                    Renderer::with_scene(self.device, &scene.scene, scene.gpu.clone(), opts)
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
}

/// The options of the point of `group` that renders with `algorithm` (`normal` keeps the
/// default patch count; the others take the group's N): the measured run's, and the
/// warm-up's, which must build the same kernels.
fn point_options(
    plan: &Plan,
    algorithm: Algorithm,
    group: &Group,
    size: (u32, u32),
) -> RenderOptions {
    let column = group.column;
    RenderOptions {
        algorithm,
        in_patch: InPatch::Uniform,
        patches_n: if algorithm == Algorithm::NORMAL {
            RenderOptions::default().patches_n
        } else {
            group.n
        },
        group_rr: column.group_rr,
        interleave: group.interleave,
        budget: Budget::KernelTime(plan.time),
        seed: plan.seed,
        size: Some(size),
        compact: column.compact,
        whole_group_end: column.whole.then_some(plan.end_continue),
        integrator: plan.integrator,
        ..Default::default()
    }
}
