//! Running the binary in a test's folder: its output, its exit code and stderr, and the
//! checks every failure must pass.

use super::fs::TempDir;
use std::process::Command;

/// Runs `meshtrace args...` in `dir`; returns its output.
pub fn output(dir: &TempDir, args: &[&str]) -> std::process::Output {
    output_with(dir, args, &[])
}

/// [`output`] with the environment variables `vars` set.
pub fn output_with(
    dir: &TempDir,
    args: &[&str],
    vars: &[(&str, &std::path::Path)],
) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_meshtrace"))
        .args(args)
        .current_dir(dir.path())
        .env("NODEVICE_SELECT", "1")
        .envs(vars.iter().copied())
        .output()
        .unwrap()
}

/// Runs `meshtrace args...` in `dir`; returns (exit code, stderr).
pub fn run(dir: &TempDir, args: &[&str]) -> (i32, String) {
    let out = output(dir, args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    (out.status.code().unwrap_or(-1), stderr)
}

/// Asserts a failed run: exit 1, one `error:` line containing every `needle`, no panic, and
/// nothing left in the folder but the inputs.
pub fn assert_fails(dir: &TempDir, args: &[&str], needles: &[&str]) {
    let before = dir.entries();
    let (code, stderr) = run(dir, args);
    let ctx = format!(
        "meshtrace {args:?} in {}: exit {code}, stderr:\n{stderr}\nfiles: {:?}",
        dir.path().display(),
        dir.entries()
    );
    assert_eq!(code, 1, "{ctx}");
    assert!(!stderr.contains("panicked"), "{ctx}");
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "{ctx}");
    for n in needles {
        assert!(errors[0].contains(n), "missing `{n}`: {ctx}");
    }
    // A cause is said once, even when the error's own message already quotes it.
    let parts: Vec<&str> = errors[0].split(": ").collect();
    assert!(
        parts.windows(2).all(|w| w[0] != w[1]),
        "repeated cause: {ctx}"
    );
    assert_eq!(dir.entries(), before, "{ctx}");
}
