//! `meshtrace.Output`: a finished render's film and its arrays. The arrays are the film's
//! values in buffers that NumPy takes over without a copy; `save` writes the film as
//! `meshtrace render` writes it, to the bit.

use crate::errors;
use meshtrace::film::{
    Aov, AovValues, BitDepth, DisplayTransform, Film, FilmError, ViewTransform, lut_folder,
};
use meshtrace::request::parse_name;
use numpy::IntoPyArray;
use numpy::ndarray::{Array2, Array3};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// A render's images by name, as a read-only mapping: `color` (float32, H×W×3, linear
/// radiance; premultiplied by `alpha` in a transparent render) and each AOV asked for:
/// `depth` (H×W, inf where nothing was hit), `normal` and `albedo` (H×W×3), `alpha`
/// (H×W), `object_id` and `material_id` (uint32, H×W, 4294967295 where nothing was hit),
/// `bvh_cost` (H×W), `diffuse_color` (H×W×3).
#[pyclass(module = "meshtrace", frozen, mapping)]
pub struct Output {
    film: Film,
    arrays: Vec<(&'static str, Py<PyAny>)>,
}

/// `values` (one vector per component, pixel-major) as an H×W or H×W×C array.
fn array(py: Python<'_>, h: usize, w: usize, values: Vec<AovValues>) -> PyResult<Py<PyAny>> {
    let shape_error = |e: numpy::ndarray::ShapeError| errors::message(e.to_string());
    let one = |a: Array2<f32>| a.into_pyarray(py).into_any().unbind();
    Ok(match <[AovValues; 1]>::try_from(values) {
        Ok([AovValues::F32(v)]) => one(Array2::from_shape_vec((h, w), v).map_err(shape_error)?),
        Ok([AovValues::U32(v)]) => Array2::from_shape_vec((h, w), v)
            .map_err(shape_error)?
            .into_pyarray(py)
            .into_any()
            .unbind(),
        Err(values) => {
            let c = values.len();
            let mut data = vec![0.0f32; h * w * c];
            for (k, v) in values.iter().enumerate() {
                if let AovValues::F32(v) = v {
                    for (i, x) in v.iter().enumerate() {
                        data[i * c + k] = *x;
                    }
                }
            }
            Array3::from_shape_vec((h, w, c), data)
                .map_err(shape_error)?
                .into_pyarray(py)
                .into_any()
                .unbind()
        }
    })
}

impl Output {
    /// The arrays of `film`: its mean radiance, the AOVs it saves, and a transparent
    /// film's alpha.
    pub fn new(py: Python<'_>, film: Film) -> PyResult<Self> {
        let (h, w) = (film.height as usize, film.width as usize);
        let color: Vec<f32> = film.mean().iter().flat_map(|c| c.to_array()).collect();
        let color = Array3::from_shape_vec((h, w, 3), color)
            .map_err(|e| errors::message(e.to_string()))?
            .into_pyarray(py)
            .into_any()
            .unbind();
        let mut arrays = vec![("color", color)];
        for aov in film.aovs() {
            let wanted =
                film.saved_aovs & aov.bit() != 0 || (aov == Aov::Alpha && film.transparent);
            if let (true, Some(values)) = (wanted, film.aov_values(aov)) {
                arrays.push((aov.name(), array(py, h, w, values)?));
            }
        }
        Ok(Self { film, arrays })
    }

    fn find(&self, key: &str) -> Option<&Py<PyAny>> {
        self.arrays.iter().find(|(k, _)| *k == key).map(|(_, v)| v)
    }
}

#[pymethods]
impl Output {
    fn __getitem__(&self, py: Python<'_>, key: &str) -> PyResult<Py<PyAny>> {
        self.find(key)
            .map(|v| v.clone_ref(py))
            .ok_or_else(|| pyo3::exceptions::PyKeyError::new_err(key.to_string()))
    }

    fn __contains__(&self, key: &str) -> bool {
        self.find(key).is_some()
    }

    fn __len__(&self) -> usize {
        self.arrays.len()
    }

    fn __iter__(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let keys = pyo3::types::PyList::new(py, self.keys())?;
        Ok(keys.try_iter()?.into_any().unbind())
    }

    /// The names of the images, `color` first.
    fn keys(&self) -> Vec<&'static str> {
        self.arrays.iter().map(|(k, _)| *k).collect()
    }

    fn values(&self, py: Python<'_>) -> Vec<Py<PyAny>> {
        self.arrays.iter().map(|(_, v)| v.clone_ref(py)).collect()
    }

    fn items(&self, py: Python<'_>) -> Vec<(&'static str, Py<PyAny>)> {
        self.arrays
            .iter()
            .map(|(k, v)| (*k, v.clone_ref(py)))
            .collect()
    }

    #[pyo3(signature = (key, default=None))]
    fn get(&self, py: Python<'_>, key: &str, default: Option<Py<PyAny>>) -> Option<Py<PyAny>> {
        self.find(key).map(|v| v.clone_ref(py)).or(default)
    }

    /// Samples per pixel the images hold.
    #[getter]
    fn samples(&self) -> u32 {
        self.film.samples
    }

    /// Rays traced for the whole image.
    #[getter]
    fn rays(&self) -> u64 {
        self.film.rays()
    }

    /// Writes the render to `path` as `meshtrace render -o path` does: the extension picks
    /// the format (.exr with the AOVs as channels; .png, .jpg, .bmp, .hdr with the AOVs in
    /// `<stem>.aovs.exr` beside it; a transparent render as an RGBA PNG), `bit_depth` 8 or
    /// 16 for a PNG, `view_transform` `"standard"`, `"filmic"` or `"agx"` for an 8- or 16-bit
    /// image. Complete or not at all. It writes the render as rendered: changes made to the
    /// arrays are not saved.
    #[pyo3(signature = (path, *, bit_depth=None, view_transform=None))]
    fn save(
        &self,
        py: Python<'_>,
        path: PathBuf,
        bit_depth: Option<u32>,
        view_transform: Option<&str>,
    ) -> PyResult<()> {
        let depth = match bit_depth {
            None | Some(8) => BitDepth::Eight,
            Some(16) => BitDepth::Sixteen,
            Some(b) => {
                return Err(errors::message(format!(
                    "bit_depth: must be 8 or 16 (bits per channel of a PNG), got {b}"
                )));
            }
        };
        let view = view_transform
            .map(|name| parse_name(name, &ViewTransform::NAMES))
            .transpose()
            .map_err(|e| errors::message(format!("view_transform: {e}")))?
            .unwrap_or_default();
        py.detach(|| {
            let display = display_transform(view)?;
            self.film.save_as(&path, depth, &display)
        })
        .map_err(|e| errors::error(&e))
    }

    fn __repr__(&self) -> String {
        format!(
            "<meshtrace.Output {}×{} at {} spp: {}>",
            self.film.width,
            self.film.height,
            self.film.samples,
            self.keys().join(", ")
        )
    }
}

/// `view` with its LUTs read, once per view and LUT folder: a script saves many images, and
/// reading AgX's LUT takes 20 to 40 ms, forty times a small image's encoding.
fn display_transform(view: ViewTransform) -> Result<Arc<DisplayTransform>, FilmError> {
    type Loaded = Vec<(ViewTransform, PathBuf, Arc<DisplayTransform>)>;
    static LOADED: Mutex<Loaded> = Mutex::new(Vec::new());
    if view == ViewTransform::Standard {
        return Ok(Arc::default());
    }
    let folder = lut_folder(view)?;
    let mut loaded = LOADED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, _, d)) = loaded.iter().find(|(v, f, _)| *v == view && *f == folder) {
        return Ok(d.clone());
    }
    let display = Arc::new(DisplayTransform::load(view)?);
    loaded.push((view, folder, display.clone()));
    Ok(display)
}

/// Writes `output` to `path` ([`Output::save`]).
#[pyfunction]
#[pyo3(signature = (output, path, *, bit_depth=None, view_transform=None))]
pub fn save(
    py: Python<'_>,
    output: &Output,
    path: PathBuf,
    bit_depth: Option<u32>,
    view_transform: Option<&str>,
) -> PyResult<()> {
    output.save(py, path, bit_depth, view_transform)
}
