//! Replays the fuzz corpora (`fuzz/corpus/{scene_file,obj_mtl,gltf,draco,meshopt}`) through the fuzz targets'
//! own harnesses, without libFuzzer: every input must load or fail with an error, never
//! panic, and whatever loads must build a valid BVH. A failure names the corpus file.

#[allow(dead_code)] // `guarded` is for the fuzz targets only
#[path = "../fuzz/src/lib.rs"]
mod harness;

use std::path::{Path, PathBuf};

fn corpus(target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("a directory entry").path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

fn replay_all(target: &str, harness: fn(&[u8]), min_files: usize) {
    harness::install_panic_hook();
    let files = corpus(target);
    assert!(
        files.len() >= min_files,
        "{target}: only {} corpus files",
        files.len()
    );
    let failures: Vec<String> = files
        .iter()
        .filter_map(|path| {
            let data = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            harness::replay(&data, harness)
                .err()
                .map(|msg| format!("{}: {msg}", path.display()))
        })
        .collect();
    assert!(
        failures.is_empty(),
        "{target}: {} of {} inputs panicked:\n{}",
        failures.len(),
        files.len(),
        failures.join("\n")
    );
}

#[test]
fn scene_file_corpus_never_panics() {
    replay_all("scene_file", harness::scene_file, 20);
}

#[test]
fn obj_mtl_corpus_never_panics() {
    replay_all("obj_mtl", harness::obj_mtl, 20);
}

#[test]
fn gltf_corpus_never_panics() {
    replay_all("gltf", harness::gltf, 20);
}

#[test]
fn draco_corpus_never_panics() {
    replay_all("draco", harness::draco, 3);
}

#[test]
fn meshopt_corpus_never_panics() {
    replay_all("meshopt", harness::meshopt, 3);
}

/// The decoder targets' seeds, made from the glTF corpus's real files
/// (`tools/gltf_corpus/fuzz_seeds.py`), load as the meshes they came from: a fuzzer that
/// starts from them starts inside the decoders, not at the harness's first error.
#[test]
fn decoder_seeds_load() {
    use meshtrace::scene::load_scene_from;
    for (target, make) in [
        ("draco", harness::draco_glb as fn(&[u8]) -> Option<Vec<u8>>),
        ("meshopt", harness::meshopt_glb),
    ] {
        let seeds: Vec<PathBuf> = corpus(target)
            .into_iter()
            .filter(|p| {
                p.file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with("seed-"))
            })
            .collect();
        assert!(seeds.len() >= 3, "{target}: {} seeds", seeds.len());
        for seed in seeds {
            let data = std::fs::read(&seed).expect("a seed");
            let glb = make(&data).unwrap_or_else(|| panic!("{}: no GLB", seed.display()));
            let files = harness::MemFiles::new(&[("fuzz.glb", &glb)]);
            let scene = load_scene_from(Path::new("fuzz.glb"), &files)
                .unwrap_or_else(|e| panic!("{}: {e}", seed.display()));
            assert!(
                scene.mesh.triangles.len() > 12,
                "{}: {} triangles",
                seed.display(),
                scene.mesh.triangles.len()
            );
        }
    }
}

/// The harness's own plumbing: a panic inside it is reported, not propagated.
#[test]
fn replay_reports_panics() {
    harness::install_panic_hook();
    let err = harness::replay(b"", |_| panic!("boom")).unwrap_err();
    assert!(err.starts_with("boom at "), "{err}");
    assert!(harness::replay(b"", |_| {}).is_ok());
}
