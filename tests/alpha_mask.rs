//! Alpha-mask cut-outs in both traversals, on both renderers, against closed forms. A quad
//! hovers at y = 1 over a Lambertian floor, its albedo texture opaque on its +X half and
//! cut out (alpha 0) on its −X half; a directional light shines straight down, and a
//! camera with a tiny field of view looks straight down (paths of two segments: no noise).
//! From above, the camera sees through the cut-out half to the lit floor (closest-hit
//! traversal) and sees the opaque half itself; from between quad and floor, it sees the
//! floor lit under the cut-out half and in shadow under the opaque half (any-hit). An
//! unlit quad (KHR_materials_unlit) is seen by the camera as its colour and by no other
//! ray: it casts no shadow.

use crate::common;

use common::fs::TempDir;
use common::gltf::Asset;
use meshtrace::scene::load_scene;
use serde_json::json;

const FLOOR: f32 = 0.6;
const E: f32 = 2.0;

/// Radiance of a lit Lambertian surface of albedo `rho`.
fn lit(rho: f32) -> f32 {
    rho / std::f32::consts::PI * E
}

/// The hovering quad (y = 1, facing +Y), OBJ vt u running along +X.
const QUAD_OBJ: &str = "v -50 1 -50\nv 50 1 -50\nv 50 1 50\nv -50 1 50\n\
                        vt 0 1\nvt 1 1\nvt 1 0\nvt 0 0\nf 1/1 4/4 3/3 2/2\n";
const FLOOR_OBJ: &str = "v -50 0 -50\nv 50 0 -50\nv 50 0 50\nv -50 0 50\nf 1 4 3 2\n";

/// 8 × 1 texels: alpha 0 on the left half (u < 1/2), 255 on the right, white.
fn mask_texels() -> Vec<[u8; 4]> {
    (0..8)
        .map(|i| [255, 255, 255, if i < 4 { 0 } else { 255 }])
        .collect()
}

/// Renders `objects` and `materials` seen from `(x, height, 0)` straight down; the
/// radiance every pixel sees, on each renderer.
fn radiance(
    dir: &TempDir,
    name: &str,
    tables: &str,
    x: f32,
    height: f32,
) -> Vec<(&'static str, f32)> {
    let toml = format!(
        "[camera]\nposition = [{x}, {height}, 0.0]\nlook_at = [{x}, -1.0, 0.0]\nup = [0.0, 0.0, -1.0]\n\
         vfov = 0.2\n[render]\nwidth = 8\nheight = 8\nspp = 2\nmax_depth = 2\n\
         [materials.floor]\ntype = \"diffuse\"\nalbedo = [{FLOOR}, {FLOOR}, {FLOOR}]\n\
         [[objects]]\nmesh = \"floor.obj\"\nmaterial = \"floor\"\n{tables}\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = [{E}, {E}, {E}]\n"
    );
    let path = dir.write("scene.toml", toml);
    let scene = load_scene(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
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
            }
            (device, first.x)
        })
        .collect()
}

fn expect(name: &str, got: Vec<(&'static str, f32)>, want: f32) {
    for (device, l) in got {
        assert!(
            (l - want).abs() <= 1e-4 * want + 1e-6,
            "{name} on the {device}: {l} against {want}"
        );
    }
}

/// The four views of a masked quad described by `tables` (its object and material).
fn four_views(name: &str, dir: &TempDir, tables: &str, quad_seen: f32) {
    let views = [
        ("through the cut-out", -25.0, 3.0, lit(FLOOR)),
        ("the opaque half", 25.0, 3.0, quad_seen),
        ("under the cut-out", -25.0, 0.5, lit(FLOOR)),
        ("under the opaque half", 25.0, 0.5, 0.0),
    ];
    for (what, x, height, want) in views {
        let case = format!("{name}: {what}");
        expect(&case, radiance(dir, &case, tables, x, height), want);
    }
}

/// The hovering quad's material: a white texture with the mask's alpha, with `extra`
/// lines (`alpha`, `alpha_cutoff`).
fn toml_quad(dir: &TempDir, extra: &str) -> String {
    dir.write("floor.obj", FLOOR_OBJ);
    dir.write("quad.obj", QUAD_OBJ);
    dir.write_png("mask.png", 8, 1, &mask_texels());
    format!(
        "[materials.mask]\ntype = \"diffuse\"\nalbedo = {{ texture = \"mask.png\" }}\n{extra}\n\
         [[objects]]\nmesh = \"quad.obj\"\nmaterial = \"mask\"\n"
    )
}

#[test]
fn a_toml_alpha_mask_cuts_out_where_the_texture_alpha_is_below_the_cutoff() {
    let dir = TempDir::new("alpha toml");
    let tables = toml_quad(&dir, "alpha_cutoff = 0.5");
    four_views("toml mask", &dir, &tables, lit(1.0));
}

#[test]
fn the_alpha_factor_multiplies_the_texture_alpha() {
    // alpha 0.4 × 1 on the opaque half is below the cut-off 0.5: all of the quad is cut.
    let dir = TempDir::new("alpha factor");
    let tables = toml_quad(&dir, "alpha = 0.4\nalpha_cutoff = 0.5");
    for (what, x, height) in [("above", 25.0, 3.0), ("below", 25.0, 0.5)] {
        let case = format!("alpha factor: {what}");
        expect(&case, radiance(&dir, &case, &tables, x, height), lit(FLOOR));
    }
}

#[test]
fn without_a_cutoff_the_texture_alpha_is_not_read() {
    let dir = TempDir::new("alpha none");
    let tables = toml_quad(&dir, "");
    let case = "no mask: above the transparent texels";
    expect(case, radiance(&dir, case, &tables, -25.0, 3.0), lit(1.0));
    let case = "no mask: below the transparent texels";
    expect(case, radiance(&dir, case, &tables, -25.0, 0.5), 0.0);
}

/// The hovering quad as a glTF file: TEXCOORD_0 u along +X, a Lambertian (specular 0)
/// material whose base colour texture carries the mask's alpha, in `mode`.
fn gltf_quad(mode: &str) -> Asset {
    gltf_quad_with(
        mode,
        json!({ "KHR_materials_specular": { "specularFactor": 0.0 } }),
        [1.0; 3],
    )
}

/// [`gltf_quad`] with the material's `extensions` and base colour factor `base`.
fn gltf_quad_with(mode: &str, extensions: serde_json::Value, base: [f32; 3]) -> Asset {
    let mut a = Asset::new();
    let p = a.positions(&[
        [-50.0, 1.0, -50.0],
        [50.0, 1.0, -50.0],
        [50.0, 1.0, 50.0],
        [-50.0, 1.0, 50.0],
    ]);
    let uv = a.floats(&[0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0], "VEC2");
    let i = a.indices(&[0, 3, 2, 0, 2, 1]);
    let png = common::gltf::png(8, 1, &mask_texels());
    let view = a.view(&png, None);
    a.push(
        "images",
        json!({ "bufferView": view, "mimeType": "image/png" }),
    );
    a.push("textures", json!({ "source": 0 }));
    a.push(
        "materials",
        json!({
            "pbrMetallicRoughness": {
                "baseColorTexture": { "index": 0 },
                "baseColorFactor": [base[0], base[1], base[2], 1.0],
                "metallicFactor": 0.0
            },
            "alphaMode": mode,
            "alphaCutoff": 0.5,
            "extensions": extensions
        }),
    );
    for name in extensions.as_object().expect("an object").keys() {
        a.push("extensionsUsed", json!(name));
    }
    let mesh = a.mesh(
        json!({ "attributes": { "POSITION": p, "TEXCOORD_0": uv }, "indices": i, "material": 0 }),
    );
    let node = a.node(json!({ "mesh": mesh }));
    a.scene(&[node]);
    a
}

#[test]
fn gltf_alpha_mode_mask_cuts_out_and_blend_is_read_as_mask() {
    for mode in ["MASK", "BLEND"] {
        let dir = TempDir::new("alpha gltf");
        dir.write("floor.obj", FLOOR_OBJ);
        dir.write("quad.gltf", gltf_quad(mode).embedded());
        four_views(
            &format!("glTF {mode}"),
            &dir,
            "[[objects]]\nmesh = \"quad.gltf\"\n",
            lit(1.0),
        );
    }
}

/// An unlit quad, masked as the others: from above the camera sees its colour as it is
/// (not lit), and the floor through its cut-out; from below, the floor is lit under both
/// halves: the unlit surface stops no light.
#[test]
fn an_unlit_surface_is_seen_by_the_camera_alone() {
    let dir = TempDir::new("unlit gltf");
    dir.write("floor.obj", FLOOR_OBJ);
    let quad = gltf_quad_with(
        "MASK",
        json!({ "KHR_materials_unlit": {} }),
        [0.3, 0.5, 0.7],
    );
    dir.write("quad.gltf", quad.embedded());
    let tables = "[[objects]]\nmesh = \"quad.gltf\"\n";
    let views = [
        ("through the cut-out", -25.0, 3.0, lit(FLOOR)),
        ("the opaque half", 25.0, 3.0, 0.3),
        ("under the cut-out", -25.0, 0.5, lit(FLOOR)),
        ("under the opaque half", 25.0, 0.5, lit(FLOOR)),
    ];
    for (what, x, height, want) in views {
        let case = format!("unlit: {what}");
        expect(&case, radiance(&dir, &case, tables, x, height), want);
    }
}
