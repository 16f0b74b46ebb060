//! The default scene's node tree: world matrices composed from the root down (TRS or
//! `matrix`), each node's mesh instanced with its matrix, its first perspective camera,
//! and its KHR_lights_punctual lights.

use super::buffers::Buffers;
use super::material::Materials;
use super::primitive::read_primitive;
use super::{Doc, GltfAsset, GltfPart};
use crate::scene::part::MeshPart;
use crate::scene::{Camera, PunctualLight, SceneError};
use glam::{Mat4, Quat, Vec3};
use gltf::json;
use gltf::json::extensions::scene::khr_lights_punctual as lights;
use gltf::json::validation::Checked;
use std::collections::HashMap;
use std::collections::hash_map::Entry;

/// Candela (lm/sr) or lux (lm/m²) per W/sr or W/m²: the luminous efficacy KHR_lights_punctual's
/// photometric units are divided by.
const LUMENS_PER_WATT: f32 = 683.0;

/// Reads the default scene (or scene 0): every node's primitives, lights and cameras.
pub(super) fn load_scene(doc: &Doc, buffers: &Buffers) -> Result<GltfAsset, SceneError> {
    let root = doc.root;
    let s = match root.scene {
        Some(s) => s.value(),
        None if !root.scenes.is_empty() => 0,
        None => return Err(doc.error("scenes", "the file has no scene to render")),
    };
    let Some(scene) = root.scenes.get(s) else {
        return Err(doc.error(
            "scene",
            format!(
                "scene {s} does not exist (the file has {})",
                super::count(root.scenes.len(), "scene")
            ),
        ));
    };
    let mut asset = GltfAsset::default();
    let mut materials = Materials::new(buffers);
    // Each mesh's triangle primitives, read once however many nodes use the mesh.
    let mut meshes: HashMap<usize, Vec<(usize, MeshPart)>> = HashMap::new();
    let mut visited = vec![false; root.nodes.len()];
    // Depth first, children in order: a stack of (node, parent's world matrix, where).
    let mut stack: Vec<(usize, Mat4, String)> = scene
        .nodes
        .iter()
        .enumerate()
        .rev()
        .map(|(k, n)| (n.value(), Mat4::IDENTITY, format!("scenes[{s}].nodes[{k}]")))
        .collect();
    while let Some((n, parent, referrer)) = stack.pop() {
        let Some(node) = root.nodes.get(n) else {
            return Err(doc.error(
                referrer,
                format!(
                    "node {n} does not exist (the file has {})",
                    super::count(root.nodes.len(), "node")
                ),
            ));
        };
        let at = format!("nodes[{n}]");
        if std::mem::replace(&mut visited[n], true) {
            return Err(doc.error(
                at,
                format!(
                    "is reached twice in scene {s}'s node tree (a node has one parent, and \
                     the tree no cycles)"
                ),
            ));
        }
        let world = parent * local_matrix(doc, node, &at)?;
        if let Some(mesh) = node.mesh {
            let m = mesh.value();
            if node.skin.is_some() {
                doc.warn(
                    &at,
                    "skinning is not applied; the mesh is drawn in its bind pose",
                );
            }
            if let Entry::Vacant(e) = meshes.entry(m) {
                e.insert(read_mesh(buffers, m, &mut materials, &at)?);
            }
            // A node that mirrors (negative determinant) turns its faces' winding, which
            // the loader undoes for every transform (`Builder::append_geometry`), as glTF
            // asks: the faces authored counter-clockwise stay the front ones.
            for (p, part) in meshes.get(&m).into_iter().flatten() {
                let part = clone_part(part);
                asset.parts.push(GltfPart {
                    part,
                    matrix: world,
                    node: n as u32,
                    at: format!("meshes[{m}].primitives[{p}]"),
                });
            }
        }
        if let Some(c) = node.camera {
            camera(doc, c.value(), world, &at, &mut asset.camera)?;
        }
        if let Some(light) = node
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            && let Some(light) = punctual_light(doc, light.light.value(), world, &at)?
        {
            asset.lights.push(light);
        }
        let children = node.children.as_deref().unwrap_or_default();
        for (k, child) in children.iter().enumerate().rev() {
            stack.push((child.value(), world, format!("{at}.children[{k}]")));
        }
    }
    asset.materials = materials.materials;
    asset.material_names = materials.names;
    asset.textures = materials.textures;
    Ok(asset)
}

/// The triangle primitives of mesh `m`, by primitive index; `at` is the node that uses it.
fn read_mesh(
    buffers: &Buffers,
    m: usize,
    materials: &mut Materials,
    at: &str,
) -> Result<Vec<(usize, MeshPart)>, SceneError> {
    let doc = buffers.doc();
    let Some(mesh) = doc.root.meshes.get(m) else {
        return Err(doc.error(
            format!("{at}.mesh"),
            format!(
                "mesh {m} does not exist (the file has {})",
                super::count(doc.root.meshes.len(), "mesh")
            ),
        ));
    };
    let mut parts = Vec::new();
    for (p, primitive) in mesh.primitives.iter().enumerate() {
        let at = format!("meshes[{m}].primitives[{p}]");
        if let Some(mut part) = read_primitive(buffers, (m, p), primitive)? {
            let material = materials.index(primitive.material.map(|i| i.value()), &at)?;
            for t in &mut part.triangles {
                t.material = Some(material);
            }
            parts.push((p, part));
        }
    }
    Ok(parts)
}

/// A copy of a part's geometry (a mesh instanced by several nodes).
fn clone_part(part: &MeshPart) -> MeshPart {
    MeshPart {
        positions: part.positions.clone(),
        normals: part.normals.clone(),
        texcoords: part.texcoords.clone(),
        tangents: part.tangents.clone(),
        triangles: part.triangles.clone(),
        ..MeshPart::default()
    }
}

/// A node's own transform: its `matrix` (column-major), or translation × rotation × scale.
fn local_matrix(doc: &Doc, node: &json::Node, at: &str) -> Result<Mat4, SceneError> {
    let finite = |field: &str, values: &[f32]| {
        if values.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(doc.error(format!("{at}.{field}"), "must be finite"))
        }
    };
    if let Some(m) = &node.matrix {
        finite("matrix", m)?;
        return Ok(Mat4::from_cols_array(m));
    }
    let t = node.translation.unwrap_or([0.0; 3]);
    let s = node.scale.unwrap_or([1.0; 3]);
    let r = node.rotation.map_or([0.0, 0.0, 0.0, 1.0], |r| r.0);
    finite("translation", &t)?;
    finite("scale", &s)?;
    finite("rotation", &r)?;
    let q = Quat::from_array(r);
    let length = q.length();
    if !(length > 0.0 && length.is_finite()) {
        return Err(doc.error(
            format!("{at}.rotation"),
            "must be a unit quaternion, not zero",
        ));
    }
    Ok(Mat4::from_scale_rotation_translation(
        Vec3::from(s),
        q / length,
        Vec3::from(t),
    ))
}

/// Sets `found` to camera `c` placed by `world`, if it is the first perspective camera;
/// an orthographic one is skipped with a warning.
fn camera(
    doc: &Doc,
    c: usize,
    world: Mat4,
    at: &str,
    found: &mut Option<Camera>,
) -> Result<(), SceneError> {
    let Some(cam) = doc.root.cameras.get(c) else {
        return Err(doc.error(
            format!("{at}.camera"),
            format!(
                "camera {c} does not exist (the file has {})",
                super::count(doc.root.cameras.len(), "camera")
            ),
        ));
    };
    if found.is_some() {
        return Ok(());
    }
    let cam_at = format!("cameras[{c}]");
    let perspective = match (cam.type_, &cam.perspective) {
        (Checked::Valid(json::camera::Type::Perspective), Some(p)) => p,
        (Checked::Valid(json::camera::Type::Orthographic), _) => {
            doc.warn(cam_at, "orthographic cameras are not supported; skipped");
            return Ok(());
        }
        _ => return Err(doc.error(cam_at, "is not a valid perspective camera")),
    };
    let vfov = perspective.yfov.to_degrees();
    if !(vfov > 0.0 && vfov < 180.0) {
        return Err(doc.error(
            format!("{cam_at}.perspective.yfov"),
            format!("must be in (0, pi) radians, got {}", perspective.yfov),
        ));
    }
    // The camera looks down its node's -Z, with +Y up.
    let position = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(Vec3::Y);
    let camera = (position.is_finite() && forward != Vec3::ZERO)
        .then(|| Camera::new(position, position + forward, up, vfov, 0.0, None))
        .flatten()
        .ok_or_else(|| {
            doc.error(
                at,
                "its transform leaves its camera no position or view direction",
            )
        })?;
    *found = Some(camera);
    Ok(())
}

/// KHR_lights_punctual light `l`, placed by `world`, in radiometric units; `None`, with a
/// warning, when the node's matrix collapses its direction.
fn punctual_light(
    doc: &Doc,
    l: usize,
    world: Mat4,
    at: &str,
) -> Result<Option<PunctualLight>, SceneError> {
    let all = doc
        .root
        .extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
        .map_or(&[][..], |l| l.lights.as_slice());
    let Some(light) = all.get(l) else {
        return Err(doc.error(
            format!("{at}.extensions.KHR_lights_punctual.light"),
            format!(
                "light {l} does not exist (the file has {})",
                super::count(all.len(), "light")
            ),
        ));
    };
    let light_at = format!("extensions.KHR_lights_punctual.lights[{l}]");
    let color = Vec3::from(light.color);
    if !(color.is_finite() && color.min_element() >= 0.0) {
        return Err(doc.error(
            format!("{light_at}.color"),
            format!("must be finite and at least 0, got {color}"),
        ));
    }
    if !(light.intensity.is_finite() && light.intensity >= 0.0) {
        return Err(doc.error(
            format!("{light_at}.intensity"),
            format!("must be finite and at least 0, got {}", light.intensity),
        ));
    }
    if light.range.is_some() {
        doc.warn(
            format!("{light_at}.range"),
            "is ignored: lights fall off with the inverse square of distance alone",
        );
    }
    let power = color * light.intensity / LUMENS_PER_WATT;
    let local = match light.type_ {
        Checked::Valid(lights::Type::Point) => PunctualLight::Point {
            position: Vec3::ZERO,
            intensity: power,
        },
        Checked::Valid(lights::Type::Directional) => PunctualLight::Directional {
            direction: Vec3::NEG_Z,
            irradiance: power,
        },
        Checked::Valid(lights::Type::Spot) => {
            let spot = light.spot.as_ref().ok_or_else(|| {
                doc.error(format!("{light_at}.spot"), "is required for a spot light")
            })?;
            let (inner, outer) = (spot.inner_cone_angle, spot.outer_cone_angle);
            if !(outer > 0.0 && outer <= std::f32::consts::FRAC_PI_2) {
                return Err(doc.error(
                    format!("{light_at}.spot.outerConeAngle"),
                    format!("must be in (0, pi/2], got {outer}"),
                ));
            }
            if !(inner >= 0.0 && inner < outer) {
                return Err(doc.error(
                    format!("{light_at}.spot.innerConeAngle"),
                    format!("must be in [0, outerConeAngle), got {inner}"),
                ));
            }
            PunctualLight::Spot {
                position: Vec3::ZERO,
                direction: Vec3::NEG_Z,
                intensity: power,
                cutoff: outer,
                beam_width: inner,
            }
        }
        Checked::Invalid => {
            return Err(doc.error(
                format!("{light_at}.type"),
                "is not point, spot or directional",
            ));
        }
    };
    let placed = local.transformed(world);
    if placed.is_none() {
        doc.warn(
            at,
            "its transform collapses its light's direction; the light is dropped",
        );
    }
    Ok(placed)
}
