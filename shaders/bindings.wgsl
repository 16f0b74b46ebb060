// The scene, group 0: the tables of src/render/mod.rs `RenderScene`, uploaded as they are
// (src/render/gpu/tables.rs).
//
// Each table is read as texels of an Rgba32Uint texture, row-major, TABLE_WIDTH texels a
// row: a texel fetch is a cheap gather on every device, while lavapipe (Mesa 22.3) lowers
// each storage-buffer load with a varying index to a loop over the SIMD lanes. Texels also
// lift the per-binding size cap of storage buffers (128 MiB on lavapipe).
@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var nodes_tex: texture_2d<u32>;
@group(0) @binding(2) var tris_tex: texture_2d<u32>;
@group(0) @binding(3) var shading_tex: texture_2d<u32>;
@group(0) @binding(4) var materials_tex: texture_2d<u32>;
@group(0) @binding(5) var emitters_tex: texture_2d<u32>;
@group(0) @binding(6) var emitter_cdf_tex: texture_2d<u32>;

// mirror: src/render/gpu/tables.rs `TABLE_WIDTH`
const TABLE_WIDTH_LOG2: u32 = 12u;

fn table_texel(t: texture_2d<u32>, i: u32) -> vec4<u32> {
    return textureLoad(t, vec2<u32>(i & ((1u << TABLE_WIDTH_LOG2) - 1u), i >> TABLE_WIDTH_LOG2), 0);
}

// BvhNode i: 2 texels.
fn load_node(i: u32) -> BvhNode {
    let a = table_texel(nodes_tex, 2u * i);
    let b = table_texel(nodes_tex, 2u * i + 1u);
    return BvhNode(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), b.w);
}

// TriVerts i: 3 texels.
fn load_tri(i: u32) -> TriVerts {
    return TriVerts(
        bitcast<vec4<f32>>(table_texel(tris_tex, 3u * i)),
        bitcast<vec4<f32>>(table_texel(tris_tex, 3u * i + 1u)),
        bitcast<vec4<f32>>(table_texel(tris_tex, 3u * i + 2u)),
    );
}

// TriShading i: 3 texels.
fn load_shading(i: u32) -> TriShading {
    let a = table_texel(shading_tex, 3u * i);
    let b = table_texel(shading_tex, 3u * i + 1u);
    let c = table_texel(shading_tex, 3u * i + 2u);
    return TriShading(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), bitcast<f32>(b.w), bitcast<vec3<f32>>(c.xyz), c.w);
}

// Material i: 3 texels.
fn load_material(i: u32) -> Material {
    let a = table_texel(materials_tex, 3u * i);
    let b = table_texel(materials_tex, 3u * i + 1u);
    let c = table_texel(materials_tex, 3u * i + 2u);
    return Material(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), bitcast<f32>(b.w), bitcast<f32>(c.x), c.y, c.z, c.w);
}

// Emitter k (a leaf-order triangle or SKY_EMITTER): 4 to a texel.
fn load_emitter(k: u32) -> u32 {
    return table_texel(emitters_tex, k >> 2u)[k & 3u];
}

// The emitter CDF's entry k: 4 to a texel.
fn load_emitter_cdf(k: u32) -> f32 {
    return bitcast<f32>(table_texel(emitter_cdf_tex, k >> 2u)[k & 3u]);
}
