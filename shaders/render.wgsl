// The render kernel: one invocation per pixel, tracing this dispatch's samples.

// The film, params.film_texels texels per pixel: the radiance sum (xyz), then one texel per
// film channel, the first being the `rays` channel (its x counts the rays traced).
// mirror: src/film.rs `Film::texels_per_pixel`
@group(1) @binding(0) var<storage, read_write> film: array<vec4<f32>>;

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
    let base = pixel * params.film_texels;
    var radiance = film[base].xyz;
    var rays = film[base + 1u].x;
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
                radiance += st.radiance;
            }
            rays += f32(st.rays);
            s += 1u;
            if s >= params.sample_end {
                break;
            }
            rng = Rng(pixel, s, params.seed);
            st = path_start(generate_camera_ray(x, y, rng));
        }
    }
    film[base] = vec4<f32>(radiance, 0.0);
    film[base + 1u].x = rays;
}
