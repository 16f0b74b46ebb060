//! The WGSL sources against their Rust twins, without a device: both modules parse and
//! validate with naga; every struct the host uploads has the same size and member offsets
//! as its `#[repr(C)]` Rust twin; the shared constants agree; and every `mirror:` tag
//! names something that exists on the other side.

use meshtrace::bvh::BvhNode;
use meshtrace::geometry::TriVerts;
use meshtrace::render::TriShading;
use meshtrace::render::gpu::params::{GpuMaterial, GpuParams};
use meshtrace::render::gpu::shader;
use meshtrace::render::rng;
use meshtrace::scene::MaterialKind;
use naga::valid::{Capabilities, ValidationFlags, Validator};
use std::path::Path;

/// Parses and validates one WGSL module, failing with naga's rendered diagnostics.
fn parse_and_validate(what: &str, source: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{what}: WGSL parse error:\n{}", e.emit_to_string(source)));
    Validator::new(ValidationFlags::all(), Capabilities::all())
        .validate(&module)
        .unwrap_or_else(|e| panic!("{what}: validation error:\n{}", e.emit_to_string(source)));
    module
}

/// Every module the host compiles, one per entry-point file; the test module first.
fn modules() -> Vec<(String, naga::Module)> {
    type Source = fn() -> String;
    let sources: [(&str, Source); 3] = [
        ("test_source", shader::test_source),
        ("render_source", shader::render_source),
        ("bench_source", shader::bench_source),
    ];
    sources
        .iter()
        .map(|&(name, source)| (name.to_string(), parse_and_validate(name, &source())))
        .collect()
}

#[test]
fn every_module_parses_and_validates() {
    for (what, m) in modules() {
        assert!(
            !m.entry_points.is_empty(),
            "{what}: no entry points after parsing"
        );
    }
}

/// One member of a struct: name, byte offset, byte size.
#[derive(Clone, Debug, PartialEq)]
struct Member {
    name: String,
    offset: usize,
    size: usize,
}

fn field_size<T, F>(_: impl Fn(&T) -> &F) -> usize {
    size_of::<F>()
}

/// The Rust struct's size and fields. The destructuring pattern makes the field list
/// exhaustive: a field added to the Rust struct and not here fails to compile.
macro_rules! rust_layout {
    ($t:ident { $($f:ident),* $(,)? }) => {{
        #[allow(dead_code)]
        fn exhaustive(x: $t) {
            let $t { $($f: _),* } = x;
        }
        (
            size_of::<$t>(),
            vec![$(Member {
                name: stringify!($f).to_string(),
                offset: std::mem::offset_of!($t, $f),
                size: field_size(|x: &$t| &x.$f),
            }),*],
        )
    }};
}

/// The WGSL struct `name`'s size and members, by naga's layout.
fn wgsl_layout(module: &naga::Module, name: &str) -> (usize, Vec<Member>) {
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).expect("layout");
    let (handle, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("WGSL struct `{name}` not found"));
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("WGSL type `{name}` is not a struct");
    };
    assert_eq!(
        layouter[handle].size, *span,
        "{name}: naga's layouter and struct span disagree"
    );
    let members = members
        .iter()
        .map(|m| Member {
            name: m.name.clone().unwrap_or_default(),
            offset: m.offset as usize,
            size: layouter[m.ty].size as usize,
        })
        .collect();
    (*span as usize, members)
}

/// Matches members by name. A WGSL member `xN` with no Rust field of that name stands for
/// element N of the Rust array field `x` (e.g. `_pad0` .. `_pad2` for `_pad: [u32; 3]`).
fn assert_same_layout(wgsl_name: &str, wgsl: (usize, Vec<Member>), rust: (usize, Vec<Member>)) {
    let (wsize, wmembers) = wgsl;
    let (rsize, rmembers) = rust;
    assert_eq!(
        wsize, rsize,
        "{wgsl_name}: WGSL size {wsize} != Rust size_of {rsize}"
    );
    let mut covered = vec![0usize; rmembers.len()];
    for w in &wmembers {
        let (ri, expect_offset) = if let Some(ri) = rmembers.iter().position(|r| r.name == w.name) {
            (ri, rmembers[ri].offset)
        } else {
            let stem = w.name.trim_end_matches(|c: char| c.is_ascii_digit());
            let index: usize = w.name[stem.len()..]
                .parse()
                .unwrap_or_else(|_| panic!("{wgsl_name}.{}: no Rust field of that name", w.name));
            let ri = rmembers
                .iter()
                .position(|r| r.name == stem)
                .unwrap_or_else(|| {
                    panic!(
                        "{wgsl_name}.{}: no Rust field `{}` or `{stem}`",
                        w.name, w.name
                    )
                });
            (ri, rmembers[ri].offset + index * w.size)
        };
        assert_eq!(
            w.offset, expect_offset,
            "{wgsl_name}.{}: WGSL offset {} != Rust offset {expect_offset} (field `{}`)",
            w.name, w.offset, rmembers[ri].name
        );
        covered[ri] += w.size;
    }
    for (r, &c) in rmembers.iter().zip(&covered) {
        assert_eq!(
            c, r.size,
            "{wgsl_name}: Rust field `{}` ({} bytes) is covered by {c} bytes of WGSL members",
            r.name, r.size
        );
    }
}

#[test]
fn structs_match_their_rust_twins() {
    for (what, module) in modules() {
        eprintln!("checking {what}");
        assert_same_layout(
            "BvhNode",
            wgsl_layout(&module, "BvhNode"),
            rust_layout!(BvhNode {
                min,
                left_or_first,
                max,
                count
            }),
        );
        assert_same_layout(
            "TriVerts",
            wgsl_layout(&module, "TriVerts"),
            rust_layout!(TriVerts { v0, v1, v2 }),
        );
        assert_same_layout(
            "TriShading",
            wgsl_layout(&module, "TriShading"),
            rust_layout!(TriShading {
                n0,
                material,
                n1,
                emitter_pmf,
                n2,
                flags
            }),
        );
        assert_same_layout(
            "Material",
            wgsl_layout(&module, "Material"),
            rust_layout!(GpuMaterial {
                albedo,
                kind,
                emission,
                roughness,
                ior,
                _pad
            }),
        );
        assert_same_layout(
            "Params",
            wgsl_layout(&module, "Params"),
            rust_layout!(GpuParams {
                cam_position,
                width,
                cam_forward,
                height,
                cam_right,
                max_depth,
                cam_up,
                seed,
                sky_zenith,
                sky_gradient,
                sky_horizon,
                num_emitters,
                tan_half_vfov,
                aspect,
                aperture,
                focus_distance,
                sample_start,
                sample_end,
                row_start,
                row_end,
                sky_pmf,
                film_texels,
                _pad,
            }),
        );
    }
}

#[test]
fn layout_check_can_fail() {
    // A twin with a member moved must be caught: the check is not vacuous.
    let module = &modules()[0].1;
    let mut rust = rust_layout!(BvhNode {
        min,
        left_or_first,
        max,
        count
    });
    rust.1[1].offset = 16; // left_or_first
    let r = std::panic::catch_unwind(|| {
        assert_same_layout("BvhNode", wgsl_layout(module, "BvhNode"), rust)
    });
    assert!(r.is_err(), "a wrong offset passed the layout check");
    let r = std::panic::catch_unwind(|| {
        assert_same_layout(
            "TriVerts",
            wgsl_layout(module, "TriVerts"),
            (32, rust_layout!(TriVerts { v0, v1, v2 }).1),
        )
    });
    assert!(r.is_err(), "a wrong size passed the layout check");
}

/// The literal initialising the WGSL constant `name`.
fn wgsl_const_literal(module: &naga::Module, name: &str) -> naga::Literal {
    let (_, c) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("WGSL constant `{name}` not found"));
    match module.global_expressions[c.init] {
        naga::Expression::Literal(l) => l,
        ref e => panic!("WGSL constant `{name}` is not a literal: {e:?}"),
    }
}

/// The value of the WGSL `const name: u32`.
fn wgsl_u32_const(module: &naga::Module, name: &str) -> u32 {
    match wgsl_const_literal(module, name) {
        naga::Literal::U32(v) => v,
        naga::Literal::I32(v) if v >= 0 => v as u32,
        naga::Literal::AbstractInt(v) => v as u32,
        l => panic!("WGSL constant `{name}` is not an integer: {l:?}"),
    }
}

#[test]
fn constants_match_rust() {
    let expected: &[(&str, u32)] = &[
        ("DIM_PIXEL_X", rng::DIM_PIXEL_X),
        ("DIM_PIXEL_Y", rng::DIM_PIXEL_Y),
        ("DIM_LENS_U", rng::DIM_LENS_U),
        ("DIM_LENS_V", rng::DIM_LENS_V),
        ("DIM_LIGHT_PICK", rng::DIM_LIGHT_PICK),
        ("DIM_LIGHT_U", rng::DIM_LIGHT_U),
        ("DIM_LIGHT_V", rng::DIM_LIGHT_V),
        ("DIM_BSDF_LOBE", rng::DIM_BSDF_LOBE),
        ("DIM_BSDF_U", rng::DIM_BSDF_U),
        ("DIM_BSDF_V", rng::DIM_BSDF_V),
        ("DIM_ROULETTE", rng::DIM_ROULETTE),
        ("DIMS_PER_BOUNCE", rng::DIMS_PER_BOUNCE),
        ("STACK_SIZE", meshtrace::bvh::STACK_SIZE as u32),
        ("RR_DEPTH", meshtrace::render::integrator::RR_DEPTH),
        ("TRI_SMOOTH", meshtrace::render::TRI_SMOOTH),
        ("MAT_DIFFUSE", MaterialKind::Diffuse as u32),
        ("MAT_CONDUCTOR", MaterialKind::Conductor as u32),
        ("MAT_ROUGH_CONDUCTOR", MaterialKind::RoughConductor as u32),
        ("MAT_DIELECTRIC", MaterialKind::Dielectric as u32),
        ("NO_HIT", u32::MAX),
    ];
    for (what, module) in modules() {
        for &(name, value) in expected {
            assert_eq!(
                wgsl_u32_const(&module, name),
                value,
                "{what}: WGSL `{name}` differs from Rust"
            );
        }
        // Every DIM_* in the WGSL is one of the above (a new dimension needs a Rust twin).
        for (_, c) in module.constants.iter() {
            let name = c.name.as_deref().unwrap_or("");
            if name.starts_with("DIM") || name.starts_with("MAT_") {
                assert!(
                    expected.iter().any(|&(n, _)| n == name),
                    "{what}: WGSL constant `{name}` has no Rust twin in this test"
                );
            }
        }
        // DIMs fit in one bounce and are distinct.
        let mut dims: Vec<u32> = expected
            .iter()
            .filter(|(n, _)| n.starts_with("DIM_"))
            .map(|&(_, v)| v)
            .collect();
        assert!(dims.iter().all(|&d| d < rng::DIMS_PER_BOUNCE));
        dims.sort();
        dims.dedup();
        assert_eq!(dims.len(), 11, "DIM_* values collide");
        // Floats: T_INF is the largest finite float on both sides; the rounding bounds of
        // the intersection tests are the same bits.
        use meshtrace::geometry::{GAMMA_2, GAMMA_3, SLAB_SLACK, T_INF};
        let floats = [
            ("T_INF", T_INF),
            ("GAMMA_2", GAMMA_2),
            ("GAMMA_3", GAMMA_3),
            ("SLAB_SLACK", SLAB_SLACK),
        ];
        for (name, value) in floats {
            assert_eq!(
                wgsl_f32_const(&module, name).to_bits(),
                value.to_bits(),
                "{what}: WGSL `{name}` differs from Rust"
            );
        }
        let (name, value) = (
            "TABLE_WIDTH_LOG2",
            meshtrace::render::gpu::TABLE_WIDTH.ilog2(),
        );
        assert_eq!(
            wgsl_u32_const(&module, name),
            value,
            "{what}: WGSL `{name}` differs from Rust"
        );
    }
}

fn wgsl_f32_const(module: &naga::Module, name: &str) -> f32 {
    match wgsl_const_literal(module, name) {
        naga::Literal::F32(v) => v,
        l => panic!("WGSL constant `{name}` is not an f32: {l:?}"),
    }
}

/// Whether Rust source `text` defines `name` (a fn, const, struct, ...). For `Type::item`,
/// both the type and the item must be defined there.
fn rust_defines(text: &str, name: &str) -> bool {
    if let Some((ty, item)) = name.split_once("::") {
        return rust_defines(text, ty) && rust_defines(text, item);
    }
    [
        "fn ", "const ", "struct ", "enum ", "static ", "type ", "trait ",
    ]
    .iter()
    .any(|kw| defines_after(text, &format!("{kw}{name}")))
}

/// Whether `needle` occurs followed by a non-identifier character.
fn defines_after(text: &str, needle: &str) -> bool {
    text.match_indices(needle).any(|(i, _)| {
        let before_ok = i == 0 || !is_ident(text[..i].chars().next_back().unwrap());
        let after = text[i + needle.len()..].chars().next();
        before_ok && !after.is_some_and(is_ident)
    })
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The mirror tags of `text`: (line number, paths named, backquoted names) for every line
/// holding `mirror:`.
fn mirror_tags(text: &str, ext: &str) -> Vec<(usize, Vec<String>, Vec<String>)> {
    let mut tags = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let Some((_, tag)) = line.split_once("mirror:") else {
            continue;
        };
        let paths: Vec<String> = tag
            .split(|c: char| c.is_whitespace() || c == ',' || c == '`')
            .filter(|w| w.ends_with(ext) && w.contains('/'))
            .map(str::to_string)
            .collect();
        // Names are the tag's backquoted words.
        let names: Vec<String> = tag
            .split('`')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect();
        tags.push((n + 1, paths, names));
    }
    tags
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn files_in(dir: &str, ext: &str) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![root().join(dir)];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == ext) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Every problem with the WGSL files' `mirror: src/...rs `name`` tags.
fn wgsl_mirror_problems(read_rust: &dyn Fn(&str) -> Option<String>) -> (usize, Vec<String>) {
    let mut problems = Vec::new();
    let mut checked = 0;
    for file in files_in("shaders", "wgsl") {
        let text = std::fs::read_to_string(&file).unwrap();
        let fname = file.file_name().unwrap().to_string_lossy().to_string();
        for (line, paths, names) in mirror_tags(&text, ".rs") {
            if paths.is_empty() {
                problems.push(format!(
                    "shaders/{fname}:{line}: mirror tag names no .rs file"
                ));
            }
            for p in &paths {
                let Some(src) = read_rust(p) else {
                    problems.push(format!("shaders/{fname}:{line}: {p} does not exist"));
                    continue;
                };
                for name in &names {
                    checked += 1;
                    if !rust_defines(&src, name) {
                        problems.push(format!("shaders/{fname}:{line}: {p} defines no `{name}`"));
                    }
                }
            }
        }
    }
    (checked, problems)
}

#[test]
fn wgsl_mirror_tags_name_existing_rust_items() {
    let read = |p: &str| std::fs::read_to_string(root().join(p)).ok();
    let (checked, problems) = wgsl_mirror_problems(&read);
    assert!(checked >= 30, "only {checked} named mirror tags found");
    assert!(
        problems.is_empty(),
        "stale mirror tags:\n{}",
        problems.join("\n")
    );
    // The check can fail: with a Rust side that defines nothing, every named tag is stale.
    let empty = |p: &str| std::fs::exists(root().join(p)).unwrap().then(String::new);
    let (_, problems) = wgsl_mirror_problems(&empty);
    assert_eq!(problems.len(), checked);
}

/// Whether WGSL source `text` defines `name`.
fn wgsl_defines(text: &str, name: &str) -> bool {
    ["fn ", "const ", "struct ", "var ", "override ", "alias "]
        .iter()
        .any(|kw| defines_after(text, &format!("{kw}{name}")))
        || text.contains(&format!("var<storage, read> {name}:"))
        || text.contains(&format!("var<uniform> {name}:"))
}

#[test]
fn rust_mirror_tags_name_existing_wgsl_items() {
    let mut problems = Vec::new();
    let mut checked = 0;
    for file in files_in("src", "rs") {
        let text = std::fs::read_to_string(&file).unwrap();
        let rel = file.strip_prefix(root()).unwrap().display().to_string();
        for (line, paths, names) in mirror_tags(&text, ".wgsl") {
            for p in &paths {
                let Ok(src) = std::fs::read_to_string(root().join(p)) else {
                    problems.push(format!("{rel}:{line}: {p} does not exist"));
                    continue;
                };
                for name in &names {
                    checked += 1;
                    if !wgsl_defines(&src, name) {
                        problems.push(format!("{rel}:{line}: {p} defines no `{name}`"));
                    }
                }
            }
        }
    }
    assert!(checked >= 30, "only {checked} named mirror tags found");
    assert!(
        problems.is_empty(),
        "stale mirror tags:\n{}",
        problems.join("\n")
    );
}

#[test]
fn documented_struct_sizes_match_naga() {
    // Tags such as "mirror: src/bvh/mod.rs `BvhNode` (32 bytes)" state the size of the
    // WGSL struct declared next.
    let module = &modules()[0].1;
    let text = std::fs::read_to_string(root().join("shaders/types.wgsl")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let mut checked = 0;
    for (i, line) in lines.iter().enumerate() {
        let Some(rest) = line.split_once("mirror:").map(|x| x.1) else {
            continue;
        };
        let Some(bytes) = rest
            .split_once('(')
            .and_then(|(_, r)| r.split_once(" bytes)"))
            .and_then(|(n, _)| n.trim().parse::<usize>().ok())
        else {
            continue;
        };
        let name = lines[i..]
            .iter()
            .find_map(|l| l.strip_prefix("struct "))
            .and_then(|l| l.split_whitespace().next())
            .expect("a struct after the tag");
        assert_eq!(
            wgsl_layout(module, name).0,
            bytes,
            "types.wgsl:{}: `{name}` documented as {bytes} bytes",
            i + 1
        );
        checked += 1;
    }
    assert!(checked >= 5, "{checked}");
}
