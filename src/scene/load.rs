//! From a file to a [`Scene`]: parse, check every value, read the meshes, and build.
//! Each error names the file and the line or field at fault.

use super::file::{
    ColorFile, LightFile, LightType, MaterialFile, MaterialType, ObjectFile, ScalarFile, ScaleFile,
    SceneFile, TextureFile, WrapFile,
};
use super::gltf::{GltfAsset, is_gltf, load_gltf};
use super::light::PunctualLight;
use super::material::MAT_ALPHA_MASK;
use super::obj::{FileSource, Fs, MeshPart, PartTriangle, load_obj};
use super::sphere::{default_subdivisions, icosphere};
use super::studio::{self, BareOptions, Up};
use super::texture::{TextureError, TextureRef, TextureSource, Textures, Usage, UvTransform, Wrap};
use super::{
    Camera, MAX_BRANCHES, Material, MaterialKind, Mesh, NO_NORMAL, NO_TANGENT, NO_TEXTURE, NO_UV,
    RenderSettings, Scene, SceneError, Sky, Triangle,
};
use crate::math::Aabb;
use glam::{Mat3, Mat4, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Most pixels an image may have: 2^26 (8192 x 8192); the film alone then takes 768 MiB.
pub const MAX_PIXELS: u64 = 1 << 26;
/// Deepest sphere subdivision accepted: 20 * 4^10 = 21M triangles.
pub const MAX_SPHERE_SUBDIVISIONS: u32 = 10;

/// Adds the equirectangular image at `path` to `textures` as an environment map reads it
/// (linear, or sRGB-decoded for an 8-bit image; repeating around, clamped at the poles);
/// its record's index, or why it cannot be read.
pub fn load_environment(
    path: &Path,
    textures: &mut Textures,
    files: &dyn FileSource,
) -> Result<u32, String> {
    let r = TextureRef::environment(TextureSource::File(path.to_path_buf()));
    textures.add(&r, files).map_err(|e| match e {
        TextureError::Fatal(e) => e.to_string(),
        TextureError::Missing(file) => format!("cannot read {file}"),
    })
}

/// Lights `scene` with the equirectangular image at `path` (strength 1, not turned)
/// instead of its own sky, as `--env` asks; why not, naming the file, when it cannot be
/// read.
pub fn replace_environment(scene: &mut Scene, path: &Path) -> Result<(), String> {
    let texture = load_environment(path, &mut scene.textures, &Fs)?;
    scene.sky = Sky::Environment {
        texture,
        strength: 1.0,
        rotation: 0.0,
    };
    Ok(())
}

/// Whether a path names an OBJ mesh (by its extension, in any case).
fn is_obj(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
}

/// Loads a scene file (`.toml`), or a bare mesh (`.obj`, `.gltf`, `.glb`) shown in the
/// studio ([`studio`](super::studio)).
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    load_scene_with(path, &Fs, &BareOptions::default())
}

/// [`load_scene`] reading through `files`, so that built-in scenes load like any other.
pub fn load_scene_from(path: &Path, files: &dyn FileSource) -> Result<Scene, SceneError> {
    load_scene_with(path, files, &BareOptions::default())
}

/// [`load_scene_from`] with the options for a bare mesh. The extension (in any case) says
/// what the file is; any other is an error that lists the inputs meshtrace reads. Options
/// given for a scene file are an error: it places its meshes itself.
pub fn load_scene_with(
    path: &Path,
    files: &dyn FileSource,
    options: &BareOptions,
) -> Result<Scene, SceneError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("obj") => return load_bare_obj(path, files, options),
        Some("gltf" | "glb") => return load_bare_gltf(path, files, options),
        Some("toml") if options.up.is_some() => {
            return Err(SceneError::Unsupported {
                path: super::shown(path),
                message: "--up applies to a bare mesh (.obj, .gltf, .glb); a scene file \
                          turns its objects with `rotate`"
                    .into(),
            });
        }
        Some("toml") => {}
        _ => {
            return Err(SceneError::Unsupported {
                path: super::shown(path),
                message: "not an input meshtrace reads: give a scene file (.toml), an OBJ mesh \
                          (.obj) or a glTF file (.gltf, .glb)"
                    .into(),
            });
        }
    }
    let io = |source| SceneError::Io {
        path: super::shown(path),
        source,
    };
    let bytes = files.read(path).map_err(io)?;
    let text = String::from_utf8(bytes)
        .map_err(|e| io(std::io::Error::new(std::io::ErrorKind::InvalidData, e)))?;
    parse_scene_from(&text, path, files)
}

/// Parses scene-file text; `path` names it in messages and anchors its relative paths.
pub fn parse_scene(text: &str, path: &Path) -> Result<Scene, SceneError> {
    parse_scene_from(text, path, &Fs)
}

fn parse_scene_from(text: &str, path: &Path, files: &dyn FileSource) -> Result<Scene, SceneError> {
    let ctx = Ctx {
        files,
        path: super::shown(path),
        dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
    };
    let file: SceneFile = toml::from_str(text).map_err(|e| ctx.syntax(text, &e))?;
    let camera = ctx.camera(&file)?;
    let settings = ctx.settings(&file)?;
    let mut builder = Builder::default();
    let sky = ctx.sky(&file, &mut builder.textures)?;
    for (name, m) in &file.materials {
        let mat = ctx.material(name, m, &mut builder.textures)?;
        let index = builder.add_material(name, mat);
        builder.named.insert(name.clone(), index);
    }
    for (i, object) in file.objects.iter().enumerate() {
        builder.object = i as u32;
        ctx.object(&mut builder, i, object)?;
    }
    for (i, light) in file.lights.iter().enumerate() {
        builder.lights.push(ctx.light(i, light)?);
    }
    Ok(builder.finish(Some(path.to_path_buf()), camera, sky, settings))
}

/// A bare OBJ in the studio: its own materials, turned so that its up axis (given, or
/// detected from its bounds) is +Y, framed by the studio camera.
fn load_bare_obj(
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
    let camera = studio::camera(&bounds).ok_or_else(|| {
        obj_error(format!(
            "the mesh spans {} to {}, too far out to frame with a camera",
            bounds.min, bounds.max
        ))
    })?;
    let sky = builder.light_the_studio(&bounds, files)?;
    let mut scene = builder.finish(
        Some(path.to_path_buf()),
        camera,
        sky,
        RenderSettings::default(),
    );
    scene.framed = Some(bounds);
    Ok(scene)
}

/// A bare glTF file in the studio: its materials and lights, turned so that its up axis
/// (given, or glTF's +Y) is +Y, seen through its first perspective camera or else the
/// studio camera.
fn load_bare_gltf(
    path: &Path,
    files: &dyn FileSource,
    options: &BareOptions,
) -> Result<Scene, SceneError> {
    let shown = super::shown(path);
    let asset = load_gltf(path, files)?;
    let turn = options.up.unwrap_or(Up::Y).to_y();
    let own_camera = asset.camera.clone();
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
        ),
        None => studio::camera(&bounds),
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
    let sky = builder.light_the_studio(&bounds, files)?;
    let mut scene = builder.finish(
        Some(path.to_path_buf()),
        camera,
        sky,
        RenderSettings::default(),
    );
    scene.framed = Some(bounds);
    Ok(scene)
}

/// Accumulates the world-space mesh and the material table while objects are read.
#[derive(Default)]
struct Builder {
    mesh: Mesh,
    materials: Vec<Material>,
    material_names: Vec<String>,
    named: HashMap<String, u32>,
    default_material: Option<u32>,
    textures: Textures,
    lights: Vec<PunctualLight>,
    degenerate: usize,
    warnings: Vec<String>,
    /// [`Builder::obj_material`]'s answers so far.
    obj_materials: HashMap<u32, u32>,
    /// The object index of the triangles appended now ([`Mesh::objects`]).
    object: u32,
}

impl Builder {
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
        let ground = self.add_material(
            studio::GROUND_MATERIAL,
            Material::diffuse(Vec3::splat(studio::GROUND_ALBEDO)),
        );
        // The ground is an object of its own, after the mesh's.
        self.object = self.mesh.objects.iter().max().map_or(0, |&o| o + 1);
        let no_error = |message: String| SceneError::Invalid {
            path: "studio".into(),
            field: "ground".into(),
            message,
        };
        self.append_part(
            studio::ground(bounds),
            Mat4::IDENTITY,
            Some(ground),
            files,
            &no_error,
        )?;
        studio::sky(&mut self.textures)
    }

    /// Appends a material to the table; returns its index.
    fn add_material(&mut self, name: &str, material: Material) -> u32 {
        self.materials.push(material);
        self.material_names.push(name.to_string());
        self.materials.len() as u32 - 1
    }

    /// The material an OBJ face reads for material `m`: `m` itself, or where one of its
    /// textures clamps or mirrors along v, a copy whose such textures are shifted one image
    /// along v. OBJ texture coordinates are stored as (u, −v) (`obj::parse_texcoord`),
    /// which a repeating lookup reads as glTF's (u, 1 − v) but which puts the image at
    /// v ∈ [−1, 0], where clamping and mirroring need it at [0, 1].
    fn obj_material(&mut self, m: u32) -> u32 {
        if let Some(&found) = self.obj_materials.get(&m) {
            return found;
        }
        let mut material = self.materials[m as usize];
        let mut shifted = false;
        for slot in material.texture_slots_mut() {
            if *slot != NO_TEXTURE
                && self.textures.records[*slot as usize].wrap >> 8 != Wrap::REPEAT.0
            {
                *slot = self.textures.shifted(*slot, [0.0, 1.0]);
                shifted = true;
            }
        }
        let found = if shifted {
            let name = self.material_names[m as usize].clone();
            self.add_material(&name, material)
        } else {
            m
        };
        self.obj_materials.insert(m, found);
        found
    }

    fn default_material(&mut self) -> u32 {
        match self.default_material {
            Some(i) => i,
            None => {
                let i = self.add_material("default", Material::default_diffuse());
                self.default_material = Some(i);
                i
            }
        }
    }

    /// Appends a mesh part transformed by `m`; `material` overrides the part's own
    /// materials. The part's textures are read (a missing optional one is a warning, and
    /// its slot falls back to the parameter's factor); a triangle without texture
    /// coordinates whose material uses a texture is an error, made by `error`. Degenerate
    /// triangles are dropped (and counted).
    fn append_part(
        &mut self,
        mut part: MeshPart,
        m: Mat4,
        material: Option<u32>,
        files: &dyn FileSource,
        error: &dyn Fn(String) -> SceneError,
    ) -> Result<(), SceneError> {
        self.warnings.append(&mut part.warnings);
        let materials = std::mem::take(&mut part.materials);
        let local =
            self.append_materials(materials, &part.material_names, &part.textures, files)?;
        self.append_geometry(part, m, material, &local, true, error)
    }

    /// Appends what a glTF file brings, transformed by `m`: its primitives with their
    /// node matrices, and its materials unless `material` overrides them; its lights. An
    /// error about a primitive is made by `error` from the primitive's JSON path. With
    /// `node_objects` (a bare file), each node's triangles belong to the object of the
    /// node's index; else to the current object.
    fn append_gltf(
        &mut self,
        asset: GltfAsset,
        m: Mat4,
        material: Option<u32>,
        node_objects: bool,
        files: &dyn FileSource,
        error: &dyn Fn(&str, String) -> SceneError,
    ) -> Result<(), SceneError> {
        self.warnings.extend(asset.warnings);
        let local = match material {
            Some(_) => Vec::new(),
            None => self.append_materials(
                asset.materials,
                &asset.material_names,
                &asset.textures,
                files,
            )?,
        };
        for p in asset.parts {
            if node_objects {
                self.object = p.node;
            }
            let at = p.at;
            self.append_geometry(p.part, m * p.matrix, material, &local, false, &|message| {
                error(&at, message)
            })?;
        }
        for light in asset.lights {
            match light.transformed(m) {
                Some(light) => self.lights.push(light),
                None => self.warnings.push(
                    "a glTF light's direction collapses under its object's transform; the light is dropped"
                        .into(),
                ),
            }
        }
        Ok(())
    }

    /// Appends materials to the table, reading the textures their slots index into
    /// `textures` (a missing optional one is a warning, and its slot falls back to the
    /// parameter's factor); returns the table index of each.
    fn append_materials(
        &mut self,
        materials: Vec<Material>,
        names: &[String],
        textures: &[TextureRef],
        files: &dyn FileSource,
    ) -> Result<Vec<u32>, SceneError> {
        let mut slots = Vec::with_capacity(textures.len());
        for r in textures {
            slots.push(match self.textures.add(r, files) {
                Ok(slot) => slot,
                Err(TextureError::Missing(file)) => {
                    self.warnings.push(format!(
                        "texture {file} could not be read; its parameter falls back to its constant factor"
                    ));
                    NO_TEXTURE
                }
                Err(TextureError::Fatal(e)) => return Err(e),
            });
        }
        let slot = |i: u32| {
            if i == NO_TEXTURE {
                i
            } else {
                slots[i as usize]
            }
        };
        Ok(materials
            .into_iter()
            .zip(names)
            .map(|(mat, name)| {
                let mat = Material {
                    albedo_texture: slot(mat.albedo_texture),
                    emission_texture: slot(mat.emission_texture),
                    roughness_texture: slot(mat.roughness_texture),
                    metallic_texture: slot(mat.metallic_texture),
                    transmission_texture: slot(mat.transmission_texture),
                    normal_texture: slot(mat.normal_texture),
                    ..mat
                };
                self.add_material(name, mat)
            })
            .collect())
    }

    /// Appends a part's geometry transformed by `m`: its triangles' materials index `local`
    /// (the table indices [`Builder::append_materials`] returned), unless `material`
    /// overrides them; `obj_uv` says that its texture coordinates are an OBJ file's, as
    /// [`Builder::obj_material`] reads them. A triangle without texture coordinates whose
    /// material uses a texture is an error, made by `error`. Degenerate triangles are
    /// dropped (and counted).
    fn append_geometry(
        &mut self,
        part: MeshPart,
        m: Mat4,
        material: Option<u32>,
        local: &[u32],
        obj_uv: bool,
        error: &dyn Fn(String) -> SceneError,
    ) -> Result<(), SceneError> {
        let base_p = self.mesh.positions.len() as u32;
        let base_n = self.mesh.normals.len() as u32;
        let base_t = self.mesh.texcoords.len() as u32;
        let base_g = self.mesh.tangents.len() as u32;
        let linear = Mat3::from_mat4(m);
        let normal_matrix = linear.inverse().transpose();
        self.mesh
            .positions
            .extend(part.positions.iter().map(|&p| m.transform_point3(p)));
        self.mesh.normals.extend(
            part.normals
                .iter()
                .map(|&n| (normal_matrix * n).normalize_or_zero()),
        );
        self.mesh.texcoords.extend(&part.texcoords);
        // A tangent follows the surface (the linear part, not the normal matrix); a mirror
        // turns the bitangent's handedness.
        let handedness = if linear.determinant() < 0.0 {
            -1.0
        } else {
            1.0
        };
        self.mesh.tangents.extend(part.tangents.iter().map(|&t| {
            (linear * t.truncate())
                .normalize_or_zero()
                .extend(t.w * handedness)
        }));
        // A mirroring transform turns the winding: swapping two corners keeps the faces
        // that the file winds counter-clockwise the front ones (emitters keep emitting
        // outwards, dielectrics keep their inside), as glTF specifies for its nodes.
        let mirrored = linear.determinant() < 0.0;
        for mut t in part.triangles {
            if mirrored {
                t.p.swap(1, 2);
                t.n.swap(1, 2);
                t.t.swap(1, 2);
                t.g.swap(1, 2);
            }
            let material = match (material, t.material) {
                (Some(m), _) => m,
                (None, Some(i)) => local[i as usize],
                (None, None) => self.default_material(),
            };
            let material = if obj_uv {
                self.obj_material(material)
            } else {
                material
            };
            let uv = if t.t[0] == NO_UV {
                t.t
            } else {
                t.t.map(|i| i + base_t)
            };
            if uv[0] == NO_UV && self.materials[material as usize].has_texture() {
                return Err(error(format!(
                    "material `{}` uses a texture, but the mesh has faces without texture coordinates",
                    self.material_names[material as usize].escape_debug()
                )));
            }
            let p = t.p.map(|i| i + base_p);
            let mut n = if t.n[0] == NO_NORMAL {
                t.n
            } else {
                t.n.map(|i| i + base_n)
            };
            let mut g = if t.g[0] == NO_TANGENT {
                t.g
            } else {
                t.g.map(|i| i + base_g)
            };
            let [a, b, c] = p.map(|i| self.mesh.positions[i as usize]);
            let area2 = (b - a).cross(c - a).length();
            if !(area2 > 0.0 && area2.is_finite()) {
                self.degenerate += 1;
                continue;
            }
            if n[0] != NO_NORMAL
                && n.iter()
                    .any(|&i| self.mesh.normals[i as usize] == Vec3::ZERO)
            {
                n = [NO_NORMAL; 3];
            }
            if g[0] != NO_TANGENT
                && g.iter()
                    .any(|&i| self.mesh.tangents[i as usize].truncate() == Vec3::ZERO)
            {
                g = [NO_TANGENT; 3];
            }
            // The tangent table runs beside the triangles from the first one with tangents.
            let corners = &mut self.mesh.tangent_corners;
            if g[0] != NO_TANGENT || !corners.is_empty() {
                corners.resize(self.mesh.triangles.len(), [NO_TANGENT; 3]);
                corners.push(g);
            }
            self.mesh.objects.push(self.object);
            self.mesh.triangles.push(Triangle {
                p,
                n,
                t: uv,
                material,
            });
        }
        Ok(())
    }

    fn finish(
        mut self,
        path: Option<PathBuf>,
        camera: Camera,
        sky: Sky,
        settings: RenderSettings,
    ) -> Scene {
        // A mesh used by several objects repeats its warnings; say each once.
        let mut seen = std::collections::HashSet::new();
        self.warnings.retain(|w| seen.insert(w.clone()));
        let untangented = super::tangents::generate_missing(&mut self.mesh, &self.materials);
        if untangented > 0 {
            self.warnings.push(format!(
                "{untangented} triangle{} with a normal map got no tangent (its texture coordinates collapse to a point or a line); the map is not applied there",
                if untangented == 1 { "" } else { "s" }
            ));
        }
        if self.degenerate > 0 {
            self.warnings.push(format!(
                "dropped {} degenerate (zero-area) triangle{}",
                self.degenerate,
                if self.degenerate == 1 { "" } else { "s" }
            ));
        }
        Scene {
            path,
            camera,
            sky,
            settings,
            materials: self.materials,
            material_names: self.material_names,
            textures: self.textures,
            lights: self.lights,
            mesh: self.mesh,
            warnings: self.warnings,
            framed: None,
        }
    }
}

/// The file being read: names it in errors and resolves its relative paths.
struct Ctx<'a> {
    files: &'a dyn FileSource,
    path: String,
    dir: PathBuf,
}

impl Ctx<'_> {
    fn invalid(&self, field: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            path: self.path.clone(),
            field: field.into(),
            message: message.into(),
        }
    }

    fn syntax(&self, text: &str, e: &toml::de::Error) -> SceneError {
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

    fn vec3(&self, field: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        let v = Vec3::from(v);
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.invalid(field, format!("must be finite, got {v}")))
        }
    }

    fn color(&self, field: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        let v = self.vec3(field, v)?;
        if v.min_element() < 0.0 {
            return Err(self.invalid(field, format!("must not be negative, got {v}")));
        }
        Ok(v)
    }

    fn scalar(
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

    fn camera(&self, file: &SceneFile) -> Result<Camera, SceneError> {
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
        Camera::new(position, look_at, up, vfov, aperture, focus).ok_or_else(|| {
            self.invalid(
                "camera.up",
                "must not be zero or parallel to the view direction",
            )
        })
    }

    fn settings(&self, file: &SceneFile) -> Result<RenderSettings, SceneError> {
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
        };
        validate_settings(&s)
            .map_err(|(field, message)| self.invalid(format!("render.{field}"), message))?;
        Ok(s)
    }

    fn sky(&self, file: &SceneFile, textures: &mut Textures) -> Result<Sky, SceneError> {
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
    fn color_param(
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
    fn texture(
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
    fn wrap(&self, field: &str, name: &str) -> Result<Wrap, SceneError> {
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

    fn material(
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
    fn scalar_param(
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
    fn light(&self, i: usize, l: &LightFile) -> Result<PunctualLight, SceneError> {
        let field = |key: &str| format!("lights[{i}].{key}");
        let given = [
            ("position", l.position.is_some()),
            ("direction", l.direction.is_some()),
            ("intensity", l.intensity.is_some()),
            ("irradiance", l.irradiance.is_some()),
            ("cutoff_angle", l.cutoff_angle.is_some()),
            ("beam_width", l.beam_width.is_some()),
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
            LightType::Directional => &["direction", "irradiance"],
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
            },
        })
    }

    fn object(&self, builder: &mut Builder, i: usize, o: &ObjectFile) -> Result<(), SceneError> {
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

    fn transform(
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

/// Checks render settings (also after command-line overrides); the error names the field.
pub fn validate_settings(s: &RenderSettings) -> Result<(), (&'static str, String)> {
    if s.width == 0 {
        return Err(("width", "must be at least 1".into()));
    }
    if s.height == 0 {
        return Err(("height", "must be at least 1".into()));
    }
    let pixels = s.width as u64 * s.height as u64;
    if pixels > MAX_PIXELS {
        return Err((
            "width",
            format!(
                "{}x{} is too large: at most {MAX_PIXELS} pixels",
                s.width, s.height
            ),
        ));
    }
    if s.spp == 0 {
        return Err(("spp", "must be at least 1".into()));
    }
    if s.max_depth == 0 {
        return Err(("max_depth", "must be at least 1".into()));
    }
    if let Some(b) = s.branches
        && !(1..=MAX_BRANCHES).contains(&b)
    {
        return Err((
            "branches",
            format!("must be from 1 to {MAX_BRANCHES}, not {b}"),
        ));
    }
    Ok(())
}
