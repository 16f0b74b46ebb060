//! `meshtrace.Scene` and `meshtrace.load`: an input loaded once (a scene file, a bare mesh,
//! `builtin:NAME`, or a dictionary in the scene file's layout) and staged as its loading
//! options ask, for any number of renders.

use crate::camera::Camera;
use crate::{dict, errors};
use meshtrace::pipeline::{self, PipelineError, Views};
use meshtrace::request::{RenderRequest, RequestError};
use meshtrace::scene::SceneError;
use meshtrace::scene::lighting::Lighting;
use meshtrace::scene::studio::Up;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::sync::{Mutex, PoisonError};

/// Where a scene came from, to load it anew with other loading options.
#[derive(Clone)]
enum Source {
    /// A path, or `builtin:NAME`.
    File(PathBuf),
    /// A dictionary's TOML text; its relative paths are relative to `base`.
    Dict { text: String, base: PathBuf },
}

/// A loaded scene: what the renderer renders, from its own camera or another.
#[pyclass(module = "meshtrace", frozen)]
pub struct Scene {
    source: Source,
    /// The loading options it was staged with: `up`, `environment`, `max_texture_size`,
    /// the studio or not.
    options: RenderRequest,
    pub(crate) scene: meshtrace::scene::Scene,
    /// Its tables as the last render built them (its BVH, on a GPU uploaded), for the
    /// next render on the same renderer that needs the same tables: views of one scene
    /// build them once.
    prepared: Mutex<Option<Kept>>,
}

/// A scene's tables kept on a renderer's device.
pub struct Kept {
    /// The renderer's [`crate::renderer::Renderer::id`].
    pub renderer: u64,
    /// Whether they hold caustic targets
    /// ([`meshtrace::render::RenderScene::caustic_tables`]).
    pub caustic_tables: bool,
    pub views: Views,
}

/// The loading part of a request: the fields that decide how an input is staged.
fn loading(request: &RenderRequest) -> RenderRequest {
    RenderRequest {
        up: request.up,
        environment: request.environment.clone(),
        lighting: request.lighting.clone(),
        max_texture_size: request.max_texture_size,
        without_studio: request.without_studio,
        ..Default::default()
    }
}

/// A bare mesh's up axis by its name.
pub fn up_axis(up: Option<&str>) -> PyResult<Option<Up>> {
    match up {
        None => Ok(None),
        Some("x") => Ok(Some(Up::X)),
        Some("y") => Ok(Some(Up::Y)),
        Some("z") => Ok(Some(Up::Z)),
        Some(other) => Err(errors::message(format!(
            "up: `{other}` is not one of x, y, z"
        ))),
    }
}

impl Scene {
    /// Loads `source` staged by `options` (the loading fields of a request).
    fn open(source: Source, options: RenderRequest) -> Result<Self, PipelineError> {
        let scene = match &source {
            Source::File(path) => pipeline::load(path, &options)?,
            Source::Dict { text, base } => {
                if options.up.is_some() {
                    return Err(RequestError {
                        field: "up",
                        message: "applies to a bare mesh (.obj, .gltf, .glb), not to a scene dict"
                            .into(),
                    }
                    .into());
                }
                let scene = meshtrace::scene::load::parse_scene(text, &base.join(DICT_NAME))
                    .map_err(|e| dict_error(e, text))?;
                pipeline::stage(scene, &options)?
            }
        };
        Ok(Self {
            source,
            options,
            scene,
            prepared: Mutex::new(None),
        })
    }

    /// Whether a render of `request` renders this scene as staged (its loading fields
    /// unset or the scene's own); otherwise [`Scene::restaged`] loads it for the render.
    pub fn staged_for(&self, request: &RenderRequest) -> bool {
        loading(request).over(&self.options) == self.options
    }

    /// This scene loaded anew as `request` stages it, the loading fields it leaves unset
    /// kept (warnings to Python).
    pub fn restaged(
        &self,
        py: Python<'_>,
        request: &RenderRequest,
    ) -> PyResult<meshtrace::scene::Scene> {
        let wanted = loading(request).over(&self.options);
        let fresh = Self::open(self.source.clone(), wanted).map_err(|e| errors::error(&e))?;
        errors::warn_all(py, &fresh.scene.warnings)?;
        Ok(fresh.scene)
    }

    /// The kept tables, taken for a render (a render beside it prepares its own); `None`
    /// when there are none, or they are another renderer's or other caustic tables.
    pub fn take_prepared(&self, renderer: u64, caustic_tables: bool) -> Option<Views> {
        let mut kept = self.prepared.lock().unwrap_or_else(PoisonError::into_inner);
        match kept.take() {
            Some(k) if k.renderer == renderer && k.caustic_tables == caustic_tables => {
                Some(k.views)
            }
            other => {
                *kept = other;
                None
            }
        }
    }

    /// Keeps `kept` for the next render.
    pub fn keep_prepared(&self, kept: Kept) {
        *self.prepared.lock().unwrap_or_else(PoisonError::into_inner) = Some(kept);
    }
}

/// The name a dictionary's scene has in messages (with the base folder before it).
const DICT_NAME: &str = "<dict>";

/// A dictionary scene's syntax error (a line of its TOML text) at the dictionary's key path.
fn dict_error(e: SceneError, text: &str) -> PipelineError {
    match e {
        SceneError::Syntax { line, message, .. } => SceneError::Invalid {
            path: "scene dict".into(),
            field: dict::key_at(text, line),
            message,
        }
        .into(),
        e => e.into(),
    }
}

#[pymethods]
impl Scene {
    /// A scene from a dictionary in the scene file's layout (docs/scene-format.md), as
    /// `tomllib.load` would read the file. Relative paths in it are relative to `base`
    /// (the working folder by default).
    #[staticmethod]
    #[pyo3(signature = (d, *, base=None, environment=None, max_texture_size=None))]
    fn from_dict(
        py: Python<'_>,
        d: &Bound<'_, PyDict>,
        base: Option<PathBuf>,
        environment: Option<PathBuf>,
        max_texture_size: Option<u32>,
    ) -> PyResult<Self> {
        let text = dict::to_toml(d)?;
        let options = RenderRequest {
            environment,
            max_texture_size,
            ..Default::default()
        };
        let source = Source::Dict {
            text,
            base: base.unwrap_or_default(),
        };
        open(py, source, options)
    }

    /// The file it was loaded from (`builtin:NAME` for a built-in scene); None for a
    /// dictionary.
    #[getter]
    fn path(&self) -> Option<String> {
        match &self.source {
            Source::File(p) => Some(p.display().to_string()),
            Source::Dict { .. } => None,
        }
    }

    /// The scene's own camera: a scene file's `[camera]`, or a bare mesh's studio framing.
    #[getter]
    fn camera(&self) -> Camera {
        Camera::from(self.scene.camera.clone())
    }

    /// The number of triangles.
    #[getter]
    fn triangles(&self) -> usize {
        self.scene.mesh.triangles.len()
    }

    /// For a bare mesh, the corners (min, max) of the box around the mesh alone (the box
    /// its studio camera, orbits and the dataset presets frame); None for a scene file.
    #[getter]
    fn framed(&self) -> Option<([f32; 3], [f32; 3])> {
        self.scene
            .framed
            .as_ref()
            .map(|b| (b.min.to_array(), b.max.to_array()))
    }

    /// The corners (min, max) of the box around every triangle (a bare mesh's studio
    /// ground included).
    #[getter]
    fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let mut min = glam::Vec3::INFINITY;
        let mut max = glam::Vec3::NEG_INFINITY;
        for t in &self.scene.mesh.triangles {
            for v in self.scene.mesh.vertices(t) {
                min = min.min(v);
                max = max.max(v);
            }
        }
        (min.to_array(), max.to_array())
    }

    /// The problems loading met that did not stop it (each also given to `warnings.warn`).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.scene.warnings.clone()
    }

    fn __repr__(&self) -> String {
        let from = match &self.source {
            Source::File(p) => format!("{:?}", p.display().to_string()),
            Source::Dict { .. } => "a dict".into(),
        };
        format!(
            "<meshtrace.Scene from {from}: {} triangles>",
            self.triangles()
        )
    }
}

fn open(py: Python<'_>, source: Source, options: RenderRequest) -> PyResult<Scene> {
    let scene = py
        .detach(|| Scene::open(source, options))
        .map_err(|e| errors::error(&e))?;
    errors::warn_all(py, &scene.scene.warnings)?;
    Ok(scene)
}

/// Loads a scene file (.toml), a bare mesh (.obj, .gltf, .glb) staged in the studio, or a
/// built-in scene (`builtin:cornell`). `up` turns a bare mesh (`x`, `y` or `z`; detected
/// when None), `environment` lights it with an equirectangular image instead of its sky,
/// `max_texture_size` scales larger textures down: the command line's `--up`, `--env` and
/// `--max-texture-size`. `lighting` lights it with a lighting preset instead of its own
/// sky and lights: a name (`"area"`) or a dict (`{"preset": "suns", "count": 6}`), as
/// `--lighting`. `studio=False` leaves a bare mesh's studio out (its ground and its light:
/// a black sky), for a caller that lights it with `environment`, as the dataset presets
/// leave it out.
#[pyfunction]
#[pyo3(signature = (
    path, *, up=None, environment=None, lighting=None, max_texture_size=None, studio=true
))]
pub fn load(
    py: Python<'_>,
    path: PathBuf,
    up: Option<&str>,
    environment: Option<PathBuf>,
    lighting: Option<&Bound<'_, PyAny>>,
    max_texture_size: Option<u32>,
    studio: bool,
) -> PyResult<Scene> {
    let options = RenderRequest {
        up: up_axis(up)?,
        environment,
        lighting: lighting.map(lighting_arg).transpose()?,
        max_texture_size,
        without_studio: !studio,
        ..Default::default()
    };
    options.validate().map_err(|e| errors::error(&e))?;
    open(py, Source::File(path), options)
}

/// A `lighting` argument: a preset's name, or a dict of a preset and its parameters (the
/// scene file's `[lighting]` table).
pub fn lighting_arg(v: &Bound<'_, PyAny>) -> PyResult<Lighting> {
    let table = match v.extract::<String>() {
        Ok(name) => toml::Value::Table(toml::Table::from_iter([(
            "preset".to_string(),
            toml::Value::String(name),
        )])),
        Err(_) => dict::value(v, "lighting")?,
    };
    table
        .try_into()
        .map_err(|e: toml::de::Error| errors::message(e.message().to_string()))
}

/// A scene argument: a [`Scene`], or a path to load.
pub fn scene_arg(py: Python<'_>, scene: &Bound<'_, PyAny>) -> PyResult<Py<Scene>> {
    if let Ok(s) = scene.cast::<Scene>() {
        return Ok(s.clone().unbind());
    }
    let path: PathBuf = scene.extract().map_err(|_| {
        pyo3::exceptions::PyTypeError::new_err("scene must be a meshtrace.Scene or a path")
    })?;
    Py::new(py, open(py, Source::File(path), RenderRequest::default())?)
}
