//! The view transforms against Blender's own colour management. Blender 5.0.1 saved the
//! premultiplied RGBA ramp `data/view_transforms/input.exr` (28 stops, greys, saturated
//! hues, partial alpha) as 8- and 16-bit PNGs through its Standard, Filmic and AgX views
//! (`tools/view_transforms.py`); meshtrace's film of the same radiance must give the same
//! pixels. Filmic and AgX read Blender's LUTs, from the folder MESHTRACE_BLENDER_LUTS names
//! (.ci/run fills it from Debian's blender-data); without them those tests skip, unless
//! MESHTRACE_REQUIRE_BLENDER_LUTS=1, as CI sets it.

use crate::common;

use common::cli::{assert_fails, output_with, run};
use common::fs::{TempDir, data};
use meshtrace::film::{Aov, BitDepth, Film, ViewTransform};
use meshtrace::fixed::{to_fixed, to_fixed3};

use common::luts::view_or_skip as load;

/// The transparent film of Blender's input image: its premultiplied colour the mean, its
/// alpha the coverage, of one sample.
fn input_film() -> Film {
    use exr::prelude::{FlatSamples, read_all_flat_layers_from_file};
    let image = read_all_flat_layers_from_file(data("view_transforms/input.exr")).expect("an EXR");
    let layer = &image.layer_data[0];
    let channel = |name: &str| -> Vec<f32> {
        let c = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name == *name)
            .unwrap_or_else(|| panic!("channel {name}"));
        match &c.sample_data {
            FlatSamples::F32(v) => v.clone(),
            FlatSamples::F16(v) => v.iter().map(|h| h.to_f32()).collect(),
            FlatSamples::U32(_) => panic!("{name} holds integers"),
        }
    };
    let [r, g, b, a] = ["R", "G", "B", "A"].map(channel);
    let (w, h) = (layer.size.0 as u32, layer.size.1 as u32);
    let mut film = Film::with_aovs(w, h, 0, true);
    film.samples = 1;
    let alpha = film
        .channels
        .iter()
        .position(|c| c.name == Aov::Alpha.name())
        .expect("a transparent film's alpha");
    for i in 0..r.len() {
        film.sum[i] = to_fixed3(glam::Vec3::new(r[i], g[i], b[i]));
        film.channels[alpha].data[i][0] = to_fixed(a[i]);
    }
    film
}

/// The largest difference in levels between two PNGs of RGBA at `bits`, and the fraction of
/// their channels that differ.
fn compare(ours: &std::path::Path, blender: &std::path::Path) -> (u16, f64) {
    let read = |p: &std::path::Path| {
        image::open(p)
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()))
            .into_rgba16()
            .into_raw()
    };
    let (a, b) = (read(ours), read(blender));
    assert_eq!(a.len(), b.len());
    let diffs: Vec<u16> = a.iter().zip(&b).map(|(x, y)| x.abs_diff(*y)).collect();
    let differ = diffs.iter().filter(|&&d| d > 0).count() as f64 / diffs.len() as f64;
    (diffs.into_iter().max().unwrap_or(0), differ)
}

/// Each view's 8- and 16-bit PNG of the ramp is Blender's to within one level, the 8-bit
/// ones in at least 99% of the channels exactly; and the three views differ, by more than
/// 40 levels of 255 somewhere (Filmic and AgX compress what the sRGB curve clips).
#[test]
fn each_view_forms_blenders_pixels() {
    let dir = TempDir::new("views");
    let film = input_film();
    let mut eight = Vec::new();
    for (name, view) in ViewTransform::NAMES {
        let Some(display) = load("each_view_forms_blenders_pixels", view) else {
            continue;
        };
        for (bits, depth) in [(8, BitDepth::Eight), (16, BitDepth::Sixteen)] {
            let ours = dir.join(format!("{name}{bits}.png"));
            film.save_as(&ours, depth, &display)
                .unwrap_or_else(|e| panic!("{e}"));
            let blender = data(&format!("view_transforms/{name}{bits}.png"));
            let (max, differ) = compare(&ours, &blender);
            // `into_rgba16` scales 8-bit levels by 257.
            let level = if bits == 8 { 257 } else { 1 };
            eprintln!(
                "{name} {bits}-bit: largest difference {} levels, {:.2}% of channels differ",
                max / level,
                100.0 * differ
            );
            assert!(
                max <= level,
                "{name} {bits}-bit: {} levels off",
                max / level
            );
            if bits == 8 {
                assert!(
                    differ <= 0.01,
                    "{name} 8-bit: {:.2}% differ",
                    100.0 * differ
                );
                eight.push((name, ours));
            }
        }
    }
    for pair in eight.windows(2) {
        let (max, _) = compare(&pair[0].1, &pair[1].1);
        assert!(
            max / 257 > 40,
            "{} and {} differ by {} levels at most",
            pair[0].0,
            pair[1].0,
            max / 257
        );
    }
}

/// `render --view-transform` writes the PNG that the view forms from the same render's
/// radiance (its EXR), bit for bit; `merge --view-transform` does the same from parts.
#[test]
fn render_and_merge_write_the_view() {
    let Some(display) = load("render_and_merge_write_the_view", ViewTransform::Agx) else {
        return;
    };
    let dir = TempDir::new("view-cli");
    let flags = [
        "--width", "24", "--height", "16", "--spp", "2", "--device", "cpu",
    ];
    let render = |extra: &[&str]| {
        let args: Vec<&str> = ["render"]
            .iter()
            .chain(&flags)
            .chain(extra)
            .copied()
            .collect();
        let (code, stderr) = run(&dir, &args);
        assert_eq!(code, 0, "{args:?}: {stderr}");
    };
    render(&["-o", "linear.exr"]);
    render(&["-o", "agx.png", "--view-transform", "agx"]);
    render(&["-o", "part0.exr", "--part", "0/2"]);
    render(&["-o", "part1.exr", "--part", "1/2"]);
    let (code, stderr) = run(
        &dir,
        &[
            "merge",
            "part0.exr",
            "part1.exr",
            "-o",
            "merged.png",
            "--view-transform",
            "agx",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    let (w, h, radiance) = meshtrace::film::read_linear(&dir.join("linear.exr")).unwrap();
    let expected: Vec<u8> = radiance
        .iter()
        .flat_map(|&c| display.encode(c).map(meshtrace::film::quantise8))
        .collect();
    for name in ["agx.png", "merged.png"] {
        let png = image::open(dir.join(name)).expect("a PNG").into_rgb8();
        assert_eq!((png.width(), png.height()), (w, h));
        assert!(png.into_raw() == expected, "{name} is not AgX of the EXR");
    }
    // The sRGB curve of the same radiance is another image.
    render(&["-o", "standard.png"]);
    let standard = image::open(dir.join("standard.png")).unwrap().into_rgb8();
    assert!(standard.into_raw() != expected);
}

/// A batch forms every image by its manifest's `render.view_transform`: the same coverage
/// as the sRGB curve's images, other colours; and without the LUTs it fails before the
/// first input, naming the manifest's field.
#[test]
fn a_batch_forms_its_images_by_the_manifest_view() {
    let Some(_) = load(
        "a_batch_forms_its_images_by_the_manifest_view",
        ViewTransform::Filmic,
    ) else {
        return;
    };
    let dir = TempDir::new("view-batch");
    dir.write("tri.obj", "v -1 -1 0\nv 1 -1 0\nv 0 1 0.5\nf 1 2 3\n");
    let manifest = |view: &str| {
        format!(
            "[render]\nspp = 2\nwidth = 16\nheight = 16\ntransparent = true\nview_transform = \"{view}\"\n\
             [[jobs]]\nmeshes = \"tri.obj\"\nviews = 1\noutput = \"{view}/{{stem}}.png\"\n"
        )
    };
    for view in ["standard", "filmic"] {
        dir.write(&format!("{view}.toml"), manifest(view));
        let (code, stderr) = run(&dir, &["batch", &format!("{view}.toml"), "--device", "cpu"]);
        assert_eq!(code, 0, "{stderr}");
    }
    let read = |view: &str| {
        image::open(dir.join(format!("{view}/tri.png")))
            .unwrap()
            .into_rgba8()
    };
    let (standard, filmic) = (read("standard"), read("filmic"));
    let alpha = |img: &image::RgbaImage| img.pixels().map(|p| p[3]).collect::<Vec<_>>();
    assert_eq!(alpha(&standard), alpha(&filmic));
    assert!(alpha(&filmic).contains(&255));
    let colour =
        |img: &image::RgbaImage| img.pixels().map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>();
    assert_ne!(colour(&standard), colour(&filmic));
    fails_with_luts(
        &dir,
        &dir.join("nowhere"),
        &["batch", "filmic.toml", "--device", "cpu"],
        &[
            "filmic.toml: render.view_transform: ",
            "filmic_desat_33.cube not found",
        ],
    );
}

/// Runs meshtrace with MESHTRACE_BLENDER_LUTS naming `luts`; asserts that it fails with
/// every one of `needles` in its output and writes no `x.png`.
fn fails_with_luts(dir: &TempDir, luts: &std::path::Path, args: &[&str], needles: &[&str]) {
    let out = output_with(dir, args, &[("MESHTRACE_BLENDER_LUTS", luts)]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
    for needle in needles {
        assert!(
            stderr.contains(needle),
            "{args:?}: no `{needle}` in {stderr}"
        );
    }
    assert!(!dir.join("x.png").exists());
}

/// Where the LUTs are missing or damaged, or the output holds floats, the render fails
/// before it starts, with one line naming the file (and its line) or the output.
#[test]
fn missing_or_bad_luts_and_float_outputs_are_refused() {
    let dir = TempDir::new("view-errors");
    let args = [
        "render", "--spp", "1", "--width", "8", "--height", "8", "-o", "x.png",
    ];
    let view = |v: &'static str| [&args[..], &["--view-transform", v]].concat();
    let empty = dir.join("empty");
    std::fs::create_dir(&empty).unwrap();
    fails_with_luts(
        &dir,
        &empty,
        &view("agx"),
        &[
            "luts/AgX_Base_sRGB.cube not found",
            "MESHTRACE_BLENDER_LUTS",
        ],
    );
    // A cube cut short, and a curve with a word that is not a number.
    let bad = dir.join("bad");
    std::fs::create_dir_all(bad.join("luts")).unwrap();
    std::fs::create_dir_all(bad.join("filmic")).unwrap();
    std::fs::write(
        bad.join("luts/AgX_Base_sRGB.cube"),
        "LUT_3D_SIZE 2\n0 0 0\n1 0 0\n",
    )
    .unwrap();
    std::fs::write(
        bad.join("filmic/filmic_desat_33.cube"),
        "LUT_3D_SIZE 2\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n",
    )
    .unwrap();
    std::fs::write(
        bad.join("filmic/filmic_to_0-70_1-03.spi1d"),
        "Version 1\nFrom 0 1\nLength 2\nComponents 1\n{\n0\nhalf\n}\n",
    )
    .unwrap();
    for (v, needle) in [
        (
            "agx",
            "AgX_Base_sRGB.cube:3: 2 entries for LUT_3D_SIZE 2 (it needs 8)",
        ),
        (
            "filmic",
            "filmic_to_0-70_1-03.spi1d:7: `half` is not a number",
        ),
    ] {
        fails_with_luts(&dir, &bad, &view(v), &[needle]);
    }
    assert_fails(
        &dir,
        &["render", "--view-transform", "agx", "-o", "x.exr"],
        &["x.exr", "EXR and HDR outputs hold the linear radiance"],
    );
    assert_fails(
        &dir,
        &[
            "render",
            "--view-transform",
            "filmic",
            "--part",
            "0/2",
            "-o",
            "x.exr",
        ],
        &["view-transform", "meshtrace merge"],
    );
}
