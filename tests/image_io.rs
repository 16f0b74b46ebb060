//! The film's image files: what each format keeps of the radiance, atomic writes, merging
//! of sample ranges, and the sRGB transfer function.

use crate::common;

use common::fs::TempDir;
use glam::Vec3;
use meshtrace::film::{
    Accumulation, BitDepth, Film, FilmError, Format, linear_to_srgb8, linear_to_srgb16,
    read_linear, srgb8_to_linear,
};
use meshtrace::fixed::{fixed_add3, texel_add, to_fixed, to_fixed3};
use std::path::Path;

const VALUES: [f32; 11] = [0.0, 0.5, 1.0, 3.7, 1e-3, 0.18, 0.02, 2.0, 0.75, 10.0, 0.04];

/// A 7x5 film with one sample per pixel, cycling through `VALUES` per channel.
fn test_film() -> Film {
    let (w, h) = (7, 5);
    let mut film = Film::new(w, h);
    for (i, px) in film.sum.iter_mut().enumerate() {
        let v = |c: usize| VALUES[(3 * i + c) % VALUES.len()];
        *px = to_fixed3(Vec3::new(v(0), v(1), v(2)));
    }
    film.samples = 1;
    film
}

fn save_and_read(film: &Film, dir: &TempDir, name: &str) -> Vec<Vec3> {
    let path = dir.path().join(name);
    film.save(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    let (w, h, pixels) = read_linear(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!((w, h), (film.width, film.height), "{name}: size");
    assert_eq!(pixels.len(), (w * h) as usize);
    pixels
}

#[test]
fn exr_is_exact() {
    let dir = TempDir::new("exr");
    let film = test_film();
    let pixels = save_and_read(&film, &dir, "out.exr");
    assert_eq!(pixels, film.mean());
}

#[test]
fn exr_keeps_the_mean_of_many_samples() {
    let dir = TempDir::new("exr-mean");
    let mut film = test_film();
    for s in &mut film.sum {
        *s = s.map(|c| c * 4);
    }
    film.samples = 4;
    let pixels = save_and_read(&film, &dir, "mean.exr");
    assert_eq!(pixels, test_film().mean());
}

#[test]
fn hdr_is_within_rgbe_precision() {
    let dir = TempDir::new("hdr");
    let film = test_film();
    let pixels = save_and_read(&film, &dir, "out.hdr");
    for (i, (got, want)) in pixels.iter().zip(film.mean()).enumerate() {
        // RGBE shares one exponent: each channel is within 1/128 of the largest one.
        let tol = want.max_element() / 128.0;
        assert!(
            (*got - want).abs().max_element() <= tol,
            "pixel {i}: got {got}, wrote {want}"
        );
        if want == Vec3::ZERO {
            assert_eq!(*got, Vec3::ZERO, "pixel {i}: black stays black");
        }
    }
}

#[test]
fn eight_bit_formats_are_srgb_quantised_and_clamped() {
    let dir = TempDir::new("8bit");
    let film = test_film();
    for name in ["out.png", "out.bmp", "OUT.PNG", "out.webp"] {
        let pixels = save_and_read(&film, &dir, name);
        for (i, (got, want)) in pixels.iter().zip(film.mean()).enumerate() {
            let expected = want.to_array().map(|x| srgb8_to_linear(linear_to_srgb8(x)));
            assert_eq!(got.to_array(), expected, "{name} pixel {i}");
            for c in 0..3 {
                if want[c] >= 1.0 {
                    assert_eq!(got[c], 1.0, "{name} pixel {i}: {} clamps to 1", want[c]);
                }
            }
        }
    }
}

#[test]
fn jpeg_is_close() {
    let dir = TempDir::new("jpeg");
    // A smooth image (JPEG's domain): a gradient in each channel, plus one clamped value.
    let (w, h) = (16, 16);
    let mut film = Film::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let fx = x as f32 / (w - 1) as f32;
            let fy = y as f32 / (h - 1) as f32;
            film.sum[(y * w + x) as usize] = to_fixed3(Vec3::new(fx, fy, 0.5 * (fx + fy)) * 2.0);
        }
    }
    film.samples = 2;
    for name in ["out.jpg", "out.jpeg"] {
        let pixels = save_and_read(&film, &dir, name);
        let mean = film.mean();
        let err: f32 = pixels
            .iter()
            .zip(&mean)
            .map(|(a, b)| (*a - b.clamp(Vec3::ZERO, Vec3::ONE)).abs().element_sum())
            .sum::<f32>()
            / (3 * pixels.len()) as f32;
        assert!(err < 0.02, "{name}: mean abs error {err}");
    }
}

#[test]
fn format_from_extension() {
    let f = |p: &str| Format::from_path(Path::new(p)).ok();
    assert_eq!(f("a.exr"), Some(Format::Exr));
    assert_eq!(f("a.HDR"), Some(Format::Hdr));
    assert_eq!(f("dir.x/a.png"), Some(Format::Png));
    assert_eq!(f("a.jpg"), Some(Format::Jpeg));
    assert_eq!(f("a.JPEG"), Some(Format::Jpeg));
    assert_eq!(f("a.bmp"), Some(Format::Bmp));
    assert_eq!(f("a.WebP"), Some(Format::Webp));
    assert_eq!(f("a.tga"), None);
    assert_eq!(f("png"), None);
    assert_eq!(f("a.png.txt"), None);
}

#[test]
fn unknown_extension_is_an_error_naming_the_path() {
    let dir = TempDir::new("unknown");
    for name in ["out.tga", "noext"] {
        let path = dir.path().join(name);
        let err = test_film().save(&path).unwrap_err();
        match &err {
            FilmError::UnknownFormat { path: p } => assert_eq!(*p, path.display().to_string()),
            other => panic!("expected UnknownFormat, got {other:?}"),
        }
        let msg = err.to_string();
        assert_eq!(
            msg,
            format!(
                "{}: unknown image format; use .exr, .hdr, .png, .jpg, .bmp or .webp",
                path.display()
            )
        );
        let err = read_linear(&path).unwrap_err();
        assert!(matches!(err, FilmError::UnknownFormat { .. }), "{err:?}");
    }
    assert!(dir.entries().is_empty(), "{:?}", dir.entries());
}

#[test]
fn write_into_missing_directory_fails_and_leaves_nothing() {
    let dir = TempDir::new("missing-dir");
    let path = dir.path().join("no_such_dir").join("out.png");
    let err = test_film().save(&path).unwrap_err();
    match &err {
        FilmError::Io { path: p, message } => {
            assert_eq!(*p, path.display().to_string());
            assert!(!message.is_empty());
        }
        other => panic!("expected Io, got {other:?}"),
    }
    assert!(err.to_string().starts_with(&path.display().to_string()));
    assert!(!path.exists());
    assert!(dir.entries().is_empty(), "{:?}", dir.entries());
}

#[test]
fn failed_encode_leaves_no_file() {
    let dir = TempDir::new("bad-film");
    // A film whose pixel count does not match its size cannot be encoded.
    let mut film = Film::new(4, 4);
    film.sum.truncate(3);
    film.samples = 1;
    for name in ["bad.png", "bad.exr"] {
        let path = dir.path().join(name);
        let err = film.save(&path).unwrap_err();
        assert!(matches!(err, FilmError::Io { .. }), "{err:?}");
        assert!(!path.exists());
    }
    assert!(dir.entries().is_empty(), "{:?}", dir.entries());
}

#[test]
fn no_temporary_file_remains_after_save() {
    let dir = TempDir::new("tmp-files");
    let film = test_film();
    let names = ["a.exr", "a.hdr", "a.png", "a.jpg", "a.bmp", "a.webp"];
    for name in names {
        film.save(&dir.path().join(name)).unwrap();
    }
    // overwriting an existing image also goes through a temporary
    film.save(&dir.path().join("a.png")).unwrap();
    let mut expected: Vec<String> = names.iter().map(|s| s.to_string()).collect();
    expected.sort();
    let entries = dir.entries();
    assert!(
        !entries
            .iter()
            .any(|n| n.starts_with('.') || n.ends_with(".tmp")),
        "{entries:?}"
    );
    assert_eq!(entries, expected);
}

/// Films of disjoint sample ranges merge into the bits of the film of all of them, for
/// every split and order, though the samples are values whose f32 sums depend on the order
/// (a spread of magnitudes from 1e-4 to 1e4).
#[test]
fn merges_of_sample_ranges_equal_all_samples_bit_for_bit() {
    let (w, h, n) = (6u32, 4u32, 12u32);
    let sample = |i: usize, k: u32| {
        let x = ((i as u32 * 7919 + k * 104729) % 1000) as f32 / 1000.0;
        Vec3::new(
            10f32.powf(8.0 * x - 4.0),
            x * 0.1 + 0.3,
            (k as f32 * 0.7).sin().abs(),
        )
    };
    let render = |range: std::ops::Range<u32>| {
        let mut film = Film::new(w, h);
        for k in range.clone() {
            for (i, px) in film.sum.iter_mut().enumerate() {
                *px = fixed_add3(*px, to_fixed3(sample(i, k)));
            }
        }
        film.samples = range.len() as u32;
        film
    };
    let all = render(0..n);
    // In f32 the order matters for these samples: the test would pass vacuously otherwise.
    let f32_sum = |order: &[u32]| {
        order
            .iter()
            .map(|&k| sample(3, k))
            .fold(Vec3::ZERO, |a, b| a + b)
    };
    let forward: Vec<u32> = (0..n).collect();
    let split: Vec<u32> = (5..n).chain(0..5).collect();
    assert_ne!(f32_sum(&forward), f32_sum(&split));
    for parts in 1..=n {
        let bounds: Vec<u32> = (0..=parts).map(|p| p * n / parts).collect();
        let films: Vec<Film> = bounds.windows(2).map(|b| render(b[0]..b[1])).collect();
        for reversed in [false, true] {
            let mut order: Vec<&Film> = films.iter().collect();
            if reversed {
                order.reverse();
            }
            let mut merged = order[0].clone();
            for f in &order[1..] {
                merged.merge(f);
            }
            assert_eq!(merged, all, "{parts} parts, reversed {reversed}");
        }
    }
    // And the mean is the mean of the samples.
    let mean0 = (0..n).map(|k| sample(0, k).as_dvec3()).sum::<glam::DVec3>() / n as f64;
    assert!((all.mean()[0].as_dvec3() - mean0).abs().max_element() < 1e-6 * mean0.max_element());
}

/// A two-pixel film holding one sample range of three channels, as a renderer would fill
/// them: a value per sample (all samples), a value per sample that hit (pixel 0's samples
/// hit when even; pixel 1's never), and the centre ray's value where the range holds
/// sample 0.
fn channel_film(range: std::ops::Range<u32>) -> Film {
    let mut film = Film::new(2, 1);
    film.add_channel("all", 1, Accumulation::AllSamples);
    film.add_channel("hits", 3, Accumulation::HitSamples);
    film.add_channel("centre", 1, Accumulation::PixelCentre);
    for k in range.clone() {
        let t = &mut film.channels[1].data;
        t[0] = texel_add(t[0], [k as f32, 0.0, 0.0, 0.0]);
        t[1] = texel_add(t[1], [1.0, 0.0, 0.0, 0.0]);
        if k % 2 == 0 {
            let t = &mut film.channels[2].data[0];
            *t = texel_add(*t, [k as f32, 1.0, 2.0, 1.0]);
        }
    }
    if range.start == 0 {
        let centre = |v: f32| texel_add([0; 4], [v, 0.0, 0.0, 1.0]);
        film.channels[3].data = vec![centre(7.0), centre(9.0)];
    }
    film.samples = range.len() as u32;
    film
}

/// Each accumulation rule gives its own mean, and films of disjoint sample ranges merge
/// into the film of all of them.
#[test]
fn channels_follow_their_accumulation_rules_and_merge() {
    let all = channel_film(0..6);
    let value = |film: &Film, name: &str| film.channel_values(film.channel(name).unwrap());
    // Pixel 0: samples 0..6 sum to 15, a mean of 2.5; pixel 1 gives 1 each time.
    assert_eq!(
        value(&all, "all"),
        [Some([2.5, 0.0, 0.0]), Some([1.0, 0.0, 0.0])]
    );
    // Pixel 0 hit with samples 0, 2, 4: a mean of 2 over the three; pixel 1 never hit.
    assert_eq!(value(&all, "hits"), [Some([2.0, 1.0, 2.0]), None]);
    assert_eq!(
        value(&all, "centre"),
        [Some([7.0, 0.0, 0.0]), Some([9.0, 0.0, 0.0])]
    );
    // The parts: the centre rays come with the part that holds sample 0, in either order.
    for split in 1..6 {
        let (a, b) = (channel_film(0..split), channel_film(split..6));
        assert_eq!(value(&b, "centre"), [None, None]);
        let mut ab = a.clone();
        ab.merge(&b);
        let mut ba = b.clone();
        ba.merge(&a);
        for merged in [ab, ba] {
            assert_eq!(merged.samples, 6);
            for name in ["all", "hits", "centre", Film::RAYS] {
                assert_eq!(value(&merged, name), value(&all, name), "{name} at {split}");
            }
        }
    }
}

#[test]
fn rays_are_counted_per_pixel() {
    let mut film = Film::new(2, 2);
    assert_eq!(film.channels[0].name, Film::RAYS);
    film.channels[0].data[1][0] = to_fixed(5.0);
    film.channels[0].data[3][0] = to_fixed(7.0);
    assert_eq!(film.rays(), 12);
    assert_eq!(film.texels_per_pixel(), 2);
}

#[test]
#[should_panic]
fn merge_of_different_channels_panics() {
    let mut a = Film::new(2, 2);
    let mut b = Film::new(2, 2);
    b.add_channel("depth", 1, Accumulation::HitSamples);
    a.merge(&b);
}

#[test]
#[should_panic]
fn merge_of_different_sizes_panics() {
    let mut a = Film::new(2, 2);
    a.merge(&Film::new(2, 3));
}

#[test]
fn empty_film_is_black() {
    let film = Film::new(3, 2);
    assert_eq!(film.samples, 0);
    assert_eq!(film.sum.len(), 6);
    assert_eq!(film.mean(), vec![Vec3::ZERO; 6]);
}

#[test]
fn srgb_round_trips_every_code() {
    for v in 0..=255u8 {
        let x = srgb8_to_linear(v);
        assert!((0.0..=1.0).contains(&x), "{v} -> {x}");
        assert_eq!(linear_to_srgb8(x), v, "code {v} via {x}");
    }
    assert_eq!(srgb8_to_linear(0), 0.0);
    assert_eq!(srgb8_to_linear(255), 1.0);
    // strictly increasing
    for v in 0..255u8 {
        assert!(srgb8_to_linear(v) < srgb8_to_linear(v + 1));
    }
}

#[test]
fn srgb_encoding_values() {
    assert_eq!(linear_to_srgb8(0.0), 0);
    assert_eq!(linear_to_srgb8(1.0), 255);
    assert_eq!(linear_to_srgb8(3.7), 255);
    assert_eq!(linear_to_srgb8(f32::INFINITY), 255);
    assert_eq!(linear_to_srgb8(-1.0), 0);
    assert_eq!(linear_to_srgb8(f32::NAN), 0);
    // mid grey: 0.5 linear is 0.7354 sRGB -> 188 (187.5 rounds up)
    assert_eq!(linear_to_srgb8(0.5), 188);
    // 0.18 linear -> 0.4614 sRGB -> 118
    assert_eq!(linear_to_srgb8(0.18), 118);
    // the linear segment: 0.001 * 12.92 * 255 = 3.29 -> 3
    assert_eq!(linear_to_srgb8(1e-3), 3);
    assert!((srgb8_to_linear(188) - 0.5029).abs() < 1e-4);
    assert!((srgb8_to_linear(10) - 10.0 / 255.0 / 12.92).abs() < 1e-9);
}

/// A 16-bit PNG holds each channel as the sRGB curve rounded to 16 bits: 257 times as many
/// levels as the 8-bit one, which it agrees with to within half an 8-bit step. Other
/// formats refuse 16 bits.
#[test]
fn png_of_16_bits_rounds_the_srgb_curve_to_16_bits() {
    let dir = TempDir::new("png16");
    let film = test_film();
    let deep = dir.path().join("deep.png");
    film.save_as(&deep, BitDepth::Sixteen, &Default::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let img = image::open(&deep).expect("a PNG");
    assert_eq!(img.color(), image::ColorType::Rgb16);
    let img = img.into_rgb16();
    let shallow = dir.path().join("shallow.png");
    film.save(&shallow).unwrap();
    let eight = image::open(&shallow).expect("a PNG").into_rgb8();
    for ((p, mean), q) in img.pixels().zip(film.mean()).zip(eight.pixels()) {
        for c in 0..3 {
            assert_eq!(p[c], linear_to_srgb16(mean[c]), "{mean}");
            let as_eight = p[c] as f64 / 65535.0 * 255.0;
            assert!(
                (as_eight - q[c] as f64).abs() <= 0.5 + 1e-9,
                "{mean}: {} vs {}",
                p[c],
                q[c]
            );
        }
    }
    // Distinct 16-bit levels where 8 bits have one: 0.18 and 0.1805 share an 8-bit level.
    assert_eq!(linear_to_srgb8(0.18), linear_to_srgb8(0.1805));
    assert_ne!(linear_to_srgb16(0.18), linear_to_srgb16(0.1805));
    for name in ["deep.exr", "deep.hdr", "deep.jpg", "deep.bmp", "deep.webp"] {
        let err = film
            .save_as(
                &dir.path().join(name),
                BitDepth::Sixteen,
                &Default::default(),
            )
            .unwrap_err();
        assert!(matches!(err, FilmError::DeepNotPng { .. }), "{name}: {err}");
        assert!(err.to_string().contains(name), "{err}");
    }
}

/// A transparent film writes the same RGBA to a lossless WebP as to a PNG (straight alpha,
/// the coverage), and refuses a format without alpha.
#[test]
fn transparent_webp_is_the_pngs_rgba() {
    let dir = TempDir::new("webp-rgba");
    let mut film = Film::with_aovs(7, 5, 0, true);
    let base = test_film();
    film.sum = base.sum.clone();
    film.samples = 1;
    let alpha = film
        .channels
        .iter()
        .position(|c| c.name == meshtrace::film::Aov::Alpha.name())
        .unwrap();
    for (i, t) in film.channels[alpha].data.iter_mut().enumerate() {
        *t = texel_add(*t, [(i % 3) as f32 / 2.0, 0.0, 0.0, 0.0]);
    }
    let read = |name: &str| {
        let path = dir.path().join(name);
        film.save(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        image::open(&path).unwrap().into_rgba8()
    };
    let (png, webp) = (read("a.png"), read("a.webp"));
    assert_eq!(webp.as_raw(), png.as_raw());
    assert!(png.pixels().any(|p| p[3] == 0) && png.pixels().any(|p| p[3] == 255));
    let err = film.save(&dir.path().join("a.jpg")).unwrap_err();
    assert!(matches!(err, FilmError::TransparentNotPng { .. }), "{err}");
}
