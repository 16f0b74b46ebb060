// The surface a ray finds, the origin of a ray leaving it and the frame its BSDF is
// evaluated in. mirror: src/render/surface.rs — every function has a Rust twin of the same
// name.

// mirror: src/render/surface.rs `SurfaceHit`
struct SurfaceHit {
    p: vec3<f32>,
    ng: vec3<f32>,
    ns: vec3<f32>,
    nc: vec3<f32>,
    material: u32,
    front_face: bool,
    tri: u32,
    uv: vec4<f32>,
    color: vec4<f32>,
}

// mirror: src/render/surface.rs `surface_at`
fn surface_at(ray: Ray, hit: Hit) -> SurfaceHit {
    let tri = load_tri(hit.tri);
    let sh = load_shading(hit.tri);
    let ng = geometric_normal(tri);
    var ns = ng;
    if (sh.flags & TRI_SMOOTH) != 0u {
        let w = 1.0 - hit.u - hit.v;
        let n = w * sh.n0 + hit.u * sh.n1 + hit.v * sh.n2;
        let len2 = dot(n, n);
        ns = select(vec3<f32>(0.0), n * inverseSqrt(len2), len2 > 0.0);
        if dot(ns, ng) < 0.0 {
            ns = -ns;
        }
        if all(ns == vec3<f32>(0.0)) {
            ns = ng;
        }
    }
    let uv = triangle_uv(hit.tri, hit.u, hit.v);
    var nc = ns;
    if (sh.flags & TRI_TANGENT) != 0u {
        let m = load_material(sh.material);
        let interpolated = ns;
        if m.normal_texture != NO_TEXTURE {
            ns = normal_mapped(hit, uv, interpolated, ng, m.normal_texture, m.normal_scale);
        }
        if m.clearcoat_normal_texture != NO_TEXTURE {
            nc = normal_mapped(hit, uv, interpolated, ng, m.clearcoat_normal_texture, m.clearcoat_normal_scale);
        }
    }
    return SurfaceHit(ray.origin + hit.t * ray.dir, ng, ns, nc, sh.material, dot(ray.dir, ng) < 0.0, hit.tri, uv, triangle_color(hit.tri, hit.u, hit.v));
}

// mirror: src/render/surface.rs `offset_ray_origin`
fn offset_ray_origin(p: vec3<f32>, ng: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    let ap = abs(p);
    let eps = 1e-5 * (1.0 + max(max(ap.x, ap.y), ap.z));
    return select(p - eps * ng, p + eps * ng, dot(w, ng) >= 0.0);
}

// The frame a BSDF is evaluated in at a hit, for light leaving along wo_world: m's columns
// are the tangent, bitangent and shading normal; ng the geometric normal, turned as the
// frame is. mirror: src/render/surface.rs `ShadingFrame`
struct ShadingFrame {
    m: mat3x3<f32>,
    ng: vec3<f32>,
}

// mirror: src/render/surface.rs `shading_frame`
fn shading_frame(mat: Material, si: SurfaceHit, wo_world: vec3<f32>) -> ShadingFrame {
    let two_sided = bsdf_is_two_sided(mat);
    let flip = two_sided && dot(wo_world, si.ng) < 0.0;
    let ng = select(si.ng, -si.ng, flip);
    var ns = select(si.ns, -si.ns, flip);
    if two_sided && dot(ns, wo_world) <= 0.0 {
        ns = ng;
    }
    return ShadingFrame(onb_from_normal(ns), ng);
}

// mirror: src/render/surface.rs `with_coat_normal`
fn with_coat_normal(mat: Material, si: SurfaceHit, frame: ShadingFrame) -> Material {
    var out = mat;
    var c = si.nc * frame.m;
    c = select(c, -c, c.z < 0.0);
    out.coat_normal = select(vec3<f32>(0.0, 0.0, 1.0), normalize(c), c.z > 1e-4);
    return out;
}

// mirror: src/render/surface.rs `needs_coat_normal`
fn needs_coat_normal(mat: Material) -> bool {
    return mat.clearcoat > 0.0 && (mat.normal_texture != NO_TEXTURE || mat.clearcoat_normal_texture != NO_TEXTURE);
}

// mirror: src/render/surface.rs `coated`
fn coated(mat: Material, si: SurfaceHit, frame: ShadingFrame) -> Material {
    if needs_coat_normal(mat) {
        return with_coat_normal(mat, si, frame);
    }
    return mat;
}

// mirror: src/render/surface.rs `geometry_agrees`
fn geometry_agrees(ng: vec3<f32>, wo_world: vec3<f32>, wi_world: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> bool {
    return (dot(wi_world, ng) * dot(wo_world, ng) > 0.0) == (wi.z * wo.z > 0.0);
}
