//! Part files: the film of one sample range of a render (`render --part K/N`), as an EXR
//! that shows the mean of its samples and also carries the film's exact fixed-point sums
//! (hidden channels `meshtrace.<channel>.<component>.lo`/`.hi`, 32-bit unsigned words)
//! and, in its header, what `merge` checks: the sample range, the total spp, the seed, the
//! device and a digest of the scene and settings.

use super::{Accumulation, Aov, Film, FilmError};
use exr::meta::attribute::{AttributeValue, Text};
use exr::prelude::{AnyChannel, FlatSamples};
use std::collections::HashMap;
use std::path::Path;

/// What a part file's header says about the render it belongs to.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartHeader {
    /// The part, `index` of `count` (K/N, K from 0).
    pub index: u32,
    pub count: u32,
    /// The samples the part was asked for: `start..end`. The film it carries holds
    /// `start..start + samples`, fewer when the render was interrupted.
    pub start: u32,
    pub end: u32,
    /// The whole render's samples per pixel and seed.
    pub spp: u32,
    pub seed: u32,
    /// The device that rendered it (the bits of a sum depend on it).
    pub device: String,
    /// SHA-256 of the scene as rendered (every table, the camera, the sky) and of the
    /// settings, in hex: parts of one render share it.
    pub digest: String,
}

impl PartHeader {
    /// The samples per pixel `start..end` of part `index` of `count` of a render of `spp`:
    /// consecutive ranges that differ in length by at most one and together cover `0..spp`.
    pub fn range(index: u32, count: u32, spp: u32) -> std::ops::Range<u32> {
        let at = |k: u32| (k as u64 * spp as u64 / count as u64) as u32;
        at(index)..at(index + 1)
    }
}

/// Header attribute names, all text.
const PART: &str = "meshtrace.part";
const RANGE: &str = "meshtrace.sample_range";
const SPP: &str = "meshtrace.spp";
const SEED: &str = "meshtrace.seed";
const DEVICE: &str = "meshtrace.device";
const DIGEST: &str = "meshtrace.digest";
const HELD: &str = "meshtrace.channels";
const SAVED: &str = "meshtrace.saved_aovs";
const TRANSPARENT: &str = "meshtrace.transparent";

/// The name of the hidden channel holding word `word` ("lo" or "hi") of component `k` of
/// the film channel `channel` (`radiance` for the radiance sums).
fn sum_channel(channel: &str, k: usize, word: &str) -> String {
    format!("meshtrace.{channel}.{k}.{word}")
}

/// The components of a film channel's texel that a part stores: those used, and `w` where
/// the accumulation rule needs it.
fn stored_components(components: usize, accumulation: Accumulation) -> Vec<usize> {
    let mut out: Vec<usize> = (0..components).collect();
    if accumulation != Accumulation::AllSamples {
        out.push(3);
    }
    out
}

/// The film's exact sums as pairs of 32-bit channels, and the header's attributes.
pub(super) fn part_channels(
    film: &Film,
    header: &PartHeader,
) -> (Vec<AnyChannel<FlatSamples>>, Vec<(Text, AttributeValue)>) {
    let mut channels = Vec::new();
    let mut push = |name: &str, k: usize, values: Vec<i64>| {
        let lo = values.iter().map(|&v| v as u32).collect();
        let hi = values.iter().map(|&v| (v >> 32) as u32).collect();
        channels.push(AnyChannel::new(
            sum_channel(name, k, "lo").as_str(),
            FlatSamples::U32(lo),
        ));
        channels.push(AnyChannel::new(
            sum_channel(name, k, "hi").as_str(),
            FlatSamples::U32(hi),
        ));
    };
    for k in 0..3 {
        push("radiance", k, film.sum.iter().map(|s| s[k]).collect());
    }
    for c in &film.channels {
        for k in stored_components(c.components, c.accumulation) {
            push(&c.name, k, c.data.iter().map(|t| t[k]).collect());
        }
    }
    let held: Vec<&str> = film.aovs().into_iter().map(Aov::name).collect();
    let saved: Vec<&str> = film
        .aovs()
        .into_iter()
        .filter(|a| film.saved_aovs & a.bit() != 0)
        .map(Aov::name)
        .collect();
    let text = |name: &str, value: String| {
        (
            Text::from(name),
            AttributeValue::Text(Text::from(value.as_str())),
        )
    };
    let attributes = vec![
        text(PART, format!("{}/{}", header.index, header.count)),
        text(RANGE, format!("{}..{}", header.start, header.end)),
        text(SPP, header.spp.to_string()),
        text(SEED, header.seed.to_string()),
        text(DEVICE, header.device.clone()),
        text(DIGEST, header.digest.clone()),
        text(HELD, held.join(",")),
        text(SAVED, saved.join(",")),
        text(TRANSPARENT, film.transparent.to_string()),
    ];
    (channels, attributes)
}

impl Film {
    /// Writes the film as a part file of the render `header` describes: the mean of its
    /// samples as `R`, `G`, `B`, its AOVs, its exact sums and the header.
    pub fn save_part(&self, path: &Path, header: &PartHeader) -> Result<(), FilmError> {
        super::write_atomically(path, |tmp| self.encode_exr(tmp, true, Some(header)))
    }

    /// Reads a part file written by [`Film::save_part`]: the film of its samples, exactly
    /// as rendered, and its header.
    pub fn read_part(path: &Path) -> Result<(Film, PartHeader), FilmError> {
        let bad = |message: String| FilmError::NotAPart {
            path: path.display().to_string(),
            message,
        };
        let image =
            exr::prelude::read_first_flat_layer_from_file(path).map_err(|e| FilmError::Io {
                path: path.display().to_string(),
                message: e.to_string(),
            })?;
        let layer = &image.layer_data;
        let attrs: HashMap<String, String> = layer
            .attributes
            .other
            .iter()
            .filter_map(|(k, v)| match v {
                AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
                _ => None,
            })
            .collect();
        let get = |name: &str| {
            attrs
                .get(name)
                .cloned()
                .ok_or_else(|| bad(format!("no `{name}` header attribute")))
        };
        let number = |name: &str| -> Result<u32, FilmError> {
            let v = get(name)?;
            v.parse()
                .map_err(|_| bad(format!("`{name}` is `{v}`, not a count")))
        };
        let pair = |name: &str, sep: &str| -> Result<(u32, u32), FilmError> {
            let v = get(name)?;
            v.split_once(sep)
                .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
                .ok_or_else(|| bad(format!("`{name}` is `{v}`")))
        };
        let (index, count) = pair(PART, "/")?;
        let (start, end) = pair(RANGE, "..")?;
        let header = PartHeader {
            index,
            count,
            start,
            end,
            spp: number(SPP)?,
            seed: number(SEED)?,
            device: get(DEVICE)?,
            digest: get(DIGEST)?,
        };
        if start > end || end > header.spp || index >= count {
            return Err(bad(format!(
                "part {index}/{count} of samples {start}..{end} of {} spp",
                header.spp
            )));
        }
        let aov_list = |name: &str| -> Result<u32, FilmError> {
            let v = get(name)?;
            if v.is_empty() {
                return Ok(0);
            }
            Aov::parse_list(&v)
                .map(|list| Aov::mask(&list))
                .map_err(|e| bad(format!("`{name}`: {e}")))
        };
        let held = aov_list(HELD)?;
        let transparent = get(TRANSPARENT)? == "true";
        let (w, h) = (layer.size.0, layer.size.1);
        let mut film = Film::with_aovs(w as u32, h as u32, held, transparent);
        film.saved_aovs = aov_list(SAVED)?;
        film.samples = layer
            .attributes
            .other
            .get(&Text::from(super::SAMPLES_ATTRIBUTE))
            .and_then(|v| match v {
                AttributeValue::I32(n) => u32::try_from(*n).ok(),
                _ => None,
            })
            .ok_or_else(|| bad(format!("no `{}` attribute", super::SAMPLES_ATTRIBUTE)))?;
        if film.samples > end - start {
            return Err(bad(format!(
                "holds {} samples of the {}..{} it was asked for",
                film.samples, start, end
            )));
        }
        let words: HashMap<String, &[u32]> = layer
            .channel_data
            .list
            .iter()
            .filter_map(|c| match &c.sample_data {
                FlatSamples::U32(v) => Some((c.name.to_string(), v.as_slice())),
                _ => None,
            })
            .collect();
        let sums = |channel: &str, k: usize| -> Result<Vec<i64>, FilmError> {
            let word = |w: &str| {
                let name = sum_channel(channel, k, w);
                words
                    .get(&name)
                    .copied()
                    .ok_or_else(|| bad(format!("no channel `{name}`")))
            };
            let (lo, hi) = (word("lo")?, word("hi")?);
            Ok(lo
                .iter()
                .zip(hi)
                .map(|(&lo, &hi)| crate::fixed::from_words([lo, hi]))
                .collect())
        };
        for k in 0..3 {
            for (s, v) in film.sum.iter_mut().zip(sums("radiance", k)?) {
                s[k] = v;
            }
        }
        for c in &mut film.channels {
            for k in stored_components(c.components, c.accumulation) {
                for (t, v) in c.data.iter_mut().zip(sums(&c.name, k)?) {
                    t[k] = v;
                }
            }
        }
        Ok((film, header))
    }
}
