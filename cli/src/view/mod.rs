//! `cohort view`: the paper's interactive renderer (§3, its fourth kernel
//! `display`). A render thread advances the wavefront loop and runs `display` on the
//! device; the window presents the latest frame, moves the camera (accumulation restarts,
//! as in the paper), switches the configuration live, and with `--compare` shows two
//! configurations side by side at equal GPU time.
//!
//! - `worker`: the render thread (renderers, slices, `display`, the frame mailbox);
//! - `window`: the winit window, input, presentation and the panel;
//! - `input`: keys and drags as actions; `camera`: orbit, pan, dolly, fly;
//! - `panel`: the text panel; `script`: `--script`, the same actions from a file.

mod camera;
mod input;
mod panel;
mod script;
mod window;
mod worker;

use std::path::PathBuf;
use std::sync::mpsc::{self, Sender};
use std::sync::Arc;
use std::time::{Duration, Instant};

use cohort_render::{Budget, RenderOptions};
use winit::event_loop::{EventLoop, EventLoopProxy};

use input::Action;
use script::{Script, Step};
use worker::{Setup, Shared};

#[derive(clap::Args)]
pub struct ViewArgs {
    #[command(flatten)]
    render: crate::RenderArgs,
    /// A second configuration beside the first, each with its own accumulation and the
    /// same GPU time: `NAME=VALUE` overrides of the first's options, separated by commas
    /// (`--compare algorithm=block_256,interleave=5`).
    #[arg(long, value_name = "NAME=VALUE,...")]
    compare: Option<String>,
    /// Drive the viewer from a file of commands (keys, drags, waits; README, "The viewer").
    #[arg(long)]
    script: Option<PathBuf>,
}

/// What reaches the window's event loop from the other threads.
pub enum UserEvent {
    /// The render thread left a new frame.
    Frame,
    /// A script's action; the reply is the restart count it leads to, or why it was refused.
    Script(Action, Sender<Result<u64, String>>),
    /// The render thread or the script failed.
    Failed(String),
}

/// The X11 window id (what screenshot tools and `xdotool` take).
fn x11_window_id(window: &winit::window::Window) -> u64 {
    use winit::raw_window_handle::{HasWindowHandle, RawWindowHandle};
    match window.window_handle().map(|h| h.as_raw()) {
        Ok(RawWindowHandle::Xlib(h)) => h.window,
        Ok(RawWindowHandle::Xcb(h)) => h.window.get() as u64,
        _ => 0,
    }
}

/// Why no window can open here, before winit tries (it would fail less clearly).
fn check_display() -> Result<String, String> {
    match std::env::var("DISPLAY") {
        Ok(d) if !d.is_empty() => Ok(d),
        _ => Err(
            "cohort view needs a display, and $DISPLAY is not set (no X11 server here; \
                  Wayland desktops provide one through XWayland). Run it on a desktop, under a \
                  virtual display (`xvfb-run cohort view ...`), or render to files with \
                  `cohort render`"
                .into(),
        ),
    }
}

pub fn run(a: ViewArgs) -> Result<(), String> {
    let r = &a.render;
    if r.shard.is_some() || r.devices.is_some() {
        return Err(
            "cohort view renders on one device: --shard and --devices are options of cohort render"
                .into(),
        );
    }
    let script = a.script.as_deref().map(Script::load).transpose()?;
    let config = r.config();
    let mut configs = vec![config.clone()];
    if let Some(c) = &a.compare {
        configs.push(
            config
                .with_overrides(c)
                .map_err(|e| format!("--compare: {e}"))?,
        );
    }
    // Without --paths or --time the viewer renders until it is closed.
    let budget = r
        .budget()
        .unwrap_or(Budget::KernelTime(Duration::from_secs(u32::MAX as u64)));
    let embedded = r.is_embedded_scene();
    let options: Vec<RenderOptions> = configs
        .iter()
        .map(|c| RenderOptions {
            budget,
            ..c.options(embedded)
        })
        .collect();
    for o in &options {
        r.check_before_scene(o)?;
    }
    let display = check_display()?;
    let scene = r.load_scene()?;
    let size = r.size(&scene);
    let (w, h) = size.unwrap_or((scene.camera.width, scene.camera.height));
    let base = RenderOptions {
        budget,
        size: Some((w, h)),
        ..Default::default()
    };
    let options = options
        .into_iter()
        .map(|o| {
            let o = RenderOptions {
                size: Some((w, h)),
                ..o
            };
            o.check(w, h).map_err(|e| e.to_string())?;
            Ok(o)
        })
        .collect::<Result<Vec<_>, String>>()?;
    for w in cohort_render::roulette::warnings(&scene, &options[0]) {
        eprintln!("warning: {w}");
    }
    let event_loop = EventLoop::<UserEvent>::with_user_event()
        .build()
        .map_err(|e| format!("cannot open a window on display `{display}`: {e}"))?;
    let proxy = event_loop.create_proxy();
    let shared = Arc::new(Shared::default());
    let (commands, receive) = mpsc::channel();
    let camera = scene.camera.with_size(w, h);
    let control = camera::CameraControl::new(camera, camera::scene_bounds(&scene));
    let setup = Setup {
        scene,
        scene_name: r.scene.clone(),
        backend: r.backend.map(crate::choices::Backend::kind),
        options: options.clone(),
        exposure: r.exposure,
        out: r.out.clone(),
        png: r.png_path()?,
    };
    let render_thread = {
        let (shared, proxy) = (shared.clone(), proxy.clone());
        std::thread::Builder::new()
            .name("render".into())
            .spawn(move || {
                let wake = || {
                    let _ = proxy.send_event(UserEvent::Frame);
                };
                if let Err(e) = worker::run(setup, receive, shared, wake) {
                    let _ = proxy.send_event(UserEvent::Failed(e));
                }
            })
            .map_err(|e| e.to_string())?
    };
    if let Some(script) = script {
        let (shared, proxy) = (shared.clone(), proxy.clone());
        std::thread::Builder::new()
            .name("script".into())
            .spawn(move || {
                if let Err(e) = run_script(&script, &proxy, &shared) {
                    let _ = proxy.send_event(UserEvent::Failed(e));
                }
            })
            .map_err(|e| e.to_string())?;
    }
    let mut app = window::App::new(window::AppSetup {
        title: format!("cohort view - {}", r.scene),
        embedded,
        base,
        configs,
        control,
        exposure: r.exposure,
        image_size: (w, h),
        commands,
        shared,
    });
    let ran = event_loop.run_app(&mut app);
    let error = app.error.take();
    // The render thread ends at `Quit`, or when the window's sender is dropped here.
    drop(app);
    let _ = render_thread.join();
    ran.map_err(|e| format!("the window's event loop failed: {e}"))?;
    error.map_or(Ok(()), Err)
}

/// Runs a script's steps against the window, as a person's input would.
fn run_script(
    script: &Script,
    proxy: &EventLoopProxy<UserEvent>,
    shared: &Shared,
) -> Result<(), String> {
    let mut generation = 0;
    for (line, step) in &script.steps {
        let at = |e: String| format!("{}:{line}: {e}", script.path.display());
        let action = match step {
            Step::Key(k) => {
                Some(input::key_action(k).ok_or_else(|| at(format!("unknown key `{k}`")))?)
            }
            Step::Drag(dx, dy) => Some(Action::Orbit(*dx, *dy)),
            Step::Pan(dx, dy) => Some(Action::Pan(*dx, *dy)),
            Step::Scroll(l) => Some(Action::Dolly(*l)),
            Step::Set(n, v) => Some(Action::Set(n.clone(), v.clone())),
            Step::Screenshot(p) => Some(Action::Screenshot(p.clone())),
            Step::Quit => Some(Action::Quit),
            Step::Sleep(d) => {
                std::thread::sleep(*d);
                None
            }
            Step::WaitFile(p) => {
                wait_for(|| p.exists())
                    .map_err(|_| at(format!("{} did not appear", p.display())))?;
                None
            }
            Step::WaitPaths(n) => {
                wait_for(|| {
                    shared.presented.lock().unwrap().as_ref().is_some_and(|p| {
                        p.generation >= generation
                            && (p.done || p.paths_per_pixel.iter().all(|&x| x >= *n))
                    })
                })
                .map_err(|_| at(format!("no frame with {n} paths per pixel on screen")))?;
                None
            }
            Step::Notify(text) => {
                // Waits for a window and a frame on it, so that what follows sees both.
                wait_for(|| shared.presented.lock().unwrap().is_some())
                    .map_err(|_| at("no frame was presented".into()))?;
                let p = shared.presented.lock().unwrap().clone().unwrap();
                let line = serde_json::json!({
                    "notify": text,
                    "window": shared.window_id.lock().unwrap().unwrap_or(0),
                    "generation": p.generation,
                    "paths_per_pixel": p.paths_per_pixel,
                    "paths_per_second": p.paths_per_second,
                    "done": p.done,
                });
                println!("{line}");
                None
            }
        };
        if let Some(action) = action {
            let (reply, answer) = mpsc::channel();
            let quit = action == Action::Quit;
            if proxy.send_event(UserEvent::Script(action, reply)).is_err() {
                return Ok(()); // The window closed.
            }
            match answer.recv() {
                Ok(Ok(g)) => generation = g,
                Ok(Err(e)) => return Err(at(e)),
                Err(_) => return Ok(()),
            }
            if quit {
                return Ok(());
            }
        }
    }
    Ok(())
}

/// Polls `ready` until it holds, or `script::WAIT_LIMIT` passes.
fn wait_for(mut ready: impl FnMut() -> bool) -> Result<(), ()> {
    let start = Instant::now();
    while !ready() {
        if start.elapsed() > script::WAIT_LIMIT {
            return Err(());
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    Ok(())
}
