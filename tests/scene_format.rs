//! The scene file format (shared/specs/scene-format.md) through `parse_scene` and
//! `load_scene`: exact values of a full scene, the defaults, and every error, each of
//! which must be one line naming the file and the field or line at fault.

use crate::common;

use common::fs::{TempDir, data};
use glam::Vec3;
use meshtrace::scene::builtin::load_builtin;
use meshtrace::scene::{
    Material, MaterialKind, NO_NORMAL, RenderSettings, Scene, SceneError, Sky, load_scene,
    parse_scene,
};
use std::path::PathBuf;

/// A path in the fixture directory (so relative mesh paths resolve there).
fn scene_path(name: &str) -> PathBuf {
    data(&format!("{name}.toml"))
}

fn parse_ok(name: &str, text: &str) -> Scene {
    match parse_scene(text, &scene_path(name)) {
        Ok(s) => s,
        Err(e) => panic!("{name}: expected a scene, got error: {e}"),
    }
}

/// Parses `text` as `<name>.toml`, expects an error, and checks that its message is one
/// line naming the file.
fn parse_err(name: &str, text: &str) -> SceneError {
    let path = scene_path(name);
    let err = match parse_scene(text, &path) {
        Ok(_) => panic!("{name}: expected an error, the scene parsed"),
        Err(e) => e,
    };
    let msg = err.to_string();
    assert!(
        !msg.contains('\n'),
        "{name}: message is not one line: {msg:?}"
    );
    assert!(
        msg.contains(&format!("{name}.toml")),
        "{name}: message does not name the file: {msg}"
    );
    err
}

/// Expects an `Invalid` error on exactly `field`; returns its message.
fn invalid(name: &str, text: &str, field: &str) -> String {
    let err = parse_err(name, text);
    let shown = err.to_string();
    match err {
        SceneError::Invalid {
            path,
            field: f,
            message,
        } => {
            assert_eq!(f, field, "{name}: wrong field in: {shown}");
            assert_eq!(path, scene_path(name).display().to_string());
            assert_eq!(shown, format!("{path}: {f}: {message}"));
            message
        }
        other => panic!("{name}: expected Invalid on {field}, got {other:?}"),
    }
}

/// Expects a `Syntax` error (TOML or serde) at `line`; returns (column, message).
fn syntax(name: &str, text: &str, line: usize) -> (usize, String) {
    let err = parse_err(name, text);
    let shown = err.to_string();
    match err {
        SceneError::Syntax {
            path,
            line: l,
            column,
            message,
        } => {
            assert_eq!(l, line, "{name}: wrong line in: {shown}");
            assert_eq!(shown, format!("{path}:{l}:{column}: {message}"));
            assert!(!message.is_empty());
            (column, message)
        }
        other => panic!("{name}: expected Syntax at line {line}, got {other:?}"),
    }
}

const CAM: &str = "[camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n";

fn with_cam(rest: &str) -> String {
    format!("{CAM}{rest}")
}

fn assert_vec(actual: Vec3, expected: [f32; 3], tol: f32, what: &str) {
    let e = Vec3::from(expected);
    assert!(
        (actual - e).abs().max_element() <= tol,
        "{what}: got {actual}, expected {e}"
    );
}

// ---------------------------------------------------------------- a full scene

fn full_scene() -> Scene {
    let path = data("full.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    parse_scene(&text, &path).unwrap_or_else(|e| panic!("full.toml: {e}"))
}

#[test]
fn full_scene_camera_settings_sky() {
    let s = full_scene();
    assert!(s.warnings.is_empty(), "warnings: {:?}", s.warnings);
    assert_eq!(s.path.as_deref(), Some(data("full.toml").as_path()));
    let c = &s.camera;
    assert_eq!(c.position, Vec3::new(1.0, 2.0, 3.0));
    assert_vec(c.forward, [0.0, 0.0, -1.0], 1e-6, "forward");
    assert_vec(c.right, [1.0, 0.0, 0.0], 1e-6, "right");
    assert_vec(c.up, [0.0, 1.0, 0.0], 1e-6, "up");
    assert_eq!(c.vfov, 55.5);
    assert_eq!(c.aperture, 0.25);
    assert_eq!(c.focus_distance, 2.5);
    assert_eq!(
        s.settings,
        RenderSettings {
            width: 320,
            height: 200,
            spp: 16,
            max_depth: 5,
            seed: 42,
            ..RenderSettings::default()
        }
    );
    assert_eq!(
        s.sky,
        Sky::Gradient {
            zenith: Vec3::new(0.5, 0.7, 1.0),
            horizon: Vec3::new(1.0, 0.9, 0.8),
        }
    );
}

#[test]
fn full_scene_materials() {
    let s = full_scene();
    let mat = |name: &str| -> &Material {
        let i = s
            .material_names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("no material {name} in {:?}", s.material_names));
        &s.materials[i]
    };
    let matte = mat("matte");
    assert_eq!(matte.kind, MaterialKind::DIFFUSE);
    assert_eq!(matte.albedo, Vec3::new(0.1, 0.2, 0.3));
    assert_eq!(matte.emission, Vec3::ZERO);
    assert!(!matte.is_emissive());

    let lamp = mat("lamp");
    assert_eq!(lamp.kind, MaterialKind::DIFFUSE);
    assert_eq!(lamp.albedo, Vec3::splat(0.4));
    assert_eq!(lamp.emission, Vec3::new(10.0, 20.0, 30.0));
    assert!(lamp.is_emissive());

    let mirror = mat("mirror");
    assert_eq!(mirror.kind, MaterialKind::CONDUCTOR);
    assert_eq!(mirror.albedo, Vec3::new(0.9, 0.8, 0.7));

    let brushed = mat("brushed");
    assert_eq!(brushed.kind, MaterialKind::ROUGH_CONDUCTOR);
    assert_eq!(brushed.albedo, Vec3::new(0.6, 0.5, 0.4));
    assert_eq!(brushed.roughness, 0.35);

    let glass = mat("glass");
    assert_eq!(glass.kind, MaterialKind::DIELECTRIC);
    assert_eq!(glass.ior, 1.33);
    assert_eq!(glass.emission, Vec3::ZERO);

    let crown = mat("crown");
    assert_eq!(crown.kind, MaterialKind::DIELECTRIC);
    assert_eq!(crown.ior, 1.5, "the spec's default ior");

    // Six named materials, plus the default for the object that names none.
    assert_eq!(s.materials.len(), 7);
    let default = mat("default");
    assert_eq!(*default, Material::default_diffuse());
    assert_eq!(default.kind, MaterialKind::DIFFUSE);
    assert_eq!(default.albedo, Vec3::splat(0.8));
}

/// The spec's transform order, computed independently: scale, then rotate about X, then
/// Y, then Z (degrees, right-handed), then translate.
fn trs(p: [f64; 3], s: [f64; 3], r_deg: [f64; 3], t: [f64; 3]) -> [f32; 3] {
    let [mut x, mut y, mut z] = [p[0] * s[0], p[1] * s[1], p[2] * s[2]];
    let [a, b, c] = r_deg.map(f64::to_radians);
    (y, z) = (y * a.cos() - z * a.sin(), y * a.sin() + z * a.cos());
    (x, z) = (x * b.cos() + z * b.sin(), -x * b.sin() + z * b.cos());
    (x, y) = (x * c.cos() - y * c.sin(), x * c.sin() + y * c.cos());
    [(x + t[0]) as f32, (y + t[1]) as f32, (z + t[2]) as f32]
}

#[test]
fn trs_reference_is_right_handed() {
    // The reference itself: +90 about Z takes +X to +Y; about X takes +Y to +Z; about Y
    // takes +Z to +X.
    let e = |v: [f32; 3], w: [f32; 3]| assert_vec(Vec3::from(v), w, 1e-12, "reference");
    e(
        trs([1.0, 0.0, 0.0], [1.0; 3], [0.0, 0.0, 90.0], [0.0; 3]),
        [0.0, 1.0, 0.0],
    );
    e(
        trs([0.0, 1.0, 0.0], [1.0; 3], [90.0, 0.0, 0.0], [0.0; 3]),
        [0.0, 0.0, 1.0],
    );
    e(
        trs([0.0, 0.0, 1.0], [1.0; 3], [0.0, 90.0, 0.0], [0.0; 3]),
        [1.0, 0.0, 0.0],
    );
}

#[test]
fn full_scene_transforms() {
    let s = full_scene();
    let m = &s.mesh;
    // unit triangle, matrix triangle, 80-triangle level-1 sphere, uniformly scaled triangle
    assert_eq!(m.triangles.len(), 1 + 1 + 80 + 1);
    assert_eq!(m.positions.len(), 3 + 3 + 42 + 3);
    let index = |name: &str| s.material_names.iter().position(|n| n == name).unwrap() as u32;

    // Object 0: scale [2,3,4], rotate [90,90,90], translate [10,20,30], by hand:
    // (1,0,0) -> (10,20,28); (0,1,0) -> (10,23,30); (0,0,1) -> (14,20,30).
    let t0 = m.triangles[0];
    assert_eq!(t0.material, index("matte"));
    assert_eq!(t0.n, [NO_NORMAL; 3]);
    let v0 = m.vertices(&t0);
    let by_hand = [[10.0, 20.0, 28.0], [10.0, 23.0, 30.0], [14.0, 20.0, 30.0]];
    let corners = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for k in 0..3 {
        assert_vec(v0[k], by_hand[k], 1e-5, "TRS corner");
        let r = trs(corners[k], [2.0, 3.0, 4.0], [90.0; 3], [10.0, 20.0, 30.0]);
        assert_vec(v0[k], r, 1e-5, "TRS corner vs reference");
    }

    // Object 1: the same transform as a row-major matrix.
    let t1 = m.triangles[1];
    assert_eq!(t1.material, index("mirror"));
    let v1 = m.vertices(&t1);
    for k in 0..3 {
        assert_vec(v1[k], by_hand[k], 1e-5, "matrix corner");
    }

    // Object 2: the sphere, every vertex on it, smooth normals from the centre.
    let lamp = index("lamp");
    let sphere: Vec<_> = m.triangles[2..82].iter().collect();
    for t in &sphere {
        assert_eq!(t.material, lamp);
        assert_ne!(t.n[0], NO_NORMAL);
        for k in 0..3 {
            let p = m.positions[t.p[k] as usize];
            let n = m.normals[t.n[k] as usize];
            let d = p - Vec3::new(0.0, -5.0, 0.0);
            assert!((d.length() - 2.0).abs() < 1e-5, "sphere vertex {p}");
            assert_vec(n, d.normalize().to_array(), 1e-5, "sphere normal");
        }
        // counter-clockwise seen from outside: the geometric normal points away
        let [a, b, c] = m.vertices(t);
        let g = (b - a).cross(c - a);
        assert!(g.dot((a + b + c) / 3.0 - Vec3::new(0.0, -5.0, 0.0)) > 0.0);
    }

    // Object 3: uniform scale 2.5, default material.
    let t3 = m.triangles[82];
    assert_eq!(t3.material, index("default"));
    let v3 = m.vertices(&t3);
    for k in 0..3 {
        let expected = corners[k].map(|x| (x * 2.5) as f32);
        assert_vec(v3[k], expected, 1e-6, "uniform scale");
    }
}

#[test]
fn rotations_with_general_angles_follow_spec_order() {
    let text = with_cam(
        "[[objects]]\nmesh = \"unit_tri.obj\"\nscale = [0.5, -2.0, 1.5]\n\
         rotate = [30.0, -50.0, 120.0]\ntranslate = [-1.0, 0.5, 7.0]\n",
    );
    let s = parse_ok("general_trs", &text);
    let t = s.mesh.triangles[0];
    let v = s.mesh.vertices(&t);
    // The negative scale mirrors, so the loader swaps the last two corners to keep the
    // front face in front.
    let corners = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]];
    for k in 0..3 {
        let r = trs(
            corners[k],
            [0.5, -2.0, 1.5],
            [30.0, -50.0, 120.0],
            [-1.0, 0.5, 7.0],
        );
        assert_vec(v[k], r, 1e-5, "general TRS corner");
    }
}

#[test]
fn matrix_equals_equivalent_trs() {
    let (s, r, t) = ([0.5, -2.0, 1.5], [30.0, -50.0, 120.0], [-1.0, 0.5, 7.0]);
    // Columns of the linear part are the images of the axes; the last column translates.
    let o = trs([0.0; 3], s, r, t);
    let cols: Vec<[f32; 3]> = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        .iter()
        .map(|&e| {
            let p = trs(e, s, r, t);
            [p[0] - o[0], p[1] - o[1], p[2] - o[2]]
        })
        .collect();
    let mut m = Vec::new();
    for row in 0..3 {
        m.extend([cols[0][row], cols[1][row], cols[2][row], o[row]]);
    }
    m.extend([0.0, 0.0, 0.0, 1.0]);
    let m: Vec<String> = m.iter().map(|x| format!("{x:?}")).collect();
    let text = with_cam(&format!(
        "[[objects]]\nmesh = \"unit_tri.obj\"\nscale = [0.5, -2.0, 1.5]\n\
         rotate = [30.0, -50.0, 120.0]\ntranslate = [-1.0, 0.5, 7.0]\n\
         [[objects]]\nmesh = \"unit_tri.obj\"\nmatrix = [{}]\n",
        m.join(", ")
    ));
    let sc = parse_ok("matrix_vs_trs", &text);
    assert_eq!(sc.mesh.triangles.len(), 2);
    let a = sc.mesh.vertices(&sc.mesh.triangles[0]);
    let b = sc.mesh.vertices(&sc.mesh.triangles[1]);
    for k in 0..3 {
        assert_vec(b[k], a[k].to_array(), 1e-5, "matrix vs TRS");
    }
}

#[test]
fn normals_follow_the_transform() {
    // A triangle in the XZ plane with normal +Y, non-uniformly scaled and rotated 90
    // degrees about Z: the normal must become -X (inverse transpose, renormalised).
    let dir = TempDir::new("normals");
    dir.write(
        "flat.obj",
        "v 0 0 0\nv 0 0 1\nv 1 0 0\nvn 0 1 0\nf 1//1 2//1 3//1\n",
    );
    let text = with_cam(
        "[[objects]]\nmesh = \"flat.obj\"\nscale = [3.0, 0.5, 2.0]\nrotate = [0.0, 0.0, 90.0]\n",
    );
    let result = parse_scene(&text, &dir.join("n.toml"));
    let s = result.unwrap();
    let t = s.mesh.triangles[0];
    for k in 0..3 {
        assert_vec(
            s.mesh.normals[t.n[k] as usize],
            [-1.0, 0.0, 0.0],
            1e-6,
            "normal",
        );
    }
}

#[test]
fn load_scene_reads_the_file() {
    let path = data("full.toml");
    let a = load_scene(&path).unwrap();
    let b = full_scene();
    assert_eq!(a.camera, b.camera);
    assert_eq!(a.settings, b.settings);
    assert_eq!(a.sky, b.sky);
    assert_eq!(a.materials, b.materials);
    assert_eq!(a.mesh.positions, b.mesh.positions);
    assert_eq!(a.mesh.triangles, b.mesh.triangles);
}

#[test]
fn load_scene_missing_file_names_it() {
    let path = data("no_such_scene.toml");
    let err = load_scene(&path).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, SceneError::Io { ref path, .. } if path.ends_with("no_such_scene.toml")));
    assert!(msg.starts_with(&path.display().to_string()), "{msg}");
    assert!(!msg.contains('\n'));
}

// ---------------------------------------------------------------- defaults

#[test]
fn defaults() {
    let s = parse_ok(
        "defaults",
        "[camera]\nposition = [1.0, 2.0, 3.0]\nlook_at = [4.0, 6.0, 3.0]\n",
    );
    let c = &s.camera;
    assert_eq!(c.vfov, 40.0);
    assert_eq!(c.aperture, 0.0);
    assert_eq!(c.focus_distance, 5.0, "|look_at - position| = |(3, 4, 0)|");
    // default up [0, 1, 0]: right = forward x up, up' = right x forward
    let f = Vec3::new(0.6, 0.8, 0.0);
    assert_vec(c.forward, f.to_array(), 1e-6, "forward");
    assert_vec(c.right, [0.0, 0.0, 1.0], 1e-6, "right");
    assert_vec(c.up, [-0.8, 0.6, 0.0], 1e-6, "up");
    assert_eq!(
        s.settings,
        RenderSettings {
            width: 640,
            height: 480,
            spp: 64,
            max_depth: 8,
            seed: 0,
            ..RenderSettings::default()
        }
    );
    assert_eq!(s.settings, RenderSettings::default());
    assert_eq!(s.sky, Sky::Constant(Vec3::ZERO));
    assert!(s.sky.is_black());
    assert!(s.materials.is_empty());
    assert!(s.mesh.triangles.is_empty());
    assert!(s.warnings.is_empty());
}

#[test]
fn explicit_focus_and_partial_render_table() {
    let s = parse_ok(
        "partial",
        &with_cam(
            "vfov = 90\nup = [1.0, 0.0, 0.0]\n[render]\nspp = 3\n[sky]\ncolor = [0.25, 0.5, 1.0]\n",
        ),
    );
    assert_eq!(s.camera.vfov, 90.0);
    assert_eq!(s.camera.focus_distance, 5.0);
    assert_vec(s.camera.up, [1.0, 0.0, 0.0], 1e-6, "up");
    assert_vec(s.camera.right, [0.0, -1.0, 0.0], 1e-6, "right");
    assert_eq!(
        s.settings,
        RenderSettings {
            spp: 3,
            ..RenderSettings::default()
        }
    );
    assert_eq!(s.sky, Sky::Constant(Vec3::new(0.25, 0.5, 1.0)));
}

#[test]
fn largest_image_is_accepted() {
    let s = parse_ok(
        "largest",
        &with_cam("[render]\nwidth = 8192\nheight = 8192\n"),
    );
    assert_eq!((s.settings.width, s.settings.height), (8192, 8192));
    let s = parse_ok(
        "tall",
        &with_cam("[render]\nwidth = 1\nheight = 67108864\n"),
    );
    assert_eq!(s.settings.height, 1 << 26);
}

// ---------------------------------------------------------------- syntax and keys

#[test]
fn toml_syntax_error_has_line_and_column() {
    let (column, _) = syntax(
        "syntax",
        "[camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = @\n",
        3,
    );
    assert_eq!(column, 11);
    let (column, _) = syntax(
        "unclosed",
        "[camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\n[render\nwidth = 4\n",
        5,
    );
    assert!(column >= 1);
}

#[test]
fn unknown_top_level_key() {
    let (_, msg) = syntax("unknown_top", &with_cam("\n[rendr]\nwidth = 5\n"), 5);
    assert!(msg.contains("rendr"), "{msg}");
    let (_, msg) = syntax("unknown_top_key", &with_cam("version = 2\n"), 4);
    assert!(msg.contains("version"), "{msg}");
}

#[test]
fn unknown_camera_key() {
    let (column, msg) = syntax("unknown_camera", &with_cam("fov = 30.0\n"), 4);
    assert!(msg.contains("`fov`"), "{msg}");
    assert_eq!(column, 1);
}

#[test]
fn unknown_render_and_sky_keys() {
    let (_, msg) = syntax("unknown_render", &with_cam("[render]\nsamples = 4\n"), 5);
    assert!(msg.contains("samples"), "{msg}");
    let (_, msg) = syntax(
        "unknown_sky",
        &with_cam("[sky]\ncolour = [1.0, 1.0, 1.0]\n"),
        5,
    );
    assert!(msg.contains("colour"), "{msg}");
}

#[test]
fn unknown_material_key() {
    let (_, msg) = syntax(
        "unknown_material_key",
        &with_cam("[materials.m]\ntype = \"diffuse\"\ncolour = [0.5, 0.5, 0.5]\n"),
        6,
    );
    assert!(msg.contains("colour"), "{msg}");
}

#[test]
fn unknown_object_key() {
    let (_, msg) = syntax(
        "unknown_object_key",
        &with_cam("[[objects]]\nmesh = \"unit_tri.obj\"\nrotation = [0.0, 0.0, 0.0]\n"),
        6,
    );
    assert!(msg.contains("rotation"), "{msg}");
    let (_, msg) = syntax(
        "unknown_sphere_key",
        &with_cam(
            "[[objects]]\nsphere = { center = [0.0, 0.0, 0.0], radius = 1.0, segments = 3 }\n",
        ),
        5,
    );
    assert!(msg.contains("segments"), "{msg}");
}

#[test]
fn wrong_types() {
    let (_, msg) = syntax("spp_string", &with_cam("[render]\nspp = \"x\"\n"), 5);
    assert!(msg.contains("string"), "{msg}");
    let (_, msg) = syntax("spp_negative", &with_cam("[render]\nspp = -4\n"), 5);
    assert!(msg.contains("-4"), "{msg}");
    let (_, msg) = syntax("spp_float", &with_cam("[render]\nspp = 1.5\n"), 5);
    assert!(msg.contains("float") || msg.contains("1.5"), "{msg}");
    syntax("short_vector", &with_cam("up = [0.0, 1.0]\n"), 4);
    syntax("vfov_string", &with_cam("vfov = \"wide\"\n"), 4);
    syntax(
        "scale_string",
        &with_cam("[[objects]]\nmesh = \"unit_tri.obj\"\nscale = \"big\"\n"),
        6,
    );
    syntax(
        "matrix_short",
        &with_cam("[[objects]]\nmesh = \"unit_tri.obj\"\nmatrix = [1.0, 0.0]\n"),
        6,
    );
}

#[test]
fn missing_required_keys() {
    let (_, msg) = syntax(
        "missing_position",
        "[camera]\nlook_at = [0.0, 0.0, 0.0]\n",
        1,
    );
    assert!(msg.contains("position"), "{msg}");
    let (_, msg) = syntax(
        "missing_look_at",
        "[camera]\nposition = [0.0, 0.0, 1.0]\n",
        1,
    );
    assert!(msg.contains("look_at"), "{msg}");
    let err = parse_err("missing_camera", "[render]\nspp = 4\n");
    assert!(err.to_string().contains("camera"), "{err}");
    let err = parse_err(
        "missing_type",
        &with_cam("[materials.m]\nalbedo = [0.5, 0.5, 0.5]\n"),
    );
    assert!(err.to_string().contains("type"), "{err}");
}

// ---------------------------------------------------------------- camera values

#[test]
fn vfov_range() {
    for (name, v) in [
        ("vfov0", "0.0"),
        ("vfov180", "180.0"),
        ("vfov200", "200.0"),
        ("vfovneg", "-10.0"),
    ] {
        let msg = invalid(name, &with_cam(&format!("vfov = {v}\n")), "camera.vfov");
        assert!(msg.contains("(0, 180)"), "{msg}");
    }
    let msg = invalid("vfov_nan", &with_cam("vfov = nan\n"), "camera.vfov");
    assert!(msg.contains("NaN"), "{msg}");
    parse_ok("vfov_small", &with_cam("vfov = 0.5\n"));
    parse_ok("vfov_large", &with_cam("vfov = 179.5\n"));
}

#[test]
fn aperture_and_focus() {
    let msg = invalid(
        "aperture",
        &with_cam("aperture = -0.1\n"),
        "camera.aperture",
    );
    assert!(msg.contains("-0.1"), "{msg}");
    invalid(
        "focus0",
        &with_cam("focus_distance = 0.0\n"),
        "camera.focus_distance",
    );
    invalid(
        "focusneg",
        &with_cam("focus_distance = -2.0\n"),
        "camera.focus_distance",
    );
    invalid(
        "focusinf",
        &with_cam("focus_distance = inf\n"),
        "camera.focus_distance",
    );
}

#[test]
fn non_finite_vectors() {
    let msg = invalid(
        "pos_nan",
        "[camera]\nposition = [nan, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n",
        "camera.position",
    );
    assert!(msg.contains("finite"), "{msg}");
    invalid(
        "look_inf",
        "[camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, inf, 0.0]\n",
        "camera.look_at",
    );
    invalid(
        "up_neg_inf",
        &with_cam("up = [0.0, -inf, 0.0]\n"),
        "camera.up",
    );
    invalid(
        "sky_nan",
        &with_cam("[sky]\ncolor = [1.0, nan, 1.0]\n"),
        "sky.color",
    );
    invalid(
        "emission_inf",
        &with_cam("[materials.m]\ntype = \"diffuse\"\nemission = [inf, 1.0, 1.0]\n"),
        "materials.m.emission",
    );
    let obj = "[[objects]]\nmesh = \"unit_tri.obj\"\n";
    invalid(
        "translate_nan",
        &with_cam(&format!("{obj}translate = [nan, 0.0, 0.0]\n")),
        "objects[0].translate",
    );
    invalid(
        "rotate_inf",
        &with_cam(&format!("{obj}rotate = [0.0, inf, 0.0]\n")),
        "objects[0].rotate",
    );
    invalid(
        "scale_nan",
        &with_cam(&format!("{obj}scale = nan\n")),
        "objects[0].scale",
    );
    let msg = invalid(
        "matrix_nan",
        &with_cam(&format!(
            "{obj}matrix = [1.0, 0.0, 0.0, nan, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\n"
        )),
        "objects[0].matrix",
    );
    assert!(msg.contains("finite"), "{msg}");
    invalid(
        "sphere_center_nan",
        &with_cam("[[objects]]\nsphere = { center = [0.0, nan, 0.0], radius = 1.0 }\n"),
        "objects[0].sphere.center",
    );
}

#[test]
fn degenerate_camera() {
    let msg = invalid(
        "same_point",
        "[camera]\nposition = [1.0, 2.0, 3.0]\nlook_at = [1.0, 2.0, 3.0]\n",
        "camera.look_at",
    );
    assert!(msg.contains("camera.position"), "{msg}");
    invalid(
        "up_parallel",
        "[camera]\nposition = [0.0, 5.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\n",
        "camera.up",
    );
    invalid(
        "up_antiparallel",
        &with_cam("up = [0.0, 0.0, 2.0]\n"),
        "camera.up",
    );
    invalid("up_zero", &with_cam("up = [0.0, 0.0, 0.0]\n"), "camera.up");
}

// ---------------------------------------------------------------- render values

#[test]
fn render_ranges() {
    for (name, key, field) in [
        ("width0", "width", "render.width"),
        ("height0", "height", "render.height"),
        ("spp0", "spp", "render.spp"),
        ("depth0", "max_depth", "render.max_depth"),
    ] {
        let msg = invalid(name, &with_cam(&format!("[render]\n{key} = 0\n")), field);
        assert_eq!(msg, "must be at least 1");
    }
    for (name, value) in [("branches0", 0), ("branches65", 65)] {
        let msg = invalid(
            name,
            &with_cam(&format!("[render]\nbranches = {value}\n")),
            "render.branches",
        );
        assert_eq!(msg, format!("must be from 1 to 64, not {value}"));
    }
}

#[test]
fn image_too_large() {
    let msg = invalid(
        "too_large",
        &with_cam("[render]\nwidth = 8193\nheight = 8192\n"),
        "render.width",
    );
    assert!(msg.contains("8193x8192"), "{msg}");
    assert!(msg.contains("67108864"), "{msg}");
    invalid(
        "too_tall",
        &with_cam("[render]\nwidth = 2\nheight = 33554433\n"),
        "render.width",
    );
    // u32 overflow of width * height must not wrap into an accepted size
    invalid(
        "overflow",
        &with_cam("[render]\nwidth = 65536\nheight = 65536\n"),
        "render.width",
    );
}

// ---------------------------------------------------------------- sky

#[test]
fn sky_combinations() {
    let msg = invalid(
        "sky_both",
        &with_cam("[sky]\ncolor = [1.0, 1.0, 1.0]\nzenith = [0.5, 0.7, 1.0]\n"),
        "sky.color",
    );
    assert!(msg.contains("zenith"), "{msg}");
    invalid(
        "sky_all",
        &with_cam(
            "[sky]\ncolor = [1.0, 1.0, 1.0]\nzenith = [0.5, 0.7, 1.0]\nhorizon = [1.0, 1.0, 1.0]\n",
        ),
        "sky.color",
    );
    let msg = invalid(
        "sky_zenith_only",
        &with_cam("[sky]\nzenith = [0.5, 0.7, 1.0]\n"),
        "sky.horizon",
    );
    assert!(msg.contains("required"), "{msg}");
    invalid(
        "sky_horizon_only",
        &with_cam("[sky]\nhorizon = [0.5, 0.7, 1.0]\n"),
        "sky.zenith",
    );
    invalid("sky_empty", &with_cam("[sky]\n"), "sky");
    invalid(
        "sky_negative",
        &with_cam("[sky]\ncolor = [1.0, -0.5, 1.0]\n"),
        "sky.color",
    );
    invalid(
        "sky_negative_zenith",
        &with_cam("[sky]\nzenith = [-1.0, 0.7, 1.0]\nhorizon = [1.0, 1.0, 1.0]\n"),
        "sky.zenith",
    );
}

// ---------------------------------------------------------------- materials

fn material(body: &str) -> String {
    with_cam(&format!("[materials.m]\n{body}"))
}

#[test]
fn negative_colours() {
    let msg = invalid(
        "neg_albedo",
        &material("type = \"diffuse\"\nalbedo = [0.5, -0.1, 0.5]\n"),
        "materials.m.albedo",
    );
    assert!(msg.contains("negative"), "{msg}");
    invalid(
        "neg_emission",
        &material("type = \"conductor\"\nemission = [0.0, 0.0, -1.0]\n"),
        "materials.m.emission",
    );
}

#[test]
fn roughness_rules() {
    for (name, r) in [("rough_high", "1.5"), ("rough_low", "-0.1")] {
        let msg = invalid(
            name,
            &material(&format!("type = \"rough_conductor\"\nroughness = {r}\n")),
            "materials.m.roughness",
        );
        assert!(msg.contains("[0, 1]"), "{msg}");
    }
    let msg = invalid(
        "rough_missing",
        &material("type = \"rough_conductor\"\nalbedo = [0.5, 0.5, 0.5]\n"),
        "materials.m.roughness",
    );
    assert!(msg.contains("required"), "{msg}");
    for (name, kind) in [
        ("rough_on_diffuse", "diffuse"),
        ("rough_on_conductor", "conductor"),
        ("rough_on_glass", "dielectric"),
    ] {
        invalid(
            name,
            &material(&format!("type = \"{kind}\"\nroughness = 0.5\n")),
            "materials.m.roughness",
        );
    }
    // the closed ends are accepted
    for r in ["0.0", "1.0"] {
        let s = parse_ok(
            "rough_ends",
            &material(&format!("type = \"rough_conductor\"\nroughness = {r}\n")),
        );
        assert_eq!(s.materials[0].roughness, r.parse::<f32>().unwrap());
    }
}

#[test]
fn ior_rules() {
    for (name, v) in [("ior0", "0.0"), ("ior_neg", "-1.5")] {
        let msg = invalid(
            name,
            &material(&format!("type = \"dielectric\"\nior = {v}\n")),
            "materials.m.ior",
        );
        assert!(msg.contains("positive"), "{msg}");
    }
    invalid(
        "ior_on_diffuse",
        &material("type = \"diffuse\"\nior = 1.5\n"),
        "materials.m.ior",
    );
    invalid(
        "ior_on_conductor",
        &material("type = \"conductor\"\nior = 1.5\n"),
        "materials.m.ior",
    );
    let msg = invalid(
        "albedo_on_glass",
        &material("type = \"dielectric\"\nalbedo = [1.0, 1.0, 1.0]\n"),
        "materials.m.albedo",
    );
    assert!(msg.contains("not a parameter"), "{msg}");
}

#[test]
fn unknown_material_type() {
    let (_, msg) = syntax("plastic", &material("type = \"plastic\"\n"), 5);
    assert!(msg.contains("plastic"), "{msg}");
}

// ---------------------------------------------------------------- objects

const TRI: &str = "[[objects]]\nmesh = \"unit_tri.obj\"\n";

#[test]
fn object_material_must_exist() {
    let msg = invalid(
        "unknown_mat",
        &with_cam(&format!("{TRI}{TRI}material = \"chrome\"\n")),
        "objects[1].material",
    );
    assert!(msg.contains("chrome"), "{msg}");
}

#[test]
fn object_needs_exactly_one_shape() {
    let msg = invalid(
        "both_shapes",
        &with_cam(&format!(
            "{TRI}sphere = {{ center = [0.0, 0.0, 0.0], radius = 1.0 }}\n"
        )),
        "objects[0].sphere",
    );
    assert!(msg.contains("not both"), "{msg}");
    let msg = invalid(
        "no_shape",
        &with_cam(&format!("{TRI}[[objects]]\ntranslate = [1.0, 0.0, 0.0]\n")),
        "objects[1]",
    );
    assert!(msg.contains("mesh") && msg.contains("sphere"), "{msg}");
}

#[test]
fn matrix_rules() {
    let ident = "1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0";
    parse_ok("identity", &with_cam(&format!("{TRI}matrix = [{ident}]\n")));
    for (name, extra) in [
        ("matrix_translate", "translate = [1.0, 0.0, 0.0]\n"),
        ("matrix_rotate", "rotate = [0.0, 10.0, 0.0]\n"),
        ("matrix_scale", "scale = 2.0\n"),
    ] {
        let msg = invalid(
            name,
            &with_cam(&format!("{TRI}matrix = [{ident}]\n{extra}")),
            "objects[0].matrix",
        );
        assert!(msg.contains("cannot be combined"), "{msg}");
    }
    let msg = invalid(
        "singular",
        &with_cam(&format!(
            "{TRI}matrix = [1.0, 2.0, 3.0, 0.0, 2.0, 4.0, 6.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\n"
        )),
        "objects[0].matrix",
    );
    assert!(msg.contains("singular"), "{msg}");
    let msg = invalid(
        "non_affine",
        &with_cam(&format!(
            "{TRI}matrix = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0]\n"
        )),
        "objects[0].matrix",
    );
    assert!(msg.contains("affine"), "{msg}");
    invalid(
        "non_affine_w",
        &with_cam(&format!(
            "{TRI}matrix = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 2.0]\n"
        )),
        "objects[0].matrix",
    );
}

#[test]
fn zero_scale() {
    for (name, s) in [("scale0", "0.0"), ("scale_axis0", "[1.0, 0.0, 1.0]")] {
        let msg = invalid(
            name,
            &with_cam(&format!("{TRI}scale = {s}\n")),
            "objects[0].scale",
        );
        assert!(msg.contains("non-zero"), "{msg}");
    }
    // a negative scale (a mirror) is allowed
    parse_ok(
        "scale_neg",
        &with_cam(&format!("{TRI}scale = [-1.0, 1.0, 1.0]\n")),
    );
}

#[test]
fn sphere_rules() {
    for (name, r) in [("radius0", "0.0"), ("radius_neg", "-1.0")] {
        let msg = invalid(
            name,
            &with_cam(&format!(
                "[[objects]]\nsphere = {{ center = [0.0, 0.0, 0.0], radius = {r} }}\n"
            )),
            "objects[0].sphere.radius",
        );
        assert!(msg.contains("positive"), "{msg}");
    }
    let msg = invalid(
        "subdiv11",
        &with_cam(
            "[[objects]]\nsphere = { center = [0.0, 0.0, 0.0], radius = 1.0, subdivisions = 11 }\n",
        ),
        "objects[0].sphere.subdivisions",
    );
    assert!(msg.contains("at most 10") && msg.contains("11"), "{msg}");
    let s = parse_ok(
        "subdiv0",
        &with_cam(
            "[[objects]]\nsphere = { center = [0.0, 0.0, 0.0], radius = 1.0, subdivisions = 0 }\n",
        ),
    );
    assert_eq!(s.mesh.triangles.len(), 20);
}

#[test]
fn default_sphere_subdivision_meets_spec_tolerance() {
    // Spec: without `subdivisions`, the largest distance between a triangle and the true
    // sphere is below 1/1000 of the radius. The deepest point of a triangle whose
    // corners are on the sphere is the foot of the perpendicular from the centre onto its
    // plane (inside these near-equilateral triangles).
    let s = parse_ok(
        "subdiv_default",
        &with_cam("[[objects]]\nsphere = { center = [1.0, 2.0, 3.0], radius = 4.0 }\n"),
    );
    let c = Vec3::new(1.0, 2.0, 3.0);
    let mut deepest = 0.0f32;
    for t in &s.mesh.triangles {
        let [a, b, d] = s.mesh.vertices(t);
        let n = (b - a).cross(d - a).normalize();
        deepest = deepest.max(4.0 - n.dot(a - c).abs());
    }
    assert!(
        deepest < 4.0 / 1000.0,
        "deepest triangle point {deepest} below the sphere (radius 4), {} triangles",
        s.mesh.triangles.len()
    );
}

#[test]
fn missing_mesh_file_is_an_io_error_naming_it() {
    let text = with_cam("[[objects]]\nmesh = \"no_such_mesh.obj\"\n");
    let err = parse_scene(&text, &scene_path("missing_mesh")).unwrap_err();
    let msg = err.to_string();
    match &err {
        SceneError::Io { path, source } => {
            assert_eq!(*path, data("no_such_mesh.obj").display().to_string());
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("expected Io, got {other:?}"),
    }
    assert!(msg.contains("no_such_mesh.obj"), "{msg}");
    assert!(!msg.contains('\n'), "{msg}");
}

// ---------------------------------------------------------------- built-in scene

#[test]
fn builtin_cornell() {
    let s = load_builtin("cornell").unwrap();
    assert_eq!(s.mesh.triangles.len(), 36);
    let emissive = s
        .mesh
        .triangles
        .iter()
        .filter(|t| s.materials[t.material as usize].is_emissive())
        .count();
    assert_eq!(emissive, 2);
    assert_eq!(s.camera.position, Vec3::new(0.0, 0.0, 3.9));
    assert_vec(s.camera.forward, [0.0, 0.0, -1.0], 1e-6, "forward");
    assert_eq!(s.camera.vfov, 39.3077);
    assert_eq!((s.settings.width, s.settings.height), (256, 256));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

#[test]
fn builtin_unknown_lists_names() {
    let err = load_builtin("sponza").unwrap_err();
    let msg = err.to_string();
    assert!(!msg.contains('\n'));
    assert!(msg.contains("sponza"), "{msg}");
    assert!(msg.contains("there are: cornell"), "{msg}");
    for (name, _) in meshtrace::scene::builtin::SCENES {
        assert!(msg.contains(name), "{msg}");
    }
}

/// A mirroring object transform keeps the faces the file winds counter-clockwise in front
/// (so an emitter keeps emitting outwards and a dielectric keeps its inside), for an OBJ
/// and for a glTF file, whose own mirroring nodes count too: two mirrors cancel.
#[test]
fn a_mirroring_object_transform_keeps_front_faces_in_front() {
    use common::gltf::Asset;
    let dir = TempDir::new("mirror-object");
    dir.write("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let mut a = Asset::new();
    let mesh = a.triangle(serde_json::json!({}));
    let plain = a.node(serde_json::json!({ "mesh": mesh, "translation": [0, 0, 1] }));
    let mirrored = a.node(serde_json::json!({ "mesh": mesh, "scale": [1, -1, 1] }));
    a.scene(&[plain, mirrored]);
    dir.write("t.gltf", a.embedded());
    for (mesh, transform) in [
        ("t.obj", "scale = [-1.0, 1.0, 1.0]"),
        ("t.obj", "scale = [2.0, -3.0, 1.0]"),
        (
            "t.obj",
            "matrix = [-1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]",
        ),
        ("t.gltf", "scale = [1.0, 1.0, 1.0]"),
        ("t.gltf", "scale = [-1.0, 1.0, 1.0]"),
    ] {
        let toml = format!(
            "[camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\
             [[objects]]\nmesh = \"{mesh}\"\n{transform}\n"
        );
        let scene = load_scene(&dir.write("scene.toml", toml)).unwrap();
        for t in &scene.mesh.triangles {
            let [p0, p1, p2] = scene.mesh.vertices(t);
            let n = (p1 - p0).cross(p2 - p0);
            assert!(
                n.z > 0.0,
                "{mesh} with {transform}: the front face turned to {n}"
            );
        }
    }
}

/// An object's mesh must be a format meshtrace reads; the error names the field and file.
#[test]
fn an_object_mesh_of_another_format_is_an_error_naming_the_field() {
    for mesh in ["bunny.ply", "bunny", "scene.toml"] {
        let text = with_cam(&format!("[[objects]]\nmesh = \"{mesh}\"\n"));
        let message = invalid("mesh-format", &text, "objects[0].mesh");
        assert!(message.contains(mesh), "{message}");
        assert!(
            message.contains(".obj") && message.contains(".glb"),
            "{message}"
        );
    }
}
