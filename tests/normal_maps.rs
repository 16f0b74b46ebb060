//! Normal maps against their closed form, on both renderers. A camera with a tiny field of
//! view looks straight down at a Lambertian floor of albedo rho whose normal map is one
//! colour, lit by a directional light alone (paths of two segments: no noise). Every pixel
//! then sees rho / pi × E × max(0, n · l), n the mapped normal: the map's texel decoded to
//! (2 × texel − 1), x and y scaled by the strength, in the frame tangent = dP/du,
//! bitangent = the direction up the image, normal = +Y. The light is placed so that a
//! wrong sign of either axis, a swapped axis or a missing map gives a different value.
//! Tangents come from MikkTSpace (OBJ, glTF without TANGENT) or from the file.

use crate::common;

use common::fs::TempDir;
use common::gltf::Asset;
use glam::Vec3;
use meshtrace::scene::load_scene;
use serde_json::json;

const RHO: f32 = 0.6;
const E: f32 = 2.0;

/// The floor, y = 0 facing +Y, its texture's u running along +X (or −X, `mirrored`) and
/// its image's up along −Z (OBJ vt v up).
fn floor_obj(mirrored: bool) -> String {
    let u = |u: f32| if mirrored { 1.0 - u } else { u };
    format!(
        "v -50 0 -50\nv 50 0 -50\nv 50 0 50\nv -50 0 50\n\
         vt {} 1\nvt {} 1\nvt {} 0\nvt {} 0\nf 1/1 4/4 3/3 2/2\n",
        u(0.0),
        u(1.0),
        u(1.0),
        u(0.0)
    )
}

/// The scene file around an object line, a material line and a light direction.
fn scene_toml(object: &str, material: &str, light: Vec3) -> String {
    format!(
        "[camera]\nposition = [0.0, 1.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\n\
         vfov = 0.2\n[render]\nwidth = 8\nheight = 8\nspp = 2\nmax_depth = 2\n\
         [materials.floor]\ntype = \"diffuse\"\nalbedo = [{RHO}, {RHO}, {RHO}]\n{material}\n\
         [[objects]]\n{object}\n[[lights]]\ntype = \"directional\"\n\
         direction = [{}, {}, {}]\nirradiance = [{E}, {E}, {E}]\n",
        light.x, light.y, light.z
    )
}

/// The radiance every pixel of `scene` sees, on each renderer (pixels must agree).
fn radiance(name: &str, scene: &std::path::Path) -> Vec<(&'static str, f32)> {
    let scene = load_scene(scene).unwrap_or_else(|e| panic!("{name}: {e}"));
    common::render_both(name, &scene)
        .into_iter()
        .map(|(device, film)| {
            let mean = film.mean();
            let first = mean[0];
            for p in &mean {
                assert!(
                    (*p - first).abs().max_element() <= 1e-5 * first.max_element() + 1e-7,
                    "{name} on the {device}: pixels vary: {p} against {first}"
                );
                assert!((p.x - p.y).abs() <= 1e-6 * p.x.abs() + 1e-7, "{name}: grey");
            }
            (device, first.x)
        })
        .collect()
}

/// The mapped normal of `texel` with `strength`, in the frame (t, b, +Y).
fn mapped(texel: [u8; 3], strength: f32, t: Vec3, b: Vec3) -> Vec3 {
    let c = Vec3::from(texel.map(|k| k as f32 / 255.0)) * 2.0 - Vec3::ONE;
    (t * (c.x * strength) + b * (c.y * strength) + Vec3::Y * c.z).normalize()
}

fn expect(name: &str, got: Vec<(&'static str, f32)>, n: Vec3, light: Vec3) {
    let want = RHO / std::f32::consts::PI * E * n.dot(-light.normalize()).max(0.0);
    for (device, l) in got {
        assert!(
            (l - want).abs() <= 1e-4 * want + 1e-6,
            "{name} on the {device}: {l} against {want} (mapped normal {n})"
        );
    }
}

/// A floor OBJ with a one-colour normal map of `texel`, rendered under `light`.
fn obj_case(name: &str, texel: [u8; 3], strength: Option<f32>, mirrored: bool, light: Vec3) {
    let dir = TempDir::new(name);
    dir.write("floor.obj", floor_obj(mirrored));
    let [r, g, b] = texel;
    dir.write_png("n.png", 4, 4, &[[r, g, b, 255]; 16]);
    let given = strength.map_or(String::new(), |s| format!(", strength = {s}"));
    let material = format!(
        "[materials.mapped]\ntype = \"diffuse\"\nalbedo = [{RHO}, {RHO}, {RHO}]\n\
         normal_map = {{ texture = \"n.png\"{given} }}"
    );
    let path = dir.write(
        "scene.toml",
        scene_toml(
            "mesh = \"floor.obj\"\nmaterial = \"mapped\"",
            &material,
            light,
        ),
    );
    let got = radiance(name, &path);
    let t = if mirrored { -Vec3::X } else { Vec3::X };
    expect(
        name,
        got,
        mapped(texel, strength.unwrap_or(1.0), t, -Vec3::Z),
        light,
    );
}

/// Lights from +X and from −Z, 45 degrees up: the first sees a tilt along the tangent, the
/// second along the bitangent.
fn from_x() -> Vec3 {
    Vec3::new(-1.0, -1.0, 0.0)
}
fn from_minus_z() -> Vec3 {
    Vec3::new(0.0, -1.0, 1.0)
}

#[test]
fn a_normal_map_tilts_the_normal_along_the_tangent() {
    // Tilted towards +u (red up): brighter from +X.
    obj_case("tangent", [200, 128, 200], None, false, from_x());
    // Tilted towards −u: dimmer from +X.
    obj_case("tangent negative", [56, 128, 200], None, false, from_x());
}

#[test]
fn a_normal_map_tilts_the_normal_up_the_image_along_the_bitangent() {
    // Green up: tilted towards the image's top edge, −Z here.
    obj_case("bitangent", [128, 200, 200], None, false, from_minus_z());
    obj_case(
        "bitangent negative",
        [128, 56, 200],
        None,
        false,
        from_minus_z(),
    );
}

#[test]
fn mirrored_texture_coordinates_turn_the_tangent_but_not_the_bitangent() {
    obj_case("mirrored tangent", [200, 128, 200], None, true, from_x());
    obj_case(
        "mirrored bitangent",
        [128, 200, 200],
        None,
        true,
        from_minus_z(),
    );
}

#[test]
fn strength_scales_the_tilt_and_zero_leaves_the_surface_flat() {
    obj_case("strength half", [200, 160, 200], Some(0.5), false, from_x());
    obj_case("strength zero", [200, 160, 200], Some(0.0), false, from_x());
    obj_case("strength two", [150, 128, 220], Some(2.0), false, from_x());
}

/// The floor as a glTF file, its TEXCOORD_0 running down the image (v = 1 − OBJ's v), a
/// normal map of `texel` with `scale`, with or without a TANGENT attribute.
fn gltf_floor(texel: [u8; 3], scale: f32, tangent: Option<[f32; 4]>) -> Asset {
    let mut a = Asset::new();
    let p = a.positions(&[
        [-50.0, 0.0, -50.0],
        [50.0, 0.0, -50.0],
        [50.0, 0.0, 50.0],
        [-50.0, 0.0, 50.0],
    ]);
    let uv = a.floats(&[0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0], "VEC2");
    let n = a.floats(&[0.0, 1.0, 0.0].repeat(4), "VEC3");
    let i = a.indices(&[0, 3, 2, 0, 2, 1]);
    let mut attributes = json!({ "POSITION": p, "TEXCOORD_0": uv, "NORMAL": n });
    if let Some(g) = tangent {
        attributes["TANGENT"] = json!(a.floats(&g.repeat(4), "VEC4"));
    }
    let [r, g, b] = texel;
    let png = common::gltf::png(4, 4, &[[r, g, b, 255]; 16]);
    let view = a.view(&png, None);
    a.push(
        "images",
        json!({ "bufferView": view, "mimeType": "image/png" }),
    );
    a.push("textures", json!({ "source": 0 }));
    a.push(
        "materials",
        json!({
            "pbrMetallicRoughness": { "baseColorFactor": [RHO, RHO, RHO, 1.0], "metallicFactor": 0.0 },
            "normalTexture": { "index": 0, "scale": scale },
            "extensions": { "KHR_materials_specular": { "specularFactor": 0.0 } }
        }),
    );
    a.push("extensionsUsed", json!("KHR_materials_specular"));
    let mesh = a.mesh(json!({ "attributes": attributes, "indices": i, "material": 0 }));
    let node = a.node(json!({ "mesh": mesh }));
    a.scene(&[node]);
    a
}

fn gltf_case(name: &str, texel: [u8; 3], scale: f32, tangent: Option<[f32; 4]>, light: Vec3) {
    let dir = TempDir::new(name);
    dir.write("floor.gltf", gltf_floor(texel, scale, tangent).embedded());
    let path = dir.write("scene.toml", scene_toml("mesh = \"floor.gltf\"", "", light));
    let got = radiance(name, &path);
    let t = match tangent {
        Some(g) => Vec3::new(g[0], g[1], g[2]),
        None => Vec3::X,
    };
    let b = match tangent {
        Some(g) if g[3] < 0.0 => -Vec3::Y.cross(t),
        _ => Vec3::Y.cross(t),
    };
    expect(name, got, mapped(texel, scale, t, b), light);
}

#[test]
fn gltf_normal_maps_use_mikktspace_tangents_or_the_files() {
    // Without TANGENT, MikkTSpace gives tangent +X and bitangent −Z (up the image).
    gltf_case("gltf mikktspace u", [200, 128, 200], 1.0, None, from_x());
    gltf_case(
        "gltf mikktspace v",
        [128, 200, 200],
        1.0,
        None,
        from_minus_z(),
    );
    gltf_case("gltf scale", [200, 128, 200], 0.5, None, from_x());
    // The file's tangents are used as given, even where they disagree with the UVs.
    gltf_case(
        "gltf tangent",
        [200, 128, 200],
        1.0,
        Some([0.0, 0.0, 1.0, 1.0]),
        Vec3::new(0.0, -1.0, -1.0),
    );
    gltf_case(
        "gltf tangent handedness",
        [128, 200, 200],
        1.0,
        Some([1.0, 0.0, 0.0, -1.0]),
        Vec3::new(0.0, -1.0, -1.0),
    );
}
