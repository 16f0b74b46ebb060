//! `EXT_mesh_gpu_instancing`: a node that draws its mesh once per instance, each placed by
//! its own TRANSLATION, ROTATION and SCALE after the node's transform.

use super::accessor::{Expect, FLOAT, QUANTIZED_ANY, QUANTIZED_SIGNED_NORMALIZED, read_floats};
use super::buffers::Buffers;
use crate::scene::SceneError;
use glam::{Mat4, Quat, Vec3};
use gltf::json;
use gltf::json::accessor::Type;

/// The extension's name, as a node's `extensions` key.
pub(super) const EXTENSION: &str = "EXT_mesh_gpu_instancing";

/// The extension's object on a node.
#[derive(serde::Deserialize)]
#[serde(rename_all = "UPPERCASE")]
struct Attributes {
    translation: Option<usize>,
    rotation: Option<usize>,
    scale: Option<usize>,
}

#[derive(serde::Deserialize)]
struct Instancing {
    attributes: Attributes,
}

/// The instances' local matrices of node `node` (at JSON path `at`), or `None` where the
/// node does not use the extension.
pub(super) fn instances(
    buffers: &Buffers,
    node: &json::Node,
    at: &str,
) -> Result<Option<Vec<Mat4>>, SceneError> {
    let doc = buffers.doc();
    let Some(value) = node
        .extensions
        .as_ref()
        .and_then(|e| e.others.get(EXTENSION))
    else {
        return Ok(None);
    };
    let at = format!("{at}.extensions.{EXTENSION}");
    let ext: Instancing = serde_json::from_value(value.clone())
        .map_err(|e| doc.error(&at, format!("is not an instancing object: {e}")))?;
    let quantized = doc
        .root
        .extensions_used
        .iter()
        .any(|e| e == "KHR_mesh_quantization");
    let vec3 = |name: &'static str| Expect {
        name,
        ty: Type::Vec3,
        // Translations and scales: floats, or with KHR_mesh_quantization any integer form.
        components: if quantized { QUANTIZED_ANY } else { FLOAT },
    };
    let rotation = Expect {
        name: "ROTATION",
        ty: Type::Vec4,
        components: QUANTIZED_SIGNED_NORMALIZED,
    };
    let read = |index: Option<usize>, name: &str, expect: &Expect, width: usize| {
        index
            .map(|i| {
                let values = read_floats(buffers, i, &format!("{at}.attributes.{name}"), expect)?;
                if values.iter().any(|v| !v.is_finite()) {
                    return Err(doc.error(
                        format!("{at}.attributes.{name}"),
                        format!("accessor {i}: a value is not finite"),
                    ));
                }
                Ok(values.chunks_exact(width).map(<[f32]>::to_vec).collect())
            })
            .transpose()
    };
    let a = &ext.attributes;
    let t: Option<Vec<Vec<f32>>> = read(a.translation, "TRANSLATION", &vec3("TRANSLATION"), 3)?;
    let r: Option<Vec<Vec<f32>>> = read(a.rotation, "ROTATION", &rotation, 4)?;
    let s: Option<Vec<Vec<f32>>> = read(a.scale, "SCALE", &vec3("SCALE"), 3)?;
    let counts: Vec<usize> = [&t, &r, &s]
        .iter()
        .filter_map(|v| v.as_ref().map(Vec::len))
        .collect();
    let Some(&count) = counts.first() else {
        return Err(doc.error(
            format!("{at}.attributes"),
            "has none of TRANSLATION, ROTATION and SCALE",
        ));
    };
    if counts.iter().any(|&c| c != count) {
        return Err(doc.error(
            format!("{at}.attributes"),
            format!("its accessors have different counts: {counts:?}"),
        ));
    }
    Ok(Some(
        (0..count)
            .map(|i| {
                let t = t.as_ref().map_or(Vec3::ZERO, |t| Vec3::from_slice(&t[i]));
                let s = s.as_ref().map_or(Vec3::ONE, |s| Vec3::from_slice(&s[i]));
                let r = r
                    .as_ref()
                    .map_or(Quat::IDENTITY, |r| Quat::from_slice(&r[i]).normalize());
                let r = if r.is_finite() { r } else { Quat::IDENTITY };
                Mat4::from_scale_rotation_translation(s, r, t)
            })
            .collect(),
    ))
}
