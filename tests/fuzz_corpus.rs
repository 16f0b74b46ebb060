//! Replays the fuzz corpora (`fuzz/corpus/{scene_file,obj_mtl,gltf}`) through the fuzz targets'
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

/// The harness's own plumbing: a panic inside it is reported, not propagated.
#[test]
fn replay_reports_panics() {
    harness::install_panic_hook();
    let err = harness::replay(b"", |_| panic!("boom")).unwrap_err();
    assert!(err.starts_with("boom at "), "{err}");
    assert!(harness::replay(b"", |_| {}).is_ok());
}
