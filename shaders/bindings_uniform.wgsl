// The scene, group 0, for small scenes on software adapters: the same tables as
// bindings.wgsl, read through the same functions, but packed one after another into a
// single uniform array. On lavapipe a uniform load with a varying index is a plain
// gather, several times cheaper than the texel fetch with its sampler set-up; on GPUs,
// textures stay (src/gpu/renderer.rs `TableStorage`).
//
// Texel 0 holds the first texels of nodes, triangles, shading data and materials;
// texel 1 those of the emitters and the emitter CDF.
@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<uniform> tables: array<vec4<u32>, UNIFORM_TABLE_TEXELS>;

// mirror: src/gpu/renderer.rs `UNIFORM_TABLE_TEXELS`
const UNIFORM_TABLE_TEXELS: u32 = 4096u;

// BvhNode i: 2 texels.
fn load_node(i: u32) -> BvhNode {
    let a = tables[tables[0].x + 2u * i];
    let b = tables[tables[0].x + 2u * i + 1u];
    return BvhNode(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), b.w);
}

// TriVerts i: 3 texels.
fn load_tri(i: u32) -> TriVerts {
    let t = tables[0].y + 3u * i;
    return TriVerts(
        bitcast<vec4<f32>>(tables[t]),
        bitcast<vec4<f32>>(tables[t + 1u]),
        bitcast<vec4<f32>>(tables[t + 2u]),
    );
}

// TriShading i: 3 texels.
fn load_shading(i: u32) -> TriShading {
    let t = tables[0].z + 3u * i;
    let a = tables[t];
    let b = tables[t + 1u];
    let c = tables[t + 2u];
    return TriShading(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), bitcast<f32>(b.w), bitcast<vec3<f32>>(c.xyz), c.w);
}

// Material i: 3 texels.
fn load_material(i: u32) -> Material {
    let t = tables[0].w + 3u * i;
    let a = tables[t];
    let b = tables[t + 1u];
    let c = tables[t + 2u];
    return Material(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), bitcast<f32>(b.w), bitcast<f32>(c.x), c.y, c.z, c.w);
}

// Emitter k (a leaf-order triangle or SKY_EMITTER): 4 to a texel.
fn load_emitter(k: u32) -> u32 {
    return tables[tables[1].x + (k >> 2u)][k & 3u];
}

// The emitter CDF's entry k: 4 to a texel.
fn load_emitter_cdf(k: u32) -> f32 {
    return bitcast<f32>(tables[tables[1].y + (k >> 2u)][k & 3u]);
}
