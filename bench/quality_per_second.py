#!/usr/bin/env python3
"""meshtrace's CPU renderer against Mitsuba 3 (llvm_ad_rgb): quality per second.

For each scene, both renderers render the same image at --spp (default 64) with seeds
0..--seeds-1 (default 3), on every core of this machine, and each image is compared with a
high-spp Mitsuba reference:

    relMSE             = mean over pixels and RGB of (x - ref)^2 / (ref^2 + 1e-2)
                         (tools/compare.py relmse), averaged over the seeds
    seconds            = median render time over the seeds
    quality per second = 1 / (relMSE x seconds)
    ratio              = quality per second of meshtrace / that of Mitsuba
                       = (relMSE_mitsuba / relMSE_meshtrace) x (s_mitsuba / s_meshtrace)

The issue's goal is a ratio of at least 1.5 on every scene. The times are render times
only: meshtrace's are the seconds its CLI prints (`... on the CPU in 2.55 s ...`, which
exclude loading the scene and building the BVH); Mitsuba's are one `mi.render` call plus
the copy of the image to numpy (tools/mitsuba_render.render), after one untimed warm-up
render at the same spp so that its LLVM kernels are compiled and cached (scene loading
is not timed either). The two renderers take turns seed by seed, so slow spells of a
shared machine hit both alike; the table shows each side's spread of times.

Scenes (--scenes, default all three):
  cornell           assets/cornell/cornell.toml, 256x256, max_depth 8, against the suite's
                    reference tests/references/cornell_ref.exr (16384 spp; --ref-spp does
                    not apply)
  glass_mirror_box  bench/scenes/glass_mirror_box.toml: the Cornell walls and light with a
                    glass sphere and a mirror sphere, 192x192, max_depth 8
  ggx_mesh          bench/scenes/ggx_mesh.toml: the Utah teapot
                    (../shared/meshes/teapot.obj) as rough GGX gold, roughness 0.3, on a
                    grey ground under a constant white sky, 256x192, max_depth 8; skipped
                    with a message where that mesh is absent
The references of the last two are rendered here with Mitsuba at --ref-spp (default 4096:
about 70 s and 35 s on 2 cores) and cached in ~/.cache/meshtrace/qps/ (--cache),
keyed by a hash of the scene file, the meshes it names, the image size, max_depth, the
spp and Mitsuba's version and variant.

Usage:
  python3 bench/quality_per_second.py [--meshtrace target/release/meshtrace]
      [--scenes cornell glass_mirror_box ggx_mesh] [--spp 64] [--seeds 3]
      [--ref-spp 4096] [--json OUT] [--threads N] [--keep DIR] [--cache DIR]

--threads sets both renderers' worker threads (default: every CPU this process may use).
--keep DIR writes every render there. Needs Python 3.11+, numpy and mitsuba 3 (with
libLLVM >= 17 for llvm_ad_rgb, found as tools/mitsuba_render.py finds it); it never builds
meshtrace.
"""
import argparse
import hashlib
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import mitsuba_render as mr  # noqa: E402
from compare import read_exr, relmse  # noqa: E402
from make_references import REF_SEED  # noqa: E402

# name -> (scene file, stored reference (exr, json) or None: rendered and cached here)
SCENES = {
    "cornell": ("assets/cornell/cornell.toml",
                ("tests/references/cornell_ref.exr", "tests/references/cornell.json")),
    "glass_mirror_box": ("bench/scenes/glass_mirror_box.toml", None),
    "ggx_mesh": ("bench/scenes/ggx_mesh.toml", None),
}
GOAL = 1.5
WARMUP_SEED = 999_983
# tests/cli.rs checks this pattern against the CLI's output
TIME_RE = re.compile(r" in ([0-9]+(?:\.[0-9]+)?) s \(")


def scene_meshes(path):
    """Absolute paths of the mesh files a scene TOML names."""
    with open(path, "rb") as fh:
        doc = tomllib.load(fh)
    base = os.path.dirname(os.path.abspath(path))
    return [os.path.normpath(os.path.join(base, o["mesh"]))
            for o in doc.get("objects", []) if "mesh" in o]


def cache_key(mi, path, w, h, depth, spp):
    hsh = hashlib.sha256()
    for f in [path] + scene_meshes(path):
        with open(f, "rb") as fh:
            hsh.update(hashlib.sha256(fh.read()).digest())
    hsh.update(("%dx%d d%d spp%d seed%d mitsuba %s %s spheres mesh" % (
        w, h, depth, spp, REF_SEED, mi.__version__, mi.variant())).encode())
    return hsh.hexdigest()[:16]


def meshtrace_render(binary, scene, out, spp, seed, w, h, depth, threads):
    cmd = [binary, "render", scene, "-o", out, "--spp", str(spp), "--seed", str(seed),
           "--width", str(w), "--height", str(h), "--max-depth", str(depth),
           "--device", "cpu", "--threads", str(threads)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit("quality_per_second: meshtrace failed (%d): %s\n%s"
                         % (p.returncode, " ".join(cmd), p.stderr))
    m = TIME_RE.search(p.stderr)
    if not m:
        raise SystemExit("quality_per_second: no render time in meshtrace's output:\n%s"
                         % p.stderr)
    return float(m.group(1)), cmd


def bench_scene(mi, name, args, threads, workdir):
    path, stored = SCENES[name]
    path = os.path.join(ROOT, path)
    missing = [m for m in scene_meshes(path) if not os.path.isfile(m)]
    if missing:
        print("%s: skipped: mesh %s not found" % (name, ", ".join(
            os.path.relpath(m, ROOT) for m in missing)), flush=True)
        return {"scene": os.path.relpath(path, ROOT), "skipped":
                "missing mesh: " + ", ".join(os.path.relpath(m, ROOT) for m in missing)}

    class A:  # no overrides: size and max_depth come from the scene file
        width = height = max_depth = spp = seed = None
        # Mitsuba traces meshtrace's own icospheres, not analytic spheres: the same
        # triangles on both sides, so that the seconds compare the renderers' work.
        spheres = "mesh"
    with tempfile.TemporaryDirectory(prefix="qps_mi_") as tmp:
        d, o = mr.build_scene_dict(mi, path, A, tmp)
        scene = mi.load_dict(d)
    w, h, depth = o["width"], o["height"], o["max_depth"]

    # the reference
    t_ref = None
    if stored:
        ref_path = os.path.join(ROOT, stored[0])
        with open(os.path.join(ROOT, stored[1])) as fh:
            meta = json.load(fh)
        if (meta["width"], meta["height"], meta["max_depth"]) != (w, h, depth):
            raise SystemExit("%s: the stored reference is %dx%d depth %d, the scene %dx%d "
                             "depth %d" % (name, meta["width"], meta["height"],
                                           meta["max_depth"], w, h, depth))
        ref_spp, ref_src = meta["reference_spp"], stored[0]
    else:
        ref_spp = args.ref_spp
        os.makedirs(args.cache, exist_ok=True)
        ref_path = os.path.join(args.cache, "%s_%s.exr" % (
            name, cache_key(mi, path, w, h, depth, ref_spp)))
        ref_src = ref_path
        if not os.path.isfile(ref_path):
            print("%s: rendering the Mitsuba reference, %dx%d at %d spp (cached in %s) ..."
                  % (name, w, h, ref_spp, args.cache), flush=True)
            img, t_ref = mr.render(mi, scene, w, h, ref_spp, REF_SEED, args.lanes,
                                   verbose=False)
            tmp_path = ref_path + ".part.exr"
            mr.write_exr(mi, img, tmp_path)
            os.replace(tmp_path, ref_path)
            print("%s: reference done in %.0f s" % (name, t_ref), flush=True)
    ref = read_exr(ref_path)
    if ref.shape[:2] != (h, w):
        raise SystemExit("%s: reference %s is %dx%d, the scene %dx%d"
                         % (name, ref_src, ref.shape[1], ref.shape[0], w, h))

    spp = args.spp
    # warm-ups, untimed: Mitsuba compiles its kernels; meshtrace's files get cached
    mr.render(mi, scene, w, h, spp, WARMUP_SEED, args.lanes, verbose=False)
    meshtrace_render(args.meshtrace, path, os.path.join(workdir, "warmup.exr"), spp,
                     WARMUP_SEED, w, h, depth, threads)

    mi_err, mi_t, mt_err, mt_t = [], [], [], []
    for s in range(args.seeds):
        img, t = mr.render(mi, scene, w, h, spp, s, args.lanes, verbose=False)
        if args.keep:
            mr.write_exr(mi, img, os.path.join(workdir, "%s_mitsuba_%d.exr" % (name, s)))
        mi_err.append(relmse(img.astype("float64"), ref))
        mi_t.append(t)
        out = os.path.join(workdir, "%s_meshtrace_%d.exr" % (name, s))
        t, cmd = meshtrace_render(args.meshtrace, path, out, spp, s, w, h, depth, threads)
        mt_err.append(relmse(read_exr(out), ref))
        mt_t.append(t)

    def side(err, ts):
        e, t = statistics.fmean(err), statistics.median(ts)
        return {"relmse": e, "relmse_per_seed": err, "seconds": t, "seconds_per_seed": ts,
                "quality_per_second": 1.0 / (e * t)}
    r = {"scene": os.path.relpath(path, ROOT), "width": w, "height": h, "max_depth": depth,
         "spp": spp, "seeds": list(range(args.seeds)), "reference": ref_src,
         "reference_spp": ref_spp, "mitsuba": side(mi_err, mi_t),
         "meshtrace": side(mt_err, mt_t),
         "meshtrace_command": " ".join([args.meshtrace_original] + cmd[1:4]
                                       + ["OUT.exr"] + cmd[5:])}
    if t_ref is not None:
        r["reference_seconds"] = t_ref
    r["error_ratio"] = r["mitsuba"]["relmse"] / r["meshtrace"]["relmse"]
    r["speed_ratio"] = r["mitsuba"]["seconds"] / r["meshtrace"]["seconds"]
    r["ratio"] = (r["meshtrace"]["quality_per_second"] / r["mitsuba"]["quality_per_second"])
    r["meets_goal"] = r["ratio"] >= GOAL
    print("%s: Mitsuba relMSE %.4g in %.2f s (%s); meshtrace relMSE %.4g in %.2f s (%s); "
          "ratio %.2f" % (name, r["mitsuba"]["relmse"], r["mitsuba"]["seconds"],
                          ", ".join("%.2f" % x for x in mi_t), r["meshtrace"]["relmse"],
                          r["meshtrace"]["seconds"], ", ".join("%.2f" % x for x in mt_t),
                          r["ratio"]), flush=True)
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--meshtrace", default="target/release/meshtrace")
    ap.add_argument("--scenes", nargs="+", choices=list(SCENES), default=list(SCENES))
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--ref-spp", type=int, default=4096,
                    help="samples per pixel of the references rendered here (not cornell's)")
    ap.add_argument("--json", help="write the results here")
    ap.add_argument("--threads", type=int, default=len(os.sched_getaffinity(0)),
                    help="worker threads of both renderers (default: every usable CPU)")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--lanes", type=int, default=1 << 23,
                    help="most Mitsuba samples in flight (higher spp is rendered in passes)")
    ap.add_argument("--cache", default=os.path.expanduser("~/.cache/meshtrace/qps"))
    ap.add_argument("--keep", help="write every render here")
    args = ap.parse_args()
    if args.spp < 1 or args.seeds < 1 or args.ref_spp < 1 or args.threads < 1:
        ap.error("--spp, --seeds, --ref-spp and --threads must be at least 1")
    binary = args.meshtrace if os.path.isabs(args.meshtrace) else os.path.join(
        ROOT, args.meshtrace)
    if not os.access(binary, os.X_OK):
        raise SystemExit("quality_per_second: no meshtrace binary at %s (build it with "
                         "cargo build --release, or pass --meshtrace)" % binary)
    args.meshtrace = binary

    t_start = time.time()
    load_start = os.getloadavg()
    work = args.keep or tempfile.mkdtemp(prefix="qps_")
    os.makedirs(work, exist_ok=True)
    # run a copy, so that a rebuild of the binary during the run changes nothing
    with open(binary, "rb") as fh:
        exe = fh.read()
    binary_sha = hashlib.sha256(exe).hexdigest()
    args.meshtrace_original = binary
    args.meshtrace = os.path.join(work, "meshtrace.bin")
    with open(args.meshtrace, "wb") as fh:
        fh.write(exe)
    os.chmod(args.meshtrace, 0o755)
    mi = mr.setup_mitsuba(args.variant)
    import drjit as dr
    dr.set_thread_count(args.threads)
    mt_version = subprocess.run([args.meshtrace, "--version"], capture_output=True,
                                text=True).stdout.strip()
    print("meshtrace %s (CPU, --threads %d) vs Mitsuba %s (%s, %d threads); %d spp, "
          "seeds 0..%d" % (binary, args.threads, mi.__version__, mi.variant(),
                           dr.thread_count(), args.spp, args.seeds - 1), flush=True)

    results = []
    try:
        for name in args.scenes:
            r = bench_scene(mi, name, args, args.threads, work)
            r["name"] = name
            results.append(r)
    finally:
        if args.keep:
            os.remove(args.meshtrace)
        else:
            for f in os.listdir(work):
                os.remove(os.path.join(work, f))
            os.rmdir(work)

    print()
    hdr = ("scene", "MI relMSE", "MI s", "MI q/s", "MT relMSE", "MT s", "MT q/s",
           "err x", "speed x", "ratio")
    print("%-17s %10s %7s %8s %10s %7s %8s %6s %7s %6s" % hdr)
    for r in results:
        if "skipped" in r:
            print("%-17s skipped (%s)" % (r["name"], r["skipped"]))
            continue
        a, b = r["mitsuba"], r["meshtrace"]
        print("%-17s %10.4g %7.2f %8.1f %10.4g %7.2f %8.1f %6.2f %7.2f %6.2f%s" % (
            r["name"], a["relmse"], a["seconds"], a["quality_per_second"], b["relmse"],
            b["seconds"], b["quality_per_second"], r["error_ratio"], r["speed_ratio"],
            r["ratio"], "" if r["meets_goal"] else "  < %.1f" % GOAL))
    total = time.time() - t_start
    print("MI = Mitsuba %s %s, MT = meshtrace CPU; relMSE mean over %d seeds, s = median "
          "render seconds, q/s = 1/(relMSE s); err x = relMSE MI/MT, speed x = s MI/MT, "
          "ratio = q/s MT/MI (goal >= %.1f). Total %.0f s."
          % (mi.__version__, mi.variant(), args.seeds, GOAL, total))
    load_end = os.getloadavg()
    print("Load average (1 min) %.2f at the start, %.2f at the end, on %d CPUs."
          % (load_start[0], load_end[0], os.cpu_count()))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"meshtrace": binary, "meshtrace_version": mt_version,
                       "meshtrace_sha256": binary_sha,
                       "load_average": {"start": load_start, "end": load_end},
                       "cpus": os.cpu_count(),
                       "mitsuba": mi.__version__, "variant": mi.variant(),
                       "libllvm": os.environ.get("DRJIT_LIBLLVM_PATH"),
                       "threads": {"meshtrace": args.threads, "mitsuba": dr.thread_count()},
                       "spp": args.spp, "seeds": args.seeds, "goal": GOAL,
                       "total_seconds": total, "scenes": results}, fh, indent=2)
            fh.write("\n")


if __name__ == "__main__":
    main()
