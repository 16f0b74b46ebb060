// The render kernel: one invocation per pixel, tracing this dispatch's samples.

// Per-pixel sums: radiance (xyz) and rays traced (w).
@group(1) @binding(0) var<storage, read_write> accum: array<vec4<f32>>;

fn is_finite3(v: vec3<f32>) -> bool {
    let e = bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u);
    return all(e != vec3<u32>(0x7f800000u));
}

// mirror: src/render/cpu.rs `render_pixel`
@compute @workgroup_size(8, 8, 1)
fn render(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let y = params.row_start + gid.y;
    if x >= params.width || y >= params.row_end {
        return;
    }
    let pixel = y * params.width + x;
    var sum = accum[pixel];
    // Persistent paths: a lane whose path ends starts its next sample at once, so the lanes
    // of a SIMD group do not all wait for the longest path of every sample.
    var s = params.sample_start;
    if s >= params.sample_end {
        return;
    }
    var rng = Rng(pixel, s, params.seed);
    var st = path_start(generate_camera_ray(x, y, rng));
    loop {
        if path_step(&st, rng) {
            if is_finite3(st.radiance) {
                sum += vec4<f32>(st.radiance, 0.0);
            }
            sum.w += f32(st.rays);
            s += 1u;
            if s >= params.sample_end {
                break;
            }
            rng = Rng(pixel, s, params.seed);
            st = path_start(generate_camera_ray(x, y, rng));
        }
    }
    accum[pixel] = sum;
}
