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

// mirror: src/render/environment.rs `texel_luminance`
fn texel_luminance(t: Texture, x: u32, y: u32) -> f32 {
    let c = texel(t, x, y);
    let l = 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    return select(0.0, l, l > 0.0);
}

// mirror: src/render/environment.rs `cell_corners`
fn cell_corners(t: Texture, i: u32, j: u32) -> vec4<f32> {
    check(t.width > 0u && t.height > 0u);
    let k = (j + 1u) % t.width;
    let below = min(i + 1u, t.height - 1u);
    return vec4<f32>(
        texel_luminance(t, j, i),
        texel_luminance(t, k, i),
        texel_luminance(t, j, below),
        texel_luminance(t, k, below),
    );
}

// mirror: src/render/environment.rs `sample_linear`
fn sample_linear(u: f32, a: f32, b: f32) -> f32 {
    if a + b <= 0.0 {
        return u;
    }
    let x = u * (a + b) / (a + sqrt(max(a * a + u * (b * b - a * a), 0.0)));
    return clamp(x, 0.0, ONE_MINUS_EPSILON);
}

// mirror: src/render/environment.rs `cell_density`
fn cell_density(c: vec4<f32>, x: f32, y: f32) -> f32 {
    let mean = 0.25 * (c.x + c.y + c.z + c.w);
    if mean <= 0.0 {
        return 0.0;
    }
    let top = c.x + x * (c.y - c.x);
    let bottom = c.z + x * (c.w - c.z);
    return (top + y * (bottom - top)) / mean;
}

// mirror: src/render/environment.rs `env_pdf`
fn env_pdf(dir: vec3<f32>) -> f32 {
    let t = load_texture(params.env_texture);
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
    let y = uv.y * f32(ny);
    let j = min(u32(max(x, 0.0)), nx - 1u);
    let i = min(u32(max(y, 0.0)), ny - 1u);
    let within = cell_density(cell_corners(t, i, j), clamp(x - f32(j), 0.0, 1.0), clamp(y - f32(i), 0.0, 1.0));
    let p = cdf_step(0u, i) * cdf_step(ny + i * nx, j) * within;
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
    return CdfPick(lo, clamp(within, 0.0, ONE_MINUS_EPSILON));
}

// A direction drawn from the environment and its solid-angle density (sample_env's pair).
struct EnvSample {
    dir: vec3<f32>,
    pdf: f32,
}

// mirror: src/render/environment.rs `sample_env`
fn sample_env(u: vec2<f32>) -> EnvSample {
    let t = load_texture(params.env_texture);
    let nx = params.env_cells.x;
    let ny = params.env_cells.y;
    let row = search_cdf(0u, ny, u.y);
    let i = row.k;
    let col = search_cdf(ny + i * nx, nx, u.x);
    let j = col.k;
    let c = cell_corners(t, i, j);
    let y = sample_linear(row.within, c.x + c.y, c.z + c.w);
    let x = sample_linear(col.within, c.x + y * (c.z - c.x), c.y + y * (c.w - c.y));
    var eu = (f32(j) + x + 0.5) / f32(nx);
    if eu >= 1.0 {
        eu -= 1.0;
    }
    let ev = (f32(i) + y) / f32(ny);
    let sin_theta = sin(PI * ev);
    let cos_theta = cos(PI * ev);
    let sin_phi = sin(2.0 * PI * eu);
    let cos_phi = cos(2.0 * PI * eu);
    let dx = sin_theta * sin_phi;
    let dz = -sin_theta * cos_phi;
    let rc = params.env_rotation.x;
    let rs = params.env_rotation.y;
    let dir = vec3<f32>(rc * dx + rs * dz, cos_theta, -rs * dx + rc * dz);
    if sin_theta <= 0.0 {
        return EnvSample(dir, 0.0);
    }
    let p = cdf_step(0u, i) * cdf_step(ny + i * nx, j) * cell_density(c, x, y);
    return EnvSample(dir, p * f32(nx * ny) / (2.0 * PI * PI * sin_theta));
}
