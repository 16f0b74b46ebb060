//! Wavefront OBJ and MTL files, read through tobj and mapped onto meshtrace materials.

use super::{Material, MaterialKind, SceneError};
use glam::Vec3;
use std::path::Path;

/// Where scene files and meshes are read from: the file system, or the scenes built in.
pub trait FileSource {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>>;
}

/// The file system.
pub struct Fs;

impl FileSource for Fs {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        std::fs::read(path)
    }
}

/// One OBJ file's geometry in its own space, with its materials already mapped.
#[derive(Debug, Default)]
pub struct ObjMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// Position indices, normal indices (or `NO_NORMAL`) and an index into `materials`
    /// (or `None` for faces that name no material).
    pub triangles: Vec<([u32; 3], [u32; 3], Option<u32>)>,
    pub materials: Vec<Material>,
    /// The MTL name of each of `materials`.
    pub material_names: Vec<String>,
    pub warnings: Vec<String>,
}

/// Reads an OBJ file, fan-triangulating polygons, and maps its MTL materials.
pub fn load_obj(path: &Path, files: &dyn FileSource) -> Result<ObjMesh, SceneError> {
    let shown = super::shown(path);
    let err = |message: String| SceneError::Obj {
        path: shown.clone(),
        line: None,
        message,
    };
    let bytes = files.read(path).map_err(|source| SceneError::Io {
        path: shown.clone(),
        source,
    })?;
    // Before tobj, whose errors name no line: the scan rejects what tobj would (and a few
    // things it lets through) with the line at fault.
    let scan = scan_obj(&bytes).map_err(|bad| SceneError::Obj {
        path: shown.clone(),
        line: Some(bad.line),
        message: bad.message,
    })?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut out = ObjMesh::default();
    // tobj reports an unreadable library only when no library at all could be read, so
    // every failure is noted here as it happens.
    let failed_mtl = std::cell::RefCell::new(Vec::new());
    // tobj 4 panics on some malformed lines (a one-number `Kd`); that is bad input, not a
    // bug of ours, so it becomes an error naming the file.
    let parsed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        tobj::load_obj_buf(&mut bytes.as_slice(), &options, |mtl| {
            let result = files
                .read(&dir.join(mtl))
                .map_err(|_| tobj::LoadError::OpenFileFailed)
                .and_then(|b| tobj::load_mtl_buf(&mut b.as_slice()));
            if let Err(e) = &result {
                failed_mtl.borrow_mut().push(format!(
                    "{} ({})",
                    dir.join(mtl).display(),
                    describe_tobj_error(e)
                ));
            }
            result
        })
    }))
    .map_err(|_| err("malformed OBJ or MTL data (the parser rejected a line)".into()))?;
    let (models, materials) = parsed.map_err(|e| err(describe_tobj_error(&e)))?;
    let failed_mtl = failed_mtl.into_inner();
    let failed_mtl_count = failed_mtl.len();
    for lib in failed_mtl {
        out.warnings.push(format!(
            "{shown}: material library {lib} could not be read; its materials fall back to the default"
        ));
    }
    if let Ok(mtls) = materials {
        out.materials = mtls.iter().map(map_mtl).collect();
        out.material_names = mtls.iter().map(|m| m.name.clone()).collect();
    }
    let names: Vec<&str> = out.material_names.iter().map(String::as_str).collect();
    if failed_mtl_count == 0 {
        for (line, name) in &scan.usemtl {
            if !names.contains(&name.as_str()) {
                out.warnings.push(format!(
                    "{shown}:{line}: unknown material `{name}`; its faces use the default material"
                ));
            }
        }
    }
    // Which triangles came from faces with normals, in file order (tobj keeps that order
    // and fans each polygon into `corners - 2` triangles); tobj itself fills a missing
    // `vn` with a neighbour's, which would smooth-shade a face that asked to be flat.
    let total: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
    let tri_has_normal: Option<Vec<bool>> =
        (scan.faces.iter().map(|f| f.0).sum::<usize>() == total).then(|| {
            scan.faces
                .iter()
                .flat_map(|&(n, has)| std::iter::repeat_n(has, n))
                .collect()
        });
    let mut tri_index = 0usize;
    for model in &models {
        let m = &model.mesh;
        let base_p = out.positions.len() as u32;
        let base_n = out.normals.len() as u32;
        for (i, p) in m.positions.chunks_exact(3).enumerate() {
            let v = Vec3::new(p[0], p[1], p[2]);
            // The scan rejects these with their line; this is a fallback in case tobj's
            // arithmetic ever differs from the scan's.
            if !v.is_finite() {
                return Err(err(format!(
                    "object `{}`: vertex {} has a non-finite coordinate {v}",
                    model.name,
                    i + 1
                )));
            }
            out.positions.push(v);
        }
        for n in m.normals.chunks_exact(3) {
            out.normals.push(Vec3::new(n[0], n[1], n[2]));
        }
        let material = match m.material_id {
            Some(id) if id < out.materials.len() => Some(id as u32),
            Some(_) => None,
            None => None,
        };
        let has_normals = m.normal_indices.len() == m.indices.len() && !m.normals.is_empty();
        for (f, tri) in m.indices.chunks_exact(3).enumerate() {
            let p = [tri[0] + base_p, tri[1] + base_p, tri[2] + base_p];
            let face_has_normals = tri_has_normal.as_ref().is_none_or(|v| v[tri_index]);
            tri_index += 1;
            let n = if has_normals && face_has_normals {
                let ni = &m.normal_indices[3 * f..3 * f + 3];
                [ni[0] + base_n, ni[1] + base_n, ni[2] + base_n]
            } else {
                [super::NO_NORMAL; 3]
            };
            out.triangles.push((p, n, material));
        }
    }
    Ok(out)
}

/// What tobj does not report: each face's triangle count and whether all its corners have
/// normals, and every `usemtl` with its line number.
struct ObjScan {
    faces: Vec<(usize, bool)>,
    usemtl: Vec<(usize, String)>,
}

/// The first line of an OBJ file that the scan rejects: its 1-based number and why.
#[derive(Debug)]
struct BadLine {
    line: usize,
    message: String,
}

/// The three kinds of element a face corner refers to, in corner order (`v/vt/vn`).
const ELEMENTS: [(&str, &str); 3] = [
    ("vertex", "vertices"),
    ("texture coordinate", "texture coordinates"),
    ("normal", "normals"),
];

/// Walks every line of an OBJ file once, before tobj sees it, collecting what tobj does not
/// report ([`ObjScan`]) and rejecting the first malformed line with its number, since tobj's
/// errors name no line.
///
/// Lines are what tobj reads (`BufRead::lines`): split at `\n`, so a `\r\n` ending leaves a
/// `\r` that splitting at whitespace drops, and a trailing `\` continues nothing (tobj does
/// not join lines, so a `\` among numbers or indices is an error, and line numbers are the
/// file's own). Keywords tobj skips (`#`, `o`, `g`, `s`, `mtllib`, `p`, unknown ones) are not
/// looked at. Indices follow tobj: negative ones count back from the elements defined so
/// far; positive ones may refer forward, so those are checked against the file's totals once
/// the walk is done, and such an error is reported only when no line is rejected on sight.
/// Besides an entry per face, the walk allocates only for `usemtl` names, messages and the
/// rare forward reference.
fn scan_obj(bytes: &[u8]) -> Result<ObjScan, BadLine> {
    let mut scan = ObjScan {
        faces: Vec::new(),
        usemtl: Vec::new(),
    };
    // Elements defined so far, in `ELEMENTS` order.
    let mut defined = [0usize; 3];
    // Per element, the (line, index) of each reference beyond what was defined at that
    // line and beyond every earlier such reference: the first line whose index exceeds the
    // file's total is always among them (any earlier reference is at most that total).
    // The third field is the message's subject (a face or a line).
    let mut forward: [Vec<(usize, usize, &str)>; 3] = Default::default();
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = i + 1;
        let bad = |message: String| BadLine { line, message };
        let Ok(text) = std::str::from_utf8(raw) else {
            return Err(bad("the line is not valid UTF-8 text".into()));
        };
        let mut words = text.split_whitespace();
        match words.next() {
            Some("v") => {
                check_position(words, defined[0] + 1).map_err(bad)?;
                defined[0] += 1;
            }
            Some("vt") => {
                check_numbers(words, 2..=3, "texture coordinate (`vt`)", "u v or u v w")
                    .map_err(bad)?;
                defined[1] += 1;
            }
            Some("vn") => {
                check_numbers(words, 3..=3, "normal (`vn`)", "x y z").map_err(bad)?;
                defined[2] += 1;
            }
            Some(keyword @ ("f" | "l")) => {
                let face = keyword == "f";
                // tobj drops `l` lines of one or two points unchecked and turns longer
                // ones into triangles like faces.
                let polygon = face || words.clone().nth(2).is_some();
                let what = if face { "face (`f`)" } else { "line (`l`)" };
                let subject = if face { "a face" } else { "a line (`l`)" };
                let mut corners = 0usize;
                let mut all_normals = true;
                for word in words {
                    corners += 1;
                    let Some(corner) = parse_corner(word) else {
                        return Err(bad(format!(
                            "malformed {what}: corner {} is not `v`, `v/vt`, `v//vn` or \
                             `v/vt/vn` with integer indices{}",
                            quoted(word),
                            continuation_hint(word)
                        )));
                    };
                    all_normals &= corner[2].is_some();
                    if !polygon {
                        continue;
                    }
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
                    }
                }
                if face && corners < 3 {
                    return Err(bad(format!(
                        "malformed face (`f`): {corners} corners, a face needs at least 3"
                    )));
                }
                if polygon {
                    scan.faces.push((corners - 2, all_normals));
                }
            }
            Some("usemtl") => {
                // tobj's reading of the name, so that it is looked up as tobj does.
                let name = text.split_once(' ').map_or("", |(_, rest)| rest.trim());
                if name.is_empty() {
                    return Err(bad("`usemtl` names no material".into()));
                }
                scan.usemtl.push((line, name.to_string()));
            }
            _ => {}
        }
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
        return Err(BadLine {
            line,
            message: format!(
                "{subject} refers to {one} {index}, which does not exist (the file defines \
                 {} {many})",
                defined[k]
            ),
        });
    }
    Ok(scan)
}

/// The indices of one face corner as written: `v`, `v/vt`, `v//vn` or `v/vt/vn`, each an
/// integer as tobj reads it (`isize`, negative counting back). `None` for anything else.
/// Byte by byte rather than through `split('/')` and `str::parse`: faces are most of a
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

/// A `v` line's fields: x y z, then tobj's optional w (which divides x y z and must not be
/// 0) or r g b; the coordinates, after any division, must be finite. `number` is the
/// vertex's 1-based index, for the message.
fn check_position(words: std::str::SplitWhitespace, number: usize) -> Result<(), String> {
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
    Ok(())
}

/// Checks that a line's fields after its keyword are a count of numbers within `allowed`;
/// `what` and `form` name the element and its fields in the message.
fn check_numbers(
    words: std::str::SplitWhitespace,
    allowed: std::ops::RangeInclusive<usize>,
    what: &str,
    form: &str,
) -> Result<(), String> {
    let mut count = 0usize;
    for word in words {
        if word.parse::<f32>().is_err() {
            return Err(format!(
                "malformed {what}: {} is not a number{}",
                quoted(word),
                continuation_hint(word)
            ));
        }
        count += 1;
    }
    if allowed.contains(&count) {
        Ok(())
    } else {
        Err(format!(
            "malformed {what}: expected {form}, found {count} numbers"
        ))
    }
}

/// A word of the file as a message shows it: quoted, escaped onto one line, and cut short.
fn quoted(word: &str) -> String {
    const MAX: usize = 32;
    let cut: String = word.chars().take(MAX).collect();
    let more = if word.chars().nth(MAX).is_some() {
        "…"
    } else {
        ""
    };
    format!("`{}{more}`", cut.escape_debug())
}

/// Why a word ending in `\` failed: OBJ's line continuation, which tobj does not support.
fn continuation_hint(word: &str) -> &'static str {
    if word.ends_with('\\') {
        " (tobj does not join lines continued with `\\`)"
    } else {
        ""
    }
}

/// The MTL mapping of the scene format: Kd, Ke, illum 3 / Pm (conductors, rough with Pr),
/// illum 7 / d < 1 with Ni > 1 (dielectric).
pub fn map_mtl(m: &tobj::Material) -> Material {
    let param = |key: &str| -> Option<&str> { m.unknown_param.get(key).map(|s| s.trim()) };
    let scalar = |key: &str| param(key).and_then(|s| s.parse::<f32>().ok());
    let color = |key: &str| {
        param(key).and_then(|s| {
            let v: Vec<f32> = s
                .split_whitespace()
                .filter_map(|x| x.parse().ok())
                .collect();
            match v.as_slice() {
                [r, g, b] => Some(Vec3::new(*r, *g, *b)),
                [x] => Some(Vec3::splat(*x)),
                _ => None,
            }
        })
    };
    let kd = m.diffuse.map(Vec3::from).unwrap_or(Vec3::splat(0.8));
    let ks = m.specular.map(Vec3::from);
    let illum = m.illumination_model;
    let metallic = illum == Some(3) || scalar("Pm").is_some_and(|pm| pm >= 0.5);
    let ior = m.optical_density.unwrap_or(1.0);
    let glass = illum == Some(7) || (m.dissolve.is_some_and(|d| d < 1.0) && ior > 1.0);
    let mut mat = Material::diffuse(kd);
    if glass {
        mat.kind = MaterialKind::DIELECTRIC;
        mat.albedo = Vec3::ONE;
        mat.ior = if ior > 0.0 { ior } else { 1.5 };
    } else if metallic {
        mat.albedo = ks.unwrap_or(kd);
        match scalar("Pr") {
            Some(r) if r > 0.0 => {
                mat.kind = MaterialKind::ROUGH_CONDUCTOR;
                mat.roughness = r.min(1.0);
            }
            _ => mat.kind = MaterialKind::CONDUCTOR,
        }
    }
    mat.emission = m
        .emissive
        .map(Vec3::from)
        .or_else(|| color("Ke"))
        .unwrap_or(Vec3::ZERO)
        .max(Vec3::ZERO);
    mat
}

fn describe_tobj_error(e: &tobj::LoadError) -> String {
    use tobj::LoadError::*;
    match e {
        OpenFileFailed => "cannot open file".into(),
        ReadError => "read error".into(),
        UnrecognizedCharacter => "unrecognized character".into(),
        PositionParseError => "malformed vertex position (`v`)".into(),
        NormalParseError => "malformed normal (`vn`)".into(),
        TexcoordParseError => "malformed texture coordinate (`vt`)".into(),
        FaceParseError => "malformed face (`f`)".into(),
        MaterialParseError => "malformed material library".into(),
        InvalidObjectName => "invalid object name".into(),
        InvalidPolygon => "invalid polygon (fewer than 3 vertices)".into(),
        FaceVertexOutOfBounds => "a face refers to a vertex that does not exist".into(),
        FaceTexCoordOutOfBounds => {
            "a face refers to a texture coordinate that does not exist".into()
        }
        FaceNormalOutOfBounds => "a face refers to a normal that does not exist".into(),
        FaceColorOutOfBounds => "a face refers to a vertex colour that does not exist".into(),
        other => format!("{other}"),
    }
}
