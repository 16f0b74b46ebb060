//! The film: per-pixel sums of radiance samples, and the image files made from them.
//!
//! The output format follows the file's extension: `.exr` (linear float RGB) and `.hdr`
//! (Radiance RGBE) keep the radiance; `.png`, `.jpg`/`.jpeg` and `.bmp` are sRGB-encoded
//! and clamped. Files are written to a temporary sibling and renamed, so a failed or
//! interrupted write never leaves a half-written image under the requested name.

use glam::Vec3;
use std::path::{Path, PathBuf};

/// Accumulated radiance: `sum[y * width + x]` is the sum of that pixel's `samples` samples.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub sum: Vec<Vec3>,
    /// Samples per pixel in `sum`.
    pub samples: u32,
}

/// The image formats meshtrace writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Exr,
    Hdr,
    Png,
    Jpeg,
    Bmp,
}

impl Format {
    /// The format named by a path's extension.
    pub fn from_path(path: &Path) -> Result<Self, FilmError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        Ok(match ext.as_str() {
            "exr" => Self::Exr,
            "hdr" => Self::Hdr,
            "png" => Self::Png,
            "jpg" | "jpeg" => Self::Jpeg,
            "bmp" => Self::Bmp,
            _ => {
                return Err(FilmError::UnknownFormat {
                    path: path.display().to_string(),
                });
            }
        })
    }
}

/// Why an image could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum FilmError {
    #[error("{path}: unknown image format; use .exr, .hdr, .png, .jpg or .bmp")]
    UnknownFormat { path: String },
    #[error("{path}: {message}")]
    Io { path: String, message: String },
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            sum: vec![Vec3::ZERO; width as usize * height as usize],
            samples: 0,
        }
    }

    /// The per-pixel mean radiance.
    pub fn mean(&self) -> Vec<Vec3> {
        let inv = if self.samples == 0 {
            0.0
        } else {
            1.0 / self.samples as f32
        };
        self.sum.iter().map(|&s| s * inv).collect()
    }

    /// Adds another film of the same size rendered over a disjoint sample range.
    pub fn merge(&mut self, other: &Film) {
        assert_eq!((self.width, self.height), (other.width, other.height));
        for (a, b) in self.sum.iter_mut().zip(&other.sum) {
            *a += *b;
        }
        self.samples += other.samples;
    }

    /// Checks, before any rendering, that `path` names a known format in a folder where a
    /// file can be created, by creating and removing the temporary file `save` would use.
    pub fn check_writable(path: &Path) -> Result<(), FilmError> {
        Format::from_path(path)?;
        let tmp = temp_sibling(path);
        std::fs::File::create(&tmp).map_err(|e| FilmError::Io {
            path: path.display().to_string(),
            message: format!("cannot write here: {e}"),
        })?;
        let _ = std::fs::remove_file(&tmp);
        Ok(())
    }

    /// Writes the mean radiance in the format the extension names.
    pub fn save(&self, path: &Path) -> Result<(), FilmError> {
        let format = Format::from_path(path)?;
        let io = |message: String| FilmError::Io {
            path: path.display().to_string(),
            message,
        };
        let tmp = temp_sibling(path);
        let result = self
            .encode(&tmp, format)
            .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
        if let Err(message) = result {
            let _ = std::fs::remove_file(&tmp);
            return Err(io(message));
        }
        Ok(())
    }

    fn encode(&self, tmp: &Path, format: Format) -> Result<(), String> {
        let (w, h) = (self.width, self.height);
        let mean = self.mean();
        let image_format = match format {
            Format::Exr => image::ImageFormat::OpenExr,
            Format::Hdr => image::ImageFormat::Hdr,
            Format::Png => image::ImageFormat::Png,
            Format::Jpeg => image::ImageFormat::Jpeg,
            Format::Bmp => image::ImageFormat::Bmp,
        };
        let file = std::fs::File::create(tmp).map_err(|e| e.to_string())?;
        let mut out = std::io::BufWriter::new(file);
        let result = match format {
            Format::Exr | Format::Hdr => {
                let data: Vec<f32> = mean.iter().flat_map(|c| c.to_array()).collect();
                let img = image::Rgb32FImage::from_raw(w, h, data).ok_or("film size mismatch")?;
                image::DynamicImage::ImageRgb32F(img).write_to(&mut out, image_format)
            }
            Format::Png | Format::Jpeg | Format::Bmp => {
                let data: Vec<u8> = mean
                    .iter()
                    .flat_map(|c| c.to_array().map(linear_to_srgb8))
                    .collect();
                let img = image::RgbImage::from_raw(w, h, data).ok_or("film size mismatch")?;
                image::DynamicImage::ImageRgb8(img).write_to(&mut out, image_format)
            }
        };
        result.map_err(|e| e.to_string())?;
        use std::io::Write;
        out.flush().map_err(|e| e.to_string())?;
        out.into_inner()
            .map_err(|e| e.to_string())?
            .sync_all()
            .map_err(|e| e.to_string())
    }
}

/// Reads an image's linear RGB radiance (EXR and HDR as stored; 8-bit formats decoded from sRGB).
pub fn read_linear(path: &Path) -> Result<(u32, u32, Vec<Vec3>), FilmError> {
    let io = |message: String| FilmError::Io {
        path: path.display().to_string(),
        message,
    };
    let format = Format::from_path(path)?;
    let img = image::open(path).map_err(|e| io(e.to_string()))?;
    let (w, h) = (img.width(), img.height());
    let pixels = match format {
        Format::Exr | Format::Hdr => img
            .into_rgb32f()
            .pixels()
            .map(|p| Vec3::from(p.0))
            .collect(),
        _ => img
            .into_rgb8()
            .pixels()
            .map(|p| Vec3::from(p.0.map(srgb8_to_linear)))
            .collect(),
    };
    Ok((w, h, pixels))
}

fn temp_sibling(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// The sRGB transfer function, clamped and rounded to 8 bits.
pub fn linear_to_srgb8(x: f32) -> u8 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let s = if x <= 0.0031308 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// Inverse of the sRGB transfer function.
pub fn srgb8_to_linear(v: u8) -> f32 {
    let s = v as f32 / 255.0;
    if s <= 0.04045 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}
