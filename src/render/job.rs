//! One render job: its settings, the samples it covers, and how it may be stopped
//! ([`RenderJob::cancel`]) or observed while it runs (checkpoints, [`watch`](super::watch)).

use super::watch;
use crate::film::Film;
use crate::scene::RenderSettings;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

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
    /// Whether to trace camera rays alone: the AOVs, and for radiance the first surface's
    /// albedo (nothing where the ray misses), without path tracing.
    pub geometry: bool,
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
            geometry: false,
            watch: None,
        }
    }

    /// The job with the AOVs of mask `aovs`, and [`RenderJob::transparent`] or not.
    pub fn with_aovs(mut self, aovs: u32, transparent: bool) -> Self {
        self.aovs = aovs;
        self.transparent = transparent;
        self
    }

    /// The job tracing camera rays alone ([`RenderJob::geometry`]) or not.
    pub fn with_geometry(mut self, geometry: bool) -> Self {
        self.geometry = geometry;
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
