//! Wavefront OBJ files, read in one pass by meshtrace's own parser, and the mapping of
//! their MTL materials (read by [`super::mtl`]) onto meshtrace materials.
//!
//! The parser keeps the geometry that tobj (the crate meshtrace used before) produced, so
//! that images stay the same: triangles in file order, polygons fanned from their first
//! corner, `v x y z w` divided by w, `l` lines of three or more points read as polygons,
//! `usemtl` resolved against the libraries loaded before it. Unlike tobj it names the line
//! of every error, and a face only partly given `vn` indices is flat-shaded rather than
//! borrowing a neighbour's normal.

use super::lines::{BadLine, quoted, text_lines};
use super::mtl::{MtlMap, MtlMaterial, parse_mtl};
use super::part::{MeshPart, PartTriangle};
use super::source::FileSource;
use super::texture::{TextureRef, TextureSource, Usage, UvTransform, Wrap};
use super::{Material, MaterialKind, NO_NORMAL, NO_TANGENT, NO_UV, SceneError};
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// Reads an OBJ file and the MTL libraries it names, fan-triangulating polygons. An error
/// names the file (the OBJ, or the MTL library at fault) and, where one is at fault, the
/// line.
pub fn load_obj(path: &Path, files: &dyn FileSource) -> Result<MeshPart, SceneError> {
    let shown = super::shown(path);
    let bytes = files.read(path).map_err(|source| SceneError::Io {
        path: shown.clone(),
        source,
    })?;
    let dir = path.parent().unwrap_or(Path::new(""));
    parse_obj(&bytes, &shown, dir, files)
}

/// The three kinds of element a face corner refers to, in corner order (`v/vt/vn`).
const ELEMENTS: [(&str, &str); 3] = [
    ("vertex", "vertices"),
    ("texture coordinate", "texture coordinates"),
    ("normal", "normals"),
];

/// One corner of the face being read: its position, normal and texture coordinate
/// indices, 0-based (`NO_NORMAL` for a missing normal or texture coordinate).
type Corner = (u32, u32, u32);

/// Parses an OBJ file's bytes; `shown` names it in messages and warnings, `dir` anchors its
/// `mtllib` paths, which are read through `files`.
///
/// Lines are split at `\n`, so a `\r\n` ending leaves a `\r` that splitting at whitespace
/// drops; a trailing `\` continues nothing (line numbers are the file's own), so a `\`
/// among numbers or indices is an error. Keywords that carry no geometry (`#`, `o`, `g`,
/// `s`, `p`, unknown ones) are skipped. Indices may be negative, counting back from the
/// elements defined so far, and positive ones may refer forward (as tobj allowed), so
/// those are checked against the file's totals once every line is read; such an error is
/// reported only when no line is rejected on sight.
fn parse_obj(
    bytes: &[u8],
    shown: &str,
    dir: &Path,
    files: &dyn FileSource,
) -> Result<MeshPart, SceneError> {
    let at = |bad: BadLine| SceneError::Obj {
        path: shown.to_string(),
        line: Some(bad.line),
        message: bad.message,
    };
    let (text, not_utf8) = text_lines(bytes);
    let mut part = MeshPart::default();
    // Elements defined so far, in `ELEMENTS` order (texture coordinates are only counted).
    let mut defined = [0usize; 3];
    // Per element, the (line, index) of each reference beyond what was defined at that
    // line and beyond every earlier such reference: the first line whose index exceeds the
    // file's total is always among them (any earlier reference is at most that total).
    // The third field is the message's subject (a face or a line).
    let mut forward: [Vec<(usize, usize, &str)>; 3] = Default::default();
    // Material name to index into `part.materials`, from the libraries loaded so far; a
    // name defined again maps to its last definition.
    let mut by_name: HashMap<String, u32> = HashMap::new();
    let mut current: Option<u32> = None;
    // `usemtl` lines whose name no library loaded before them defines.
    let mut unresolved: Vec<(usize, String)> = Vec::new();
    let mut failed_libraries: Vec<String> = Vec::new();
    // The corners of the face being read, reused from face to face.
    let mut corners: Vec<Corner> = Vec::new();
    for (i, text) in text.split('\n').enumerate() {
        let line = i + 1;
        let bad = |message: String| at(BadLine { line, message });
        let mut words = text.split_whitespace();
        match words.next() {
            Some("v") => {
                let p = parse_position(words, defined[0] + 1).map_err(bad)?;
                part.positions.push(p);
                defined[0] += 1;
            }
            Some("vt") => {
                let uv = parse_texcoord(words).map_err(bad)?;
                part.texcoords.push(uv);
                defined[1] += 1;
            }
            Some("vn") => {
                let n = parse_normal(words).map_err(bad)?;
                part.normals.push(n);
                defined[2] += 1;
            }
            Some(keyword @ ("f" | "l")) => {
                let face = keyword == "f";
                // `l` lines of one or two points are dropped (their corners are only
                // checked for syntax), longer ones become polygons like faces, as in tobj.
                let polygon = face || words.clone().nth(2).is_some();
                let what = if face { "face (`f`)" } else { "line (`l`)" };
                let subject = if face { "a face" } else { "a line (`l`)" };
                corners.clear();
                let mut count = 0usize;
                let mut all_normals = true;
                let mut all_uvs = true;
                for word in words {
                    count += 1;
                    let Some(corner) = parse_corner(word) else {
                        return Err(bad(format!(
                            "malformed {what}: corner {} is not `v`, `v/vt`, `v//vn` or \
                             `v/vt/vn` with integer indices{}",
                            quoted(word),
                            continuation_hint(word)
                        )));
                    };
                    all_normals &= corner[2].is_some();
                    all_uvs &= corner[1].is_some();
                    if !polygon {
                        continue;
                    }
                    let mut resolved = [NO_NORMAL; 3];
                    for (k, index) in corner.into_iter().enumerate() {
                        let Some(index) = index else { continue };
                        let (one, many) = ELEMENTS[k];
                        if index == 0 {
                            return Err(bad(format!(
                                "malformed {what}: {one} index 0 (OBJ indices start at 1)"
                            )));
                        }
                        let back = index.unsigned_abs();
                        if index < 0 && back > defined[k] {
                            return Err(bad(format!(
                                "{subject} refers to {one} {index}, which does not exist \
                                 (only {} {many} are defined before this line)",
                                defined[k]
                            )));
                        }
                        let records = &mut forward[k];
                        if index > 0
                            && back > defined[k]
                            && records.last().is_none_or(|&(_, max, _)| back > max)
                        {
                            records.push((line, back, subject));
                        }
                        let zero_based = if index < 0 {
                            defined[k] - back
                        } else {
                            back - 1
                        };
                        // An index past `u32::MAX` is past the file's total too (checked
                        // below), so saturating loses nothing.
                        resolved[k] = u32::try_from(zero_based).unwrap_or(u32::MAX);
                    }
                    corners.push((resolved[0], resolved[2], resolved[1]));
                }
                if face && count < 3 {
                    return Err(bad(format!(
                        "malformed face (`f`): {count} corners, a face needs at least 3"
                    )));
                }
                if count == 0 {
                    // tobj rejected an empty `l` line as an invalid polygon.
                    return Err(bad("malformed line (`l`): no points".into()));
                }
                if polygon {
                    // A fan from the first corner: (a, b, c), (a, c, d), (a, d, e)…
                    let (a, rest) = (corners[0], &corners[1..]);
                    for pair in rest.windows(2) {
                        let (b, c) = (pair[0], pair[1]);
                        part.triangles.push(PartTriangle {
                            p: [a.0, b.0, c.0],
                            n: if all_normals {
                                [a.1, b.1, c.1]
                            } else {
                                [NO_NORMAL; 3]
                            },
                            t: if all_uvs { [a.2, b.2, c.2] } else { [NO_UV; 3] },
                            g: [NO_TANGENT; 3],
                            material: current,
                        });
                    }
                }
            }
            Some("usemtl") => {
                // The name as tobj read it: after the first space, trimmed.
                let name = text.split_once(' ').map_or("", |(_, rest)| rest.trim());
                if name.is_empty() {
                    return Err(bad("`usemtl` names no material".into()));
                }
                current = by_name.get(name).copied();
                if current.is_none() {
                    unresolved.push((line, name.to_string()));
                }
            }
            Some("mtllib") => {
                // One file name, which may hold spaces: the rest of the line, as tobj
                // read it.
                let name = text.split_once(' ').map_or("", |(_, rest)| rest.trim());
                let lib = dir.join(name);
                let Ok(lib_bytes) = files.read(&lib) else {
                    failed_libraries.push(format!("{} (cannot open file)", super::shown(&lib)));
                    continue;
                };
                let (materials, warnings) =
                    parse_mtl(&lib_bytes).map_err(|bad| SceneError::Obj {
                        path: super::shown(&lib),
                        line: Some(bad.line),
                        message: bad.message,
                    })?;
                for (line, warning) in warnings {
                    part.warnings
                        .push(format!("{}:{line}: {warning}", super::shown(&lib)));
                }
                let lib_dir = lib.parent().unwrap_or(Path::new(""));
                for m in materials {
                    by_name.insert(m.name.clone(), part.materials.len() as u32);
                    part.materials
                        .push(map_mtl(&m, lib_dir, &mut part.textures));
                    part.material_names.push(m.name.clone());
                }
            }
            _ => {}
        }
    }
    if let Some(bad) = not_utf8 {
        return Err(at(bad));
    }
    let first_beyond = (0..3)
        .filter_map(|k| {
            let &(line, index, subject) = forward[k]
                .iter()
                .find(|&&(_, index, _)| index > defined[k])?;
            Some((line, k, index, subject))
        })
        .min();
    if let Some((line, k, index, subject)) = first_beyond {
        let (one, many) = ELEMENTS[k];
        return Err(at(BadLine {
            line,
            message: format!(
                "{subject} refers to {one} {index}, which does not exist (the file defines \
                 {} {many})",
                defined[k]
            ),
        }));
    }
    // Indices are `u32`, and `NO_NORMAL` and `NO_UV` are `u32::MAX`.
    if [
        part.positions.len(),
        part.normals.len(),
        part.texcoords.len(),
    ]
    .iter()
    .any(|&n| n >= u32::MAX as usize)
    {
        return Err(SceneError::Obj {
            path: shown.to_string(),
            line: None,
            message: "more than 2^32 - 2 vertices, normals or texture coordinates".into(),
        });
    }
    for lib in &failed_libraries {
        part.warnings.push(format!(
            "{shown}: material library {lib} could not be read; its materials fall back to the default"
        ));
    }
    for (line, name) in unresolved {
        if by_name.contains_key(&name) {
            // As in tobj, a library applies from its `mtllib` line on.
            part.warnings.push(format!(
                "{shown}:{line}: material `{name}` is defined only by a material library \
                 loaded after this line; its faces use the default material"
            ));
        } else if failed_libraries.is_empty() {
            // When a library could not be read, the name may well be one of its own.
            part.warnings.push(format!(
                "{shown}:{line}: unknown material `{name}`; its faces use the default material"
            ));
        }
    }
    Ok(part)
}

/// The indices of one face corner as written: `v`, `v/vt`, `v//vn` or `v/vt/vn`, each an
/// integer as `isize::from_str` reads it (negative counting back). `None` for anything
/// else. Byte by byte rather than through `split('/')` and `str::parse`: faces are most of a
/// large mesh's lines, and this runs on every corner.
fn parse_corner(word: &str) -> Option<[Option<isize>; 3]> {
    let mut fields = [None; 3];
    let mut rest = word.as_bytes();
    for (k, field) in fields.iter_mut().enumerate() {
        let end = rest.iter().position(|&b| b == b'/').unwrap_or(rest.len());
        let (text, tail) = rest.split_at(end);
        // Only `vt` may be empty, and only before a `vn` (`v//vn`).
        if !(text.is_empty() && k == 1 && !tail.is_empty()) {
            *field = Some(parse_index(text)?);
        }
        match tail.split_first() {
            None => return Some(fields),
            Some((_, after)) => rest = after,
        }
    }
    // A fourth `/`-separated field.
    None
}

/// An index as `isize::from_str` reads it (an optional sign, then decimal digits, no
/// overflow), without going through `str`.
fn parse_index(text: &[u8]) -> Option<isize> {
    let (negative, digits) = match text {
        [b'-', rest @ ..] => (true, rest),
        [b'+', rest @ ..] => (false, rest),
        _ => (false, text),
    };
    if digits.is_empty() {
        return None;
    }
    let mut value: isize = 0;
    for &b in digits {
        let digit = b.wrapping_sub(b'0');
        if digit > 9 {
            return None;
        }
        value = value.checked_mul(10)?;
        value = if negative {
            value.checked_sub(digit as isize)?
        } else {
            value.checked_add(digit as isize)?
        };
    }
    Some(value)
}

/// A `v` line's fields: x y z, then an optional w (which divides x y z and must not be 0)
/// or r g b (a vertex colour, checked and ignored); the coordinates, after any division,
/// must be finite. Numbers are read by `str::parse::<f32>`, as tobj read them, so every
/// coordinate keeps its bits. `number` is the vertex's 1-based index, for the message.
fn parse_position(words: std::str::SplitWhitespace, number: usize) -> Result<Vec3, String> {
    let mut values = [0f32; 4];
    let mut count = 0usize;
    for word in words {
        let value: f32 = word.parse().map_err(|_| {
            format!(
                "malformed vertex position (`v`): {} is not a number{}",
                quoted(word),
                continuation_hint(word)
            )
        })?;
        if let Some(slot) = values.get_mut(count) {
            *slot = value;
        }
        count += 1;
    }
    let [mut x, mut y, mut z, w] = values;
    match count {
        3 | 6 => {}
        4 if w == 0.0 => {
            return Err("malformed vertex position (`v`): the weight w is 0".into());
        }
        4 => [x, y, z] = [x / w, y / w, z / w],
        _ => {
            return Err(format!(
                "malformed vertex position (`v`): expected x y z, x y z w or x y z r g b, \
                 found {count} numbers"
            ));
        }
    }
    if !(x.is_finite() && y.is_finite() && z.is_finite()) {
        return Err(format!(
            "vertex {number} has a non-finite coordinate: {x} {y} {z}"
        ));
    }
    Ok(Vec3::new(x, y, z))
}

/// A `vn` line's three numbers.
fn parse_normal(words: std::str::SplitWhitespace) -> Result<Vec3, String> {
    let mut values = [0f32; 3];
    let count = check_numbers_into(words, &mut values, 3..=3, "normal (`vn`)", "x y z")?;
    debug_assert_eq!(count, 3);
    Ok(Vec3::from(values))
}

/// A `vt` line's u and v (an optional w is checked and ignored), finite, in meshtrace's
/// convention, where v runs down the image from its top edge: (u, −v). OBJ runs v up from
/// the bottom edge; a repeating lookup wraps −v to 1 − v, and negating rather than
/// subtracting from 1 keeps a UV scale (`-s`, `scale`) tiling from the bottom edge, as in
/// the file's own terms. Textures that clamp or mirror along v are shifted by one image to
/// match (`Builder::obj_material`).
fn parse_texcoord(words: std::str::SplitWhitespace) -> Result<Vec2, String> {
    let mut values = [0f32; 2];
    check_numbers_into(
        words,
        &mut values,
        2..=3,
        "texture coordinate (`vt`)",
        "u v or u v w",
    )?;
    let [u, v] = values;
    if !(u.is_finite() && v.is_finite()) {
        return Err(format!(
            "texture coordinate (`vt`) has a non-finite value: {u} {v}"
        ));
    }
    Ok(Vec2::new(u, -v))
}

/// Checks that a line's fields after its keyword are a count of numbers within `allowed`,
/// keeping the first numbers in `values`; returns the count. `what` and `form` name the
/// element and its fields in the message.
fn check_numbers_into(
    words: std::str::SplitWhitespace,
    values: &mut [f32],
    allowed: std::ops::RangeInclusive<usize>,
    what: &str,
    form: &str,
) -> Result<usize, String> {
    let mut count = 0usize;
    for word in words {
        let Ok(value) = word.parse::<f32>() else {
            return Err(format!(
                "malformed {what}: {} is not a number{}",
                quoted(word),
                continuation_hint(word)
            ));
        };
        if let Some(slot) = values.get_mut(count) {
            *slot = value;
        }
        count += 1;
    }
    if allowed.contains(&count) {
        Ok(count)
    } else {
        Err(format!(
            "malformed {what}: expected {form}, found {count} numbers"
        ))
    }
}

/// Why a word ending in `\` failed: OBJ's line continuation, which is not supported.
fn continuation_hint(word: &str) -> &'static str {
    if word.ends_with('\\') {
        " (lines continued with `\\` are not joined)"
    } else {
        ""
    }
}

/// The MTL mapping of the scene format: Kd, Ke, illum 3 / Pm (conductors, rough with Pr),
/// illum 7 / d < 1 with Ni > 1 (dielectric); `map_Kd`, `map_Ke`, `map_Pr` and `map_Pm`
/// (relative to `dir`, the library's folder) multiply their statement's value, or 1 where
/// it is absent. A metallic map makes the material `pbr` (base colour Kd, metallic Pm,
/// roughness Pr, 0.5 without it), as only `pbr` varies metalness over a surface. A normal
/// map (`map_Bump`, `bump`, `norm`) applies to any kind. The maps are appended to
/// `textures`, which the material's slots index.
pub fn map_mtl(m: &MtlMaterial, dir: &Path, textures: &mut Vec<TextureRef>) -> Material {
    let kd = m.diffuse.unwrap_or(Vec3::splat(0.8));
    let ks = m.specular;
    let illum = m.illumination_model;
    let metallic = illum == Some(3) || m.metallic.is_some_and(|pm| pm >= 0.5);
    let ior = m.optical_density.unwrap_or(1.0);
    let glass = illum == Some(7) || (m.dissolve.is_some_and(|d| d < 1.0) && ior > 1.0);
    let mut slot = |map: &MtlMap, usage: Usage| {
        textures.push(TextureRef {
            source: TextureSource::File(dir.join(&map.file)),
            usage,
            transform: UvTransform::scale(map.scale[0], map.scale[1]),
            wrap: [if map.clamp { Wrap::CLAMP } else { Wrap::REPEAT }; 2],
            optional: true,
            uv_set: 0,
        });
        textures.len() as u32 - 1
    };
    let mut mat = Material::diffuse(kd);
    // A map multiplies its statement's value, or 1 where the statement is absent.
    let albedo_map = |mat: &mut Material, slot: &mut dyn FnMut(&MtlMap, Usage) -> u32| {
        if let Some(map) = &m.map_diffuse {
            mat.albedo = m.diffuse.unwrap_or(Vec3::ONE);
            mat.albedo_texture = slot(map, Usage::Colour);
        }
    };
    if glass {
        mat.kind = MaterialKind::DIELECTRIC;
        mat.albedo = Vec3::ONE;
        // Without a usable `Ni`, glass of index 1.5 (index 1 would be invisible).
        mat.ior = match m.optical_density {
            Some(n) if n > 0.0 => n,
            _ => 1.5,
        };
    } else if let Some(map) = &m.map_metallic {
        mat.kind = MaterialKind::PBR;
        albedo_map(&mut mat, &mut slot);
        mat.metallic = m.metallic.unwrap_or(1.0).clamp(0.0, 1.0);
        mat.metallic_texture = slot(map, Usage::Scalar { channel: 0 });
        match (m.roughness, &m.map_roughness) {
            (r, Some(map)) => {
                mat.roughness = r.unwrap_or(1.0).clamp(0.0, 1.0);
                mat.roughness_texture = slot(map, Usage::Scalar { channel: 0 });
            }
            (r, None) => mat.roughness = r.unwrap_or(0.5).clamp(0.0, 1.0),
        }
    } else if metallic {
        match ks {
            Some(ks) => mat.albedo = ks,
            None => albedo_map(&mut mat, &mut slot),
        }
        match (m.roughness, &m.map_roughness) {
            (r, Some(map)) => {
                mat.kind = MaterialKind::ROUGH_CONDUCTOR;
                mat.roughness = r.filter(|&r| r > 0.0).unwrap_or(1.0).min(1.0);
                mat.roughness_texture = slot(map, Usage::Scalar { channel: 0 });
            }
            (Some(r), None) if r > 0.0 => {
                mat.kind = MaterialKind::ROUGH_CONDUCTOR;
                mat.roughness = r.min(1.0);
            }
            _ => mat.kind = MaterialKind::CONDUCTOR,
        }
    } else {
        albedo_map(&mut mat, &mut slot);
    }
    mat.emission = m.emission.unwrap_or(Vec3::ZERO).max(Vec3::ZERO);
    if let Some(map) = &m.map_emission {
        mat.emission = m.emission.unwrap_or(Vec3::ONE).max(Vec3::ZERO);
        mat.emission_texture = slot(map, Usage::Colour);
    }
    if let Some(map) = &m.map_normal {
        mat.normal_texture = slot(map, Usage::Linear);
    }
    mat
}
