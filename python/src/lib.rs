//! meshtrace's Python bindings, the `meshtrace._meshtrace` extension module that the
//! `meshtrace` package (`python/meshtrace`) re-exports: scenes loaded from files or
//! dictionaries ([`scene`]), cameras ([`camera`]), a renderer that keeps its device across
//! renders ([`renderer`]) and its outputs as NumPy arrays ([`output`]). Every render goes
//! through the library's one [`RenderRequest`](meshtrace::request::RenderRequest), so the
//! keyword arguments, defaults and errors are the command line's.

mod camera;
mod dict;
mod errors;
mod output;
mod renderer;
mod scene;

use pyo3::prelude::*;

#[pymodule]
fn _meshtrace(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add(
        "MeshtraceError",
        m.py().get_type::<errors::MeshtraceError>(),
    )?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<camera::Camera>()?;
    m.add_class::<renderer::Renderer>()?;
    m.add_class::<output::Output>()?;
    m.add_function(wrap_pyfunction!(scene::load, m)?)?;
    m.add_function(wrap_pyfunction!(output::save, m)?)?;
    m.add_function(wrap_pyfunction!(camera::orbit, m)?)?;
    m.add_function(wrap_pyfunction!(camera::preset, m)?)?;
    m.add_function(wrap_pyfunction!(camera::preset_settings, m)?)?;
    m.add("PRESETS", meshtrace::batch::preset::NAMES.to_vec())?;
    Ok(())
}
