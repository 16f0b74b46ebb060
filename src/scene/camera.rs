//! The camera: where it stands, where it looks, and its projection (a pinhole or thin lens
//! with a field of view, or orthographic with a view height). Ray generation from it is
//! `render::camera`.

use glam::Vec3;

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
    /// An orthographic camera's view height in world units (its width follows the image's
    /// aspect); 0 for a perspective camera, which `vfov` describes.
    pub ortho_height: f32,
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
            ortho_height: 0.0,
        })
    }

    /// This camera made orthographic, seeing a view `height` world units high (and as wide
    /// as the image's aspect makes it) along parallel rays: no field of view, no lens.
    pub fn orthographic(self, height: f32) -> Self {
        Self {
            ortho_height: height,
            aperture: 0.0,
            ..self
        }
    }

    /// Whether the camera is orthographic.
    pub fn is_orthographic(&self) -> bool {
        self.ortho_height > 0.0
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
}
