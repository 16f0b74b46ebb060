//! The scene builder: accumulates the world-space mesh, the material table, the textures
//! and the lights as a scene file's objects or a bare mesh's parts are read, then finishes
//! the [`Scene`] (tangents where normal maps need them, warnings said once).

use super::gltf::GltfAsset;
use super::light::PunctualLight;
use super::part::MeshPart;
use super::source::FileSource;
use super::texture::{TextureError, TextureRef, Textures, Wrap};
use super::{
    Camera, Material, Mesh, NO_COLOR, NO_NORMAL, NO_TANGENT, NO_TEXTURE, NO_UV, RenderSettings,
    Scene, SceneError, Sky, Triangle,
};
use glam::{Mat3, Mat4, Vec3};
use std::collections::HashMap;
use std::path::PathBuf;

/// Accumulates the world-space mesh and the material table while objects are read.
#[derive(Default)]
pub(super) struct Builder {
    pub(super) mesh: Mesh,
    pub(super) materials: Vec<Material>,
    pub(super) material_names: Vec<String>,
    pub(super) named: HashMap<String, u32>,
    pub(super) default_material: Option<u32>,
    pub(super) textures: Textures,
    pub(super) lights: Vec<PunctualLight>,
    pub(super) degenerate: usize,
    pub(super) warnings: Vec<String>,
    /// [`Scene::notes`] so far.
    pub(super) notes: Vec<String>,
    /// [`Builder::obj_material`]'s answers so far.
    pub(super) obj_materials: HashMap<u32, u32>,
    /// The object index of the triangles appended now ([`Mesh::objects`]).
    pub(super) object: u32,
}

impl Builder {
    /// Appends a material to the table; returns its index.
    pub(super) fn add_material(&mut self, name: &str, material: Material) -> u32 {
        self.materials.push(material);
        self.material_names.push(name.to_string());
        self.materials.len() as u32 - 1
    }

    /// The material an OBJ face reads for material `m`: `m` itself, or where one of its
    /// textures clamps or mirrors along v, a copy whose such textures are shifted one image
    /// along v. OBJ texture coordinates are stored as (u, −v) (`obj::parse_texcoord`),
    /// which a repeating lookup reads as glTF's (u, 1 − v) but which puts the image at
    /// v ∈ [−1, 0], where clamping and mirroring need it at [0, 1].
    pub(super) fn obj_material(&mut self, m: u32) -> u32 {
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

    /// Which texture coordinate sets (0, 1) the textures of material `m` read.
    fn uv_sets(&self, m: u32) -> [bool; 2] {
        let mut material = self.materials[m as usize];
        let mut sets = [false; 2];
        for slot in material.texture_slots_mut() {
            if *slot != NO_TEXTURE {
                let set = self.textures.records[*slot as usize].uv_set;
                sets[usize::from(set == 1)] = true;
            }
        }
        sets
    }

    pub(super) fn default_material(&mut self) -> u32 {
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
    pub(super) fn append_part(
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
    pub(super) fn append_gltf(
        &mut self,
        asset: GltfAsset,
        m: Mat4,
        material: Option<u32>,
        node_objects: bool,
        files: &dyn FileSource,
        error: &dyn Fn(&str, String) -> SceneError,
    ) -> Result<(), SceneError> {
        self.warnings.extend(asset.warnings);
        self.notes.extend(asset.notes);
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
    pub(super) fn append_materials(
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
            .map(|(mut mat, name)| {
                for s in mat.texture_slots_mut() {
                    *s = slot(*s);
                }
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
    pub(super) fn append_geometry(
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
        let base_t1 = self.mesh.texcoords.len() as u32;
        self.mesh.texcoords.extend(&part.texcoords1);
        let base_c = self.mesh.colors.len() as u32;
        self.mesh.colors.extend(&part.colors);
        let (has_t1, has_c) = (!part.texcoords1.is_empty(), !part.colors.is_empty());
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
            // The second set and the colours index the part's vertex table, as `p` does.
            let uv1 = if has_t1 {
                t.p.map(|i| i + base_t1)
            } else {
                [NO_UV; 3]
            };
            let color = if has_c {
                t.p.map(|i| i + base_c)
            } else {
                [NO_COLOR; 3]
            };
            let [set0, set1] = self.uv_sets(material);
            if uv[0] == NO_UV && set0 {
                return Err(error(format!(
                    "material `{}` uses a texture, but the mesh has faces without texture coordinates",
                    self.material_names[material as usize].escape_debug()
                )));
            }
            if uv1[0] == NO_UV && set1 {
                return Err(error(format!(
                    "material `{}` reads a texture through TEXCOORD_1, but the mesh has faces without a second texture coordinate set",
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
            // The tangent, second-set and colour tables run beside the triangles from the
            // first one that has such corners.
            let count = self.mesh.triangles.len();
            for (corners, value, none) in [
                (&mut self.mesh.tangent_corners, g, NO_TANGENT),
                (&mut self.mesh.uv1_corners, uv1, NO_UV),
                (&mut self.mesh.color_corners, color, NO_COLOR),
            ] {
                if value[0] != none || !corners.is_empty() {
                    corners.resize(count, [none; 3]);
                    corners.push(value);
                }
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

    pub(super) fn finish(
        mut self,
        path: Option<PathBuf>,
        camera: Camera,
        sky: Sky,
        settings: RenderSettings,
    ) -> Scene {
        // A mesh used by several objects repeats its warnings; say each once.
        let mut seen = std::collections::HashSet::new();
        self.warnings.retain(|w| seen.insert(w.clone()));
        let untangented = super::tangents::generate_missing(
            &mut self.mesh,
            &self.materials,
            &self.textures.records,
        );
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
            notes: self.notes,
            framed: None,
            root_origin: None,
        }
    }
}
