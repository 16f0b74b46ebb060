//! The WGSL sources, joined in a fixed order (WGSL has no includes): first what is
//! generated from the Rust side (the shared constants, the table bindings and loaders),
//! then the library files of `shaders/`, then one entry-point file: `render.wgsl` (the
//! render kernel), `tests.wgsl` (the shader unit-test kernels) or `bench.wgsl` (the
//! ray-throughput kernels). A device that traces with hardware ray queries gets
//! `ray_query.wgsl` in place of `traverse.wgsl` (the same functions over the scene's TLAS),
//! the `enable wgpu_ray_query;` directive and the TLAS binding.

use super::layout::StructLayout;
use super::params::{Params, SKY_CONSTANT, SKY_ENVIRONMENT, SKY_GRADIENT};
use super::tables::{Element, TABLE_WIDTH, TABLES, wgsl_tables, wgsl_tlas};
use crate::bvh::STACK_SIZE;
use crate::film::{Aov, NO_ID};
use crate::fixed::{FIXED_LIMIT, FIXED_ONE};
use crate::geometry::{GAMMA_2, GAMMA_3, SLAB_SLACK, T_INF};
use crate::render::bsdf::{COAT_FRESNEL_AVERAGE, LOBE_DIFFUSE, LOBE_GLOSSY, LOBE_TRANSMISSION};
use crate::render::caustics::{LIGHT_SUBPATH_RATE, MAX_CAUSTIC_HOPS};
use crate::render::integrator::RR_DEPTH;
use crate::render::rng;
use crate::render::sampling::{ONE_MINUS_EPSILON, UNIFORM_SPHERE_PDF};
use crate::render::sheen::{
    SHEEN_MIN_ROUGHNESS, SHEEN_TABLE_COSINES, SHEEN_TABLE_OFFSET, SHEEN_TABLE_ROUGHNESSES,
};
use crate::render::tables::{
    LIGHT_DIRECTIONAL, LIGHT_EMITTER, LIGHT_POINT, LIGHT_RECT, LIGHT_SPOT, RenderScene,
    SKY_EMITTER, TRI_COLOR, TRI_SMOOTH, TRI_TANGENT, TRI_UV, TRI_UV1,
};
use crate::scene::material::{MAT_ALPHA_MASK, MAT_SPEC_GLOSS, MAT_THIN_WALLED};
use crate::scene::{Material, MaterialKind, NO_TEXTURE, TextureFormat, Wrap};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4, PI};

/// The value of a shared constant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    U32(u32),
    F32(f32),
}

/// Every constant that Rust and WGSL share, with its Rust value: the one list. The WGSL
/// files declare none of these; [`wgsl_constants`] generates them.
pub fn shared_constants() -> Vec<(String, Value)> {
    use Value::{F32, U32};
    let mut list: Vec<(String, Value)> = [
        ("DIM_PIXEL_X", U32(rng::DIM_PIXEL_X)),
        ("DIM_PIXEL_Y", U32(rng::DIM_PIXEL_Y)),
        ("DIM_LENS_U", U32(rng::DIM_LENS_U)),
        ("DIM_LENS_V", U32(rng::DIM_LENS_V)),
        ("DIM_LIGHT_U", U32(rng::DIM_LIGHT_U)),
        ("DIM_LIGHT_V", U32(rng::DIM_LIGHT_V)),
        ("DIM_BSDF_LOBE", U32(rng::DIM_BSDF_LOBE)),
        ("DIM_BSDF_U", U32(rng::DIM_BSDF_U)),
        ("DIM_BSDF_V", U32(rng::DIM_BSDF_V)),
        ("DIM_ROULETTE", U32(rng::DIM_ROULETTE)),
        ("DIM_LIGHT_SUBPATH", U32(rng::DIM_LIGHT_SUBPATH)),
        ("DIM_CAUSTIC_LIGHT_U", U32(rng::DIM_CAUSTIC_LIGHT_U)),
        ("DIM_CAUSTIC_LIGHT_V", U32(rng::DIM_CAUSTIC_LIGHT_V)),
        ("DIM_CAUSTIC_DIR_U", U32(rng::DIM_CAUSTIC_DIR_U)),
        ("DIM_CAUSTIC_DIR_V", U32(rng::DIM_CAUSTIC_DIR_V)),
        ("DIM_CAUSTIC_LOBE", U32(rng::DIM_CAUSTIC_LOBE)),
        ("MAX_CAUSTIC_HOPS", U32(MAX_CAUSTIC_HOPS as u32)),
        ("LIGHT_SUBPATH_RATE", F32(LIGHT_SUBPATH_RATE)),
        ("DIMS_PER_BOUNCE", U32(rng::DIMS_PER_BOUNCE)),
        ("STACK_SIZE", U32(STACK_SIZE as u32)),
        ("RR_DEPTH", U32(RR_DEPTH)),
        ("LOBE_DIFFUSE", U32(LOBE_DIFFUSE)),
        ("LOBE_GLOSSY", U32(LOBE_GLOSSY)),
        ("LOBE_TRANSMISSION", U32(LOBE_TRANSMISSION)),
        ("TRI_SMOOTH", U32(TRI_SMOOTH)),
        ("TRI_UV", U32(TRI_UV)),
        ("TRI_TANGENT", U32(TRI_TANGENT)),
        ("TRI_COLOR", U32(TRI_COLOR)),
        ("TRI_UV1", U32(TRI_UV1)),
        ("LIGHT_POINT", U32(LIGHT_POINT)),
        ("LIGHT_SPOT", U32(LIGHT_SPOT)),
        ("LIGHT_DIRECTIONAL", U32(LIGHT_DIRECTIONAL)),
        ("LIGHT_RECT", U32(LIGHT_RECT)),
        ("LIGHT_EMITTER", U32(LIGHT_EMITTER)),
        ("SKY_EMITTER", U32(SKY_EMITTER)),
        ("SKY_CONSTANT", U32(SKY_CONSTANT)),
        ("SKY_GRADIENT", U32(SKY_GRADIENT)),
        ("SKY_ENVIRONMENT", U32(SKY_ENVIRONMENT)),
        ("NO_TEXTURE", U32(NO_TEXTURE)),
        ("NO_ID", U32(NO_ID)),
        ("MAT_THIN_WALLED", U32(MAT_THIN_WALLED)),
        ("MAT_ALPHA_MASK", U32(MAT_ALPHA_MASK)),
        ("MAT_SPEC_GLOSS", U32(MAT_SPEC_GLOSS)),
        ("SHEEN_MIN_ROUGHNESS", F32(SHEEN_MIN_ROUGHNESS)),
        ("COAT_FRESNEL_AVERAGE", F32(COAT_FRESNEL_AVERAGE)),
        ("SHEEN_TABLE_COSINES", U32(SHEEN_TABLE_COSINES)),
        ("SHEEN_TABLE_ROUGHNESSES", U32(SHEEN_TABLE_ROUGHNESSES)),
        ("SHEEN_TABLE_OFFSET", U32(SHEEN_TABLE_OFFSET)),
        ("TABLE_WIDTH_LOG2", U32(TABLE_WIDTH.ilog2())),
        ("T_INF", F32(T_INF)),
        ("GAMMA_2", F32(GAMMA_2)),
        ("GAMMA_3", F32(GAMMA_3)),
        ("SLAB_SLACK", F32(SLAB_SLACK)),
        ("PI", F32(PI)),
        ("FRAC_1_PI", F32(FRAC_1_PI)),
        ("FRAC_PI_4", F32(FRAC_PI_4)),
        ("UNIFORM_SPHERE_PDF", F32(UNIFORM_SPHERE_PDF)),
        ("ONE_MINUS_EPSILON", F32(ONE_MINUS_EPSILON)),
        ("FIXED_ONE", F32(FIXED_ONE)),
        ("FIXED_LIMIT", F32(FIXED_LIMIT)),
    ]
    .map(|(n, v)| (n.to_string(), v))
    .into();
    for (kind, name) in MaterialKind::ALL {
        list.push((format!("MAT_{}", name.to_uppercase()), U32(kind.0)));
    }
    for (format, name) in TextureFormat::ALL {
        list.push((format!("TEX_{}", name.to_uppercase()), U32(format.0)));
    }
    for (wrap, name) in Wrap::ALL {
        list.push((format!("WRAP_{}", name.to_uppercase()), U32(wrap.0)));
    }
    for aov in Aov::ALL {
        list.push((format!("AOV_{}", aov.name().to_uppercase()), U32(aov.bit())));
    }
    list.push(("AOV_COUNT".into(), U32(Aov::ALL.len() as u32)));
    list
}

/// The shared constants as WGSL declarations. Floats are written in the shortest decimal
/// that reads back as the same f32 (Rust's `{:?}`); `tests/layout.rs` checks the bits.
pub fn wgsl_constants() -> String {
    shared_constants()
        .iter()
        .map(|(name, value)| match value {
            Value::U32(v) => format!("const {name}: u32 = {v}u;\n"),
            Value::F32(v) => format!("const {name}: f32 = {v:?};\n"),
        })
        .collect()
}

/// Every host-shared struct, described from its Rust definition, once each: the tables'
/// elements and the parameter block. `tests/layout.rs` checks each against its WGSL twin.
pub fn host_structs() -> Vec<StructLayout> {
    let mut out: Vec<StructLayout> = Vec::new();
    for t in TABLES {
        // Two tables may share a struct (both texture coordinate sets are `TriUvs`).
        if let Element::Struct(s) = (t.element)()
            && !out.iter().any(|o| o.name == s.name)
        {
            out.push(s);
        }
    }
    out.push(Params::layout());
    out
}

/// A source file of `shaders/`: its name and text.
type Source = (&'static str, &'static str);

macro_rules! shader {
    ($name:literal) => {
        ($name, include_str!(concat!("../../../shaders/", $name)))
    };
}

/// The shared library, in dependency order (struct types and bindings first): this part,
/// then the traversal ([`TRAVERSE`] or [`RAY_QUERY`]), then [`SHADING`].
const LIBRARY: &[Source] = &[
    shader!("types.wgsl"),
    shader!("math.wgsl"),
    shader!("fixed.wgsl"),
    shader!("material.wgsl"),
    shader!("bindings.wgsl"),
    shader!("rng.wgsl"),
    shader!("sampling.wgsl"),
    shader!("geometry.wgsl"),
];

/// The rest of the library, which calls the traversal: these, then the caustics
/// ([`CAUSTICS`] or [`NO_CAUSTICS`]), then the integrator.
const SHADING: &[Source] = &[
    shader!("sheen.wgsl"),
    shader!("bsdf.wgsl"),
    shader!("camera.wgsl"),
    shader!("texture.wgsl"),
    shader!("surface.wgsl"),
    shader!("environment.wgsl"),
    shader!("lights.wgsl"),
];

/// Light subpaths for caustics.
const CAUSTICS: Source = shader!("caustics.wgsl");
/// Their replacement in the render kernel of a scene without caustic targets, and in the
/// ray-throughput kernels, which trace none: the names the integrator uses, doing nothing.
const NO_CAUSTICS: Source = shader!("no_caustics.wgsl");

const INTEGRATOR: Source = shader!("integrator.wgsl");

/// The software BVH walk.
const TRAVERSE: Source = shader!("traverse.wgsl");
/// Its replacement on a device that traces with hardware ray queries.
const RAY_QUERY: Source = shader!("ray_query.wgsl");

const RENDER: Source = shader!("render.wgsl");
const TESTS: Source = shader!("tests.wgsl");
const BENCH: Source = shader!("bench.wgsl");

/// How a module is compiled and what it checks at run time.
///
/// A trusted module is created with `create_shader_module_trusted` and every runtime
/// check off but ray-query tracking: naga then adds no index clamps, no loop counters
/// and no guards on integer division, which it would otherwise put in every iteration
/// of the traversal. That is
/// sound because the kernels index only in range and every loop ends: the traversal stack
/// holds at most the tree's depth, which `Bvh::build` keeps under `STACK_SIZE`; every
/// table index comes from validated scene data; the divisors are texture sizes, at least 1.
/// A checked module keeps naga's checks and also tests each of those claims itself where
/// it relies on them (`check` in shaders/bindings.wgsl), counting the failures, which the
/// render kernel reports: tests/checked_kernels.rs renders the test scenes checked, and
/// requires no failure and the trusted kernel's bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ShaderChecks {
    /// No runtime checks (but ray-query tracking): what renders and benchmarks run.
    #[default]
    Trusted,
    /// naga's checks, plus the kernel's own count of out-of-range indices and zero divisors.
    Checked,
}

/// The optional parts of the path tracer that a scene uses: the kernels read each as a WGSL
/// pipeline-overridable constant (`override` in `shaders/texture.wgsl`), set per pipeline,
/// and a part that is off compiles out. Drivers inline every call, so without this the
/// texture lookups of `material_at` and the alpha test sit in every shading site and every
/// copy of the traversal loop, where lanes that never take them still pay for them
/// (lavapipe runs both sides of every branch, masked: its Cornell box renders 3.4× faster
/// without them) and hold registers for them. The results do not change: a scene without
/// textures has no texture to look up, and one without alpha masks no masked triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Features {
    /// The scene has textures (material slots, normal maps, an environment map): `TEXTURES`.
    pub textures: bool,
    /// Some material is an alpha mask or unlit (rays pass through it): `ALPHA_MASKS`.
    pub alpha_masks: bool,
}

impl Features {
    /// The parts `scene` uses.
    pub fn of(scene: &RenderScene) -> Self {
        Self {
            textures: !scene.textures.is_empty(),
            alpha_masks: scene.materials.iter().any(Material::is_masked),
        }
    }

    /// The pipeline constants that set these (a WGSL bool is 0.0 or 1.0 here).
    pub fn constants(self) -> [(&'static str, f64); 2] {
        let value = |on: bool| if on { 1.0 } else { 0.0 };
        [
            ("TEXTURES", value(self.textures)),
            ("ALPHA_MASKS", value(self.alpha_masks)),
        ]
    }
}

/// A module's source for a traversal (`ray_query`) and [`ShaderChecks`]: one of
/// [`render_source`], [`render_source_without_caustics`], [`test_source`] and
/// [`bench_source`].
pub type Module = fn(bool, ShaderChecks) -> String;

fn join(entry_points: Source, ray_query: bool, checks: ShaderChecks, caustics: bool) -> String {
    let mut src = String::new();
    if ray_query {
        src += "enable wgpu_ray_query;\n\n";
    }
    src += "// ---- generated: src/render/gpu/shader.rs `wgsl_constants`\n";
    src += &wgsl_constants();
    src += &format!(
        "const SHADER_CHECKS: bool = {};\n",
        checks == ShaderChecks::Checked
    );
    src += "\n// ---- generated: src/render/gpu/tables.rs `wgsl_tables`\n";
    src += &wgsl_tables();
    if ray_query {
        src += "\n// ---- generated: src/render/gpu/tables.rs `wgsl_tlas`\n";
        src += &wgsl_tlas();
    }
    let traversal = if ray_query { RAY_QUERY } else { TRAVERSE };
    let caustics = if caustics { CAUSTICS } else { NO_CAUSTICS };
    for (name, text) in LIBRARY.iter().chain([&traversal]).chain(SHADING).chain([
        &caustics,
        &INTEGRATOR,
        &entry_points,
    ]) {
        src.push_str(&format!("\n// ---- {name}\n{text}"));
    }
    src
}

/// The module with the `render` entry point; with `ray_query`, traversing by hardware ray
/// queries; `checks` as [`ShaderChecks`] says.
pub fn render_source(ray_query: bool, checks: ShaderChecks) -> String {
    join(RENDER, ray_query, checks, true)
}

/// [`render_source`] for a scene without caustic targets: `no_caustics.wgsl` in place of
/// `caustics.wgsl`.
pub fn render_source_without_caustics(ray_query: bool, checks: ShaderChecks) -> String {
    join(RENDER, ray_query, checks, false)
}

/// The module with the `test_*` entry points; arguments as [`render_source`].
pub fn test_source(ray_query: bool, checks: ShaderChecks) -> String {
    join(TESTS, ray_query, checks, true)
}

/// The module with the `bench_*` ray-throughput entry points, which trace no light
/// subpaths; arguments as [`render_source`].
pub fn bench_source(ray_query: bool, checks: ShaderChecks) -> String {
    join(BENCH, ray_query, checks, false)
}
