//! The CPU renderer's driver: passes of a few samples per pixel over the whole image,
//! each pass parallel over 16×16 tiles with rayon. Each sample is [`trace_path`] on a
//! camera ray, the same stages the GPU kernel (`shaders/render.wgsl`) runs. A job's
//! [`Watch`](super::watch::Watch) is told of each tile as a thread starts and ends it. No I/O.

use super::camera::{CameraRays, generate_camera_ray, pixel_centre_ray};
use super::integrator::{FirstHit, first_hit, first_hit_uncounted, trace_path};
use super::job::{Checkpoints, RenderJob};
use super::rng::{Rng, SeedTable};
use super::tables::RenderScene;
use super::watch::Region;
use crate::film::{Aov, Film};
use crate::fixed::{Texel, fixed_add, fixed_add3, texel_add, to_fixed, to_fixed3};
use crate::math::Ray;
use crate::scene::RenderSettings;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicI64, Ordering};

/// Tiles are square, this many pixels on a side.
pub const TILE: u32 = 16;

/// Paths traced per pass over the image: a pass is the unit of cancellation and checkpoints.
pub const PATHS_PER_PASS: u64 = 1 << 20;

/// One pixel's accumulators, exact fixed-point sums ([`crate::fixed`]) as the GPU's
/// accumulation buffer holds them: the radiance sum and the `rays` channel's count.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelSums {
    pub radiance: [i64; 3],
    pub rays: i64,
}

/// One pixel's AOV accumulators: a texel per [`Aov`] (indexed by it), as the AOV's film
/// channel holds it. Kept only by a render with AOVs.
/// mirror: shaders/render.wgsl `AovSums`
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AovSums(pub [Texel; Aov::ALL.len()]);

/// Renders the job's sample range with rayon over tiles, in passes of a few samples per
/// pixel over the whole image. `progress` is told of every finished tile's sample count; it
/// runs on worker threads. Stops early, after a whole pass, when the job is cancelled; the
/// film's `samples` says how many samples it holds.
pub fn render(scene: &RenderScene, job: &RenderJob, progress: &(dyn Fn(u64) + Sync)) -> Film {
    let s = &job.settings;
    let (w, h) = (s.width, s.height);
    let tiles: Vec<(u32, u32)> = (0..h.div_ceil(TILE))
        .flat_map(|ty| (0..w.div_ceil(TILE)).map(move |tx| (tx * TILE, ty * TILE)))
        .collect();
    let step = (PATHS_PER_PASS / (w as u64 * h as u64)).max(1) as u32;
    let cam = CameraRays::new(&scene.camera, w, h)
        .with_filter(s.filter_width)
        .with_window(&scene.bounds());
    let mut film = job.film();
    let mut pixels = vec![PixelSums::default(); film.sum.len()];
    let aov_pixels = if film.aovs().is_empty() {
        0
    } else {
        film.sum.len()
    };
    let mut aovs = vec![AovSums::default(); aov_pixels];
    let mut checkpoints = Checkpoints::new(job);
    let splats = Splats::new(film.sum.len());
    let mut start = job.samples.start;
    while start < job.samples.end && !job.cancelled() {
        let end = (start + step).min(job.samples.end);
        let (before, aovs_before) = (&pixels, &aovs);
        type TileSums = ((u32, u32), Vec<PixelSums>, Vec<AovSums>);
        let done: Vec<TileSums> = tiles
            .par_iter()
            .map(|&(x0, y0)| {
                let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
                let region = Region { x0, y0, x1, y1 };
                let worker = rayon::current_thread_index().unwrap_or(0);
                if let Some(watch) = &job.watch {
                    watch.started(worker, region, start..end);
                }
                let mut sums = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
                let mut aov_sums = Vec::new();
                for y in y0..y1 {
                    for x in x0..x1 {
                        let i = (y * w + x) as usize;
                        let mut aov = aovs_before.get(i).copied();
                        let acc = render_pixel(
                            scene,
                            &cam,
                            job,
                            x,
                            y,
                            start..end,
                            before[i],
                            aov.as_mut(),
                            &splats,
                        );
                        sums.push(acc);
                        aov_sums.extend(aov);
                    }
                }
                progress(sums.len() as u64 * (end - start) as u64);
                if let Some(watch) = &job.watch {
                    let tile = watch.wants_pixels().then(|| {
                        let mut tile = Film::with_aovs(
                            region.width(),
                            region.height(),
                            job.aovs,
                            job.transparent,
                        );
                        tile.samples = end - job.samples.start;
                        fill(&mut tile, &sums, &aov_sums);
                        splats.add_region_to(&mut tile, region, w);
                        tile
                    });
                    watch.finished(worker, region, tile.as_ref());
                }
                ((x0, y0), sums, aov_sums)
            })
            .collect();
        for ((x0, y0), sums, aov_sums) in done {
            let tw = (x0 + TILE).min(w) - x0;
            for (i, acc) in sums.into_iter().enumerate() {
                let (x, y) = (x0 + i as u32 % tw, y0 + i as u32 / tw);
                pixels[(y * w + x) as usize] = acc;
            }
            for (i, acc) in aov_sums.into_iter().enumerate() {
                let (x, y) = (x0 + i as u32 % tw, y0 + i as u32 / tw);
                aovs[(y * w + x) as usize] = acc;
            }
        }
        film.samples += end - start;
        start = end;
        if start < job.samples.end && checkpoints.due() {
            fill(&mut film, &pixels, &aovs);
            splats.add_region_to(&mut film, Region::whole(w, h), w);
            checkpoints.write(&film);
        }
    }
    fill(&mut film, &pixels, &aovs);
    splats.add_region_to(&mut film, Region::whole(w, h), w);
    film
}

/// What light subpaths seen through the lens add to the pixels they land in, from every
/// worker: each splat rounded once to fixed point (as a sample's radiance is) and added
/// atomically, so that the sums are the same bits in whatever order the workers add them.
/// mirror: shaders/render.wgsl `splats`
pub struct Splats(Vec<[AtomicI64; 3]>);

impl Splats {
    /// Zero sums for `pixels` pixels.
    pub fn new(pixels: usize) -> Self {
        Self((0..pixels).map(|_| Default::default()).collect())
    }

    /// Adds `value` to pixel `pixel`; a non-finite value is dropped, as a sample's is.
    pub fn add(&self, pixel: u32, value: Vec3) {
        if value == Vec3::ZERO || !value.is_finite() {
            return;
        }
        for (sum, v) in self.0[pixel as usize].iter().zip(to_fixed3(value)) {
            sum.fetch_add(v, Ordering::Relaxed);
        }
    }

    /// Adds the sums of the pixels of `region` (of an image `width` pixels wide) to the
    /// radiance sums of `film`, which covers the region.
    fn add_region_to(&self, film: &mut Film, region: Region, width: u32) {
        let rw = region.width();
        for (i, dst) in film.sum.iter_mut().enumerate() {
            let (x, y) = (region.x0 + i as u32 % rw, region.y0 + i as u32 / rw);
            let sums = &self.0[(y * width + x) as usize];
            *dst = fixed_add3(*dst, sums.each_ref().map(|s| s.load(Ordering::Relaxed)));
        }
    }
}

/// The AOVs `aovs` alone of the first `samples` camera samples of every pixel, no paths
/// traced: what a render's AOV channels would hold after those samples (ids from the
/// pixel-centre ray), at a fraction of its cost. `info --heatmap` and the preview window's
/// views read it.
pub fn first_hits(scene: &RenderScene, settings: &RenderSettings, samples: u32, aovs: u32) -> Film {
    let (w, h) = (settings.width, settings.height);
    let cam = CameraRays::new(&scene.camera, w, h).with_filter(settings.filter_width);
    let sums: Vec<AovSums> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let mut sums = AovSums::default();
            let table = SeedTable::new();
            let mut rng = Rng::with_table(i, 0, settings.seed, &table);
            for sample in 0..samples {
                rng.set_sample(sample);
                let fh = aov_hit(scene, &generate_camera_ray(&cam, x, y, &rng), aovs);
                add_aov_sample(&mut sums, &cam, &fh);
            }
            set_aov_ids(
                &mut sums,
                &first_hit_uncounted(scene, &pixel_centre_ray(&cam, x, y)),
            );
            sums
        })
        .collect();
    let mut film = Film::with_aovs(w, h, aovs, false);
    film.samples = samples;
    fill(&mut film, &vec![PixelSums::default(); sums.len()], &sums);
    film
}

/// [`render_pixel`] for a geometry-only job: each sample's camera ray and first hit alone,
/// its albedo as the radiance (none where it misses), one ray a sample.
/// mirror: shaders/render.wgsl `geometry`
#[allow(clippy::too_many_arguments)]
pub fn geometry_pixel(
    scene: &RenderScene,
    cam: &CameraRays,
    x: u32,
    y: u32,
    rng: &mut Rng,
    samples: std::ops::Range<u32>,
    mut acc: PixelSums,
    mut aov: Option<&mut AovSums>,
    aovs: u32,
) -> PixelSums {
    for sample in samples {
        rng.set_sample(sample);
        let fh = aov_hit(scene, &generate_camera_ray(cam, x, y, rng), aovs);
        if let Some(aov) = aov.as_deref_mut() {
            add_aov_sample(aov, cam, &fh);
            if sample == 0 {
                set_aov_ids(
                    aov,
                    &first_hit_uncounted(scene, &pixel_centre_ray(cam, x, y)),
                );
            }
        }
        acc.rays = fixed_add(acc.rays, to_fixed(1.0));
        if fh.hit {
            acc.radiance = fixed_add3(acc.radiance, to_fixed3(fh.albedo));
        }
    }
    acc
}

/// Copies the accumulators into the film's radiance, `rays` channel and AOV channels.
fn fill(film: &mut Film, pixels: &[PixelSums], aovs: &[AovSums]) {
    for (dst, p) in film.sum.iter_mut().zip(pixels) {
        *dst = p.radiance;
    }
    let rays = &mut film.channels[0];
    debug_assert_eq!(rays.name, Film::RAYS);
    for (dst, p) in rays.data.iter_mut().zip(pixels) {
        *dst = [p.rays, 0, 0, 0];
    }
    for aov in Aov::ALL {
        if let Some(channel) = film.channels.iter_mut().find(|c| c.name == aov.name()) {
            for (dst, p) in channel.data.iter_mut().zip(aovs) {
                *dst = p.0[aov as usize];
            }
        }
    }
}

/// Adds one camera sample's first hit to a pixel's AOV sums: its cost, and where it hit,
/// its depth along the viewing axis, normal, albedo, coverage and diffuse colour.
/// mirror: shaders/render.wgsl `add_aov_sample`
pub fn add_aov_sample(sums: &mut AovSums, cam: &CameraRays, fh: &FirstHit) {
    let t = &mut sums.0;
    let cost = &mut t[Aov::BvhCost as usize];
    *cost = texel_add(*cost, [fh.cost as f32, 0.0, 0.0, 0.0]);
    if !fh.hit {
        return;
    }
    let depth = (fh.p - cam.position).dot(cam.forward);
    let mut add = |aov: Aov, [x, y, z]: [f32; 3]| {
        let texel = &mut t[aov as usize];
        *texel = texel_add(*texel, [x, y, z, 1.0]);
    };
    add(Aov::Depth, [depth, 0.0, 0.0]);
    add(Aov::Normal, fh.normal.to_array());
    add(Aov::Albedo, fh.albedo.to_array());
    add(Aov::Alpha, [1.0, 0.0, 0.0]);
    add(Aov::DiffuseColor, fh.diffuse.to_array());
}

/// Sets a pixel's ids from its centre ray's first hit: each id as its low and high 16
/// bits (exact in f32 and in fixed point), `w` = 1 to say the centre ray was traced.
/// mirror: shaders/render.wgsl `set_aov_ids`
pub fn set_aov_ids(sums: &mut AovSums, fh: &FirstHit) {
    let split = |id: u32| texel_add([0; 4], [(id & 0xffff) as f32, (id >> 16) as f32, 0.0, 1.0]);
    sums.0[Aov::ObjectId as usize] = split(fh.object);
    sums.0[Aov::MaterialId as usize] = split(fh.material);
}

/// Camera ray `ray`'s first hit for the AOVs `aovs`, counting its BVH cost only where
/// `bvh_cost` is among them (the counting traversal walks the binary tree, slower than
/// the wide one).
fn aov_hit(scene: &RenderScene, ray: &Ray, aovs: u32) -> FirstHit {
    if aovs & Aov::BvhCost.bit() != 0 {
        first_hit(scene, ray)
    } else {
        first_hit_uncounted(scene, ray)
    }
}

/// Whether pixel (`x`, `y`) of a transparent render need not be traced: its camera rays all
/// miss the scene ([`CameraRays::outside_window`]), and a missed sample adds only its ray
/// to the film (a transparent film takes no sky radiance, and without caustic targets no
/// light subpath starts). Where the BVH cost AOV is asked for, every ray is traced for its
/// count. Dataset renders of one object on a transparent film spend most of their samples
/// on such pixels. mirror: shaders/render.wgsl `skips_pixel`
pub fn skips_pixel(scene: &RenderScene, cam: &CameraRays, job: &RenderJob, x: u32, y: u32) -> bool {
    job.transparent
        && scene.caustic_targets.is_empty()
        && job.aovs & Aov::BvhCost.bit() == 0
        && cam.outside_window(x, y)
}

/// `acc` plus one pixel's samples over `samples`, each rounded to fixed point and added
/// exactly, as the GPU adds them; non-finite radiance samples are dropped (their rays
/// still count). With AOVs,
/// `aov` gets each sample's first hit, and with sample 0 the pixel-centre ray's ids; in a
/// transparent render, a sample whose camera ray misses adds no radiance. The splats of the
/// samples' light subpaths go to `splats`, whichever pixels they land in.
/// mirror: shaders/render.wgsl `render`
#[allow(clippy::too_many_arguments)]
pub fn render_pixel(
    scene: &RenderScene,
    cam: &CameraRays,
    job: &RenderJob,
    x: u32,
    y: u32,
    samples: std::ops::Range<u32>,
    mut acc: PixelSums,
    mut aov: Option<&mut AovSums>,
    splats: &Splats,
) -> PixelSums {
    let s = &job.settings;
    let pixel = y * s.width + x;
    // A pass of one sample per pixel has no seeds to reuse.
    let table = SeedTable::new();
    let mut rng = if samples.len() > 1 {
        Rng::with_table(pixel, samples.start, s.seed, &table)
    } else {
        Rng::new(pixel, samples.start, s.seed)
    };
    if job.geometry {
        return geometry_pixel(scene, cam, x, y, &mut rng, samples, acc, aov, job.aovs);
    }
    if skips_pixel(scene, cam, job, x, y) {
        // What its samples would add: one ray each, no radiance, and the ids of a miss.
        for sample in samples {
            if sample == 0
                && let Some(aov) = aov.as_deref_mut()
            {
                set_aov_ids(aov, &FirstHit::MISS);
            }
            acc.rays = fixed_add(acc.rays, to_fixed(1.0));
        }
        return acc;
    }
    for sample in samples {
        rng.set_sample(sample);
        let ray = generate_camera_ray(cam, x, y, &rng);
        let mut seen = true;
        if let Some(aov) = aov.as_deref_mut() {
            let fh = aov_hit(scene, &ray, job.aovs);
            add_aov_sample(aov, cam, &fh);
            seen = fh.hit || !job.transparent;
            if sample == 0 {
                set_aov_ids(
                    aov,
                    &first_hit_uncounted(scene, &pixel_centre_ray(cam, x, y)),
                );
            }
        }
        let ps = trace_path(
            scene,
            cam,
            ray,
            &rng,
            s.max_depth,
            s.bounces.budget(),
            s.branches(!scene.caustic_targets.is_empty()),
            &mut |pixel, value| splats.add(pixel, value),
        );
        acc.rays = fixed_add(acc.rays, to_fixed(ps.rays as f32));
        if ps.radiance.is_finite() && seen {
            acc.radiance = fixed_add3(acc.radiance, to_fixed3(ps.radiance));
        }
    }
    acc
}
