//! From a file's bytes to a validated glTF JSON document: the GLB container (header, JSON
//! and BIN chunks), the JSON itself (syntax errors with their line and column), the
//! version, the required extensions, and the `gltf` crate's validation of the references
//! between objects.

use super::Doc;
use crate::scene::SceneError;
use gltf::json;
use gltf::json::validation::{Error as Invalid, Validate};

/// The extensions meshtrace reads; a file that requires any other is refused.
pub(super) const SUPPORTED_EXTENSIONS: &[&str] = &[
    "EXT_mesh_gpu_instancing",
    "EXT_meshopt_compression",
    "EXT_texture_webp",
    "KHR_draco_mesh_compression",
    "KHR_lights_punctual",
    "KHR_materials_clearcoat",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_pbrSpecularGlossiness",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
    "KHR_materials_volume",
    "KHR_mesh_quantization",
    "KHR_meshopt_compression",
    "KHR_texture_basisu",
    "KHR_texture_transform",
];

/// The prefix of the material extensions' names, which each material that uses one not
/// in [`SUPPORTED_EXTENSIONS`] warns of (`material.rs`).
pub(super) const MATERIAL_EXTENSION: &str = "KHR_materials_";

/// The GLB header's magic, `glTF`.
const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: &[u8; 4] = b"JSON";
const CHUNK_BIN: &[u8; 4] = b"BIN\0";

/// Parses a `.gltf` (JSON) or `.glb` (binary container) file's bytes, whichever its first
/// bytes say it is; returns the validated document and the GLB's BIN chunk, if any.
pub(super) fn parse(
    bytes: &[u8],
    shown: &str,
) -> Result<(json::Root, Option<Vec<u8>>), SceneError> {
    let error = |at: &str, message: String| SceneError::Gltf {
        path: shown.to_string(),
        at: at.to_string(),
        message,
    };
    let (text, blob, in_glb) = if bytes.starts_with(GLB_MAGIC) {
        let (json, bin) = split_glb(bytes).map_err(|(at, m)| error(at, m))?;
        (json, bin.map(<[u8]>::to_vec), true)
    } else {
        (bytes, None, false)
    };
    let text = text.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(text);
    let root: json::Root =
        json::deserialize::from_slice(text).map_err(|e| json_error(text, &e, shown, in_glb))?;
    check_version(&root).map_err(|(at, m)| error(at, m))?;
    check_required(&root.extensions_required).map_err(|m| error("extensionsRequired", m))?;
    guard_validation(&root).map_err(|(at, m)| error(&at, m))?;
    validate(&root).map_err(|(at, m)| error(&at, m))?;
    Ok((root, blob))
}

/// A GLB file's JSON chunk and, if present, its BIN chunk.
type Chunks<'a> = (&'a [u8], Option<&'a [u8]>);

/// The chunks of a GLB file. An error names the part of the container at fault.
fn split_glb(bytes: &[u8]) -> Result<Chunks<'_>, (&'static str, String)> {
    let (Some(version), Some(length)) = (read_u32(bytes, 4), read_u32(bytes, 8)) else {
        return Err((
            "GLB header",
            format!(
                "the file is {} bytes, shorter than the 12-byte GLB header",
                bytes.len()
            ),
        ));
    };
    if version != 2 {
        return Err((
            "GLB header",
            format!("GLB version {version}; meshtrace reads version 2"),
        ));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err((
            "GLB header",
            format!(
                "the header gives the file's length as {length} bytes, but it has {} (truncated?)",
                bytes.len()
            ),
        ));
    }
    let bytes = &bytes[..length];
    let mut chunks = Vec::new();
    let mut at = 12usize;
    while at < bytes.len() {
        let names = ["GLB JSON chunk", "GLB BIN chunk"];
        let name = names.get(chunks.len()).copied().unwrap_or("GLB chunk");
        let (Some(size), Some(kind)) = (read_u32(bytes, at), bytes.get(at + 4..at + 8)) else {
            return Err((
                name,
                format!(
                    "the chunk header at byte {at} is cut off by the end of the file (truncated?)"
                ),
            ));
        };
        let start = at + 8;
        let data = start
            .checked_add(size as usize)
            .and_then(|end| bytes.get(start..end))
            .ok_or((
                name,
                format!(
                    "the chunk claims {size} bytes, but only {} remain in the file (truncated?)",
                    bytes.len() - start
                ),
            ))?;
        chunks.push((kind, data));
        at = start + data.len();
    }
    let Some(&(kind, json)) = chunks.first() else {
        return Err(("GLB JSON chunk", "the file has no chunks".into()));
    };
    if kind != CHUNK_JSON {
        return Err((
            "GLB JSON chunk",
            format!(
                "the first chunk is of type {}, not JSON",
                String::from_utf8_lossy(kind).escape_debug()
            ),
        ));
    }
    // A BIN chunk, if any, comes second; chunks of other types are to be ignored.
    let bin = chunks
        .get(1)
        .filter(|(kind, _)| *kind == CHUNK_BIN)
        .map(|&(_, data)| data);
    Ok((json, bin))
}

/// The little-endian `u32` at byte `at`, if the bytes reach that far.
fn read_u32(bytes: &[u8], at: usize) -> Option<u32> {
    let b: [u8; 4] = bytes.get(at..at.checked_add(4)?)?.try_into().ok()?;
    Some(u32::from_le_bytes(b))
}

/// A JSON error as a syntax error at its line and column (within the JSON chunk of a
/// GLB). A file that requires an extension meshtrace does not read, or that is not glTF
/// 2.0, says so instead, since that is why its JSON does not fit.
fn json_error(text: &[u8], e: &json::Error, shown: &str, in_glb: bool) -> SceneError {
    if let Ok(value) = json::deserialize::from_slice::<json::Value>(text) {
        let required: Vec<String> = value
            .get("extensionsRequired")
            .and_then(json::Value::as_array)
            .map(|a| {
                a.iter()
                    .filter_map(|v| v.as_str().map(str::to_string))
                    .collect()
            })
            .unwrap_or_default();
        let version = value
            .get("asset")
            .and_then(|a| a.get("version"))
            .and_then(json::Value::as_str);
        let early = match version {
            Some(v) if !v.starts_with("2.") => Some(("asset.version", version_message(v))),
            _ => check_required(&required)
                .err()
                .map(|m| ("extensionsRequired", m)),
        };
        if let Some((at, message)) = early {
            return SceneError::Gltf {
                path: shown.to_string(),
                at: at.into(),
                message,
            };
        }
    }
    // serde_json's message ends with " at line L column C", which the error shows before it.
    let message = e.to_string();
    let message = match message.rfind(" at line ") {
        Some(i) => &message[..i],
        None => &message,
    };
    let chunk = if in_glb {
        " (in the GLB's JSON chunk)"
    } else {
        ""
    };
    SceneError::Syntax {
        path: shown.to_string(),
        line: e.line(),
        column: e.column(),
        message: format!("{}{chunk}", message.escape_debug()),
    }
}

fn version_message(version: &str) -> String {
    format!("glTF {}: meshtrace reads glTF 2.0", super::quoted(version))
}

/// The asset's version must be 2.x.
fn check_version(root: &json::Root) -> Result<(), (&'static str, String)> {
    let v = &root.asset.version;
    if v.starts_with("2.") {
        Ok(())
    } else {
        Err(("asset.version", version_message(v)))
    }
}

/// An error naming the required extensions that meshtrace does not read.
fn check_required(required: &[String]) -> Result<(), String> {
    let unsupported: Vec<String> = required
        .iter()
        .filter(|e| !SUPPORTED_EXTENSIONS.contains(&e.as_str()))
        .map(|e| super::quoted(e))
        .collect();
    if unsupported.is_empty() {
        return Ok(());
    }
    Err(format!(
        "the file requires {}, which meshtrace does not support (it reads {})",
        unsupported.join(", "),
        SUPPORTED_EXTENSIONS.join(", ")
    ))
}

/// Warns of the extensions the file uses, without requiring them, that meshtrace ignores.
/// Material extensions are left to the warning of each material that uses one.
pub(super) fn check_extensions(doc: &Doc) {
    let ignored: Vec<String> = doc
        .root
        .extensions_used
        .iter()
        .filter(|e| {
            !SUPPORTED_EXTENSIONS.contains(&e.as_str()) && !e.starts_with(MATERIAL_EXTENSION)
        })
        .map(|e| super::quoted(e))
        .collect();
    if !ignored.is_empty() {
        doc.warn(
            "extensionsUsed",
            format!(
                "{} not supported; the file is read without {}",
                ignored.join(", "),
                if ignored.len() == 1 { "it" } else { "them" }
            ),
        );
    }
}

/// Checks what the `gltf` crate's validation would otherwise panic on: its check of a
/// primitive's POSITION bounds looks up the accessor before the index is known to exist.
fn guard_validation(root: &json::Root) -> Result<(), (String, String)> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = json::validation::Checked::Valid(json::mesh::Semantic::Positions);
            let Some(index) = primitive.attributes.get(&position) else {
                continue;
            };
            if root.accessors.get(index.value()).is_none() {
                return Err((
                    format!("meshes[{m}].primitives[{p}].attributes[\"POSITION\"]"),
                    format!(
                        "accessor {} does not exist (the file has {})",
                        index.value(),
                        super::count(root.accessors.len(), "accessor")
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The `gltf` crate's validation of the document: every reference between objects in
/// range, every enumerated value known, every required property present. Its first
/// problem is the error, with the count of any others. Two of its rules are stricter than
/// the specification and are not enforced: POSITION accessors without `min` and `max` (which
/// meshtrace does not use), and accessors with neither `bufferView` nor `sparse` (zeros).
/// Required extensions are [`check_required`]'s: the crate knows only those it parses.
fn validate(root: &json::Root) -> Result<(), (String, String)> {
    let mut problems: Vec<(String, Invalid)> = Vec::new();
    root.validate(root, json::Path::new, &mut |path, error| {
        let path = path().0;
        let ignored = (path.ends_with("[\"POSITION\"].min")
            || path.ends_with("[\"POSITION\"].max"))
            || (path.starts_with("accessors[")
                && path.ends_with("].bufferView")
                && error == Invalid::Missing)
            || (path.starts_with("extensionsRequired") && error == Invalid::Unsupported);
        if !ignored {
            problems.push((path, error));
        }
    });
    let Some((path, error)) = problems.first() else {
        return Ok(());
    };
    let message = match error {
        Invalid::IndexOutOfBounds => "refers to an object that the file does not have",
        Invalid::Invalid => "has an invalid value",
        Invalid::Missing => "is required but missing",
        Invalid::Oversize => "is too large for this machine's address space",
        Invalid::Unsupported => "is not supported",
    };
    let more = match problems.len() - 1 {
        0 => String::new(),
        1 => " (and 1 more problem)".into(),
        n => format!(" (and {n} more problems)"),
    };
    Err((path.escape_debug().to_string(), format!("{message}{more}")))
}
