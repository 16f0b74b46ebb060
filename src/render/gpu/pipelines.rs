//! Compute pipelines: a WGSL module compiled once for one entry point, over the scene's
//! bind group (group 0) and one group of storage buffers of its own (group 1).

use super::device::GpuDevice;
use super::error::GpuError;
use super::shader::{Features, ShaderChecks};

/// A compiled entry point and the layout of its storage group.
pub struct Pipeline {
    pub pipeline: wgpu::ComputePipeline,
    pub io_layout: wgpu::BindGroupLayout,
}

impl Pipeline {
    /// Compiles `entry` of the WGSL `source` (a module of [`super::shader`], generated for
    /// the device's traversal and `checks`), as `checks` says and with the scene's
    /// `features`, over `scene_layout` plus one group of storage buffers: `inputs`
    /// read-only ones, then `outputs` read-write ones.
    pub fn new(
        ctx: &GpuDevice,
        scene_layout: &wgpu::BindGroupLayout,
        source: &str,
        entry: &str,
        (inputs, outputs): (u32, u32),
        checks: ShaderChecks,
        features: Features,
    ) -> Result<Self, GpuError> {
        let io_entries: Vec<_> = (0..inputs + outputs)
            .map(|binding| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage {
                        read_only: binding < inputs,
                    },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            })
            .collect();
        let io_layout = ctx
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("io"),
                entries: &io_entries,
            });
        let desc = wgpu::ShaderModuleDescriptor {
            label: Some("meshtrace"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        };
        let module = match checks {
            ShaderChecks::Checked => ctx.device.create_shader_module(desc),
            // SAFETY: the kernels index only in range, divide by no zero and end all
            // their loops, as `ShaderChecks` sets out; tests/checked_kernels.rs checks it
            // on the test scenes with the checked build of the same source. Ray-query
            // tracking stays on: it also guards queries against rays with NaN in them,
            // which a degenerate path can produce.
            ShaderChecks::Trusted => unsafe {
                ctx.device.create_shader_module_trusted(
                    desc,
                    wgpu::ShaderRuntimeChecks {
                        ray_query_initialization_tracking: true,
                        ..wgpu::ShaderRuntimeChecks::unchecked()
                    },
                )
            },
        };
        let layout = ctx
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(entry),
                bind_group_layouts: &[Some(scene_layout), Some(&io_layout)],
                immediate_size: 0,
            });
        let pipeline = ctx
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &features.constants(),
                    ..Default::default()
                },
                cache: None,
            });
        ctx.check()?;
        Ok(Self {
            pipeline,
            io_layout,
        })
    }

    /// A bind group for the storage group, binding `buffers` in order.
    pub fn io_group(&self, ctx: &GpuDevice, buffers: &[&wgpu::Buffer]) -> wgpu::BindGroup {
        let entries: Vec<_> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("io"),
            layout: &self.io_layout,
            entries: &entries,
        })
    }
}
