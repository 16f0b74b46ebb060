//! What the preview window shows, kept up to date from the render's worker threads: each
//! pixel's mean radiance and AOVs as of the last region that covered it, the regions being
//! traced now, and the counts behind the statistics.

use super::super::progress::Throughput;
use glam::Vec3;
use meshtrace::film::{Aov, AovValues, Film};
use meshtrace::fixed::FIXED_FRACTION_BITS;
use meshtrace::render::watch::Region;
use std::collections::BTreeMap;
use std::ops::Range;
use std::time::Instant;

/// The AOVs behind the views other than the beauty one.
pub const VIEW_AOVS: [Aov; 4] = [Aov::Albedo, Aov::Normal, Aov::Depth, Aov::BvhCost];

/// What the image area shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// The radiance, exposed and sRGB-encoded as a PNG output is.
    Beauty,
    Albedo,
    /// The shading normal, each component mapped from [-1, 1] to [0, 1].
    Normal,
    /// Distance along the view axis, near white to far black.
    Depth,
    /// BVH nodes visited plus triangles tested per camera ray, in viridis.
    BvhCost,
}

impl View {
    /// The views in key order: `1` is the first.
    pub const ALL: [View; 5] = [
        View::Beauty,
        View::Albedo,
        View::Normal,
        View::Depth,
        View::BvhCost,
    ];

    pub fn name(self) -> &'static str {
        match self {
            View::Beauty => "beauty",
            View::Albedo => "albedo",
            View::Normal => "normal",
            View::Depth => "depth",
            View::BvhCost => "bvh_cost",
        }
    }

    /// The view after this one (Tab).
    pub fn next(self) -> View {
        let i = View::ALL.iter().position(|&v| v == self).unwrap_or(0);
        View::ALL[(i + 1) % View::ALL.len()]
    }
}

/// The render as the window sees it.
pub struct Picture {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel the job traces.
    pub spp: u32,
    radiance: Vec<Vec3>,
    albedo: Vec<Vec3>,
    normal: Vec<Vec3>,
    /// +inf where no sample hit.
    depth: Vec<f32>,
    cost: Vec<f32>,
    /// Samples each pixel holds, and rays its paths traced.
    samples: Vec<u32>,
    rays: Vec<u64>,
    /// Sums of `samples` and `rays` over the image.
    pub samples_done: u64,
    pub rays_done: u64,
    /// The region each worker traces now, with its sample range.
    pub active: BTreeMap<usize, (Region, Range<u32>)>,
    pub start: Instant,
    sample_rate: Throughput,
    ray_rate: Throughput,
    /// Recent samples and rays per second, as of the last finished region.
    pub samples_per_second: f64,
    pub rays_per_second: f64,
    /// Set when the image changed since the window last drew it.
    pub dirty: bool,
    /// The outcome once the render has ended (`wrote render.png …`), and when it ended.
    pub ended: Option<(String, Instant)>,
}

impl Picture {
    pub fn new(width: u32, height: u32, spp: u32) -> Self {
        let n = width as usize * height as usize;
        let start = Instant::now();
        Self {
            width,
            height,
            spp,
            radiance: vec![Vec3::ZERO; n],
            albedo: vec![Vec3::ZERO; n],
            normal: vec![Vec3::ZERO; n],
            depth: vec![f32::INFINITY; n],
            cost: vec![0.0; n],
            samples: vec![0; n],
            rays: vec![0; n],
            samples_done: 0,
            rays_done: 0,
            active: BTreeMap::new(),
            start,
            sample_rate: Throughput::new(start),
            ray_rate: Throughput::new(start),
            samples_per_second: 0.0,
            rays_per_second: 0.0,
            dirty: true,
            ended: None,
        }
    }

    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }

    /// Notes that `worker` traces `samples` over `region` now.
    pub fn started(&mut self, worker: usize, region: Region, samples: Range<u32>) {
        self.active.insert(worker, (region, samples));
        self.dirty = true;
    }

    /// Takes a finished region: `pixels` (a film of the region's size) replaces what its
    /// pixels showed.
    pub fn finished(&mut self, worker: usize, region: Region, pixels: Option<&Film>) {
        if self.active.get(&worker).is_some_and(|a| a.0 == region) {
            self.active.remove(&worker);
        }
        self.dirty = true;
        let Some(film) = pixels else { return };
        if (film.width, film.height) != (region.width(), region.height())
            || region.x1 > self.width
            || region.y1 > self.height
        {
            return;
        }
        let mean = film.mean();
        self.copy_views(region, film);
        let rays = film.channel(Film::RAYS);
        for (k, y) in (region.y0..region.y1).enumerate() {
            for (j, x) in (region.x0..region.x1).enumerate() {
                let src = k * region.width() as usize + j;
                let dst = (y * self.width + x) as usize;
                self.radiance[dst] = mean[src];
                self.samples_done += film.samples.saturating_sub(self.samples[dst]) as u64;
                self.samples[dst] = film.samples;
                if let Some(r) = rays {
                    let r = (r.data[src][0] >> FIXED_FRACTION_BITS) as u64;
                    self.rays_done += r.saturating_sub(self.rays[dst]);
                    self.rays[dst] = r;
                }
            }
        }
        let now = Instant::now();
        self.samples_per_second = self.sample_rate.record(now, self.samples_done);
        self.rays_per_second = self.ray_rate.record(now, self.rays_done);
    }

    /// Takes the views of a whole-image film of first hits
    /// ([`first_hits`](meshtrace::render::cpu::first_hits)): the AOVs it holds replace what
    /// those views showed.
    pub fn set_views(&mut self, film: &Film) {
        if (film.width, film.height) == (self.width, self.height) {
            self.copy_views(Region::whole(self.width, self.height), film);
            self.dirty = true;
        }
    }

    /// Copies the view AOVs that `film` (of `region`'s size) holds into `region`.
    fn copy_views(&mut self, region: Region, film: &Film) {
        let scalar = |aov: Aov| match film.aov_values(aov).as_deref() {
            Some([AovValues::F32(v)]) => Some(v.clone()),
            _ => None,
        };
        let vector = |aov: Aov| match film.aov_values(aov).as_deref() {
            Some([AovValues::F32(x), AovValues::F32(y), AovValues::F32(z)]) => Some(
                x.iter()
                    .zip(y)
                    .zip(z)
                    .map(|((&x, &y), &z)| Vec3::new(x, y, z))
                    .collect::<Vec<_>>(),
            ),
            _ => None,
        };
        let (albedo, normal) = (vector(Aov::Albedo), vector(Aov::Normal));
        let (depth, cost) = (scalar(Aov::Depth), scalar(Aov::BvhCost));
        for (k, y) in (region.y0..region.y1).enumerate() {
            for (j, x) in (region.x0..region.x1).enumerate() {
                let src = k * region.width() as usize + j;
                let dst = (y * self.width + x) as usize;
                if let Some(a) = &albedo {
                    self.albedo[dst] = a[src];
                }
                if let Some(n) = &normal {
                    self.normal[dst] = n[src];
                }
                if let Some(d) = &depth {
                    self.depth[dst] = d[src];
                }
                if let Some(c) = &cost {
                    self.cost[dst] = c[src];
                }
            }
        }
    }

    /// The image of `view` at the render's size, 8-bit RGB; `exposure` in stops scales the
    /// beauty view. Also returns the range the view's colours stand for (depth and cost:
    /// the lowest and highest value in the image), for the legend.
    pub fn image(&self, view: View, exposure: f32) -> (Vec<[u8; 3]>, Option<(f32, f32)>) {
        let srgb = |c: Vec3| c.to_array().map(meshtrace::film::linear_to_srgb8);
        match view {
            View::Beauty => {
                let k = exposure.exp2();
                (self.radiance.iter().map(|&c| srgb(c * k)).collect(), None)
            }
            View::Albedo => (self.albedo.iter().map(|&c| srgb(c)).collect(), None),
            View::Normal => (
                self.normal
                    .iter()
                    .map(|&n| {
                        if n == Vec3::ZERO {
                            [0; 3]
                        } else {
                            (n * 0.5 + Vec3::splat(0.5))
                                .to_array()
                                .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
                        }
                    })
                    .collect(),
                None,
            ),
            View::Depth => {
                let finite = self.depth.iter().copied().filter(|d| d.is_finite());
                let (lo, hi) = finite.fold((f32::INFINITY, 0.0f32), |(lo, hi), d| {
                    (lo.min(d), hi.max(d))
                });
                let span = (hi - lo).max(1e-6);
                let img = self
                    .depth
                    .iter()
                    .map(|&d| {
                        if d.is_finite() {
                            let g = 40.0 + 215.0 * (1.0 - (d - lo) / span);
                            [g.round() as u8; 3]
                        } else {
                            [0; 3]
                        }
                    })
                    .collect();
                (img, lo.is_finite().then_some((lo, hi)))
            }
            View::BvhCost => {
                let hi = self.cost.iter().copied().fold(0.0f32, f32::max).max(1.0);
                let img = self
                    .cost
                    .iter()
                    .map(|&c| meshtrace::figures::viridis(c / hi))
                    .collect();
                (img, Some((0.0, hi)))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshtrace::fixed::texel_add;

    /// A region's film with radiance `value` in every pixel after `samples` samples.
    fn tile(region: Region, samples: u32, value: f32, aovs: u32) -> Film {
        let mut f = Film::with_aovs(region.width(), region.height(), aovs, false);
        f.samples = samples;
        for s in &mut f.sum {
            *s = meshtrace::fixed::to_fixed3(Vec3::splat(value * samples as f32));
        }
        for c in &mut f.channels {
            for t in &mut c.data {
                *t = texel_add([0; 4], [2.0 * samples as f32, 0.0, 0.0, samples as f32]);
            }
        }
        f
    }

    #[test]
    fn finished_regions_replace_their_pixels_and_count_samples_once() {
        let mut p = Picture::new(32, 16, 8);
        let r = Region {
            x0: 16,
            y0: 0,
            x1: 32,
            y1: 16,
        };
        p.started(1, r, 0..4);
        assert_eq!(p.active.len(), 1);
        p.finished(1, r, Some(&tile(r, 4, 0.5, 0)));
        assert!(p.active.is_empty());
        assert_eq!(p.samples_done, 16 * 16 * 4);
        // Rays: 2 per sample in the tile's `rays` channel.
        assert_eq!(p.rays_done, 16 * 16 * 8);
        p.finished(1, r, Some(&tile(r, 8, 1.0, 0)));
        assert_eq!(p.samples_done, 16 * 16 * 8, "samples counted once");
        let (img, _) = p.image(View::Beauty, 0.0);
        assert_eq!(img[0], [0; 3], "the left half is not rendered yet");
        assert_eq!(img[31], [255; 3], "radiance 1 is white");
        let (img, _) = p.image(View::Beauty, -1.0);
        assert_eq!(img[31], [meshtrace::film::linear_to_srgb8(0.5); 3]);
    }

    #[test]
    fn aov_views_read_the_regions_channels() {
        let mut p = Picture::new(16, 16, 4);
        let r = Region::whole(16, 16);
        p.finished(0, r, Some(&tile(r, 4, 0.25, Aov::mask(&VIEW_AOVS))));
        // Depth: every sample hit at 2 (the hit count is in w).
        let (img, range) = p.image(View::Depth, 0.0);
        assert_eq!(range, Some((2.0, 2.0)));
        assert_eq!(img[0], [255; 3], "the nearest depth is white");
        let (img, range) = p.image(View::BvhCost, 0.0);
        // Cost: the mean over all samples, 2 a ray.
        assert_eq!(range, Some((0.0, 2.0)));
        assert_eq!(img[0], meshtrace::figures::viridis(1.0));
        let (img, _) = p.image(View::Normal, 0.0);
        assert_eq!(img[0], [255, 128, 128], "normal +x");
    }

    #[test]
    fn views_from_first_hits_leave_the_radiance_and_counts_alone() {
        let mut p = Picture::new(16, 16, 4);
        let r = Region::whole(16, 16);
        p.set_views(&tile(r, 4, 0.25, Aov::mask(&VIEW_AOVS)));
        assert_eq!((p.samples_done, p.rays_done), (0, 0));
        assert_eq!(p.image(View::Beauty, 0.0).0[0], [0; 3]);
        assert_eq!(p.image(View::Depth, 0.0).1, Some((2.0, 2.0)));
    }

    #[test]
    fn a_region_of_the_wrong_size_is_ignored() {
        let mut p = Picture::new(16, 16, 4);
        let r = Region::whole(8, 8);
        let wrong = Region { x1: 4, ..r };
        p.finished(0, r, Some(&tile(wrong, 4, 1.0, 0)));
        assert_eq!(p.samples_done, 0);
    }
}
