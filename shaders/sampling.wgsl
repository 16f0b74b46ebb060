// Warps from the unit square. mirror: src/render/sampling.rs

// mirror: src/render/sampling.rs `sample_concentric_disk`
fn sample_concentric_disk(u: vec2<f32>) -> vec2<f32> {
    let o = 2.0 * u - vec2<f32>(1.0);
    if o.x == 0.0 && o.y == 0.0 {
        return vec2<f32>(0.0);
    }
    // About the y axis theta = pi/2 - phi: cos theta = sin phi, sin theta = cos phi. Both
    // kinds of octant run the same operations on selected operands, as on the CPU.
    let x_major = abs(o.x) > abs(o.y);
    let rq = select(o.yx, o, x_major);
    let sc = sincos_octant(FRAC_PI_4 * (rq.y / rq.x));
    return rq.x * select(sc, sc.yx, x_major);
}

// (sin x, cos x) for x in [-pi/4, pi/4]. mirror: src/render/sampling.rs `sincos_octant`
fn sincos_octant(x: f32) -> vec2<f32> {
    let z = x * x;
    let s = ((-1.9515296e-4 * z + 8.332161e-3) * z - 1.6666655e-1) * z * x + x;
    let c = ((2.4433157e-5 * z - 1.3887316e-3) * z + 4.1666646e-2) * z * z - 0.5 * z + 1.0;
    return vec2<f32>(s, c);
}

// mirror: src/render/sampling.rs `sample_cosine_hemisphere`
fn sample_cosine_hemisphere(u: vec2<f32>) -> vec3<f32> {
    let d = sample_concentric_disk(u);
    let o = 2.0 * u - vec2<f32>(1.0);
    let r = max(abs(o.x), abs(o.y));
    let z = sqrt(max((1.0 - r) * (1.0 + r), 0.0));
    return vec3<f32>(d.x, d.y, z);
}

// mirror: src/render/sampling.rs `cosine_hemisphere_pdf`
fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    return max(cos_theta, 0.0) * FRAC_1_PI;
}

// mirror: src/render/sampling.rs `sample_uniform_sphere`
fn sample_uniform_sphere(u: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - 2.0 * u.x;
    let r = sqrt(max(1.0 - z * z, 0.0));
    let phi = 2.0 * PI * u.y;
    return vec3<f32>(r * cos(phi), r * sin(phi), z);
}

// mirror: src/render/sampling.rs `sample_uniform_triangle`
fn sample_uniform_triangle(u: vec2<f32>) -> vec2<f32> {
    let su = sqrt(u.x);
    return vec2<f32>(1.0 - su, u.y * su);
}

// mirror: src/render/sampling.rs `power_heuristic`
fn power_heuristic(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    let b2 = b * b;
    if a2 + b2 == 0.0 {
        return 0.0;
    }
    return a2 / (a2 + b2);
}

// The emitter whose CDF bucket holds `u`, and the CDF entry below it (0 for the first).
struct CdfBucket {
    index: u32,
    below: f32,
}

// A binary search whose steps depend only on the number of emitters, as on the CPU.
// mirror: src/render/sampling.rs `sample_cdf`
fn sample_cdf(u: f32) -> CdfBucket {
    // The answer lies in base .. base + n; the last entry is never at or below u.
    var base = 0u;
    var n = params.num_emitters;
    var below = 0.0;
    while n > 1u {
        let half = n / 2u;
        let c = load_emitter_cdf(base + half - 1u);
        base = select(base, base + half, c <= u);
        below = select(below, c, c <= u);
        n -= half;
    }
    return CdfBucket(base, below);
}
