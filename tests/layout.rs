//! The WGSL sources against their Rust twins, without a device: both modules parse and
//! validate with naga; every struct the host uploads has the same size and member offsets
//! as its `#[repr(C)]` Rust twin; the shared constants agree; and every `mirror:` tag
//! names something that exists on the other side.

use meshtrace::render::gpu::shader::{self, ShaderChecks, Value};
use meshtrace::render::gpu::tables;
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

/// Every module the host compiles, one per entry-point file, traversal (the software
/// BVH, then hardware ray queries) and checks; the test module with the software BVH,
/// trusted, first.
fn modules() -> Vec<(String, naga::Module)> {
    let sources: [(&str, shader::Module); 4] = [
        ("test_source", shader::test_source),
        ("render_source", shader::render_source),
        (
            "render_source_without_caustics",
            shader::render_source_without_caustics,
        ),
        ("bench_source", shader::bench_source),
    ];
    let mut out = Vec::new();
    for ray_query in [false, true] {
        for checks in [ShaderChecks::Trusted, ShaderChecks::Checked] {
            for &(name, source) in &sources {
                let name = format!("{name}({ray_query}, {checks:?})");
                let module = parse_and_validate(&name, &source(ray_query, checks));
                out.push((name, module));
            }
        }
    }
    out
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

/// A Rust struct's size and members as the shader generator describes it.
fn rust_layout(name: &str) -> (usize, Vec<Member>) {
    let layout = shader::host_structs()
        .into_iter()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no host-shared struct `{name}`"));
    let members = layout
        .members
        .iter()
        .map(|m| Member {
            name: m.name.to_string(),
            offset: m.offset,
            size: m.size,
        })
        .collect();
    (layout.size, members)
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

/// Every host-shared struct (the tables' elements and the parameter block), as the shader
/// generator describes it from the Rust definition, has the size and member offsets of its
/// WGSL twin in every module. The generated table loaders read each member from the
/// texel and component of its Rust offset, so this also checks them.
#[test]
fn structs_match_their_rust_twins() {
    let names: Vec<&str> = shader::host_structs().iter().map(|s| s.name).collect();
    assert_eq!(
        names,
        [
            "BvhNode",
            "TriVerts",
            "TriShading",
            "Material",
            "TriUvs",
            "TriTangents",
            "TriColors",
            "Texture",
            "Light",
            "CausticTarget",
            "Params"
        ]
    );
    for (what, module) in modules() {
        eprintln!("checking {what}");
        for name in &names {
            assert_same_layout(name, wgsl_layout(&module, name), rust_layout(name));
        }
    }
}

#[test]
fn layout_check_can_fail() {
    // A twin with a member moved must be caught: the check is not vacuous.
    let module = &modules()[0].1;
    let mut rust = rust_layout("BvhNode");
    rust.1[1].offset = 16; // left_or_first
    let r = std::panic::catch_unwind(|| {
        assert_same_layout("BvhNode", wgsl_layout(module, "BvhNode"), rust)
    });
    assert!(r.is_err(), "a wrong offset passed the layout check");
    let r = std::panic::catch_unwind(|| {
        assert_same_layout(
            "TriVerts",
            wgsl_layout(module, "TriVerts"),
            (32, rust_layout("TriVerts").1),
        )
    });
    assert!(r.is_err(), "a wrong size passed the layout check");
}

/// The generated loaders: one per table, in every module, each building its struct from
/// the texels that hold it. `TriShading`'s is spelled out as an example of the scheme.
#[test]
fn table_loaders_are_generated_from_the_rust_layouts() {
    let generated = tables::wgsl_tables();
    assert!(generated.contains(
        "fn load_shading(i: u32) -> TriShading {
    let t0 = table_texel(shading_tex, 3u * i + 0u);
    let t1 = table_texel(shading_tex, 3u * i + 1u);
    let t2 = table_texel(shading_tex, 3u * i + 2u);
    return TriShading(bitcast<vec3<f32>>(t0.xyz), t0.w, bitcast<vec3<f32>>(t1.xyz), bitcast<f32>(t1.w), bitcast<vec3<f32>>(t2.xyz), t2.w);
}"
    ), "{generated}");
    for (what, module) in modules() {
        for (i, t) in tables::TABLES.iter().enumerate() {
            let (_, f) = module
                .functions
                .iter()
                .find(|(_, f)| f.name.as_deref() == Some(t.loader))
                .unwrap_or_else(|| panic!("{what}: no loader `{}`", t.loader));
            assert_eq!(f.arguments.len(), 1, "{what}: {}", t.loader);
            let binding = module
                .global_variables
                .iter()
                .find(|(_, g)| g.name.as_deref() == Some(t.texture))
                .and_then(|(_, g)| g.binding)
                .unwrap_or_else(|| panic!("{what}: no binding for `{}`", t.texture));
            assert_eq!((binding.group, binding.binding), (0, i as u32 + 1));
        }
    }
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

/// The shared constants are generated from one Rust list: each reaches every module with
/// the Rust value's exact bits, and no WGSL file declares one of its own.
#[test]
fn constants_match_rust() {
    let list = shader::shared_constants();
    assert!(list.len() >= 30, "{} constants", list.len());
    for (what, module) in modules() {
        for (name, value) in &list {
            match *value {
                Value::U32(v) => assert_eq!(wgsl_u32_const(&module, name), v, "{what}: {name}"),
                Value::F32(v) => assert_eq!(
                    wgsl_f32_const(&module, name).to_bits(),
                    v.to_bits(),
                    "{what}: {name}"
                ),
            }
        }
    }
    for file in files_in("shaders", "wgsl") {
        let text = std::fs::read_to_string(&file).unwrap();
        for (name, _) in &list {
            assert!(
                !defines_after(&text, &format!("const {name}")),
                "{}: declares `{name}`, which is generated from Rust",
                file.display()
            );
        }
    }
    // The Rust values themselves: the DIM_* fit in one bounce and are distinct, and the
    // kinds are the material codes.
    let mut dims: Vec<u32> = list
        .iter()
        .filter(|(n, _)| n.starts_with("DIM_"))
        .map(|(_, v)| match v {
            Value::U32(v) => *v,
            Value::F32(_) => panic!("a float DIM"),
        })
        .collect();
    assert_eq!(dims.len(), 16);
    assert!(dims.iter().all(|&d| d < rng::DIMS_PER_BOUNCE));
    dims.sort();
    dims.dedup();
    assert_eq!(dims.len(), 16, "DIM_* values collide");
    assert!(list.contains(&(
        "MAT_DIELECTRIC".into(),
        Value::U32(MaterialKind::DIELECTRIC.0)
    )));
    assert!(list.contains(&("T_INF".into(), Value::F32(f32::MAX))));
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
        || text.contains(&format!("var<storage, read_write> {name}:"))
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
    let mut checked = 0;
    for file in files_in("shaders", "wgsl") {
        let text = std::fs::read_to_string(&file).unwrap();
        let fname = file.file_name().unwrap().to_string_lossy().to_string();
        let lines: Vec<&str> = text.lines().collect();
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
                "{fname}:{}: `{name}` documented as {bytes} bytes",
                i + 1
            );
            checked += 1;
        }
    }
    assert!(checked >= 5, "{checked}");
}

/// The twin files ARCHITECTURE.md lists: its table between `<!-- twins -->` and
/// `<!-- /twins -->`, whose second and third columns name a Rust file and its WGSL twin.
fn twins() -> Vec<(String, String)> {
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).unwrap();
    let start = text
        .find("<!-- twins -->")
        .expect("ARCHITECTURE.md lists the twins");
    let end = text.find("<!-- /twins -->").expect("the twin table ends");
    text[start..end]
        .lines()
        .filter_map(|row| {
            let cells: Vec<&str> = row.split('|').map(str::trim).collect();
            let file = |c: &str| c.strip_prefix('`')?.strip_suffix('`').map(String::from);
            match cells.as_slice() {
                ["", _, rust, wgsl, ""] => Some((file(rust)?, file(wgsl)?)),
                _ => None,
            }
        })
        .collect()
}

/// The name declared by the first `fn`, `struct`, `const`, `enum` or `type` line at or
/// after line `i`.
fn declared_after(lines: &[&str], i: usize) -> Option<String> {
    lines[i..].iter().find_map(|l| {
        let l = l.trim_start().trim_start_matches("pub ");
        ["fn ", "struct ", "const ", "enum ", "type "]
            .iter()
            .find_map(|kw| {
                let rest = l.strip_prefix(kw)?;
                let name: String = rest.chars().take_while(|&c| is_ident(c)).collect();
                (!name.is_empty()).then_some(name)
            })
    })
}

/// The type of the `impl` block that line `i` lies in, if any.
fn impl_before(lines: &[&str], i: usize) -> Option<String> {
    lines[..=i].iter().rev().find_map(|l| {
        if l.starts_with('}') {
            return Some(None);
        }
        let rest = l.strip_prefix("impl ")?;
        Some(Some(rest.split_whitespace().next()?.to_string()))
    })?
}

/// Whether a tag naming `tagged` fits the declaration `declared` that follows it: the same
/// name (for `Type::method`, the method's), or `Type::new` for WGSL's snake-case `type`.
fn same_name(tagged: &str, declared: &str) -> bool {
    match tagged.rsplit_once("::") {
        Some((ty, "new")) => declared == "new" || declared == ty || snake_case(ty) == declared,
        Some((_, item)) => item == declared,
        None => tagged == declared,
    }
}

fn snake_case(name: &str) -> String {
    let mut out = String::new();
    for (i, c) in name.chars().enumerate() {
        if c.is_uppercase() && i > 0 {
            out.push('_');
        }
        out.extend(c.to_lowercase());
    }
    out
}

/// Every problem with the twin files: a file missing, stems that differ, a tag in one
/// twin that names a file other than its twin, or a tag whose name is not that of the
/// function, struct or constant it stands on.
fn twin_problems(twins: &[(&str, &str)]) -> (usize, Vec<String>) {
    let mut problems = Vec::new();
    let mut checked = 0;
    for &(rust, wgsl) in twins {
        let stem = |p: &str| {
            Path::new(p)
                .file_stem()
                .unwrap()
                .to_string_lossy()
                .to_string()
        };
        if stem(rust) != stem(wgsl) {
            problems.push(format!("{rust} and {wgsl}: the twins' names differ"));
        }
        for (this, twin, ext) in [(rust, wgsl, ".wgsl"), (wgsl, rust, ".rs")] {
            let Ok(text) = std::fs::read_to_string(root().join(this)) else {
                problems.push(format!("{this} does not exist"));
                continue;
            };
            let lines: Vec<&str> = text.lines().collect();
            for (line, paths, names) in mirror_tags(&text, ext) {
                for p in paths.iter().filter(|p| *p != twin) {
                    problems.push(format!("{this}:{line}: names {p}, not its twin {twin}"));
                }
                // A tag on a declaration (a file's heading tag stands on none).
                if let [name] = names.as_slice()
                    && let Some(declared) = declared_after(&lines, line - 1)
                {
                    checked += 1;
                    // A Rust constructor is `Type::new` where WGSL has `type`.
                    let declared = match impl_before(&lines, line - 1) {
                        Some(ty) if declared == "new" => format!("{ty}::new"),
                        _ => declared,
                    };
                    if !same_name(name, &declared) && !same_name(&declared, name) {
                        problems.push(format!(
                            "{this}:{line}: tag `{name}` stands on `{declared}`"
                        ));
                    }
                }
            }
        }
    }
    (checked, problems)
}

#[test]
fn twin_files_hold_the_same_functions_under_the_same_names() {
    let twins = twins();
    assert!(
        twins.len() >= 15,
        "ARCHITECTURE.md lists {} twin pairs",
        twins.len()
    );
    let pairs: Vec<(&str, &str)> = twins
        .iter()
        .map(|(r, w)| (r.as_str(), w.as_str()))
        .collect();
    let (checked, problems) = twin_problems(&pairs);
    assert!(checked >= 60, "only {checked} tagged declarations");
    assert!(problems.is_empty(), "twin files:\n{}", problems.join("\n"));
    // The check can fail: pairing files with the wrong twins is caught.
    let crossed = [("src/render/lights.rs", "shaders/camera.wgsl")];
    assert!(!twin_problems(&crossed).1.is_empty());
    assert!(same_name("ShearedRay::new", "sheared_ray"));
    assert!(!same_name("Sky::radiance", "sky_radiance"));
}
