//! The viewer's render thread: it owns the device and the renderers, advances them in
//! slices of about a frame's GPU time, runs the `display` kernel after each slice and
//! leaves the result in a mailbox. It never waits for the window: a frame the window has
//! not presented yet is replaced by the next one (frames are skipped, iterations never).

use std::path::PathBuf;
use std::sync::mpsc::{Receiver, RecvTimeoutError, TryRecvError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use cohort::runtime::{Device, GpuBuffer};
use cohort_render::provenance::Provenance;
use cohort_render::{
    output, Budget, GpuScene, PreparedScene, RenderOptions, RenderStats, Renderer, SceneBvh,
};
use cohort_scenes::{Camera, Scene};

/// GPU time one slice aims at: a new image about 30 times a second.
const SLICE: Duration = Duration::from_millis(33);

/// What the window asks of the render thread.
pub enum Command {
    /// Restart every side from this camera.
    Camera(Camera),
    /// New options for one side (0: the left or only one), restarting it.
    Configure(usize, RenderOptions),
    /// Exposure in stops; redisplays without rendering.
    Exposure(f32),
    /// Write each side's current estimate (EXR and PNG).
    Save,
    Quit,
}

/// One side of the window (two with `--compare`).
#[derive(Clone)]
pub struct SideStats {
    pub stats: RenderStats,
    /// Its budget is spent: it waits for a change.
    pub done: bool,
}

/// A finished frame: the `display` kernel's output and what the panel shows.
#[derive(Clone)]
pub struct Published {
    /// 0x00RRGGBB, row-major, `width` x `height`.
    pub pixels: Vec<u32>,
    pub width: u32,
    pub height: u32,
    /// Counts the restarts (camera moves and configuration changes) behind this frame.
    pub generation: u64,
    pub sides: Vec<SideStats>,
    /// GPU time of the last `display` dispatches.
    pub display: Duration,
}

/// What the render thread, the window and a script share.
#[derive(Default)]
pub struct Shared {
    /// The latest frame; the window takes it.
    pub latest: Mutex<Option<Published>>,
    /// Set once the device is open: its name and backend.
    pub device: Mutex<Option<String>>,
    /// Why the last change was refused (empty: it was not).
    pub status: Mutex<String>,
    /// What the window shows now (a script waits on it).
    pub presented: Mutex<Option<Presented>>,
    /// The X11 id of the window, once it is open.
    pub window_id: Mutex<Option<u64>>,
}

/// The frame on screen: its restart count, and each side's paths per pixel and paths per
/// second of kernel time (the figure the panel shows).
#[derive(Clone, Debug)]
pub struct Presented {
    pub generation: u64,
    pub paths_per_pixel: Vec<f64>,
    pub paths_per_second: Vec<f64>,
    pub done: bool,
}

/// Everything the render thread needs to begin.
pub struct Setup {
    pub scene: Scene,
    pub scene_name: String,
    pub backend: Option<cohort::runtime::BackendKind>,
    /// One per side.
    pub options: Vec<RenderOptions>,
    pub exposure: f32,
    /// Where `Save` writes: the left side's EXR and PNG (the right one's get `-compare`).
    pub out: PathBuf,
    pub png: PathBuf,
}

/// `stem.ext` -> `stem-compare.ext`: where the right side of a comparison is saved.
fn compare_path(p: &std::path::Path) -> PathBuf {
    let stem = p
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = match p.extension() {
        Some(ext) => format!("{stem}-compare.{}", ext.to_string_lossy()),
        None => format!("{stem}-compare"),
    };
    p.with_file_name(name)
}

/// The render thread's body; `wake` tells the window a frame is ready. Returns an error
/// the window reports (and then exits with).
pub fn run(
    setup: Setup,
    commands: Receiver<Command>,
    shared: Arc<Shared>,
    wake: impl Fn(),
) -> Result<(), String> {
    let device = crate::devices::one(setup.backend)?;
    *shared.device.lock().unwrap() = Some(format!(
        "{} [{}]",
        device.info().adapter_name,
        device.info().backend.name()
    ));
    // Through the BVH cache, as `cohort render`: a large scene's window opens sooner.
    let built = SceneBvh::cached(&setup.scene).map_err(|e| e.to_string())?;
    let prepared = PreparedScene::new(&setup.scene, built);
    let gpu = GpuScene::upload_prepared(&device, &prepared).map_err(|e| e.to_string())?;
    // A tree built here is written to the cache while the window renders.
    let _saving = prepared.save_beside();
    let mut sides = setup
        .options
        .iter()
        .map(|o| {
            Renderer::with_scene(&device, &setup.scene, gpu.clone(), o.clone())
                .map_err(|e| e.to_string())
        })
        .collect::<Result<Vec<_>, _>>()?;
    for s in sides.iter_mut() {
        s.start().map_err(|e| e.to_string())?;
    }
    let (w, h) = sides[0].size();
    let out: GpuBuffer<u32> = device.alloc((w * h) as usize).map_err(|e| e.to_string())?;
    let mut view = View {
        device: &device,
        out,
        exposure: setup.exposure,
        generation: 0,
        stats: vec![RenderStats::default(); sides.len()],
        // Paths per pixel of one slice, per side: grows until a slice takes SLICE.
        slice_paths: vec![1; sides.len()],
    };
    view.publish(&sides, &shared)?;
    wake();
    loop {
        let idle = sides.iter().zip(&view.stats).all(|(s, st)| finished(s, st));
        // Changes first; while every side is finished, wait for one.
        let first = if idle {
            match commands.recv_timeout(Duration::from_millis(250)) {
                Ok(c) => Some(c),
                Err(RecvTimeoutError::Timeout) => continue,
                Err(RecvTimeoutError::Disconnected) => return Ok(()),
            }
        } else {
            match commands.try_recv() {
                Ok(c) => Some(c),
                Err(TryRecvError::Empty) => None,
                // The window is gone: nobody will see another frame.
                Err(TryRecvError::Disconnected) => return Ok(()),
            }
        };
        let mut changed = false;
        for c in first
            .into_iter()
            .chain(std::iter::from_fn(|| commands.try_recv().ok()))
        {
            match c {
                Command::Quit => return Ok(()),
                Command::Camera(camera) => {
                    for (i, s) in sides.iter_mut().enumerate() {
                        s.set_camera(camera).map_err(|e| e.to_string())?;
                        s.start().map_err(|e| e.to_string())?;
                        view.restarted(i);
                    }
                    view.generation += 1;
                }
                Command::Configure(i, opts) => {
                    // The camera stays: `reconfigure` changes only the options.
                    // A refused configuration leaves the side as it was, and says why.
                    let s = &mut sides[i];
                    match s.reconfigure(opts) {
                        Ok(()) => {
                            s.start().map_err(|e| e.to_string())?;
                            view.restarted(i);
                        }
                        Err(e) => *shared.status.lock().unwrap() = format!("refused: {e}"),
                    }
                    view.generation += 1;
                }
                Command::Exposure(stops) => view.exposure = stops,
                // A file that cannot be written is reported; the render goes on.
                Command::Save => {
                    if let Err(e) = save(&sides, &setup, &device, view.exposure) {
                        eprintln!("error: {e}");
                        *shared.status.lock().unwrap() = e;
                    }
                }
            }
            changed = true;
        }
        // The side with the least GPU time renders next: both get the same time.
        let next = (0..sides.len())
            .filter(|&i| !finished(&sides[i], &view.stats[i]))
            .min_by_key(|&i| view.stats[i].kernel.total());
        if let Some(i) = next {
            view.advance(&mut sides[i], i)?;
        } else if !changed {
            continue;
        }
        view.publish(&sides, &shared)?;
        wake();
    }
}

/// A side's budget is spent (never, without `--paths` or `--time`).
fn finished(r: &Renderer, stats: &RenderStats) -> bool {
    match r.options().budget {
        Budget::PathsPerPixel(p) => stats.completed_paths >= p as u64 * stats.pixels.max(1),
        Budget::KernelTime(t) => stats.kernel.total() >= t,
    }
}

/// The render thread's state besides the renderers.
struct View<'d> {
    device: &'d Device,
    out: GpuBuffer<u32>,
    exposure: f32,
    generation: u64,
    stats: Vec<RenderStats>,
    slice_paths: Vec<u32>,
}

impl View<'_> {
    fn restarted(&mut self, side: usize) {
        self.stats[side] = RenderStats::default();
        self.slice_paths[side] = 1;
    }

    /// One slice of side `i`: a few more paths per pixel, as many as fit in SLICE.
    fn advance(&mut self, r: &mut Renderer, i: usize) -> Result<(), String> {
        let stats = &self.stats[i];
        let (w, h) = r.size();
        let done = stats.completed_paths / (w as u64 * h as u64);
        let mut until = done as u32 + self.slice_paths[i];
        if let Budget::PathsPerPixel(p) = r.options().budget {
            until = until.min(p);
        }
        let before = stats.kernel.total();
        // Slices count paths, so that a batch is as long as the renderer likes it; the
        // last slice of a time budget ends at the budget.
        let slice = match r.options().budget {
            Budget::KernelTime(t) if before + 2 * SLICE >= t => Budget::KernelTime(t),
            _ => Budget::PathsPerPixel(until),
        };
        let stats = r.advance(slice).map_err(|e| e.to_string())?;
        let took = (stats.kernel.total() - before).as_secs_f64();
        let per_path = took / self.slice_paths[i] as f64;
        if per_path > 0.0 {
            self.slice_paths[i] = ((SLICE.as_secs_f64() / per_path) as u32).clamp(1, 256);
        }
        self.stats[i] = stats;
        Ok(())
    }

    /// Runs `display` for every side (each writes its columns) and leaves the frame.
    fn publish(&mut self, sides: &[Renderer], shared: &Shared) -> Result<(), String> {
        let (w, h) = sides[0].size();
        let n = sides.len() as u32;
        let mut display = Duration::ZERO;
        for (i, s) in sides.iter().enumerate() {
            let i = i as u32;
            let columns = i * w / n..(i + 1) * w / n;
            let st = s
                .display(&self.out, self.exposure, columns)
                .map_err(|e| e.to_string())?;
            display += Duration::from_nanos(st.gpu_time_ns.unwrap_or(0));
        }
        let pixels = self.device.read(&self.out).map_err(|e| e.to_string())?;
        let frame = Published {
            pixels,
            width: w,
            height: h,
            generation: self.generation,
            sides: sides
                .iter()
                .zip(&self.stats)
                .map(|(s, st)| SideStats {
                    stats: st.clone(),
                    done: finished(s, st),
                })
                .collect(),
            display,
        };
        *shared.latest.lock().unwrap() = Some(frame);
        Ok(())
    }
}

/// Writes every side's current estimate, as `cohort render` writes its result.
fn save(sides: &[Renderer], setup: &Setup, device: &Device, stops: f32) -> Result<(), String> {
    let started = Instant::now();
    for (i, s) in sides.iter().enumerate() {
        let (out, png) = if i == 0 {
            (setup.out.clone(), setup.png.clone())
        } else {
            (compare_path(&setup.out), compare_path(&setup.png))
        };
        let image = s.image().map_err(|e| e.to_string())?;
        let provenance = Provenance::of(
            &setup.scene_name,
            s.size(),
            s.options(),
            &device.info().adapter_name,
        );
        output::write_exr(&out, &image, &provenance.to_attributes()).map_err(|e| e.to_string())?;
        output::write_png(&png, &image, stops).map_err(|e| e.to_string())?;
        println!(
            "wrote {} and {} ({:.2} paths/pixel, {:.0} ms)",
            out.display(),
            png.display(),
            image.paths.iter().map(|&p| p as f64).sum::<f64>() / image.paths.len().max(1) as f64,
            started.elapsed().as_secs_f64() * 1e3
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_compared_side_is_saved_beside_the_first() {
        assert_eq!(
            compare_path(std::path::Path::new("out/render.exr")),
            PathBuf::from("out/render-compare.exr")
        );
        assert_eq!(
            compare_path(std::path::Path::new("img")),
            PathBuf::from("img-compare")
        );
    }
}
