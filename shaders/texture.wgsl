// Texture lookups. mirror: src/render/texture.rs — every function has a Rust twin of the
// same name.

// Whether the scene has textures and alpha masks, set per pipeline from the scene
// (src/render/gpu/shader.rs `Features`). Off, the code that reads them compiles out of the
// kernel, which changes no result: a scene without textures has no texture slot to look
// up, and one without alpha masks no masked triangle. (The Rust twins need no such switch:
// a branch the CPU never takes costs it next to nothing.)
override TEXTURES: bool = true;
override ALPHA_MASKS: bool = true;

// mirror: src/render/texture.rs `texel`
fn texel(t: Texture, x: u32, y: u32) -> vec4<f32> {
    let i = y * t.width + x;
    if t.format == TEX_RGBA32F {
        let k = t.offset + 4u * i;
        return vec4<f32>(
            bitcast<f32>(load_texel(k)),
            bitcast<f32>(load_texel(k + 1u)),
            bitcast<f32>(load_texel(k + 2u)),
            bitcast<f32>(load_texel(k + 3u)),
        );
    }
    let w = load_texel(t.offset + i);
    let colour = select(256u, 0u, t.format == TEX_RGBA8_SRGB);
    return vec4<f32>(
        load_texel_lut(colour + (w & 255u)),
        load_texel_lut(colour + ((w >> 8u) & 255u)),
        load_texel_lut(colour + ((w >> 16u) & 255u)),
        load_texel_lut(256u + (w >> 24u)),
    );
}

// The texels a bilinear lookup blends along one axis, and the weight of the second.
struct TexelSpan {
    a: u32,
    b: u32,
    f: f32,
}

// mirror: src/render/texture.rs `texel_span`
fn texel_span(s: f32, size: u32, mode: u32) -> TexelSpan {
    check(size > 0u);
    let n = i32(size);
    if mode == WRAP_CLAMP {
        let x = clamp(s, 0.0, 1.0) * f32(size) - 0.5;
        let x0 = floor(x);
        let i = i32(x0);
        return TexelSpan(u32(clamp(i, 0, n - 1)), u32(clamp(i + 1, 0, n - 1)), x - x0);
    }
    if mode == WRAP_MIRROR {
        let f = s - 2.0 * floor(s * 0.5);
        let x = f * f32(size) - 0.5;
        let x0 = floor(x);
        let a = (i32(x0) + 2 * n) % (2 * n);
        let b = (a + 1) % (2 * n);
        let ma = select(2 * n - 1 - a, a, a < n);
        let mb = select(2 * n - 1 - b, b, b < n);
        return TexelSpan(u32(ma), u32(mb), x - x0);
    }
    let f = s - floor(s);
    let x = f * f32(size) - 0.5;
    let x0 = floor(x);
    let a = u32((i32(x0) + n) % n);
    return TexelSpan(a, (a + 1u) % size, x - x0);
}

// mirror: src/render/texture.rs `texture_lookup`
fn texture_lookup(index: u32, uv: vec2<f32>) -> vec4<f32> {
    let t = load_texture(index);
    let m = t.uv_matrix;
    let s = vec2<f32>(m.x * uv.x + m.y * uv.y + t.uv_offset.x, m.z * uv.x + m.w * uv.y + t.uv_offset.y);
    let x = texel_span(s.x, t.width, t.wrap & 255u);
    let y = texel_span(s.y, t.height, t.wrap >> 8u);
    let top = texel(t, x.a, y.a) * (1.0 - x.f) + texel(t, x.b, y.a) * x.f;
    let bottom = texel(t, x.a, y.b) * (1.0 - x.f) + texel(t, x.b, y.b) * x.f;
    return top * (1.0 - y.f) + bottom * y.f;
}

// mirror: src/render/texture.rs `triangle_uv`
fn triangle_uv(tri: u32, b1: f32, b2: f32) -> vec4<f32> {
    let flags = load_shading(tri).flags;
    var first = vec2<f32>(0.0);
    if (flags & TRI_UV) != 0u {
        let t = load_tri_uvs(tri);
        first = (1.0 - b1 - b2) * t.uv0 + b1 * t.uv1 + b2 * t.uv2;
    }
    var second = vec2<f32>(0.0);
    if (flags & TRI_UV1) != 0u {
        let t = load_tri_uvs1(tri);
        second = (1.0 - b1 - b2) * t.uv0 + b1 * t.uv1 + b2 * t.uv2;
    }
    return vec4<f32>(first, second);
}

// mirror: src/render/texture.rs `triangle_color`
fn triangle_color(tri: u32, b1: f32, b2: f32) -> vec4<f32> {
    if (load_shading(tri).flags & TRI_COLOR) == 0u {
        return vec4<f32>(1.0);
    }
    let c = load_tri_colors(tri);
    return (1.0 - b1 - b2) * c.c0 + b1 * c.c1 + b2 * c.c2;
}

// mirror: src/render/texture.rs `surface_lookup`
fn surface_lookup(index: u32, uv: vec4<f32>) -> vec4<f32> {
    let st = select(uv.xy, uv.zw, load_texture(index).uv_set == 1u);
    return texture_lookup(index, st);
}

// mirror: src/render/texture.rs `scalar_lookup`
fn scalar_lookup(index: u32, uv: vec4<f32>) -> f32 {
    let channel = load_texture(index).channel;
    check(channel < 4u);
    return surface_lookup(index, uv)[channel];
}

// mirror: src/render/texture.rs `material_at`
fn material_at(m: Material, uv: vec4<f32>, color: vec4<f32>) -> Material {
    var out = m;
    out.albedo *= color.xyz;
    if !TEXTURES {
        return out;
    }
    out.albedo = textured_colour(m.albedo_texture, uv, out.albedo);
    out.emission = textured_colour(m.emission_texture, uv, m.emission);
    if m.roughness_texture != NO_TEXTURE && (m.flags & MAT_SPEC_GLOSS) != 0u {
        let g = scalar_lookup(m.roughness_texture, uv);
        out.roughness = clamp(1.0 - (1.0 - m.roughness) * g, 0.0, 1.0);
    } else {
        out.roughness = textured_scalar(m.roughness_texture, uv, m.roughness);
    }
    out.metallic = textured_scalar(m.metallic_texture, uv, m.metallic);
    out.transmission = textured_scalar(m.transmission_texture, uv, m.transmission);
    out.specular_color = textured_colour(m.specular_color_texture, uv, m.specular_color);
    out.specular = textured_scalar(m.specular_texture, uv, m.specular);
    out.clearcoat = textured_scalar(m.clearcoat_texture, uv, m.clearcoat);
    out.clearcoat_roughness = textured_scalar(m.clearcoat_roughness_texture, uv, m.clearcoat_roughness);
    out.sheen_color = textured_colour(m.sheen_color_texture, uv, m.sheen_color);
    out.sheen_roughness = textured_scalar(m.sheen_roughness_texture, uv, m.sheen_roughness);
    return out;
}

// mirror: src/render/texture.rs `textured_colour`
fn textured_colour(slot: u32, uv: vec4<f32>, value: vec3<f32>) -> vec3<f32> {
    if slot == NO_TEXTURE {
        return value;
    }
    return value * surface_lookup(slot, uv).xyz;
}

// mirror: src/render/texture.rs `textured_scalar`
fn textured_scalar(slot: u32, uv: vec4<f32>, value: f32) -> f32 {
    if slot == NO_TEXTURE {
        return value;
    }
    return clamp(value * scalar_lookup(slot, uv), 0.0, 1.0);
}

// mirror: src/render/texture.rs `normal_mapped`
fn normal_mapped(hit: Hit, uv: vec4<f32>, n: vec3<f32>, ng: vec3<f32>, map: u32, scale: f32) -> vec3<f32> {
    if !TEXTURES {
        return n;
    }
    let g = load_tri_tangents(hit.tri);
    let w = 1.0 - hit.u - hit.v;
    let t4 = w * g.t0 + hit.u * g.t1 + hit.v * g.t2;
    let tr = t4.xyz - n * dot(n, t4.xyz);
    let tlen2 = dot(tr, tr);
    if !(tlen2 > 0.0) {
        return n;
    }
    let t = tr * inverseSqrt(tlen2);
    let b = select(cross(n, t), -cross(n, t), t4.w < 0.0);
    let c = surface_lookup(map, uv).xyz * 2.0 - vec3<f32>(1.0);
    let p = t * (c.x * scale) + b * (c.y * scale) + n * c.z;
    let plen2 = dot(p, p);
    if !(plen2 > 0.0) {
        return n;
    }
    let mapped = p * inverseSqrt(plen2);
    if dot(mapped, ng) <= 0.0 {
        return n;
    }
    return mapped;
}

// mirror: src/render/texture.rs `alpha_test`
fn alpha_test(tri: u32, b1: f32, b2: f32, camera: bool) -> bool {
    if !ALPHA_MASKS {
        return true;
    }
    let m = load_material(load_shading(tri).material);
    if m.kind == MAT_UNLIT && !camera {
        return false;
    }
    if (m.flags & MAT_ALPHA_MASK) == 0u {
        return true;
    }
    var alpha = m.alpha * triangle_color(tri, b1, b2).w;
    if TEXTURES && m.albedo_texture != NO_TEXTURE {
        let uv = triangle_uv(tri, b1, b2);
        alpha *= surface_lookup(m.albedo_texture, uv).w;
    }
    return alpha >= m.alpha_cutoff;
}
