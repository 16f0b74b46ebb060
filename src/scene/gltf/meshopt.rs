//! `EXT_meshopt_compression` and `KHR_meshopt_compression`: buffer views whose bytes are
//! meshoptimizer's compressed vertex or index streams, decoded by the `meshopt` crate's
//! bindings of meshoptimizer 1.3 (whose decoders are written for untrusted input), then
//! unfiltered (octahedral normals, quaternions, exponent floats, YCoCg colours).

use serde::Deserialize;

/// The extensions' names, as a buffer view's `extensions` keys.
pub(super) const EXTENSIONS: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// The extension's object on a buffer view.
#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct Compressed {
    pub buffer: usize,
    #[serde(default)]
    pub byte_offset: usize,
    pub byte_length: usize,
    pub byte_stride: usize,
    pub count: usize,
    pub mode: Mode,
    #[serde(default)]
    pub filter: Filter,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "UPPERCASE")]
pub(super) enum Mode {
    Attributes,
    Triangles,
    Indices,
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "UPPERCASE")]
pub(super) enum Filter {
    #[default]
    None,
    Octahedral,
    Quaternion,
    Exponential,
    /// KHR_meshopt_compression only.
    Color,
}

/// Largest decoded view: its bytes are made in memory before any accessor reads them.
const MAX_DECODED: usize = 1 << 31;

/// Decodes `c`'s stream, `encoded` (the `byteLength` bytes at `byteOffset` of its buffer),
/// into `count × byteStride` bytes; an error says what is wrong in words.
pub(super) fn decode(c: &Compressed, encoded: &[u8], khr: bool) -> Result<Vec<u8>, String> {
    let stride = c.byte_stride;
    let size = c
        .count
        .checked_mul(stride)
        .filter(|&s| s <= MAX_DECODED)
        .ok_or_else(|| {
            format!(
                "count {} × byteStride {stride} is more than meshtrace decodes",
                c.count
            )
        })?;
    match c.mode {
        Mode::Attributes if stride == 0 || !stride.is_multiple_of(4) || stride > 256 => {
            return Err(format!(
                "byteStride {stride}: ATTRIBUTES streams have a multiple of 4 up to 256"
            ));
        }
        Mode::Triangles | Mode::Indices if stride != 2 && stride != 4 => {
            return Err(format!("byteStride {stride}: index streams have 2 or 4"));
        }
        Mode::Triangles if !c.count.is_multiple_of(3) => {
            return Err(format!(
                "count {} is not a whole number of triangles",
                c.count
            ));
        }
        _ => {}
    }
    if c.mode != Mode::Attributes && c.filter != Filter::None {
        return Err(format!(
            "filter {:?} applies to ATTRIBUTES streams only",
            c.filter
        ));
    }
    let filter_fits = match c.filter {
        Filter::None => true,
        Filter::Octahedral | Filter::Color => stride == 4 || stride == 8,
        Filter::Quaternion => stride == 8,
        Filter::Exponential => stride.is_multiple_of(4),
    };
    if !filter_fits {
        return Err(format!(
            "filter {:?} cannot apply to byteStride {stride}",
            c.filter
        ));
    }
    if c.filter == Filter::Color && !khr {
        return Err("filter COLOR belongs to KHR_meshopt_compression, not EXT_".into());
    }
    // Four-byte aligned storage: the filters read the stream as 16- and 32-bit words.
    let mut words = vec![0u32; size.div_ceil(4)];
    let out = words.as_mut_ptr().cast::<std::ffi::c_void>();
    let (ptr, len) = (encoded.as_ptr(), encoded.len());
    // SAFETY: `out` holds at least `count × stride` bytes, the size each decoder writes;
    // `ptr` and `len` are `encoded`'s. meshoptimizer's decoders bound every read by `len`
    // and report a malformed stream by a non-zero result instead of reading past it.
    let result = unsafe {
        match c.mode {
            Mode::Attributes => {
                meshopt::ffi::meshopt_decodeVertexBuffer(out, c.count, stride, ptr, len)
            }
            Mode::Triangles => {
                meshopt::ffi::meshopt_decodeIndexBuffer(out, c.count, stride, ptr, len)
            }
            Mode::Indices => {
                meshopt::ffi::meshopt_decodeIndexSequence(out, c.count, stride, ptr, len)
            }
        }
    };
    if result != 0 {
        return Err(format!(
            "the compressed {:?} stream is malformed (meshoptimizer's decoder returned {result})",
            c.mode
        ));
    }
    // SAFETY: each filter rewrites `count` elements of `stride` bytes in place, within
    // `words`; the strides were checked against what each filter takes above.
    unsafe {
        match c.filter {
            Filter::None => {}
            Filter::Octahedral => meshopt::ffi::meshopt_decodeFilterOct(out, c.count, stride),
            Filter::Quaternion => meshopt::ffi::meshopt_decodeFilterQuat(out, c.count, stride),
            Filter::Exponential => meshopt::ffi::meshopt_decodeFilterExp(out, c.count, stride),
            Filter::Color => meshopt::ffi::meshopt_decodeFilterColor(out, c.count, stride),
        }
    }
    let mut bytes: Vec<u8> = bytemuck::cast_slice(&words).to_vec();
    bytes.truncate(size);
    Ok(bytes)
}
