//! Wavefront OBJ and MTL files, read through tobj and mapped onto meshtrace materials.

use super::{Material, MaterialKind, SceneError};
use glam::Vec3;
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

/// One OBJ file's geometry in its own space, with its materials already mapped.
#[derive(Debug, Default)]
pub struct ObjMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// Position indices, normal indices (or `NO_NORMAL`) and an index into `materials`
    /// (or `None` for faces that name no material).
    pub triangles: Vec<([u32; 3], [u32; 3], Option<u32>)>,
    pub materials: Vec<Material>,
    pub warnings: Vec<String>,
}

/// Reads an OBJ file, fan-triangulating polygons, and maps its MTL materials.
pub fn load_obj(path: &Path, files: &dyn FileSource) -> Result<ObjMesh, SceneError> {
    let shown = super::shown(path);
    let err = |message: String| SceneError::Obj {
        path: shown.clone(),
        line: None,
        message,
    };
    let bytes = files.read(path).map_err(|source| SceneError::Io {
        path: shown.clone(),
        source,
    })?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut out = ObjMesh::default();
    // tobj reports an unreadable library only when no library at all could be read, so
    // every failure is noted here as it happens.
    let failed_mtl = std::cell::RefCell::new(Vec::new());
    // tobj 4 panics on some malformed lines (a one-number `Kd`); that is bad input, not a
    // bug of ours, so it becomes an error naming the file.
    let parsed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        tobj::load_obj_buf(&mut bytes.as_slice(), &options, |mtl| {
            let result = files
                .read(&dir.join(mtl))
                .map_err(|_| tobj::LoadError::OpenFileFailed)
                .and_then(|b| tobj::load_mtl_buf(&mut b.as_slice()));
            if let Err(e) = &result {
                failed_mtl.borrow_mut().push(format!(
                    "{} ({})",
                    dir.join(mtl).display(),
                    describe_tobj_error(e)
                ));
            }
            result
        })
    }))
    .map_err(|_| err("malformed OBJ or MTL data (the parser rejected a line)".into()))?;
    let (models, materials) = parsed.map_err(|e| err(describe_tobj_error(&e)))?;
    let failed_mtl = failed_mtl.into_inner();
    let failed_mtl_count = failed_mtl.len();
    for lib in failed_mtl {
        out.warnings.push(format!(
            "{shown}: material library {lib} could not be read; its materials fall back to the default"
        ));
    }
    if let Ok(mtls) = materials {
        out.materials = mtls.iter().map(map_mtl).collect();
    }
    let scan = scan_obj(&bytes);
    let names: Vec<&str> = out.materials.iter().map(|m| m.name.as_str()).collect();
    if failed_mtl_count == 0 {
        for (line, name) in &scan.usemtl {
            if !names.contains(&name.as_str()) {
                out.warnings.push(format!(
                    "{shown}:{line}: unknown material `{name}`; its faces use the default material"
                ));
            }
        }
    }
    // Which triangles came from faces with normals, in file order (tobj keeps that order
    // and fans each polygon into `corners - 2` triangles); tobj itself fills a missing
    // `vn` with a neighbour's, which would smooth-shade a face that asked to be flat.
    let total: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
    let tri_has_normal: Option<Vec<bool>> =
        (scan.faces.iter().map(|f| f.0).sum::<usize>() == total).then(|| {
            scan.faces
                .iter()
                .flat_map(|&(n, has)| std::iter::repeat_n(has, n))
                .collect()
        });
    let mut tri_index = 0usize;
    for model in &models {
        let m = &model.mesh;
        let base_p = out.positions.len() as u32;
        let base_n = out.normals.len() as u32;
        for (i, p) in m.positions.chunks_exact(3).enumerate() {
            let v = Vec3::new(p[0], p[1], p[2]);
            if !v.is_finite() {
                return Err(err(format!(
                    "object `{}`: vertex {} has a non-finite coordinate {v}",
                    model.name,
                    i + 1
                )));
            }
            out.positions.push(v);
        }
        for n in m.normals.chunks_exact(3) {
            out.normals.push(Vec3::new(n[0], n[1], n[2]));
        }
        let material = match m.material_id {
            Some(id) if id < out.materials.len() => Some(id as u32),
            Some(_) => None,
            None => None,
        };
        let has_normals = m.normal_indices.len() == m.indices.len() && !m.normals.is_empty();
        for (f, tri) in m.indices.chunks_exact(3).enumerate() {
            let p = [tri[0] + base_p, tri[1] + base_p, tri[2] + base_p];
            let face_has_normals = tri_has_normal.as_ref().is_none_or(|v| v[tri_index]);
            tri_index += 1;
            let n = if has_normals && face_has_normals {
                let ni = &m.normal_indices[3 * f..3 * f + 3];
                [ni[0] + base_n, ni[1] + base_n, ni[2] + base_n]
            } else {
                [super::NO_NORMAL; 3]
            };
            out.triangles.push((p, n, material));
        }
    }
    Ok(out)
}

/// What tobj does not report: each face's triangle count and whether all its corners have
/// normals, and every `usemtl` with its line number.
struct ObjScan {
    faces: Vec<(usize, bool)>,
    usemtl: Vec<(usize, String)>,
}

fn scan_obj(bytes: &[u8]) -> ObjScan {
    let mut scan = ObjScan {
        faces: Vec::new(),
        usemtl: Vec::new(),
    };
    for (i, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = String::from_utf8_lossy(line);
        let mut words = line.split_whitespace();
        match words.next() {
            Some("f") => {
                let corners: Vec<&str> = words.collect();
                let has = corners
                    .iter()
                    .all(|c| c.split('/').nth(2).is_some_and(|n| !n.is_empty()));
                scan.faces.push((corners.len().saturating_sub(2), has));
            }
            Some("usemtl") => {
                let name = line.trim().strip_prefix("usemtl").unwrap_or("").trim();
                scan.usemtl.push((i + 1, name.to_string()));
            }
            _ => {}
        }
    }
    scan
}

/// The MTL mapping of the scene format: Kd, Ke, illum 3 / Pm (conductors, rough with Pr),
/// illum 7 / d < 1 with Ni > 1 (dielectric).
pub fn map_mtl(m: &tobj::Material) -> Material {
    let param = |key: &str| -> Option<&str> { m.unknown_param.get(key).map(|s| s.trim()) };
    let scalar = |key: &str| param(key).and_then(|s| s.parse::<f32>().ok());
    let color = |key: &str| {
        param(key).and_then(|s| {
            let v: Vec<f32> = s
                .split_whitespace()
                .filter_map(|x| x.parse().ok())
                .collect();
            match v.as_slice() {
                [r, g, b] => Some(Vec3::new(*r, *g, *b)),
                [x] => Some(Vec3::splat(*x)),
                _ => None,
            }
        })
    };
    let kd = m.diffuse.map(Vec3::from).unwrap_or(Vec3::splat(0.8));
    let ks = m.specular.map(Vec3::from);
    let illum = m.illumination_model;
    let metallic = illum == Some(3) || scalar("Pm").is_some_and(|pm| pm >= 0.5);
    let ior = m.optical_density.unwrap_or(1.0);
    let glass = illum == Some(7) || (m.dissolve.is_some_and(|d| d < 1.0) && ior > 1.0);
    let mut mat = Material::diffuse(&m.name, kd);
    if glass {
        mat.kind = MaterialKind::Dielectric;
        mat.albedo = Vec3::ONE;
        mat.ior = if ior > 0.0 { ior } else { 1.5 };
    } else if metallic {
        mat.albedo = ks.unwrap_or(kd);
        match scalar("Pr") {
            Some(r) if r > 0.0 => {
                mat.kind = MaterialKind::RoughConductor;
                mat.roughness = r.min(1.0);
            }
            _ => mat.kind = MaterialKind::Conductor,
        }
    }
    mat.emission = m
        .emissive
        .map(Vec3::from)
        .or_else(|| color("Ke"))
        .unwrap_or(Vec3::ZERO)
        .max(Vec3::ZERO);
    mat
}

fn describe_tobj_error(e: &tobj::LoadError) -> String {
    use tobj::LoadError::*;
    match e {
        OpenFileFailed => "cannot open file".into(),
        ReadError => "read error".into(),
        UnrecognizedCharacter => "unrecognized character".into(),
        PositionParseError => "malformed vertex position (`v`)".into(),
        NormalParseError => "malformed normal (`vn`)".into(),
        TexcoordParseError => "malformed texture coordinate (`vt`)".into(),
        FaceParseError => "malformed face (`f`)".into(),
        MaterialParseError => "malformed material library".into(),
        InvalidObjectName => "invalid object name".into(),
        InvalidPolygon => "invalid polygon (fewer than 3 vertices)".into(),
        FaceVertexOutOfBounds => "a face refers to a vertex that does not exist".into(),
        FaceTexCoordOutOfBounds => {
            "a face refers to a texture coordinate that does not exist".into()
        }
        FaceNormalOutOfBounds => "a face refers to a normal that does not exist".into(),
        FaceColorOutOfBounds => "a face refers to a vertex colour that does not exist".into(),
        other => format!("{other}"),
    }
}
