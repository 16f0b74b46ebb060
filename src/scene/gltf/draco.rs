//! `KHR_draco_mesh_compression`: a primitive whose indices and attributes lie in one
//! Draco stream, decoded by `draco-core` (a pure-Rust port of Google's Draco decoder,
//! with limits on what a header may claim). The primitive's accessors still describe the
//! decoded data (count, type, component type), and are checked against it.

use super::accessor::{Expect, decoded_floats, index_count, read_floats};
use super::buffers::Buffers;
use crate::scene::SceneError;
use gltf::json::mesh::{Primitive, Semantic};
use gltf::json::validation::Checked;
use std::collections::BTreeMap;

/// The extension's name, as a primitive's `extensions` key.
pub(super) const EXTENSION: &str = "KHR_draco_mesh_compression";

/// The extension's object on a primitive.
#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct Extension {
    buffer_view: usize,
    /// Attribute semantic → the Draco attribute's unique id.
    attributes: BTreeMap<String, u32>,
}

/// A primitive's geometry: from its Draco stream where it has one, else from its
/// accessors.
pub(super) struct Source<'a> {
    buffers: &'a Buffers<'a>,
    primitive: &'a Primitive,
    at: String,
    draco: Option<Decoded>,
}

/// A decoded Draco stream: its points, its triangles' corners, and the attributes the
/// extension names, by semantic.
struct Decoded {
    mesh: draco_core::Mesh,
    attributes: BTreeMap<String, u32>,
}

impl<'a> Source<'a> {
    /// The geometry of `primitive` (at JSON path `at`), its Draco stream decoded if it has
    /// one.
    pub fn new(
        buffers: &'a Buffers<'a>,
        primitive: &'a Primitive,
        at: &str,
    ) -> Result<Self, SceneError> {
        let doc = buffers.doc();
        let draco = match primitive
            .extensions
            .as_ref()
            .and_then(|e| e.others.get(EXTENSION))
        {
            None => None,
            Some(value) => {
                let ext_at = format!("{at}.extensions.{EXTENSION}");
                let ext: Extension = serde_json::from_value(value.clone())
                    .map_err(|e| doc.error(&ext_at, format!("is not a Draco object: {e}")))?;
                let view = buffers.view(
                    ext.buffer_view,
                    &format!("{ext_at}.bufferView"),
                    "the Draco stream",
                )?;
                let mut mesh = draco_core::Mesh::new();
                let mut stream = draco_core::DecoderBuffer::new(view.bytes());
                draco_core::MeshDecoder::new()
                    .decode(&mut stream, &mut mesh)
                    .map_err(|e| {
                        doc.error(&ext_at, format!("the Draco stream cannot be decoded: {e}"))
                    })?;
                for (name, &id) in &ext.attributes {
                    if mesh.attribute_by_unique_id(id).is_none() {
                        return Err(doc.error(
                            format!("{ext_at}.attributes[\"{name}\"]"),
                            format!("the Draco stream has no attribute {id}"),
                        ));
                    }
                }
                Some(Decoded {
                    mesh,
                    attributes: ext.attributes,
                })
            }
        };
        Ok(Self {
            buffers,
            primitive,
            at: at.to_string(),
            draco,
        })
    }

    /// The buffers the primitive's accessors read.
    pub fn buffers(&self) -> &'a Buffers<'a> {
        self.buffers
    }

    /// The accessor attribute `semantic` names, if the primitive has it.
    pub fn has(&self, semantic: Semantic) -> Option<usize> {
        self.primitive
            .attributes
            .get(&Checked::Valid(semantic))
            .map(|i| i.value())
    }

    /// The JSON path of attribute `name`, for messages.
    pub fn attribute_at(&self, name: &str) -> String {
        format!("{}.attributes[\"{name}\"]", self.at)
    }

    /// Attribute `semantic` as floats (`None` where the primitive lacks it), from the Draco
    /// stream where the extension names it, else from its accessor.
    pub fn floats(
        &self,
        semantic: Semantic,
        expect: &Expect,
    ) -> Result<Option<Vec<f32>>, SceneError> {
        let Some(index) = self.has(semantic.clone()) else {
            return Ok(None);
        };
        let name = semantic.to_string();
        let at = self.attribute_at(&name);
        let compressed = self.draco.as_ref().and_then(|d| {
            let id = d.attributes.get(&name)?;
            d.mesh.attribute_by_unique_id(*id)
        });
        match (compressed, &self.draco) {
            (Some(attribute), Some(d)) => {
                let components = expect.ty.multiplicity();
                let values = attribute.read_f32s(d.mesh.num_points(), components);
                decoded_floats(self.buffers, index, &at, expect, values).map(Some)
            }
            _ => read_floats(self.buffers, index, &at, expect).map(Some),
        }
    }

    /// The triangles' corners from the Draco stream, checked against the `indices`
    /// accessor's count; `None` for a primitive without one.
    pub fn draco_indices(&self) -> Result<Option<Vec<u32>>, SceneError> {
        let Some(d) = &self.draco else {
            return Ok(None);
        };
        let doc = self.buffers.doc();
        let faces = d.mesh.num_faces();
        let mut corners = Vec::with_capacity(faces * 3);
        for f in 0..faces {
            let face = d.mesh.face(draco_core::FaceIndex(f as u32));
            corners.extend(face.iter().map(|p| p.0));
        }
        if let Some(index) = self.primitive.indices {
            let at = format!("{}.indices", self.at);
            let count = index_count(self.buffers, index.value(), &at)?;
            if count != corners.len() as u64 {
                return Err(doc.error(
                    at,
                    format!(
                        "accessor {} has {count} indices, but the Draco stream has {} triangles",
                        index.value(),
                        faces
                    ),
                ));
            }
        }
        Ok(Some(corners))
    }
}
