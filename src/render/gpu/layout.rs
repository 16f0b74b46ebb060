//! The host-shared structs as the shader generator sees them: each `#[repr(C)]` Pod struct
//! that the GPU reads, described member by member from the Rust definition itself (names,
//! byte offsets by `offset_of!`, WGSL types from the Rust field types). The table loaders
//! of `shaders/` are generated from these descriptions (`tables.rs`), and
//! `tests/layout.rs` checks each against naga's layout of its WGSL twin in
//! `shaders/types.wgsl`, so no third copy of a layout is kept by hand.

use crate::scene::{MaterialKind, TextureFormat};
use glam::Vec3;

/// A Rust field type and the WGSL type it is uploaded as.
pub trait WgslType {
    const WGSL: &'static str;
}

impl WgslType for u32 {
    const WGSL: &'static str = "u32";
}

impl WgslType for f32 {
    const WGSL: &'static str = "f32";
}

impl WgslType for [f32; 3] {
    const WGSL: &'static str = "vec3<f32>";
}

impl WgslType for Vec3 {
    const WGSL: &'static str = "vec3<f32>";
}

impl WgslType for [f32; 2] {
    const WGSL: &'static str = "vec2<f32>";
}

impl WgslType for [f32; 4] {
    const WGSL: &'static str = "vec4<f32>";
}

impl WgslType for MaterialKind {
    const WGSL: &'static str = "u32";
}

impl WgslType for TextureFormat {
    const WGSL: &'static str = "u32";
}

impl<const N: usize> WgslType for [u32; N] {
    const WGSL: &'static str = "padding";
}

/// One member of a host-shared struct.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Member {
    pub name: &'static str,
    /// Its WGSL type (`padding` for an array of padding words).
    pub wgsl: &'static str,
    pub offset: usize,
    pub size: usize,
}

/// A host-shared struct: its name (the same in Rust and WGSL), size and members in
/// declaration order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StructLayout {
    pub name: &'static str,
    pub size: usize,
    pub members: Vec<Member>,
}

/// The member `name` at `offset` whose type `get` returns.
#[doc(hidden)]
pub fn member<T, F: WgslType>(name: &'static str, offset: usize, _get: fn(&T) -> &F) -> Member {
    Member {
        name,
        wgsl: F::WGSL,
        offset,
        size: size_of::<F>(),
    }
}

/// The [`StructLayout`] of Rust struct `$t`, whose fields must all be listed: the
/// destructuring pattern fails to compile when one is missing.
macro_rules! struct_layout {
    ($t:ident { $($f:ident),* $(,)? }) => {{
        let _every_field_listed = |x: $t| {
            let $t { $($f: _),* } = x;
        };
        $crate::render::gpu::layout::StructLayout {
            name: stringify!($t),
            size: size_of::<$t>(),
            members: vec![$(
                $crate::render::gpu::layout::member::<$t, _>(
                    stringify!($f),
                    std::mem::offset_of!($t, $f),
                    |x: &$t| &x.$f,
                )
            ),*],
        }
    }};
}
pub(crate) use struct_layout;
