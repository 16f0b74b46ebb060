//! The uniform block of every dispatch, twin of `Params` in `shaders/types.wgsl` (the scene
//! tables' structs live beside the code that builds them); `tests/layout.rs` checks them
//! all against naga's layout.

use super::layout::{StructLayout, struct_layout};
use crate::math::Aabb;
use crate::render::camera::CameraRays;
use crate::render::integrator::branch_weight;
use crate::render::tables::RenderScene;
use crate::scene::{Camera, RenderSettings, Sky};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// What [`Params::sky_kind`] says the sky is. The shaders get these from
/// `shader::shared_constants`.
pub const SKY_CONSTANT: u32 = 0;
pub const SKY_GRADIENT: u32 = 1;
pub const SKY_ENVIRONMENT: u32 = 2;

/// One dispatch's parameters (256 bytes). mirror: shaders/types.wgsl `Params`
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Params {
    pub cam_position: [f32; 3],
    pub width: u32,
    pub cam_forward: [f32; 3],
    pub height: u32,
    pub cam_right: [f32; 3],
    pub max_depth: u32,
    pub cam_up: [f32; 3],
    pub seed: u32,
    pub sky_zenith: [f32; 3],
    /// A `SKY_*` code.
    pub sky_kind: u32,
    pub sky_horizon: [f32; 3],
    pub num_emitters: u32,
    pub tan_half_vfov: f32,
    pub aspect: f32,
    pub aperture: f32,
    pub focus_distance: f32,
    pub sample_start: u32,
    pub sample_end: u32,
    pub row_start: u32,
    pub row_end: u32,
    pub sky_pmf: f32,
    /// Texels per pixel of the accumulation buffer
    /// ([`Film::texels_per_pixel`](crate::film::Film::texels_per_pixel)); set with the film.
    pub film_texels: u32,
    /// The environment map ([`crate::render::Environment`]), for `SKY_ENVIRONMENT`.
    pub env_texture: u32,
    pub env_strength: f32,
    pub env_rotation: [f32; 2],
    pub env_cells: [u32; 2],
    /// The film's AOVs ([`Aov::mask`](crate::film::Aov::mask)) and whether it is
    /// [`transparent`](crate::film::Film::transparent) (1); set with the film.
    pub aovs: u32,
    pub transparent: u32,
    /// Spheres in the caustic targets table ([`RenderScene::caustic_targets`]); 0 traces
    /// no light subpaths.
    pub num_caustic_targets: u32,
    /// The branches of each camera sample at its first hit
    /// ([`RenderSettings::branches`]; set with the settings, after the scene), and their weight
    /// ([`branch_weight`](crate::render::integrator::branch_weight)).
    pub branches: u32,
    /// [`RenderScene::scene_sphere`]: where a directional light's light subpaths start.
    pub scene_center: [f32; 3],
    pub scene_radius: f32,
    pub branch_weight: f32,
    /// Half an orthographic camera's view height; 0 for a perspective camera.
    pub ortho_half_height: f32,
    /// [`RenderScene::lights_in_full`].
    pub lights_in_full: u32,
    /// [`CameraRays::filter_width`].
    pub filter_width: f32,
    /// [`CameraRays::window`]: the pixels whose camera rays may meet the scene.
    pub window: [u32; 4],
    /// The lights in the table, and [`RenderScene::first_rect_light`].
    pub num_lights: u32,
    pub first_rect_light: u32,
    /// [`BounceLimits::budget`](crate::scene::BounceLimits::budget): the diffuse, glossy
    /// and transmission scatterings a path may take.
    pub diffuse_bounces: u32,
    pub glossy_bounces: u32,
    pub transmission_bounces: u32,
    pub _pad: [u32; 3],
}

impl Params {
    /// The block's layout, for the shader generator's checks.
    pub fn layout() -> StructLayout {
        struct_layout!(Params {
            cam_position,
            width,
            cam_forward,
            height,
            cam_right,
            max_depth,
            cam_up,
            seed,
            sky_zenith,
            sky_kind,
            sky_horizon,
            num_emitters,
            tan_half_vfov,
            aspect,
            aperture,
            focus_distance,
            sample_start,
            sample_end,
            row_start,
            row_end,
            sky_pmf,
            film_texels,
            env_texture,
            env_strength,
            env_rotation,
            env_cells,
            aovs,
            transparent,
            num_caustic_targets,
            branches,
            scene_center,
            scene_radius,
            branch_weight,
            ortho_half_height,
            lights_in_full,
            filter_width,
            window,
            num_lights,
            first_rect_light,
            diffuse_bounces,
            glossy_bounces,
            transmission_bounces,
            _pad,
        })
    }

    /// The parameters of a render of `scene` with `settings`, covering every row and no
    /// samples yet (`sample_*`, `row_*` and `film_texels` are set per dispatch).
    pub fn new(scene: &RenderScene, settings: &RenderSettings) -> Self {
        Self::for_scene(scene).with_settings(&scene.camera, settings, &scene.bounds())
    }

    /// The scene's own part: its sky and lights.
    pub fn for_scene(scene: &RenderScene) -> Self {
        let (zenith, horizon, kind) = match scene.sky {
            Sky::Constant(c) => (c, c, SKY_CONSTANT),
            Sky::Gradient { zenith, horizon } => (zenith, horizon, SKY_GRADIENT),
            Sky::Environment { .. } => (Vec3::ZERO, Vec3::ZERO, SKY_ENVIRONMENT),
        };
        let env = &scene.env;
        Self {
            sky_zenith: zenith.into(),
            sky_kind: kind,
            sky_horizon: horizon.into(),
            env_texture: env.texture,
            env_strength: env.strength,
            env_rotation: env.rotation,
            env_cells: env.cells,
            num_emitters: scene.emitters.len() as u32,
            sky_pmf: scene.sky_pmf,
            num_caustic_targets: scene.caustic_targets.len() as u32,
            scene_center: scene.scene_sphere.0.into(),
            scene_radius: scene.scene_sphere.1,
            lights_in_full: scene.lights_in_full,
            num_lights: scene.lights.len() as u32,
            first_rect_light: scene.first_rect_light,
            ..Self::default()
        }
    }

    /// These parameters with the camera and image of a render of `settings` of a scene
    /// within `bounds`, covering every row and no samples yet.
    pub fn with_settings(self, camera: &Camera, settings: &RenderSettings, bounds: &Aabb) -> Self {
        let c = CameraRays::new(camera, settings.width, settings.height)
            .with_filter(settings.filter_width)
            .with_window(bounds);
        let branches = settings.branches(self.num_caustic_targets != 0);
        let bounces = settings.bounces.budget();
        Self {
            cam_position: c.position.into(),
            width: settings.width,
            cam_forward: c.forward.into(),
            height: settings.height,
            cam_right: c.right.into(),
            max_depth: settings.max_depth,
            diffuse_bounces: bounces.x,
            glossy_bounces: bounces.y,
            transmission_bounces: bounces.z,
            branches,
            branch_weight: branch_weight(branches),
            cam_up: c.up.into(),
            seed: settings.seed,
            tan_half_vfov: c.tan_half_vfov,
            aspect: c.aspect,
            aperture: c.aperture,
            focus_distance: c.focus_distance,
            ortho_half_height: c.ortho_half_height,
            filter_width: c.filter_width,
            window: c.window,
            sample_start: 0,
            sample_end: 0,
            row_start: 0,
            row_end: settings.height,
            ..self
        }
    }
}
