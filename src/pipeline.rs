//! From an input and a [`RenderRequest`] to a [`Film`]: load the input (a scene file, a
//! bare mesh, `builtin:NAME`), light it with the requested environment, resolve the
//! settings, build the tables and render on the chosen backend, denoising the result when
//! asked. `meshtrace render`, `batch` and `bench` and the preview window all go through
//! here; [`render`] is the whole of it in one call.

use crate::bvh::{BuildParams, BvhError};
#[cfg(feature = "denoise")]
use crate::denoise::{DenoiseError, Denoiser};
use crate::film::{Aov, Film, FilmError, PartHeader};
use crate::math::Aabb;
use crate::render::backend::{self, Backend};
use crate::render::digest::render_digest;
use crate::render::gpu::GpuError;
use crate::render::{RenderJob, RenderScene};
use crate::request::{Part, RenderRequest, RequestError};
use crate::scene::camera::Camera;
use crate::scene::source::Fs;
use crate::scene::{RenderSettings, Scene, SceneError, builtin, load};
use std::path::Path;

/// Why an input could not be rendered as requested: one line naming the file, field or
/// device at fault.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    #[error(transparent)]
    Request(#[from] RequestError),
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Bvh(#[from] BvhError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Film(#[from] FilmError),
    #[cfg(feature = "denoise")]
    #[error(transparent)]
    Denoise(#[from] DenoiseError),
}

/// Loads `input` as `request` stages it: a path, or `builtin:NAME`; a bare mesh turned to
/// the requested up axis; the sky replaced by the requested environment; textures larger
/// than the requested maximum scaled down (each with a warning). The scene's warnings are
/// in [`Scene::warnings`].
pub fn load(input: &Path, request: &RenderRequest) -> Result<Scene, PipelineError> {
    let text = input.to_string_lossy();
    let scene = match text.strip_prefix("builtin:") {
        Some(_) if request.up.is_some() => {
            return Err(RequestError {
                field: "up",
                message: "applies to a bare mesh (.obj, .gltf, .glb), not to a built-in scene"
                    .into(),
            }
            .into());
        }
        Some(name) => builtin::load_builtin(name)?,
        None => load::load_scene_with(input, &Fs, &request.bare_options())?,
    };
    stage(scene, request)
}

/// Stages a loaded `scene` as `request` asks, as [`load`] does: the sky replaced by the
/// requested environment, or the sky and lights by the requested lighting preset, textures
/// larger than the requested maximum scaled down (each with a warning in
/// [`Scene::warnings`]). For scenes that come from elsewhere than a file (the Python API's
/// dictionaries).
pub fn stage(mut scene: Scene, request: &RenderRequest) -> Result<Scene, PipelineError> {
    if let Some(env) = &request.environment {
        load::replace_environment(&mut scene, env).map_err(|message| RequestError {
            field: "environment",
            message,
        })?;
    }
    if let Some(lighting) = &request.lighting {
        lighting.apply(&mut scene, &Fs)?;
    }
    if let Some(max) = request.max_texture_size {
        for t in scene.textures.limit_size(max) {
            let ((w, h), (w2, h2)) = (t.from, t.to);
            scene.warnings.push(format!(
                "{}: {w}×{h} texels exceed max_texture_size = {max}; scaled down to {w2}×{h2}",
                t.name
            ));
        }
    }
    Ok(scene)
}

/// An input made ready to render as a request asks: its tables built and its job set up.
pub struct Prepared {
    pub scene: RenderScene,
    /// What the render traces: the settings, the sample range (a part's, or all), the AOVs
    /// the output holds plus the denoiser's guides, transparency. A caller may add a
    /// cancel flag, a checkpoint and a watcher.
    pub job: RenderJob,
    /// The requested part, if any.
    pub part: Option<Part>,
    /// What a bare mesh's camera frames ([`Scene::framed`]), for other views framed alike.
    pub framed: Option<Aabb>,
    finish: Finish,
}

/// What a finished film gets before it is written.
struct Finish {
    /// The AOVs the output holds ([`Aov::mask`]).
    saved_aovs: u32,
    /// Behind a lock: an Open Image Denoise device may move between threads but not be
    /// shared, and a prepared render is shared with the preview window's thread.
    #[cfg(feature = "denoise")]
    denoiser: Option<std::sync::Mutex<Denoiser>>,
}

impl Finish {
    /// The AOVs to save, and the denoiser where asked for and `film` holds all the samples
    /// `job` traces.
    fn apply(&self, job: &RenderJob, film: &mut Film) -> Result<(), PipelineError> {
        film.saved_aovs = self.saved_aovs;
        #[cfg(feature = "denoise")]
        if let Some(d) = &self.denoiser
            && film.samples == job.samples.end - job.samples.start
        {
            d.lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .denoise_film(film)?;
        }
        #[cfg(not(feature = "denoise"))]
        let _ = job;
        Ok(())
    }
}

/// What a render of `settings` traces, as `request` asks: the sample range (a part's, or
/// all), the AOVs it saves plus the denoiser's guides, transparency, geometry only; and
/// what its film gets before it is written (the denoiser, made now).
fn job(
    settings: RenderSettings,
    request: &RenderRequest,
) -> Result<(RenderJob, Finish), PipelineError> {
    #[cfg(feature = "denoise")]
    let denoiser = if request.denoise() {
        Some(std::sync::Mutex::new(Denoiser::with_threads(
            rayon::current_num_threads(),
        )?))
    } else {
        None
    };
    let saved_aovs = request.aov_mask();
    // The denoiser is guided by the first surface's albedo and normal, which the film
    // then holds whether or not they are written.
    let guides = if request.denoise() {
        Aov::Albedo.bit() | Aov::Normal.bit()
    } else {
        0
    };
    let samples = match request.part {
        Some(p) => PartHeader::range(p.index, p.count, settings.spp),
        None => 0..settings.spp,
    };
    let job = RenderJob::new(settings)
        .with_aovs(saved_aovs | guides, request.transparent())
        .with_geometry(request.geometry_only())
        .with_samples(samples);
    let finish = Finish {
        saved_aovs,
        #[cfg(feature = "denoise")]
        denoiser,
    };
    Ok((job, finish))
}

impl Prepared {
    /// Loads `input` ([`load`]) and prepares it; the scene's warnings go to `warn`.
    pub fn new(
        input: &Path,
        request: &RenderRequest,
        warn: &dyn Fn(&str),
    ) -> Result<Self, PipelineError> {
        request.validate()?;
        let scene = load(input, request)?;
        for w in &scene.warnings {
            warn(w);
        }
        Self::build(scene, request)
    }

    /// Prepares `scene`, loaded by [`load`] and changed by the caller (a batch preset lights
    /// it), for `request`.
    pub fn from_scene(scene: Scene, request: &RenderRequest) -> Result<Self, PipelineError> {
        request.validate()?;
        Self::build(scene, request)
    }

    /// Prepares a loaded scene for a validated request: resolves the settings over the
    /// scene's own and builds its tables.
    fn build(mut scene: Scene, request: &RenderRequest) -> Result<Self, PipelineError> {
        let settings: RenderSettings = request.settings(scene.settings)?;
        // The tables follow the settings too: `caustics` decides the caustic targets.
        scene.settings = settings;
        // The job first: a missing Open Image Denoise fails before the tables are built.
        let (job, finish) = job(settings, request)?;
        Ok(Self {
            scene: RenderScene::new(&scene, &BuildParams::default())?,
            job,
            part: request.part,
            framed: scene.framed,
            finish,
        })
    }

    /// The AOVs the output holds ([`Aov::mask`]).
    pub fn saved_aovs(&self) -> u32 {
        self.finish.saved_aovs
    }

    /// The header of the part file this render writes, when it renders a part: it ties the
    /// part to its scene, settings and device.
    pub fn part_header(&self, backend: &Backend) -> Option<PartHeader> {
        let s = self.job.settings;
        self.part.map(|p| PartHeader {
            index: p.index,
            count: p.count,
            start: self.job.samples.start,
            end: self.job.samples.end,
            spp: s.spp,
            seed: s.seed,
            device: backend.device_id(),
            digest: render_digest(&self.scene, &self.job),
        })
    }

    /// Renders the job on `backend` ([`Backend::render`]); `progress` is told the samples
    /// finished as they finish. A film cut short by the job's cancel flag has fewer
    /// samples than asked for, and is not denoised.
    pub fn render(
        &self,
        backend: &Backend,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Film, PipelineError> {
        let mut film = backend.render(&self.scene, &self.job, progress)?;
        self.finish.apply(&self.job, &mut film)?;
        Ok(film)
    }

    /// The scene made ready on `backend` once (on a GPU, its tables uploaded) for several
    /// views that differ in camera: a batch's.
    pub fn views(self, backend: &Backend) -> Result<Views, PipelineError> {
        Ok(Views {
            on_device: backend.prepare(self.scene)?,
            job: self.job,
            finish: self.finish,
        })
    }
}

/// A scene prepared once on a device, rendered from camera after camera.
pub struct Views {
    on_device: backend::Prepared,
    job: RenderJob,
    finish: Finish,
}

impl Views {
    /// The job every view renders (a caller may set its cancel flag).
    pub fn job_mut(&mut self) -> &mut RenderJob {
        &mut self.job
    }

    /// Renders from now on as `request` asks, its settings laid over `own` (the scene's
    /// own `[render]`): for a caller that keeps a scene's tables on the device for renders
    /// that differ in settings as well as in camera (the Python API). The tables stay: a
    /// request that needs others, caustic targets where there were none or none where
    /// there were ([`RenderScene::caustic_tables`]), must be prepared anew.
    pub fn set_request(
        &mut self,
        own: RenderSettings,
        request: &RenderRequest,
    ) -> Result<(), PipelineError> {
        request.validate()?;
        let (job, finish) = job(request.settings(own)?, request)?;
        self.job = job;
        self.finish = finish;
        Ok(())
    }

    /// Renders the view from `camera`.
    pub fn render(
        &mut self,
        camera: &Camera,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Film, PipelineError> {
        self.on_device.set_camera(camera);
        let mut film = self.on_device.render(&self.job, progress)?;
        self.finish.apply(&self.job, &mut film)?;
        Ok(film)
    }
}

/// Renders `input` as `request` asks, on the backend it asks for: the whole pipeline in
/// one call, for library callers. Warnings are dropped; [`Prepared::new`] passes them on.
pub fn render(input: &Path, request: &RenderRequest) -> Result<Film, PipelineError> {
    let prepared = Prepared::new(input, request, &|_| {})?;
    let (backend, _) = request.backend()?;
    prepared.render(&backend, &|_| {})
}
