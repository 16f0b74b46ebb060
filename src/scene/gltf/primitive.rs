//! Mesh primitives: their attributes (POSITION, NORMAL, TEXCOORD_0 and _1, TANGENT,
//! COLOR_0; morph targets and skin attributes are `deform`'s) and their topology (triangle
//! lists, strips and fans, indexed or not) as a [`MeshPart`] whose corners all index one
//! vertex table.

use super::accessor::{self, read_indices};
use super::buffers::Buffers;
use super::deform::Deform;
use super::draco::Source;
use crate::scene::part::{MeshPart, PartTriangle};
use crate::scene::{NO_NORMAL, NO_TANGENT, NO_UV, SceneError};
use glam::{Vec2, Vec3, Vec4};
use gltf::json::accessor::Type;
use gltf::json::mesh::{Mode, Primitive, Semantic};
use gltf::json::validation::Checked;

/// Reads primitive `p` of mesh `m`, its triangles without a material yet, and its morph
/// targets and skin attributes; `None`, with a warning, for a primitive of points or lines.
pub(super) fn read_primitive(
    buffers: &Buffers,
    (m, p): (usize, usize),
    primitive: &Primitive,
) -> Result<Option<(MeshPart, Deform)>, SceneError> {
    let doc = buffers.doc();
    let at = format!("meshes[{m}].primitives[{p}]");
    let Checked::Valid(mode) = primitive.mode else {
        return Err(doc.error(format!("{at}.mode"), "is not a primitive mode"));
    };
    let mode_name = match mode {
        Mode::Points => Some("POINTS"),
        Mode::Lines => Some("LINES"),
        Mode::LineLoop => Some("LINE_LOOP"),
        Mode::LineStrip => Some("LINE_STRIP"),
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => None,
    };
    if let Some(name) = mode_name {
        doc.warn(
            at,
            format!("mode {name} draws no triangles; the primitive is skipped"),
        );
        return Ok(None);
    }
    let quantized = doc
        .root
        .extensions_used
        .iter()
        .any(|e| e == "KHR_mesh_quantization");
    let source = Source::new(buffers, primitive, &at)?;
    let attribute = |s: Semantic| source.has(s);
    let attribute_at = |name: &str| source.attribute_at(name);

    let Some(position) = attribute(Semantic::Positions) else {
        return Err(doc.error(format!("{at}.attributes"), "has no POSITION"));
    };
    let at_p = attribute_at("POSITION");
    let values = source
        .floats(Semantic::Positions, &accessor::position(quantized))?
        .unwrap_or_default();
    let positions: Vec<Vec3> = values.chunks_exact(3).map(Vec3::from_slice).collect();
    if let Some((i, v)) = positions.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(doc.error(
            at_p,
            format!("accessor {position}: vertex {i} is not finite: {v}"),
        ));
    }
    let n = positions.len();
    if n >= u32::MAX as usize {
        return Err(doc.error(
            at_p,
            format!("{n} vertices are more than meshtrace indexes"),
        ));
    }
    let same_count = |name: &str, index: usize, len: usize| {
        if len == n {
            Ok(())
        } else {
            Err(doc.error(
                attribute_at(name),
                format!("accessor {index} has {len} elements, but POSITION has {n}"),
            ))
        }
    };

    let mut part = MeshPart {
        positions,
        ..MeshPart::default()
    };
    if let Some(index) = attribute(Semantic::Normals) {
        let values = source
            .floats(Semantic::Normals, &accessor::normal(quantized))?
            .unwrap_or_default();
        // A non-finite normal becomes zero, which the scene builder reads as none.
        part.normals = values
            .chunks_exact(3)
            .map(Vec3::from_slice)
            .map(|v| if v.is_finite() { v } else { Vec3::ZERO })
            .collect();
        same_count("NORMAL", index, part.normals.len())?;
    }
    // glTF's (0, 0) is the image's top-left corner, as meshtrace's.
    let texcoords = |set: u32, name: &'static str| -> Result<Vec<Vec2>, SceneError> {
        let Some(index) = attribute(Semantic::TexCoords(set)) else {
            return Ok(Vec::new());
        };
        let values = source
            .floats(
                Semantic::TexCoords(set),
                &accessor::texcoord(quantized, name),
            )?
            .unwrap_or_default();
        let uvs: Vec<Vec2> = values.chunks_exact(2).map(Vec2::from_slice).collect();
        same_count(name, index, uvs.len())?;
        if let Some((i, v)) = uvs.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(doc.error(
                attribute_at(name),
                format!("accessor {index}: texture coordinate {i} is not finite: {v}"),
            ));
        }
        Ok(uvs)
    };
    part.texcoords = texcoords(0, "TEXCOORD_0")?;
    part.texcoords1 = texcoords(1, "TEXCOORD_1")?;
    if let Some(index) = attribute(Semantic::Tangents) {
        let values = source
            .floats(Semantic::Tangents, &accessor::tangent(quantized))?
            .unwrap_or_default();
        part.tangents = values
            .chunks_exact(4)
            .map(Vec4::from_slice)
            .map(|v| if v.is_finite() { v } else { Vec4::ZERO })
            .collect();
        same_count("TANGENT", index, part.tangents.len())?;
    }
    if let Some(index) = attribute(Semantic::Colors(0)) {
        // The accessor's own type says RGB or RGBA; another type fails the check.
        let ty = doc
            .root
            .accessors
            .get(index)
            .and_then(|a| match a.type_ {
                Checked::Valid(ty) => Some(ty),
                Checked::Invalid => None,
            })
            .unwrap_or(Type::Vec4);
        let expect = accessor::color(ty);
        let values = source
            .floats(Semantic::Colors(0), &expect)?
            .unwrap_or_default();
        let k = expect.ty.multiplicity();
        // The specification bounds colours to [0, 1]; a component that is not finite
        // becomes 1, leaving the base colour as it is.
        part.colors = values
            .chunks_exact(k)
            .map(|c| {
                let rgba = Vec4::new(c[0], c[1], c[2], if k == 4 { c[3] } else { 1.0 });
                Vec4::select(rgba.is_finite_mask(), rgba, Vec4::ONE).clamp(Vec4::ZERO, Vec4::ONE)
            })
            .collect();
        same_count("COLOR_0", index, part.colors.len())?;
    }
    let deform = Deform::read(&source, primitive, &at, n, quantized)?;

    let draco = source.draco_indices()?;
    let vertices: Vec<u32> = match (draco, primitive.indices) {
        (Some(indices), _) => {
            if let Some((k, &i)) = indices.iter().enumerate().find(|&(_, &i)| i as usize >= n) {
                return Err(doc.error(
                    format!("{at}.extensions.KHR_draco_mesh_compression"),
                    format!(
                        "the Draco stream's corner {k} is point {i}, but POSITION has {n} vertices"
                    ),
                ));
            }
            indices
        }
        (None, Some(index)) => {
            let at_i = format!("{at}.indices");
            let indices = read_indices(buffers, index.value(), &at_i)?;
            if let Some((k, &i)) = indices.iter().enumerate().find(|&(_, &i)| i as usize >= n) {
                return Err(doc.error(
                    at_i,
                    format!(
                        "index {i} (entry {k} of accessor {}) is out of range: POSITION has {n} vertices",
                        index.value(),
                    ),
                ));
            }
            indices
        }
        (None, None) => (0..n as u32).collect(),
    };
    let corners = triangles(mode, &vertices);
    let leftover = match mode {
        Mode::Triangles => vertices.len() % 3,
        _ => 0,
    };
    if leftover != 0 {
        doc.warn(
            &at,
            format!(
                "{} vertices do not make whole triangles; the last {leftover} are ignored",
                vertices.len()
            ),
        );
    }
    let (has_n, has_t, has_g) = (
        !part.normals.is_empty(),
        !part.texcoords.is_empty(),
        !part.tangents.is_empty(),
    );
    part.triangles = corners
        .map(|c| PartTriangle {
            p: c,
            n: if has_n { c } else { [NO_NORMAL; 3] },
            t: if has_t { c } else { [NO_UV; 3] },
            g: if has_g { c } else { [NO_TANGENT; 3] },
            material: None,
        })
        .collect();
    Ok(Some((part, deform)))
}

/// The triangles a primitive's vertex sequence makes, as the specification orders their
/// corners: lists by threes; strips {v_i, v_(i+1+i%2), v_(i+2-i%2)}; fans
/// {v_(i+1), v_(i+2), v_0}.
fn triangles(mode: Mode, v: &[u32]) -> Box<dyn Iterator<Item = [u32; 3]> + '_> {
    let strips = v.len().saturating_sub(2);
    match mode {
        Mode::TriangleStrip => {
            Box::new((0..strips).map(|i| [v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]]))
        }
        Mode::TriangleFan => Box::new((0..strips).map(|i| [v[i + 1], v[i + 2], v[0]])),
        _ => Box::new(v.chunks_exact(3).map(|c| [c[0], c[1], c[2]])),
    }
}
