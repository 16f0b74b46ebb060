// Primary rays. mirror: src/render/camera.rs

// A box-filtered sample of pixel (px, py) through a pinhole or thin lens, or along
// parallel rays for an orthographic camera.
// mirror: src/render/camera.rs `generate_camera_ray`
fn generate_camera_ray(px: u32, py: u32, rng: Rng) -> Ray {
    let j = rng_2d(rng, 0u, DIM_PIXEL_X);
    var jx = j.x;
    var jy = j.y;
    if params.filter_width != 1.0 {
        jx = 0.5 + params.filter_width * (jx - 0.5);
        jy = 0.5 + params.filter_width * (jy - 0.5);
    }
    if params.ortho_half_height > 0.0 {
        return orthographic_ray(f32(px) + jx, f32(py) + jy);
    }
    let sx = (2.0 * (f32(px) + jx) / f32(params.width) - 1.0) * params.tan_half_vfov * params.aspect;
    let sy = (1.0 - 2.0 * (f32(py) + jy) / f32(params.height)) * params.tan_half_vfov;
    let dir = params.cam_forward + sx * params.cam_right + sy * params.cam_up;
    if params.aperture <= 0.0 {
        return Ray(params.cam_position, normalize(dir));
    }
    let lens = 0.5 * params.aperture * sample_concentric_disk(rng_2d(rng, 0u, DIM_LENS_U));
    let focus = params.cam_position + params.focus_distance * dir;
    let origin = params.cam_position + lens.x * params.cam_right + lens.y * params.cam_up;
    return Ray(origin, normalize(focus - origin));
}

// The ray through the centre of pixel (px, py) and of the lens, for the pixel-centre AOVs.
// mirror: src/render/camera.rs `pixel_centre_ray`
fn pixel_centre_ray(px: u32, py: u32) -> Ray {
    if params.ortho_half_height > 0.0 {
        return orthographic_ray(f32(px) + 0.5, f32(py) + 0.5);
    }
    let sx = (2.0 * (f32(px) + 0.5) / f32(params.width) - 1.0) * params.tan_half_vfov * params.aspect;
    let sy = (1.0 - 2.0 * (f32(py) + 0.5) / f32(params.height)) * params.tan_half_vfov;
    return Ray(params.cam_position, normalize(params.cam_forward + sx * params.cam_right + sy * params.cam_up));
}

// An orthographic camera's ray through image point (x, y), in pixels from the top-left
// corner: from the plane across the view through the camera's position, along forward.
// mirror: src/render/camera.rs `orthographic_ray`
fn orthographic_ray(x: f32, y: f32) -> Ray {
    let sx = (2.0 * x / f32(params.width) - 1.0) * params.ortho_half_height * params.aspect;
    let sy = (1.0 - 2.0 * y / f32(params.height)) * params.ortho_half_height;
    return Ray(params.cam_position + sx * params.cam_right + sy * params.cam_up, params.cam_forward);
}

// mirror: src/render/camera.rs `CameraRays::outside_window`
fn outside_window(x: u32, y: u32) -> bool {
    let w = params.window;
    return x < w.x || x >= w.z || y < w.y || y >= w.w;
}
