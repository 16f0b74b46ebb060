//! With the `denoise` feature and `OIDN_DIR` set (the folder holding Open Image Denoise's
//! `lib/`, such as the pyoidn wheel's `pyoidn/oidn`), records that `lib/` as an rpath of
//! the binaries and tests, and of the Python extension module (`python/` uses this script
//! too), so they find libOpenImageDenoise without `LD_LIBRARY_PATH`.
//! Otherwise it does nothing.

use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=OIDN_DIR");
    if std::env::var_os("CARGO_FEATURE_DENOISE").is_none() {
        return;
    }
    let Some(dir) = std::env::var_os("OIDN_DIR").filter(|d| !d.is_empty()) else {
        return;
    };
    let lib = PathBuf::from(dir).join("lib");
    // An rpath must be absolute: a relative one would be read from the run's directory.
    let Ok(lib) = lib.canonicalize() else {
        println!(
            "cargo:warning=OIDN_DIR has no lib/ folder ({}); no rpath set",
            lib.display()
        );
        return;
    };
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if os == "linux" || os == "macos" {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", lib.display());
    }
}
