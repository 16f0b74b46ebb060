// The scene, group 0: the tables of src/render/tables.rs `RenderScene`, uploaded as they are
// (src/render/gpu/tables.rs).
//
// Each table is read as texels of an Rgba32Uint texture, row-major, TABLE_WIDTH texels a
// row: a texel fetch is a cheap gather on every device, while lavapipe (Mesa 22.3) lowers
// each storage-buffer load with a varying index to a loop over the SIMD lanes. Texels also
// lift the per-binding size cap of storage buffers (128 MiB on lavapipe).
@group(0) @binding(0) var<uniform> params: Params;
// The table bindings (1, 2, …) and their loaders, load_node(i) and the like, are generated
// from the Rust list of tables and the Rust structs' layouts (src/render/gpu/tables.rs
// `TABLES`, `wgsl_tables`).

// The claims a trusted module rests on (src/render/gpu/shader.rs `ShaderChecks`) that a
// checked one (SHADER_CHECKS, generated) tests where it relies on them: each that fails
// counts here, and the render kernel reports the count. A trusted module compiles the
// calls away.
var<private> check_failures: u32;

fn check(ok: bool) {
    if SHADER_CHECKS && !ok {
        check_failures += 1u;
    }
}

// Texel i of a table, TABLE_WIDTH_LOG2 being generated from the Rust TABLE_WIDTH.
fn table_texel(t: texture_2d<u32>, i: u32) -> vec4<u32> {
    if SHADER_CHECKS {
        let size = textureDimensions(t);
        check(i < size.x * size.y);
    }
    return textureLoad(t, vec2<u32>(i & ((1u << TABLE_WIDTH_LOG2) - 1u), i >> TABLE_WIDTH_LOG2), 0);
}
