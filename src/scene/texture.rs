//! Image textures: the record a material's texture slot points to ([`Texture`]), and the
//! scene's texture table ([`Textures`]), which reads each image file once and packs its
//! texels into one array of 32-bit words. 8-bit images stay 8-bit (one word a texel,
//! RGBA); 16-bit and floating-point images (HDR, EXR) are stored as four `f32` words a
//! texel. The lookup, the same on both renderers, is `render::texture`.

use super::SceneError;
use super::source::FileSource;
use bytemuck::{Pod, Zeroable};
use image::ImageFormat;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// How a texture's texels are stored and decoded: a `u32` code, as the shaders compare it.
#[repr(transparent)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct TextureFormat(pub u32);

impl TextureFormat {
    /// One word a texel, RGBA 8 bits each; colour channels sRGB-encoded.
    pub const RGBA8_SRGB: Self = Self(0);
    /// One word a texel, RGBA 8 bits each, linear.
    pub const RGBA8_LINEAR: Self = Self(1);
    /// Four words a texel, RGBA `f32`, linear.
    pub const RGBA32F: Self = Self(2);

    /// Every format with its name for the shaders' constants (`TEX_*`).
    pub const ALL: [(Self, &'static str); 3] = [
        (Self::RGBA8_SRGB, "rgba8_srgb"),
        (Self::RGBA8_LINEAR, "rgba8_linear"),
        (Self::RGBA32F, "rgba32f"),
    ];

    /// Words of the texel table per texel.
    pub fn words_per_texel(self) -> usize {
        if self == Self::RGBA32F { 4 } else { 1 }
    }
}

/// What a lookup outside [0, 1] reads, along one axis: a `u32` code, as the shaders
/// compare it.
#[repr(transparent)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct Wrap(pub u32);

impl Wrap {
    /// The image tiles (glTF's REPEAT; the default everywhere).
    pub const REPEAT: Self = Self(0);
    /// The edge texels extend outwards (glTF's CLAMP_TO_EDGE, MTL's `-clamp on`).
    pub const CLAMP: Self = Self(1);
    /// The image tiles, every other copy mirrored (glTF's MIRRORED_REPEAT).
    pub const MIRROR: Self = Self(2);

    /// Every mode with its name, as scene files spell it and the shaders' constants
    /// (`WRAP_*`) are named.
    pub const ALL: [(Self, &'static str); 3] = [
        (Self::REPEAT, "repeat"),
        (Self::CLAMP, "clamp"),
        (Self::MIRROR, "mirror"),
    ];

    /// The modes along u and v as [`Texture::wrap`] packs them: u in the low byte, v in
    /// the next.
    pub fn pack(u: Wrap, v: Wrap) -> u32 {
        u.0 | (v.0 << 8)
    }
}

/// One texture as a material slot reads it (64 bytes): an image in the texel table, how
/// its texels decode, the affine map applied to texture coordinates before the lookup
/// (`uv_matrix · uv + uv_offset`: a tiling scale, and glTF's KHR_texture_transform), for
/// a scalar parameter the channel it reads, the wrap modes along u and v, and the
/// texture coordinate set it reads.
/// mirror: shaders/types.wgsl `Texture`
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Texture {
    /// Index of the image's first word in the texel table.
    pub offset: u32,
    pub width: u32,
    pub height: u32,
    pub format: TextureFormat,
    /// The linear part, row by row: u' = m0 u + m1 v, v' = m2 u + m3 v.
    pub uv_matrix: [f32; 4],
    pub uv_offset: [f32; 2],
    /// The channel a scalar parameter reads (0 = red).
    pub channel: u32,
    /// [`Wrap`] codes packed by [`Wrap::pack`].
    pub wrap: u32,
    /// The texture coordinate set a surface lookup reads: 0, or 1 for glTF's
    /// `TEXCOORD_1` (the triangles' second set).
    pub uv_set: u32,
    pub _pad: [u32; 3],
}

/// An affine map of texture coordinates, as scene files and glTF's KHR_texture_transform
/// give it: scale, then rotate (radians, as the extension's matrix), then offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    pub scale: [f32; 2],
    pub rotation: f32,
    pub offset: [f32; 2],
}

impl UvTransform {
    /// A tiling scale alone.
    pub fn scale(su: f32, sv: f32) -> Self {
        Self {
            scale: [su, sv],
            rotation: 0.0,
            offset: [0.0, 0.0],
        }
    }

    /// The matrix of [`Texture::uv_matrix`]: KHR_texture_transform's rotation
    /// (u' = cos·u + sin·v, v' = −sin·u + cos·v) times the scale. That is the direction
    /// Khronos's TextureTransformTest asset checks and the extension's own JSON example
    /// implies (the image turns clockwise as seen with v running down), and the transpose
    /// of what the draft README's GLSL matrix reads as in column-major order.
    pub fn matrix(&self) -> [f32; 4] {
        let [su, sv] = self.scale;
        if self.rotation == 0.0 {
            return [su, 0.0, 0.0, sv];
        }
        let (s, c) = self.rotation.sin_cos();
        [c * su, s * sv, -s * su, c * sv]
    }
}

/// How a parameter reads its texture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Usage {
    /// A colour (albedo, emission): 8-bit images are sRGB-decoded.
    Colour,
    /// A number read from one channel, linear.
    Scalar { channel: u32 },
    /// Linear RGB data that is not a colour, such as a tangent-space normal map: never
    /// sRGB-decoded.
    Linear,
}

/// An image's format, as its file name or MIME type gives it: one the `image` crate decodes,
/// or KTX2 with Basis Universal data (glTF's KHR_texture_basisu), which `basisu` transcodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageType {
    Image(ImageFormat),
    Ktx2,
}

impl ImageType {
    /// The format a MIME type names (`image/ktx2`, or one the `image` crate knows).
    pub fn from_mime_type(mime: &str) -> Option<Self> {
        if mime.eq_ignore_ascii_case("image/ktx2") {
            return Some(ImageType::Ktx2);
        }
        ImageFormat::from_mime_type(mime).map(ImageType::Image)
    }

    /// The format a file name's extension names (`.ktx2`, or one the `image` crate knows).
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?;
        if ext.eq_ignore_ascii_case("ktx2") {
            return Some(ImageType::Ktx2);
        }
        ImageFormat::from_extension(ext).map(ImageType::Image)
    }
}

/// Where a texture's image comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum TextureSource {
    /// An image file, read through the scene's file source when the texture is added.
    File(PathBuf),
    /// Encoded image bytes already in memory (a glTF file's images): `name` identifies them
    /// (images of one name are decoded once) and shows them in messages; `format` is the
    /// format their MIME type or file name gives, else it is guessed from the bytes.
    Memory {
        name: String,
        bytes: Arc<[u8]>,
        format: Option<ImageType>,
    },
}

impl TextureSource {
    /// The image as messages show it: its path, or its name.
    pub fn shown(&self) -> String {
        match self {
            TextureSource::File(path) => super::shown(path),
            TextureSource::Memory { name, .. } => name.clone(),
        }
    }

    /// What identifies the image in the cache of decoded images.
    fn key(&self) -> SourceKey {
        match self {
            TextureSource::File(path) => SourceKey::File(path.clone()),
            TextureSource::Memory { name, .. } => SourceKey::Memory(name.clone()),
        }
    }
}

/// [`TextureSource::key`]: a file by its path, bytes in memory by their name.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum SourceKey {
    File(PathBuf),
    Memory(String),
}

/// A texture a material asks for before its image is read: the image, its use, its UV
/// transform, its wrap modes along u and v, whether a missing file falls back to the
/// parameter's constant factor (MTL and glTF files) or is an error (scene files), and
/// the texture coordinate set it reads ([`Texture::uv_set`]).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureRef {
    pub source: TextureSource,
    pub usage: Usage,
    pub transform: UvTransform,
    pub wrap: [Wrap; 2],
    pub optional: bool,
    pub uv_set: u32,
}

impl TextureRef {
    /// An equirectangular image as an environment map reads it: a colour (linear, or
    /// sRGB-decoded for an 8-bit image), repeating around, clamped at the poles; a file that
    /// cannot be read is an error.
    pub fn environment(source: TextureSource) -> Self {
        Self {
            source,
            usage: Usage::Colour,
            transform: UvTransform::scale(1.0, 1.0),
            wrap: [Wrap::REPEAT, Wrap::CLAMP],
            optional: false,
            uv_set: 0,
        }
    }
}

/// The scene's textures: the records material slots index, and the texel table their
/// images are packed into.
#[derive(Clone, Debug, Default)]
pub struct Textures {
    pub records: Vec<Texture>,
    /// The image each record reads (its file, or its name), for messages.
    pub names: Vec<String>,
    pub texels: Vec<u32>,
    /// Images already packed, by image and whether their texels were sRGB-decoded on the
    /// way in (16-bit images for colour): (offset, width, height).
    packed: HashMap<(SourceKey, bool), (u32, u32, u32)>,
    /// What each image read so far holds.
    kinds: HashMap<SourceKey, Kind>,
}

/// Why a texture could not be added.
pub enum TextureError {
    /// The file could not be read and the reference allows falling back.
    Missing(String),
    Fatal(SceneError),
}

impl Textures {
    /// The index of a record like record `index` whose lookups are shifted by `offset` in
    /// texture space (after its UV transform).
    pub fn shifted(&mut self, index: u32, offset: [f32; 2]) -> u32 {
        let mut record = self.records[index as usize];
        record.uv_offset[0] += offset[0];
        record.uv_offset[1] += offset[1];
        if let Some(i) = self.records.iter().position(|t| *t == record) {
            return i as u32;
        }
        self.records.push(record);
        self.names.push(self.names[index as usize].clone());
        self.records.len() as u32 - 1
    }

    /// The index of a record reading `r`'s image as `r` says, reading and packing the image
    /// unless an earlier record already did. The image's path or name is shown in messages.
    pub fn add(&mut self, r: &TextureRef, files: &dyn FileSource) -> Result<u32, TextureError> {
        let shown = r.source.shown();
        let (kind, (offset, width, height)) = match self.cached(r) {
            Some(found) => found,
            None => self.pack(r, &shown, files)?,
        };
        let format = match (kind, r.usage) {
            (Kind::Ldr, Usage::Colour) => TextureFormat::RGBA8_SRGB,
            (Kind::Ldr, Usage::Scalar { .. } | Usage::Linear) => TextureFormat::RGBA8_LINEAR,
            _ => TextureFormat::RGBA32F,
        };
        let record = Texture {
            offset,
            width,
            height,
            format,
            uv_matrix: r.transform.matrix(),
            uv_offset: r.transform.offset,
            channel: match r.usage {
                Usage::Colour | Usage::Linear => 0,
                Usage::Scalar { channel } => channel,
            },
            wrap: Wrap::pack(r.wrap[0], r.wrap[1]),
            uv_set: r.uv_set,
            _pad: [0; 3],
        };
        if let Some(i) = self.records.iter().position(|t| *t == record) {
            return Ok(i as u32);
        }
        self.records.push(record);
        self.names.push(shown);
        Ok(self.records.len() as u32 - 1)
    }

    /// Where `r`'s texels already lie, if an earlier texture packed them.
    fn cached(&self, r: &TextureRef) -> Option<(Kind, (u32, u32, u32))> {
        let key = r.source.key();
        let kind = *self.kinds.get(&key)?;
        let found = *self.packed.get(&(key, decodes_srgb(kind, r.usage)))?;
        Some((kind, found))
    }

    /// Reads, decodes and packs `r`'s image.
    fn pack(
        &mut self,
        r: &TextureRef,
        shown: &str,
        files: &dyn FileSource,
    ) -> Result<(Kind, (u32, u32, u32)), TextureError> {
        let (bytes, format) = match &r.source {
            TextureSource::File(path) => match files.read(path) {
                Ok(bytes) => (bytes.into(), ImageType::from_path(path)),
                Err(e) if r.optional => {
                    return Err(TextureError::Missing(format!("{shown} ({e})")));
                }
                Err(source) => {
                    return Err(TextureError::Fatal(SceneError::Io {
                        path: shown.to_string(),
                        source,
                    }));
                }
            },
            TextureSource::Memory { bytes, format, .. } => (bytes.clone(), *format),
        };
        let invalid = |message: String| {
            TextureError::Fatal(SceneError::Image {
                path: shown.to_string(),
                message,
            })
        };
        let (kind, image) = decode(format, &bytes).map_err(invalid)?;
        let decode_srgb = decodes_srgb(kind, r.usage);
        let offset = u32::try_from(self.texels.len())
            .map_err(|_| invalid("the scene's textures exceed 2^32 words (16 GiB)".into()))?;
        let (width, height) = (image.width(), image.height());
        match image {
            Decoded::Ldr(img) => self
                .texels
                .extend(img.pixels().map(|p| u32::from_le_bytes(p.0))),
            Decoded::Float(image) => {
                for p in image.pixels() {
                    let [r, g, b, a] = p.0;
                    let c = |x: f32| if decode_srgb { srgb_to_linear(x) } else { x };
                    self.texels.extend([c(r), c(g), c(b), a].map(f32::to_bits));
                }
            }
        }
        if self.texels.len() > u32::MAX as usize {
            return Err(invalid(
                "the scene's textures exceed 2^32 words (16 GiB)".into(),
            ));
        }
        let key = r.source.key();
        self.kinds.insert(key.clone(), kind);
        self.packed
            .insert((key, decode_srgb), (offset, width, height));
        Ok((kind, (offset, width, height)))
    }

    /// Bytes of the texel table.
    pub fn bytes(&self) -> usize {
        self.texels.len() * 4
    }

    /// Scales every image whose larger side exceeds `max` texels down to `max` on that side
    /// (the aspect ratio kept, the other side rounded, at least 1), and packs the table again
    /// without the space they gave up, so both renderers read the smaller images. The filter
    /// is the `image` crate's triangle filter widened to the scale (each new texel a tent-
    /// weighted mean of the old ones it covers): it has no negative lobes, so an HDR sun
    /// does not ring into negative radiance, and a map's mean is kept. 8-bit images are
    /// filtered in the values they store (sRGB-encoded for colour), as image editors do;
    /// float texels below 0 become 0. Returns the images scaled, in table order.
    pub fn limit_size(&mut self, max: u32) -> Vec<Scaled> {
        // Each image once, by where it lies: (offset, width, height, words a texel), and
        // the first record that reads it, for its name.
        let mut images: Vec<(u32, u32, u32, usize, usize)> = self
            .records
            .iter()
            .enumerate()
            .map(|(i, t)| (t.offset, t.width, t.height, t.format.words_per_texel(), i))
            .collect();
        images.sort_unstable();
        images.dedup_by_key(|image| image.0);
        let mut scaled = Vec::new();
        // Old offset → new (offset, width, height). Images are moved in table order, each
        // to at or before where it was, and none grows, so the table is packed in place.
        let mut moved = HashMap::new();
        let mut at = 0;
        for (offset, width, height, words, record) in images {
            let start = offset as usize;
            let len = width as usize * height as usize * words;
            let (w, h) = fitted(width, height, max);
            if (w, h) == (width, height) {
                self.texels.copy_within(start..start + len, at);
            } else {
                let image = &self.texels[start..start + len];
                let smaller = resize(image, (width, height), words, (w, h));
                self.texels[at..at + smaller.len()].copy_from_slice(&smaller);
                scaled.push(Scaled {
                    name: self.names[record].clone(),
                    from: (width, height),
                    to: (w, h),
                });
            }
            moved.insert(offset, (at as u32, w, h));
            at += w as usize * h as usize * words;
        }
        self.texels.truncate(at);
        if !scaled.is_empty() {
            self.texels.shrink_to_fit();
        }
        for t in &mut self.records {
            (t.offset, t.width, t.height) = moved[&t.offset];
        }
        for place in self.packed.values_mut() {
            if let Some(&now) = moved.get(&place.0) {
                *place = now;
            }
        }
        scaled
    }
}

/// An image [`Textures::limit_size`] scaled down: its file or name, and its size (width,
/// height) before and after.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Scaled {
    pub name: String,
    pub from: (u32, u32),
    pub to: (u32, u32),
}

/// The size of a `width` × `height` image whose larger side is at most `max`: its own, or
/// scaled to `max` along the larger side and the other side in proportion (at least 1).
fn fitted(width: u32, height: u32, max: u32) -> (u32, u32) {
    let long = width.max(height);
    if long <= max {
        return (width, height);
    }
    let side = |s: u32| {
        let scaled = (u64::from(s) * u64::from(max) + u64::from(long) / 2) / u64::from(long);
        (scaled as u32).max(1)
    };
    (side(width), side(height))
}

/// `texels` (a packed image of `words` words a texel) resized from `from` to `to` with the
/// triangle filter; the packed texels of the result.
fn resize(texels: &[u32], from: (u32, u32), words: usize, to: (u32, u32)) -> Vec<u32> {
    use image::imageops::{FilterType, resize};
    let (width, height) = from;
    let index = |x: u32, y: u32| (y as usize * width as usize + x as usize) * words;
    if words == 1 {
        let image = image::RgbaImage::from_fn(width, height, |x, y| {
            image::Rgba(texels[index(x, y)].to_le_bytes())
        });
        let small = resize(&image, to.0, to.1, FilterType::Triangle);
        return small.pixels().map(|p| u32::from_le_bytes(p.0)).collect();
    }
    // The crate clamps a float image's values to [0, 1] as it filters: they are divided by
    // the power of two at or above the largest one first, and multiplied by it after, which
    // is exact (powers of two change only the exponent).
    let peak = texels
        .iter()
        .map(|&b| f32::from_bits(b))
        .filter(|x| x.is_finite())
        .fold(1.0f32, f32::max);
    let scale = 2f32.powi(peak.log2().ceil().min(127.0) as i32);
    let image = image::Rgba32FImage::from_fn(width, height, |x, y| {
        let i = index(x, y);
        image::Rgba(std::array::from_fn(|c| {
            f32::from_bits(texels[i + c]) / scale
        }))
    });
    let small = resize(&image, to.0, to.1, FilterType::Triangle);
    small
        .pixels()
        .flat_map(|p| p.0.map(|c| (c * scale).to_bits()))
        .collect()
}

/// What an image file holds: 8-bit channels, or more precise ones that are sRGB-encoded
/// (16-bit integer images) or linear (HDR, EXR).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Ldr,
    FloatSrgb,
    FloatLinear,
}

/// Whether texels of `kind` are sRGB-decoded when packed for `usage` (8-bit ones are
/// decoded at lookup, through the decoding table, instead).
fn decodes_srgb(kind: Kind, usage: Usage) -> bool {
    kind == Kind::FloatSrgb && usage == Usage::Colour
}

/// A decoded image: 8-bit RGBA, or `f32` RGBA.
enum Decoded {
    Ldr(image::RgbaImage),
    Float(image::Rgba32FImage),
}

impl Decoded {
    fn width(&self) -> u32 {
        match self {
            Decoded::Ldr(i) => i.width(),
            Decoded::Float(i) => i.width(),
        }
    }

    fn height(&self) -> u32 {
        match self {
            Decoded::Ldr(i) => i.height(),
            Decoded::Float(i) => i.height(),
        }
    }
}

/// OpenEXR's compression codes, in order (the header's `compression` attribute).
const EXR_COMPRESSIONS: [&str; 11] = [
    "NONE", "RLE", "ZIPS", "ZIP", "PIZ", "PXR24", "B44", "B44A", "DWAA", "DWAB", "HTJ2K",
];

/// Refuses an OpenEXR file whose compression the `exr` crate cannot read (DWAA, DWAB,
/// HTJ2K), naming it, where the decoder would give a less helpful message. The header is a
/// list of attributes (name, type, size, value) after 8 bytes of magic number and version;
/// a header this cannot follow is left to the decoder.
fn check_exr_compression(bytes: &[u8]) -> Result<(), String> {
    let mut at = 8;
    let text = |at: &mut usize| -> Option<&[u8]> {
        let rest = bytes.get(*at..)?;
        let end = rest.iter().position(|&b| b == 0)?;
        *at += end + 1;
        Some(&rest[..end])
    };
    while let Some(name) = text(&mut at) {
        if name.is_empty() {
            break;
        }
        text(&mut at);
        let size = bytes
            .get(at..at + 4)
            .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]));
        let Some(size) = size.and_then(|s| usize::try_from(s).ok()) else {
            return Ok(());
        };
        at += 4;
        if name == b"compression" {
            let code = bytes.get(at).copied().unwrap_or(0) as usize;
            return match EXR_COMPRESSIONS.get(code) {
                Some(&c @ ("DWAA" | "DWAB" | "HTJ2K")) => Err(format!(
                    "the EXR is compressed with {c}, which meshtrace's EXR reader (the exr \
                     crate) cannot read; save it with ZIP or PIZ compression instead \
                     (for example `oiiotool in.exr --compression zip -o out.exr`)"
                )),
                _ => Ok(()),
            };
        }
        at += size;
    }
    Ok(())
}

/// Decodes an image's bytes, in `format` where its extension or MIME type names one (TGA
/// has no magic number), or else in the format guessed from its first bytes. Before it
/// allocates, the image's size is checked against the memory the machine has free: an
/// image that cannot fit is an error that says how much it needs and how much there is.
fn decode(format: Option<ImageType>, bytes: &[u8]) -> Result<(Kind, Decoded), String> {
    use image::ImageDecoder;
    let format = match format {
        Some(ImageType::Ktx2) => return decode_ktx2(bytes),
        None if bytes.starts_with(KTX2_IDENTIFIER) => return decode_ktx2(bytes),
        Some(ImageType::Image(format)) => Ok(format),
        None if bytes.starts_with(RGBE_SIGNATURE) => Ok(ImageFormat::Hdr),
        None => image::guess_format(bytes),
    }
    .map_err(|_| {
        "not an image format meshtrace reads (PNG, JPEG, BMP, TGA, WebP, HDR, EXR, KTX2)"
            .to_string()
    })?;
    let cannot = |e: image::ImageError| format!("cannot decode the image: {e}");
    let decoder: Box<dyn ImageDecoder + '_> = match format {
        ImageFormat::Hdr => hdr_decoder(bytes)?,
        _ => {
            if format == ImageFormat::OpenExr {
                check_exr_compression(bytes)?;
            }
            let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
            // The image crate's default cap (512 MiB) would refuse an 16384² texture that
            // fits; the check below against the free memory replaces it.
            reader.no_limits();
            Box::new(reader.into_decoder().map_err(cannot)?)
        }
    };
    let (width, height) = decoder.dimensions();
    if width == 0 || height == 0 {
        return Err("the image has no pixels".into());
    }
    // Decoded, then packed at 4 bytes a texel (8-bit images) or 16 (the others).
    let texels = width as u64 * height as u64;
    use image::ColorType as C;
    let packed = match decoder.color_type() {
        C::L8 | C::La8 | C::Rgb8 | C::Rgba8 => 4,
        _ => 16,
    };
    let need = decoder
        .total_bytes()
        .saturating_add(texels.saturating_mul(packed));
    check_memory(width, height, need)?;
    let image = image::DynamicImage::from_decoder(decoder).map_err(cannot)?;
    use image::DynamicImage as D;
    Ok(match image {
        D::ImageLuma8(_) | D::ImageLumaA8(_) | D::ImageRgb8(_) | D::ImageRgba8(_) => {
            (Kind::Ldr, Decoded::Ldr(image.to_rgba8()))
        }
        D::ImageRgb32F(_) | D::ImageRgba32F(_) => {
            (Kind::FloatLinear, Decoded::Float(image.to_rgba32f()))
        }
        other => (Kind::FloatSrgb, Decoded::Float(other.to_rgba32f())),
    })
}

/// Refuses an image of `width` × `height` texels whose decoding and packing needs `need`
/// bytes, more than the machine has free, saying how much each is.
fn check_memory(width: u32, height: u32, need: u64) -> Result<(), String> {
    match available_memory() {
        Some(free) if need > free => Err(format!(
            "the image is {width}×{height} texels: decoding and packing it needs {}, more than the {} of memory free",
            gibibytes(need),
            gibibytes(free)
        )),
        _ => Ok(()),
    }
}

/// The 12 bytes that open every KTX2 file: `«KTX 20»\r\n\x1A\n`.
const KTX2_IDENTIFIER: &[u8; 12] = b"\xABKTX 20\xBB\r\n\x1A\n";

/// Decodes a KTX2 image whose data is Basis Universal ETC1S or UASTC (LDR), the two that
/// glTF's KHR_texture_basisu allows, to 8-bit RGBA: level 0 (the full-size image; the
/// renderer filters without mipmaps) transcoded by `basisu`'s RGBA32 target. The texels
/// are left as stored, sRGB or linear being the texture slot's business, as for a PNG. A
/// texture array, cubemap or video is refused: a glTF texture is one 2D image.
fn decode_ktx2(bytes: &[u8]) -> Result<(Kind, Decoded), String> {
    use basisu::{DecodeFlags, SourceFormat, TargetFormat, Transcoder};
    if !bytes.starts_with(KTX2_IDENTIFIER) {
        return Err("not a KTX2 file (it does not start with the KTX2 identifier)".into());
    }
    let ktx2 = Transcoder::new(bytes).map_err(|e| {
        format!(
            "cannot read the KTX2 file: {} (meshtrace reads KTX2 files with Basis Universal \
             ETC1S or UASTC data, as KHR_texture_basisu requires)",
            basisu_error(&e)
        )
    })?;
    let source = ktx2.source_format();
    if !matches!(source, SourceFormat::Etc1s | SourceFormat::UastcLdr) {
        return Err(format!(
            "the KTX2 image holds {source:?} data; KHR_texture_basisu allows only ETC1S and \
             UASTC (LDR), which meshtrace reads"
        ));
    }
    let (layers, faces) = (ktx2.layer_count(), ktx2.face_count());
    if ktx2.is_video() || layers > 1 || faces != 1 {
        return Err(format!(
            "the KTX2 file is {}, not one 2D image as a glTF texture must be",
            if ktx2.is_video() {
                "a video".to_string()
            } else if faces != 1 {
                format!("a cubemap ({faces} faces)")
            } else {
                format!("a texture array ({layers} layers)")
            }
        ));
    }
    let (width, height) = ktx2.base_dimensions();
    if width == 0 || height == 0 {
        return Err("the image has no pixels".into());
    }
    // The transcoder sizes its RGBA32 output as width · height · 4 in u32 arithmetic.
    let texels = u64::from(width) * u64::from(height);
    if texels > u64::from(u32::MAX / 4) {
        return Err(format!(
            "the KTX2 image is {width}×{height} texels, more than meshtrace's limit of 2^30"
        ));
    }
    check_ktx2_inflated_size(bytes, width, height)?;
    // Transcoded, then packed, at 4 bytes a texel each.
    check_memory(width, height, texels * 8)?;
    let rgba = ktx2
        .transcode(0, TargetFormat::Rgba32, DecodeFlags::NONE)
        .map_err(|e| {
            // The formats are checked above: the transcoder's one remaining failure, which it
            // calls an unimplemented feature, is level data it cannot follow.
            let why = match e {
                basisu::Error::UnsupportedFeature(_) => {
                    "the data of its level 0 is corrupt or truncated".to_string()
                }
                e => basisu_error(&e),
            };
            format!("cannot transcode the KTX2 image: {why}")
        })?;
    let got = rgba.len();
    let image = image::RgbaImage::from_raw(width, height, rgba).ok_or_else(|| {
        format!("the KTX2 transcoder gave {got} bytes for a {width}×{height} image")
    })?;
    Ok((Kind::Ldr, Decoded::Ldr(image)))
}

/// KTX2's supercompressionScheme for Zstandard.
const KTX2_ZSTD: u32 = 2;

/// Refuses a Zstandard-supercompressed KTX2 whose level 0 claims to inflate to other than
/// the UASTC blocks of a `width`×`height` image (16 bytes a 4×4 block): the transcoder
/// allocates what the claim says before it inflates, so a forged header could ask for any
/// amount of memory. The header is 48 bytes, its index 32 more; level 0's entry follows:
/// byteOffset, byteLength and uncompressedByteLength, each a u64 (KTX 2.0 §3.9).
fn check_ktx2_inflated_size(bytes: &[u8], width: u32, height: u32) -> Result<(), String> {
    let u32_at = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let u64_at = |at: usize| {
        bytes
            .get(at..at + 8)
            .map(|b| u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
    };
    if u32_at(44) != Some(KTX2_ZSTD) {
        return Ok(());
    }
    let Some(claimed) = u64_at(80 + 16) else {
        return Err("the file is truncated, or an offset in it is out of range".into());
    };
    let blocks = u64::from(width.div_ceil(4)) * u64::from(height.div_ceil(4));
    if claimed != blocks * 16 {
        return Err(format!(
            "its level 0 claims to inflate to {claimed} bytes, but a {width}×{height} UASTC \
             image is {} bytes",
            blocks * 16
        ));
    }
    Ok(())
}

/// What a `basisu` error means, in words (the crate gives its errors no `Display`).
fn basisu_error(e: &basisu::Error) -> String {
    use basisu::Error as E;
    match e {
        E::InvalidData => "the file is corrupt or not a Basis Universal texture".into(),
        E::Truncated => "the file is truncated, or an offset in it is out of range".into(),
        E::ZstdRequired => "its Zstandard-supercompressed data cannot be read".into(),
        other => format!("{other:?}"),
    }
}

/// The signature line of a Radiance HDR file as the `image` crate's decoder knows it.
const RADIANCE_SIGNATURE: &[u8] = b"#?RADIANCE";

/// The other signature line stb_image accepts (its `stbi__hdr_test`), with its line end:
/// the program type that Bruce Walter's rgbe.c, and the tools built on it, write.
const RGBE_SIGNATURE: &[u8] = b"#?RGBE\n";

/// A decoder of a Radiance HDR file, with either signature stb_image accepts. A file that
/// starts `#?RGBE` is read as a chain of `#?RADIANCE` and the bytes after its first line,
/// so the `image` crate's decoder (which knows only `#?RADIANCE`) reads it without a copy
/// of the file. Any other first line is an error that quotes it.
fn hdr_decoder(bytes: &[u8]) -> Result<Box<dyn image::ImageDecoder + '_>, String> {
    use image::codecs::hdr::HdrDecoder;
    use std::io::Read;
    let cannot = |e: image::ImageError| format!("cannot decode the image: {e}");
    if let Some(rest) = bytes.strip_prefix(RGBE_SIGNATURE) {
        let reader = Read::chain(&b"#?RADIANCE\n"[..], rest);
        return Ok(Box::new(HdrDecoder::new(reader).map_err(cannot)?));
    }
    if !bytes.starts_with(RADIANCE_SIGNATURE) {
        let line = bytes.split(|&b| b == b'\n').next().unwrap_or_default();
        let line: String = String::from_utf8_lossy(line).chars().take(40).collect();
        return Err(format!(
            "not a Radiance HDR file: its first line is `{}`, not #?RADIANCE or #?RGBE",
            line.escape_debug()
        ));
    }
    Ok(Box::new(HdrDecoder::new(bytes).map_err(cannot)?))
}

/// Memory the system can give without swapping (Linux's MemAvailable), in bytes; `None`
/// where it does not say.
fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

fn gibibytes(bytes: u64) -> String {
    format!("{:.2} GiB", bytes as f64 / (1u64 << 30) as f64)
}

/// The sRGB transfer function's inverse on a value in [0, 1].
fn srgb_to_linear(s: f32) -> f32 {
    if s <= 0.04045 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

/// Adds the equirectangular image at `path` to `textures` as an environment map reads it
/// (linear, or sRGB-decoded for an 8-bit image; repeating around, clamped at the poles);
/// its record's index, or why it cannot be read.
pub fn load_environment(
    path: &Path,
    textures: &mut Textures,
    files: &dyn FileSource,
) -> Result<u32, String> {
    let r = TextureRef::environment(TextureSource::File(path.to_path_buf()));
    textures.add(&r, files).map_err(|e| match e {
        TextureError::Fatal(e) => e.to_string(),
        TextureError::Missing(file) => format!("cannot read {file}"),
    })
}
