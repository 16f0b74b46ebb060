// The environment map: radiance from an equirectangular image around the scene, read as
// Mitsuba 3's envmap reads it, and its importance sampling by the host-built distribution
// over cells (env_cdf). mirror: src/render/environment.rs — every function has a Rust twin
// of the same name.

// mirror: src/render/environment.rs `env_uv`
fn env_uv(dir: vec3<f32>) -> vec2<f32> {
    let c = params.env_rotation.x;
    let s = params.env_rotation.y;
    let x = c * dir.x - s * dir.z;
    let z = s * dir.x + c * dir.z;
    var u = atan2(x, -z) * (0.5 / PI);
    if u < 0.0 {
        u += 1.0;
    }
    let theta = atan2(sqrt(x * x + z * z), dir.y);
    return vec2<f32>(u, theta * (1.0 / PI));
}

// mirror: src/render/environment.rs `env_radiance`
fn env_radiance(dir: vec3<f32>) -> vec3<f32> {
    let t = load_texture(params.env_texture);
    let uv = env_uv(dir);
    let x = texel_span(uv.x, t.width, WRAP_REPEAT);
    let y = uv.y * f32(t.height - 1u);
    let y0 = floor(y);
    let fy = y - y0;
    let ya = min(u32(max(y0, 0.0)), t.height - 1u);
    let yb = min(ya + 1u, t.height - 1u);
    let top = texel(t, x.a, ya) * (1.0 - x.f) + texel(t, x.b, ya) * x.f;
    let bottom = texel(t, x.a, yb) * (1.0 - x.f) + texel(t, x.b, yb) * x.f;
    return params.env_strength * (top * (1.0 - fy) + bottom * fy).xyz;
}

// mirror: src/render/environment.rs `env_pdf`
fn env_pdf(dir: vec3<f32>) -> f32 {
    let nx = params.env_cells.x;
    let ny = params.env_cells.y;
    let uv = env_uv(dir);
    let sin_theta = sqrt(max(1.0 - dir.y * dir.y, 0.0));
    if sin_theta <= 0.0 {
        return 0.0;
    }
    var x = uv.x * f32(nx) - 0.5;
    if x < 0.0 {
        x += f32(nx);
    }
    let j = min(u32(max(x, 0.0)), nx - 1u);
    let i = min(u32(max(uv.y * f32(ny), 0.0)), ny - 1u);
    let p = cdf_step(0u, i) * cdf_step(ny + i * nx, j);
    return p * f32(nx * ny) / (2.0 * PI * PI * sin_theta);
}

// mirror: src/render/environment.rs `cdf_step`
fn cdf_step(start: u32, k: u32) -> f32 {
    let at = start + k;
    var prev = 0.0;
    if k > 0u {
        prev = load_env_cdf(at - 1u);
    }
    return load_env_cdf(at) - prev;
}

// A bucket of a CDF and where in it a uniform number falls (search_cdf's two results).
struct CdfPick {
    k: u32,
    within: f32,
}

// mirror: src/render/environment.rs `search_cdf`
fn search_cdf(start: u32, n: u32, u: f32) -> CdfPick {
    var lo = 0u;
    var hi = n - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if load_env_cdf(start + mid) <= u {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    let p = cdf_step(start, lo);
    let prev = load_env_cdf(start + lo) - p;
    var within = 0.5;
    if p > 0.0 {
        within = (u - prev) / p;
    }
    return CdfPick(lo, clamp(within, 0.0, 0.99999994));
}

// A direction drawn from the environment and its solid-angle density (sample_env's pair).
struct EnvSample {
    dir: vec3<f32>,
    pdf: f32,
}

// mirror: src/render/environment.rs `sample_env`
fn sample_env(u: vec2<f32>) -> EnvSample {
    let nx = params.env_cells.x;
    let ny = params.env_cells.y;
    let row = search_cdf(0u, ny, u.y);
    let i = row.k;
    let col = search_cdf(ny + i * nx, nx, u.x);
    let j = col.k;
    var eu = (f32(j) + col.within + 0.5) / f32(nx);
    if eu >= 1.0 {
        eu -= 1.0;
    }
    let ev = (f32(i) + row.within) / f32(ny);
    let sin_theta = sin(PI * ev);
    let cos_theta = cos(PI * ev);
    let sin_phi = sin(2.0 * PI * eu);
    let cos_phi = cos(2.0 * PI * eu);
    let x = sin_theta * sin_phi;
    let z = -sin_theta * cos_phi;
    let c = params.env_rotation.x;
    let s = params.env_rotation.y;
    let dir = vec3<f32>(c * x + s * z, cos_theta, -s * x + c * z);
    if sin_theta <= 0.0 {
        return EnvSample(dir, 0.0);
    }
    let p = cdf_step(0u, i) * cdf_step(ny + i * nx, j);
    return EnvSample(dir, p * f32(nx * ny) / (2.0 * PI * PI * sin_theta));
}
