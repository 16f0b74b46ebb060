//! Image textures end to end, through scene files written for each test: a textured
//! emitter seen directly renders its texture's mean (sRGB-decoded), the image's corners land
//! where the scene format says OBJ texture coordinates put them, both renderers agree,
//! Radiance HDR files read with either signature, and `max_texture_size` scales textures
//! down.

use crate::common;

use common::fs::TempDir;
use common::rand::SplitMix;
use meshtrace::bvh::BuildParams;
use meshtrace::film::srgb8_to_linear;
use meshtrace::render::RenderScene;
use meshtrace::request::RenderRequest;
use meshtrace::scene::{Scene, load_scene};

/// A quad over [-1, 1]² at z = 0 facing +Z, OBJ texture coordinate (0, 0) at its
/// bottom-left corner and (1, 1) at its top-right.
const QUAD: &str = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n";

/// A scene that sees exactly the quad (a square image, vfov 40 degrees at the distance
/// where the quad fills it), an emitter of `emission` (a TOML value), at `size`² pixels.
fn emitter_scene(dir: &TempDir, emission: &str, size: u32, spp: u32) -> Scene {
    dir.write("quad.obj", QUAD);
    let distance = 1.0 / 20f64.to_radians().tan();
    let toml = format!(
        "[camera]\nposition = [0.0, 0.0, {distance}]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\n\
         [render]\nwidth = {size}\nheight = {size}\nspp = {spp}\nmax_depth = 1\n\
         [materials.light]\ntype = \"diffuse\"\nalbedo = [0.0, 0.0, 0.0]\nemission = {emission}\n\
         [[objects]]\nmesh = \"quad.obj\"\nmaterial = \"light\"\n"
    );
    let path = dir.write("scene.toml", toml);
    load_scene(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// A bilinear, repeat-wrapped texture integrates to the mean of its texels, so an emitter
/// that fills the view renders strength × that mean, the texels decoded from sRGB. (Read
/// as linear, the mean would be about twice as large.)
#[test]
fn textured_emitter_renders_the_mean_of_its_texels() {
    let dir = TempDir::new("textured-emitter");
    let mut r = SplitMix::new(0x7e47_0001);
    let texels: Vec<[u8; 4]> = (0..32)
        .map(|_| [0; 4].map(|_| (r.u32() >> 24) as u8))
        .collect();
    dir.write_png("light.png", 8, 4, &texels);
    let strength = 2.0;
    let scene = emitter_scene(
        &dir,
        &format!("{{ texture = \"light.png\", strength = {strength} }}"),
        64,
        16,
    );
    let mut expect = [0.0f64; 3];
    for t in &texels {
        for c in 0..3 {
            expect[c] += strength * srgb8_to_linear(t[c]) as f64 / texels.len() as f64;
        }
    }
    for (device, film) in common::render_both("textured_emitter", &scene) {
        let mean = film.mean();
        for c in 0..3 {
            let m = mean.iter().map(|p| p[c] as f64).sum::<f64>() / mean.len() as f64;
            let err = (m - expect[c]).abs() / expect[c];
            eprintln!(
                "{device}: channel {c}: mean {m:.5}, expected {:.5}",
                expect[c]
            );
            assert!(
                err < 0.005,
                "{device}: channel {c}: mean {m}, expected {}",
                expect[c]
            );
        }
    }
}

/// OBJ texture coordinate (0, 0) is the image's bottom-left corner: a 2×2 image of red
/// (top-left), green (top-right), blue (bottom-left) and white (bottom-right) appears the
/// right way up on a quad whose vt run as the quad's corners.
#[test]
fn obj_texture_coordinates_put_the_image_the_right_way_up() {
    let dir = TempDir::new("texture-orientation");
    let (red, green, blue, white) = (
        [255, 0, 0, 255],
        [0, 255, 0, 255],
        [0, 0, 255, 255],
        [255, 255, 255, 255],
    );
    dir.write_png("corners.png", 2, 2, &[red, green, blue, white]);
    let scene = emitter_scene(&dir, "{ texture = \"corners.png\" }", 32, 16);
    for (device, film) in common::render_both("texture_orientation", &scene) {
        let mean = film.mean();
        for ((x, y), colour) in [
            ((8, 8), red),
            ((24, 8), green),
            ((8, 24), blue),
            ((24, 24), white),
        ] {
            let p = mean[y * 32 + x];
            for c in 0..3 {
                let want = colour[c] as f32 / 255.0;
                assert!(
                    (p[c] - want).abs() < 0.1,
                    "{device}: pixel ({x}, {y}) is {p}, expected {colour:?}"
                );
            }
        }
    }
}

/// A UV scale tiles the image in the file's own terms: OBJ's v counts up from the image's
/// bottom edge, so with `scale = [1, 1.5]` the quad's middle (v = 0.5, scaled 0.75) shows
/// the texel centre a quarter of the way down from the top edge: the top row. (Flipping v
/// before scaling would show the bottom row there.)
#[test]
fn a_uv_scale_tiles_in_the_files_own_terms() {
    let dir = TempDir::new("texture-scale");
    let (red, green, blue, white) = (
        [255, 0, 0, 255],
        [0, 255, 0, 255],
        [0, 0, 255, 255],
        [255, 255, 255, 255],
    );
    dir.write_png("corners.png", 2, 2, &[red, green, blue, white]);
    let scene = emitter_scene(
        &dir,
        "{ texture = \"corners.png\", scale = [1.0, 1.5] }",
        32,
        16,
    );
    for (device, film) in common::render_both("texture_scale", &scene) {
        let mean = film.mean();
        for ((x, y), colour) in [((8, 15), red), ((24, 16), green)] {
            let p = mean[y * 32 + x];
            for c in 0..3 {
                let want = colour[c] as f32 / 255.0;
                assert!(
                    (p[c] - want).abs() < 0.15,
                    "{device}: pixel ({x}, {y}) is {p}, expected {colour:?}"
                );
            }
        }
    }
}

/// A scene with `files` written to a fresh directory and `scene.toml` holding a camera and
/// `rest`; the load's result.
fn load_with(
    name: &str,
    rest: &str,
    files: &[(&str, &[u8])],
) -> (TempDir, Result<Scene, meshtrace::scene::SceneError>) {
    let dir = TempDir::new(name);
    for (file, bytes) in files {
        dir.write(file, bytes);
    }
    let toml = format!("[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n{rest}");
    let result = load_scene(&dir.write("scene.toml", toml));
    (dir, result)
}

/// A PNG file's bytes: `width` × `height` texels of one colour.
fn png(width: u32, height: u32, colour: [u8; 4]) -> Vec<u8> {
    let img = image::RgbaImage::from_pixel(width, height, image::Rgba(colour));
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
    bytes.into_inner()
}

const TRI_UV: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n";
const TRI_NO_UV: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

#[test]
fn scene_file_textures_load_with_their_use_scale_and_strength() {
    use meshtrace::scene::{NO_TEXTURE, TextureFormat};
    let grey = png(4, 2, [128, 64, 32, 255]);
    let (_dir, result) = load_with(
        "texture-params",
        "[materials.a]\ntype = \"rough_conductor\"\n\
         albedo = { texture = \"c.png\", scale = [2.0, 0.5] }\n\
         roughness = { texture = \"c.png\" }\n\
         emission = { texture = \"c.png\", strength = 4.0 }\n\
         [[objects]]\nmesh = \"t.obj\"\nmaterial = \"a\"\n",
        &[("c.png", &grey), ("t.obj", TRI_UV.as_bytes())],
    );
    let s = result.unwrap();
    let m = &s.materials[0];
    let t = &s.textures.records;
    assert_eq!(t.len(), 3, "{t:?}");
    assert_eq!(s.textures.texels.len(), 8, "one image, read once, 8-bit");
    let albedo = &t[m.albedo_texture as usize];
    assert_eq!(
        (albedo.format, albedo.uv_matrix, albedo.width, albedo.height),
        (TextureFormat::RGBA8_SRGB, [2.0, 0.0, 0.0, 0.5], 4, 2)
    );
    let rough = &t[m.roughness_texture as usize];
    assert_eq!(
        (rough.format, rough.channel),
        (TextureFormat::RGBA8_LINEAR, 0)
    );
    assert_eq!((m.albedo, m.roughness), (glam::Vec3::ONE, 1.0));
    assert_eq!(m.emission, glam::Vec3::splat(4.0));
    assert_ne!(m.emission_texture, NO_TEXTURE);
    // The texel: R in the low byte.
    assert_eq!(s.textures.texels[0], u32::from_le_bytes([128, 64, 32, 255]));
}

#[test]
fn bad_texture_parameters_are_errors_naming_the_field() {
    let grey = png(2, 2, [128; 4]);
    let files: &[(&str, &[u8])] = &[
        ("c.png", &grey),
        ("junk.png", b"not an image"),
        ("t.obj", TRI_UV.as_bytes()),
    ];
    let material = |param: &str| {
        let kind = if param.starts_with("type") {
            ""
        } else {
            "type = \"diffuse\"\n"
        };
        format!("[materials.m]\n{kind}{param}\n[[objects]]\nmesh = \"t.obj\"\nmaterial = \"m\"\n")
    };
    for (param, needles) in [
        (
            "albedo = { texture = \"c.png\", strength = 2.0 }",
            &["materials.m.albedo.strength", "only emission"][..],
        ),
        (
            "type = \"pbr\"\nroughness = { texture = \"c.png\", strength = 2.0 }",
            &["materials.m.roughness.strength", "only emission"],
        ),
        (
            "albedo = { texture = \"c.png\", scale = [0.0, 1.0] }",
            &["materials.m.albedo.scale", "non-zero"],
        ),
        (
            "albedo = { texture = \"gone.png\" }",
            &["materials.m.albedo.texture", "gone.png"],
        ),
        (
            "albedo = { texture = \"junk.png\" }",
            &["materials.m.albedo.texture", "junk.png", "cannot decode"],
        ),
        (
            "albedo = { texture = \"c.png\", scael = [1.0, 1.0] }",
            &["scene.toml:"],
        ),
        (
            "albedo = { texture = \"c.png\", wrap = \"tile\" }",
            &["materials.m.albedo.wrap", "unknown wrap mode `tile`"],
        ),
        (
            "normal_map = { texture = \"gone.png\" }",
            &["materials.m.normal_map.texture", "gone.png"],
        ),
        (
            "normal_map = { texture = \"c.png\", strength = inf }",
            &["materials.m.normal_map.strength", "finite"],
        ),
        ("alpha = 0.5", &["materials.m.alpha", "alpha_cutoff"]),
        (
            "alpha_cutoff = 1.5",
            &["materials.m.alpha_cutoff", "in [0, 1]"],
        ),
        (
            "alpha = -1.0\nalpha_cutoff = 0.5",
            &["materials.m.alpha", "in [0, 1]"],
        ),
    ] {
        let (_dir, result) = load_with("bad-texture", &material(param), files);
        let message = result.expect_err(param).to_string();
        assert!(!message.contains('\n'), "{message}");
        for needle in needles {
            assert!(
                message.contains(needle),
                "{param}: {message:?} lacks {needle:?}"
            );
        }
    }
}

#[test]
fn a_texture_on_faces_without_texture_coordinates_is_an_error_naming_the_object() {
    let grey = png(2, 2, [128; 4]);
    let textured = "[materials.m]\ntype = \"diffuse\"\nalbedo = { texture = \"c.png\" }\n";
    for (object, needle) in [
        (
            "[[objects]]\nmesh = \"t.obj\"\nmaterial = \"m\"\n",
            "objects[0]",
        ),
        (
            "[[objects]]\nsphere = { center = [0.0, 0.0, 0.0], radius = 1.0 }\nmaterial = \"m\"\n",
            "objects[0]",
        ),
    ] {
        let (_dir, result) = load_with(
            "texture-no-uv",
            &format!("{textured}{object}"),
            &[("c.png", &grey), ("t.obj", TRI_NO_UV.as_bytes())],
        );
        let message = result.expect_err(object).to_string();
        assert!(message.contains(needle), "{message}");
        assert!(message.contains("texture coordinates"), "{message}");
    }
    // A bare OBJ whose MTL maps a texture onto faces without `vt`.
    let dir = TempDir::new("texture-no-uv-obj");
    dir.write("c.png", &grey);
    dir.write("m.mtl", "newmtl t\nmap_Kd c.png\n");
    let obj = dir.write("m.obj", format!("mtllib m.mtl\nusemtl t\n{TRI_NO_UV}"));
    let message = load_scene(&obj).unwrap_err().to_string();
    assert!(message.starts_with(&obj.display().to_string()), "{message}");
    assert!(message.contains("texture coordinates"), "{message}");
}

#[test]
fn mtl_texture_maps_load_with_their_options() {
    use meshtrace::scene::{MaterialKind, NO_TEXTURE};
    let grey = png(2, 2, [200; 4]);
    let dir = TempDir::new("mtl-maps");
    dir.write("c.png", &grey);
    dir.write(
        "m.mtl",
        "newmtl wood\nKd 0.5 0.5 0.5\nmap_Kd -s 3 2 -o 0.5 0.5 -clamp on c.png\nmap_d c.png\n\
         newmtl metal\nPm 1\nmap_Pr c.png\n\
         newmtl lamp\nKe 2 2 2\nmap_Ke -s 4 c.png\n\
         newmtl lost\nKd 0.25 0.5 0.75\nmap_Kd missing.png\n",
    );
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
         usemtl wood\nf 1/1 2/2 3/3\nusemtl metal\nf 1/1 2/2 3/3\n\
         usemtl lamp\nf 1/1 2/2 3/3\nusemtl lost\nf 1/1 2/2 3/3\n";
    let s = load_scene(&dir.write("m.obj", obj)).unwrap();
    let by = |name: &str| {
        let i = s.material_names.iter().position(|n| n == name).unwrap();
        s.materials[i]
    };
    let t = &s.textures.records;
    let wood = by("wood");
    assert_eq!(wood.albedo, glam::Vec3::splat(0.5), "map_Kd multiplies Kd");
    assert_eq!(
        t[wood.albedo_texture as usize].uv_matrix,
        [3.0, 0.0, 0.0, 2.0]
    );
    let metal = by("metal");
    assert_eq!(metal.kind, MaterialKind::ROUGH_CONDUCTOR);
    assert_eq!(metal.roughness, 1.0);
    assert_ne!(metal.roughness_texture, NO_TEXTURE);
    let lamp = by("lamp");
    assert_eq!(lamp.emission, glam::Vec3::splat(2.0));
    assert_eq!(
        t[lamp.emission_texture as usize].uv_matrix,
        [4.0, 0.0, 0.0, 1.0]
    );
    let lost = by("lost");
    assert_eq!(lost.albedo_texture, NO_TEXTURE, "a missing map falls back");
    assert_eq!(lost.albedo, glam::Vec3::new(0.25, 0.5, 0.75));
    let warned = |needles: &[&str]| {
        s.warnings
            .iter()
            .any(|w| needles.iter().all(|n| w.contains(n)))
    };
    assert!(warned(&["m.mtl:3", "-o"]), "{:?}", s.warnings);
    assert!(!warned(&["-clamp"]), "{:?}", s.warnings);
    let clamp = meshtrace::scene::Wrap::CLAMP;
    assert_eq!(
        t[wood.albedo_texture as usize].wrap,
        meshtrace::scene::Wrap::pack(clamp, clamp),
        "-clamp on"
    );
    assert_eq!(t[lamp.emission_texture as usize].wrap, 0, "repeats");
    assert!(warned(&["m.mtl:4", "map_d"]), "{:?}", s.warnings);
    assert!(warned(&["missing.png", "falls back"]), "{:?}", s.warnings);
}

#[test]
fn mtl_normal_and_metallic_maps_load() {
    use meshtrace::scene::{MaterialKind, NO_TEXTURE, TextureFormat};
    let dir = TempDir::new("mtl-normal-maps");
    dir.write("c.png", png(2, 2, [200; 4]));
    dir.write(
        "m.mtl",
        "newmtl bumpy\nKd 0.5 0.5 0.5\nbump -bm 0.3 c.png\n\
         newmtl normal\nnorm c.png\n\
         newmtl map\nmap_Bump c.png\n\
         newmtl metal\nKd 0.9 0.8 0.7\nPr 0.25\nmap_Pm c.png\n",
    );
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
         usemtl bumpy\nf 1/1 2/2 3/3\nusemtl normal\nf 1/1 2/2 3/3\n\
         usemtl map\nf 1/1 2/2 3/3\nusemtl metal\nf 1/1 2/2 3/3\n";
    let s = load_scene(&dir.write("m.obj", obj)).unwrap();
    let by = |name: &str| {
        let i = s.material_names.iter().position(|n| n == name).unwrap();
        s.materials[i]
    };
    for name in ["bumpy", "normal", "map"] {
        let m = by(name);
        assert_ne!(m.normal_texture, NO_TEXTURE, "{name}");
        // Normal maps are data: never sRGB-decoded.
        let t = &s.textures.records[m.normal_texture as usize];
        assert_eq!(t.format, TextureFormat::RGBA8_LINEAR, "{name}");
    }
    assert_eq!(by("bumpy").kind, MaterialKind::DIFFUSE);
    let metal = by("metal");
    assert_eq!(metal.kind, MaterialKind::PBR, "a metallic map needs pbr");
    assert_eq!(metal.albedo, glam::Vec3::new(0.9, 0.8, 0.7));
    assert_eq!((metal.metallic, metal.roughness), (1.0, 0.25));
    assert_ne!(metal.metallic_texture, NO_TEXTURE);
    // MikkTSpace gave the normal-mapped triangles tangents.
    for i in 0..3 {
        assert_ne!(s.mesh.tangent_indices(i)[0], meshtrace::scene::NO_TANGENT);
    }
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("m.mtl:3") && w.contains("-bm")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn a_malformed_map_option_is_an_error_naming_the_library_line() {
    let dir = TempDir::new("mtl-map-option");
    for (mtl, needle) in [
        ("newmtl a\nmap_Kd -zz 1 c.png\n", "unknown option"),
        ("newmtl a\nmap_Kd -s c.png\n", "-s needs"),
        ("newmtl a\nmap_Kd -s 2 2\n", "names no image"),
        (
            "newmtl a\nmap_Kd -clamp yes c.png\n",
            "-clamp takes on or off",
        ),
    ] {
        dir.write("m.mtl", mtl);
        let obj = dir.write("m.obj", format!("mtllib m.mtl\n{TRI_UV}"));
        let message = load_scene(&obj).unwrap_err().to_string();
        assert!(message.contains("m.mtl:2:"), "{mtl}: {message}");
        assert!(message.contains(needle), "{mtl}: {message}");
    }
}

/// KHR_texture_transform's matrix: scale, then rotate by u' = cos u + sin v,
/// v' = −sin u + cos v (the direction Khronos's TextureTransformTest checks, see
/// tests/gltf_samples.rs), then offset.
#[test]
fn uv_transforms_scale_then_rotate() {
    use meshtrace::scene::texture::UvTransform;
    let t = UvTransform {
        scale: [2.0, 3.0],
        rotation: std::f32::consts::FRAC_PI_2,
        offset: [0.25, 0.5],
    };
    let m = t.matrix();
    let apply = |u: f32, v: f32| (m[0] * u + m[1] * v, m[2] * u + m[3] * v);
    let (x, y) = apply(1.0, 0.0);
    assert!(x.abs() < 1e-6 && (y + 2.0).abs() < 1e-6, "({x}, {y})");
    let (x, y) = apply(0.0, 1.0);
    assert!((x - 3.0).abs() < 1e-6 && y.abs() < 1e-6, "({x}, {y})");
    assert_eq!(UvTransform::scale(2.0, 3.0).matrix(), [2.0, 0.0, 0.0, 3.0]);
}

/// CRC-32 (IEEE) of PNG chunks.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// A texture whose image is larger than the machine's free memory is an error that says
/// how large it is and how much memory there is, before anything is allocated: a PNG
/// whose header claims 200000² RGBA texels (160 GB decoded).
#[test]
fn a_texture_larger_than_memory_is_an_error_naming_its_size() {
    if !std::path::Path::new("/proc/meminfo").exists() {
        eprintln!("skipped: no /proc/meminfo, so meshtrace cannot know the free memory here");
        return;
    }
    let dir = TempDir::new("huge-texture");
    let mut png = png(1, 1, [200; 4]);
    // IHDR's data starts after the 8-byte signature and the chunk's length and type.
    png[16..20].copy_from_slice(&200_000u32.to_be_bytes());
    png[20..24].copy_from_slice(&200_000u32.to_be_bytes());
    let crc = crc32(&png[12..29]);
    png[29..33].copy_from_slice(&crc.to_be_bytes());
    dir.write("huge.png", &png);
    dir.write("t.obj", TRI_UV);
    let toml = "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n\
                [materials.m]\ntype = \"diffuse\"\nalbedo = { texture = \"huge.png\" }\n\
                [[objects]]\nmesh = \"t.obj\"\nmaterial = \"m\"\n";
    let err = load_scene(&dir.write("scene.toml", toml)).expect_err("the texture cannot fit");
    let message = err.to_string();
    assert!(!message.contains('\n'), "{message}");
    for needle in [
        "materials.m.albedo.texture",
        "huge.png",
        "200000×200000",
        "GiB of memory free",
    ] {
        assert!(message.contains(needle), "{message:?} lacks {needle:?}");
    }
}

/// Textures that do not fit the adapter's limits are an error that names the limit, before
/// anything is uploaded: here an adapter of 2-row tables (128 KiB) and a 256² texture.
#[test]
fn textures_beyond_the_adapter_limits_are_an_error_naming_the_limit() {
    let Some(ctx) = common::gpu("textures beyond the limits") else {
        return;
    };
    let mut small = ctx.clone();
    small.limits.max_texture_dimension_2d = 2;
    let dir = TempDir::new("texture-limit");
    let texels: Vec<[u8; 4]> = (0..256 * 256)
        .map(|i| [(i % 251) as u8, 0, 0, 255])
        .collect();
    dir.write_png("big.png", 256, 256, &texels);
    dir.write("t.obj", TRI_UV);
    let toml = "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n\
                [materials.m]\ntype = \"diffuse\"\nalbedo = { texture = \"big.png\" }\n\
                [[objects]]\nmesh = \"t.obj\"\nmaterial = \"m\"\n";
    let scene = load_scene(&dir.write("scene.toml", toml)).unwrap();
    let rs = RenderScene::new(&scene, &BuildParams::default()).unwrap();
    let err = match meshtrace::render::gpu::GpuRenderer::new(&small, &rs) {
        Ok(_) => panic!("256 KiB of texels fit a 128 KiB table"),
        Err(e) => e.to_string(),
    };
    for needle in [
        "texels need 262144 bytes",
        "max_texture_dimension_2d = 2",
        "--max-texture-size",
        "--device cpu",
    ] {
        assert!(err.contains(needle), "{err:?} lacks {needle:?}");
    }
    // With the adapter's own limits it fits, and so it does on the small adapter once the
    // texture is scaled down to 64² (16 KiB) as the message says.
    assert!(meshtrace::render::gpu::GpuRenderer::new(&ctx, &rs).is_ok());
    let request = RenderRequest {
        max_texture_size: Some(64),
        ..Default::default()
    };
    let scene = meshtrace::pipeline::load(&dir.join("scene.toml"), &request).unwrap();
    let rs = RenderScene::new(&scene, &BuildParams::default()).unwrap();
    assert!(meshtrace::render::gpu::GpuRenderer::new(&small, &rs).is_ok());
}

/// A Radiance HDR file may begin `#?RGBE` instead of `#?RADIANCE`, as stb_image accepts
/// (and Bruce Walter's rgbe.c writes). The `#?RGBE` file here is `assets/env/test_16x8.hdr`
/// with its first line changed and nothing else: read as an environment and as a texture,
/// with the `.hdr` extension and with none that names a format, it gives the very texels of
/// its `#?RADIANCE` twin. Any other first line is a one-line error naming the file.
#[test]
fn radiance_hdr_files_read_with_either_signature() {
    let radiance = std::fs::read(common::fs::root().join("assets/env/test_16x8.hdr")).unwrap();
    let body = radiance
        .strip_prefix(b"#?RADIANCE\n")
        .expect("the test map starts with #?RADIANCE");
    let dir = TempDir::new("rgbe-signature");
    dir.write("radiance.hdr", &radiance);
    dir.write("rgbe.hdr", [&b"#?RGBE\n"[..], body].concat());
    dir.write("rgbe.map", [&b"#?RGBE\n"[..], body].concat());
    dir.write("other.hdr", [&b"#?RADIANT\n"[..], body].concat());
    dir.write("quad.obj", QUAD);
    let load = |image: &str| {
        let toml = format!(
            "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n\
             [sky]\nenvironment = \"{image}\"\n\
             [materials.m]\ntype = \"diffuse\"\nemission = {{ texture = \"{image}\" }}\n\
             [[objects]]\nmesh = \"quad.obj\"\nmaterial = \"m\"\n"
        );
        load_scene(&dir.write("scene.toml", toml))
    };
    let twin = load("radiance.hdr").unwrap();
    assert_eq!(twin.textures.texels.len(), 16 * 8 * 4, "one float image");
    for image in ["rgbe.hdr", "rgbe.map"] {
        let s = load(image).unwrap_or_else(|e| panic!("{image}: {e}"));
        assert_eq!(s.textures.records, twin.textures.records, "{image}");
        assert_eq!(s.textures.texels, twin.textures.texels, "{image}");
    }
    let message = load("other.hdr").unwrap_err().to_string();
    assert!(!message.contains('\n'), "{message}");
    for needle in ["sky.environment", "other.hdr", "#?RADIANT", "#?RGBE"] {
        assert!(message.contains(needle), "{message:?} lacks {needle:?}");
    }
}

/// A scene of `files` in `dir` whose emitting quad reads `texture`, with an environment,
/// loaded as a request of `max_texture_size` = `max` asks.
fn limited(dir: &TempDir, texture: &str, max: Option<u32>) -> Scene {
    dir.write("quad.obj", QUAD);
    let distance = 1.0 / 20f64.to_radians().tan();
    let env = common::fs::root().join("assets/env/test_16x8.exr");
    let toml = format!(
        "[camera]\nposition = [0.0, 0.0, {distance}]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\n\
         [render]\nwidth = 32\nheight = 32\nspp = 16\nmax_depth = 1\n\
         [sky]\nenvironment = {:?}\n\
         [materials.light]\ntype = \"diffuse\"\nalbedo = [0.0, 0.0, 0.0]\n\
         emission = {{ texture = \"{texture}\" }}\n\
         [[objects]]\nmesh = \"quad.obj\"\nmaterial = \"light\"\n",
        env.display().to_string()
    );
    let request = RenderRequest {
        max_texture_size: max,
        ..Default::default()
    };
    meshtrace::pipeline::load(&dir.write("scene.toml", toml), &request)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// `max_texture_size` scales a texture whose larger side exceeds it down to it, the aspect
/// kept, with the `image` crate's triangle filter (the texels are the crate's own resize of
/// the image), and the environment map too, each with a warning giving both sizes; images
/// within the limit are left as they are. Both renderers read the scaled texels: the emitter
/// renders their mean on each.
#[test]
fn max_texture_size_scales_large_textures_down() {
    let dir = TempDir::new("max-texture-size");
    let mut r = SplitMix::new(0x5ca1_0001);
    let texels: Vec<[u8; 4]> = (0..64 * 32)
        .map(|_| [0; 4].map(|_| (r.u32() >> 24) as u8))
        .collect();
    dir.write_png("big.png", 64, 32, &texels);
    let full = limited(&dir, "big.png", None);
    assert!(full.warnings.is_empty(), "{:?}", full.warnings);
    let within = limited(&dir, "big.png", Some(64));
    assert_eq!(within.textures.texels, full.textures.texels);
    assert!(within.warnings.is_empty(), "{:?}", within.warnings);

    let scene = limited(&dir, "big.png", Some(16));
    let t = scene.textures.records[scene.materials[0].emission_texture as usize];
    assert_eq!((t.width, t.height), (16, 8));
    let image =
        image::RgbaImage::from_fn(64, 32, |x, y| image::Rgba(texels[(y * 64 + x) as usize]));
    let want = image::imageops::resize(&image, 16, 8, image::imageops::FilterType::Triangle);
    let got = &scene.textures.texels[t.offset as usize..][..16 * 8];
    let want: Vec<u32> = want.pixels().map(|p| u32::from_le_bytes(p.0)).collect();
    assert_eq!(got, &want[..]);
    let env = scene
        .textures
        .records
        .iter()
        .find(|r| r.format == meshtrace::scene::TextureFormat::RGBA32F)
        .unwrap();
    assert_eq!(
        (env.width, env.height),
        (16, 8),
        "the environment is within 16"
    );
    let warned = |needles: &[&str]| {
        scene
            .warnings
            .iter()
            .any(|w| needles.iter().all(|n| w.contains(n)))
    };
    assert!(
        warned(&["big.png", "64×32", "max_texture_size = 16", "16×8"]),
        "{:?}",
        scene.warnings
    );
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    let small = limited(&dir, "big.png", Some(8));
    assert!(
        small
            .warnings
            .iter()
            .any(|w| w.contains("test_16x8.exr") && w.contains("16×8") && w.contains("8×4")),
        "{:?}",
        small.warnings
    );
    // Texels of 64 × 32 = 2048 + the environment's 16 × 8 × 4 = 512 words, then 128 + 512.
    assert_eq!(full.textures.texels.len(), 2048 + 512);
    assert_eq!(scene.textures.texels.len(), 128 + 512);

    let mut expect = [0.0f64; 3];
    for &w in &want {
        let t = w.to_le_bytes();
        for c in 0..3 {
            expect[c] += srgb8_to_linear(t[c]) as f64 / want.len() as f64;
        }
    }
    let films = common::render_both("max_texture_size", &scene);
    for (device, film) in &films {
        let mean = film.mean();
        for c in 0..3 {
            let m = mean.iter().map(|p| p[c] as f64).sum::<f64>() / mean.len() as f64;
            eprintln!(
                "{device}: channel {c}: mean {m:.5}, expected {:.5}",
                expect[c]
            );
            assert!(
                (m - expect[c]).abs() / expect[c] < 0.01,
                "{device}: channel {c}: mean {m}, expected {}",
                expect[c]
            );
        }
    }
    if let [(_, cpu), (_, gpu)] = &films[..] {
        let (a, b) = (cpu.mean(), gpu.mean());
        let worst = a
            .iter()
            .zip(&b)
            .map(|(p, q)| (*p - *q).abs().max_element())
            .fold(0.0f32, f32::max);
        eprintln!("largest pixel difference, CPU against GPU: {worst}");
        assert!(worst < 1e-3, "the renderers read different texels: {worst}");
    }
}

/// Float images keep their range when scaled: a constant HDR texture of 3000 stays 3000
/// (the `image` crate alone would clamp it to 1), and a random one keeps its mean to within
/// a few per cent.
#[test]
fn max_texture_size_keeps_the_range_of_float_images() {
    let dir = TempDir::new("max-texture-size-float");
    dir.write_exr("flat.exr", 8, 4, &[[3000.0, 0.5, 0.0, 1.0]; 32]);
    let scene = limited(&dir, "flat.exr", Some(4));
    let t = scene.textures.records[scene.materials[0].emission_texture as usize];
    assert_eq!((t.width, t.height), (4, 2));
    for texel in scene.textures.texels[t.offset as usize..][..4 * 2 * 4].chunks(4) {
        let [r, g, b, a] = [0, 1, 2, 3].map(|c| f32::from_bits(texel[c]));
        assert!((r - 3000.0).abs() < 3000.0 * 1e-5, "{r}");
        assert!(
            (g - 0.5).abs() < 1e-5 && b == 0.0 && (a - 1.0).abs() < 1e-5,
            "{texel:?}"
        );
    }
    let mut r = SplitMix::new(0x5ca1_0002);
    let texels: Vec<[f32; 4]> = (0..64 * 64)
        .map(|_| [r.range(0.0, 5000.0), r.range(0.0, 1.0), 0.25, 1.0])
        .collect();
    dir.write_exr("noisy.exr", 64, 64, &texels);
    let scene = limited(&dir, "noisy.exr", Some(16));
    let t = scene.textures.records[scene.materials[0].emission_texture as usize];
    assert_eq!((t.width, t.height), (16, 16));
    let mean = |values: &mut dyn Iterator<Item = f32>, n: usize| {
        values.map(f64::from).sum::<f64>() / n as f64
    };
    let before = mean(&mut texels.iter().map(|t| t[0]), texels.len());
    let after = mean(
        &mut scene.textures.texels[t.offset as usize..][..16 * 16 * 4]
            .chunks(4)
            .map(|t| f32::from_bits(t[0])),
        256,
    );
    eprintln!("mean red before {before:.2}, after {after:.2}");
    assert!((after - before).abs() / before < 0.03, "{before} → {after}");
}

/// The wrap modes along u, on a 4 × 1 float image of texels 0, 1, 2, 3 (texel centres at
/// u = 0.125, 0.375, ...): repeat tiles, clamp extends the edge texels, mirror reflects
/// about every integer u. The expected values are worked out by hand from those rules.
#[test]
fn wrap_modes_repeat_clamp_and_mirror_as_glsl_does() {
    use meshtrace::render::texture::texture_lookup;
    let dir = TempDir::new("wrap-modes");
    let texels: Vec<[f32; 4]> = (0..4).map(|i| [i as f32, 0.0, 0.0, 1.0]).collect();
    dir.write_exr("ramp.exr", 4, 1, &texels);
    dir.write("quad.obj", QUAD);
    let cases: [(f32, [f32; 3]); 7] = [
        // u: repeat, clamp, mirror
        (0.125, [0.0, 0.0, 0.0]),
        (0.0, [1.5, 0.0, 0.0]),
        (1.0, [1.5, 3.0, 3.0]),
        (1.125, [0.0, 3.0, 3.0]),
        (-0.375, [2.0, 0.0, 1.0]),
        (2.375, [1.0, 3.0, 1.0]),
        (1.3, [0.7, 3.0, 2.3]),
    ];
    for (k, mode) in ["repeat", "clamp", "mirror"].into_iter().enumerate() {
        let toml = format!(
            "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n\
             [materials.m]\ntype = \"diffuse\"\n\
             emission = {{ texture = \"ramp.exr\", wrap = [\"{mode}\", \"clamp\"] }}\n\
             [[objects]]\nmesh = \"quad.obj\"\nmaterial = \"m\"\n"
        );
        let scene = load_scene(&dir.write("scene.toml", toml)).unwrap();
        let rs = RenderScene::new(&scene, &BuildParams::default()).unwrap();
        for (u, expected) in cases {
            for v in [0.5, -3.0, 7.25] {
                let got = texture_lookup(&rs, 0, glam::Vec2::new(u, v)).x;
                assert!(
                    (got - expected[k]).abs() < 1e-5,
                    "{mode} at u = {u}, v = {v}: got {got}, expected {}",
                    expected[k]
                );
            }
        }
    }
}

/// On an OBJ mesh, the wrap modes work in the file's own terms, where the image spans
/// v ∈ [0, 1] from its bottom edge: a 1 × 4 float image of rows 0 (top) to 3 (bottom),
/// tiled twice along v, reads at OBJ coordinate v the row of 1 − wrap(2v), whether the
/// texture clamps or mirrors (and the second image is a reflection of the first).
#[test]
fn wrap_modes_on_obj_texture_coordinates_work_in_the_files_terms() {
    use meshtrace::render::texture::{material_at, triangle_uv};
    let dir = TempDir::new("wrap-obj");
    let texels: Vec<[f32; 4]> = (0..4).map(|i| [i as f32, 0.0, 0.0, 1.0]).collect();
    dir.write_exr("rows.exr", 1, 4, &texels);
    dir.write("quad.obj", QUAD);
    let mut r = SplitMix::new(0x3a9_0001);
    for mode in ["clamp", "mirror"] {
        let toml = format!(
            "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n\
             [materials.m]\ntype = \"diffuse\"\n\
             albedo = {{ texture = \"rows.exr\", scale = [1.0, 2.0], wrap = \"{mode}\" }}\n\
             [[objects]]\nmesh = \"quad.obj\"\nmaterial = \"m\"\n"
        );
        let scene = load_scene(&dir.write("scene.toml", toml)).unwrap();
        let rs = RenderScene::new(&scene, &BuildParams::default()).unwrap();
        for tri in 0..rs.shading.len() as u32 {
            let material = rs.materials[rs.shading[tri as usize].material as usize];
            for _ in 0..200 {
                let (b1, b2) = (r.range(0.0, 1.0), r.range(0.0, 1.0));
                let (b1, b2) = if b1 + b2 > 1.0 {
                    (1.0 - b1, 1.0 - b2)
                } else {
                    (b1, b2)
                };
                let uv = triangle_uv(&rs, tri, b1, b2);
                // Stored as (u, −v); back to the file's v, tiled twice.
                let t = -2.0 * uv.y;
                let wrapped = match mode {
                    "clamp" => t.clamp(0.0, 1.0),
                    _ if t > 1.0 => 2.0 - t,
                    _ => t,
                };
                let expected = ((1.0 - wrapped) * 4.0 - 0.5).clamp(0.0, 3.0);
                let got = material_at(&rs, &material, uv, glam::Vec4::ONE).albedo.x;
                assert!(
                    (got - expected).abs() < 1e-4,
                    "{mode} at OBJ v = {}: got {got}, expected {expected}",
                    -uv.y
                );
            }
        }
    }
}
