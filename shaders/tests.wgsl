// Shader unit-test kernels: each case reads two vec4<u32> and writes two. Run by
// src/render/gpu/kernels.rs from tests/shader_units.rs, which compares every output with the Rust
// function of the same name.

@group(1) @binding(0) var<storage, read> test_in: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> test_out: array<vec4<u32>>;

fn case_index(gid: vec3<u32>) -> u32 {
    return gid.x + gid.y * 65535u * 64u;
}

fn case_count() -> u32 {
    return arrayLength(&test_in) / 2u;
}

// Word k (0 or 1) of case i's input.
fn case_in(i: u32, k: u32) -> vec4<u32> {
    return test_in[2u * i + k];
}

fn case_out(i: u32, a: vec4<u32>, b: vec4<u32>) {
    test_out[2u * i] = a;
    test_out[2u * i + 1u] = b;
}

fn f4(v: vec4<u32>) -> vec4<f32> {
    return bitcast<vec4<f32>>(v);
}

fn u4(v: vec4<f32>) -> vec4<u32> {
    return bitcast<vec4<u32>>(v);
}

fn case_ray(i: u32) -> Ray {
    return Ray(f4(case_in(i, 0u)).xyz, f4(case_in(i, 1u)).xyz);
}

// in: (pixel, sample, seed, bounce * 16 + dim) | out: (rng_u32, rng_1d bits, rng_2d bits
// of the pair of dim), pcg4d
@compute @workgroup_size(64)
fn test_rng(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let k = case_in(i, 0u);
    let rng = Rng(k.x, k.y, k.z);
    let bounce = k.w / DIMS_PER_BOUNCE;
    let dim = k.w % DIMS_PER_BOUNCE;
    let h = pcg4d(vec4<u32>(k.x, k.y, k.w, k.z));
    let pair = bitcast<vec2<u32>>(rng_2d(rng, bounce, dim_pair(dim).x));
    case_out(i, vec4<u32>(rng_u32(rng, bounce, dim), bitcast<u32>(rng_1d(rng, bounce, dim)), pair), h);
}

// in: (origin, tri index), (dir, t_max) | out: (hit, t, u, v)
@compute @workgroup_size(64)
fn test_intersect_triangle(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let tri = case_in(i, 0u).w;
    let t_max = f4(case_in(i, 1u)).w;
    let h = intersect_triangle(sheared_ray(case_ray(i)), load_tri(tri), t_max);
    case_out(i, vec4<u32>(select(0u, 1u, h.hit), bitcast<u32>(h.t), bitcast<u32>(h.u), bitcast<u32>(h.v)), vec4<u32>(0u));
}

// in: (origin, node index), (dir, t_max) | out: (t_near of the node's box)
@compute @workgroup_size(64)
fn test_intersect_aabb(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let node = load_node(case_in(i, 0u).w);
    let ray = case_ray(i);
    let t = intersect_aabb(ray.origin, safe_inverse(ray.dir), node.min, node.max, f4(case_in(i, 1u)).w);
    case_out(i, vec4<u32>(bitcast<u32>(t), 0u, 0u, 0u), vec4<u32>(0u));
}

// in: (origin, _), (dir, t_max) | out: (tri, t, u, v), (any-hit, ...)
@compute @workgroup_size(64)
fn test_traverse(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let ray = case_ray(i);
    let t_max = f4(case_in(i, 1u)).w;
    let h = traverse_closest(ray, t_max, false);
    case_out(i, vec4<u32>(h.tri, bitcast<u32>(h.t), bitcast<u32>(h.u), bitcast<u32>(h.v)), vec4<u32>(select(0u, 1u, traverse_any(ray, t_max)), 0u, 0u, 0u));
}

// in: (u0, u1, u2, u3) as float bits | out: (disk.xy, triangle.xy), (cosine hemisphere xyz, pdf)
@compute @workgroup_size(64)
fn test_sampling(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let u = f4(case_in(i, 0u));
    let d = sample_concentric_disk(u.xy);
    let b = sample_uniform_triangle(u.zw);
    let c = sample_cosine_hemisphere(u.xy);
    case_out(i, u4(vec4<f32>(d, b)), u4(vec4<f32>(c, cosine_hemisphere_pdf(c.z))));
}

// in: (u xy, _, _) | out: (pick_light's index, its emitter, power_heuristic(u.x, 1 - u.x)
// bits, _), (its pmf, u.x, u.y bits, _)
@compute @workgroup_size(64)
fn test_light_pick(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let u = f4(case_in(i, 0u)).xy;
    let pick = pick_light(u);
    let k = pick.index;
    case_out(i, vec4<u32>(k, load_emitter(k), bitcast<u32>(power_heuristic(u.x, 1.0 - u.x)), 0u),
        vec4<u32>(bitcast<u32>(pick.pmf), bitcast<u32>(pick.u.x), bitcast<u32>(pick.u.y), 0u));
}

// in: (wo xyz, material), (u_lobe, u1, u2, _) | out: (wi xyz, pdf), (weight xyz, flags:
// bit 0 valid, bit 1 delta, bits 2.. the lobe) ; and eval/pdf of the sampled direction are checked on the host.
@compute @workgroup_size(64)
fn test_bsdf_sample(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let a = case_in(i, 0u);
    let u = f4(case_in(i, 1u));
    let m = load_material(a.w);
    let s = bsdf_sample(m, f4(a).xyz, u.x, u.yz);
    let flags = select(0u, 1u, s.valid) | select(0u, 2u, s.delta) | (s.lobe << 2u);
    case_out(i, u4(vec4<f32>(s.wi, s.pdf)), vec4<u32>(u4(vec4<f32>(s.weight, 0.0)).xyz, flags));
}

// in: (wo xyz, material), (wi xyz, _) | out: (f cos xyz, pdf)
@compute @workgroup_size(64)
fn test_bsdf_eval(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let a = case_in(i, 0u);
    let wo = f4(a).xyz;
    let wi = f4(case_in(i, 1u)).xyz;
    let m = load_material(a.w);
    case_out(i, u4(vec4<f32>(bsdf_eval(m, wo, wi), bsdf_pdf(m, wo, wi))), vec4<u32>(0u));
}

// in: (x, y, sample, _) | out: (camera ray origin, _), (dir, _) ; and the full path:
// test_trace_path writes (radiance, rays).
@compute @workgroup_size(64)
fn test_camera_ray(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let k = case_in(i, 0u);
    let rng = Rng(k.y * params.width + k.x, k.z, params.seed);
    let ray = generate_camera_ray(k.x, k.y, rng);
    case_out(i, u4(vec4<f32>(ray.origin, 0.0)), u4(vec4<f32>(ray.dir, 0.0)));
}

// in: (x, y, _, _) | out: first_hit of pixel_centre_ray(x, y): (hit, cost, material,
// object), (normal xyz, depth along the view axis)
@compute @workgroup_size(64)
fn test_first_hit(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let k = case_in(i, 0u);
    let fh = first_hit(pixel_centre_ray(k.x, k.y));
    let depth = dot(fh.p - params.cam_position, params.cam_forward);
    case_out(i, vec4<u32>(select(0u, 1u, fh.hit), fh.cost, fh.material, fh.object), u4(vec4<f32>(fh.normal, depth)));
}

// in: (x, y, _, _) | out: the pixel-centre ray's first hit: (albedo xyz, hit), (diffuse
// colour xyz, material)
@compute @workgroup_size(64)
fn test_first_hit_colours(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let k = case_in(i, 0u);
    let fh = first_hit(pixel_centre_ray(k.x, k.y));
    case_out(i, vec4<u32>(u4(vec4<f32>(fh.albedo, 0.0)).xyz, select(0u, 1u, fh.hit)), vec4<u32>(u4(vec4<f32>(fh.diffuse, 0.0)).xyz, fh.material));
}

// in: (x, y, sample, _) | out: (radiance xyz, rays), (splat values summed xyz, the sum of
// the pixels of the splats that land)
@compute @workgroup_size(64)
fn test_trace_path(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let k = case_in(i, 0u);
    let rng = Rng(k.y * params.width + k.x, k.z, params.seed);
    let p = trace_path(generate_camera_ray(k.x, k.y, rng), rng);
    case_out(i, vec4<u32>(u4(vec4<f32>(p.radiance, 0.0)).xyz, p.rays), vec4<u32>(u4(vec4<f32>(p.splat_sum, 0.0)).xyz, p.splat_pixel_sum));
}

// in: (x, y, sample, _) | out: the light subpath's (vertex count, rays of start_light,
// segments of vertices 0 and 1), (vertex 0's position xyz, its throughput's luminance)
@compute @workgroup_size(64)
fn test_light_subpath(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let k = case_in(i, 0u);
    let rng = Rng(k.y * params.width + k.x, k.z, params.seed);
    let ls = start_light(rng);
    let v = ls.light.vertices[0];
    let lum = dot(v.beta, vec3<f32>(0.2126, 0.7152, 0.0722));
    case_out(i, vec4<u32>(ls.light.count, ls.rays, v.segments, ls.light.vertices[1].segments), u4(vec4<f32>(v.si.p, lum)));
}

// in: (p xyz, d.z), (u.x, u.y, d.x, d.y) | out: (sample_target(p, u): dir xyz, its pdf),
// (target_pdf(p, normalize(d)), the first target's cone from p: cos_max, height, _)
@compute @workgroup_size(64)
fn test_caustic_targets(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let a = f4(case_in(i, 0u));
    let b = f4(case_in(i, 1u));
    let p = a.xyz;
    let st = sample_target(p, b.xy);
    let dir = normalize(vec3<f32>(b.z, b.w, a.w));
    let cone = target_cone(load_caustic_target(0u), p);
    case_out(i, u4(st), u4(vec4<f32>(target_pdf(p, dir), cone.cos_max, cone.height, 0.0)));
}

// in: (u, v, texture index, material index) | out: texture_lookup(texture, uv),
// (material_at(material, uv in both sets, white).albedo, its roughness)
@compute @workgroup_size(64)
fn test_texture(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let k = case_in(i, 0u);
    let uv = bitcast<vec2<f32>>(k.xy);
    let m = material_at(load_material(k.w), vec4<f32>(uv, uv), vec4<f32>(1.0));
    case_out(i, u4(texture_lookup(k.z, uv)), u4(vec4<f32>(m.albedo, m.roughness)));
}

// in: (triangle, b1, b2, -) | out: (material_at(its material, triangle_uv,
// triangle_color).albedo, alpha_test as 0 or 1), triangle_uv(triangle, b1, b2)
@compute @workgroup_size(64)
fn test_surface_colors(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let k = case_in(i, 0u);
    let tri = k.x;
    let b1 = bitcast<f32>(k.y);
    let b2 = bitcast<f32>(k.z);
    let uv = triangle_uv(tri, b1, b2);
    let m = material_at(load_material(load_shading(tri).material), uv, triangle_color(tri, b1, b2));
    let passes = select(0u, 1u, alpha_test(tri, b1, b2, false));
    case_out(i, vec4<u32>(u4(vec4<f32>(m.albedo, 0.0)).xyz, passes), u4(uv));
}

// in: (triangle, b1, b2, -), (n.xyz, -) | out: (normal_mapped(triangle, b1, b2, its uv, n,
// its geometric normal), alpha_test as 0 or 1), (material_at(its material, uv).metallic,
// .transmission, -, -)
@compute @workgroup_size(64)
fn test_surface_maps(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let k = case_in(i, 0u);
    let tri = k.x;
    let b1 = bitcast<f32>(k.y);
    let b2 = bitcast<f32>(k.z);
    let n = f4(case_in(i, 1u)).xyz;
    let uv = triangle_uv(tri, b1, b2);
    let ng = geometric_normal(load_tri(tri));
    let base = load_material(load_shading(tri).material);
    let mapped = normal_mapped(Hit(0.0, b1, b2, tri), uv, n, ng, base.normal_texture, base.normal_scale);
    let passes = select(0u, 1u, alpha_test(tri, b1, b2, false));
    let m = material_at(base, uv, triangle_color(tri, b1, b2));
    case_out(i, vec4<u32>(u4(vec4<f32>(mapped, 0.0)).xyz, passes), u4(vec4<f32>(m.metallic, m.transmission, 0.0, 0.0)));
}

// in: (dir.xyz, -), (u.x, u.y, -, -) | out: (env_radiance(dir), env_pdf(dir)),
// (sample_env(u).dir, its pdf)
@compute @workgroup_size(64)
fn test_environment(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let dir = f4(case_in(i, 0u)).xyz;
    let u = f4(case_in(i, 1u)).xy;
    let e = sample_env(u);
    case_out(i, u4(vec4<f32>(env_radiance(dir), env_pdf(dir))), u4(vec4<f32>(e.dir, e.pdf)));
}

// in: (v0 bits, v1 bits, a.lo, a.hi), (b.lo, b.hi, -, -) | out: (to_fixed(v0), to_fixed(v1)),
// (fixed_add(a, b), texel_add of (v0, v1, 0, 1) to (a, b, a, b) in its first two sums)
@compute @workgroup_size(64)
fn test_fixed(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = case_index(gid);
    if i >= case_count() { return; }
    let k = case_in(i, 0u);
    let b = case_in(i, 1u).xy;
    let v0 = bitcast<f32>(k.x);
    let v1 = bitcast<f32>(k.y);
    let t = texel_add(Texel(vec4<u32>(k.zw, b), vec4<u32>(k.zw, b)), vec4<f32>(v0, v1, 0.0, 1.0));
    case_out(i, vec4<u32>(to_fixed(v0), to_fixed(v1)), vec4<u32>(fixed_add(k.zw, b), t.xy.zw));
}
