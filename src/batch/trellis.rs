//! TRELLIS's optional passes (`blender_script/render.py --save_depth --save_normal
//! --save_albedo --save_mist`): Cycles' render passes of each view, which the script's
//! compositor File Output nodes write beside the image as `{view:03}_{pass}.{ext}`:
//! - `depth`: the Depth pass mapped from [r − √3/2, r + √3/2] (r the camera's distance from
//!   the centre) to [0, 1], a 16-bit grey PNG; `transforms.json` gives the range per frame;
//! - `normal`: the Normal pass, RGB half floats in an EXR, unencoded;
//! - `albedo`: the Diffuse Color pass with the render's alpha, an 8-bit RGBA PNG formed by
//!   the view transform;
//! - `mist`: the Mist pass (start 0, depth 10, Blender's quadratic falloff), a 16-bit grey
//!   PNG.
//!
//! Blender's `Map Range` and File Output nodes leave the depth and mist values linear: their
//! PNGs are the same bits under every view transform.

use crate::film::{
    Aov, AovValues, DisplayTransform, Film, FilmError, Quantum, exr_bytes, quantise8, write_bytes,
};
use crate::fixed::from_fixed;
use crate::render::camera::{CameraRays, pixel_centre_ray};
use crate::scene::camera::Camera;
use std::path::{Path, PathBuf};

/// Which of TRELLIS's optional passes a preset writes (its script's `--save_*` flags; all
/// off, as `dataset_toolkits/render.py` runs the script).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Passes {
    pub depth: bool,
    pub normal: bool,
    pub albedo: bool,
    pub mist: bool,
}

/// The mist pass's range, as the script sets the world's mist: from 0 to 10 m.
const MIST_DEPTH: f64 = 10.0;

impl Passes {
    /// The pass of manifest key `key`, to set.
    pub fn flag(&mut self, key: &str) -> Option<&mut bool> {
        match key {
            "save_depth" => Some(&mut self.depth),
            "save_normal" => Some(&mut self.normal),
            "save_albedo" => Some(&mut self.albedo),
            "save_mist" => Some(&mut self.mist),
            _ => None,
        }
    }

    /// Whether any pass is on.
    pub fn any(self) -> bool {
        self.depth || self.normal || self.albedo || self.mist
    }

    /// The AOVs the passes are made of.
    pub fn aovs(self) -> Vec<Aov> {
        let mut aovs = Vec::new();
        if self.depth || self.mist {
            aovs.extend([Aov::Depth, Aov::Alpha]);
        }
        if self.normal {
            aovs.push(Aov::Normal);
        }
        if self.albedo {
            aovs.extend([Aov::DiffuseColor, Aov::Alpha]);
        }
        aovs.sort();
        aovs.dedup();
        aovs
    }

    /// The files of the passes beside the image at `image`: its stem with `_{pass}` and the
    /// pass's extension (`renders/uid/007.png` → `renders/uid/007_depth.png`).
    pub fn paths(self, image: &Path) -> Vec<PathBuf> {
        [
            (self.depth, "depth", "png"),
            (self.normal, "normal", "exr"),
            (self.albedo, "albedo", "png"),
            (self.mist, "mist", "png"),
        ]
        .into_iter()
        .filter(|(on, ..)| *on)
        .map(|(_, name, ext)| pass_path(image, name, ext))
        .collect()
    }

    /// Writes the passes of the view at `image`, rendered into `film` through `camera` at
    /// `distance` from the object's centre in the normalised frame, which is the file's
    /// scaled by `scale` (the film's depths are the file's); the albedo formed by `view`.
    pub fn write(
        self,
        image: &Path,
        film: &Film,
        camera: &Camera,
        [distance, scale]: [f64; 2],
        view: &DisplayTransform,
    ) -> Result<(), FilmError> {
        let (w, h) = (film.width, film.height);
        let fail = |path: &Path| {
            let path = path.display().to_string();
            move |message: String| FilmError::Io { path, message }
        };
        if self.depth {
            let path = pass_path(image, "depth", "png");
            let pass = depth_pass(film, scale, depth_range(distance)).map_err(fail(&path))?;
            write_png(
                &path,
                image::DynamicImage::ImageLuma16(gray16(&path, w, h, pass)?),
            )?;
        }
        if self.normal {
            let path = pass_path(image, "normal", "exr");
            write_normal_exr(&path, w, h, normal_pass(film).map_err(fail(&path))?)?;
        }
        if self.albedo {
            let path = pass_path(image, "albedo", "png");
            let rgba = albedo_pass(film, view).map_err(fail(&path))?;
            let img = image::RgbaImage::from_raw(w, h, rgba)
                .ok_or_else(|| fail(&path)("image size mismatch".into()))?;
            write_png(&path, image::DynamicImage::ImageRgba8(img))?;
        }
        if self.mist {
            let path = pass_path(image, "mist", "png");
            let pass = mist_pass(film, camera, scale).map_err(fail(&path))?;
            write_png(
                &path,
                image::DynamicImage::ImageLuma16(gray16(&path, w, h, pass)?),
            )?;
        }
        Ok(())
    }
}

/// `image`'s stem with `_{name}` and extension `ext`, beside it.
fn pass_path(image: &Path, name: &str, ext: &str) -> PathBuf {
    let stem = image
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    image.with_file_name(format!("{stem}_{name}.{ext}"))
}

/// The depth range the script maps to [0, 1] for a camera `distance` from the centre:
/// `radius ∓ 0.5 * np.sqrt(3)`, the unit box's half diagonal, as `transforms.json` records it.
pub fn depth_range(distance: f64) -> [f64; 2] {
    let half = 0.5 * 3f64.sqrt();
    [distance - half, distance + half]
}

/// The values of a one-component float AOV of `film`.
fn scalar(film: &Film, aov: Aov) -> Result<Vec<f32>, String> {
    match film.aov_values(aov) {
        Some(mut v) if v.len() == 1 => match v.remove(0) {
            AovValues::F32(v) => Ok(v),
            AovValues::U32(_) => Err(format!("the {} AOV is not a float", aov.name())),
        },
        _ => Err(format!("the render has no {} AOV", aov.name())),
    }
}

/// The depth PNG's values of `film` (rendered with the depth and alpha AOVs): Cycles' Depth
/// pass, the distance along the camera's axis (the film's times `scale`), through the
/// script's `Map Range` from `range` to [0, 1]. Cycles takes a pixel's depth from its first sample alone, which hits
/// the object with the probability of the pixel's coverage; here a pixel takes its depth
/// where the object covers at least half of it (the mean over the samples that hit), and
/// is the background's, which maps past 1, elsewhere.
pub fn depth_pass(film: &Film, scale: f64, range: [f64; 2]) -> Result<Vec<f32>, String> {
    let depth = scalar(film, Aov::Depth)?;
    let alpha = scalar(film, Aov::Alpha)?;
    let [lo, hi] = range;
    Ok(depth
        .iter()
        .zip(&alpha)
        .map(|(&z, &a)| {
            if a >= 0.5 {
                ((z as f64 * scale - lo) / (hi - lo)) as f32
            } else {
                1.0
            }
        })
        .collect())
}

/// The mist PNG's values of `film` (rendered through `camera` with the depth and alpha
/// AOVs): Cycles' Mist pass with the script's start 0 and depth 10 and the world's default
/// quadratic falloff, 1 − Σ (1 − (d / 10)²) over the samples that hit / all samples, d the
/// hit's distance from the camera. Here d is the mean depth along the axis, scaled to the
/// distance along the pixel's centre ray, times `scale` (the film's depths are the file's).
pub fn mist_pass(film: &Film, camera: &Camera, scale: f64) -> Result<Vec<f32>, String> {
    let depth = scalar(film, Aov::Depth)?;
    let alpha = scalar(film, Aov::Alpha)?;
    let rays = CameraRays::new(camera, film.width, film.height);
    let width = film.width.max(1) as usize;
    Ok(depth
        .iter()
        .zip(&alpha)
        .enumerate()
        .map(|(i, (&z, &a))| {
            if a == 0.0 {
                return 1.0;
            }
            let ray = pixel_centre_ray(&rays, (i % width) as u32, (i / width) as u32);
            let d = z as f64 * scale / ray.dir.dot(rays.forward) as f64;
            let mist = (d / MIST_DEPTH).clamp(0.0, 1.0).powi(2);
            (1.0 - a as f64 * (1.0 - mist)).clamp(0.0, 1.0) as f32
        })
        .collect())
}

/// The albedo PNG's pixels of `film` (rendered with the diffuse colour and alpha AOVs),
/// 8-bit RGBA: Cycles' Diffuse Color pass (the mean over all samples, a miss counting 0)
/// through the script's `Set Alpha` node, whose default mode multiplies the pass by the
/// render's alpha once more: the PNG's colour is the pass itself formed by `view`, darker
/// than the surface's where the object covers a pixel in part, as in the script's files.
pub fn albedo_pass(film: &Film, view: &DisplayTransform) -> Result<Vec<u8>, String> {
    let alpha = scalar(film, Aov::Alpha)?;
    let colour = match film.aov_values(Aov::DiffuseColor).as_deref() {
        Some([AovValues::F32(r), AovValues::F32(g), AovValues::F32(b)]) => {
            (r.clone(), g.clone(), b.clone())
        }
        _ => return Err("the render has no diffuse_color AOV".into()),
    };
    Ok(alpha
        .iter()
        .enumerate()
        .flat_map(|(i, &a)| {
            if a == 0.0 {
                return [0; 4];
            }
            let c = glam::Vec3::new(colour.0[i], colour.1[i], colour.2[i]);
            let [r, g, b] = view.encode(c).map(quantise8);
            [r, g, b, quantise8(a)]
        })
        .collect())
}

/// `values` as a `width` × `height` 16-bit grey image, each clamped to [0, 1] and rounded
/// as Blender's PNG writer rounds floats.
fn gray16(
    path: &Path,
    width: u32,
    height: u32,
    values: Vec<f32>,
) -> Result<image::ImageBuffer<image::Luma<u16>, Vec<u16>>, FilmError> {
    let levels = values.into_iter().map(u16::quantise).collect();
    image::ImageBuffer::from_raw(width, height, levels).ok_or_else(|| FilmError::Io {
        path: path.display().to_string(),
        message: "image size mismatch".into(),
    })
}

/// Writes `img` to `path` as a PNG, complete or not at all.
fn write_png(path: &Path, img: image::DynamicImage) -> Result<(), FilmError> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png)
        .map_err(|e| FilmError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
    write_bytes(path, &bytes.into_inner())
}

/// Cycles' normal pass of `film` (rendered with the [`Aov::Normal`] AOV), in Blender's
/// frame, by channel: per pixel the sum of its samples' first-hit shading normals (turned
/// to face the ray, as Cycles turns a back face's) over all its samples, not normalised.
/// A pixel that the object covers in part holds that part of a normal, and one it misses
/// holds 0, as in Cycles' pass. The file's +Y-up (x, y, z) is Blender's (x, −z, y), and
/// the preset's normalisation, a scale and a shift, leaves directions alone.
fn normal_pass(film: &Film) -> Result<[Vec<f32>; 3], String> {
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
fn write_normal_exr(
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
    fn the_passes_go_beside_the_image() {
        let all = Passes {
            depth: true,
            normal: true,
            albedo: true,
            mist: true,
        };
        assert_eq!(
            all.paths(Path::new("renders/abc/007.png")),
            ["depth.png", "normal.exr", "albedo.png", "mist.png"]
                .map(|p| PathBuf::from(format!("renders/abc/007_{p}")))
        );
    }

    #[test]
    fn the_depth_range_is_the_scripts() {
        // `view['radius'] ∓ 0.5 * np.sqrt(3)` for radius 2, as Python prints them.
        assert_eq!(depth_range(2.0), [1.1339745962155614, 2.8660254037844384]);
    }
}
