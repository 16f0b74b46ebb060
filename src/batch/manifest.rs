//! The batch manifest (TOML): render settings for every job, then jobs, each a glob of
//! meshes or one scene file, a number of turntable views and an output pattern. Every
//! error names the manifest and the field (`jobs[1].output`) or line.

use super::BatchError;
use crate::request::RenderRequest;
use crate::scene::studio::Up;
use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ManifestFile {
    /// Seconds one input may take, loading and every view.
    time_limit: Option<f64>,
    render: Option<RenderRequest>,
    jobs: Option<Vec<JobFile>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct JobFile {
    meshes: Option<String>,
    scene: Option<String>,
    views: Option<u32>,
    elevation: Option<f32>,
    azimuth: Option<f32>,
    up: Option<String>,
    output: Option<String>,
}

/// What a job renders.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// Every file the glob matches (absolute, or relative to the manifest), as bare meshes.
    Meshes(String),
    /// One scene file (or a bare mesh), relative to the manifest.
    Scene(PathBuf),
}

/// One `[[jobs]]` entry.
#[derive(Clone, Debug, PartialEq)]
pub struct Job {
    pub source: Source,
    /// Turntable views: cameras evenly spaced in azimuth around the mesh. With 1 (the
    /// default), a bare mesh is seen as `render` shows it and a scene through its camera.
    pub views: u32,
    /// Degrees above the horizontal (bare meshes: the studio's 22 by default; scenes: their
    /// camera's).
    pub elevation: Option<f32>,
    /// Degrees from +Z towards +X of view 0 (bare meshes: the studio's 35 by default;
    /// scenes: their camera's).
    pub azimuth: Option<f32>,
    /// The up axis of the meshes, as `render --up`; by default detected as `render` does.
    pub up: Option<Up>,
    /// The output path pattern, relative to the manifest: `{stem}` (the input's file
    /// name without extension), `{view}` (0 to views − 1) and `{job}` (the job's index).
    pub output: String,
}

/// A parsed and checked manifest.
#[derive(Clone, Debug, PartialEq)]
pub struct Manifest {
    /// The manifest file, for messages.
    pub path: PathBuf,
    /// Its folder: relative paths start here.
    pub dir: PathBuf,
    /// The `[render]` table: what every image asks for beyond its input (relative paths
    /// in it resolved against the manifest's folder).
    pub request: RenderRequest,
    pub jobs: Vec<Job>,
    /// The most time one input may take, loading and every view (`time_limit`, seconds):
    /// one over it fails, and the batch goes on.
    pub time_limit: Option<std::time::Duration>,
}

/// The placeholders an output pattern may use.
const PLACEHOLDERS: [&str; 3] = ["stem", "view", "job"];

impl Manifest {
    /// Reads and checks the manifest at `path`.
    pub fn load(path: &Path) -> Result<Self, BatchError> {
        let text = std::fs::read_to_string(path).map_err(|e| BatchError::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        Self::parse(path, &text)
    }

    /// Parses and checks manifest text read from `path`.
    pub fn parse(path: &Path, text: &str) -> Result<Self, BatchError> {
        let shown = path.display().to_string();
        let invalid = |field: String, message: String| BatchError::Invalid {
            path: shown.clone(),
            field,
            message,
        };
        let file: ManifestFile = toml::from_str(text).map_err(|e| {
            let offset = e.span().map_or(0, |s| s.start).min(text.len());
            BatchError::Syntax {
                path: shown.clone(),
                line: text[..offset].matches('\n').count() + 1,
                message: e.message().replace(['\n', '\r'], " ").trim().to_string(),
            }
        })?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut request = file.render.unwrap_or_default();
        if let Some(env) = &request.environment {
            request.environment = Some(dir.join(env));
        }
        request
            .validate()
            .map_err(|e| invalid(format!("render.{}", e.field), e.message))?;
        let time_limit = match file.time_limit {
            None => None,
            Some(t) if t.is_finite() && t > 0.0 => Some(std::time::Duration::from_secs_f64(t)),
            Some(t) => {
                return Err(invalid(
                    "time_limit".into(),
                    format!("must be a positive number of seconds, got {t}"),
                ));
            }
        };
        let jobs = file.jobs.unwrap_or_default();
        if jobs.is_empty() {
            return Err(invalid(
                "jobs".into(),
                "no [[jobs]]: add at least one, with meshes = \"GLOB\" or scene = \"FILE\" and output = \"PATTERN\"".into(),
            ));
        }
        let mut out = Vec::new();
        for (i, j) in jobs.into_iter().enumerate() {
            let field = |key: &str| format!("jobs[{i}].{key}");
            let source = match (j.meshes, j.scene) {
                (Some(glob), None) => Source::Meshes(glob),
                (None, Some(scene)) => Source::Scene(PathBuf::from(scene)),
                (Some(_), Some(_)) => {
                    return Err(invalid(
                        field("scene"),
                        "give meshes or scene, not both".into(),
                    ));
                }
                (None, None) => {
                    return Err(invalid(
                        field("meshes"),
                        "missing: give meshes = \"GLOB\" or scene = \"FILE\"".into(),
                    ));
                }
            };
            let views = j.views.unwrap_or(1);
            if views == 0 {
                return Err(invalid(field("views"), "must be at least 1".into()));
            }
            if let Some(e) = j.elevation
                && !(e.is_finite() && e.abs() < 90.0)
            {
                return Err(invalid(
                    field("elevation"),
                    format!("{e} degrees: must be strictly between -90 and 90"),
                ));
            }
            if let Some(a) = j.azimuth
                && !a.is_finite()
            {
                return Err(invalid(field("azimuth"), "must be finite".into()));
            }
            let up = match j.up.as_deref() {
                None => None,
                Some("x") => Some(Up::X),
                Some("y") => Some(Up::Y),
                Some("z") => Some(Up::Z),
                Some(other) => {
                    return Err(invalid(field("up"), format!("`{other}`: use x, y or z")));
                }
            };
            let output = j.output.ok_or_else(|| {
                invalid(
                    field("output"),
                    "missing: give the output path pattern, such as \"out/{stem}_{view}.png\""
                        .into(),
                )
            })?;
            check_pattern(&output, views).map_err(|m| invalid(field("output"), m))?;
            let format = crate::film::Format::from_path(Path::new(&output))
                .map_err(|e| invalid(field("output"), e.to_string()))?;
            if request.transparent() && format != crate::film::Format::Png {
                return Err(invalid(
                    field("output"),
                    "render.transparent writes RGBA PNGs (alpha is the coverage); give a .png pattern".into(),
                ));
            }
            if request.bit_depth() == crate::film::BitDepth::Sixteen
                && format != crate::film::Format::Png
            {
                return Err(invalid(
                    field("output"),
                    "render.bit_depth = 16 writes 16-bit PNGs; give a .png pattern".into(),
                ));
            }
            out.push(Job {
                source,
                views,
                elevation: j.elevation,
                azimuth: j.azimuth,
                up,
                output,
            });
        }
        Ok(Self {
            dir,
            path: path.to_path_buf(),
            request,
            jobs: out,
            time_limit,
        })
    }
}

/// An output pattern's placeholders must be known, and a job of several views must
/// use `{view}` (else every view would write the same file).
fn check_pattern(pattern: &str, views: u32) -> Result<(), String> {
    let mut rest = pattern;
    while let Some(open) = rest.find('{') {
        let close = rest[open..]
            .find('}')
            .ok_or_else(|| format!("`{pattern}`: a `{{` without its `}}`"))?;
        let name = &rest[open + 1..open + close];
        if !PLACEHOLDERS.contains(&name) {
            return Err(format!(
                "`{pattern}`: unknown placeholder {{{name}}}; there are {{stem}}, {{view}} and {{job}}"
            ));
        }
        rest = &rest[open + close + 1..];
    }
    if views > 1 && !pattern.contains("{view}") {
        return Err(format!(
            "`{pattern}` has no {{view}}, so its {views} views would overwrite each other"
        ));
    }
    Ok(())
}

/// The output path of view `view` of input `stem` in job `job`.
pub fn output_path(pattern: &str, stem: &str, view: u32, job: usize) -> String {
    pattern
        .replace("{stem}", stem)
        .replace("{view}", &view.to_string())
        .replace("{job}", &job.to_string())
}
