//! Every glTF file the tests read as a third-party writer's output passes Khronos'
//! glTF-Validator with no errors: the corpus (`tests/data/gltf/corpus`) and the WebP and
//! KTX2 samples. Needs Node.js and the npm package `gltf-validator` (2.0.0-dev.3.10), found where
//! MESHTRACE_GLTF_VALIDATOR says (.ci/run installs it); skipped without them unless
//! MESHTRACE_REQUIRE_GLTF_VALIDATOR=1.

use crate::common;

use common::fs::{data, root};
use std::process::Command;

#[test]
fn third_party_files_pass_gltf_validator() {
    let required = std::env::var("MESHTRACE_REQUIRE_GLTF_VALIDATOR").as_deref() == Ok("1");
    let Ok(validator) = std::env::var("MESHTRACE_GLTF_VALIDATOR") else {
        assert!(
            !required,
            "MESHTRACE_REQUIRE_GLTF_VALIDATOR=1 but MESHTRACE_GLTF_VALIDATOR is unset"
        );
        eprintln!(
            "third_party_files_pass_gltf_validator: skipped: MESHTRACE_GLTF_VALIDATOR is unset"
        );
        return;
    };
    let mut files: Vec<_> = std::fs::read_dir(data("gltf/corpus"))
        .expect("the corpus folder")
        .map(|e| e.expect("an entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "glb" || e == "gltf"))
        .collect();
    files.sort();
    files.push(data("gltf/BoxTexturedWebp/BoxTexturedWebp.glb"));
    files.push(data("gltf/BoxTexturedBasisu/BoxTexturedEtc1s.glb"));
    files.push(data("gltf/BoxTexturedBasisu/BoxTexturedUastc.glb"));
    assert!(files.len() >= 12, "{} files", files.len());
    let out = Command::new("node")
        .arg(root().join("tools/gltf_corpus/validate.mjs"))
        .args(&files)
        .env("MESHTRACE_GLTF_VALIDATOR", &validator)
        .output()
        .expect("node runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "glTF-Validator found errors:\n{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(text.matches(": 0 errors").count(), files.len(), "{text}");
}
