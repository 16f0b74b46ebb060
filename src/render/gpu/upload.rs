//! The scene's tables uploaded to one device, with its acceleration structure where the
//! device traces with ray queries, and the bind group that holds them.

use super::accel::SceneAccel;
use super::device::GpuDevice;
use super::error::GpuError;
use super::params::Params;
use super::tables::{TABLE_WIDTH, TABLES, TLAS_BINDING};
use crate::render::tables::RenderScene;

/// Rows of a table texture written per upload step: wgpu stages each write in memory of
/// its own, so bounded steps keep the upload from doubling the scene's footprint.
const UPLOAD_ROWS: usize = 256;

/// A scene uploaded to one device: its table textures, on a device that traces with ray
/// queries its acceleration structure, and the layout of the bind group (group 0) that
/// holds them with a parameter block (the device's [`scene_layout`](super::tables::scene_layout)).
pub struct SceneTables {
    views: Vec<wgpu::TextureView>,
    accel: Option<SceneAccel>,
    pub layout: wgpu::BindGroupLayout,
}

impl SceneTables {
    /// Uploads every table, checking each against the adapter's limits, and builds the
    /// acceleration structure where `ctx` traces with ray queries.
    pub fn new(ctx: &GpuDevice, scene: &RenderScene) -> Result<Self, GpuError> {
        let views = TABLES
            .iter()
            .map(|t| table_texture(ctx, t.what, (t.bytes)(scene)))
            .collect::<Result<Vec<_>, _>>()?;
        let accel = if ctx.ray_query {
            Some(SceneAccel::new(ctx, &scene.tris)?)
        } else {
            None
        };
        let layout = ctx.scene_layout.clone();
        ctx.check()?;
        Ok(Self {
            views,
            accel,
            layout,
        })
    }

    /// The scene bind group: `params` (one [`Params`] block), the tables and the TLAS.
    pub fn bind_group(&self, ctx: &GpuDevice, params: &wgpu::Buffer) -> wgpu::BindGroup {
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
        if let Some(accel) = &self.accel {
            entries.push(wgpu::BindGroupEntry {
                binding: TLAS_BINDING,
                resource: wgpu::BindingResource::AccelerationStructure(&accel.tlas),
            });
        }
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &self.layout,
            entries: &entries,
        })
    }
}

/// A uniform buffer holding one parameter block, rewritten before each dispatch.
pub fn params_buffer(ctx: &GpuDevice) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("dispatch parameters"),
        size: size_of::<Params>() as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Uploads a table of 16-byte texels as an Rgba32Uint texture `TABLE_WIDTH` texels wide.
/// The table is written from where it lies, in steps of [`UPLOAD_ROWS`] rows, each
/// finished before the next, so no copy of the whole table is ever made.
fn table_texture(
    ctx: &GpuDevice,
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
            rule: format!(
                "a table is a texture of at most max_texture_dimension_2d = {max_rows} rows of {TABLE_WIDTH} 16-byte texels"
            ),
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
