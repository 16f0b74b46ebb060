//! Primary rays: the mapping from a pixel sample to a camera ray, through a pinhole or a
//! thin lens, or along parallel rays for an orthographic camera. Every function has a WGSL twin of the same name in `shaders/camera.wgsl`.

use super::rng::{self, Rng};
use super::sampling::sample_concentric_disk;
use crate::math::{Aabb, Ray};
use crate::scene::Camera;
use glam::{Vec2, Vec3};

/// What ray generation reads of the camera and the image, computed once per render rather
/// than once per ray (tan(vfov / 2) and the aspect ratio). The GPU receives the same values
/// in its parameter block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraRays {
    pub position: Vec3,
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    /// tan(vfov / 2): the image plane's half height at unit distance.
    pub tan_half_vfov: f32,
    /// Width over height.
    pub aspect: f32,
    pub aperture: f32,
    pub focus_distance: f32,
    /// Half an orthographic camera's view height in world units; 0 for a perspective one.
    pub ortho_half_height: f32,
    pub width: u32,
    pub height: u32,
    /// The pixels [x0, x1) × [y0, y1) whose camera rays may meet the scene
    /// ([`CameraRays::with_window`]); all of them until it is set.
    pub window: [u32; 4],
    /// [`RenderSettings::filter_width`](crate::scene::RenderSettings::filter_width); 1
    /// until [`CameraRays::with_filter`] sets it.
    pub filter_width: f32,
}

impl CameraRays {
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        Self {
            position: camera.position,
            forward: camera.forward,
            right: camera.right,
            up: camera.up,
            tan_half_vfov: (0.5 * camera.vfov.to_radians()).tan(),
            aspect: width as f32 / height as f32,
            aperture: camera.aperture,
            focus_distance: camera.focus_distance,
            ortho_half_height: 0.5 * camera.ortho_height,
            width,
            height,
            window: [0, 0, width, height],
            filter_width: 1.0,
        }
    }

    /// These rays with camera samples over a square of `width` pixels about each pixel's
    /// centre.
    pub fn with_filter(mut self, width: f32) -> Self {
        self.filter_width = width;
        self
    }

    /// These rays with [`CameraRays::window`] set to the pixels whose rays may meet a box
    /// `bounds` (the scene's): those whose square overlaps the rectangle around the box's
    /// eight corners projected onto the image, one pixel wider on each side for rounding
    /// (and wider still by what a [`CameraRays::filter_width`] above 1 reaches past a pixel:
    /// set it first). A ray meets the box only through its corners' convex hull, which the
    /// rectangle holds, so every ray of a pixel outside misses. All pixels where that cannot be told: a
    /// thin lens, whose rays do not share an origin, or a corner at or behind the pinhole.
    pub fn with_window(mut self, bounds: &Aabb) -> Self {
        self.window = [0, 0, self.width, self.height];
        if bounds.is_empty() || self.aperture > 0.0 {
            return self;
        }
        let (w, h) = (self.width as f32, self.height as f32);
        let (mut lo, mut hi) = (Vec2::INFINITY, Vec2::NEG_INFINITY);
        for k in 0..8 {
            let v = bounds.corner(k) - self.position;
            // The corner's image-plane coordinates, in [-1, 1] across the image.
            let (x, y) = if self.ortho_half_height > 0.0 {
                let half = self.ortho_half_height;
                (
                    v.dot(self.right) / (half * self.aspect),
                    v.dot(self.up) / half,
                )
            } else {
                let z = v.dot(self.forward);
                if z.is_nan() || z <= 0.0 {
                    return self;
                }
                let half = z * self.tan_half_vfov;
                (
                    v.dot(self.right) / (half * self.aspect),
                    v.dot(self.up) / half,
                )
            };
            let p = Vec2::new((x + 1.0) * 0.5 * w, (1.0 - y) * 0.5 * h);
            lo = lo.min(p);
            hi = hi.max(p);
        }
        if !(lo.is_finite() && hi.is_finite()) {
            return self;
        }
        let clamp = |v: f32, max: u32| v.clamp(0.0, max as f32) as u32;
        let margin = 1.0 + (0.5 * (self.filter_width - 1.0)).max(0.0).ceil();
        self.window = [
            clamp(lo.x.floor() - margin, self.width),
            clamp(lo.y.floor() - margin, self.height),
            clamp(hi.x.ceil() + margin, self.width),
            clamp(hi.y.ceil() + margin, self.height),
        ];
        self
    }

    /// Whether pixel (`x`, `y`) lies outside [`CameraRays::window`]: its camera rays all
    /// miss the scene. mirror: shaders/camera.wgsl `outside_window`
    pub fn outside_window(&self, x: u32, y: u32) -> bool {
        let [x0, y0, x1, y1] = self.window;
        x < x0 || x >= x1 || y < y0 || y >= y1
    }
}

/// The primary ray of one sample of pixel (`px`, `py`): a box filter (uniform jitter over
/// the pixel, or over the square of [`CameraRays::filter_width`] about its centre) and, for
/// a thin lens, a uniform point on the aperture.
/// mirror: shaders/camera.wgsl `generate_camera_ray`
pub fn generate_camera_ray(cam: &CameraRays, px: u32, py: u32, rng: &Rng) -> Ray {
    let Vec2 {
        x: mut jx,
        y: mut jy,
    } = rng.rng_2d(0, rng::DIM_PIXEL_X);
    // The unit square is left alone, so that the default rays stay as they were, bit for bit.
    if cam.filter_width != 1.0 {
        jx = 0.5 + cam.filter_width * (jx - 0.5);
        jy = 0.5 + cam.filter_width * (jy - 0.5);
    }
    if cam.ortho_half_height > 0.0 {
        return orthographic_ray(cam, px as f32 + jx, py as f32 + jy);
    }
    let sx = (2.0 * (px as f32 + jx) / cam.width as f32 - 1.0) * cam.tan_half_vfov * cam.aspect;
    let sy = (1.0 - 2.0 * (py as f32 + jy) / cam.height as f32) * cam.tan_half_vfov;
    let dir = cam.forward + sx * cam.right + sy * cam.up;
    if cam.aperture <= 0.0 {
        return Ray::new(cam.position, dir.normalize());
    }
    let lens = 0.5 * cam.aperture * sample_concentric_disk(rng.rng_2d(0, rng::DIM_LENS_U));
    // `dir` has unit length along `forward`, so this point lies on the focal plane.
    let focus = cam.position + cam.focus_distance * dir;
    let origin = cam.position + lens.x * cam.right + lens.y * cam.up;
    Ray::new(origin, (focus - origin).normalize())
}

/// The ray through the centre of pixel (`px`, `py`) and of the lens: what the pixel-centre
/// AOVs (object and material ids) see. Draws no random numbers.
/// mirror: shaders/camera.wgsl `pixel_centre_ray`
pub fn pixel_centre_ray(cam: &CameraRays, px: u32, py: u32) -> Ray {
    if cam.ortho_half_height > 0.0 {
        return orthographic_ray(cam, px as f32 + 0.5, py as f32 + 0.5);
    }
    let sx = (2.0 * (px as f32 + 0.5) / cam.width as f32 - 1.0) * cam.tan_half_vfov * cam.aspect;
    let sy = (1.0 - 2.0 * (py as f32 + 0.5) / cam.height as f32) * cam.tan_half_vfov;
    Ray::new(
        cam.position,
        (cam.forward + sx * cam.right + sy * cam.up).normalize(),
    )
}

/// An orthographic camera's ray through image point (`x`, `y`) (in pixels from the top-left
/// corner): it starts on the plane through the camera's position across its view, and runs
/// along `forward`.
/// mirror: shaders/camera.wgsl `orthographic_ray`
pub fn orthographic_ray(cam: &CameraRays, x: f32, y: f32) -> Ray {
    let sx = (2.0 * x / cam.width as f32 - 1.0) * cam.ortho_half_height * cam.aspect;
    let sy = (1.0 - 2.0 * y / cam.height as f32) * cam.ortho_half_height;
    Ray::new(cam.position + sx * cam.right + sy * cam.up, cam.forward)
}
