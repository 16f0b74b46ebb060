//! Lighting presets: a set of lights made for the object's bounds, so that one line lights
//! any mesh alike (docs/scene-format.md, section 3.10). A scene file names one in
//! `[lighting]`, a batch manifest in `render.lighting`, `meshtrace render` with
//! `--lighting`: an area key light, seeded random suns, a uniform world, the studio
//! environment or an HDRI. Each replaces the sky; the key light and the suns add their
//! lights.

use super::light::PunctualLight;
use super::source::FileSource;
use super::texture::load_environment;
use super::{Scene, SceneError, Sky};
use crate::math::{Aabb, uniform};
use glam::Vec3;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Blender's factory world, a grey of 0.0509: the area light's and the suns' default world,
/// as in the dataset scripts, so that shadows are dim rather than black.
const FACTORY_WORLD: f32 = 0.0509;

/// A checked lighting preset.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(try_from = "LightingFile")]
pub enum Lighting {
    /// A square `rect` light facing the centre of the object's bounding sphere (radius R)
    /// from `distance` R away, `size` R wide, `elevation` degrees above the horizontal and
    /// `azimuth` degrees from +Z towards +X; bright enough that a surface at the centre
    /// facing it receives `irradiance` W/m², and a `world` grey all round.
    Area {
        irradiance: f32,
        elevation: f32,
        azimuth: f32,
        distance: f32,
        size: f32,
        world: f32,
    },
    /// `count` directional lights, each from a direction uniform in azimuth and in the
    /// sine of its elevation within `elevation` (degrees: uniform over that band of the
    /// sky), of an irradiance uniform in `irradiance` (W/m²), all drawn from the input's
    /// uid and `seed`; with a `world` grey all round.
    Suns {
        count: u32,
        irradiance: [f32; 2],
        elevation: [f32; 2],
        shadows: bool,
        seed: u32,
        world: f32,
    },
    /// The same radiance `color` from every direction.
    Uniform { color: Vec3 },
    /// The built-in studio environment (the bare-mesh look), at `strength`, turned by
    /// `rotate` degrees about +Y.
    Studio { strength: f32, rotate: f32 },
    /// An equirectangular image, as `[sky] environment` reads it.
    Hdri {
        environment: PathBuf,
        strength: f32,
        rotate: f32,
    },
}

/// The preset names, as files spell them.
const NAMES: [&str; 5] = ["area", "suns", "uniform", "studio", "hdri"];

/// A `lighting` table as written: every key of every preset, checked by [`Lighting`]'s
/// conversion, which names the key at fault.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LightingFile {
    preset: String,
    irradiance: Option<Span>,
    elevation: Option<Span>,
    azimuth: Option<f32>,
    distance: Option<f32>,
    size: Option<f32>,
    world: Option<f32>,
    count: Option<u32>,
    shadows: Option<bool>,
    seed: Option<u32>,
    color: Option<[f32; 3]>,
    strength: Option<f32>,
    rotate: Option<f32>,
    environment: Option<PathBuf>,
}

/// A number, or a range `[min, max]` of them.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(untagged)]
enum Span {
    One(f32),
    Two([f32; 2]),
}

impl Span {
    fn range(self) -> [f32; 2] {
        match self {
            Span::One(x) => [x, x],
            Span::Two(r) => r,
        }
    }
}

impl TryFrom<LightingFile> for Lighting {
    type Error = String;

    fn try_from(f: LightingFile) -> Result<Self, String> {
        let preset = f.preset.as_str();
        let given: [(&str, bool); 13] = [
            ("irradiance", f.irradiance.is_some()),
            ("elevation", f.elevation.is_some()),
            ("azimuth", f.azimuth.is_some()),
            ("distance", f.distance.is_some()),
            ("size", f.size.is_some()),
            ("world", f.world.is_some()),
            ("count", f.count.is_some()),
            ("shadows", f.shadows.is_some()),
            ("seed", f.seed.is_some()),
            ("color", f.color.is_some()),
            ("strength", f.strength.is_some()),
            ("rotate", f.rotate.is_some()),
            ("environment", f.environment.is_some()),
        ];
        let takes: &[&str] = match preset {
            "area" => &[
                "irradiance",
                "elevation",
                "azimuth",
                "distance",
                "size",
                "world",
            ],
            "suns" => &[
                "count",
                "irradiance",
                "elevation",
                "shadows",
                "seed",
                "world",
            ],
            "uniform" => &["color"],
            "studio" => &["strength", "rotate"],
            "hdri" => &["environment", "strength", "rotate"],
            _ => {
                return Err(format!(
                    "lighting.preset: `{preset}` is not a lighting preset; there are {}",
                    NAMES.map(|n| format!("\"{n}\"")).join(", ")
                ));
            }
        };
        if let Some((key, _)) = given.iter().find(|(k, set)| *set && !takes.contains(k)) {
            return Err(format!(
                "lighting.{key}: is not a parameter of the `{preset}` preset, which takes {}",
                takes.join(", ")
            ));
        }
        let at_least = |key: &str, v: f32, min: f32| {
            if v.is_finite() && v >= min {
                Ok(v)
            } else {
                Err(format!("lighting.{key}: must be at least {min}, got {v}"))
            }
        };
        let positive = |key: &str, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(format!("lighting.{key}: must be positive, got {v}"))
            }
        };
        let angle = |key: &str, v: f32| {
            if v.is_finite() {
                Ok(v)
            } else {
                Err(format!(
                    "lighting.{key}: must be a finite number of degrees"
                ))
            }
        };
        let world = at_least("world", f.world.unwrap_or(FACTORY_WORLD), 0.0)?;
        let strength = at_least("strength", f.strength.unwrap_or(1.0), 0.0)?;
        let rotate = angle("rotate", f.rotate.unwrap_or(0.0))?;
        Ok(match preset {
            "area" => {
                let irradiance = match f.irradiance {
                    None => 2.5,
                    Some(Span::One(e)) => at_least("irradiance", e, 0.0)?,
                    Some(Span::Two(_)) => {
                        return Err("lighting.irradiance: the area light takes one number".into());
                    }
                };
                let elevation = match f.elevation {
                    None => 50.0,
                    Some(Span::One(e)) if (-90.0..=90.0).contains(&e) => e,
                    Some(_) => {
                        return Err(
                            "lighting.elevation: the area light takes one angle in [-90, 90]"
                                .into(),
                        );
                    }
                };
                let distance = positive("distance", f.distance.unwrap_or(4.0))?;
                if distance <= 1.0 {
                    return Err(format!(
                        "lighting.distance: must exceed 1 (bounding radii), so that the light \
                         is outside the object; got {distance}"
                    ));
                }
                Lighting::Area {
                    irradiance,
                    elevation,
                    azimuth: angle("azimuth", f.azimuth.unwrap_or(-30.0))?,
                    distance,
                    size: positive("size", f.size.unwrap_or(2.0))?,
                    world,
                }
            }
            "suns" => {
                let [lo, hi] = f.irradiance.map_or([0.5, 1.5], Span::range);
                let [e0, e1] = f.elevation.map_or([15.0, 75.0], Span::range);
                if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi) {
                    return Err(format!(
                        "lighting.irradiance: must be a number or a range [min, max] with \
                         0 ≤ min ≤ max, got [{lo}, {hi}]"
                    ));
                }
                if !(-90.0 <= e0 && e0 <= e1 && e1 <= 90.0) {
                    return Err(format!(
                        "lighting.elevation: must be an angle or a range [min, max] with \
                         -90 ≤ min ≤ max ≤ 90, got [{e0}, {e1}]"
                    ));
                }
                let count = f.count.unwrap_or(4);
                if !(1..=64).contains(&count) {
                    return Err(format!("lighting.count: must be 1 to 64, got {count}"));
                }
                Lighting::Suns {
                    count,
                    irradiance: [lo, hi],
                    elevation: [e0, e1],
                    shadows: f.shadows.unwrap_or(true),
                    seed: f.seed.unwrap_or(0),
                    world,
                }
            }
            "uniform" => {
                let color = f.color.unwrap_or([0.8; 3]);
                if !color.iter().all(|c| c.is_finite() && *c >= 0.0) {
                    return Err(format!(
                        "lighting.color: must be three numbers ≥ 0, got {color:?}"
                    ));
                }
                Lighting::Uniform {
                    color: Vec3::from(color),
                }
            }
            "studio" => Lighting::Studio {
                strength: f.strength.map_or(Ok(super::studio::STUDIO_STRENGTH), |s| {
                    at_least("strength", s, 0.0)
                })?,
                rotate,
            },
            _ => Lighting::Hdri {
                environment: f
                    .environment
                    .ok_or("lighting.environment: the hdri preset needs an image file")?,
                strength,
                rotate,
            },
        })
    }
}

impl Lighting {
    /// The preset with a relative HDRI path taken from `dir` (the file that names it).
    pub fn relative_to(mut self, dir: &Path) -> Self {
        if let Lighting::Hdri { environment, .. } = &mut self {
            *environment = dir.join(&*environment);
        }
        self
    }

    /// Lights `scene` by the preset: its sky replaced, its point, spot, directional and
    /// rect lights replaced by the preset's (emissive surfaces stay). The lights are placed
    /// about the bounds of what a bare mesh's camera frames, or of the whole mesh; random
    /// draws are keyed by the input's uid (its file name up to the first dot) and the seed,
    /// so that each object of a batch gets its own, the same on every run.
    pub fn apply(&self, scene: &mut Scene, files: &dyn FileSource) -> Result<(), SceneError> {
        let bounds = scene
            .framed
            .unwrap_or_else(|| Aabb::from_points(&scene.mesh.positions));
        let (center, radius) = if bounds.is_empty() {
            (Vec3::ZERO, 1.0)
        } else {
            (bounds.center(), (0.5 * bounds.extent().length()).max(1e-6))
        };
        let grey = |g: f32| Sky::Constant(Vec3::splat(g));
        match self {
            Lighting::Area {
                irradiance,
                elevation,
                azimuth,
                distance,
                size,
                world,
            } => {
                scene.lights = vec![area_light(
                    center,
                    radius,
                    *irradiance,
                    *elevation,
                    *azimuth,
                    *distance,
                    *size,
                )];
                scene.sky = grey(*world);
            }
            Lighting::Suns {
                count,
                irradiance,
                elevation,
                shadows,
                seed,
                world,
            } => {
                let key = scene.path.as_deref().map(super::uid).unwrap_or_default();
                scene.lights = (0..*count)
                    .map(|k| sun(&key, *seed, k, *irradiance, *elevation, *shadows))
                    .collect();
                scene.sky = grey(*world);
            }
            Lighting::Uniform { color } => {
                scene.lights.clear();
                scene.sky = Sky::Constant(*color);
            }
            Lighting::Studio { strength, rotate } => {
                scene.lights.clear();
                scene.sky = Sky::Environment {
                    texture: super::studio::environment(&mut scene.textures)?,
                    strength: *strength,
                    rotation: rotate.to_radians(),
                };
            }
            Lighting::Hdri {
                environment,
                strength,
                rotate,
            } => {
                scene.lights.clear();
                // Named by the file that asked for it (the image's own name is in the message).
                let asker = scene.path.as_deref().unwrap_or(environment);
                let texture = load_environment(environment, &mut scene.textures, files).map_err(
                    |message| SceneError::Invalid {
                        path: super::shown(asker),
                        field: "lighting.environment".into(),
                        message,
                    },
                )?;
                scene.sky = Sky::Environment {
                    texture,
                    strength: *strength,
                    rotation: rotate.to_radians(),
                };
            }
        }
        Ok(())
    }
}

/// The unit direction `elevation` degrees above the horizontal (+Y up) and `azimuth`
/// degrees from +Z towards +X.
fn direction(elevation: f32, azimuth: f32) -> Vec3 {
    let (e, a) = (elevation.to_radians(), azimuth.to_radians());
    Vec3::new(e.cos() * a.sin(), e.sin(), e.cos() * a.cos())
}

/// [`Lighting::Area`]'s light for a bounding sphere at `center` of `radius`.
fn area_light(
    center: Vec3,
    radius: f32,
    irradiance: f32,
    elevation: f32,
    azimuth: f32,
    distance: f32,
    size: f32,
) -> PunctualLight {
    let towards = direction(elevation, azimuth);
    // Edges perpendicular to the axis, ordered so that edge_u × edge_v (= −towards) faces
    // the centre.
    let side = towards.any_orthonormal_vector();
    let (edge_u, edge_v) = (towards.cross(side), side);
    PunctualLight::Rect {
        center: center + distance * radius * towards,
        edge_u: edge_u * (size * radius),
        edge_v: edge_v * (size * radius),
        radiance: Vec3::splat(irradiance / square_irradiance(size / distance)),
    }
}

/// The irradiance that a square of unit radiance, `width` times its distance wide, sends to
/// a point on its axis facing it: its projected solid angle, 4 A / √(1 + A²) · atan(A /
/// √(1 + A²)) with A its half-width over its distance (the form factor of a parallel
/// rectangle, four corner quarters). π for an infinite plane.
fn square_irradiance(width: f32) -> f32 {
    let a = 0.5 * width;
    let r = (1.0 + a * a).sqrt();
    4.0 * a / r * (a / r).atan()
}

/// [`Lighting::Suns`]'s sun `k`, drawn for the input `key` and `seed`.
fn sun(
    key: &str,
    seed: u32,
    k: u32,
    [lo, hi]: [f32; 2],
    [e0, e1]: [f32; 2],
    shadows: bool,
) -> PunctualLight {
    // Keyed apart from a batch preset's draws for the same uid.
    let key = format!("lighting:{key}");
    let u = |dim: u32| uniform(&key, seed, 3 * k + dim) as f32;
    // Uniform over the band of the sky: uniform in the sine of the elevation.
    let (s0, s1) = (e0.to_radians().sin(), e1.to_radians().sin());
    let elevation = (s0 + (s1 - s0) * u(0)).clamp(-1.0, 1.0).asin().to_degrees();
    let azimuth = 360.0 * u(1);
    PunctualLight::Directional {
        direction: -direction(elevation, azimuth),
        irradiance: Vec3::splat(lo + (hi - lo) * u(2)),
        shadows,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    fn parse(text: &str) -> Result<Lighting, String> {
        #[derive(Deserialize)]
        struct Doc {
            lighting: Lighting,
        }
        toml::from_str::<Doc>(text)
            .map(|d| d.lighting)
            .map_err(|e| e.message().to_string())
    }

    #[test]
    fn a_square_sends_its_projected_solid_angle() {
        // Midpoint-rule integral of cos θ over the square, seen from 1 away on its axis.
        let width = 1.5f32;
        let n = 800;
        let mut sum = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let x = (((i as f64) + 0.5) / n as f64 - 0.5) * width as f64;
                let y = (((j as f64) + 0.5) / n as f64 - 0.5) * width as f64;
                let r2 = x * x + y * y + 1.0;
                // cos at the receiver × cos at the emitter / r² × dA.
                sum += 1.0 / (r2 * r2) * (width as f64 / n as f64).powi(2);
            }
        }
        let analytic = square_irradiance(width) as f64;
        assert!((analytic - sum).abs() < 1e-5 * sum, "{analytic} vs {sum}");
        assert!((square_irradiance(1e6) - PI).abs() < 1e-3);
    }

    #[test]
    fn the_area_light_faces_the_centre_from_its_angles() {
        let light = area_light(Vec3::new(1.0, 2.0, 3.0), 2.0, 2.5, 90.0, 0.0, 4.0, 2.0);
        let PunctualLight::Rect {
            center,
            edge_u,
            edge_v,
            radiance,
        } = light
        else {
            panic!("not a rect light");
        };
        assert!((center - Vec3::new(1.0, 10.0, 3.0)).length() < 1e-5);
        assert!(edge_u.cross(edge_v).normalize().dot(Vec3::NEG_Y) > 0.9999);
        assert!((edge_u.length() - 4.0).abs() < 1e-5 && (edge_v.length() - 4.0).abs() < 1e-5);
        assert!((radiance.x * square_irradiance(0.5) - 2.5).abs() < 1e-5);
    }

    #[test]
    fn suns_are_drawn_per_object_and_seed_within_their_ranges() {
        let draw = |key: &str, seed| {
            (0..4)
                .map(|k| sun(key, seed, k, [1.0, 3.0], [15.0, 75.0], true))
                .collect::<Vec<_>>()
        };
        assert_eq!(draw("a", 0), draw("a", 0));
        assert_ne!(draw("a", 0), draw("b", 0));
        assert_ne!(draw("a", 0), draw("a", 1));
        for light in draw("a", 0).into_iter().chain(draw("b", 7)) {
            let PunctualLight::Directional {
                direction,
                irradiance,
                ..
            } = light
            else {
                panic!("not a sun");
            };
            // Travelling down, from 15° to 75° above the horizon.
            let elevation = (-direction.y).asin().to_degrees();
            assert!(
                (15.0 - 1e-3..=75.0 + 1e-3).contains(&elevation),
                "{elevation}"
            );
            assert!((1.0..=3.0).contains(&irradiance.x));
        }
    }

    #[test]
    fn presets_take_their_own_keys_and_name_the_bad_one() {
        assert_eq!(
            parse("[lighting]\npreset = \"suns\"\ncount = 2\nirradiance = 2.0"),
            Ok(Lighting::Suns {
                count: 2,
                irradiance: [2.0, 2.0],
                elevation: [15.0, 75.0],
                shadows: true,
                seed: 0,
                world: FACTORY_WORLD,
            })
        );
        let bad = [
            (
                "preset = \"spot\"",
                "lighting.preset: `spot` is not a lighting preset",
            ),
            (
                "preset = \"area\"\ncount = 2",
                "lighting.count: is not a parameter of the `area`",
            ),
            (
                "preset = \"suns\"\ncount = 0",
                "lighting.count: must be 1 to 64",
            ),
            (
                "preset = \"suns\"\nirradiance = [3, 1]",
                "lighting.irradiance: must be",
            ),
            (
                "preset = \"area\"\ndistance = 0.5",
                "lighting.distance: must exceed 1",
            ),
            (
                "preset = \"hdri\"",
                "lighting.environment: the hdri preset needs",
            ),
            (
                "preset = \"uniform\"\ncolor = [1, -1, 0]",
                "lighting.color: must be",
            ),
        ];
        for (body, expected) in bad {
            let e = parse(&format!("[lighting]\n{body}")).expect_err(body);
            assert!(e.contains(expected), "{body}: {e}");
        }
    }
}
