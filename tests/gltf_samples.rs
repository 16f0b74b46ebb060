//! Khronos's glTF sample assets in `tests/data/gltf/` (see its README for their sources and
//! licences), loaded as bare files: what each contains.

use crate::common;

use common::fs::data;
use glam::Vec3;
use meshtrace::scene::{MaterialKind, NO_TEXTURE, NO_UV, Scene, Sky, Wrap, load_scene};

fn sample(path: &str) -> Scene {
    common::studio::without_ground(
        load_scene(&data(&format!("gltf/{path}"))).unwrap_or_else(|e| panic!("{e}")),
    )
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

/// Twice each triangle's area along its front-face normal ((b − a) × (c − a)).
fn normals(scene: &Scene) -> Vec<Vec3> {
    let mesh = &scene.mesh;
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = mesh.vertices(t);
            (b - a).cross(c - a)
        })
        .collect()
}

#[test]
fn box_textured_glb() {
    let scene = sample("BoxTextured/BoxTextured.glb");
    assert_eq!(scene.mesh.triangles.len(), 12);
    assert_eq!(scene.mesh.positions.len(), 24);
    assert_eq!(scene.material_names, ["Texture"]);
    let m = scene.materials[0];
    assert_eq!(
        (m.kind, m.metallic, m.roughness),
        (MaterialKind::PBR, 0.0, 1.0)
    );
    assert_ne!(m.albedo_texture, NO_TEXTURE);
    let texture = scene.textures.records[m.albedo_texture as usize];
    assert!(texture.width > 0 && texture.height > 0);
    assert!(
        scene
            .mesh
            .triangles
            .iter()
            .all(|t| t.t[0] != NO_UV && t.n[0] != meshtrace::scene::NO_NORMAL)
    );
    // A unit cube about the origin (the root node turns Z up into Y up).
    let (lo, hi) = scene
        .mesh
        .positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    assert!(
        close(lo, Vec3::splat(-0.5)) && close(hi, Vec3::splat(0.5)),
        "{lo} {hi}"
    );
    // Every face points out of the cube.
    let mesh = &scene.mesh;
    for (t, n) in mesh.triangles.iter().zip(normals(&scene)) {
        let centre = mesh.vertices(t).iter().sum::<Vec3>() / 3.0;
        assert!(n.dot(centre) > 0.0, "a face turned inwards: {centre} {n}");
    }
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    // No light of its own: the studio's.
    assert!(
        matches!(scene.sky, Sky::Environment { .. }),
        "{:?}",
        scene.sky
    );
}

#[test]
fn cameras_uses_the_perspective_camera() {
    let scene = sample("Cameras/Cameras.gltf");
    let c = &scene.camera;
    assert!(
        close(c.position, Vec3::new(0.5, 0.5, 3.0)),
        "{}",
        c.position
    );
    assert!(close(c.forward, Vec3::NEG_Z) && close(c.up, Vec3::Y));
    assert!((c.vfov - 0.7f32.to_degrees()).abs() < 1e-4, "{}", c.vfov);
    assert_eq!(scene.mesh.triangles.len(), 2);
    // The square is turned about X by the node's rotation: (0, 1, 0) moves towards -z.
    let top = scene.mesh.positions[2];
    assert!(top.y > 0.0 && top.y < 1.0 && top.z < 0.0, "{top}");
    // Without a material, the specification's default one.
    assert_eq!(scene.material_names, ["default (glTF)"]);
}

#[test]
fn simple_sparse_accessor_moves_three_vertices() {
    let scene = sample("SimpleSparseAccessor/SimpleSparseAccessor.gltf");
    let p = &scene.mesh.positions;
    assert_eq!(p.len(), 14);
    assert_eq!(scene.mesh.triangles.len(), 12);
    // The base: a row of 7 at y = 0 and 7 at y = 1; vertices 8, 10 and 12 move up.
    assert_eq!(p[0], Vec3::ZERO);
    assert_eq!(p[7], Vec3::new(0.0, 1.0, 0.0));
    assert_eq!(p[8], Vec3::new(1.0, 2.0, 0.0));
    assert_eq!(p[9], Vec3::new(2.0, 1.0, 0.0));
    assert_eq!(p[10], Vec3::new(3.0, 3.0, 0.0));
    assert_eq!(p[12], Vec3::new(5.0, 4.0, 0.0));
}

#[test]
fn texture_transform_test_offsets_rotations_and_scales() {
    let scene = sample("TextureTransformTest/TextureTransformTest.gltf");
    let record = |name: &str| {
        let i = scene.material_names.iter().position(|n| n == name).unwrap();
        scene.textures.records[scene.materials[i].albedo_texture as usize]
    };
    assert_eq!(record("Offset U").uv_offset, [0.5, 0.0]);
    assert_eq!(record("Offset V").uv_offset, [0.0, 0.5]);
    assert_eq!(record("Offset UV").uv_offset, [0.5, 0.5]);
    // 0.392699 rad, 22.5 degrees.
    let (s, c) = std::f32::consts::FRAC_PI_8.sin_cos();
    let rotation = record("Rotation").uv_matrix;
    for (g, e) in rotation.iter().zip([c, s, -s, c]) {
        assert!((g - e).abs() < 1e-5, "{rotation:?}");
    }
    assert_eq!(record("Scale").uv_matrix, [1.5, 0.0, 0.0, 1.5]);
    let all = record("All");
    assert_eq!(all.uv_offset, [-0.2, -0.1]);
    let (s, c) = 0.3f32.sin_cos();
    for (g, e) in all
        .uv_matrix
        .iter()
        .zip([1.5 * c, 1.5 * s, -1.5 * s, 1.5 * c])
    {
        assert!((g - e).abs() < 1e-5, "{:?}", all.uv_matrix);
    }
    assert_eq!(scene.materials.len(), 9);
    // The file's sampler clamps to the edge along both axes, which the records keep.
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(all.wrap, Wrap::pack(Wrap::CLAMP, Wrap::CLAMP));
}

#[test]
fn primitive_modes_strips_fans_and_lines() {
    for n in ["04", "05", "11", "12", "14"] {
        let scene = sample(&format!("Mesh_PrimitiveMode/Mesh_PrimitiveMode_{n}.gltf"));
        let normals = normals(&scene);
        assert_eq!(normals.len(), 2, "{n}");
        // The unit square, both triangles facing +Z.
        let area: f32 = normals.iter().map(|v| 0.5 * v.z).sum();
        assert!((area - 1.0).abs() < 1e-6, "{n}: area {area}");
        assert!(normals.iter().all(|v| v.z > 0.0), "{n}: {normals:?}");
    }
    let err = load_scene(&data("gltf/Mesh_PrimitiveMode/Mesh_PrimitiveMode_01.gltf"))
        .unwrap_err()
        .to_string();
    assert!(
        err.ends_with("scene: the default scene has no triangles to render"),
        "{err}"
    );
}

/// The albedo texture's size and texels (8-bit, sRGB) of a one-material scene.
fn albedo_texels(scene: &Scene) -> (u32, u32, Vec<[u8; 4]>) {
    let t = scene.textures.records[scene.materials[0].albedo_texture as usize];
    assert_eq!(t.format, meshtrace::scene::TextureFormat::RGBA8_SRGB);
    let n = (t.width * t.height) as usize;
    let texels = scene.textures.texels[t.offset as usize..][..n]
        .iter()
        .map(|w| w.to_le_bytes())
        .collect();
    (t.width, t.height, texels)
}

/// Mean absolute difference of two images' RGB values, in [0, 1].
fn texel_difference(a: &[[u8; 4]], b: &[[u8; 4]]) -> f64 {
    let sum: u64 = a
        .iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |c| p[c].abs_diff(q[c]) as u64))
        .sum();
    sum as f64 / (a.len() * 3) as f64 / 255.0
}

/// Mean absolute difference of two renders' pixels, relative to the first's mean.
fn render_difference(a: &Scene, b: &Scene) -> f64 {
    let render = |s: &Scene| {
        let settings = meshtrace::scene::RenderSettings {
            width: 48,
            height: 48,
            spp: 8,
            ..s.settings
        };
        let rs = meshtrace::render::RenderScene::new(s, &Default::default()).unwrap();
        common::cpu_render(&rs, &meshtrace::render::RenderJob::new(settings)).mean()
    };
    let (a, b) = (render(a), render(b));
    let diff: f64 = a
        .iter()
        .zip(&b)
        .map(|(p, q)| f64::from((*p - *q).abs().element_sum()))
        .sum();
    let total: f64 = a.iter().map(|p| f64::from(p.element_sum())).sum();
    diff / total
}

/// BoxTextured with its PNG made a lossy WebP by glTF-Transform 4.5.1, named by the
/// texture's EXT_texture_webp alone (see tests/data/gltf/README.md): the extension is
/// required and read, the WebP image has the PNG's size and nearly its texels, and the box
/// renders as the PNG original does. The bounds are set by a wrong texture: the PNG
/// mirrored left to right differs from the PNG many times more, texels and render alike.
#[test]
fn box_textured_webp_reads_the_ext_texture_webp_image() {
    let png = sample("BoxTextured/BoxTextured.glb");
    let webp = sample("BoxTexturedWebp/BoxTexturedWebp.glb");
    assert!(webp.warnings.is_empty(), "{:?}", webp.warnings);
    let (w, h, png_texels) = albedo_texels(&png);
    let (w2, h2, webp_texels) = albedo_texels(&webp);
    assert_eq!((w, h), (w2, h2));
    let mirrored: Vec<[u8; 4]> = (0..w * h)
        .map(|i| png_texels[((i / w) * w + (w - 1 - i % w)) as usize])
        .collect();
    let own = texel_difference(&png_texels, &webp_texels);
    let wrong = texel_difference(&png_texels, &mirrored);
    eprintln!("texels: WebP against PNG {own:.4}, mirrored PNG against PNG {wrong:.4}");
    assert!(
        own < 0.015,
        "the WebP's texels differ from the PNG's by {own}"
    );
    assert!(wrong > 0.05, "a mirrored texture differs by {wrong} only");

    let mut wrong_scene = sample("BoxTextured/BoxTextured.glb");
    let t = wrong_scene.textures.records[wrong_scene.materials[0].albedo_texture as usize];
    for (k, p) in mirrored.iter().enumerate() {
        wrong_scene.textures.texels[t.offset as usize + k] = u32::from_le_bytes(*p);
    }
    let own = render_difference(&png, &webp);
    let wrong = render_difference(&png, &wrong_scene);
    eprintln!("renders: WebP against PNG {own:.4}, mirrored PNG against PNG {wrong:.4}");
    assert!(
        own < 0.02,
        "the WebP render differs from the PNG's by {own}"
    );
    assert!(
        wrong > 0.03,
        "a mirrored texture's render differs by {wrong} only"
    );
}

/// BoxTextured with its PNG encoded as KTX2 by Binomial's basisu encoder, ETC1S and UASTC
/// (Zstandard-supercompressed), named by the texture's KHR_texture_basisu alone and written
/// by glTF-Transform 4.5.1 (see tests/data/gltf/README.md): the extension is required and
/// read, and the transcoded image has the PNG's size (211², not a multiple of the 4×4
/// blocks) and nearly its texels: ETC1S, the lossier, within 2 % on average (measured
/// 0.63 %), UASTC within 0.5 % (0.03 %). A wrong decode (the PNG mirrored) differs by 10 %.
#[test]
fn box_textured_basisu_reads_the_khr_texture_basisu_image() {
    let png = sample("BoxTextured/BoxTextured.glb");
    let (w, h, png_texels) = albedo_texels(&png);
    let mirrored: Vec<[u8; 4]> = (0..w * h)
        .map(|i| png_texels[((i / w) * w + (w - 1 - i % w)) as usize])
        .collect();
    let wrong = texel_difference(&png_texels, &mirrored);
    assert!(wrong > 0.05, "a mirrored texture differs by {wrong} only");
    for (file, bound) in [("Etc1s", 0.02), ("Uastc", 0.005)] {
        let ktx2 = sample(&format!("BoxTexturedBasisu/BoxTextured{file}.glb"));
        assert!(ktx2.warnings.is_empty(), "{file}: {:?}", ktx2.warnings);
        let (w2, h2, texels) = albedo_texels(&ktx2);
        assert_eq!((w, h), (w2, h2), "{file}");
        let own = texel_difference(&png_texels, &texels);
        eprintln!("texels: {file} against PNG {own:.4}, mirrored PNG against PNG {wrong:.4}");
        assert!(
            own < bound,
            "{file}: the texels differ from the PNG's by {own}"
        );
    }
}
