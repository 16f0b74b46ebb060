//! Split renders (`render --part K/N`) and `merge`: parts merge into the bytes of one
//! render on the CPU and on the GPU (lavapipe in CI), and a merge that would not be one
//! render's image (a gap, an overlap, another scene, seed or device) is refused with one
//! line and no output.

use crate::common;

use common::cli::{assert_fails, run};
use common::fs::TempDir;
use meshtrace::film::{Film, PartHeader};

/// A small render of the Cornell box with every AOV.
const RENDER: &[&str] = &[
    "render",
    "--spp",
    "12",
    "--width",
    "40",
    "--height",
    "30",
    "--aov",
    "depth,normal,albedo,alpha,object_id,material_id,bvh_cost",
    "-q",
];

/// Runs `meshtrace` in `dir` and asserts success.
fn ok(dir: &TempDir, args: &[&str]) -> String {
    let (code, stderr) = run(dir, args);
    assert_eq!(code, 0, "meshtrace {args:?}: {stderr}");
    stderr
}

/// `render` with [`RENDER`]'s settings and `extra`.
fn render(dir: &TempDir, extra: &[&str]) {
    ok(dir, &[RENDER, extra].concat());
}

fn bytes(dir: &TempDir, name: &str) -> Vec<u8> {
    std::fs::read(dir.path().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The devices to check: the CPU, and the GPU where there is an adapter (CI's lavapipe).
fn devices(test: &str) -> Vec<&'static str> {
    let mut out = vec!["cpu"];
    if common::gpu(test).is_some() {
        out.push("gpu");
    }
    out
}

#[test]
fn parts_merge_into_the_bytes_of_one_render() {
    for device in devices("parts_merge_into_the_bytes_of_one_render (GPU)") {
        let dir = TempDir::new(&format!("parts-{device}"));
        let dev = ["--device", device];
        render(&dir, &[&dev[..], &["-o", "full.exr"]].concat());
        render(&dir, &[&dev[..], &["-o", "full.png"]].concat());
        // Every part on lavapipe compiles the kernel again (seconds each), so the GPU
        // checks 1 and 3 parts, the CPU 1, 3 and 5.
        let counts: &[u32] = if device == "gpu" { &[1, 3] } else { &[1, 3, 5] };
        for &n in counts {
            let names: Vec<String> = (0..n).map(|k| format!("p{k}of{n}.exr")).collect();
            for (k, name) in names.iter().enumerate() {
                let part = format!("{k}/{n}");
                render(&dir, &[&dev[..], &["--part", &part, "-o", name]].concat());
                // Each part shows the mean of its own samples and records its range.
                let (film, header) = Film::read_part(&dir.path().join(name)).unwrap();
                let range = PartHeader::range(k as u32, n, 12);
                assert_eq!((header.start, header.end), (range.start, range.end));
                assert_eq!(film.samples, range.len() as u32);
            }
            // In reverse order, to show the order does not matter.
            let mut args = vec!["merge", "-o", "merged.exr"];
            args.extend(names.iter().rev().map(String::as_str));
            let said = ok(&dir, &args);
            assert!(!said.contains("warning"), "{said}");
            let mut png = vec!["merge", "-q", "-o", "merged.png"];
            png.extend(names.iter().map(String::as_str));
            ok(&dir, &png);
            assert!(
                bytes(&dir, "merged.exr") == bytes(&dir, "full.exr"),
                "{device}: {n} parts merged differ from one render"
            );
            assert!(
                bytes(&dir, "merged.png") == bytes(&dir, "full.png"),
                "{device}: {n} parts merged to PNG differ"
            );
        }
    }
}

/// Parts of a render with caustics (tests/scenes/box_area.toml: glass and mirror spheres
/// under an area light), whose light subpaths splat into pixels anywhere in the image, merge
/// into the bytes of one render too, and `--caustics off` is another render's setting.
#[test]
fn parts_with_caustics_merge_into_the_bytes_of_one_render() {
    let scene = common::fs::root().join("tests/scenes/box_area.toml");
    let scene = scene.to_str().unwrap();
    for device in devices("parts_with_caustics_merge_into_the_bytes_of_one_render (GPU)") {
        let dir = TempDir::new(&format!("parts-caustics-{device}"));
        let args = [scene, "--device", device, "--spp", "6", "-q"];
        ok(
            &dir,
            &[&["render"], &args[..], &["-o", "full.exr"]].concat(),
        );
        for k in 0..3 {
            let (part, name) = (format!("{k}/3"), format!("p{k}.exr"));
            ok(
                &dir,
                &[&["render"], &args[..], &["--part", &part, "-o", &name]].concat(),
            );
        }
        ok(
            &dir,
            &["merge", "-o", "merged.exr", "p2.exr", "p0.exr", "p1.exr"],
        );
        assert!(
            bytes(&dir, "merged.exr") == bytes(&dir, "full.exr"),
            "{device}: parts with caustics merged differ from one render"
        );
        let off = [
            &["render"],
            &args[..],
            &["--caustics", "off", "--part", "1/3", "-o", "p1.exr"],
        ]
        .concat();
        ok(&dir, &off);
        assert_fails(
            &dir,
            &["merge", "-o", "mixed.exr", "p0.exr", "p1.exr", "p2.exr"],
            &["parts of different scenes or settings"],
        );
    }
}

#[test]
fn merges_that_are_not_one_render_are_refused() {
    let dir = TempDir::new("parts-refused");
    let cpu = ["--device", "cpu"];
    for k in 0..3 {
        let (part, name) = (format!("{k}/3"), format!("p{k}.exr"));
        render(&dir, &[&cpu[..], &["--part", &part, "-o", &name]].concat());
    }
    render(
        &dir,
        &[
            &cpu[..],
            &["--part", "1/3", "--seed", "9", "-o", "seed.exr"],
        ]
        .concat(),
    );
    render(
        &dir,
        &[
            &cpu[..],
            &["--part", "1/3", "--max-depth", "3", "-o", "depth.exr"],
        ]
        .concat(),
    );
    render(
        &dir,
        &[&cpu[..], &["--part", "1/2", "-o", "half.exr"]].concat(),
    );
    render(&dir, &[&cpu[..], &["-o", "plain.exr"]].concat());
    fn merge<'a>(parts: &[&'a str]) -> Vec<&'a str> {
        [&["merge", "-o", "out.exr"][..], parts].concat()
    }
    assert_fails(
        &dir,
        &merge(&["p0.exr", "p2.exr"]),
        &["samples 4..8 of 12 are in no part"],
    );
    assert_fails(
        &dir,
        &merge(&["p0.exr", "p1.exr"]),
        &["samples 8..12 of 12 are in no part"],
    );
    assert_fails(
        &dir,
        &merge(&["p1.exr", "p2.exr"]),
        &["samples 0..4 of 12 are in no part"],
    );
    assert_fails(
        &dir,
        &merge(&["p0.exr", "p1.exr", "p1.exr", "p2.exr"]),
        &["p1.exr and p1.exr overlap (samples 4..8)"],
    );
    assert_fails(
        &dir,
        &merge(&["p0.exr", "p1.exr", "half.exr", "p2.exr"]),
        &["overlap"],
    );
    assert_fails(
        &dir,
        &merge(&["p0.exr", "seed.exr", "p2.exr"]),
        &["seed 0", "seed 9", "different renders"],
    );
    assert_fails(
        &dir,
        &merge(&["p0.exr", "depth.exr", "p2.exr"]),
        &["depth.exr are parts of different scenes or settings"],
    );
    assert_fails(
        &dir,
        &merge(&["p0.exr", "plain.exr"]),
        &["plain.exr: not a part file", "meshtrace.part"],
    );
    assert_fails(&dir, &merge(&["p0.exr", "nothing.exr"]), &["nothing.exr"]);
    // A part must be an EXR, and there must be samples for every part.
    assert_fails(
        &dir,
        &[RENDER, &["--part", "0/2", "-o", "part.png"]].concat(),
        &["part.png", "--part writes an .exr part file"],
    );
    assert_fails(
        &dir,
        &[RENDER, &["--part", "0/13", "-o", "x.exr"]].concat(),
        &["13 parts of 12 spp"],
    );
    assert_fails(
        &dir,
        &[RENDER, &["--part", "3/3", "-o", "x.exr"]].concat(),
        &["--part", "must be below N"],
    );
}

#[test]
fn parts_of_different_devices_merge_only_when_allowed() {
    if common::gpu("parts_of_different_devices_merge_only_when_allowed").is_none() {
        return;
    }
    let dir = TempDir::new("parts-devices");
    render(&dir, &["--device", "cpu", "--part", "0/2", "-o", "cpu.exr"]);
    render(&dir, &["--device", "gpu", "--part", "1/2", "-o", "gpu.exr"]);
    assert_fails(
        &dir,
        &["merge", "-o", "out.exr", "cpu.exr", "gpu.exr"],
        &["cpu.exr was rendered on cpu", "--allow-mixed-devices"],
    );
    ok(
        &dir,
        &[
            "merge",
            "-q",
            "--allow-mixed-devices",
            "-o",
            "out.exr",
            "cpu.exr",
            "gpu.exr",
        ],
    );
    assert!(dir.path().join("out.exr").exists());
}

/// A part that an interruption cut short (its film holds fewer samples than its range)
/// merges with a warning into the mean of the samples the parts hold.
#[test]
fn an_interrupted_part_merges_with_a_warning() {
    let dir = TempDir::new("parts-interrupted");
    let cpu = ["--device", "cpu"];
    render(
        &dir,
        &[&cpu[..], &["--part", "0/2", "-o", "a.exr"]].concat(),
    );
    render(
        &dir,
        &[&cpu[..], &["--part", "1/2", "-o", "b.exr"]].concat(),
    );
    // What SIGTERM leaves of part 1/2 (samples 6..12) after 2 samples: the film of
    // samples 6..8 under part 1/2's header (cli.rs's interruption test sends the signal).
    let b = dir.path().join("b.exr");
    let (_, header) = Film::read_part(&b).unwrap();
    render(
        &dir,
        &[&cpu[..], &["--part", "3/6", "-o", "six.exr"]].concat(),
    );
    let (six, _) = Film::read_part(&dir.path().join("six.exr")).unwrap();
    assert_eq!(six.samples, 2);
    six.save_part(&b, &header).unwrap();
    let said = ok(&dir, &["merge", "-o", "out.exr", "a.exr", "b.exr"]);
    assert!(
        said.contains("warning: b.exr: holds 2 of its 6 samples")
            && said.contains("mean of the 8 samples"),
        "{said}"
    );
    let (w, h, pixels) = meshtrace::film::read_linear(&dir.path().join("out.exr")).unwrap();
    assert_eq!((w, h), (40, 30));
    let (a, _) = Film::read_part(&dir.path().join("a.exr")).unwrap();
    let mut expect = a.clone();
    expect.merge(&six);
    assert_eq!(expect.samples, 8);
    assert_eq!(pixels, expect.mean());
}

/// The same part written twice has the same bytes: its header attributes are written in
/// name order, not in the order of the `exr` crate's hash map (different for every map).
#[test]
fn a_part_file_has_the_same_bytes_every_time() {
    let dir = TempDir::new("parts-same-bytes");
    let mut film = Film::new(4, 3);
    film.samples = 2;
    let header = PartHeader {
        index: 1,
        count: 3,
        start: 4,
        end: 6,
        spp: 9,
        seed: 7,
        device: "cpu (test)".into(),
        digest: "0".repeat(64),
    };
    let first: Vec<Vec<u8>> = (0..4)
        .map(|k| {
            let path = dir.path().join(format!("p{k}.exr"));
            film.save_part(&path, &header).expect("part written");
            std::fs::read(&path).expect("part reads")
        })
        .collect();
    assert!(first.windows(2).all(|w| w[0] == w[1]), "the bytes differ");
    let (back, h) = Film::read_part(&dir.path().join("p0.exr")).expect("part reads back");
    assert_eq!(
        (back.samples, h.start, h.end, h.device),
        (2, 4, 6, header.device)
    );
}
