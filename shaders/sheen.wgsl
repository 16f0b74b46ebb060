// KHR_materials_sheen's Charlie lobe and its albedo table. mirror: src/render/sheen.rs —
// every function has a Rust twin of the same name; the table's values are the Rust
// table's, read from the scene's lookup table at SHEEN_TABLE_OFFSET.

// mirror: src/render/sheen.rs `sheen_l`
fn sheen_l(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let a = 21.5473 + (25.3245 - 21.5473) * t;
    let b = 3.82987 + (3.32435 - 3.82987) * t;
    let c = 0.19823 + (0.16801 - 0.19823) * t;
    let d = -1.97760 + (-1.27393 - -1.97760) * t;
    let e = -4.32054 + (-4.85967 - -4.32054) * t;
    return a / (1.0 + b * pow(x, c)) + d * x + e;
}

// mirror: src/render/sheen.rs `sheen_lambda`
fn sheen_lambda(cos_t: f32, alpha: f32) -> f32 {
    let c = abs(cos_t);
    if c < 0.5 {
        return exp(sheen_l(c, alpha));
    }
    return exp(2.0 * sheen_l(0.5, alpha) - sheen_l(1.0 - c, alpha));
}

// mirror: src/render/sheen.rs `sheen_d`
fn sheen_d(cos_h: f32, alpha: f32) -> f32 {
    let inv = 1.0 / alpha;
    let sin2 = max(1.0 - cos_h * cos_h, 0.0);
    return (2.0 + inv) * pow(sin2, 0.5 * inv) * (0.5 * FRAC_1_PI);
}

// mirror: src/render/sheen.rs `sheen_reflect`
fn sheen_reflect(color: vec3<f32>, roughness: f32, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return vec3<f32>(0.0);
    }
    let alpha = max(roughness, SHEEN_MIN_ROUGHNESS);
    let hs = wo + wi;
    let len2 = dot(hs, hs);
    var hz = 0.0;
    if len2 > 0.0 {
        hz = hs.z * inverseSqrt(len2);
    }
    let g = 1.0 + sheen_lambda(wo.z, alpha) + sheen_lambda(wi.z, alpha);
    return color * (sheen_d(hz, alpha) / (g * 4.0 * wo.z));
}

// mirror: src/render/sheen.rs `sheen_albedo`
fn sheen_albedo(cos_t: f32, roughness: f32) -> f32 {
    let x = clamp(cos_t, 0.0, 1.0) * f32(SHEEN_TABLE_COSINES - 1u);
    let r = clamp(roughness, SHEEN_MIN_ROUGHNESS, 1.0);
    let y = (r - SHEEN_MIN_ROUGHNESS) / (1.0 - SHEEN_MIN_ROUGHNESS) * f32(SHEEN_TABLE_ROUGHNESSES - 1u);
    let i = min(u32(x), SHEEN_TABLE_COSINES - 2u);
    let j = min(u32(y), SHEEN_TABLE_ROUGHNESSES - 2u);
    let fx = x - f32(i);
    let fy = y - f32(j);
    let k = SHEEN_TABLE_OFFSET + j * SHEEN_TABLE_COSINES + i;
    let near = load_texel_lut(k) * (1.0 - fx) + load_texel_lut(k + 1u) * fx;
    let far = load_texel_lut(k + SHEEN_TABLE_COSINES) * (1.0 - fx) + load_texel_lut(k + SHEEN_TABLE_COSINES + 1u) * fx;
    return near * (1.0 - fy) + far * fy;
}
