//! `meshtrace render --preview`: a window (winit) that shows the render converging, fed
//! from the CPU through a plain framebuffer (softbuffer), so it works with either renderer
//! and with no GPU at all. The render runs on a worker thread and reports region by region
//! through [`Watch`]; the window redraws at most [`FPS`] times a second while it runs and
//! only on input afterwards, so an idle window costs no CPU. Closing the window (or Esc)
//! ends the render as Ctrl-C does: the samples so far are written.

mod frame;
mod picture;

use anyhow::{Context, Result, anyhow};
use frame::{Controls, MIN_WIDTH, PANEL};
use meshtrace::film::{self, Aov, Film};
use meshtrace::render::watch::{Region, Watch};
use meshtrace::render::{self, RenderScene};
use meshtrace::scene::RenderSettings;
use picture::{Picture, View};
use std::num::NonZeroU32;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, KeyEvent, StartCause, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use picture::VIEW_AOVS;

/// Camera rays a pixel behind the views the render does not gather (albedo, normal,
/// depth, BVH cost): as many as `info --heatmap` traces.
pub const VIEW_SAMPLES: u32 = meshtrace::figures::HEATMAP_SAMPLES;

/// Frames per second at most while the render runs.
pub const FPS: u32 = 30;

/// While the render runs, the window redraws at least this often (the clock moves).
const TICK: Duration = Duration::from_secs(1);

/// What the render thread tells the window.
pub enum Wake {
    /// Regions changed: a frame is due.
    Changed,
    /// The render has ended with this outcome; `close` when the window should go too (the
    /// render was stopped, or failed).
    Ended { outcome: String, close: bool },
}

/// The window's event loop, opened before the scene is loaded so that a machine without a
/// display fails at once.
pub struct Preview {
    event_loop: EventLoop<Wake>,
    /// Set while a [`Wake::Changed`] is on its way and no frame has been drawn since, so
    /// that the workers send one wake a frame, not one a region.
    pending: Arc<AtomicBool>,
}

/// What the window shows besides the image: for its title and panel, its BVH boxes, and
/// where `s` saves.
pub struct Setup<'a> {
    pub scene: &'a RenderScene,
    /// The render's size and seed (`spp` is the whole render's, not the job's).
    pub settings: RenderSettings,
    /// Samples per pixel the job traces.
    pub spp: u32,
    /// The AOVs the render gathers itself (`--aov`, the denoiser's guides): their views
    /// show the render's; the other views come from [`VIEW_SAMPLES`] first hits a pixel.
    pub gathered: u32,
    /// Scene and device, for the title and the panel.
    pub title: String,
    /// The render's output: `s` saves `<stem>.<view>.png` beside it.
    pub output: PathBuf,
    /// Set to stop the render after its current pass.
    pub cancel: Arc<AtomicBool>,
    /// The shortest time between two read-backs of a finished region's pixels: 0 on the
    /// CPU, where they are at hand; on a GPU each read-back copies them off the device.
    pub pixels_every: Duration,
}

impl Preview {
    /// Connects to the display (Wayland or X11).
    pub fn open() -> Result<Self> {
        let event_loop = EventLoop::<Wake>::with_user_event().build().map_err(|e| {
            anyhow!(
                "--preview: cannot open a window ({}); run without --preview, or under a display (xvfb-run on a headless machine)",
                without_source_location(&e.to_string())
            )
        })?;
        Ok(Self {
            event_loop,
            pending: Arc::new(AtomicBool::new(false)),
        })
    }

    /// The job's watcher, and the picture it keeps for the window.
    pub fn watch(&self, setup: &Setup) -> (Arc<dyn Watch>, Arc<Mutex<Picture>>) {
        let picture = Arc::new(Mutex::new(Picture::new(
            setup.settings.width,
            setup.settings.height,
            setup.spp,
        )));
        let watch = PreviewWatch {
            picture: picture.clone(),
            proxy: self.event_loop.create_proxy(),
            pending: self.pending.clone(),
            pixels_every: setup.pixels_every,
            last_pixels: Mutex::new(None),
        };
        (Arc::new(watch), picture)
    }

    /// Opens the window, then runs `render` on a worker thread while the window shows it;
    /// returns `render`'s result once the window is closed. `render` does not start if the
    /// window cannot be made.
    pub fn run(
        self,
        setup: Setup,
        picture: Arc<Mutex<Picture>>,
        render: impl FnOnce() -> Result<()> + Send,
    ) -> Result<()> {
        let (go, ready) = mpsc::channel::<bool>();
        let proxy = self.event_loop.create_proxy();
        let cancel = setup.cancel.clone();
        let output = setup.output.clone();
        let views = Aov::mask(&VIEW_AOVS) & !setup.gathered;
        let (scene, settings) = (setup.scene, setup.settings);
        let (view_picture, view_proxy) = (picture.clone(), self.event_loop.create_proxy());
        std::thread::scope(|s| {
            // The views the render does not gather: a few first hits a pixel, once, beside
            // the render (they share its worker threads), not AOVs of every sample.
            s.spawn(move || {
                let film = render::cpu::first_hits(scene, &settings, VIEW_SAMPLES, views);
                if let Ok(mut p) = view_picture.lock() {
                    p.set_views(&film);
                }
                let _ = view_proxy.send_event(Wake::Changed);
            });
            let worker = s.spawn(move || -> Result<()> {
                if ready.recv() != Ok(true) {
                    return Ok(());
                }
                let result = render();
                let stopped = cancel.load(Ordering::SeqCst);
                let outcome = match &result {
                    Ok(()) => format!(
                        "done: wrote {}; close the window (Esc) to exit",
                        output.display()
                    ),
                    Err(e) => e.to_string(),
                };
                let _ = proxy.send_event(Wake::Ended {
                    outcome,
                    close: stopped || result.is_err(),
                });
                result
            });
            let mut app = App::new(setup, picture, go, self.pending.clone());
            let ran = self.event_loop.run_app(&mut app);
            // However the loop ended, the render must not go on without its window.
            if !app.ended {
                app.setup.cancel.store(true, Ordering::SeqCst);
            }
            drop(app.go.take());
            let result = worker
                .join()
                .map_err(|_| anyhow!("the render thread panicked"))?;
            ran.context("--preview: the window's event loop failed")?;
            if let Some(e) = app.error.take() {
                return Err(e);
            }
            result
        })
    }
}

/// The job's [`Watch`]: updates the picture and wakes the window, once per frame at most.
struct PreviewWatch {
    picture: Arc<Mutex<Picture>>,
    proxy: EventLoopProxy<Wake>,
    /// Shared with the window: see [`Preview::pending`].
    pending: Arc<AtomicBool>,
    pixels_every: Duration,
    last_pixels: Mutex<Option<Instant>>,
}

impl PreviewWatch {
    fn wake(&self) {
        if !self.pending.swap(true, Ordering::AcqRel) {
            let _ = self.proxy.send_event(Wake::Changed);
        }
    }
}

impl Watch for PreviewWatch {
    fn started(&self, worker: usize, region: Region, samples: Range<u32>) {
        if let Ok(mut p) = self.picture.lock() {
            p.started(worker, region, samples);
        }
        self.wake();
    }

    fn finished(&self, worker: usize, region: Region, pixels: Option<&Film>) {
        if let Ok(mut p) = self.picture.lock() {
            p.finished(worker, region, pixels);
        }
        self.wake();
    }

    fn wants_pixels(&self) -> bool {
        if self.pixels_every.is_zero() {
            return true;
        }
        let Ok(mut last) = self.last_pixels.lock() else {
            return true;
        };
        let now = Instant::now();
        if last.is_some_and(|t| now - t < self.pixels_every) {
            return false;
        }
        *last = Some(now);
        true
    }
}

type Surface = softbuffer::Surface<Rc<Window>, Rc<Window>>;

/// The window and what it shows.
struct App<'a> {
    setup: Setup<'a>,
    picture: Arc<Mutex<Picture>>,
    controls: Controls,
    /// Tells the render thread to start (true) once the window exists, or not to.
    go: Option<mpsc::Sender<bool>>,
    pending: Arc<AtomicBool>,
    window: Option<(Rc<Window>, Surface)>,
    last_frame: Option<Instant>,
    /// A frame is wanted as soon as the frame rate allows.
    due: bool,
    /// The render has ended (or, the window failing, never started): closing no longer
    /// stops it, and the clock no longer ticks.
    ended: bool,
    error: Option<anyhow::Error>,
}

impl<'a> App<'a> {
    fn new(
        setup: Setup<'a>,
        picture: Arc<Mutex<Picture>>,
        go: mpsc::Sender<bool>,
        pending: Arc<AtomicBool>,
    ) -> Self {
        let controls = Controls {
            view: View::Beauty,
            exposure: 0.0,
            tiles: true,
            level: None,
            max_level: setup.scene.bvh.stats.depth,
            edges: Vec::new(),
            boxes: 0,
            title: setup.title.clone(),
            note: String::new(),
        };
        Self {
            setup,
            picture,
            controls,
            go: Some(go),
            pending,
            window: None,
            last_frame: None,
            due: true,
            ended: false,
            error: None,
        }
    }

    /// The window's first size: the image at a whole scale of up to 3 (at most 90% of the
    /// screen), or scaled down to fit, with the panel below.
    fn first_size(&self, event_loop: &ActiveEventLoop) -> PhysicalSize<u32> {
        let screen = event_loop
            .primary_monitor()
            .map(|m| m.size())
            .filter(|s| s.width > 0 && s.height > 0)
            .unwrap_or(PhysicalSize::new(1600, 1000));
        let room = (
            (screen.width as f64 * 0.9) as u32,
            ((screen.height as f64 * 0.9) as u32).saturating_sub(PANEL),
        );
        let (w, h) = (
            self.setup.settings.width as f64,
            self.setup.settings.height as f64,
        );
        let fit = (room.0 as f64 / w).min(room.1 as f64 / h);
        let scale = if fit >= 1.0 {
            fit.floor().min(3.0)
        } else {
            fit
        };
        PhysicalSize::new(
            ((w * scale) as u32).max(MIN_WIDTH),
            (h * scale) as u32 + PANEL,
        )
    }

    fn make_window(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let attributes = Window::default_attributes()
            .with_title(format!("meshtrace: {}", self.setup.title))
            .with_inner_size(self.first_size(event_loop))
            .with_min_inner_size(PhysicalSize::new(MIN_WIDTH, PANEL + 64));
        let window = Rc::new(
            event_loop
                .create_window(attributes)
                .context("--preview: cannot open a window")?,
        );
        let context = softbuffer::Context::new(window.clone())
            .map_err(|e| anyhow!("--preview: cannot draw into the window: {e}"))?;
        let surface = softbuffer::Surface::new(&context, window.clone())
            .map_err(|e| anyhow!("--preview: cannot draw into the window: {e}"))?;
        self.window = Some((window, surface));
        Ok(())
    }

    /// Draws and presents one frame.
    fn redraw(&mut self) -> Result<()> {
        let Some((window, surface)) = &mut self.window else {
            return Ok(());
        };
        let size = window.inner_size();
        let (Some(w), Some(h)) = (NonZeroU32::new(size.width), NonZeroU32::new(size.height)) else {
            return Ok(());
        };
        surface
            .resize(w, h)
            .map_err(|e| anyhow!("--preview: cannot resize the window's buffer: {e}"))?;
        let mut buffer = surface
            .buffer_mut()
            .map_err(|e| anyhow!("--preview: cannot draw into the window: {e}"))?;
        {
            let Ok(mut picture) = self.picture.lock() else {
                return Err(anyhow!("the render thread panicked"));
            };
            frame::draw(&picture, &self.controls, (w.get(), h.get()), &mut buffer);
            picture.dirty = false;
        }
        buffer
            .present()
            .map_err(|e| anyhow!("--preview: cannot show the frame: {e}"))?;
        self.last_frame = Some(Instant::now());
        self.due = false;
        Ok(())
    }

    fn request_frame(&mut self) {
        self.due = true;
        let ready = self
            .last_frame
            .is_none_or(|t| t.elapsed() >= Duration::from_secs(1) / FPS);
        if ready && let Some((window, _)) = &self.window {
            window.request_redraw();
        }
    }

    /// Closes the window; a render still running stops after its pass and is written.
    fn close(&mut self, event_loop: &ActiveEventLoop) {
        if !self.ended {
            self.setup.cancel.store(true, Ordering::SeqCst);
        }
        event_loop.exit();
    }

    fn set_level(&mut self, level: Option<u32>) {
        self.controls.level = level.map(|l| l.min(self.controls.max_level));
        self.controls.edges.clear();
        self.controls.boxes = 0;
        if let Some(l) = self.controls.level {
            let scene = self.setup.scene;
            let boxes = meshtrace::figures::level_boxes(&scene.bvh.nodes, l);
            self.controls.boxes = boxes.len();
            self.controls.edges = boxes
                .iter()
                .flat_map(|b| {
                    meshtrace::figures::box_edges(
                        &scene.camera,
                        b,
                        self.setup.settings.width,
                        self.setup.settings.height,
                    )
                })
                .collect();
        }
    }

    /// Saves the current view at the render's size as `<stem>.<view>.png` beside the output.
    fn save(&mut self) {
        let path = view_path(&self.setup.output, self.controls.view);
        let result = self
            .picture
            .lock()
            .map_err(|_| anyhow!("the render thread panicked"))
            .and_then(|p| {
                let (img, _) = p.image(self.controls.view, self.controls.exposure);
                let spp = p.samples_done as f64 / p.pixels().max(1) as f64;
                save_png(&path, p.width, p.height, &img)?;
                Ok(spp)
            });
        self.controls.note = match result {
            Ok(spp) => format!("saved {} ({spp:.1} spp)", path.display()),
            Err(e) => format!("not saved: {e}"),
        };
    }

    fn key(&mut self, event_loop: &ActiveEventLoop, key: &Key) {
        match key {
            Key::Named(NamedKey::Escape) => return self.close(event_loop),
            Key::Named(NamedKey::Tab) => self.controls.view = self.controls.view.next(),
            Key::Character(c) => match c.as_str() {
                "q" => return self.close(event_loop),
                "1" | "2" | "3" | "4" | "5" => {
                    let i = c.parse::<usize>().unwrap_or(1) - 1;
                    self.controls.view = View::ALL[i];
                }
                "t" => self.controls.tiles = !self.controls.tiles,
                "b" => {
                    let level = match self.controls.level {
                        Some(_) => None,
                        None => Some(1),
                    };
                    self.set_level(level);
                }
                "+" | "=" => {
                    let l = self.controls.level.map_or(1, |l| l + 1);
                    self.set_level(Some(l));
                }
                "-" => {
                    let l = self.controls.level.map_or(0, |l| l.saturating_sub(1));
                    self.set_level(Some(l));
                }
                "[" => self.controls.exposure -= 0.5,
                "]" => self.controls.exposure += 0.5,
                "s" => self.save(),
                _ => return,
            },
            _ => return,
        }
        self.request_frame();
    }
}

impl ApplicationHandler<Wake> for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        match self.make_window(event_loop) {
            Ok(()) => {
                if let Some(go) = self.go.take() {
                    let _ = go.send(true);
                }
            }
            Err(e) => {
                if let Some(go) = self.go.take() {
                    let _ = go.send(false);
                }
                self.error = Some(e);
                self.ended = true;
                event_loop.exit();
            }
        }
    }

    fn new_events(&mut self, _event_loop: &ActiveEventLoop, cause: StartCause) {
        if let StartCause::ResumeTimeReached { .. } = cause {
            self.request_frame();
        }
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, event: Wake) {
        match event {
            Wake::Changed => self.request_frame(),
            Wake::Ended { outcome, close } => {
                if let Ok(mut p) = self.picture.lock() {
                    p.active.clear();
                    p.ended = Some((outcome, Instant::now()));
                }
                self.ended = true;
                if close {
                    event_loop.exit();
                } else {
                    self.request_frame();
                }
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested | WindowEvent::Destroyed => self.close(event_loop),
            WindowEvent::Resized(_) => self.request_frame(),
            WindowEvent::RedrawRequested => {
                // Changes after this point wake the window again.
                self.pending.store(false, Ordering::Release);
                if let Err(e) = self.redraw() {
                    self.error = Some(e);
                    self.close(event_loop);
                }
            }
            WindowEvent::KeyboardInput {
                event:
                    KeyEvent {
                        logical_key,
                        state: ElementState::Pressed,
                        ..
                    },
                ..
            } => self.key(event_loop, &logical_key),
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        // A frame the rate held back is drawn when its time comes; a running render also
        // redraws every TICK for its clock. Otherwise the window sleeps until an event.
        let next_frame = self
            .last_frame
            .map(|t| t + Duration::from_secs(1) / FPS)
            .filter(|_| self.due);
        let tick = self.last_frame.map(|t| t + TICK).filter(|_| !self.ended);
        match next_frame.into_iter().chain(tick).min() {
            Some(at) => event_loop.set_control_flow(ControlFlow::WaitUntil(at)),
            None => event_loop.set_control_flow(ControlFlow::Wait),
        }
    }
}

/// winit's OS errors read `os error at /path/to/winit/src/….rs:765: what went wrong`; the
/// user needs only what went wrong.
fn without_source_location(message: &str) -> &str {
    match message.strip_prefix("os error at ") {
        Some(rest) => rest
            .find(".rs:")
            .and_then(|i| rest[i..].find(": ").map(|j| &rest[i + j + 2..]))
            .unwrap_or(message),
        None => message,
    }
}

/// Where `s` saves `view`: `<stem>.<view>.png` beside the render's output.
fn view_path(output: &Path, view: View) -> PathBuf {
    let stem = output
        .file_stem()
        .map_or("render".into(), |s| s.to_string_lossy());
    output.with_file_name(format!("{stem}.{}.png", view.name()))
}

/// Writes an 8-bit RGB image as a PNG, complete or not at all.
fn save_png(path: &Path, width: u32, height: u32, rgb: &[[u8; 3]]) -> Result<()> {
    let image = image::RgbImage::from_raw(width, height, rgb.concat())
        .ok_or_else(|| anyhow!("{}: image size mismatch", path.display()))?;
    let mut bytes = Vec::new();
    image
        .write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .with_context(|| path.display().to_string())?;
    film::write_bytes(path, &bytes)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn winit_errors_lose_their_source_location() {
        assert_eq!(
            without_source_location(
                "os error at /root/.cargo/registry/src/x/winit-0.30.13/src/platform_impl/linux/mod.rs:765: neither WAYLAND_DISPLAY nor WAYLAND_SOCKET nor DISPLAY is set."
            ),
            "neither WAYLAND_DISPLAY nor WAYLAND_SOCKET nor DISPLAY is set."
        );
        assert_eq!(without_source_location("no display"), "no display");
    }

    #[test]
    fn views_are_saved_beside_the_output() {
        assert_eq!(
            view_path(Path::new("out/cornell.exr"), View::Normal),
            PathBuf::from("out/cornell.normal.png")
        );
        assert_eq!(
            view_path(Path::new("render.png"), View::Beauty),
            PathBuf::from("render.beauty.png")
        );
    }
}
