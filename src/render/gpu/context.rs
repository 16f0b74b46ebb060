//! A device with its kernels: the [`GpuDevice`] that every GPU stage uses, plus the
//! kernels compiled on it, kept for every later scene (a batch's meshes, a test's scenes).

use super::device::{Accel, GpuDevice};
use super::error::GpuError;
use super::pipelines::Pipeline;
use super::shader::{self, Features, Module, ShaderChecks};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// What makes a compiled kernel: its WGSL source (the traversal and the checks' constant
/// in it), its entry point, its storage group's (read-only, read-write) buffers, how it was
/// compiled ([`ShaderChecks`]) and the [`Features`] it was specialised for.
type KernelKey = (String, String, (u32, u32), ShaderChecks, Features);

/// One key's kernel once compiled. Its own lock, held while it compiles, makes the
/// callers that want the same kernel wait for that one compile, and no others: the
/// cache's lock is held only to find or add the slot.
type KernelSlot = Mutex<Option<Arc<Pipeline>>>;

/// An open device and its kernels. Cloning is cheap and shares both. It reads as
/// the [`GpuDevice`] it holds (`ctx.device`, `ctx.check()`), which is all the stages below
/// the renderer (uploads, pipelines, acceleration structures) take.
#[derive(Clone)]
pub struct GpuContext {
    gpu: GpuDevice,
    /// How the render kernel is compiled: trusted unless [`GpuContext::with_shader_checks`].
    checks: ShaderChecks,
    /// The kernels, each compiled by the first render or run on this device that needs it:
    /// the render kernel without and with the caustics code (`CAUSTICS`), the
    /// geometry-only kernel, and the test and bench entry points, for each set of
    /// [`Features`]. On lavapipe a kernel takes 2–30 s to compile, far longer than most
    /// renders of tests, and on any device a batch's assets share it.
    kernels: Arc<Mutex<HashMap<KernelKey, Arc<KernelSlot>>>>,
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
            kernels: Default::default(),
        })
    }

    /// This device with its render kernel compiled checked ([`ShaderChecks::Checked`]):
    /// every render on it then fails with [`GpuError::Fault`] where the kernel indexed out
    /// of range or divided by zero. For tests, and for telling a kernel's fault from a
    /// driver's.
    pub fn with_shader_checks(mut self) -> Self {
        self.checks = ShaderChecks::Checked;
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
        let module = if caustics {
            shader::render_source
        } else {
            shader::render_source_without_caustics
        };
        let entry = if geometry { "geometry" } else { "render" };
        self.pipeline(module, entry, (0, 3), self.checks, features)
    }

    /// Entry point `entry` of `module` (a function of [`shader`]) over the scene group
    /// and `io` storage buffers (read-only, read-write), compiled as `checks` says with
    /// `features`: from the cache, or compiled now and kept.
    pub fn pipeline(
        &self,
        module: Module,
        entry: &str,
        io: (u32, u32),
        checks: ShaderChecks,
        features: Features,
    ) -> Result<Arc<Pipeline>, GpuError> {
        let key = (
            module(self.ray_query, checks),
            entry.to_string(),
            io,
            checks,
            features,
        );
        let slot = {
            let mut kernels = self.kernels.lock().unwrap_or_else(|p| p.into_inner());
            kernels.entry(key).or_default().clone()
        };
        let mut slot = slot.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(p) = &*slot {
            return Ok(p.clone());
        }
        // The key holds the source: made again for the compile (seconds) rather than
        // copied on every call.
        let p = Arc::new(Pipeline::new(
            &self.gpu,
            &self.scene_layout,
            &module(self.ray_query, checks),
            entry,
            io,
            checks,
            features,
        )?);
        *slot = Some(p.clone());
        Ok(p)
    }
}
