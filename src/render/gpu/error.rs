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
        "the {what} need {bytes} bytes but this adapter holds at most {limit} ({rule}); use --device cpu or a smaller scene"
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
