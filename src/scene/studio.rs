//! The studio a bare mesh (an `.obj`, `.gltf` or `.glb` rendered on its own) is shown in:
//! the mesh turned so that its up axis is +Y, a three-quarter camera above the front that
//! frames its bounding sphere, a ground under it that takes its shadow, and an embedded
//! studio environment (`assets/env/studio.hdr`, made by `tools/gen_studio_env.py`) whose
//! soft key, fill and rim lights show its shape.

use super::builder::Builder;
use super::camera::Camera;
use super::gltf::load_gltf;
use super::material::Material;
use super::obj::load_obj;
use super::part::{MeshPart, PartTriangle};
use super::settings::RenderSettings;
use super::source::FileSource;
use super::texture::{ImageType, TextureError, TextureRef, TextureSource, Textures};
use super::{NO_NORMAL, NO_TANGENT, NO_UV, Scene, SceneError, Sky};
use crate::math::Aabb;
use glam::{Mat4, Vec3};
use std::path::Path;
use std::sync::Arc;

/// The studio environment, built into the binary.
const STUDIO_HDR: &[u8] = include_bytes!("../../assets/env/studio.hdr");

/// The axis of a bare mesh that points up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Up {
    X,
    Y,
    Z,
}

impl Up {
    /// The up axis a bare mesh without other cues is taken to have: Z where its extent is
    /// largest along Z (scans and CAD exports), else Y (the OBJ and glTF convention).
    pub fn detect(bounds: &Aabb) -> Up {
        let e = bounds.extent();
        if e.z > e.x && e.z > e.y { Up::Z } else { Up::Y }
    }

    /// The rotation that turns this axis to +Y: a quarter turn about X for Z-up (+Z to +Y,
    /// +Y to −Z), about Z for X-up (+X to +Y).
    pub fn to_y(self) -> Mat4 {
        match self {
            Up::X => Mat4::from_rotation_z(std::f32::consts::FRAC_PI_2),
            Up::Y => Mat4::IDENTITY,
            Up::Z => Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2),
        }
    }
}

/// Options for showing a bare mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BareOptions {
    /// The mesh's up axis; `None` detects it ([`Up::detect`]) for an OBJ and takes glTF's
    /// +Y for a glTF file.
    pub up: Option<Up>,
    /// Leave the studio out: no ground and no studio environment (a black sky), for a
    /// caller that lights the mesh itself (a batch preset).
    pub unlit: bool,
}

/// Vertical field of view of the studio camera, in degrees.
const VFOV: f32 = 40.0;

/// How much of the vertical field of view the bounding sphere fills.
const FILL: f32 = 0.8;

/// Where the studio camera stands, in degrees: 35 from +Z towards +X (front-right), 22 above
/// the horizontal.
pub const AZIMUTH: f32 = 35.0;
pub const ELEVATION: f32 = 22.0;

/// The studio camera for a Y-up mesh of `bounds`: [`orbit_camera`] at [`AZIMUTH`] and
/// [`ELEVATION`].
pub fn camera(bounds: &Aabb) -> Option<Camera> {
    orbit_camera(bounds, AZIMUTH, ELEVATION)
}

/// A camera looking at the centre of a Y-up mesh of `bounds` from `azimuth` degrees (from
/// +Z towards +X) and `elevation` degrees above the horizontal, at the distance where the
/// bounding sphere fills 80% of the vertical field of view: how a bare mesh is framed, and
/// each view of a turntable (`meshtrace batch`). `None` when the bounds are too large for
/// f32 or the view is straight down or up.
pub fn orbit_camera(bounds: &Aabb, azimuth: f32, elevation: f32) -> Option<Camera> {
    let center = bounds.center();
    // Far from the origin, a tiny mesh still needs a camera distance that f32 resolves.
    let resolvable = 1e-5 * (1.0 + center.abs().max_element());
    let radius = (0.5 * bounds.extent().length()).max(resolvable);
    let distance = radius / (0.5 * FILL * VFOV.to_radians()).sin();
    let (azimuth, elevation) = (azimuth.to_radians(), elevation.to_radians());
    let towards = Vec3::new(
        azimuth.sin() * elevation.cos(),
        elevation.sin(),
        azimuth.cos() * elevation.cos(),
    );
    let position = center + distance * towards;
    if !(center.is_finite() && position.is_finite()) {
        return None;
    }
    Camera::new(position, center, Vec3::Y, VFOV, 0.0, None)
}

/// The ground under a Y-up mesh of `bounds`: a square 40 bounding radii across, facing
/// up, a hair below the mesh's lowest point (so that a flat base does not coincide with
/// it), without texture coordinates.
pub fn ground(bounds: &Aabb) -> MeshPart {
    let center = bounds.center();
    let radius = 0.5 * bounds.extent().length();
    let half = 20.0 * radius;
    let y = bounds.min.y - 1e-4 * radius;
    let positions = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .map(|(x, z)| Vec3::new(center.x + x * half, y, center.z + z * half))
        .to_vec();
    let triangle = |p: [u32; 3]| PartTriangle {
        p,
        n: [NO_NORMAL; 3],
        t: [NO_UV; 3],
        g: [NO_TANGENT; 3],
        material: None,
    };
    MeshPart {
        positions,
        // Counter-clockwise seen from above.
        triangles: vec![triangle([0, 2, 1]), triangle([0, 3, 2])],
        ..MeshPart::default()
    }
}

/// The name of the studio ground's material, which tells the ground from the mesh.
pub const GROUND_MATERIAL: &str = "studio ground";

/// The albedo of the studio ground: a light neutral grey.
pub const GROUND_ALBEDO: f32 = 0.6;

/// The studio environment's strength: its irradiance on an upward surface is 2.23 π, so a
/// white surface facing up comes out at 0.9 and the ground at 0.54, within a PNG's range.
pub const STUDIO_STRENGTH: f32 = 0.4;

/// The studio environment, added to `textures`.
pub fn sky(textures: &mut Textures) -> Result<Sky, SceneError> {
    Ok(Sky::Environment {
        texture: environment(textures)?,
        strength: STUDIO_STRENGTH,
        rotation: 0.0,
    })
}

/// The studio environment's image, added to `textures`: its index there.
pub fn environment(textures: &mut Textures) -> Result<u32, SceneError> {
    let r = TextureRef::environment(TextureSource::Memory {
        name: "studio.hdr (built in)".into(),
        bytes: Arc::from(STUDIO_HDR),
        format: Some(ImageType::Image(image::ImageFormat::Hdr)),
    });
    textures.add(&r, &super::source::Fs).map_err(|e| match e {
        TextureError::Fatal(e) => e,
        TextureError::Missing(name) => SceneError::Invalid {
            path: name,
            field: "sky".into(),
            message: "the built-in studio environment cannot be read".into(),
        },
    })
}

/// A bare OBJ in the studio: its own materials, turned so that its up axis (given, or
/// detected from its bounds) is +Y, framed by the studio camera.
pub(super) fn load_bare_obj(
    path: &Path,
    files: &dyn FileSource,
    options: &BareOptions,
) -> Result<Scene, SceneError> {
    let mut builder = Builder::default();
    let part = load_obj(path, files)?;
    // The frame is that of the vertices the faces use, degenerate faces included: a file
    // may define vertices that no face uses, and they must not move the camera.
    let mut used = vec![false; part.positions.len()];
    for t in &part.triangles {
        for i in t.p {
            used[i as usize] = true;
        }
    }
    let shown = super::shown(path);
    let obj_error = |message: String| SceneError::Obj {
        path: shown.clone(),
        line: None,
        message,
    };
    let raw = part
        .positions
        .iter()
        .zip(&used)
        .filter(|&(_, &used)| used)
        .fold(Aabb::EMPTY, |b, (&p, _)| b.grow(p));
    if raw.is_empty() {
        return Err(obj_error("the mesh has no faces".into()));
    }
    let turn = options.up.unwrap_or_else(|| Up::detect(&raw)).to_y();
    builder.append_part(part, turn, None, files, &obj_error)?;
    let bounds = builder
        .mesh
        .positions
        .iter()
        .zip(&used)
        .filter(|&(_, &used)| used)
        .fold(Aabb::EMPTY, |b, (&p, _)| b.grow(p));
    let camera = camera(&bounds).ok_or_else(|| {
        obj_error(format!(
            "the mesh spans {} to {}, too far out to frame with a camera",
            bounds.min, bounds.max
        ))
    })?;
    builder.finish_in_studio(path, camera, bounds, files, options)
}

/// A bare glTF file in the studio: its materials and lights, turned so that its up axis
/// (given, or glTF's +Y) is +Y, seen through its first perspective camera or else the
/// studio camera.
pub(super) fn load_bare_gltf(
    path: &Path,
    files: &dyn FileSource,
    options: &BareOptions,
) -> Result<Scene, SceneError> {
    let shown = super::shown(path);
    let asset = load_gltf(path, files)?;
    let turn = options.up.unwrap_or(Up::Y).to_y();
    let own_camera = asset.camera.clone();
    let root_origin = asset.root_origin.map(|t| turn.transform_point3(t));
    let mut builder = Builder::default();
    let error = |at: &str, message: String| SceneError::Gltf {
        path: shown.clone(),
        at: at.to_string(),
        message,
    };
    builder.append_gltf(asset, turn, None, true, files, &error)?;
    let mesh = &builder.mesh;
    if mesh.triangles.is_empty() {
        return Err(error(
            "scene",
            "the default scene has no triangles to render".into(),
        ));
    }
    let bounds = mesh.triangles.iter().fold(Aabb::EMPTY, |b, t| {
        b.union(Aabb::from_points(&mesh.vertices(t)))
    });
    let camera = match own_camera {
        Some(c) => Camera::new(
            turn.transform_point3(c.position),
            turn.transform_point3(c.position + c.forward),
            turn.transform_vector3(c.up),
            c.vfov,
            c.aperture,
            Some(c.focus_distance),
        )
        .map(|turned| Camera {
            ortho_height: c.ortho_height,
            ..turned
        }),
        None => camera(&bounds),
    }
    .ok_or_else(|| {
        error(
            "scene",
            format!(
                "the scene spans {} to {}, too far out to frame with a camera",
                bounds.min, bounds.max
            ),
        )
    })?;
    let mut scene = builder.finish_in_studio(path, camera, bounds, files, options)?;
    scene.root_origin = root_origin;
    Ok(scene)
}

impl Builder {
    /// The bare mesh's scene: lit in the studio (unless `options` leave it out), seen by
    /// `camera`, `bounds` framed.
    fn finish_in_studio(
        mut self,
        path: &Path,
        camera: Camera,
        bounds: Aabb,
        files: &dyn FileSource,
        options: &BareOptions,
    ) -> Result<Scene, SceneError> {
        let sky = if options.unlit {
            Sky::Constant(Vec3::ZERO)
        } else {
            self.light_the_studio(&bounds, files)?
        };
        let mut scene = self.finish(
            Some(path.to_path_buf()),
            camera,
            sky,
            RenderSettings::default(),
        );
        scene.framed = Some(bounds);
        Ok(scene)
    }

    /// The lighting of a bare mesh of `bounds`: a file that brings its own light
    /// (emissive materials or punctual lights) is lit by that alone, under a black sky;
    /// any other gets the studio environment and a ground under it.
    fn light_the_studio(
        &mut self,
        bounds: &Aabb,
        files: &dyn FileSource,
    ) -> Result<Sky, SceneError> {
        let emissive = self
            .mesh
            .triangles
            .iter()
            .any(|t| self.materials[t.material as usize].is_emissive());
        if emissive || !self.lights.is_empty() {
            return Ok(Sky::Constant(Vec3::ZERO));
        }
        let ground_material = self.add_material(
            GROUND_MATERIAL,
            Material::diffuse(Vec3::splat(GROUND_ALBEDO)),
        );
        // The ground is an object of its own, after the mesh's.
        self.object = self.mesh.objects.iter().max().map_or(0, |&o| o + 1);
        let no_error = |message: String| SceneError::Invalid {
            path: "studio".into(),
            field: "ground".into(),
            message,
        };
        self.append_part(
            ground(bounds),
            Mat4::IDENTITY,
            Some(ground_material),
            files,
            &no_error,
        )?;
        sky(&mut self.textures)
    }
}
