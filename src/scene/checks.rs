//! The checks of a scene file's tables: every value of the camera, `[render]`, the sky,
//! materials, textures, lights and objects is checked and converted, and each error names
//! the file and the field (`materials.glass.ior`). Objects are handed to the
//! [`Builder`](super::builder::Builder) once checked.

use super::builder::Builder;
use super::file::{
    ColorFile, LightFile, LightType, MaterialFile, MaterialType, ObjectFile, Projection,
    ScalarFile, ScaleFile, SceneFile, TextureFile, WrapFile,
};
use super::gltf::{is_gltf, load_gltf};
use super::light::PunctualLight;
use super::material::MAT_ALPHA_MASK;
use super::obj::load_obj;
use super::part::{MeshPart, PartTriangle};
use super::source::FileSource;
use super::sphere::{default_subdivisions, icosphere};
use super::texture::{
    TextureError, TextureRef, TextureSource, Textures, Usage, UvTransform, Wrap, load_environment,
};
use super::{
    BounceLimits, Camera, Material, MaterialKind, NO_TANGENT, NO_TEXTURE, NO_UV, RenderSettings,
    SceneError, Sky,
};
use glam::{Mat3, Mat4, Vec3};
use std::path::{Path, PathBuf};

/// Deepest sphere subdivision accepted: 20 * 4^10 = 21M triangles.
pub const MAX_SPHERE_SUBDIVISIONS: u32 = 10;

/// Whether a path names an OBJ mesh (by its extension, in any case).
fn is_obj(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
}

/// The file being read: names it in errors and resolves its relative paths.
pub(super) struct Ctx<'a> {
    pub(super) files: &'a dyn FileSource,
    pub(super) path: String,
    pub(super) dir: PathBuf,
}

impl Ctx<'_> {
    pub(super) fn invalid(
        &self,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> SceneError {
        SceneError::Invalid {
            path: self.path.clone(),
            field: field.into(),
            message: message.into(),
        }
    }

    pub(super) fn syntax(&self, text: &str, e: &toml::de::Error) -> SceneError {
        let offset = e.span().map(|s| s.start).unwrap_or(0).min(text.len());
        let before = &text[..offset];
        let line = before.matches('\n').count() + 1;
        let column = before.len() - before.rfind('\n').map(|i| i + 1).unwrap_or(0) + 1;
        SceneError::Syntax {
            path: self.path.clone(),
            line,
            column,
            message: e.message().replace(['\n', '\r'], " ").trim().to_string(),
        }
    }

    pub(super) fn vec3(&self, field: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        let v = Vec3::from(v);
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.invalid(field, format!("must be finite, got {v}")))
        }
    }

    pub(super) fn color(&self, field: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        let v = self.vec3(field, v)?;
        if v.min_element() < 0.0 {
            return Err(self.invalid(field, format!("must not be negative, got {v}")));
        }
        Ok(v)
    }

    pub(super) fn scalar(
        &self,
        field: &str,
        x: f32,
        ok: impl Fn(f32) -> bool,
        range: &str,
    ) -> Result<f32, SceneError> {
        if x.is_finite() && ok(x) {
            Ok(x)
        } else {
            Err(self.invalid(field, format!("must be {range}, got {x}")))
        }
    }

    pub(super) fn camera(&self, file: &SceneFile) -> Result<Camera, SceneError> {
        let c = &file.camera;
        let position = self.vec3("camera.position", c.position)?;
        let look_at = self.vec3("camera.look_at", c.look_at)?;
        let up = self.vec3("camera.up", c.up.unwrap_or([0.0, 1.0, 0.0]))?;
        let vfov = self.scalar(
            "camera.vfov",
            c.vfov.unwrap_or(40.0),
            |v| v > 0.0 && v < 180.0,
            "in (0, 180)",
        )?;
        let aperture = self.scalar(
            "camera.aperture",
            c.aperture.unwrap_or(0.0),
            |v| v >= 0.0,
            "at least 0",
        )?;
        let focus = c
            .focus_distance
            .map(|f| self.scalar("camera.focus_distance", f, |v| v > 0.0, "positive"))
            .transpose()?;
        if position == look_at {
            return Err(self.invalid("camera.look_at", "must differ from camera.position"));
        }
        let camera =
            Camera::new(position, look_at, up, vfov, aperture, focus).ok_or_else(|| {
                self.invalid(
                    "camera.up",
                    "must not be zero or parallel to the view direction",
                )
            })?;
        match c.projection.unwrap_or(Projection::Perspective) {
            Projection::Perspective => match c.height {
                Some(_) => Err(self.invalid(
                    "camera.height",
                    "is an orthographic camera's; add `projection = \"orthographic\"` or use `vfov`",
                )),
                None => Ok(camera),
            },
            Projection::Orthographic => {
                for (field, given) in [
                    ("vfov", c.vfov.is_some()),
                    ("aperture", c.aperture.is_some()),
                    ("focus_distance", c.focus_distance.is_some()),
                ] {
                    if given {
                        return Err(self.invalid(
                            format!("camera.{field}"),
                            "does not apply to an orthographic camera, which sees `height` world units along parallel rays",
                        ));
                    }
                }
                let Some(height) = c.height else {
                    return Err(self.invalid(
                        "camera.height",
                        "is required for an orthographic camera: the view's height in world units",
                    ));
                };
                let height = self.scalar("camera.height", height, |v| v > 0.0, "positive")?;
                Ok(camera.orthographic(height))
            }
        }
    }

    pub(super) fn settings(&self, file: &SceneFile) -> Result<RenderSettings, SceneError> {
        let r = &file.render;
        let d = RenderSettings::default();
        let s = RenderSettings {
            width: r.width.unwrap_or(d.width),
            height: r.height.unwrap_or(d.height),
            spp: r.spp.unwrap_or(d.spp),
            max_depth: r.max_depth.unwrap_or(d.max_depth),
            seed: r.seed.unwrap_or(d.seed),
            caustics: r.caustics.unwrap_or(d.caustics),
            branches: r.branches.or(d.branches),
            filter_width: r.filter_width.unwrap_or(d.filter_width),
            bounces: BounceLimits {
                diffuse: r.diffuse_bounces,
                glossy: r.glossy_bounces,
                transmission: r.transmission_bounces,
            },
        };
        s.validate()
            .map_err(|(field, message)| self.invalid(format!("render.{field}"), message))?;
        Ok(s)
    }

    pub(super) fn sky(&self, file: &SceneFile, textures: &mut Textures) -> Result<Sky, SceneError> {
        let Some(sky) = &file.sky else {
            return Ok(Sky::Constant(Vec3::ZERO));
        };
        if let Some(image) = &sky.environment {
            if sky.color.is_some() || sky.zenith.is_some() || sky.horizon.is_some() {
                return Err(self.invalid(
                    "sky.environment",
                    "cannot be combined with `color`, `zenith` or `horizon`",
                ));
            }
            let strength = match sky.strength {
                Some(s) => self.scalar("sky.strength", s, |s| s >= 0.0, "at least 0")?,
                None => 1.0,
            };
            let rotate = match sky.rotate {
                Some(r) => self.scalar("sky.rotate", r, f32::is_finite, "finite")?,
                None => 0.0,
            };
            let texture = load_environment(&self.dir.join(image), textures, self.files)
                .map_err(|message| self.invalid("sky.environment", message))?;
            return Ok(Sky::Environment {
                texture,
                strength,
                rotation: rotate.to_radians(),
            });
        }
        for (key, given) in [("rotate", sky.rotate), ("strength", sky.strength)] {
            if given.is_some() {
                return Err(self.invalid(format!("sky.{key}"), "is read only with `environment`"));
            }
        }
        match (sky.color, sky.zenith, sky.horizon) {
            (Some(c), None, None) => Ok(Sky::Constant(self.color("sky.color", c)?)),
            (None, Some(z), Some(h)) => Ok(Sky::Gradient {
                zenith: self.color("sky.zenith", z)?,
                horizon: self.color("sky.horizon", h)?,
            }),
            (None, None, None) => Err(self.invalid(
                "sky",
                "needs `color`, `zenith` and `horizon`, or `environment`",
            )),
            (Some(_), _, _) => {
                Err(self.invalid("sky.color", "cannot be combined with `zenith` or `horizon`"))
            }
            (None, None, Some(_)) => Err(self.invalid("sky.zenith", "is required with `horizon`")),
            (None, Some(_), None) => Err(self.invalid("sky.horizon", "is required with `zenith`")),
        }
    }

    /// A colour parameter's factor and texture slot: an RGB triple and no texture, or
    /// factor 1 (`strength` for emission) and the texture.
    pub(super) fn color_param(
        &self,
        field: &str,
        c: &ColorFile,
        emission: bool,
        textures: &mut Textures,
    ) -> Result<(Vec3, u32), SceneError> {
        match c {
            ColorFile::Rgb(rgb) => Ok((self.color(field, *rgb)?, NO_TEXTURE)),
            ColorFile::Texture(t) => {
                let strength = match (t.strength, emission) {
                    (None, _) => 1.0,
                    (Some(s), true) => {
                        self.scalar(&format!("{field}.strength"), s, |s| s >= 0.0, "at least 0")?
                    }
                    (Some(_), false) => {
                        return Err(self.invalid(
                            format!("{field}.strength"),
                            "only emission textures and normal maps have a strength",
                        ));
                    }
                };
                let slot = self.texture(field, t, Usage::Colour, textures)?;
                Ok((Vec3::splat(strength), slot))
            }
        }
    }

    /// Reads a texture a scene file names, relative to the scene file: an error names the
    /// field and the image.
    pub(super) fn texture(
        &self,
        field: &str,
        t: &TextureFile,
        usage: Usage,
        textures: &mut Textures,
    ) -> Result<u32, SceneError> {
        let scale = t.scale.unwrap_or([1.0, 1.0]);
        if !scale.iter().all(|s| s.is_finite() && *s != 0.0) {
            return Err(self.invalid(
                format!("{field}.scale"),
                format!("must be finite and non-zero, got {scale:?}"),
            ));
        }
        let wrap = match &t.wrap {
            None => [Wrap::REPEAT; 2],
            Some(WrapFile::Both(w)) => [self.wrap(field, w)?; 2],
            Some(WrapFile::Each([u, v])) => [self.wrap(field, u)?, self.wrap(field, v)?],
        };
        let r = TextureRef {
            source: TextureSource::File(self.dir.join(&t.texture)),
            usage,
            transform: UvTransform::scale(scale[0], scale[1]),
            wrap,
            optional: false,
            uv_set: 0,
        };
        textures.add(&r, self.files).map_err(|e| {
            let message = match e {
                TextureError::Fatal(e) => e.to_string(),
                TextureError::Missing(file) => format!("cannot read {file}"),
            };
            self.invalid(format!("{field}.texture"), message)
        })
    }

    /// A wrap mode by its name.
    pub(super) fn wrap(&self, field: &str, name: &str) -> Result<Wrap, SceneError> {
        Wrap::ALL
            .iter()
            .find(|(_, n)| *n == name)
            .map(|&(w, _)| w)
            .ok_or_else(|| {
                self.invalid(
                    format!("{field}.wrap"),
                    format!(
                        "unknown wrap mode `{}`; there is: repeat, clamp, mirror",
                        name.escape_debug()
                    ),
                )
            })
    }

    pub(super) fn material(
        &self,
        name: &str,
        m: &MaterialFile,
        textures: &mut Textures,
    ) -> Result<Material, SceneError> {
        // A quoted TOML key may hold any character; keep messages on one line.
        let field = |key: &str| format!("materials.{}.{key}", name.escape_debug());
        let not_for = |key: &str| {
            self.invalid(
                field(key),
                format!("is not a parameter of {} materials", m.kind.name()),
            )
        };
        let kind = match m.kind {
            MaterialType::Diffuse => MaterialKind::DIFFUSE,
            MaterialType::Conductor => MaterialKind::CONDUCTOR,
            MaterialType::RoughConductor => MaterialKind::ROUGH_CONDUCTOR,
            MaterialType::Dielectric => MaterialKind::DIELECTRIC,
            MaterialType::Pbr => MaterialKind::PBR,
        };
        let pbr = kind == MaterialKind::PBR;
        // Which parameters each kind takes.
        let takes = [
            (
                "albedo",
                m.albedo.is_some(),
                !pbr && kind != MaterialKind::DIELECTRIC,
            ),
            (
                "roughness",
                m.roughness.is_some(),
                pbr || kind == MaterialKind::ROUGH_CONDUCTOR,
            ),
            (
                "ior",
                m.ior.is_some(),
                pbr || kind == MaterialKind::DIELECTRIC,
            ),
            ("base_color", m.base_color.is_some(), pbr),
            ("metallic", m.metallic.is_some(), pbr),
            ("specular", m.specular.is_some(), pbr),
            ("transmission", m.transmission.is_some(), pbr),
        ];
        if let Some((key, _, _)) = takes.iter().find(|(_, given, ok)| *given && !ok) {
            return Err(not_for(key));
        }
        let mut mat = Material::new(kind);
        if kind == MaterialKind::DIFFUSE {
            mat.albedo = Vec3::splat(0.8);
        }
        if pbr {
            // Blender's Principled defaults: a grey, half-rough dielectric.
            (mat.albedo, mat.metallic, mat.roughness) = (Vec3::splat(0.8), 0.0, 0.5);
        }
        if let Some(a) = m.albedo.as_ref().or(m.base_color.as_ref()) {
            let key = if pbr { "base_color" } else { "albedo" };
            (mat.albedo, mat.albedo_texture) = self.color_param(&field(key), a, false, textures)?;
        }
        if let Some(e) = &m.emission {
            (mat.emission, mat.emission_texture) =
                self.color_param(&field("emission"), e, true, textures)?;
        }
        let unit = |r: f32| (0.0..=1.0).contains(&r);
        match (&m.roughness, kind) {
            (Some(r), _) => {
                (mat.roughness, mat.roughness_texture) =
                    self.scalar_param(&field("roughness"), r, textures)?;
            }
            (None, MaterialKind::ROUGH_CONDUCTOR) => {
                return Err(self.invalid(field("roughness"), "is required for rough_conductor"));
            }
            (None, _) => {}
        }
        if let Some(x) = &m.metallic {
            (mat.metallic, mat.metallic_texture) =
                self.scalar_param(&field("metallic"), x, textures)?;
        }
        if let Some(x) = &m.transmission {
            (mat.transmission, mat.transmission_texture) =
                self.scalar_param(&field("transmission"), x, textures)?;
        }
        if let Some(x) = m.specular {
            mat.specular = self.scalar(&field("specular"), x, unit, "in [0, 1]")?;
        }
        if let Some(ior) = m.ior {
            mat.ior = self.scalar(&field("ior"), ior, |v| v > 0.0, "positive")?;
        }
        if let Some(t) = &m.normal_map {
            let key = field("normal_map");
            if let Some(s) = t.strength {
                mat.normal_scale =
                    self.scalar(&format!("{key}.strength"), s, f32::is_finite, "finite")?;
            }
            mat.normal_texture = self.texture(&key, t, Usage::Linear, textures)?;
        }
        match (m.alpha, m.alpha_cutoff) {
            (Some(_), None) => {
                return Err(self.invalid(
                    field("alpha"),
                    "is read only by an alpha mask: set alpha_cutoff too (meshtrace does not blend)",
                ));
            }
            (alpha, Some(cutoff)) => {
                mat.alpha_cutoff =
                    self.scalar(&field("alpha_cutoff"), cutoff, unit, "in [0, 1]")?;
                if let Some(a) = alpha {
                    mat.alpha = self.scalar(&field("alpha"), a, unit, "in [0, 1]")?;
                }
                mat.flags |= MAT_ALPHA_MASK;
            }
            (None, None) => {}
        }
        Ok(mat)
    }

    /// A scalar parameter in [0, 1]: the number and no texture, or factor 1 and a texture
    /// read from its first channel.
    pub(super) fn scalar_param(
        &self,
        field: &str,
        x: &ScalarFile,
        textures: &mut Textures,
    ) -> Result<(f32, u32), SceneError> {
        match x {
            ScalarFile::Value(v) => Ok((
                self.scalar(field, *v, |r| (0.0..=1.0).contains(&r), "in [0, 1]")?,
                NO_TEXTURE,
            )),
            ScalarFile::Texture(t) if t.strength.is_some() => Err(self.invalid(
                format!("{field}.strength"),
                "only emission textures and normal maps have a strength",
            )),
            ScalarFile::Texture(t) => Ok((
                1.0,
                self.texture(field, t, Usage::Scalar { channel: 0 }, textures)?,
            )),
        }
    }

    /// A `[[lights]]` table, each type with its own fields.
    pub(super) fn light(&self, i: usize, l: &LightFile) -> Result<PunctualLight, SceneError> {
        let field = |key: &str| format!("lights[{i}].{key}");
        let given = [
            ("position", l.position.is_some()),
            ("direction", l.direction.is_some()),
            ("intensity", l.intensity.is_some()),
            ("irradiance", l.irradiance.is_some()),
            ("cutoff_angle", l.cutoff_angle.is_some()),
            ("beam_width", l.beam_width.is_some()),
            ("shadows", l.shadows.is_some()),
            ("size", l.size.is_some()),
            ("radiance", l.radiance.is_some()),
        ];
        let takes: &[&str] = match l.kind {
            LightType::Point => &["position", "intensity"],
            LightType::Spot => &[
                "position",
                "direction",
                "intensity",
                "cutoff_angle",
                "beam_width",
            ],
            LightType::Directional => &["direction", "irradiance", "shadows"],
            LightType::Rect => &["position", "direction", "size", "radiance"],
        };
        if let Some((key, _)) = given.iter().find(|(k, g)| *g && !takes.contains(k)) {
            return Err(self.invalid(
                field(key),
                format!("is not a parameter of {} lights", l.kind.name()),
            ));
        }
        let required = |key: &str, v: Option<[f32; 3]>| {
            v.ok_or_else(|| {
                self.invalid(
                    field(key),
                    format!("is required for {} lights", l.kind.name()),
                )
            })
        };
        let direction = |v: Option<[f32; 3]>| -> Result<Vec3, SceneError> {
            let d = self.vec3(&field("direction"), required("direction", v)?)?;
            d.try_normalize()
                .ok_or_else(|| self.invalid(field("direction"), "must not be zero"))
        };
        Ok(match l.kind {
            LightType::Point => PunctualLight::Point {
                position: self.vec3(&field("position"), required("position", l.position)?)?,
                intensity: self.color(&field("intensity"), required("intensity", l.intensity)?)?,
            },
            LightType::Spot => {
                let cutoff = self.scalar(
                    &field("cutoff_angle"),
                    l.cutoff_angle.unwrap_or(20.0),
                    |a| a > 0.0 && a <= 180.0,
                    "in (0, 180] degrees",
                )?;
                let beam = self.scalar(
                    &field("beam_width"),
                    l.beam_width.unwrap_or(0.75 * cutoff),
                    |b| b > 0.0 && b <= cutoff,
                    "in (0, cutoff_angle] degrees",
                )?;
                PunctualLight::Spot {
                    position: self.vec3(&field("position"), required("position", l.position)?)?,
                    direction: direction(l.direction)?,
                    intensity: self
                        .color(&field("intensity"), required("intensity", l.intensity)?)?,
                    cutoff: cutoff.to_radians(),
                    beam_width: beam.to_radians(),
                }
            }
            LightType::Directional => PunctualLight::Directional {
                direction: direction(l.direction)?,
                irradiance: self
                    .color(&field("irradiance"), required("irradiance", l.irradiance)?)?,
                shadows: l.shadows.unwrap_or(true),
            },
            LightType::Rect => {
                let n = direction(l.direction)?;
                let [w, h] = l
                    .size
                    .ok_or_else(|| self.invalid(field("size"), "is required for rect lights"))?;
                for (k, x) in [w, h].into_iter().enumerate() {
                    self.scalar(
                        &format!("{}[{k}]", field("size")),
                        x,
                        |x| x > 0.0,
                        "positive",
                    )?;
                }
                // Its width runs horizontally (along X when it faces straight up or down),
                // its height across it.
                let u = n
                    .cross(Vec3::Y)
                    .try_normalize()
                    .filter(|_| n.y.abs() < 0.9999)
                    .unwrap_or(Vec3::X);
                PunctualLight::Rect {
                    center: self.vec3(&field("position"), required("position", l.position)?)?,
                    edge_u: w * u,
                    edge_v: h * n.cross(u),
                    radiance: self.color(&field("radiance"), required("radiance", l.radiance)?)?,
                }
            }
        })
    }

    pub(super) fn object(
        &self,
        builder: &mut Builder,
        i: usize,
        o: &ObjectFile,
    ) -> Result<(), SceneError> {
        let field = |key: &str| format!("objects[{i}].{key}");
        let material = match &o.material {
            Some(name) => Some(*builder.named.get(name).ok_or_else(|| {
                self.invalid(
                    field("material"),
                    format!("unknown material `{}`", name.escape_debug()),
                )
            })?),
            None => None,
        };
        let transform = self.transform(o, &field)?;
        let object_error = |message: String| self.invalid(format!("objects[{i}]"), message);
        match (&o.mesh, &o.sphere) {
            (Some(mesh), None) => {
                let path = self.dir.join(mesh);
                let no_faces = || {
                    object_error(format!(
                        "{} has no faces",
                        super::shown(&path).escape_debug()
                    ))
                };
                if is_gltf(&path) {
                    let asset = load_gltf(&path, self.files)?;
                    if asset.parts.iter().all(|p| p.part.triangles.is_empty()) {
                        return Err(no_faces());
                    }
                    let shown = super::shown(&path);
                    let error = |at: &str, message: String| {
                        object_error(format!("{shown}: {at}: {message}"))
                    };
                    builder.append_gltf(asset, transform, material, false, self.files, &error)?;
                } else if is_obj(&path) {
                    let part = load_obj(&path, self.files)?;
                    if part.triangles.is_empty() {
                        return Err(no_faces());
                    }
                    builder.append_part(part, transform, material, self.files, &object_error)?;
                } else {
                    return Err(self.invalid(
                        field("mesh"),
                        format!(
                            "{} is not a mesh meshtrace reads: give an OBJ (.obj) or glTF \
                             (.gltf, .glb) file",
                            super::shown(&path).escape_debug()
                        ),
                    ));
                }
            }
            (None, Some(s)) => {
                let center = self.vec3(&field("sphere.center"), s.center)?;
                let radius =
                    self.scalar(&field("sphere.radius"), s.radius, |r| r > 0.0, "positive")?;
                let level = match s.subdivisions {
                    Some(l) if l > MAX_SPHERE_SUBDIVISIONS => {
                        return Err(self.invalid(
                            field("sphere.subdivisions"),
                            format!("must be at most {MAX_SPHERE_SUBDIVISIONS}, got {l}"),
                        ));
                    }
                    Some(l) => l,
                    None => default_subdivisions(),
                };
                let (verts, faces) = icosphere(level);
                let part = MeshPart {
                    positions: verts.iter().map(|&v| center + radius * v).collect(),
                    normals: verts,
                    triangles: faces
                        .into_iter()
                        .map(|f| PartTriangle {
                            p: f,
                            n: f,
                            t: [NO_UV; 3],
                            g: [NO_TANGENT; 3],
                            material: None,
                        })
                        .collect(),
                    ..MeshPart::default()
                };
                builder.append_part(part, transform, material, self.files, &object_error)?;
            }
            (Some(_), Some(_)) => {
                return Err(self.invalid(
                    field("sphere"),
                    "an object has either `mesh` or `sphere`, not both",
                ));
            }
            (None, None) => {
                return Err(self.invalid(format!("objects[{i}]"), "needs `mesh` or `sphere`"));
            }
        }
        Ok(())
    }

    pub(super) fn transform(
        &self,
        o: &ObjectFile,
        field: &dyn Fn(&str) -> String,
    ) -> Result<Mat4, SceneError> {
        if let Some(m) = o.matrix {
            if o.translate.is_some() || o.rotate.is_some() || o.scale.is_some() {
                return Err(self.invalid(
                    field("matrix"),
                    "cannot be combined with translate, rotate or scale",
                ));
            }
            if m.iter().any(|x| !x.is_finite()) {
                return Err(self.invalid(field("matrix"), "must be finite"));
            }
            let mat = Mat4::from_cols_array(&m).transpose();
            if m[12..] != [0.0, 0.0, 0.0, 1.0] {
                return Err(self.invalid(
                    field("matrix"),
                    "last row must be [0, 0, 0, 1] (an affine transform)",
                ));
            }
            if Mat3::from_mat4(mat).determinant() == 0.0 {
                return Err(self.invalid(field("matrix"), "is singular"));
            }
            return Ok(mat);
        }
        let scale = match o.scale {
            None => Vec3::ONE,
            Some(ScaleFile::Uniform(s)) => Vec3::splat(s),
            Some(ScaleFile::Axes(s)) => Vec3::from(s),
        };
        if !scale.is_finite() || scale.cmpeq(Vec3::ZERO).any() {
            return Err(self.invalid(
                field("scale"),
                format!("must be finite and non-zero, got {scale}"),
            ));
        }
        let rotate = self.vec3(&field("rotate"), o.rotate.unwrap_or([0.0; 3]))?;
        let translate = self.vec3(&field("translate"), o.translate.unwrap_or([0.0; 3]))?;
        let r = rotate * (std::f32::consts::PI / 180.0);
        Ok(Mat4::from_translation(translate)
            * Mat4::from_rotation_z(r.z)
            * Mat4::from_rotation_y(r.y)
            * Mat4::from_rotation_x(r.x)
            * Mat4::from_scale(scale))
    }
}
