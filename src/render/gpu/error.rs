//! What can go wrong on the GPU path.

/// What can go wrong on the GPU path; each message says what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no Vulkan adapter found; install a Vulkan driver (for a CPU-only machine, Mesa's lavapipe: `apt-get install mesa-vulkan-drivers`) or use --device cpu"
    )]
    NoAdapter,
    #[error("no adapter matches `{0}` (there are {1}); run `meshtrace adapters` to list them")]
    NoSuchAdapter(String, usize),
    #[error("cannot open the GPU device: {0}")]
    Device(String),
    #[error(
        "the {what} need {bytes} bytes but this adapter holds at most {limit} ({rule}); {}",
        too_large_fix(what)
    )]
    TooLarge {
        what: &'static str,
        bytes: u64,
        limit: u64,
        /// The adapter limit that sets `limit`, as wgpu names it, with its value.
        rule: String,
    },
    #[error(
        "--accel hardware: the adapter {0} offers no hardware ray queries; use --accel auto or --accel software"
    )]
    NoRayQuery(String),
    #[error("GPU error: {0}")]
    Fault(String),
}

/// The texel table's name in [`GpuError::TooLarge`] (its `what`).
pub const TEXEL_TABLE: &str = "texels";

/// What [`GpuError::TooLarge`] advises for the table it names: the texel table shrinks when
/// textures are scaled down on load; anything else fits only on the CPU or in a smaller scene.
fn too_large_fix(what: &str) -> &'static str {
    if what == TEXEL_TABLE {
        "scale the textures down with --max-texture-size N (a manifest's max_texture_size; \
         N = 4096 or 2048, say), or use --device cpu"
    } else {
        "use --device cpu or a smaller scene"
    }
}
