//! The settings that decide an image's size, samples and light transport: the `[render]`
//! table of a scene file, over which a render request lays its own.

/// How to render: the `[render]` table, after command-line overrides.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// Longest path in segments from the camera (1 = emitters seen directly).
    pub max_depth: u32,
    pub seed: u32,
    /// Whether some camera samples also trace light subpaths through the scene's specular
    /// materials, joined to the camera paths (`render::caustics`): caustics with far less
    /// noise. Off, the render is the path tracer's alone, as Mitsuba 3's `path` renders.
    pub caustics: bool,
    /// How many paths each camera sample branches into at its first hit
    /// (`render::integrator`): the samples of indirect light per camera sample. Each
    /// costs about a path less its camera ray and first vertex. `None`: [`Self::branches`]
    /// decides.
    pub branches: Option<u32>,
    /// The side, in pixels, of the square centred on a pixel over which its camera samples
    /// fall uniformly (a box filter): 1 by default; below 1 sharper and aliased, down to 0,
    /// every sample through the pixel's centre (the Zero123 script's `filter_width`
    /// 0.01); above 1 softer.
    pub filter_width: f32,
    /// The most bounces of each kind of scattering a path may take, as Cycles limits them
    /// (the dataset scripts set its `diffuse_bounces` and `glossy_bounces` to 1); none by
    /// default, where `max_depth` alone ends paths.
    pub bounces: BounceLimits,
}

/// Cycles' bounce limits by kind of scattering: its `diffuse_bounces`, `glossy_bounces`
/// and `transmission_bounces`, with its meaning. A limit of n lets a path scatter n + 1
/// times of that kind (the last scattering's ray still finds emission), so that 0 gives
/// direct light alone and each step one more indirect bounce; the surface the path meets
/// after its last allowed scattering adds only its emission. Diffuse counts the diffuse
/// and sheen lobes' reflections, glossy the specular lobes', the clear coat's and the
/// conductors', transmission every direction through a surface. `None`: no limit.
/// Light subpaths (caustics) count towards `max_depth` alone.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BounceLimits {
    pub diffuse: Option<u32>,
    pub glossy: Option<u32>,
    pub transmission: Option<u32>,
}

impl BounceLimits {
    /// The scatterings of each kind (diffuse, glossy, transmission) a path may take: each
    /// limit plus one, or `u32::MAX` for none. The path state counts them down.
    pub fn budget(&self) -> glam::UVec3 {
        let left = |limit: Option<u32>| limit.map_or(u32::MAX, |n| n.saturating_add(1));
        glam::UVec3::new(
            left(self.diffuse),
            left(self.glossy),
            left(self.transmission),
        )
    }
}

/// The widest [`RenderSettings::filter_width`], as Cycles' widest pixel filter.
pub const MAX_FILTER_WIDTH: f32 = 10.0;

/// Most pixels an image may have: 2^26 (8192 x 8192); the film alone then takes 768 MiB.
pub const MAX_PIXELS: u64 = 1 << 26;

/// Whether renders trace caustic light subpaths unless told otherwise.
pub const CAUSTICS_DEFAULT: bool = true;

/// Branches at the first hit unless told otherwise, in a render without caustic light
/// subpaths (BENCHMARKS.md: the quality per second of 1, 2, 4 and 8 on the benchmark
/// scenes).
pub const BRANCHES_DEFAULT: u32 = 4;

/// The most branches a setting may ask for.
pub const MAX_BRANCHES: u32 = 64;

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            spp: 64,
            max_depth: 8,
            seed: 0,
            caustics: CAUSTICS_DEFAULT,
            branches: None,
            filter_width: 1.0,
            bounces: BounceLimits::default(),
        }
    }
}

impl RenderSettings {
    /// Checks the settings, wherever they came from (a scene file, a manifest, flags, a
    /// library caller): the one check of them all. The error names the field as the scene
    /// format spells it (`max_depth`), for the caller to place (`render.max_depth`,
    /// `--max-depth`).
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        let s = self;
        if s.width == 0 {
            return Err(("width", "must be at least 1".into()));
        }
        if s.height == 0 {
            return Err(("height", "must be at least 1".into()));
        }
        let pixels = s.width as u64 * s.height as u64;
        if pixels > MAX_PIXELS {
            return Err((
                "width",
                format!(
                    "{}x{} is too large: at most {MAX_PIXELS} pixels",
                    s.width, s.height
                ),
            ));
        }
        if s.spp == 0 {
            return Err(("spp", "must be at least 1".into()));
        }
        if s.max_depth == 0 {
            return Err(("max_depth", "must be at least 1".into()));
        }
        if !(0.0..=MAX_FILTER_WIDTH).contains(&s.filter_width) {
            return Err((
                "filter_width",
                format!(
                    "must be from 0 to {MAX_FILTER_WIDTH} pixels, not {}",
                    s.filter_width
                ),
            ));
        }
        if let Some(b) = s.branches
            && !(1..=MAX_BRANCHES).contains(&b)
        {
            return Err((
                "branches",
                format!("must be from 1 to {MAX_BRANCHES}, not {b}"),
            ));
        }
        Ok(())
    }

    /// The branches of each camera sample: as set, else [`BRANCHES_DEFAULT`] in a render
    /// that traces no caustic light subpaths and 1 in one that does. There each branch
    /// traces a light subpath of its own and costs nearly a whole sample, so that
    /// branching no longer pays (BENCHMARKS.md, the glass-and-mirror box).
    pub fn branches(&self, light_subpaths: bool) -> u32 {
        self.branches
            .unwrap_or(if light_subpaths { 1 } else { BRANCHES_DEFAULT })
    }
}
