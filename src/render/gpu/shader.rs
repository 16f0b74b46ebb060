//! The WGSL sources, joined in a fixed order (WGSL has no includes). The library files hold
//! the path tracer's stages; `render.wgsl` adds the render kernel, `tests.wgsl` the
//! shader unit-test kernels and `bench.wgsl` the ray-throughput kernels.

/// A source file of `shaders/`: its name and text.
type Source = (&'static str, &'static str);

macro_rules! shader {
    ($name:literal) => {
        ($name, include_str!(concat!("../../../shaders/", $name)))
    };
}

/// The shared library, in dependency order (struct types and bindings first).
const LIBRARY: &[Source] = &[
    shader!("types.wgsl"),
    shader!("bindings.wgsl"),
    shader!("rng.wgsl"),
    shader!("sampling.wgsl"),
    shader!("geometry.wgsl"),
    shader!("traverse.wgsl"),
    shader!("bsdf.wgsl"),
    shader!("camera.wgsl"),
    shader!("lights.wgsl"),
    shader!("integrator.wgsl"),
];

const RENDER: Source = shader!("render.wgsl");
const TESTS: Source = shader!("tests.wgsl");
const BENCH: Source = shader!("bench.wgsl");

fn join(entry_points: Source) -> String {
    let mut src = String::new();
    for (name, text) in LIBRARY.iter().chain([&entry_points]) {
        src.push_str(&format!("// ---- {name}\n{text}\n"));
    }
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
