//! Texture lookups, the same on both renderers: texels decoded through one table
//! ([`RenderScene::texel_lut`]) for 8-bit images, bilinear filtering with repeat, clamp or
//! mirror wrapping, the texture coordinate sets and vertex colours of a surface point,
//! and materials whose textured parameters (and vertex-coloured base colour) are
//! evaluated there. Every function has a WGSL twin of the same name in
//! `shaders/texture.wgsl`.

use super::tables::{RenderScene, TRI_COLOR, TRI_UV, TRI_UV1, TriUvs};
use crate::bvh::Hit;
use crate::scene::material::{MAT_ALPHA_MASK, MAT_SPEC_GLOSS};
use crate::scene::{Material, MaterialKind, NO_TEXTURE, Texture, TextureFormat, Wrap};
use glam::{Vec2, Vec3, Vec4};

/// Texel (`x`, `y`) of texture `t`, decoded to linear RGBA: 8-bit channels through the
/// decoding table (sRGB for colour formats, alpha always linear), floats as stored.
/// mirror: shaders/texture.wgsl `texel`
pub fn texel(scene: &RenderScene, t: &Texture, x: u32, y: u32) -> Vec4 {
    let i = (y * t.width + x) as usize;
    let k = t.offset as usize;
    if t.format == TextureFormat::RGBA32F {
        let w = &scene.texels[k + 4 * i..k + 4 * i + 4];
        return Vec4::new(
            f32::from_bits(w[0]),
            f32::from_bits(w[1]),
            f32::from_bits(w[2]),
            f32::from_bits(w[3]),
        );
    }
    let w = scene.texels[k + i];
    let colour = if t.format == TextureFormat::RGBA8_SRGB {
        0
    } else {
        256
    };
    let lut = |byte: u32, base: u32| scene.texel_lut[(base + (byte & 255)) as usize];
    Vec4::new(
        lut(w, colour),
        lut(w >> 8, colour),
        lut(w >> 16, colour),
        lut(w >> 24, 256),
    )
}

/// The two texels a bilinear lookup blends along one axis of `size` texels, and the
/// weight of the second, at coordinate `s` (1 spans the image) wrapped by `mode`:
/// repeating, clamped to the edge texels, or repeating with every other copy mirrored.
/// mirror: shaders/texture.wgsl `texel_span`
pub fn texel_span(s: f32, size: u32, mode: u32) -> (u32, u32, f32) {
    let n = size as i32;
    if mode == Wrap::CLAMP.0 {
        // Beyond the edge every coordinate reads the edge texel, so clamping first also
        // keeps the integer conversion in range.
        let x = s.clamp(0.0, 1.0) * size as f32 - 0.5;
        let x0 = x.floor();
        let i = x0 as i32;
        return (
            i.clamp(0, n - 1) as u32,
            (i + 1).clamp(0, n - 1) as u32,
            x - x0,
        );
    }
    if mode == Wrap::MIRROR.0 {
        // One period is the image and its mirror image: 2 · size texels.
        let f = s - 2.0 * (s * 0.5).floor();
        let x = f * size as f32 - 0.5;
        let x0 = x.floor();
        let a = (x0 as i32 + 2 * n) % (2 * n);
        let b = (a + 1) % (2 * n);
        let mirror = |i: i32| (if i < n { i } else { 2 * n - 1 - i }) as u32;
        return (mirror(a), mirror(b), x - x0);
    }
    // Only the fractional part matters, which also keeps the integer conversions in range
    // for any finite coordinate.
    let f = s - s.floor();
    let x = f * size as f32 - 0.5;
    let x0 = x.floor();
    let a = ((x0 as i32 + n) % n) as u32;
    (a, (a + 1) % size, x - x0)
}

/// Texture `index` at `uv` (v running down from the image's top edge), mapped by the
/// texture's UV transform: bilinear between the four nearest texel centres, wrapped along
/// u and v by the texture's modes.
/// mirror: shaders/texture.wgsl `texture_lookup`
pub fn texture_lookup(scene: &RenderScene, index: u32, uv: Vec2) -> Vec4 {
    let t = &scene.textures[index as usize];
    let m = &t.uv_matrix;
    let s = Vec2::new(
        m[0] * uv.x + m[1] * uv.y + t.uv_offset[0],
        m[2] * uv.x + m[3] * uv.y + t.uv_offset[1],
    );
    let (xa, xb, fx) = texel_span(s.x, t.width, t.wrap & 255);
    let (ya, yb, fy) = texel_span(s.y, t.height, t.wrap >> 8);
    let top = texel(scene, t, xa, ya) * (1.0 - fx) + texel(scene, t, xb, ya) * fx;
    let bottom = texel(scene, t, xa, yb) * (1.0 - fx) + texel(scene, t, xb, yb) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// The texture coordinates of triangle `tri` at barycentrics (`b1`, `b2`) of its second
/// and third corners: xy its first set, zw its second (glTF's `TEXCOORD_1`); zero for a
/// set the triangle lacks.
/// mirror: shaders/texture.wgsl `triangle_uv`
pub fn triangle_uv(scene: &RenderScene, tri: u32, b1: f32, b2: f32) -> Vec4 {
    let flags = scene.shading[tri as usize].flags;
    let at = |t: &TriUvs| {
        (1.0 - b1 - b2) * Vec2::from(t.uv0) + b1 * Vec2::from(t.uv1) + b2 * Vec2::from(t.uv2)
    };
    let first = if flags & TRI_UV != 0 {
        at(&scene.tri_uvs[tri as usize])
    } else {
        Vec2::ZERO
    };
    let second = if flags & TRI_UV1 != 0 {
        at(&scene.tri_uvs1[tri as usize])
    } else {
        Vec2::ZERO
    };
    Vec4::new(first.x, first.y, second.x, second.y)
}

/// The vertex colour of triangle `tri` at barycentrics (`b1`, `b2`) of its second and
/// third corners (linear RGBA); white, alpha 1, for a triangle without colours.
/// mirror: shaders/texture.wgsl `triangle_color`
pub fn triangle_color(scene: &RenderScene, tri: u32, b1: f32, b2: f32) -> Vec4 {
    if scene.shading[tri as usize].flags & TRI_COLOR == 0 {
        return Vec4::ONE;
    }
    let c = &scene.tri_colors[tri as usize];
    (1.0 - b1 - b2) * Vec4::from(c.c0) + b1 * Vec4::from(c.c1) + b2 * Vec4::from(c.c2)
}

/// Texture `index` at a surface point whose texture coordinate sets are `uv` (xy the
/// first, zw the second, as [`triangle_uv`] gives them): the set its record names.
/// mirror: shaders/texture.wgsl `surface_lookup`
pub fn surface_lookup(scene: &RenderScene, index: u32, uv: Vec4) -> Vec4 {
    let st = if scene.textures[index as usize].uv_set == 1 {
        Vec2::new(uv.z, uv.w)
    } else {
        Vec2::new(uv.x, uv.y)
    };
    texture_lookup(scene, index, st)
}

/// Texture `index` at a surface point whose texture coordinate sets are `uv`, read as a
/// number: the channel its record names.
/// mirror: shaders/texture.wgsl `scalar_lookup`
pub fn scalar_lookup(scene: &RenderScene, index: u32, uv: Vec4) -> f32 {
    let channel = scene.textures[index as usize].channel as usize;
    surface_lookup(scene, index, uv)[channel]
}

/// `m` at a surface point whose texture coordinate sets are `uv` and whose vertex colour
/// is `color`: its base colour multiplied by the colour's RGB (glTF's `COLOR_0`; white
/// leaves it as it is), and every textured parameter multiplied by its texture (roughness
/// by glossiness, where [`MAT_SPEC_GLOSS`] says the texture holds it: 1 − (1 − r) g). A
/// material without textures, at white, is returned as it is. Scalar parameters stay
/// within [0, 1].
/// mirror: shaders/texture.wgsl `material_at`
pub fn material_at(scene: &RenderScene, m: &Material, uv: Vec4, color: Vec4) -> Material {
    let mut out = *m;
    out.albedo = textured_colour(scene, m.albedo_texture, uv, m.albedo * color.truncate());
    out.emission = textured_colour(scene, m.emission_texture, uv, m.emission);
    if m.roughness_texture != NO_TEXTURE && m.flags & MAT_SPEC_GLOSS != 0 {
        // The texture holds glossiness, which scales 1 − roughness.
        let g = scalar_lookup(scene, m.roughness_texture, uv);
        out.roughness = (1.0 - (1.0 - m.roughness) * g).clamp(0.0, 1.0);
    } else {
        out.roughness = textured_scalar(scene, m.roughness_texture, uv, m.roughness);
    }
    out.metallic = textured_scalar(scene, m.metallic_texture, uv, m.metallic);
    out.transmission = textured_scalar(scene, m.transmission_texture, uv, m.transmission);
    out.specular_color = textured_colour(scene, m.specular_color_texture, uv, m.specular_color);
    out.specular = textured_scalar(scene, m.specular_texture, uv, m.specular);
    out.clearcoat = textured_scalar(scene, m.clearcoat_texture, uv, m.clearcoat);
    out.clearcoat_roughness = textured_scalar(
        scene,
        m.clearcoat_roughness_texture,
        uv,
        m.clearcoat_roughness,
    );
    out.sheen_color = textured_colour(scene, m.sheen_color_texture, uv, m.sheen_color);
    out.sheen_roughness = textured_scalar(scene, m.sheen_roughness_texture, uv, m.sheen_roughness);
    out
}

/// `value` times the RGB of texture `slot` at `uv`, or `value` where the slot holds none.
/// mirror: shaders/texture.wgsl `textured_colour`
pub fn textured_colour(scene: &RenderScene, slot: u32, uv: Vec4, value: Vec3) -> Vec3 {
    if slot == NO_TEXTURE {
        return value;
    }
    value * surface_lookup(scene, slot, uv).truncate()
}

/// `value` times texture `slot`'s channel at `uv`, kept within [0, 1]; `value` where the
/// slot holds none. mirror: shaders/texture.wgsl `textured_scalar`
pub fn textured_scalar(scene: &RenderScene, slot: u32, uv: Vec4, value: f32) -> f32 {
    if slot == NO_TEXTURE {
        return value;
    }
    (value * scalar_lookup(scene, slot, uv)).clamp(0.0, 1.0)
}

/// The shading normal that normal map `map` (of XY strength `scale`) gives at `hit` (its
/// triangle and barycentrics) with texture coordinate sets `uv`, around the unit
/// normal `n` (interpolated or geometric, on the side of `ng`): the map's tangent-space
/// normal (2 · texel − 1, its x and y scaled by `scale`) in the frame of the interpolated
/// tangent made orthogonal to `n` and the bitangent w · n × tangent. `n` itself where that
/// frame degenerates or the mapped normal would face away from `ng`.
/// mirror: shaders/texture.wgsl `normal_mapped`
pub fn normal_mapped(
    scene: &RenderScene,
    hit: &Hit,
    uv: Vec4,
    n: Vec3,
    ng: Vec3,
    map: u32,
    scale: f32,
) -> Vec3 {
    let g = &scene.tri_tangents[hit.tri as usize];
    let (b1, b2) = (hit.u, hit.v);
    let w = 1.0 - b1 - b2;
    let t4 = w * Vec4::from(g.t0) + b1 * Vec4::from(g.t1) + b2 * Vec4::from(g.t2);
    let t = (t4.truncate() - n * n.dot(t4.truncate())).normalize_or_zero();
    if t == Vec3::ZERO {
        return n;
    }
    let b = if t4.w < 0.0 { -n.cross(t) } else { n.cross(t) };
    let c = surface_lookup(scene, map, uv).truncate() * 2.0 - Vec3::ONE;
    let mapped = (t * (c.x * scale) + b * (c.y * scale) + n * c.z).normalize_or_zero();
    if mapped.dot(ng) <= 0.0 {
        return n;
    }
    mapped
}

/// Whether a hit at barycentrics (`b1`, `b2`) of triangle `tri` counts for a ray from the
/// camera (`camera`) or another: false on an unlit surface for any ray but the camera's,
/// and where the material is an alpha mask and the base colour's alpha (factor times the
/// vertex colour's alpha times the base colour texture's alpha) is below the cut-off, as
/// glTF's `alphaMode` MASK says.
/// mirror: shaders/texture.wgsl `alpha_test`
pub fn alpha_test(scene: &RenderScene, tri: u32, b1: f32, b2: f32, camera: bool) -> bool {
    let m = &scene.materials[scene.shading[tri as usize].material as usize];
    if m.kind == MaterialKind::UNLIT && !camera {
        return false;
    }
    if m.flags & MAT_ALPHA_MASK == 0 {
        return true;
    }
    let mut alpha = m.alpha * triangle_color(scene, tri, b1, b2).w;
    if m.albedo_texture != NO_TEXTURE {
        let uv = triangle_uv(scene, tri, b1, b2);
        alpha *= surface_lookup(scene, m.albedo_texture, uv).w;
    }
    alpha >= m.alpha_cutoff
}
