//! The Kubernetes manifests of `deploy/k8s/`, offline: every file validates strictly against
//! the Kubernetes schema (`kubernetes-validate --strict`, from PyPI), and each Indexed Job
//! says `completionMode: Indexed`, with the count in its `auto/N` equal to its completions
//! (the schema checks neither). Skipped, saying so, without kubernetes-validate, unless
//! `MESHTRACE_REQUIRE_K8S_VALIDATE=1` (as CI sets it).

use crate::common;

use common::fs::root;
use std::process::Command;

fn manifests() -> Vec<std::path::PathBuf> {
    let mut out: Vec<_> = std::fs::read_dir(root().join("deploy/k8s"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .collect();
    out.sort();
    out
}

#[test]
fn kubernetes_manifests_validate_strictly() {
    let files = manifests();
    assert!(files.len() >= 4, "{files:?}");
    let required = std::env::var("MESHTRACE_REQUIRE_K8S_VALIDATE").is_ok_and(|v| v == "1");
    let out = match Command::new("kubernetes-validate")
        .arg("--strict")
        .args(&files)
        .output()
    {
        Ok(out) => out,
        Err(e) => {
            assert!(
                !required,
                "MESHTRACE_REQUIRE_K8S_VALIDATE=1 but kubernetes-validate: {e}"
            );
            eprintln!(
                "skipped: kubernetes-validate not installed (pip install kubernetes-validate)"
            );
            return;
        }
    };
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{said}");
    assert_eq!(said.matches("passed").count(), files.len(), "{said}");
}

/// The value of the first `key: value` line of `text`.
fn value<'a>(text: &'a str, key: &str) -> Option<&'a str> {
    text.lines()
        .find_map(|l| l.trim().strip_prefix(&format!("{key}:")))
        .map(str::trim)
}

#[test]
fn indexed_jobs_are_indexed_and_count_their_completions() {
    let mut indexed = 0;
    for path in manifests() {
        let text = std::fs::read_to_string(&path).unwrap();
        let name = path.display();
        let Some(n) = text.split("auto/").nth(1).map(|rest| {
            rest.chars()
                .take_while(char::is_ascii_digit)
                .collect::<String>()
        }) else {
            continue;
        };
        indexed += 1;
        assert_eq!(value(&text, "kind"), Some("Job"), "{name}");
        assert_eq!(value(&text, "completionMode"), Some("Indexed"), "{name}");
        assert_eq!(
            value(&text, "completions"),
            Some(n.as_str()),
            "{name}: auto/{n}"
        );
    }
    assert_eq!(indexed, 2, "the parts and batch Indexed Jobs");
}
