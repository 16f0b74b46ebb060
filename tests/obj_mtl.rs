//! OBJ and MTL files as the scene format maps them (shared/specs/scene-format.md,
//! "OBJ and MTL" and "A bare OBJ"): through `load_obj`, scene files and bare OBJs.

use crate::common;

use common::fs::{TempDir, data};
use common::studio::without_ground;
use glam::Vec3;
use meshtrace::math::Aabb;
use meshtrace::scene::load::load_scene_with;
use meshtrace::scene::obj::load_obj;
use meshtrace::scene::part::MeshPart;
use meshtrace::scene::source::Fs;
use meshtrace::scene::studio::{BareOptions, Up};
use meshtrace::scene::{Material, MaterialKind, NO_NORMAL, SceneError, Sky, load_scene};
use std::path::PathBuf;

fn obj(name: &str) -> MeshPart {
    load_obj(&data(name), &Fs).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The corners of each triangle as coordinates, in order.
fn corners(m: &MeshPart) -> Vec<[[f32; 3]; 3]> {
    m.triangles
        .iter()
        .map(|t| t.p.map(|i| m.positions[i as usize].to_array()))
        .collect()
}

#[test]
fn fans_and_relative_indices() {
    let m = obj("polys.obj");
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
    let v = |x: f32, y: f32| [x, y, 0.0];
    let expected = vec![
        // f -4 -3 -2 -> 1 2 3
        [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)],
        // quad 1 2 3 4 -> (1 2 3) (1 3 4)
        [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)],
        [v(0.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)],
        // pentagon 5 6 7 8 9 -> (5 6 7) (5 7 8) (5 8 9)
        [v(2.0, 0.0), v(3.0, 0.0), v(3.5, 1.0)],
        [v(2.0, 0.0), v(3.5, 1.0), v(2.5, 2.0)],
        [v(2.0, 0.0), v(2.5, 2.0), v(1.5, 1.0)],
        // f -3 -2 -1 -> 7 8 9
        [v(3.5, 1.0), v(2.5, 2.0), v(1.5, 1.0)],
    ];
    assert_eq!(corners(&m), expected);
    for t in &m.triangles {
        assert_eq!(t.n, [NO_NORMAL; 3], "faces without vn have no normals");
        assert_eq!(t.material, None);
    }
    assert!(m.normals.is_empty());
    assert!(m.materials.is_empty());
}

#[test]
fn per_corner_normals() {
    let m = obj("normals.obj");
    assert_eq!(m.triangles.len(), 2);
    let normal = |t: usize, k: usize| {
        let i = m.triangles[t].n[k];
        assert_ne!(i, NO_NORMAL);
        m.normals[i as usize].to_array()
    };
    let (n1, n2, n3) = ([0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, 0.6, 0.8]);
    // f 1/1/1 2/2/2 3/3/3
    assert_eq!([normal(0, 0), normal(0, 1), normal(0, 2)], [n1, n2, n3]);
    // f 2//2 4//1 3//3
    assert_eq!([normal(1, 0), normal(1, 1), normal(1, 2)], [n2, n1, n3]);
    assert_eq!(
        corners(&m)[1],
        [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]
    );
}

#[test]
fn face_without_normals_among_faces_with_normals_is_flat() {
    let m = obj("mixed_normals.obj");
    assert_eq!(m.triangles.len(), 2);
    assert_ne!(m.triangles[0].n, [NO_NORMAL; 3]);
    assert_eq!(
        m.triangles[1].n,
        [NO_NORMAL; 3],
        "`f 2 4 3` has no vn: flat geometric normals (spec), got normals {:?}",
        m.triangles[1].n.map(|i| m.normals.get(i as usize).copied())
    );
}

// ---------------------------------------------------------------- MTL mapping

/// The material of each triangle of materials.obj, by its MTL name (`None` for the
/// first triangle, which names none).
fn materials() -> (MeshPart, Vec<Option<(String, Material)>>) {
    let m = obj("materials.obj");
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
    let mats = m
        .triangles
        .iter()
        .map(|t| {
            t.material.map(|i| {
                (
                    m.material_names[i as usize].clone(),
                    m.materials[i as usize],
                )
            })
        })
        .collect();
    (m, mats)
}

fn mtl(name: &str) -> Material {
    let (_, mats) = materials();
    mats.into_iter()
        .flatten()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no triangle uses {name}"))
        .1
}

#[test]
fn every_face_gets_its_material() {
    let (m, mats) = materials();
    assert_eq!(m.triangles.len(), 9);
    assert_eq!(m.materials.len(), 8);
    let names: Vec<Option<String>> = mats
        .iter()
        .map(|m| m.as_ref().map(|(n, _)| n.clone()))
        .collect();
    let expected = [
        None,
        Some("kd"),
        Some("emit"),
        Some("metal_ks"),
        Some("metal_kd"),
        Some("pm"),
        Some("pm_pr"),
        Some("glass7"),
        Some("glass_d"),
    ];
    assert_eq!(names, expected.map(|n| n.map(String::from)));
}

#[test]
fn kd_is_diffuse_albedo() {
    let m = mtl("kd");
    assert_eq!(m.kind, MaterialKind::DIFFUSE);
    assert_eq!(m.albedo, Vec3::new(0.1, 0.2, 0.3));
    assert_eq!(m.emission, Vec3::ZERO);
}

#[test]
fn ke_is_emission() {
    let m = mtl("emit");
    assert_eq!(m.kind, MaterialKind::DIFFUSE);
    assert_eq!(m.albedo, Vec3::splat(0.5));
    assert_eq!(m.emission, Vec3::new(4.0, 5.0, 6.0));
    assert!(m.is_emissive());
}

#[test]
fn illum3_is_conductor_with_ks() {
    let m = mtl("metal_ks");
    assert_eq!(m.kind, MaterialKind::CONDUCTOR);
    assert_eq!(m.albedo, Vec3::new(0.9, 0.8, 0.7));
}

#[test]
fn illum3_without_ks_uses_kd() {
    let m = mtl("metal_kd");
    assert_eq!(m.kind, MaterialKind::CONDUCTOR);
    assert_eq!(m.albedo, Vec3::new(0.6, 0.5, 0.4));
}

#[test]
fn pm_is_conductor() {
    let m = mtl("pm");
    assert_eq!(m.kind, MaterialKind::CONDUCTOR);
    assert_eq!(m.albedo, Vec3::new(0.3, 0.4, 0.5));
}

#[test]
fn pm_with_pr_is_rough_conductor() {
    let m = mtl("pm_pr");
    assert_eq!(m.kind, MaterialKind::ROUGH_CONDUCTOR);
    assert_eq!(m.roughness, 0.3);
    assert_eq!(m.albedo, Vec3::new(0.3, 0.4, 0.5));
}

#[test]
fn illum7_is_dielectric_with_ni() {
    let m = mtl("glass7");
    assert_eq!(m.kind, MaterialKind::DIELECTRIC);
    assert_eq!(m.ior, 1.7);
}

#[test]
fn dissolve_with_ni_is_dielectric() {
    let m = mtl("glass_d");
    assert_eq!(m.kind, MaterialKind::DIELECTRIC);
    assert_eq!(m.ior, 1.33);
}

#[test]
fn face_without_material_is_default_diffuse() {
    let (m, mats) = materials();
    assert_eq!(m.triangles[0].material, None);
    assert!(mats[0].is_none());
    // ... and in a scene it gets the default diffuse 0.8
    let s = load_scene(&data("materials.obj")).unwrap();
    let first = s.mesh.triangles[0];
    let mat = &s.materials[first.material as usize];
    assert_eq!(*mat, Material::default_diffuse());
    assert_eq!(mat.kind, MaterialKind::DIFFUSE);
    assert_eq!(mat.albedo, Vec3::splat(0.8));
    assert_eq!(mat.emission, Vec3::ZERO);
    // the other faces keep their MTL materials
    let names: Vec<&str> = s.mesh.triangles[1..]
        .iter()
        .map(|t| s.material_names[t.material as usize].as_str())
        .collect();
    assert_eq!(
        names,
        [
            "kd", "emit", "metal_ks", "metal_kd", "pm", "pm_pr", "glass7", "glass_d"
        ]
    );
}

#[test]
fn scene_material_overrides_every_face() {
    let s = load_scene(&data("override.toml")).unwrap();
    assert_eq!(s.mesh.triangles.len(), 9);
    for t in &s.mesh.triangles {
        let m = &s.materials[t.material as usize];
        assert_eq!(s.material_names[t.material as usize], "paint");
        assert_eq!(m.kind, MaterialKind::CONDUCTOR);
        assert_eq!(m.albedo, Vec3::new(0.25, 0.5, 0.75));
    }
}

// ---------------------------------------------------------------- warnings

#[test]
fn missing_mtl_is_a_warning() {
    let m = obj("missing_mtl.obj");
    assert_eq!(m.triangles.len(), 1);
    assert_eq!(m.triangles[0].material, None);
    assert_eq!(m.warnings.len(), 1, "{:?}", m.warnings);
    let w = &m.warnings[0];
    assert!(w.contains("missing_mtl.obj"), "{w}");
    assert!(w.contains("material library"), "{w}");
    assert!(!w.contains('\n'));

    // through a bare-OBJ scene load: the warning is kept, the face is default diffuse
    let s = load_scene(&data("missing_mtl.obj")).unwrap();
    assert_eq!(s.warnings, m.warnings);
    let mat = &s.materials[s.mesh.triangles[0].material as usize];
    assert_eq!(*mat, Material::default_diffuse());
}

#[test]
fn missing_mtl_warning_reaches_scene_load() {
    let (_, result) = load_through_scene("missing-mtl-scene", "missing_mtl.obj");
    let s = result.unwrap();
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert!(s.warnings[0].contains("m.obj"), "{:?}", s.warnings);
}

#[test]
fn missing_second_mtl_is_a_warning() {
    let m = obj("two_mtllibs.obj");
    assert_eq!(m.materials.len(), 8);
    assert_eq!(m.warnings.len(), 1, "{:?}", m.warnings);
    assert!(m.warnings[0].contains("two_mtllibs.obj"));
}

#[test]
fn malformed_mtl_does_not_panic() {
    // `Kd 0.5`: one number where r g b are needed (tobj 4 panicked on it).
    let path = data("short_kd.obj");
    let result = std::panic::catch_unwind(|| load_obj(&path, &Fs));
    let result = result.expect("load_obj panicked on a malformed MTL");
    let err = result.expect_err("a malformed MTL line is an error");
    let msg = err.to_string();
    let prefix = format!("{}:2: ", data("short_kd.mtl").display());
    assert!(msg.starts_with(&prefix), "expected {prefix:?}: {msg}");
    assert!(msg.contains("`Kd`") && msg.contains("1 number"), "{msg}");
    assert!(!msg.contains('\n'), "{msg}");
    match &err {
        SceneError::Obj { path, line, .. } => {
            assert_eq!(*path, data("short_kd.mtl").display().to_string());
            assert_eq!(*line, Some(2));
        }
        other => panic!("expected SceneError::Obj, got {other:?}"),
    }
    // the same error through a scene load
    assert_eq!(load_scene(&path).unwrap_err().to_string(), msg);
}

#[test]
fn degenerate_triangles_are_dropped_with_a_count() {
    let s = without_ground(load_scene(&data("degenerate.obj")).unwrap());
    assert_eq!(s.mesh.triangles.len(), 1);
    assert_eq!(
        s.mesh.vertices(&s.mesh.triangles[0]),
        [Vec3::ZERO, Vec3::X, Vec3::Y]
    );
    assert_eq!(
        s.warnings,
        vec!["dropped 2 degenerate (zero-area) triangles".to_string()]
    );
    // load_obj itself keeps every triangle
    assert_eq!(obj("degenerate.obj").triangles.len(), 3);
}

// ---------------------------------------------------------------- errors

fn obj_error(name: &str) -> String {
    let err = load_obj(&data(name), &Fs).expect_err("expected an error");
    let msg = err.to_string();
    match &err {
        SceneError::Obj { path, .. } => assert_eq!(*path, data(name).display().to_string()),
        other => panic!("expected SceneError::Obj, got {other:?}"),
    }
    assert!(msg.starts_with(&data(name).display().to_string()), "{msg}");
    assert!(!msg.contains('\n'), "{msg}");
    // the same error through a scene load
    let scene_msg = load_scene(&data(name)).unwrap_err().to_string();
    assert_eq!(scene_msg, msg);
    msg
}

/// `obj_error` for a file whose first bad line is `line`: the message must name it right
/// after the path, and contain each of `needles`.
fn obj_error_at(name: &str, line: usize, needles: &[&str]) -> String {
    let msg = obj_error(name);
    let prefix = format!("{}:{line}: ", data(name).display());
    assert!(msg.starts_with(&prefix), "expected {prefix:?}: {msg}");
    match load_obj(&data(name), &Fs) {
        Err(SceneError::Obj { line: at, .. }) => assert_eq!(at, Some(line), "{msg}"),
        other => panic!("expected SceneError::Obj, got {other:?}"),
    }
    for needle in needles {
        assert!(msg.contains(needle), "expected {needle:?}: {msg}");
    }
    msg
}

#[test]
fn position_with_two_coordinates_names_its_line() {
    obj_error_at(
        "bad_v.obj",
        4,
        &["malformed vertex position (`v`)", "2 numbers"],
    );
}

#[test]
fn nan_coordinate_names_its_line() {
    obj_error_at("nan_vertex.obj", 2, &["non-finite", "NaN", "vertex 2"]);
}

#[test]
fn infinite_coordinate_names_its_line() {
    obj_error_at("inf_vertex.obj", 3, &["non-finite", "inf", "vertex 3"]);
}

#[test]
fn normal_with_two_numbers_names_its_line() {
    obj_error_at("bad_vn.obj", 5, &["malformed normal (`vn`)", "2 numbers"]);
}

#[test]
fn texture_coordinate_that_is_not_a_number_names_its_line() {
    obj_error_at(
        "bad_vt.obj",
        6,
        &["malformed texture coordinate (`vt`)", "`one`"],
    );
}

#[test]
fn face_with_two_corners_names_its_line() {
    obj_error_at(
        "two_corners.obj",
        5,
        &["malformed face (`f`)", "at least 3"],
    );
}

#[test]
fn face_index_zero_names_its_line() {
    obj_error_at("zero_index.obj", 5, &["malformed face (`f`)", "index 0"]);
}

#[test]
fn out_of_range_index_names_its_line() {
    obj_error_at(
        "bad_index.obj",
        4,
        &["vertex 4", "does not exist", "defines 3 vertices"],
    );
}

#[test]
fn out_of_range_negative_index_names_its_line() {
    // `-4` after three vertices; the fourth vertex comes after the face.
    obj_error_at(
        "negative_index.obj",
        5,
        &[
            "vertex -4",
            "does not exist",
            "3 vertices are defined before",
        ],
    );
}

#[test]
fn non_integer_index_names_its_line() {
    obj_error_at(
        "non_integer_index.obj",
        6,
        &["malformed face (`f`)", "`2.0`"],
    );
}

#[test]
fn forward_index_beyond_the_file_names_the_face_line() {
    // Faces may come before their vertices, as tobj allowed (`f 1 2 3` on line 2 loads);
    // line 3's `5` is past the four vertices the file ends up defining.
    obj_error_at("forward_index.obj", 3, &["vertex 5", "defines 4 vertices"]);
}

#[test]
fn backslash_does_not_continue_a_line() {
    // As in tobj: `\` is a word of its own line, not a continuation.
    obj_error_at("continued_face.obj", 4, &["malformed face (`f`)", "`\\\\`"]);
}

#[test]
fn valid_crlf_file_with_every_corner_form_loads() {
    let bytes = std::fs::read(data("crlf_valid.obj")).unwrap();
    assert_eq!(
        bytes.windows(2).filter(|w| w == b"\r\n").count(),
        bytes.iter().filter(|&&b| b == b'\n').count(),
        "crlf_valid.obj must keep its CRLF line endings"
    );
    let m = obj("crlf_valid.obj");
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
    let (o, x, y, xy) = (
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    );
    assert_eq!(
        corners(&m),
        vec![
            // `f 1 2 3` before the vertices; `v 2 0 0 2` is (1, 0, 0) after its w
            [o, x, y],
            // `f -4/-2 -3/-1 -2/-1`
            [o, x, y],
            // `f 2//1 4//-1 3//1`
            [x, xy, y],
            // `f 1/1/1 2/2/1 4/2/-1`
            [o, x, xy],
        ]
    );
    let normals: Vec<bool> = m.triangles.iter().map(|t| t.n != [NO_NORMAL; 3]).collect();
    assert_eq!(normals, [false, false, true, true]);
    for t in &m.triangles[2..] {
        for i in t.n {
            assert_eq!(m.normals[i as usize], Vec3::Z);
        }
    }
}

#[test]
fn scene_file_error_names_the_obj_and_its_line() {
    let (dir, result) = load_through_scene("obj-line-scene", "bad_vn.obj");
    let msg = result.unwrap_err().to_string();
    let expected = format!("{}:5: malformed normal (`vn`)", dir.join("m.obj").display());
    assert!(msg.starts_with(&expected), "{msg}");
}

#[test]
fn odd_obj_path_stays_on_one_line_with_its_line_number() {
    let dir = TempDir::new("obj-line-name");
    let path = dir.join("two\nlines.obj");
    std::fs::copy(data("bad_vn.obj"), &path).unwrap();
    let result = load_obj(&path, &Fs);
    let msg = result.unwrap_err().to_string();
    assert!(!msg.contains('\n'), "{msg}");
    assert!(msg.contains("two\\nlines.obj:5: "), "{msg}");
}

#[test]
fn missing_obj_is_io_error() {
    let err = load_obj(&data("no_such.obj"), &Fs).unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("no_such.obj"));
}

#[test]
fn obj_without_faces_is_an_error_for_a_bare_load() {
    let dir = TempDir::new("no-faces");
    let path = dir.write("points.obj", "v 0 0 0\nv 1 0 0\n");
    let result = load_scene(&path);
    let msg = result.unwrap_err().to_string();
    assert!(
        msg.contains("points.obj") && msg.contains("no faces"),
        "{msg}"
    );
}

// ---------------------------------------------------------------- bare OBJ

/// A bare OBJ in the studio, its up axis given as Y: the studio environment, a ground
/// just under the mesh, and a camera from the front-right and above whose view holds every
/// corner and whose vertical field of view the bounding sphere fills to 80%.
#[test]
fn bare_obj_is_shown_in_the_studio() {
    let options = BareOptions {
        up: Some(Up::Y),
        ..BareOptions::default()
    };
    let s = load_scene_with(&data("box.obj"), &Fs, &options).unwrap();
    assert!(matches!(s.sky, Sky::Environment { .. }), "{:?}", s.sky);
    assert_eq!(s.mesh.triangles.len(), 14, "the box and the ground");
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let (min, max) = (Vec3::new(1.0, 2.0, 3.0), Vec3::new(3.0, 3.0, 7.0));
    let center = 0.5 * (min + max);
    // The ground: level, facing up, just below the box and far wider than it.
    let ground: Vec<Vec3> = s.mesh.positions[s.mesh.positions.len() - 4..].to_vec();
    for p in &ground {
        assert!(p.y < min.y && p.y > min.y - 1e-3, "ground corner {p}");
        assert!((*p - center).length() > 10.0 * (max - min).length());
    }
    let t = s.mesh.triangles[13];
    let [a, b, c] = s.mesh.vertices(&t);
    assert!((b - a).cross(c - a).y > 0.0, "the ground faces up");
    let c = &s.camera;
    assert!(c.position.z > max.z, "camera in front (+Z): {}", c.position);
    assert!(
        c.position.x > max.x,
        "camera to the right (+X): {}",
        c.position
    );
    assert!(c.position.y > center.y, "camera above: {}", c.position);
    assert!((c.forward - (center - c.position).normalize()).length() < 1e-5);
    assert!(c.up.y > 0.0);
    let radius = 0.5 * (max - min).length();
    let seen = (radius / (center - c.position).length())
        .asin()
        .to_degrees();
    assert!(
        (seen - 0.4 * c.vfov).abs() < 1e-3,
        "the bounding sphere spans {} degrees of {}",
        2.0 * seen,
        c.vfov
    );
    let tan_v = (0.5 * c.vfov.to_radians()).tan();
    let aspect = s.settings.width as f32 / s.settings.height as f32;
    for i in 0..8 {
        let p = Vec3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        );
        let d = p - c.position;
        let z = d.dot(c.forward);
        assert!(z > 0.0, "corner {p} behind the camera");
        assert!(
            d.dot(c.up).abs() / z <= tan_v,
            "corner {p} outside the vertical FOV"
        );
        assert!(
            d.dot(c.right).abs() / z <= tan_v * aspect,
            "corner {p} outside the horizontal FOV"
        );
    }
}

/// A mesh whose extent is largest along Z is taken as Z-up and turned so that +Z is up
/// (+Y), as `--up z` does; `--up x` turns +X up; `--up y` leaves it as it is.
#[test]
fn the_up_axis_is_detected_or_given() {
    let turned = |up: Option<Up>| {
        let s = without_ground(
            load_scene_with(
                &data("box.obj"),
                &Fs,
                &BareOptions {
                    up,
                    ..BareOptions::default()
                },
            )
            .unwrap(),
        );
        s.mesh.positions.iter().fold(Aabb::EMPTY, |b, &p| b.grow(p))
    };
    // box.obj spans (1, 2, 3) to (3, 3, 7): longest along Z.
    let close = |b: Aabb, min: [f32; 3], max: [f32; 3]| {
        (b.min - Vec3::from(min)).abs().max_element() < 1e-5
            && (b.max - Vec3::from(max)).abs().max_element() < 1e-5
    };
    for up in [None, Some(Up::Z)] {
        let b = turned(up);
        assert!(
            close(b, [1.0, 3.0, -3.0], [3.0, 7.0, -2.0]),
            "{up:?}: {b:?}"
        );
    }
    let b = turned(Some(Up::Y));
    assert!(close(b, [1.0, 2.0, 3.0], [3.0, 3.0, 7.0]), "{b:?}");
    let b = turned(Some(Up::X));
    assert!(close(b, [-3.0, 1.0, 3.0], [-2.0, 3.0, 7.0]), "{b:?}");
}

/// A bare OBJ that brings its own light (an emissive MTL material) is lit by it alone:
/// a black sky and no ground.
#[test]
fn a_bare_obj_with_its_own_light_gets_no_studio() {
    let dir = TempDir::new("bare-lit");
    dir.write("m.mtl", "newmtl lamp\nKe 4 4 4\n");
    let obj = dir.write(
        "m.obj",
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl lamp\nf 1 2 3\n",
    );
    let s = load_scene(&obj).unwrap();
    assert_eq!(s.sky, Sky::Constant(Vec3::ZERO));
    assert_eq!(s.mesh.triangles.len(), 1);
}

/// `--up` belongs to bare meshes: a scene file turns its objects itself.
#[test]
fn up_for_a_scene_file_is_an_error() {
    let options = BareOptions {
        up: Some(Up::Z),
        ..BareOptions::default()
    };
    let message = load_scene_with(&data("full.toml"), &Fs, &options)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("--up") && message.contains("bare mesh"),
        "{message}"
    );
}

// ---------------------------------------------------------------- a real mesh

#[test]
fn suzanne() {
    let Some(path) = common::fs::shared_mesh("suzanne.obj") else {
        return;
    };
    // Expected triangle count from the file itself: a fan gives n - 2 per n-gon.
    let text = std::fs::read_to_string(&path).unwrap();
    let arities: Vec<usize> = text
        .lines()
        .filter(|l| l.starts_with("f "))
        .map(|l| l.split_whitespace().count() - 1)
        .collect();
    assert_eq!(arities.len(), 500, "suzanne has 500 faces");
    let expected: usize = arities.iter().map(|n| n - 2).sum();

    let m = load_obj(&path, &Fs).unwrap();
    assert_eq!(m.triangles.len(), expected);
    assert!(m.triangles.iter().all(|t| t.n != [NO_NORMAL; 3]), "has vn");
    let s = without_ground(load_scene(&path).unwrap());
    assert_eq!(s.mesh.triangles.len(), expected, "no degenerate triangles");
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // quads and triangles only: 500 faces of which the quads give two triangles each
    let quads = arities.iter().filter(|&&n| n == 4).count();
    let tris = arities.iter().filter(|&&n| n == 3).count();
    assert_eq!(quads + tris, 500);
    assert_eq!(expected, 2 * quads + tris);
}

/// Loads `tests/data/{obj}`, copied to `m.obj`, through a scene file naming it, in a fresh
/// folder `name`; returns the folder (removed again) and the result.
fn load_through_scene(
    name: &str,
    obj: &str,
) -> (PathBuf, Result<meshtrace::scene::Scene, SceneError>) {
    let dir = TempDir::new(name);
    std::fs::copy(data(obj), dir.join("m.obj")).unwrap();
    let scene = dir.write(
        "s.toml",
        "[camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n[[objects]]\nmesh = \"m.obj\"\n",
    );
    let result = load_scene(&scene);
    (dir.path().to_path_buf(), result)
}

#[test]
fn unknown_usemtl_is_a_warning_with_its_line() {
    let m = obj("unknown_usemtl.obj");
    assert_eq!(m.triangles.len(), 2);
    assert_eq!(m.warnings.len(), 1, "{:?}", m.warnings);
    let w = &m.warnings[0];
    assert!(
        w.contains("unknown_usemtl.obj:7:") && w.contains("no_such_material"),
        "{w}"
    );
    // The face falls back to the default material; the known one keeps its own.
    assert!(m.triangles[0].material.is_some());
    assert_eq!(m.triangles[1].material, None);
}

// ---------------------------------------------------------------- the parser's semantics

/// Writes `files` (name, contents) into a fresh folder `name` and loads its `m.obj`;
/// returns the folder (removed again) and the result.
fn load_files(name: &str, files: &[(&str, &[u8])]) -> (PathBuf, Result<MeshPart, SceneError>) {
    let dir = TempDir::new(name);
    for (file, contents) in files {
        dir.write(file, contents);
    }
    let result = load_obj(&dir.join("m.obj"), &Fs);
    (dir.path().to_path_buf(), result)
}

/// The name of each triangle's material (`None` for the default).
fn material_names(m: &MeshPart) -> Vec<Option<&str>> {
    m.triangles
        .iter()
        .map(|t| t.material.map(|i| m.material_names[i as usize].as_str()))
        .collect()
}

const TRI: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

#[test]
fn malformed_mtl_lines_are_errors_naming_the_library_and_line() {
    // (library text, line at fault, what the message says)
    let cases: &[(&[u8], usize, &[&str])] = &[
        (b"newmtl a\nKd 0.5 0.5\n", 2, &["`Kd`", "found 2 numbers"]),
        (
            b"# c\nnewmtl a\nKs 1 x 1\n",
            3,
            &["`Ks`", "`x` is not a number"],
        ),
        (b"newmtl a\nKe 1 2\n", 2, &["`Ke`", "found 2 numbers"]),
        (b"newmtl a\n\nNi\n", 3, &["`Ni`", "expected a number"]),
        (b"newmtl a\nd half\n", 2, &["`d`", "`half` is not a number"]),
        (b"newmtl a\nillum 3.5\n", 2, &["`illum`", "`3.5`"]),
        (b"newmtl a\nPm 1 0\n", 2, &["`Pm`", "expected one number"]),
        (
            b"newmtl a\nPr rough\n",
            2,
            &["`Pr`", "`rough` is not a number"],
        ),
        (
            b"newmtl a\nKd 1 1 1\nnewmtl  \r\n",
            3,
            &["`newmtl` names no material"],
        ),
        // Statements before any `newmtl` are checked too.
        (b"Kd 1\nnewmtl a\n", 1, &["`Kd`", "found 1 number"]),
        // The first bad line is reported, before a later non-UTF-8 one.
        (b"newmtl a\r\nKd 1 2\r\n\xff\n", 2, &["`Kd`"]),
        (b"newmtl a\nKd 1 1 1\n\xffKd\n", 3, &["not valid UTF-8"]),
    ];
    for (k, (mtl, line, needles)) in cases.iter().enumerate() {
        let obj = format!("mtllib my lib.mtl\n{TRI}usemtl a\nf 1 2 3\n");
        let (dir, result) = load_files(
            &format!("mtl-error-{k}"),
            &[("m.obj", obj.as_bytes()), ("my lib.mtl", mtl)],
        );
        let lib = dir.join("my lib.mtl").display().to_string();
        let err = result.expect_err(&format!("case {k}: expected an error"));
        let msg = err.to_string();
        assert!(
            msg.starts_with(&format!("{lib}:{line}: ")),
            "case {k}: expected {lib}:{line}: … got {msg}"
        );
        assert!(!msg.contains('\n'), "case {k}: {msg}");
        for needle in *needles {
            assert!(msg.contains(needle), "case {k}: expected {needle:?}: {msg}");
        }
        match err {
            SceneError::Obj { path, line: at, .. } => {
                assert_eq!(path, lib, "case {k}");
                assert_eq!(at, Some(*line), "case {k}");
            }
            other => panic!("case {k}: expected SceneError::Obj, got {other:?}"),
        }
    }
}

#[test]
fn mtl_values_are_read_as_before() {
    // `Ke` may be one grey number; extra words after `Kd`'s three numbers are ignored (as
    // tobj did); unused statements (Ka, Ns, Tr, maps not read, unknown ones) are not
    // checked. (`map_Kd`, `map_Ke`, `map_Pr`, `map_Pm` and the normal maps are read:
    // tests/textures.rs.)
    let mtl = b"newmtl grey_light\nKd 0.25 0.5 1 # comment\nKe 3\nKa x\nNs\nTr y\n\
map_Ks\nmap_Ns\nfoo bar\n";
    let obj = format!("mtllib m.mtl\n{TRI}usemtl grey_light\nf 1 2 3\n");
    let (_, result) = load_files("mtl-values", &[("m.obj", obj.as_bytes()), ("m.mtl", mtl)]);
    let m = result.unwrap();
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
    let index = m.triangles[0].material.unwrap() as usize;
    let mat = &m.materials[index];
    assert_eq!(m.material_names[index], "grey_light");
    assert_eq!(mat.kind, MaterialKind::DIFFUSE);
    assert_eq!(mat.albedo, Vec3::new(0.25, 0.5, 1.0));
    assert_eq!(mat.emission, Vec3::splat(3.0));
}

#[test]
fn usemtl_before_its_mtllib_uses_the_default_material() {
    // As in tobj, a library applies from its `mtllib` line on: `blue` is unknown at line 7.
    let obj = format!(
        "mtllib red.mtl\n{TRI}usemtl red\nf 1 2 3\nusemtl blue\nf 1 2 3\n\
mtllib blue.mtl\nusemtl blue\nf 1 2 3\n"
    );
    let (dir, result) = load_files(
        "usemtl-before-mtllib",
        &[
            ("m.obj", obj.as_bytes()),
            ("red.mtl", b"newmtl red\nKd 1 0 0\n"),
            ("blue.mtl", b"newmtl blue\nKd 0 0 1\n"),
        ],
    );
    let m = result.unwrap();
    assert_eq!(
        material_names(&m),
        [Some("red"), None, Some("blue")],
        "the face after `usemtl blue` on line 7 (before blue.mtl) is default"
    );
    // Said once, at its line: the name is only defined later.
    assert_eq!(m.warnings.len(), 1, "{:?}", m.warnings);
    let w = &m.warnings[0];
    let prefix = format!("{}:7: ", dir.join("m.obj").display());
    assert!(w.starts_with(&prefix), "expected {prefix:?}: {w}");
    assert!(w.contains("`blue`") && w.contains("after this line"), "{w}");
}

#[test]
fn duplicated_material_names_use_the_last_definition() {
    // Twice in one library, and again in a second one; every definition is listed.
    let obj = format!(
        "mtllib a.mtl\n{TRI}usemtl dup\nf 1 2 3\nmtllib b.mtl\nusemtl dup\nf 1 2 3\n\
usemtl once\nf 1 2 3\n"
    );
    let (_, result) = load_files(
        "duplicate-names",
        &[
            ("m.obj", obj.as_bytes()),
            (
                "a.mtl",
                b"newmtl dup\nKd 1 0 0\nnewmtl once\nKd 0 1 0\nnewmtl dup\nKd 0 0 1\n",
            ),
            ("b.mtl", b"newmtl dup\nKd 0.5 0.5 0.5\n"),
        ],
    );
    let m = result.unwrap();
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
    let names: Vec<&str> = m.material_names.iter().map(String::as_str).collect();
    assert_eq!(names, ["dup", "once", "dup", "dup"]);
    let albedo = |t: usize| m.materials[m.triangles[t].material.unwrap() as usize].albedo;
    // Before b.mtl: a.mtl's second `dup`; after: b.mtl's.
    assert_eq!(albedo(0), Vec3::new(0.0, 0.0, 1.0));
    assert_eq!(albedo(1), Vec3::splat(0.5));
    assert_eq!(albedo(2), Vec3::new(0.0, 1.0, 0.0));
    assert_eq!(m.triangles[0].material, Some(2));
    assert_eq!(m.triangles[1].material, Some(3));
}

#[test]
fn lines_of_three_or_more_points_are_polygons() {
    // `l` of 1 or 2 points is dropped, longer ones fan like faces (as tobj did); `p` is
    // ignored.
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nl 1 2\nl 3\np 1 2 3\nl 1 2 3 4\n\
l 1/1 -3/2 -2/1\nvt 0 0\nvt 1 0\nf 4 1 2\n";
    let (_, result) = load_files("l-polygons", &[("m.obj", obj.as_bytes())]);
    let m = result.unwrap();
    let (o, x, xy, y) = (
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    );
    assert_eq!(corners(&m), [[o, x, xy], [o, xy, y], [o, x, xy], [y, o, x]]);
    assert!(m.triangles.iter().all(|t| t.n == [NO_NORMAL; 3]));
    // An `l` line of three points is checked like a face; an empty one is an error.
    let (_, result) = load_files("l-bad", &[("m.obj", b"v 0 0 0\nl 1 2 3\n")]);
    let msg = result.unwrap_err().to_string();
    assert!(msg.contains(":2: ") && msg.contains("vertex 2"), "{msg}");
    let (_, result) = load_files("l-empty", &[("m.obj", b"v 0 0 0\nl\n")]);
    let msg = result.unwrap_err().to_string();
    assert!(msg.contains(":2: malformed line (`l`)"), "{msg}");
}

#[test]
fn face_with_normals_on_only_some_corners_is_flat() {
    // The quad's first triangle (1 2 3) has a vn at every corner, but its face does not:
    // both of its triangles are flat, like the triangle with one bare corner. tobj would
    // have lent the bare corners a neighbour's normal.
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvn 0.6 0 0.8\n\
f 1//1 2//2 3//1 4\nf 1//2 3 4//1\nf 1//1 2//2 3//2 4//1\n";
    let (_, result) = load_files("partial-vn", &[("m.obj", obj.as_bytes())]);
    let m = result.unwrap();
    let n: Vec<[u32; 3]> = m.triangles.iter().map(|t| t.n).collect();
    assert_eq!(
        n,
        [
            [NO_NORMAL; 3],
            [NO_NORMAL; 3],
            [NO_NORMAL; 3],
            [0, 1, 1],
            [0, 1, 0],
        ]
    );
}

#[test]
fn bare_obj_is_framed_by_the_vertices_its_faces_use() {
    // box.obj plus vertices no face uses (one before, one after, far away): the camera
    // must not move.
    let text = std::fs::read_to_string(data("box.obj")).unwrap();
    // One vertex more in front: every face index moves up by one.
    let shifted: String = text
        .lines()
        .map(|line| match line.strip_prefix("f ") {
            Some(corners) => {
                let corners: Vec<String> = corners
                    .split_whitespace()
                    .map(|i| (i.parse::<u32>().unwrap() + 1).to_string())
                    .collect();
                format!("f {}\n", corners.join(" "))
            }
            None => format!("{line}\n"),
        })
        .collect();
    let padded = format!("v -100 -100 -100\n{shifted}v 100 100 100\n");
    let dir = TempDir::new("unused-vertices");
    let padded = load_scene(&dir.write("padded.obj", padded));
    let padded = without_ground(padded.unwrap());
    let plain = load_scene(&data("box.obj")).unwrap();
    assert_eq!(padded.mesh.triangles.len(), 12);
    assert_eq!(padded.camera, plain.camera);
}

/// Glass (`illum 7`) without `Ni` has index 1.5, not the 1 that would make it vanish; a
/// negative `Kd` is read as 0 with a warning naming the library's line.
#[test]
fn mtl_glass_without_ni_and_negative_colours() {
    let dir = TempDir::new("mtl-defaults");
    dir.write(
        "m.mtl",
        "newmtl glass\nillum 7\nnewmtl dark\nKd -0.5 0.25 0.5\n",
    );
    let obj = dir.write(
        "m.obj",
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl glass\nf 1 2 3\nusemtl dark\nf 1 3 2\n",
    );
    let s = load_scene(&obj).unwrap();
    let material = |k: usize| s.materials[s.mesh.triangles[k].material as usize];
    let glass = material(0);
    assert_eq!(glass.kind, MaterialKind::DIELECTRIC);
    assert_eq!(glass.ior, 1.5);
    assert_eq!(material(1).albedo, Vec3::new(0.0, 0.25, 0.5));
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    let w = &s.warnings[0];
    assert!(w.contains("m.mtl:4") && w.contains("Kd"), "{w}");
}
