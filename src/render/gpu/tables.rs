//! The scene's tables on the device: each uploaded as it lies in memory into an
//! Rgba32Uint texture, [`TABLE_WIDTH`] texels a row, and the bind group layout (group 0)
//! that the shaders read them through (`shaders/bindings.wgsl`). A texel fetch is a
//! gather on every device, and a texture of 4096 × 16384 texels holds 1 GiB, far beyond
//! some drivers' limits on a storage binding.

use super::params::{GpuMaterial, GpuParams};
use super::{GpuContext, GpuError};
use crate::render::RenderScene;

/// Texels per row of the table textures. mirror: shaders/bindings.wgsl `TABLE_WIDTH_LOG2`
pub const TABLE_WIDTH: u32 = 1 << 12;

/// Rows of a table texture written per upload step: wgpu stages each write in memory of
/// its own, so bounded steps keep the upload from doubling the scene's footprint.
const UPLOAD_ROWS: usize = 256;

/// The scene's tables in binding order (bindings 1, 2, …; binding 0 is the parameter
/// block), each with the name errors give it.
fn scene_tables<'a>(
    scene: &'a RenderScene,
    materials: &'a [GpuMaterial],
) -> Vec<(&'static str, &'a [u8])> {
    vec![
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

/// A scene uploaded to one device: its table textures and the layout of the bind group
/// (group 0) that holds them with a parameter block.
pub struct SceneTables {
    views: Vec<wgpu::TextureView>,
    pub layout: wgpu::BindGroupLayout,
}

impl SceneTables {
    /// Uploads every table, checking each against the adapter's limits.
    pub fn new(ctx: &GpuContext, scene: &RenderScene) -> Result<Self, GpuError> {
        let materials: Vec<GpuMaterial> = scene.materials.iter().map(GpuMaterial::from).collect();
        let views = scene_tables(scene, &materials)
            .into_iter()
            .map(|(what, data)| table_texture(ctx, what, data))
            .collect::<Result<Vec<_>, _>>()?;
        let mut entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: wgpu::BufferSize::new(size_of::<GpuParams>() as u64),
            },
            count: None,
        }];
        entries.extend(
            (1..=views.len() as u32).map(|binding| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Uint,
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }),
        );
        let layout = ctx
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("scene"),
                entries: &entries,
            });
        ctx.check()?;
        Ok(Self { views, layout })
    }

    /// The scene bind group: `params` (one [`GpuParams`] block) and the tables.
    pub fn bind_group(&self, ctx: &GpuContext, params: &wgpu::Buffer) -> wgpu::BindGroup {
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: params.as_entire_binding(),
        }];
        entries.extend(
            self.views
                .iter()
                .enumerate()
                .map(|(i, v)| wgpu::BindGroupEntry {
                    binding: i as u32 + 1,
                    resource: wgpu::BindingResource::TextureView(v),
                }),
        );
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &self.layout,
            entries: &entries,
        })
    }
}

/// A uniform buffer holding one parameter block, rewritten before each dispatch.
pub fn params_buffer(ctx: &GpuContext) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("dispatch parameters"),
        size: size_of::<GpuParams>() as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

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
