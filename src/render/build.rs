//! Laying out the scene tables ([`RenderScene`]) from a scene, on the host: the BVH and
//! the per-triangle records in its leaf order, the light records, the emitter distribution
//! of next event estimation, the environment's sampling distribution and the caustic
//! targets. It runs once per scene, before either renderer, so nothing here has a WGSL
//! twin; the stages only read what it builds, and none of them imports it.

use super::environment::cell_corners;
use super::sheen::{SHEEN_TABLE_OFFSET, sheen_table};
use super::tables::{
    CausticTarget, Environment, LIGHT_DIRECTIONAL, LIGHT_EMITTER, LIGHT_POINT, LIGHT_RECT,
    LIGHT_SPOT, LIGHTS_IN_FULL_MAX, Light, RenderScene, SKY_EMITTER, TRI_COLOR, TRI_SMOOTH,
    TRI_TANGENT, TRI_UV, TRI_UV1, TriColors, TriShading, TriTangents, TriUvs,
};
use super::texture::texel;
use crate::bvh::{BuildParams, Bvh, BvhError, WideBvh};
use crate::film::srgb8_to_linear;
use crate::geometry::{self, TriVerts};
use crate::math::{Aabb, luminance};
use crate::scene::{
    Material, MaterialKind, NO_COLOR, NO_NORMAL, NO_TANGENT, NO_TEXTURE, NO_UV, PunctualLight,
    Scene, Sky, Texture,
};
use glam::Vec3;

impl RenderScene {
    /// The box around every triangle (the BVH's root); empty for a scene without any.
    pub fn bounds(&self) -> Aabb {
        self.bvh.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds())
    }

    /// Whether the tables of a scene rendered with `settings` from `camera` hold caustic
    /// targets: caustics on, and a perspective camera. Light subpaths reach the film through
    /// the camera's lens or pinhole; no light path meets an orthographic camera's parallel
    /// rays, so with one the render is the path tracer's alone (the same image in
    /// expectation). Tables kept for several renders serve only those that agree on it.
    pub fn caustic_tables(
        settings: &crate::scene::RenderSettings,
        camera: &crate::scene::camera::Camera,
    ) -> bool {
        settings.caustics && !camera.is_orthographic()
    }

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
                if m.is_masked() {
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
                if textured && mesh.uv1_indices(i as usize)[0] != NO_UV {
                    s.flags |= TRI_UV1;
                }
                if mesh.color_indices(i as usize)[0] != NO_COLOR {
                    s.flags |= TRI_COLOR;
                }
                if textured && t.t[0] != NO_UV {
                    s.flags |= TRI_UV;
                }
                // The scene builder gives a triangle whose material has a normal map the
                // texture coordinates the map reads (set 0 or 1).
                let normal_map = scene.materials[t.material as usize].tangent_map();
                if textured
                    && normal_map != NO_TEXTURE
                    && mesh.tangent_indices(i as usize)[0] != NO_TANGENT
                {
                    s.flags |= TRI_TANGENT;
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
        // Only a scene with textures reads texture coordinates; the second set and the
        // colours only where some triangle has them.
        let uvs = |corners: &dyn Fn(usize) -> [u32; 3]| -> Vec<TriUvs> {
            bvh.order
                .iter()
                .map(|&i| {
                    let [a, b, c] = corners(i as usize).map(|k| {
                        if k == NO_UV {
                            [0.0; 2]
                        } else {
                            mesh.texcoords[k as usize].to_array()
                        }
                    });
                    TriUvs {
                        uv0: a,
                        uv1: b,
                        uv2: c,
                        _pad: [0; 2],
                    }
                })
                .collect()
        };
        let tri_uvs = if textured {
            uvs(&|i| mesh.triangles[i].t)
        } else {
            Vec::new()
        };
        let tri_uvs1 = if shading.iter().any(|s| s.flags & TRI_UV1 != 0) {
            uvs(&|i| mesh.uv1_indices(i))
        } else {
            Vec::new()
        };
        let tri_colors: Vec<TriColors> = if shading.iter().any(|s| s.flags & TRI_COLOR != 0) {
            bvh.order
                .iter()
                .map(|&i| {
                    let c = mesh.color_indices(i as usize);
                    if c[0] == NO_COLOR {
                        return TriColors::default();
                    }
                    let [c0, c1, c2] = c.map(|k| mesh.colors[k as usize].to_array());
                    TriColors { c0, c1, c2 }
                })
                .collect()
        } else {
            Vec::new()
        };
        // The decoding of 8-bit texels (sRGB, then linear), and after it the sheen's
        // albedo table where some material has sheen.
        let mut texel_lut: Vec<f32> = (0..=255u8)
            .map(srgb8_to_linear)
            .chain((0..=255u8).map(|k| k as f32 / 255.0))
            .collect();
        debug_assert_eq!(texel_lut.len(), SHEEN_TABLE_OFFSET as usize);
        if scene
            .materials
            .iter()
            .any(|m| m.sheen_color.max_element() > 0.0)
        {
            texel_lut.extend_from_slice(sheen_table());
        }
        let scene_bounds = bounds.iter().fold(Aabb::EMPTY, |a, &b| a.union(b));
        let scene_sphere = if bounds.is_empty() {
            (Vec3::ZERO, 0.0)
        } else {
            let c = scene_bounds.center();
            (c, (scene_bounds.max - c).length() * (1.0 + 1e-3))
        };
        let caustic_targets = if Self::caustic_tables(&scene.settings, &scene.camera) {
            let tri_materials: Vec<u32> = shading.iter().map(|s| s.material).collect();
            caustic_targets(&tris, &tri_materials, &scene.materials)
        } else {
            Vec::new()
        };
        // Rectangles last, each kind in the scene's order.
        let (mut lights, rects): (Vec<PunctualLight>, Vec<PunctualLight>) = scene
            .lights
            .iter()
            .partition(|l| !matches!(l, PunctualLight::Rect { .. }));
        lights.extend(rects);
        let mut rs = Self {
            wide: WideBvh::collapse(&bvh.nodes, &tris),
            bvh,
            tri_normals: tris.iter().map(geometry::geometric_normal).collect(),
            tris,
            shading,
            tri_uvs,
            tri_tangents,
            tri_uvs1,
            tri_colors,
            materials: scene.materials.clone(),
            textures: scene.textures.records.clone(),
            texels: scene.textures.texels.clone(),
            texel_lut,
            lights: lights.iter().map(Light::new).collect(),
            first_rect_light: lights
                .iter()
                .position(|l| matches!(l, PunctualLight::Rect { .. }))
                .unwrap_or(lights.len()) as u32,
            emitters: Vec::new(),
            emitter_cdf: Vec::new(),
            emitter_areas: Vec::new(),
            sky_pmf: 0.0,
            lights_in_full: 0,
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
                cells: env_cells(&rs.textures[texture as usize]),
            };
            rs.env_cdf = env_distribution(&rs, texture);
        }
        rs.build_emitters(&lights);
        Ok(rs)
    }

    /// Chooses the lights next event estimation samples: emissive triangles and punctual
    /// lights, then the sky. Without punctual lights, triangles are picked by power (pi ×
    /// area × emission luminance, times a texture's mean luminance). With them, half the
    /// probability goes by power (a punctual light's radiant flux, a directional light's
    /// through the disc of the scene's bounding sphere) and half evenly to each punctual
    /// light and to the emissive triangles as a group (by power within it): power alone
    /// starves a narrow, bright spot light, whose flux is small. Lights that next event
    /// estimation samples in full ([`RenderScene::lights_in_full`]) are left out where no
    /// caustic light subpath may start on them.
    fn build_emitters(&mut self, lights: &[PunctualLight]) {
        self.lights_in_full = if lights.len() <= LIGHTS_IN_FULL_MAX {
            lights.len() as u32
        } else {
            0
        };
        // A light sampled in full needs no pick, where no light subpath starts on it either.
        let unpicked = |l: &PunctualLight| {
            self.lights_in_full != 0
                && self.caustic_targets.is_empty()
                && !matches!(l, PunctualLight::Rect { .. })
        };
        let mut emitters = Vec::new();
        // Each entry's power, and whether it is a triangle.
        let mut powers: Vec<(f64, bool)> = Vec::new();
        let mean: Vec<f64> = (0..self.textures.len() as u32)
            .map(|t| luminance(texture_mean(self, t)) as f64)
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
                // What leaves it, but no more than a rectangle as wide as the scene sends:
                // a light far wider than the scene lights it as a directional light would.
                PunctualLight::Rect {
                    edge_u,
                    edge_v,
                    radiance,
                    ..
                } => {
                    let area = edge_u.cross(edge_v).length() as f64;
                    let wide = std::f64::consts::PI * radius * radius;
                    std::f64::consts::PI * area.min(wide) * luminance(radiance) as f64
                }
            };
            if power > 0.0 && !unpicked(l) {
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
            let pmf = emitter_cdf[k] - prev;
            if i & LIGHT_EMITTER == 0 {
                self.shading[i as usize].emitter_pmf = pmf;
            } else {
                self.lights[(i & !LIGHT_EMITTER) as usize].pmf = pmf;
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

impl Light {
    /// The table entry of a scene light.
    pub fn new(l: &PunctualLight) -> Self {
        let mut out = Self {
            shadows: 1,
            ..Self::default()
        };
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
                    ..out
                };
            }
            PunctualLight::Directional {
                direction,
                irradiance,
                shadows,
            } => {
                (out.kind, out.direction, out.intensity) =
                    (LIGHT_DIRECTIONAL, direction.into(), irradiance.into());
                out.shadows = shadows as u32;
            }
            PunctualLight::Rect {
                center,
                edge_u,
                edge_v,
                radiance,
            } => {
                out = Self {
                    position: (center - 0.5 * (edge_u + edge_v)).into(),
                    kind: LIGHT_RECT,
                    direction: edge_u.into(),
                    intensity: radiance.into(),
                    area: edge_u.cross(edge_v).length(),
                    edge: edge_v.into(),
                    ..out
                };
            }
        }
        out
    }
}

/// At most this many targets: objects beyond it share spheres.
const MAX_CAUSTIC_TARGETS: usize = 8;

/// Whether a material may scatter through a delta lobe alone somewhere on its surface
/// (where [`bsdf_is_delta`](super::bsdf::bsdf_is_delta) may hold once its textures are
/// applied).
fn may_be_delta(m: &Material) -> bool {
    match m.kind {
        MaterialKind::CONDUCTOR | MaterialKind::DIELECTRIC => true,
        MaterialKind::PBR => {
            (m.roughness == 0.0 || m.roughness_texture != NO_TEXTURE)
                && (m.metallic >= 1.0 || m.transmission >= 1.0)
        }
        _ => false,
    }
}

/// The spheres that bound the triangles whose materials [`may_be_delta`]: one per object
/// that has such triangles, centred on their box and reaching their farthest corner; with
/// more than [`MAX_CAUSTIC_TARGETS`] objects, objects are grouped by halving them along
/// their boxes' widest spread of centres. Empty when no material may be delta.
fn caustic_targets(tris: &[TriVerts], materials: &[u32], table: &[Material]) -> Vec<CausticTarget> {
    let delta: Vec<bool> = table.iter().map(may_be_delta).collect();
    // Each object's triangles with a delta material: (object, box, triangle indices).
    let mut objects: std::collections::BTreeMap<u32, (Aabb, Vec<usize>)> = Default::default();
    for (i, t) in tris.iter().enumerate() {
        if delta[materials[i] as usize] {
            let entry = objects
                .entry(t.object())
                .or_insert_with(|| (Aabb::EMPTY, Vec::new()));
            entry.0 = entry.0.union(Aabb::from_points(&t.corners()));
            entry.1.push(i);
        }
    }
    let mut groups: Vec<(Aabb, Vec<usize>)> = objects.into_values().collect();
    let mut out = Vec::new();
    split_groups(&mut groups, MAX_CAUSTIC_TARGETS, &mut |part| {
        let bounds = part.iter().fold(Aabb::EMPTY, |b, g| b.union(g.0));
        let center = bounds.center();
        let radius = part
            .iter()
            .flat_map(|g| g.1.iter())
            .flat_map(|&i| tris[i].corners())
            .map(|c| c.distance(center))
            .fold(0.0f32, f32::max);
        // A margin, so that rounding never leaves a specular point outside its cone.
        let radius = radius * (1.0 + 1e-3) + 1e-6 * (1.0 + center.abs().max_element());
        out.push(CausticTarget {
            center: center.into(),
            radius,
        });
    });
    out
}

/// Calls `emit` with `groups` cut into at most `n` parts: halved at the median of their
/// centres along the axis where the centres spread most.
fn split_groups<T>(groups: &mut [(Aabb, T)], n: usize, emit: &mut impl FnMut(&[(Aabb, T)])) {
    if groups.is_empty() {
        return;
    }
    if groups.len() <= n || n == 1 {
        if n == 1 {
            emit(groups);
        } else {
            for g in groups.chunks(1) {
                emit(g);
            }
        }
        return;
    }
    let centres = groups.iter().fold(Aabb::EMPTY, |b, g| b.grow(g.0.center()));
    let axis = centres.extent().max_position();
    groups.sort_by(|a, b| a.0.center()[axis].total_cmp(&b.0.center()[axis]));
    let half = groups.len() / 2;
    let (lo, hi) = groups.split_at_mut(half);
    split_groups(lo, n / 2, emit);
    split_groups(hi, n - n / 2, emit);
}

/// The environment's cells along u and v: one per column (between its texel centre and
/// the next, around), and one between each two rows (one for an image of one row).
fn env_cells(t: &Texture) -> [u32; 2] {
    [t.width, t.height.saturating_sub(1).max(1)]
}

/// The sampling distribution of texture `index` as an environment map: for its
/// [`env_cells`] [nx, ny], the inclusive
/// CDF over the ny rows of cells, then each row's inclusive CDF over its nx cells, each
/// normalised to end at 1; empty when the environment sends no light. A cell weighs the
/// mean luminance of its four corners (the integral of their bilinear interpolation) times
/// sin θ at its centre, which is positive wherever the radiance in the cell is.
fn env_distribution(scene: &RenderScene, index: u32) -> Vec<f32> {
    let t = &scene.textures[index as usize];
    let [nx, ny] = env_cells(t);
    let mut rows = Vec::with_capacity(ny as usize);
    let mut cdf = vec![0.0f32; (ny + nx * ny) as usize];
    for i in 0..ny {
        let sin_theta = (std::f64::consts::PI * (i as f64 + 0.5) / ny as f64).sin();
        let mut total = 0.0f64;
        let sums: Vec<f64> = (0..nx)
            .map(|j| {
                let c = cell_corners(scene, t, i, j).as_dvec4();
                total += 0.25 * (c.x + c.y + c.z + c.w) * sin_theta;
                total
            })
            .collect();
        let row = &mut cdf[(ny + i * nx) as usize..(ny + (i + 1) * nx) as usize];
        for (c, s) in row.iter_mut().zip(&sums) {
            // A row that sends nothing is never picked; a uniform CDF keeps it well formed.
            *c = if total > 0.0 {
                (s / total) as f32
            } else {
                (sums.len() as f64).recip() as f32
            };
        }
        if let Some(last) = row.last_mut() {
            *last = 1.0;
        }
        rows.push(total);
    }
    let all: f64 = rows.iter().sum();
    if !(all > 0.0 && all.is_finite()) {
        return Vec::new();
    }
    let mut running = 0.0f64;
    for (c, r) in cdf.iter_mut().zip(&rows) {
        running += r;
        *c = (running / all) as f32;
    }
    cdf[ny as usize - 1] = 1.0;
    cdf
}

/// The mean colour of texture `index` over its texels, for weighing textured emitters by
/// power.
fn texture_mean(scene: &RenderScene, index: u32) -> Vec3 {
    let t = &scene.textures[index as usize];
    let mut sum = glam::DVec3::ZERO;
    for y in 0..t.height {
        for x in 0..t.width {
            sum += texel(scene, t, x, y).truncate().as_dvec3();
        }
    }
    (sum / (t.width as f64 * t.height as f64)).as_vec3()
}
