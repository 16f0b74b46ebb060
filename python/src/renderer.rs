//! `meshtrace.Renderer`: one device (a GPU with its compiled kernels, or the CPU with its
//! threads) kept across renders and scenes. A render releases the GIL and runs on a worker
//! thread while the calling thread watches for Ctrl-C, which stops it at the next pass.

use crate::camera::Camera;
use crate::errors;
use crate::output::Output;
use crate::scene::{self, Kept, Scene};
use meshtrace::film::{Aov, Film};
use meshtrace::pipeline::{PipelineError, Prepared};
use meshtrace::render::RenderScene;
use meshtrace::render::backend::Backend;
use meshtrace::request::RenderRequest;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{RecvTimeoutError, channel};
use std::time::Duration;

/// The number of the next renderer opened.
static NEXT_ID: AtomicU64 = AtomicU64::new(0);

/// How often a running render's caller looks for Ctrl-C.
const SIGNAL_CHECK: Duration = Duration::from_millis(50);

/// A device to render on, opened once: `device` is `auto` (a hardware GPU, else the CPU),
/// `cpu` or `gpu` (any Vulkan adapter, lavapipe included); `adapter` an index or a name
/// substring from `meshtrace adapters`; `accel` `auto`, `software` or `hardware` (ray
/// queries); `threads` the CPU renderer's worker threads (all cores by default).
#[pyclass(module = "meshtrace", frozen)]
pub struct Renderer {
    /// This renderer's number in the process, which a scene's kept tables name.
    pub id: u64,
    backend: Backend,
    /// Why the CPU renders when `auto` found no usable GPU.
    notice: Option<String>,
    pool: Option<rayon::ThreadPool>,
}

/// The value `text` names in `names`, or an error naming the keyword argument `field`.
fn named<T: Copy>(field: &str, text: &str, names: &[(&str, T)]) -> PyResult<T> {
    meshtrace::request::parse_name(text, names)
        .map_err(|m| errors::message(format!("{field}: {m}")))
}

impl Renderer {
    /// Renders `scene` as staged from `camera`, on the tables it keeps for this renderer
    /// where they suit the request, else on tables built now (and then kept).
    fn render_kept(
        &self,
        scene: &Scene,
        camera: &meshtrace::scene::camera::Camera,
        request: &RenderRequest,
        cancel: &Arc<AtomicBool>,
    ) -> Result<Film, PipelineError> {
        let own = scene.scene.settings;
        let caustic_tables = RenderScene::caustic_tables(&request.settings(own)?, camera);
        let mut views = match scene.take_prepared(self.id, caustic_tables) {
            Some(views) => views,
            None => {
                let mut staged = scene.scene.clone();
                staged.camera = camera.clone();
                Prepared::from_scene(staged, request)?.views(&self.backend)?
            }
        };
        views.set_request(own, request)?;
        views.job_mut().cancel = Some(cancel.clone());
        let film = self.install(|| views.render(camera, &|_| {}))?;
        scene.keep_prepared(Kept {
            renderer: self.id,
            caustic_tables,
            views,
        });
        Ok(film)
    }

    /// Runs `work` on the renderer's threads.
    fn install<T: Send>(&self, work: impl FnOnce() -> T + Send) -> T {
        match &self.pool {
            Some(pool) => pool.install(work),
            None => work(),
        }
    }
}

/// Runs `work` on a worker thread without the GIL while this thread checks for signals;
/// on Ctrl-C, sets `cancel` (the render stops at its next pass), waits for `work` and
/// raises `KeyboardInterrupt`.
fn interruptible<T: Send>(
    py: Python<'_>,
    cancel: &AtomicBool,
    work: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    py.detach(|| {
        std::thread::scope(|s| {
            let (done, finished) = channel();
            s.spawn(move || {
                // The receiver waits until this is sent: a send cannot fail.
                let _ = done.send(work());
            });
            let mut interrupted = None;
            loop {
                match finished.recv_timeout(SIGNAL_CHECK) {
                    Ok(value) => return interrupted.map_or(Ok(value), Err),
                    Err(RecvTimeoutError::Timeout) if interrupted.is_none() => {
                        if let Err(e) = Python::attach(|py| py.check_signals()) {
                            cancel.store(true, Ordering::SeqCst);
                            interrupted = Some(e);
                        }
                    }
                    Err(RecvTimeoutError::Timeout) => {}
                    Err(RecvTimeoutError::Disconnected) => {
                        return Err(pyo3::exceptions::PyRuntimeError::new_err(
                            "the render thread stopped without a result",
                        ));
                    }
                }
            }
        })
    })
}

#[pymethods]
impl Renderer {
    #[new]
    #[pyo3(signature = (device="auto", *, adapter=None, accel=None, threads=None))]
    fn new(
        py: Python<'_>,
        device: &str,
        adapter: Option<String>,
        accel: Option<&str>,
        threads: Option<usize>,
    ) -> PyResult<Self> {
        let choice = named("device", device, &meshtrace::request::DEVICES)?;
        let accel = accel
            .map(|a| named("accel", a, &meshtrace::request::ACCELS))
            .transpose()?;
        let request = RenderRequest {
            device: Some(choice),
            adapter,
            accel,
            ..Default::default()
        };
        request.validate().map_err(|e| errors::error(&e))?;
        let pool = match threads {
            None => None,
            Some(0) => return Err(errors::message("threads: must be at least 1")),
            Some(n) => Some(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .map_err(|e| errors::message(format!("threads: cannot start them: {e}")))?,
            ),
        };
        let (backend, notice) = py
            .detach(|| request.backend())
            .map_err(|e| errors::error(&e))?;
        Ok(Self {
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            backend,
            notice,
            pool,
        })
    }

    /// `cpu` or `gpu`: the renderer chosen.
    #[getter]
    fn device(&self) -> &'static str {
        match self.backend {
            Backend::Cpu => "cpu",
            Backend::Gpu(_) => "gpu",
        }
    }

    /// The device's name: the adapter's with how it finds hits, or "the CPU".
    #[getter]
    fn name(&self) -> String {
        self.backend.name()
    }

    /// Why the CPU renders where `device="auto"` found no usable GPU; else None.
    #[getter]
    fn notice(&self) -> Option<String> {
        self.notice.clone()
    }

    /// Renders `scene` (a Scene, or a path to load) from its own camera or `camera`, with
    /// the command line's settings under the same names; those left None keep the scene's
    /// own (a scene file's `[render]`) or the defaults. `aovs` lists the images to add
    /// beside `color`: depth, normal, albedo, alpha, object_id, material_id, bvh_cost,
    /// diffuse_color.
    /// Returns an Output, a mapping of NumPy arrays. Ctrl-C stops the render at its next
    /// pass and raises KeyboardInterrupt.
    #[pyo3(signature = (
        scene, *, camera=None, width=None, height=None, spp=None, max_depth=None, seed=None,
        caustics=None, branches=None, filter_width=None, diffuse_bounces=None,
        glossy_bounces=None, transmission_bounces=None, aovs=None, transparent=None,
        geometry_only=None, denoise=None, up=None, environment=None, lighting=None,
        max_texture_size=None
    ))]
    #[allow(clippy::too_many_arguments)]
    fn render(
        &self,
        py: Python<'_>,
        scene: &Bound<'_, PyAny>,
        camera: Option<&Camera>,
        width: Option<u32>,
        height: Option<u32>,
        spp: Option<u32>,
        max_depth: Option<u32>,
        seed: Option<u32>,
        caustics: Option<bool>,
        branches: Option<u32>,
        filter_width: Option<f32>,
        diffuse_bounces: Option<u32>,
        glossy_bounces: Option<u32>,
        transmission_bounces: Option<u32>,
        aovs: Option<Vec<String>>,
        transparent: Option<bool>,
        geometry_only: Option<bool>,
        denoise: Option<bool>,
        up: Option<&str>,
        environment: Option<PathBuf>,
        lighting: Option<&Bound<'_, PyAny>>,
        max_texture_size: Option<u32>,
    ) -> PyResult<Output> {
        // An empty list asks for none (the command line's list has at least one name).
        let aov = match aovs {
            Some(names) if names.is_empty() => Some(Vec::new()),
            names => names
                .map(|names| Aov::parse_list(&names.join(",")))
                .transpose()
                .map_err(|e| errors::message(format!("aovs: {e}")))?,
        };
        let request = RenderRequest {
            width,
            height,
            spp,
            max_depth,
            seed,
            caustics,
            branches,
            filter_width,
            diffuse_bounces,
            glossy_bounces,
            transmission_bounces,
            aov,
            transparent,
            geometry_only,
            denoise,
            up: scene::up_axis(up)?,
            environment,
            lighting: lighting.map(scene::lighting_arg).transpose()?,
            max_texture_size,
            ..Default::default()
        };
        request.validate().map_err(|e| errors::error(&e))?;
        let scene = scene::scene_arg(py, scene)?;
        let scene = scene.get();
        let cancel = Arc::new(AtomicBool::new(false));
        let film = if scene.staged_for(&request) {
            let camera = camera.map_or_else(|| scene.scene.camera.clone(), |c| c.inner.clone());
            interruptible(py, &cancel, || {
                self.render_kept(scene, &camera, &request, &cancel)
            })?
        } else {
            let mut staged = scene.restaged(py, &request)?;
            if let Some(c) = camera {
                staged.camera = c.inner.clone();
            }
            interruptible(py, &cancel, || {
                let mut prepared = Prepared::from_scene(staged, &request)?;
                prepared.job.cancel = Some(cancel.clone());
                self.install(|| prepared.render(&self.backend, &|_| {}))
            })?
        }
        .map_err(|e| errors::error(&e))?;
        Output::new(py, film)
    }

    fn __repr__(&self) -> String {
        format!("<meshtrace.Renderer on {}>", self.backend.name())
    }
}
