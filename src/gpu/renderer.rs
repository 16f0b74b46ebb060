//! The dispatch loop: uploads a scene, traces batches of samples, accumulates, reads back.

use super::layout::{GpuMaterial, GpuParams};
use super::{GpuContext, GpuError, shader};
use crate::film::Film;
use crate::render::{Checkpoints, RenderJob, RenderScene};
use glam::Vec3;
use wgpu::util::DeviceExt;

/// Paths traced per dispatch: about one sample per pixel of a 1080p image, so that no
/// dispatch runs long enough (~100 ms on a desktop GPU) for a driver watchdog to kill it.
pub const PATHS_PER_DISPATCH: u64 = 1 << 21;
const WORKGROUP: u32 = 8;
/// Texels per row of the table textures. mirror: shaders/bindings.wgsl `TABLE_WIDTH_LOG2`
pub const TABLE_WIDTH: u32 = 1 << 12;

/// Rows of a table texture written per upload step: wgpu stages each write in memory of
/// its own, so bounded steps keep the upload from doubling the scene's footprint.
const UPLOAD_ROWS: usize = 256;

/// Uploads a table of 16-byte texels as an Rgba32Uint texture `TABLE_WIDTH` texels wide.
/// The table is written from where it lies, in steps of [`UPLOAD_ROWS`] rows, each
/// finished before the next, so no copy of the whole table is ever made.
fn table_texture(
    ctx: &GpuContext,
    what: &'static str,
    data: &[u8],
) -> Result<wgpu::TextureView, GpuError> {
    let texels = (data.len() as u64).div_ceil(16);
    let rows = texels.div_ceil(TABLE_WIDTH as u64).max(1);
    let max_rows = ctx.limits.max_texture_dimension_2d as u64;
    if rows > max_rows {
        return Err(GpuError::TooLarge {
            what,
            bytes: data.len() as u64,
            limit: max_rows * TABLE_WIDTH as u64 * 16,
        });
    }
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(what),
        size: wgpu::Extent3d {
            width: TABLE_WIDTH,
            height: rows as u32,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Uint,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let row_bytes = TABLE_WIDTH as usize * 16;
    let write = |first_row: usize, bytes: &[u8]| {
        let n = (bytes.len() / row_bytes) as u32;
        let mut dst = texture.as_image_copy();
        dst.origin.y = first_row as u32;
        ctx.queue.write_texture(
            dst,
            bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row_bytes as u32),
                rows_per_image: Some(n),
            },
            wgpu::Extent3d {
                width: TABLE_WIDTH,
                height: n,
                depth_or_array_layers: 1,
            },
        );
    };
    let full = data.len() / row_bytes;
    for (i, chunk) in data[..full * row_bytes]
        .chunks(UPLOAD_ROWS * row_bytes)
        .enumerate()
    {
        write(i * UPLOAD_ROWS, chunk);
        ctx.queue.submit([]);
        ctx.wait()?;
    }
    if full < rows as usize {
        // The last row, zero-padded (an empty table is one row of zeros).
        let mut last = vec![0u8; row_bytes];
        let tail = &data[full * row_bytes..];
        last[..tail.len()].copy_from_slice(tail);
        write(full, &last);
    }
    Ok(texture.create_view(&Default::default()))
}

/// How the scene's tables are bound: the shaders read them through the same `load_*`
/// functions either way (`shaders/bindings.wgsl`, `shaders/bindings_uniform.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TableStorage {
    /// One Rgba32Uint texture per table: any size, and fast on GPUs.
    Textures,
    /// All tables packed into one 64 KiB uniform array: small scenes only. lavapipe
    /// gathers uniform loads far more cheaply than it fetches texels.
    Uniform,
}

/// Texels (16 bytes) of the packed uniform array, header included.
/// mirror: shaders/bindings_uniform.wgsl `UNIFORM_TABLE_TEXELS`
pub const UNIFORM_TABLE_TEXELS: usize = 4096;

/// Texels of the packed array's header: where each table starts.
const UNIFORM_HEADER_TEXELS: usize = 2;

impl TableStorage {
    /// The storage for `scene` on this device: the packed uniform array on software
    /// adapters when the scene fits, textures otherwise.
    pub fn choose(ctx: &GpuContext, scene: &RenderScene) -> Self {
        let fits = packed_bytes(&scene_tables(scene, &materials(scene))) <= uniform_capacity(ctx);
        if ctx.adapter.software && fits {
            TableStorage::Uniform
        } else {
            TableStorage::Textures
        }
    }
}

fn materials(scene: &RenderScene) -> Vec<GpuMaterial> {
    scene.materials.iter().map(GpuMaterial::from).collect()
}

/// The six tables in binding order, named for errors.
fn scene_tables<'a>(
    scene: &'a RenderScene,
    materials: &'a [GpuMaterial],
) -> [(&'static str, &'a [u8]); 6] {
    [
        ("BVH nodes", bytemuck::cast_slice(&scene.bvh.nodes)),
        ("triangles", bytemuck::cast_slice(&scene.tris)),
        (
            "triangle shading data",
            bytemuck::cast_slice(&scene.shading),
        ),
        ("materials", bytemuck::cast_slice(materials)),
        ("emitters", bytemuck::cast_slice(&scene.emitters)),
        ("emitter CDF", bytemuck::cast_slice(&scene.emitter_cdf)),
    ]
}

/// Bytes the packed uniform array needs for `tables`, header included.
fn packed_bytes(tables: &[(&str, &[u8]); 6]) -> u64 {
    let texels = UNIFORM_HEADER_TEXELS
        + tables
            .iter()
            .map(|(_, data)| data.len().div_ceil(16))
            .sum::<usize>();
    texels as u64 * 16
}

/// Bytes the packed uniform array can hold on this device: the WGSL array's whole size,
/// which is always bound, or nothing where the adapter's uniform bindings are smaller.
fn uniform_capacity(ctx: &GpuContext) -> u64 {
    let bytes = (UNIFORM_TABLE_TEXELS * 16) as u64;
    if bytes <= ctx.limits.max_uniform_buffer_binding_size {
        bytes
    } else {
        0
    }
}

/// The packed uniform array: a header of first texels, then each table, 16-byte aligned.
fn pack_tables(tables: &[(&str, &[u8]); 6]) -> Vec<u8> {
    let mut header = [0u32; 4 * UNIFORM_HEADER_TEXELS];
    let mut body = Vec::new();
    for (i, (_, data)) in tables.iter().enumerate() {
        header[i] = (UNIFORM_HEADER_TEXELS + body.len() / 16) as u32;
        body.extend_from_slice(data);
        body.resize(body.len().next_multiple_of(16), 0);
    }
    let mut out = bytemuck::cast_slice(&header).to_vec();
    out.extend(body);
    out.resize(UNIFORM_TABLE_TEXELS * 16, 0);
    out
}

/// What a scene's tables were uploaded as.
enum Tables {
    Textures(Vec<wgpu::TextureView>),
    Uniform(wgpu::Buffer),
}

/// A scene uploaded to one device: its tables, the scene bind group's layout.
pub struct GpuScene {
    tables: Tables,
    pub layout: wgpu::BindGroupLayout,
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// The byte stride between per-dispatch parameter blocks in the uniform buffer.
fn params_stride(ctx: &GpuContext) -> u64 {
    let align = ctx.limits.min_uniform_buffer_offset_alignment as u64;
    (size_of::<GpuParams>() as u64).div_ceil(align) * align
}

impl GpuScene {
    /// Uploads the scene's tables as `storage` says, checking them against the adapter's
    /// limits.
    pub fn new(
        ctx: &GpuContext,
        scene: &RenderScene,
        storage: TableStorage,
    ) -> Result<Self, GpuError> {
        let materials = materials(scene);
        let tables = scene_tables(scene, &materials);
        let mut entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: wgpu::BufferSize::new(size_of::<GpuParams>() as u64),
            },
            count: None,
        }];
        let tables = match storage {
            TableStorage::Textures => {
                let views = tables
                    .iter()
                    .map(|(what, data)| table_texture(ctx, what, data))
                    .collect::<Result<Vec<_>, _>>()?;
                entries.extend((1..=views.len() as u32).map(|binding| {
                    wgpu::BindGroupLayoutEntry {
                        binding,
                        visibility: wgpu::ShaderStages::COMPUTE,
                        ty: wgpu::BindingType::Texture {
                            sample_type: wgpu::TextureSampleType::Uint,
                            view_dimension: wgpu::TextureViewDimension::D2,
                            multisampled: false,
                        },
                        count: None,
                    }
                }));
                Tables::Textures(views)
            }
            TableStorage::Uniform => {
                let (bytes, limit) = (packed_bytes(&tables), uniform_capacity(ctx));
                if bytes > limit {
                    return Err(GpuError::TooLarge {
                        what: "packed scene tables",
                        bytes,
                        limit,
                    });
                }
                let buffer = ctx
                    .device
                    .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("scene tables"),
                        contents: &pack_tables(&tables),
                        usage: wgpu::BufferUsages::UNIFORM,
                    });
                entries.push(wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new((UNIFORM_TABLE_TEXELS * 16) as u64),
                    },
                    count: None,
                });
                Tables::Uniform(buffer)
            }
        };
        let layout = ctx
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("scene"),
                entries: &entries,
            });
        ctx.check()?;
        Ok(Self { tables, layout })
    }

    /// How the tables were uploaded; the shader source must match it.
    pub fn storage(&self) -> TableStorage {
        match self.tables {
            Tables::Textures(_) => TableStorage::Textures,
            Tables::Uniform(_) => TableStorage::Uniform,
        }
    }

    /// The scene bind group, with `params` (one block per dispatch, at `params_stride`).
    pub fn bind_group(&self, ctx: &GpuContext, params: &wgpu::Buffer) -> wgpu::BindGroup {
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: params,
                offset: 0,
                size: wgpu::BufferSize::new(size_of::<GpuParams>() as u64),
            }),
        }];
        match &self.tables {
            Tables::Textures(views) => {
                entries.extend(views.iter().enumerate().map(|(i, v)| wgpu::BindGroupEntry {
                    binding: i as u32 + 1,
                    resource: wgpu::BindingResource::TextureView(v),
                }))
            }
            Tables::Uniform(buffer) => entries.push(wgpu::BindGroupEntry {
                binding: 1,
                resource: buffer.as_entire_binding(),
            }),
        }
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &self.layout,
            entries: &entries,
        })
    }
}

/// Uploads per-dispatch parameter blocks into one uniform buffer.
pub fn params_buffer(ctx: &GpuContext, blocks: &[GpuParams]) -> wgpu::Buffer {
    let stride = params_stride(ctx) as usize;
    let mut data = vec![0u8; stride * blocks.len().max(1)];
    for (i, p) in blocks.iter().enumerate() {
        data[i * stride..i * stride + size_of::<GpuParams>()]
            .copy_from_slice(bytemuck::bytes_of(p));
    }
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("dispatch parameters"),
            contents: &data,
            usage: wgpu::BufferUsages::UNIFORM,
        })
}

/// Builds a compute pipeline over the scene layout plus one group of storage buffers
/// (`outputs` read-write ones after `inputs` read-only ones).
pub fn pipeline(
    ctx: &GpuContext,
    scene: &GpuScene,
    source: &str,
    entry: &str,
    inputs: u32,
    outputs: u32,
) -> Result<(wgpu::ComputePipeline, wgpu::BindGroupLayout), GpuError> {
    let io_entries: Vec<_> = (0..inputs + outputs)
        .map(|b| storage_entry(b, b < inputs))
        .collect();
    let io_layout = ctx
        .device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("io"),
            entries: &io_entries,
        });
    let module = ctx
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("meshtrace"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
    let layout = ctx
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(entry),
            bind_group_layouts: &[Some(&scene.layout), Some(&io_layout)],
            immediate_size: 0,
        });
    let pipeline = ctx
        .device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&layout),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
    ctx.check()?;
    Ok((pipeline, io_layout))
}

/// Copies a storage buffer back to the host.
pub fn read_back(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let size = buffer.size();
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    ctx.queue.submit([enc.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    ctx.wait()?;
    rx.recv()
        .map_err(|e| GpuError::Fault(e.to_string()))?
        .map_err(|e| GpuError::Fault(e.to_string()))?;
    let data = staging
        .get_mapped_range(..)
        .map_err(|e| GpuError::Fault(e.to_string()))?
        .to_vec();
    staging.unmap();
    Ok(data)
}

/// The dispatches of a job: sample ranges over row bands, each at most
/// [`PATHS_PER_DISPATCH`] paths, in an order that keeps every pixel's samples in sequence.
pub fn plan_dispatches(base: &GpuParams, job: &RenderJob) -> Vec<GpuParams> {
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
            out.push(GpuParams {
                sample_start: s,
                sample_end: s_end,
                row_start: r as u32,
                row_end: r_end as u32,
                ..*base
            });
            r = r_end;
        }
        s = s_end;
    }
    out
}

/// The film and ray count in a read-back accumulation buffer.
fn film_of(data: &[u8], w: u32, h: u32, samples: u32) -> (Film, u64) {
    let sums: &[[f32; 4]] = bytemuck::cast_slice(data);
    let mut film = Film::new(w, h);
    film.samples = samples;
    let mut rays = 0u64;
    for (dst, s) in film.sum.iter_mut().zip(sums) {
        *dst = Vec3::new(s[0], s[1], s[2]);
        rays += s[3] as u64;
    }
    (film, rays)
}

/// Renders the job's sample range on the GPU. `progress` is told the samples each
/// dispatch finished. Stops early, after a whole pass, when the job is cancelled; the film's
/// `samples` says how many it holds. Returns the film and the number of rays traced.
pub fn render(
    ctx: &GpuContext,
    scene: &RenderScene,
    job: &RenderJob,
    progress: &dyn Fn(u64),
) -> Result<(Film, u64), GpuError> {
    render_with(ctx, scene, job, TableStorage::choose(ctx, scene), progress)
}

/// [`render`] with the tables stored as `storage` says; the image is the same either way.
pub fn render_with(
    ctx: &GpuContext,
    scene: &RenderScene,
    job: &RenderJob,
    storage: TableStorage,
    progress: &dyn Fn(u64),
) -> Result<(Film, u64), GpuError> {
    let (w, h) = (job.settings.width, job.settings.height);
    let pixels = w as u64 * h as u64;
    let accum_bytes = pixels * 16;
    let limit = ctx.limits.max_storage_buffer_binding_size;
    if accum_bytes > limit {
        return Err(GpuError::TooLarge {
            what: "film",
            bytes: accum_bytes,
            limit,
        });
    }
    let gpu_scene = GpuScene::new(ctx, scene, storage)?;
    let blocks = plan_dispatches(&GpuParams::new(scene, &job.settings), job);
    let params = params_buffer(ctx, &blocks);
    let scene_group = gpu_scene.bind_group(ctx, &params);
    let (pipeline, io_layout) = pipeline(
        ctx,
        &gpu_scene,
        &shader::render_source(storage),
        "render",
        0,
        1,
    )?;
    let accum = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("accumulation"),
        size: accum_bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let io_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("accumulation"),
        layout: &io_layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: accum.as_entire_binding(),
        }],
    });
    let stride = params_stride(ctx);
    let mut checkpoints = Checkpoints::new(job);
    // Samples every pixel has received: a pass is complete when its last row band is.
    let mut samples_done = 0;
    for (i, b) in blocks.iter().enumerate() {
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("render"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &scene_group, &[(i as u64 * stride) as u32]);
            pass.set_bind_group(1, &io_group, &[]);
            pass.dispatch_workgroups(
                w.div_ceil(WORKGROUP),
                (b.row_end - b.row_start).div_ceil(WORKGROUP),
                1,
            );
        }
        ctx.queue.submit([enc.finish()]);
        ctx.wait()?;
        progress(
            (b.sample_end - b.sample_start) as u64 * w as u64 * (b.row_end - b.row_start) as u64,
        );
        if b.row_end == h {
            samples_done = b.sample_end - job.samples.start;
            let more = b.sample_end < job.samples.end;
            if more && job.cancelled() {
                break;
            }
            if more && checkpoints.due() {
                checkpoints.write(&film_of(&read_back(ctx, &accum)?, w, h, samples_done).0);
            }
        }
    }
    let (film, rays) = film_of(&read_back(ctx, &accum)?, w, h, samples_done);
    Ok((film, rays))
}
