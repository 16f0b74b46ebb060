//! Dataset presets: a batch job that renders each mesh as a public dataset script does
//! (docs/dataset-scripts.md, docs/datasets.md): the script's normalisation of the object
//! into a unit box about the origin, its cameras, lens, lighting and image size, and its
//! files. Poses are the script's, in its own world frame: Blender's, Z up, which its glTF
//! and OBJ importers make of a Y-up file as (x, y, z) → (x, −z, y).
//!
//! Rather than move the mesh, the scene is left where the file puts it and the cameras
//! and lights are moved by the inverse of the normalisation: the images are the same.

use crate::math::Aabb;
use crate::request::RenderRequest;
use crate::scene::camera::Camera;
use crate::scene::light::PunctualLight;
use crate::scene::studio::Up;
use crate::scene::texture::{ImageType, TextureError, TextureRef, TextureSource, Textures};
use crate::scene::{Scene, SceneError, Sky};
use glam::{DVec3, Vec3};

/// The presets there are, by their manifest names.
pub const NAMES: [&str; 2] = ["objaverse", "syncdreamer"];

/// How a script lights the object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lighting {
    /// objaverse-rendering's area light of 30,000 W, 100 m × 100 m, 0.5 over the object,
    /// with the factory world's grey (0.0509) below.
    AreaAbove,
    /// Blender's factory point light (1,000 W at (4.0762, 1.0055, 5.9039), moved with the
    /// object by the normalisation) in a uniform world of this grey.
    FactoryPoint { world: f32 },
}

/// A dataset script's way of rendering, with the parameters a manifest may override.
#[derive(Clone, Debug, PartialEq)]
pub struct Preset {
    /// Its manifest name.
    pub name: &'static str,
    /// Views per object.
    pub views: u32,
    /// The cameras' elevation above the object's horizontal plane, in degrees.
    pub elevation: f32,
    /// The cameras' distance from the object's centre, in normalised units.
    pub distance: f32,
    /// The field of view of the square image, in degrees.
    pub fov: f32,
    /// The image's side in pixels.
    pub size: u32,
    /// Samples per pixel.
    pub spp: u32,
    pub lighting: Lighting,
}

impl Preset {
    /// The preset named `name` with its script's parameters, or why there is none.
    pub fn named(name: &str) -> Result<Self, String> {
        match name {
            // allenai/objaverse-rendering scripts/blender_script.py: 12 views on a ring at
            // 30° elevation (polar angle 60°), distance 1.5, a 35 mm lens on a 32 mm
            // sensor, 512², RGBA PNG.
            "objaverse" => Ok(Self {
                name: "objaverse",
                views: 12,
                elevation: 30.0,
                distance: 1.5,
                fov: fov_of_lens(35.0, 32.0),
                size: 512,
                spp: 64,
                lighting: Lighting::AreaAbove,
            }),
            // liuyuan-pal/SyncDreamer blender_script.py, --camera_type fixed (its target
            // views): 16 views on a ring at 30° elevation, distance 1.5, the same lens,
            // 256², no lights of its own (the factory point light stays) and a world of
            // grey 0.5.
            "syncdreamer" => Ok(Self {
                name: "syncdreamer",
                views: 16,
                elevation: 30.0,
                distance: 1.5,
                fov: fov_of_lens(35.0, 32.0),
                size: 256,
                spp: 128,
                lighting: Lighting::FactoryPoint { world: 0.5 },
            }),
            _ => Err(format!(
                "`{name}` is not a preset; there are {}",
                NAMES.map(|n| format!("\"{n}\"")).join(", ")
            )),
        }
    }

    /// What the preset asks of every image, under the manifest's `[render]`: its size and
    /// samples, RGBA PNGs (the scripts' transparent film), no studio, and the mesh read
    /// with +Y up, as Blender's glTF and OBJ importers read it.
    pub fn request(&self) -> RenderRequest {
        RenderRequest {
            up: Some(Up::Y),
            width: Some(self.size),
            height: Some(self.size),
            spp: Some(self.spp),
            transparent: Some(true),
            without_studio: true,
            ..RenderRequest::default()
        }
    }

    /// The output pattern of the script's files: one folder per object (its file name up
    /// to the first dot), the views numbered with three digits.
    pub fn output(&self) -> &'static str {
        "views/{uid}/{view:03}.png"
    }

    /// The camera position of view `view` in the script's normalised frame (Blender's, Z
    /// up): on a ring at the preset's elevation and distance, view 0 on +X, turning
    /// counter-clockwise seen from +Z.
    pub fn blender_position(&self, view: u32) -> DVec3 {
        let theta = std::f64::consts::TAU * view as f64 / self.views as f64;
        let phi = (90.0 - self.elevation as f64).to_radians();
        self.distance as f64
            * DVec3::new(phi.sin() * theta.cos(), phi.sin() * theta.sin(), phi.cos())
    }

    /// The camera of view `view` of a mesh that `norm` normalises, in the mesh's own frame:
    /// at the script's position, looking at the origin with Blender's +Z up, both taken
    /// back through the normalisation.
    pub fn camera(&self, view: u32, norm: &Normalisation) -> Option<Camera> {
        let position = norm.to_scene(to_meshtrace(self.blender_position(view)));
        Camera::new(
            position,
            norm.to_scene(Vec3::ZERO),
            Vec3::Y,
            self.fov,
            0.0,
            None,
        )
    }

    /// Lights `scene`, normalised by `norm`, as the script does ([`Lighting`]).
    ///
    /// objaverse-rendering's area light emits 30,000 / (π · 100²) as Cycles emits a watt
    /// of an area light (P / (π A)). Seen from the object, below it, it fills the sky down
    /// to within a degree of the horizon, and in Blender it neither occludes nor is seen by
    /// the camera: so it is this environment, the light's radiance above the horizon and
    /// the world's grey below.
    ///
    /// The factory point light is a root object when the script normalises, so it moves
    /// with the object: in the mesh's own frame it stays at its Blender position divided
    /// by the scale, and its intensity, P / (4π) W/sr as Cycles emits a point light's
    /// watts, is divided by the scale squared, so that the object receives what it does in
    /// the script. (Blender's light is a sphere of radius 0.1 m, meshtrace's a point: the
    /// shadows are harder.)
    pub fn light(&self, scene: &mut Scene, norm: &Normalisation) -> Result<(), SceneError> {
        match self.lighting {
            Lighting::AreaAbove => {
                let side = 100.0f32;
                let radiance = 30_000.0 / (std::f32::consts::PI * side * side);
                let texture = split_sky(&mut scene.textures, radiance, 0.0509)?;
                scene.sky = Sky::Environment {
                    texture,
                    strength: 1.0,
                    rotation: 0.0,
                };
            }
            Lighting::FactoryPoint { world } => {
                let position = to_meshtrace(DVec3::new(4.0762, 1.0055, 5.9039)) / norm.scale;
                let intensity = 1000.0 / (4.0 * std::f32::consts::PI) / (norm.scale * norm.scale);
                scene.lights.push(PunctualLight::Point {
                    position,
                    intensity: Vec3::splat(intensity),
                });
                scene.sky = Sky::Constant(Vec3::splat(world));
            }
        }
        Ok(())
    }
}

/// An environment of radiance `above` over the horizon and `below` under it: an
/// equirectangular image of 256 × 128 texels (its rows blend only within 0.7° of the
/// horizon).
fn split_sky(textures: &mut Textures, above: f32, below: f32) -> Result<u32, SceneError> {
    let (w, h) = (256u32, 128u32);
    let pixels: Vec<image::Rgb<f32>> = (0..h)
        .flat_map(|y| {
            let v = if y < h / 2 { above } else { below };
            (0..w).map(move |_| image::Rgb([v; 3]))
        })
        .collect();
    let mut bytes = Vec::new();
    let invalid = |message: String| SceneError::Invalid {
        path: "preset".into(),
        field: "sky".into(),
        message,
    };
    image::codecs::hdr::HdrEncoder::new(&mut bytes)
        .encode(&pixels, w as usize, h as usize)
        .map_err(|e| invalid(e.to_string()))?;
    let r = TextureRef::environment(TextureSource::Memory {
        name: "preset sky (built in)".into(),
        bytes: bytes.into(),
        format: Some(ImageType::Image(image::ImageFormat::Hdr)),
    });
    textures
        .add(&r, &crate::scene::source::Fs)
        .map_err(|e| match e {
            TextureError::Fatal(e) => e,
            TextureError::Missing(name) => invalid(format!("{name} cannot be read")),
        })
}

/// The horizontal field of view, in degrees, of a lens of `focal` mm on a sensor `width`
/// mm wide (a square image: the vertical one too).
pub fn fov_of_lens(focal: f32, width: f32) -> f32 {
    2.0 * (width / 2.0 / focal).atan().to_degrees()
}

/// A Blender-frame point (Z up) in meshtrace's frame (Y up).
pub fn to_meshtrace(b: DVec3) -> Vec3 {
    Vec3::new(b.x as f32, b.z as f32, -b.y as f32)
}

/// The scripts' normalisation: scaled by 1 / (the bounding box's largest extent) and
/// moved so that the box's centre is the origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Normalisation {
    pub scale: f32,
    /// The box's centre in the mesh's own frame.
    pub centre: Vec3,
}

impl Normalisation {
    /// The normalisation of a mesh of bounds `b`; `None` for an empty or flat-less box.
    pub fn of(b: &Aabb) -> Option<Self> {
        let extent = (b.max - b.min).max_element();
        (extent.is_finite() && extent > 0.0).then(|| Self {
            scale: 1.0 / extent,
            centre: (b.min + b.max) * 0.5,
        })
    }

    /// A normalised point back in the mesh's frame.
    pub fn to_scene(&self, n: Vec3) -> Vec3 {
        n / self.scale + self.centre
    }
}
