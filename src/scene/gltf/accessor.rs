//! Accessors: typed views of buffer data, read with every offset and count checked. An
//! accessor's elements lie in a buffer view (strided or packed), or are zeros where it has
//! none; a sparse accessor then replaces the elements its indices name. Components are
//! converted as the specification says: floats as they are, normalized integers to [0, 1]
//! (unsigned) or [-1, 1] (signed), other integers to their value.

use super::buffers::Buffers;
use crate::scene::SceneError;
use gltf::json::accessor::{ComponentType as C, Type};
use gltf::json::validation::Checked;

/// The most elements an accessor without a buffer view (all zeros, but for its sparse
/// values) may have: its elements are made in memory, not read.
pub(super) const MAX_ZERO_ELEMENTS: u64 = 1 << 24;

/// What a use of an accessor requires of it: its element type and the (component type,
/// normalized) pairs allowed. `name` names the use in messages.
pub(super) struct Expect {
    pub name: &'static str,
    pub ty: Type,
    pub components: &'static [(C, bool)],
}

/// Floats, and with KHR_mesh_quantization also these integer forms.
pub(super) const FLOAT: &[(C, bool)] = &[(C::F32, false)];
pub(super) const QUANTIZED_ANY: &[(C, bool)] = &[
    (C::F32, false),
    (C::I8, false),
    (C::I8, true),
    (C::U8, false),
    (C::U8, true),
    (C::I16, false),
    (C::I16, true),
    (C::U16, false),
    (C::U16, true),
];
pub(super) const QUANTIZED_SIGNED_NORMALIZED: &[(C, bool)] =
    &[(C::F32, false), (C::I8, true), (C::I16, true)];

/// The accessors a primitive reads, as glTF 2.0 allows them and, with
/// `quantized` (KHR_mesh_quantization), as that extension widens them.
pub(super) fn position(quantized: bool) -> Expect {
    Expect {
        name: "POSITION",
        ty: Type::Vec3,
        components: if quantized { QUANTIZED_ANY } else { FLOAT },
    }
}

pub(super) fn normal(quantized: bool) -> Expect {
    Expect {
        name: "NORMAL",
        ty: Type::Vec3,
        components: if quantized {
            QUANTIZED_SIGNED_NORMALIZED
        } else {
            FLOAT
        },
    }
}

pub(super) fn tangent(quantized: bool) -> Expect {
    Expect {
        name: "TANGENT",
        ty: Type::Vec4,
        components: if quantized {
            QUANTIZED_SIGNED_NORMALIZED
        } else {
            FLOAT
        },
    }
}

/// Texture coordinate set `name` (`TEXCOORD_0`, `TEXCOORD_1`).
pub(super) fn texcoord(quantized: bool, name: &'static str) -> Expect {
    Expect {
        name,
        ty: Type::Vec2,
        components: if quantized {
            QUANTIZED_ANY
        } else {
            &[(C::F32, false), (C::U8, true), (C::U16, true)]
        },
    }
}

/// `COLOR_0`: RGB or RGBA (`ty`, the accessor's own type, either one), floats or
/// normalized unsigned bytes or shorts.
pub(super) fn color(ty: Type) -> Expect {
    Expect {
        name: "COLOR_0",
        ty: if ty == Type::Vec3 {
            Type::Vec3
        } else {
            Type::Vec4
        },
        components: &[(C::F32, false), (C::U8, true), (C::U16, true)],
    }
}

/// A morph target's POSITION deltas: floats, or with KHR_mesh_quantization signed bytes
/// and shorts, normalized or not.
pub(super) fn delta(quantized: bool) -> Expect {
    Expect {
        name: "a POSITION delta",
        ty: Type::Vec3,
        components: if quantized {
            &[
                (C::F32, false),
                (C::I8, false),
                (C::I8, true),
                (C::I16, false),
                (C::I16, true),
            ]
        } else {
            FLOAT
        },
    }
}

/// A morph target's NORMAL or TANGENT deltas (three components each).
pub(super) fn normal_delta(quantized: bool) -> Expect {
    Expect {
        name: "a NORMAL or TANGENT delta",
        ty: Type::Vec3,
        components: if quantized {
            QUANTIZED_SIGNED_NORMALIZED
        } else {
            FLOAT
        },
    }
}

const INDICES: Expect = Expect {
    name: "indices",
    ty: Type::Scalar,
    components: &[(C::U8, false), (C::U16, false), (C::U32, false)],
};

/// Accessor `index` as floats, `components` of them per element, for the use `expect`
/// describes; `at` is the JSON path of the reference, for messages.
pub(super) fn read_floats(
    buffers: &Buffers,
    index: usize,
    at: &str,
    expect: &Expect,
) -> Result<Vec<f32>, SceneError> {
    read(buffers, index, at, expect, decode_f32)
}

/// Index accessor `index` checked as [`read_indices`] checks it, its count returned, for
/// indices a decoder gives instead.
pub(super) fn index_count(buffers: &Buffers, index: usize, at: &str) -> Result<u64, SceneError> {
    checked(buffers, index, at, &INDICES).map(|(a, ..)| a.count.0)
}

/// Index accessor `index` (unsigned bytes, shorts or ints).
pub(super) fn read_indices(
    buffers: &Buffers,
    index: usize,
    at: &str,
) -> Result<Vec<u32>, SceneError> {
    read(buffers, index, at, &INDICES, decode_u32)
}

/// Accessor `index` checked against `expect`: the accessor, its type, component type and
/// whether it is normalized.
fn checked<'r>(
    buffers: &Buffers<'r>,
    index: usize,
    at: &str,
    expect: &Expect,
) -> Result<(&'r gltf::json::Accessor, Type, C, bool), SceneError> {
    let doc = buffers.doc();
    let root = doc.root;
    let error = |message: String| doc.error(at, format!("accessor {index}{message}"));
    let Some(accessor) = root.accessors.get(index) else {
        return Err(error(format!(
            " does not exist (the file has {})",
            super::count(root.accessors.len(), "accessor")
        )));
    };
    let (Checked::Valid(ty), Checked::Valid(component)) = (accessor.type_, accessor.component_type)
    else {
        return Err(error(" has an invalid type or componentType".into()));
    };
    let c = component.0;
    let normalized = accessor.normalized;
    if ty != expect.ty || !expect.components.contains(&(c, normalized)) {
        let allowed: Vec<String> = expect
            .components
            .iter()
            .map(|&(c, n)| component_name(c, n))
            .collect();
        return Err(error(format!(
            " holds {} of {}; {} must be {} of {}",
            type_name(ty),
            component_name(c, normalized),
            expect.name,
            type_name(expect.ty),
            allowed.join(" or ")
        )));
    }
    Ok((accessor, ty, c, normalized))
}

/// Accessor `index` as floats whose values a decoder gave (`values`: a Draco stream's
/// attribute, each component as its integer or float value) rather than a buffer view:
/// checked against `expect` as [`read_floats`] checks it, with as many elements as the
/// accessor's count, and normalized integers mapped as the specification maps them.
pub(super) fn decoded_floats(
    buffers: &Buffers,
    index: usize,
    at: &str,
    expect: &Expect,
    mut values: Vec<f32>,
) -> Result<Vec<f32>, SceneError> {
    let (accessor, ty, c, normalized) = checked(buffers, index, at, expect)?;
    let want = accessor.count.0 as usize * ty.multiplicity();
    if values.len() != want {
        return Err(buffers.doc().error(
            at,
            format!(
                "accessor {index} has {} elements, but the compressed stream decodes to {}",
                accessor.count.0,
                values.len() / ty.multiplicity()
            ),
        ));
    }
    if normalized {
        let scale = match c {
            C::I8 | C::U8 => [127.0, 255.0],
            C::I16 | C::U16 => [32767.0, 65535.0],
            _ => [1.0, 1.0],
        };
        let signed = matches!(c, C::I8 | C::I16);
        for v in &mut values {
            *v = if signed {
                (*v / scale[0]).max(-1.0)
            } else {
                *v / scale[1]
            };
        }
    }
    Ok(values)
}

/// Reads an accessor's elements, each component through `decode`.
fn read<T: Copy + Default>(
    buffers: &Buffers,
    index: usize,
    at: &str,
    expect: &Expect,
    decode: fn(&[u8], C, bool) -> T,
) -> Result<Vec<T>, SceneError> {
    let doc = buffers.doc();
    let error = |message: String| doc.error(at, format!("accessor {index}{message}"));
    let (accessor, ty, c, normalized) = checked(buffers, index, at, expect)?;
    let comps = ty.multiplicity();
    let size = c.size();
    let element = comps * size;
    let count = accessor.count.0;
    let offset = accessor.byte_offset.map_or(0, |o| o.0);
    let mut out: Vec<T> = match accessor.buffer_view {
        Some(v) => {
            let view = buffers.view(v.value(), at, &format!("accessor {index}"))?;
            let stride = view.stride.unwrap_or(element);
            if stride < element {
                return Err(error(format!(
                    ": bufferView {}'s byteStride {stride} is less than its {element}-byte elements",
                    v.value()
                )));
            }
            let needed = span(count, stride, element, offset);
            if needed > view.len as u64 {
                return Err(error(format!(
                    " reads past the end of bufferView {}: {count} elements of {element} bytes, \
                     {stride} apart from byte {offset}, need {} bytes, the view has {}",
                    v.value(),
                    needed.min(u64::MAX - 1),
                    view.len
                )));
            }
            // `needed` fits the view, so every position below is in it.
            let bytes = view.bytes();
            let mut out = Vec::with_capacity(count as usize * comps);
            for e in 0..count as usize {
                let at = offset as usize + e * stride;
                for k in 0..comps {
                    let b = bytes.get(at + k * size..at + (k + 1) * size).unwrap_or(&[]);
                    out.push(decode(b, c, normalized));
                }
            }
            out
        }
        None if count > MAX_ZERO_ELEMENTS => {
            return Err(error(format!(
                " has no bufferView and {count} elements, more than the {MAX_ZERO_ELEMENTS} \
                 meshtrace makes for such an accessor"
            )));
        }
        None => vec![T::default(); count as usize * comps],
    };
    if let Some(sparse) = &accessor.sparse {
        apply_sparse(
            buffers,
            sparse,
            &mut out,
            index,
            at,
            comps,
            (c, normalized),
            decode,
        )?;
    }
    Ok(out)
}

/// Replaces the elements a sparse accessor's indices name with its values.
#[allow(clippy::too_many_arguments)]
fn apply_sparse<T: Copy>(
    buffers: &Buffers,
    sparse: &gltf::json::accessor::sparse::Sparse,
    out: &mut [T],
    index: usize,
    at: &str,
    comps: usize,
    (c, normalized): (C, bool),
    decode: fn(&[u8], C, bool) -> T,
) -> Result<(), SceneError> {
    let doc = buffers.doc();
    let error = |message: String| doc.error(at, format!("accessor {index}'s sparse {message}"));
    let count = (out.len() / comps.max(1)) as u64;
    let n = sparse.count.0;
    if n > count {
        return Err(error(format!(
            "count {n} exceeds the accessor's count {count}"
        )));
    }
    let n = n as usize;
    // Indices: tightly packed unsigned integers, strictly increasing, each below `count`.
    let Checked::Valid(ic) = sparse.indices.component_type else {
        return Err(error("indices have an invalid componentType".into()));
    };
    let ic = ic.0;
    if !matches!(ic, C::U8 | C::U16 | C::U32) {
        return Err(error(format!(
            "indices are {}; they must be unsigned bytes, shorts or ints",
            component_name(ic, false)
        )));
    }
    let what = format!("accessor {index}'s sparse indices");
    let view = buffers.view(sparse.indices.buffer_view.value(), at, &what)?;
    let offset = sparse.indices.byte_offset.0;
    let needed = span(n as u64, ic.size(), ic.size(), offset);
    if needed > view.len as u64 {
        return Err(error(format!(
            "indices read past the end of bufferView {}: {n} of {} bytes from byte {offset} \
             need {needed} bytes, the view has {}",
            sparse.indices.buffer_view.value(),
            ic.size(),
            view.len
        )));
    }
    let bytes = view.bytes();
    let mut indices = Vec::with_capacity(n);
    for k in 0..n {
        let at = offset as usize + k * ic.size();
        let i = decode_u32(bytes.get(at..at + ic.size()).unwrap_or(&[]), ic, false);
        if u64::from(i) >= count {
            return Err(error(format!(
                "index {i} (entry {k}) is past the accessor's {count} elements"
            )));
        }
        if indices.last().is_some_and(|&last| i <= last) {
            return Err(error(format!(
                "indices are not strictly increasing: {i} (entry {k}) follows {}",
                indices.last().copied().unwrap_or(0)
            )));
        }
        indices.push(i);
    }
    // Values: tightly packed elements of the accessor's own type.
    let element = comps * c.size();
    let what = format!("accessor {index}'s sparse values");
    let view = buffers.view(sparse.values.buffer_view.value(), at, &what)?;
    let offset = sparse.values.byte_offset.0;
    let needed = span(n as u64, element, element, offset);
    if needed > view.len as u64 {
        return Err(error(format!(
            "values read past the end of bufferView {}: {n} of {element} bytes from byte \
             {offset} need {needed} bytes, the view has {}",
            sparse.values.buffer_view.value(),
            view.len
        )));
    }
    let bytes = view.bytes();
    for (k, &i) in indices.iter().enumerate() {
        for j in 0..comps {
            let at = offset as usize + k * element + j * c.size();
            let b = bytes.get(at..at + c.size()).unwrap_or(&[]);
            if let Some(slot) = out.get_mut(i as usize * comps + j) {
                *slot = decode(b, c, normalized);
            }
        }
    }
    Ok(())
}

/// Bytes `count` elements of `element` bytes, `stride` apart from byte `offset`, reach to;
/// `u64::MAX` when that overflows.
fn span(count: u64, stride: usize, element: usize, offset: u64) -> u64 {
    if count == 0 {
        return offset;
    }
    (count - 1)
        .checked_mul(stride as u64)
        .and_then(|x| x.checked_add(element as u64))
        .and_then(|x| x.checked_add(offset))
        .unwrap_or(u64::MAX)
}

/// `N` bytes from the start of `b` (zeros past its end).
fn le<const N: usize>(b: &[u8]) -> [u8; N] {
    let mut a = [0u8; N];
    for (x, y) in a.iter_mut().zip(b) {
        *x = *y;
    }
    a
}

/// A component as a float: floats as they are, normalized integers as the specification
/// maps them, other integers to their value.
fn decode_f32(b: &[u8], c: C, normalized: bool) -> f32 {
    match (c, normalized) {
        (C::F32, _) => f32::from_le_bytes(le(b)),
        (C::U8, false) => f32::from(b.first().copied().unwrap_or(0)),
        (C::U8, true) => f32::from(b.first().copied().unwrap_or(0)) / 255.0,
        (C::I8, false) => f32::from(i8::from_le_bytes(le(b))),
        (C::I8, true) => (f32::from(i8::from_le_bytes(le(b))) / 127.0).max(-1.0),
        (C::U16, false) => f32::from(u16::from_le_bytes(le(b))),
        (C::U16, true) => f32::from(u16::from_le_bytes(le(b))) / 65535.0,
        (C::I16, false) => f32::from(i16::from_le_bytes(le(b))),
        (C::I16, true) => (f32::from(i16::from_le_bytes(le(b))) / 32767.0).max(-1.0),
        (C::U32, _) => u32::from_le_bytes(le(b)) as f32,
    }
}

/// An unsigned integer component as a `u32`.
fn decode_u32(b: &[u8], c: C, _normalized: bool) -> u32 {
    match c {
        C::U8 => u32::from(b.first().copied().unwrap_or(0)),
        C::U16 => u32::from(u16::from_le_bytes(le(b))),
        _ => u32::from_le_bytes(le(b)),
    }
}

/// An element type as glTF spells it.
fn type_name(t: Type) -> &'static str {
    match t {
        Type::Scalar => "SCALAR",
        Type::Vec2 => "VEC2",
        Type::Vec3 => "VEC3",
        Type::Vec4 => "VEC4",
        Type::Mat2 => "MAT2",
        Type::Mat3 => "MAT3",
        Type::Mat4 => "MAT4",
    }
}

/// A component type as glTF spells it, with `normalized`.
fn component_name(c: C, normalized: bool) -> String {
    let name = match c {
        C::I8 => "BYTE",
        C::U8 => "UNSIGNED_BYTE",
        C::I16 => "SHORT",
        C::U16 => "UNSIGNED_SHORT",
        C::U32 => "UNSIGNED_INT",
        C::F32 => "FLOAT",
    };
    if normalized {
        format!("normalized {name}")
    } else {
        name.to_string()
    }
}
