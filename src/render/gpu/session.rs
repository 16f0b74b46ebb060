//! The GPU renderer session: a scene uploaded and its render pipeline compiled once, then
//! any number of dispatches into a film that lives on the device until read back.

use super::params::Params;
use super::pipelines::Pipeline;
use super::tables::{SceneTables, params_buffer};
use super::{GpuContext, GpuError, shader};
use crate::film::Film;
use crate::render::{Checkpoints, RenderJob, RenderScene};
use crate::scene::{Camera, RenderSettings};
use glam::Vec3;
use std::ops::Range;

/// Paths traced per dispatch: about one sample per pixel of a 1080p image, so that no
/// dispatch runs long enough (~100 ms on a desktop GPU) for a driver watchdog to kill it.
pub const PATHS_PER_DISPATCH: u64 = 1 << 21;

/// Invocations per workgroup side of the render kernel. mirror: shaders/render.wgsl `render`
const WORKGROUP: u32 = 8;

/// The film being accumulated on the device: one texel per pixel for radiance, then one per
/// film channel ([`Film::texels_per_pixel`]).
struct DeviceFilm {
    template: Film,
    buffer: wgpu::Buffer,
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
    /// The render kernel, compiled by the first [`GpuRenderer::begin`] (a renderer that
    /// only serves [`Kernel`](super::kernels::Kernel)s never needs it).
    render: Option<Pipeline>,
    /// The parameters of the scene and of the film's settings; dispatches set the ranges.
    base: Params,
    params: wgpu::Buffer,
    scene_group: wgpu::BindGroup,
    film: Option<DeviceFilm>,
    /// The scene's part of the parameters and its camera, for the films of any settings.
    scene_params: Params,
    camera: Camera,
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
            base: scene_params,
            params,
            scene_group,
            film: None,
            scene_params,
            camera: scene.camera.clone(),
        })
    }

    /// The device this renderer runs on.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// The scene's tables, for kernels that read the same scene.
    pub(super) fn tables(&self) -> &SceneTables {
        &self.tables
    }

    /// The parameters of a render of `settings` on this scene, covering every row and no
    /// samples yet.
    pub(super) fn params_for(&self, settings: &RenderSettings) -> Params {
        self.scene_params.with_settings(&self.camera, settings)
    }

    /// Starts an empty film for `settings`, whose first sample will be `first_sample`.
    pub fn begin(&mut self, settings: &RenderSettings, first_sample: u32) -> Result<(), GpuError> {
        let template = Film::new(settings.width, settings.height);
        let texels = template.texels_per_pixel() as u32;
        let bytes = template.sum.len() as u64 * texels as u64 * 16;
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
            ..self.params_for(settings)
        };
        let buffer = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("film"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let render = match self.render.take() {
            Some(render) => render,
            None => Pipeline::new(
                &self.ctx,
                &self.tables.layout,
                &shader::render_source(),
                "render",
                0,
                1,
            )?,
        };
        let io_group = render.io_group(&self.ctx, &[&buffer]);
        self.render = Some(render);
        self.film = Some(DeviceFilm {
            template,
            buffer,
            io_group,
            first_sample,
            samples: 0,
        });
        self.ctx.check()
    }

    /// Traces samples `samples` of the pixels of rows `rows` into the film and waits for
    /// them. A pixel's samples must be dispatched in order, as the CPU adds them.
    pub fn dispatch(&mut self, samples: Range<u32>, rows: Range<u32>) -> Result<(), GpuError> {
        let (Some(film), Some(render)) = (&mut self.film, &self.render) else {
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
        let mut enc = self.ctx.device.create_command_encoder(&Default::default());
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
        self.ctx.wait()?;
        if rows.end == p.height {
            film.samples = samples.end - film.first_sample;
        }
        Ok(())
    }

    /// The film so far, with the samples that every pixel has received.
    pub fn read_film(&self) -> Result<Film, GpuError> {
        let Some(film) = &self.film else {
            return Err(GpuError::Fault("read_film before begin".into()));
        };
        let data = self.ctx.read_buffer(&film.buffer)?;
        let texels: &[[f32; 4]] = bytemuck::cast_slice(&data);
        let mut out = film.template.clone();
        out.samples = film.samples;
        let stride = out.texels_per_pixel();
        for (i, pixel) in texels.chunks_exact(stride).enumerate() {
            out.sum[i] = Vec3::new(pixel[0][0], pixel[0][1], pixel[0][2]);
            for (channel, &texel) in out.channels.iter_mut().zip(&pixel[1..]) {
                channel.data[i] = texel;
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
        self.begin(&job.settings, job.samples.start)?;
        let mut checkpoints = Checkpoints::new(job);
        for (samples, rows) in plan_dispatches(job) {
            self.dispatch(samples.clone(), rows.clone())?;
            progress(
                (samples.end - samples.start) as u64 * w as u64 * (rows.end - rows.start) as u64,
            );
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
