//! The default scene's node tree: world matrices composed from the root down (TRS or
//! `matrix`), each node's mesh instanced with its matrix (once per instance under
//! EXT_mesh_gpu_instancing), morphed by its default weights and bent by its skin, its
//! first camera, and its KHR_lights_punctual lights.

use super::buffers::Buffers;
use super::deform::{Deform, inverse_bind_matrices};
use super::instancing::instances;
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
    let mut meshes: HashMap<usize, Vec<(usize, MeshPart, Deform)>> = HashMap::new();
    // Every node's global transform, for skins' joints (made when a skin is first met).
    let mut globals: Option<Vec<Option<Mat4>>> = None;
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
        if scene.nodes.len() == 1 && parent == Mat4::IDENTITY && asset.root_origin.is_none() {
            asset.root_origin = Some(world.w_axis.truncate());
        }
        if let Some(mesh) = node.mesh {
            let m = mesh.value();
            if let Entry::Vacant(e) = meshes.entry(m) {
                e.insert(read_mesh(buffers, m, &mut materials, &at)?);
            }
            let skin = match node.skin {
                Some(s) => {
                    let globals = match &mut globals {
                        Some(g) => g,
                        None => globals.insert(global_matrices(doc)?),
                    };
                    Some(joint_matrices(buffers, s.value(), globals, &at)?)
                }
                None => None,
            };
            let placements = instances(buffers, node, &at)?;
            let primitives = meshes.get(&m).map_or(&[][..], Vec::as_slice);
            let weights = morph_weights(doc, node, m, primitives, &at)?;
            // A node that mirrors (negative determinant) turns its faces' winding, which
            // the loader undoes for every transform (`Builder::append_geometry`), as glTF
            // asks: the faces authored counter-clockwise stay the front ones.
            for (p, part, deform) in primitives {
                let mut part = clone_part(part);
                deform.morph(&mut part, &weights);
                let mut matrix = world;
                match &skin {
                    Some(joints) if deform.is_skinned() => {
                        if let Some(j) = deform.max_joint().filter(|&j| j as usize >= joints.len())
                        {
                            return Err(doc.error(
                                format!("meshes[{m}].primitives[{p}].attributes[\"JOINTS_0\"]"),
                                format!(
                                    "names joint {j}, but the skin of {at} has {}",
                                    super::count(joints.len(), "joint")
                                ),
                            ));
                        }
                        // A skinned mesh is placed by its joints alone: the node's own
                        // transform is ignored, as the specification says.
                        deform.skin(&mut part, joints);
                        matrix = Mat4::IDENTITY;
                    }
                    Some(_) => doc.warn(
                        format!("meshes[{m}].primitives[{p}]"),
                        "has no JOINTS_0 and WEIGHTS_0 for its node's skin; it is drawn unskinned",
                    ),
                    None => {}
                }
                let at = format!("meshes[{m}].primitives[{p}]");
                match &placements {
                    None => asset.parts.push(GltfPart {
                        part,
                        matrix,
                        node: n as u32,
                        at,
                    }),
                    Some(placements) => {
                        for instance in placements {
                            asset.parts.push(GltfPart {
                                part: clone_part(&part),
                                matrix: matrix * *instance,
                                node: n as u32,
                                at: at.clone(),
                            });
                        }
                    }
                }
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
    let animations = root.animations.len();
    if animations > 0 {
        let are = if animations == 1 { "is" } else { "are" };
        asset.notes.push(format!(
            "{}: {} {are} not played; the nodes' own transforms and default morph weights are drawn",
            doc.shown,
            super::count(animations, "animation")
        ));
    }
    asset.materials = materials.materials;
    asset.material_names = materials.names;
    asset.textures = materials.textures;
    Ok(asset)
}

/// The triangle primitives of mesh `m`, by primitive index, each with its morph targets
/// and skin attributes; `at` is the node that uses it.
fn read_mesh(
    buffers: &Buffers,
    m: usize,
    materials: &mut Materials,
    at: &str,
) -> Result<Vec<(usize, MeshPart, Deform)>, SceneError> {
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
        if let Some((mut part, deform)) = read_primitive(buffers, (m, p), primitive)? {
            let material = materials.index(primitive.material.map(|i| i.value()), &at)?;
            for t in &mut part.triangles {
                t.material = Some(material);
            }
            parts.push((p, part, deform));
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
        texcoords1: part.texcoords1.clone(),
        colors: part.colors.clone(),
        tangents: part.tangents.clone(),
        triangles: part.triangles.clone(),
        ..MeshPart::default()
    }
}

/// The morph weights node `node` (at `at`) draws mesh `m` with: the node's `weights`, else
/// the mesh's, else zeros; one per morph target of the mesh's primitives.
fn morph_weights(
    doc: &Doc,
    node: &json::Node,
    m: usize,
    primitives: &[(usize, MeshPart, Deform)],
    at: &str,
) -> Result<Vec<f32>, SceneError> {
    let targets = primitives
        .iter()
        .map(|(_, _, d)| d.target_count())
        .max()
        .unwrap_or(0);
    if let Some((p, _, d)) = primitives
        .iter()
        .find(|(_, _, d)| d.target_count() != targets)
    {
        return Err(doc.error(
            format!("meshes[{m}].primitives[{p}].targets"),
            format!(
                "has {}, but another primitive of the mesh has {targets}; every primitive \
                 of a mesh has the same number",
                super::count(d.target_count(), "target")
            ),
        ));
    }
    let mesh_weights = doc
        .root
        .meshes
        .get(m)
        .and_then(|mesh| mesh.weights.as_ref());
    let (weights, field) = match (&node.weights, mesh_weights) {
        (Some(w), _) => (w.clone(), format!("{at}.weights")),
        (None, Some(w)) => (w.clone(), format!("meshes[{m}].weights")),
        (None, None) => return Ok(vec![0.0; targets]),
    };
    if weights.len() != targets {
        return Err(doc.error(
            field,
            format!(
                "has {}, but the mesh's primitives have {}",
                super::count(weights.len(), "weight"),
                super::count(targets, "morph target")
            ),
        ));
    }
    if let Some(w) = weights.iter().find(|w| !w.is_finite()) {
        return Err(doc.error(field, format!("{w} is not finite")));
    }
    Ok(weights)
}

/// Every node's global transform (its ancestors' transforms times its own), found from the
/// nodes that are no node's child; `None` for a node on a cycle, which no root reaches.
fn global_matrices(doc: &Doc) -> Result<Vec<Option<Mat4>>, SceneError> {
    let nodes = &doc.root.nodes;
    let mut child = vec![false; nodes.len()];
    for node in nodes {
        for c in node.children.iter().flatten() {
            if let Some(slot) = child.get_mut(c.value()) {
                *slot = true;
            }
        }
    }
    let mut globals = vec![None; nodes.len()];
    let mut stack: Vec<(usize, Mat4)> = (0..nodes.len())
        .filter(|&n| !child[n])
        .map(|n| (n, Mat4::IDENTITY))
        .collect();
    while let Some((n, parent)) = stack.pop() {
        let Some(node) = nodes.get(n) else { continue };
        if globals[n].is_some() {
            continue;
        }
        let world = parent * local_matrix(doc, node, &format!("nodes[{n}]"))?;
        globals[n] = Some(world);
        for c in node.children.iter().flatten() {
            stack.push((c.value(), world));
        }
    }
    Ok(globals)
}

/// Skin `s`'s joint matrices, for the node at `at`: each joint node's global transform
/// times its inverse bind matrix.
fn joint_matrices(
    buffers: &Buffers,
    s: usize,
    globals: &[Option<Mat4>],
    at: &str,
) -> Result<Vec<Mat4>, SceneError> {
    let doc = buffers.doc();
    let Some(skin) = doc.root.skins.get(s) else {
        return Err(doc.error(
            format!("{at}.skin"),
            format!(
                "skin {s} does not exist (the file has {})",
                super::count(doc.root.skins.len(), "skin")
            ),
        ));
    };
    let inverse_binds = inverse_bind_matrices(buffers, s, skin)?;
    skin.joints
        .iter()
        .zip(inverse_binds)
        .enumerate()
        .map(|(k, (joint, inverse_bind))| {
            let j = joint.value();
            match globals.get(j).copied().flatten() {
                Some(global) => Ok(global * inverse_bind),
                None => Err(doc.error(
                    format!("skins[{s}].joints[{k}]"),
                    format!("node {j} does not exist or lies on a cycle of children"),
                )),
            }
        })
        .collect()
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

/// Sets `found` to camera `c` placed by `world`, if it is the first camera: perspective
/// (`yfov`) or orthographic (`ymag`, half the view's height).
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
    // A perspective camera's field of view, or an orthographic camera's view height.
    let (vfov, ortho_height) = match (cam.type_, &cam.perspective, &cam.orthographic) {
        (Checked::Valid(json::camera::Type::Perspective), Some(p), _) => {
            let vfov = p.yfov.to_degrees();
            if !(vfov > 0.0 && vfov < 180.0) {
                return Err(doc.error(
                    format!("{cam_at}.perspective.yfov"),
                    format!("must be in (0, pi) radians, got {}", p.yfov),
                ));
            }
            (vfov, None)
        }
        (Checked::Valid(json::camera::Type::Orthographic), _, Some(o)) => {
            if !(o.ymag.is_finite() && o.ymag > 0.0) {
                return Err(doc.error(
                    format!("{cam_at}.orthographic.ymag"),
                    format!("must be positive, got {}", o.ymag),
                ));
            }
            (40.0, Some(2.0 * o.ymag))
        }
        _ => return Err(doc.error(cam_at, "is not a valid perspective or orthographic camera")),
    };
    // The camera looks down its node's -Z, with +Y up.
    let position = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(Vec3::Y);
    let camera = (position.is_finite() && forward != Vec3::ZERO)
        .then(|| Camera::new(position, position + forward, up, vfov, 0.0, None))
        .flatten()
        .map(|c| match ortho_height {
            Some(h) => c.orthographic(h),
            None => c,
        })
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
            shadows: true,
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
