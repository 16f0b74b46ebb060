//! Wavefront MTL material libraries: the statements meshtrace's material mapping reads
//! ([`super::obj::map_mtl`]), each checked, with the line of the first malformed one.
//!
//! The values are those tobj (the crate meshtrace used before) read, so that materials stay
//! the same: `Kd`, `Ks` and `Ke` take their first three numbers (`Ke` also a single grey
//! value), `Ni`, `d` and `illum` their first, and `Pm` and `Pr` exactly one. Where tobj
//! failed or panicked on a line (`Kd 0.5`, a word that is not a number, a `newmtl` without
//! a name) the library is an error naming that line. The texture maps `map_Kd`, `map_Ke`,
//! `map_Pr`, `map_Pm` and the normal maps `map_Bump`, `bump` and `norm` are read with their
//! option flags (`-s` sets the UV scale; the others, `-bm` among them, are ignored with a
//! warning), as is `map_d` (ignored, with a warning). Every other statement
//! (`Ka`, `Ns`, `Tr`, unknown keywords) is ignored: nothing reads it.

use super::lines::{BadLine, quoted, text_lines};
use glam::Vec3;

/// One `newmtl` block of a library, as far as the mapping reads it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MtlMaterial {
    /// The `newmtl` name: the rest of its line, trimmed (it may hold spaces).
    pub name: String,
    /// `Kd`.
    pub diffuse: Option<Vec3>,
    /// `Ks`.
    pub specular: Option<Vec3>,
    /// `Ke`; a single number is a grey.
    pub emission: Option<Vec3>,
    /// `Ni`, the index of refraction.
    pub optical_density: Option<f32>,
    /// `d`, the opacity.
    pub dissolve: Option<f32>,
    /// `illum`.
    pub illumination_model: Option<u8>,
    /// `Pm` (PBR extension: metallic).
    pub metallic: Option<f32>,
    /// `Pr` (PBR extension: roughness).
    pub roughness: Option<f32>,
    /// `map_Kd`, `map_Ke`, `map_Pr`, `map_Pm`.
    pub map_diffuse: Option<MtlMap>,
    pub map_emission: Option<MtlMap>,
    pub map_roughness: Option<MtlMap>,
    pub map_metallic: Option<MtlMap>,
    /// `map_Bump`, `bump` or `norm`: a tangent-space normal map.
    pub map_normal: Option<MtlMap>,
}

/// A texture map statement: its image (relative to the library) and UV scale.
#[derive(Clone, Debug, PartialEq)]
pub struct MtlMap {
    pub file: String,
    /// From `-s su sv`; (1, 1) without it.
    pub scale: [f32; 2],
    /// `-clamp on`: the edge texels extend outwards instead of the image repeating.
    pub clamp: bool,
}

/// The option flags of MTL texture maps and how many values each takes (`-o`, `-s`, `-t`
/// take one to three numbers).
const MAP_OPTIONS: [(&str, usize); 13] = [
    ("-blendu", 1),
    ("-blendv", 1),
    ("-boost", 1),
    ("-mm", 2),
    ("-o", 3),
    ("-s", 3),
    ("-t", 3),
    ("-texres", 1),
    ("-clamp", 1),
    ("-bm", 1),
    ("-imfchan", 1),
    ("-type", 1),
    ("-cc", 1),
];

/// What was read from a library: its materials, and warnings with their lines.
pub(super) type Library = (Vec<MtlMaterial>, Vec<(usize, String)>);

/// Reads an MTL library: its materials in file order (a name defined twice is listed
/// twice; whoever looks names up takes the last), and warnings about what it ignores.
/// Statements before the first `newmtl` are checked and belong to no material. Lines are
/// split at `\n` like an OBJ's.
pub(super) fn parse_mtl(bytes: &[u8]) -> Result<Library, BadLine> {
    let (text, not_utf8) = text_lines(bytes);
    let mut materials = Vec::new();
    let mut warnings = Vec::new();
    let mut current: Option<MtlMaterial> = None;
    for (i, raw) in text.split('\n').enumerate() {
        let bad = |message: String| BadLine {
            line: i + 1,
            message,
        };
        let line = raw.trim();
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        // Statements before the first `newmtl` are checked, then dropped (as in tobj).
        let mut orphan = MtlMaterial::default();
        let m = current.as_mut().unwrap_or(&mut orphan);
        match keyword {
            "newmtl" => {
                let name = line["newmtl".len()..].trim();
                if name.is_empty() {
                    return Err(bad("`newmtl` names no material".into()));
                }
                materials.extend(current.take());
                current = Some(MtlMaterial {
                    name: name.to_string(),
                    ..MtlMaterial::default()
                });
            }
            "Kd" | "Ks" | "Ke" => {
                let c = color(keyword, words, keyword == "Ke").map_err(bad)?;
                if c.min_element() < 0.0 {
                    warnings.push((
                        i + 1,
                        format!("`{keyword}` {c} has negative values; they are read as 0"),
                    ));
                }
                let c = Some(c.max(Vec3::ZERO));
                match keyword {
                    "Kd" => m.diffuse = c,
                    "Ks" => m.specular = c,
                    _ => m.emission = c,
                }
            }
            "Ni" => m.optical_density = Some(first_number(keyword, words).map_err(bad)?),
            "d" => m.dissolve = Some(first_number(keyword, words).map_err(bad)?),
            "Pm" => m.metallic = Some(only_number(keyword, words).map_err(bad)?),
            "Pr" => m.roughness = Some(only_number(keyword, words).map_err(bad)?),
            "map_Kd" | "map_Ke" | "map_Pr" | "map_Pm" | "map_Bump" | "map_bump" | "bump"
            | "norm" => {
                let rest = line[keyword.len()..].trim();
                let map =
                    texture_map(keyword, rest, &mut |w| warnings.push((i + 1, w))).map_err(bad)?;
                match keyword {
                    "map_Kd" => m.map_diffuse = Some(map),
                    "map_Ke" => m.map_emission = Some(map),
                    "map_Pr" => m.map_roughness = Some(map),
                    "map_Pm" => m.map_metallic = Some(map),
                    _ => m.map_normal = Some(map),
                }
            }
            "map_d" => warnings.push((
                i + 1,
                "`map_d` (an opacity map) is ignored: the surface is opaque".into(),
            )),
            "illum" => {
                let Some(word) = words.next() else {
                    return Err(bad(
                        "malformed `illum`: expected an illumination model number".into(),
                    ));
                };
                let model = word.parse::<u8>().map_err(|_| {
                    bad(format!(
                        "malformed `illum`: {} is not an illumination model number (0 to 255)",
                        quoted(word)
                    ))
                })?;
                m.illumination_model = Some(model);
            }
            _ => {}
        }
    }
    if let Some(bad) = not_utf8 {
        return Err(bad);
    }
    materials.extend(current);
    Ok((materials, warnings))
}

/// A texture map statement's options and file name (the rest of the line, which may hold
/// spaces). `-s` sets the scale; other options are ignored with a warning.
fn texture_map(keyword: &str, rest: &str, warn: &mut dyn FnMut(String)) -> Result<MtlMap, String> {
    let mut scale = [1.0f32, 1.0];
    let mut clamp = false;
    let mut rest = rest;
    while rest.starts_with('-') {
        let (flag, after) = rest.split_once(char::is_whitespace).unwrap_or((rest, ""));
        let Some(&(_, arity)) = MAP_OPTIONS.iter().find(|(f, _)| *f == flag) else {
            return Err(format!(
                "malformed `{keyword}`: unknown option {}",
                quoted(flag)
            ));
        };
        let mut after = after.trim_start();
        let mut values = Vec::new();
        let numeric = matches!(
            flag,
            "-o" | "-s" | "-t" | "-mm" | "-boost" | "-bm" | "-texres"
        );
        while values.len() < arity {
            let (word, tail) = after.split_once(char::is_whitespace).unwrap_or((after, ""));
            // `-o`, `-s` and `-t` take one to three numbers; the file name follows.
            if word.is_empty() || (numeric && word.parse::<f32>().is_err()) {
                break;
            }
            values.push(word);
            after = tail.trim_start();
        }
        let needed = if matches!(flag, "-o" | "-s" | "-t") {
            1
        } else {
            arity
        };
        if values.len() < needed {
            return Err(format!(
                "malformed `{keyword}`: option {flag} needs {needed} value{}",
                if needed == 1 { "" } else { "s" }
            ));
        }
        if flag == "-s" {
            let su: f32 = values[0].parse().unwrap_or(1.0);
            let sv: f32 = values.get(1).map_or(Ok(1.0), |v| v.parse()).unwrap_or(1.0);
            if !(su.is_finite() && sv.is_finite() && su != 0.0 && sv != 0.0) {
                return Err(format!(
                    "malformed `{keyword}`: -s needs finite non-zero scales, got {su} {sv}"
                ));
            }
            scale = [su, sv];
        } else if flag == "-clamp" {
            clamp = match values[0] {
                "on" => true,
                "off" => false,
                other => {
                    return Err(format!(
                        "malformed `{keyword}`: -clamp takes on or off, got {}",
                        quoted(other)
                    ));
                }
            };
        } else {
            warn(format!("option {flag} of `{keyword}` is ignored"));
        }
        rest = after;
    }
    if rest.is_empty() {
        return Err(format!("malformed `{keyword}`: names no image file"));
    }
    Ok(MtlMap {
        file: rest.to_string(),
        scale,
        clamp,
    })
}

/// A colour statement's first three numbers (further words are ignored, as tobj did); with
/// `grey`, a single number stands for all three.
fn color(keyword: &str, words: std::str::SplitWhitespace, grey: bool) -> Result<Vec3, String> {
    let mut values = [0f32; 3];
    let mut count = 0;
    for word in words.take(3) {
        values[count] = number(keyword, word)?;
        count += 1;
    }
    match count {
        3 => Ok(Vec3::from(values)),
        1 if grey => Ok(Vec3::splat(values[0])),
        _ => Err(format!(
            "malformed `{keyword}`: expected r g b{}, found {count} number{}",
            if grey { " or a single grey value" } else { "" },
            if count == 1 { "" } else { "s" }
        )),
    }
}

/// A scalar statement's first number (further words are ignored, as tobj did).
fn first_number(keyword: &str, mut words: std::str::SplitWhitespace) -> Result<f32, String> {
    let word = words
        .next()
        .ok_or_else(|| format!("malformed `{keyword}`: expected a number"))?;
    number(keyword, word)
}

/// A scalar statement that must hold exactly one number: for `Pm` and `Pr`, which tobj
/// kept as text and the mapping read whole, so that `Pm 1 0` meant no `Pm` at all.
fn only_number(keyword: &str, words: std::str::SplitWhitespace) -> Result<f32, String> {
    let words: Vec<&str> = words.collect();
    match words[..] {
        [word] => number(keyword, word),
        _ => Err(format!(
            "malformed `{keyword}`: expected one number, found {} words",
            words.len()
        )),
    }
}

/// A word read as `str::parse::<f32>` reads it.
fn number(keyword: &str, word: &str) -> Result<f32, String> {
    word.parse()
        .map_err(|_| format!("malformed `{keyword}`: {} is not a number", quoted(word)))
}
