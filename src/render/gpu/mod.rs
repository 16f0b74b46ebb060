//! The GPU renderer: the WGSL path tracer in `shaders/`, run as a compute shader through
//! wgpu on Vulkan (a real GPU, or lavapipe on the CPU). Only this module imports wgpu.
//!
//! The host uploads the tables of [`RenderScene`](crate::render::RenderScene) unchanged,
//! so the GPU traces exactly the paths the CPU renderer traces for the same
//! (pixel, sample, seed). `context` opens devices, `accel` builds the acceleration structure
//! of hardware ray queries (`--accel`), `params` holds the uniform block,
//! `layout` describes the host-shared structs, `shader` generates and joins the WGSL, `tables` uploads the scene, `pipelines` compiles entry
//! points, `session` is the renderer ([`GpuRenderer`]) and `kernels` runs the shader
//! unit-test and ray-throughput entry points against it.

mod accel;
mod context;
pub mod kernels;
pub mod layout;
pub mod params;
mod pipelines;
mod session;
pub mod shader;
pub mod tables;

pub use accel::Accel;
pub use context::{AdapterSummary, GpuContext, choose_adapter, list_adapters};
pub use session::{GpuRenderer, PATHS_PER_DISPATCH};
pub use tables::TABLE_WIDTH;

/// What can go wrong on the GPU path; each message says what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no Vulkan adapter found; install a Vulkan driver (for a CPU-only machine, Mesa's lavapipe: `apt-get install mesa-vulkan-drivers`) or use --device cpu"
    )]
    NoAdapter,
    #[error("no adapter matches `{0}` (there are {1}); run `meshtrace adapters` to list them")]
    NoSuchAdapter(String, usize),
    #[error("cannot open the GPU device: {0}")]
    Device(String),
    #[error(
        "the {what} need {bytes} bytes but this adapter holds at most {limit} ({rule}); use --device cpu or a smaller scene"
    )]
    TooLarge {
        what: &'static str,
        bytes: u64,
        limit: u64,
        /// The adapter limit that sets `limit`, as wgpu names it, with its value.
        rule: String,
    },
    #[error(
        "--accel hardware: the adapter {0} offers no hardware ray queries; use --accel auto or --accel software"
    )]
    NoRayQuery(String),
    #[error("GPU error: {0}")]
    Fault(String),
}
