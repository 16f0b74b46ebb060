// The render kernel: one invocation per pixel, tracing this dispatch's samples.

// The film, params.film_texels texels per pixel: the radiance sum (xyz) and the index of
// the pixel's next sample (w, as a float: exact to 2^24), then one texel per film channel,
// the first being the `rays` channel (its x counts the rays traced).
// mirror: src/film.rs `Film::texels_per_pixel`
@group(1) @binding(0) var<storage, read_write> film: array<vec4<f32>>;

// [0]: invocations whose work a driver's loop limit cut short; [1]: always 0, read where
// the compiler must not know it. The host reads them as `Status` (render/gpu/session.rs).
@group(1) @binding(1) var<storage, read_write> status: array<atomic<u32>, 2>;

fn is_finite3(v: vec3<f32>) -> bool {
    let e = bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u);
    return all(e != vec3<u32>(0x7f800000u));
}

// mirror: src/render/cpu.rs `render_pixel`
//
// A pixel adds its samples of this dispatch's range to the film, from the one after those
// it already has, or adds nothing at all: Mesa's lavapipe ends every loop of an invocation
// once their iterations together pass 65535, which would silently cut paths short. An
// invocation that sees that happen (its sample loop ended early, or a two-round canary
// loop after it stopped after one) leaves its pixel as it was and counts itself in
// `status`; the host then dispatches the range again in smaller parts, which such a pixel
// resumes and a finished one skips.
@compute @workgroup_size(8, 8, 1)
fn render(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let y = params.row_start + gid.y;
    if x >= params.width || y >= params.row_end {
        return;
    }
    let pixel = y * params.width + x;
    let base = pixel * params.film_texels;
    let start = film[base];
    var radiance = start.xyz;
    var rays = film[base + 1u].x;
    var s = max(params.sample_start, u32(start.w));
    if s >= params.sample_end {
        return;
    }
    // Persistent paths: a lane whose path ends starts its next sample at once, so the lanes
    // of a SIMD group do not all wait for the longest path of every sample.
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
    var rounds = 0u;
    let bound = 2u + atomicLoad(&status[1]);
    loop {
        rounds += 1u;
        if rounds >= bound {
            break;
        }
    }
    if s < params.sample_end || rounds != bound {
        atomicAdd(&status[0], 1u);
        return;
    }
    film[base] = vec4<f32>(radiance, f32(s));
    film[base + 1u].x = rays;
}
