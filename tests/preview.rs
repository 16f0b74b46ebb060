//! `render --preview` in a real window on a virtual X display (Xvfb): the window shows the
//! image as it converges, its keys switch views and save them, closing it ends the render
//! as Ctrl-C does, a finished render's window sleeps, and the output has the same bytes as
//! a render without the window, on the CPU and on the GPU (lavapipe).
//!
//! Needs Xvfb, xdotool, ImageMagick's `import` and x11-utils' `xwininfo`; skipped, saying
//! so, without them, unless `MESHTRACE_REQUIRE_XVFB=1` (as CI sets it), which fails instead.

use crate::common;

use common::fs::{TempDir, root};
use image::RgbImage;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// A virtual X display, stopped on drop. One at a time: Xvfb servers started together can
/// take each other's display number, and one window at a time keeps the searches for it
/// unambiguous.
struct Display {
    server: Child,
    name: String,
    _one_at_a_time: MutexGuard<'static, ()>,
}

static DISPLAYS: Mutex<()> = Mutex::new(());

impl Display {
    /// Starts Xvfb on the first free display number (it reports the number it took), or
    /// `None` where the tools are missing (after saying so).
    fn start(test: &str) -> Option<Self> {
        let required = std::env::var("MESHTRACE_REQUIRE_XVFB").is_ok_and(|v| v == "1");
        let missing: Vec<&str> = ["Xvfb", "xdotool", "import", "xwininfo"]
            .into_iter()
            .filter(|tool| {
                !Command::new("sh")
                    .args(["-c", &format!("command -v {tool}")])
                    .output()
                    .is_ok_and(|o| o.status.success())
            })
            .collect();
        if !missing.is_empty() {
            assert!(
                !required,
                "{test}: MESHTRACE_REQUIRE_XVFB=1 but {missing:?} are not installed"
            );
            eprintln!(
                "{test}: skipped: {missing:?} not installed (apt-get install xvfb xdotool imagemagick x11-utils)"
            );
            return None;
        }
        // A test that failed while holding the lock poisons it; the next may still run.
        let guard = DISPLAYS.lock().unwrap_or_else(|e| e.into_inner());
        // -noreset: an X server otherwise resets when its last client leaves, and a client
        // that connects meanwhile is refused; the searches for the window come and go
        // every 100 ms, so meshtrace's own connection could meet a reset.
        let mut server = Command::new("Xvfb")
            .args([
                "-noreset",
                "-displayfd",
                "1",
                "-screen",
                "0",
                "1280x1024x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb starts");
        let mut line = String::new();
        BufReader::new(server.stdout.take().expect("piped"))
            .read_line(&mut line)
            .expect("Xvfb reports its display");
        let name = format!(":{}", line.trim());
        assert!(line.trim().parse::<u32>().is_ok(), "Xvfb said {line:?}");
        Some(Self {
            server,
            name,
            _one_at_a_time: guard,
        })
    }

    /// Runs an X client on this display; returns its standard output.
    fn x(&self, program: &str, args: &[&str]) -> String {
        let out = Command::new(program)
            .args(args)
            .env("DISPLAY", &self.name)
            .output()
            .unwrap_or_else(|e| panic!("{program}: {e}"));
        assert!(
            out.status.success(),
            "{program} {args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    }

    /// `meshtrace args...` in `dir`, showing its window on this display.
    fn meshtrace(&self, dir: &TempDir, args: &[&str]) -> Child {
        Command::new(env!("CARGO_BIN_EXE_meshtrace"))
            .args(args)
            .current_dir(dir.path())
            .env("DISPLAY", &self.name)
            .env_remove("WAYLAND_DISPLAY")
            .env("NODEVICE_SELECT", "1")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("meshtrace starts")
    }

    /// The preview window's id, once it is mapped.
    fn window(&self, child: &mut Child) -> String {
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let out = Command::new("xdotool")
                .args(["search", "--onlyvisible", "--name", "^meshtrace: "])
                .env("DISPLAY", &self.name)
                .output()
                .expect("xdotool runs");
            if let Some(id) = String::from_utf8_lossy(&out.stdout).lines().next() {
                return id.to_string();
            }
            if let Ok(Some(status)) = child.try_wait() {
                let mut stderr = String::new();
                if let Some(mut e) = child.stderr.take() {
                    let _ = std::io::Read::read_to_string(&mut e, &mut stderr);
                }
                panic!("meshtrace ended ({status}) before its window showed: {stderr}");
            }
            assert!(Instant::now() < deadline, "no preview window after 60 s");
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// Gives the window the keyboard and types `keys` (xdotool key names).
    fn keys(&self, window: &str, keys: &[&str]) {
        self.x("xdotool", &["windowfocus", "--sync", window]);
        let mut args = vec!["key", "--delay", "50"];
        args.extend(keys);
        self.x("xdotool", &args);
        // The window redraws at most 30 times a second.
        std::thread::sleep(Duration::from_millis(300));
    }

    /// A screenshot of the whole screen (`import -window root`), saved at `path`, and the
    /// part of it the window covers.
    fn screenshot(&self, window: &str, path: &Path) -> RgbImage {
        self.x("import", &["-window", "root", &path.to_string_lossy()]);
        let screen = image::open(path).expect("screenshot reads").to_rgb8();
        let info = self.x("xwininfo", &["-id", window]);
        let field = |name: &str| -> u32 {
            info.lines()
                .find_map(|l| l.trim().strip_prefix(name))
                .and_then(|v| v.trim().parse().ok())
                .unwrap_or_else(|| panic!("xwininfo gave no {name}:\n{info}"))
        };
        let (x, y) = (
            field("Absolute upper-left X:"),
            field("Absolute upper-left Y:"),
        );
        let (w, h) = (field("Width:"), field("Height:"));
        image::imageops::crop_imm(&screen, x, y, w, h).to_image()
    }

    /// Screenshots every half second until one shows what `ready` looks for, or 30 s have
    /// gone (then the last, for the caller's assertion to report).
    fn screenshot_until(
        &self,
        window: &str,
        path: &Path,
        ready: impl Fn(&RgbImage) -> bool,
    ) -> RgbImage {
        let start = std::time::Instant::now();
        loop {
            let shot = self.screenshot(window, path);
            if ready(&shot) || start.elapsed() > Duration::from_secs(30) {
                return shot;
            }
            std::thread::sleep(Duration::from_millis(500));
        }
    }
}

impl Drop for Display {
    fn drop(&mut self) {
        // SIGTERM, so that Xvfb removes its socket and lock file (SIGKILL leaves them for the
        // next server to find); SIGKILL only if that fails.
        let terminated = Command::new("kill")
            .arg(self.server.id().to_string())
            .status()
            .is_ok_and(|s| s.success());
        if !terminated {
            let _ = self.server.kill();
        }
        let _ = self.server.wait();
    }
}

/// Kills process `pid` when dropped: a test that fails while its window is open must not
/// leave the render running (a window whose display has gone does not notice).
struct KillOnDrop(u32);

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        if std::thread::panicking() {
            let _ = Command::new("kill")
                .args(["-9", &self.0.to_string()])
                .status();
        }
    }
}

/// Waits for `child` to end; returns its exit code and standard error.
fn wait(mut child: Child, within: Duration) -> (i32, String) {
    let deadline = Instant::now() + within;
    while child.try_wait().expect("waits").is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("meshtrace did not end within {within:?}");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let out = child.wait_with_output().expect("output");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Waits until `path` exists (outputs appear complete, by rename).
fn wait_for_file(path: &Path, child: &mut Child, within: Duration) {
    let deadline = Instant::now() + within;
    while !path.exists() {
        if let Ok(Some(status)) = child.try_wait() {
            panic!(
                "meshtrace ended ({status}) before writing {}",
                path.display()
            );
        }
        assert!(Instant::now() < deadline, "{} not written", path.display());
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The share of pixels for which `test` holds, and their mean x (0 to 1 across).
fn share(img: &RgbImage, rows: std::ops::Range<u32>, test: impl Fn([u8; 3]) -> bool) -> (f64, f64) {
    let (mut n, mut x_sum, mut all) = (0u64, 0f64, 0u64);
    for y in rows {
        for x in 0..img.width() {
            all += 1;
            if test(img.get_pixel(x, y).0) {
                n += 1;
                x_sum += x as f64 / img.width() as f64;
            }
        }
    }
    (n as f64 / all.max(1) as f64, x_sum / n.max(1) as f64)
}

/// CPU time (user + system) the process has used, in clock ticks (1/100 s on Linux).
fn cpu_ticks(pid: u32) -> u64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).expect("/proc/PID/stat");
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = &stat[stat.rfind(')').expect("stat format") + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    f[11].parse::<u64>().unwrap() + f[12].parse::<u64>().unwrap()
}

/// The channel names and the `meshtrace.samples` attribute of an EXR output.
fn exr_channels_and_samples(path: &Path) -> (Vec<String>, String) {
    let meta = exr::meta::MetaData::read_from_file(path, false).expect("EXR reads");
    let header = &meta.headers[0];
    let names = header
        .channels
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    let samples = header
        .own_attributes
        .other
        .iter()
        .find(|(k, _)| *k == "meshtrace.samples")
        .map(|(_, v)| format!("{v:?}"))
        .unwrap_or_default();
    (names, samples)
}

/// Where the screenshots go, kept after the test for a person to look at.
fn screenshot_dir() -> PathBuf {
    let dir = root().join("target/preview");
    std::fs::create_dir_all(&dir).expect("target/preview");
    dir
}

#[test]
fn without_a_display_preview_is_a_one_line_error() {
    let dir = TempDir::new("preview-no-display");
    let out = Command::new(env!("CARGO_BIN_EXE_meshtrace"))
        .args(["render", "--preview", "--device", "cpu", "-o", "out.png"])
        .current_dir(dir.path())
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .expect("meshtrace runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(
        lines[0].starts_with("error: --preview: cannot open a window")
            && lines[0].contains("DISPLAY")
            && !lines[0].contains(".rs:"),
        "{stderr}"
    );
    assert!(dir.entries().is_empty(), "{:?}", dir.entries());
}

#[test]
fn the_window_shows_the_render_its_views_and_closing_it_writes_the_samples() {
    let Some(display) = Display::start("preview") else {
        return;
    };
    let dir = TempDir::new("preview-cpu");
    let mut child = display.meshtrace(
        &dir,
        &[
            "render",
            "--preview",
            "--spp",
            "100000",
            "--device",
            "cpu",
            "-o",
            "out.exr",
        ],
    );
    let _kill = KillOnDrop(child.id());
    let window = display.window(&mut child);
    let shots = screenshot_dir();
    // Let passes land: on a busy machine (the CI's tests run beside each other) the first
    // pass over the whole image takes a few seconds, so look until it is there.
    let walls = |img: &RgbImage| {
        let rows = 0..img.height() - 80;
        let (red, red_x) = share(img, rows.clone(), |[r, g, b]| {
            r > 60 && r as u32 > 2 * g as u32 && r as u32 > 2 * b as u32
        });
        let (green, green_x) = share(img, rows, |[r, g, b]| {
            g > 40 && g as u32 > r as u32 * 3 / 2 && g as u32 > b as u32 * 3 / 2
        });
        (red, red_x, green, green_x)
    };
    let beauty = display.screenshot_until(&window, &shots.join("beauty.png"), |img| {
        let (red, _, green, _) = walls(img);
        red > 0.05 && green > 0.05
    });
    let (w, h) = beauty.dimensions();
    let image_rows = 0..h - 80;
    // The Cornell box: the red wall on the left, the green one on the right.
    let (red, red_x, green, green_x) = walls(&beauty);
    assert!(
        red > 0.05 && green > 0.05 && red_x < 0.4 && green_x > 0.6,
        "a {w}x{h} window: red {red:.3} at x {red_x:.2}, green {green:.3} at x {green_x:.2}"
    );
    // The panel's text: light pixels on its dark ground.
    let (ink, _) = share(&beauty, h - 78..h, |[r, g, b]| {
        r > 170 && g > 170 && b > 170
    });
    assert!(ink > 0.003, "panel ink {ink:.4}");

    // Key 3: the normal view. The floor faces up, +y: (0.5, 1, 0.5) as colour.
    // The views are traced once beside the render, which shares their threads: wait for
    // them as for the passes.
    display.keys(&window, &["3"]);
    let up = |[r, g, b]: [u8; 3]| r.abs_diff(128) < 8 && g > 245 && b.abs_diff(128) < 8;
    let normals = display.screenshot_until(&window, &shots.join("normal.png"), |img| {
        share(img, 0..img.height() - 80, up).0 > 0.05
    });
    let (floor, _) = share(&normals, image_rows.clone(), up);
    assert!(floor > 0.05, "floor normals {floor:.3}");
    let (floor_before, _) = share(&beauty, image_rows.clone(), up);
    assert!(
        floor_before < 0.001,
        "the beauty view has {floor_before:.3} of them"
    );

    // s saves the view; b and + draw BVH boxes; Esc closes, which stops the render.
    display.keys(&window, &["s", "b", "plus"]);
    display.screenshot(&window, &shots.join("boxes.png"));
    let saved = dir.join("out.normal.png");
    let img = image::open(&saved).expect("the saved view reads").to_rgb8();
    assert_eq!(img.dimensions(), (256, 256));
    display.keys(&window, &["Escape"]);
    let (code, stderr) = wait(child, Duration::from_secs(60));
    assert_eq!(code, 130, "{stderr}");
    assert!(
        stderr.contains("interrupted: wrote out.exr with "),
        "{stderr}"
    );
    let (channels, samples) = exr_channels_and_samples(&dir.join("out.exr"));
    assert_eq!(channels, ["B", "G", "R"], "the views' AOVs are not written");
    assert!(
        !samples.is_empty() && !samples.contains("100000"),
        "{samples}"
    );
}

/// A finished render's window stays open, uses no CPU while idle, and the render's output
/// has the bytes of one without the window.
fn finished_render_matches(test: &str, device: &str, size: [&str; 2], spp: &str, extra: &[&str]) {
    let Some(display) = Display::start(test) else {
        return;
    };
    let dir = TempDir::new(test);
    let args = |out: &'static str| {
        let mut a = vec![
            "render", "--device", device, "--spp", spp, "--width", size[0], "--height", size[1],
            "-o", out,
        ];
        a.extend(extra);
        a
    };
    let mut with = args("window.exr");
    with.push("--preview");
    let mut child = display.meshtrace(&dir, &with);
    let _kill = KillOnDrop(child.id());
    let window = display.window(&mut child);
    wait_for_file(
        &dir.join("window.exr"),
        &mut child,
        Duration::from_secs(120),
    );
    std::thread::sleep(Duration::from_millis(500));
    let shot = display.screenshot(&window, &screenshot_dir().join(format!("{test}.png")));
    let (lit, _) = share(&shot, 0..shot.height() - 80, |[r, g, b]| {
        r as u32 + g as u32 + b as u32 > 150
    });
    assert!(
        lit > 0.02,
        "{test}: the finished image is not in the window ({lit:.3} lit)"
    );
    // Idle: no more than 0.2 s of CPU over 2 s.
    let pid = child.id();
    let before = cpu_ticks(pid);
    std::thread::sleep(Duration::from_secs(2));
    let idle = cpu_ticks(pid) - before;
    assert!(
        idle <= 20,
        "{test}: the idle window used {idle} ticks of CPU in 2 s"
    );
    display.keys(&window, &["Escape"]);
    let (code, stderr) = wait(child, Duration::from_secs(30));
    assert_eq!(code, 0, "{stderr}");
    let out = common::cli::output(&dir, &args("plain.exr"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let read = |name: &str| std::fs::read(dir.join(name)).expect("output reads");
    assert!(
        read("window.exr") == read("plain.exr"),
        "{test}: the render with the window differs from the one without"
    );
}

/// A part file holds the exact sums of every channel of its film: the views' AOVs must
/// not be among them.
#[test]
fn a_finished_cpu_part_in_the_window_is_the_part_without_it() {
    finished_render_matches(
        "preview-done-cpu",
        "cpu",
        ["96", "64"],
        "16",
        &["--part", "1/2", "--aov", "depth"],
    );
}

#[test]
fn a_finished_gpu_render_in_the_window_is_the_render_without_it() {
    if common::gpu("preview-done-gpu").is_none() {
        return;
    }
    finished_render_matches(
        "preview-done-gpu",
        "gpu",
        ["64", "48"],
        "4",
        &["--aov", "depth"],
    );
}
