//! Runs the shader unit-test entry points of `shaders/tests.wgsl`: each takes two input
//! `vec4<u32>` per case and writes two output `vec4<u32>` per case, over a scene's
//! buffers, so the tests can compare every WGSL stage with its Rust twin.

use super::layout::GpuParams;
use super::renderer::{GpuScene, params_buffer, pipeline, read_back};
use super::{GpuContext, GpuError, shader};
use crate::render::RenderScene;
use crate::scene::RenderSettings;
use wgpu::util::DeviceExt;

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
    let gpu_scene = GpuScene::new(ctx, scene)?;
    let mut p = GpuParams::new(scene, settings);
    p.sample_end = settings.spp;
    let params = params_buffer(ctx, &[p]);
    let scene_group = gpu_scene.bind_group(ctx, &params);
    let (pipeline, io_layout) = pipeline(ctx, &gpu_scene, &shader::test_source(), entry, 1, 1)?;
    let input_buf = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("test input"),
            contents: bytemuck::cast_slice(input),
            usage: wgpu::BufferUsages::STORAGE,
        });
    let output = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("test output"),
        size: (input.len() * 16) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let io_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("test io"),
        layout: &io_layout,
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
    let cases = (input.len() / 2) as u32;
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &scene_group, &[0]);
        pass.set_bind_group(1, &io_group, &[]);
        // 64 invocations per workgroup, at most 65535 workgroups along x.
        let groups = cases.div_ceil(64);
        pass.dispatch_workgroups(groups.min(65535), groups.div_ceil(65535), 1);
    }
    ctx.queue.submit([enc.finish()]);
    ctx.wait()?;
    let data = read_back(ctx, &output)?;
    Ok(bytemuck::cast_slice(&data).to_vec())
}
