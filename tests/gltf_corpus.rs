//! The glTF corpus that third-party writers made (`tests/data/gltf/corpus`, rebuilt by
//! `tools/gltf_corpus/make.sh`): Blender 5's exporter wrote the originals, gltf-transform
//! 4.5 their instanced and compressed forms, and Khronos' glTF-Validator reports no errors
//! in any. Each file must load into the shape Blender's importer evaluates for its
//! original (`NAME.expected.json`): skins bent, morph targets at their default weights,
//! every instance placed, compressed geometry decoded.

mod common;

use common::fs::data;
use glam::{DMat3, DVec3};
use meshtrace::scene::{Scene, load_scene};

/// What is compared, whatever the vertex order: the triangle count, the total area, the
/// bounds, and the area-weighted mean and covariance of the triangle centroids.
#[derive(Debug)]
struct Shape {
    triangles: usize,
    area: f64,
    min: DVec3,
    max: DVec3,
    mean: DVec3,
    covariance: DMat3,
}

fn shape_of(scene: &Scene) -> Shape {
    let mesh = &scene.mesh;
    let (mut area, mut first, mut second) = (0.0, DVec3::ZERO, DMat3::ZERO);
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for t in &mesh.triangles {
        let [a, b, c] = mesh.vertices(t).map(|v| v.as_dvec3());
        let w = 0.5 * (b - a).cross(c - a).length();
        let centroid = (a + b + c) / 3.0;
        area += w;
        min = min.min(a).min(b).min(c);
        max = max.max(a).max(b).max(c);
        first += w * centroid;
        second += w * DMat3::from_cols(
            centroid * centroid.x,
            centroid * centroid.y,
            centroid * centroid.z,
        );
    }
    let mean = first / area;
    let covariance =
        second * (1.0 / area) - DMat3::from_cols(mean * mean.x, mean * mean.y, mean * mean.z);
    Shape {
        triangles: mesh.triangles.len(),
        area,
        min,
        max,
        mean,
        covariance,
    }
}

fn expected(name: &str) -> Shape {
    let path = data(&format!("gltf/corpus/{name}.expected.json"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let v: serde_json::Value = serde_json::from_str(&text).expect("expected shape JSON");
    let vec3 = |key: &str| {
        let a: Vec<f64> = serde_json::from_value(v[key].clone()).expect("three numbers");
        DVec3::new(a[0], a[1], a[2])
    };
    let rows: Vec<Vec<f64>> = serde_json::from_value(v["covariance"].clone()).expect("3×3");
    Shape {
        triangles: v["triangles"].as_u64().expect("a count") as usize,
        area: v["area"].as_f64().expect("an area"),
        min: vec3("min"),
        max: vec3("max"),
        mean: vec3("mean"),
        // Symmetric, so rows and columns alike.
        covariance: DMat3::from_cols(
            DVec3::from_slice(&rows[0]),
            DVec3::from_slice(&rows[1]),
            DVec3::from_slice(&rows[2]),
        ),
    }
}

/// Loads corpus file `file` as a bare mesh (without the studio's ground) and checks it
/// against `reference`'s expected shape, lengths within `tolerance` of the shape's size
/// (the quantisation of compressed forms moves vertices a little).
fn check(file: &str, reference: &str, tolerance: f64) {
    let path = data(&format!("gltf/corpus/{file}.glb"));
    let scene =
        common::studio::without_ground(load_scene(&path).unwrap_or_else(|e| panic!("{file}: {e}")));
    let got = shape_of(&scene);
    let want = expected(reference);
    let size = (want.max - want.min).max_element();
    let close = |a: DVec3, b: DVec3, scale: f64| (a - b).abs().max_element() <= tolerance * scale;
    let report = format!("{file} against {reference}:\n got  {got:?}\n want {want:?}");
    // The loader drops zero-area triangles (the skin folds a few at the bend), saying so.
    let dropped: usize = scene
        .warnings
        .iter()
        .filter_map(|w| {
            w.split("dropped ")
                .nth(1)?
                .split(' ')
                .next()?
                .parse::<usize>()
                .ok()
        })
        .sum();
    assert_eq!(got.triangles + dropped, want.triangles, "{report}");
    assert!(
        (got.area - want.area).abs() <= 4.0 * tolerance * want.area,
        "area: {report}"
    );
    assert!(close(got.min, want.min, size), "min: {report}");
    assert!(close(got.max, want.max, size), "max: {report}");
    assert!(close(got.mean, want.mean, size), "mean: {report}");
    for i in 0..3 {
        assert!(
            close(got.covariance.col(i), want.covariance.col(i), size * size),
            "covariance: {report}"
        );
    }
    assert!(
        scene.warnings.iter().all(|w| w.contains("degenerate")),
        "{file}: {:?}",
        scene.warnings
    );
}

/// Exported files hold floats: Blender's import and meshtrace's agree to float rounding.
const EXACT: f64 = 1e-5;
/// gltf-transform's meshopt quantises positions to 14 bits and normals to 8 of the
/// shape's extent; Draco's to 14 and 10 bits.
const QUANTISED: f64 = 2e-3;

#[test]
fn a_skin_bends_the_arm_at_its_static_pose() {
    check("skinned_arm", "skinned_arm", EXACT);
}

#[test]
fn morph_targets_apply_their_default_weights() {
    check("morph_box", "morph_box", EXACT);
}

#[test]
fn every_node_of_a_shared_mesh_is_drawn() {
    check("crowd", "crowd", EXACT);
}

#[test]
fn gpu_instancing_draws_every_instance() {
    check("crowd_instanced", "crowd", EXACT);
}

#[test]
fn meshopt_compression_is_decoded() {
    check("skinned_arm_meshopt", "skinned_arm", QUANTISED);
    check("morph_box_meshopt", "morph_box", QUANTISED);
    check("crowd_meshopt", "crowd", QUANTISED);
}

#[test]
fn draco_compression_is_decoded() {
    check("draco_monkey", "draco_monkey", QUANTISED);
    check("crowd_draco", "crowd", QUANTISED);
    check("skinned_arm_draco", "skinned_arm", QUANTISED);
}

#[test]
fn animations_are_noted_not_warned() {
    let scene = load_scene(&data("gltf/corpus/animated_cube.glb")).expect("loads");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.notes.len(), 1, "{:?}", scene.notes);
    assert!(
        scene.notes[0].contains("animated_cube.glb: 1 animation is not played"),
        "{:?}",
        scene.notes
    );
    let still = load_scene(&data("gltf/corpus/skinned_arm.glb")).expect("loads");
    assert!(still.notes.is_empty(), "{:?}", still.notes);
}
