//! The command line: argument types (clap) and the commands they run. Only this module and
//! `main` know about clap, indicatif (through `progress`) or anyhow.

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand, ValueEnum};
use glam::Vec3;
use meshtrace::bvh::BuildParams;
#[cfg(feature = "denoise")]
use meshtrace::denoise::Denoiser;
use meshtrace::film::{Aov, Film, Format, PartHeader};
use meshtrace::math::Aabb;
use meshtrace::render::backend::{Backend, DeviceChoice};
use meshtrace::render::digest::render_digest;
use meshtrace::render::gpu::{self, Accel, GpuError};
use meshtrace::render::{LIGHT_EMITTER, RenderJob, RenderScene, SKY_EMITTER};
use meshtrace::scene::studio::{BareOptions, Up};
use meshtrace::scene::{self, Scene, TextureFormat, builtin};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

mod batch;
mod merge;
mod preview;
mod progress;
pub use batch::{BatchArgs, batch};
pub use merge::{MergeArgs, merge};
use progress::Progress;

/// `println!` that returns an error instead of panicking when standard output is closed
/// (`meshtrace info scene.toml | head`); `main` ends quietly on a broken pipe.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout(), $($arg)*)?
    }};
}

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

#[derive(clap::Args)]
pub struct InfoArgs {
    /// Scene file, .obj mesh, .gltf/.glb file, or builtin:NAME.
    pub scene: PathBuf,
    /// Also write a heat map of the BVH cost of each camera ray (nodes visited plus
    /// triangles tested, the mean of 4 jittered rays a pixel) with a colour bar, as a PNG
    /// at the scene's image size.
    #[arg(long, value_name = "FILE")]
    pub heatmap: Option<PathBuf>,
    /// Also draw the BVH's boxes of level DEPTH (the root is 0; leaves above it too) over a
    /// quick render of the scene, as a PNG.
    #[arg(long, num_args = 2, value_names = ["DEPTH", "FILE"])]
    pub bounds: Option<Vec<String>>,
}

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
    fn accel(self) -> Accel {
        match self {
            Self::Auto => Accel::Auto,
            Self::Software => Accel::Software,
            Self::Hardware => Accel::Hardware,
        }
    }
}

/// The backend for `choice` with `--adapter` and `--accel`; `--accel hardware` with
/// `--device cpu` is an error (the CPU has only the software BVH).
fn choose_backend(
    choice: DeviceChoice,
    adapter: Option<&str>,
    accel: AccelArg,
) -> Result<(Backend, Option<String>)> {
    if choice == DeviceChoice::Cpu && accel == AccelArg::Hardware {
        bail!("--accel hardware needs the GPU renderer; drop --device cpu or use --accel auto");
    }
    Ok(Backend::choose(choice, adapter, accel.accel())?)
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
    /// (auto), the software BVH, or hardware ray queries (an error without them).
    #[arg(long, value_enum, default_value = "auto")]
    pub accel: AccelArg,
    /// Worker threads for the CPU path (default: one per core).
    #[arg(long)]
    pub threads: Option<usize>,
}

impl DeviceArgs {
    /// The backend these options choose, and the notice to print when the CPU was chosen
    /// for want of a usable GPU (unless `quiet`).
    fn backend(&self, quiet: bool) -> Result<Backend> {
        let choice = match self.device {
            None => DeviceChoice::Auto,
            Some(Device::Cpu) => DeviceChoice::Cpu,
            Some(Device::Gpu) => DeviceChoice::Gpu,
        };
        let (backend, notice) = choose_backend(choice, self.adapter.as_deref(), self.accel)?;
        if let Some(notice) = notice
            && !quiet
        {
            eprintln!("notice: {notice}");
        }
        Ok(backend)
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Device {
    /// The WGSL compute renderer on a Vulkan adapter.
    Gpu,
    /// The CPU reference path tracer, parallel over all cores.
    Cpu,
}

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Scene file (.toml), bare mesh (.obj, .gltf, .glb), or builtin:NAME; the built-in
    /// scenes are builtin:cornell (the Cornell box, the default when omitted).
    pub scene: Option<PathBuf>,
    /// Output image; the extension picks the format (.png .jpg .bmp .exr .hdr).
    #[arg(short, long, default_value = "render.png")]
    pub output: PathBuf,
    /// Samples per pixel [scene's [render] spp; else 64]. The flag wins over the scene
    /// file, as for every setting below.
    #[arg(long)]
    pub spp: Option<u32>,
    /// Longest path in segments from the camera, 1 = emitters seen directly [scene's
    /// [render] max_depth; else 8].
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Image width in pixels [scene's [render] width; else 640].
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels [scene's [render] height; else 480].
    #[arg(long)]
    pub height: Option<u32>,
    /// Seed of the random sequences; the same seed gives the same image [scene's [render]
    /// seed; else 0].
    #[arg(long)]
    pub seed: Option<u32>,
    /// Also trace light subpaths through the scene's specular materials (glass, mirrors),
    /// for caustics with far less noise; off renders with the path tracer alone [scene's
    /// [render] caustics; else on].
    #[arg(long, value_name = "on|off", value_parser = clap::builder::BoolishValueParser::new())]
    pub caustics: Option<bool>,
    /// Paths each camera sample branches into at its first hit: the samples of indirect
    /// light per camera sample (1 to 64; powers of two stratify best) [scene's [render]
    /// branches; else 4, or 1 in a render with caustic light subpaths].
    #[arg(long)]
    pub branches: Option<u32>,
    #[command(flatten)]
    pub on: DeviceArgs,
    /// Print nothing but warnings and errors.
    #[arg(short, long)]
    pub quiet: bool,
    /// Also write the image every this many seconds while rendering.
    #[arg(long, value_name = "SECONDS")]
    pub checkpoint: Option<f64>,
    /// Render outputs to add, comma-separated: depth, normal, albedo, alpha, object_id,
    /// material_id, bvh_cost. Extra channels of an .exr output; beside any other output,
    /// one <stem>.aovs.exr.
    #[arg(long, value_name = "LIST")]
    pub aov: Option<String>,
    /// Write an RGBA PNG whose alpha is the coverage; the sky still lights the scene but
    /// is not seen directly.
    #[arg(long)]
    pub transparent: bool,
    /// On Ctrl-C or SIGTERM, write no image (by default the samples finished so far are
    /// written; checkpoints already written stay).
    #[arg(long)]
    pub no_partial: bool,
    /// The up axis of a bare mesh (.obj, .gltf, .glb). By default an OBJ whose extent is
    /// largest along Z is taken as Z-up, anything else as Y-up.
    #[arg(long, value_enum)]
    pub up: Option<UpAxis>,
    /// Light the scene or the bare mesh with this equirectangular image (.hdr or .exr)
    /// instead of its own sky.
    #[arg(long, value_name = "FILE")]
    pub env: Option<PathBuf>,
    /// Denoise the image with Intel Open Image Denoise before writing it (checkpoints are
    /// written as rendered). Needs a build with `--features denoise`.
    #[arg(long)]
    pub denoise: bool,
    /// Render only part K of N (K from 0) of the samples, into an .exr part file that
    /// `meshtrace merge` combines with the others: the merged image has the bits of one
    /// render of all the samples on the same device. `auto` and `auto/N` take K (and N)
    /// from a Slurm job array or a Kubernetes Indexed Job, as `batch --shard` does.
    #[arg(long, value_name = "K/N|auto|auto/N")]
    pub part: Option<String>,
    /// Show the render converging in a window: the tiles being traced, samples and rays per
    /// second, elapsed time and ETA; keys 1-5 (or Tab) switch between the image and its
    /// albedo, normal, depth and BVH-cost views, b and -/+ draw a level of BVH boxes, [ and ]
    /// set the exposure, s saves the view as <stem>.<view>.png, Esc closes. Closing the
    /// window ends the render as Ctrl-C does; after a finished render the window stays open
    /// until closed. The output is the same as without the window.
    #[arg(long)]
    pub preview: bool,
}

/// `--part K/N` (K from 0, below N), or `auto`/`auto/N` from a job array's environment
/// (as `batch --shard`).
fn parse_part(text: &str) -> Result<(u32, u32)> {
    batch::resolve_shard(text, "--part", &|name| std::env::var(name).ok())
}

/// What `--denoise` says in a build without the `denoise` feature.
#[cfg(not(feature = "denoise"))]
const NO_DENOISE: &str = "--denoise needs a build with Open Image Denoise: `pip install pyoidn==2.5.1.0`, \
     set OIDN_DIR to its pyoidn/oidn folder, then `cargo build --release --features denoise` \
     (README.md, \"Denoising (optional)\")";

/// Without the `denoise` feature there is no denoiser: [`denoiser`] refuses `--denoise`.
#[cfg(not(feature = "denoise"))]
enum Denoiser {}

#[cfg(not(feature = "denoise"))]
impl Denoiser {
    fn denoise_film(&self, _film: &mut Film) -> Result<()> {
        match *self {}
    }
}

/// The denoiser `--denoise` asks for, made before the render so that a missing or unusable
/// Open Image Denoise fails at once; `None` without `--denoise`.
fn denoiser(wanted: bool, threads: Option<usize>) -> Result<Option<Denoiser>> {
    if !wanted {
        return Ok(None);
    }
    #[cfg(feature = "denoise")]
    return Ok(Some(match threads {
        Some(n) => Denoiser::with_threads(n)?,
        None => Denoiser::new()?,
    }));
    #[cfg(not(feature = "denoise"))]
    {
        let _ = threads;
        bail!("{NO_DENOISE}");
    }
}

/// An axis for `--up`.
#[derive(Clone, Copy, ValueEnum)]
pub enum UpAxis {
    X,
    Y,
    Z,
}

/// Loads a scene given on the command line: a path, or `builtin:NAME`; a bare mesh with
/// `options`.
fn load(path: &Path, options: &BareOptions) -> Result<Scene> {
    let text = path.to_string_lossy();
    let scene = match text.strip_prefix("builtin:") {
        Some(_) if options.up.is_some() => {
            bail!("--up: applies to a bare mesh (.obj, .gltf, .glb), not to a built-in scene")
        }
        Some(name) => builtin::load_builtin(name)?,
        None => scene::load::load_scene_with(path, &scene::source::Fs, options)?,
    };
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
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

pub fn render(args: &RenderArgs) -> Result<()> {
    let began = Instant::now();
    let part = args.part.as_deref().map(parse_part).transpose()?;
    if part.is_some() {
        if args.denoise {
            bail!(
                "--denoise applies to a whole image: denoise when merging the parts, not in a part"
            );
        }
        if Format::from_path(&args.output)? != Format::Exr {
            bail!(
                "{}: --part writes an .exr part file (it carries the exact sums `meshtrace merge` adds); give a .exr output",
                args.output.display()
            );
        }
    }
    let denoiser = denoiser(args.denoise, args.on.threads)?;
    // The display first: without one, --preview fails before any work.
    let window = if args.preview {
        Some(preview::Preview::open()?)
    } else {
        None
    };
    let aovs = match &args.aov {
        Some(list) => Aov::parse_list(list).context("--aov")?,
        None => Vec::new(),
    };
    Film::check_writable(&args.output, args.transparent && part.is_none())?;
    if !aovs.is_empty() && part.is_none() && Format::from_path(&args.output)? != Format::Exr {
        Film::check_writable(&Film::aov_path(&args.output), false)?;
    }
    set_threads(args.on.threads)?;
    let options = BareOptions {
        up: args.up.map(|u| match u {
            UpAxis::X => Up::X,
            UpAxis::Y => Up::Y,
            UpAxis::Z => Up::Z,
        }),
    };
    let default = PathBuf::from(format!("builtin:{}", builtin::DEFAULT));
    let mut scene = load(args.scene.as_ref().unwrap_or(&default), &options)?;
    if let Some(env) = &args.env {
        scene::load::replace_environment(&mut scene, env)
            .map_err(|message| anyhow::anyhow!("--env: {message}"))?;
    }
    let s = &mut scene.settings;
    s.width = args.width.unwrap_or(s.width);
    s.height = args.height.unwrap_or(s.height);
    s.spp = args.spp.unwrap_or(s.spp);
    s.max_depth = args.max_depth.unwrap_or(s.max_depth);
    s.seed = args.seed.unwrap_or(s.seed);
    s.caustics = args.caustics.unwrap_or(s.caustics);
    s.branches = args.branches.or(s.branches);
    if let Err((field, message)) = s.validate() {
        bail!("--{}: {message}", field.replace('_', "-"));
    }
    let settings = *s;
    if let Some((_, n)) = part
        && n > settings.spp
    {
        bail!(
            "--part: {n} parts of {} spp would leave some empty; use at most {} parts",
            settings.spp,
            settings.spp
        );
    }
    let rs = RenderScene::new(&scene, &BuildParams::default())?;
    // The denoiser is guided by the first surface's albedo and normal, which the film then
    // holds whether or not they are written.
    let saved = Aov::mask(&aovs);
    let guides = if denoiser.is_some() {
        Aov::Albedo.bit() | Aov::Normal.bit()
    } else {
        0
    };
    let mut job = RenderJob::new(settings).with_aovs(saved | guides, args.transparent);
    let samples = match part {
        Some((k, n)) => PartHeader::range(k, n, settings.spp),
        None => 0..settings.spp,
    };
    job = job.with_samples(samples.clone());
    let backend = args.on.backend(args.quiet)?;
    // A part file records which render it belongs to; any other output is an image.
    let header = part.map(|(index, count)| PartHeader {
        index,
        count,
        start: samples.start,
        end: samples.end,
        spp: settings.spp,
        seed: settings.seed,
        device: backend.device_id(),
        digest: render_digest(&rs, &job),
    });
    let output = args.output.clone();
    let write = Arc::new(move |film: &Film| match &header {
        Some(h) => film.save_part(&output, h),
        None => film.save(&output),
    });
    let cancel = Arc::new(AtomicBool::new(false));
    job.cancel = Some(cancel.clone());
    // Ctrl-C, SIGTERM and SIGHUP (ctrlc's `termination` feature) end the render after the
    // current pass, which is then written with its sample count.
    let signalled = cancel.clone();
    ctrlc::set_handler(move || {
        if signalled.swap(true, Ordering::SeqCst) {
            // A second signal: stop now, without waiting for the pass.
            std::process::exit(130);
        }
    })
    .context("cannot install the Ctrl-C and SIGTERM handler")?;
    if let Some(every) = args.checkpoint {
        if !(every > 0.0 && every.is_finite()) {
            bail!("--checkpoint must be a positive number of seconds");
        }
        let write = write.clone();
        job.checkpoint = Some((
            Duration::from_secs_f64(every),
            Arc::new(move |film: &Film| {
                let mut film = film.clone();
                film.saved_aovs = saved;
                if let Err(e) = write(&film) {
                    eprintln!("warning: checkpoint not written: {e}");
                }
            }),
        ));
    }
    let wanted = samples.end - samples.start;
    // With --preview, the job reports to the window, which runs the render beside it.
    let shown = window.map(|window| {
        let setup = preview::Setup {
            scene: &rs,
            settings,
            spp: wanted,
            title: format!(
                "{} on {}",
                args.scene.as_ref().unwrap_or(&default).display(),
                backend.name()
            ),
            output: args.output.clone(),
            gathered: job.aovs,
            cancel,
            pixels_every: match backend {
                Backend::Cpu => Duration::ZERO,
                Backend::Gpu(_) => Duration::from_millis(200),
            },
        };
        let (watch, picture) = window.watch(&setup);
        job.watch = Some(watch);
        (window, setup, picture)
    });
    let prepared = Prepared {
        args,
        part,
        rs: &rs,
        job: &job,
        backend: &backend,
        denoiser,
        write,
        began,
        saved,
    };
    match shown {
        None => prepared.finish(),
        Some((window, setup, picture)) => window.run(setup, picture, move || prepared.finish()),
    }
}

/// What writes a render's film: as an image or as a part file.
type WriteFn = Arc<dyn Fn(&Film) -> Result<(), meshtrace::film::FilmError> + Send + Sync>;

/// A render set up and ready to run: what [`Prepared::finish`] needs.
struct Prepared<'a> {
    args: &'a RenderArgs,
    /// `--part`, parsed.
    part: Option<(u32, u32)>,
    rs: &'a RenderScene,
    job: &'a RenderJob,
    backend: &'a Backend,
    denoiser: Option<Denoiser>,
    write: WriteFn,
    /// When the command began (for the set-up time it reports).
    began: Instant,
    /// The AOVs asked for, which the output holds.
    saved: u32,
}

impl Prepared<'_> {
    /// The rest of `render`: the render itself with its progress line, the denoiser, the
    /// output (or, when stopped, the samples so far) and the summary.
    fn finish(self) -> Result<()> {
        let Prepared {
            args,
            part,
            rs,
            job,
            backend,
            denoiser,
            write,
            began,
            saved,
        } = self;
        let settings = job.settings;
        let samples = job.samples.clone();
        let wanted = samples.end - samples.start;
        let progress = Progress::new(settings.width, settings.height, wanted, args.quiet);
        // What a split render pays again in every part: loading the scene, building its BVH and
        // opening the device.
        let prepared = began.elapsed().as_secs_f64();
        let start = Instant::now();
        let mut film = backend.render(rs, job, &|n| progress.inc(n))?;
        film.saved_aovs = saved;
        let rays = film.rays();
        let seconds = start.elapsed().as_secs_f64();
        progress.finish();
        // The denoised image replaces the radiance, in the complete and the interrupted film.
        if let Some(d) = &denoiser
            && film.samples > 0
            && !(film.samples < wanted && args.no_partial)
        {
            d.denoise_film(&mut film)?;
        }
        if film.samples < wanted {
            let what = if args.no_partial {
                format!(
                    "at {} of {wanted} spp; nothing written (--no-partial)",
                    film.samples
                )
            } else if film.samples == 0 {
                "before the first pass finished; nothing written".to_string()
            } else {
                write(&film)?;
                format!(
                    "wrote {} with {} of {wanted} spp",
                    args.output.display(),
                    film.samples,
                )
            };
            return Err(Interrupted(what).into());
        }
        write(&film)?;
        if !args.quiet {
            let what = match part {
                Some((k, n)) => format!(
                    "part {k}/{n} (samples {}..{} of {})",
                    samples.start, samples.end, settings.spp
                ),
                None => format!("{} spp", settings.spp),
            };
            eprintln!(
                "{}x{} at {what} on {} in {:.2} s ({:.2} Mrays/s; {:.2} s to load, build and set up before) -> {}",
                settings.width,
                settings.height,
                backend.name(),
                seconds,
                rays as f64 / seconds / 1e6,
                prepared,
                args.output.display()
            );
        }
        Ok(())
    }
}

pub fn info(args: &InfoArgs) -> Result<()> {
    let path = args.scene.as_path();
    let level = match args.bounds.as_deref() {
        Some([depth, file]) => {
            let depth: u32 = depth.parse().with_context(|| {
                format!("--bounds: `{depth}` is not a tree level (0 is the root)")
            })?;
            Some((depth, PathBuf::from(file)))
        }
        _ => None,
    };
    for out in args.heatmap.iter().chain(level.as_ref().map(|b| &b.1)) {
        if Format::from_path(out)? != Format::Png {
            bail!(
                "{}: figures are written as PNG; give a .png file",
                out.display()
            );
        }
        Film::check_writable(out, false)?;
    }
    let scene = load(path, &BareOptions::default())?;
    let rs = RenderScene::new(&scene, &BuildParams::default())?;
    let st = &rs.bvh.stats;
    let name = scene.path.as_deref().unwrap_or(path).display();
    out!("scene        {name}");
    out!("triangles    {}", st.triangles);
    out!("vertices     {}", scene.mesh.positions.len());
    out!("materials    {}", scene.materials.len());
    let bounds = rs.bvh.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds());
    if bounds.is_empty() {
        out!("bounds       empty");
    } else {
        let v = |p: Vec3| format!("({:.4}, {:.4}, {:.4})", p.x, p.y, p.z);
        out!("bounds       {} to {}", v(bounds.min), v(bounds.max));
        out!("centre       {}", v(bounds.center()));
        out!("size         {}", v(bounds.extent()));
    }
    let sky = rs.sky_pmf > 0.0;
    let punctual = rs
        .emitters
        .iter()
        .filter(|&&e| e & LIGHT_EMITTER != 0 && e != SKY_EMITTER)
        .count();
    let tris = rs.emitters.len() - punctual - sky as usize;
    out!(
        "emitters     {tris} triangles, {} point, spot or directional lights{}",
        punctual,
        if sky { " and the sky" } else { "" }
    );
    print_textures(&scene)?;
    out!(
        "bvh build    {:.2} ms ({:.2} M triangles/s)",
        st.build_seconds * 1e3,
        st.triangles as f64 / st.build_seconds.max(1e-9) / 1e6
    );
    out!("sah cost     {:.3}", st.sah_cost);
    out!(
        "nodes        {} ({} leaves, {} bytes)",
        st.nodes,
        st.leaves,
        st.nodes * 32
    );
    out!("depth        {}", st.depth);
    let hist: Vec<String> = st
        .leaf_sizes
        .iter()
        .enumerate()
        .filter(|(_, n)| **n > 0)
        .map(|(k, n)| format!("{k}:{n}"))
        .collect();
    out!("leaf sizes   {}", hist.join(" "));
    if let Some(file) = &args.heatmap {
        let s = &scene.settings;
        let costs = meshtrace::figures::ray_costs(&rs, s);
        meshtrace::figures::write_heatmap(file, s.width, s.height, &costs)?;
        let mean = costs.iter().map(|&c| c as f64).sum::<f64>() / costs.len().max(1) as f64;
        let max = costs.iter().copied().fold(0.0f32, f32::max);
        out!(
            "heat map     {} (nodes + triangles per camera ray: mean {mean:.1}, max {max:.0})",
            file.display()
        );
    }
    if let Some((depth, file)) = &level {
        let n = meshtrace::figures::write_bounds(file, &rs, &scene.settings, *depth)?;
        out!("bounds       {} (level {depth}: {n} boxes)", file.display());
    }
    if let Some(kib) = peak_memory_kib() {
        out!("peak memory  {:.1} MiB", kib as f64 / 1024.0);
    }
    Ok(())
}

/// The scene's textures: how many, the distinct images they read, and the memory their
/// texels take (the same on the host and the device), then one line per image.
fn print_textures(scene: &Scene) -> Result<()> {
    let t = &scene.textures;
    let mut images: Vec<(u32, usize)> = Vec::new();
    for (k, r) in t.records.iter().enumerate() {
        if !images.iter().any(|&(offset, _)| offset == r.offset) {
            images.push((r.offset, k));
        }
    }
    out!(
        "textures     {} ({} images, {})",
        t.records.len(),
        images.len(),
        mebibytes(t.texels.len() as u64 * 4)
    );
    for (_, k) in images {
        let r = &t.records[k];
        let (kind, bytes) = if r.format == TextureFormat::RGBA32F {
            ("RGBA 32-bit float", 16)
        } else {
            ("RGBA 8-bit", 4)
        };
        out!(
            "  {}  {}x{} {kind}, {}",
            t.names[k],
            r.width,
            r.height,
            mebibytes(r.width as u64 * r.height as u64 * bytes)
        );
    }
    Ok(())
}

fn mebibytes(bytes: u64) -> String {
    format!("{:.2} MiB", bytes as f64 / (1024.0 * 1024.0))
}

/// The process's peak resident memory, from /proc (Linux only).
fn peak_memory_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

pub fn adapters() -> Result<()> {
    let list = gpu::list_adapters();
    if list.is_empty() {
        bail!("{}", GpuError::NoAdapter);
    }
    for a in list {
        out!(
            "{}  {}  ({}, {}, {}; {})",
            a.index,
            a.name,
            a.backend,
            a.device_type,
            a.driver,
            if a.ray_query {
                "ray queries"
            } else {
                "no ray queries"
            }
        );
    }
    Ok(())
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
    let (backend, notice) = choose_backend(choice, args.adapter.as_deref(), args.accel)?;
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
                let scene = load(path, &BareOptions::default())?;
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
