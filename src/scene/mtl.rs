//! Wavefront MTL material libraries: the statements meshtrace's material mapping reads
//! ([`super::obj::map_mtl`]), each checked, with the line of the first malformed one.
//!
//! The values are those tobj (the crate meshtrace used before) read, so that materials stay
//! the same: `Kd`, `Ks` and `Ke` take their first three numbers (`Ke` also a single grey
//! value), `Ni`, `d` and `illum` their first, and `Pm` and `Pr` exactly one. Where tobj
//! failed or panicked on a line (`Kd 0.5`, a word that is not a number, a `newmtl` without
//! a name) the library is an error naming that line. Every other statement (`Ka`, `Ns`,
//! `Tr`, texture maps, unknown keywords) is ignored: nothing reads it.

use super::obj::{BadLine, quoted, text_lines};
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
}

/// Reads an MTL library: its materials in file order (a name defined twice is listed
/// twice; whoever looks names up takes the last). Statements before the first `newmtl` are
/// checked and belong to no material. Lines are split at `\n` like an OBJ's.
pub(super) fn parse_mtl(bytes: &[u8]) -> Result<Vec<MtlMaterial>, BadLine> {
    let (text, not_utf8) = text_lines(bytes);
    let mut materials = Vec::new();
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
            "Kd" => m.diffuse = Some(color(keyword, words, false).map_err(bad)?),
            "Ks" => m.specular = Some(color(keyword, words, false).map_err(bad)?),
            "Ke" => m.emission = Some(color(keyword, words, true).map_err(bad)?),
            "Ni" => m.optical_density = Some(first_number(keyword, words).map_err(bad)?),
            "d" => m.dissolve = Some(first_number(keyword, words).map_err(bad)?),
            "Pm" => m.metallic = Some(only_number(keyword, words).map_err(bad)?),
            "Pr" => m.roughness = Some(only_number(keyword, words).map_err(bad)?),
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
    Ok(materials)
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
