//! Runs auxiliary compute entry points over a [`GpuRenderer`]'s scene: the shader unit-test
//! kernels of `shaders/tests.wgsl` (two `vec4<u32>` in and two out per case), and the
//! ray-throughput kernels of `shaders/bench.wgsl` (one ray in, one hit out).

use super::pipelines::Pipeline;
use super::shader::{Module, ShaderChecks};
use super::upload::params_buffer;
use super::{GpuContext, GpuError, GpuRenderer, shader};
use crate::render::tables::RenderScene;
use crate::scene::RenderSettings;
use std::sync::Arc;
use std::time::Instant;
use wgpu::util::DeviceExt;

/// A compiled entry point bound to a renderer's scene, ready to run on many inputs.
pub struct Kernel<'a> {
    renderer: &'a GpuRenderer,
    pipeline: Arc<Pipeline>,
    scene_group: wgpu::BindGroup,
    _params: wgpu::Buffer,
}

impl<'a> Kernel<'a> {
    /// `entry` of `module` (a function of [`shader`]), compiled as `checks` says (or
    /// taken from the device's cache), over the renderer's scene, with the parameters of
    /// a render of `settings` (all its samples).
    pub fn new(
        renderer: &'a GpuRenderer,
        settings: &RenderSettings,
        module: Module,
        checks: ShaderChecks,
        entry: &str,
    ) -> Result<Self, GpuError> {
        let ctx = renderer.context();
        let tables = renderer.tables();
        let mut p = renderer.params_for(settings);
        p.sample_end = settings.spp;
        let params = params_buffer(ctx);
        ctx.queue.write_buffer(&params, 0, bytemuck::bytes_of(&p));
        let scene_group = tables.bind_group(ctx, &params);
        let pipeline = ctx.pipeline(module, entry, (1, 1), checks, renderer.features())?;
        Ok(Self {
            renderer,
            pipeline,
            scene_group,
            _params: params,
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
        let ctx = self.renderer.context();
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
        let io_group = self.pipeline.io_group(ctx, &[&input_buf, &output]);
        // Finish the uploads first so that the timing covers the dispatch alone.
        ctx.wait()?;
        let start = Instant::now();
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline.pipeline);
            pass.set_bind_group(0, &self.scene_group, &[]);
            pass.set_bind_group(1, &io_group, &[]);
            // 64 invocations per workgroup, at most 65535 workgroups along x.
            let groups = (cases as u32).div_ceil(64);
            pass.dispatch_workgroups(groups.min(65535), groups.div_ceil(65535), 1);
        }
        ctx.queue.submit([enc.finish()]);
        ctx.wait()?;
        let seconds = start.elapsed().as_secs_f64();
        let data = ctx.read_buffer(&output)?;
        Ok((bytemuck::cast_slice(&data).to_vec(), seconds))
    }
}

/// Uploads `scene` and runs test entry point `entry` over `input` (two words per case);
/// returns its two output words per case. The module is checked ([`ShaderChecks`]), since
/// the unit tests feed it arbitrary inputs.
pub fn run_test_kernel(
    ctx: &GpuContext,
    scene: &RenderScene,
    settings: &RenderSettings,
    entry: &str,
    input: &[[u32; 4]],
) -> Result<Vec<[u32; 4]>, GpuError> {
    assert!(input.len().is_multiple_of(2), "two input words per case");
    let renderer = GpuRenderer::new(ctx, scene)?;
    let checks = ShaderChecks::Checked;
    let kernel = Kernel::new(&renderer, settings, shader::test_source, checks, entry)?;
    Ok(kernel.run(input, input.len() / 2, input.len())?.0)
}
