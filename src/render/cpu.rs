//! The CPU renderer's driver: passes of a few samples per pixel over the whole image,
//! each pass parallel over 16×16 tiles with rayon. Each sample is [`trace_path`] on a
//! camera ray, the same stages the GPU kernel (`shaders/render.wgsl`) runs. No I/O.

use super::camera::{CameraRays, generate_camera_ray};
use super::integrator::trace_path;
use super::rng::Rng;
use super::{Checkpoints, RenderJob, RenderScene};
use crate::film::Film;
use glam::Vec3;
use rayon::prelude::*;

/// Tiles are square, this many pixels on a side.
pub const TILE: u32 = 16;

/// Paths traced per pass over the image: a pass is the unit of cancellation and checkpoints.
pub const PATHS_PER_PASS: u64 = 1 << 20;

/// One pixel's accumulators, as a texel of the GPU's accumulation buffer holds them:
/// the radiance sum and the `rays` channel's count.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelSums {
    pub radiance: Vec3,
    pub rays: f32,
}

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
    let cam = CameraRays::new(&scene.camera, w, h);
    let mut film = Film::new(w, h);
    let mut pixels = vec![PixelSums::default(); film.sum.len()];
    let mut checkpoints = Checkpoints::new(job);
    let mut start = job.samples.start;
    while start < job.samples.end && !job.cancelled() {
        let end = (start + step).min(job.samples.end);
        let before = &pixels;
        let done: Vec<((u32, u32), Vec<PixelSums>)> = tiles
            .par_iter()
            .map(|&(x0, y0)| {
                let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
                let mut sums = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
                for y in y0..y1 {
                    for x in x0..x1 {
                        let acc = before[(y * w + x) as usize];
                        sums.push(render_pixel(scene, &cam, job, x, y, start..end, acc));
                    }
                }
                progress(sums.len() as u64 * (end - start) as u64);
                ((x0, y0), sums)
            })
            .collect();
        for ((x0, y0), sums) in done {
            let tw = (x0 + TILE).min(w) - x0;
            for (i, acc) in sums.into_iter().enumerate() {
                let (x, y) = (x0 + i as u32 % tw, y0 + i as u32 / tw);
                pixels[(y * w + x) as usize] = acc;
            }
        }
        film.samples += end - start;
        start = end;
        if start < job.samples.end && checkpoints.due() {
            fill(&mut film, &pixels);
            checkpoints.write(&film);
        }
    }
    fill(&mut film, &pixels);
    film
}

/// Copies the accumulators into the film's radiance and `rays` channel.
fn fill(film: &mut Film, pixels: &[PixelSums]) {
    for (dst, p) in film.sum.iter_mut().zip(pixels) {
        *dst = p.radiance;
    }
    let rays = &mut film.channels[0];
    debug_assert_eq!(rays.name, Film::RAYS);
    for (dst, p) in rays.data.iter_mut().zip(pixels) {
        dst[0] = p.rays;
    }
}

/// `acc` plus one pixel's samples over `samples`, added in sample order in f32 as the GPU
/// adds them; non-finite radiance samples are dropped (their rays still count).
/// mirror: shaders/render.wgsl `render`
pub fn render_pixel(
    scene: &RenderScene,
    cam: &CameraRays,
    job: &RenderJob,
    x: u32,
    y: u32,
    samples: std::ops::Range<u32>,
    mut acc: PixelSums,
) -> PixelSums {
    let s = &job.settings;
    let pixel = y * s.width + x;
    for sample in samples {
        let rng = Rng::new(pixel, sample, s.seed);
        let ray = generate_camera_ray(cam, x, y, &rng);
        let (l, rays) = trace_path(scene, ray, &rng, s.max_depth);
        acc.rays += rays as f32;
        if l.is_finite() {
            acc.radiance += l;
        }
    }
    acc
}
