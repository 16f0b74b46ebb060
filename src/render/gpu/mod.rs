//! The GPU renderer: the WGSL path tracer in `shaders/`, run as a compute shader through
//! wgpu on Vulkan (a real GPU, or lavapipe on the CPU). Only this module imports wgpu.
//!
//! The host uploads the tables of [`RenderScene`](crate::render::RenderScene) unchanged,
//! so the GPU traces exactly the paths the CPU renderer traces for the same
//! (pixel, sample, seed). From the bottom up: `error` says what went wrong, `layout`
//! describes the host-shared structs, `params` holds the uniform block, `tables` lists the
//! scene's tables and their bind group layout, `shader` generates and joins the WGSL,
//! `device` opens adapters (with or without hardware ray queries, `--accel`), `accel`
//! builds their acceleration structure, `upload` puts a scene on a device, `pipelines`
//! compiles entry points, `context` keeps a device's render kernels, `session` is the
//! renderer ([`GpuRenderer`]) and `kernels` runs the shader unit-test and ray-throughput
//! entry points against it.

mod accel;
mod context;
mod device;
mod error;
pub mod kernels;
pub mod layout;
pub mod params;
mod pipelines;
mod session;
pub mod shader;
pub mod tables;
mod upload;

pub use context::GpuContext;
pub use device::{Accel, AdapterSummary, GpuDevice, choose_adapter, list_adapters};
pub use error::GpuError;
pub use session::{GpuRenderer, PATHS_PER_DISPATCH};
pub use tables::TABLE_WIDTH;
