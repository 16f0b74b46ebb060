//! `meshtrace.Camera` and the layouts of `meshtrace.cameras`: orbits like `meshtrace
//! batch`'s turntables, and the dataset presets' cameras (docs/datasets.md).

use crate::errors;
use crate::scene::Scene;
use glam::Vec3;
use meshtrace::batch::preset::Preset;
use meshtrace::batch::transforms::{Intrinsics, camera_to_world};
use numpy::{PyArray2, ToPyArray, ndarray::Array2};
use pyo3::prelude::*;

/// Where a camera stands, where it looks and its projection: a pinhole with a vertical
/// field of view (or a thin lens with an aperture), or orthographic with a view height.
#[pyclass(module = "meshtrace", frozen, eq)]
#[derive(Clone, PartialEq)]
pub struct Camera {
    pub(crate) inner: meshtrace::scene::camera::Camera,
}

impl From<meshtrace::scene::camera::Camera> for Camera {
    fn from(inner: meshtrace::scene::camera::Camera) -> Self {
        Self { inner }
    }
}

/// A finite point or direction.
fn vec3(name: &str, v: [f32; 3]) -> PyResult<Vec3> {
    let v = Vec3::from(v);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(errors::message(format!("{name}: must be finite, got {v}")))
    }
}

fn check_fov(fov: f32) -> PyResult<f32> {
    if fov > 0.0 && fov < 180.0 {
        Ok(fov)
    } else {
        Err(errors::message(format!(
            "fov: must be in (0, 180), got {fov}"
        )))
    }
}

/// A camera at `eye` looking at `target`, or why there is none.
fn aimed(
    eye: Vec3,
    target: Vec3,
    up: Vec3,
    fov: f32,
    aperture: f32,
    focus: Option<f32>,
) -> PyResult<Camera> {
    if !(aperture >= 0.0 && aperture.is_finite()) {
        return Err(errors::message(format!(
            "aperture: must be at least 0, got {aperture}"
        )));
    }
    if let Some(f) = focus
        && !(f > 0.0 && f.is_finite())
    {
        return Err(errors::message(format!(
            "focus_distance: must be positive, got {f}"
        )));
    }
    meshtrace::scene::camera::Camera::new(eye, target, up, check_fov(fov)?, aperture, focus)
        .map(Camera::from)
        .ok_or_else(|| {
            errors::message("target: must differ from eye, and up must not be parallel to the view")
        })
}

/// The convention of a camera-to-world matrix: OpenGL's (the camera looks down −Z, +Y up;
/// NeRF's transforms.json, Blender) or OpenCV's (looks down +Z, +Y down; COLMAP).
#[derive(Clone, Copy, PartialEq)]
enum Convention {
    OpenGl,
    OpenCv,
}

fn convention(name: &str) -> PyResult<Convention> {
    match name {
        "opengl" => Ok(Convention::OpenGl),
        "opencv" => Ok(Convention::OpenCv),
        other => Err(errors::message(format!(
            "convention: `{other}` is not one of opengl, opencv"
        ))),
    }
}

#[pymethods]
impl Camera {
    /// A perspective camera at `eye` looking at `target`, `up` towards the top of the
    /// picture, with a vertical field of view of `fov` degrees; `aperture` > 0 makes it a
    /// thin lens focused at `focus_distance` (by default the distance to `target`).
    #[staticmethod]
    #[pyo3(signature = (eye, target, up=[0.0, 1.0, 0.0], fov=40.0, aperture=0.0, focus_distance=None))]
    fn look_at(
        eye: [f32; 3],
        target: [f32; 3],
        up: [f32; 3],
        fov: f32,
        aperture: f32,
        focus_distance: Option<f32>,
    ) -> PyResult<Self> {
        aimed(
            vec3("eye", eye)?,
            vec3("target", target)?,
            vec3("up", up)?,
            fov,
            aperture,
            focus_distance,
        )
    }

    /// An orthographic camera at `eye` looking at `target` along parallel rays, seeing a
    /// view `height` world units high (and as wide as the image's aspect makes it).
    #[staticmethod]
    #[pyo3(signature = (eye, target, height, up=[0.0, 1.0, 0.0]))]
    fn orthographic(eye: [f32; 3], target: [f32; 3], height: f32, up: [f32; 3]) -> PyResult<Self> {
        if !(height > 0.0 && height.is_finite()) {
            return Err(errors::message(format!(
                "height: must be positive, got {height}"
            )));
        }
        let c = aimed(
            vec3("eye", eye)?,
            vec3("target", target)?,
            vec3("up", up)?,
            40.0,
            0.0,
            None,
        )?;
        Ok(Self::from(c.inner.orthographic(height)))
    }

    /// A camera from a 4×4 (or 3×4) camera-to-world matrix in the `opengl` or `opencv`
    /// convention, with a vertical field of view of `fov` degrees, or orthographic with a
    /// view `ortho_height` high. The rotation's columns are the camera's axes.
    #[staticmethod]
    #[pyo3(signature = (matrix, fov=40.0, convention="opengl", ortho_height=None))]
    fn from_matrix(
        matrix: Vec<Vec<f64>>,
        fov: f32,
        convention: &str,
        ortho_height: Option<f32>,
    ) -> PyResult<Self> {
        let conv = self::convention(convention)?;
        let shape_ok =
            (matrix.len() == 3 || matrix.len() == 4) && matrix.iter().all(|r| r.len() == 4);
        if !shape_ok {
            return Err(errors::message(
                "matrix: must be 4×4 or 3×4 (camera to world)",
            ));
        }
        let column = |j: usize| {
            Vec3::new(
                matrix[0][j] as f32,
                matrix[1][j] as f32,
                matrix[2][j] as f32,
            )
        };
        let position = vec3("matrix", column(3).to_array())?;
        let (up, forward) = match conv {
            Convention::OpenGl => (column(1), -column(2)),
            Convention::OpenCv => (-column(1), column(2)),
        };
        let forward = forward
            .try_normalize()
            .ok_or_else(|| errors::message("matrix: its rotation has a zero column"))?;
        let c = aimed(
            position,
            position + forward,
            vec3("matrix", up.to_array())?,
            fov,
            0.0,
            None,
        )?;
        match ortho_height {
            None => Ok(c),
            Some(h) if h > 0.0 && h.is_finite() => Ok(Self::from(c.inner.orthographic(h))),
            Some(h) => Err(errors::message(format!(
                "ortho_height: must be positive, got {h}"
            ))),
        }
    }

    /// The 4×4 camera-to-world matrix in the `opengl` or `opencv` convention (float64).
    #[pyo3(signature = (convention="opengl"))]
    fn matrix<'py>(
        &self,
        py: Python<'py>,
        convention: &str,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let m = camera_to_world(&self.inner);
        let flip = match self::convention(convention)? {
            Convention::OpenGl => 1.0,
            Convention::OpenCv => -1.0,
        };
        let a = Array2::from_shape_fn((4, 4), |(i, j)| {
            let v = m[i][j] as f64;
            if (j == 1 || j == 2) && i < 3 {
                v * flip
            } else {
                v
            }
        });
        Ok(a.to_pyarray(py))
    }

    /// The 3×3 intrinsic matrix K of a `width`×`height` image (pixels, origin at the top
    /// left corner of the image, square pixels); a perspective camera's only.
    fn intrinsics<'py>(
        &self,
        py: Python<'py>,
        width: u32,
        height: u32,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        if self.inner.is_orthographic() {
            return Err(errors::message(
                "intrinsics: an orthographic camera has no focal length",
            ));
        }
        if width == 0 || height == 0 {
            return Err(errors::message("width and height: must be at least 1"));
        }
        let k = Intrinsics::of(&self.inner, width, height);
        let a = Array2::from_shape_vec(
            (3, 3),
            vec![
                k.fl_x as f64,
                0.0,
                k.cx as f64,
                0.0,
                k.fl_y as f64,
                k.cy as f64,
                0.0,
                0.0,
                1.0,
            ],
        )
        .map_err(|e| errors::message(e.to_string()))?;
        Ok(a.to_pyarray(py))
    }

    #[getter]
    fn position(&self) -> [f32; 3] {
        self.inner.position.to_array()
    }

    /// The unit vector the camera looks along.
    #[getter]
    fn forward(&self) -> [f32; 3] {
        self.inner.forward.to_array()
    }

    /// The unit vector towards the top of the picture.
    #[getter]
    fn up(&self) -> [f32; 3] {
        self.inner.up.to_array()
    }

    /// The unit vector towards the right of the picture.
    #[getter]
    fn right(&self) -> [f32; 3] {
        self.inner.right.to_array()
    }

    /// The vertical field of view in degrees (a perspective camera's).
    #[getter]
    fn fov(&self) -> f32 {
        self.inner.vfov
    }

    /// An orthographic camera's view height in world units; None for a perspective one.
    #[getter]
    fn ortho_height(&self) -> Option<f32> {
        self.inner
            .is_orthographic()
            .then_some(self.inner.ortho_height)
    }

    fn __repr__(&self) -> String {
        let c = &self.inner;
        let projection = if c.is_orthographic() {
            format!("orthographic height {}", c.ortho_height)
        } else {
            format!("fov {}", c.vfov)
        };
        format!(
            "<meshtrace.Camera at {:?} looking along {:?}, {projection}>",
            c.position.to_array(),
            c.forward.to_array()
        )
    }
}

/// `views` cameras evenly spaced in azimuth at `elevation` degrees, as `meshtrace batch`
/// puts a turntable's: about a bare mesh framed as `render` frames it, or about the point
/// a scene file's camera looks at, at its distance (Y up). Unset angles keep the studio's
/// (azimuth 35°, elevation 22°) or the scene camera's.
#[pyfunction]
#[pyo3(signature = (scene, views=12, elevation=None, azimuth=None))]
pub fn orbit(
    scene: &Scene,
    views: u32,
    elevation: Option<f32>,
    azimuth: Option<f32>,
) -> PyResult<Vec<Camera>> {
    if views == 0 {
        return Err(errors::message("views: must be at least 1"));
    }
    let s = &scene.scene;
    (0..views)
        .map(|view| {
            meshtrace::batch::orbit(
                views,
                view,
                azimuth,
                elevation,
                &s.camera,
                s.framed.as_ref(),
            )
            .map(Camera::from)
            .ok_or_else(|| errors::message(format!("view {view} cannot be framed")))
        })
        .collect()
}

/// The cameras of dataset preset `name` (`meshtrace.PRESETS`; docs/datasets.md) for a bare
/// mesh, as the script places them for the object named `uid` (by default the file name up
/// to its first dot): `views` of them (the preset's own count by default), in the mesh's
/// own frame. Render them with the preset's settings ([`preset_settings`]).
#[pyfunction]
#[pyo3(signature = (scene, name, views=None, uid=None))]
pub fn preset(
    scene: &Scene,
    name: &str,
    views: Option<u32>,
    uid: Option<String>,
) -> PyResult<Vec<Camera>> {
    let preset = Preset::named(name).map_err(|m| errors::message(format!("preset: {m}")))?;
    let s = &scene.scene;
    let norm = s
        .framed
        .as_ref()
        .and_then(|b| preset.normalisation(b))
        .ok_or_else(|| {
            errors::message("preset: frames a bare mesh (.obj, .gltf, .glb) with an extent")
        })?;
    let uid = match (uid, &s.path) {
        (Some(u), _) => u,
        (None, Some(p)) => meshtrace::scene::uid(p),
        (None, None) => return Err(errors::message("uid: give one for a scene without a file")),
    };
    let views = views.unwrap_or(preset.views);
    let preset = Preset { views, ..preset };
    (0..views)
        .map(|view| {
            preset
                .camera(&uid, view, &norm)
                .map(Camera::from)
                .ok_or_else(|| errors::message(format!("view {view} cannot be framed")))
        })
        .collect()
}

/// The render settings of dataset preset `name`, as keyword arguments of
/// `Renderer.render`: its image size, samples per pixel, pixel filter width, its script's
/// light paths (`max_depth` and the bounce limits) and whether its film is transparent (all
/// but Wonder3D's, whose mask and normals are the `object_id` and `normal` AOVs).
#[pyfunction]
pub fn preset_settings<'py>(
    py: Python<'py>,
    name: &str,
) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
    let p = Preset::named(name).map_err(|m| errors::message(format!("preset: {m}")))?;
    let d = pyo3::types::PyDict::new(py);
    d.set_item("width", p.size)?;
    d.set_item("height", p.size)?;
    d.set_item("spp", p.spp)?;
    d.set_item("filter_width", p.filter_width)?;
    d.set_item("max_depth", p.max_depth)?;
    for (key, limit) in [
        ("diffuse_bounces", p.bounces.diffuse),
        ("glossy_bounces", p.bounces.glossy),
        ("transmission_bounces", p.bounces.transmission),
    ] {
        if let Some(n) = limit {
            d.set_item(key, n)?;
        }
    }
    d.set_item("transparent", p.request().transparent())?;
    Ok(d)
}
