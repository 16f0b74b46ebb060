#!/usr/bin/env python3
"""Compare meshtrace's CPU ray throughput with Embree 4, per thread.

`meshtrace bench SCENE --device cpu --threads 1 --json --rays-out DIR` measures its own
rates and writes the triangles it traces (DIR/NAME.triangles.f32) and its ray sets: two
primary views (DIR/NAME.primary.rays.f32: the scene's camera;
DIR/NAME.primary_fill.rays.f32: a narrower view that the mesh fills), a cosine bounce from
each primary hit (DIR/NAME.incoherent.rays.f32) and a shadow ray from each primary hit
towards a light (DIR/NAME.shadow.rays.f32). This script runs that command, then
bench/embree_rays.c (compiled here with $CC, default cc) builds an Embree scene of the same
triangles as Mitsuba 3 builds its scenes (build quality high, no scene flags) and traces
the same rays through it on one thread: one `rtcIntersect1` per ray (`rtcOccluded1` for
the shadow rays), the measure; for reference also with RTC_SCENE_FLAG_ROBUST and as
packets of 8 and 16 rays. meshtrace and Embree take turns for --rounds rounds, and each
ratio is the median of the rounds' ratios. It prints both rates and their ratio for each
set, with the BVH build rates, and a brute-force check of a sample of the rays.

Needs numpy, embreex (`pip install embreex`: only for the Embree 4 library its wheel
bundles; --embree-lib names another), a C compiler and a release build of meshtrace
(`cargo build --release`). See bench/README.md.
"""

import argparse
import importlib.metadata
import importlib.util
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
DEFAULT_SCENE = REPO.parent / "shared" / "meshes" / "stanford-bunny.obj"
VIEWS = ("primary", "primary_fill", "incoherent", "shadow")
# The ray sets meshtrace reports the share of rays on the mesh for (`VIEW_hits`).
HIT_VIEWS = ("primary", "primary_fill")
# The sets traced as any-hit queries (occlusion up to t_max) rather than closest hit.
ANY_HIT_VIEWS = ("shadow",)
F = np.float32
MAX_MISMATCH = 0.01  # hit/miss disagreements with the brute force that fail the run


# --- meshtrace's files (little-endian float32) -------------------------------------------


def read_f32(path, per_row):
    """The float32 rows of `path`, `per_row` values each."""
    if not path.is_file():
        raise SystemExit(f"{path} is missing (does this meshtrace's bench have --rays-out?)")
    data = np.fromfile(path, dtype="<f4")
    if data.size == 0 or data.size % per_row:
        raise SystemExit(f"{path}: {data.size} floats, not a positive multiple of {per_row}")
    return data.reshape(-1, per_row)


def load_triangles(path):
    """The triangle soup as Embree takes it: corners (3n x 3) and indices 0..3n (n x 3)."""
    verts = np.ascontiguousarray(read_f32(path, 9).reshape(-1, 3), dtype=F)
    if not np.isfinite(verts).all():
        raise SystemExit(f"{path}: non-finite vertex coordinates")
    return verts, np.arange(len(verts), dtype=np.int32).reshape(-1, 3)


def load_rays(path):
    """Origins, unit directions (n x 3) and t_max (n) of a ray file (8 floats a ray)."""
    r = read_f32(path, 8)
    origins = np.ascontiguousarray(r[:, 0:3], dtype=F)
    t_max = np.ascontiguousarray(r[:, 3], dtype=F)
    dirs = np.ascontiguousarray(r[:, 4:7], dtype=F)
    length = np.sqrt((dirs.astype(np.float64) ** 2).sum(axis=1))
    if not (np.isfinite(r).all() and np.abs(length - 1).max() < 1e-5 and (t_max > 0).all()
            and (r[:, 7] == 0).all()):
        raise SystemExit(f"{path}: not rays of the expected layout (origin, t_max, unit "
                         "direction, 0)")
    return origins, dirs, t_max


def run_meshtrace(binary, scene, rays_dir, width, height, repeats, spp):
    """Runs `meshtrace bench`: returns the command, the scene's name (the rows' `scene`,
    which names the files) and its rows by (device, measure)."""
    cmd = [str(binary), "bench", str(scene), "--device", "cpu", "--threads", "1", "--json",
           "--rays-out", str(rays_dir), "--width", str(width), "--height", str(height),
           "--repeats", str(repeats), "--spp", str(spp)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stderr}")
    rows = json.loads(r.stdout)
    names = {row["scene"] for row in rows}
    if len(names) != 1:
        raise SystemExit(f"expected the rows of one scene from meshtrace, got {sorted(names)}")
    got = {(row["device"], row["measure"]): row for row in rows}
    need = [("cpu", f"{v}_rays") for v in VIEWS] + [("host", f"{v}_hits") for v in HIT_VIEWS]
    missing = [f"{d}/{m}" for d, m in need + [("host", "bvh_build")] if (d, m) not in got]
    if missing:
        raise SystemExit(f"meshtrace's bench reported no {', '.join(missing)}")
    return cmd, names.pop(), got


def saved_scene_name(rays_dir, scene):
    """The scene whose files an earlier run left in `rays_dir`: the only one there, or else
    the one named like `scene` (its file stem, or the name after `builtin:`)."""
    names = sorted(p.name[: -len(".triangles.f32")] for p in rays_dir.glob("*.triangles.f32"))
    guess = str(scene).split(":", 1)[1] if str(scene).startswith("builtin:") else Path(scene).stem
    if len(names) == 1:
        return names[0]
    if guess in names:
        return guess
    raise SystemExit(f"{rays_dir}: no files of scene `{guess}` (there: {names or 'none'})")


def meshtrace_version(binary):
    r = subprocess.run([str(binary), "--version"], capture_output=True, text=True)
    return r.stdout.strip() if r.returncode == 0 else None


# --- a brute-force check of a sample of rays ----------------------------------------------


def brute_force_t(verts, origins, dirs, t_max):
    """Closest hit distance in (0, t_max) (inf for a miss) by Moller-Trumbore against
    every triangle of the soup, in float64."""
    v = verts.astype(np.float64).reshape(-1, 3, 3)
    a, e1, e2 = v[:, 0], v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
    chunk = max(1, 2_000_000 // len(v))  # rays per step: ~2M ray-triangle pairs
    out = np.full(len(dirs), np.inf)
    for s in range(0, len(dirs), chunk):
        o = origins[s:s + chunk, None, :].astype(np.float64)
        d = dirs[s:s + chunk, None, :].astype(np.float64)
        p = np.cross(d, e2)
        det = np.sum(e1 * p, axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            tv = o - a
            u = np.sum(tv * p, axis=-1) * inv
            q = np.cross(tv, e1)
            w = np.sum(d * q, axis=-1) * inv
            t = np.sum(e2 * q, axis=-1) * inv
        ok = (det != 0) & (u >= 0) & (w >= 0) & (u + w <= 1) & (t > 0)
        ok &= t < t_max[s:s + chunk, None].astype(np.float64)
        out[s:s + chunk] = np.where(ok, t, np.inf).min(axis=1)
    return out


def verify(verts, origins, dirs, t_max, t_embree, hit, count):
    """Compares Embree's hits of `count` rays spread over the set with the brute force
    (hit or miss, and for closest hits the distance)."""
    n = len(dirs)
    sel = np.unique(np.linspace(0, n - 1, min(count, n)).astype(np.int64))
    bf = brute_force_t(verts, origins[sel], dirs[sel], t_max[sel])
    bf_hit = np.isfinite(bf)
    both = bf_hit & hit[sel]
    # Occlusion queries (`t_embree` None) give no distance to compare.
    rel = (np.abs(t_embree[sel][both] - bf[both]) / bf[both] if t_embree is not None
           else np.zeros(0))
    return {"rays": int(len(sel)), "hit_disagree": int((bf_hit != hit[sel]).sum()),
            "brute_hits": int(bf_hit.sum()),
            "max_rel_t_diff": float(rel.max()) if rel.size else None}


# --- Embree ------------------------------------------------------------------------------


def embree_library(explicit):
    """The Embree 4 shared library: `explicit`, or the one the embreex wheel bundles."""
    if explicit:
        if not explicit.is_file():
            raise SystemExit(f"--embree-lib {explicit}: no such file")
        return explicit
    spec = importlib.util.find_spec("embreex")
    if spec is None or spec.origin is None:
        raise SystemExit("embreex is not installed: run `pip install embreex` (its wheel "
                         "bundles Embree 4), or pass --embree-lib PATH/libembree4.so.4")
    libs = sorted((Path(spec.origin).parent.parent / "embreex.libs").glob("libembree4*.so*"))
    if not libs:
        raise SystemExit(f"no libembree4*.so* beside {spec.origin}; pass --embree-lib")
    return libs[0]


def compile_helper(out_dir):
    """Compiles bench/embree_rays.c (the timing loop, in C so that the figures are
    Embree's and not a binding's) with $CC (default cc)."""
    cc = os.environ.get("CC", "cc")
    if shutil.which(cc) is None:
        raise SystemExit(f"no C compiler `{cc}` (set CC, or install gcc): "
                         "bench/embree_rays.c times Embree")
    exe = out_dir / "embree_rays"
    cmd = [cc, "-O2", "-std=c11", "-D_GNU_SOURCE", str(REPO / "bench" / "embree_rays.c"),
           "-o", str(exe), "-ldl", "-lm"]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{r.stderr}")
    return exe


def trace_view(helper, lib, tri_path, ray_path, rays, verts, repeats, build_threads,
               build_repeats, verify_count, any_hit, tmp):
    """Embree's rates, hits and `build_repeats` timed builds for one ray set
    (embree_rays.c): closest hits, or with `any_hit` occlusion within each ray's t_max
    (`rtcOccluded1`)."""
    origins, dirs, t_max = rays
    n = len(dirs)
    out = Path(tmp) / "embree_out.f32"
    cmd = [str(helper), str(lib), str(tri_path), str(ray_path),
           "any" if any_hit else "closest", str(repeats), str(build_threads),
           str(build_repeats), str(out)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stderr}")
    got = json.loads(r.stdout)
    if got["rays"] != n:
        raise SystemExit(f"embree_rays traced {got['rays']} rays of {ray_path}, not {n}")
    res = np.fromfile(out, dtype="<f4")
    if any_hit:
        hit, t_hit = res > 0.5, None
    else:
        t_hit = res
        hit = np.isfinite(t_hit) & (t_hit < t_max)
    hits = int(hit.sum())
    med = statistics.median
    modes = {m: {"mrays": n / med(v["seconds"]) / 1e6,
                 "mrays_all": [n / t / 1e6 for t in v["seconds"]],
                 "differ": v.get("differ")}
             for m, v in got["modes"].items()}
    disagree = {m: v["differ"] for m, v in modes.items() if v["differ"]}
    if any(d > MAX_MISMATCH * n for d in disagree.values()):
        raise SystemExit(f"{ray_path}: Embree's modes disagree with its default on "
                         f"{disagree} of {n} rays")
    return {
        "rays": n,
        # The measure: single rays on a scene built as Mitsuba 3 builds its scenes.
        "mrays": modes["default"]["mrays"],
        "mrays_all": modes["default"]["mrays_all"],
        "modes": modes,
        "build_seconds": got["build_seconds"],
        "embree_version": got["embree_version"],
        "hits": hits,
        "hit_fraction": hits / n,
        "mean_t": (float(t_hit[hit].astype(np.float64).mean())
                   if t_hit is not None and hits else None),
        "verify": (verify(verts, origins, dirs, t_max, t_hit, hit, verify_count)
                   if verify_count > 0 else None),
    }


# --- main --------------------------------------------------------------------------------


def parse_size(text):
    parts = text.lower().split("x")
    if len(parts) == 1:
        parts = parts * 2
    try:
        w, h = (int(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"bad size `{text}`: use N or WxH")
    if w < 1 or h < 1:
        raise argparse.ArgumentTypeError("the size must be at least 1x1")
    return w, h


def fmt(x, spec=".3f"):
    return "-" if x is None else format(x, spec)


def print_table(result):
    m = result["meshtrace"]
    row = "{:<22} {:>9} {:>10} {:>10} {:>10} {:>10} {:>10}"
    print(row.format("", "", "meshtrace", "embree", "", "mesh hits", "any hit"))
    print(row.format("view (1 thread)", "rays", "Mrays/s", "Mrays/s", "mt/embree",
                     "meshtrace", "embree"))
    for view, v in result["views"].items():
        e = v["embree"]
        mt = v["meshtrace"] or {}
        print(row.format(view, e["rays"], fmt(mt.get("mrays")), fmt(e["mrays"]),
                         fmt(v["ratio"]), fmt(mt.get("mesh_hit_fraction"), ".1%"),
                         fmt(e["hit_fraction"], ".1%")))
    e = result["embree"]
    print(row.format("BVH build   Mtris/s", result["triangles"],
                     fmt(m and m["bvh_build_mtris"]), fmt(e["bvh_build_mtris"]),
                     fmt(result["ratio_build"]), "", ""))
    print(row.format("BVH build   ms", "", fmt(m and 1e3 * m["bvh_build_s"]),
                     fmt(1e3 * e["bvh_build_s"]), "", "", ""))
    print()
    for view, v in result["views"].items():
        e = v["embree"]
        line = (f"{view}: embree {e['hits']} of {e['rays']} rays hit "
                f"({e['hit_fraction']:.2%}), mean t {fmt(e['mean_t'], '.6g')}; "
                + ", ".join(f"{k} {v['mrays']:.3f}" for k, v in e["modes"].items())
                + " Mrays/s")
        if v["meshtrace"]:
            lo, hi = v["meshtrace"]["min_max"]
            line += f"; meshtrace min..max {lo:.3f}..{hi:.3f}"
        print(line)
        c = e["verify"]
        if c:
            print(f"  brute force, {c['rays']} rays: {c['hit_disagree']} disagree on hit/miss "
                  f"({c['brute_hits']} hits), max relative t difference "
                  f"{fmt(c['max_rel_t_diff'], '.2e')}")
    print(f"embree ({result['embree']['library']}) build threads: "
          f"{result['embree']['bvh_build_threads']}; "
          + "; ".join(f"{k} {v}" for k, v in result["versions"].items() if v))
    if m:
        print(f"meshtrace: {m['command']}")


def trace_all(args, cmd, name, mt_first, run_mt, tri_path, verts, rays, rays_dir, lib,
              helper, tmp, say):
    """Traces every ray set through Embree in `args.rounds` rounds. Each round follows a
    round of meshtrace (`mt_first`, the run that wrote the rays, then `run_mt()`; None
    without meshtrace), and each view's ratio is the median of the rounds' ratios, so that
    a slow spell of a shared machine hits both sides of a ratio alike. Returns the result
    object and the checks that failed."""
    width, height = args.size
    ntris = len(verts) // 3
    med = statistics.median
    result = {
        "scene": args.scene, "name": name, "triangles": ntris, "width": width,
        "height": height, "repeats": args.repeats, "rounds": args.rounds,
        "meshtrace": None,
        "embree": {"bvh_build_threads": args.embree_build_threads or os.cpu_count(),
                   "library": str(lib), "scene_flags": "none (as Mitsuba 3 builds its "
                   "scenes)", "build_quality": "high"},
        "views": {},
        "ratio_build": None,
        "versions": {
            "embree": None,
            "embreex": (importlib.metadata.version("embreex")
                        if importlib.util.find_spec("embreex") else None),
            "numpy": np.__version__,
            "python": platform.python_version(),
            "meshtrace": None if args.skip_meshtrace else meshtrace_version(args.binary),
        },
    }
    failures = []
    embree_rounds = []  # per round: {view: trace_view's result}
    mt_rounds = [mt_first]
    for i in range(args.rounds):
        if i > 0:
            say(f"round {i + 1}/{args.rounds}: meshtrace bench ...")
            mt_rounds.append(run_mt())
        got = {}
        for view, r in rays.items():
            say(f"round {i + 1}/{args.rounds}: tracing {view} with embree ...")
            # The build is the same for every view: timed once a round, with the first.
            got[view] = trace_view(helper, lib, tri_path, rays_dir / f"{name}.{view}.rays.f32",
                                   r, verts, args.repeats, args.embree_build_threads,
                                   args.repeats if view == VIEWS[0] else 0,
                                   args.verify if i == 0 else 0, view in ANY_HIT_VIEWS, tmp)
        embree_rounds.append(got)
    v0 = embree_rounds[0][VIEWS[0]]["embree_version"]
    result["versions"]["embree"] = f"{v0 // 10000}.{v0 // 100 % 100}.{v0 % 100}"
    build = [t for rnd in embree_rounds for t in rnd[VIEWS[0]]["build_seconds"]]
    result["embree"].update(bvh_build_s=med(build), bvh_build_mtris=ntris / med(build) / 1e6)
    if mt_rounds[0] is not None:
        builds = [rnd[("host", "bvh_build")]["median"] for rnd in mt_rounds]
        result["meshtrace"] = {"command": " ".join(cmd), "bvh_build_mtris": med(builds),
                               "bvh_build_s": ntris / med(builds) / 1e6}
        result["ratio_build"] = med(
            b / (ntris / med(rnd[VIEWS[0]]["build_seconds"]) / 1e6)
            for b, rnd in zip(builds, embree_rounds))
    for view in rays:
        per_round = [rnd[view] for rnd in embree_rounds]
        e = dict(per_round[0])
        e["mrays"] = med(x["mrays"] for x in per_round)
        e["mrays_rounds"] = [x["mrays"] for x in per_round]
        e["modes"] = {k: {"mrays": med(x["modes"][k]["mrays"] for x in per_round),
                          "differ": max(x["modes"][k]["differ"] or 0 for x in per_round)}
                      for k in per_round[0]["modes"]}
        m, ratio = None, None
        if mt_rounds[0] is not None:
            rows = [rnd[("cpu", f"{view}_rays")] for rnd in mt_rounds]
            hits = mt_rounds[0].get(("host", f"{view}_hits"))
            m = {"mrays": med(r["median"] for r in rows),
                 "mrays_rounds": [r["median"] for r in rows],
                 "min_max": [min(r["min"] for r in rows), max(r["max"] for r in rows)],
                 "mesh_hit_fraction": hits["median"] if hits else None}
            ratio = med(r["median"] / x["mrays"] for r, x in zip(rows, per_round))
        result["views"][view] = {"meshtrace": m, "embree": e, "ratio": ratio}
        if e["hits"] == 0 and view not in ANY_HIT_VIEWS:
            failures.append(f"{view}: no ray hits any triangle in Embree")
        c = e["verify"]
        if c and c["hit_disagree"] > MAX_MISMATCH * c["rays"]:
            failures.append(f"{view}: Embree and the brute force disagree on hit/miss for "
                            f"{c['hit_disagree']} of {c['rays']} rays")
    return result, failures


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", "--mesh", default=str(DEFAULT_SCENE),
                    help="any scene `meshtrace bench` takes: a mesh file, a scene file, "
                         "builtin:NAME (default: %(default)s)")
    ap.add_argument("--size", type=parse_size, default=(512, 512), help="N or WxH (default 512)")
    ap.add_argument("--repeats", type=int, default=5, help="timed runs after one warm-up (median)")
    ap.add_argument("--rounds", type=int, default=3,
                    help="meshtrace and Embree measured in turn this many times; each ratio "
                         "is the median of the rounds' ratios (default 3)")
    ap.add_argument("--binary", type=Path, default=REPO / "target" / "release" / "meshtrace")
    ap.add_argument("--spp", type=int, default=1,
                    help="meshtrace bench's path-tracing spp (not compared; kept small to save time)")
    ap.add_argument("--embree-build-threads", type=int, default=1,
                    help="CPUs Embree's BVH builder may use (0: all; default 1, like --threads 1)")
    ap.add_argument("--embree-lib", type=Path,
                    help="an Embree 4 shared library (default: the one the embreex wheel "
                         "bundles)")
    ap.add_argument("--verify", type=int, default=256,
                    help="rays of each view checked against a brute-force intersection (0: none)")
    ap.add_argument("--rays-dir", type=Path,
                    help="where meshtrace writes the triangles and rays, kept afterwards "
                         "(default: a temporary directory)")
    ap.add_argument("--skip-meshtrace", action="store_true",
                    help="don't run meshtrace: trace the files an earlier run left in "
                         "--rays-dir (Embree numbers only)")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args()
    if args.rounds < 1 or args.repeats < 1:
        raise SystemExit("--rounds and --repeats must be at least 1")
    width, height = args.size
    say = (lambda *a: print(*a, file=sys.stderr)) if args.json else print

    with tempfile.TemporaryDirectory(prefix="embree_compare.") as tmp:
        rays_dir = args.rays_dir or Path(tmp)
        lib = embree_library(args.embree_lib)
        helper = compile_helper(Path(tmp))
        if args.skip_meshtrace:
            if not args.rays_dir:
                raise SystemExit("--skip-meshtrace needs --rays-dir")
            cmd, mt = None, None
            name = saved_scene_name(rays_dir, args.scene)
        else:
            rays_dir.mkdir(parents=True, exist_ok=True)
            say(f"running meshtrace bench on {args.scene} ...")
            cmd, name, mt = run_meshtrace(args.binary, args.scene, rays_dir, width, height,
                                          args.repeats, args.spp)
        tri_path = rays_dir / f"{name}.triangles.f32"
        verts, indices = load_triangles(tri_path)
        rays = {v: load_rays(rays_dir / f"{name}.{v}.rays.f32") for v in VIEWS}
        say(f"{tri_path}: {len(indices)} triangles; "
            + ", ".join(f"{v} {len(r[1])} rays" for v, r in rays.items()))
        def run_mt():
            # A later round of meshtrace: the same rays again (its bench is
            # deterministic), rewritten into the same files.
            return None if mt is None else run_meshtrace(
                args.binary, args.scene, rays_dir, width, height, args.repeats, args.spp)[2]

        result, failures = trace_all(args, cmd, name, mt, run_mt, tri_path, verts, rays,
                                     rays_dir, lib, helper, tmp, say)
    result["failures"] = failures

    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print()
        print_table(result)
    if failures:
        raise SystemExit("FAILED: " + "; ".join(failures))


if __name__ == "__main__":
    main()
