//! The GPU renderer session: a scene uploaded and its render pipeline compiled once, then
//! any number of dispatches into a film that lives on the device until read back.

use super::params::Params;
use super::pipelines::Pipeline;
use super::shader::Features;
use super::upload::{SceneTables, params_buffer};
use super::{GpuContext, GpuError};
use crate::film::{Aov, Film};
use crate::fixed::{fixed_add3, from_words};
use crate::render::job::{Checkpoints, RenderJob};
use crate::render::tables::RenderScene;
use crate::render::watch::Region;
use crate::scene::{Camera, RenderSettings};
use std::ops::Range;
use std::sync::Arc;

/// Paths traced per dispatch: about one sample per pixel of a 1080p image, so that no
/// dispatch runs long enough (~100 ms on a desktop GPU) for a driver watchdog to kill it.
pub const PATHS_PER_DISPATCH: u64 = 1 << 21;

/// Invocations per workgroup side of the render kernel. mirror: shaders/render.wgsl `render`
const WORKGROUP: u32 = 8;

/// Samples per pixel a dispatch asks of each invocation at most on a software adapter, to
/// begin with: Mesa's lavapipe ends an invocation's loops after 65535 iterations in all,
/// which a few dozen paths of a large scene can reach. (The kernel detects a cut and the
/// renderer then halves the step, so this only saves the first failed tries.)
const SOFTWARE_SAMPLES_PER_DISPATCH: u32 = 16;

/// Bytes of a film texel on the device: four fixed-point sums of two 32-bit words each.
/// mirror: shaders/fixed.wgsl `Texel`
const TEXEL_BYTES: u64 = 32;

/// Bytes of a pixel's splat sums on the device: three fixed-point sums of two 32-bit words.
/// mirror: shaders/render.wgsl `splats`
const SPLAT_BYTES: u64 = 24;

/// The render kernel's status words (`status` in shaders/render.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct Status {
    /// Invocations that a driver's loop limit cut short, leaving their pixels unchanged.
    cut: u32,
    /// Always 0: the kernel's canary loop reads its bound from here.
    zero: u32,
    /// A checked kernel's out-of-range indices and zero divisors
    /// ([`ShaderChecks`](super::shader::ShaderChecks)); always 0 in a trusted one.
    check_failures: u32,
    _pad: u32,
}

/// The film being accumulated on the device: one texel per pixel for radiance, then one per
/// film channel ([`Film::texels_per_pixel`]).
struct DeviceFilm {
    template: Film,
    buffer: wgpu::Buffer,
    /// The splats of light subpaths (`splats` in shaders/render.wgsl): per pixel three
    /// fixed-point sums of two words each, added to the radiance when the film is read.
    splats: wgpu::Buffer,
    /// In a render with caustics, copies of `buffer` and `splats` from before the last
    /// dispatch: a dispatch that the driver cut short is undone from them, since its
    /// finished samples' splats, unlike their pixels' sums, cannot be told from the rest.
    backup: Option<(wgpu::Buffer, wgpu::Buffer)>,
    /// The kernel's [`Status`].
    status: wgpu::Buffer,
    io_group: wgpu::BindGroup,
    /// The first sample of the render, and how many samples every pixel has received.
    first_sample: u32,
    samples: u32,
}

/// A scene on one GPU, ready to render. [`GpuRenderer::new`] uploads the tables once and
/// the first [`GpuRenderer::begin`] compiles the render kernel; `begin` starts a film,
/// [`GpuRenderer::dispatch`] traces sample ranges into it and [`GpuRenderer::read_film`]
/// brings it back. [`GpuRenderer::render`] runs a whole [`RenderJob`] through them.
pub struct GpuRenderer {
    ctx: GpuContext,
    tables: SceneTables,
    /// The device's render kernel, taken by the first [`GpuRenderer::begin`] (a renderer
    /// that only serves [`Kernel`](super::kernels::Kernel)s never needs it).
    render: Option<Arc<Pipeline>>,
    /// The optional parts of the path tracer the scene uses, which its kernels compile in.
    features: Features,
    /// Whether the films begun trace camera rays alone ([`RenderJob::geometry`]).
    geometry: bool,
    /// The parameters of the scene and of the film's settings; dispatches set the ranges.
    base: Params,
    params: wgpu::Buffer,
    scene_group: wgpu::BindGroup,
    film: Option<DeviceFilm>,
    /// The scene's part of the parameters and its camera, for the films of any settings.
    scene_params: Params,
    camera: Camera,
    /// The most samples per pixel one dispatch traces: unbounded on hardware, halved each
    /// time the kernel reports a cut (see [`SOFTWARE_SAMPLES_PER_DISPATCH`]).
    max_step: u32,
    /// The scene's bounds, which say which pixels' rays may meet it.
    bounds: crate::math::Aabb,
}

impl GpuRenderer {
    /// Uploads `scene`'s tables to the device.
    pub fn new(ctx: &GpuContext, scene: &RenderScene) -> Result<Self, GpuError> {
        let tables = SceneTables::new(ctx, scene)?;
        let params = params_buffer(ctx);
        let scene_group = tables.bind_group(ctx, &params);
        let scene_params = Params::for_scene(scene);
        Ok(Self {
            ctx: ctx.clone(),
            tables,
            render: None,
            features: Features::of(scene),
            geometry: false,
            base: scene_params,
            params,
            scene_group,
            film: None,
            scene_params,
            camera: scene.camera.clone(),
            bounds: scene.bounds(),
            max_step: if ctx.adapter.software {
                SOFTWARE_SAMPLES_PER_DISPATCH
            } else {
                u32::MAX
            },
        })
    }

    /// Sets the most samples per pixel one dispatch traces (by default unbounded on a
    /// hardware adapter, [`SOFTWARE_SAMPLES_PER_DISPATCH`] on a software one). More let a
    /// lane run more paths back to back; the renderer still halves the step wherever the
    /// driver cuts an invocation short.
    pub fn set_max_samples_per_dispatch(&mut self, samples: u32) {
        self.max_step = samples.max(1);
    }

    /// Renders from `camera` from the next [`GpuRenderer::begin`] on (the scene's tables
    /// do not hold the camera, so views of one scene share its upload).
    pub fn set_camera(&mut self, camera: &Camera) {
        self.camera = camera.clone();
    }

    /// The device this renderer runs on.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// The scene's tables, for kernels that read the same scene.
    pub(super) fn tables(&self) -> &SceneTables {
        &self.tables
    }

    /// The optional parts of the path tracer the scene uses, for kernels over the same scene.
    pub(super) fn features(&self) -> Features {
        self.features
    }

    /// The parameters of a render of `settings` on this scene, covering every row and no
    /// samples yet.
    pub(super) fn params_for(&self, settings: &RenderSettings) -> Params {
        self.scene_params
            .with_settings(&self.camera, settings, &self.bounds)
    }

    /// Starts an empty film for `settings`, whose first sample will be `first_sample`.
    pub fn begin(&mut self, settings: &RenderSettings, first_sample: u32) -> Result<(), GpuError> {
        let template = Film::new(settings.width, settings.height);
        self.begin_film(settings, template, first_sample)
    }

    /// Starts a film like `template` (empty, of `settings`' size: its channels say which
    /// AOVs to fill), whose first sample will be `first_sample`.
    pub fn begin_film(
        &mut self,
        settings: &RenderSettings,
        template: Film,
        first_sample: u32,
    ) -> Result<(), GpuError> {
        let texels = template.texels_per_pixel() as u32;
        let bytes = template.sum.len() as u64 * texels as u64 * TEXEL_BYTES;
        let limit = self.ctx.limits.max_storage_buffer_binding_size;
        if bytes > limit {
            return Err(GpuError::TooLarge {
                what: "film",
                bytes,
                limit,
                rule: format!("max_storage_buffer_binding_size = {limit}"),
            });
        }
        self.base = Params {
            film_texels: texels,
            aovs: Aov::mask(&template.aovs()),
            transparent: template.transparent as u32,
            ..self.params_for(settings)
        };
        let buffer_of = |label: &'static str, size: u64, storage: bool| {
            let usage = wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
            self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: if storage {
                    usage | wgpu::BufferUsages::STORAGE
                } else {
                    usage
                },
                mapped_at_creation: false,
            })
        };
        let splat_bytes = template.sum.len() as u64 * SPLAT_BYTES;
        let buffer = buffer_of("film", bytes, true);
        let splats = buffer_of("splats", splat_bytes, true);
        if self.geometry {
            self.base.num_caustic_targets = 0;
        }
        let caustics = self.base.num_caustic_targets > 0;
        let backup = caustics.then(|| {
            (
                buffer_of("film backup", bytes, false),
                buffer_of("splats backup", splat_bytes, false),
            )
        });
        let status = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("status"),
            size: size_of::<Status>() as u64,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let render = if self.geometry {
            self.ctx.geometry_pipeline(self.features)?
        } else {
            self.ctx.render_pipeline(caustics, self.features)?
        };
        let io_group = render.io_group(&self.ctx, &[&buffer, &status, &splats]);
        self.render = Some(render);
        self.film = Some(DeviceFilm {
            template,
            buffer,
            splats,
            backup,
            status,
            io_group,
            first_sample,
            samples: 0,
        });
        self.ctx.check()
    }

    /// Traces samples `samples` of the pixels of rows `rows` into the film and waits for
    /// them. A pixel's samples must be dispatched in order, as the CPU adds them. The range
    /// goes out in parts of at most [`GpuRenderer::max_step`] samples; a part that a
    /// driver's loop limit cut short (the kernel says so, leaving the cut pixels as they
    /// were) is sent again in halves, and the step halves for the rest of the session. A
    /// single sample that is still cut is an error.
    pub fn dispatch(&mut self, samples: Range<u32>, rows: Range<u32>) -> Result<(), GpuError> {
        let mut start = samples.start;
        while start < samples.end {
            let end = samples.end.min(start.saturating_add(self.max_step));
            self.dispatch_part(start..end, rows.clone())?;
            start = end;
        }
        if rows.end == self.base.height
            && let Some(film) = &mut self.film
        {
            film.samples = samples.end - film.first_sample;
        }
        Ok(())
    }

    /// One part of [`GpuRenderer::dispatch`], split further where the kernel reports cuts.
    fn dispatch_part(&mut self, samples: Range<u32>, rows: Range<u32>) -> Result<(), GpuError> {
        if self.run_kernel(samples.clone(), rows.clone())? == 0 {
            return Ok(());
        }
        let n = samples.end - samples.start;
        if n == 1 {
            return Err(GpuError::Fault(format!(
                "{}: one path of sample {} ran past the driver's limit on loop iterations (lavapipe's is 65535 per invocation); use --device cpu",
                self.ctx.adapter.name, samples.start
            )));
        }
        self.max_step = self.max_step.min(n / 2);
        let mid = samples.start + n / 2;
        self.dispatch_part(samples.start..mid, rows.clone())?;
        self.dispatch_part(mid..samples.end, rows)
    }

    /// Runs the render kernel once over `samples` of `rows`, waits for it and returns how
    /// many invocations were cut short (their pixels keep what they had; in a render with
    /// caustics the whole dispatch is undone, splats included).
    fn run_kernel(&mut self, samples: Range<u32>, rows: Range<u32>) -> Result<u32, GpuError> {
        let (Some(film), Some(render)) = (&self.film, &self.render) else {
            return Err(GpuError::Fault("dispatch before begin".into()));
        };
        let p = Params {
            sample_start: samples.start,
            sample_end: samples.end,
            row_start: rows.start,
            row_end: rows.end,
            ..self.base
        };
        self.ctx
            .queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&p));
        self.ctx
            .queue
            .write_buffer(&film.status, 0, bytemuck::bytes_of(&Status::default()));
        let mut enc = self.ctx.device.create_command_encoder(&Default::default());
        if let Some((film_copy, splats_copy)) = &film.backup {
            enc.copy_buffer_to_buffer(&film.buffer, 0, film_copy, 0, None);
            enc.copy_buffer_to_buffer(&film.splats, 0, splats_copy, 0, None);
        }
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&render.pipeline);
            pass.set_bind_group(0, &self.scene_group, &[]);
            pass.set_bind_group(1, &film.io_group, &[]);
            pass.dispatch_workgroups(
                p.width.div_ceil(WORKGROUP),
                (rows.end - rows.start).div_ceil(WORKGROUP),
                1,
            );
        }
        self.ctx.queue.submit([enc.finish()]);
        let status = self.ctx.read_buffer(&film.status)?;
        let status: Status = bytemuck::pod_read_unaligned(&status);
        if status.check_failures != 0 {
            return Err(GpuError::Fault(format!(
                "the checked render kernel indexed out of range or divided by zero {} times",
                status.check_failures
            )));
        }
        if status.cut > 0
            && let Some((film_copy, splats_copy)) = &film.backup
        {
            let mut enc = self.ctx.device.create_command_encoder(&Default::default());
            enc.copy_buffer_to_buffer(film_copy, 0, &film.buffer, 0, None);
            enc.copy_buffer_to_buffer(splats_copy, 0, &film.splats, 0, None);
            self.ctx.queue.submit([enc.finish()]);
        }
        Ok(status.cut)
    }

    /// The film so far, with the samples that every pixel has received.
    pub fn read_film(&self) -> Result<Film, GpuError> {
        let Some(film) = &self.film else {
            return Err(GpuError::Fault("read_film before begin".into()));
        };
        self.read_rows(0..film.template.height, film.template.clone(), film.samples)
    }

    /// Rows `rows` of the film so far, as a film of their size (shaped as `template`, which
    /// has that size) holding `samples` samples a pixel.
    fn read_rows(&self, rows: Range<u32>, template: Film, samples: u32) -> Result<Film, GpuError> {
        let Some(film) = &self.film else {
            return Err(GpuError::Fault("read_film before begin".into()));
        };
        let stride = template.texels_per_pixel();
        let row_bytes = (template.width as usize * stride * 32) as u64;
        let data = self.ctx.read_buffer_range(
            &film.buffer,
            rows.start as u64 * row_bytes..rows.end as u64 * row_bytes,
        )?;
        let words: &[[u32; 8]] = bytemuck::cast_slice(&data);
        let texel = |w: &[u32; 8]| [0, 1, 2, 3].map(|k| from_words([w[2 * k], w[2 * k + 1]]));
        let splat_row = template.width as u64 * SPLAT_BYTES;
        let splat_data = self.ctx.read_buffer_range(
            &film.splats,
            rows.start as u64 * splat_row..rows.end as u64 * splat_row,
        )?;
        let splats: &[[u32; 6]] = bytemuck::cast_slice(&splat_data);
        let mut out = template;
        out.samples = samples;
        for (i, (pixel, splat)) in words.chunks_exact(stride).zip(splats).enumerate() {
            let [r, g, b, _next] = texel(&pixel[0]);
            let splat = [0, 1, 2].map(|k| from_words([splat[2 * k], splat[2 * k + 1]]));
            out.sum[i] = fixed_add3([r, g, b], splat);
            for (channel, w) in out.channels.iter_mut().zip(&pixel[1..]) {
                channel.data[i] = texel(w);
            }
        }
        Ok(out)
    }

    /// Renders the job's sample range: [`GpuRenderer::begin`], then the dispatches of
    /// [`plan_dispatches`], then [`GpuRenderer::read_film`]. `progress` is told the samples
    /// each dispatch finished. Stops early, after a whole pass, when the job is cancelled;
    /// the film's `samples` says how many it holds.
    pub fn render(&mut self, job: &RenderJob, progress: &dyn Fn(u64)) -> Result<Film, GpuError> {
        let (w, h) = (job.settings.width, job.settings.height);
        self.geometry = job.geometry;
        self.begin_film(&job.settings, job.film(), job.samples.start)?;
        let mut checkpoints = Checkpoints::new(job);
        for (samples, rows) in plan_dispatches(job) {
            let region = Region {
                x0: 0,
                y0: rows.start,
                x1: w,
                y1: rows.end,
            };
            if let Some(watch) = &job.watch {
                watch.started(0, region, samples.clone());
            }
            self.dispatch(samples.clone(), rows.clone())?;
            progress(
                (samples.end - samples.start) as u64 * w as u64 * (rows.end - rows.start) as u64,
            );
            if let Some(watch) = &job.watch {
                // A band's last dispatch always brings its pixels: the window ends on
                // the final image.
                let last = samples.end == job.samples.end;
                let band = if last || watch.wants_pixels() {
                    let template = Film::with_aovs(w, region.height(), job.aovs, job.transparent);
                    Some(self.read_rows(rows.clone(), template, samples.end - job.samples.start)?)
                } else {
                    None
                };
                watch.finished(0, region, band.as_ref());
            }
            if rows.end == h {
                let more = samples.end < job.samples.end;
                if more && job.cancelled() {
                    break;
                }
                if more && checkpoints.due() {
                    checkpoints.write(&self.read_film()?);
                }
            }
        }
        self.read_film()
    }
}

/// The dispatches of a job: sample ranges over row bands, each at most
/// [`PATHS_PER_DISPATCH`] paths, in an order that keeps every pixel's samples in sequence.
pub fn plan_dispatches(job: &RenderJob) -> Vec<(Range<u32>, Range<u32>)> {
    let (w, h) = (job.settings.width as u64, job.settings.height as u64);
    let rows = (PATHS_PER_DISPATCH / w).clamp(1, h);
    let spp_step = if rows == h {
        (PATHS_PER_DISPATCH / (w * h)).max(1) as u32
    } else {
        1
    };
    let mut out = Vec::new();
    let mut s = job.samples.start;
    while s < job.samples.end {
        let s_end = (s + spp_step).min(job.samples.end);
        let mut r = 0;
        while r < h {
            let r_end = (r + rows).min(h);
            out.push((s..s_end, r as u32..r_end as u32));
            r = r_end;
        }
        s = s_end;
    }
    out
}
