//! Punctual lights: points, spots and directional lights, from `[[lights]]` tables and
//! glTF's KHR_lights_punctual. They are delta lights: next event estimation reaches them,
//! and no ray ever hits one.

use glam::{Mat4, Vec3};

/// A validated punctual light, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PunctualLight {
    /// Radiant intensity `intensity` (W/sr) in every direction from `position`.
    Point { position: Vec3, intensity: Vec3 },
    /// A point light restricted to a cone about unit `direction`: full intensity within
    /// `beam_width` of the axis, falling off linearly in angle to zero at `cutoff` (both
    /// in radians, `beam_width` ≤ `cutoff`), as Mitsuba 3's `spot`.
    Spot {
        position: Vec3,
        direction: Vec3,
        intensity: Vec3,
        cutoff: f32,
        beam_width: f32,
    },
    /// Parallel light travelling along unit `direction`, of irradiance `irradiance`
    /// (W/m²) on a surface facing it.
    Directional { direction: Vec3, irradiance: Vec3 },
}

impl PunctualLight {
    /// The light moved by the affine transform `m`: its position as a point, its direction
    /// as a vector, renormalised. `None` when `m` collapses the direction or takes the
    /// position out of finite space.
    pub fn transformed(&self, m: Mat4) -> Option<Self> {
        let point = |p: Vec3| Some(m.transform_point3(p)).filter(|p| p.is_finite());
        let direction = |d: Vec3| m.transform_vector3(d).try_normalize();
        Some(match *self {
            PunctualLight::Point {
                position,
                intensity,
            } => PunctualLight::Point {
                position: point(position)?,
                intensity,
            },
            PunctualLight::Spot {
                position,
                direction: d,
                intensity,
                cutoff,
                beam_width,
            } => PunctualLight::Spot {
                position: point(position)?,
                direction: direction(d)?,
                intensity,
                cutoff,
                beam_width,
            },
            PunctualLight::Directional {
                direction: d,
                irradiance,
            } => PunctualLight::Directional {
                direction: direction(d)?,
                irradiance,
            },
        })
    }
}
