//! The command line: argument types (clap) and the commands they run, one module each.
//! Only this folder and `main` know about clap, indicatif (through `progress`) or anyhow;
//! the commands turn their flags into a [`RenderRequest`] and leave the work to the
//! library's [`pipeline`](meshtrace::pipeline).

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand, ValueEnum};
use meshtrace::film::ViewTransform;
use meshtrace::pipeline::PipelineError;
use meshtrace::render::backend::{Backend, DeviceChoice};
use meshtrace::render::gpu::Accel;
use meshtrace::request::{RenderRequest, RequestError};
use meshtrace::scene::studio::Up;

mod adapters;
mod batch;
mod bench;
mod info;
mod merge;
mod preview;
mod progress;
mod render;
pub use adapters::adapters;
pub use batch::{BatchArgs, batch};
pub use bench::{BenchArgs, bench};
pub use info::{InfoArgs, info};
pub use merge::{MergeArgs, merge};
pub use render::{RenderArgs, render};

/// `println!` that returns an error instead of panicking when standard output is closed
/// (`meshtrace info scene.toml | head`); `main` ends quietly on a broken pipe.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout(), $($arg)*)?
    }};
}

pub(crate) use out;

#[derive(Parser)]
#[command(
    name = "meshtrace",
    version,
    about = "A physically based path tracer for triangle meshes"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Render a scene file (.toml), a bare mesh (.obj), a glTF file (.gltf, .glb) or, with
    /// none, the built-in Cornell box.
    Render(RenderArgs),
    /// Print a scene's size and its BVH's statistics.
    Info(InfoArgs),
    /// Add the part files of one render (`render --part K/N`) into its image: bit for bit
    /// one render of all the samples on the same device.
    Merge(MergeArgs),
    /// Render the jobs of a manifest (docs/batch.md): many meshes, turntable views, a
    /// transforms.json per folder; split across a job array with --shard.
    Batch(BatchArgs),
    /// List the Vulkan adapters; pick one with --adapter INDEX or a name substring.
    Adapters,
    /// Measure BVH build, ray and path-tracing throughput of both renderers.
    Bench(BenchArgs),
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum AccelArg {
    /// Hardware ray queries where the adapter offers them, else the software BVH.
    Auto,
    /// The software BVH walk, on any adapter.
    Software,
    /// Hardware ray queries; an error on an adapter without them.
    Hardware,
}

impl AccelArg {
    pub fn accel(self) -> Accel {
        match self {
            Self::Auto => Accel::Auto,
            Self::Software => Accel::Software,
            Self::Hardware => Accel::Hardware,
        }
    }
}

/// How an 8- or 16-bit image is formed ([`ViewTransform`]).
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ViewArg {
    /// The sRGB curve of the clamped radiance.
    Standard,
    /// Blender's Filmic, its default in 2.80–3.6.
    Filmic,
    /// Blender's AgX, its default since 4.0.
    Agx,
}

impl ViewArg {
    pub fn view(self) -> ViewTransform {
        match self {
            Self::Standard => ViewTransform::Standard,
            Self::Filmic => ViewTransform::Filmic,
            Self::Agx => ViewTransform::Agx,
        }
    }
}

/// Where a render runs: the options `render` and `batch` share.
#[derive(clap::Args)]
pub struct DeviceArgs {
    /// Renderer; by default the GPU on a hardware adapter, else the CPU (which is faster
    /// than a software adapter such as lavapipe, and makes the same image).
    #[arg(long, value_enum)]
    pub device: Option<Device>,
    /// GPU adapter: an index or a name substring from `meshtrace adapters` (or set WGPU_ADAPTER_NAME).
    #[arg(long)]
    pub adapter: Option<String>,
    /// How the GPU finds ray hits: hardware ray queries where the adapter offers them
    /// (auto, the default), the software BVH, or hardware ray queries (an error without them).
    #[arg(long, value_enum)]
    pub accel: Option<AccelArg>,
    /// Worker threads for the CPU path (default: one per core).
    #[arg(long)]
    pub threads: Option<usize>,
}

impl DeviceArgs {
    /// The request's device fields these options set.
    fn request(&self) -> RenderRequest {
        RenderRequest {
            device: self.device.map(|d| match d {
                Device::Cpu => DeviceChoice::Cpu,
                Device::Gpu => DeviceChoice::Gpu,
            }),
            adapter: self.adapter.clone(),
            accel: self.accel.map(AccelArg::accel),
            ..Default::default()
        }
    }
}

/// The backend `request` asks for, with the notice to print when the CPU was chosen for
/// want of a usable GPU (unless `quiet`).
fn backend(request: &RenderRequest, quiet: bool) -> Result<Backend> {
    request.validate().map_err(flag_error)?;
    let (backend, notice) = request.backend()?;
    if let Some(notice) = notice
        && !quiet
    {
        eprintln!("notice: {notice}");
    }
    Ok(backend)
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Device {
    /// The WGSL compute renderer on a Vulkan adapter.
    Gpu,
    /// The CPU reference path tracer, parallel over all cores.
    Cpu,
}

/// An axis for `--up`.
#[derive(Clone, Copy, ValueEnum)]
pub enum UpAxis {
    X,
    Y,
    Z,
}

impl UpAxis {
    fn up(self) -> Up {
        match self {
            UpAxis::X => Up::X,
            UpAxis::Y => Up::Y,
            UpAxis::Z => Up::Z,
        }
    }
}

/// A request's error as the command line says it: the field as its flag (`--max-depth`).
fn flag_error(e: RequestError) -> anyhow::Error {
    if e.message.starts_with("--") {
        return anyhow::anyhow!("{}", e.message);
    }
    let flag = match e.field {
        "environment" => "env".to_string(),
        field => field.replace('_', "-"),
    };
    anyhow::anyhow!("--{flag}: {}", e.message)
}

/// A pipeline's error as the command line says it: a request's field as its flag.
fn pipeline_error(e: PipelineError) -> anyhow::Error {
    match e {
        PipelineError::Request(e) => flag_error(e),
        e => e.into(),
    }
}

/// Prints a scene's warnings.
fn warn(message: &str) {
    eprintln!("warning: {message}");
}

fn set_threads(threads: Option<usize>) -> Result<()> {
    if let Some(n) = threads {
        if n == 0 {
            bail!("--threads must be at least 1");
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .context("cannot start the worker threads")?;
    }
    Ok(())
}

/// A render stopped by Ctrl-C, or by SIGTERM or SIGHUP (what Slurm and Kubernetes send on
/// a time-out or an eviction); the binary exits with status 130 for it.
#[derive(Debug, thiserror::Error)]
#[error("interrupted: {0}")]
pub struct Interrupted(String);

/// The process's peak resident memory, from /proc (Linux only).
pub(crate) fn peak_memory_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}
