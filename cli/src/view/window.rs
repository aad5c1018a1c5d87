//! The viewer's window (winit, presented with softbuffer): it turns input into actions,
//! sends camera and configuration changes to the render thread, and presents the latest
//! frame the render thread's `display` kernel produced, with the panel beside it.

use std::num::NonZeroU32;
use std::rc::Rc;
use std::sync::mpsc::Sender;
use std::sync::Arc;
use std::time::Instant;

use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use super::camera::CameraControl;
use super::input::{key_action, next_in_cycle, Action, HELP};
use super::panel::{self, Canvas, Line};
use super::worker::{Command, Presented, Published, Shared};
use super::UserEvent;
use crate::choices::AlgorithmChoice;
use crate::options::Config;
use cohort_render::RenderOptions;

/// The smallest window height, so that the panel fits beside small images.
const MIN_HEIGHT: u32 = 380;

pub struct App {
    title: String,
    embedded: bool,
    base: RenderOptions,
    configs: Vec<Config>,
    control: CameraControl,
    exposure: f32,
    image_size: (u32, u32),
    commands: Sender<Command>,
    shared: Arc<Shared>,
    /// Set when the viewer must exit with an error.
    pub error: Option<String>,
    window: Option<Rc<Window>>,
    surface: Option<softbuffer::Surface<Rc<Window>, Rc<Window>>>,
    frame: Option<Published>,
    focus: usize,
    show_panel: bool,
    status: String,
    left: bool,
    right: bool,
    cursor: Option<(f64, f64)>,
    /// Restarts asked of the render thread so far.
    generation: u64,
    last_present: Option<Instant>,
    frame_ms: f64,
    /// What the last present put on screen: width, height, 0x00RRGGBB pixels.
    on_screen: Option<(u32, u32, Vec<u32>)>,
}

/// What the window starts from.
pub struct AppSetup {
    pub title: String,
    /// An embedded scene (it decides the `auto` roulette).
    pub embedded: bool,
    /// Budget and size every side keeps when its configuration changes.
    pub base: RenderOptions,
    pub configs: Vec<Config>,
    pub control: CameraControl,
    pub exposure: f32,
    pub image_size: (u32, u32),
    pub commands: Sender<Command>,
    pub shared: Arc<Shared>,
}

impl App {
    pub fn new(s: AppSetup) -> App {
        App {
            title: s.title,
            embedded: s.embedded,
            base: s.base,
            configs: s.configs,
            control: s.control,
            exposure: s.exposure,
            image_size: s.image_size,
            commands: s.commands,
            shared: s.shared,
            error: None,
            window: None,
            surface: None,
            frame: None,
            focus: 0,
            show_panel: true,
            status: String::new(),
            left: false,
            right: false,
            cursor: None,
            generation: 0,
            last_present: None,
            frame_ms: 0.0,
            on_screen: None,
        }
    }

    fn window_size(&self) -> (u32, u32) {
        let (w, h) = self.image_size;
        (w + panel::WIDTH, h.max(MIN_HEIGHT))
    }

    fn send(&self, c: Command) {
        // The render thread is gone only after an error it reported itself.
        let _ = self.commands.send(c);
    }

    /// Applies an action; returns the restart count it leads to, or why it was refused.
    fn apply(&mut self, action: Action, event_loop: &ActiveEventLoop) -> Result<u64, String> {
        let camera_moved = match action {
            Action::Orbit(dx, dy) => {
                self.control.orbit(dx, dy);
                true
            }
            Action::Pan(dx, dy) => {
                self.control.pan(dx, dy);
                true
            }
            Action::Dolly(steps) => {
                self.control.dolly(steps);
                true
            }
            Action::Fly(r, u, f) => {
                self.control.fly(r, u, f);
                true
            }
            Action::ResetCamera => {
                self.control.reset();
                true
            }
            Action::Set(ref name, ref value) => {
                let mut c = self.configs[self.focus].clone();
                c.set(name, value)?;
                self.configure(c)?;
                false
            }
            Action::Algorithm(i) => {
                let mut c = self.configs[self.focus].clone();
                c.algorithm = *<AlgorithmChoice as clap::ValueEnum>::value_variants()
                    .get(i)
                    .ok_or("no such algorithm")?;
                self.configure(c)?;
                false
            }
            Action::ScaleN(f) => {
                let mut c = self.configs[self.focus].clone();
                c.n = ((c.n as f32 * f).round() as u32).clamp(1, 1000);
                self.configure(c)?;
                false
            }
            Action::Cycle(name) => {
                let c = &self.configs[self.focus];
                let current = c.get(name).unwrap_or_default();
                let next = next_in_cycle(name, &current).ok_or("no such option")?;
                let mut c = c.clone();
                c.set(name, &next)?;
                self.configure(c)?;
                false
            }
            Action::Exposure(d) => {
                self.exposure += d;
                self.send(Command::Exposure(self.exposure));
                false
            }
            Action::Save => {
                self.send(Command::Save);
                false
            }
            Action::Screenshot(ref path) => {
                let (w, h, pixels) = self.on_screen.as_ref().ok_or("nothing presented yet")?;
                write_png(path, *w, *h, pixels)?;
                false
            }
            Action::TogglePanel => {
                self.show_panel = !self.show_panel;
                self.redraw();
                false
            }
            Action::SwitchSide => {
                self.focus = (self.focus + 1) % self.configs.len();
                self.redraw();
                false
            }
            Action::Quit => {
                self.send(Command::Quit);
                event_loop.exit();
                false
            }
        };
        if camera_moved {
            self.send(Command::Camera(self.control.camera()));
            self.generation += 1;
        }
        Ok(self.generation)
    }

    /// A new configuration for the focused side, checked before the render thread sees it.
    fn configure(&mut self, c: Config) -> Result<(), String> {
        let opts = RenderOptions {
            budget: self.base.budget,
            size: self.base.size,
            ..c.options(self.embedded)
        };
        let (w, h) = self.image_size;
        opts.check(w, h).map_err(|e| e.to_string())?;
        self.send(Command::Configure(self.focus, opts));
        self.configs[self.focus] = c;
        self.generation += 1;
        self.status.clear();
        self.shared.status.lock().unwrap().clear();
        Ok(())
    }

    fn redraw(&self) {
        if let Some(w) = &self.window {
            w.request_redraw();
        }
    }

    fn panel_lines(&self, frame: &Published) -> Vec<Line> {
        let mut lines = vec![
            Line::accent(self.title.clone()),
            Line::plain(
                self.shared
                    .device
                    .lock()
                    .unwrap()
                    .clone()
                    .unwrap_or_default(),
            ),
            Line::plain(format!(
                "{}x{}  exposure {:+.1}  frame {:.0} ms",
                frame.width, frame.height, self.exposure, self.frame_ms
            )),
            Line::plain(""),
        ];
        let names = ["left", "right"];
        for (i, (c, s)) in self.configs.iter().zip(&frame.sides).enumerate() {
            let who = if self.configs.len() > 1 {
                format!("{} ", names[i])
            } else {
                String::new()
            };
            let marker = if i == self.focus && self.configs.len() > 1 {
                " <- keys"
            } else {
                ""
            };
            for (j, l) in panel::wrap(&format!("{who}{}{marker}", c.label()), 45)
                .into_iter()
                .enumerate()
            {
                lines.push(if j == 0 {
                    Line::accent(l)
                } else {
                    Line::plain(format!(" {l}"))
                });
            }
            let st = &s.stats;
            let k = st.kernel;
            let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
            lines.push(Line::plain(format!(
                " {:.2} paths/px{}  {:.1} s GPU",
                st.paths_per_pixel(),
                if s.done { " (done)" } else { "" },
                k.total().as_secs_f64()
            )));
            lines.push(Line::plain(format!(
                " {:.2} M paths/s  {:.2} M rays/s",
                st.paths_per_second() / 1e6,
                st.rays_per_second() / 1e6
            )));
            lines.push(Line::plain(format!(
                " ms: trav {:.0} ext {:.0} shad {:.0} comp {:.0}",
                ms(k.traverse),
                ms(k.extend),
                ms(k.shadow),
                ms(k.compact)
            )));
            if !k.reorder.is_zero() {
                lines.push(Line::plain(format!(" ms: sort {:.0}", ms(k.reorder))));
            }
            if !k.queue.is_zero() {
                lines.push(Line::plain(format!(" ms: queues {:.0}", ms(k.queue))));
            }
        }
        lines.push(Line::plain(format!(
            "display kernel {:.2} ms per frame",
            frame.display.as_secs_f64() * 1e3
        )));
        let status = match self.shared.status.lock().unwrap().as_str() {
            "" => self.status.clone(),
            s => s.to_string(),
        };
        if !status.is_empty() {
            lines.push(Line::plain(""));
            for l in panel::wrap(&status, 45) {
                lines.push(Line::accent(l));
            }
        }
        lines.push(Line::plain(""));
        lines.extend(HELP.iter().map(|h| Line::plain(*h)));
        lines
    }

    fn present(&mut self) -> Result<(), String> {
        if let Some(f) = self.shared.latest.lock().unwrap().take() {
            self.frame = Some(f);
        }
        let now = Instant::now();
        if let Some(last) = self.last_present {
            self.frame_ms = 0.8 * self.frame_ms + 0.2 * (now - last).as_secs_f64() * 1e3;
        }
        self.last_present = Some(now);
        let lines = match &self.frame {
            Some(f) if self.show_panel => self.panel_lines(f),
            _ => Vec::new(),
        };
        let (Some(window), Some(surface)) = (&self.window, self.surface.as_mut()) else {
            return Ok(());
        };
        let Some(frame) = &self.frame else {
            return Ok(());
        };
        let size = window.inner_size();
        let (ww, wh) = (size.width.max(1), size.height.max(1));
        surface
            .resize(NonZeroU32::new(ww).unwrap(), NonZeroU32::new(wh).unwrap())
            .map_err(|e| format!("cannot size the window's buffer: {e}"))?;
        let mut buffer = surface
            .buffer_mut()
            .map_err(|e| format!("cannot draw into the window: {e}"))?;
        buffer.fill(0x0010_1010);
        let (fw, fh) = (frame.width.min(ww), frame.height.min(wh));
        for y in 0..fh {
            let src = (y * frame.width) as usize;
            let dst = (y * ww) as usize;
            buffer[dst..dst + fw as usize].copy_from_slice(&frame.pixels[src..src + fw as usize]);
        }
        if self.show_panel && ww > frame.width {
            let mut canvas = Canvas {
                pixels: &mut buffer,
                width: ww,
                height: wh,
            };
            panel::draw(&mut canvas, frame.width, &lines);
        }
        let shown = buffer.to_vec();
        buffer
            .present()
            .map_err(|e| format!("cannot present the window: {e}"))?;
        // softbuffer's X11 present only queues the image for the X server; asking for the
        // next buffer waits until the server has drawn it. Only then is the frame
        // `presented` (what a script's `wait-paths` waits for, and what a screenshot after
        // `notify` captures): on a loaded machine, a screenshot taken at once could still
        // show the previous frame.
        surface
            .buffer_mut()
            .map_err(|e| format!("cannot draw into the window: {e}"))?;
        self.on_screen = Some((ww, wh, shown));
        *self.shared.presented.lock().unwrap() = Some(Presented {
            generation: frame.generation,
            paths_per_pixel: frame
                .sides
                .iter()
                .map(|s| s.stats.paths_per_pixel())
                .collect(),
            paths_per_second: frame
                .sides
                .iter()
                .map(|s| s.stats.paths_per_second())
                .collect(),
            done: frame.sides.iter().all(|s| s.done),
        });
        Ok(())
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: String) {
        self.error.get_or_insert(e);
        self.send(Command::Quit);
        event_loop.exit();
    }
}

/// An 8-bit RGB PNG of `0x00RRGGBB` pixels, written through a temporary file.
fn write_png(path: &std::path::Path, w: u32, h: u32, pixels: &[u32]) -> Result<(), String> {
    let rgb: Vec<u8> = pixels
        .iter()
        .flat_map(|p| [(p >> 16) as u8, (p >> 8) as u8, *p as u8])
        .collect();
    cohort_render::output::write_atomically(path, |tmp| {
        let file = std::fs::File::create(tmp).map_err(|e| e.to_string())?;
        let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
        writer.write_image_data(&rgb).map_err(|e| e.to_string())
    })
    .map_err(|e| e.to_string())
}

/// The name a script uses for a key (see `input::key_action`).
fn key_name(key: &Key) -> Option<String> {
    Some(match key {
        Key::Character(c) => c.to_string(),
        Key::Named(NamedKey::Escape) => "escape".into(),
        Key::Named(NamedKey::Tab) => "tab".into(),
        Key::Named(NamedKey::ArrowLeft) => "left".into(),
        Key::Named(NamedKey::ArrowRight) => "right".into(),
        Key::Named(NamedKey::ArrowUp) => "up".into(),
        Key::Named(NamedKey::ArrowDown) => "down".into(),
        _ => return None,
    })
}

impl ApplicationHandler<UserEvent> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let (w, h) = self.window_size();
        let attributes = Window::default_attributes()
            .with_title(self.title.clone())
            .with_inner_size(winit::dpi::PhysicalSize::new(w, h))
            .with_resizable(false);
        let created = event_loop
            .create_window(attributes)
            .map_err(|e| format!("cannot open a window: {e}"))
            .and_then(|window| {
                let window = Rc::new(window);
                let context = softbuffer::Context::new(window.clone())
                    .map_err(|e| format!("cannot present to this display: {e}"))?;
                let surface = softbuffer::Surface::new(&context, window.clone())
                    .map_err(|e| format!("cannot present to the window: {e}"))?;
                Ok((window, surface))
            });
        match created {
            Ok((window, surface)) => {
                *self.shared.window_id.lock().unwrap() = Some(super::x11_window_id(&window));
                self.window = Some(window);
                self.surface = Some(surface);
                self.redraw();
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let action = match event {
            WindowEvent::CloseRequested => Some(Action::Quit),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.present() {
                    self.fail(event_loop, e);
                }
                None
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                key_name(&event.logical_key).and_then(|k| key_action(&k))
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => self.left = down,
                    MouseButton::Right => self.right = down,
                    _ => {}
                }
                None
            }
            WindowEvent::CursorMoved { position, .. } => {
                let last = self.cursor.replace((position.x, position.y));
                match last {
                    Some((x, y)) if self.left || self.right => {
                        let (dx, dy) = ((position.x - x) as f32, (position.y - y) as f32);
                        Some(if self.left {
                            Action::Orbit(dx, dy)
                        } else {
                            Action::Pan(dx, dy)
                        })
                    }
                    _ => None,
                }
            }
            WindowEvent::MouseWheel { delta, .. } => Some(Action::Dolly(match delta {
                MouseScrollDelta::LineDelta(_, y) => y,
                MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
            })),
            _ => None,
        };
        if let Some(a) = action {
            if let Err(e) = self.apply(a, event_loop) {
                // A refused change is shown, not fatal: the render goes on as it was.
                self.status = e;
                self.redraw();
            }
        }
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, event: UserEvent) {
        match event {
            UserEvent::Frame => self.redraw(),
            UserEvent::Script(action, reply) => {
                let r = self.apply(action, event_loop);
                let _ = reply.send(r);
            }
            UserEvent::Failed(e) => self.fail(event_loop, e),
        }
    }
}
