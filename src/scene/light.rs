//! Lights that are not surfaces: points, spots and directional lights, from `[[lights]]`
//! tables and glTF's KHR_lights_punctual, and the rectangular lights of dataset presets and
//! `[[lights]]`. Next event estimation reaches them, and no ray ever hits one: a rectangle
//! is seen by no camera and casts no shadow, as a Blender area light in Cycles.

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
    /// (W/m²) on a surface facing it; with `shadows` false it passes through everything
    /// (Blender's sun with `use_shadow` off, which dataset scripts use).
    Directional {
        direction: Vec3,
        irradiance: Vec3,
        shadows: bool,
    },
    /// A rectangle of uniform `radiance` (W/m²/sr) centred on `center`, spanned by the
    /// perpendicular edges `edge_u` and `edge_v` (their full lengths), emitting on the side
    /// of `edge_u × edge_v`.
    Rect {
        center: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        radiance: Vec3,
    },
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
                shadows,
            } => PunctualLight::Directional {
                direction: direction(d)?,
                irradiance,
                shadows,
            },
            PunctualLight::Rect {
                center,
                edge_u,
                edge_v,
                radiance,
            } => {
                // A transform that shears or scales the plane changes the area; the
                // radiance stays, as a surface's does.
                let (u, v) = (m.transform_vector3(edge_u), m.transform_vector3(edge_v));
                u.cross(v).try_normalize()?;
                PunctualLight::Rect {
                    center: point(center)?,
                    edge_u: u,
                    edge_v: v,
                    radiance,
                }
            }
        })
    }
}
