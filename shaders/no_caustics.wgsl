// The caustics library of a render kernel for a scene without caustic targets: the types and
// functions the integrator and the render kernel name, none of which does anything, in
// place of caustics.wgsl (src/render/gpu/shader.rs `render_source_without_caustics`).
// Such a scene traces no light subpath (params.num_caustic_targets is 0), so the kernel is
// the same program; without caustics.wgsl's code it compiles in well under half the time,
// and holds no registers for light vertices.

const CAUSTICS: bool = false;

struct LightVertex {
    si: SurfaceHit,
    wi: vec3<f32>,
    beta: vec3<f32>,
    pdf: f32,
    segments: u32,
}

struct LightPath {
    vertices: array<LightVertex, MAX_CAUSTIC_HOPS>,
    count: u32,
}

fn no_light_path() -> LightPath {
    var path: LightPath;
    return path;
}

struct TracedLight {
    path: LightPath,
    rays: u32,
}

fn trace_light_subpath(rng: Rng, max_segments: u32) -> TracedLight {
    return TracedLight(no_light_path(), 0u);
}

struct CausticLink {
    ray: Ray,
    t_max: f32,
    value: vec3<f32>,
    valid: bool,
}

fn caustic_link(si: SurfaceHit, mat: Material, frame: ShadingFrame, wo_world: vec3<f32>, wo: vec3<f32>, lv: LightVertex) -> CausticLink {
    var link: CausticLink;
    return link;
}

fn caustic_hit_weight(pmf: f32, area: f32, p: vec3<f32>, dir: vec3<f32>, cos_l: f32, pdf_bsdf: f32) -> f32 {
    return 1.0;
}

fn camera_pdf(dir: vec3<f32>) -> f32 {
    return 0.0;
}

struct CameraLink {
    pixel: u32,
    ray: Ray,
    t_max: f32,
    value: vec3<f32>,
    valid: bool,
}

fn camera_link(lv: LightVertex, u_lens: vec2<f32>) -> CameraLink {
    var link: CameraLink;
    return link;
}
