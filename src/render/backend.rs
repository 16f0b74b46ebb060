//! Which renderer runs a render: the one rule that `render`, `bench` and the tests share.
//! A hardware GPU renders by default; a software Vulkan adapter (lavapipe) gives way to
//! the CPU renderer, which is faster on the same cores and makes the same image, unless the
//! GPU is asked for (`--device gpu`, `--accel hardware`, or an adapter named by `--adapter`
//! or `WGPU_ADAPTER_NAME`); with no adapter at all the CPU renders. On the GPU, `--accel`
//! chooses between hardware ray queries and the software BVH ([`Accel`]).

use super::cpu;
use super::gpu::{self, Accel, GpuContext, GpuError, GpuRenderer};
use super::job::RenderJob;
use super::tables::RenderScene;
use crate::film::Film;
use crate::scene::camera::Camera;

/// What the user asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceChoice {
    /// The GPU on a hardware adapter, else the CPU.
    Auto,
    Cpu,
    /// A Vulkan adapter, even a software one.
    Gpu,
}

/// The renderer chosen.
pub enum Backend {
    Cpu,
    Gpu(Box<GpuContext>),
}

impl Backend {
    /// Applies the rule to `choice` and `adapter` (an index or a name substring), opening
    /// a GPU with `accel`. Returns the backend and, when the CPU was chosen for want of a
    /// usable GPU, a notice saying why.
    pub fn choose(
        choice: DeviceChoice,
        adapter: Option<&str>,
        accel: Accel,
    ) -> Result<(Self, Option<String>), GpuError> {
        let open = || Ok(Self::Gpu(Box::new(GpuContext::new(adapter, accel)?)));
        match choice {
            DeviceChoice::Cpu => Ok((Self::Cpu, None)),
            DeviceChoice::Gpu => Ok((open()?, None)),
            DeviceChoice::Auto => match gpu::choose_adapter(adapter) {
                // Software adapters are ranked last, so this one is all there is; no device
                // is opened for it unless hardware ray queries are asked for.
                Ok((summary, false)) if summary.software && accel != Accel::Hardware => Ok((
                    Self::Cpu,
                    Some(format!(
                        "{} is a software driver; rendering on the faster CPU (--device gpu to use it)",
                        summary.name
                    )),
                )),
                Ok(_) => Ok((open()?, None)),
                Err(GpuError::NoAdapter) => Ok((
                    Self::Cpu,
                    Some(
                        "no Vulkan adapter found; rendering on the CPU (install mesa-vulkan-drivers for lavapipe)"
                            .into(),
                    ),
                )),
                Err(e) => Err(e),
            },
        }
    }

    /// The device's name for messages: the adapter's with how it finds hits, or "the CPU".
    pub fn name(&self) -> String {
        match self {
            Self::Cpu => "the CPU".into(),
            Self::Gpu(ctx) => format!("{} ({})", ctx.adapter.name, ctx.accel_name()),
        }
    }

    /// The device's identity for part files ([`crate::film::PartHeader::device`]): what
    /// the bits of a render depend on beyond the scene. The CPU's is its architecture and
    /// system (its libm decides the last bits of a few functions); a GPU's is the
    /// adapter, its driver and how it finds hits.
    pub fn device_id(&self) -> String {
        match self {
            Self::Cpu => format!("cpu ({}-{})", std::env::consts::ARCH, std::env::consts::OS),
            Self::Gpu(ctx) => format!(
                "{} ({}; {})",
                ctx.adapter.name,
                ctx.adapter.driver,
                ctx.accel_name()
            ),
        }
    }

    /// Renders the job on this backend. `progress` is told the samples finished as they
    /// finish.
    pub fn render(
        &self,
        scene: &RenderScene,
        job: &RenderJob,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Film, GpuError> {
        match self {
            Self::Cpu => Ok(cpu::render(scene, job, progress)),
            Self::Gpu(ctx) => GpuRenderer::new(ctx, scene)?.render(job, progress),
        }
    }
}

/// A scene made ready once on a backend (on a GPU: its tables uploaded), for several
/// renders that differ in camera and settings: the views of a batch.
pub struct Prepared {
    scene: RenderScene,
    gpu: Option<GpuRenderer>,
}

impl Backend {
    /// Makes `scene` ready to render on this backend.
    pub fn prepare(&self, scene: RenderScene) -> Result<Prepared, GpuError> {
        let gpu = match self {
            Self::Cpu => None,
            Self::Gpu(ctx) => Some(GpuRenderer::new(ctx, &scene)?),
        };
        Ok(Prepared { scene, gpu })
    }
}

impl Prepared {
    /// The scene as prepared.
    pub fn scene(&self) -> &RenderScene {
        &self.scene
    }

    /// Renders from `camera` from now on.
    pub fn set_camera(&mut self, camera: &Camera) {
        self.scene.camera = camera.clone();
        if let Some(g) = &mut self.gpu {
            g.set_camera(camera);
        }
    }

    /// Renders the job, as [`Backend::render`] does.
    pub fn render(
        &mut self,
        job: &RenderJob,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Film, GpuError> {
        match &mut self.gpu {
            None => Ok(cpu::render(&self.scene, job, progress)),
            Some(g) => g.render(job, progress),
        }
    }
}
