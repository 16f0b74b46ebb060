// Structs shared with the host. Each mirrors a #[repr(C)] Pod struct in Rust;
// tests/layout.rs checks sizes and offsets against naga's layout of this file. The
// constants shared with Rust (DIM_*, MAT_*, T_INF, …) are generated before this file
// (src/render/gpu/shader.rs `shared_constants`).

// mirror: src/bvh/mod.rs `BvhNode` (32 bytes). Interior (count == 0): children at
// index + 1 and left_or_first. Leaf: triangles left_or_first .. left_or_first + count.
struct BvhNode {
    min: vec3<f32>,
    left_or_first: u32,
    max: vec3<f32>,
    count: u32,
}

// mirror: src/render/tables.rs `TriShading` (48 bytes)
struct TriShading {
    n0: vec3<f32>,
    material: u32,
    n1: vec3<f32>,
    emitter_pmf: f32,
    n2: vec3<f32>,
    flags: u32,
}

// mirror: src/render/tables.rs `TriTangents` (48 bytes): each corner's unit tangent and its
// bitangent's handedness (w = ±1).
struct TriTangents {
    t0: vec4<f32>,
    t1: vec4<f32>,
    t2: vec4<f32>,
}

// mirror: src/render/tables.rs `TriUvs` (32 bytes): texture coordinates, v running down.
struct TriUvs {
    uv0: vec2<f32>,
    uv1: vec2<f32>,
    uv2: vec2<f32>,
    _pad0: u32,
    _pad1: u32,
}

// mirror: src/render/tables.rs `TriColors` (48 bytes): each corner's vertex colour, linear
// RGBA.
struct TriColors {
    c0: vec4<f32>,
    c1: vec4<f32>,
    c2: vec4<f32>,
}

// mirror: src/scene/texture.rs `Texture` (64 bytes): an image in the texel table, its
// format (a TEX_* code), the UV map uv_matrix (rows: xy, zw) · uv + uv_offset, the
// channel a scalar parameter reads, the WRAP_* codes along u (low byte) and v, and the
// texture coordinate set a surface lookup reads (0 or 1).
struct Texture {
    offset: u32,
    width: u32,
    height: u32,
    format: u32,
    uv_matrix: vec4<f32>,
    uv_offset: vec2<f32>,
    channel: u32,
    wrap: u32,
    uv_set: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// mirror: src/render/tables.rs `Light` (80 bytes): a light that is not a surface; kind is a
// LIGHT_* code.
struct Light {
    position: vec3<f32>,
    kind: u32,
    direction: vec3<f32>,
    cos_cutoff: f32,
    intensity: vec3<f32>,
    cos_beam: f32,
    cutoff: f32,
    inv_transition: f32,
    shadows: u32,
    area: f32,
    edge: vec3<f32>,
    // The probability that next event estimation picks the light (0 where it does not).
    pmf: f32,
}

// mirror: src/render/tables.rs `CausticTarget` (16 bytes): a sphere around specular
// geometry, which light subpaths aim at.
struct CausticTarget {
    center: vec3<f32>,
    radius: f32,
}

// mirror: src/render/gpu/params.rs `Params` (256 bytes): one dispatch's camera, sky and range.
struct Params {
    cam_position: vec3<f32>,
    width: u32,
    cam_forward: vec3<f32>,
    height: u32,
    cam_right: vec3<f32>,
    max_depth: u32,
    cam_up: vec3<f32>,
    seed: u32,
    sky_zenith: vec3<f32>,
    // SKY_CONSTANT (`sky_zenith`), SKY_GRADIENT (from `sky_horizon` to `sky_zenith`) or
    // SKY_ENVIRONMENT (the env_* fields).
    sky_kind: u32,
    sky_horizon: vec3<f32>,
    num_emitters: u32,
    tan_half_vfov: f32,
    aspect: f32,
    aperture: f32,
    focus_distance: f32,
    // This dispatch traces samples sample_start .. sample_end of rows row_start .. row_end.
    sample_start: u32,
    sample_end: u32,
    row_start: u32,
    row_end: u32,
    // Probability that light sampling picks the sky (RenderScene::sky_pmf on the host).
    sky_pmf: f32,
    // Texels per pixel of the accumulation buffer: radiance, then one per film channel.
    film_texels: u32,
    // The environment map: its texture record, strength, the cosine and sine of its
    // rotation about +Y, and its cells along u and v (src/render/tables.rs `Environment`).
    env_texture: u32,
    env_strength: f32,
    env_rotation: vec2<f32>,
    env_cells: vec2<u32>,
    // The AOVs the film holds (AOV_* bits), and 1 if camera rays that miss add no radiance
    // (a transparent render); set with the film.
    aovs: u32,
    transparent: u32,
    // Spheres in the caustic targets table; 0 traces no light subpaths.
    num_caustic_targets: u32,
    // The branches of each camera sample at its first hit, and 1 / branches as the host
    // computes it (src/render/integrator.rs `branch_weight`).
    branches: u32,
    // A sphere around every triangle, outside which a directional light's light subpaths
    // start.
    scene_center: vec3<f32>,
    scene_radius: f32,
    branch_weight: f32,
    // Half an orthographic camera's view height; 0 for a perspective camera.
    ortho_half_height: f32,
    // RenderScene::lights_in_full: the first lights that next event estimation samples at
    // every vertex.
    lights_in_full: u32,
    // The width in pixels of the square over which a pixel's camera samples fall.
    filter_width: f32,
    // The pixels [x0, x1) × [y0, y1) whose camera rays may meet the scene.
    window: vec4<u32>,
    // The lights in the lights table, and the index of the first rectangle among them
    // (RenderScene::first_rect_light): BSDF-sampled rays test those from there on.
    num_lights: u32,
    first_rect_light: u32,
    // The diffuse, glossy and transmission scatterings a path may take: each bounce limit
    // plus one, or the largest u32 for none (src/scene/settings.rs `BounceLimits`).
    diffuse_bounces: u32,
    glossy_bounces: u32,
    transmission_bounces: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}


// A leaf-order triangle index that stands for "no hit" (T_INF, the largest finite float,
// stands for "no hit" and "unbounded ray": WGSL has no infinity literal).
const NO_HIT: u32 = 0xffffffffu;
