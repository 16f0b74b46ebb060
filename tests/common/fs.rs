//! Files: the checkout's paths, the test fixtures, the shared meshes beside the checkout,
//! and temporary directories.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The checkout's root (where `Cargo.toml` is).
pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A fixture: `tests/data/{name}`.
pub fn data(name: &str) -> PathBuf {
    root().join("tests/data").join(name)
}

/// The `../shared/meshes` folder beside the checkout, if present.
pub fn shared_mesh(name: &str) -> Option<PathBuf> {
    let p = root().join("../shared/meshes").join(name);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipped: {} absent", p.display());
        None
    }
}

/// A fresh, empty directory for one test, `meshtrace-test-{process}-{n}-{name}` in the
/// system's temporary directory (unique per process, call and name); removed with its
/// contents on drop.
pub struct TempDir(PathBuf);

impl TempDir {
    pub fn new(name: &str) -> Self {
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("meshtrace-test-{}-{n}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        Self(dir)
    }

    pub fn path(&self) -> &Path {
        &self.0
    }

    /// The path of `name` in the directory.
    pub fn join(&self, name: impl AsRef<Path>) -> PathBuf {
        self.0.join(name)
    }

    /// Writes `contents` to `name` in the directory; returns its path.
    pub fn write(&self, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
        let p = self.0.join(name);
        std::fs::write(&p, contents).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        p
    }

    /// Writes an 8-bit RGBA PNG of `width` × `height` texels, row by row from the top.
    pub fn write_png(&self, name: &str, width: u32, height: u32, texels: &[[u8; 4]]) -> PathBuf {
        let p = self.0.join(name);
        let data: Vec<u8> = texels.iter().flatten().copied().collect();
        image::RgbaImage::from_raw(width, height, data)
            .expect("width × height texels")
            .save(&p)
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        p
    }

    /// Writes a 32-bit float RGBA EXR of `width` × `height` texels, row by row from the top.
    pub fn write_exr(&self, name: &str, width: u32, height: u32, texels: &[[f32; 4]]) -> PathBuf {
        let p = self.0.join(name);
        let data: Vec<f32> = texels.iter().flatten().copied().collect();
        image::Rgba32FImage::from_raw(width, height, data)
            .expect("width × height texels")
            .save(&p)
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        p
    }

    /// The names in the directory, sorted.
    pub fn entries(&self) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(&self.0)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
