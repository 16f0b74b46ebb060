//! The bytes a glTF file refers to: its buffers (the GLB's BIN chunk, `data:` URIs, or files
//! beside it), its buffer views (meshopt-compressed ones decoded) and its images (the same, or a buffer view), each read once, when first
//! needed, through the scene's [`FileSource`](crate::scene::source::FileSource).

use super::{Doc, meshopt};
use crate::scene::SceneError;
use crate::scene::texture::{ImageType, TextureSource};
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The file's buffers, read on first use.
pub(super) struct Buffers<'a> {
    doc: &'a Doc<'a>,
    /// The GLB's BIN chunk, which buffer 0 may name by having no URI.
    blob: RefCell<Option<Vec<u8>>>,
    loaded: RefCell<Vec<Option<Arc<[u8]>>>>,
    /// The images read so far: `None` for an external file that could not be read.
    images: RefCell<Vec<Option<Option<TextureSource>>>>,
    /// The meshopt-compressed buffer views decoded so far, by index.
    decoded: RefCell<HashMap<usize, Arc<[u8]>>>,
}

/// Bytes of a buffer view: the buffer, and the range within it.
pub(super) struct ViewBytes {
    pub data: Arc<[u8]>,
    pub start: usize,
    pub len: usize,
    /// The view's `byteStride`, if it has one.
    pub stride: Option<usize>,
}

impl ViewBytes {
    /// The view's bytes.
    pub fn bytes(&self) -> &[u8] {
        self.data
            .get(self.start..self.start + self.len)
            .unwrap_or(&[])
    }
}

impl<'a> Buffers<'a> {
    pub fn new(doc: &'a Doc<'a>, blob: Option<Vec<u8>>) -> Self {
        Self {
            doc,
            blob: RefCell::new(blob),
            loaded: RefCell::new(vec![None; doc.root.buffers.len()]),
            images: RefCell::new(vec![None; doc.root.images.len()]),
            decoded: RefCell::default(),
        }
    }

    /// The document the buffers belong to.
    pub fn doc(&self) -> &Doc<'a> {
        self.doc
    }

    /// Buffer `index`'s bytes, exactly `byteLength` of them.
    pub fn buffer(&self, index: usize) -> Result<Arc<[u8]>, SceneError> {
        let doc = self.doc;
        let at = format!("buffers[{index}]");
        let Some(buffer) = doc.root.buffers.get(index) else {
            return Err(doc.error(
                at,
                format!(
                    "does not exist (the file has {})",
                    super::count(doc.root.buffers.len(), "buffer")
                ),
            ));
        };
        if let Some(Some(data)) = self.loaded.borrow().get(index) {
            return Ok(data.clone());
        }
        let (data, source) = match &buffer.uri {
            Some(uri) => {
                let (data, source) = self.read_uri(uri, &format!("{at}.uri"), false)?;
                (
                    data.ok_or_else(|| doc.error(format!("{at}.uri"), "cannot be read"))?,
                    source,
                )
            }
            None if index == 0 => {
                let blob = self.blob.borrow_mut().take().ok_or_else(|| {
                    doc.error(
                        &at,
                        "has no uri, and the file has no GLB BIN chunk to stand for it",
                    )
                })?;
                (blob, "the GLB BIN chunk".to_string())
            }
            None => {
                return Err(doc.error(
                    at,
                    "has no uri; only buffer 0 may stand for a GLB's BIN chunk",
                ));
            }
        };
        let length = buffer.byte_length.0;
        if (data.len() as u64) < length {
            return Err(doc.error(
                at,
                format!(
                    "byteLength is {length} bytes, but {source} holds {} (truncated?)",
                    data.len()
                ),
            ));
        }
        let data: Arc<[u8]> = data[..length as usize].into();
        if let Some(slot) = self.loaded.borrow_mut().get_mut(index) {
            *slot = Some(data.clone());
        }
        Ok(data)
    }

    /// Buffer view `index`'s bytes. `at` and `what` name the reference in messages.
    pub fn view(&self, index: usize, at: &str, what: &str) -> Result<ViewBytes, SceneError> {
        let doc = self.doc;
        let Some(view) = doc.root.buffer_views.get(index) else {
            return Err(doc.error(
                at,
                format!(
                    "{what}: bufferView {index} does not exist (the file has {})",
                    super::count(doc.root.buffer_views.len(), "buffer view")
                ),
            ));
        };
        if let Some(decoded) = self.decompressed(index, view)? {
            let len = decoded.len();
            return Ok(ViewBytes {
                data: decoded,
                start: 0,
                len,
                stride: view.byte_stride.map(|s| s.0),
            });
        }
        let b = view.buffer.value();
        let data = self.buffer(b)?;
        let start = view.byte_offset.map_or(0, |o| o.0);
        let len = view.byte_length.0;
        let end = start.saturating_add(len);
        if end > data.len() as u64 {
            return Err(doc.error(
                at,
                format!(
                    "{what}: bufferView {index} (bytes {start} to {end}) lies past the end of buffer {b} ({} bytes)",
                    data.len()
                ),
            ));
        }
        Ok(ViewBytes {
            data,
            start: start as usize,
            len: len as usize,
            stride: view.byte_stride.map(|s| s.0),
        })
    }

    /// Buffer view `index`'s bytes decoded, where meshopt compression holds them
    /// (EXT_ or KHR_meshopt_compression), decoded once; `None` for a plain view.
    fn decompressed(
        &self,
        index: usize,
        view: &gltf::json::buffer::View,
    ) -> Result<Option<Arc<[u8]>>, SceneError> {
        let doc = self.doc;
        let Some((name, value)) = view.extensions.as_ref().and_then(|e| {
            meshopt::EXTENSIONS
                .iter()
                .find_map(|name| e.others.get(*name).map(|v| (*name, v)))
        }) else {
            return Ok(None);
        };
        if let Some(done) = self.decoded.borrow().get(&index) {
            return Ok(Some(done.clone()));
        }
        let at = format!("bufferViews[{index}].extensions.{name}");
        let c: meshopt::Compressed = serde_json::from_value(value.clone())
            .map_err(|e| doc.error(&at, format!("is not a meshopt object: {e}")))?;
        let data = self.buffer(c.buffer)?;
        let encoded = c
            .byte_offset
            .checked_add(c.byte_length)
            .and_then(|end| data.get(c.byte_offset..end))
            .ok_or_else(|| {
                doc.error(
                    &at,
                    format!(
                        "bytes {} to {} lie past the end of buffer {} ({} bytes)",
                        c.byte_offset,
                        c.byte_offset.saturating_add(c.byte_length),
                        c.buffer,
                        data.len()
                    ),
                )
            })?;
        let decoded =
            meshopt::decode(&c, encoded, name.starts_with("KHR")).map_err(|m| doc.error(&at, m))?;
        let length = view.byte_length.0;
        if (decoded.len() as u64) < length {
            return Err(doc.error(
                &at,
                format!(
                    "decodes to {} bytes, fewer than the view's byteLength {length}",
                    decoded.len()
                ),
            ));
        }
        let decoded: Arc<[u8]> = decoded[..length as usize].into();
        self.decoded.borrow_mut().insert(index, decoded.clone());
        Ok(Some(decoded))
    }

    /// Image `index` as a texture source, read on first use: `None` (with a warning) for
    /// an external image file that cannot be read, whose texture falls back to its factor.
    pub fn image(&self, index: usize, at: &str) -> Result<Option<TextureSource>, SceneError> {
        let doc = self.doc;
        let Some(image) = doc.root.images.get(index) else {
            return Err(doc.error(
                at,
                format!(
                    "image {index} does not exist (the file has {})",
                    super::count(doc.root.images.len(), "image")
                ),
            ));
        };
        if let Some(Some(found)) = self.images.borrow().get(index) {
            return Ok(found.clone());
        }
        let image_at = format!("images[{index}]");
        let mime = image.mime_type.as_ref().map(|m| m.0.as_str());
        let source = match (&image.uri, image.buffer_view) {
            (Some(uri), _) => {
                let (bytes, source) = self.read_uri(uri, &format!("{image_at}.uri"), true)?;
                match bytes {
                    Some(bytes) => {
                        let format = mime
                            .or(data_uri_mime(uri))
                            .and_then(ImageType::from_mime_type)
                            .or_else(|| ImageType::from_path(Path::new(&source)));
                        let name = if uri.starts_with("data:") {
                            format!("{}: {image_at}", doc.shown)
                        } else {
                            format!("{}: {image_at} ({source})", doc.shown)
                        };
                        Some(TextureSource::Memory {
                            name,
                            bytes: bytes.into(),
                            format,
                        })
                    }
                    None => None,
                }
            }
            (None, Some(view)) => {
                let view = self.view(view.value(), &image_at, "the image")?;
                Some(TextureSource::Memory {
                    name: format!("{}: {image_at}", doc.shown),
                    bytes: view.bytes().into(),
                    format: mime.and_then(ImageType::from_mime_type),
                })
            }
            (None, None) => {
                return Err(doc.error(image_at, "has neither a uri nor a bufferView"));
            }
        };
        if let Some(slot) = self.images.borrow_mut().get_mut(index) {
            *slot = Some(source.clone());
        }
        Ok(source)
    }

    /// The bytes a URI names: a `data:` URI's own, or a file's relative to the glTF file
    /// (`None`, with a warning, when an `optional` file cannot be read), with how messages
    /// show where they came from. `at` is the URI's JSON path.
    fn read_uri(
        &self,
        uri: &str,
        at: &str,
        optional: bool,
    ) -> Result<(Option<Vec<u8>>, String), SceneError> {
        let doc = self.doc;
        if let Some(rest) = uri.strip_prefix("data:") {
            let bytes = decode_data_uri(rest).map_err(|m| doc.error(at, m))?;
            return Ok((Some(bytes), "its data URI".into()));
        }
        if has_scheme(uri) {
            return Err(doc.error(
                at,
                format!(
                    "`{}`: only relative paths and data: URIs are read",
                    super::quoted(uri)
                ),
            ));
        }
        let decoded = percent_decode(uri).map_err(|m| doc.error(at, m))?;
        let path: PathBuf = doc.dir.join(decoded);
        let shown = crate::scene::shown(&path);
        match doc.files.read(&path) {
            Ok(bytes) => Ok((Some(bytes), shown)),
            Err(e) if optional => {
                doc.warn(
                    at,
                    format!(
                        "image {shown} could not be read ({e}); its textures fall back to their factors"
                    ),
                );
                Ok((None, shown))
            }
            Err(e) => Err(doc.error(at, format!("cannot read {shown}: {e}"))),
        }
    }
}

/// The MIME type of a `data:` URI, if it gives one.
fn data_uri_mime(uri: &str) -> Option<&str> {
    let header = uri.strip_prefix("data:")?.split(',').next()?;
    let mime = header.split(';').next()?;
    (!mime.is_empty()).then_some(mime)
}

/// Whether a URI starts with a scheme (`http:`, `file:`…): letters, then letters, digits,
/// `+`, `-` or `.`, then `:`.
fn has_scheme(uri: &str) -> bool {
    let Some((scheme, _)) = uri.split_once(':') else {
        return false;
    };
    let mut chars = scheme.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
}

/// The bytes of a `data:` URI after its `data:`: `[type][;base64],payload`.
fn decode_data_uri(rest: &str) -> Result<Vec<u8>, String> {
    let Some((header, payload)) = rest.split_once(',') else {
        return Err("a data: URI without a comma before its data".into());
    };
    if header.ends_with(";base64") {
        base64_decode(payload)
    } else {
        Ok(percent_decode_bytes(payload))
    }
}

/// Percent-decodes a relative URI into a path, which must be UTF-8. A `%` not followed by
/// two hexadecimal digits stands for itself, as files written with unescaped names have it.
fn percent_decode(uri: &str) -> Result<String, String> {
    String::from_utf8(percent_decode_bytes(uri)).map_err(|_| {
        format!(
            "`{}` is not UTF-8 once its %-escapes are decoded",
            super::quoted(uri)
        )
    })
}

fn percent_decode_bytes(text: &str) -> Vec<u8> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |k: usize| bytes.get(k).and_then(|&b| (b as char).to_digit(16));
        match (bytes[i], hex(i + 1), hex(i + 2)) {
            (b'%', Some(hi), Some(lo)) => {
                out.push((hi * 16 + lo) as u8);
                i += 3;
            }
            (b, _, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    out
}

/// Decodes base64 (the standard alphabet; `-` and `_` of the URL-safe one are accepted
/// too), ignoring ASCII whitespace; the `=` padding is optional.
fn base64_decode(text: &str) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(text.len() / 4 * 3);
    let mut acc = 0u32;
    let mut bits = 0u32;
    let mut padding = false;
    for (i, c) in text.bytes().enumerate() {
        let value = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' => {
                padding = true;
                continue;
            }
            c if c.is_ascii_whitespace() => continue,
            _ => {
                return Err(format!(
                    "the data URI is not base64: character {} at offset {i}",
                    (c as char).escape_debug()
                ));
            }
        };
        if padding {
            return Err(format!(
                "the data URI is not base64: data after `=` padding at offset {i}"
            ));
        }
        acc = (acc << 6) | u32::from(value);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_with_and_without_padding() {
        assert_eq!(base64_decode("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(base64_decode("aGVsbG8").unwrap(), b"hello");
        assert_eq!(base64_decode("aGVs\nbG8h").unwrap(), b"hello!");
        assert_eq!(base64_decode("").unwrap(), b"");
        assert_eq!(base64_decode("/+8=").unwrap(), [0xff, 0xef]);
        assert!(base64_decode("aGV*").is_err());
        assert!(base64_decode("aG=Vs").is_err());
    }

    #[test]
    fn uris() {
        assert_eq!(percent_decode("a%20b%2Fc.bin").unwrap(), "a b/c.bin");
        assert_eq!(percent_decode("100%.bin").unwrap(), "100%.bin");
        assert!(percent_decode("%FF.bin").is_err());
        assert!(has_scheme("http://x/y.bin"));
        assert!(has_scheme("file:///y.bin"));
        assert!(!has_scheme("y.bin"));
        assert!(!has_scheme("dir/a:b.bin"));
        assert_eq!(
            data_uri_mime("data:image/png;base64,AAAA"),
            Some("image/png")
        );
        assert_eq!(decode_data_uri("text/plain,a%41").unwrap(), b"aA");
    }
}
