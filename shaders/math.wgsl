// Rays and frames. mirror: src/math.rs

// mirror: src/math.rs `Ray`
struct Ray {
    origin: vec3<f32>,
    dir: vec3<f32>,
}

// mirror: src/math.rs `onb_from_normal`
fn onb_from_normal(n: vec3<f32>) -> mat3x3<f32> {
    let sgn = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sgn + n.z);
    let b = n.x * n.y * a;
    let t = vec3<f32>(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x);
    let bt = vec3<f32>(b, sgn + n.y * n.y * a, -n.y);
    return mat3x3<f32>(t, bt, n);
}
