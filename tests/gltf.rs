//! glTF 2.0 input, on files built here: the node tree, every attribute component type,
//! sparse accessors, strips and fans, materials and every extension meshtrace reads,
//! texture transforms, embedded and external images, GLB, the camera, KHR_lights_punctual,
//! the bare-file set-up and glTF meshes in scene files. Errors are `tests/gltf_errors.rs`;
//! Khronos's sample assets are `tests/gltf_samples.rs`.

use crate::common;

use common::fs::TempDir;
use common::gltf::*;
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use meshtrace::scene::material::{MAT_ALPHA_MASK, MAT_SPEC_GLOSS, MAT_THIN_WALLED};
use meshtrace::scene::studio;
use meshtrace::scene::{
    MaterialKind, NO_TANGENT, NO_TEXTURE, PunctualLight, Scene, Sky, TextureFormat, Wrap,
    load_scene,
};
use serde_json::json;

/// Loads `asset` as an embedded `.gltf` from a fresh directory.
fn load(asset: &Asset) -> Scene {
    let dir = TempDir::new("gltf");
    let path = dir.write("a.gltf", asset.embedded());
    common::studio::without_ground(load_scene(&path).unwrap_or_else(|e| panic!("{e}")))
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

/// The world-space corners of every triangle.
fn corners(scene: &Scene) -> Vec<[Vec3; 3]> {
    let mesh = &scene.mesh;
    mesh.triangles.iter().map(|t| mesh.vertices(t)).collect()
}

#[test]
fn node_tree_composes_transforms_from_root_to_leaf() {
    let mut a = Asset::new();
    let mesh = a.triangle(json!({}));
    // leaf: a matrix (column-major) translating by +1 in z.
    let leaf = a.node(json!({ "mesh": mesh, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,1,1] }));
    let q = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let middle = a.node(json!({
        "mesh": mesh, "children": [leaf],
        "rotation": q.to_array(), "scale": [2, 2, 2],
    }));
    let root = a.node(json!({ "children": [middle], "translation": [10, 0, 0] }));
    a.scene(&[root]);
    let scene = load(&a);
    let parent = Mat4::from_translation(Vec3::new(10.0, 0.0, 0.0))
        * Mat4::from_scale_rotation_translation(Vec3::splat(2.0), q, Vec3::ZERO);
    let leaf_m = parent * Mat4::from_translation(Vec3::Z);
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let got = corners(&scene);
    assert_eq!(got.len(), 2, "the mesh once per node that uses it");
    for (c, m) in got.iter().zip([parent, leaf_m]) {
        for (p, q) in c.iter().zip(tri) {
            assert!(
                close(*p, m.transform_point3(q)),
                "{p} vs {}",
                m.transform_point3(q)
            );
        }
    }
    // (1, 0, 0) turned a quarter about Z, doubled, moved: (10, 2, 0); the leaf adds z 2.
    assert!(close(got[0][1], Vec3::new(10.0, 2.0, 0.0)));
    assert!(close(got[1][1], Vec3::new(10.0, 2.0, 2.0)));
}

#[test]
fn a_mirroring_node_keeps_front_faces_in_front() {
    let mut a = Asset::new();
    let n = a.floats(&[0.0, 0.0, 1.0].repeat(3), "VEC3");
    let mesh = a.triangle(json!({ "attributes": { "NORMAL": n } }));
    let plain = a.node(json!({ "mesh": mesh }));
    let mirrored = a.node(json!({ "mesh": mesh, "scale": [-1, 1, 1] }));
    a.scene(&[plain, mirrored]);
    let scene = load(&a);
    for [p0, p1, p2] in corners(&scene) {
        let n = (p1 - p0).cross(p2 - p0);
        assert!(n.z > 0.0, "the front face turned away: {n}");
    }
    // The shading normals stay +Z too (the normal matrix of a mirror in x keeps z).
    assert!(scene.mesh.normals.iter().all(|n| close(*n, Vec3::Z)));
}

#[test]
fn texture_coordinates_of_every_component_type() {
    // (u, v) pairs as floats, normalized unsigned bytes and normalized unsigned shorts.
    let uv = [[0.0f32, 0.0], [1.0, 0.5], [0.25, 1.0]];
    let mut a = Asset::new();
    let p = a.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let floats: Vec<f32> = uv.iter().flatten().copied().collect();
    let t_f32 = a.floats(&floats, "VEC2");
    let bytes: Vec<u8> = floats.iter().map(|x| (x * 255.0).round() as u8).collect();
    let t_u8 = a.accessor(&bytes, UNSIGNED_BYTE, 3, "VEC2", true);
    let shorts: Vec<u8> = floats
        .iter()
        .flat_map(|x| ((x * 65535.0).round() as u16).to_le_bytes())
        .collect();
    let t_u16 = a.accessor(&shorts, UNSIGNED_SHORT, 3, "VEC2", true);
    let i_u8 = a.accessor(&[0, 1, 2], UNSIGNED_BYTE, 3, "SCALAR", false);
    let i_u16 = a.accessor(&[0, 0, 1, 0, 2, 0], UNSIGNED_SHORT, 3, "SCALAR", false);
    let i_u32 = a.indices(&[0, 1, 2]);
    let mut nodes = Vec::new();
    for (t, i) in [(t_f32, i_u8), (t_u8, i_u16), (t_u16, i_u32)] {
        let mesh =
            a.mesh(json!({ "attributes": { "POSITION": p, "TEXCOORD_0": t }, "indices": i }));
        nodes.push(a.node(json!({ "mesh": mesh })));
    }
    a.scene(&nodes);
    let scene = load(&a);
    let mesh = &scene.mesh;
    assert_eq!(mesh.triangles.len(), 3);
    for t in &mesh.triangles {
        for (k, &i) in t.t.iter().enumerate() {
            // As glTF gives them: (0, 0) is the image's top-left corner, as meshtrace's.
            let got = mesh.texcoords[i as usize];
            // Within a step of the 8-bit encoding.
            let error = (got - Vec2::from(uv[k])).abs().max_element();
            assert!(error < 1.0 / 255.0, "{got}");
        }
        assert_eq!(t.p, [t.p[0], t.p[0] + 1, t.p[0] + 2]);
    }
}

#[test]
fn quantized_attributes_with_khr_mesh_quantization() {
    let mut a = Asset::new();
    a.json["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
    a.json["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    // Positions as normalized shorts, normals as normalized bytes, texture coordinates as
    // plain (unnormalized) unsigned bytes, tangents as normalized shorts.
    let short = |x: f32| ((x * 32767.0).round() as i16).to_le_bytes();
    let pos: Vec<u8> = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.5]]
        .iter()
        .flat_map(|p: &[f32; 3]| p.iter().flat_map(|&x| short(x)).chain([0, 0]))
        .collect();
    // VEC3 of shorts is 6 bytes; a stride of 8 keeps the 4-byte alignment quantized files use.
    let view = a.view(&pos, Some(8));
    let p = a.push(
        "accessors",
        json!({ "bufferView": view, "componentType": SHORT, "normalized": true, "count": 3, "type": "VEC3" }),
    );
    let n_bytes: Vec<u8> = [0i8, 0, 127, 0, 0, 0, 127, 0, 0, 0, -128, 0]
        .iter()
        .map(|&b| b as u8)
        .collect();
    // VEC3 of bytes padded to 4 bytes a vertex.
    let nv = a.view(&n_bytes, Some(4));
    let n = a.push(
        "accessors",
        json!({ "bufferView": nv, "componentType": BYTE, "normalized": true, "count": 3, "type": "VEC3" }),
    );
    let t = a.accessor(&[0, 0, 2, 1, 255, 3], UNSIGNED_BYTE, 3, "VEC2", false);
    let g: Vec<u8> = [1.0, 0.0, 0.0, -1.0]
        .repeat(3)
        .iter()
        .flat_map(|&x| short(x))
        .collect();
    let g = a.accessor(&g, SHORT, 3, "VEC4", true);
    a.triangle(json!({}));
    a.json["meshes"][0]["primitives"][0]["attributes"] =
        json!({ "POSITION": p, "NORMAL": n, "TEXCOORD_0": t, "TANGENT": g });
    let scene = load(&a);
    let mesh = &scene.mesh;
    assert!(close(mesh.positions[1], Vec3::X));
    assert!(close(
        mesh.positions[2],
        Vec3::new(0.0, -1.0, 16384.0 / 32767.0)
    ));
    assert!(close(mesh.normals[0], Vec3::Z));
    // -128 clamps to -1.
    assert!(close(mesh.normals[2], Vec3::NEG_Z));
    assert_eq!(mesh.texcoords[2], Vec2::new(255.0, 3.0));
    assert_eq!(mesh.tangents[0], Vec4::new(1.0, 0.0, 0.0, -1.0));
}

#[test]
fn tangents_follow_the_node_and_mirrors_turn_their_handedness() {
    let mut a = Asset::new();
    let g = a.floats(&[1.0, 0.0, 0.0, 1.0].repeat(3), "VEC4");
    let n = a.floats(&[0.0, 0.0, 1.0].repeat(3), "VEC3");
    let mesh = a.triangle(json!({ "attributes": { "TANGENT": g, "NORMAL": n } }));
    let q = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let turned = a.node(json!({ "mesh": mesh, "rotation": q.to_array(), "scale": [3, 3, 3] }));
    let mirrored = a.node(json!({ "mesh": mesh, "scale": [1, -1, 1] }));
    let flat = {
        let p = a.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        let m = a.mesh(json!({ "attributes": { "POSITION": p } }));
        a.node(json!({ "mesh": m }))
    };
    a.scene(&[0, turned, mirrored, flat]);
    let scene = load(&a);
    let mesh = &scene.mesh;
    assert_eq!(mesh.triangles.len(), 4);
    assert_eq!(mesh.tangent_corners.len(), 4, "one entry per triangle");
    let tangent = |tri: usize, k: usize| mesh.tangents[mesh.tangent_indices(tri)[k] as usize];
    assert_eq!(tangent(0, 0), Vec4::new(1.0, 0.0, 0.0, 1.0));
    // Turned a quarter about Z and scaled: +Y, renormalised, the same handedness.
    assert!(
        (tangent(1, 0) - Vec4::new(0.0, 1.0, 0.0, 1.0))
            .abs()
            .max_element()
            < 1e-6
    );
    // Mirrored in y: x stays, the handedness turns.
    assert_eq!(tangent(2, 0), Vec4::new(1.0, 0.0, 0.0, -1.0));
    assert_eq!(mesh.tangent_indices(3), [NO_TANGENT; 3]);
}

#[test]
fn sparse_accessors_over_a_buffer_view_and_over_zeros() {
    let mut a = Asset::new();
    let base = a.positions(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [9.0, 9.0, 9.0]]);
    // Replace vertex 3 by (1, 1, 0) through u8 sparse indices.
    let iv = a.view(&[3], None);
    let vals: Vec<u8> = [1.0f32, 1.0, 0.0]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let vv = a.view(&vals, None);
    a.json["accessors"][base]["sparse"] = json!({
        "count": 1,
        "indices": { "bufferView": iv, "componentType": UNSIGNED_BYTE },
        "values": { "bufferView": vv },
    });
    // An accessor of zeros but for u16-indexed and u32-indexed sparse values.
    let iv16 = a.view(&[1, 0, 2, 0], None);
    let normals: Vec<u8> = [[0.0f32, 0.0, 1.0], [0.0, 0.0, 1.0]]
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let nv = a.view(&normals, None);
    let zeros = a.push(
        "accessors",
        json!({
            "componentType": FLOAT, "count": 4, "type": "VEC3",
            "sparse": {
                "count": 2,
                "indices": { "bufferView": iv16, "componentType": UNSIGNED_SHORT, "byteOffset": 0 },
                "values": { "bufferView": nv },
            },
        }),
    );
    // Sparse indices of the index accessor itself, u32: [0, 1, 2] becomes [1, 3, 2].
    let idx = a.indices(&[0, 1, 2]);
    let siv = a.view(&[0, 0, 0, 0, 1, 0, 0, 0], None);
    let svv = a.view(&[1, 0, 0, 0, 3, 0, 0, 0], None);
    a.json["accessors"][idx]["sparse"] = json!({
        "count": 2,
        "indices": { "bufferView": siv, "componentType": UNSIGNED_INT },
        "values": { "bufferView": svv },
    });
    let mesh =
        a.mesh(json!({ "attributes": { "POSITION": base, "NORMAL": zeros }, "indices": idx }));
    let node = a.node(json!({ "mesh": mesh }));
    a.scene(&[node]);
    let scene = load(&a);
    let m = &scene.mesh;
    assert!(close(m.positions[3], Vec3::new(1.0, 1.0, 0.0)));
    assert_eq!(m.normals[0], Vec3::ZERO);
    assert!(close(m.normals[1], Vec3::Z) && close(m.normals[2], Vec3::Z));
    assert_eq!(m.triangles.len(), 1);
    assert_eq!(m.triangles[0].p, [1, 3, 2]);
    // Vertex 3's normal was zero, so the triangle is flat-shaded.
    assert_eq!(m.triangles[0].n, [meshtrace::scene::NO_NORMAL; 3]);
}

#[test]
fn strips_and_fans_make_triangles_in_the_specification_order() {
    // Five vertices along a zig-zag, so that no triangle is degenerate.
    let pts = [
        [0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [2.0, 0.0, 0.0],
    ];
    for (mode, expected) in [
        // strip: {v_i, v_(i+1+i%2), v_(i+2-i%2)}
        (5, vec![[0, 1, 2], [1, 3, 2], [2, 3, 4]]),
        // fan: {v_(i+1), v_(i+2), v_0}
        (6, vec![[1, 2, 0], [2, 3, 0], [3, 4, 0]]),
    ] {
        let mut a = Asset::new();
        let p = a.positions(&pts);
        let mesh = a.mesh(json!({ "attributes": { "POSITION": p }, "mode": mode }));
        let node = a.node(json!({ "mesh": mesh }));
        a.scene(&[node]);
        let scene = load(&a);
        let got: Vec<[u32; 3]> = scene.mesh.triangles.iter().map(|t| t.p).collect();
        assert_eq!(got, expected, "mode {mode}");
    }
}

#[test]
fn points_and_lines_are_skipped_with_a_warning() {
    let mut a = Asset::new();
    let mesh = a.triangle(json!({}));
    let p = a.json["meshes"][mesh]["primitives"][0]["attributes"]["POSITION"].clone();
    for mode in [0, 1, 2, 3] {
        a.json["meshes"][mesh]["primitives"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "attributes": { "POSITION": p }, "mode": mode }));
    }
    let scene = load(&a);
    assert_eq!(scene.mesh.triangles.len(), 1);
    let w = scene.warnings.join("\n");
    assert!(
        w.contains("meshes[0].primitives[1]: mode POINTS draws no triangles"),
        "{w}"
    );
    assert!(w.contains("LINE_STRIP"), "{w}");
}

/// A 2x1 RGBA PNG: a red and a green texel.
fn two_texels() -> Vec<u8> {
    png(2, 1, &[[255, 0, 0, 255], [0, 255, 0, 128]])
}

#[test]
fn materials_become_pbr_with_every_extension() {
    let mut a = Asset::new();
    a.json["extensionsUsed"] = json!([
        "KHR_materials_ior",
        "KHR_materials_specular",
        "KHR_materials_transmission",
        "KHR_materials_volume",
        "KHR_materials_emissive_strength",
        "KHR_texture_transform",
    ]);
    let image_view = a.view(&two_texels(), None);
    a.push(
        "images",
        json!({ "bufferView": image_view, "mimeType": "image/png" }),
    );
    // CLAMP_TO_EDGE along u, MIRRORED_REPEAT along v.
    a.push("samplers", json!({ "wrapS": 33071, "wrapT": 33648 }));
    a.push("textures", json!({ "source": 0, "sampler": 0 }));
    let t = a.floats(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0], "VEC2");
    let mesh = a.triangle(json!({ "attributes": { "TEXCOORD_0": t }, "material": 0 }));
    let prim = a.json["meshes"][mesh]["primitives"][0].clone();
    a.json["materials"] = json!([
        {
            "name": "textured",
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.5, 0.25, 1.0, 0.75],
                "baseColorTexture": { "index": 0 },
                "metallicFactor": 0.3, "roughnessFactor": 0.6,
                "metallicRoughnessTexture": { "index": 0 },
            },
            "normalTexture": { "index": 0, "scale": 0.5 },
            "emissiveTexture": { "index": 0 },
            "emissiveFactor": [1.0, 0.5, 0.0],
            "alphaMode": "MASK", "alphaCutoff": 0.3,
            "doubleSided": true,
            "extensions": {
                "KHR_materials_emissive_strength": { "emissiveStrength": 4.0 },
                "KHR_materials_ior": { "ior": 1.33 },
                "KHR_materials_specular": { "specularFactor": 0.7, "specularColorFactor": [1.0, 0.5, 2.0] },
                "KHR_materials_transmission": { "transmissionFactor": 0.9, "transmissionTexture": { "index": 0 } },
            },
        },
        {
            "alphaMode": "BLEND",
            "extensions": {
                "KHR_materials_transmission": { "transmissionFactor": 1.0 },
                "KHR_materials_volume": { "thicknessFactor": 0.1 },
            },
        },
    ]);
    for m in [1, -1] {
        let mut p = prim.clone();
        if m < 0 {
            p.as_object_mut().unwrap().remove("material");
        } else {
            p["material"] = json!(m);
        }
        let mesh = a.mesh(p);
        let node = a.node(json!({ "mesh": mesh }));
        a.json["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!(node));
    }
    let scene = load(&a);
    let material = |name: &str| {
        let i = scene
            .material_names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("no material {name} in {:?}", scene.material_names));
        scene.materials[i]
    };
    let m = material("textured");
    assert_eq!(m.kind, MaterialKind::PBR);
    assert_eq!(m.albedo, Vec3::new(0.5, 0.25, 1.0));
    assert_eq!((m.alpha, m.metallic, m.roughness), (0.75, 0.3, 0.6));
    assert_eq!(m.emission, Vec3::new(4.0, 2.0, 0.0));
    assert_eq!((m.ior, m.specular, m.transmission), (1.33, 0.7, 0.9));
    assert_eq!(m.specular_color, Vec3::new(1.0, 0.5, 2.0));
    assert_eq!(m.flags, MAT_ALPHA_MASK | MAT_THIN_WALLED);
    assert_eq!((m.alpha_cutoff, m.normal_scale), (0.3, 0.5));
    let records = &scene.textures.records;
    let record = |slot: u32| {
        assert_ne!(slot, NO_TEXTURE);
        records[slot as usize]
    };
    // One image, packed once, read as sRGB colour, linear channels and linear RGB.
    assert_eq!(record(m.albedo_texture).format, TextureFormat::RGBA8_SRGB);
    assert_eq!(record(m.emission_texture).format, TextureFormat::RGBA8_SRGB);
    assert_eq!(record(m.roughness_texture).channel, 1);
    assert_eq!(record(m.metallic_texture).channel, 2);
    assert_eq!(record(m.transmission_texture).channel, 0);
    let normal = record(m.normal_texture);
    assert_eq!(
        (normal.format, normal.channel),
        (TextureFormat::RGBA8_LINEAR, 0)
    );
    assert_eq!(
        record(m.roughness_texture).format,
        TextureFormat::RGBA8_LINEAR
    );
    assert!(
        records
            .iter()
            .all(|r| r.offset == records[0].offset && r.width == 2)
    );
    assert!(
        records
            .iter()
            .all(|r| r.wrap == Wrap::pack(Wrap::CLAMP, Wrap::MIRROR))
    );
    assert_eq!(scene.textures.texels.len(), 2, "the image is packed once");
    assert_eq!(
        scene.textures.texels[1],
        u32::from_le_bytes([0, 255, 0, 128])
    );

    let blend = material("materials[1]");
    assert_eq!(blend.flags, MAT_ALPHA_MASK, "a volume: not a thin wall");
    assert_eq!((blend.alpha_cutoff, blend.transmission), (0.5, 1.0));
    // The specification's default material.
    let d = material("default (glTF)");
    assert_eq!(
        (d.kind, d.metallic, d.roughness, d.albedo),
        (MaterialKind::PBR, 1.0, 1.0, Vec3::ONE)
    );
    let w = scene.warnings.join("\n");
    assert!(
        w.contains("materials[1].alphaMode: BLEND is rendered as MASK"),
        "{w}"
    );
    // An emissive material: the bare file is lit by it alone.
    assert_eq!(scene.sky, Sky::Constant(Vec3::ZERO));
}

#[test]
fn specular_glossiness_clearcoat_sheen_and_unlit_materials() {
    let mut a = Asset::new();
    a.json["extensionsUsed"] = json!([
        "KHR_materials_pbrSpecularGlossiness",
        "KHR_materials_clearcoat",
        "KHR_materials_sheen",
        "KHR_materials_unlit",
        "KHR_materials_specular",
        "KHR_materials_iridescence",
    ]);
    let image_view = a.view(&two_texels(), None);
    a.push(
        "images",
        json!({ "bufferView": image_view, "mimeType": "image/png" }),
    );
    a.push("textures", json!({ "source": 0 }));
    let t = a.floats(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0], "VEC2");
    let n = a.floats(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0], "VEC3");
    let mesh = a.triangle(json!({ "attributes": { "TEXCOORD_0": t, "NORMAL": n }, "material": 0 }));
    let prim = a.json["meshes"][mesh]["primitives"][0].clone();
    a.json["materials"] = json!([
        {
            "name": "specgloss",
            "pbrMetallicRoughness": { "baseColorFactor": [0.1, 0.1, 0.1, 1.0] },
            "extensions": { "KHR_materials_pbrSpecularGlossiness": {
                "diffuseFactor": [0.5, 0.25, 1.0, 0.75],
                "diffuseTexture": { "index": 0 },
                "specularFactor": [0.9, 0.6, 0.3],
                "glossinessFactor": 0.8,
                "specularGlossinessTexture": { "index": 0 },
            } },
        },
        {
            "name": "coated velvet",
            "pbrMetallicRoughness": { "roughnessFactor": 0.5 },
            "extensions": {
                "KHR_materials_clearcoat": {
                    "clearcoatFactor": 0.8, "clearcoatTexture": { "index": 0 },
                    "clearcoatRoughnessFactor": 0.2, "clearcoatRoughnessTexture": { "index": 0 },
                    "clearcoatNormalTexture": { "index": 0, "scale": 0.5 },
                },
                "KHR_materials_sheen": {
                    "sheenColorFactor": [1.0, 0.5, 0.25], "sheenColorTexture": { "index": 0 },
                    "sheenRoughnessFactor": 0.3, "sheenRoughnessTexture": { "index": 0 },
                },
                "KHR_materials_specular": {
                    "specularTexture": { "index": 0 }, "specularColorTexture": { "index": 0 },
                },
                "KHR_materials_iridescence": { "iridescenceFactor": 1.0 },
            },
        },
        {
            "name": "flat",
            "pbrMetallicRoughness": { "baseColorFactor": [0.2, 0.7, 0.3, 1.0] },
            "emissiveFactor": [1.0, 1.0, 1.0],
            "extensions": { "KHR_materials_unlit": {} },
        },
        {
            "name": "bad coat",
            "extensions": { "KHR_materials_clearcoat": { "clearcoatFactor": "thick" } },
        },
    ]);
    for m in [1, 2] {
        let mut p = prim.clone();
        p["material"] = json!(m);
        let mesh = a.mesh(p);
        let node = a.node(json!({ "mesh": mesh }));
        a.json["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!(node));
    }
    let scene = load(&a);
    let material = |name: &str| {
        let i = scene
            .material_names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("no material {name} in {:?}", scene.material_names));
        scene.materials[i]
    };
    let records = &scene.textures.records;
    let record = |slot: u32| {
        assert_ne!(slot, NO_TEXTURE);
        records[slot as usize]
    };

    // Specular-glossiness replaces the metallic-roughness parameters.
    let m = material("specgloss");
    assert_eq!(m.kind, MaterialKind::PBR);
    assert_eq!((m.albedo, m.alpha), (Vec3::new(0.5, 0.25, 1.0), 0.75));
    assert_eq!(m.specular_color, Vec3::new(0.9, 0.6, 0.3));
    assert_eq!((m.metallic, m.flags), (0.0, MAT_SPEC_GLOSS));
    assert!((m.roughness - 0.2).abs() < 1e-6, "{}", m.roughness);
    assert_eq!(record(m.albedo_texture).format, TextureFormat::RGBA8_SRGB);
    assert_eq!(
        record(m.specular_color_texture).format,
        TextureFormat::RGBA8_SRGB
    );
    // Glossiness in the alpha channel, linear.
    let gloss = record(m.roughness_texture);
    assert_eq!(
        (gloss.format, gloss.channel),
        (TextureFormat::RGBA8_LINEAR, 3)
    );

    let m = material("coated velvet");
    assert_eq!((m.clearcoat, m.clearcoat_roughness), (0.8, 0.2));
    assert_eq!(m.clearcoat_normal_scale, 0.5);
    assert_eq!(record(m.clearcoat_texture).channel, 0);
    assert_eq!(record(m.clearcoat_roughness_texture).channel, 1);
    assert_eq!(
        record(m.clearcoat_normal_texture).format,
        TextureFormat::RGBA8_LINEAR
    );
    assert_eq!(
        (m.sheen_color, m.sheen_roughness),
        (Vec3::new(1.0, 0.5, 0.25), 0.3)
    );
    assert_eq!(
        record(m.sheen_color_texture).format,
        TextureFormat::RGBA8_SRGB
    );
    assert_eq!(record(m.sheen_roughness_texture).channel, 3);
    assert_eq!(record(m.specular_texture).channel, 3);
    assert_eq!(
        record(m.specular_color_texture).format,
        TextureFormat::RGBA8_SRGB
    );
    // The coat's normal map needs tangents, which the loader generates.
    assert!(
        scene.mesh.tangents.iter().all(|t| t.truncate().is_finite())
            && !scene.mesh.tangents.is_empty()
    );

    // Unlit: the base colour alone; the emission is not read.
    let m = material("flat");
    assert_eq!(m.kind, MaterialKind::UNLIT);
    assert_eq!(
        (m.albedo, m.emission),
        (Vec3::new(0.2, 0.7, 0.3), Vec3::ZERO)
    );

    let w = scene.warnings.join("\n");
    assert!(
        w.contains("materials[1].extensions.KHR_materials_iridescence: is not supported; the material is rendered without it"),
        "{w}"
    );
    assert!(
        !w.contains("extensionsUsed"),
        "material extensions are warned of per material: {w}"
    );

    // A malformed extension object is an error naming its path.
    let mut bad = a.clone();
    for mesh in bad.json["meshes"].as_array_mut().unwrap() {
        mesh["primitives"][0]["material"] = json!(3);
    }
    let dir = TempDir::new("bad coat");
    let err = load_scene(&dir.write("bad.gltf", bad.embedded()))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("materials[3].extensions.KHR_materials_clearcoat: is malformed"),
        "{err}"
    );
}

#[test]
fn out_of_range_factors_are_clamped_with_a_warning() {
    let mut a = Asset::new();
    a.triangle(json!({ "material": 0 }));
    a.json["materials"] = json!([{ "pbrMetallicRoughness": { "metallicFactor": 1.5 } }]);
    let scene = load(&a);
    assert_eq!(scene.materials[0].metallic, 1.0);
    let w = scene.warnings.join("\n");
    assert!(
        w.contains("materials[0].pbrMetallicRoughness.metallicFactor: 1.5 is outside [0, 1]"),
        "{w}"
    );
}

#[test]
fn texture_transforms_reach_the_texture_records() {
    let mut a = Asset::new();
    let image_view = a.view(&two_texels(), None);
    a.push(
        "images",
        json!({ "bufferView": image_view, "mimeType": "image/png" }),
    );
    a.push("textures", json!({ "source": 0 }));
    let t = a.floats(&[0.0; 6], "VEC2");
    let t1 = a.floats(&[0.5; 6], "VEC2");
    a.triangle(json!({ "attributes": { "TEXCOORD_0": t, "TEXCOORD_1": t1 }, "material": 0 }));
    let r = 0.5f32;
    a.json["materials"] = json!([{
        "pbrMetallicRoughness": { "baseColorTexture": { "index": 0, "texCoord": 0,
            "extensions": { "KHR_texture_transform": {
                "offset": [0.25, 0.5], "rotation": r, "scale": [2.0, 3.0], "texCoord": 1 } } } },
        "normalTexture": { "index": 0,
            "extensions": { "KHR_texture_transform": { "offset": [0.125, 0.0] } } },
        "emissiveTexture": { "index": 0, "texCoord": 2 },
    }]);
    let scene = load(&a);
    let m = scene.materials[0];
    let base = scene.textures.records[m.albedo_texture as usize];
    let (s, c) = r.sin_cos();
    let expected = [c * 2.0, s * 3.0, -s * 2.0, c * 3.0];
    for (g, e) in base.uv_matrix.iter().zip(expected) {
        assert!((g - e).abs() < 1e-6, "{:?} vs {expected:?}", base.uv_matrix);
    }
    assert_eq!(base.uv_offset, [0.25, 0.5]);
    let normal = scene.textures.records[m.normal_texture as usize];
    assert_eq!(
        (normal.uv_matrix, normal.uv_offset),
        ([1.0, 0.0, 0.0, 1.0], [0.125, 0.0])
    );
    // The extension's texCoord overrides the texture's own: set 1 is read; set 2 is not.
    assert_eq!(base.uv_set, 1);
    assert_eq!(normal.uv_set, 0);
    let emissive = scene.textures.records[m.emission_texture as usize];
    assert_eq!(emissive.uv_set, 0);
    let w = scene.warnings.join("\n");
    assert!(!w.contains("baseColorTexture"), "{w}");
    assert!(
        w.contains("emissiveTexture: TEXCOORD_2 is not supported (only TEXCOORD_0 and TEXCOORD_1 are); TEXCOORD_0 is used"),
        "{w}"
    );
}

/// COLOR_0 as normalised unsigned bytes, RGB, and TEXCOORD_1 reach the mesh: each
/// triangle's colour and second-set corners index the file's values, and the texture
/// record on set 1 reads them through `triangle_uv`'s zw.
#[test]
fn vertex_colors_and_a_second_texture_coordinate_set_reach_the_mesh() {
    use meshtrace::render::texture::{triangle_color, triangle_uv};
    let mut a = Asset::new();
    let image_view = a.view(&two_texels(), None);
    a.push(
        "images",
        json!({ "bufferView": image_view, "mimeType": "image/png" }),
    );
    a.push("textures", json!({ "source": 0 }));
    let t0 = a.floats(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0], "VEC2");
    let t1 = a.floats(&[0.25, 0.75, 0.5, 0.5, 0.75, 0.25], "VEC2");
    let bytes = [255u8, 0, 0, 0, 255, 0, 0, 0, 51, 0];
    let c = a.accessor(&bytes[..9], common::gltf::UNSIGNED_BYTE, 3, "VEC3", true);
    a.triangle(json!({
        "attributes": { "TEXCOORD_0": t0, "TEXCOORD_1": t1, "COLOR_0": c }, "material": 0 }));
    a.json["materials"] = json!([{
        "pbrMetallicRoughness": { "baseColorTexture": { "index": 0, "texCoord": 1 } } }]);
    let scene = load(&a);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let mesh = &scene.mesh;
    let colors = mesh.color_indices(0).map(|k| mesh.colors[k as usize]);
    assert_eq!(colors[0], glam::Vec4::new(1.0, 0.0, 0.0, 1.0));
    assert_eq!(colors[1], glam::Vec4::new(0.0, 1.0, 0.0, 1.0));
    assert!(
        (colors[2] - glam::Vec4::new(0.0, 0.0, 0.2, 1.0))
            .abs()
            .max_element()
            < 1e-6
    );
    let second = mesh.uv1_indices(0).map(|k| mesh.texcoords[k as usize]);
    assert_eq!(
        second,
        [
            Vec2::new(0.25, 0.75),
            Vec2::new(0.5, 0.5),
            Vec2::new(0.75, 0.25)
        ]
    );
    let rs = meshtrace::render::RenderScene::new(&scene, &Default::default()).unwrap();
    let (b1, b2) = (0.2, 0.3);
    let uv = triangle_uv(&rs, 0, b1, b2);
    let expect1 = 0.5 * second[0] + b1 * second[1] + b2 * second[2];
    let expect0 = b1 * Vec2::new(1.0, 0.0) + b2 * Vec2::new(0.0, 1.0);
    assert!(
        (Vec2::new(uv.z, uv.w) - expect1).abs().max_element() < 1e-6,
        "{uv}"
    );
    assert!(
        (Vec2::new(uv.x, uv.y) - expect0).abs().max_element() < 1e-6,
        "{uv}"
    );
    let color = triangle_color(&rs, 0, b1, b2);
    let expect = 0.5 * colors[0] + b1 * colors[1] + b2 * colors[2];
    assert!((color - expect).abs().max_element() < 1e-6, "{color}");
}

/// A texture on TEXCOORD_1 of a primitive without that set is an error naming the
/// primitive.
#[test]
fn a_texture_on_a_missing_second_set_is_an_error() {
    let mut a = Asset::new();
    let image_view = a.view(&two_texels(), None);
    a.push(
        "images",
        json!({ "bufferView": image_view, "mimeType": "image/png" }),
    );
    a.push("textures", json!({ "source": 0 }));
    let t0 = a.floats(&[0.0; 6], "VEC2");
    a.triangle(json!({ "attributes": { "TEXCOORD_0": t0 }, "material": 0 }));
    a.json["materials"] = json!([{
        "pbrMetallicRoughness": { "baseColorTexture": { "index": 0, "texCoord": 1 } } }]);
    let dir = TempDir::new("gltf-set1");
    let path = dir.write("a.gltf", a.embedded());
    let e = load_scene(&path).expect_err("set 1 is missing").to_string();
    assert!(
        e.contains("a.gltf: meshes[0].primitives[0]: material `materials[0]` reads a texture through TEXCOORD_1, but the mesh has faces without a second texture coordinate set"),
        "{e}"
    );
    assert_eq!(e.lines().count(), 1);
}

#[test]
fn images_embedded_external_and_in_buffer_views_read_alike() {
    let dir = TempDir::new("gltf-images");
    dir.write("tex dir.png", two_texels());
    let mut a = Asset::new();
    let image_view = a.view(&two_texels(), None);
    a.json["images"] = json!([
        { "uri": format!("data:image/png;base64,{}", base64(&two_texels())) },
        { "uri": "tex%20dir.png" },
        { "bufferView": image_view, "mimeType": "image/png" },
        { "uri": "missing.png" },
    ]);
    a.json["textures"] =
        json!([{ "source": 0 }, { "source": 1 }, { "source": 2 }, { "source": 3 }]);
    let t = a.floats(&[0.0; 6], "VEC2");
    let mesh = a.triangle(json!({ "attributes": { "TEXCOORD_0": t }, "material": 0 }));
    let prim = a.json["meshes"][mesh]["primitives"][0].clone();
    let mut materials = Vec::new();
    for k in 0..4 {
        materials.push(json!({ "pbrMetallicRoughness": { "baseColorTexture": { "index": k } } }));
        let mut p = prim.clone();
        p["material"] = json!(k);
        let m = a.mesh(p);
        let n = a.node(json!({ "mesh": m }));
        a.json["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!(n));
    }
    a.json["materials"] = json!(materials);
    for (name, bytes) in [("a.gltf", a.embedded()), ("b.glb", a.glb())] {
        let path = dir.write(name, bytes);
        let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
        let slots: Vec<u32> = scene.materials.iter().map(|m| m.albedo_texture).collect();
        assert_eq!(
            slots[3], NO_TEXTURE,
            "{name}: a missing image falls back to the factor"
        );
        let texels = &scene.textures.texels;
        for &s in &slots[..3] {
            let r = scene.textures.records[s as usize];
            let t = &texels[r.offset as usize..r.offset as usize + 2];
            assert_eq!(
                t,
                [
                    u32::from_le_bytes([255, 0, 0, 255]),
                    u32::from_le_bytes([0, 255, 0, 128])
                ]
            );
        }
        let w = scene.warnings.join("\n");
        assert!(
            w.contains("images[3].uri: image") && w.contains("missing.png could not be read"),
            "{w}"
        );
    }
}

#[test]
fn gltf_with_embedded_or_external_buffers_and_glb_load_the_same() {
    let mut a = Asset::new();
    let n = a.floats(&[0.0, 0.0, 1.0].repeat(3), "VEC3");
    a.triangle(json!({ "attributes": { "NORMAL": n } }));
    let dir = TempDir::new("gltf-forms");
    let bare =
        |path: std::path::PathBuf| common::studio::without_ground(load_scene(&path).unwrap());
    let embedded = bare(dir.write("e.gltf", a.embedded()));
    let (json, bin) = a.external("sub/buffer data.bin");
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    dir.write("sub/buffer data.bin", bin);
    let external = bare(dir.write("x.gltf", json));
    let glb = bare(dir.write("g.glb", a.glb()));
    for s in [&external, &glb] {
        assert_eq!(s.mesh.positions, embedded.mesh.positions);
        assert_eq!(s.mesh.normals, embedded.mesh.normals);
        assert_eq!(s.mesh.triangles, embedded.mesh.triangles);
    }
    assert_eq!(embedded.mesh.triangles.len(), 1);
    // Upper-case extensions are read too.
    assert!(load_scene(&dir.write("G.GLB", a.glb())).is_ok());
}

#[test]
fn the_first_camera_in_the_node_tree() {
    let mut a = Asset::new();
    let mesh = a.triangle(json!({}));
    a.json["cameras"] = json!([
        { "type": "orthographic", "orthographic": { "xmag": 1, "ymag": 0.75, "zfar": 10, "znear": 0.1 } },
        { "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.1, "aspectRatio": 3.0 } },
        { "type": "perspective", "perspective": { "yfov": 1.0, "znear": 0.1 } },
    ]);
    // Depth first: the orthographic camera's node, then a child holding camera 1, then a
    // later root with camera 2.
    let q = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let child = a.node(json!({ "camera": 1, "translation": [0, 0, 5] }));
    let ortho = a.node(json!({ "camera": 0, "children": [child], "rotation": q.to_array(), "translation": [1, 2, 3] }));
    let later = a.node(json!({ "camera": 2 }));
    a.scene(&[0, ortho, later]);
    let _ = mesh;
    let scene = load(&a);
    let c = &scene.camera;
    assert!(
        close(c.position, Vec3::new(1.0, 2.0, 3.0)),
        "{}",
        c.position
    );
    assert!(
        close(c.forward, Vec3::NEG_X) && close(c.up, Vec3::Y),
        "{c:?}"
    );
    assert!(c.is_orthographic() && c.ortho_height == 1.5, "{c:?}");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);

    // Without it, the perspective camera of the child, placed by both nodes' transforms.
    a.json["nodes"][ortho]["camera"] = json!(null);
    a.json["nodes"][ortho]
        .as_object_mut()
        .expect("a node")
        .remove("camera");
    let scene = load(&a);
    let world = Mat4::from_rotation_translation(q, Vec3::new(1.0, 2.0, 3.0))
        * Mat4::from_translation(Vec3::new(0.0, 0.0, 5.0));
    let position = world.transform_point3(Vec3::ZERO);
    let c = &scene.camera;
    assert!(close(c.position, position), "{}", c.position);
    assert!(close(c.forward, Vec3::NEG_X), "{c:?}");
    assert!(!c.is_orthographic());
    assert!((c.vfov - 0.5f32.to_degrees()).abs() < 1e-4);
}

#[test]
fn punctual_lights_in_radiometric_units() {
    let mut a = Asset::new();
    a.json["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    a.json["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
        { "type": "point", "color": [1.0, 0.5, 0.0], "intensity": 683.0, "range": 10.0 },
        { "type": "spot", "intensity": 1366.0, "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.5 } },
        { "type": "directional", "intensity": 68.3 },
    ] } });
    let mesh = a.triangle(json!({}));
    let _ = mesh;
    let down = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    let point = a.node(json!({ "translation": [1, 2, 3],
        "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
    let spot = a.node(
        json!({ "translation": [0, 4, 0], "rotation": down.to_array(),
        "extensions": { "KHR_lights_punctual": { "light": 1 } } }),
    );
    let sun = a.node(json!({ "rotation": down.to_array(),
        "extensions": { "KHR_lights_punctual": { "light": 2 } } }));
    a.scene(&[0, point, spot, sun]);
    let scene = load(&a);
    assert_eq!(scene.lights.len(), 3);
    let PunctualLight::Point {
        position,
        intensity,
    } = scene.lights[0]
    else {
        panic!("{:?}", scene.lights[0]);
    };
    assert!(close(position, Vec3::new(1.0, 2.0, 3.0)));
    assert!(
        close(intensity, Vec3::new(1.0, 0.5, 0.0)),
        "candela / 683 = W/sr: {intensity}"
    );
    let PunctualLight::Spot {
        position,
        direction,
        intensity,
        cutoff,
        beam_width,
    } = scene.lights[1]
    else {
        panic!("{:?}", scene.lights[1]);
    };
    assert!(close(position, Vec3::new(0.0, 4.0, 0.0)));
    assert!(close(direction, Vec3::NEG_Y), "-Z turned down: {direction}");
    assert!(close(intensity, Vec3::splat(2.0)));
    assert_eq!((cutoff, beam_width), (0.5, 0.2));
    let PunctualLight::Directional {
        direction,
        irradiance,
        shadows: true,
    } = scene.lights[2]
    else {
        panic!("{:?}", scene.lights[2]);
    };
    assert!(close(direction, Vec3::NEG_Y));
    assert!(
        close(irradiance, Vec3::splat(0.1)),
        "lux / 683 = W/m²: {irradiance}"
    );
    let w = scene.warnings.join("\n");
    assert!(w.contains("lights[0].range: is ignored"), "{w}");
    // A file with its own lights is lit by them alone.
    assert_eq!(scene.sky, Sky::Constant(Vec3::ZERO));
}

/// A bare file without camera or light is shown in the studio: its camera, its
/// environment, and a ground under it.
#[test]
fn a_bare_file_without_camera_or_light_is_shown_in_the_studio() {
    let mut a = Asset::new();
    a.triangle(json!({}));
    a.json["nodes"][0]["translation"] = json!([5, 0, 0]);
    let dir = TempDir::new("gltf-studio");
    let scene = load_scene(&dir.write("a.gltf", a.embedded())).unwrap();
    assert!(
        matches!(scene.sky, Sky::Environment { .. }),
        "{:?}",
        scene.sky
    );
    assert_eq!(scene.mesh.triangles.len(), 3, "the triangle and the ground");
    let scene = common::studio::without_ground(scene);
    let bounds = meshtrace::math::Aabb::from_points(&[
        Vec3::new(5.0, 0.0, 0.0),
        Vec3::new(6.0, 0.0, 0.0),
        Vec3::new(5.0, 1.0, 0.0),
    ]);
    assert_eq!(scene.camera, studio::camera(&bounds).unwrap());
}

#[test]
fn gltf_meshes_in_scene_files_with_their_materials_and_lights() {
    let dir = TempDir::new("gltf-toml");
    let mut a = Asset::new();
    a.json["extensions"] = json!({ "KHR_lights_punctual": { "lights": [{ "type": "point" }] } });
    a.triangle(json!({ "material": 0 }));
    a.json["nodes"][0]["translation"] = json!([0, 0, 1]);
    a.json["nodes"][0]["extensions"] = json!({ "KHR_lights_punctual": { "light": 0 } });
    a.json["materials"] =
        json!([{ "name": "red", "pbrMetallicRoughness": { "baseColorFactor": [1, 0, 0, 1] } }]);
    dir.write("m.glb", a.glb());
    let toml = r#"
[camera]
position = [0, 0, 10]
look_at = [0, 0, 0]

[materials.grey]
type = "diffuse"
albedo = [0.5, 0.5, 0.5]

[[objects]]
mesh = "m.glb"
translate = [10, 0, 0]

[[objects]]
mesh = "m.glb"
material = "grey"
scale = 2.0
"#;
    let scene = load_scene(&dir.write("s.toml", toml)).unwrap_or_else(|e| panic!("{e}"));
    let c = corners(&scene);
    assert_eq!(c.len(), 2);
    // The node's translation, then the object's transform on top.
    assert!(close(c[0][1], Vec3::new(11.0, 0.0, 1.0)));
    assert!(close(c[1][1], Vec3::new(2.0, 0.0, 2.0)));
    let names: Vec<&str> = scene
        .mesh
        .triangles
        .iter()
        .map(|t| scene.material_names[t.material as usize].as_str())
        .collect();
    assert_eq!(names, ["red", "grey"]);
    assert_eq!(
        scene.materials[scene.mesh.triangles[0].material as usize].albedo,
        Vec3::X
    );
    // Each object brings the file's light, placed by the node and then the object.
    let positions: Vec<Vec3> = scene
        .lights
        .iter()
        .map(|l| match l {
            PunctualLight::Point { position, .. } => *position,
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(
        positions,
        [Vec3::new(10.0, 0.0, 1.0), Vec3::new(0.0, 0.0, 2.0)]
    );
}

#[test]
fn objects_whose_mesh_has_no_faces_are_errors() {
    let dir = TempDir::new("no-faces");
    dir.write("empty.obj", "# nothing\nfoo bar\nv 0 0 0\n");
    let mut a = Asset::new();
    let p = a.positions(&[[0.0; 3], [1.0, 0.0, 0.0]]);
    let mesh = a.mesh(json!({ "attributes": { "POSITION": p }, "mode": 1 }));
    let node = a.node(json!({ "mesh": mesh }));
    a.scene(&[node]);
    dir.write("lines.gltf", a.embedded());
    for (i, mesh) in ["empty.obj", "lines.gltf"].iter().enumerate() {
        let toml = format!(
            "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\n[[objects]]\nmesh = \"box.obj\"\n\n[[objects]]\nmesh = \"{mesh}\"\n"
        );
        dir.write("box.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        let err = load_scene(&dir.write(&format!("s{i}.toml"), toml))
            .unwrap_err()
            .to_string();
        assert!(err.contains("s") && err.contains(": objects[1]: "), "{err}");
        assert!(err.contains(&format!("{mesh} has no faces")), "{err}");
    }
    // As a bare file, a glTF scene without triangles is an error too.
    let err = load_scene(&dir.join("lines.gltf")).unwrap_err().to_string();
    assert!(
        err.ends_with("lines.gltf: scene: the default scene has no triangles to render"),
        "{err}"
    );
}

#[test]
fn other_extensions_say_which_inputs_are_read() {
    let dir = TempDir::new("inputs");
    for name in ["README.md", "scene", "model.fbx"] {
        let err = load_scene(&dir.write(name, "# text"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(name)
                && err.contains("(.toml)")
                && err.contains("(.obj)")
                && err.contains(".gltf, .glb"),
            "{err}"
        );
    }
}

/// A WebP file's bytes (lossless): `width` × `height` texels of one colour.
fn webp(width: u32, height: u32, colour: [u8; 4]) -> Vec<u8> {
    let image = image::RgbaImage::from_pixel(width, height, image::Rgba(colour));
    let mut bytes = Vec::new();
    image::codecs::webp::WebPEncoder::new_lossless(&mut bytes)
        .encode(&image, width, height, image::ExtendedColorType::Rgba8)
        .unwrap();
    bytes
}

/// EXT_texture_webp: a texture whose extension names a WebP image reads it, not the PNG
/// its `source` keeps as a fallback; a texture with the extension alone reads it too; the
/// WebP may come as a `data:` URI of type image/webp or a buffer view; the extension,
/// required or used, gives no warning.
#[test]
fn ext_texture_webp_is_preferred_over_the_fallback_source() {
    let red = [255, 0, 0, 255];
    let blue = [0, 0, 255, 255];
    let mut a = Asset::new();
    let t = a.floats(&[0.0; 6], "VEC2");
    a.triangle(json!({ "attributes": { "TEXCOORD_0": t }, "material": 0 }));
    let view = a.view(&webp(2, 2, blue), None);
    a.json["images"] = json!([
        { "uri": format!("data:image/png;base64,{}", base64(&png(2, 2, &[red; 4]))) },
        { "uri": format!("data:image/webp;base64,{}", base64(&webp(2, 1, blue))) },
        { "bufferView": view, "mimeType": "image/webp" },
    ]);
    a.json["extensionsUsed"] = json!(["EXT_texture_webp"]);
    a.json["extensionsRequired"] = json!(["EXT_texture_webp"]);
    a.json["materials"] =
        json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]);
    for (texture, size) in [
        (
            json!({ "source": 0, "extensions": { "EXT_texture_webp": { "source": 1 } } }),
            (2, 1),
        ),
        (
            json!({ "extensions": { "EXT_texture_webp": { "source": 2 } } }),
            (2, 2),
        ),
        (json!({ "source": 0 }), (2, 2)),
    ] {
        a.json["textures"] = json!([texture]);
        let s = load(&a);
        assert!(s.warnings.is_empty(), "{texture}: {:?}", s.warnings);
        let t = s.textures.records[s.materials[0].albedo_texture as usize];
        assert_eq!((t.width, t.height), size, "{texture}");
        let want = if texture.get("extensions").is_some() {
            blue
        } else {
            red
        };
        assert_eq!(
            s.textures.texels[t.offset as usize].to_le_bytes(),
            want,
            "{texture}"
        );
    }
}

/// A normal map on TEXCOORD_1 of a primitive without TANGENT gets MikkTSpace tangents
/// from that set: where the second set's u runs along +y (the first set's along +x), the
/// generated tangents point along +y.
#[test]
fn generated_tangents_follow_the_set_the_normal_map_reads() {
    for (set, along) in [(0, Vec3::X), (1, Vec3::Y)] {
        let mut a = Asset::new();
        let image_view = a.view(&two_texels(), None);
        a.push(
            "images",
            json!({ "bufferView": image_view, "mimeType": "image/png" }),
        );
        a.push("textures", json!({ "source": 0 }));
        // Corners (0,0,0), (1,0,0), (0,1,0): set 0 is (x, 1 − y), set 1 is (y, x).
        let t0 = a.floats(&[0.0, 1.0, 1.0, 1.0, 0.0, 0.0], "VEC2");
        let t1 = a.floats(&[0.0, 0.0, 0.0, 1.0, 1.0, 0.0], "VEC2");
        let n = a.floats(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0], "VEC3");
        a.triangle(
            json!({ "attributes": { "TEXCOORD_0": t0, "TEXCOORD_1": t1, "NORMAL": n },
            "material": 0 }),
        );
        a.json["materials"] = json!([{ "normalTexture": { "index": 0, "texCoord": set } }]);
        let scene = load(&a);
        let mesh = &scene.mesh;
        for k in mesh.tangent_indices(0) {
            let t = mesh.tangents[k as usize];
            assert!(
                close(t.truncate(), along),
                "set {set}: tangent {t}, want {along}"
            );
        }
    }
}
