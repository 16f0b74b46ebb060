//! TRELLIS's optional normal pass (`blender_script/render.py --save_normal`): Cycles'
//! `Normal` render pass of each view, which a compositor File Output node writes beside the
//! image as `{view:03}_normal.exr`, RGB half floats, unencoded.

use crate::film::{Aov, Film, FilmError, exr_bytes, write_bytes};
use crate::fixed::from_fixed;
use std::path::{Path, PathBuf};

/// Where the normal pass of the image at `image` goes: beside it, its stem with `_normal`
/// and `.exr` (`renders/uid/007.png` → `renders/uid/007_normal.exr`).
pub fn normal_path(image: &Path) -> PathBuf {
    let stem = image
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    image.with_file_name(format!("{stem}_normal.exr"))
}

/// Cycles' normal pass of `film` (rendered with the [`Aov::Normal`] AOV), in Blender's
/// frame, by channel: per pixel the sum of its samples' first-hit shading normals (turned
/// to face the ray, as Cycles turns a back face's) over all its samples, not normalised.
/// A pixel that the object covers in part holds that part of a normal, and one it misses
/// holds 0, as in Cycles' pass. The file's +Y-up (x, y, z) is Blender's (x, −z, y), and
/// the preset's normalisation, a scale and a shift, leaves directions alone.
pub fn normal_pass(film: &Film) -> Result<[Vec<f32>; 3], String> {
    let channel = film
        .channel(Aov::Normal.name())
        .ok_or("the render has no normal AOV")?;
    let samples = film.samples.max(1) as f64;
    let mut out = [(); 3].map(|_| Vec::with_capacity(channel.data.len()));
    for texel in &channel.data {
        let [x, y, z] = [0, 1, 2].map(|k| (from_fixed(texel[k]) / samples) as f32);
        for (c, v) in out.iter_mut().zip([x, -z, y]) {
            // −z is −0.0 where the file's z sums to 0, as in every pixel the object misses:
            // +0 there, as Cycles' pass holds in pixels with no hit.
            c.push(v + 0.0);
        }
    }
    Ok(out)
}

/// Writes `rgb` (channels of `width` × `height`, top row first) to `path` as Blender's File
/// Output node writes an `OPEN_EXR` of `color_depth = '16'` and `color_mode = 'RGB'`: one
/// layer of half-float `R`, `G` and `B`, ZIP-compressed; complete or not at all.
pub fn write_normal_exr(
    path: &Path,
    width: u32,
    height: u32,
    rgb: [Vec<f32>; 3],
) -> Result<(), FilmError> {
    use exr::prelude::{AnyChannel, FlatSamples, LayerAttributes, f16};
    let channels = ["R", "G", "B"]
        .into_iter()
        .zip(rgb)
        .map(|(name, values)| {
            let half = values.into_iter().map(f16::from_f32).collect();
            AnyChannel::new(name, FlatSamples::F16(half))
        })
        .collect();
    let size = (width as usize, height as usize);
    let bytes =
        exr_bytes(size, LayerAttributes::default(), channels).map_err(|message| FilmError::Io {
            path: path.display().to_string(),
            message,
        })?;
    write_bytes(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_normal_pass_goes_beside_the_image() {
        assert_eq!(
            normal_path(Path::new("renders/abc/007.png")),
            Path::new("renders/abc/007_normal.exr")
        );
    }
}
