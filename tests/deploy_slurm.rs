//! The Slurm job scripts of `deploy/slurm/` on a real single-node cluster
//! (`deploy/slurm/local-cluster.sh`): a 4-task array of parts and its merge, which waits
//! for the array (`--dependency=afterok`), give the bytes of one render; so do 1 and 2
//! parts, whose wall times are printed for BENCHMARKS.md; and a 2-task batch array renders
//! 3 meshes × 4 views into 12 images and one transforms.json.
//!
//! Needs root and Debian's slurmctld, slurmd, slurm-client and munge; skipped, saying so,
//! without them, unless `MESHTRACE_REQUIRE_SLURM=1` (as CI sets it), which fails instead.
//!
//! (Most of its 26 s is waiting on the scheduler. libtest starts tests in name order: as
//! `slurm` it started last and ended CI's suite alone, the cores 5-8% busy, for 24 s.)

use crate::common;

use common::fs::{TempDir, data, root};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

/// A running local cluster, stopped on drop.
struct Cluster {
    dir: PathBuf,
    conf: String,
}

impl Cluster {
    fn start(dir: &Path) -> Cluster {
        let out = Command::new("bash")
            .arg(root().join("deploy/slurm/local-cluster.sh"))
            .arg("start")
            .arg(dir)
            .output()
            .unwrap();
        let said = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "local-cluster.sh start: {}{}",
            said,
            String::from_utf8_lossy(&out.stderr)
        );
        let conf = said
            .trim()
            .strip_prefix("export SLURM_CONF=")
            .unwrap_or_else(|| panic!("no SLURM_CONF in {said}"))
            .to_string();
        Cluster {
            dir: dir.to_path_buf(),
            conf,
        }
    }

    /// A command with the cluster's configuration and the test's binary as `meshtrace`.
    fn command(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", &self.conf)
            .env("MESHTRACE", env!("CARGO_BIN_EXE_meshtrace"))
            .env("NODEVICE_SELECT", "1");
        c
    }

    /// Runs `program args` and returns its standard output, failing on an error.
    fn run(&self, program: &str, args: &[&str], cwd: &Path) -> String {
        let out = self
            .command(program)
            .args(args)
            .current_dir(cwd)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{program} {args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    }

    /// Waits until no job is queued or running (at most `limit`).
    fn wait_idle(&self, limit: Duration) {
        let start = Instant::now();
        loop {
            let queue = self.run("squeue", &["-h"], &self.dir);
            if queue.trim().is_empty() {
                return;
            }
            assert!(
                start.elapsed() < limit,
                "jobs still queued after {limit:?}:\n{queue}"
            );
            std::thread::sleep(Duration::from_millis(200));
        }
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new("bash")
            .arg(root().join("deploy/slurm/local-cluster.sh"))
            .arg("stop")
            .arg(&self.dir)
            .status();
    }
}

/// Whether this machine can run the cluster; with `MESHTRACE_REQUIRE_SLURM=1`, it must.
fn available() -> bool {
    let required = std::env::var("MESHTRACE_REQUIRE_SLURM").is_ok_and(|v| v == "1");
    let have = ["slurmctld", "slurmd", "sbatch", "munged"].iter().all(|p| {
        Command::new("sh")
            .args(["-c", &format!("command -v {p} || test -x /usr/sbin/{p}")])
            .output()
            .is_ok_and(|o| o.status.success())
    });
    let is_root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    if have && is_root {
        return true;
    }
    let why = if have {
        "not root"
    } else {
        "Slurm or munge not installed"
    };
    assert!(!required, "MESHTRACE_REQUIRE_SLURM=1 but {why}");
    eprintln!("skipped: {why} (apt-get install slurmctld slurmd slurm-client munge, as root)");
    false
}

/// The render the parts split: the Cornell box at 24 spp, or as many as
/// `MESHTRACE_SLURM_SPP` says (BENCHMARKS.md's scaling measure uses 1536).
fn render_options() -> Vec<String> {
    let spp = std::env::var("MESHTRACE_SLURM_SPP").unwrap_or_else(|_| "24".into());
    [
        "--device",
        "cpu",
        "--spp",
        &spp,
        "--width",
        "96",
        "--height",
        "72",
        "--aov",
        "depth,normal",
    ]
    .map(String::from)
    .into()
}

#[test]
fn slurm_arrays_split_merge_and_batch() {
    if !available() {
        return;
    }
    let dir = TempDir::new("slurm");
    let cluster = Cluster::start(&dir.path().join("cluster"));
    let work = dir.path();
    // The single render the parts must match.
    let one = Instant::now();
    let options = render_options();
    let mut single = vec![
        "render",
        "builtin:cornell",
        "-o",
        "full.exr",
        "--threads",
        "1",
    ];
    single.extend(options.iter().map(String::as_str));
    cluster.run(env!("CARGO_BIN_EXE_meshtrace"), &single, work);
    let one = one.elapsed().as_secs_f64();
    let full = std::fs::read(work.join("full.exr")).unwrap();
    let submit = root().join("deploy/slurm/submit-parts.sh");
    let mut times = Vec::new();
    for n in [1u32, 2, 4] {
        let (parts, result) = (format!("parts{n}"), format!("result{n}.exr"));
        let start = Instant::now();
        let mut args = vec![
            submit.to_str().unwrap().to_string(),
            n.to_string(),
            "builtin:cornell".into(),
            parts.clone(),
            result.clone(),
        ];
        args.extend(options.iter().cloned());
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let merge_job = cluster.run("bash", &args, work);
        assert!(
            merge_job.trim().parse::<u64>().is_ok(),
            "merge job id: {merge_job}"
        );
        cluster.wait_idle(Duration::from_secs(300));
        let wall = start.elapsed().as_secs_f64();
        let logs = || {
            std::fs::read_dir(work.join(&parts))
                .map(|d| {
                    d.filter_map(|e| e.ok())
                        .filter(|e| e.file_name().to_string_lossy().ends_with(".log"))
                        .map(|e| {
                            format!(
                                "{:?}: {}",
                                e.file_name(),
                                std::fs::read_to_string(e.path()).unwrap_or_default()
                            )
                        })
                        .collect::<Vec<_>>()
                        .join("\n")
                })
                .unwrap_or_default()
        };
        let merged = std::fs::read(work.join(&result))
            .unwrap_or_else(|e| panic!("{result}: {e}; logs:\n{}", logs()));
        assert!(
            merged == full,
            "{n} parts merged by Slurm differ from one render; logs:\n{}",
            logs()
        );
        let parts_seen = (0..n)
            .filter(|k| work.join(&parts).join(format!("part-{k}.exr")).exists())
            .count();
        assert_eq!(parts_seen, n as usize);
        times.push((n, wall));
    }
    // Efficiency against the cores the node has: N parts can use min(N, cores) at once.
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    eprintln!("slurm: one render on one thread outside Slurm {one:.2} s; {cores} cores");
    for (n, wall) in &times {
        let t1 = times[0].1;
        eprintln!(
            "slurm: {n} part(s): {wall:.2} s from submission to merged image; speed-up {:.2}, efficiency {:.2} of min(N, cores)",
            t1 / wall,
            t1 / (wall * (*n as f64).min(cores))
        );
    }
    for n in [1u32, 2, 4] {
        for k in 0..n {
            let log = std::fs::read_to_string(work.join(format!("parts{n}/part-{k}.log")))
                .unwrap_or_default();
            eprintln!("slurm: part {k}/{n}: {}", log.trim());
        }
    }
    // A batch array: 3 meshes × 4 views in two shards.
    let models = work.join("models");
    std::fs::create_dir_all(&models).unwrap();
    for name in ["box.obj", "polys.obj", "normals.obj"] {
        std::fs::copy(data(name), models.join(name)).unwrap();
    }
    let manifest = "[render]\nspp = 2\nwidth = 24\nheight = 16\n\n[[jobs]]\nmeshes = \"models/*.obj\"\nviews = 4\noutput = \"out/{stem}_{view}.png\"\n";
    std::fs::write(work.join("m.toml"), manifest).unwrap();
    let batch = root().join("deploy/slurm/batch.sbatch");
    let mut sbatch = cluster.command("sbatch");
    sbatch
        .args(["--parsable", "--array=0-1", "--output=batch-%a.log"])
        .arg(&batch)
        .args(["--device", "cpu", "-q"])
        .env("MANIFEST", "m.toml")
        .current_dir(work);
    let out = sbatch.output().unwrap();
    assert!(
        out.status.success(),
        "sbatch: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    cluster.wait_idle(Duration::from_secs(300));
    let log =
        |k: u32| std::fs::read_to_string(work.join(format!("batch-{k}.log"))).unwrap_or_default();
    for k in 0..2 {
        assert!(
            log(k).contains(&format!("shard {k}/2: images: 6 rendered")),
            "shard {k}: {}",
            log(k)
        );
    }
    let images = std::fs::read_dir(work.join("out"))
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .is_ok_and(|e| e.file_name().to_string_lossy().ends_with(".png"))
        })
        .count();
    assert_eq!(images, 12);
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(work.join("out/transforms.json")).unwrap())
            .unwrap();
    assert_eq!(doc["frames"].as_array().map(Vec::len), Some(12));
}
