//! `transforms.json`: the cameras of a folder of images in the NeRF convention that
//! instant-ngp and nerfstudio read: `camera_angle_x` (and the pinhole intrinsics `fl_x`,
//! `fl_y`, `cx`, `cy`, `w`, `h`), then `frames[]`, each a `file_path` relative to the
//! folder and the 4×4 camera-to-world `transform_matrix` with OpenGL camera axes (x right,
//! y up, looking down −z).
//!
//! Several processes (the shards of a job array) may add frames to one folder at once:
//! each takes an exclusive lock on `transforms.json` itself, reads it, adds or replaces its
//! frames (keyed by `file_path`), and writes it to a temporary file renamed into place, so
//! no shard's frames are lost, no reader sees half a file, and no lock file is left.

use super::BatchError;
use crate::scene::camera::Camera;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The name of the file in each output folder.
pub const FILE_NAME: &str = "transforms.json";

/// One image and its camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// The image's path relative to the folder of `transforms.json`.
    pub file_path: String,
    /// Camera to world, rows of a 4×4 matrix.
    pub transform_matrix: [[f32; 4]; 4],
    /// Pinhole intrinsics of the image.
    pub intrinsics: Intrinsics,
}

/// A pinhole camera's intrinsics in pixels, as nerfstudio names them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Intrinsics {
    pub camera_angle_x: f32,
    pub camera_angle_y: f32,
    pub fl_x: f32,
    pub fl_y: f32,
    pub cx: f32,
    pub cy: f32,
    pub w: u32,
    pub h: u32,
}

impl Intrinsics {
    /// The intrinsics of `camera` rendering a `w`×`h` image (square pixels).
    pub fn of(camera: &Camera, w: u32, h: u32) -> Self {
        let half_y = (0.5 * camera.vfov.to_radians()).tan();
        let half_x = half_y * w as f32 / h as f32;
        Self {
            camera_angle_x: 2.0 * half_x.atan(),
            camera_angle_y: 2.0 * half_y.atan(),
            fl_x: 0.5 * w as f32 / half_x,
            fl_y: 0.5 * h as f32 / half_y,
            cx: 0.5 * w as f32,
            cy: 0.5 * h as f32,
            w,
            h,
        }
    }
}

/// The file as serde reads and writes it: intrinsics at the top level (those of the first
/// frame), and in a frame only where they differ.
#[derive(Serialize, Deserialize)]
struct Document {
    #[serde(flatten)]
    intrinsics: Option<Intrinsics>,
    frames: Vec<FrameEntry>,
}

#[derive(Serialize, Deserialize)]
struct FrameEntry {
    file_path: String,
    transform_matrix: [[f32; 4]; 4],
    #[serde(flatten)]
    intrinsics: Option<Intrinsics>,
}

/// The camera-to-world matrix of `camera` with OpenGL camera axes: columns right, up,
/// backwards (−forward) and the position.
pub fn camera_to_world(camera: &Camera) -> [[f32; 4]; 4] {
    let (r, u, b, p) = (camera.right, camera.up, -camera.forward, camera.position);
    [
        [r.x, u.x, b.x, p.x],
        [r.y, u.y, b.y, p.y],
        [r.z, u.z, b.z, p.z],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// Adds `frames` to the `transforms.json` of folder `dir` (creating it), replacing frames
/// of the same `file_path`, under the file's lock ([`lock_file`]). The top level takes the intrinsics of
/// the first frame (by path); a frame whose intrinsics differ carries its own, as
/// nerfstudio allows. Returns how many frames already in the file were rewritten with
/// them: the part of the work that grows with the folder rather than with `frames`.
pub fn record(dir: &Path, frames: &[Frame]) -> Result<usize, BatchError> {
    if frames.is_empty() {
        return Ok(0);
    }
    let path = dir.join(FILE_NAME);
    let io = |p: &Path, e: &dyn std::fmt::Display| BatchError::Io {
        path: p.display().to_string(),
        message: e.to_string(),
    };
    let lock = lock_file(&path).map_err(|e| io(&path, &e))?;
    let mut all = match std::fs::read(&path) {
        Ok(bytes) if bytes.is_empty() => Vec::new(),
        Ok(bytes) => read(&bytes).map_err(|m| io(&path, &m))?,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
        Err(e) => return Err(io(&path, &e)),
    };
    let earlier = all.len();
    let mut at: std::collections::HashMap<String, usize> = all
        .iter()
        .enumerate()
        .map(|(i, f)| (f.file_path.clone(), i))
        .collect();
    for f in frames {
        match at.get(&f.file_path) {
            Some(&i) => all[i] = f.clone(),
            None => {
                at.insert(f.file_path.clone(), all.len());
                all.push(f.clone());
            }
        }
    }
    all.sort_by(|a, b| a.file_path.cmp(&b.file_path));
    let top = all.first().map(|f| f.intrinsics);
    let document = Document {
        intrinsics: top,
        frames: all
            .into_iter()
            .map(|f| FrameEntry {
                intrinsics: (Some(f.intrinsics) != top).then_some(f.intrinsics),
                file_path: f.file_path,
                transform_matrix: f.transform_matrix,
            })
            .collect(),
    };
    let mut bytes = serde_json::to_vec_pretty(&document).map_err(|e| io(&path, &e))?;
    bytes.push(b'\n');
    crate::film::write_bytes(&path, &bytes).map_err(|e| io(&path, &e))?;
    drop(lock);
    Ok(earlier)
}

/// An exclusive lock on the file at `path` (created empty if missing), held until the
/// returned handle drops. The file is replaced by renaming a new one over it, so a process
/// that waited on the lock of the file it opened may hold a file no longer at `path`: it
/// opens and locks again until the two are the same file. No lock file is left beside it.
fn lock_file(path: &Path) -> std::io::Result<std::fs::File> {
    loop {
        let file = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .read(true)
            .write(true)
            .open(path)?;
        file.lock()?;
        if still_at(&file, path)? {
            return Ok(file);
        }
    }
}

/// Whether the open `file` is still the one at `path`.
#[cfg(unix)]
fn still_at(file: &std::fs::File, path: &Path) -> std::io::Result<bool> {
    use std::os::unix::fs::MetadataExt;
    let (a, b) = (file.metadata()?, std::fs::metadata(path));
    Ok(b.is_ok_and(|b| a.dev() == b.dev() && a.ino() == b.ino()))
}

/// Whether the open `file` is still the one at `path` (elsewhere a file open here cannot
/// be renamed over).
#[cfg(not(unix))]
fn still_at(_file: &std::fs::File, path: &Path) -> std::io::Result<bool> {
    Ok(path.exists())
}

/// The `file_path`s the `transforms.json` of folder `dir` has frames for (none where it is
/// missing or unreadable).
pub fn recorded(dir: &Path) -> std::collections::HashSet<String> {
    std::fs::read(dir.join(FILE_NAME))
        .ok()
        .and_then(|bytes| read(&bytes).ok())
        .map(|frames| frames.into_iter().map(|f| f.file_path).collect())
        .unwrap_or_default()
}

/// The frames of a file written by [`record`], each with its intrinsics.
fn read(bytes: &[u8]) -> Result<Vec<Frame>, String> {
    let doc: Document =
        serde_json::from_slice(bytes).map_err(|e| format!("not a transforms.json: {e}"))?;
    doc.frames
        .into_iter()
        .map(|f| {
            let intrinsics = f.intrinsics.or(doc.intrinsics).ok_or_else(|| {
                format!(
                    "frame {} has no camera_angle_x, fl_x, … and neither has the file",
                    f.file_path
                )
            })?;
            Ok(Frame {
                file_path: f.file_path,
                transform_matrix: f.transform_matrix,
                intrinsics,
            })
        })
        .collect()
}
