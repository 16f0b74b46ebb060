//! `meshtrace batch`: a manifest of meshes × turntable views split into shards that run at
//! once, one transforms.json per folder with every view's pose, resuming without
//! re-rendering, flat memory over 3,000 jobs, and one-line errors for bad manifests.

use crate::common;

use common::cli::{assert_fails, run};
use common::fs::{TempDir, data};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Copies three small meshes of the fixtures into `dir/models`.
fn models(dir: &TempDir) {
    let models = dir.path().join("models");
    std::fs::create_dir_all(&models).unwrap();
    for name in ["box.obj", "polys.obj", "normals.obj"] {
        std::fs::copy(data(name), models.join(name)).unwrap();
    }
}

const MANIFEST: &str = r#"
[render]
spp = 2
width = 24
height = 16
aov = ["depth"]

[[jobs]]
meshes = "models/*.obj"
views = 4
elevation = 20
output = "out/{stem}_{view}.png"
"#;

/// A camera-to-world matrix, by rows.
type Pose = [[f64; 4]; 4];

/// The frames of a transforms.json: (file_path, camera-to-world rows).
fn frames(path: &Path) -> (serde_json::Value, Vec<(String, Pose)>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    let list = doc["frames"]
        .as_array()
        .expect("a frames array")
        .iter()
        .map(|f| {
            let m: Pose = serde_json::from_value(f["transform_matrix"].clone()).unwrap();
            (f["file_path"].as_str().unwrap().to_string(), m)
        })
        .collect();
    (doc, list)
}

/// The modification times of the images in `dir/out`.
fn mtimes(dir: &TempDir) -> Vec<(String, std::time::SystemTime)> {
    let mut out: Vec<_> = std::fs::read_dir(dir.path().join("out"))
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".png"))
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                e.metadata().unwrap().modified().unwrap(),
            )
        })
        .collect();
    out.sort();
    out
}

#[test]
fn two_shards_render_every_view_once_and_resume_without_rendering() {
    let dir = TempDir::new("batch-shards");
    models(&dir);
    std::fs::write(dir.path().join("m.toml"), MANIFEST).unwrap();
    // The two shards run at the same time, as a job array's tasks do.
    let shard = |k: u32| {
        Command::new(env!("CARGO_BIN_EXE_meshtrace"))
            .args([
                "batch",
                "m.toml",
                "--device",
                "cpu",
                "--shard",
                &format!("{k}/2"),
            ])
            .current_dir(dir.path())
            .env("NODEVICE_SELECT", "1")
            .output()
            .unwrap()
    };
    let (a, b) = std::thread::scope(|s| {
        let a = s.spawn(|| shard(0));
        let b = s.spawn(|| shard(1));
        (a.join().unwrap(), b.join().unwrap())
    });
    for (k, out) in [a, b].iter().enumerate() {
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "shard {k}: {err}");
        assert!(
            err.contains(&format!(
                "shard {k}/2: images: 6 rendered, 0 already complete, 0 failed"
            )),
            "{err}"
        );
        assert!(err.contains("images/hour"), "{err}");
        // Fewer images than the summary's warm-up: its peak memory alone, no growth.
        assert!(
            err.contains("; peak memory ") && !err.contains("at the end"),
            "{err}"
        );
    }
    let images = mtimes(&dir);
    assert_eq!(images.len(), 12, "{images:?}");
    for stem in ["box", "polys", "normals"] {
        for v in 0..4 {
            let name = format!("{stem}_{v}");
            assert!(
                images.iter().any(|(n, _)| *n == format!("{name}.png")),
                "{name}"
            );
            assert!(
                dir.path().join(format!("out/{name}.aovs.exr")).exists(),
                "{name}"
            );
        }
    }
    // One transforms.json with the 12 frames, 12 distinct poses, each looking at its mesh
    // from 20 degrees above the horizontal.
    let (doc, list) = frames(&dir.path().join("out/transforms.json"));
    assert_eq!(list.len(), 12);
    let angle = doc["camera_angle_x"].as_f64().unwrap();
    let expect = 2.0 * ((20f64.to_radians()).tan() * 24.0 / 16.0).atan();
    assert!(
        (angle - expect).abs() < 1e-5,
        "camera_angle_x {angle}, expected {expect}"
    );
    let mut poses: Vec<String> = list.iter().map(|(_, m)| format!("{m:?}")).collect();
    poses.sort();
    poses.dedup();
    assert_eq!(poses.len(), 12);
    for (name, m) in &list {
        // The camera looks down its -z axis (the third column is backwards).
        let back = [m[0][2], m[1][2], m[2][2]];
        let elevation = back[1].asin().to_degrees();
        assert!(
            (elevation - 20.0).abs() < 1e-3,
            "{name}: elevation {elevation}"
        );
        assert_eq!(m[3], [0.0, 0.0, 0.0, 1.0]);
    }
    // The views of one mesh go around: view k is 90 degrees of azimuth after view 0.
    let azimuth = |name: &str| {
        let m = list.iter().find(|(n, _)| n == name).unwrap().1;
        m[0][2].atan2(m[2][2]).to_degrees()
    };
    let turn = (azimuth("box_1.png") - azimuth("box_0.png")).rem_euclid(360.0);
    assert!((turn - 90.0).abs() < 1e-3, "turn {turn}");
    // Resuming renders nothing and leaves every image as it was.
    let (code, err) = run(
        &dir,
        &["batch", "m.toml", "--device", "cpu", "--shard", "1/2"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("0 rendered, 6 already complete"), "{err}");
    assert_eq!(mtimes(&dir), images);
    // A half-written output (a temporary file) and a missing frame are not complete.
    std::fs::remove_file(dir.path().join("out/polys_2.png")).unwrap();
    std::fs::write(dir.path().join("out/.polys_2.png.123.tmp"), b"half").unwrap();
    let (code, err) = run(&dir, &["batch", "m.toml", "-q", "--device", "cpu"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("1 rendered, 11 already complete"), "{err}");
    assert_eq!(frames(&dir.path().join("out/transforms.json")).1.len(), 12);
}

/// A distinct mesh for asset `i`: a grid of n × n quads (n from 4 to 32), its heights a
/// wave whose phase and frequency depend on `i`.
fn generated_obj(i: usize) -> String {
    let n = 4 + i % 29;
    let (phase, k) = (i as f32 * 0.37, 1.0 + (i % 7) as f32);
    let mut obj = String::new();
    for y in 0..=n {
        for x in 0..=n {
            let (u, v) = (x as f32 / n as f32, y as f32 / n as f32);
            let h = 0.2 * (k * u * 6.3 + phase).sin() * (v * 3.1).cos();
            obj += &format!("v {u} {h} {v}\n");
        }
    }
    for y in 0..n {
        for x in 0..n {
            let a = y * (n + 1) + x + 1;
            obj += &format!("f {a} {} {} {}\n", a + n + 1, a + n + 2, a + 1);
        }
    }
    obj
}

/// Peak memory over a batch of distinct generated assets (3,000 here; set
/// MESHTRACE_MEMORY_ASSETS for more, 10,000 for the figure in BENCHMARKS.md), each into
/// its own folder, grows less than 5% after the summary's first peak (a tenth of the
/// images, at least 1,000). (The loader and encoder threads warm their allocator arenas
/// over the first several hundred inputs: from the 300th image of 3,000 the peak grew
/// 4-10% in runs without a leak, from the 1,000th 0.4-1.8%.)
#[test]
fn memory_stays_flat_over_distinct_assets() {
    let count: usize = std::env::var("MESHTRACE_MEMORY_ASSETS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3000);
    let dir = TempDir::new("batch-memory");
    let models = dir.path().join("models");
    std::fs::create_dir_all(&models).unwrap();
    for i in 0..count {
        std::fs::write(models.join(format!("m{i:05}.obj")), generated_obj(i)).unwrap();
    }
    // A folder per asset, as the dataset scripts lay theirs out. (Into one folder, the
    // folder's transforms.json, rewritten whole, grows with the images: BENCHMARKS.md.)
    let manifest = "[render]\nspp = 1\nwidth = 8\nheight = 8\n\n[[jobs]]\nmeshes = \"models/*.obj\"\noutput = \"out/{stem}/view.png\"\n";
    std::fs::write(dir.path().join("m.toml"), manifest).unwrap();
    let (code, err) = run(&dir, &["batch", "m.toml", "-q", "--device", "cpu"]);
    assert_eq!(code, 0, "{err}");
    eprintln!("{err}");
    assert!(err.contains(&format!("{count} rendered")), "{err}");
    let growth: f64 = err
        .rsplit_once('(')
        .and_then(|(_, g)| g.split_once('%'))
        .and_then(|(g, _)| g.parse().ok())
        .unwrap_or_else(|| panic!("no memory growth in: {err}"));
    assert!(
        growth < 5.0,
        "peak memory grew {growth}% over {count} distinct assets: {err}"
    );
    for i in [0, count / 2, count - 1] {
        let folder = dir.path().join(format!("out/m{i:05}"));
        assert_eq!(frames(&folder.join("transforms.json")).1.len(), 1);
    }
}

#[test]
fn bad_manifests_fail_cleanly() {
    let dir = TempDir::new("batch-bad");
    models(&dir);
    let cases: &[(&str, &[&str])] = &[
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\n",
            &["bad.toml", "jobs[0].output", "missing"],
        ),
        (
            "[render]\nspp = 0\n[[jobs]]\nmeshes = \"m/*.obj\"\noutput = \"a.png\"\n",
            &["render.spp", "at least 1"],
        ),
        ("[render]\nspp = 1\ncolour = 3\n", &["bad.toml:3", "colour"]),
        (
            "[[jobs]]\nmeshes = \"nothing/*.obj\"\noutput = \"a.png\"\n",
            &["jobs[0].meshes", "matches no file"],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\nviews = 3\noutput = \"{stem}.png\"\n",
            &["jobs[0].output", "no {view}"],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\noutput = \"{nom}.png\"\n",
            &["jobs[0].output", "unknown placeholder {nom}"],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\noutput = \"same.png\"\n",
            &["jobs[0].output", "same.png would be written by"],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"wonder3d-persp\"\n",
            &[
                "jobs[0].preset",
                "`wonder3d-persp` is not a preset; there are \"objaverse\", \"objaverse-xl\", \"syncdreamer\", \"trellis\", \"wonder3d\", \"zero123\"",
            ],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"zero123\"\noutput = \"v/{uid}/{name}.png\"\n",
            &[
                "jobs[0].output",
                "{name} is a named view of a preset that names them",
            ],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"zero123\"\nrandom_pose = false\n",
            &[
                "jobs[0].random_pose",
                "is not a camera parameter of `zero123`",
            ],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"wonder3d\"\nsave_normal = true\n",
            &[
                "jobs[0].save_normal",
                "is TRELLIS's `--save_normal`, which the `wonder3d` script does not take",
            ],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\nsave_normal = true\noutput = \"{view}.png\"\n",
            &["jobs[0].save_normal", "add preset = \"trellis\""],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"zero123\"\nsave_mist = true\n",
            &[
                "jobs[0].save_mist",
                "is TRELLIS's `--save_mist`, which the `zero123` script does not take",
            ],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\nsave_depth = false\noutput = \"{view}.png\"\n",
            &["jobs[0].save_depth", "add preset = \"trellis\""],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"wonder3d\"\northo_scale = 0\n",
            &["jobs[0].ortho_scale", "0: must be positive"],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\nrandom_pose = true\noutput = \"{view}.png\"\n",
            &["jobs[0].random_pose", "applies to a preset's cameras"],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"zero123\"\ndistance = 2.0\n",
            &[
                "jobs[0].distance",
                "is not a camera parameter of `zero123`, whose are radius = [min, max]",
            ],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"zero123\"\nradius = [2.0, 1.0]\n",
            &["jobs[0].radius", "[2, 1]: must be 0 < min <= max"],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"objaverse\"\nradius = [1.0, 2.0]\n",
            &[
                "jobs[0].radius",
                "is not a camera parameter of `objaverse`, whose are elevation and distance",
            ],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\ndistance = 2.0\noutput = \"{stem}.png\"\n",
            &["jobs[0].distance", "applies to a preset's cameras"],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"objaverse\"\nfov = 200\n",
            &["jobs[0].fov", "below 180 degrees"],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"objaverse\"\noutput = \"v/{uid}/{view:03}.exr\"\n",
            &["jobs[0].output", ".png"],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\noutput = \"{stem}.tga\"\n",
            &["jobs[0].output", "unknown image format"],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\nelevation = 90\noutput = \"{stem}.png\"\n",
            &["jobs[0].elevation", "between -90 and 90"],
        ),
        (
            "[render]\naov = [\"colour\"]\n[[jobs]]\nscene = \"x.toml\"\noutput = \"a.png\"\n",
            &["bad.toml:2", "unknown AOV `colour`"],
        ),
        (
            "[render]\nbranches = 99\ncaustics = false\n[[jobs]]\nscene = \"x.toml\"\noutput = \"a.png\"\n",
            &["render.branches", "from 1 to 64"],
        ),
        (
            "[render]\nbit_depth = 16\n[[jobs]]\nmeshes = \"models/*.obj\"\noutput = \"{stem}.exr\"\n",
            &["jobs[0].output", "16-bit PNGs"],
        ),
        (
            "[render]\nbit_depth = 10\n[[jobs]]\nmeshes = \"models/*.obj\"\noutput = \"{stem}.png\"\n",
            &["render.bit_depth", "8 or 16"],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"objaverse\"\ncamera_type = \"random\"\n",
            &[
                "jobs[0].camera_type",
                "SyncDreamer's `--camera_type`, which the `objaverse` script does not take",
            ],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"syncdreamer\"\ncamera_type = \"even\"\n",
            &["jobs[0].camera_type", "`even`: use \"fixed\" or \"random\""],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"syncdreamer\"\nelevation_range = [0, 10]\n",
            &[
                "jobs[0].elevation_range",
                "is not a camera parameter of `syncdreamer`, whose are elevation and distance",
            ],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"syncdreamer\"\ncamera_type = \"random\"\nelevation = 20\n",
            &[
                "jobs[0].elevation",
                "whose are elevation_range = [min, max] and distance",
            ],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\npreset = \"syncdreamer\"\ncamera_type = \"random\"\nelevation_range = [40, -10]\n",
            &[
                "jobs[0].elevation_range",
                "[40, -10]: must be -90 < min <= max < 90 degrees",
            ],
        ),
        (
            "[[jobs]]\nmeshes = \"models/*.obj\"\ncamera_type = \"random\"\noutput = \"{stem}.png\"\n",
            &["jobs[0].camera_type", "applies to a preset's cameras"],
        ),
        (
            "[render]\nview_transform = \"agx\"\n[[jobs]]\nmeshes = \"models/*.obj\"\noutput = \"{stem}.exr\"\n",
            &[
                "jobs[0].output",
                "render.view_transform forms 8- and 16-bit images",
            ],
        ),
        (
            "[render]\nview_transform = \"aces\"\n[[jobs]]\nmeshes = \"models/*.obj\"\noutput = \"{stem}.png\"\n",
            &["bad.toml:2", "`aces` is not one of standard, filmic, agx"],
        ),
        (
            "[render]\npart = 1\n[[jobs]]\nscene = \"x.toml\"\noutput = \"a.png\"\n",
            &["bad.toml:2", "unknown field `part`"],
        ),
        ("[render]\nspp = 1\n", &["jobs", "no [[jobs]]"]),
    ];
    for (text, needles) in cases {
        std::fs::write(dir.path().join("bad.toml"), text).unwrap();
        assert_fails(&dir, &["batch", "bad.toml", "--device", "cpu"], needles);
        std::fs::remove_file(dir.path().join("bad.toml")).unwrap();
    }
    std::fs::write(dir.path().join("m.toml"), MANIFEST).unwrap();
    assert_fails(
        &dir,
        &["batch", "m.toml", "--shard", "2/2"],
        &["--shard 2/2", "below N"],
    );
    assert_fails(
        &dir,
        &["batch", "m.toml", "--shard", "auto"],
        &["not in a Slurm job array"],
    );
}

/// `--shard auto` reads a Slurm array's index and count, or Kubernetes' completion index.
#[test]
fn shard_auto_reads_the_job_array() {
    let dir = TempDir::new("batch-auto");
    models(&dir);
    std::fs::write(
        dir.path().join("m.toml"),
        MANIFEST
            .replace("views = 4", "views = 1")
            .replace("_{view}", ""),
    )
    .unwrap();
    let go = |args: &[&str], env: &[(&str, &str)]| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_meshtrace"));
        c.args(args)
            .current_dir(dir.path())
            .env("NODEVICE_SELECT", "1");
        for v in [
            "SLURM_ARRAY_TASK_ID",
            "SLURM_ARRAY_TASK_COUNT",
            "SLURM_ARRAY_TASK_MIN",
            "SLURM_ARRAY_TASK_MAX",
            "JOB_COMPLETION_INDEX",
        ] {
            c.env_remove(v);
        }
        c.envs(env.iter().copied());
        let out = c.output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let base = ["batch", "m.toml", "-q", "--device", "cpu", "--shard"];
    let said = go(
        &[&base[..], &["auto"]].concat(),
        &[
            ("SLURM_ARRAY_TASK_ID", "4"),
            ("SLURM_ARRAY_TASK_MIN", "3"),
            ("SLURM_ARRAY_TASK_MAX", "5"),
        ],
    );
    assert!(said.contains("shard 1/3: images: 1 rendered"), "{said}");
    let said = go(
        &[&base[..], &["auto"]].concat(),
        &[
            ("SLURM_ARRAY_TASK_ID", "2"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ],
    );
    assert!(said.contains("shard 2/3: images: 1 rendered"), "{said}");
    let said = go(
        &[&base[..], &["auto/3"]].concat(),
        &[("JOB_COMPLETION_INDEX", "0")],
    );
    assert!(said.contains("shard 0/3: images: 1 rendered"), "{said}");
    assert_eq!(frames(&dir.path().join("out/transforms.json")).1.len(), 3);
}

/// A scene job's views go around the point its camera looks at, at the camera's distance,
/// view 0 from the camera itself.
#[test]
fn scene_views_orbit_the_point_the_camera_looks_at() {
    let dir = TempDir::new("batch-scene");
    let manifest = "[render]\nspp = 1\nwidth = 16\nheight = 16\n\n[[jobs]]\nscene = \"builtin:cornell\"\nviews = 3\noutput = \"out/{stem}_{view}.png\"\n";
    std::fs::write(dir.path().join("m.toml"), manifest).unwrap();
    let (code, err) = run(&dir, &["batch", "m.toml", "-q", "--device", "cpu"]);
    assert_eq!(code, 0, "{err}");
    let (_, list) = frames(&dir.path().join("out/transforms.json"));
    let names: Vec<&str> = list.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["cornell_0.png", "cornell_1.png", "cornell_2.png"]);
    let cam = meshtrace::scene::builtin::load_builtin("cornell")
        .unwrap()
        .camera;
    let target = cam.position + cam.forward * cam.focus_distance;
    for (name, m) in &list {
        let p = glam::Vec3::new(m[0][3] as f32, m[1][3] as f32, m[2][3] as f32);
        let d = (p - target).length();
        assert!(
            (d - cam.focus_distance).abs() < 1e-4 * d,
            "{name}: distance {d}"
        );
        // It looks at the target: -z (the third column, negated) points there.
        let look = -glam::Vec3::new(m[0][2] as f32, m[1][2] as f32, m[2][2] as f32);
        assert!(look.dot((target - p).normalize()) > 0.9999, "{name}");
    }
    let p0 = glam::Vec3::new(
        list[0].1[0][3] as f32,
        list[0].1[1][3] as f32,
        list[0].1[2][3] as f32,
    );
    assert!(
        (p0 - cam.position).length() < 1e-4 * cam.focus_distance,
        "view 0 at {p0}, camera at {}",
        cam.position
    );
}

/// An input whose camera is orthographic (here a glTF file's) is refused on its own
/// `error:` line, since transforms.json describes pinhole cameras; the other inputs render,
/// and the summary counts the failure.
#[test]
fn an_orthographic_input_is_reported_and_the_rest_render() {
    let dir = TempDir::new("batch-ortho");
    models(&dir);
    let mut g = common::gltf::Asset::new();
    g.triangle(serde_json::json!({}));
    let camera = g.push(
        "cameras",
        serde_json::json!({"type": "orthographic", "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}}),
    );
    let node = g.node(serde_json::json!({"camera": camera, "translation": [0.0, 0.0, 3.0]}));
    g.scene(&[0, node]);
    std::fs::write(dir.path().join("models/flat.gltf"), g.embedded()).unwrap();
    let manifest = MANIFEST.replace("models/*.obj", "models/*.*");
    std::fs::write(dir.path().join("m.toml"), manifest).unwrap();
    let (code, stderr) = run(&dir, &["batch", "m.toml", "--device", "cpu"]);
    assert_eq!(code, 1, "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 2, "{stderr}");
    assert!(
        errors[0].contains("flat.gltf: its camera is orthographic"),
        "{stderr}"
    );
    assert!(
        errors[1].contains("4 of 16 images failed, from 1 input (each said above, and logged in"),
        "{stderr}"
    );
    assert!(
        stderr.contains("images: 12 rendered, 0 already complete, 4 failed in"),
        "{stderr}"
    );
    // The failure log: one JSON line naming the input and the reason.
    let log = dir.path().join("m.failures.jsonl");
    let lines = |n: usize| -> Vec<serde_json::Value> {
        let text = std::fs::read_to_string(&log).expect("the failure log");
        let v: Vec<serde_json::Value> = text
            .lines()
            .map(|l| serde_json::from_str(l).expect("a JSON line"))
            .collect();
        assert_eq!(v.len(), n, "{text}");
        v
    };
    let first = lines(1);
    assert!(first[0]["input"].as_str().unwrap().ends_with("flat.gltf"));
    assert!(
        first[0]["reason"]
            .as_str()
            .unwrap()
            .contains("orthographic")
    );
    assert_eq!(first[0]["job"], 0);
    // A rerun skips the logged input and succeeds; --retry-failed tries it again.
    let (code, stderr) = run(&dir, &["batch", "m.toml", "--device", "cpu"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("images: 0 rendered, 12 already complete, 0 failed, 4 skipped as their inputs failed before (--retry-failed renders them)"),
        "{stderr}"
    );
    let (code, stderr) = run(
        &dir,
        &["batch", "m.toml", "--device", "cpu", "--retry-failed"],
    );
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("4 of 16 images failed"), "{stderr}");
    lines(2);
    // No file but images and transforms.json in the output folders.
    for entry in walk(dir.path()) {
        let name = entry.file_name().unwrap().to_string_lossy().into_owned();
        assert!(
            !name.ends_with(".lock") && !name.ends_with(".tmp"),
            "stray file {}",
            entry.display()
        );
    }
}

/// Every file under `dir`.
fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

/// An input over the time limit fails on its own line and in the failure log, and the
/// batch goes on: with the manifest's `time_limit` too short to load anything, every input
/// fails; with `--time-limit` over it and renders too long for it, each input fails at its
/// first view.
#[test]
fn inputs_over_the_time_limit_fail_and_the_batch_goes_on() {
    let dir = TempDir::new("batch-time-limit");
    models(&dir);
    let manifest = format!("time_limit = 0.000001\n{MANIFEST}");
    std::fs::write(dir.path().join("m.toml"), manifest).unwrap();
    let (code, stderr) = run(&dir, &["batch", "m.toml", "--device", "cpu"]);
    assert_eq!(code, 1, "{stderr}");
    let over: Vec<&str> = stderr
        .lines()
        .filter(|l| {
            l.contains("took longer than the time limit of 0.000001 s") && l.contains("to load)")
        })
        .collect();
    assert_eq!(over.len(), 3, "{stderr}");
    assert!(
        stderr.contains("12 of 12 images failed, from 3 inputs"),
        "{stderr}"
    );
    let log = std::fs::read_to_string(dir.path().join("m.failures.jsonl")).unwrap();
    assert_eq!(log.lines().count(), 3, "{log}");

    // Renders of many samples, cut at the next pass once half a second has gone.
    let slow = MANIFEST
        .replace("spp = 2", "spp = 100000")
        .replace("width = 24", "width = 64");
    std::fs::write(dir.path().join("slow.toml"), slow).unwrap();
    let start = std::time::Instant::now();
    let (code, stderr) = run(
        &dir,
        &[
            "batch",
            "slow.toml",
            "--device",
            "cpu",
            "--time-limit",
            "0.5",
        ],
    );
    let seconds = start.elapsed().as_secs_f64();
    assert_eq!(code, 1, "{stderr}");
    let cut = stderr
        .lines()
        .filter(|l| {
            l.contains("took longer than the time limit of 0.5 s") && l.contains("by view 0)")
        })
        .count();
    assert_eq!(cut, 3, "{stderr}");
    assert!(seconds < 30.0, "the batch took {seconds} s");
    // Bad limits are refused.
    let (code, stderr) = run(
        &dir,
        &["batch", "slow.toml", "--device", "cpu", "--time-limit=-1"],
    );
    assert_eq!(code, 1);
    assert!(
        stderr.contains("--time-limit: must be a positive number of seconds, got -1"),
        "{stderr}"
    );
    std::fs::write(
        dir.path().join("bad.toml"),
        format!("time_limit = 0\n{MANIFEST}"),
    )
    .unwrap();
    let (code, stderr) = run(&dir, &["batch", "bad.toml", "--device", "cpu"]);
    assert_eq!(code, 1);
    assert!(
        stderr.contains("bad.toml: time_limit: must be a positive number of seconds, got 0"),
        "{stderr}"
    );
}

/// The normalised vertices of `file` as the dataset scripts see it: read with +Y up, as
/// Blender's importers read glTF and OBJ, turned into Blender's Z-up frame, scaled to a
/// largest extent of 1 and centred on the origin.
fn normalised_vertices(file: &Path) -> Vec<glam::DVec3> {
    normalised(file).0
}

/// [`normalised_vertices`], with the normalisation's scale and the original box's centre
/// (Blender's frame).
fn normalised(file: &Path) -> (Vec<glam::DVec3>, f64, glam::DVec3) {
    normalised_to(file, glam::DVec3::max_element)
}

/// [`normalised`], the box's `size` (its largest extent, or Wonder3D's diagonal) scaled to 1.
fn normalised_to(
    file: &Path,
    size: fn(glam::DVec3) -> f64,
) -> (Vec<glam::DVec3>, f64, glam::DVec3) {
    let scene = meshtrace::scene::load::load_scene_with(
        file,
        &meshtrace::scene::source::Fs,
        &meshtrace::scene::studio::BareOptions {
            up: Some(meshtrace::scene::studio::Up::Y),
            unlit: true,
        },
    )
    .unwrap();
    let points: Vec<glam::DVec3> = scene
        .mesh
        .positions
        .iter()
        .map(|p| glam::DVec3::new(p.x as f64, -(p.z as f64), p.y as f64))
        .collect();
    let (lo, hi) = points.iter().fold(
        (glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let (scale, centre) = (1.0 / size(hi - lo), (lo + hi) / 2.0);
    let out = points.iter().map(|p| (*p - centre) * scale).collect();
    (out, scale, centre)
}

/// How a camera projects: a pinhole with its focal length in pixels, or orthographic with
/// the width it sees (Blender's `ortho_scale`).
#[derive(Clone, Copy)]
enum Lens {
    Pinhole(f64),
    Orthographic(f64),
}

/// The fraction of `points` that the world→camera pose `rt` (Blender's camera convention:
/// rows right, up, back) and `lens` put on the alpha of `image` (square, `size` wide),
/// dilated by one pixel, among those it puts inside the image, and the fraction it puts
/// inside.
fn on_mask(
    points: &[glam::DVec3],
    rt: &[[f64; 4]; 3],
    lens: Lens,
    image: &image::RgbaImage,
) -> (f64, f64) {
    let size = image.width() as i64;
    let row = |r: &[f64; 4]| glam::DVec3::new(r[0], r[1], r[2]);
    let (mut seen, mut on) = (0, 0);
    for p in points {
        let [x, y, z] = [0, 1, 2].map(|k| row(&rt[k]).dot(*p) + rt[k][3]);
        let (x, y) = match lens {
            Lens::Pinhole(fx) => (fx * x / -z, fx * y / -z),
            Lens::Orthographic(width) => (size as f64 * x / width, size as f64 * y / width),
        };
        let u = size as f64 / 2.0 + x;
        let v = size as f64 / 2.0 - y;
        if !(z < 0.0 && (0.0..size as f64).contains(&u) && (0.0..size as f64).contains(&v)) {
            continue;
        }
        seen += 1;
        let (i, j) = (u.floor() as i64, v.floor() as i64);
        on += usize::from((-1..=1).any(|di| {
            (-1..=1).any(|dj| {
                let (a, b) = (i + di, j + dj);
                (0..size).contains(&a)
                    && (0..size).contains(&b)
                    && image.get_pixel(a as u32, b as u32)[3] > 0
            })
        }));
    }
    (
        on as f64 / seen.max(1) as f64,
        seen as f64 / points.len() as f64,
    )
}

/// A `.npy` file of a 3 × 4 float32 matrix, as `np.load` reads it: the header checked.
fn read_npy(path: &Path) -> [[f64; 4]; 3] {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00", "{}", path.display());
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + len]).unwrap();
    assert!(
        header.contains("'descr': '<f4'")
            && header.contains("'fortran_order': False")
            && header.contains("'shape': (3, 4)")
            && (10 + len).is_multiple_of(64)
            && header.ends_with('\n'),
        "{header}"
    );
    let data = &bytes[10 + len..];
    assert_eq!(data.len(), 48);
    let mut out = [[0.0; 4]; 3];
    for (k, c) in data.chunks(4).enumerate() {
        out[k / 4][k % 4] = f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64;
    }
    out
}

/// Renders `crowd.glb` and an off-centre box (named `box.v1.obj`: its uid stops at the
/// first dot) with preset `preset` at `size`², `views` views, 2 samples, from `dir/models`,
/// which it returns.
fn render_preset(dir: &TempDir, preset: &str, size: u32, views: u32) -> PathBuf {
    render_preset_with(dir, preset, size, views, "")
}

/// [`render_preset`] with the job's `extra` keys (TOML lines).
fn render_preset_with(dir: &TempDir, preset: &str, size: u32, views: u32, extra: &str) -> PathBuf {
    let models = dir.path().join("models");
    std::fs::create_dir_all(&models).unwrap();
    std::fs::copy(data("gltf/corpus/crowd.glb"), models.join("crowd.glb")).unwrap();
    std::fs::copy(data("box.obj"), models.join("box.v1.obj")).unwrap();
    let manifest = format!(
        "[render]\nspp = 2\nwidth = {size}\nheight = {size}\n\n[[jobs]]\nmeshes = \"models/*\"\npreset = \"{preset}\"\nviews = {views}\n{extra}"
    );
    std::fs::write(dir.path().join("m.toml"), manifest).unwrap();
    let (code, stderr) = run(dir, &["batch", "m.toml", "--device", "cpu"]);
    assert_eq!(code, 0, "{stderr}");
    models
}

/// [`render_preset`], returning the folder of each object's views (`views/{uid}`), with the
/// file it came from.
fn preset_views(dir: &TempDir, preset: &str, size: u32, views: u32) -> Vec<(PathBuf, PathBuf)> {
    let models = render_preset(dir, preset, size, views);
    [("crowd.glb", "crowd"), ("box.v1.obj", "box")]
        .into_iter()
        .map(|(file, uid)| (dir.path().join("views").join(uid), models.join(file)))
        .collect()
}

/// The files in `folder`, sorted.
fn files_in(folder: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(folder)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The objaverse preset, checked by reprojection: each mesh normalised as the script
/// normalises it (largest extent 1, box centred on the origin, in Blender's Z-up frame of
/// the file), its vertices projected with the script's camera (a ring at 30° elevation,
/// distance 1.5, a 35 mm lens on a 32 mm sensor; the pose and intrinsics computed here
/// from the script's formulas) land on the rendered image's alpha, dilated by one pixel,
/// for at least 99% of them. The folders hold the script's files and nothing else.
#[test]
fn the_objaverse_preset_projects_the_normalised_mesh_onto_its_masks() {
    let dir = TempDir::new("batch-objaverse");
    let size = 96;
    let fx = size as f64 / 2.0 / (16.0f64 / 35.0);
    for (folder, file) in preset_views(&dir, "objaverse", size, 5) {
        assert_eq!(
            files_in(&folder),
            ["000.png", "001.png", "002.png", "003.png", "004.png"]
        );
        let points = normalised_vertices(&file);
        for view in 0..5 {
            let image = image::open(folder.join(format!("{view:03}.png")))
                .unwrap()
                .to_rgba8();
            let theta = std::f64::consts::TAU * view as f64 / 5.0;
            let phi = 60f64.to_radians();
            let eye =
                1.5 * glam::DVec3::new(phi.sin() * theta.cos(), phi.sin() * theta.sin(), phi.cos());
            // Blender's camera: looking down its −Z at the origin, its +Y towards world +Z.
            let back = eye.normalize();
            let right = glam::DVec3::Z.cross(back).normalize();
            let up = back.cross(right);
            let rt = [right, up, back].map(|a| [a.x, a.y, a.z, -a.dot(eye)]);
            let (fraction, framed) = on_mask(&points, &rt, Lens::Pinhole(fx), &image);
            assert_eq!(framed, 1.0, "view {view}: the object leaves the image");
            eprintln!(
                "{} view {view}: {fraction} of the vertices on the mask",
                folder.display()
            );
            assert!(
                fraction >= 0.99,
                "{} view {view}: {fraction}",
                folder.display()
            );
        }
    }
    // Poses would lie without the normalisation: a mask is not all of the image.
    let image = image::open(dir.path().join("views/crowd/000.png"))
        .unwrap()
        .to_rgba8();
    let covered = image.pixels().filter(|p| p[3] > 0).count();
    assert!(
        covered > 100 && covered < (size * size / 2) as usize,
        "{covered} pixels covered"
    );
}

/// SyncDreamer's `--camera_type random` (its input views), checked through the `meta.pkl`
/// it writes per object: K (float32) for the image's size, the ring's azimuths (float32), an
/// elevation per view (float64) drawn in [−10°, 40°], the distance 1.5 (float64), and poses
/// (float64, OpenCV's convention) whose camera centres sit at those angles and project the
/// normalised mesh onto each view's mask. A second run writes the same bytes.
#[test]
fn syncdreamers_random_views_write_the_meta_pkl_of_its_script() {
    let dir = TempDir::new("batch-syncdreamer-random");
    let (size, views) = (96u32, 5usize);
    let extra = "camera_type = \"random\"\n";
    let models = render_preset_with(&dir, "syncdreamer", size, views as u32, extra);
    let mut elevations = Vec::new();
    for (file, uid) in [("crowd.glb", "crowd"), ("box.v1.obj", "box")] {
        let folder = dir.path().join("views").join(uid);
        let mut want: Vec<String> = (0..views).map(|v| format!("{v:03}.png")).collect();
        want.push("meta.pkl".into());
        assert_eq!(files_in(&folder), want);
        let arrays = read_pickled_arrays(&folder.join("meta.pkl"));
        let kinds: Vec<(&str, Vec<usize>)> = arrays
            .iter()
            .map(|(k, shape, _)| (k.as_str(), shape.clone()))
            .collect();
        assert_eq!(
            kinds,
            [
                ("f4", vec![3, 3]),
                ("f4", vec![views]),
                ("f8", vec![views]),
                ("f8", vec![views]),
                ("f8", vec![views, 3, 4]),
            ]
        );
        let f = size as f64 / 2.0 / (16.0f64 / 35.0);
        let c = size as f64 / 2.0;
        for (got, want) in arrays[0]
            .2
            .iter()
            .zip([f, 0.0, c, 0.0, f, c, 0.0, 0.0, 1.0])
        {
            assert!((got - want).abs() < 1e-4, "K: {:?}", arrays[0].2);
        }
        let (points, _, _) = normalised(&models.join(file));
        for v in 0..views {
            let (a, e, d) = (arrays[1].2[v], arrays[2].2[v], arrays[3].2[v]);
            assert_eq!(
                a,
                (std::f64::consts::TAU * v as f64 / views as f64) as f32 as f64
            );
            assert!(
                (-10.0..=40.0).contains(&e.to_degrees()),
                "{}",
                e.to_degrees()
            );
            assert_eq!(d, 1.5);
            elevations.push(e);
            // OpenCV's [R | t] back to Blender's camera convention: rows 1 and 2 negated.
            let p = &arrays[4].2[v * 12..v * 12 + 12];
            let sign = [1.0, -1.0, -1.0];
            let rt: [[f64; 4]; 3] =
                std::array::from_fn(|k| std::array::from_fn(|j| sign[k] * p[k * 4 + j]));
            let row = |k: usize| glam::DVec3::new(rt[k][0], rt[k][1], rt[k][2]);
            let centre = camera_centre(&rt);
            let want = d * glam::DVec3::new(a.cos() * e.cos(), a.sin() * e.cos(), e.sin());
            assert!(
                (centre - want).length() < 1e-6,
                "view {v}: {centre} against {want}"
            );
            assert!(
                (row(2) - centre.normalize()).length() < 1e-6,
                "view {v}: {rt:?}"
            );
            assert!(row(0).cross(row(1)).dot(row(2)) > 0.9999);
            let image = image::open(folder.join(format!("{v:03}.png")))
                .unwrap()
                .to_rgba8();
            let (fraction, framed) = on_mask(&points, &rt, Lens::Pinhole(f), &image);
            eprintln!(
                "{uid} view {v}: elevation {:.1}°, {fraction} on the mask",
                e.to_degrees()
            );
            assert_eq!(framed, 1.0, "{uid} view {v}: the object leaves the image");
            assert!(fraction >= 0.99, "{uid} view {v}: {fraction}");
        }
    }
    let spread = elevations.iter().cloned().fold(f64::MIN, f64::max)
        - elevations.iter().cloned().fold(f64::MAX, f64::min);
    assert!(spread.to_degrees() > 10.0, "{elevations:?}");
    let again = TempDir::new("batch-syncdreamer-random-again");
    render_preset_with(&again, "syncdreamer", size, views as u32, extra);
    for uid in ["crowd", "box"] {
        let path = |d: &TempDir| d.path().join("views").join(uid).join("meta.pkl");
        assert!(std::fs::read(path(&dir)).unwrap() == std::fs::read(path(&again)).unwrap());
    }
}

/// The camera centre C = −Rᵀt of a world→camera pose [R | t].
fn camera_centre(rt: &[[f64; 4]; 3]) -> glam::DVec3 {
    let row = |k: usize| glam::DVec3::new(rt[k][0], rt[k][1], rt[k][2]);
    -(row(0) * rt[0][3] + row(1) * rt[1][3] + row(2) * rt[2][3])
}

/// The NumPy arrays of a pickle as meshtrace writes `meta.pkl` (protocol 3: a list of
/// `_reconstruct` calls, each built with its shape, dtype and bytes): each array's dtype
/// (`f4`, `f8`), shape and values. Python's own reading is `python/tests`'.
fn read_pickled_arrays(path: &Path) -> Vec<(String, Vec<usize>, Vec<f64>)> {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..2], b"\x80\x03", "protocol 3");
    let (mut at, mut ints, mut texts, mut data) = (2, Vec::new(), Vec::new(), Vec::new());
    let mut arrays = Vec::new();
    let take = |at: &mut usize, n: usize| {
        *at += n;
        &bytes[*at - n..*at]
    };
    while at < bytes.len() {
        match take(&mut at, 1)[0] {
            b'c' => {
                for _ in 0..2 {
                    let end = at + bytes[at..].iter().position(|&b| b == b'\n').unwrap();
                    at = end + 1;
                }
            }
            b'J' => ints.push(i32::from_le_bytes(take(&mut at, 4).try_into().unwrap())),
            b'X' | b'B' => {
                let n = u32::from_le_bytes(take(&mut at, 4).try_into().unwrap()) as usize;
                let body = take(&mut at, n).to_vec();
                match bytes[at - n - 5] {
                    b'X' => texts.push(String::from_utf8(body).unwrap()),
                    _ => data.push(body),
                }
            }
            // A built array: its state's ints were (1, shape..., then the dtype's 3, -1,
            // -1, 0), its texts (kind, "<"), its bytes (b"b", data).
            b'b' if texts.len() == 2 && data.len() == 2 => {
                let shape: Vec<usize> = ints[2..ints.len() - 4]
                    .iter()
                    .map(|&d| d as usize)
                    .collect();
                let kind = texts[0].clone();
                let values = match kind.as_str() {
                    "f4" => data[1]
                        .chunks(4)
                        .map(|c| f32::from_le_bytes(c.try_into().unwrap()) as f64)
                        .collect(),
                    _ => data[1]
                        .chunks(8)
                        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                        .collect(),
                };
                arrays.push((kind, shape, values));
                (ints, texts, data) = (Vec::new(), Vec::new(), Vec::new());
            }
            b']' | b'(' | b't' | b'R' | b'b' | b'N' | 0x88 | 0x89 | b'e' | b'.' => {}
            op => panic!("{}: opcode {op:#x} at {}", path.display(), at - 1),
        }
    }
    arrays
}

/// The zero123 preset, checked by reprojection through the pose files it writes: each
/// view's `.npy` is NumPy's 3 × 4 float32 world→camera matrix in Blender's camera
/// convention, its camera on a shell of radius 1.5–2.2 looking at the origin, and the
/// normalised vertices it projects land on the view's mask. The views differ (drawn per
/// view) and are the same in a second run (seeded by the object and view).
#[test]
fn the_zero123_preset_writes_poses_that_project_the_normalised_mesh_onto_its_masks() {
    shell_preset_check("zero123", false);
}

/// The objaverse-xl preset, as zero123's, but looking at the file's origin as the script's
/// tracking target does (the off-centre box comes out off-centre, in its image and its
/// pose alike), with `metadata.json` beside the views.
#[test]
fn the_objaverse_xl_preset_writes_poses_metadata_and_masks_that_agree() {
    shell_preset_check("objaverse-xl", true);
}

fn shell_preset_check(preset: &str, xl: bool) {
    let dir = TempDir::new(&format!("batch-{preset}"));
    let size = 96;
    let fx = size as f64 / 2.0 / (16.0f64 / 35.0);
    let views = 6;
    let mut centres = Vec::new();
    for (folder, file) in preset_views(&dir, preset, size, views) {
        let mut want: Vec<String> = (0..views)
            .flat_map(|v| [format!("{v:03}.npy"), format!("{v:03}.png")])
            .collect();
        if xl {
            want.push("metadata.json".into());
        }
        want.sort();
        assert_eq!(files_in(&folder), want);
        let (points, scale, centre) = normalised(&file);
        // Where the cameras look: the origin, or the file's origin carried by the
        // normalisation.
        let target = if xl {
            -scale * centre
        } else {
            glam::DVec3::ZERO
        };
        let mut seen = 0.0;
        for view in 0..views {
            let rt = read_npy(&folder.join(format!("{view:03}.npy")));
            let row = |k: usize| glam::DVec3::new(rt[k][0], rt[k][1], rt[k][2]);
            // A rotation, and a camera centre on the shell, looking at the target.
            let c = camera_centre(&rt);
            assert!((1.5 - 1e-5..=2.2 + 1e-5).contains(&c.length()), "{c}");
            assert!(
                (row(2) - (c - target).normalize()).length() < 1e-5,
                "view {view}: {rt:?}"
            );
            assert!(row(0).cross(row(1)).dot(row(2)) > 0.9999);
            let image = image::open(folder.join(format!("{view:03}.png")))
                .unwrap()
                .to_rgba8();
            let (fraction, framed) = on_mask(&points, &rt, Lens::Pinhole(fx), &image);
            // Looking at the file's origin, objaverse-xl leaves the off-centre box partly
            // or wholly out of the image, as the script does.
            if !xl {
                assert_eq!(framed, 1.0, "view {view}: the object leaves the image");
            }
            eprintln!(
                "{} view {view}: {fraction} of the {framed} in the image on the mask",
                folder.display()
            );
            assert!(
                framed == 0.0 || fraction >= 0.99,
                "{} view {view}: {fraction}",
                folder.display()
            );
            seen += framed;
            centres.push(c);
        }
        assert!(seen > 0.5, "{}: hardly ever in the image", folder.display());
        if xl {
            let meta: serde_json::Value =
                serde_json::from_slice(&std::fs::read(folder.join("metadata.json")).unwrap())
                    .unwrap();
            let scene = meshtrace::scene::load::load_scene_with(
                &file,
                &meshtrace::scene::source::Fs,
                &meshtrace::scene::studio::BareOptions {
                    up: Some(meshtrace::scene::studio::Up::Y),
                    unlit: true,
                },
            )
            .unwrap();
            assert_eq!(meta["poly_count"], scene.mesh.triangles.len());
            assert_eq!(meta["file_size"], std::fs::metadata(&file).unwrap().len());
            let (lo, hi) = (centre - 0.5 / scale, centre + 0.5 / scale);
            let bmin: Vec<f64> =
                serde_json::from_value(meta["scene_size"]["bbox_min"].clone()).unwrap();
            let bmax: Vec<f64> =
                serde_json::from_value(meta["scene_size"]["bbox_max"].clone()).unwrap();
            // The largest extent is 1 / scale; the box's centre is the file's.
            let mid = (glam::DVec3::from_slice(&bmin) + glam::DVec3::from_slice(&bmax)) / 2.0;
            assert!(
                (mid - centre).length() < 1e-5 * (hi - lo).length(),
                "{meta}"
            );
            let extent =
                (glam::DVec3::from_slice(&bmax) - glam::DVec3::from_slice(&bmin)).max_element();
            assert!((extent * scale - 1.0).abs() < 1e-5, "{meta}");
        }
    }
    for (i, a) in centres.iter().enumerate() {
        for b in &centres[..i] {
            assert!((*a - *b).length() > 1e-3, "two views at {a}");
        }
    }
    // The same poses again.
    let again = TempDir::new(&format!("batch-{preset}-again"));
    let folders = preset_views(&again, preset, size, views);
    assert_eq!(
        std::fs::read(folders[0].0.join("003.npy")).unwrap(),
        std::fs::read(dir.path().join("views/crowd/003.npy")).unwrap()
    );
}

/// A 3 × 4 matrix as `np.savetxt` writes it and `np.loadtxt` reads it: every value in
/// `%.18e`, four a line.
fn read_savetxt(path: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .map(|line| {
            line.split(' ')
                .map(|v| {
                    let (mantissa, exponent) = v.split_once('e').unwrap();
                    assert_eq!(mantissa.split_once('.').unwrap().1.len(), 18, "{v}");
                    assert!(
                        exponent.len() >= 3 && exponent.starts_with(['+', '-']),
                        "{v}"
                    );
                    v.parse().unwrap()
                })
                .collect()
        })
        .collect()
}

/// The wonder3d preset, checked through the files it writes as Wonder3D's
/// `blenderProc_ortho.py` names them (`views/{uid[:2]}/{uid}/`): per view
/// `rgb_000_front.webp` (RGBA, alpha the binary mask), `normals_000_front.webp` and
/// `000_front_RT.txt`, and per object `scale_offset_matrix.txt`.
/// - The normalisation: the box's diagonal scaled to 1, centred, the orthographic scale
///   1.35.
/// - Each pose puts the camera 2 from the centre, looking at it, and projects the
///   normalised vertices orthographically onto its mask.
/// - The rig's cameras keep their relative poses when it turns: those of Wonder3D's own
///   fixed poses (`tests/data/wonder3d`, written by the script in Blender) for the eight
///   horizontal views, and the viewing direction for `top` (whose roll Blender's TRACK_TO
///   takes from rounding when the rig is turned).
/// - The box's normals, decoded as Wonder3D decodes them and turned back to the world by
///   the pose, are its faces' (±X, ±Y, ±Z) and face the camera.
/// - The second render of the rig (view 13) is turned otherwise than the first.
#[test]
fn the_wonder3d_preset_writes_its_scripts_files_and_poses_that_agree() {
    let dir = TempDir::new("batch-wonder3d");
    let size = 160u32;
    let views = 14;
    let models = render_preset(&dir, "wonder3d", size, views as u32);
    let names = [
        "front",
        "back",
        "right",
        "left",
        "front_right",
        "front_left",
        "back_right",
        "back_left",
        "top",
        "front_right_top",
        "front_left_top",
        "back_right_top",
        "back_left_top",
    ];
    let view_name = |v: usize| format!("{:03}_{}", v / 13, names[v % 13]);
    let row = |m: &[Vec<f64>], k: usize| glam::DVec3::new(m[k][0], m[k][1], m[k][2]);
    for (file, uid) in [("crowd.glb", "crowd"), ("box.v1.obj", "box")] {
        let folder = dir.path().join("views").join(&uid[..2]).join(uid);
        let mut want: Vec<String> = (0..views)
            .flat_map(|v| {
                let n = view_name(v);
                [
                    format!("rgb_{n}.webp"),
                    format!("normals_{n}.webp"),
                    format!("{n}_RT.txt"),
                ]
            })
            .collect();
        want.push("scale_offset_matrix.txt".into());
        want.sort();
        assert_eq!(files_in(&folder), want);
        let (points, scale, centre) = normalised_to(&models.join(file), glam::DVec3::length);
        let so = read_savetxt(&folder.join("scale_offset_matrix.txt"));
        assert_eq!(so.len(), 5);
        assert!((so[0][0] - scale).abs() < 1e-6 * scale, "{so:?}");
        let offset = glam::DVec3::new(so[1][0], so[2][0], so[3][0]);
        assert!((offset + scale * centre).length() < 1e-5, "{so:?}");
        assert_eq!(so[4][0], 1.35);
        let poses: Vec<Vec<Vec<f64>>> = (0..views)
            .map(|v| read_savetxt(&folder.join(format!("{}_RT.txt", view_name(v)))))
            .collect();
        for (view, rt) in poses.iter().enumerate() {
            assert!(rt.len() == 3 && rt.iter().all(|r| r.len() == 4), "{rt:?}");
            let t = glam::DVec3::new(rt[0][3], rt[1][3], rt[2][3]);
            let c = -(row(rt, 0) * t.x + row(rt, 1) * t.y + row(rt, 2) * t.z);
            assert!((c.length() - 2.0).abs() < 1e-5, "view {view}: {c}");
            assert!((row(rt, 2) - c.normalize()).length() < 1e-5, "view {view}");
            assert!(row(rt, 0).cross(row(rt, 1)).dot(row(rt, 2)) > 0.9999);
            let rgb = image::open(folder.join(format!("rgb_{}.webp", view_name(view))))
                .unwrap()
                .to_rgba8();
            assert_eq!(rgb.dimensions(), (size, size));
            assert!(
                rgb.pixels().all(|p| p[3] == 0 || p[3] == 255),
                "a binary mask"
            );
            let rt3: [[f64; 4]; 3] = std::array::from_fn(|k| std::array::from_fn(|j| rt[k][j]));
            let (fraction, framed) = on_mask(&points, &rt3, Lens::Orthographic(1.35), &rgb);
            assert_eq!(
                framed, 1.0,
                "{uid} view {view}: the object leaves the image"
            );
            eprintln!("{uid} view {view}: {fraction} of the vertices on the mask");
            assert!(fraction >= 0.99, "{uid} view {view}: {fraction}");
            let normals = image::open(folder.join(format!("normals_{}.webp", view_name(view))))
                .unwrap()
                .to_rgba8();
            let (mut faces, mut masked, mut stray) = (0, 0, 0);
            for (x, y, p) in normals.enumerate_pixels() {
                assert_eq!(
                    p[3],
                    rgb.get_pixel(x, y)[3],
                    "the normals' mask is the colour's"
                );
                if p[3] == 0 {
                    // Off the mask, no normal, but where some of the pixel's samples hit
                    // and its centre missed (as in Cycles' normal pass): at the mask's edge
                    // and, in the crowd, on features thinner than a pixel.
                    let near = (-1..=1).any(|d: i64| {
                        (-1..=1).any(|e: i64| {
                            let (a, b) = (x as i64 + d, y as i64 + e);
                            (0..size as i64).contains(&a)
                                && (0..size as i64).contains(&b)
                                && rgb.get_pixel(a as u32, b as u32)[3] > 0
                        })
                    });
                    stray += usize::from(!near && p.0[..3] != [127, 127, 127]);
                    continue;
                }
                masked += 1;
                // Wonder3D reads n = 2 v / 255 − 1 in the camera's frame (+Z to the viewer).
                let n = glam::DVec3::from_array([0, 1, 2].map(|k| 2.0 * p[k] as f64 / 255.0 - 1.0));
                assert!(n.z > -0.01, "{uid} view {view} ({x}, {y}): faces away: {n}");
                let world = row(rt, 0) * n.x + row(rt, 1) * n.y + row(rt, 2) * n.z;
                let interior = (-1..=1).all(|d: i64| {
                    (-1..=1).all(|e: i64| {
                        let (a, b) = (x as i64 + d, y as i64 + e);
                        (0..size as i64).contains(&a)
                            && (0..size as i64).contains(&b)
                            && normals.get_pixel(a as u32, b as u32).0 == p.0
                    })
                });
                if uid == "box" && interior {
                    faces += 1;
                    assert!(
                        world.abs().max_element() > 0.98,
                        "{uid} view {view} ({x}, {y}): {world} is not a face's normal"
                    );
                }
            }
            assert!(
                uid != "box" || stray == 0,
                "{uid} view {view}: {stray} normals away from a mask of {masked}"
            );
            assert!(
                uid != "box" || faces > 50,
                "{uid} view {view}: {faces} face pixels"
            );
        }
        // The rig's relative poses, against the script's own.
        let fixed = |name: &str| read_savetxt(&data(&format!("wonder3d/000_{name}_RT.txt")));
        let rotation =
            |m: &[Vec<f64>]| glam::DMat3::from_cols(row(m, 0), row(m, 1), row(m, 2)).transpose();
        let (ours_front, theirs_front) = (rotation(&poses[0]), rotation(&fixed("front")));
        for (j, name) in names[..9].iter().enumerate() {
            let ours = rotation(&poses[j]) * ours_front.transpose();
            let theirs = rotation(&fixed(name)) * theirs_front.transpose();
            let rows = if *name == "top" { 2..3 } else { 0..3 };
            for k in rows {
                let d = (ours.row(k) - theirs.row(k)).length();
                assert!(
                    d < 1e-5,
                    "{name}: row {k} of the relative rotation is {d} off"
                );
            }
        }
        assert!(
            (row(&poses[13], 2) - row(&poses[0], 2)).length() > 1e-3,
            "{uid}: the second render's rig is turned as the first's"
        );
    }
}

/// The wonder3d preset against Wonder3D's own script: `render_codes/blenderProc_ortho.py`
/// run unchanged through BlenderProc in Blender 4.2 (`tools/gltf_corpus/
/// wonder3d_blenderproc.py`; `wonder3d.blenderproc`) on the corpus's five spheres, the rig
/// unturned (`random_pose` off), 128², Filmic. The folder holds the script's files and no
/// others; every `_RT.txt` is the script's within 10⁻⁶ (2.7 × 10⁻⁷ measured: Blender's
/// single-precision rounding); `scale_offset_matrix.txt` holds its scale (within 10⁻⁷
/// relative), its offset (within 10⁻⁶: the file's one root node is translated, about
/// which Blender scales it) and orthographic scale. Per view,
/// the masks (alpha) have an IoU of at least 0.99 (1.0 measured in all 13 views); where
/// both cover, the normals differ by a median of at most 8 levels and a 90th percentile of
/// at most 48 (4–5 and 26–39 measured), the colours by at most 14 and 40 (6–10 and 16–27:
/// Cycles' 1,024 adaptive samples denoised), and by a mean of at most 4 levels either way
/// (10 in the end-on views, whose 216 pixels are one sphere's; −2.6 to −0.3 and −7.8
/// measured). The script's WebP is lossy: decoded by libwebp (Pillow), its normals are 2–3
/// levels (median) and 15–23 (90th percentile) from the preset's.
#[test]
fn the_wonder3d_preset_writes_what_its_script_writes_in_blenderproc() {
    let view = meshtrace::film::ViewTransform::Filmic;
    if common::luts::view_or_skip(
        "the_wonder3d_preset_writes_what_its_script_writes_in_blenderproc",
        view,
    )
    .is_none()
    {
        return;
    }
    let dir = TempDir::new("batch-wonder3d-blenderproc");
    let models = dir.path().join("models");
    std::fs::create_dir_all(&models).unwrap();
    let glb = data("gltf/corpus/materials_joined.glb");
    std::fs::copy(glb, models.join("spheres.glb")).unwrap();
    std::fs::write(
        dir.path().join("m.toml"),
        "[render]\nwidth = 128\nheight = 128\nspp = 64\nview_transform = \"filmic\"\n\n\
         [[jobs]]\nmeshes = \"models/*\"\npreset = \"wonder3d\"\nrandom_pose = false\n",
    )
    .unwrap();
    let (code, stderr) = run(&dir, &["batch", "m.toml", "--device", "cpu", "-q"]);
    assert_eq!(code, 0, "{stderr}");
    let ours = dir.path().join("views/sp/spheres");
    let script = data("gltf/corpus/wonder3d.blenderproc");
    assert_eq!(files_in(&ours), files_in(&script));
    let numbers = |path: PathBuf| -> Vec<f64> {
        std::fs::read_to_string(&path)
            .unwrap()
            .split_whitespace()
            .map(|v| v.parse().unwrap())
            .collect()
    };
    let (a, b) = (
        numbers(ours.join("scale_offset_matrix.txt")),
        numbers(script.join("scale_offset_matrix.txt")),
    );
    assert!((a[0] - b[0]).abs() <= 1e-7 * b[0], "scale: {a:?} {b:?}");
    for k in 1..4 {
        assert!((a[k] - b[k]).abs() < 1e-6, "offset: {a:?} {b:?}");
    }
    assert_eq!(a[4], b[4], "ortho_scale");
    let percentile = |mut d: Vec<u32>, p: usize| {
        d.sort_unstable();
        d[(d.len() - 1) * p / 100]
    };
    let rgba = |path: PathBuf| image::open(&path).unwrap().into_rgba8().into_raw();
    for entry in files_in(&script) {
        let Some(name) = entry.strip_suffix("_RT.txt") else {
            continue;
        };
        let (a, b) = (numbers(ours.join(&entry)), numbers(script.join(&entry)));
        let worst = a
            .iter()
            .zip(&b)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "{entry}: {worst}");
        let (rgb, their_rgb) = (
            rgba(ours.join(format!("rgb_{name}.webp"))),
            rgba(script.join(format!("rgb_{name}.webp"))),
        );
        let (normals, their_normals) = (
            rgba(ours.join(format!("normals_{name}.webp"))),
            rgba(script.join(format!("normals_{name}.webp"))),
        );
        let covered = |px: &[u8], i: usize| px[4 * i + 3] > 127;
        let pixels = rgb.len() / 4;
        let both: Vec<usize> = (0..pixels)
            .filter(|&i| covered(&rgb, i) && covered(&their_rgb, i))
            .collect();
        let either = (0..pixels)
            .filter(|&i| covered(&rgb, i) || covered(&their_rgb, i))
            .count();
        let iou = both.len() as f64 / either as f64;
        assert!(iou >= 0.99 && both.len() > 200, "{name}: IoU {iou}");
        let levels = |a: &[u8], b: &[u8]| -> Vec<u32> {
            both.iter()
                .map(|&i| {
                    (0..3)
                        .map(|c| a[4 * i + c].abs_diff(b[4 * i + c]) as u32)
                        .max()
                        .unwrap_or(0)
                })
                .collect()
        };
        for (what, d, median, p90) in [
            ("normals", levels(&normals, &their_normals), 8, 48),
            ("colour", levels(&rgb, &their_rgb), 14, 40),
        ] {
            let (m, q) = (percentile(d.clone(), 50), percentile(d, 90));
            eprintln!("{name} {what}: median {m}, 90th percentile {q}");
            assert!(m <= median && q <= p90, "{name} {what}: {m}, {q}");
        }
        // The colour's mean difference, which the noise and the WebP average out of: a
        // light or a material off shows here first.
        let (ours_rgb, theirs_rgb) = (&rgb, &their_rgb);
        let sum: i64 = both
            .iter()
            .flat_map(|&i| {
                (0..3).map(move |c| ours_rgb[4 * i + c] as i64 - theirs_rgb[4 * i + c] as i64)
            })
            .sum();
        let bias = sum as f64 / (3 * both.len()) as f64;
        let limit = if both.len() >= 500 { 4.0 } else { 10.0 };
        eprintln!("{name} colour: mean difference {bias:.2}");
        assert!(
            bias.abs() <= limit,
            "{name}: colour off by {bias:.2} levels on average"
        );
    }
}

/// The trellis preset, checked through the `transforms.json` it writes per object: the unit
/// box, the normalisation's scale and offset, and per view the image, the field of view and
/// a camera→world matrix (Blender's camera convention) of a camera at distance 2 looking at
/// the origin, which projects the normalised vertices onto the view's mask; a quarter of
/// the views (here 2 of 8) below the horizon, as TRELLIS's Hammersley sequence has them.
#[test]
fn the_trellis_preset_writes_transforms_that_project_the_normalised_mesh_onto_its_masks() {
    let dir = TempDir::new("batch-trellis");
    let size = 96;
    let views = 8;
    let models = render_preset(&dir, "trellis", size, views as u32);
    for (file, uid) in [("crowd.glb", "crowd"), ("box.v1.obj", "box")] {
        let folder = dir.path().join("renders").join(uid);
        let mut want: Vec<String> = (0..views).map(|v| format!("{v:03}.png")).collect();
        want.push("transforms.json".into());
        assert_eq!(files_in(&folder), want);
        let (points, scale, centre) = normalised(&models.join(file));
        let t: serde_json::Value =
            serde_json::from_slice(&std::fs::read(folder.join("transforms.json")).unwrap())
                .unwrap();
        assert_eq!(
            t["aabb"],
            serde_json::json!([[-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]])
        );
        assert!(
            (t["scale"].as_f64().unwrap() - scale).abs() < 1e-6 * scale,
            "{}",
            t["scale"]
        );
        let offset: Vec<f64> = serde_json::from_value(t["offset"].clone()).unwrap();
        assert!(
            (glam::DVec3::from_slice(&offset) + scale * centre).length() < 1e-5,
            "{offset:?}"
        );
        let frames = t["frames"].as_array().unwrap();
        assert_eq!(frames.len(), views);
        let mut below = 0;
        for (view, f) in frames.iter().enumerate() {
            assert_eq!(f["file_path"], format!("{view:03}.png"));
            let fov = f["camera_angle_x"].as_f64().unwrap();
            assert!((fov - 40f64.to_radians()).abs() < 1e-12);
            let m: Vec<Vec<f64>> = serde_json::from_value(f["transform_matrix"].clone()).unwrap();
            assert_eq!(m[3], [0.0, 0.0, 0.0, 1.0]);
            let col = |k: usize| glam::DVec3::new(m[0][k], m[1][k], m[2][k]);
            let c = col(3);
            assert!((c.length() - 2.0).abs() < 1e-9, "{c}");
            assert!(
                (col(2) - c.normalize()).length() < 1e-9,
                "view {view}: looks at the origin"
            );
            below += usize::from(c.z < 0.0);
            let rt = [col(0), col(1), col(2)].map(|a| [a.x, a.y, a.z, -a.dot(c)]);
            let image = image::open(folder.join(format!("{view:03}.png")))
                .unwrap()
                .to_rgba8();
            let fx = size as f64 / 2.0 / (fov / 2.0).tan();
            let (fraction, framed) = on_mask(&points, &rt, Lens::Pinhole(fx), &image);
            assert_eq!(framed, 1.0, "view {view}: the object leaves the image");
            eprintln!("{uid} view {view}: {fraction} of the vertices on the mask");
            assert!(fraction >= 0.99, "{uid} view {view}: {fraction}");
        }
        assert_eq!(below, views / 4, "{uid}: views below the horizon");
    }
}

/// TRELLIS's `--save_normal` (`save_normal = true`): beside each image `{view:03}_normal.exr`,
/// Cycles' normal pass as the script's File Output node writes it: one layer of half-float
/// R, G, B, the first hits' shading normals in Blender's world frame, summed over all the
/// pixel's samples and divided by their count. On the off-centre box (not a cube), each
/// pixel whose samples all met one face (≥ 80% of those it covers whole; the others lie on
/// an edge and average two faces' normals) holds the outward normal of the face by which
/// the pixel's centre ray, traced through the written `transforms.json` pose and field of
/// view, enters the normalised box (≥ 98% of them);
/// pixels it misses hold exactly 0; pixels on the silhouette hold less than a unit normal;
/// and the folder holds nothing else.
#[test]
fn the_trellis_preset_saves_the_normal_pass_of_cycles_beside_each_image() {
    let dir = TempDir::new("batch-trellis-normal");
    let (size, views) = (64usize, 4);
    let (folder, models) = render_trellis_normals(&dir, "box.obj", "box.obj", size, 4, views);
    let mut want: Vec<String> = (0..views)
        .flat_map(|v| [format!("{v:03}.png"), format!("{v:03}_normal.exr")])
        .collect();
    want.push("transforms.json".into());
    want.sort();
    assert_eq!(files_in(&folder), want);
    let points = normalised_vertices(&models.join("box.obj"));
    let lo = points.iter().fold(glam::DVec3::MAX, |a, &p| a.min(p));
    let hi = points.iter().fold(glam::DVec3::MIN, |a, &p| a.max(p));
    let t: serde_json::Value =
        serde_json::from_slice(&std::fs::read(folder.join("transforms.json")).unwrap()).unwrap();
    for (view, f) in t["frames"].as_array().unwrap().iter().enumerate() {
        let path = folder.join(format!("{view:03}_normal.exr"));
        let meta = exr::meta::MetaData::read_from_file(&path, false).unwrap();
        assert_eq!(meta.headers.len(), 1, "one layer");
        assert_eq!(meta.headers[0].layer_size.0, size);
        let channels: Vec<(String, exr::meta::attribute::SampleType)> = meta.headers[0]
            .channels
            .list
            .iter()
            .map(|c| (c.name.to_string(), c.sample_type))
            .collect();
        let half = exr::meta::attribute::SampleType::F16;
        assert_eq!(
            channels,
            ["B", "G", "R"].map(|n| (n.to_string(), half)),
            "{}",
            path.display()
        );
        let normals = exr_channels(&path, ["R", "G", "B"]);
        let alpha = image::open(folder.join(format!("{view:03}.png")))
            .unwrap()
            .to_rgba8();
        let m: Vec<Vec<f64>> = serde_json::from_value(f["transform_matrix"].clone()).unwrap();
        let col = |k: usize| glam::DVec3::new(m[0][k], m[1][k], m[2][k]);
        let (right, up, back, eye) = (col(0), col(1), col(2), col(3));
        let fx = size as f64 / 2.0 / (f["camera_angle_x"].as_f64().unwrap() / 2.0).tan();
        let (mut whole, mut one_face, mut agree, mut partial) = (0, 0, 0, 0);
        for (i, px) in alpha.pixels().enumerate() {
            let n = normals[i];
            match px[3] {
                0 => assert_eq!(
                    n,
                    glam::DVec3::ZERO,
                    "view {view}: pixel {i} missed the box"
                ),
                255 => {
                    whole += 1;
                    if n.length() < 0.999 {
                        // On an edge: its samples met two faces.
                        continue;
                    }
                    one_face += 1;
                    let (x, y) = ((i % size) as f64 + 0.5, (i / size) as f64 + 0.5);
                    let d = (x - size as f64 / 2.0) / fx * right
                        - (y - size as f64 / 2.0) / fx * up
                        - back;
                    agree += usize::from((n - entry_normal(eye, d, lo, hi)).length() < 2e-3);
                }
                _ => partial += usize::from(n.length() < 0.999),
            }
        }
        let fraction = agree as f64 / one_face as f64;
        eprintln!(
            "view {view}: {agree} of {one_face} pixels on one face (of {whole} covered) hold its normal, {partial} partial"
        );
        assert!(
            one_face as f64 >= 0.8 * whole as f64 && whole > 100,
            "view {view}: {one_face} of {whole} covered pixels on one face"
        );
        assert!(fraction >= 0.98, "view {view}: {fraction} of {one_face}");
        assert!(
            partial > 0,
            "view {view}: no pixel on the silhouette holds part of a normal"
        );
    }
    // A view whose pass is missing is not done: a rerun renders it again, and it alone.
    std::fs::remove_file(folder.join("001_normal.exr")).unwrap();
    let (code, stderr) = run(&dir, &["batch", "m.toml", "--device", "cpu"]);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(files_in(&folder), want);
    assert!(
        stderr.contains("images: 1 rendered, 3 already complete"),
        "{stderr}"
    );
}

/// The trellis preset's normal pass against Cycles' own (`tests/data/gltf/corpus/
/// trellis-normal.cycles`: the script's set-up on the five spheres, 64 samples through its
/// 1 px Blackman–Harris filter (its request for a box sets no Cycles property), 128², the
/// Normal pass of Blender's import; `blender_corpus.py`), both at 64 samples: the pixels
/// each covers whole are the same (IoU ≥ 0.97; 0.983 and 0.986 measured), and there the
/// two normals differ in direction by a median under 0.5° and a 95th percentile under 3°
/// (0.05° and 1.4–1.9° measured: the smooth normals Blender imports from the file,
/// interpolated alike, averaged over a pixel by different filters).
#[test]
fn the_trellis_normal_pass_is_cycles_normal_pass() {
    let dir = TempDir::new("batch-trellis-normal-cycles");
    let size = 128;
    let model = "gltf/corpus/materials_joined.glb";
    let (folder, _) = render_trellis_normals(&dir, model, "spheres.glb", size, 64, 2);
    for view in [0, 1] {
        let ours = exr_channels(
            &dir.path()
                .join(format!("renders/spheres/{view:03}_normal.exr")),
            ["R", "G", "B"],
        );
        let cycles = exr_channels(
            &data(&format!("gltf/corpus/trellis-normal.cycles/{view:03}.exr")),
            [
                "ViewLayer.Normal.X",
                "ViewLayer.Normal.Y",
                "ViewLayer.Normal.Z",
            ],
        );
        let ours_alpha = image::open(folder.join(format!("{view:03}.png")))
            .unwrap()
            .to_rgba8();
        let cycles_alpha = exr_channels(
            &data(&format!("gltf/corpus/trellis-normal.cycles/{view:03}.exr")),
            ["ViewLayer.Combined.A"; 3],
        );
        let (mut both, mut either, mut angles) = (0, 0, Vec::new());
        for (i, (a, b)) in ours.iter().zip(&cycles).enumerate() {
            let (wa, wb) = (
                ours_alpha.as_raw()[4 * i + 3] == 255,
                cycles_alpha[i].x > 0.999,
            );
            both += usize::from(wa && wb);
            either += usize::from(wa || wb);
            if wa && wb {
                angles.push(a.angle_between(*b).to_degrees());
            }
        }
        angles.sort_by(f64::total_cmp);
        let iou = both as f64 / either as f64;
        let (median, p95) = (angles[angles.len() / 2], angles[angles.len() * 95 / 100]);
        eprintln!(
            "view {view}: covered whole by both {both} pixels (IoU {iou:.3}); angle to Cycles' normal: median {median:.3}°, 95th percentile {p95:.3}°, largest {:.3}°",
            angles[angles.len() - 1]
        );
        assert!(
            iou >= 0.97 && both > 400,
            "view {view}: IoU {iou} over {both}"
        );
        assert!(
            median < 0.5 && p95 < 3.0,
            "view {view}: median {median}°, 95th percentile {p95}°"
        );
    }
}

/// TRELLIS's other passes (`save_depth`, `save_albedo`, `save_mist`, with `save_normal`)
/// against the script's own files: `blender_script/render.py` run unchanged by Blender
/// 4.5.15 with all four flags on the corpus's five spheres
/// (`tools/gltf_corpus/trellis_passes.py`; `trellis-passes.blender45`), the same two views
/// at 256², 128 samples, AgX. The folder holds the script's files and no others, and
/// `transforms.json` the script's depth ranges, scale and offset. The images' silhouettes
/// agree (IoU ≥ 0.99; 0.9991 measured) and so do their colours on average (within 5
/// levels; −3.3 and −1.9 measured: the script's image is denoised). Over the pixels that
/// both images cover whole, the passes' levels differ by a median of at most 8 of 65,535
/// in the depth PNG, 2 in the mist PNG and 2 of 255 in the albedo PNG, and by a 90th
/// percentile of at most 64, 4 and 10 (measured: 2, 0, 1 and 11–25, 0–1, 7: a depth pixel
/// is one sample in Cycles, the mean of those that hit here); where the depth PNG shows
/// the object (not 65,535) agrees in all but 1% of the object's pixels (2 of 2,292 and
/// 3,515 differ).
#[test]
fn the_trellis_passes_are_the_scripts_own_files() {
    let view = meshtrace::film::ViewTransform::Agx;
    if common::luts::view_or_skip("the_trellis_passes_are_the_scripts_own_files", view).is_none() {
        return;
    }
    let dir = TempDir::new("batch-trellis-passes");
    let (ours, _) = render_trellis(
        &dir,
        "gltf/corpus/materials_joined.glb",
        "spheres.glb",
        "spp = 128\nwidth = 256\nheight = 256\nview_transform = \"agx\"\n",
        "views = 2\nsave_depth = true\nsave_normal = true\nsave_albedo = true\nsave_mist = true\n",
    );
    let blender = data("gltf/corpus/trellis-passes.blender45");
    assert_eq!(files_in(&ours), files_in(&blender));
    let json = |folder: &Path| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(folder.join("transforms.json")).unwrap()).unwrap()
    };
    let (a, b) = (json(&ours), json(&blender));
    for view in 0..2 {
        assert_eq!(a["frames"][view]["depth"], b["frames"][view]["depth"]);
    }
    // The normalisation the script records, whose offset depends on the translation of the
    // file's one root node, about which Blender scales it.
    let number = |v: &serde_json::Value| v.as_f64().unwrap();
    let s = number(&b["scale"]);
    assert!((number(&a["scale"]) - s).abs() <= 1e-7 * s, "{a} {b}");
    for k in 0..3 {
        let (p, q) = (number(&a["offset"][k]), number(&b["offset"][k]));
        assert!(
            (p - q).abs() < 1e-6,
            "offset {k}: {p} against the script's {q}"
        );
    }
    let rgba = |path: PathBuf| image::open(&path).unwrap().into_rgba8().into_raw();
    let gray16 = |path: PathBuf| image::open(&path).unwrap().into_luma16().into_raw();
    let percentile = |mut d: Vec<u32>, p: usize| {
        d.sort_unstable();
        d[(d.len() - 1) * p / 100]
    };
    for view in 0..2 {
        let name = |pass: &str| format!("{view:03}{pass}.png");
        let (a, b) = (rgba(ours.join(name(""))), rgba(blender.join(name(""))));
        let whole: Vec<usize> = (0..a.len() / 4)
            .filter(|&i| a[4 * i + 3] == 255 && b[4 * i + 3] == 255)
            .collect();
        assert!(whole.len() > 2000, "view {view}: {} pixels", whole.len());
        // The image itself (the script's denoised, ours not): the same silhouette, and
        // colours that agree on average.
        let covered = |px: &[u8], i: usize| px[4 * i + 3] > 127;
        let both = (0..a.len() / 4)
            .filter(|&i| covered(&a, i) && covered(&b, i))
            .count();
        let either = (0..a.len() / 4)
            .filter(|&i| covered(&a, i) || covered(&b, i))
            .count();
        let iou = both as f64 / either as f64;
        let sum: i64 = whole
            .iter()
            .map(|&i| {
                (0..3)
                    .map(|c| a[4 * i + c] as i64 - b[4 * i + c] as i64)
                    .sum::<i64>()
            })
            .sum();
        let bias = sum as f64 / (3 * whole.len()) as f64;
        eprintln!("view {view} image: IoU {iou:.4}, mean difference {bias:.2}");
        assert!(
            iou >= 0.99 && bias.abs() <= 5.0,
            "view {view}: IoU {iou}, {bias:.2}"
        );
        let check = |pass: &str, diffs: Vec<u32>, median: u32, p90: u32| {
            let (m, q) = (percentile(diffs.clone(), 50), percentile(diffs, 90));
            eprintln!("view {view} {pass}: median {m}, 90th percentile {q}");
            assert!(m <= median && q <= p90, "view {view} {pass}: {m}, {q}");
        };
        for (pass, median, p90) in [("depth", 8, 64), ("mist", 2, 4)] {
            let (a, b) = (
                gray16(ours.join(name(&format!("_{pass}")))),
                gray16(blender.join(name(&format!("_{pass}")))),
            );
            check(
                pass,
                whole.iter().map(|&i| a[i].abs_diff(b[i]) as u32).collect(),
                median,
                p90,
            );
            if pass == "depth" {
                let object = b.iter().filter(|&&v| v < u16::MAX).count();
                let differ = (0..a.len())
                    .filter(|&i| (a[i] < u16::MAX) != (b[i] < u16::MAX))
                    .count();
                assert!(
                    differ * 100 <= object,
                    "view {view}: {differ} of {object} pixels"
                );
            }
        }
        let (a, b) = (
            rgba(ours.join(name("_albedo"))),
            rgba(blender.join(name("_albedo"))),
        );
        let diffs = whole
            .iter()
            .map(|&i| {
                (0..3)
                    .map(|c| a[4 * i + c].abs_diff(b[4 * i + c]) as u32)
                    .max()
                    .unwrap_or(0)
            })
            .collect();
        check("albedo", diffs, 2, 10);
    }
}

/// The channels `names` of the EXR at `path`, as vectors by pixel, from whichever of its
/// layers holds them (Blender's multilayer EXR puts each pass in a part of its own, its
/// channels named in full: `ViewLayer.Normal.X`).
fn exr_channels(path: &Path, names: [&str; 3]) -> Vec<glam::DVec3> {
    let image = exr::prelude::read_all_flat_layers_from_file(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let channel = |name: &str| -> Vec<f64> {
        let c = image
            .layer_data
            .iter()
            .flat_map(|layer| &layer.channel_data.list)
            .find(|c| c.name.to_string() == name)
            .unwrap_or_else(|| panic!("{}: no channel {name}", path.display()));
        c.sample_data.values_as_f32().map(f64::from).collect()
    };
    let [x, y, z] = names.map(channel);
    (0..x.len())
        .map(|i| glam::DVec3::new(x[i], y[i], z[i]))
        .collect()
}

/// Renders `model` (under tests/data), copied as `name`, with the trellis preset, the
/// manifest's `[render]` table holding `render` and its job `job` (each lines of TOML).
/// Returns the object's folder and the models' folder.
fn render_trellis(
    dir: &TempDir,
    model: &str,
    name: &str,
    render: &str,
    job: &str,
) -> (PathBuf, PathBuf) {
    let models = dir.path().join("models");
    std::fs::create_dir_all(&models).unwrap();
    std::fs::copy(data(model), models.join(name)).unwrap();
    std::fs::write(
        dir.path().join("m.toml"),
        format!("[render]\n{render}\n[[jobs]]\nmeshes = \"models/*\"\npreset = \"trellis\"\n{job}"),
    )
    .unwrap();
    let (code, stderr) = run(dir, &["batch", "m.toml", "--device", "cpu", "-q"]);
    assert_eq!(code, 0, "{stderr}");
    let uid = name.split('.').next().unwrap_or_default();
    (dir.path().join("renders").join(uid), models)
}

/// [`render_trellis`] with `save_normal = true`: `views` views of `size`² at `spp` samples.
fn render_trellis_normals(
    dir: &TempDir,
    model: &str,
    name: &str,
    size: usize,
    spp: u32,
    views: u32,
) -> (PathBuf, PathBuf) {
    let render = format!("spp = {spp}\nwidth = {size}\nheight = {size}\n");
    let job = format!("views = {views}\nsave_normal = true\n");
    render_trellis(dir, model, name, &render, &job)
}

/// The outward normal of the face by which the ray from `eye` along `d` enters the box
/// [`lo`, `hi`] (the slab test), or 0 where it misses.
fn entry_normal(eye: glam::DVec3, d: glam::DVec3, lo: glam::DVec3, hi: glam::DVec3) -> glam::DVec3 {
    let (mut near, mut far, mut face) = (f64::MIN, f64::MAX, glam::DVec3::ZERO);
    for k in 0..3 {
        let (a, b) = ((lo[k] - eye[k]) / d[k], (hi[k] - eye[k]) / d[k]);
        let (t0, t1) = (a.min(b), a.max(b));
        if t0 > near {
            near = t0;
            face = glam::DVec3::ZERO;
            face[k] = -d[k].signum();
        }
        far = far.min(t1);
    }
    if near <= far && near > 0.0 {
        face
    } else {
        glam::DVec3::ZERO
    }
}

/// Preset `preset` on `materials_joined.glb` (`spp` samples) against its script's own
/// set-up run by Blender 5's Cycles on the same file (`tools/gltf_corpus/blender_corpus.py`
/// `syncdreamer_cycles`, `objaverse_cycles`; views `views`, `size`²): the silhouettes agree
/// (IoU ≥ 0.99), and so does the light: the mean colour within `bounds.0` and the mean of
/// each half of the image within `bounds.1`, which glTF's metallic-roughness base (darker
/// than Cycles' Principled BSDF by 10–12%, `tests/gltf_corpus.rs`) and the two sheen models
/// leave room for.
fn preset_against_cycles(preset: &str, spp: u32, views: &[u32], size: usize, bounds: (f64, f64)) {
    preset_views_against_cycles(preset, None, spp, views, size, bounds);
}

/// [`preset_against_cycles`] with the preset's view count set to `count` (where its
/// cameras depend on it, the reference was made with the same count).
fn preset_views_against_cycles(
    preset: &str,
    count: Option<u32>,
    spp: u32,
    views: &[u32],
    size: usize,
    bounds: (f64, f64),
) {
    let dir = TempDir::new(&format!("batch-{preset}-cycles"));
    let models = dir.path().join("models");
    std::fs::create_dir_all(&models).unwrap();
    std::fs::copy(
        data("gltf/corpus/materials_joined.glb"),
        models.join("spheres.glb"),
    )
    .unwrap();
    let manifest = format!(
        "[render]\nspp = {spp}\n\n[[jobs]]\nmeshes = \"models/*\"\npreset = \"{preset}\"\n\
         output = \"views/{{uid}}/{{view:03}}.png\"\n{}",
        count.map_or(String::new(), |n| format!("views = {n}\n"))
    );
    std::fs::write(dir.path().join("m.toml"), manifest).unwrap();
    let (code, stderr) = run(&dir, &["batch", "m.toml", "--device", "cpu", "-q"]);
    assert_eq!(code, 0, "{stderr}");
    let linear = |c: u8| {
        let c = c as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let mut failures = Vec::new();
    for &view in views {
        let ours = image::open(dir.path().join(format!("views/spheres/{view:03}.png")))
            .unwrap()
            .to_rgba8();
        assert_eq!(ours.dimensions(), (size as u32, size as u32));
        let cycles = exr::prelude::read_first_rgba_layer_from_file(
            data(&format!("gltf/corpus/{preset}.cycles/{view:03}.exr")),
            |s, _| vec![[0.0f32; 4]; s.0 * s.1],
            move |px: &mut Vec<[f32; 4]>, pos, (r, g, b, a): (f32, f32, f32, f32)| {
                px[pos.1 * size + pos.0] = [r, g, b, a];
            },
        )
        .unwrap()
        .layer_data
        .channel_data
        .pixels;
        let (mut both, mut either) = (0, 0);
        // Sums over the pixels both cover fully: the whole image, its left and right halves.
        let mut sums = [[glam::DVec3::ZERO; 2]; 3];
        for (i, c) in cycles.iter().enumerate() {
            let (x, y) = ((i % size) as u32, (i / size) as u32);
            let p = ours.get_pixel(x, y);
            let (a, b) = (p[3] > 127, c[3] > 0.5);
            both += usize::from(a && b);
            either += usize::from(a || b);
            if p[3] == 255 && c[3] > 0.999 {
                let ours = glam::DVec3::new(linear(p[0]), linear(p[1]), linear(p[2]));
                // An 8-bit PNG holds no more than 1: Cycles' linear values are clipped as
                // the preset's image is (its brightest highlights exceed 1).
                let theirs =
                    glam::DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64).min(glam::DVec3::ONE);
                for s in [0, 1 + usize::from(x as usize >= size / 2)] {
                    sums[s][0] += ours;
                    sums[s][1] += theirs;
                }
            }
        }
        let iou = both as f64 / either as f64;
        eprintln!("{preset} view {view}: IoU {iou:.4}");
        if iou < 0.99 {
            failures.push(format!("{preset} view {view}: IoU {iou}"));
        }
        for (what, [x, y], bound) in [
            ("mean", sums[0], bounds.0),
            ("left half", sums[1], bounds.1),
            ("right half", sums[2], bounds.1),
        ] {
            let err = ((x - y) / y).abs().max_element();
            eprintln!("{preset} view {view}: {what}: {x:.2} against Cycles {y:.2}: {err:.3}");
            if err > bound {
                failures.push(format!(
                    "{preset} view {view}: {what}: relative error {err:.3} > {bound}"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The syncdreamer preset: a ring of 16 views at 256², the factory point light and a grey
/// world (mirroring the light fails this by 22–38%).
#[test]
fn the_syncdreamer_preset_renders_as_its_script_does_in_cycles() {
    preset_against_cycles("syncdreamer", 16, &[0, 5], 256, (0.12, 0.2));
}

/// The objaverse preset: a ring of 12 views at 512², its area light (as an environment)
/// over the factory world.
#[test]
fn the_objaverse_preset_renders_as_its_script_does_in_cycles() {
    preset_against_cycles("objaverse", 4, &[0, 7], 512, (0.13, 0.2));
}

/// The zero123 preset: its shell of cameras and, drawn for the file's uid, its area light
/// (made before the object is normalised, and so scaled with it), with the factory point
/// light and world.
#[test]
fn the_zero123_preset_renders_as_its_script_does_in_cycles() {
    preset_against_cycles("zero123", 16, &[0, 1], 512, (0.12, 0.2));
}

/// The objaverse-xl preset: the shell's cameras looking at the file's origin (moved with
/// the object), and its four shadowless suns with the strengths drawn for the file's uid.
#[test]
fn the_objaverse_xl_preset_renders_as_its_script_does_in_cycles() {
    preset_against_cycles("objaverse-xl", 16, &[0, 1], 512, (0.12, 0.2));
}

/// The trellis preset: views on the Hammersley sphere with the uid's offsets (2 views, so
/// that the test renders no more), a 40° field of view, its point and area lights made after
/// the object is normalised, a 1 px filter.
#[test]
fn the_trellis_preset_renders_as_its_script_does_in_cycles() {
    preset_views_against_cycles("trellis", Some(2), 16, &[0, 1], 512, (0.12, 0.2));
}

/// A manifest's `render.lighting` lights each input in place of a dataset preset's script
/// lighting: under a black uniform world the zero123 preset's object comes out black
/// (its area and point lights gone) where the preset's own lights show it.
#[test]
fn a_manifests_lighting_replaces_the_presets_lights() {
    let covered_rgb = |lighting: &str| {
        let dir = TempDir::new("batch-lighting");
        let models = dir.path().join("models");
        std::fs::create_dir_all(&models).unwrap();
        std::fs::copy(data("box.obj"), models.join("box.obj")).unwrap();
        let manifest = format!(
            "[render]\nspp = 2\nwidth = 24\nheight = 24\n{lighting}\n\n[[jobs]]\n\
             meshes = \"models/*\"\npreset = \"zero123\"\nviews = 1\n"
        );
        std::fs::write(dir.path().join("m.toml"), manifest).unwrap();
        let (code, stderr) = run(&dir, &["batch", "m.toml", "--device", "cpu"]);
        assert_eq!(code, 0, "{stderr}");
        let image = image::open(dir.path().join("views/box/000.png"))
            .unwrap()
            .into_rgba8();
        let covered: Vec<_> = image.pixels().filter(|p| p[3] == 255).collect();
        assert!(!covered.is_empty(), "the box covers no pixel");
        covered
            .iter()
            .map(|p| p[0] as u64 + p[1] as u64 + p[2] as u64)
            .sum::<u64>()
    };
    assert!(covered_rgb("") > 0);
    assert_eq!(
        covered_rgb("lighting = { preset = \"uniform\", color = [0.0, 0.0, 0.0] }"),
        0
    );

    // Objaverse-XL's metadata counts the input's own lights, not the preset's suns.
    let dir = TempDir::new("batch-lighting-metadata");
    let models = dir.path().join("models");
    std::fs::create_dir_all(&models).unwrap();
    std::fs::copy(data("box.obj"), models.join("box.obj")).unwrap();
    let manifest = "[render]\nspp = 1\nwidth = 16\nheight = 16\n\
                    lighting = { preset = \"suns\", count = 3 }\n\n[[jobs]]\n\
                    meshes = \"models/*\"\npreset = \"objaverse-xl\"\nviews = 1\n";
    std::fs::write(dir.path().join("m.toml"), manifest).unwrap();
    let (code, stderr) = run(&dir, &["batch", "m.toml", "--device", "cpu"]);
    assert_eq!(code, 0, "{stderr}");
    let metadata: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("views/box/metadata.json")).unwrap())
            .unwrap();
    assert_eq!(metadata["lamp_count"], 0, "{metadata}");
}
