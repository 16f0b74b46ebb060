//! The WGSL sources, joined in a fixed order (WGSL has no includes). The library files hold
//! the path tracer's stages; `render.wgsl` adds the render kernel, `tests.wgsl` the
//! shader unit-test kernels and `bench.wgsl` the ray-throughput kernels.

/// The shared library, in dependency order.
pub const LIBRARY: &[(&str, &str)] = &[
    ("types.wgsl", include_str!("../../shaders/types.wgsl")),
    ("bindings.wgsl", include_str!("../../shaders/bindings.wgsl")),
    ("rng.wgsl", include_str!("../../shaders/rng.wgsl")),
    ("sampling.wgsl", include_str!("../../shaders/sampling.wgsl")),
    (
        "intersect.wgsl",
        include_str!("../../shaders/intersect.wgsl"),
    ),
    ("traverse.wgsl", include_str!("../../shaders/traverse.wgsl")),
    ("bsdf.wgsl", include_str!("../../shaders/bsdf.wgsl")),
    ("camera.wgsl", include_str!("../../shaders/camera.wgsl")),
    (
        "pathtrace.wgsl",
        include_str!("../../shaders/pathtrace.wgsl"),
    ),
];

const RENDER: &str = include_str!("../../shaders/render.wgsl");
const TESTS: &str = include_str!("../../shaders/tests.wgsl");
const BENCH: &str = include_str!("../../shaders/bench.wgsl");

fn join(extra: &str) -> String {
    let mut src = String::new();
    for (name, text) in LIBRARY {
        src.push_str(&format!("// ---- {name}\n{text}\n"));
    }
    src.push_str(extra);
    src
}

/// The module with the `render` entry point.
pub fn render_source() -> String {
    join(RENDER)
}

/// The module with the `test_*` entry points.
pub fn test_source() -> String {
    join(TESTS)
}

/// The module with the `bench_*` ray-throughput entry points.
pub fn bench_source() -> String {
    join(BENCH)
}
