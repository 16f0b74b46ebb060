// Primary rays. mirror: src/render/camera.rs

// A box-filtered sample of pixel (px, py) through a pinhole or thin lens.
// mirror: src/render/camera.rs `generate_camera_ray`
fn generate_camera_ray(px: u32, py: u32, rng: Rng) -> Ray {
    let j = rng_2d(rng, 0u, DIM_PIXEL_X);
    let jx = j.x;
    let jy = j.y;
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
    let sx = (2.0 * (f32(px) + 0.5) / f32(params.width) - 1.0) * params.tan_half_vfov * params.aspect;
    let sy = (1.0 - 2.0 * (f32(py) + 0.5) / f32(params.height)) * params.tan_half_vfov;
    return Ray(params.cam_position, normalize(params.cam_forward + sx * params.cam_right + sy * params.cam_up));
}
