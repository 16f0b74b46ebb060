//! The film: per-pixel sums of radiance samples and of named channels, and the image files
//! made from them.
//!
//! The output format follows the file's extension: `.exr` (linear float RGB) and `.hdr`
//! (Radiance RGBE) keep the radiance; `.png`, `.jpg`/`.jpeg` and `.bmp` are sRGB-encoded
//! and clamped. Files are written to a temporary sibling and renamed, so a failed or
//! interrupted write never leaves a half-written image under the requested name.
//!
//! Render outputs beyond radiance ([`Aov`]s) are film channels too. They go into an `.exr`
//! output as extra channels of the one part, and beside any other output into one
//! `<stem>.aovs.exr`; object and material ids are 32-bit unsigned channels there.

use crate::fixed::{self, FIXED_FRACTION_BITS, Texel, fixed_add, from_fixed};
use glam::Vec3;
use std::path::{Path, PathBuf};

mod part;
mod view;
pub use part::PartHeader;
pub use view::{DisplayTransform, LUT_FOLDER_VAR, ViewTransform, lut_folder};

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

/// A render output beyond radiance (an AOV), filled from each camera ray's first hit. Each
/// is a film channel of the same name; the order of [`Aov::ALL`] is the channels' order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Aov {
    /// Distance of the hit point along the camera's viewing axis, over the samples that hit.
    Depth,
    /// World-space shading normal facing the camera ray, over the samples that hit.
    Normal,
    /// Reflectance at the hit (textures applied), a miss counting 0.
    Albedo,
    /// The fraction of the camera samples that hit a surface.
    Alpha,
    /// The `[[objects]]` entry (glTF: mesh node) the pixel-centre ray hits.
    ObjectId,
    /// The material the pixel-centre ray hits.
    MaterialId,
    /// BVH nodes visited plus triangles tested per camera ray.
    BvhCost,
    /// The colour of the diffuse lobe at the hit (Cycles' Diffuse Color pass), a miss
    /// counting 0: what the first hit scatters diffusely, as `render::bsdf::diffuse_color`
    /// defines it.
    DiffuseColor,
}

/// The id an [`Aov::ObjectId`] or [`Aov::MaterialId`] pixel holds where nothing is hit.
pub const NO_ID: u32 = u32::MAX;

impl Aov {
    /// Every AOV, in channel order.
    pub const ALL: [Aov; 8] = [
        Aov::Depth,
        Aov::Normal,
        Aov::Albedo,
        Aov::Alpha,
        Aov::ObjectId,
        Aov::MaterialId,
        Aov::BvhCost,
        Aov::DiffuseColor,
    ];

    /// The name on the command line and of the film channel.
    pub fn name(self) -> &'static str {
        match self {
            Aov::Depth => "depth",
            Aov::Normal => "normal",
            Aov::Albedo => "albedo",
            Aov::Alpha => "alpha",
            Aov::ObjectId => "object_id",
            Aov::MaterialId => "material_id",
            Aov::BvhCost => "bvh_cost",
            Aov::DiffuseColor => "diffuse_color",
        }
    }

    /// The AOV's bit in a mask of AOVs ([`Aov::mask`]; the GPU kernel's `params.aovs`).
    pub fn bit(self) -> u32 {
        1 << self as u32
    }

    /// The mask of a list of AOVs.
    pub fn mask(aovs: &[Aov]) -> u32 {
        aovs.iter().fold(0, |m, a| m | a.bit())
    }

    /// Parses a comma-separated list of names (`depth,normal`) into a sorted set.
    pub fn parse_list(list: &str) -> Result<Vec<Aov>, FilmError> {
        let mut out = Vec::new();
        for name in list.split(',').map(str::trim) {
            let aov = Aov::ALL
                .into_iter()
                .find(|a| a.name() == name)
                .ok_or_else(|| FilmError::UnknownAov {
                    name: name.to_string(),
                    valid: Aov::ALL.map(Aov::name).join(", "),
                })?;
            out.push(aov);
        }
        out.sort();
        out.dedup();
        Ok(out)
    }

    /// Components of the AOV's channel, and how they accumulate. Ids are held as their
    /// low and high 16 bits, each exact in an f32.
    fn channel(self) -> (usize, Accumulation) {
        match self {
            Aov::Depth => (1, Accumulation::HitSamples),
            Aov::Normal => (3, Accumulation::HitSamples),
            Aov::Albedo | Aov::DiffuseColor => (3, Accumulation::AllSamples),
            Aov::Alpha | Aov::BvhCost => (1, Accumulation::AllSamples),
            Aov::ObjectId | Aov::MaterialId => (2, Accumulation::PixelCentre),
        }
    }

    /// The EXR channel names of the AOV's components.
    pub fn exr_channels(self) -> &'static [&'static str] {
        match self {
            Aov::Depth => &["Z"],
            Aov::Normal => &["normal.X", "normal.Y", "normal.Z"],
            Aov::Albedo => &["albedo.R", "albedo.G", "albedo.B"],
            Aov::Alpha => &["A"],
            Aov::ObjectId => &["object_id"],
            Aov::MaterialId => &["material_id"],
            Aov::BvhCost => &["bvh_cost"],
            Aov::DiffuseColor => &["diffuse_color.R", "diffuse_color.G", "diffuse_color.B"],
        }
    }
}

/// One AOV's per-pixel values, as an EXR channel holds them.
#[derive(Clone, Debug, PartialEq)]
pub enum AovValues {
    F32(Vec<f32>),
    U32(Vec<u32>),
}

/// One named per-pixel channel beyond radiance. A pixel's entry is one texel of exact
/// fixed-point sums ([`crate::fixed`]), as in the GPU's accumulation buffer: up to three
/// components in `xyz`, and in `w` what the accumulation rule needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    pub name: String,
    /// Components used, 1 to 3.
    pub components: usize,
    pub accumulation: Accumulation,
    pub data: Vec<Texel>,
}

/// Accumulated samples: per-pixel sums of radiance, plus the named channels, each with
/// its accumulation rule. The first channel is always [`Film::RAYS`]. Every sum is exact
/// ([`crate::fixed`]), so films of disjoint sample ranges merge into the bits of one render.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// `sum[y * width + x]` is the fixed-point sum of that pixel's radiance samples.
    pub sum: Vec<[i64; 3]>,
    /// Samples per pixel in `sum` and in the channels.
    pub samples: u32,
    pub channels: Vec<Channel>,
    /// Whether camera rays that miss added no radiance (the sky seen directly is left out),
    /// so that the mean radiance is premultiplied by the [`Aov::Alpha`] coverage: the film
    /// of a `--transparent` render, saved as an RGBA PNG.
    pub transparent: bool,
    /// The AOVs [`Film::save`] writes (an [`Aov::mask`]): those asked for. A transparent
    /// film holds the alpha AOV for its PNG's alpha channel even when not asked for it.
    pub saved_aovs: u32,
}

/// Bits per channel of a PNG output (the other formats have their own: 8 for JPEG and BMP,
/// floats for HDR and EXR).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BitDepth {
    #[default]
    Eight,
    /// 16-bit sRGB-encoded channels (and 16-bit alpha), for pipelines that keep more than
    /// 8 bits of an image's gradients.
    Sixteen,
}

/// The image formats meshtrace writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Exr,
    Hdr,
    Png,
    Jpeg,
    Bmp,
    /// Lossless WebP, 8 bits a channel (RGB, or RGBA for a transparent film).
    Webp,
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
            "webp" => Self::Webp,
            _ => {
                return Err(FilmError::UnknownFormat {
                    path: path.display().to_string(),
                });
            }
        })
    }

    /// Whether the format holds an 8-bit alpha channel: a transparent film's coverage.
    pub fn has_alpha(self) -> bool {
        matches!(self, Self::Png | Self::Webp)
    }
}

/// Why an image could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum FilmError {
    #[error("{path}: unknown image format; use .exr, .hdr, .png, .jpg, .bmp or .webp")]
    UnknownFormat { path: String },
    #[error("{path}: {message}")]
    Io { path: String, message: String },
    #[error("unknown AOV `{name}`; the AOVs are {valid}")]
    UnknownAov { name: String, valid: String },
    #[error("{path}: not a part file of `meshtrace render --part`: {message}")]
    NotAPart { path: String, message: String },
    #[error(
        "{path}: a transparent render is written as a PNG or WebP (its alpha channel is the coverage); give a .png or .webp output"
    )]
    TransparentNotPng { path: String },
    #[error(
        "{file} not found ({from}): the view transform reads Blender's LUTs, which \
         meshtrace does not ship; set {var} to the datafiles/colormanagement folder of a \
         Blender 4.0 or later (`pip install bpy`, or Debian's blender-data), or use the \
         standard view transform",
        var = LUT_FOLDER_VAR
    )]
    MissingLut { file: String, from: String },
    #[error("{path}:{line}: {message}")]
    BadLut {
        path: String,
        line: usize,
        message: String,
    },
    #[error(
        "{path}: a view transform forms an 8- or 16-bit image (PNG, WebP, JPEG, BMP); EXR and \
         HDR outputs hold the linear radiance"
    )]
    ViewOfFloats { path: String },
    #[error(
        "{path}: 16-bit output is a PNG's (EXR and HDR hold floats; JPEG and BMP 8 bits); give a .png output"
    )]
    DeepNotPng { path: String },
}

/// The EXR header attribute that records an image's samples per pixel.
pub const SAMPLES_ATTRIBUTE: &str = "meshtrace.samples";

impl Film {
    /// The channel that counts the rays each pixel's paths traced (camera, bounce and shadow
    /// rays), summed over its samples: the renderers' cost per pixel.
    pub const RAYS: &str = "rays";

    /// An empty film with the [`Film::RAYS`] channel.
    pub fn new(width: u32, height: u32) -> Self {
        let mut film = Self {
            width,
            height,
            sum: vec![[0; 3]; width as usize * height as usize],
            samples: 0,
            channels: Vec::new(),
            transparent: false,
            saved_aovs: 0,
        };
        film.add_channel(Self::RAYS, 1, Accumulation::AllSamples);
        film
    }

    /// An empty film with the [`Film::RAYS`] channel and one channel per AOV of `aovs`
    /// (a mask of [`Aov::bit`]s), in the order of [`Aov::ALL`]; a `transparent` one
    /// ([`Film::transparent`]) also holds [`Aov::Alpha`].
    pub fn with_aovs(width: u32, height: u32, aovs: u32, transparent: bool) -> Self {
        let mut film = Self::new(width, height);
        let held = aovs | if transparent { Aov::Alpha.bit() } else { 0 };
        for aov in Aov::ALL.into_iter().filter(|a| held & a.bit() != 0) {
            let (components, accumulation) = aov.channel();
            film.add_channel(aov.name(), components, accumulation);
        }
        film.transparent = transparent;
        film.saved_aovs = aovs;
        film
    }

    /// The AOVs the film holds, in channel order.
    pub fn aovs(&self) -> Vec<Aov> {
        Aov::ALL
            .into_iter()
            .filter(|a| self.channel(a.name()).is_some())
            .collect()
    }

    /// An AOV's per-pixel values, as the table of [`Aov`] defines them: `None` if the film
    /// does not hold it. Depth is +inf and the normal 0 where no sample hit; the normal is
    /// the normalised mean; ids are [`NO_ID`] where the centre ray hit nothing.
    pub fn aov_values(&self, aov: Aov) -> Option<Vec<AovValues>> {
        let channel = self.channel(aov.name())?;
        let values = self.channel_values(channel);
        let scalar = |f: &dyn Fn(Option<[f32; 3]>) -> f32| {
            AovValues::F32(values.iter().map(|&v| f(v)).collect())
        };
        Some(match aov {
            Aov::Depth => vec![scalar(&|v| v.map_or(f32::INFINITY, |v| v[0]))],
            Aov::Alpha | Aov::BvhCost => vec![scalar(&|v| v.map_or(0.0, |v| v[0]))],
            Aov::Albedo | Aov::DiffuseColor => (0..3)
                .map(|k| scalar(&|v: Option<[f32; 3]>| v.map_or(0.0, |v| v[k])))
                .collect(),
            Aov::Normal => {
                let unit: Vec<Vec3> = values
                    .iter()
                    .map(|v| v.map_or(Vec3::ZERO, |v| Vec3::from(v).normalize_or_zero()))
                    .collect();
                (0..3)
                    .map(|k| AovValues::F32(unit.iter().map(|n| n[k]).collect()))
                    .collect()
            }
            Aov::ObjectId | Aov::MaterialId => vec![AovValues::U32(
                values
                    .iter()
                    .map(|v| v.map_or(NO_ID, |v| v[0] as u32 | (v[1] as u32) << 16))
                    .collect(),
            )],
        })
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
            data: vec![[0; 4]; self.sum.len()],
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
        self.channel(Self::RAYS).map_or(0, |c| {
            c.data
                .iter()
                .map(|t| (t[0] >> FIXED_FRACTION_BITS) as u64)
                .sum()
        })
    }

    /// The per-pixel mean radiance.
    pub fn mean(&self) -> Vec<Vec3> {
        self.sum.iter().map(|&s| self.mean_of(s)).collect()
    }

    /// The mean of a pixel's radiance sum over the film's samples (0 with none).
    fn mean_of(&self, sum: [i64; 3]) -> Vec3 {
        if self.samples == 0 {
            return Vec3::ZERO;
        }
        let n = self.samples as f64;
        Vec3::from(sum.map(|s| (from_fixed(s) / n) as f32))
    }

    /// Sets pixel `i`'s radiance sum to that of `samples` samples of mean `mean` (the
    /// denoiser replaces the image this way).
    pub fn set_mean(&mut self, i: usize, mean: Vec3) {
        self.sum[i] = fixed::to_fixed3(mean * self.samples as f32);
    }

    /// A channel's per-pixel values by its rule: the mean over all samples, the mean over
    /// the samples that hit, or the centre ray's value. `None` for a pixel that has none
    /// (no sample hit, or its centre ray is not in this film).
    pub fn channel_values(&self, channel: &Channel) -> Vec<Option<[f32; 3]>> {
        let scaled = |t: &Texel, n: f64| [0, 1, 2].map(|k| (from_fixed(t[k]) / n) as f32);
        let samples = self.samples as f64;
        channel
            .data
            .iter()
            .map(|t| match channel.accumulation {
                Accumulation::AllSamples => (self.samples > 0).then(|| scaled(t, samples)),
                Accumulation::HitSamples => (t[3] > 0).then(|| scaled(t, from_fixed(t[3]))),
                Accumulation::PixelCentre => (t[3] > 0).then(|| scaled(t, 1.0)),
            })
            .collect()
    }

    /// Adds another film of the same size and channels rendered over a disjoint sample
    /// range: exactly, so the result does not depend on the order or the split.
    /// Pixel-centre values come from whichever film traced them.
    pub fn merge(&mut self, other: &Film) {
        assert_eq!((self.width, self.height), (other.width, other.height));
        for (a, b) in self.sum.iter_mut().zip(&other.sum) {
            *a = fixed::fixed_add3(*a, *b);
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
                        *x = [0, 1, 2, 3].map(|k| fixed_add(x[k], y[k]));
                    }
                    Accumulation::PixelCentre if y[3] > 0 => *x = *y,
                    Accumulation::PixelCentre => {}
                }
            }
        }
        self.samples += other.samples;
        self.transparent |= other.transparent;
        self.saved_aovs |= other.saved_aovs;
    }

    /// Checks, before any rendering, that `path` names a known format in a folder where a
    /// file can be created, by creating and removing the temporary file `save` would use.
    /// A `transparent` render must name a PNG.
    pub fn check_writable(path: &Path, transparent: bool) -> Result<(), FilmError> {
        let format = Format::from_path(path)?;
        if transparent && !format.has_alpha() {
            return Err(FilmError::TransparentNotPng {
                path: path.display().to_string(),
            });
        }
        Self::check_encoding(path, format, BitDepth::Eight, ViewTransform::Standard)?;
        let tmp = temp_sibling(path);
        std::fs::File::create(&tmp).map_err(|e| FilmError::Io {
            path: path.display().to_string(),
            message: format!("cannot write here: {e}"),
        })?;
        let _ = std::fs::remove_file(&tmp);
        Ok(())
    }

    /// The file that holds the AOVs of an output `path` that is not an EXR:
    /// `<stem>.aovs.exr` beside it.
    pub fn aov_path(path: &Path) -> PathBuf {
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        path.with_file_name(format!("{stem}.aovs.exr"))
    }

    /// Refuses a `depth` or a `view` transform that `path`'s `format` cannot hold: 16 bits
    /// are a PNG's, and EXR and HDR files keep the linear radiance.
    pub fn check_encoding(
        path: &Path,
        format: Format,
        depth: BitDepth,
        view: ViewTransform,
    ) -> Result<(), FilmError> {
        if depth == BitDepth::Sixteen && format != Format::Png {
            return Err(FilmError::DeepNotPng {
                path: path.display().to_string(),
            });
        }
        if view != ViewTransform::Standard && matches!(format, Format::Exr | Format::Hdr) {
            return Err(FilmError::ViewOfFloats {
                path: path.display().to_string(),
            });
        }
        Ok(())
    }

    /// Writes the mean radiance in the format the extension names, with the AOVs the film
    /// holds: extra channels of an EXR, or else [`Film::aov_path`] beside the image. A
    /// transparent film is written as an RGBA PNG. PNGs have 8 bits a channel, and 8- and
    /// 16-bit images the sRGB curve ([`ViewTransform::Standard`]).
    pub fn save(&self, path: &Path) -> Result<(), FilmError> {
        self.save_as(path, BitDepth::Eight, &DisplayTransform::default())
    }

    /// [`Film::save`], with a PNG's channels of `depth` bits, and 8- and 16-bit images
    /// formed by `view`.
    pub fn save_as(
        &self,
        path: &Path,
        depth: BitDepth,
        view: &DisplayTransform,
    ) -> Result<(), FilmError> {
        let format = Format::from_path(path)?;
        if self.transparent && !format.has_alpha() {
            return Err(FilmError::TransparentNotPng {
                path: path.display().to_string(),
            });
        }
        Self::check_encoding(path, format, depth, view.view())?;
        // An EXR holds the AOVs itself; another format's go beside it.
        if format == Format::Exr || self.saved_aovs == 0 {
            return write_atomically(path, |tmp| self.encode(tmp, format, depth, view));
        }
        write_atomically(&Self::aov_path(path), |tmp| {
            self.encode_exr(tmp, false, None)
        })?;
        write_atomically(path, |tmp| self.encode(tmp, format, depth, view))
    }

    /// One single-part EXR: the mean radiance as `R`, `G`, `B` if `radiance`, then every
    /// AOV's channels (ids as 32-bit unsigned), losslessly compressed (ZIP); for a `part`, also
    /// the exact sums and the part's header ([`Film::save_part`]).
    fn encode_exr(
        &self,
        tmp: &Path,
        radiance: bool,
        part: Option<&PartHeader>,
    ) -> Result<(), String> {
        use exr::prelude::{AnyChannel, FlatSamples, LayerAttributes};
        let pixels = self.width as usize * self.height as usize;
        if self.sum.len() != pixels {
            return Err("film size mismatch".into());
        }
        let mut channels = Vec::new();
        if radiance {
            let mean = self.mean();
            for (k, name) in ["R", "G", "B"].into_iter().enumerate() {
                let samples = FlatSamples::F32(mean.iter().map(|c| c[k]).collect());
                channels.push(AnyChannel::new(name, samples));
            }
        }
        for aov in self.aovs() {
            if self.saved_aovs & aov.bit() == 0 {
                continue;
            }
            let values = self.aov_values(aov).ok_or("missing AOV channel")?;
            for (name, v) in aov.exr_channels().iter().zip(values) {
                let samples = match v {
                    AovValues::F32(v) => FlatSamples::F32(v),
                    AovValues::U32(v) => FlatSamples::U32(v),
                };
                channels.push(AnyChannel::new(*name, samples));
            }
        }
        let size = (self.width as usize, self.height as usize);
        // The samples per pixel the image holds: all of them, or those an interruption
        // (Ctrl-C, SIGTERM) left.
        let mut attributes = LayerAttributes::default();
        if let Some(header) = part {
            let (sums, header) = part::part_channels(self, header);
            channels.extend(sums);
            attributes.other.extend(header);
        }
        attributes.other.insert(
            exr::meta::attribute::Text::from(SAMPLES_ATTRIBUTE),
            exr::meta::attribute::AttributeValue::I32(self.samples.min(i32::MAX as u32) as i32),
        );
        let mut bytes = exr_bytes(size, attributes, channels)?;
        sort_exr_attributes(&mut bytes)?;
        let file = std::fs::File::create(tmp).map_err(|e| e.to_string())?;
        let mut out = std::io::BufWriter::new(file);
        std::io::Write::write_all(&mut out, &bytes).map_err(|e| e.to_string())?;
        finish_file(out)
    }

    /// The image in `format`: an EXR through [`Film::encode_exr`] (with the AOVs and the
    /// sample count), HDR as floats, the others through the `image` crate, formed by `view`.
    fn encode(
        &self,
        tmp: &Path,
        format: Format,
        depth: BitDepth,
        view: &DisplayTransform,
    ) -> Result<(), String> {
        let (w, h) = (self.width, self.height);
        let image_format = match format {
            Format::Exr => return self.encode_exr(tmp, true, None),
            Format::Hdr => image::ImageFormat::Hdr,
            Format::Png => image::ImageFormat::Png,
            Format::Jpeg => image::ImageFormat::Jpeg,
            Format::Bmp => image::ImageFormat::Bmp,
            Format::Webp => image::ImageFormat::WebP,
        };
        let mean = self.mean();
        let size = "film size mismatch";
        let image = match format {
            Format::Exr | Format::Hdr => {
                let data: Vec<f32> = mean.iter().flat_map(|c| c.to_array()).collect();
                image::Rgb32FImage::from_raw(w, h, data).ok_or(size)?.into()
            }
            Format::Png if self.transparent && depth == BitDepth::Sixteen => {
                let data = self.display_rgba::<u16>(&mean, view)?;
                image::ImageBuffer::<image::Rgba<u16>, _>::from_raw(w, h, data)
                    .ok_or(size)?
                    .into()
            }
            Format::Png | Format::Webp if self.transparent => {
                let data = self.display_rgba::<u8>(&mean, view)?;
                image::RgbaImage::from_raw(w, h, data).ok_or(size)?.into()
            }
            Format::Png if depth == BitDepth::Sixteen => {
                let data = display_rgb::<u16>(&mean, view);
                image::ImageBuffer::<image::Rgb<u16>, _>::from_raw(w, h, data)
                    .ok_or(size)?
                    .into()
            }
            Format::Png | Format::Jpeg | Format::Bmp | Format::Webp => {
                let data = display_rgb::<u8>(&mean, view);
                image::RgbImage::from_raw(w, h, data).ok_or(size)?.into()
            }
        };
        let file = std::fs::File::create(tmp).map_err(|e| e.to_string())?;
        let mut out = std::io::BufWriter::new(file);
        image::DynamicImage::write_to(&image, &mut out, image_format).map_err(|e| e.to_string())?;
        finish_file(out)
    }

    /// A transparent film's RGBA in `T`'s 8 or 16 bits: alpha the coverage, colour the
    /// premultiplied mean divided by it (PNG stores straight alpha, and Blender forms the
    /// straight colour too), formed by `view`; 0 where nothing was hit.
    fn display_rgba<T: Quantum>(
        &self,
        mean: &[Vec3],
        view: &DisplayTransform,
    ) -> Result<Vec<T>, String> {
        let alpha = self
            .channel(Aov::Alpha.name())
            .map(|c| self.channel_values(c))
            .ok_or("a transparent film needs its alpha channel")?;
        Ok(mean
            .iter()
            .zip(alpha)
            .flat_map(|(&c, a)| {
                let a = a.map_or(0.0, |a| a[0]);
                let c = if a > 0.0 { c / a } else { Vec3::ZERO };
                let [r, g, b] = view.encode(c).map(T::quantise);
                [r, g, b, T::quantise(a)]
            })
            .collect())
    }
}

/// An opaque film's RGB in `T`'s 8 or 16 bits, formed by `view`.
fn display_rgb<T: Quantum>(mean: &[Vec3], view: &DisplayTransform) -> Vec<T> {
    mean.iter()
        .flat_map(|&c| view.encode(c).map(T::quantise))
        .collect()
}

/// One single-part EXR of `channels` with `attributes`, in memory: ZIP over blocks of 16
/// rows, written in increasing order, so lossless, compact, and the same bytes for the same
/// pixels (a merge of parts is `cmp`-equal to one render).
pub fn exr_bytes(
    size: (usize, usize),
    attributes: exr::prelude::LayerAttributes,
    channels: Vec<exr::prelude::AnyChannel<exr::prelude::FlatSamples>>,
) -> Result<Vec<u8>, String> {
    use exr::prelude::{AnyChannels, Encoding, Image, Layer, WritableImage};
    let layer = Layer::new(
        size,
        attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| e.to_string())?;
    Ok(bytes.into_inner())
}

/// Writes `bytes` to `path` as [`Film`]'s images are written: complete or not at all.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), FilmError> {
    write_atomically(path, |tmp| {
        let mut out =
            std::io::BufWriter::new(std::fs::File::create(tmp).map_err(|e| e.to_string())?);
        std::io::Write::write_all(&mut out, bytes).map_err(|e| e.to_string())?;
        finish_file(out)
    })
}

/// Writes `path` through `encode` into a temporary sibling, renamed into place once
/// complete; the temporary file is removed on failure.
fn write_atomically(
    path: &Path,
    encode: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), FilmError> {
    let tmp = temp_sibling(path);
    let result = encode(&tmp).and_then(|()| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
    if let Err(message) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(FilmError::Io {
            path: path.display().to_string(),
            message,
        });
    }
    Ok(())
}

/// Puts the header attributes of a single-part EXR file in name order. The `exr` crate
/// writes its custom attributes from a `HashMap`, whose order changes from one map to the
/// next, so a part file (ten attributes) came out in a different byte order on every write.
/// Reordering keeps the header's length, so the offset table after it stays valid.
fn sort_exr_attributes(bytes: &mut [u8]) -> Result<(), String> {
    const MULTIPART: u32 = 1 << 12;
    let flags = bytes
        .get(4..8)
        .map(|v| u32::from_le_bytes([v[0], v[1], v[2], v[3]]))
        .ok_or("EXR shorter than its version field")?;
    if flags & MULTIPART != 0 {
        return Err("meshtrace writes single-part EXR files only".into());
    }
    let end_of_string = |at: usize| -> Result<usize, String> {
        bytes[at..]
            .iter()
            .position(|&b| b == 0)
            .map(|i| at + i)
            .ok_or_else(|| "EXR header attribute without its terminating NUL".to_string())
    };
    let mut at = 8;
    let mut attributes: Vec<(usize, usize, usize)> = Vec::new();
    while bytes.get(at).is_some_and(|&b| b != 0) {
        let name_end = end_of_string(at)?;
        let kind_end = end_of_string(name_end + 1)?;
        let size = bytes
            .get(kind_end + 1..kind_end + 5)
            .map(|v| u32::from_le_bytes([v[0], v[1], v[2], v[3]]) as usize)
            .ok_or("EXR header attribute cut short")?;
        let end = kind_end + 5 + size;
        if end > bytes.len() {
            return Err("EXR header attribute cut short".into());
        }
        attributes.push((at, name_end, end));
        at = end;
    }
    let mut sorted: Vec<&(usize, usize, usize)> = attributes.iter().collect();
    sorted.sort_by_key(|&&(start, name_end, _)| &bytes[start..name_end]);
    let header: Vec<u8> = sorted
        .iter()
        .flat_map(|&&(start, _, end)| bytes[start..end].iter().copied())
        .collect();
    bytes[8..8 + header.len()].copy_from_slice(&header);
    Ok(())
}

/// Flushes a written file to the disk.
fn finish_file(mut out: std::io::BufWriter<std::fs::File>) -> Result<(), String> {
    use std::io::Write;
    out.flush().map_err(|e| e.to_string())?;
    out.into_inner()
        .map_err(|e| e.to_string())?
        .sync_all()
        .map_err(|e| e.to_string())
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
    quantise8(srgb(x))
}

/// `x` in [0, 1] (clamped) rounded to the nearest of 256 levels.
pub fn quantise8(x: f32) -> u8 {
    (x.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// The sRGB transfer function, clamped and rounded to 16 bits.
pub fn linear_to_srgb16(x: f32) -> u16 {
    (srgb(x) * 65535.0 + 0.5) as u16
}

/// The sRGB transfer function of `x` clamped to [0, 1] (NaN as 0).
fn srgb(x: f32) -> f32 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    if x <= 0.0031308 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// An integer channel of a PNG, 8 or 16 bits.
pub trait Quantum: Copy {
    /// `x` in [0, 1] (clamped), rounded to the nearest level.
    fn quantise(x: f32) -> Self;
}

impl Quantum for u8 {
    fn quantise(x: f32) -> Self {
        quantise8(x)
    }
}

impl Quantum for u16 {
    fn quantise(x: f32) -> Self {
        (x.clamp(0.0, 1.0) * 65535.0 + 0.5) as u16
    }
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
