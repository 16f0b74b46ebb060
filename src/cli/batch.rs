//! `meshtrace batch`: the tasks of a manifest (or one shard of them), each input loaded and
//! prepared on the device once for all its views, outputs that are already complete
//! skipped, and every output folder's `transforms.json` kept up to date.

use super::{DeviceArgs, Interrupted, backend, pipeline_error, set_threads, warn};
use anyhow::{Context, Result, bail};
use meshtrace::batch::preset::Normalisation;
use meshtrace::batch::preset::{Poses, Preset, metadata, write_npy};
use meshtrace::batch::transforms::{self, Frame, Intrinsics};
use meshtrace::batch::{self, Manifest, Task};
use meshtrace::batch::{syncdreamer, trellis, wonder3d};
use meshtrace::film::{BitDepth, DisplayTransform, Film, Format};
use meshtrace::pipeline::Prepared;
use meshtrace::render::backend::Backend;
use meshtrace::request::RenderRequest;
use meshtrace::scene::camera::Camera;
use meshtrace::scene::source::Fs;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

#[derive(clap::Args)]
pub struct BatchArgs {
    /// The manifest (.toml; see docs/batch.md).
    pub manifest: PathBuf,
    /// Render only shard K of N (K from 0): the K-th of N consecutive blocks of the
    /// manifest's tasks, so that a mesh's views mostly stay in one shard. `auto` takes K
    /// and N from a Slurm job array (SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT, or
    /// _MIN and _MAX); `auto/N` takes K from SLURM_ARRAY_TASK_ID or Kubernetes'
    /// JOB_COMPLETION_INDEX, with N given.
    #[arg(long, value_name = "K/N|auto|auto/N")]
    pub shard: Option<String>,
    /// Render again the inputs that the failure log lists; by default a rerun skips them.
    #[arg(long)]
    pub retry_failed: bool,
    /// The most seconds one input may take, loading and all its views (over the manifest's
    /// `time_limit`): one over it fails, logged, and the batch goes on. It is checked once
    /// the input is loaded and between sample passes.
    #[arg(long, value_name = "SECONDS")]
    pub time_limit: Option<f64>,
    #[command(flatten)]
    pub on: DeviceArgs,
    /// Print nothing but warnings, errors and the closing summary.
    #[arg(short, long)]
    pub quiet: bool,
}

/// The shard `spec` names: `K/N`, `auto` or `auto/N` (see [`BatchArgs::shard`]), read
/// from `env`.
pub fn resolve_shard(
    spec: &str,
    flag: &str,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<(u32, u32)> {
    let number = |name: &str| -> Result<Option<u32>> {
        match env(name) {
            None => Ok(None),
            Some(v) => v
                .trim()
                .parse()
                .map(Some)
                .with_context(|| format!("{flag} auto: {name} is `{v}`, not a number")),
        }
    };
    let (k, n) = match spec.split_once('/') {
        None if spec == "auto" => {
            let id = number("SLURM_ARRAY_TASK_ID")?;
            let count = number("SLURM_ARRAY_TASK_COUNT")?;
            let (min, max) = (
                number("SLURM_ARRAY_TASK_MIN")?,
                number("SLURM_ARRAY_TASK_MAX")?,
            );
            match (id, count, min, max) {
                (Some(id), _, Some(min), Some(max)) if min <= id && id <= max => {
                    (id - min, max - min + 1)
                }
                (Some(id), Some(count), _, _) => (id, count),
                _ => bail!(
                    "{flag} auto: not in a Slurm job array (no SLURM_ARRAY_TASK_ID with SLURM_ARRAY_TASK_COUNT or _MIN and _MAX); in a Kubernetes Indexed Job use {flag} auto/N"
                ),
            }
        }
        Some(("auto", n)) => {
            let n: u32 = n
                .trim()
                .parse()
                .with_context(|| format!("{flag} auto/{n}: `{n}` is not a count"))?;
            let id = match (
                number("JOB_COMPLETION_INDEX")?,
                number("SLURM_ARRAY_TASK_ID")?,
            ) {
                (Some(k), _) => k,
                (None, Some(id)) => id - number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0),
                (None, None) => bail!(
                    "{flag} auto/{n}: neither JOB_COMPLETION_INDEX (Kubernetes) nor SLURM_ARRAY_TASK_ID (Slurm) is set"
                ),
            };
            (id, n)
        }
        Some((k, n)) => match (k.trim().parse::<u32>(), n.trim().parse::<u32>()) {
            (Ok(k), Ok(n)) => (k, n),
            _ => bail!("{flag} `{spec}`: not K/N (such as 0/4), auto or auto/N"),
        },
        None => bail!("{flag} `{spec}`: not K/N (such as 0/4), auto or auto/N"),
    };
    if k >= n {
        bail!("{flag} {k}/{n}: K counts from 0 and must be below N");
    }
    Ok((k, n))
}

/// The process's peak resident memory so far, in KiB (Linux).
fn peak_kib() -> Option<u64> {
    super::peak_memory_kib()
}

/// Whether `task`'s output is complete: the image (written last, by rename) and, beside a
/// non-EXR image with AOVs, their `.aovs.exr`, and TRELLIS's `passes`.
fn complete(task: &Task, aovs: bool, passes: trellis::Passes) -> bool {
    let image = task.output.is_file();
    let beside = !aovs
        || Format::from_path(&task.output).is_ok_and(|f| f == Format::Exr)
        || Film::aov_path(&task.output).is_file();
    image && beside && passes.paths(&task.output).iter().all(|p| p.is_file())
}

/// The `transforms.json` entry of `task` seen through `camera`.
fn frame(task: &Task, camera: &Camera, w: u32, h: u32) -> Frame {
    Frame {
        file_path: task
            .output
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        transform_matrix: transforms::camera_to_world(camera),
        intrinsics: Intrinsics::of(camera, w, h),
    }
}

/// Adds `frames` (by output) to their folders' `transforms.json`. Returns the share of the
/// frames written that were already there (rewritten because a flush writes a file whole).
fn record(frames: &[(PathBuf, Frame)]) -> Result<f64> {
    let mut by_dir: BTreeMap<PathBuf, Vec<Frame>> = BTreeMap::new();
    for (output, f) in frames {
        let dir = output.parent().map(Path::to_path_buf).unwrap_or_default();
        by_dir.entry(dir).or_default().push(f.clone());
    }
    let mut earlier = 0;
    for (dir, frames) in by_dir {
        earlier += transforms::record(&dir, &frames)?;
    }
    Ok(earlier as f64 / (earlier + frames.len()).max(1) as f64)
}

/// How often waiting frames go into their `transforms.json` at most: every 2 s, and no
/// sooner than 20 times as long as the last flush spent rewriting frames already in their
/// files after it, so that rewriting a large folder's file (a flush reads and writes it
/// whole) takes at most 5% of the run. Only that part is counted: writing new frames
/// costs the same however they are grouped, and counting it would let the wait, and the
/// frames waiting, grow without bound where each image has its own folder.
const FLUSH_SECONDS: f64 = 2.0;
const FLUSH_SHARE: f64 = 0.05;

/// The wait before the next flush after one that `took` this long, of which the share
/// `rewritten` went to frames already in their files.
fn flush_wait(took: Duration, rewritten: f64) -> Duration {
    took.mul_f64(rewritten / FLUSH_SHARE)
        .max(Duration::from_secs_f64(FLUSH_SECONDS))
}

/// The fewest images rendered before the summary's first peak memory is taken; a shard
/// that renders fewer reports its peak alone.
const WARM_UP_IMAGES: usize = 1000;

/// What the shard's tasks came to so far.
#[derive(Default)]
struct Tally {
    rendered: usize,
    skipped: usize,
    /// Images not rendered because their input failed, and the inputs that failed.
    failed_images: usize,
    failed: Vec<String>,
    /// Images skipped because the failure log lists their input.
    skipped_failed: usize,
    /// The peak memory once `warm_up` images are rendered (a tenth of the shard, and at
    /// least 1,000 images: the allocator's arenas and the loader's and encoder's buffers
    /// settle over the first several hundred), against which the closing summary measures
    /// growth; none in a shard that renders fewer.
    first_peak: Option<u64>,
    warm_up: usize,
    /// Frames waiting to go into their transforms.json: every few seconds and at the end,
    /// so a run killed in between leaves complete images without frames, which a resumed
    /// run records without rendering them again.
    frames: Vec<(PathBuf, Frame)>,
    /// The time spent in each [`Stage`], over every input and image.
    stages: [Duration; 4],
}

/// Where a batch spends its time: loading inputs (reading, decoding, a preset's lights),
/// building their tables and BVH and putting them on the device, rendering views, and
/// writing the files (images and poses).
#[derive(Clone, Copy)]
enum Stage {
    Load,
    Build,
    Render,
    Encode,
}

pub fn batch(args: &BatchArgs) -> Result<()> {
    set_threads(args.on.threads)?;
    let manifest = Manifest::load(&args.manifest)?;
    let all = manifest.tasks()?;
    let (k, n) = match &args.shard {
        Some(spec) => resolve_shard(spec, "--shard", &|name| std::env::var(name).ok())?,
        None => (0, 1),
    };
    let tasks = batch::shard(&all, k, n);
    let limit = match args.time_limit {
        None => manifest.time_limit,
        Some(t) if t.is_finite() && t > 0.0 => Some(Duration::from_secs_f64(t)),
        Some(t) => bail!("--time-limit: must be a positive number of seconds, got {t}"),
    };
    let failure_log = batch::failures::log_path(&manifest.path);
    let known_failures = if args.retry_failed {
        Default::default()
    } else {
        batch::failures::read(&failure_log)?
    };
    // The command line's device options win over the manifest's.
    let request = args.on.request().over(&manifest.request);
    let view = DisplayTransform::load(request.view_transform())
        .with_context(|| format!("{}: render.view_transform", manifest.path.display()))?;
    let backend = backend(&request, args.quiet)?;
    if !args.quiet {
        eprintln!(
            "shard {k}/{n}: {} of {} images, on {}",
            tasks.len(),
            all.len(),
            backend.name()
        );
    }
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    ctrlc::set_handler(move || {
        if flag.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    })
    .context("cannot install the Ctrl-C and SIGTERM handler")?;
    let start = Instant::now();
    let mut tally = Tally {
        warm_up: (tasks.len() / 10).max(WARM_UP_IMAGES),
        ..Tally::default()
    };
    let (mut flushed, mut flush_every) = (Instant::now(), Duration::from_secs_f64(FLUSH_SECONDS));
    // The tasks of one input are consecutive: load and prepare it once for all its views.
    let mut groups = Vec::new();
    let mut rest = &tasks[..];
    while let Some(first) = rest.first() {
        let len = rest
            .iter()
            .take_while(|t| t.job == first.job && t.input == first.input)
            .count();
        let (group, next) = rest.split_at(len);
        groups.push(group);
        rest = next;
    }
    // The next input loads and builds its BVH on a thread of its own while this one
    // renders, one waiting ready at most; with worker threads of its own, as the renders
    // keep the global pool busy (half as many: on a GPU they have the CPU to themselves,
    // on the CPU they share it with the renders).
    let loader_pool = rayon::ThreadPoolBuilder::new()
        .num_threads((rayon::current_num_threads() / 2).max(1))
        .thread_name(|i| format!("meshtrace-loader-{i}"))
        .build()
        .context("cannot start the loader's worker threads")?;
    std::thread::scope(|s| -> Result<()> {
        let (send, receive) = std::sync::mpsc::sync_channel::<Result<Loaded>>(0);
        let loading = {
            let (groups, cancel, manifest, request) = (&groups, &cancel, &manifest, &request);
            let (known_failures, pool) = (&known_failures, &loader_pool);
            s.spawn(move || {
                for group in groups {
                    if cancel.load(Ordering::SeqCst) {
                        break;
                    }
                    let loaded = pool
                        .install(|| load_input(manifest, request, group, known_failures, cancel));
                    if send.send(loaded).is_err() {
                        break;
                    }
                }
            })
        };
        for group in &groups {
            let first = &group[0];
            if cancel.load(Ordering::SeqCst) {
                break;
            }
            let Ok(loaded) = receive.recv() else {
                break;
            };
            if cancel.load(Ordering::SeqCst) {
                break;
            }
            let before = tally.rendered + tally.skipped;
            let result = match loaded {
                Ok(Loaded::FailedBefore) => {
                    tally.skipped_failed += group.len();
                    continue;
                }
                Ok(Loaded::Complete) => {
                    tally.skipped += group.len();
                    continue;
                }
                Ok(Loaded::Ready(input)) => {
                    let watchdog = Watchdog::start(cancel.clone(), limit, input.load + input.build);
                    let run = Run {
                        manifest: &manifest,
                        backend: &backend,
                        view: &view,
                        quiet: args.quiet,
                    };
                    render_input(&run, *input, group, &watchdog, &mut tally)
                }
                Err(e) => Err(e),
            };
            if flushed.elapsed() > flush_every {
                let t = Instant::now();
                let rewritten = record(&std::mem::take(&mut tally.frames))?;
                flush_every = flush_wait(t.elapsed(), rewritten);
                flushed = Instant::now();
            }
            if let Err(e) = result {
                if e.is::<Interrupted>() {
                    break;
                }
                let reason = crate::one_line(&e);
                eprintln!("error: {}: {reason}", first.input.display());
                batch::failures::append(&failure_log, first.job, &first.input, &reason)?;
                tally.failed_images += group.len() - (tally.rendered + tally.skipped - before);
                tally.failed.push(reason);
            }
        }
        // The frames finished are recorded before the loader, which may be loading ahead,
        // is waited for (a SIGTERM's grace period may not cover that load).
        record(&std::mem::take(&mut tally.frames))?;
        // The loader stops at its next hand-over.
        drop(receive);
        loading
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        Ok(())
    })?;
    record(&tally.frames)?;
    let seconds = start.elapsed().as_secs_f64();
    let per_hour = tally.rendered as f64 / seconds.max(1e-9) * 3600.0;
    let memory = match (tally.first_peak, peak_kib()) {
        (Some(a), Some(b)) => format!(
            "; peak memory {:.1} MiB after {} images, {:.1} MiB at the end ({:+.1}%)",
            a as f64 / 1024.0,
            tally.warm_up,
            b as f64 / 1024.0,
            100.0 * (b as f64 / a as f64 - 1.0)
        ),
        // Fewer images rendered than the warm-up: the peak alone, as growth over a
        // settling allocator would mean nothing.
        (None, Some(b)) => format!("; peak memory {:.1} MiB", b as f64 / 1024.0),
        _ => String::new(),
    };
    let logged = if tally.skipped_failed > 0 {
        format!(
            ", {} skipped as their inputs failed before (--retry-failed renders them)",
            tally.skipped_failed
        )
    } else {
        String::new()
    };
    let per_image = if tally.rendered > 0 {
        let each = |s: Stage| tally.stages[s as usize].as_secs_f64() / tally.rendered as f64;
        format!(
            "; per image: load {:.3} s, build {:.3} s, render {:.3} s, encode {:.3} s",
            each(Stage::Load),
            each(Stage::Build),
            each(Stage::Render),
            each(Stage::Encode)
        )
    } else {
        String::new()
    };
    eprintln!(
        "shard {k}/{n}: images: {} rendered, {} already complete, {} failed{logged} in {seconds:.1} s: {per_hour:.0} images/hour{per_image}{memory}",
        tally.rendered, tally.skipped, tally.failed_images
    );
    if cancel.load(Ordering::SeqCst) {
        return Err(Interrupted(format!(
            "stopped after {} of {} images; run again to resume",
            tally.rendered + tally.skipped,
            tasks.len()
        ))
        .into());
    }
    if !tally.failed.is_empty() {
        bail!(
            "{} of {} images failed, from {} (each said above, and logged in {})",
            tally.failed_images,
            tasks.len(),
            count(tally.failed.len(), "input"),
            failure_log.display()
        );
    }
    Ok(())
}

/// Stops one input's renders: on Ctrl-C (the batch's flag) and once the input has taken
/// longer than the time limit. A thread watches both, every few milliseconds, and raises
/// [`Watchdog::stop`], which the renders poll between sample passes.
struct Watchdog {
    stop: Arc<AtomicBool>,
    start: Instant,
    limit: Option<Duration>,
    done: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Watchdog {
    /// Watches an input that has taken `spent` already (loading it, ahead of its renders).
    fn start(cancel: Arc<AtomicBool>, limit: Option<Duration>, spent: Duration) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let done = Arc::new(AtomicBool::new(false));
        let now = Instant::now();
        let start = now.checked_sub(spent).unwrap_or(now);
        let thread = {
            let (stop, done) = (stop.clone(), done.clone());
            std::thread::spawn(move || {
                while !done.load(Ordering::SeqCst) {
                    let late = limit.is_some_and(|l| start.elapsed() > l);
                    if late || cancel.load(Ordering::SeqCst) {
                        stop.store(true, Ordering::SeqCst);
                    }
                    std::thread::sleep(Duration::from_millis(5));
                }
            })
        };
        Self {
            stop,
            start,
            limit,
            done,
            thread: Some(thread),
        }
    }

    /// An error saying the input took too long (`what`: "to load", "by view 3") where it
    /// has taken longer than the limit.
    fn check(&self, what: &str) -> Result<()> {
        match self.limit {
            Some(limit) if self.start.elapsed() > limit => bail!(
                "took longer than the time limit of {} s ({:.2} s {what})",
                limit.as_secs_f64(),
                self.start.elapsed().as_secs_f64()
            ),
            _ => Ok(()),
        }
    }
}

impl Drop for Watchdog {
    fn drop(&mut self) {
        self.done.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// `n` things, singular or plural: "1 input", "2 inputs".
fn count(n: usize, thing: &str) -> String {
    format!("{n} {thing}{}", if n == 1 { "" } else { "s" })
}

/// One input as the loader thread hands it to the renders: made ready, or why not.
enum Loaded {
    /// Every view is complete and recorded: nothing was loaded.
    Complete,
    /// The failure log lists the input (and `--retry-failed` was not given).
    FailedBefore,
    Ready(Box<Input>),
}

/// An input loaded, lit and built, its views still to render.
struct Input {
    /// The request its images take: the manifest's, the job's and its preset's.
    request: RenderRequest,
    /// The AOVs the manifest asks for, which go beside the images (a preset's own go into
    /// its files).
    saved_aovs: u32,
    /// Per task, whether its output is complete already.
    done: Vec<bool>,
    norm: Option<Normalisation>,
    uid: String,
    /// A preset's per-object files (metadata, poses of the whole object), each path with
    /// its bytes: written by the renders, so that an input loaded ahead and never rendered
    /// leaves nothing behind.
    files: Vec<(PathBuf, Vec<u8>)>,
    prepared: Prepared,
    /// Time spent loading (reading, decoding, lighting) and building its tables and BVH.
    load: Duration,
    build: Duration,
}

/// Loads the input of `group` as its job asks, where some view needs rendering or
/// recording: on the loader thread, while the previous input renders.
fn load_input(
    manifest: &Manifest,
    request: &RenderRequest,
    group: &[Task],
    known_failures: &std::collections::HashSet<(usize, PathBuf)>,
    cancel: &AtomicBool,
) -> Result<Loaded> {
    let job = &manifest.jobs[group[0].job];
    if known_failures.contains(&(group[0].job, group[0].input.clone())) {
        return Ok(Loaded::FailedBefore);
    }
    // Wonder3D's preset writes its AOVs into its own images, not beside them.
    let named = job.preset.as_ref().is_some_and(Preset::rig);
    let aovs = request.aov_mask() != 0 && !named;
    // A rerun that asks for TRELLIS's passes renders the views that lack them.
    let passes = job.preset.as_ref().map(|p| p.passes).unwrap_or_default();
    let done: Vec<bool> = group.iter().map(|t| complete(t, aovs, passes)).collect();
    // A preset writes its script's files alone: no transforms.json.
    let recorded = job.preset.is_some() || all_recorded(group);
    if done.iter().all(|&d| d) && recorded {
        return Ok(Loaded::Complete);
    }
    // The job's up axis, where it gives one, over the request's, over the preset's.
    let preset_request = job.preset.as_ref().map(Preset::request).unwrap_or_default();
    let mut request = RenderRequest {
        up: job.up,
        ..Default::default()
    }
    .over(&request.over(&preset_request));
    // The AOVs the manifest asks for, before a preset adds those its own files need.
    let saved_aovs = request.aov_mask();
    if let Some(preset) = &job.preset
        && !preset.aovs().is_empty()
    {
        let mut aovs = request.aov.clone().unwrap_or_default();
        aovs.extend(
            preset
                .aovs()
                .iter()
                .filter(|a| !aovs.contains(a))
                .collect::<Vec<_>>(),
        );
        request.aov = Some(aovs);
    }
    let request_error = |e| request_error(manifest, e);
    let uid = meshtrace::scene::uid(&group[0].input);
    let t = Instant::now();
    // A lighting preset is applied below, once a preset's metadata has counted the input's
    // own lights.
    let unlit = RenderRequest {
        lighting: None,
        ..request.clone()
    };
    let mut scene = meshtrace::pipeline::load(&group[0].input, &unlit).map_err(request_error)?;
    for w in &scene.warnings {
        warn(w);
    }
    if cancel.load(Ordering::SeqCst) {
        // Interrupted while loading ahead: not built, and dropped.
        return Err(Interrupted("interrupted".into()).into());
    }
    let mut files = Vec::new();
    let norm = match &job.preset {
        None => None,
        Some(preset) => {
            // The bare mesh's bounds, as the studio frames them (the preset has no ground).
            let norm = scene
                .framed
                .as_ref()
                .and_then(|b| preset.normalisation(b))
                .context("the mesh has no extent to normalise")?
                .with_root(preset, scene.root_origin);
            // Per object, beside its first view's image (before the preset's lights, which
            // the metadata does not count).
            let dir = group[0].output.parent().unwrap_or(Path::new(""));
            let json = |value: serde_json::Value| {
                serde_json::to_string_pretty(&value).map(|text| (text + "\n").into_bytes())
            };
            if preset.metadata {
                let value = metadata(&group[0].input, &scene, &norm);
                files.push((dir.join("metadata.json"), json(value)?));
            }
            if preset.poses == Poses::Transforms {
                let value = preset.trellis_transforms(&uid, &norm);
                files.push((dir.join("transforms.json"), json(value)?));
            }
            if preset.poses == Poses::RtTxt {
                // np.savetxt([scale] + list(offset) + [ortho_scale]): the offset is
                // Blender's single-precision vector.
                let offset = norm.blender_offset().to_array().map(|x| x as f32 as f64);
                let values = [norm.scale as f64]
                    .into_iter()
                    .chain(offset)
                    .chain([decimal(preset.ortho_scale)]);
                let rows: Vec<Vec<f64>> = values.map(|v| vec![v]).collect();
                let text = wonder3d::savetxt_text(&rows);
                files.push((dir.join("scale_offset_matrix.txt"), text.into_bytes()));
            }
            if preset.poses == Poses::MetaPkl {
                let size = (
                    request.width.unwrap_or(preset.size),
                    request.height.unwrap_or(preset.size),
                );
                let bytes = syncdreamer::meta_pkl(preset, &uid, &norm, size);
                files.push((dir.join("meta.pkl"), bytes));
            }
            Some(norm)
        }
    };
    // The request's lighting preset, else a dataset preset's script lighting.
    match (&request.lighting, &job.preset, &norm) {
        (Some(lighting), _, _) => lighting.apply(&mut scene, &Fs)?,
        (None, Some(preset), Some(norm)) => preset.light(&mut scene, norm, &uid)?,
        _ => {}
    }
    let load = t.elapsed();
    let t = Instant::now();
    let prepared = Prepared::from_scene(scene, &request).map_err(request_error)?;
    if prepared.scene.camera.is_orthographic() && job.preset.is_none() {
        bail!(
            "its camera is orthographic, which transforms.json's pinhole intrinsics cannot \
             describe; give it a perspective camera, or render it with `meshtrace render`"
        );
    }
    Ok(Loaded::Ready(Box::new(Input {
        request,
        saved_aovs,
        done,
        norm,
        uid,
        files,
        prepared,
        load,
        build: t.elapsed(),
    })))
}

/// A pipeline error as a batch says it: a request's field as the manifest's key.
fn request_error(manifest: &Manifest, e: meshtrace::pipeline::PipelineError) -> anyhow::Error {
    match e {
        meshtrace::pipeline::PipelineError::Request(e) => {
            anyhow::anyhow!("{}: render.{e}", manifest.path.display())
        }
        e => pipeline_error(e),
    }
}

/// What every input of a batch renders with: the manifest, the device, the view transform
/// of its images, and whether to print each image.
#[derive(Clone, Copy)]
struct Run<'a> {
    manifest: &'a Manifest,
    backend: &'a Backend,
    view: &'a DisplayTransform,
    quiet: bool,
}

/// Renders the views of `input` (the input of `group`) that are not complete yet and
/// records every view's camera. The images are encoded and written on a thread of their
/// own while the next view renders; the input's result waits for them.
fn render_input(
    run: &Run,
    input: Input,
    group: &[Task],
    watchdog: &Watchdog,
    tally: &mut Tally,
) -> Result<()> {
    let Run {
        manifest,
        backend,
        view,
        quiet,
    } = *run;
    let job = &manifest.jobs[group[0].job];
    let Input {
        request,
        saved_aovs,
        done,
        norm,
        uid,
        files,
        prepared,
        load,
        build,
    } = input;
    tally.stages[Stage::Load as usize] += load;
    watchdog.check("to load")?;
    let t = Instant::now();
    let settings = prepared.job.settings;
    let own = prepared.scene.camera.clone();
    let framed = prepared.framed;
    let mut views = prepared.views(backend).map_err(pipeline_error)?;
    views.job_mut().cancel = Some(watchdog.stop.clone());
    tally.stages[Stage::Build as usize] += build + t.elapsed();
    let encoder = Encoder {
        preset: job.preset.as_ref(),
        norm: norm.as_ref(),
        uid: &uid,
        bit_depth: request.bit_depth(),
        saved_aovs,
        view,
        quiet,
    };
    std::thread::scope(|s| {
        // Two images at most wait for the encoder: memory stays bounded where it is
        // slower than the renders.
        let (send, receive) = std::sync::mpsc::sync_channel::<Rendered>(2);
        let encoding = s.spawn(|| encoder.run(receive, files));
        let rendered = (|| {
            for (task, &done) in group.iter().zip(&done) {
                let camera = match (&job.preset, &norm) {
                    (Some(preset), Some(norm)) => preset.camera(&uid, task.view, norm),
                    _ => batch::view_camera(job, task.view, &own, framed.as_ref()),
                }
                .with_context(|| format!("view {} cannot be framed", task.view))?;
                if job.preset.is_none() {
                    let f = frame(task, &camera, settings.width, settings.height);
                    tally.frames.push((task.output.clone(), f));
                }
                if done {
                    tally.skipped += 1;
                    continue;
                }
                let began = Instant::now();
                let film = views.render(&camera, &|_| {}).map_err(pipeline_error)?;
                tally.stages[Stage::Render as usize] += began.elapsed();
                if film.samples < settings.spp {
                    // An image cut short is not written (nor its frame): a resumed run
                    // renders it.
                    if job.preset.is_none() {
                        tally.frames.pop();
                    }
                    watchdog.check(&format!("by view {}", task.view))?;
                    return Err(Interrupted("interrupted".into()).into());
                }
                let view = Rendered {
                    task: task.clone(),
                    film,
                    camera,
                    began,
                };
                if send.send(view).is_err() {
                    // The encoder stopped at an error, which is the input's.
                    break;
                }
            }
            Ok(())
        })();
        drop(send);
        let (written, seconds, encoded) = encoding
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        tally.rendered += written;
        tally.stages[Stage::Encode as usize] += seconds;
        if tally.first_peak.is_none() && tally.rendered >= tally.warm_up {
            tally.first_peak = peak_kib();
        }
        // A write that failed is the input's error even where the renders stopped too.
        encoded.and(rendered)
    })
}

/// One rendered view on its way to the encoder thread.
struct Rendered {
    task: Task,
    film: Film,
    camera: Camera,
    /// When its render began, for the line that reports it.
    began: Instant,
}

/// Writes the files of an input's rendered views, off the render thread.
struct Encoder<'a> {
    preset: Option<&'a Preset>,
    norm: Option<&'a Normalisation>,
    uid: &'a str,
    bit_depth: BitDepth,
    /// The AOVs the manifest asks for ([`Input::saved_aovs`]).
    saved_aovs: u32,
    view: &'a DisplayTransform,
    quiet: bool,
}

impl Encoder<'_> {
    /// Writes each view that `receive` brings until the renders end or a write fails,
    /// the input's own `files` (path and bytes) before the first, so that an input with no
    /// finished view leaves nothing: the images written, the time spent, and the first
    /// error.
    fn run(
        &self,
        receive: std::sync::mpsc::Receiver<Rendered>,
        mut files: Vec<(PathBuf, Vec<u8>)>,
    ) -> (usize, Duration, Result<()>) {
        let (mut written, mut spent) = (0, Duration::ZERO);
        for view in receive {
            let t = Instant::now();
            let mut own = std::mem::take(&mut files).into_iter();
            let (output, began) = (view.task.output.clone(), view.began);
            if let Err(e) = own
                .try_for_each(|(path, bytes)| write_file(&path, &bytes))
                .and_then(|()| self.write(view))
            {
                return (written, spent, Err(e));
            }
            spent += t.elapsed();
            written += 1;
            if !self.quiet {
                eprintln!(
                    "{} ({:.2} s)",
                    output.display(),
                    began.elapsed().as_secs_f64()
                );
            }
        }
        (written, spent, Ok(()))
    }

    /// A view's files: its pose (and TRELLIS's normal pass) first, as the image marks the
    /// view complete.
    fn write(&self, view: Rendered) -> Result<()> {
        let Rendered {
            task,
            mut film,
            camera,
            ..
        } = view;
        let (task, camera) = (&task, &camera);
        if let Some(dir) = task.output.parent() {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
        }
        match (self.preset, self.norm) {
            (Some(preset), Some(norm)) if preset.poses == Poses::Npy => {
                let path = task.output.with_extension("npy");
                write_npy(&path, &preset.pose(self.uid, task.view, norm))
                    .with_context(|| format!("cannot write {}", path.display()))?;
                film.save_as(&task.output, self.bit_depth, self.view)?;
            }
            (Some(preset), Some(norm)) if preset.poses == Poses::RtTxt => {
                write_wonder3d(preset, norm, self.uid, task, &film, camera, self.view)?;
            }
            (Some(preset), Some(norm)) if preset.passes.any() => {
                let frame = [preset.distance as f64, norm.scale as f64];
                let passes = preset.passes;
                passes.write(&task.output, &film, camera, frame, self.view)?;
                // The passes are the AOVs' files: only those the manifest asks for go beside
                // the image too.
                film.saved_aovs = self.saved_aovs;
                film.save_as(&task.output, self.bit_depth, self.view)?;
            }
            _ => film.save_as(&task.output, self.bit_depth, self.view)?,
        }
        Ok(())
    }
}

/// The f64 nearest the shortest decimal of `x` (1.35f32 → 1.35, not 1.35000002384…): the
/// value as a manifest or a script's command line writes it.
fn decimal(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(x as f64)
}

/// Writes `text` to `path` (through a temporary file), its folder made first.
fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    meshtrace::film::write_bytes(path, bytes)?;
    Ok(())
}

/// Wonder3D's files of `task` (rendered into `film` through `camera`), in the order that
/// leaves the colour image, which marks the view complete, last: `{name}_RT.txt` (Blender's
/// single-precision matrix, as `np.savetxt` writes it), the normals image (the output's
/// name with `normals` for its leading `rgb`) and the colour image with the mask as alpha.
fn write_wonder3d(
    preset: &Preset,
    norm: &Normalisation,
    uid: &str,
    task: &Task,
    film: &Film,
    camera: &Camera,
    view: &DisplayTransform,
) -> Result<()> {
    let dir = task.output.parent().unwrap_or(Path::new(""));
    let name = preset.view_name(task.view).unwrap_or_default();
    let rows: Vec<Vec<f64>> = preset
        .pose(uid, task.view, norm)
        .iter()
        .map(|row| row.iter().map(|&x| x as f32 as f64).collect())
        .collect();
    wonder3d::savetxt(&dir.join(format!("{name}_RT.txt")), &rows)?;
    let (rgb, normals) = wonder3d::images(film, camera, view)
        .map_err(|m| anyhow::anyhow!("{}: {m}", task.output.display()))?;
    let file = task
        .output
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let normals_file = match file.strip_prefix("rgb") {
        Some(rest) => format!("normals{rest}"),
        None => format!("normals_{file}"),
    };
    let (w, h) = (film.width, film.height);
    wonder3d::write_rgba(&dir.join(normals_file), w, h, normals)?;
    wonder3d::write_rgba(&task.output, w, h, rgb)?;
    Ok(())
}

/// Whether every task's output is in its folder's `transforms.json`, each folder's file
/// read once.
fn all_recorded(tasks: &[Task]) -> bool {
    let mut folders: BTreeMap<&Path, std::collections::HashSet<String>> = BTreeMap::new();
    tasks
        .iter()
        .all(|t| match (t.output.parent(), t.output.file_name()) {
            (Some(dir), Some(name)) => folders
                .entry(dir)
                .or_insert_with(|| transforms::recorded(dir))
                .contains(name.to_string_lossy().as_ref()),
            _ => false,
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// New frames cost the same however they are grouped, so only the rewriting of frames
    /// already in the files lengthens the wait: were a flush's whole time counted, a batch
    /// with a folder per image would wait ever longer and gather ever more frames for the
    /// next flush (3,000 grids, 8², 1 spp: 363 frames in 0.46 s, then 1,639 in 1.87 s).
    #[test]
    fn flushes_wait_for_the_rewriting_of_earlier_frames_only() {
        let s = Duration::from_secs_f64;
        assert_eq!(flush_wait(s(0.5), 0.0), s(2.0));
        assert_eq!(flush_wait(s(30.0), 0.0), s(2.0));
        assert_eq!(flush_wait(s(0.05), 1.0), s(2.0));
        let wait = flush_wait(s(0.4), 0.9).as_secs_f64();
        assert!((wait - 7.2).abs() < 1e-9, "{wait}");
    }
}
