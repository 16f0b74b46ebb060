//! glTF errors: each is one line naming the file and the JSON path (or the part of a GLB)
//! at fault, and none is a panic: malformed JSON (with its line and column), unsupported
//! versions and required extensions, truncated GLB chunks, unreadable or undecodable
//! buffers and images, accessors out of bounds or of the wrong type, indices out of range,
//! textures without texture coordinates, non-finite positions, invalid references, node
//! cycles.

use crate::common;

use common::fs::TempDir;
use common::gltf::*;
use meshtrace::scene::load_scene;
use serde_json::json;

/// The error of loading `bytes` as `name`, checked to be one line that starts with the
/// file's path.
fn error_of(name: &str, bytes: &[u8]) -> String {
    let dir = TempDir::new("gltf-errors");
    let path = dir.write(name, bytes);
    let message = match load_scene(&path) {
        Ok(_) => panic!("{name} loaded"),
        Err(e) => e.to_string(),
    };
    assert!(!message.contains('\n'), "{message}");
    let shown = path.display().to_string();
    let rest = message
        .strip_prefix(&shown)
        .unwrap_or_else(|| panic!("does not start with the file: {message}"));
    rest.to_string()
}

fn expect(name: &str, bytes: &[u8], needles: &[&str]) {
    let message = error_of(name, bytes);
    for needle in needles {
        assert!(message.contains(needle), "{needle:?} not in {message:?}");
    }
}

/// A valid one-triangle asset.
fn triangle() -> Asset {
    let mut a = Asset::new();
    a.triangle(json!({}));
    a
}

#[test]
fn malformed_json_names_its_line_and_column() {
    expect(
        "a.gltf",
        b"{\n  \"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [ { \"mesh\": } ]\n}\n",
        &[":3:", "expected value"],
    );
    expect(
        "a.gltf",
        b"{\"asset\": {\"version\": \"2.0\"}, \"nodes\": 7}",
        &[":1:", "invalid type: integer `7`"],
    );
    // In a GLB the line and column are within its JSON chunk.
    let glb = glb(b"{\"asset\": {\"version\": \"2.0\"},\n\"scene\": [}", None);
    expect("a.glb", &glb, &[":2:", "(in the GLB's JSON chunk)"]);
    // Not JSON at all, nor a GLB.
    expect("a.gltf", &[0xff, 0xfe, 0, 1], &[":1:1: "]);
}

#[test]
fn versions_and_extensions_meshtrace_does_not_read() {
    let mut a = triangle();
    a.json["asset"]["version"] = json!("1.0");
    expect(
        "a.gltf",
        &a.embedded(),
        &[": asset.version: glTF 1.0: meshtrace reads glTF 2.0"],
    );
    let mut a = triangle();
    a.json["extensionsUsed"] = json!(["EXT_lights_image_based", "KHR_texture_transform"]);
    a.json["extensionsRequired"] = json!(["EXT_lights_image_based"]);
    expect(
        "a.gltf",
        &a.embedded(),
        &[
            ": extensionsRequired: the file requires EXT_lights_image_based, which meshtrace does not support (it reads EXT_mesh_gpu_instancing, ",
        ],
    );
    // A glTF 1.0 file's JSON does not fit 2.0's types; the version is still what is said.
    let v1 = br#"{"asset": {"version": "1.0"}, "meshes": {"m": {}}}"#;
    expect("a.gltf", v1, &[": asset.version: glTF 1.0"]);
    // Required, and the JSON does not parse as 2.0 without it (a texture without source is
    // not enough: that is a validation error): still the extension is named.
    let avif =
        br#"{"asset": {"version": "2.0"}, "extensionsRequired": ["EXT_texture_avif"], "nodes": 5}"#;
    expect(
        "a.gltf",
        avif,
        &["extensionsRequired: the file requires EXT_texture_avif"],
    );
}

#[test]
fn extensions_used_but_not_required_are_warnings() {
    let dir = TempDir::new("gltf-used");
    let mut a = triangle();
    a.json["extensionsUsed"] = json!(["KHR_materials_iridescence", "EXT_foo", "EXT_bar"]);
    let scene = load_scene(&dir.write("a.gltf", a.embedded())).unwrap();
    let w = scene.warnings.join("\n");
    assert!(
        w.contains(
            "a.gltf: extensionsUsed: EXT_foo, EXT_bar not supported; the file is read without them"
        ),
        "{w}"
    );
    // A material extension is warned of by the materials that use it (tests/gltf.rs).
    assert!(!w.contains("iridescence"), "{w}");
}

#[test]
fn truncated_and_malformed_glb_containers() {
    let good = triangle().glb();
    expect(
        "a.glb",
        &good[..10],
        &[": GLB header: the file is 10 bytes, shorter than the 12-byte GLB header"],
    );
    expect(
        "a.glb",
        &good[..good.len() - 4],
        &[
            ": GLB header: the header gives the file's length as",
            "(truncated?)",
        ],
    );
    // The BIN chunk claims more than the file holds (the header's length agrees).
    let mut cut = good[..good.len() - 8].to_vec();
    let len = cut.len() as u32;
    cut[8..12].copy_from_slice(&len.to_le_bytes());
    expect(
        "a.glb",
        &cut,
        &[": GLB BIN chunk: the chunk claims", "(truncated?)"],
    );
    // A chunk header cut off.
    let mut short = good.clone();
    short.truncate(good.len() - 8 - 36 + 4);
    let len = short.len() as u32;
    short[8..12].copy_from_slice(&len.to_le_bytes());
    let message = error_of("a.glb", &short);
    assert!(message.contains(": GLB BIN chunk: "), "{message}");
    let mut version = good.clone();
    version[4] = 1;
    expect(
        "a.glb",
        &version,
        &[": GLB header: GLB version 1; meshtrace reads version 2"],
    );
    let mut kind = good.clone();
    kind[16..20].copy_from_slice(b"BIN\0");
    expect(
        "a.glb",
        &kind,
        &[": GLB JSON chunk: the first chunk is of type BIN"],
    );
    // Buffer 0 without a uri in a .gltf: no BIN chunk stands for it.
    let mut a = triangle();
    a.json["buffers"] = json!([{ "byteLength": a.bin.len() }]);
    let json = serde_json::to_vec(&a.json).unwrap();
    expect(
        "a.gltf",
        &json,
        &[": buffers[0]: has no uri, and the file has no GLB BIN chunk"],
    );
}

#[test]
fn buffers_that_cannot_be_read() {
    let a = triangle();
    let (json, _) = a.external("missing.bin");
    expect(
        "a.gltf",
        &json,
        &[": buffers[0].uri: cannot read ", "missing.bin"],
    );
    let mut bad = a.embedded();
    let text = String::from_utf8(bad.clone())
        .unwrap()
        .replacen("base64,", "base64,*", 1);
    bad = text.into_bytes();
    expect(
        "a.gltf",
        &bad,
        &[": buffers[0].uri: the data URI is not base64: character * at offset 0"],
    );
    let mut a = triangle();
    a.json["buffers"] = json!([{ "byteLength": 1000, "uri": "b.bin" }]);
    let dir = TempDir::new("gltf-short");
    dir.write("b.bin", &a.bin);
    let path = dir.write("a.gltf", serde_json::to_vec(&a.json).unwrap());
    let message = load_scene(&path).unwrap_err().to_string();
    assert!(
        message.contains(": buffers[0]: byteLength is 1000 bytes, but ")
            && message.contains("b.bin holds 36"),
        "{message}"
    );
    let mut a = triangle();
    a.json["buffers"] = json!([{ "byteLength": 36, "uri": "https://example.com/b.bin" }]);
    expect(
        "a.gltf",
        &serde_json::to_vec(&a.json).unwrap(),
        &[
            ": buffers[0].uri: `https://example.com/b.bin`: only relative paths and data: URIs are read",
        ],
    );
}

/// An asset whose one triangle's base colour is image 0 (given by `image`).
fn textured(image: serde_json::Value) -> Asset {
    let mut a = Asset::new();
    let t = a.floats(&[0.0; 6], "VEC2");
    a.triangle(json!({ "attributes": { "TEXCOORD_0": t }, "material": 0 }));
    a.json["images"] = json!([image]);
    a.json["textures"] = json!([{ "source": 0 }]);
    a.json["materials"] =
        json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]);
    a
}

#[test]
fn images_that_cannot_be_decoded() {
    let a = textured(json!({ "uri": format!("data:image/png;base64,{}", base64(b"not a png")) }));
    expect(
        "a.gltf",
        &a.embedded(),
        &[": images[0]: cannot decode the image"],
    );
    let mut a = textured(json!({ "bufferView": 0, "mimeType": "image/png" }));
    let v = a.view(b"\x89PNG\r\n\x1a\n truncated", None);
    a.json["images"][0]["bufferView"] = json!(v);
    expect("a.glb", &a.glb(), &[": images[0]: cannot decode the image"]);
    let dir = TempDir::new("gltf-bad-image");
    dir.write("bad.png", b"garbage");
    let a = textured(json!({ "uri": "bad.png" }));
    let path = dir.write("a.gltf", a.embedded());
    let message = load_scene(&path).unwrap_err().to_string();
    assert!(
        message.contains("a.gltf: images[0] (") && message.contains("bad.png): "),
        "{message}"
    );
    let a = textured(json!({ "mimeType": "image/png" }));
    expect(
        "a.gltf",
        &a.embedded(),
        &[": images[0]: has neither a uri nor a bufferView"],
    );
}

/// A texture must name an image, in `source` or in EXT_texture_webp's or
/// KHR_texture_basisu's `source`, and the extension's must be an index of an image the file
/// has.
#[test]
fn textures_without_an_image() {
    let mut a = textured(
        json!({ "uri": format!("data:image/png;base64,{}", base64(&png(1, 1, &[[9; 4]]))) }),
    );
    for (texture, needle) in [
        (
            json!({}),
            ": textures[0].source: is missing, and the texture names no EXT_texture_webp or KHR_texture_basisu image instead",
        ),
        (
            json!({ "extensions": { "KHR_texture_basisu": { "source": "0" } } }),
            ": textures[0].extensions.KHR_texture_basisu.source: must be an image index",
        ),
        (
            json!({ "source": 0, "extensions": { "KHR_texture_basisu": { "source": 2 } } }),
            ": textures[0].extensions.KHR_texture_basisu.source: image 2 does not exist (the file has 1 image)",
        ),
        (
            json!({ "extensions": { "EXT_texture_webp": { "source": -1 } } }),
            ": textures[0].extensions.EXT_texture_webp.source: must be an image index",
        ),
        (
            json!({ "extensions": { "EXT_texture_webp": {} } }),
            ": textures[0].extensions.EXT_texture_webp.source: is required but missing",
        ),
        (
            json!({ "source": 0, "extensions": { "EXT_texture_webp": { "source": 3 } } }),
            ": textures[0].extensions.EXT_texture_webp.source: image 3 does not exist (the file has 1 image)",
        ),
    ] {
        a.json["textures"] = json!([texture]);
        expect("a.gltf", &a.embedded(), &[needle]);
    }
}

/// A KTX2 image that cannot be transcoded is one line naming the file, the image and why:
/// bytes that are not KTX2 under its MIME type or file name, a KTX2 file cut short, and a
/// KTX2 file whose data is not Basis Universal (KHR_texture_basisu allows nothing else).
#[test]
fn ktx2_images_that_cannot_be_decoded() {
    let ktx2 = std::fs::read(common::fs::data("gltf/BoxTexturedBasisu/Uastc.ktx2")).unwrap();
    // A KTX2 header (identifier, then vkFormat 37, R8G8B8A8_UNORM) with no Basis data.
    let mut plain = ktx2[..80].to_vec();
    plain[12..16].copy_from_slice(&37u32.to_le_bytes());
    for (image, bytes, needle) in [
        (
            json!({ "bufferView": 0, "mimeType": "image/ktx2" }),
            b"not a texture".to_vec(),
            ": images[0]: not a KTX2 file",
        ),
        (
            json!({ "bufferView": 0, "mimeType": "image/ktx2" }),
            ktx2[..ktx2.len() / 2].to_vec(),
            ": images[0]: cannot transcode the KTX2 image: the data of its level 0 is corrupt or truncated",
        ),
        (
            json!({ "bufferView": 0, "mimeType": "image/ktx2" }),
            plain,
            ": images[0]: cannot read the KTX2 file: ",
        ),
    ] {
        let mut a = textured(image);
        a.json["textures"] = json!([{ "extensions": { "KHR_texture_basisu": { "source": 0 } } }]);
        let v = a.view(&bytes, None);
        a.json["images"][0]["bufferView"] = json!(v);
        expect("a.glb", &a.glb(), &[needle]);
    }
    let dir = TempDir::new("gltf-bad-ktx2");
    dir.write("bad.ktx2", b"garbage");
    let mut a = textured(json!({ "uri": "bad.ktx2" }));
    a.json["textures"] = json!([{ "extensions": { "KHR_texture_basisu": { "source": 0 } } }]);
    let path = dir.write("a.gltf", a.embedded());
    let message = load_scene(&path).unwrap_err().to_string();
    assert!(
        message.contains("a.gltf: images[0] (") && message.contains("bad.ktx2): not a KTX2 file"),
        "{message}"
    );
}

#[test]
fn a_texture_on_a_primitive_without_texture_coordinates() {
    let mut a = textured(
        json!({ "uri": format!("data:image/png;base64,{}", base64(&png(1, 1, &[[1, 2, 3, 4]]))) }),
    );
    a.json["meshes"][0]["primitives"][0]["attributes"]
        .as_object_mut()
        .unwrap()
        .remove("TEXCOORD_0");
    expect(
        "a.gltf",
        &a.embedded(),
        &[
            ": meshes[0].primitives[0]: material `materials[0]` uses a texture, but the mesh has faces without texture coordinates",
        ],
    );
}

#[test]
fn accessors_out_of_bounds_or_of_the_wrong_type() {
    let mut a = triangle();
    a.json["accessors"][0]["count"] = json!(4);
    expect(
        "a.gltf",
        &a.embedded(),
        &[
            ": meshes[0].primitives[0].attributes[\"POSITION\"]: accessor 0 reads past the end of bufferView 0: 4 elements of 12 bytes, 12 apart from byte 0, need 48 bytes, the view has 36",
        ],
    );
    let mut a = triangle();
    a.json["accessors"][0]["count"] = json!(u64::MAX / 2);
    expect(
        "a.gltf",
        &a.embedded(),
        &["accessor 0 reads past the end of bufferView 0"],
    );
    let mut a = triangle();
    a.json["bufferViews"][0]["byteOffset"] = json!(8);
    expect(
        "a.gltf",
        &a.embedded(),
        &[
            ": meshes[0].primitives[0].attributes[\"POSITION\"]: accessor 0: bufferView 0 (bytes 8 to 44) lies past the end of buffer 0 (36 bytes)",
        ],
    );
    let mut a = triangle();
    a.json["bufferViews"][0]["byteStride"] = json!(8);
    expect(
        "a.gltf",
        &a.embedded(),
        &["accessor 0: bufferView 0's byteStride 8 is less than its 12-byte elements"],
    );
    let mut a = triangle();
    a.json["accessors"][0]["type"] = json!("VEC2");
    expect(
        "a.gltf",
        &a.embedded(),
        &[
            "attributes[\"POSITION\"]: accessor 0 holds VEC2 of FLOAT; POSITION must be VEC3 of FLOAT",
        ],
    );
    let mut a = triangle();
    let t = a.accessor(&[0; 6], UNSIGNED_BYTE, 3, "VEC2", false);
    a.json["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(t);
    expect(
        "a.gltf",
        &a.embedded(),
        &[
            "TEXCOORD_0\"]: accessor 1 holds VEC2 of UNSIGNED_BYTE; TEXCOORD_0 must be VEC2 of FLOAT or normalized UNSIGNED_BYTE or normalized UNSIGNED_SHORT",
        ],
    );
    let mut a = triangle();
    let n = a.floats(&[0.0, 0.0, 1.0], "VEC3");
    a.json["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = json!(n);
    expect(
        "a.gltf",
        &a.embedded(),
        &["attributes[\"NORMAL\"]: accessor 1 has 1 elements, but POSITION has 3"],
    );
    // Zeros without a buffer view, in impossible numbers.
    let mut a = triangle();
    a.json["accessors"][0] = json!({ "componentType": FLOAT, "count": 1u64 << 40, "type": "VEC3" });
    expect(
        "a.gltf",
        &a.embedded(),
        &["accessor 0 has no bufferView and 1099511627776 elements"],
    );
}

#[test]
fn sparse_accessors_out_of_order_or_out_of_range() {
    for (indices, needle) in [
        (
            vec![2u8, 1],
            "accessor 0's sparse indices are not strictly increasing: 1 (entry 1) follows 2",
        ),
        (
            vec![0, 3],
            "accessor 0's sparse index 3 (entry 1) is past the accessor's 3 elements",
        ),
    ] {
        let mut a = triangle();
        let iv = a.view(&indices, None);
        let vv = a.view(&[0; 24], None);
        a.json["accessors"][0]["sparse"] = json!({
            "count": 2,
            "indices": { "bufferView": iv, "componentType": UNSIGNED_BYTE },
            "values": { "bufferView": vv },
        });
        expect("a.gltf", &a.embedded(), &[needle]);
    }
    let mut a = triangle();
    let iv = a.view(&[0], None);
    let vv = a.view(&[0; 4], None);
    a.json["accessors"][0]["sparse"] = json!({
        "count": 1,
        "indices": { "bufferView": iv, "componentType": UNSIGNED_BYTE },
        "values": { "bufferView": vv },
    });
    expect(
        "a.gltf",
        &a.embedded(),
        &["accessor 0's sparse values read past the end of bufferView 2"],
    );
}

#[test]
fn indices_out_of_range() {
    let mut a = triangle();
    let i = a.indices(&[0, 1, 7]);
    a.json["meshes"][0]["primitives"][0]["indices"] = json!(i);
    expect(
        "a.gltf",
        &a.embedded(),
        &[
            ": meshes[0].primitives[0].indices: index 7 (entry 2 of accessor 1) is out of range: POSITION has 3 vertices",
        ],
    );
    let mut a = triangle();
    let i = a.floats(&[0.0, 1.0, 2.0], "SCALAR");
    a.json["meshes"][0]["primitives"][0]["indices"] = json!(i);
    expect(
        "a.gltf",
        &a.embedded(),
        &["indices: accessor 1 holds SCALAR of FLOAT; indices must be SCALAR of"],
    );
}

#[test]
fn non_finite_positions() {
    for bad in [f32::NAN, f32::INFINITY] {
        let mut a = Asset::new();
        let p = a.positions(&[[0.0; 3], [1.0, bad, 0.0], [0.0, 1.0, 0.0]]);
        let mesh = a.mesh(json!({ "attributes": { "POSITION": p } }));
        let node = a.node(json!({ "mesh": mesh }));
        a.scene(&[node]);
        expect(
            "a.gltf",
            &a.embedded(),
            &[
                ": meshes[0].primitives[0].attributes[\"POSITION\"]: accessor 0: vertex 1 is not finite",
            ],
        );
    }
    // A JSON number too large for f32 in a transform.
    let mut a = triangle();
    a.json["nodes"][0]["translation"] = json!([1e39, 0, 0]);
    expect(
        "a.gltf",
        &a.embedded(),
        &[": nodes[0].translation: must be finite"],
    );
}

#[test]
fn references_to_objects_that_do_not_exist() {
    let mut a = triangle();
    a.json["nodes"][0]["mesh"] = json!(5);
    expect(
        "a.gltf",
        &a.embedded(),
        &[": nodes[0].mesh: refers to an object that the file does not have"],
    );
    // The `gltf` crate's validation would look this accessor up before checking it.
    let mut a = triangle();
    a.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(9);
    expect(
        "a.gltf",
        &a.embedded(),
        &[
            ": meshes[0].primitives[0].attributes[\"POSITION\"]: accessor 9 does not exist (the file has 1 accessor)",
        ],
    );
    let mut a = triangle();
    a.json["meshes"][0]["primitives"][0]["material"] = json!(0);
    a.json["scenes"][0]["nodes"] = json!([0, 3]);
    let message = error_of("a.gltf", &a.embedded());
    assert!(message.contains("(and 1 more problem)"), "{message}");
    let mut a = triangle();
    a.json["meshes"][0]["primitives"][0]["mode"] = json!(9);
    expect(
        "a.gltf",
        &a.embedded(),
        &["meshes[0].primitives[0].mode: has an invalid value"],
    );
}

#[test]
fn node_trees_with_cycles_or_shared_children() {
    let mut a = triangle();
    a.json["nodes"][0]["children"] = json!([0]);
    expect(
        "a.gltf",
        &a.embedded(),
        &[": nodes[0]: is reached twice in scene 0's node tree"],
    );
    let mut a = triangle();
    let child = a.node(json!({}));
    a.json["nodes"][0]["children"] = json!([child]);
    a.json["scenes"][0]["nodes"] = json!([0, child]);
    expect("a.gltf", &a.embedded(), &[": nodes[1]: is reached twice"]);
    // A deep chain is walked without recursion.
    let mut a = triangle();
    for k in 0..20_000usize {
        a.json["nodes"][k]["children"] = json!([k + 1]);
        a.node(json!({}));
    }
    let dir = TempDir::new("gltf-deep");
    assert!(load_scene(&dir.write("a.gltf", a.embedded())).is_ok());
}

#[test]
fn scenes_and_cameras_that_cannot_be_used() {
    let mut a = triangle();
    a.json.as_object_mut().unwrap().remove("scenes");
    a.json.as_object_mut().unwrap().remove("scene");
    expect(
        "a.gltf",
        &a.embedded(),
        &[": scenes: the file has no scene to render"],
    );
    let mut a = triangle();
    a.json["cameras"] =
        json!([{ "type": "perspective", "perspective": { "yfov": 4.0, "znear": 0.1 } }]);
    a.json["nodes"][0]["camera"] = json!(0);
    expect(
        "a.gltf",
        &a.embedded(),
        &[": cameras[0].perspective.yfov: must be in (0, pi) radians, got 4"],
    );
    let mut a = triangle();
    a.json["nodes"][0]["rotation"] = json!([0, 0, 0, 0]);
    expect(
        "a.gltf",
        &a.embedded(),
        &[": nodes[0].rotation: must be a unit quaternion, not zero"],
    );
}

#[test]
fn invalid_lights_and_materials() {
    let mut a = triangle();
    a.json["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
        { "type": "spot", "spot": { "innerConeAngle": 0.6, "outerConeAngle": 0.5 } },
    ] } });
    a.json["nodes"][0]["extensions"] = json!({ "KHR_lights_punctual": { "light": 0 } });
    expect(
        "a.gltf",
        &a.embedded(),
        &[
            ": extensions.KHR_lights_punctual.lights[0].spot.innerConeAngle: must be in [0, outerConeAngle), got 0.6",
        ],
    );
    let mut a = triangle();
    a.json["meshes"][0]["primitives"][0]["material"] = json!(0);
    a.json["materials"] = json!([{ "extensions": { "KHR_materials_ior": { "ior": 0.5 } } }]);
    expect(
        "a.gltf",
        &a.embedded(),
        &[": materials[0].extensions.KHR_materials_ior.ior: must be at least 1, got 0.5"],
    );
    let mut a = triangle();
    a.json["meshes"][0]["primitives"][0]["material"] = json!(0);
    a.json["materials"] = json!([{ "emissiveFactor": [1, -1, 0] }]);
    expect(
        "a.gltf",
        &a.embedded(),
        &[": materials[0].emissiveFactor: component 1 must be finite and at least 0, got -1"],
    );
}

#[test]
fn errors_inside_scene_files_name_the_object_and_the_gltf() {
    let dir = TempDir::new("gltf-in-toml");
    let mut a = triangle();
    a.json["accessors"][0]["count"] = json!(4);
    dir.write("m.glb", a.glb());
    let toml =
        "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\n[[objects]]\nmesh = \"m.glb\"\n";
    let message = load_scene(&dir.write("s.toml", toml))
        .unwrap_err()
        .to_string();
    assert!(
        message.contains(
            "m.glb: meshes[0].primitives[0].attributes[\"POSITION\"]: accessor 0 reads past"
        ),
        "{message}"
    );
    let mut a = textured(
        json!({ "uri": format!("data:image/png;base64,{}", base64(&png(1, 1, &[[1, 2, 3, 4]]))) }),
    );
    a.json["meshes"][0]["primitives"][0]["attributes"]
        .as_object_mut()
        .unwrap()
        .remove("TEXCOORD_0");
    dir.write("t.gltf", a.embedded());
    let toml =
        "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\n[[objects]]\nmesh = \"t.gltf\"\n";
    let message = load_scene(&dir.write("t.toml", toml))
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("t.toml: objects[0]: ")
            && message.contains(
                "t.gltf: meshes[0].primitives[0]: material `materials[0]` uses a texture"
            ),
        "{message}"
    );
}
