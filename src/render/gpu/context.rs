//! A device with its render kernels: the [`GpuDevice`] that every GPU stage uses, plus the
//! render kernels compiled on it, kept for every later scene (a batch's meshes).

use super::device::{Accel, GpuDevice};
use super::error::GpuError;
use super::pipelines::Pipeline;
use super::shader::{self, Features, ShaderChecks};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// A device's render kernels by (caustics, geometry-only, [`Features`]).
type RenderKernels = HashMap<(bool, bool, Features), Arc<Pipeline>>;

/// An open device and its render kernels. Cloning is cheap and shares both. It reads as
/// the [`GpuDevice`] it holds (`ctx.device`, `ctx.check()`), which is all the stages below
/// the renderer (uploads, pipelines, acceleration structures) take.
#[derive(Clone)]
pub struct GpuContext {
    gpu: GpuDevice,
    /// How the render kernel is compiled: trusted unless [`GpuContext::with_shader_checks`].
    checks: ShaderChecks,
    /// The render kernels, each compiled by the first render on this device that needs it:
    /// without and with the caustics code (`CAUSTICS`), and the geometry-only kernel, for
    /// each set of [`Features`].
    render: Arc<Mutex<RenderKernels>>,
}

impl std::ops::Deref for GpuContext {
    type Target = GpuDevice;
    fn deref(&self) -> &GpuDevice {
        &self.gpu
    }
}

/// A test may narrow a clone's limits (`ctx.limits`) to see a scene refused.
impl std::ops::DerefMut for GpuContext {
    fn deref_mut(&mut self) -> &mut GpuDevice {
        &mut self.gpu
    }
}

impl GpuContext {
    /// Opens a device as [`GpuDevice::new`] does, with no kernel compiled yet.
    pub fn new(spec: Option<&str>, accel: Accel) -> Result<Self, GpuError> {
        Ok(Self {
            gpu: GpuDevice::new(spec, accel)?,
            checks: ShaderChecks::Trusted,
            render: Default::default(),
        })
    }

    /// This device with a render kernel of its own that is compiled checked
    /// ([`ShaderChecks::Checked`]): every render on it then fails with
    /// [`GpuError::Fault`] where the kernel indexed out of range or divided by zero.
    /// For tests, and for telling a kernel's fault from a driver's.
    pub fn with_shader_checks(mut self) -> Self {
        self.checks = ShaderChecks::Checked;
        self.render = Default::default();
        self
    }

    /// The render kernel (`shaders/render.wgsl`), compiled on first use: with the code of
    /// caustic light subpaths for scenes that have caustic targets, or without it
    /// ([`shader::render_source_without_caustics`]), which compiles in less than
    /// half the time and holds no registers for light subpaths that it never traces; and
    /// with the optional parts the scene uses (`features`).
    pub fn render_pipeline(
        &self,
        caustics: bool,
        features: Features,
    ) -> Result<Arc<Pipeline>, GpuError> {
        self.kernel(caustics, false, features)
    }

    /// The geometry-only kernel (`geometry` in `shaders/render.wgsl`): camera rays and
    /// their first hits alone, compiled on first use without the caustic stage.
    pub fn geometry_pipeline(&self, features: Features) -> Result<Arc<Pipeline>, GpuError> {
        self.kernel(false, true, features)
    }

    /// The render kernel or (`geometry`) the geometry-only one, from the cache.
    fn kernel(
        &self,
        caustics: bool,
        geometry: bool,
        features: Features,
    ) -> Result<Arc<Pipeline>, GpuError> {
        let mut kernels = self.render.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(p) = kernels.get(&(caustics, geometry, features)) {
            return Ok(p.clone());
        }
        let p = Arc::new(Pipeline::new(
            &self.gpu,
            &self.scene_layout,
            if caustics {
                shader::render_source
            } else {
                shader::render_source_without_caustics
            },
            if geometry { "geometry" } else { "render" },
            (0, 3),
            self.checks,
            features,
        )?);
        kernels.insert((caustics, geometry, features), p.clone());
        Ok(p)
    }
}
