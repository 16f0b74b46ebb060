//! `meshtrace render`: the flags made into a [`RenderRequest`], the library's
//! [`Prepared`] render run with a progress line, Ctrl-C handling, checkpoints and the
//! optional preview window, and the image (or part file) written.

use super::{
    DeviceArgs, Interrupted, UpAxis, ViewArg, backend, batch, flag_error, pipeline_error, preview,
    progress::Progress, set_threads, warn,
};
use anyhow::{Context, Result, bail};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use meshtrace::film::{Aov, DisplayTransform, Film, Format};
use meshtrace::pipeline::Prepared;
use meshtrace::render::backend::Backend;
use meshtrace::request::{Part, RenderRequest};
use meshtrace::scene::builtin;
use meshtrace::scene::lighting::Lighting;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

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
    #[arg(long, value_name = "on|off", value_parser = on_off())]
    pub caustics: Option<bool>,
    /// Paths each camera sample branches into at its first hit: the samples of indirect
    /// light per camera sample (1 to 64; powers of two stratify best) [scene's [render]
    /// branches; else 4, or 1 in a render with caustic light subpaths].
    #[arg(long)]
    pub branches: Option<u32>,
    /// The side in pixels of the square over which a pixel's camera samples fall (a box
    /// filter), 0 to 10: 0 puts every sample through the pixel's centre [scene's [render]
    /// filter_width; else 1].
    #[arg(long, value_name = "PIXELS")]
    pub filter_width: Option<f32>,
    /// The most indirect diffuse bounces of a path, as Cycles' `diffuse_bounces`: 0 lights
    /// diffuse surfaces directly alone [scene's [render] diffuse_bounces; else no limit].
    #[arg(long, value_name = "N")]
    pub diffuse_bounces: Option<u32>,
    /// The most glossy bounces, as Cycles' `glossy_bounces` [scene's [render]
    /// glossy_bounces; else no limit].
    #[arg(long, value_name = "N")]
    pub glossy_bounces: Option<u32>,
    /// The most transmission bounces, as Cycles' `transmission_bounces` [scene's [render]
    /// transmission_bounces; else no limit].
    #[arg(long, value_name = "N")]
    pub transmission_bounces: Option<u32>,
    #[command(flatten)]
    pub on: DeviceArgs,
    /// Print nothing but warnings and errors.
    #[arg(short, long)]
    pub quiet: bool,
    /// Also write the image every this many seconds while rendering.
    #[arg(long, value_name = "SECONDS")]
    pub checkpoint: Option<f64>,
    /// Render outputs to add, comma-separated: depth, normal, albedo, alpha, object_id,
    /// material_id, bvh_cost, diffuse_color. Extra channels of an .exr output; beside any other output,
    /// one <stem>.aovs.exr.
    #[arg(long, value_name = "LIST")]
    pub aov: Option<String>,
    /// Write an RGBA PNG whose alpha is the coverage; the sky still lights the scene but
    /// is not seen directly.
    #[arg(long)]
    pub transparent: bool,
    /// Bits per channel of a PNG output: 8, or 16 for pipelines that keep the finer
    /// gradients (alpha too, with --transparent).
    #[arg(long, value_name = "8|16")]
    pub bit_depth: Option<u32>,
    /// How a PNG, WebP, JPEG or BMP output is formed from the radiance: `standard` (the
    /// sRGB curve), or Blender's `filmic` (its default in 2.80–3.6) or `agx` (4.0 and
    /// later), read from Blender's LUTs (docs/outputs.md, "View transforms").
    #[arg(long, value_enum)]
    pub view_transform: Option<ViewArg>,
    /// Trace camera rays alone, for the AOVs (depth, normal, alpha, ids) without path
    /// tracing; the image is the first surface's base colour, unlit. A few samples a pixel
    /// antialias the AOVs.
    #[arg(long)]
    pub geometry_only: bool,
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
    /// Light the scene or the bare mesh with a lighting preset instead of its own sky and
    /// lights: `area`, `suns`, `uniform`, `studio`, or a TOML inline table with its
    /// parameters, `'{ preset = "suns", count = 6, seed = 2 }'` (docs/scene-format.md).
    #[arg(long, value_name = "PRESET|TABLE")]
    pub lighting: Option<String>,
    /// Scale every texture (environment maps included) whose larger side exceeds N texels
    /// down to N on that side, keeping its aspect ratio, with a warning for each: for a
    /// scene whose textures are too large for the GPU, or to save memory.
    #[arg(long, value_name = "N")]
    pub max_texture_size: Option<u32>,
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

/// `--lighting`: a preset's name, or a TOML inline table of a preset and its parameters.
fn parse_lighting(text: &str) -> Result<Lighting, String> {
    let value = if text.trim_start().starts_with('{') {
        toml::from_str::<toml::Table>(&format!("lighting = {text}"))
            .map_err(|e| e.message().replace('\n', " "))?
            .remove("lighting")
            .unwrap_or(toml::Value::Boolean(false))
    } else {
        toml::Value::Table(toml::Table::from_iter([(
            "preset".to_string(),
            toml::Value::String(text.to_string()),
        )]))
    };
    value
        .try_into()
        .map_err(|e: toml::de::Error| e.message().to_string())
}

/// `on` or `off`, listed as such in `--help`.
fn on_off() -> impl TypedValueParser<Value = bool> {
    PossibleValuesParser::new(["on", "off"]).map(|v| v == "on")
}

/// `--part K/N` (K from 0, below N), or `auto`/`auto/N` from a job array's environment
/// (as `batch --shard`).
fn parse_part(text: &str) -> Result<(u32, u32)> {
    batch::resolve_shard(text, "--part", &|name| std::env::var(name).ok())
}

impl RenderArgs {
    /// The request these flags make; `part` is `--part`, resolved.
    fn request(&self, part: Option<(u32, u32)>) -> Result<RenderRequest> {
        let aov = match &self.aov {
            Some(list) => Some(Aov::parse_list(list).context("--aov")?),
            None => None,
        };
        let lighting = (self.lighting.as_deref())
            .map(parse_lighting)
            .transpose()
            .map_err(|e| anyhow::anyhow!("--lighting: {e}"))?;
        Ok(RenderRequest {
            width: self.width,
            height: self.height,
            spp: self.spp,
            max_depth: self.max_depth,
            seed: self.seed,
            caustics: self.caustics,
            branches: self.branches,
            filter_width: self.filter_width,
            diffuse_bounces: self.diffuse_bounces,
            glossy_bounces: self.glossy_bounces,
            transmission_bounces: self.transmission_bounces,
            aov,
            transparent: Some(self.transparent),
            bit_depth: self.bit_depth,
            view_transform: self.view_transform.map(ViewArg::view),
            geometry_only: Some(self.geometry_only),
            up: self.up.map(UpAxis::up),
            environment: self.env.clone(),
            lighting,
            max_texture_size: self.max_texture_size,
            part: part.map(|(index, count)| Part { index, count }),
            denoise: Some(self.denoise),
            ..self.on.request()
        })
    }
}

pub fn render(args: &RenderArgs) -> Result<()> {
    let began = Instant::now();
    let part = args.part.as_deref().map(parse_part).transpose()?;
    let request = args.request(part)?;
    request.validate().map_err(flag_error)?;
    if part.is_some() && Format::from_path(&args.output)? != Format::Exr {
        bail!(
            "{}: --part writes an .exr part file (it carries the exact sums `meshtrace merge` adds); give a .exr output",
            args.output.display()
        );
    }
    // The display first: without one, --preview fails before any work.
    let window = if args.preview {
        Some(preview::Preview::open()?)
    } else {
        None
    };
    Film::check_writable(&args.output, args.transparent && part.is_none())?;
    // A part holds sums; `merge` forms the image.
    let view = match part {
        None => {
            Film::check_encoding(
                &args.output,
                Format::from_path(&args.output)?,
                request.bit_depth(),
                request.view_transform(),
            )?;
            DisplayTransform::load(request.view_transform())?
        }
        Some(_) => DisplayTransform::default(),
    };
    if request.aov_mask() != 0 && part.is_none() && Format::from_path(&args.output)? != Format::Exr
    {
        Film::check_writable(&Film::aov_path(&args.output), false)?;
    }
    set_threads(args.on.threads)?;
    let default = PathBuf::from(format!("builtin:{}", builtin::DEFAULT));
    let input = args.scene.as_ref().unwrap_or(&default);
    let mut prepared = Prepared::new(input, &request, &warn).map_err(pipeline_error)?;
    let backend = backend(&request, args.quiet)?;
    // A part file records which render it belongs to; any other output is an image.
    let header = prepared.part_header(&backend);
    let output = args.output.clone();
    let depth = request.bit_depth();
    let write = Arc::new(move |film: &Film| match &header {
        Some(h) => film.save_part(&output, h),
        None => film.save_as(&output, depth, &view),
    });
    let cancel = Arc::new(AtomicBool::new(false));
    prepared.job.cancel = Some(cancel.clone());
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
    let saved = prepared.saved_aovs();
    if let Some(every) = args.checkpoint {
        if !(every > 0.0 && every.is_finite()) {
            bail!("--checkpoint must be a positive number of seconds");
        }
        let write = write.clone();
        prepared.job.checkpoint = Some((
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
    // With --preview, the job reports to the window, which runs the render beside it.
    let shown = match window {
        None => None,
        Some(window) => {
            let (watch, picture) =
                window.watch(&preview_setup(&prepared, args, input, &backend, &cancel));
            prepared.job.watch = Some(watch);
            Some((window, picture))
        }
    };
    let run = Run {
        args,
        prepared: &prepared,
        backend: &backend,
        write,
        began,
    };
    match shown {
        None => run.finish(),
        Some((window, picture)) => window.run(
            preview_setup(&prepared, args, input, &backend, &cancel),
            picture,
            move || run.finish(),
        ),
    }
}

/// What the preview window shows of a render.
fn preview_setup<'a>(
    prepared: &'a Prepared,
    args: &RenderArgs,
    input: &std::path::Path,
    backend: &Backend,
    cancel: &Arc<AtomicBool>,
) -> preview::Setup<'a> {
    preview::Setup {
        scene: &prepared.scene,
        settings: prepared.job.settings,
        spp: prepared.job.samples.end - prepared.job.samples.start,
        title: format!("{} on {}", input.display(), backend.name()),
        output: args.output.clone(),
        gathered: prepared.job.aovs,
        cancel: cancel.clone(),
        pixels_every: match backend {
            Backend::Cpu => Duration::ZERO,
            Backend::Gpu(_) => Duration::from_millis(200),
        },
    }
}

/// What writes a render's film: as an image or as a part file.
type WriteFn = Arc<dyn Fn(&Film) -> Result<(), meshtrace::film::FilmError> + Send + Sync>;

/// A render set up and ready to run: what [`Run::finish`] needs.
struct Run<'a> {
    args: &'a RenderArgs,
    prepared: &'a Prepared,
    backend: &'a Backend,
    write: WriteFn,
    /// When the command began (for the set-up time it reports).
    began: Instant,
}

impl Run<'_> {
    /// The rest of `render`: the render itself with its progress line, the output (or,
    /// when stopped, the samples so far) and the summary.
    fn finish(self) -> Result<()> {
        let Run {
            args,
            prepared,
            backend,
            write,
            began,
        } = self;
        let settings = prepared.job.settings;
        let samples = prepared.job.samples.clone();
        let wanted = samples.end - samples.start;
        let progress = Progress::new(settings.width, settings.height, wanted, args.quiet);
        // What a split render pays again in every part: loading the scene, building its BVH
        // and opening the device.
        let set_up = began.elapsed().as_secs_f64();
        let start = Instant::now();
        let film = prepared
            .render(backend, &|n| progress.inc(n))
            .map_err(pipeline_error)?;
        let rays = film.rays();
        let seconds = start.elapsed().as_secs_f64();
        progress.finish();
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
            let what = match prepared.part {
                Some(p) => format!(
                    "part {}/{} (samples {}..{} of {})",
                    p.index, p.count, samples.start, samples.end, settings.spp
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
                set_up,
                args.output.display()
            );
        }
        Ok(())
    }
}
