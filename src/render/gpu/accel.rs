//! The scene's acceleration structure for hardware ray queries (`--accel`, chosen when
//! the device is opened: [`super::Accel`]), one BLAS of the leaf-ordered triangles in one
//! TLAS, which `shaders/ray_query.wgsl` walks in place of `shaders/traverse.wgsl`.

use super::device::GpuDevice;
use super::error::GpuError;
use crate::geometry::TriVerts;
use wgpu::util::DeviceExt;

/// The scene's acceleration structure on the device: one BLAS over every triangle, in the
/// leaf order of the tables (no index buffer, so a hit's primitive index is the triangle's
/// index there, the `tri` of the software walk), as the one instance of a TLAS.
pub struct SceneAccel {
    /// Kept alive for the TLAS, which refers to it.
    _blas: wgpu::Blas,
    pub tlas: wgpu::Tlas,
}

impl SceneAccel {
    /// Builds the structures over `tris` and waits for the build. The geometry is opaque
    /// unless a triangle is masked: then every hit comes to the shader as a candidate, which
    /// confirms it where the alpha test passes.
    pub fn new(ctx: &GpuDevice, tris: &[TriVerts]) -> Result<Self, GpuError> {
        let count = tris.len() as u64;
        let limit = ctx.limits.max_blas_primitive_count as u64;
        if count > limit {
            return Err(GpuError::TooLarge {
                what: "triangles of the ray-query BLAS",
                bytes: count * size_of::<TriVerts>() as u64,
                limit: limit * size_of::<TriVerts>() as u64,
                rule: format!("max_blas_primitive_count = {limit} triangles; use --accel software"),
            });
        }
        let flags = if tris.iter().any(TriVerts::is_masked) {
            wgpu::AccelerationStructureGeometryFlags::empty()
        } else {
            wgpu::AccelerationStructureGeometryFlags::OPAQUE
        };
        let size = wgpu::BlasTriangleGeometrySizeDescriptor {
            vertex_format: wgpu::VertexFormat::Float32x3,
            vertex_count: 3 * tris.len() as u32,
            index_format: None,
            index_count: None,
            flags,
        };
        let blas = ctx.device.create_blas(
            &wgpu::CreateBlasDescriptor {
                label: Some("scene BLAS"),
                flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
                update_mode: wgpu::AccelerationStructureUpdateMode::Build,
            },
            wgpu::BlasGeometrySizeDescriptors::Triangles {
                descriptors: vec![size.clone()],
            },
        );
        let mut tlas = ctx.device.create_tlas(&wgpu::CreateTlasDescriptor {
            label: Some("scene TLAS"),
            max_instances: 1,
            flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
            update_mode: wgpu::AccelerationStructureUpdateMode::Build,
        });
        // The corners as they lie in the table: a vertex every 16 bytes (its fourth word,
        // the mask or object bits, is padding to the BLAS).
        let vertices = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("BLAS vertices"),
                contents: bytemuck::cast_slice(tris),
                usage: wgpu::BufferUsages::BLAS_INPUT,
            });
        let identity = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        if !tris.is_empty() {
            tlas[0] = Some(wgpu::TlasInstance::new(&blas, identity, 0, 0xff));
        }
        let geometry = wgpu::BlasTriangleGeometry {
            size: &size,
            vertex_buffer: &vertices,
            first_vertex: 0,
            vertex_stride: 16,
            index_buffer: None,
            first_index: None,
            transform_buffer: None,
            transform_buffer_offset: None,
        };
        let entry = wgpu::BlasBuildEntry {
            blas: &blas,
            geometry: wgpu::BlasGeometries::TriangleGeometries(vec![geometry]),
        };
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        let blases: &[wgpu::BlasBuildEntry] = if tris.is_empty() { &[] } else { &[entry] };
        enc.build_acceleration_structures(blases, [&tlas]);
        ctx.queue.submit([enc.finish()]);
        ctx.wait()?;
        Ok(Self { _blas: blas, tlas })
    }
}
