//! Where scene files, meshes and images are read from: the file system, or the files built
//! into the binary ([`super::builtin`]), behind one trait so that every loader reads both.

use std::path::Path;

/// Where scene files and meshes are read from: the file system, or the scenes built in.
pub trait FileSource {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>>;
}

/// The file system.
pub struct Fs;

impl FileSource for Fs {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        std::fs::read(path)
    }
}
