//! Watching a render while it runs: which part of the image each worker is tracing, and
//! each part's pixels once it is done. `render --preview` draws from this; both drivers
//! call it ([`cpu`](super::cpu) per 16×16 tile and rayon thread, [`gpu`](super::gpu) per
//! dispatch over a band of rows).

use crate::film::Film;
use std::ops::Range;

/// A rectangle of pixels: columns `x0..x1`, rows `y0..y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Region {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl Region {
    /// All of a `width` × `height` image.
    pub fn whole(width: u32, height: u32) -> Self {
        Self {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    /// Pixels in the region.
    pub fn pixels(&self) -> u64 {
        self.width() as u64 * self.height() as u64
    }
}

/// Told of a render's progress region by region, from the worker threads.
pub trait Watch: Send + Sync {
    /// `worker` (a CPU thread's index, or 0 for the GPU's queue) starts tracing samples
    /// `samples` of every pixel of `region`.
    fn started(&self, worker: usize, region: Region, samples: Range<u32>);

    /// `worker` finished `region`. `pixels` is a film of the region's size holding
    /// everything its pixels have gathered so far (`samples` of them each, AOVs included),
    /// or `None` where [`Watch::wants_pixels`] declined them.
    fn finished(&self, worker: usize, region: Region, pixels: Option<&Film>);

    /// Whether the next finished region should bring its pixels. The GPU reads them back
    /// from the device only when this says so (and for a region's last samples), so a
    /// watcher can bound what that costs.
    fn wants_pixels(&self) -> bool {
        true
    }
}
