//! The film: per-pixel sums of radiance samples and of named channels, and the image files
//! made from them.
//!
//! The output format follows the file's extension: `.exr` (linear float RGB) and `.hdr`
//! (Radiance RGBE) keep the radiance; `.png`, `.jpg`/`.jpeg` and `.bmp` are sRGB-encoded
//! and clamped. Files are written to a temporary sibling and renamed, so a failed or
//! interrupted write never leaves a half-written image under the requested name.

use glam::Vec3;
use std::path::{Path, PathBuf};

/// How a channel combines the samples of a pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Accumulation {
    /// The mean over all the pixel's samples: a sample that contributes nothing counts as 0.
    AllSamples,
    /// The mean over the samples that hit a surface; the texel's `w` counts them.
    HitSamples,
    /// The value of the one ray through the pixel centre, traced by the render that holds
    /// sample 0; the texel's `w` is 1 where it was traced.
    PixelCentre,
}

/// One named per-pixel channel beyond radiance. A pixel's entry is one texel, as in the
/// GPU's accumulation buffer: up to three components in `xyz`, and in `w` what the
/// accumulation rule needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    pub name: String,
    /// Components used, 1 to 3.
    pub components: usize,
    pub accumulation: Accumulation,
    pub data: Vec<[f32; 4]>,
}

/// Accumulated samples: per-pixel sums of radiance, plus the named channels, each with
/// its accumulation rule. The first channel is always [`Film::RAYS`].
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// `sum[y * width + x]` is the sum of that pixel's radiance samples.
    pub sum: Vec<Vec3>,
    /// Samples per pixel in `sum` and in the channels.
    pub samples: u32,
    pub channels: Vec<Channel>,
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
    /// The channel that counts the rays each pixel's paths traced (camera, bounce and shadow
    /// rays), summed over its samples: the renderers' cost per pixel.
    pub const RAYS: &str = "rays";

    /// An empty film with the [`Film::RAYS`] channel.
    pub fn new(width: u32, height: u32) -> Self {
        let mut film = Self {
            width,
            height,
            sum: vec![Vec3::ZERO; width as usize * height as usize],
            samples: 0,
            channels: Vec::new(),
        };
        film.add_channel(Self::RAYS, 1, Accumulation::AllSamples);
        film
    }

    /// Adds an empty channel of `components` (1 to 3) values per pixel.
    pub fn add_channel(&mut self, name: &str, components: usize, accumulation: Accumulation) {
        assert!(
            (1..=3).contains(&components),
            "{name}: {components} components"
        );
        self.channels.push(Channel {
            name: name.to_string(),
            components,
            accumulation,
            data: vec![[0.0; 4]; self.sum.len()],
        });
    }

    /// The channel named `name`.
    pub fn channel(&self, name: &str) -> Option<&Channel> {
        self.channels.iter().find(|c| c.name == name)
    }

    /// Texels per pixel in the GPU's accumulation buffer: radiance, then one per channel.
    pub fn texels_per_pixel(&self) -> usize {
        1 + self.channels.len()
    }

    /// The rays traced for all the film's samples.
    pub fn rays(&self) -> u64 {
        self.channel(Self::RAYS)
            .map_or(0, |c| c.data.iter().map(|t| t[0] as u64).sum())
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

    /// A channel's per-pixel values by its rule: the mean over all samples, the mean over
    /// the samples that hit, or the centre ray's value. `None` for a pixel that has none
    /// (no sample hit, or its centre ray is not in this film).
    pub fn channel_values(&self, channel: &Channel) -> Vec<Option<[f32; 3]>> {
        let inv = if self.samples == 0 {
            0.0
        } else {
            1.0 / self.samples as f32
        };
        let scaled = |t: &[f32; 4], k: f32| [t[0] * k, t[1] * k, t[2] * k];
        channel
            .data
            .iter()
            .map(|t| match channel.accumulation {
                Accumulation::AllSamples => (self.samples > 0).then(|| scaled(t, inv)),
                Accumulation::HitSamples => (t[3] > 0.0).then(|| scaled(t, 1.0 / t[3])),
                Accumulation::PixelCentre => (t[3] > 0.0).then(|| scaled(t, 1.0)),
            })
            .collect()
    }

    /// Adds another film of the same size and channels rendered over a disjoint sample
    /// range. Pixel-centre values come from whichever film traced them.
    pub fn merge(&mut self, other: &Film) {
        assert_eq!((self.width, self.height), (other.width, other.height));
        for (a, b) in self.sum.iter_mut().zip(&other.sum) {
            *a += *b;
        }
        assert_eq!(self.channels.len(), other.channels.len(), "channel lists");
        for (a, b) in self.channels.iter_mut().zip(&other.channels) {
            assert_eq!(
                (&a.name, a.components, a.accumulation),
                (&b.name, b.components, b.accumulation)
            );
            for (x, y) in a.data.iter_mut().zip(&b.data) {
                match a.accumulation {
                    Accumulation::AllSamples | Accumulation::HitSamples => {
                        for k in 0..4 {
                            x[k] += y[k];
                        }
                    }
                    Accumulation::PixelCentre if y[3] > 0.0 => *x = *y,
                    Accumulation::PixelCentre => {}
                }
            }
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
