//! The batch manifest (TOML): render settings for every job, then jobs, each a glob of
//! meshes or one scene file, a number of turntable views and an output pattern. Every
//! error names the manifest and the field (`jobs[1].output`) or line.

use super::BatchError;
use super::preset::{Layout, Poses, Preset};
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
    preset: Option<String>,
    views: Option<u32>,
    elevation: Option<f32>,
    azimuth: Option<f32>,
    distance: Option<f32>,
    /// A shell layout's radii, [min, max].
    radius: Option<[f32; 2]>,
    /// A shell layout's cameras above the object's horizontal plane only.
    only_northern_hemisphere: Option<bool>,
    /// Wonder3D's rig turned at random per render (its `--random_pose`).
    random_pose: Option<bool>,
    /// SyncDreamer's `--camera_type`: `fixed` (the ring) or `random` (each view at its own
    /// elevation, and `meta.pkl`).
    camera_type: Option<String>,
    /// A random ring's elevations, [min, max] degrees (SyncDreamer's `--elevation_start`
    /// and `--elevation_end`).
    elevation_range: Option<[f32; 2]>,
    /// An orthographic preset's view width in normalised units (Blender's `ortho_scale`).
    ortho_scale: Option<f32>,
    /// TRELLIS's `--save_depth`, `--save_normal`, `--save_albedo` and `--save_mist`: each
    /// view's passes beside its image.
    save_depth: Option<bool>,
    save_normal: Option<bool>,
    save_albedo: Option<bool>,
    save_mist: Option<bool>,
    fov: Option<f32>,
    up: Option<String>,
    output: Option<String>,
}

impl JobFile {
    /// TRELLIS's pass flags by manifest key, as given.
    fn passes(&self) -> [(&'static str, Option<bool>); 4] {
        [
            ("save_depth", self.save_depth),
            ("save_normal", self.save_normal),
            ("save_albedo", self.save_albedo),
            ("save_mist", self.save_mist),
        ]
    }
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
    /// name without extension), `{uid}` (its file name up to the first dot, as the
    /// dataset scripts name their folders; `{uid:2}` its first two characters), `{view}`
    /// (0 to views − 1; `{view:03}` pads it to three digits), `{name}` (a preset's name of
    /// the view, where its script names them: `000_front`) and `{job}` (the job's index).
    pub output: String,
    /// A dataset script's way of rendering (`preset = "objaverse"`), its parameters
    /// overridden by the job's `views`, `elevation`, `distance` and `fov`.
    pub preset: Option<Preset>,
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

/// The placeholders an output pattern may use (and `view:0N`, the view padded to N digits).
const PLACEHOLDERS: [&str; 6] = ["stem", "uid", "uid:2", "view", "name", "job"];

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
        request.lighting = request.lighting.map(|l| l.relative_to(&dir));
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
            let passes = j.passes();
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
            let preset = match &j.preset {
                None => None,
                Some(name) => {
                    if !matches!(source, Source::Meshes(_)) {
                        return Err(invalid(
                            field("preset"),
                            "renders meshes as a dataset script does: give meshes = \"GLOB\""
                                .into(),
                        ));
                    }
                    let mut p = Preset::named(name).map_err(|m| invalid(field("preset"), m))?;
                    if let Some(v) = j.views {
                        p.views = v;
                    }
                    match j.camera_type.as_deref() {
                        None | Some("fixed") if p.name == "syncdreamer" => {}
                        Some("random") if p.name == "syncdreamer" => {
                            p.layout = Layout::RandomRing {
                                min: -10.0,
                                max: 40.0,
                            };
                            p.poses = Poses::MetaPkl;
                        }
                        Some(other) if p.name == "syncdreamer" => {
                            return Err(invalid(
                                field("camera_type"),
                                format!(
                                    "`{other}`: use \"fixed\" or \"random\", as SyncDreamer's script"
                                ),
                            ));
                        }
                        Some(_) => {
                            return Err(invalid(
                                field("camera_type"),
                                format!(
                                    "is SyncDreamer's `--camera_type`, which the `{name}` script does not take"
                                ),
                            ));
                        }
                        None => {}
                    }
                    for (key, given) in [
                        ("elevation", j.elevation.is_some()),
                        ("distance", j.distance.is_some()),
                        ("radius", j.radius.is_some()),
                        (
                            "only_northern_hemisphere",
                            j.only_northern_hemisphere.is_some(),
                        ),
                        ("random_pose", j.random_pose.is_some()),
                        ("ortho_scale", j.ortho_scale.is_some()),
                        ("elevation_range", j.elevation_range.is_some()),
                    ] {
                        if given && !p.layout.takes(key) {
                            return Err(invalid(
                                field(key),
                                format!(
                                    "is not a camera parameter of `{name}`, whose are {}",
                                    p.layout.keys()
                                ),
                            ));
                        }
                    }
                    if let Layout::Shell {
                        radius_min,
                        radius_max,
                        north_only,
                    } = &mut p.layout
                    {
                        if let Some([lo, hi]) = j.radius {
                            if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo <= hi) {
                                return Err(invalid(
                                    field("radius"),
                                    format!("[{lo}, {hi}]: must be 0 < min <= max"),
                                ));
                            }
                            (*radius_min, *radius_max) = (lo, hi);
                        }
                        if let Some(north) = j.only_northern_hemisphere {
                            *north_only = north;
                        }
                    }
                    if let (Layout::Rig { random }, Some(given)) = (&mut p.layout, j.random_pose) {
                        *random = given;
                    }
                    if let (Layout::RandomRing { min, max }, Some([lo, hi])) =
                        (&mut p.layout, j.elevation_range)
                    {
                        if !(lo.is_finite()
                            && hi.is_finite()
                            && -90.0 < lo
                            && lo <= hi
                            && hi < 90.0)
                        {
                            return Err(invalid(
                                field("elevation_range"),
                                format!("[{lo}, {hi}]: must be -90 < min <= max < 90 degrees"),
                            ));
                        }
                        (*min, *max) = (lo, hi);
                    }
                    for (key, given) in passes {
                        let Some(save) = given else { continue };
                        match p.passes.flag(key) {
                            Some(flag) if p.poses == Poses::Transforms => *flag = save,
                            _ => {
                                return Err(invalid(
                                    field(key),
                                    format!(
                                        "is TRELLIS's `--{key}`, which the `{name}` script does not take"
                                    ),
                                ));
                            }
                        }
                    }
                    if let Some(e) = j.elevation {
                        p.elevation = e;
                    }
                    for (key, value, slot) in [
                        ("distance", j.distance, &mut p.distance),
                        ("fov", j.fov, &mut p.fov),
                        ("ortho_scale", j.ortho_scale, &mut p.ortho_scale),
                    ] {
                        if let Some(v) = value {
                            let fine = v.is_finite() && v > 0.0 && (key != "fov" || v < 180.0);
                            if !fine {
                                return Err(invalid(
                                    field(key),
                                    format!(
                                        "{v}: must be positive (and a field of view below 180 degrees)"
                                    ),
                                ));
                            }
                            *slot = v;
                        }
                    }
                    if j.azimuth.is_some() {
                        return Err(invalid(
                            field("azimuth"),
                            "a preset's cameras follow its script; give elevation, distance, fov or views".into(),
                        ));
                    }
                    Some(p)
                }
            };
            if preset.is_none()
                && let Some((key, _)) = passes.into_iter().find(|(_, g)| g.is_some())
            {
                return Err(invalid(
                    field(key),
                    format!("is TRELLIS's `--{key}`; add preset = \"trellis\""),
                ));
            }
            if preset.is_none() {
                for (key, given) in [
                    ("distance", j.distance.is_some()),
                    ("fov", j.fov.is_some()),
                    ("radius", j.radius.is_some()),
                    (
                        "only_northern_hemisphere",
                        j.only_northern_hemisphere.is_some(),
                    ),
                    ("random_pose", j.random_pose.is_some()),
                    ("ortho_scale", j.ortho_scale.is_some()),
                    ("camera_type", j.camera_type.is_some()),
                    ("elevation_range", j.elevation_range.is_some()),
                ] {
                    if given {
                        return Err(invalid(
                            field(key),
                            "applies to a preset's cameras; add preset = \"...\"".into(),
                        ));
                    }
                }
            }
            let views = j.views.unwrap_or(preset.as_ref().map_or(1, |p| p.views));
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
            let output = j
                .output
                .or_else(|| preset.as_ref().map(|p| p.output().to_string()))
                .ok_or_else(|| {
                    invalid(
                        field("output"),
                        "missing: give the output path pattern, such as \"out/{stem}_{view}.png\""
                            .into(),
                    )
                })?;
            let named = preset.as_ref().is_some_and(|p| p.view_name(0).is_some());
            check_pattern(&output, views, named).map_err(|m| invalid(field("output"), m))?;
            let format = crate::film::Format::from_path(Path::new(&output))
                .map_err(|e| invalid(field("output"), e.to_string()))?;
            if (request.transparent() || preset.is_some()) && !format.has_alpha() {
                return Err(invalid(
                    field("output"),
                    "a preset or render.transparent writes RGBA images (alpha is the coverage or the mask); give a .png or .webp pattern".into(),
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
            if request.view_transform() != crate::film::ViewTransform::Standard
                && matches!(format, crate::film::Format::Exr | crate::film::Format::Hdr)
            {
                return Err(invalid(
                    field("output"),
                    "render.view_transform forms 8- and 16-bit images; give a .png or .webp pattern".into(),
                ));
            }
            out.push(Job {
                source,
                views,
                elevation: j.elevation,
                azimuth: j.azimuth,
                up,
                output,
                preset,
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

/// An output pattern's placeholders must be known (`{name}` only where the views have
/// names: `named`), and a job of several views must use `{view}` or `{name}` (else every
/// view would write the same file).
fn check_pattern(pattern: &str, views: u32, named: bool) -> Result<(), String> {
    let mut rest = pattern;
    while let Some(open) = rest.find('{') {
        let close = rest[open..]
            .find('}')
            .ok_or_else(|| format!("`{pattern}`: a `{{` without its `}}`"))?;
        let name = &rest[open + 1..open + close];
        if !PLACEHOLDERS.contains(&name) && padding(name).is_none() {
            return Err(format!(
                "`{pattern}`: unknown placeholder {{{name}}}; there are {{stem}}, {{uid}} (or {{uid:2}}, its first two characters), {{view}} (or {{view:03}}, padded), {{name}} and {{job}}"
            ));
        }
        if name == "name" && !named {
            return Err(format!(
                "`{pattern}`: {{name}} is a named view of a preset that names them (wonder3d); use {{view}}"
            ));
        }
        rest = &rest[open + close + 1..];
    }
    if views > 1 && !pattern.contains("{view") && !pattern.contains("{name}") {
        return Err(format!(
            "`{pattern}` has no {{view}}, so its {views} views would overwrite each other"
        ));
    }
    Ok(())
}

/// The width N of a `view:0N` placeholder (1 to 9).
fn padding(name: &str) -> Option<usize> {
    let n = name.strip_prefix("view:0")?;
    let n: usize = n.parse().ok()?;
    (1..=9).contains(&n).then_some(n)
}

/// The output path of view `view` (named `name` where the preset names its views) of
/// input `stem` (`uid`: its file name up to the first dot) in job `job`.
pub fn output_path(
    pattern: &str,
    stem: &str,
    uid: &str,
    (view, name): (u32, Option<&str>),
    job: usize,
) -> String {
    let prefix: String = uid.chars().take(2).collect();
    let mut out = pattern
        .replace("{stem}", stem)
        .replace("{uid}", uid)
        .replace("{uid:2}", &prefix)
        .replace("{name}", name.unwrap_or_default())
        .replace("{view}", &view.to_string())
        .replace("{job}", &job.to_string());
    for n in 1..=9 {
        out = out.replace(&format!("{{view:0{n}}}"), &format!("{view:0n$}"));
    }
    out
}
