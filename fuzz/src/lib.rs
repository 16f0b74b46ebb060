//! The fuzz harnesses, shared by the cargo-fuzz targets (`fuzz_targets/`) and by the
//! regression test that replays the corpora without libFuzzer (`tests/fuzz_corpus.rs`,
//! which includes this file as a module), so both run exactly the same code.
//!
//! A harness panics only on a bug: a panic escaping the library, a malformed loaded scene,
//! or an invalid BVH. Errors from bad input are the expected outcome.

use meshtrace::bvh::{BuildParams, validate};
use meshtrace::math::Aabb;
use meshtrace::render::RenderScene;
use meshtrace::scene::obj::load_obj;
use meshtrace::scene::source::FileSource;
use meshtrace::scene::{
    NO_NORMAL, NO_TANGENT, NO_TEXTURE, NO_UV, PunctualLight, Scene, load_scene_from,
};
use std::cell::RefCell;
use std::path::{Path, PathBuf};

/// Separates the OBJ part of an `obj_mtl` input from the part also served as `m.mtl`.
pub const MTL_MARKER: &[u8] = b"\n#MTL\n";

/// Sphere triangles a fuzzed scene may ask for. The format allows 21M per sphere
/// (`MAX_SPHERE_SUBDIVISIONS`), which is slow and large by design, not a bug; inputs asking
/// for more than this are skipped so that the fuzzer spends its time on parsing.
pub const SPHERE_TRIANGLE_BUDGET: u64 = 50_000;

/// A mesh that scene inputs may name as `mesh = "m.obj"`, with a material library.
pub const SCENE_OBJ: &str = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\n\
usemtl red\nf 1//1 2//1 3//1 4//1\nusemtl glass\nf 1 3 2\n";
pub const SCENE_MTL: &str = "newmtl red\nKd 0.8 0.1 0.1\nKe 1 1 1\n\
newmtl glass\nillum 7\nNi 1.5\n";

/// Files served from memory; any other path is "not found". Nothing touches the disk.
pub struct MemFiles {
    files: Vec<(PathBuf, Vec<u8>)>,
}

impl MemFiles {
    pub fn new(files: &[(&str, &[u8])]) -> Self {
        Self {
            files: files
                .iter()
                .map(|(p, b)| (PathBuf::from(p), b.to_vec()))
                .collect(),
        }
    }
}

impl FileSource for MemFiles {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        self.files
            .iter()
            .find(|(p, _)| p == path)
            .map(|(_, b)| b.clone())
            .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "not in memory"))
    }
}

/// Fuzz target `scene_file`: the input is `fuzz.toml`, read through the same path as
/// `parse_scene` (`load_scene_from` on a `.toml` is UTF-8 decoding then `parse_scene`'s
/// code) but with an in-memory file source, so that `mesh = "/dev/zero"` cannot hang the
/// fuzzer and `mesh = "m.obj"` reaches a real mesh.
pub fn scene_file(data: &[u8]) {
    if exceeds_sphere_budget(data) {
        return;
    }
    let files = MemFiles::new(&[
        ("fuzz.toml", data),
        ("m.obj", SCENE_OBJ.as_bytes()),
        ("m.mtl", SCENE_MTL.as_bytes()),
    ]);
    if let Ok(scene) = load_scene_from(Path::new("fuzz.toml"), &files) {
        check_scene(&scene);
    }
}

/// Fuzz target `obj_mtl`: the input is `m.obj`; the bytes after the first `\n#MTL\n`
/// are also served as `m.mtl` (an OBJ reaches them with `mtllib m.mtl`).
pub fn obj_mtl(data: &[u8]) {
    let mtl = data
        .windows(MTL_MARKER.len())
        .position(|w| w == MTL_MARKER)
        .map_or(&[][..], |i| &data[i + MTL_MARKER.len()..]);
    let files = MemFiles::new(&[("m.obj", data), ("m.mtl", mtl)]);
    let Ok(obj) = load_obj(Path::new("m.obj"), &files) else {
        return;
    };
    for (k, t) in obj.triangles.iter().enumerate() {
        let (p, n, material) = (&t.p, &t.n, t.material);
        assert!(
            p.iter().all(|&i| (i as usize) < obj.positions.len()),
            "triangle {k}: position index out of range: {p:?} of {}",
            obj.positions.len()
        );
        assert!(
            *n == [NO_NORMAL; 3] || n.iter().all(|&i| (i as usize) < obj.normals.len()),
            "triangle {k}: normal index out of range: {n:?} of {}",
            obj.normals.len()
        );
        assert!(
            material.is_none_or(|m| (m as usize) < obj.materials.len()),
            "triangle {k}: material {material:?} of {}",
            obj.materials.len()
        );
    }
    assert!(
        obj.positions.iter().all(|p| p.is_finite()),
        "a non-finite position was accepted"
    );
    // The same file as a bare OBJ scene ("the mesh has no faces" is an error).
    if let Ok(scene) = load_scene_from(Path::new("m.obj"), &files) {
        check_scene(&scene);
    }
}

/// The external files a `gltf` input may name: a buffer and an image beside it.
pub const GLTF_BIN: &str = "b.bin";
pub const GLTF_PNG: &str = "t.png";

/// A 2x2 RGBA PNG (red and green columns), served as `t.png` to `gltf` inputs.
pub const PNG_2X2: &[u8] = &[
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52,
    0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x02, 0x08, 0x06, 0x00, 0x00, 0x00, 0x72, 0xb6, 0x0d,
    0x24, 0x00, 0x00, 0x00, 0x10, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0xf8, 0xcf, 0xc0, 0xf0,
    0x1f, 0x0a, 0x21, 0x14, 0x00, 0x45, 0xcc, 0x07, 0xf9, 0x66, 0xcb, 0xff, 0x39, 0x00, 0x00, 0x00,
    0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82,
];

/// The bytes served as `b.bin`: three vertices of a triangle (36 bytes of floats), then
/// the indices 0, 1, 2 as unsigned shorts, then 26 bytes counting up.
pub fn gltf_bin() -> Vec<u8> {
    let mut bin: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    bin.extend([0, 0, 1, 0, 2, 0]);
    bin.extend(0u8..26);
    bin
}

/// Fuzz target `gltf`: the input is `fuzz.glb` when it starts with the GLB magic, else
/// `fuzz.gltf`, beside `b.bin` and `t.png`; loaded as a bare glTF scene, it must load or
/// fail with an error, and a loaded scene must be well formed.
pub fn gltf(data: &[u8]) {
    let name = if data.starts_with(b"glTF") {
        "fuzz.glb"
    } else {
        "fuzz.gltf"
    };
    let bin = gltf_bin();
    let files = MemFiles::new(&[(name, data), (GLTF_BIN, &bin), (GLTF_PNG, PNG_2X2)]);
    if let Ok(scene) = load_scene_from(Path::new(name), &files) {
        check_scene(&scene);
        check_gltf_scene(&scene);
    }
}

/// A GLB file of `json` and the BIN chunk `bin`.
pub fn glb(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut text = json.to_string().into_bytes();
    text.resize(text.len().next_multiple_of(4), b' ');
    let mut bin = bin.to_vec();
    bin.resize(bin.len().next_multiple_of(4), 0);
    let length = 12 + 8 + text.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(length);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((length as u32).to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(text);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// Loads `glb` as a bare glTF scene; a loaded scene must be well formed.
pub fn load_glb(glb: &[u8]) {
    let files = MemFiles::new(&[("fuzz.glb", glb)]);
    if let Ok(scene) = load_scene_from(Path::new("fuzz.glb"), &files) {
        check_scene(&scene);
        check_gltf_scene(&scene);
    }
}

/// Bounds wide enough for any decoded position (glTF requires POSITION's min and max).
const WIDE: [f32; 3] = [1e30, 1e30, 1e30];

/// Fuzz target `draco`: the input is a 4-byte header, the vertex and index counts (u16,
/// little-endian) that the accessors declare, then a Draco stream, served as the one
/// buffer view of a KHR_draco_mesh_compression primitive whose POSITION (attribute 0),
/// NORMAL (1) and TEXCOORD_0 (2) come from the stream.
pub fn draco(data: &[u8]) {
    if let Some(glb) = draco_glb(data) {
        load_glb(&glb);
    }
}

/// The GLB file the `draco` target loads for `data`; `None` for an input too short.
pub fn draco_glb(data: &[u8]) -> Option<Vec<u8>> {
    let (head, stream) = (data.get(..4)?, data.get(4..)?);
    let points = u16::from_le_bytes([head[0], head[1]]);
    let corners = u16::from_le_bytes([head[2], head[3]]);
    let accessor = |ty: &str, component: u32, count: u16| serde_json::json!({"componentType": component, "type": ty, "count": count});
    let mut position = accessor("VEC3", 5126, points);
    position["min"] = serde_json::json!(WIDE.map(|x| -x));
    position["max"] = serde_json::json!(WIDE);
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_draco_mesh_compression"],
        "extensionsRequired": ["KHR_draco_mesh_compression"],
        "buffers": [{"byteLength": stream.len().next_multiple_of(4)}],
        "bufferViews": [{"buffer": 0, "byteLength": stream.len()}],
        "accessors": [
            position,
            accessor("VEC3", 5126, points),
            accessor("VEC2", 5126, points),
            accessor("SCALAR", 5125, corners),
        ],
        "meshes": [{"primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
            "indices": 3,
            "extensions": {"KHR_draco_mesh_compression": {
                "bufferView": 0,
                "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}
            }}
        }]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    });
    Some(glb(&json, stream))
}

/// Texels a fuzzed KTX2 header may declare: the format allows 2^32 × 2^32, which the loader
/// refuses or allocates as the memory free allows, by design; inputs declaring more than
/// this are skipped so that the fuzzer spends its time in the transcoder, not in allocation.
pub const KTX2_TEXEL_BUDGET: u64 = 1 << 20;

/// Fuzz target `ktx2`: the input is a KTX2 file, served as the image (a buffer view of
/// MIME type image/ktx2) that a textured triangle's KHR_texture_basisu extension names;
/// loading it must succeed or fail with an error, and a loaded scene must be well formed.
pub fn ktx2(data: &[u8]) {
    if let Some(glb) = ktx2_glb(data) {
        load_glb(&glb);
    }
}

/// The GLB file the `ktx2` target loads for `data`; `None` for an input whose header (the
/// width and height after the 12-byte identifier and two u32s) declares more than
/// [`KTX2_TEXEL_BUDGET`] texels.
pub fn ktx2_glb(data: &[u8]) -> Option<Vec<u8>> {
    let u32_at = |at: usize| {
        data.get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    if let (Some(width), Some(height)) = (u32_at(20), u32_at(24))
        && u64::from(width) * u64::from(height) > KTX2_TEXEL_BUDGET
    {
        return None;
    }
    let mut bin = gltf_bin();
    bin.truncate(42);
    bin.extend([0, 0]);
    bin.extend(
        [0.0f32, 0.0, 1.0, 0.0, 0.0, 1.0]
            .iter()
            .flat_map(|x| x.to_le_bytes()),
    );
    let image_at = bin.len();
    bin.extend(data);
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_texture_basisu"],
        "extensionsRequired": ["KHR_texture_basisu"],
        "buffers": [{"byteLength": bin.len().next_multiple_of(4)}],
        "bufferViews": [
            {"buffer": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6},
            {"buffer": 0, "byteOffset": 44, "byteLength": 24},
            {"buffer": 0, "byteOffset": image_at, "byteLength": data.len()}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": 3,
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "type": "SCALAR", "count": 3},
            {"bufferView": 2, "componentType": 5126, "type": "VEC2", "count": 3}
        ],
        "images": [{"bufferView": 3, "mimeType": "image/ktx2"}],
        "textures": [{"extensions": {"KHR_texture_basisu": {"source": 0}}}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "meshes": [{"primitives": [{
            "attributes": {"POSITION": 0, "TEXCOORD_0": 2},
            "indices": 1,
            "material": 0
        }]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    });
    Some(glb(&json, &bin))
}

/// Fuzz target `meshopt`: the input is a 7-byte header, then a vertex stream and an index
/// stream, served as two EXT_ or KHR_meshopt_compression buffer views of one primitive
/// (over a fallback buffer that is never read). The header: flags (bit 0 positions as
/// 16-bit integers with KHR_mesh_quantization, stride 8, rather than floats, stride 12;
/// bit 1 the EXPONENTIAL filter, on floats; bit 2 the INDICES mode rather than TRIANGLES;
/// bit 3 16-bit indices rather than 32-bit; bit 4 KHR_ rather than EXT_), the vertex count
/// and the index count (u16 each) and the vertex stream's length (u16), all little-endian.
pub fn meshopt(data: &[u8]) {
    if let Some(glb) = meshopt_glb(data) {
        load_glb(&glb);
    }
}

/// The GLB file the `meshopt` target loads for `data`; `None` for an input whose header
/// is cut short or whose vertex stream runs past its end.
pub fn meshopt_glb(data: &[u8]) -> Option<Vec<u8>> {
    let head = data.get(..7)?;
    let u16_at = |i: usize| u16::from_le_bytes([head[i], head[i + 1]]) as usize;
    let (flags, points, corners, split) = (head[0], u16_at(1), u16_at(3), u16_at(5));
    let rest = &data[7..];
    let (vertices, indices) = (split <= rest.len()).then(|| rest.split_at(split))?;
    let quantized = flags & 1 != 0;
    let (stride, component) = if quantized { (8, 5122) } else { (12, 5126) };
    let filter = if flags & 2 != 0 && !quantized {
        "EXPONENTIAL"
    } else {
        "NONE"
    };
    let mode = if flags & 4 != 0 {
        "INDICES"
    } else {
        "TRIANGLES"
    };
    let (index_stride, index_component) = if flags & 8 != 0 { (2, 5123) } else { (4, 5125) };
    let name = if flags & 16 != 0 {
        "KHR_meshopt_compression"
    } else {
        "EXT_meshopt_compression"
    };
    let mut used = vec![name];
    if quantized {
        used.push("KHR_mesh_quantization");
    }
    let fallback = points * stride + corners * index_stride;
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": used,
        "extensionsRequired": used,
        "buffers": [
            {"byteLength": data.len() - 7},
            {"byteLength": fallback.max(4), "extensions": {name: {"fallback": true}}}
        ],
        "bufferViews": [
            {"buffer": 1, "byteLength": points * stride, "byteStride": stride, "extensions": {name: {
                "buffer": 0, "byteLength": vertices.len(), "byteStride": stride,
                "count": points, "mode": "ATTRIBUTES", "filter": filter
            }}},
            {"buffer": 1, "byteOffset": points * stride, "byteLength": corners * index_stride,
             "extensions": {name: {
                "buffer": 0, "byteOffset": vertices.len(), "byteLength": indices.len(),
                "byteStride": index_stride, "count": corners, "mode": mode
            }}}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": component, "type": "VEC3", "count": points,
             "min": WIDE.map(|x| -x), "max": WIDE},
            {"bufferView": 1, "componentType": index_component, "type": "SCALAR", "count": corners}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}]
    });
    Some(glb(&json, rest))
}

/// What a glTF scene adds to [`check_scene`]: texture coordinates and tangents in range,
/// texture slots that name records, finite lights.
fn check_gltf_scene(scene: &Scene) {
    let mesh = &scene.mesh;
    for (k, t) in mesh.triangles.iter().enumerate() {
        assert!(
            t.t == [NO_UV; 3] || t.t.iter().all(|&i| (i as usize) < mesh.texcoords.len()),
            "triangle {k}: texture coordinate index out of range: {:?}",
            t.t
        );
        let g = mesh.tangent_indices(k);
        assert!(
            g == [NO_TANGENT; 3] || g.iter().all(|&i| (i as usize) < mesh.tangents.len()),
            "triangle {k}: tangent index out of range: {g:?}"
        );
    }
    assert!(
        mesh.tangent_corners.is_empty() || mesh.tangent_corners.len() == mesh.triangles.len(),
        "{} tangent entries for {} triangles",
        mesh.tangent_corners.len(),
        mesh.triangles.len()
    );
    for (i, m) in scene.materials.iter().enumerate() {
        for slot in [
            m.albedo_texture,
            m.emission_texture,
            m.roughness_texture,
            m.metallic_texture,
            m.transmission_texture,
            m.normal_texture,
        ] {
            assert!(
                slot == NO_TEXTURE || (slot as usize) < scene.textures.records.len(),
                "material {i}: texture slot {slot} of {}",
                scene.textures.records.len()
            );
        }
    }
    for light in &scene.lights {
        let finite = match *light {
            PunctualLight::Point {
                position,
                intensity,
            } => position.is_finite() && intensity.is_finite(),
            PunctualLight::Spot {
                position,
                direction,
                intensity,
                ..
            } => position.is_finite() && direction.is_normalized() && intensity.is_finite(),
            PunctualLight::Directional {
                direction,
                irradiance,
                ..
            } => direction.is_normalized() && irradiance.is_finite(),
            PunctualLight::Rect {
                center,
                edge_u,
                edge_v,
                radiance,
            } => center.is_finite() && edge_u.cross(edge_v).length() > 0.0 && radiance.is_finite(),
        };
        assert!(finite, "a light that is not finite: {light:?}");
    }
    assert!(scene.camera.position.is_finite(), "{:?}", scene.camera);
}

/// A loaded scene is well formed, and if its BVH fits the traversal stack the tree is valid.
pub fn check_scene(scene: &Scene) {
    let mesh = &scene.mesh;
    for (k, t) in mesh.triangles.iter().enumerate() {
        assert!(
            t.p.iter().all(|&i| (i as usize) < mesh.positions.len()),
            "triangle {k}: position index out of range: {:?}",
            t.p
        );
        assert!(
            t.n == [NO_NORMAL; 3] || t.n.iter().all(|&i| (i as usize) < mesh.normals.len()),
            "triangle {k}: normal index out of range: {:?}",
            t.n
        );
        assert!(
            (t.material as usize) < scene.materials.len(),
            "triangle {k}: material {} of {}",
            t.material,
            scene.materials.len()
        );
        assert!(
            mesh.vertices(t).iter().all(|p| p.is_finite()),
            "triangle {k} has a non-finite corner"
        );
    }
    // `RenderScene::new` refuses trees deeper than the traversal stack; that is an error,
    // not a bug.
    let Ok(rs) = RenderScene::new(scene, &BuildParams::default()) else {
        return;
    };
    let bounds: Vec<Aabb> = mesh
        .triangles
        .iter()
        .map(|t| Aabb::from_points(&mesh.vertices(t)))
        .collect();
    if let Err(e) = validate(&rs.bvh, &bounds) {
        panic!("invalid BVH: {e}");
    }
    assert_eq!(rs.tris.len(), mesh.triangles.len());
}

/// Whether the scene asks for more sphere triangles than [`SPHERE_TRIANGLE_BUDGET`].
/// Inputs that do not parse are within budget: the loader rejects them first.
fn exceeds_sphere_budget(data: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(data) else {
        return false;
    };
    let Ok(file) = toml::from_str::<meshtrace::scene::file::SceneFile>(text) else {
        return false;
    };
    static DEFAULT: std::sync::OnceLock<u32> = std::sync::OnceLock::new();
    let default = *DEFAULT.get_or_init(meshtrace::scene::sphere::default_subdivisions);
    let total: u64 = file
        .objects
        .iter()
        .filter_map(|o| o.sphere.as_ref())
        .map(|s| 20u64 << (2 * s.subdivisions.unwrap_or(default).min(20)))
        .sum();
    total > SPHERE_TRIANGLE_BUDGET
}

thread_local! {
    static IN_REPLAY: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    static LAST_PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Makes panics inside [`replay`] quiet: their message is recorded (per thread) instead of
/// printed, so that [`guarded`] and [`replay`] report each escaped panic once, with its
/// message and place, rather than libFuzzer's hook aborting on it first. Panics elsewhere go
/// to the previous hook. Installing twice is harmless.
pub fn install_panic_hook() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !IN_REPLAY.with(|r| r.get()) {
                return previous(info);
            }
            let at = info
                .location()
                .map(|l| format!(" at {}:{}", l.file(), l.line()))
                .unwrap_or_default();
            let msg = info
                .payload()
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| info.payload().downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "(non-string panic)".into());
            LAST_PANIC.with(|p| *p.borrow_mut() = Some(format!("{msg}{at}")));
        }));
    });
}

/// Runs `harness` on `data`; returns the message of a panic that escaped it.
pub fn replay(data: &[u8], harness: fn(&[u8])) -> Result<(), String> {
    LAST_PANIC.with(|p| p.borrow_mut().take());
    IN_REPLAY.with(|r| r.set(true));
    let result = std::panic::catch_unwind(|| harness(data));
    IN_REPLAY.with(|r| r.set(false));
    result.map_err(|_| {
        LAST_PANIC
            .with(|p| p.borrow_mut().take())
            .unwrap_or_else(|| "panic".into())
    })
}

/// Runs `harness` on `data` and aborts, printing the panic, if one escaped it.
pub fn guarded(data: &[u8], harness: fn(&[u8])) {
    if let Err(msg) = replay(data, harness) {
        eprintln!("panic escaped the library: {msg}");
        std::process::abort();
    }
}
