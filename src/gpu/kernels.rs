//! Runs auxiliary compute entry points over a scene's buffers: the shader unit-test kernels
//! of `shaders/tests.wgsl` (two `vec4<u32>` in and two out per case), and the ray-throughput
//! kernels of `shaders/bench.wgsl` (one ray in, one hit out).

use super::layout::GpuParams;
use super::renderer::{GpuScene, TableStorage, params_buffer, pipeline, read_back};
use super::{GpuContext, GpuError, shader};
use crate::render::RenderScene;
use crate::scene::RenderSettings;
use std::time::Instant;
use wgpu::util::DeviceExt;

/// A compiled entry point bound to an uploaded scene, ready to run on many inputs.
pub struct Kernel<'a> {
    ctx: &'a GpuContext,
    pipeline: wgpu::ComputePipeline,
    io_layout: wgpu::BindGroupLayout,
    scene_group: wgpu::BindGroup,
    _params: wgpu::Buffer,
    _scene: GpuScene,
}

impl<'a> Kernel<'a> {
    /// Uploads `scene` as the renderer would and compiles `entry` of the module that
    /// `source` joins (a function of [`shader`]) for that upload.
    pub fn new(
        ctx: &'a GpuContext,
        scene: &RenderScene,
        settings: &RenderSettings,
        source: fn(TableStorage) -> String,
        entry: &str,
    ) -> Result<Self, GpuError> {
        let gpu_scene = GpuScene::new(ctx, scene, TableStorage::choose(ctx, scene))?;
        let source = source(gpu_scene.storage());
        let mut p = GpuParams::new(scene, settings);
        p.sample_end = settings.spp;
        let params = params_buffer(ctx, &[p]);
        let scene_group = gpu_scene.bind_group(ctx, &params);
        let (pipeline, io_layout) = pipeline(ctx, &gpu_scene, &source, entry, 1, 1)?;
        Ok(Self {
            ctx,
            pipeline,
            io_layout,
            scene_group,
            _params: params,
            _scene: gpu_scene,
        })
    }

    /// Runs one invocation per `cases` over `input`, returning `output_len` words and the
    /// seconds the dispatch took on the device (upload and readback excluded).
    pub fn run(
        &self,
        input: &[[u32; 4]],
        cases: usize,
        output_len: usize,
    ) -> Result<(Vec<[u32; 4]>, f64), GpuError> {
        let ctx = self.ctx;
        let input_buf = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("kernel input"),
                contents: bytemuck::cast_slice(input),
                usage: wgpu::BufferUsages::STORAGE,
            });
        let output = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("kernel output"),
            size: (output_len.max(1) * 16) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let io_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("kernel io"),
            layout: &self.io_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: input_buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: output.as_entire_binding(),
                },
            ],
        });
        // Finish the uploads first so that the timing covers the dispatch alone.
        ctx.wait()?;
        let start = Instant::now();
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.scene_group, &[0]);
            pass.set_bind_group(1, &io_group, &[]);
            // 64 invocations per workgroup, at most 65535 workgroups along x.
            let groups = (cases as u32).div_ceil(64);
            pass.dispatch_workgroups(groups.min(65535), groups.div_ceil(65535), 1);
        }
        ctx.queue.submit([enc.finish()]);
        ctx.wait()?;
        let seconds = start.elapsed().as_secs_f64();
        let data = read_back(ctx, &output)?;
        Ok((bytemuck::cast_slice(&data).to_vec(), seconds))
    }
}

/// Runs test entry point `entry` over `input` (two words per case) and returns its two
/// output words per case.
pub fn run_test_kernel(
    ctx: &GpuContext,
    scene: &RenderScene,
    settings: &RenderSettings,
    entry: &str,
    input: &[[u32; 4]],
) -> Result<Vec<[u32; 4]>, GpuError> {
    assert!(input.len() % 2 == 0, "two input words per case");
    let kernel = Kernel::new(ctx, scene, settings, shader::test_source, entry)?;
    Ok(kernel.run(input, input.len() / 2, input.len())?.0)
}
