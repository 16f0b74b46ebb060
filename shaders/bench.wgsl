// Ray-throughput kernels for `meshtrace bench`: one ray per invocation, no shading.
// Each ray is two vec4: (origin, t_max) and (dir, _), as float bits.

@group(1) @binding(0) var<storage, read> bench_rays: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> bench_hits: array<vec4<u32>>;

fn bench_ray(i: u32) -> Ray {
    return Ray(bitcast<vec4<f32>>(bench_rays[2u * i]).xyz, bitcast<vec4<f32>>(bench_rays[2u * i + 1u]).xyz);
}

// out: (triangle or NO_HIT, t bits, _, _)
@compute @workgroup_size(64)
fn bench_closest(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * 65535u * 64u;
    if 2u * i >= arrayLength(&bench_rays) { return; }
    let h = traverse_closest(bench_ray(i), bitcast<f32>(bench_rays[2u * i].w), false);
    bench_hits[i] = vec4<u32>(h.tri, bitcast<u32>(h.t), 0u, 0u);
}

// out: (1 if occluded, _, _, _)
@compute @workgroup_size(64)
fn bench_any(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * 65535u * 64u;
    if 2u * i >= arrayLength(&bench_rays) { return; }
    let hit = traverse_any(bench_ray(i), bitcast<f32>(bench_rays[2u * i].w));
    bench_hits[i] = vec4<u32>(select(0u, 1u, hit), 0u, 0u, 0u);
}
