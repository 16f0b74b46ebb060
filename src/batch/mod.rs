//! Batch renders (`meshtrace batch`): a manifest of jobs ([`manifest`]) expanded into one
//! task per (input, view), split into shards for job arrays, each view's camera, and the
//! NeRF-style `transforms.json` of every output folder ([`transforms`]), and the log of the
//! inputs that failed ([`failures`]). No rendering here: the binary runs the tasks.

pub mod failures;
pub mod manifest;
pub mod preset;
pub mod syncdreamer;
pub mod transforms;
pub mod trellis;
pub mod wonder3d;

pub use manifest::{Job, Manifest, Source};

use crate::scene::camera::Camera;
use crate::scene::studio;
use std::path::{Path, PathBuf};

/// Why a batch could not run. Each message is one line naming the file and the field.
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    #[error("{path}: {message}")]
    Io { path: String, message: String },
    #[error("{path}:{line}: {message}")]
    Syntax {
        path: String,
        line: usize,
        message: String,
    },
    #[error("{path}: {field}: {message}")]
    Invalid {
        path: String,
        field: String,
        message: String,
    },
}

/// One image to render: view `view` of `input`, for job `job`, into `output`.
#[derive(Clone, Debug, PartialEq)]
pub struct Task {
    pub job: usize,
    pub input: PathBuf,
    pub view: u32,
    pub output: PathBuf,
}

impl Manifest {
    /// Every task of every job, in a fixed order: jobs in manifest order, a glob's files
    /// sorted by path, views in order. Two tasks writing the same output are an error.
    pub fn tasks(&self) -> Result<Vec<Task>, BatchError> {
        let shown = self.path.display().to_string();
        let mut out = Vec::new();
        for (j, job) in self.jobs.iter().enumerate() {
            let field = |key: &str| format!("jobs[{j}].{key}");
            let inputs = match &job.source {
                // A built-in scene (`builtin:cornell`) is a name, not a path.
                Source::Scene(p) if p.to_string_lossy().starts_with("builtin:") => vec![p.clone()],
                Source::Scene(p) => vec![self.dir.join(p)],
                Source::Meshes(glob) => {
                    self.expand(glob).map_err(|message| BatchError::Invalid {
                        path: shown.clone(),
                        field: field("meshes"),
                        message,
                    })?
                }
            };
            for input in inputs {
                let stem = input
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                let stem = stem.strip_prefix("builtin:").unwrap_or(&stem).to_string();
                let uid = crate::scene::uid(&input);
                for view in 0..job.views {
                    let name = job.preset.as_ref().and_then(|p| p.view_name(view));
                    let output =
                        manifest::output_path(&job.output, &stem, &uid, (view, name.as_deref()), j);
                    out.push(Task {
                        job: j,
                        input: input.clone(),
                        view,
                        output: self.dir.join(output),
                    });
                }
            }
        }
        let mut seen = std::collections::HashMap::new();
        for t in &out {
            if let Some(first) = seen.insert(t.output.clone(), t) {
                return Err(BatchError::Invalid {
                    path: shown,
                    field: format!("jobs[{}].output", t.job),
                    message: format!(
                        "{} would be written by view {} of {} and view {} of {}; put {{stem}} or {{view}} in the pattern",
                        t.output.display(),
                        first.view,
                        first.input.display(),
                        t.view,
                        t.input.display()
                    ),
                });
            }
        }
        Ok(out)
    }

    /// The files a glob matches (relative to the manifest's folder), sorted; an error if
    /// none or if the pattern is malformed.
    fn expand(&self, pattern: &str) -> Result<Vec<PathBuf>, String> {
        let full = if Path::new(pattern).is_absolute() {
            PathBuf::from(pattern)
        } else {
            self.dir.join(pattern)
        };
        let text = full.to_string_lossy();
        let paths = glob::glob(&text).map_err(|e| format!("`{pattern}`: {e}"))?;
        let mut files = Vec::new();
        for p in paths {
            let p = p.map_err(|e| e.to_string())?;
            if p.is_file() {
                files.push(p);
            }
        }
        files.sort();
        if files.is_empty() {
            return Err(format!(
                "`{pattern}` matches no file (in {})",
                display_dir(&self.dir)
            ));
        }
        Ok(files)
    }
}

fn display_dir(dir: &Path) -> String {
    if dir.as_os_str().is_empty() {
        ".".into()
    } else {
        dir.display().to_string()
    }
}

/// The tasks of shard `index` of `count`: the `index`-th of `count` consecutive blocks,
/// whose sizes differ by at most one. Consecutive tasks share an input (the views of a
/// mesh), so each input is loaded by as few shards as possible.
pub fn shard(tasks: &[Task], index: u32, count: u32) -> Vec<Task> {
    let at = |k: u32| (k as u64 * tasks.len() as u64 / count as u64) as usize;
    tasks[at(index)..at(index + 1)].to_vec()
}

/// The camera of view `view` of `job` for a scene whose own camera is `own` and, for a
/// bare mesh, whose studio framing is of `framed`. One view keeps the scene's camera
/// unless the job sets an angle; several go around as [`orbit`] puts them. `None` when the
/// view cannot be framed (a degenerate direction).
pub fn view_camera(
    job: &Job,
    view: u32,
    own: &Camera,
    framed: Option<&crate::math::Aabb>,
) -> Option<Camera> {
    if job.views == 1 && job.elevation.is_none() && job.azimuth.is_none() {
        return Some(own.clone());
    }
    orbit(job.views, view, job.azimuth, job.elevation, own, framed)
}

/// View `view` of `views` evenly spaced in azimuth (degrees, from `azimuth`) at
/// `elevation` (degrees): about a bare mesh framed as `render` frames it (`framed`, its
/// studio framing's bounds, with the studio's angles by default), or about the point the
/// scene's camera `own` looks at, at the same distance, Y up (with that camera's angles by
/// default). `None` when the view cannot be framed (a degenerate direction).
pub fn orbit(
    views: u32,
    view: u32,
    azimuth: Option<f32>,
    elevation: Option<f32>,
    own: &Camera,
    framed: Option<&crate::math::Aabb>,
) -> Option<Camera> {
    let step = 360.0 * view as f32 / views.max(1) as f32;
    match framed {
        Some(bounds) => {
            let azimuth = azimuth.unwrap_or(studio::AZIMUTH) + step;
            let elevation = elevation.unwrap_or(studio::ELEVATION);
            studio::orbit_camera(bounds, azimuth, elevation)
        }
        None => {
            // About the point the scene's camera looks at, at the same distance; Y up.
            let target = own.position + own.forward * own.focus_distance;
            let back = -own.forward;
            let azimuth = azimuth.unwrap_or(back.x.atan2(back.z).to_degrees()) + step;
            let elevation = elevation.unwrap_or(back.y.clamp(-1.0, 1.0).asin().to_degrees());
            let (a, e) = (azimuth.to_radians(), elevation.to_radians());
            let towards = glam::Vec3::new(a.sin() * e.cos(), e.sin(), a.cos() * e.cos());
            Camera::new(
                target + own.focus_distance * towards,
                target,
                glam::Vec3::Y,
                own.vfov,
                own.aperture,
                Some(own.focus_distance),
            )
            .map(|view| Camera {
                ortho_height: own.ortho_height,
                ..view
            })
        }
    }
}
