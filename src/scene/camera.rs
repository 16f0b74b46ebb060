//! The camera: pinhole or thin lens, and the mapping from a pixel sample to a primary ray.

use crate::math::Ray;
use crate::render::rng::{self, Rng};
use crate::render::sampling::sample_concentric_disk;
use glam::{Vec2, Vec3};

/// A validated camera with its orthonormal frame precomputed.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    /// Unit vector towards `look_at`.
    pub forward: Vec3,
    /// Unit vector towards increasing image x.
    pub right: Vec3,
    /// Unit vector towards decreasing image y (up in the picture).
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub vfov: f32,
    /// Lens diameter; 0 is a pinhole.
    pub aperture: f32,
    /// Distance along `forward` of the plane in focus.
    pub focus_distance: f32,
}

impl Camera {
    /// Builds the frame; `None` when `look_at` equals `position` or `up` is parallel to the view.
    pub fn new(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        vfov: f32,
        aperture: f32,
        focus_distance: Option<f32>,
    ) -> Option<Self> {
        let forward = (look_at - position).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        Some(Self {
            position,
            forward,
            right,
            up,
            vfov,
            aperture,
            focus_distance: focus_distance.unwrap_or((look_at - position).length()),
        })
    }

    /// A pinhole camera (vertical field of view 40 degrees) that frames `bounds` from the
    /// front (+Z) and slightly above, as for a bare mesh. `None` when the bounds are too large
    /// for f32 (their size or the camera distance overflows).
    pub fn framing(bounds: &crate::math::Aabb) -> Option<Self> {
        let vfov = 40.0f32;
        let center = bounds.center();
        // Far from the origin, a tiny mesh still needs a camera distance that f32 resolves.
        let resolvable = 1e-5 * (1.0 + center.abs().max_element());
        let radius = (0.5 * bounds.extent().length()).max(resolvable);
        let distance = 1.1 * radius / (0.5 * vfov.to_radians()).sin();
        let position = center + distance * Vec3::new(0.0, 0.25, 1.0).normalize();
        if !(center.is_finite() && position.is_finite()) {
            return None;
        }
        Self::new(position, center, Vec3::Y, vfov, 0.0, None)
    }

    /// tan(vfov / 2): the image plane's half height at unit distance.
    pub fn tan_half_vfov(&self) -> f32 {
        (0.5 * self.vfov.to_radians()).tan()
    }

    /// The primary ray of one sample of pixel (`px`, `py`): a box filter (uniform jitter
    /// over the pixel) and, for a thin lens, a uniform point on the aperture.
    /// mirror: shaders/camera.wgsl `generate_camera_ray`
    pub fn generate_camera_ray(&self, px: u32, py: u32, width: u32, height: u32, rng: &Rng) -> Ray {
        let jx = rng.rng_1d(0, rng::DIM_PIXEL_X);
        let jy = rng.rng_1d(0, rng::DIM_PIXEL_Y);
        let tan_half = self.tan_half_vfov();
        let aspect = width as f32 / height as f32;
        let sx = (2.0 * (px as f32 + jx) / width as f32 - 1.0) * tan_half * aspect;
        let sy = (1.0 - 2.0 * (py as f32 + jy) / height as f32) * tan_half;
        let dir = self.forward + sx * self.right + sy * self.up;
        if self.aperture <= 0.0 {
            return Ray::new(self.position, dir.normalize());
        }
        let lens = 0.5
            * self.aperture
            * sample_concentric_disk(Vec2::new(
                rng.rng_1d(0, rng::DIM_LENS_U),
                rng.rng_1d(0, rng::DIM_LENS_V),
            ));
        // `dir` has unit length along `forward`, so this point lies on the focal plane.
        let focus = self.position + self.focus_distance * dir;
        let origin = self.position + lens.x * self.right + lens.y * self.up;
        Ray::new(origin, (focus - origin).normalize())
    }
}
