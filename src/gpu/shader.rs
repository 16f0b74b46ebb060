//! The WGSL sources, joined in a fixed order (WGSL has no includes). The library files hold
//! the path tracer's stages; `render.wgsl` adds the render kernel, `tests.wgsl` the
//! shader unit-test kernels and `bench.wgsl` the ray-throughput kernels.

use super::TableStorage;

const TYPES: (&str, &str) = ("types.wgsl", include_str!("../../shaders/types.wgsl"));

/// How the tables are bound, one file per [`TableStorage`].
const TEXTURE_BINDINGS: (&str, &str) =
    ("bindings.wgsl", include_str!("../../shaders/bindings.wgsl"));
const UNIFORM_BINDINGS: (&str, &str) = (
    "bindings_uniform.wgsl",
    include_str!("../../shaders/bindings_uniform.wgsl"),
);

/// The shared library after the types and bindings, in dependency order.
const LIBRARY: &[(&str, &str)] = &[
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

fn join(tables: TableStorage, extra: &str) -> String {
    let bindings = match tables {
        TableStorage::Textures => TEXTURE_BINDINGS,
        TableStorage::Uniform => UNIFORM_BINDINGS,
    };
    let mut src = String::new();
    for (name, text) in [TYPES, bindings].iter().chain(LIBRARY) {
        src.push_str(&format!("// ---- {name}\n{text}\n"));
    }
    src.push_str(extra);
    src
}

/// The module with the `render` entry point, for tables bound as `tables` says.
pub fn render_source(tables: TableStorage) -> String {
    join(tables, RENDER)
}

/// The module with the `test_*` entry points.
pub fn test_source(tables: TableStorage) -> String {
    join(tables, TESTS)
}

/// The module with the `bench_*` ray-throughput entry points.
pub fn bench_source(tables: TableStorage) -> String {
    join(tables, BENCH)
}
