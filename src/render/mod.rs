//! Rendering: the flat scene tables both devices read ([`RenderScene`]); the stages of the
//! path tracer, each a Rust file with a WGSL twin of the same name in `shaders/` (`rng`,
//! `sampling`, `bsdf`, `camera`, `surface`, `lights`, `integrator`); and the two drivers that run
//! them, [`cpu`] and [`gpu`], chosen by [`backend`]. The GPU renderer uploads exactly these
//! tables, so a path can be replayed on either device.

pub mod backend;
pub mod bsdf;
pub mod camera;
pub mod caustics;
pub mod cpu;
pub mod digest;
pub mod environment;
pub mod gpu;
pub mod integrator;
pub mod lights;
pub mod rng;
pub mod sampling;
pub mod surface;
pub mod texture;
pub mod watch;

use crate::bvh::{BuildParams, Bvh, BvhError, WideBvh};
use crate::film::Film;
use crate::film::srgb8_to_linear;
use crate::geometry::{self, TriVerts};
use crate::math::{Aabb, luminance};
use crate::scene::material::MAT_ALPHA_MASK;
use crate::scene::{
    Camera, Material, NO_NORMAL, NO_TANGENT, NO_TEXTURE, NO_UV, PunctualLight, RenderSettings,
    Scene, Sky, Texture,
};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Per-triangle shading data in leaf order (48 bytes): vertex normals, the material, and
/// the probability that light sampling picks this triangle.
/// mirror: shaders/types.wgsl `TriShading`
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TriShading {
    pub n0: [f32; 3],
    pub material: u32,
    pub n1: [f32; 3],
    /// Probability of choosing this triangle in next event estimation; 0 for non-emitters.
    pub emitter_pmf: f32,
    pub n2: [f32; 3],
    /// [`TRI_SMOOTH`], [`TRI_UV`] and [`TRI_TANGENT`] bits.
    pub flags: u32,
}

/// [`TriShading::flags`]: the triangle has vertex normals (smooth shading).
pub const TRI_SMOOTH: u32 = 1;
/// [`TriShading::flags`]: the triangle has texture coordinates in [`RenderScene::tri_uvs`].
pub const TRI_UV: u32 = 2;
/// [`TriShading::flags`]: the triangle's material has a normal map, and the triangle has
/// tangents in [`RenderScene::tri_tangents`].
pub const TRI_TANGENT: u32 = 4;

/// Per-triangle tangents in leaf order (48 bytes): each corner's unit tangent (xyz) and
/// the handedness of its bitangent (w = ±1; bitangent = w · normal × tangent).
/// mirror: shaders/types.wgsl `TriTangents`
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TriTangents {
    pub t0: [f32; 4],
    pub t1: [f32; 4],
    pub t2: [f32; 4],
}

/// Per-triangle texture coordinates in leaf order (32 bytes), v running down an image
/// from its top edge. mirror: shaders/types.wgsl `TriUvs`
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TriUvs {
    pub uv0: [f32; 2],
    pub uv1: [f32; 2],
    pub uv2: [f32; 2],
    pub _pad: [u32; 2],
}

/// A punctual light as both renderers read it (64 bytes), from
/// [`PunctualLight`](crate::scene::PunctualLight). mirror: shaders/types.wgsl `Light`
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Light {
    pub position: [f32; 3],
    /// [`LIGHT_POINT`], [`LIGHT_SPOT`] or [`LIGHT_DIRECTIONAL`].
    pub kind: u32,
    /// A spot's axis, or the direction a directional light travels (unit).
    pub direction: [f32; 3],
    /// cos of a spot's cutoff angle.
    pub cos_cutoff: f32,
    /// Radiant intensity (W/sr), or a directional light's irradiance (W/m²).
    pub intensity: [f32; 3],
    /// cos of a spot's full-intensity beam width.
    pub cos_beam: f32,
    /// A spot's cutoff angle (radians) and 1 / (cutoff − beam width): its falloff is linear
    /// in the angle from the axis.
    pub cutoff: f32,
    pub inv_transition: f32,
    pub _pad: [u32; 2],
}

/// [`Light::kind`] codes.
pub const LIGHT_POINT: u32 = 0;
pub const LIGHT_SPOT: u32 = 1;
pub const LIGHT_DIRECTIONAL: u32 = 2;

/// The bit of an entry of [`RenderScene::emitters`] that marks a punctual light: the other
/// bits are its index in [`RenderScene::lights`].
pub const LIGHT_EMITTER: u32 = 1 << 31;

impl Light {
    /// The table entry of a scene light.
    pub fn new(l: &PunctualLight) -> Self {
        let mut out = Self::default();
        match *l {
            PunctualLight::Point {
                position,
                intensity,
            } => {
                (out.kind, out.position, out.intensity) =
                    (LIGHT_POINT, position.into(), intensity.into());
            }
            PunctualLight::Spot {
                position,
                direction,
                intensity,
                cutoff,
                beam_width,
            } => {
                out = Self {
                    position: position.into(),
                    kind: LIGHT_SPOT,
                    direction: direction.into(),
                    cos_cutoff: cutoff.cos(),
                    intensity: intensity.into(),
                    cos_beam: beam_width.cos(),
                    cutoff,
                    inv_transition: if cutoff > beam_width {
                        1.0 / (cutoff - beam_width)
                    } else {
                        0.0
                    },
                    _pad: [0; 2],
                };
            }
            PunctualLight::Directional {
                direction,
                irradiance,
            } => {
                (out.kind, out.direction, out.intensity) =
                    (LIGHT_DIRECTIONAL, direction.into(), irradiance.into());
            }
        }
        out
    }
}

/// The entry of [`RenderScene::emitters`] that stands for the sky.
/// The shaders get it from `render::gpu::shader::shared_constants`.
pub const SKY_EMITTER: u32 = u32::MAX;

/// Everything an integrator reads, as flat tables in BVH leaf order.
#[derive(Clone, Debug)]
pub struct RenderScene {
    pub bvh: Bvh,
    /// The same tree collapsed to eight children a node, which the CPU renderer traverses
    /// (the GPU traverses `bvh`).
    pub wide: WideBvh,
    pub tris: Vec<TriVerts>,
    /// Each triangle's unit geometric normal, as `geometry::geometric_normal` gives it:
    /// derived data of the CPU renderer, which would otherwise take a square root and a
    /// division at every hit (the shaders recompute it).
    pub tri_normals: Vec<Vec3>,
    pub shading: Vec<TriShading>,
    /// Texture coordinates of every triangle, or empty when the scene has no textures.
    pub tri_uvs: Vec<TriUvs>,
    /// Tangents of every triangle, or empty when no triangle has a normal map.
    pub tri_tangents: Vec<TriTangents>,
    pub materials: Vec<Material>,
    /// The textures material slots index, and their texels.
    pub textures: Vec<Texture>,
    pub texels: Vec<u32>,
    /// Texel values of 8-bit channels: entries 0–255 decode sRGB, 256–511 are linear
    /// (`k / 255`). The shaders read the same table, so both renderers decode alike.
    pub texel_lut: Vec<f32>,
    /// Point, spot and directional lights.
    pub lights: Vec<Light>,
    /// The lights next event estimation picks from: leaf-order indices of emissive
    /// triangles, then punctual lights ([`LIGHT_EMITTER`] | index), then [`SKY_EMITTER`]
    /// if the sky is not black; and their inclusive CDF.
    pub emitters: Vec<u32>,
    pub emitter_cdf: Vec<f32>,
    /// The area of each entry of `emitters` that is a triangle (zero for the others), as
    /// `geometry::triangle_area` gives it: derived data of the CPU renderer, which would
    /// otherwise recompute it at every light sample (the shaders recompute it); the
    /// triangle's normal is in `tri_normals`.
    pub emitter_areas: Vec<f32>,
    /// Probability that next event estimation picks the sky (sampled uniformly over the
    /// sphere): 0 for a black sky, 1 with no emissive triangles, else 1/2.
    pub sky_pmf: f32,
    pub camera: Camera,
    pub sky: Sky,
    /// The environment map's parameters (all zero for another sky).
    pub env: Environment,
    /// The environment's sampling distribution ([`environment::env_distribution`]); empty
    /// for another sky.
    pub env_cdf: Vec<f32>,
    /// Spheres around the specular geometry, which caustic light subpaths aim at
    /// ([`caustics::caustic_targets`]); empty where no material may be delta or the scene's
    /// settings turn caustics off, and then no light subpath is traced.
    pub caustic_targets: Vec<caustics::CausticTarget>,
    /// A sphere around every triangle (centre, radius), outside which a directional light's
    /// light subpaths start ([`caustics::start_at_directional`]).
    pub scene_sphere: (Vec3, f32),
}

/// An environment map as both renderers read it: its texture record, strength, the cosine
/// and sine of its rotation about +Y, and its cells ([`environment::env_cells`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Environment {
    pub texture: u32,
    pub strength: f32,
    pub rotation: [f32; 2],
    pub cells: [u32; 2],
}

impl RenderScene {
    /// Builds the BVH over the scene's triangles and lays out the tables in its leaf order.
    pub fn new(scene: &Scene, params: &BuildParams) -> Result<Self, BvhError> {
        let mesh = &scene.mesh;
        let corners: Vec<[Vec3; 3]> = mesh.triangles.iter().map(|t| mesh.vertices(t)).collect();
        let bounds: Vec<Aabb> = corners.iter().map(|c| Aabb::from_points(c)).collect();
        let bvh = Bvh::build(&bounds, params)?;
        let tris: Vec<TriVerts> = bvh
            .order
            .iter()
            .map(|&i| {
                let mut t = TriVerts::new(corners[i as usize]);
                t.set_object(mesh.object(i as usize));
                let m = &scene.materials[mesh.triangles[i as usize].material as usize];
                if m.flags & MAT_ALPHA_MASK != 0 {
                    t.set_masked();
                }
                t
            })
            .collect();
        drop(corners);
        let textured = !scene.textures.records.is_empty();
        let shading: Vec<TriShading> = bvh
            .order
            .iter()
            .map(|&i| {
                let t = &mesh.triangles[i as usize];
                let mut s = TriShading {
                    material: t.material,
                    ..Default::default()
                };
                if t.n[0] != NO_NORMAL {
                    let [a, b, c] = t.n.map(|k| mesh.normals[k as usize].to_array());
                    (s.n0, s.n1, s.n2, s.flags) = (a, b, c, TRI_SMOOTH);
                }
                if textured && t.t[0] != NO_UV {
                    s.flags |= TRI_UV;
                    let normal_map = scene.materials[t.material as usize].normal_texture;
                    if normal_map != NO_TEXTURE && mesh.tangent_indices(i as usize)[0] != NO_TANGENT
                    {
                        s.flags |= TRI_TANGENT;
                    }
                }
                s
            })
            .collect();
        // Only a scene with normal maps reads tangents.
        let tri_tangents: Vec<TriTangents> = if shading.iter().any(|s| s.flags & TRI_TANGENT != 0) {
            bvh.order
                .iter()
                .map(|&i| {
                    let g = mesh.tangent_indices(i as usize);
                    if g[0] == NO_TANGENT {
                        return TriTangents::default();
                    }
                    let [t0, t1, t2] = g.map(|k| mesh.tangents[k as usize].to_array());
                    TriTangents { t0, t1, t2 }
                })
                .collect()
        } else {
            Vec::new()
        };
        // Only a scene with textures reads texture coordinates.
        let tri_uvs: Vec<TriUvs> = if textured {
            bvh.order
                .iter()
                .map(|&i| {
                    let t = &mesh.triangles[i as usize];
                    let uv = |k: usize| {
                        if t.t[k] == NO_UV {
                            [0.0; 2]
                        } else {
                            mesh.texcoords[t.t[k] as usize].to_array()
                        }
                    };
                    TriUvs {
                        uv0: uv(0),
                        uv1: uv(1),
                        uv2: uv(2),
                        _pad: [0; 2],
                    }
                })
                .collect()
        } else {
            Vec::new()
        };
        let texel_lut = (0..=255u8)
            .map(srgb8_to_linear)
            .chain((0..=255u8).map(|k| k as f32 / 255.0))
            .collect();
        let scene_bounds = bounds.iter().fold(Aabb::EMPTY, |a, &b| a.union(b));
        let scene_sphere = if bounds.is_empty() {
            (Vec3::ZERO, 0.0)
        } else {
            let c = scene_bounds.center();
            (c, (scene_bounds.max - c).length() * (1.0 + 1e-3))
        };
        let caustic_targets = if scene.settings.caustics {
            let tri_materials: Vec<u32> = shading.iter().map(|s| s.material).collect();
            caustics::caustic_targets(&tris, &tri_materials, &scene.materials)
        } else {
            Vec::new()
        };
        let mut rs = Self {
            wide: WideBvh::collapse(&bvh.nodes, &tris),
            bvh,
            tri_normals: tris.iter().map(geometry::geometric_normal).collect(),
            tris,
            shading,
            tri_uvs,
            tri_tangents,
            materials: scene.materials.clone(),
            textures: scene.textures.records.clone(),
            texels: scene.textures.texels.clone(),
            texel_lut,
            lights: scene.lights.iter().map(Light::new).collect(),
            emitters: Vec::new(),
            emitter_cdf: Vec::new(),
            emitter_areas: Vec::new(),
            sky_pmf: 0.0,
            camera: scene.camera.clone(),
            sky: scene.sky,
            env: Environment::default(),
            env_cdf: Vec::new(),
            caustic_targets,
            scene_sphere,
        };
        if let Sky::Environment {
            texture,
            strength,
            rotation,
        } = scene.sky
        {
            rs.env = Environment {
                texture,
                strength,
                rotation: [rotation.cos(), rotation.sin()],
                cells: environment::env_cells(&rs.textures[texture as usize]),
            };
            rs.env_cdf = environment::env_distribution(&rs, texture);
        }
        rs.build_emitters(&scene.lights);
        Ok(rs)
    }

    /// Chooses the lights next event estimation samples: emissive triangles and punctual
    /// lights, then the sky. Without punctual lights, triangles are picked by power (pi ×
    /// area × emission luminance, times a texture's mean luminance). With them, half the
    /// probability goes by power (a punctual light's radiant flux, a directional light's
    /// through the disc of the scene's bounding sphere) and half evenly to each punctual
    /// light and to the emissive triangles as a group (by power within it): power alone
    /// starves a narrow, bright spot light, whose flux is small.
    fn build_emitters(&mut self, lights: &[PunctualLight]) {
        let mut emitters = Vec::new();
        // Each entry's power, and whether it is a triangle.
        let mut powers: Vec<(f64, bool)> = Vec::new();
        let mean: Vec<f64> = (0..self.textures.len() as u32)
            .map(|t| luminance(texture::texture_mean(self, t)) as f64)
            .collect();
        for (i, s) in self.shading.iter().enumerate() {
            let m = &self.materials[s.material as usize];
            // A Lambertian emitter's flux: pi × area × radiance.
            let mut power = std::f64::consts::PI
                * geometry::triangle_area(&self.tris[i]) as f64
                * luminance(m.emission) as f64;
            if m.emission_texture != NO_TEXTURE {
                power *= mean[m.emission_texture as usize];
            }
            if power > 0.0 {
                emitters.push(i as u32);
                powers.push((power, true));
            }
        }
        let radius = self.bvh.nodes.first().map_or(1.0, |n| {
            let b = n.bounds();
            if b.is_empty() {
                1.0
            } else {
                0.5 * b.extent().length() as f64
            }
        });
        for (k, l) in lights.iter().enumerate() {
            let power = match *l {
                PunctualLight::Point { intensity, .. } => {
                    4.0 * std::f64::consts::PI * luminance(intensity) as f64
                }
                PunctualLight::Spot {
                    intensity, cutoff, ..
                } => {
                    2.0 * std::f64::consts::PI
                        * (1.0 - cutoff.cos() as f64)
                        * luminance(intensity) as f64
                }
                PunctualLight::Directional { irradiance, .. } => {
                    std::f64::consts::PI * radius * radius * luminance(irradiance) as f64
                }
            };
            if power > 0.0 {
                emitters.push(LIGHT_EMITTER | k as u32);
                powers.push((power, false));
            }
        }
        let all: f64 = powers.iter().map(|p| p.0).sum();
        let triangles: f64 = powers.iter().filter(|p| p.1).map(|p| p.0).sum();
        let punctual = powers.iter().filter(|p| !p.1).count();
        let groups = punctual as f64 + if triangles > 0.0 { 1.0 } else { 0.0 };
        let weights = powers.iter().map(|&(p, triangle)| {
            if punctual == 0 {
                p
            } else {
                let group = if triangle { p / triangles } else { 1.0 };
                0.5 * p / all + 0.5 * group / groups
            }
        });
        let mut total = 0.0f64;
        let emitter_cdf: Vec<f64> = weights
            .map(|w| {
                total += w;
                total
            })
            .collect();
        let black = match self.sky {
            Sky::Environment { .. } => self.env.strength == 0.0 || self.env_cdf.is_empty(),
            _ => self.sky.is_black(),
        };
        let sky_pmf = match (black, emitters.is_empty()) {
            (true, _) => 0.0,
            (false, true) => 1.0,
            (false, false) => 0.5,
        };
        let tri_share = 1.0 - sky_pmf as f64;
        let mut emitter_cdf: Vec<f32> = emitter_cdf
            .iter()
            .map(|&c| (tri_share * c / total) as f32)
            .collect();
        let mut prev = 0.0;
        for (k, &i) in emitters.iter().enumerate() {
            if i & LIGHT_EMITTER == 0 {
                self.shading[i as usize].emitter_pmf = emitter_cdf[k] - prev;
            }
            prev = emitter_cdf[k];
        }
        if sky_pmf > 0.0 {
            emitters.push(SKY_EMITTER);
            emitter_cdf.push(1.0);
        }
        self.emitter_areas = emitters
            .iter()
            .map(|&i| {
                if i & LIGHT_EMITTER != 0 || i == SKY_EMITTER {
                    0.0
                } else {
                    geometry::triangle_area(&self.tris[i as usize])
                }
            })
            .collect();
        (self.emitters, self.emitter_cdf, self.sky_pmf) = (emitters, emitter_cdf, sky_pmf);
    }
}

/// One render: its settings, the sample range it covers (all of `0..spp` unless merging
/// partial renders), and how it may be stopped or observed while it runs.
#[derive(Clone)]
pub struct RenderJob {
    pub settings: RenderSettings,
    pub samples: std::ops::Range<u32>,
    /// Set from another thread (a Ctrl-C handler) to stop at the next sample pass; the
    /// render then returns the film of the passes it finished.
    pub cancel: Option<Arc<AtomicBool>>,
    /// Called with the film so far after a finished pass, at most once per interval.
    pub checkpoint: Option<(Duration, CheckpointFn)>,
    /// The AOVs to fill ([`Aov::mask`](crate::film::Aov::mask)); 0 for radiance alone.
    pub aovs: u32,
    /// Whether camera rays that miss add no radiance ([`Film::transparent`]); the film
    /// then holds the alpha AOV, for the coverage.
    pub transparent: bool,
    /// Told which region each worker traces and of each region's pixels once done
    /// (`render --preview`).
    pub watch: Option<Arc<dyn watch::Watch>>,
}

/// What a checkpoint does with the film so far (the CLI writes the output image).
pub type CheckpointFn = Arc<dyn Fn(&Film) + Send + Sync>;

impl RenderJob {
    pub fn new(settings: RenderSettings) -> Self {
        Self {
            settings,
            samples: 0..settings.spp,
            cancel: None,
            checkpoint: None,
            aovs: 0,
            transparent: false,
            watch: None,
        }
    }

    /// The job with the AOVs of mask `aovs`, and [`RenderJob::transparent`] or not.
    pub fn with_aovs(mut self, aovs: u32, transparent: bool) -> Self {
        self.aovs = aovs;
        self.transparent = transparent;
        self
    }

    /// An empty film for this job's settings and AOVs.
    pub fn film(&self) -> Film {
        Film::with_aovs(
            self.settings.width,
            self.settings.height,
            self.aovs,
            self.transparent,
        )
    }

    /// The job over samples `range` only.
    pub fn with_samples(mut self, range: std::ops::Range<u32>) -> Self {
        self.samples = range;
        self
    }

    pub fn cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
    }
}

/// Hands out checkpoints of a running render at most once per the job's interval.
pub struct Checkpoints<'a> {
    job: &'a RenderJob,
    last: Instant,
}

impl<'a> Checkpoints<'a> {
    pub fn new(job: &'a RenderJob) -> Self {
        Self {
            job,
            last: Instant::now(),
        }
    }

    /// Whether a checkpoint is due now.
    pub fn due(&self) -> bool {
        self.job
            .checkpoint
            .as_ref()
            .is_some_and(|(every, _)| self.last.elapsed() >= *every)
    }

    /// Passes `film` to the job's checkpoint callback.
    pub fn write(&mut self, film: &Film) {
        if let Some((_, f)) = &self.job.checkpoint {
            f(film);
        }
        self.last = Instant::now();
    }
}
