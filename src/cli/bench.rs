//! `meshtrace bench`: BVH build, ray and path-tracing throughput of both renderers.

use super::{AccelArg, out, pipeline_error, set_threads, warn};
use anyhow::{Result, bail};
use clap::ValueEnum;
use meshtrace::pipeline;
use meshtrace::render::backend::{Backend, DeviceChoice};
use meshtrace::request::RenderRequest;
use std::path::PathBuf;

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BenchDevice {
    Cpu,
    Gpu,
    All,
}

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scene files, .obj meshes, .gltf/.glb files, builtin:NAME or generated:terrain; by
    /// default the built-in Cornell box, the Stanford bunny (from ../shared/meshes) and a
    /// 2M-triangle terrain.
    pub scenes: Vec<PathBuf>,
    /// Devices to measure; by default the CPU, and the GPU where the render rule picks
    /// it (a hardware adapter, or one named by --adapter). `gpu` and `all` use a software
    /// adapter too.
    #[arg(long, value_enum)]
    pub device: Option<BenchDevice>,
    /// GPU adapter: an index or a name substring from `meshtrace adapters`.
    #[arg(long)]
    pub adapter: Option<String>,
    /// How the GPU finds ray hits: hardware ray queries where the adapter offers them
    /// (auto), the software BVH, or hardware ray queries (an error without them).
    #[arg(long, value_enum, default_value = "auto")]
    pub accel: AccelArg,
    /// Worker threads for the CPU path (default: one per core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Timed repeats per measure, after one warm-up run.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Image size of the ray and path measures.
    #[arg(long, default_value_t = 512)]
    pub width: u32,
    #[arg(long, default_value_t = 512)]
    pub height: u32,
    /// Samples per pixel of the path-tracing measure.
    #[arg(long, default_value_t = 4)]
    pub spp: u32,
    /// Print one JSON array instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Also write each scene's triangles and ray sets (primary, primary_fill, incoherent,
    /// shadow) into this folder, as raw
    /// little-endian floats (see bench/README.md), for comparisons with other ray tracers.
    #[arg(long, value_name = "DIR")]
    pub rays_out: Option<PathBuf>,
}

pub fn bench(args: &BenchArgs) -> Result<()> {
    set_threads(args.threads)?;
    if args.width == 0 || args.height == 0 || args.spp == 0 || args.repeats == 0 {
        bail!("--width, --height, --spp and --repeats must be at least 1");
    }
    if let Some(dir) = &args.rays_out
        && !dir.is_dir()
    {
        bail!("--rays-out {}: not a folder", dir.display());
    }
    let mut scenes: Vec<PathBuf> = args.scenes.clone();
    if scenes.is_empty() {
        scenes.push(PathBuf::from("builtin:cornell"));
        let bunny = PathBuf::from("../shared/meshes/stanford-bunny.obj");
        if bunny.exists() {
            scenes.push(bunny);
        } else {
            eprintln!("notice: {} absent; skipping the bunny", bunny.display());
        }
        scenes.push(PathBuf::from("generated:terrain"));
    }
    let choice = match args.device {
        None => DeviceChoice::Auto,
        Some(BenchDevice::Cpu) => DeviceChoice::Cpu,
        Some(BenchDevice::Gpu | BenchDevice::All) => DeviceChoice::Gpu,
    };
    let request = RenderRequest {
        device: Some(choice),
        adapter: args.adapter.clone(),
        accel: Some(args.accel.accel()),
        ..Default::default()
    };
    request.validate().map_err(super::flag_error)?;
    let (backend, notice) = request.backend()?;
    if let Some(notice) = notice {
        eprintln!("notice: {notice}; measuring the CPU only");
    }
    let gpu = match backend {
        Backend::Gpu(ctx) => Some(*ctx),
        Backend::Cpu => None,
    };
    let opts = meshtrace::bench::BenchOptions {
        repeats: args.repeats,
        width: args.width,
        height: args.height,
        spp: args.spp,
    };
    if !args.json {
        eprintln!(
            "CPU: {} ({} threads){}",
            cpu_name(),
            rayon::current_num_threads(),
            gpu.as_ref().map_or(String::new(), |g| format!(
                "; GPU: {} ({})",
                g.adapter.name,
                g.accel_name()
            ))
        );
        out!(
            "{:<22} {:<6} {:<16} {:>12} {:>18}  unit",
            "scene",
            "device",
            "measure",
            "median",
            "min..max"
        );
    }
    let mut all = Vec::new();
    for path in &scenes {
        let text = path.to_string_lossy();
        let (name, scene) = match text.strip_prefix("generated:") {
            Some("terrain") => ("terrain-2M".to_string(), meshtrace::bench::terrain(1000)),
            Some(other) => bail!("unknown generated scene `{other}`; there is: terrain"),
            None => {
                let scene =
                    pipeline::load(path, &RenderRequest::default()).map_err(pipeline_error)?;
                for w in &scene.warnings {
                    warn(w);
                }
                let name = path
                    .file_stem()
                    .map_or(text.to_string(), |s| s.to_string_lossy().into_owned());
                (name.trim_start_matches("builtin:").to_string(), scene)
            }
        };
        let measures = meshtrace::bench::bench_scene(
            &name,
            &scene,
            gpu.as_ref(),
            args.device != Some(BenchDevice::Gpu),
            &opts,
            args.rays_out.as_deref(),
        )?;
        if !args.json {
            for m in &measures {
                out!(
                    "{:<22} {:<6} {:<16} {:>12.3} {:>18}  {}",
                    m.scene,
                    m.device,
                    m.measure,
                    m.median,
                    format!("{:.3}..{:.3}", m.min, m.max),
                    m.unit
                );
            }
            // The comparison the numbers are for, from medians of this one run.
            for g in measures.iter().filter(|m| m.device == "gpu") {
                if let Some(c) = measures
                    .iter()
                    .find(|c| c.device == "cpu" && c.measure == g.measure && c.median > 0.0)
                {
                    out!(
                        "{:<22} {:<6} {:<16} {:>12.3} {:>18}  GPU/CPU",
                        g.scene,
                        "ratio",
                        g.measure,
                        g.median / c.median,
                        ""
                    );
                }
            }
        }
        all.extend(measures);
    }
    if args.json {
        out!("{}", meshtrace::bench::to_json(&all));
    }
    Ok(())
}

/// The CPU's model name, from /proc/cpuinfo (Linux), for labelling results.
fn cpu_name() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|n| n.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}
