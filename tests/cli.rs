//! The binary on bad input: every case exits non-zero with one line on stderr that names the
//! file and the line or field at fault, and leaves no output file behind. And on good input,
//! it writes the image and nothing else.

use crate::common;

use common::cli::{assert_fails, output, run};
use common::fs::{TempDir, data};
use std::process::Command;

const CAMERA: &str = "[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n";

#[test]
fn bad_scene_files_fail_cleanly() {
    let dir = TempDir::new("scenes");
    let cases: &[(&str, String, &[&str])] = &[
        (
            "syntax.toml",
            format!("{CAMERA}[render\nspp = 4\n"),
            &["syntax.toml:4:"],
        ),
        (
            "unknown.toml",
            format!("{CAMERA}[render]\nssp = 4\n"),
            &["unknown.toml", "ssp"],
        ),
        (
            "type.toml",
            format!("{CAMERA}[render]\nspp = \"many\"\n"),
            &["type.toml:5:"],
        ),
        (
            "negative.toml",
            format!("{CAMERA}[render]\nspp = -3\n"),
            &["negative.toml:5:"],
        ),
        (
            "zero.toml",
            format!("{CAMERA}[render]\nwidth = 0\n"),
            &["zero.toml", "render.width"],
        ),
        (
            "huge.toml",
            format!("{CAMERA}[render]\nwidth = 100000\nheight = 100000\n"),
            &["huge.toml", "render.width", "too large"],
        ),
        (
            "vfov.toml",
            format!("{CAMERA}vfov = 180\n"),
            &["vfov.toml", "camera.vfov"],
        ),
        (
            "nan.toml",
            "[camera]\nposition = [nan, 0, 3]\nlook_at = [0, 0, 0]\n".into(),
            &["nan.toml", "camera.position"],
        ),
        (
            "ior.toml",
            format!("{CAMERA}[materials.glass]\ntype = \"dielectric\"\nior = 0\n"),
            &["ior.toml", "materials.glass.ior"],
        ),
        (
            "rough.toml",
            format!("{CAMERA}[materials.m]\ntype = \"rough_conductor\"\nroughness = 1.5\n"),
            &["rough.toml", "materials.m.roughness"],
        ),
        (
            "nomesh.toml",
            format!("{CAMERA}[[objects]]\nmesh = \"nowhere.obj\"\n"),
            &["nowhere.obj"],
        ),
    ];
    for (name, text, needles) in cases {
        let scene = dir.write(name, text);
        assert_fails(
            &dir,
            &[
                "render",
                scene.to_str().unwrap(),
                "-o",
                "out.png",
                "--device",
                "cpu",
            ],
            needles,
        );
        std::fs::remove_file(scene).unwrap();
    }
}

#[test]
fn bad_meshes_fail_cleanly() {
    let dir = TempDir::new("meshes");
    for (file, needle) in [
        ("bad_index.obj", "bad_index.obj:4: "),
        ("nan_vertex.obj", "nan_vertex.obj:2: "),
    ] {
        let path = data(file);
        assert_fails(
            &dir,
            &[
                "render",
                path.to_str().unwrap(),
                "-o",
                "out.png",
                "--device",
                "cpu",
            ],
            &[needle],
        );
    }
    let empty = dir.write("empty.obj", "# nothing\n");
    assert_fails(
        &dir,
        &["render", empty.to_str().unwrap(), "-o", "out.png"],
        &["empty.obj", "no faces"],
    );
}

#[test]
fn other_inputs_and_bad_gltf_files_fail_cleanly() {
    let dir = TempDir::new("inputs");
    dir.write("README.md", "# meshtrace\n");
    assert_fails(
        &dir,
        &["render", "README.md", "-o", "out.png", "--device", "cpu"],
        &["README.md", "(.toml)", "(.obj)", "(.gltf, .glb)"],
    );
    dir.write("cut.glb", b"glTF\x02\0\0\0");
    assert_fails(
        &dir,
        &["render", "cut.glb", "-o", "out.png", "--device", "cpu"],
        &["cut.glb: GLB header: "],
    );
    let box_textured = data("gltf/BoxTextured/BoxTextured.glb");
    let (code, stderr) = run(
        &dir,
        &[
            "render",
            box_textured.to_str().unwrap(),
            "-o",
            "box.png",
            "--spp",
            "1",
            "--width",
            "8",
            "--height",
            "8",
            "--device",
            "cpu",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(dir.join("box.png").is_file());
}

#[test]
fn bad_arguments_and_outputs_fail_cleanly() {
    let dir = TempDir::new("args");
    assert_fails(
        &dir,
        &["render", "missing.toml", "-o", "out.png"],
        &["missing.toml"],
    );
    assert_fails(
        &dir,
        &["render", "-o", "out.xyz", "--device", "cpu"],
        &["out.xyz", "unknown image format"],
    );
    assert_fails(
        &dir,
        &["render", "-o", "no/such/dir/out.png", "--device", "cpu"],
        &["no/such/dir/out.png"],
    );
    assert_fails(
        &dir,
        &["render", "-o", "out.png", "--spp", "0", "--device", "cpu"],
        &["--spp"],
    );
    assert_fails(
        &dir,
        &[
            "render",
            "-o",
            "out.png",
            "--threads",
            "0",
            "--device",
            "cpu",
        ],
        &["--threads"],
    );
    assert_fails(
        &dir,
        &["render", "builtin:nope", "-o", "out.png"],
        &["builtin:nope", "cornell"],
    );
    assert_fails(
        &dir,
        &["render", "-o", "out.png", "--max-texture-size", "0"],
        &["--max-texture-size", "at least 1"],
    );
    assert_fails(
        &dir,
        &["render", "-o", "out.png", "--bit-depth", "12"],
        &["--bit-depth", "8 or 16"],
    );
    assert_fails(
        &dir,
        &["render", "-o", "out.exr", "--bit-depth", "16"],
        &["out.exr", "16-bit output is a PNG's"],
    );
    assert_fails(
        &dir,
        &["render", "-o", "out.png", "--geometry-only", "--denoise"],
        &["denoise", "a geometry-only render has no noise to remove"],
    );
}

#[test]
fn warnings_do_not_stop_a_render() {
    let dir = TempDir::new("warn");
    let obj = data("degenerate.obj");
    let (code, stderr) = run(
        &dir,
        &[
            "render",
            obj.to_str().unwrap(),
            "-o",
            "out.png",
            "--spp",
            "1",
            "--width",
            "8",
            "--height",
            "8",
            "--device",
            "cpu",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("warning: dropped 2 degenerate"), "{stderr}");
    assert_eq!(dir.entries(), vec!["out.png".to_string()]);
}

#[test]
fn a_render_writes_exactly_its_output() {
    let dir = TempDir::new("ok");
    let (code, stderr) = run(
        &dir,
        &[
            "render", "-o", "x.exr", "--spp", "2", "--width", "16", "--height", "16", "--device",
            "cpu", "--quiet",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(stderr, "", "--quiet prints nothing");
    assert_eq!(dir.entries(), vec!["x.exr".to_string()]);
    let (code, stderr) = run(
        &dir,
        &[
            "render", "-o", "y.png", "--spp", "1", "--width", "16", "--height", "16", "--device",
            "cpu",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("16x16 at 1 spp on the CPU"), "{stderr}");
    let (code, stdout) = {
        let out = output(&dir, &["info", "builtin:cornell"]);
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
        )
    };
    assert_eq!(code, Some(0));
    assert!(
        stdout.contains("triangles    36") && stdout.contains("sah cost"),
        "{stdout}"
    );
}

/// Ctrl-C writes the samples finished so far (exit 130), or nothing with --no-partial.
#[cfg(unix)]
#[test]
fn interruption_writes_the_partial_image_unless_told_not_to() {
    let dir = TempDir::new("interrupt");
    // Ctrl-C, and SIGTERM as a scheduler sends it on a time-out or an eviction.
    for (signal, flag, output, needle) in [
        ("-INT", None, Some("part.png"), "of 100000 spp"),
        ("-TERM", None, Some("part.exr"), "of 100000 spp"),
        ("-INT", Some("--no-partial"), None, "nothing written"),
        ("-TERM", Some("--no-partial"), None, "nothing written"),
    ] {
        let out_name = output.unwrap_or("part.png");
        let mut args = vec![
            "render", "-o", out_name, "--spp", "100000", "--width", "64", "--height", "64",
            "--device", "cpu",
        ];
        args.extend(flag);
        let child = Command::new(env!("CARGO_BIN_EXE_meshtrace"))
            .args(&args)
            .current_dir(dir.path())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(1500));
        let killed = Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status()
            .unwrap();
        assert!(killed.success());
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(130), "{signal}: {stderr}");
        assert!(
            stderr.contains("interrupted") && stderr.contains(needle),
            "{signal}: {stderr}"
        );
        let expect: Vec<String> = output.into_iter().map(String::from).collect();
        assert_eq!(dir.entries(), expect, "{signal}: {stderr}");
        if out_name.ends_with(".exr") && output.is_some() {
            // The EXR says how many samples it holds: those the message reports.
            let meta = exr::meta::MetaData::read_from_file(dir.join(out_name), false).unwrap();
            let samples =
                match meta.headers[0]
                    .own_attributes
                    .other
                    .get(&exr::meta::attribute::Text::from(
                        meshtrace::film::SAMPLES_ATTRIBUTE,
                    )) {
                    Some(exr::meta::attribute::AttributeValue::I32(n)) => *n,
                    other => panic!("{signal}: samples attribute {other:?}"),
                };
            assert!(
                samples > 0 && stderr.contains(&format!("with {samples} of 100000 spp")),
                "{signal}: {samples} samples; {stderr}"
            );
        }
        let _ = std::fs::remove_file(dir.join(out_name));
    }
}

/// With no `--device`, a software adapter (lavapipe) gives way to the faster CPU renderer,
/// saying so; naming the adapter uses it. Only where every adapter is a software one.
#[test]
fn a_software_adapter_gives_way_to_the_cpu_unless_named() {
    let dir = TempDir::new("software");
    let listing = String::from_utf8_lossy(&output(&dir, &["adapters"]).stdout).into_owned();
    let adapters: Vec<&str> = listing.lines().filter(|l| l.contains("(Vulkan,")).collect();
    if adapters.is_empty() || !adapters.iter().all(|l| l.contains("(Vulkan, Cpu,")) {
        eprintln!("skipped: needs software Vulkan adapters only; found {adapters:?}");
        return;
    }
    let args = [
        "render", "-o", "a.png", "--spp", "1", "--width", "8", "--height", "8",
    ];
    let (code, stderr) = run(&dir, &args);
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("is a software driver"), "{stderr}");
    assert!(stderr.contains("on the CPU"), "{stderr}");
    let (code, stderr) = run(&dir, &[&args[..], &["--adapter", "0"]].concat());
    assert_eq!(code, 0, "{stderr}");
    assert!(!stderr.contains("software driver"), "{stderr}");
    assert!(!stderr.contains("on the CPU"), "{stderr}");
}

/// `bench --json` gives one object per (scene, device, measure) with its unit; the table
/// ends each scene with GPU/CPU ratio rows when both devices ran.
#[test]
fn bench_reports_every_measure() {
    let dir = TempDir::new("bench");
    let small = [
        "bench",
        "builtin:cornell",
        "--repeats",
        "1",
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "1",
    ];
    let out = output(&dir, &[&small[..], &["--device", "cpu", "--json"]].concat());
    let json = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for (device, measure, unit) in [
        ("host", "bvh_build", "Mtris/s"),
        ("host", "sah_cost", "cost"),
        ("host", "primary_hits", "fraction"),
        ("host", "primary_fill_hits", "fraction"),
        ("cpu", "primary_rays", "Mrays/s"),
        ("cpu", "primary_fill_rays", "Mrays/s"),
        ("cpu", "incoherent_rays", "Mrays/s"),
        ("cpu", "shadow_rays", "Mrays/s"),
        ("cpu", "path_samples", "Msamples/s"),
        ("cpu", "path_rays", "Mrays/s"),
    ] {
        let object = format!(
            r#"{{"scene": "cornell", "device": "{device}", "measure": "{measure}", "unit": "{unit}", "median": "#
        );
        assert_eq!(json.matches(&object).count(), 1, "{object} in {json}");
    }
    assert!(json.trim_start().starts_with('[') && json.trim_end().ends_with(']'));
    // --rays-out: the triangles (9 floats each) and every ray set's rays (8 floats each):
    // a camera ray per pixel in both views, a bounce and a shadow ray per primary hit.
    let rays = dir.path().join("rays");
    std::fs::create_dir(&rays).unwrap();
    let out = output(
        &dir,
        &[&small[..], &["--device", "cpu", "--rays-out", "rays"]].concat(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let size = |name: &str| {
        std::fs::metadata(rays.join(name))
            .map(|m| m.len())
            .unwrap_or(0)
    };
    assert_eq!(size("cornell.triangles.f32") % 36, 0);
    assert!(size("cornell.triangles.f32") >= 36 * 30);
    for view in ["primary", "primary_fill"] {
        assert_eq!(
            size(&format!("cornell.{view}.rays.f32")),
            16 * 16 * 32,
            "{view}"
        );
    }
    for set in ["incoherent", "shadow"] {
        let n = size(&format!("cornell.{set}.rays.f32"));
        assert!(
            n > 0 && n % 32 == 0 && n <= 16 * 16 * 32,
            "{set}: {n} bytes"
        );
    }
    assert_fails(
        &dir,
        &[&small[..], &["--rays-out", "nowhere"]].concat(),
        &["--rays-out", "nowhere"],
    );
    if common::gpu("bench_reports_every_measure, GPU part").is_none() {
        return;
    }
    // A software adapter measures only when asked for (`--device all`), as it renders.
    let out = output(&dir, &[&small[..], &["--device", "all"]].concat());
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let ratios: Vec<&str> = table.lines().filter(|l| l.contains(" ratio ")).collect();
    assert_eq!(ratios.len(), 6, "{table}");
    assert!(ratios.iter().all(|l| l.ends_with("GPU/CPU")), "{table}");
}

/// A reader that stops early (`meshtrace info scene | head -1`) ends `info` quietly: exit 0
/// and nothing on stderr, where `println!` would panic on the broken pipe.
#[test]
fn info_into_a_closed_pipe_ends_quietly() {
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_meshtrace"))
        .args(["info", "builtin:cornell"])
        .env("NODEVICE_SELECT", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Closing the read end before the scene has loaded makes every write fail with EPIPE.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.is_empty(), "stderr: {stderr}");
    assert_eq!(out.status.code(), Some(0), "stderr: {stderr}");
}

/// `--up` and `--env`: a bad value or a file that is not there fails cleanly, naming the
/// option; a bare mesh renders with `--up z` and lit by another map with `--env`.
#[test]
fn up_env_and_lighting_options() {
    let dir = TempDir::new("up-env");
    dir.write("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    dir.write("junk.hdr", "not an image");
    let map = common::fs::root().join("assets/env/test_16x8.exr");
    let map = map.to_str().unwrap();
    assert_fails(
        &dir,
        &["render", "t.obj", "--env", "gone.hdr"],
        &["--env", "gone.hdr"],
    );
    assert_fails(
        &dir,
        &["render", "t.obj", "--env", "junk.hdr"],
        &["--env", "junk.hdr"],
    );
    assert_fails(
        &dir,
        &["render", "builtin:cornell", "--up", "z"],
        &["--up", "bare mesh"],
    );
    assert_fails(
        &dir,
        &["render", "t.obj", "--lighting", "sunny"],
        &["--lighting", "`sunny` is not a lighting preset"],
    );
    assert_fails(
        &dir,
        &[
            "render",
            "t.obj",
            "--lighting",
            "{ preset = \"hdri\", environment = \"gone.hdr\" }",
        ],
        &["lighting.environment", "gone.hdr"],
    );
    assert_fails(
        &dir,
        &["render", "t.obj", "--env", map, "--lighting", "studio"],
        &["--lighting", "cannot be combined with `environment`"],
    );
    let hdri = format!("{{ preset = \"hdri\", environment = \"{map}\", rotate = 90 }}");
    for args in [
        &["render", "t.obj", "--up", "z", "-o", "up.png"][..],
        &[
            "render",
            "t.obj",
            "--lighting",
            "{ preset = \"suns\", count = 2 }",
            "-o",
            "suns.png",
        ],
        &[
            "render",
            "builtin:cornell",
            "--lighting",
            "area",
            "-o",
            "area.png",
        ],
        &["render", "t.obj", "--lighting", &hdri, "-o", "hdri.png"],
        &["render", "t.obj", "--env", map, "-o", "env.png"],
        &[
            "render",
            "builtin:cornell",
            "--env",
            map,
            "-o",
            "cornell.png",
        ],
    ] {
        let mut args = args.to_vec();
        args.extend([
            "--spp", "1", "--width", "8", "--height", "6", "--device", "cpu",
        ]);
        let (code, stderr) = run(&dir, &args);
        assert_eq!(code, 0, "{args:?}: {stderr}");
    }
    assert!(dir.path().join("up.png").is_file() && dir.path().join("cornell.png").is_file());
}

/// Without the `denoise` feature, `--denoise` fails at once, says how to build with it, and
/// writes nothing.
#[cfg(not(feature = "denoise"))]
#[test]
fn denoise_without_the_feature_says_how_to_get_it() {
    let dir = TempDir::new("no-denoise");
    for out in ["out.png", "out.exr"] {
        assert_fails(
            &dir,
            &[
                "render",
                "--denoise",
                "--spp",
                "1",
                "--device",
                "cpu",
                "-o",
                out,
            ],
            &[
                "--denoise",
                "pip install pyoidn==2.5.1.0",
                "OIDN_DIR",
                "cargo build --release --features denoise",
            ],
        );
    }
}

/// `--accel hardware` is refused, naming why, by the CPU renderer and (where no adapter
/// offers ray queries, as on the system's lavapipe) by the GPU renderer, writing nothing.
#[test]
fn hardware_ray_queries_are_refused_where_there_are_none() {
    let dir = TempDir::new("accel");
    let render = ["render", "builtin:cornell", "--spp", "1", "-o", "out.png"];
    assert_fails(
        &dir,
        &[&render[..], &["--device", "cpu", "--accel", "hardware"]].concat(),
        &["--accel hardware", "--device cpu"],
    );
    let adapters = output(&dir, &["adapters"]);
    let list = String::from_utf8_lossy(&adapters.stdout);
    if list.contains("; ray queries") || common::gpu("hardware ray queries refused").is_none() {
        eprintln!("an adapter offers ray queries, or there is no GPU: the GPU case is skipped");
        return;
    }
    assert_fails(
        &dir,
        &[&render[..], &["--accel", "hardware"]].concat(),
        &["--accel hardware", "offers no hardware ray queries"],
    );
}

/// bench/quality_per_second.py and bench/device.sh read the render time (device.sh also the
/// ray rate) from `render`'s summary line, each with its own `TIME_RE`: every one of them must
/// match the line, so that a change to it fails here and not on a lent GPU. Skips, saying
/// so, where there is no python3.
#[test]
fn the_benchmark_scripts_parse_the_render_summary() {
    let probe =
        "import re, sys; m = re.search(sys.argv[1], sys.stdin.read()); sys.exit(0 if m else 1)";
    if Command::new("python3").arg("--version").output().is_err() {
        eprintln!("skipped: no python3 to run the scripts' patterns");
        return;
    }
    let dir = TempDir::new("summary");
    let scene = common::fs::root().join("assets/cornell/cornell.toml");
    let (code, stderr) = run(
        &dir,
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            "out.exr",
            "--spp",
            "1",
            "--width",
            "16",
            "--height",
            "16",
            "--device",
            "cpu",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    for script in ["bench/quality_per_second.py", "bench/device.sh"] {
        let text = std::fs::read_to_string(common::fs::root().join(script)).unwrap();
        let patterns: Vec<&str> = text
            .lines()
            .filter_map(|l| l.trim().strip_prefix("TIME_RE = re.compile(r\""))
            .filter_map(|l| l.strip_suffix("\")"))
            .collect();
        assert_eq!(
            patterns.len(),
            1,
            "{script}: one TIME_RE = re.compile(r\"...\")"
        );
        let mut child = Command::new("python3")
            .args(["-c", probe, patterns[0]])
            .stdin(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        use std::io::Write;
        child
            .stdin
            .take()
            .unwrap()
            .write_all(stderr.as_bytes())
            .unwrap();
        assert!(
            child.wait().unwrap().success(),
            "{script}'s TIME_RE {:?} does not match render's output:\n{stderr}",
            patterns[0]
        );
    }
}
