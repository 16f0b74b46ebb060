// The render kernel: one invocation per pixel, tracing this dispatch's samples.

// The film, params.film_texels texels per pixel, each texel four exact fixed-point sums
// (fixed.wgsl `Texel`: two vec4<u32>): the radiance sum (xyz) and the index of the pixel's
// next sample (w, as a plain integer), then one texel per film channel, the first being
// the `rays` channel (its x counts the rays traced), then one per AOV in params.aovs, in
// the order of their bits.
// mirror: src/film.rs `Film::texels_per_pixel`
@group(1) @binding(0) var<storage, read_write> film: array<Texel>;

// [0]: invocations whose work a driver's loop limit cut short; [1]: always 0, read where
// the compiler must not know it; [2]: a checked module's failed checks (bindings.wgsl
// `check`); [3]: padding. The host reads them as `Status` (render/gpu/session.rs).
@group(1) @binding(1) var<storage, read_write> status: array<atomic<u32>, 4>;

// What light subpaths seen through the lens add to the pixels they land in: per pixel and
// channel a fixed-point sum (fixed.wgsl) as (low, high) words, added atomically from any
// invocation, so that the sums are the same bits in whatever order they arrive. The host
// adds them to the film's radiance when it reads it back.
// mirror: src/render/cpu.rs `Splats`
@group(1) @binding(2) var<storage, read_write> splats: array<atomic<u32>>;

// Adds a splat to pixel `pixel`; a non-finite one is dropped, as a sample's radiance is. The
// low word's carry goes to the high word, so the pair adds as one 64-bit integer.
// mirror: src/render/cpu.rs `Splats::add`
fn add_splat(pixel: u32, v: vec3<f32>) {
    if all(v == vec3<f32>(0.0)) || !is_finite3(v) {
        return;
    }
    let i = 6u * pixel;
    if SHADER_CHECKS {
        check(i + 6u <= arrayLength(&splats));
    }
    let r = to_fixed(v.x);
    let g = to_fixed(v.y);
    let b = to_fixed(v.z);
    let r_lo = atomicAdd(&splats[i], r.x);
    atomicAdd(&splats[i + 1u], r.y + select(0u, 1u, r_lo + r.x < r_lo));
    let g_lo = atomicAdd(&splats[i + 2u], g.x);
    atomicAdd(&splats[i + 3u], g.y + select(0u, 1u, g_lo + g.x < g_lo));
    let b_lo = atomicAdd(&splats[i + 4u], b.x);
    atomicAdd(&splats[i + 5u], b.y + select(0u, 1u, b_lo + b.x < b_lo));
}

// Adds this invocation's failed checks (bindings.wgsl `check`) to status[2].
fn report_checks() {
    if SHADER_CHECKS && check_failures != 0u {
        atomicAdd(&status[2], check_failures);
    }
}

fn is_finite3(v: vec3<f32>) -> bool {
    let e = bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u);
    return all(e != vec3<u32>(0x7f800000u));
}

// A pixel's AOV accumulators: a texel per AOV, indexed by its bit's position, as the AOV's
// film channel holds it. mirror: src/render/cpu.rs `AovSums`
struct AovSums {
    t: array<Texel, AOV_COUNT>,
}

// The film texel of the AOV of bit `bit` for the pixel whose first texel is `base`.
fn aov_texel(base: u32, bit: u32) -> u32 {
    return base + 2u + countOneBits(params.aovs & (bit - 1u));
}

// mirror: src/render/cpu.rs `add_aov_sample`
fn add_aov_sample(sums: ptr<function, AovSums>, fh: FirstHit) {
    (*sums).t[6] = texel_add((*sums).t[6], vec4<f32>(f32(fh.cost), 0.0, 0.0, 0.0));
    if !fh.hit {
        return;
    }
    let depth = dot(fh.p - params.cam_position, params.cam_forward);
    (*sums).t[0] = texel_add((*sums).t[0], vec4<f32>(depth, 0.0, 0.0, 1.0));
    (*sums).t[1] = texel_add((*sums).t[1], vec4<f32>(fh.normal, 1.0));
    (*sums).t[2] = texel_add((*sums).t[2], vec4<f32>(fh.albedo, 1.0));
    (*sums).t[3] = texel_add((*sums).t[3], vec4<f32>(1.0, 0.0, 0.0, 1.0));
    (*sums).t[7] = texel_add((*sums).t[7], vec4<f32>(fh.diffuse, 1.0));
}

// mirror: src/render/cpu.rs `set_aov_ids`
fn set_aov_ids(sums: ptr<function, AovSums>, fh: FirstHit) {
    let none = Texel(vec4<u32>(0u), vec4<u32>(0u));
    (*sums).t[4] = texel_add(none, vec4<f32>(f32(fh.object & 0xffffu), f32(fh.object >> 16u), 0.0, 1.0));
    (*sums).t[5] = texel_add(none, vec4<f32>(f32(fh.material & 0xffffu), f32(fh.material >> 16u), 0.0, 1.0));
}

// A sample's path up to its camera ray. With AOVs, also adds its first hit to `sums` (and
// with sample 0 the pixel-centre ray's ids), and returns in `seen` whether its radiance
// counts: not in a transparent render where it misses.
fn start_sample(x: u32, y: u32, s: u32, rng: Rng, sums: ptr<function, AovSums>, seen: ptr<function, bool>) -> PathState {
    let ray = generate_camera_ray(x, y, rng);
    *seen = true;
    if params.aovs != 0u {
        let fh = first_hit(ray);
        add_aov_sample(sums, fh);
        *seen = fh.hit || params.transparent == 0u;
        if s == 0u {
            set_aov_ids(sums, first_hit(pixel_centre_ray(x, y)));
        }
    }
    return path_start(ray, camera_pdf(ray.dir));
}

// The branches of a sample whose first vertex is `v`: none where the path ended there and
// there are no light subpaths to trace. mirror: src/render/integrator.rs `camera_sample`
fn sample_branches(v: PathVertex) -> u32 {
    if !(CAUSTICS && params.num_caustic_targets != 0u) && !v.valid {
        return 0u;
    }
    return params.branches;
}

// What a lane does next in render's loop: start a sample (its camera ray), find the next
// vertex of its path, or start the sample's next branch (or end the sample).
const PHASE_CAMERA: u32 = 0u;
const PHASE_VERTEX: u32 = 1u;
const PHASE_BRANCH: u32 = 2u;

// mirror: src/render/cpu.rs `render_pixel`
//
// A pixel adds its samples of this dispatch's range to the film, from the one after those
// it already has, or adds nothing at all: Mesa's lavapipe ends every loop of an invocation
// once their iterations together pass 65535, which would silently cut paths short. An
// invocation that sees that happen (its sample loop ended early, or a two-round canary
// loop after it stopped after one) leaves its pixel as it was and counts itself in
// `status`; the host then dispatches the range again in smaller parts, which such a
// pixel resumes and a finished one skips. The splats its light subpaths made are in
// `splats` already: in a render with caustics the host takes the film and the splats back
// to what they held before the dispatch (render/gpu/session.rs `run_kernel`), so that no
// splat is added twice.
@compute @workgroup_size(8, 8, 1)
fn render(@builtin(global_invocation_id) gid: vec3<u32>) {
    let start = pixel_start(gid);
    if !start.run {
        return;
    }
    let x = start.x;
    let y = start.y;
    let pixel = start.pixel;
    let base = start.base;
    if skips_pixel(x, y) {
        // What its samples would add: one ray each, no radiance, and the ids of a miss.
        var miss_sums = film_aov_sums(base);
        var miss_rays = start.rays;
        for (var m = start.s; m < params.sample_end; m++) {
            if m == 0u && params.aovs != 0u {
                set_aov_ids(&miss_sums, FirstHit(false, vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), NO_ID, NO_ID, 0u));
            }
            miss_rays = texel_add(miss_rays, vec4<f32>(1.0, 0.0, 0.0, 0.0));
        }
        finish_pixel(base, params.sample_end, start.radiance, miss_rays, miss_sums);
        return;
    }
    var radiance = start.radiance;
    var rays = start.rays;
    var s = start.s;
    // Persistent paths: a lane whose path ends starts its next branch or sample at once, so
    // the lanes of a SIMD group do not all wait for the longest path of every sample.
    var sums = film_aov_sums(base);
    // Each stage of a path is called from one place in this loop, so the compiler, which
    // inlines every call, makes one copy of each: a lane runs the stages its phase needs.
    var seen = true;
    var phase = PHASE_CAMERA;
    // The sample's stream and its path to the first vertex (`first`, vertex `v0`).
    var rng: Rng;
    var first: PathState;
    var v0: PathVertex;
    // The sample's branches: the next to start (j of nb), the path being traced (`st`, its
    // stream `path_rng` and light subpath `light`), their radiance so far and the sample's
    // rays.
    var nb = 0u;
    var j = 0u;
    var st: PathState;
    var path_rng: Rng;
    var light = no_light_path();
    var sum = vec3<f32>(0.0);
    var sample_rays = 0u;
    loop {
        // A sample's camera ray goes on to its first vertex in the same round.
        let at_first = phase == PHASE_CAMERA;
        if at_first {
            rng = Rng(pixel, s, params.seed);
            st = start_sample(x, y, s, rng, &sums, &seen);
            path_rng = rng;
            phase = PHASE_VERTEX;
        }
        // The vertex whose BSDF the path samples next, where `step`.
        var v: PathVertex;
        var step = false;
        if phase == PHASE_VERTEX {
            v = path_vertex(&st, path_rng, select(1u, params.branches, at_first));
            if at_first {
                first = st;
                v0 = v;
                nb = sample_branches(v0);
                j = 0u;
                sum = vec3<f32>(0.0);
                sample_rays = st.rays;
                phase = PHASE_BRANCH;
            } else if v.valid {
                step = true;
            } else {
                sum += st.radiance;
                sample_rays += st.rays;
                phase = PHASE_BRANCH;
            }
        }
        if phase == PHASE_BRANCH {
            if j < nb {
                let b = branch_start(first, rng, j, nb);
                j += 1u;
                if CAUSTICS {
                    for (var i = 0u; i < MAX_CAUSTIC_HOPS; i++) {
                        add_splat(b.ls.splat_pixels[i], b.ls.splats[i]);
                    }
                }
                light = b.ls.light;
                st = b.st;
                path_rng = b.rng;
                if v0.valid {
                    v = v0;
                    branch_numbers(&v, first.depth, path_rng, nb);
                    step = true;
                    phase = PHASE_VERTEX;
                } else {
                    sum += st.radiance;
                    sample_rays += st.rays;
                }
            } else {
                let sample_radiance = first.radiance + sum * params.branch_weight;
                if is_finite3(sample_radiance) && seen {
                    radiance = texel_add(radiance, vec4<f32>(sample_radiance, 0.0));
                }
                rays = texel_add(rays, vec4<f32>(f32(sample_rays), 0.0, 0.0, 0.0));
                s += 1u;
                if s >= params.sample_end {
                    break;
                }
                phase = PHASE_CAMERA;
            }
        }
        if step {
            connect_light_path(&st, v, &light);
            if path_continue(&st, v, path_rng) {
                sum += st.radiance;
                sample_rays += st.rays;
                phase = PHASE_BRANCH;
            } else {
                phase = PHASE_VERTEX;
            }
        }
    }
    finish_pixel(base, s, radiance, rays, sums);
}

// mirror: src/render/cpu.rs `skips_pixel`
fn skips_pixel(x: u32, y: u32) -> bool {
    return params.transparent != 0u && params.num_caustic_targets == 0u
        && (params.aovs & AOV_BVH_COST) == 0u && outside_window(x, y);
}

// Where an invocation's pixel stands: its coordinates, its first film texel, its
// radiance and rays sums so far, the next sample it traces, and whether it traces any.
struct PixelStart {
    x: u32,
    y: u32,
    pixel: u32,
    base: u32,
    radiance: Texel,
    rays: Texel,
    s: u32,
    run: bool,
}

// The pixel of invocation `gid`: none outside the image or the dispatch's rows, and none
// to trace where it has this dispatch's samples already (a resumed dispatch). The radiance
// texel's w holds the next sample's index as is (adding 0 keeps it).
fn pixel_start(gid: vec3<u32>) -> PixelStart {
    var p: PixelStart;
    p.run = false;
    p.x = gid.x;
    p.y = params.row_start + gid.y;
    if p.x >= params.width || p.y >= params.row_end {
        return p;
    }
    p.pixel = p.y * params.width + p.x;
    p.base = p.pixel * params.film_texels;
    if SHADER_CHECKS {
        check(p.base + params.film_texels <= arrayLength(&film));
    }
    p.radiance = film[p.base];
    p.rays = film[p.base + 1u];
    p.s = max(params.sample_start, p.radiance.zw.z);
    if p.s >= params.sample_end {
        report_checks();
        return p;
    }
    p.run = true;
    return p;
}

// A pixel's AOV sums as the film holds them so far.
fn film_aov_sums(base: u32) -> AovSums {
    var sums = AovSums();
    for (var k = 0u; k < AOV_COUNT; k++) {
        if (params.aovs & (1u << k)) != 0u {
            sums.t[k] = film[aov_texel(base, 1u << k)];
        }
    }
    return sums;
}

// Writes a pixel's sums back, its next sample `s` with them, unless a driver's loop limit
// cut its loops short (a two-round canary loop tells): the pixel is then left as it was and
// counted in status[0], for the host to dispatch its range again in smaller parts.
fn finish_pixel(base: u32, s: u32, radiance_sums: Texel, rays: Texel, sums: AovSums) {
    var rounds = 0u;
    let bound = 2u + atomicLoad(&status[1]);
    loop {
        rounds += 1u;
        if rounds >= bound {
            break;
        }
    }
    report_checks();
    if s < params.sample_end || rounds != bound {
        atomicAdd(&status[0], 1u);
        return;
    }
    var radiance = radiance_sums;
    radiance.zw.z = s;
    film[base] = radiance;
    film[base + 1u] = rays;
    for (var k = 0u; k < AOV_COUNT; k++) {
        if (params.aovs & (1u << k)) != 0u {
            film[aov_texel(base, 1u << k)] = sums.t[k];
        }
    }
}

// A geometry-only job: each sample's camera ray and first hit alone, its albedo as the
// radiance (none where it misses), one ray a sample; the film, resumption and loop-limit
// handling of `render`. mirror: src/render/cpu.rs `geometry_pixel`
@compute @workgroup_size(8, 8, 1)
fn geometry(@builtin(global_invocation_id) gid: vec3<u32>) {
    let start = pixel_start(gid);
    if !start.run {
        return;
    }
    let x = start.x;
    let y = start.y;
    let pixel = start.pixel;
    let base = start.base;
    var radiance = start.radiance;
    var rays = start.rays;
    var s = start.s;
    var sums = film_aov_sums(base);
    loop {
        let fh = first_hit(generate_camera_ray(x, y, Rng(pixel, s, params.seed)));
        if params.aovs != 0u {
            add_aov_sample(&sums, fh);
            if s == 0u {
                set_aov_ids(&sums, first_hit(pixel_centre_ray(x, y)));
            }
        }
        rays = texel_add(rays, vec4<f32>(1.0, 0.0, 0.0, 0.0));
        if fh.hit {
            radiance = texel_add(radiance, vec4<f32>(fh.albedo, 0.0));
        }
        s += 1u;
        if s >= params.sample_end {
            break;
        }
    }
    finish_pixel(base, s, radiance, rays, sums);
}
